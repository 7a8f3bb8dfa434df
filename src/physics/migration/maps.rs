//! Per-cell maps of an ensemble (RAMMS-style): on a grid of cells in the face's along-dip ×
//! across frame, the number of runs whose path enters each cell and, over those runs, the mean
//! and 95th percentile of each run's largest speed and kinetic energy while in the cell.
//!
//! The point mapped is the rock's centre projected on the face: along the dip, the foot of the
//! perpendicular on the face's mean plane (`MeanPlane::along`, the frame of the release and
//! supports), across, its y. A run's path is the polyline through samples of its closed-form
//! pieces (lumped-mass flights and slides, rigid-block flights and settled slides) taken at most
//! half the smaller cell side apart in that frame, and through its states at every rigid-block
//! step; each chord between samples is walked cell by cell (its crossings of the cell lines,
//! speed and energy interpolated linearly along it), so a cell the polyline crosses is never
//! missed, however short the crossing. A cell's value for a run is the largest over the samples
//! in it and the chord's entry and exit points.

use nalgebra::Vector3;

use super::terrain::MeanPlane;
use crate::physics::stats::percentile_sorted;

/// The cells of a map: `cells_along_dip` × `cells_across` equal rectangles covering
/// [along_dip_min, along_dip_max] × [across_min, across_max], m.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MapGrid {
    /// Upper edge of the first row of cells, m along the dip.
    pub along_dip_min: f64,
    /// Lower edge of the last row of cells, m along the dip.
    pub along_dip_max: f64,
    /// First column's edge, m across (y).
    pub across_min: f64,
    /// Last column's edge, m across (y).
    pub across_max: f64,
    /// Number of cells along the dip.
    pub cells_along_dip: u32,
    /// Number of cells across.
    pub cells_across: u32,
}

impl MapGrid {
    /// Number of cells.
    #[must_use]
    pub fn cells(&self) -> u64 {
        u64::from(self.cells_along_dip) * u64::from(self.cells_across)
    }

    /// Cell side along the dip, m.
    #[must_use]
    pub fn cell_along_dip(&self) -> f64 {
        (self.along_dip_max - self.along_dip_min) / f64::from(self.cells_along_dip)
    }

    /// Cell side across, m.
    #[must_use]
    pub fn cell_across(&self) -> f64 {
        (self.across_max - self.across_min) / f64::from(self.cells_across)
    }

    /// Largest distance between samples of a closed-form piece, m: half the smaller cell side.
    #[must_use]
    pub fn sample_spacing(&self) -> f64 {
        0.5 * self.cell_along_dip().min(self.cell_across())
    }

    /// Index of cell (i along the dip, j across): i × cells_across + j.
    #[must_use]
    pub fn index(&self, i: u32, j: u32) -> u32 {
        i * self.cells_across + j
    }

    /// Cell of the point (s, y) on the grid (a point on the far edges belongs to the last cell).
    fn cell_of(&self, s: f64, y: f64) -> (u32, u32) {
        let fi = ((s - self.along_dip_min) / self.cell_along_dip()).floor();
        let fj = ((y - self.across_min) / self.cell_across()).floor();
        let i = fi.clamp(0.0, f64::from(self.cells_along_dip - 1)) as u32;
        let j = fj.clamp(0.0, f64::from(self.cells_across - 1)) as u32;
        (i, j)
    }
}

/// Largest distance of a closed-form piece from the chords between its samples, as a share of
/// the smaller cell side.
pub const CHORD_SAG: f64 = 1e-3;

/// A run's largest speed and kinetic energy in one cell.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CellMax {
    /// The cell's index ([`MapGrid::index`]).
    pub cell: u32,
    /// Largest speed of the centre while in the cell, m/s.
    pub speed: f64,
    /// Largest kinetic energy (translation and rotation) while in the cell, J.
    pub kinetic_energy: f64,
}

/// The cells one run's path entered, by ascending cell index.
pub type RunCells = Vec<CellMax>;

/// A point of a path in the map's frame: along the dip (m), across (m), speed (m/s), kinetic
/// energy (J).
#[derive(Debug, Clone, Copy)]
struct Sample {
    s: f64,
    y: f64,
    speed: f64,
    ke: f64,
}

/// Follows one run's path and keeps, per cell entered, its largest speed and kinetic energy.
#[derive(Debug)]
pub(crate) struct CellTrack<'g> {
    grid: &'g MapGrid,
    mean: MeanPlane,
    last: Option<Sample>,
    /// The cells entered so far, in the order entered; `cur` indexes the last one kept (a path
    /// stays in a cell for several samples and seldom comes back to an older one).
    cells: Vec<CellMax>,
    cur: usize,
}

