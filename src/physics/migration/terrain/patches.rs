//! Coplanar patches of a grid floor: maximal rectangles of cells whose facets share one slope
//! (to [`PATCH_SLOPE_TOL`]), so that a slide (positions in m, times in s) crosses a patch in one
//! closed-form piece and a flight above one strikes its plane without a cell walk.

use nalgebra::Vector3;

use super::flight::descent_root;
use super::grid::GridFloor;
use super::slide::outward_root;
use super::walk::{CellGrid, fl};
use super::{Facet, FlightEnd, Floor, FloorKind, NONE};

/// Largest difference, in each of ∂z/∂x and ∂z/∂y, between the slopes of the facets of one
/// coplanar patch. Facets of a floor that is one plane differ by rounding (a few 1e-16 over
/// a spacing of 0.5 m); at this bound a patch 1 km wide departs from each of its facets' planes
/// by at most 2e-9 m, which the rock's height corrections at the patch's boundary book exactly.
const PATCH_SLOPE_TOL: f64 = 1e-12;

/// A rectangle of grid cells, columns `ci[0]..ci[1]` and rows `cj[0]..cj[1]`, whose facets all
/// have one slope (to [`PATCH_SLOPE_TOL`]) and no holes: the grid is continuous, so they lie in
/// one plane, and a slide across them is one closed-form piece to the rectangle's boundary
/// (the same motion the per-triangle pieces give, without a step per triangle).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Patch {
    ci: [usize; 2],
    cj: [usize; 2],
}

impl GridFloor {
    /// The common slope (∂z/∂x, ∂z/∂y) of the two facets of cell (column ci, row cj), or None
    /// when they differ (beyond [`PATCH_SLOPE_TOL`]) or either is a hole.
    fn cell_slope(&self, ci: usize, cj: usize) -> Option<(f64, f64)> {
        let f = self.facet(ci, cj, 0);
        if self.holes.get(f as usize).copied().unwrap_or(false)
            || self.holes.get(f as usize + 1).copied().unwrap_or(false)
        {
            return None;
        }
        let (a, b) = (self.planes[f as usize], self.planes[f as usize + 1]);
        slopes_agree((a.bx, a.by), (b.bx, b.by)).then_some((a.bx, a.by))
    }

    /// Partitions the cells greedily (row by row) into maximal rectangles of one slope: each
    /// unassigned cell whose facets agree starts a patch, grown along its row while the next
    /// cell has the start cell's slope, then row by row while every cell of the row does. Only
    /// when the planes are tabled.
    pub(super) fn find_patches(&mut self) {
        let (ncx, ncy) = (self.cells.ncx, self.cells.ncy);
        if self.planes.len() != 2 * ncx * ncy {
            return;
        }
        let mut patch = vec![NONE; ncx * ncy];
        let mut patches = Vec::new();
        for cj in 0..ncy {
            for ci in 0..ncx {
                if patch[cj * ncx + ci] != NONE {
                    continue;
                }
                let Some(r) = self.cell_slope(ci, cj) else {
                    continue;
                };
                let fits = |patch: &[u32], c: usize, row: usize| {
                    patch[row * ncx + c] == NONE
                        && self.cell_slope(c, row).is_some_and(|s| slopes_agree(s, r))
                };
                let mut ce = ci + 1;
                while ce < ncx && fits(&patch, ce, cj) {
                    ce += 1;
                }
                let mut re = cj + 1;
                while re < ncy && (ci..ce).all(|c| fits(&patch, c, re)) {
                    re += 1;
                }
                let id = patches.len() as u32;
                patches.push(Patch {
                    ci: [ci, ce],
                    cj: [cj, re],
                });
                for row in cj..re {
                    patch[row * ncx + ci..row * ncx + ce].fill(id);
                }
            }
        }
        self.patch = patch;
        self.patches = patches;
    }

    /// The coplanar patch holding facet f, if any.
    #[inline]
    pub(super) fn patch_of(&self, f: Facet) -> Option<&Patch> {
        let k = *self.patch.get((f >> 1) as usize)?;
        self.patches.get(k as usize)
    }

