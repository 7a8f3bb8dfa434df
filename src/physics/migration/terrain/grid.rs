//! The regular height grid: heights (m) at nodes `spacing` m apart, each cell split into two
//! triangular facets; its facet ids, corners, planes and neighbours, the filling of nodes
//! without data (holes), its memory estimate (bytes) and [`Floor::grid`].

use super::facet::{FacetPlane, inside_tri};
use super::patches::Patch;
use super::walk::{CellGrid, fl};
use super::{Facet, Floor, FloorKind, MAX_TABLED_FACETS, MeanPlane};
use crate::physics::error::{Param, PhysicsError, PhysicsResult};

/// Regular height grid: heights[i][j] is z at (x₀ + j d, y₀ + i d); each cell is split along
/// its (j, i)–(j+1, i+1) diagonal into two triangles.
#[derive(Debug, Clone)]
pub(crate) struct GridFloor {
    pub(super) cells: CellGrid,
    pub(super) nx: usize,
    pub(super) z: Vec<f64>,
    /// The facets' planes, precomputed unless there are more than [`MAX_TABLED_FACETS`].
    pub(super) planes: Vec<FacetPlane>,
    /// Facets removed because a corner had no data (empty: none removed).
    pub(super) holes: Vec<bool>,
    /// Per cell (row-major), the index in `patches` of the coplanar patch holding it, or
    /// [`NONE`](super::NONE); empty when the planes are not tabled.
    pub(super) patch: Vec<u32>,
    /// Rectangles of cells whose facets all have one slope ([`Patch`]).
    pub(super) patches: Vec<Patch>,
}

impl GridFloor {
    /// Row i and column j of facet f's cell.
    #[inline]
    pub(super) fn cell_of(&self, f: Facet) -> (usize, usize) {
        // facet ids are u32, so the cell index and the row length fit u32 (a cheaper division)
        let cell = f >> 1;
        let ncx = self.cells.ncx as u32;
        ((cell / ncx) as usize, (cell % ncx) as usize)
    }

    #[inline]
    pub(super) fn corners(&self, f: Facet) -> ([[f64; 2]; 3], [f64; 3]) {
        let (i, j) = self.cell_of(f);
        self.corners_at(f, i, j)
    }

    #[inline]
    pub(super) fn corners_at(&self, f: Facet, i: usize, j: usize) -> ([[f64; 2]; 3], [f64; 3]) {
        let d = self.cells.d;
        let x = self.cells.x0 + fl(j) * d;
        let y = self.cells.y0 + fl(i) * d;
        let (xe, ye) = (self.cells.x0 + fl(j + 1) * d, self.cells.y0 + fl(i + 1) * d);
        let z00 = self.z[i * self.nx + j];
        let z10 = self.z[i * self.nx + j + 1];
        let z01 = self.z[(i + 1) * self.nx + j];
        let z11 = self.z[(i + 1) * self.nx + j + 1];
        if f & 1 == 0 {
            ([[x, y], [xe, y], [xe, ye]], [z00, z10, z11])
        } else {
            ([[x, y], [xe, ye], [x, ye]], [z00, z11, z01])
        }
    }

    #[inline(always)]
    pub(super) fn plane(&self, f: Facet) -> FacetPlane {
        match self.planes.get(f as usize) {
            Some(p) => *p,
            None => self.plane_of(f),
        }
    }

    /// Height of facet f's plane at (x, y), m: [`GridFloor::plane`]'s `z`, read in place from
    /// the table (no copy of the whole plane).
    #[inline]
    pub(super) fn plane_z(&self, f: Facet, x: f64, y: f64) -> f64 {
        match self.planes.get(f as usize) {
            Some(p) => p.z(x, y),
            None => self.plane_of(f).z(x, y),
        }
    }

    pub(super) fn plane_of(&self, f: Facet) -> FacetPlane {
        let (i, j) = self.cell_of(f);
        let d = self.cells.d;
        let z00 = self.z[i * self.nx + j];
        let z10 = self.z[i * self.nx + j + 1];
        let z01 = self.z[(i + 1) * self.nx + j];
        let z11 = self.z[(i + 1) * self.nx + j + 1];
        let (bx, by) = if f & 1 == 0 {
            ((z10 - z00) / d, (z11 - z10) / d)
        } else {
            ((z11 - z01) / d, (z01 - z00) / d)
        };
        FacetPlane::new(
            self.cells.x0 + fl(j) * d,
            self.cells.y0 + fl(i) * d,
            z00,
            bx,
            by,
        )
    }