impl<'g> CellTrack<'g> {
    /// An empty track on `grid` for a face whose mean plane is `mean`.
    pub(crate) fn new(grid: &'g MapGrid, mean: MeanPlane) -> Self {
        Self {
            grid,
            mean,
            last: None,
            cells: Vec::new(),
            cur: 0,
        }
    }

    /// The next point of the path: centre `p` (m), its speed (m/s) and kinetic energy (J). The
    /// chord from the previous point is walked cell by cell.
    pub(crate) fn point(&mut self, p: &Vector3<f64>, speed: f64, ke: f64) {
        let b = Sample {
            s: self.mean.along(p),
            y: p.y,
            speed,
            ke,
        };
        match self.last {
            None => self.chord(b, b),
            Some(a) => self.chord(a, b),
        }
        self.last = Some(b);
    }

    /// A closed-form piece p(τ) = p₀ + v₀ τ + ½ a τ², τ in [0, dt], sampled at most
    /// [`MapGrid::sample_spacing`] apart (its start and end included); `ke(v)` is the kinetic
    /// energy (J) at velocity v.
    pub(crate) fn piece(
        &mut self,
        p0: &Vector3<f64>,
        v0: &Vector3<f64>,
        a: &Vector3<f64>,
        dt: f64,
        ke: &dyn Fn(&Vector3<f64>) -> f64,
    ) {
        let h = self.grid.sample_spacing();
        // n equal time steps: each moves at most (|v₀| + |a| dt) dt / n, the largest speed on
        // the piece times the step, and strays at most |a| (dt/n)² / 8 from its chord, kept
        // below CHORD_SAG of a cell side (so a cell the curve enters deeper is entered)
        let len = (v0.norm() + a.norm() * dt) * dt;
        let sag = (a.norm() / (8.0 * CHORD_SAG * 2.0 * h)).sqrt() * dt;
        let n = if len.is_finite() && sag.is_finite() && h > 0.0 {
            (len / h).max(sag).ceil().clamp(1.0, 1e7) as u64
        } else {
            1
        };
        for k in 0..=n {
            let tau = if k == n { dt } else { dt * k as f64 / n as f64 };
            let p = p0 + v0 * tau + a * (0.5 * tau * tau);
            let v = v0 + a * tau;
            self.point(&p, v.norm(), ke(&v));
        }
    }

    /// Keeps the larger of the values kept and `speed`, `ke` for cell `c`.
    fn keep(&mut self, c: u32, speed: f64, ke: f64) {
        if self.cells.get(self.cur).is_none_or(|x| x.cell != c) {
            self.cur = match self.cells.iter().rposition(|x| x.cell == c) {
                Some(k) => k,
                None => {
                    self.cells.push(CellMax {
                        cell: c,
                        speed,
                        kinetic_energy: ke,
                    });
                    self.cells.len() - 1
                }
            };
        }
        let e = &mut self.cells[self.cur];
        e.speed = e.speed.max(speed);
        e.kinetic_energy = e.kinetic_energy.max(ke);
    }

    /// Walks the chord a → b over the grid: the part inside the grid (clipped), each cell it
    /// passes with the values at its entry and exit (linear along the chord) and at its ends.
    fn chord(&mut self, a: Sample, b: Sample) {
        let g = *self.grid;
        let (ds, dy) = (b.s - a.s, b.y - a.y);
        // clip λ ∈ [0, 1] to the grid's rectangle (Liang–Barsky)
        let (mut l0, mut l1) = (0.0f64, 1.0f64);
        for (p, q) in [
            (-ds, a.s - g.along_dip_min),
            (ds, g.along_dip_max - a.s),
            (-dy, a.y - g.across_min),
            (dy, g.across_max - a.y),
        ] {
            if p == 0.0 {
                if q < 0.0 || q.is_nan() {
                    return;
                }
            } else {
                let r = q / p;
                if p < 0.0 {
                    l0 = l0.max(r);
                } else {
                    l1 = l1.min(r);
                }
            }
        }
        if l0 > l1 || l0.is_nan() || l1.is_nan() {
            return;
        }
        let at = |l: f64| Sample {
            s: a.s + l * ds,
            y: a.y + l * dy,
            speed: a.speed + l * (b.speed - a.speed),
            ke: a.ke + l * (b.ke - a.ke),
        };
        let start = if l0 == 0.0 { a } else { at(l0) };
        let end = if l1 == 1.0 { b } else { at(l1) };
        let (mut i, mut j) = g.cell_of(start.s, start.y);
        let (ie, je) = g.cell_of(end.s, end.y);
        self.keep(g.index(i, j), start.speed, start.ke);
        // crossings of the cell lines, in order along the chord (each a step of i or j)
        let (hs, hy) = (g.cell_along_dip(), g.cell_across());
        let mut guard = u64::from(ie.abs_diff(i)) + u64::from(je.abs_diff(j)) + 2;
        while (i, j) != (ie, je) && guard > 0 {
            guard -= 1;
            let next_s = if ie > i {
                Some((g.along_dip_min + f64::from(i + 1) * hs - a.s) / ds)
            } else if ie < i {
                Some((g.along_dip_min + f64::from(i) * hs - a.s) / ds)
            } else {
                None
            };
            let next_y = if je > j {
                Some((g.across_min + f64::from(j + 1) * hy - a.y) / dy)
            } else if je < j {
                Some((g.across_min + f64::from(j) * hy - a.y) / dy)
            } else {
                None
            };
            let step_s = match (next_s, next_y) {
                (Some(ls), Some(ly)) => ls <= ly,
                (Some(_), None) => true,
                _ => false,
            };
            let l = if step_s { next_s } else { next_y }
                .unwrap_or(l0)
                .clamp(l0, l1);
            let x = at(l);
            self.keep(g.index(i, j), x.speed, x.ke);
            if step_s {
                i = if ie > i { i + 1 } else { i - 1 };
            } else {
                j = if je > j { j + 1 } else { j - 1 };
            }
            self.keep(g.index(i, j), x.speed, x.ke);
        }
        self.keep(g.index(ie, je), end.speed, end.ke);
    }