    /// First exit of the planar motion p + v t + ½ a t² from the patch `pa` within t ≤ t_max,
    /// as [`Floor::slide_exit`] gives it for a facet: the time, the facet across the boundary
    /// (None: off the floor or a hole) and the end points of the cell edge crossed, in the
    /// counter-clockwise order of the facet inside.
    fn patch_exit(
        &self,
        pa: &Patch,
        p: &Vector3<f64>,
        v: &Vector3<f64>,
        a: &Vector3<f64>,
        t_max: f64,
    ) -> Option<(f64, Option<Facet>, [[f64; 2]; 2])> {
        let c = &self.cells;
        let xs = [c.x0 + fl(pa.ci[0]) * c.d, c.x0 + fl(pa.ci[1]) * c.d];
        let ys = [c.y0 + fl(pa.cj[0]) * c.d, c.y0 + fl(pa.cj[1]) * c.d];
        // sides in the order of the facet edges they are made of: bottom (edge 0 of lower
        // halves), right (edge 1 of lower halves), top (edge 1 of upper halves), left (edge 2
        // of upper halves); each as the outward distance and its rates
        let sides = [
            (ys[0] - p.y, -v.y, -a.y),
            (p.x - xs[1], v.x, a.x),
            (p.y - ys[1], v.y, a.y),
            (xs[0] - p.x, -v.x, -a.x),
        ];
        let mut best: Option<(f64, usize)> = None;
        for (k, &(f0, f1, f2)) in sides.iter().enumerate() {
            if let Some(t) = outward_root(f0, f1, f2)
                && t <= t_max
                && best.is_none_or(|b| t < b.0)
            {
                best = Some((t, k));
            }
        }
        let (t, k) = best?;
        let q = (
            p.x + (v.x + 0.5 * a.x * t) * t,
            p.y + (v.y + 0.5 * a.y * t) * t,
        );
        // the cell along the side that the exit point lies in (clamped to the patch)
        let along = |u: f64, o: f64, r: [usize; 2]| -> usize {
            let i = ((u - o) / c.d).floor();
            if i.is_nan() || i < r[0] as f64 {
                r[0]
            } else {
                (i as usize).min(r[1] - 1)
            }
        };
        let (ci, cj, half, edge) = match k {
            0 => (along(q.0, c.x0, pa.ci), pa.cj[0], 0, 0),
            1 => (pa.ci[1] - 1, along(q.1, c.y0, pa.cj), 0, 1),
            2 => (along(q.0, c.x0, pa.ci), pa.cj[1] - 1, 1, 1),
            _ => (pa.ci[0], along(q.1, c.y0, pa.cj), 1, 2),
        };
        let f = self.facet(ci, cj, half);
        let (corners, _) = self.corners_at(f, cj, ci);
        let next = self
            .neighbor_at(f, cj, ci, edge)
            .filter(|&n| !self.holes.get(n as usize).copied().unwrap_or(false));
        Some((t, next, [corners[edge], corners[(edge + 1) % 3]]))
    }
}

impl GridFloor {
    /// The strike of the parabola p + v t + ½ (0, 0, −g) t² when the flight starts above a
    /// coplanar patch and strikes its plane within t_max at a point inside the patch (by more
    /// than a hair): the floor under the straight plan-view path between the two points is
    /// that plane alone (the rectangle is convex), so the plane's descending root is the first
    /// strike, whatever the number of cells crossed. None otherwise (the cell walk decides).
    pub(super) fn patch_flight(
        &self,
        p: &Vector3<f64>,
        v: &Vector3<f64>,
        g: f64,
        t_max: f64,
    ) -> Option<FlightEnd> {
        if self.patch.is_empty() {
            return None;
        }
        let c = &self.cells;
        let ci = CellGrid::axis_cell((p.x - c.x0) / c.d, v.x, c.ncx)?;
        let cj = CellGrid::axis_cell((p.y - c.y0) / c.d, v.y, c.ncy)?;
        let pa = self.patch_of(self.facet(ci, cj, 0))?;
        let pl = self.planes[self.facet(ci, cj, 0) as usize];
        let h0 = pl.height(p);
        // clearly above the floor at the start (a start on it is for the walk's rules)
        if h0.is_nan() || h0 <= 1e-9 * c.d {
            return None;
        }
        let t = descent_root(h0, pl.height_rate(v), g)?;
        if t.is_nan() || t > t_max {
            return None;
        }
        let (qx, qy) = (p.x + v.x * t, p.y + v.y * t);
        let hair = 1e-6 * c.d;
        let inside = |x: f64, y: f64| {
            x > c.x0 + fl(pa.ci[0]) * c.d + hair
                && x < c.x0 + fl(pa.ci[1]) * c.d - hair
                && y > c.y0 + fl(pa.cj[0]) * c.d + hair
                && y < c.y0 + fl(pa.cj[1]) * c.d - hair
        };
        if !(inside(p.x, p.y) && inside(qx, qy)) {
            return None;
        }
        let qi = CellGrid::axis_cell((qx - c.x0) / c.d, v.x, c.ncx)?;
        let qj = CellGrid::axis_cell((qy - c.y0) / c.d, v.y, c.ncy)?;
        let (fx, fy) = ((qx - c.x0) / c.d - fl(qi), (qy - c.y0) / c.d - fl(qj));
        let half = if fx > fy || (fx == fy && v.x > v.y) {
            0
        } else {
            1
        };
        Some(FlightEnd::Hit {
            t,
            facet: self.facet(qi, qj, half),
        })
    }
}