    #[inline]
    pub(super) fn facet(&self, ci: usize, cj: usize, half: u32) -> Facet {
        (((cj * (self.nx - 1) + ci) as u32) << 1) | half
    }

    #[inline]
    pub(super) fn neighbor_at(&self, f: Facet, i: usize, j: usize, edge: usize) -> Option<Facet> {
        let ncx = self.nx - 1;
        let ncy = self.cells.ncy;
        match (f & 1, edge) {
            (0, 0) => (i > 0).then(|| self.facet(j, i - 1, 1)),
            (0, 1) => (j + 1 < ncx).then(|| self.facet(j + 1, i, 1)),
            (0, _) => Some(f | 1),
            (_, 0) => Some(f & !1),
            (_, 1) => (i + 1 < ncy).then(|| self.facet(j, i + 1, 0)),
            _ => (j > 0).then(|| self.facet(j - 1, i, 0)),
        }
    }
}

impl GridFloor {
    /// Whether (x, y) (m), at (gx, gy) in units of the spacing from the lower corner of facet
    /// f's cell (column ni, row nj), lies in f's triangle or within `tol` m of it: the decision
    /// [`inside_tri`] takes on f's corners. Each edge of a grid triangle is axis-parallel or the
    /// cell's diagonal, so the signed distances beyond the three edge lines are differences of
    /// gx and gy; when the largest is clear of `t` = tol / spacing by more than
    /// [`GridFloor::clear_margin`] (far more than the rounding of either form) the answer is the
    /// same, and otherwise [`inside_tri`] takes it on the corners.
    #[inline]
    pub(super) fn near_facet(
        &self,
        f: Facet,
        (ni, nj): (usize, usize),
        (x, y): (f64, f64),
        (gx, gy): (f64, f64),
        tol: f64,
        (t, eps): (f64, f64),
    ) -> bool {
        let beyond = if f & 1 == 0 {
            // corners (0, 0), (1, 0), (1, 1): edges gy = 0, gx = 1 and the diagonal
            (-gy)
                .max(gx - 1.0)
                .max((gy - gx) * std::f64::consts::FRAC_1_SQRT_2)
        } else {
            // corners (0, 0), (1, 1), (0, 1): the diagonal, gy = 1 and gx = 0
            (-gx)
                .max(gy - 1.0)
                .max((gx - gy) * std::f64::consts::FRAC_1_SQRT_2)
        };
        if beyond < t - eps {
            true
        } else if beyond > t + eps {
            false
        } else {
            inside_tri(&self.corners_at(f, nj, ni).0, x, y, tol)
        }
    }

    /// The margin, in cells, by which [`GridFloor::near_facet`] takes its decision from the cell
    /// coordinates of a point near (x, y) (m): 1e-3 of `t` (the tolerance in cells) plus 1e-14
    /// of the coordinates' size in cells, beyond the rounding of both forms (a few ulps).
    #[inline]
    pub(super) fn clear_margin(&self, x: f64, y: f64, t: f64) -> f64 {
        let c = &self.cells;
        let size = (x.abs() + y.abs() + c.x0.abs() + c.y0.abs()) / c.d;
        1e-3 * t + 1e-14 * (1.0 + 2.0 * size)
    }