    /// The cells entered, by ascending index.
    pub(crate) fn finish(self) -> RunCells {
        let mut out = self.cells;
        out.sort_unstable_by_key(|c| c.cell);
        out.shrink_to_fit();
        out
    }
}

/// Mean and 95th percentile (type 7) of one statistic over the runs that entered a cell.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeanP95 {
    /// Mean, the left-to-right sum in run order divided by the count.
    pub mean: f64,
    /// 95th percentile (Hyndman & Fan type 7).
    pub p95: f64,
}

/// One cell of a map.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CellStatistics {
    /// Runs whose path entered the cell.
    pub passages: u64,
    /// Each run's largest speed in the cell, m/s (None without passages).
    pub speed: Option<MeanP95>,
    /// Each run's largest kinetic energy in the cell, J (None without passages).
    pub kinetic_energy: Option<MeanP95>,
}

/// The maps of an ensemble: the grid and its cells by [`MapGrid::index`].
#[derive(Debug, Clone, PartialEq)]
pub struct Maps {
    /// The grid.
    pub grid: MapGrid,
    /// Runs of the ensemble.
    pub runs: u64,
    /// The cells, i × cells_across + j.
    pub cells: Vec<CellStatistics>,
}

/// Bytes held per passage (a run entering a cell) while an ensemble's maps are made: the
/// per-run record (cell index and two values, 24 bytes) and the per-cell columns (16 bytes).
pub const BYTES_PER_PASSAGE: u64 = 40;

/// Mean (left-to-right sum from −0 in the given order, clamped to the values' range) and type-7
/// 95th percentile of `values`; `values` is sorted in place after the sum.
fn mean_p95(values: &mut [f64]) -> Option<MeanP95> {
    if values.is_empty() {
        return None;
    }
    let mut sum = -0.0;
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for &x in values.iter() {
        sum += x;
        lo = lo.min(x);
        hi = hi.max(x);
    }
    let mean = (sum / values.len() as f64).clamp(lo, hi);
    values.sort_unstable_by(f64::total_cmp);
    Some(MeanP95 {
        mean,
        p95: percentile_sorted(values, 0.95),
    })
}

/// The maps of the runs `runs` (each run's cells, in run order) on `grid`.
#[must_use]
pub fn build_maps(grid: &MapGrid, runs: &[RunCells]) -> Maps {
    let n = grid.cells() as usize;
    // counts, then the cells' columns in run order (compressed rows)
    let mut start = vec![0usize; n + 1];
    for r in runs {
        for c in r {
            start[c.cell as usize + 1] += 1;
        }
    }
    for k in 0..n {
        start[k + 1] += start[k];
    }
    let total = start[n];
    let mut speed = vec![0.0; total];
    let mut ke = vec![0.0; total];
    let mut fill = start.clone();
    for r in runs {
        for c in r {
            let k = &mut fill[c.cell as usize];
            speed[*k] = c.speed;
            ke[*k] = c.kinetic_energy;
            *k += 1;
        }
    }
    let cells = (0..n)
        .map(|k| {
            let (a, b) = (start[k], start[k + 1]);
            CellStatistics {
                passages: (b - a) as u64,
                speed: mean_p95(&mut speed[a..b]),
                kinetic_energy: mean_p95(&mut ke[a..b]),
            }
        })
        .collect();
    Maps {
        grid: *grid,
        runs: runs.len() as u64,
        cells,
    }
}

#[cfg(test)]
mod tests {
    //! The chord walk against a brute-force reference: every cell a straight segment passes
    //! (found by sampling it 10⁵ times) is entered, and no other.
    use super::*;
    use proptest::prelude::*;