/// Whether two slopes (∂z/∂x, ∂z/∂y) agree to [`PATCH_SLOPE_TOL`].
#[inline]
fn slopes_agree(a: (f64, f64), b: (f64, f64)) -> bool {
    (a.0 - b.0).abs() <= PATCH_SLOPE_TOL && (a.1 - b.1).abs() <= PATCH_SLOPE_TOL
}

impl Floor {
    /// Whether facet f lies in a coplanar patch of a grid (several facets in one plane, see
    /// [`Floor::slide_exit_merged`]).
    #[inline]
    pub(crate) fn in_patch(&self, f: Facet) -> bool {
        match &self.kind {
            FloorKind::Grid(g) => g.patch_of(f).is_some(),
            _ => false,
        }
    }

    /// As [`Floor::slide_exit`], but from the whole coplanar patch holding facet f when there
    /// is one (a rectangle of grid cells in one plane): the motion, planar in f's plane, leaves
    /// the patch at the first crossing of its boundary, so the triangles inside cost no steps.
    /// The edge returned is the cell edge crossed; a piece that ends inside the patch may end
    /// on another facet of it ([`Floor::locate`] finds which).
    #[inline]
    pub(crate) fn slide_exit_merged(
        &self,
        f: Facet,
        p: &Vector3<f64>,
        v: &Vector3<f64>,
        a: &Vector3<f64>,
        t_max: f64,
    ) -> Option<(f64, Option<Facet>, [[f64; 2]; 2])> {
        if let FloorKind::Grid(g) = &self.kind
            && let Some(pa) = g.patch_of(f)
        {
            return g.patch_exit(pa, p, v, a, t_max);
        }
        self.slide_exit(f, p, v, a, t_max)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A grid that is one plane is one coplanar patch, and a slide leaves it where the chain of
    /// per-triangle exits leads (same time and point to rounding); a raised node splits the
    /// patches so that no patch holds a cell touching it.
    #[test]
    fn a_plane_grid_is_one_patch_left_where_the_triangle_exits_lead() {
        let (d, tan) = (0.5, 0.7);
        let mut h: Vec<Vec<f64>> = (0..5)
            .map(|_| (0..9).map(|j| -(j as f64 * d) * tan).collect())
            .collect();
        let floor = Floor::grid(tan.atan(), [0.0, -1.0], d, &h).unwrap();
        let FloorKind::Grid(g) = &floor.kind else {
            panic!("a grid")
        };
        assert_eq!(
            g.patches,
            vec![Patch {
                ci: [0, 8],
                cj: [0, 4]
            }]
        );
        let pl = floor.facet_plane(0);
        let n = pl.normal();
        let gv = Vector3::new(0.0, 0.0, -9.81);
        let a = gv - n * gv.dot(&n);
        for (x, y, vx, vy) in [
            (0.3, -0.8, 1.0, 0.4),
            (3.7, 0.9, -2.0, -0.3),
            (1.1, 0.1, 0.0, 1.5),
            (2.1, -0.45, 0.2, 0.01),
        ] {
            let p0 = Vector3::new(x, y, pl.z(x, y));
            let mut v0 = Vector3::new(vx, vy, 0.0);
            v0.z = -(n.x * vx + n.y * vy) / n.z;
            let f0 = floor.locate(x, y, vx, vy).unwrap();
            // the chain of triangle exits up to the floor's edge
            let (mut p, mut v, mut f, mut t) = (p0, v0, f0, 0.0);
            let (t_end, edge_end) = loop {
                let (dt, next, edge) = floor.slide_exit(f, &p, &v, &a, 100.0).unwrap();
                p += v * dt + a * (0.5 * dt * dt);
                v += a * dt;
                t += dt;
                match next {
                    Some(nf) => f = nf,
                    None => break (t, edge),
                }
            };
            let (tm, next, edge) = floor.slide_exit_merged(f0, &p0, &v0, &a, 100.0).unwrap();
            assert_eq!(next, None);
            assert!((tm - t_end).abs() <= 1e-12 * t_end, "{tm} vs {t_end}");
            assert_eq!(edge, edge_end);
            let q = p0 + v0 * tm + a * (0.5 * tm * tm);
            assert!((q - p).norm() <= 1e-12, "{q:?} vs {p:?}");
        }
        // a raised node (column 4, row 2) leaves the cells around it out of every patch
        h[2][4] += 0.01;
        let floor = Floor::grid(tan.atan(), [0.0, -1.0], d, &h).unwrap();
        let FloorKind::Grid(g) = &floor.kind else {
            panic!("a grid")
        };
        for (ci, cj) in [(3, 1), (4, 1), (3, 2), (4, 2)] {
            assert!(g.patch_of(g.facet(ci, cj, 0)).is_none(), "cell {ci}, {cj}");
        }
        let covered: usize = g
            .patches
            .iter()
            .map(|p| (p.ci[1] - p.ci[0]) * (p.cj[1] - p.cj[0]))
            .sum();
        assert_eq!(covered, 32 - 4);
    }
}