    /// [`Floor::top_height_near`] on the grid: the highest plane at (x, y) (m) among the
    /// facets (holes excepted) whose closed triangle comes within `tol` m of it in plan.
    pub(super) fn top_height_near(&self, x: f64, y: f64, tol: f64) -> Option<f64> {
        let c = &self.cells;
        let ux = (x - c.x0) / c.d;
        let uy = (y - c.y0) / c.d;
        let (Some(ci), Some(cj)) = (
            CellGrid::axis_cell(ux, 0.0, c.ncx),
            CellGrid::axis_cell(uy, 0.0, c.ncy),
        ) else {
            return None;
        };
        let is_hole = |f: Facet| self.holes.get(f as usize).copied().unwrap_or(false);
        // only the facets whose closed triangles can come within tol of (x, y): inside_tri
        // accepts no point farther than tol / sin 22.5° < 2.7 tol from its triangle (at a 45°
        // corner), so a cell farther than `margin` (4 tol, in cell units here, where rounding is
        // below 1e-13 of a cell) holds none it would accept
        let t = tol / c.d;
        let margin = 4.0 * t;
        let (fx, fy) = (ux - fl(ci), uy - fl(cj));
        let (near_lo_x, near_hi_x) = (fx <= margin, 1.0 - fx <= margin);
        let (near_lo_y, near_hi_y) = (fy <= margin, 1.0 - fy <= margin);
        if !(near_lo_x || near_hi_x || near_lo_y || near_hi_y)
            && (fx - fy).abs() * std::f64::consts::FRAC_1_SQRT_2 > margin
        {
            // inside one triangle by more than the margin: its plane alone (inside_tri accepts
            // the point, and refuses it for every other facet)
            let f = self.facet(ci, cj, u32::from(fx <= fy));
            return (!is_hole(f)).then(|| self.plane_z(f, x, y));
        }
        // the cells along one axis: cell k, and a neighbour only within the margin
        let span = |near_lo: bool, near_hi: bool, k: usize, n: usize| {
            let first = if near_lo { k.saturating_sub(1) } else { k };
            let last = if near_hi { (k + 1).min(n - 1) } else { k };
            (first, last)
        };
        let (i0, i1) = span(near_lo_x, near_hi_x, ci, c.ncx);
        let (j0, j1) = span(near_lo_y, near_hi_y, cj, c.ncy);
        let te = (t, self.clear_margin(x, y, t));
        let mut top: Option<f64> = None;
        let mut nj = j0;
        while nj <= j1 {
            let mut ni = i0;
            while ni <= i1 {
                let g = (ux - fl(ni), uy - fl(nj));
                for half in 0..2 {
                    let f = self.facet(ni, nj, half);
                    if !is_hole(f) && self.near_facet(f, (ni, nj), (x, y), g, tol, te) {
                        let z = self.plane_z(f, x, y);
                        top = Some(top.map_or(z, |t: f64| t.max(z)));
                    }
                }
                ni += 1;
            }
            nj += 1;
        }
        top
    }
}

/// Fills the NaN nodes of a `nx`-wide grid in layers outward from the nodes with data, each with
/// the mean of its neighbours (4-connected) filled in earlier layers; false when no node has data.
fn fill_holes(z: &mut [f64], nx: usize, ny: usize) -> bool {
    if z.iter().all(|h| h.is_nan()) {
        return false;
    }
    let nbrs = |k: usize| {
        let (i, j) = (k / nx, k % nx);
        let mut out = [usize::MAX; 4];
        if i > 0 {
            out[0] = k - nx;
        }
        if i + 1 < ny {
            out[1] = k + nx;
        }
        if j > 0 {
            out[2] = k - 1;
        }
        if j + 1 < nx {
            out[3] = k + 1;
        }
        out
    };
    let mut layer: Vec<usize> = (0..z.len())
        .filter(|&k| z[k].is_nan() && nbrs(k).iter().any(|&n| n != usize::MAX && !z[n].is_nan()))
        .collect();
    let mut queued = vec![false; z.len()];
    for &k in &layer {
        queued[k] = true;
    }
    let mut values = Vec::new();
    while !layer.is_empty() {
        values.clear();
        for &k in &layer {
            let (sum, n) = nbrs(k)
                .iter()
                .filter(|&&n| n != usize::MAX && !z[n].is_nan())
                .fold((0.0, 0.0), |(s, c), &n| (s + z[n], c + 1.0));
            values.push(sum / n);
        }
        for (&k, &v) in layer.iter().zip(&values) {
            z[k] = v;
        }
        let mut next = Vec::new();
        for &k in &layer {
            for n in nbrs(k) {
                if n != usize::MAX && z[n].is_nan() && !queued[n] {
                    queued[n] = true;
                    next.push(n);
                }
            }
        }
        layer = next;
    }
    true
}

/// Bound on the memory of a grid floor, bytes per height (the heights as received and as
/// stored, with room for the allocator), besides its facet table (see [`grid_bytes`]).
pub const GRID_BYTES_PER_POINT: f64 = 32.0;

/// Estimated memory of an `rows` × `cols` grid floor, bytes: [`GRID_BYTES_PER_POINT`] per
/// height plus the 64-byte planes of at most 2²⁰ tabled facets.
#[must_use]
pub fn grid_bytes(rows: usize, cols: usize) -> f64 {
    let points = rows as f64 * cols as f64;
    let facets = 2.0 * rows.saturating_sub(1) as f64 * cols.saturating_sub(1) as f64;
    GRID_BYTES_PER_POINT * points + 64.0 * facets.min(MAX_TABLED_FACETS as f64)
}