    fn grid() -> MapGrid {
        MapGrid {
            along_dip_min: 0.0,
            along_dip_max: 10.0,
            across_min: -2.0,
            across_max: 2.0,
            cells_along_dip: 10,
            cells_across: 8,
        }
    }

    fn plane() -> MeanPlane {
        MeanPlane {
            x0: 0.0,
            z_ref: 0.0,
            cos: 1.0,
            sin: 0.0,
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 300, ..ProptestConfig::default() })]
        #[test]
        fn a_chord_enters_exactly_the_cells_it_crosses(
            s0 in -3.0f64..13.0, y0 in -3.0f64..3.0, s1 in -3.0f64..13.0, y1 in -3.0f64..3.0,
        ) {
            let g = grid();
            let mut t = CellTrack::new(&g, plane());
            t.point(&Vector3::new(s0, y0, 0.0), 1.0, 1.0);
            t.point(&Vector3::new(s1, y1, 0.0), 2.0, 4.0);
            let got: Vec<u32> = t.finish().iter().map(|c| c.cell).collect();
            let mut want = std::collections::BTreeSet::new();
            let n = 100_000;
            for k in 0..=n {
                let l = f64::from(k) / f64::from(n);
                let (s, y) = (s0 + l * (s1 - s0), y0 + l * (y1 - y0));
                if (0.0..=10.0).contains(&s) && (-2.0..=2.0).contains(&y) {
                    let (i, j) = g.cell_of(s, y);
                    want.insert(g.index(i, j));
                }
            }
            // a sampled reference can miss a corner clipped by less than 1e-4 of the chord
            for c in &want {
                prop_assert!(got.contains(c), "cell {} missed: {:?} vs {:?}", c, got, want);
            }
            prop_assert!(got.len() <= want.len() + 2, "{:?} vs {:?}", got, want);
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]
        #[test]
        fn a_curved_piece_enters_every_cell_it_passes(
            i in 1u32..9, j in 1u32..7, ds in -0.1f64..0.1, dy in -0.1f64..0.1,
            vs in -2.0f64..2.0, vy in -2.0f64..2.0, as_ in -20.0f64..20.0, ay in -20.0f64..20.0,
            dt in 0.01f64..1.0,
        ) {
            // near a corner of the cells, short and strongly curved: where chords cut corners
            let g = grid();
            let (s0, y0) = (f64::from(i) + ds, -2.0 + 0.5 * f64::from(j) + dy);
            let (p0, v0, a) = (
                Vector3::new(s0, y0, 0.0),
                Vector3::new(vs, vy, 0.0),
                Vector3::new(as_, ay, 0.0),
            );
            let mut t = CellTrack::new(&g, plane());
            t.piece(&p0, &v0, &a, dt, &|v| v.norm_squared());
            let got: Vec<u32> = t.finish().iter().map(|c| c.cell).collect();
            // brute force: 20 000 points of the curve; a cell counts where a point lies deeper
            // in it than twice the allowed sag
            let (hs, hy) = (g.cell_along_dip(), g.cell_across());
            let depth = 2.0 * CHORD_SAG * hs.min(hy);
            for k in 0..=20_000 {
                let tau = dt * f64::from(k) / 20_000.0;
                let p = p0 + v0 * tau + a * (0.5 * tau * tau);
                let (u, w) = ((p.x - g.along_dip_min) / hs, (p.y - g.across_min) / hy);
                if u < 0.0 || w < 0.0 || u >= 10.0 || w >= 8.0 {
                    continue;
                }
                let (du, dw) = ((u - u.floor()).min(u.ceil() - u) * hs, (w - w.floor()).min(w.ceil() - w) * hy);
                if du.min(dw) < depth {
                    continue;
                }
                let c = g.index(u.floor() as u32, w.floor() as u32);
                prop_assert!(got.contains(&c), "cell {} at τ = {} missed", c, tau);
            }
        }
    }

    #[test]
    fn mean_and_p95_over_the_runs_of_a_cell() {
        let g = grid();
        let run = |v: f64| {
            vec![CellMax {
                cell: 3,
                speed: v,
                kinetic_energy: 2.0 * v,
            }]
        };
        let runs: Vec<RunCells> = [4.0, 1.0, 3.0, 2.0].iter().map(|&v| run(v)).collect();
        let m = build_maps(&g, &runs);
        let c = m.cells[3];
        assert_eq!(c.passages, 4);
        let s = c.speed.unwrap();
        assert_eq!(s.mean, 2.5);
        // type 7: h = 0.95 × 3 = 2.85 → 3 + 0.85 × (4 − 3)
        assert!((s.p95 - 3.85).abs() < 1e-12);
        assert_eq!(c.kinetic_energy.unwrap().mean, 5.0);
        assert_eq!(m.cells[0].passages, 0);
        assert!(m.cells[0].speed.is_none());
    }
}