impl Floor {
    /// A regular height grid; the mean plane passes through the mean height of column j = 0.
    pub(crate) fn grid(
        dip: f64,
        origin: [f64; 2],
        spacing: f64,
        heights: &[Vec<f64>],
    ) -> PhysicsResult<Self> {
        let ny = heights.len();
        let nx = heights.first().map_or(0, Vec::len);
        if ny < 2 || nx < 2 {
            return Err(PhysicsError::invalid(
                Param::FloorHeights,
                ny.min(nx) as f64,
                "a grid needs at least 2 × 2 points",
            ));
        }
        let mut z = Vec::with_capacity(nx * ny);
        for (i, row) in heights.iter().enumerate() {
            if row.len() != nx {
                return Err(PhysicsError::invalid(
                    Param::FloorHeightRow(i),
                    row.len() as f64,
                    format!("every row must have {nx} heights, like row 0"),
                ));
            }
            for (j, &h) in row.iter().enumerate() {
                if h.is_infinite() {
                    return Err(PhysicsError::invalid(
                        Param::FloorHeight(i, j),
                        0.0,
                        "heights must be finite numbers (m)",
                    ));
                }
            }
            z.extend_from_slice(row);
        }
        // NaN marks a node without data: the facets touching it are removed
        let missing: Vec<bool> = z.iter().map(|h| h.is_nan()).collect();
        let any_missing = missing.iter().any(|&m| m);
        let z_ref = if any_missing {
            let (sum, n) = heights
                .iter()
                .map(|r| r[0])
                .filter(|h| !h.is_nan())
                .fold((0.0, 0usize), |(s, n), h| (s + h, n + 1));
            if !fill_holes(&mut z, nx, ny) {
                return Err(PhysicsError::invalid(
                    Param::Floor,
                    0.0,
                    "every node of the grid is without data",
                ));
            }
            if n > 0 {
                sum / n as f64
            } else {
                (0..ny).map(|i| z[i * nx]).sum::<f64>() / ny as f64
            }
        } else {
            heights.iter().map(|r| r[0]).sum::<f64>() / ny as f64
        };
        let (sin, cos) = dip.sin_cos();
        let mut grid = GridFloor {
            cells: CellGrid {
                x0: origin[0],
                y0: origin[1],
                d: spacing,
                ncx: nx - 1,
                ncy: ny - 1,
            },
            nx,
            z,
            planes: Vec::new(),
            holes: Vec::new(),
            patch: Vec::new(),
            patches: Vec::new(),
        };
        let n_facets = 2 * (nx - 1) * (ny - 1);
        if n_facets <= MAX_TABLED_FACETS {
            grid.planes = (0..n_facets as Facet).map(|f| grid.plane_of(f)).collect();
        }
        if any_missing {
            let node = |i: usize, j: usize| missing[i * nx + j];
            grid.holes = (0..n_facets as Facet)
                .map(|f| {
                    let (i, j) = grid.cell_of(f);
                    node(i, j)
                        || node(i + 1, j + 1)
                        || if f & 1 == 0 {
                            node(i, j + 1)
                        } else {
                            node(i + 1, j)
                        }
                })
                .collect();
        }
        grid.find_patches();
        Ok(Floor {
            kind: FloorKind::Grid(grid),
            mean: MeanPlane {
                x0: origin[0],
                z_ref,
                cos,
                sin,
            },
        })
    }
}

#[cfg(test)]
mod tests {
    use super::super::facet::plane_of;
    use super::*;
    use proptest::prelude::*;

    /// A rough grid of 6 × 5 nodes, spacing `d` m, origin (x0, y0) m.
    fn rough(x0: f64, y0: f64, d: f64) -> GridFloor {
        let h: Vec<Vec<f64>> = (0..5)
            .map(|i| {
                (0..6)
                    .map(|j| (1.3 * i as f64 + 0.7 * j as f64).sin() * d - 0.8 * j as f64 * d)
                    .collect()
            })
            .collect();
        let fl = Floor::grid(0.7, [x0, y0], d, &h).unwrap();
        let FloorKind::Grid(g) = fl.kind else {
            panic!("a grid")
        };
        g
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 4000, ..ProptestConfig::default() })]

        /// The grid's point-in-triangle decision from cell coordinates is inside_tri's on the
        /// facet's corners, for points anywhere in and around a cell and for points within a few
        /// tolerances of its edge lines and corners (where the two forms must agree to the bit
        /// of the decision), near the origin and 1e5 m from it.
        #[test]
        fn near_facet_decides_as_inside_tri(
            far in prop_oneof![Just(0.0), Just(1e5)],
            d in prop_oneof![Just(0.1), Just(0.5), Just(2.0)],
            ci in 0usize..5, cj in 0usize..4, half in 0u32..2,
            base in prop_oneof![
                (-0.2..1.2f64, -0.2..1.2f64),
                (prop_oneof![Just(0.0), Just(1.0)], -0.1..1.1f64),
                (-0.1..1.1f64, prop_oneof![Just(0.0), Just(1.0)]),
                (0.0..1.0f64).prop_map(|u| (u, u)),
            ],
            off in (-5.0..5.0f64, -5.0..5.0f64),
        ) {
            let g = rough(far, -far, d);
            let tol = 2e-9 * d;
            // the point: a base in cell units, moved by up to 5 tol each way
            let x = far + (ci as f64 + base.0) * d + off.0 * tol;
            let y = -far + (cj as f64 + base.1) * d + off.1 * tol;
            let f = g.facet(ci, cj, half);
            let gx = (x - far) / d - ci as f64;
            let gy = (y + far) / d - cj as f64;
            let t = tol / d;
            let te = (t, g.clear_margin(x, y, t));
            let fast = g.near_facet(f, (ci, cj), (x, y), (gx, gy), tol, te);
            let exact = inside_tri(&g.corners_at(f, cj, ci).0, x, y, tol);
            prop_assert_eq!(fast, exact, "({}, {}) in facet {} of cell ({}, {})", x, y, f, ci, cj);
        }

        /// The floor-surface height near a point is the highest plane among every facet of the
        /// grid whose triangle inside_tri puts within tol of it (all facets searched).
        #[test]
        fn top_height_near_is_the_highest_plane_within_tol(
            d in prop_oneof![Just(0.1), Just(0.5)],
            base in prop_oneof![
                (0.0..5.0f64, 0.0..4.0f64),
                ((0usize..=5).prop_map(|k| k as f64), 0.0..4.0f64),
                (0.0..5.0f64, (0usize..=4).prop_map(|k| k as f64)),
                ((0usize..=5).prop_map(|k| k as f64), (0usize..=4).prop_map(|k| k as f64)),
                (0.0..4.0f64).prop_map(|u| (u.floor() + u.fract(), u.floor() + u.fract())),
            ],
            off in (-5.0..5.0f64, -5.0..5.0f64),
        ) {
            let g = rough(0.0, 0.0, d);
            let tol = 2e-9 * d;
            let (x, y) = (base.0 * d + off.0 * tol, base.1 * d + off.1 * tol);
            let mut brute: Option<f64> = None;
            for f in 0..(2 * g.cells.ncx * g.cells.ncy) as Facet {
                if inside_tri(&g.corners(f).0, x, y, tol) {
                    let z = g.plane(f).z(x, y);
                    brute = Some(brute.map_or(z, |b: f64| b.max(z)));
                }
            }
            let inside = (0.0..=g.cells.x_max()).contains(&x) && (0.0..=g.cells.y_max()).contains(&y);
            if inside {
                prop_assert_eq!(g.top_height_near(x, y, tol), brute, "at ({}, {})", x, y);
            }
        }
    }

    #[test]
    fn tabled_planes_equal_planes_set_up_on_demand() {
        let h: Vec<Vec<f64>> = (0..4)
            .map(|i| {
                (0..5)
                    .map(|j| (0.3 * i as f64).sin() - 0.7 * j as f64)
                    .collect()
            })
            .collect();
        let f = Floor::grid(0.6, [1.0, -2.0], 0.5, &h).unwrap();
        let FloorKind::Grid(g) = &f.kind else {
            unreachable!()
        };
        assert_eq!(g.planes.len(), 2 * 4 * 3);
        for id in 0..g.planes.len() as Facet {
            let (c, z) = g.corners(id);
            assert_eq!(g.plane(id), g.plane_of(id));
            // the same plane as through the facet's corners, up to rounding
            let p = plane_of(&c, &z);
            assert!((p.bx - g.plane(id).bx).abs() < 1e-12);
            assert!((p.by - g.plane(id).by).abs() < 1e-12);
        }
    }

    #[test]
    fn grid_plane_matches_heights() {
        let d = 0.5;
        let h: Vec<Vec<f64>> = (0..3)
            .map(|i| {
                (0..4)
                    .map(|j| 1.0 + 0.2 * j as f64 * d - 0.1 * i as f64 * d)
                    .collect()
            })
            .collect();
        let f = Floor::grid(0.5, [2.0, -1.0], d, &h).unwrap();
        let id = f.locate(2.7, -0.6, 0.0, 0.0).unwrap();
        let pl = f.facet_plane(id);
        assert!((pl.z(2.7, -0.6) - (1.0 + 0.2 * 0.7 - 0.1 * 0.4)).abs() < 1e-14);
    }
}
