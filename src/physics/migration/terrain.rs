//! Floors of the face: the analytic plane, a regular height grid and a Delaunay-triangulated
//! contour set, with the queries the energy tracking method needs.
//!
//! Every floor is a height field z = h(x, y) made of planar facets (the plane is one facet). The
//! horizontal projection of a free-flight parabola is a straight line, so a flight's first hit is
//! found by walking the cells of a uniform grid along that line (cost ∝ path length, not floor
//! size) and, in each cell, taking the descending root of the quadratic height above each
//! candidate facet. A slide on one facet has constant acceleration, so its exit through an edge is
//! the smallest outward root of a quadratic per edge.
//!
//! References: physics.md §C.2 ("On a triangulated floor …"), api.md `POST /v1/migration` (floors).

use nalgebra::Vector3;
use spade::{DelaunayTriangulation, HasPosition, Point2, Triangulation};

use crate::physics::error::{Param, PhysicsError, PhysicsResult};

/// Identifier of one planar facet of a floor (the plane floor has the single facet 0).
pub(crate) type Facet = u32;

/// A planar facet z = z_r + b_x (x − x_r) + b_y (y − y_r), heights in m, with its unit normal.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct FacetPlane {
    xr: f64,
    yr: f64,
    zr: f64,
    bx: f64,
    by: f64,
    n: Vector3<f64>,
}

/// Largest number of facets whose planes a floor keeps precomputed (64 bytes each); larger
/// floors set each plane up when it is needed.
const MAX_TABLED_FACETS: usize = 1 << 20;

impl FacetPlane {
    fn new(xr: f64, yr: f64, zr: f64, bx: f64, by: f64) -> Self {
        let k = 1.0 / (1.0 + bx * bx + by * by).sqrt();
        FacetPlane {
            xr,
            yr,
            zr,
            bx,
            by,
            n: Vector3::new(-bx * k, -by * k, k),
        }
    }

    /// Height of the facet's plane at (x, y), m.
    #[inline]
    pub(crate) fn z(&self, x: f64, y: f64) -> f64 {
        self.zr + self.bx * (x - self.xr) + self.by * (y - self.yr)
    }

    /// Unit normal pointing up (n_z > 0).
    pub(crate) fn normal(&self) -> Vector3<f64> {
        self.n
    }

    /// Vertical height of p above the plane, m.
    #[inline]
    pub(crate) fn height(&self, p: &Vector3<f64>) -> f64 {
        p.z - self.z(p.x, p.y)
    }

    /// Rate of change of the vertical height for velocity v, m/s.
    #[inline]
    pub(crate) fn height_rate(&self, v: &Vector3<f64>) -> f64 {
        v.z - self.bx * v.x - self.by * v.y
    }

    /// Unit vector in the plane whose horizontal part points along +x (the local down-dip).
    pub(crate) fn down_dip(&self) -> Vector3<f64> {
        Vector3::new(1.0, 0.0, self.bx).normalize()
    }
}

/// Descending root of h0 + b t − ½ g t² (the larger root), or None when the parabola stays below.
#[inline]
fn descent_root(h0: f64, b: f64, g: f64) -> Option<f64> {
    let d = b * b + 2.0 * g * h0;
    if d < 0.0 {
        return None;
    }
    let s = d.sqrt();
    if b >= 0.0 {
        Some((b + s) / g)
    } else if s - b > 0.0 {
        Some(2.0 * h0 / (s - b))
    } else {
        Some(0.0)
    }
}

/// Result of a flight query.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum FlightEnd {
    /// The parabola strikes facet `facet` after `t` s.
    Hit {
        /// Time of flight, s.
        t: f64,
        /// Struck facet.
        facet: Facet,
    },
    /// The horizontal path leaves the floor's extent after `t` s without a hit.
    Leaves {
        /// Time of flight, s.
        t: f64,
    },
    /// No hit within the time asked for.
    Clear,
}

/// The face's mean plane (dip θ) used for `along_dip_m` and the potential-energy zero.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct MeanPlane {
    /// x of the upper end, m.
    pub(crate) x0: f64,
    /// Height of the mean plane at x₀, m.
    pub(crate) z_ref: f64,
    /// cos θ.
    pub(crate) cos: f64,
    /// sin θ.
    pub(crate) sin: f64,
}

impl MeanPlane {
    /// Distance along dip of the foot of the perpendicular from p to the mean plane, m.
    pub(crate) fn along(&self, p: &Vector3<f64>) -> f64 {
        (p.x - self.x0) * self.cos - (p.z - self.z_ref) * self.sin
    }

    /// Unit down-dip vector of the mean plane.
    pub(crate) fn dip_dir(&self) -> Vector3<f64> {
        Vector3::new(self.cos, 0.0, -self.sin)
    }

    /// Unit outward normal of the mean plane.
    pub(crate) fn normal(&self) -> Vector3<f64> {
        Vector3::new(self.sin, 0.0, self.cos)
    }

    /// Height of the mean plane where `along_dip` = s, m.
    pub(crate) fn z_at(&self, s: f64) -> f64 {
        self.z_ref - s * self.sin
    }
}

/// Uniform cell grid over a rectangle, used to walk a straight horizontal line cell by cell.
#[derive(Debug, Clone, Copy)]
struct CellGrid {
    x0: f64,
    y0: f64,
    d: f64,
    ncx: usize,
    ncy: usize,
}

impl CellGrid {
    fn x_max(&self) -> f64 {
        self.x0 + self.ncx as f64 * self.d
    }
    fn y_max(&self) -> f64 {
        self.y0 + self.ncy as f64 * self.d
    }

    /// Cell index along one axis for coordinate u (in cells) moving with rate r, or None outside.
    fn axis_cell(u: f64, r: f64, n: usize) -> Option<usize> {
        // points a rounding error outside the extent count as on its boundary
        let u = if u < 0.0 && u > -1e-9 {
            0.0
        } else if u > n as f64 && u < n as f64 + 1e-9 {
            n as f64
        } else {
            u
        };
        if !(u >= 0.0 && u <= n as f64) {
            return None;
        }
        // u ≥ 0 here, so truncation is the floor (and avoids a libm call on baseline x86-64)
        let mut c = (u as u64) as f64;
        if c == u && r < 0.0 {
            c -= 1.0;
        }
        if c >= n as f64 {
            // on the far boundary: inside only when moving back in (or not moving)
            if r > 0.0 {
                return None;
            }
            c = n as f64 - 1.0;
        }
        if c < 0.0 {
            return None;
        }
        Some(c as usize)
    }

    /// The cell (ci, cj) and those of its neighbours whose shared boundary (edge or corner) the
    /// straight path (x, y) + (vx, vy) t over [t0, t1] comes within `tol` of, m: a path running
    /// along a grid line is in both cells at once as far as rounding can tell, and the instant it
    /// crosses the line is then ill-conditioned, so both cells' facets are candidates.
    #[allow(clippy::too_many_arguments)]
    fn near_cells(
        &self,
        ci: usize,
        cj: usize,
        (x, y, vx, vy): (f64, f64, f64, f64),
        t0: f64,
        t1: f64,
        tol: f64,
    ) -> ([(usize, usize); 9], usize) {
        let span = |u: f64, r: f64| {
            let (a, b) = (u + r * t0, u + r * t1.min(1e300));
            (a.min(b), a.max(b))
        };
        let (xa, xb) = span(x, vx);
        let (ya, yb) = span(y, vy);
        let lo_x = self.x0 + ci as f64 * self.d;
        let lo_y = self.y0 + cj as f64 * self.d;
        let dx: &[isize] = match (
            ci > 0 && xa <= lo_x + tol,
            ci + 1 < self.ncx && xb >= lo_x + self.d - tol,
        ) {
            (true, true) => &[0, -1, 1],
            (true, false) => &[0, -1],
            (false, true) => &[0, 1],
            _ => &[0],
        };
        let dy: &[isize] = match (
            cj > 0 && ya <= lo_y + tol,
            cj + 1 < self.ncy && yb >= lo_y + self.d - tol,
        ) {
            (true, true) => &[0, -1, 1],
            (true, false) => &[0, -1],
            (false, true) => &[0, 1],
            _ => &[0],
        };
        let mut out = [(ci, cj); 9];
        let mut n = 0;
        for &oy in dy {
            for &ox in dx {
                out[n] = ((ci as isize + ox) as usize, (cj as isize + oy) as usize);
                n += 1;
            }
        }
        (out, n)
    }

    /// Walks the cells crossed by (x, y) + (vx, vy) t for t in [0, t_max]; `visit(ci, cj, t0, t1)`
    /// returns a hit inside the cell's time window or None to go on.
    fn walk(
        &self,
        x: f64,
        y: f64,
        vx: f64,
        vy: f64,
        t_max: f64,
        mut visit: impl FnMut(usize, usize, f64, f64) -> Option<(f64, Facet)>,
    ) -> FlightEnd {
        let ux = (x - self.x0) / self.d;
        let uy = (y - self.y0) / self.d;
        let rx = vx / self.d;
        let ry = vy / self.d;
        let (Some(mut ci), Some(mut cj)) = (
            Self::axis_cell(ux, rx, self.ncx),
            Self::axis_cell(uy, ry, self.ncy),
        ) else {
            return FlightEnd::Leaves { t: 0.0 };
        };
        let mut t0 = 0.0_f64;
        loop {
            let tx = if rx > 0.0 {
                ((ci + 1) as f64 - ux) / rx
            } else if rx < 0.0 {
                (ci as f64 - ux) / rx
            } else {
                f64::INFINITY
            };
            let ty = if ry > 0.0 {
                ((cj + 1) as f64 - uy) / ry
            } else if ry < 0.0 {
                (cj as f64 - uy) / ry
            } else {
                f64::INFINITY
            };
            let t1 = tx.min(ty).max(t0);
            if let Some((t, f)) = visit(ci, cj, t0, t1.min(t_max)) {
                return FlightEnd::Hit { t, facet: f };
            }
            if t1 >= t_max {
                return FlightEnd::Clear;
            }
            // step to the next cell (both axes when the line passes a corner)
            if tx <= ty {
                if rx > 0.0 {
                    ci += 1;
                    if ci >= self.ncx {
                        return FlightEnd::Leaves { t: t1 };
                    }
                } else {
                    if ci == 0 {
                        return FlightEnd::Leaves { t: t1 };
                    }
                    ci -= 1;
                }
            }
            if ty <= tx {
                if ry > 0.0 {
                    cj += 1;
                    if cj >= self.ncy {
                        return FlightEnd::Leaves { t: t1 };
                    }
                } else {
                    if cj == 0 {
                        return FlightEnd::Leaves { t: t1 };
                    }
                    cj -= 1;
                }
            }
            t0 = t1;
        }
    }
}

/// Regular height grid: heights[i][j] is z at (x₀ + j d, y₀ + i d); each cell is split along
/// its (j, i)–(j+1, i+1) diagonal into two triangles.
#[derive(Debug, Clone)]
pub(crate) struct GridFloor {
    cells: CellGrid,
    nx: usize,
    z: Vec<f64>,
    /// The facets' planes, precomputed unless there are more than [`MAX_TABLED_FACETS`].
    planes: Vec<FacetPlane>,
    /// Facets removed because a corner had no data (empty: none removed).
    holes: Vec<bool>,
    /// Per cell (row-major), the index in `patches` of the coplanar patch holding it, or
    /// [`NONE`]; empty when the planes are not tabled.
    patch: Vec<u32>,
    /// Rectangles of cells whose facets all have one slope ([`Patch`]).
    patches: Vec<Patch>,
}

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
struct Patch {
    ci: [usize; 2],
    cj: [usize; 2],
}

/// Triangulated contour set with a bucket grid for point and line queries.
#[derive(Debug, Clone)]
pub(crate) struct MeshFloor {
    xyz: Vec<[f64; 3]>,
    tris: Vec<[u32; 3]>,
    nbr: Vec<[u32; 3]>,
    cells: CellGrid,
    bucket_start: Vec<u32>,
    bucket_items: Vec<u32>,
    bbox: [f64; 4],
    /// The facets' planes, precomputed unless there are more than [`MAX_TABLED_FACETS`].
    planes: Vec<FacetPlane>,
    /// Facets removed because a corner had no data (empty: none removed).
    holes: Vec<bool>,
}

const NONE: u32 = u32::MAX;

/// A floor of the face.
#[derive(Debug, Clone)]
pub(crate) enum FloorKind {
    /// The plane z = −x tan θ.
    Plane(FacetPlane),
    /// A regular height grid.
    Grid(GridFloor),
    /// Delaunay-triangulated contours.
    Mesh(MeshFloor),
}

/// A floor with its mean plane.
#[derive(Debug, Clone)]
pub(crate) struct Floor {
    /// The facets.
    pub(crate) kind: FloorKind,
    /// Mean plane for `along_dip_m` and the energy zero.
    pub(crate) mean: MeanPlane,
}

#[inline]
pub(crate) fn inside_tri(c: &[[f64; 2]; 3], x: f64, y: f64, tol: f64) -> bool {
    (0..3).all(|k| {
        let a = c[k];
        let b = c[(k + 1) % 3];
        let (ex, ey) = (b[0] - a[0], b[1] - a[1]);
        // axis-parallel edges (every edge of a grid cell but its diagonal) need no square root
        let len = if ey == 0.0 {
            ex.abs()
        } else if ex == 0.0 {
            ey.abs()
        } else {
            (ex * ex + ey * ey).sqrt()
        };
        // outward normal of a ccw edge is (ey, −ex)
        (ey * (x - a[0]) - ex * (y - a[1])) <= tol * len
    })
}

fn plane_of(c: &[[f64; 2]; 3], z: &[f64; 3]) -> FacetPlane {
    let (ax, ay) = (c[1][0] - c[0][0], c[1][1] - c[0][1]);
    let (bx, by) = (c[2][0] - c[0][0], c[2][1] - c[0][1]);
    let (az, bz) = (z[1] - z[0], z[2] - z[0]);
    let det = ax * by - ay * bx;
    FacetPlane::new(
        c[0][0],
        c[0][1],
        z[0],
        (az * by - bz * ay) / det,
        (ax * bz - bx * az) / det,
    )
}

impl GridFloor {
    /// Row i and column j of facet f's cell.
    #[inline]
    fn cell_of(&self, f: Facet) -> (usize, usize) {
        // facet ids are u32, so the cell index and the row length fit u32 (a cheaper division)
        let cell = f >> 1;
        let ncx = self.cells.ncx as u32;
        ((cell / ncx) as usize, (cell % ncx) as usize)
    }

    #[inline]
    fn corners(&self, f: Facet) -> ([[f64; 2]; 3], [f64; 3]) {
        let (i, j) = self.cell_of(f);
        self.corners_at(f, i, j)
    }

    #[inline]
    fn corners_at(&self, f: Facet, i: usize, j: usize) -> ([[f64; 2]; 3], [f64; 3]) {
        let d = self.cells.d;
        let x = self.cells.x0 + j as f64 * d;
        let y = self.cells.y0 + i as f64 * d;
        let (xe, ye) = (
            self.cells.x0 + (j + 1) as f64 * d,
            self.cells.y0 + (i + 1) as f64 * d,
        );
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

    #[inline]
    fn plane(&self, f: Facet) -> FacetPlane {
        match self.planes.get(f as usize) {
            Some(p) => *p,
            None => self.plane_of(f),
        }
    }

    fn plane_of(&self, f: Facet) -> FacetPlane {
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
            self.cells.x0 + j as f64 * d,
            self.cells.y0 + i as f64 * d,
            z00,
            bx,
            by,
        )
    }

    #[inline]
    fn facet(&self, ci: usize, cj: usize, half: u32) -> Facet {
        (((cj * (self.nx - 1) + ci) as u32) << 1) | half
    }

    #[inline]
    fn neighbor_at(&self, f: Facet, i: usize, j: usize, edge: usize) -> Option<Facet> {
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
    fn find_patches(&mut self) {
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
    fn patch_of(&self, f: Facet) -> Option<&Patch> {
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
        let xs = [c.x0 + pa.ci[0] as f64 * c.d, c.x0 + pa.ci[1] as f64 * c.d];
        let ys = [c.y0 + pa.cj[0] as f64 * c.d, c.y0 + pa.cj[1] as f64 * c.d];
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
    fn patch_flight(
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
            x > c.x0 + pa.ci[0] as f64 * c.d + hair
                && x < c.x0 + pa.ci[1] as f64 * c.d - hair
                && y > c.y0 + pa.cj[0] as f64 * c.d + hair
                && y < c.y0 + pa.cj[1] as f64 * c.d - hair
        };
        if !(inside(p.x, p.y) && inside(qx, qy)) {
            return None;
        }
        let qi = CellGrid::axis_cell((qx - c.x0) / c.d, v.x, c.ncx)?;
        let qj = CellGrid::axis_cell((qy - c.y0) / c.d, v.y, c.ncy)?;
        let (fx, fy) = ((qx - c.x0) / c.d - qi as f64, (qy - c.y0) / c.d - qj as f64);
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

impl MeshFloor {
    #[inline]
    fn plane(&self, f: Facet) -> FacetPlane {
        match self.planes.get(f as usize) {
            Some(p) => *p,
            None => {
                let (c, z) = self.corners(f);
                plane_of(&c, &z)
            }
        }
    }

    #[inline]
    fn corners(&self, f: Facet) -> ([[f64; 2]; 3], [f64; 3]) {
        let t = self.tris[f as usize];
        let p = t.map(|k| self.xyz[k as usize]);
        (p.map(|q| [q[0], q[1]]), p.map(|q| q[2]))
    }

    fn bucket(&self, ci: usize, cj: usize) -> &[u32] {
        let b = cj * self.cells.ncx + ci;
        &self.bucket_items[self.bucket_start[b] as usize..self.bucket_start[b + 1] as usize]
    }
}

impl MeshFloor {
    /// A mesh from its vertices, counter-clockwise triangles, their neighbours across edge k
    /// (corner k to k + 1; [`NONE`] on the boundary) and removed facets (empty: none), with the
    /// bucket grid for point and line queries.
    fn new(xyz: Vec<[f64; 3]>, tris: Vec<[u32; 3]>, nbr: Vec<[u32; 3]>, holes: Vec<bool>) -> Self {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in &xyz {
            for a in 0..2 {
                lo[a] = lo[a].min(p[a]);
                hi[a] = hi[a].max(p[a]);
            }
        }
        let (w, h) = (hi[0] - lo[0], hi[1] - lo[1]);
        let mut d = ((w * h) / tris.len() as f64).sqrt() * 1.5;
        if d.is_nan() || d <= 0.0 {
            d = w.max(h);
        }
        d = d.max(w.max(h) / 4096.0);
        let ncx = ((w / d).ceil() as usize).max(1);
        let ncy = ((h / d).ceil() as usize).max(1);
        let cells = CellGrid {
            x0: lo[0],
            y0: lo[1],
            d,
            ncx,
            ncy,
        };
        let mut counts = vec![0u32; ncx * ncy + 1];
        let range = |t: &[u32; 3]| {
            let (mut a, mut b) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
            for &k in t {
                for q in 0..2 {
                    a[q] = a[q].min(xyz[k as usize][q]);
                    b[q] = b[q].max(xyz[k as usize][q]);
                }
            }
            let c = |v: f64, o: f64, n: usize| (((v - o) / d).floor().max(0.0) as usize).min(n - 1);
            (
                c(a[0], lo[0], ncx),
                c(b[0], lo[0], ncx),
                c(a[1], lo[1], ncy),
                c(b[1], lo[1], ncy),
            )
        };
        for t in &tris {
            let (i0, i1, j0, j1) = range(t);
            for j in j0..=j1 {
                for i in i0..=i1 {
                    counts[j * ncx + i + 1] += 1;
                }
            }
        }
        for k in 1..counts.len() {
            counts[k] += counts[k - 1];
        }
        let mut fill = counts.clone();
        let mut items = vec![0u32; counts[ncx * ncy] as usize];
        for (id, t) in tris.iter().enumerate() {
            let (i0, i1, j0, j1) = range(t);
            for j in j0..=j1 {
                for i in i0..=i1 {
                    let b = j * ncx + i;
                    items[fill[b] as usize] = id as u32;
                    fill[b] += 1;
                }
            }
        }
        let mut mesh = MeshFloor {
            xyz,
            tris,
            nbr,
            cells,
            bucket_start: counts,
            bucket_items: items,
            bbox: [lo[0], hi[0], lo[1], hi[1]],
            planes: Vec::new(),
            holes,
        };
        if mesh.tris.len() <= MAX_TABLED_FACETS {
            mesh.planes = (0..mesh.tris.len() as Facet)
                .map(|f| {
                    let (c, z) = mesh.corners(f);
                    plane_of(&c, &z)
                })
                .collect();
        }
        mesh
    }
}

/// Placement of a floor given in map coordinates (easting E, northing N, m) on the face: the
/// face's origin is at `origin` and its x axis (down the dip) points at azimuth
/// `dip_direction_deg` (clockwise from north); y is x turned 90° anticlockwise seen from above.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MapFrame {
    /// Map coordinates [E, N] of the face's origin, m.
    pub origin: [f64; 2],
    /// Azimuth of the face's down-dip x axis, degrees clockwise from north, in [0, 360).
    pub dip_direction_deg: f64,
}

impl MapFrame {
    /// Face coordinates [x, y] (m) of the map point [E, N] (m).
    #[must_use]
    pub fn to_face(&self, p: [f64; 2]) -> [f64; 2] {
        let (de, dn) = (p[0] - self.origin[0], p[1] - self.origin[1]);
        if self.dip_direction_deg == 90.0 {
            return [de, dn];
        }
        let (s, c) = self.dip_direction_deg.to_radians().sin_cos();
        [de * s + dn * c, dn * s - de * c]
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

impl GridFloor {
    /// The same triangles (ids, corners, neighbours, holes) as a mesh, its nodes moved from map
    /// coordinates relative to the map origin into the face frame.
    fn to_mesh(&self, map: &MapFrame) -> MeshFloor {
        let ny = self.cells.ncy + 1;
        let rel = MapFrame {
            origin: [0.0, 0.0],
            dip_direction_deg: map.dip_direction_deg,
        };
        let mut xyz = Vec::with_capacity(self.nx * ny);
        for i in 0..ny {
            for j in 0..self.nx {
                let p = rel.to_face([
                    self.cells.x0 + j as f64 * self.cells.d,
                    self.cells.y0 + i as f64 * self.cells.d,
                ]);
                xyz.push([p[0], p[1], self.z[i * self.nx + j]]);
            }
        }
        let n_facets = 2 * self.cells.ncx * self.cells.ncy;
        let mut tris = Vec::with_capacity(n_facets);
        let mut nbr = Vec::with_capacity(n_facets);
        for f in 0..n_facets as Facet {
            let (i, j) = self.cell_of(f);
            let id = |di: usize, dj: usize| ((i + di) * self.nx + j + dj) as u32;
            tris.push(if f & 1 == 0 {
                [id(0, 0), id(0, 1), id(1, 1)]
            } else {
                [id(0, 0), id(1, 1), id(1, 0)]
            });
            nbr.push([0, 1, 2].map(|k| self.neighbor_at(f, i, j, k).unwrap_or(NONE)));
        }
        MeshFloor::new(xyz, tris, nbr, self.holes.clone())
    }
}

/// A contour line: an elevation and a polyline in plan.
#[derive(Debug, Clone, PartialEq)]
pub struct ContourLine {
    /// Elevation z of the line, m.
    pub elevation: f64,
    /// Plan points [x, y] of the polyline, m.
    pub points: Vec<[f64; 2]>,
}

/// Bound on the memory a contour floor takes while it is built and used, bytes per resampled
/// point: the triangulation's vertices, half-edges and faces (about 2 triangles per point), the
/// facet table (two 64-byte planes per point), the neighbour and bucket arrays; measured peak
/// 1e5–1e6 points: see README "Limits".
pub const CONTOUR_BYTES_PER_POINT: f64 = 512.0;

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

/// Number of points a contour set resampled at most `resolution` m apart will have, computed
/// before resampling (as f64, so that no count overflows): the figure the memory limit is
/// checked against.
#[must_use]
pub fn contour_points(lines: &[ContourLine], resolution: f64) -> f64 {
    let mut n = 0.0;
    for line in lines {
        n += line.points.len() as f64;
        for w in line.points.windows(2) {
            // the resampling's own arithmetic (Floor::contours)
            let len = ((w[1][0] - w[0][0]).powi(2) + (w[1][1] - w[0][1]).powi(2)).sqrt();
            let k = (len / resolution).ceil().max(1.0);
            n += k - 1.0;
        }
    }
    n
}

struct HPoint {
    x: f64,
    y: f64,
    z: f64,
}

impl HasPosition for HPoint {
    type Scalar = f64;
    fn position(&self) -> Point2<f64> {
        Point2::new(self.x, self.y)
    }
}

impl Floor {
    /// The plane z = −x tan θ.
    pub(crate) fn plane(dip: f64) -> Self {
        let (sin, cos) = dip.sin_cos();
        Floor {
            kind: FloorKind::Plane(FacetPlane::new(0.0, 0.0, 0.0, -sin / cos, 0.0)),
            mean: MeanPlane {
                x0: 0.0,
                z_ref: 0.0,
                cos,
                sin,
            },
        }
    }

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

    /// A grid given in map coordinates (origin (E₀, N₀) of the grid, spacing, heights with NaN
    /// for nodes without data) placed in the face frame of `map`: a rigid transform of its nodes.
    /// A dip direction of exactly 90° (east) keeps it a grid; any other turns it into a
    /// triangle mesh with the same triangles. The mean plane passes through the floor's height
    /// at the map origin, where `along_dip` is 0.
    pub(crate) fn grid_in_map(
        dip: f64,
        origin: [f64; 2],
        spacing: f64,
        heights: &[Vec<f64>],
        map: &MapFrame,
    ) -> PhysicsResult<Self> {
        let rel = [origin[0] - map.origin[0], origin[1] - map.origin[1]];
        let mut floor = Floor::grid(dip, rel, spacing, heights)?;
        if map.dip_direction_deg != 90.0 {
            let FloorKind::Grid(g) = &floor.kind else {
                unreachable!("Floor::grid builds a grid")
            };
            floor.kind = FloorKind::Mesh(g.to_mesh(map));
        }
        floor.place_mean_at_origin()?;
        Ok(floor)
    }

    /// Contours given in map coordinates placed in the face frame of `map` (a rigid transform
    /// of their points, then [`Floor::contours`]); the mean plane passes through the floor's
    /// height at the map origin.
    pub(crate) fn contours_in_map(
        dip: f64,
        lines: &[ContourLine],
        resolution: f64,
        map: &MapFrame,
    ) -> PhysicsResult<Self> {
        let moved: Vec<ContourLine> = lines
            .iter()
            .map(|l| ContourLine {
                elevation: l.elevation,
                points: l.points.iter().map(|p| map.to_face(*p)).collect(),
            })
            .collect();
        let mut floor = Floor::contours(dip, &moved, resolution)?;
        floor.place_mean_at_origin()?;
        Ok(floor)
    }

    /// Puts `along_dip` = 0 at (0, 0), the mean plane through the floor's height there.
    fn place_mean_at_origin(&mut self) -> PhysicsResult<()> {
        let z = self.height_at(0.0, 0.0).ok_or_else(|| {
            PhysicsError::invalid(
                Param::FloorMapOrigin,
                0.0,
                "the map origin is not on the floor (outside it or over a hole): along_dip_m = 0 \
                 is measured from the floor's height there",
            )
        })?;
        self.mean.x0 = 0.0;
        self.mean.z_ref = z;
        Ok(())
    }

    /// Contours resampled at most `resolution` apart and Delaunay-triangulated; the mean plane
    /// starts at the smallest x of all points, at the height of that point.
    pub(crate) fn contours(
        dip: f64,
        lines: &[ContourLine],
        resolution: f64,
    ) -> PhysicsResult<Self> {
        let mut pts: Vec<HPoint> = Vec::new();
        for (c, line) in lines.iter().enumerate() {
            for (k, p) in line.points.iter().enumerate() {
                if !(p[0].is_finite() && p[1].is_finite()) {
                    return Err(PhysicsError::invalid(
                        Param::FloorContourPoint(c, k),
                        0.0,
                        "points must be finite numbers (m)",
                    ));
                }
                if k > 0 {
                    let q = line.points[k - 1];
                    let len = ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)).sqrt();
                    let n = (len / resolution).ceil().max(1.0) as usize;
                    for s in 1..n {
                        let f = s as f64 / n as f64;
                        pts.push(HPoint {
                            x: q[0] + f * (p[0] - q[0]),
                            y: q[1] + f * (p[1] - q[1]),
                            z: line.elevation,
                        });
                    }
                }
                pts.push(HPoint {
                    x: p[0],
                    y: p[1],
                    z: line.elevation,
                });
            }
        }
        if pts.len() > 50_000_000 {
            return Err(PhysicsError::invalid(
                Param::FloorResolution,
                resolution,
                "the resampled contours have more than 5e7 points: use a coarser resolution_m",
            ));
        }
        let (mut x_min, mut z_at_min) = (f64::INFINITY, 0.0);
        for p in &pts {
            if p.x < x_min {
                x_min = p.x;
                z_at_min = p.z;
            }
        }
        let tri: DelaunayTriangulation<HPoint> =
            DelaunayTriangulation::bulk_load(pts).map_err(|e| {
                PhysicsError::invalid(
                    Param::FloorContours,
                    0.0,
                    format!("cannot triangulate: {e}"),
                )
            })?;
        let n_all = tri.num_all_faces();
        let mut xyz = Vec::with_capacity(tri.num_vertices());
        for v in tri.vertices() {
            let d = v.data();
            xyz.push([d.x, d.y, d.z]);
        }
        // face index k ≥ 1 (0 is the outer face) → facet k − 1
        let mut tris = vec![[0u32; 3]; n_all.saturating_sub(1)];
        let mut nbr = vec![[NONE; 3]; n_all.saturating_sub(1)];
        for f in tri.inner_faces() {
            let id = f.fix().index() - 1;
            let vs = f.vertices();
            tris[id] = vs.map(|v| v.fix().index() as u32);
            let es = f.adjacent_edges();
            for k in 0..3 {
                nbr[id][k] = es[k]
                    .rev()
                    .face()
                    .as_inner()
                    .map_or(NONE, |g| (g.fix().index() - 1) as u32);
            }
        }
        if tris.is_empty() {
            return Err(PhysicsError::invalid(
                Param::FloorContours,
                xyz.len() as f64,
                "the contours do not span a surface (need at least 3 points not on one line)",
            ));
        }
        let (sin, cos) = dip.sin_cos();
        Ok(Floor {
            kind: FloorKind::Mesh(MeshFloor::new(xyz, tris, nbr, Vec::new())),
            mean: MeanPlane {
                x0: x_min,
                z_ref: z_at_min,
                cos,
                sin,
            },
        })
    }

    /// The facet's plane.
    #[inline]
    pub(crate) fn facet_plane(&self, f: Facet) -> FacetPlane {
        match &self.kind {
            FloorKind::Plane(p) => *p,
            FloorKind::Grid(g) => g.plane(f),
            FloorKind::Mesh(m) => m.plane(f),
        }
    }

    /// Plan extent [x_min, x_max, y_min, y_max] (infinite for the plane), m.
    pub(crate) fn extent(&self) -> [f64; 4] {
        match &self.kind {
            FloorKind::Plane(_) => [
                f64::NEG_INFINITY,
                f64::INFINITY,
                f64::NEG_INFINITY,
                f64::INFINITY,
            ],
            FloorKind::Grid(GridFloor { cells, .. }) => {
                [cells.x0, cells.x_max(), cells.y0, cells.y_max()]
            }
            FloorKind::Mesh(m) => m.bbox,
        }
    }

    /// Plan corners [x, y] (m, counter-clockwise) and heights z (m) of facet f; None for the
    /// plane, which has no corners.
    pub(crate) fn facet_corners(&self, f: Facet) -> Option<([[f64; 2]; 3], [f64; 3])> {
        match &self.kind {
            FloorKind::Plane(_) => None,
            FloorKind::Grid(g) => Some(g.corners(f)),
            FloorKind::Mesh(m) => Some(m.corners(f)),
        }
    }

    /// Length scale of the floor's facets (grid spacing or bucket cell), m; 1 for the plane.
    pub(crate) fn cell_size(&self) -> f64 {
        match &self.kind {
            FloorKind::Plane(_) => 1.0,
            FloorKind::Grid(g) => g.cells.d,
            FloorKind::Mesh(m) => m.cells.d,
        }
    }

    /// Height of the floor under (x, y), m, or None off the floor.
    pub(crate) fn height_at(&self, x: f64, y: f64) -> Option<f64> {
        self.locate(x, y, 0.0, 0.0)
            .map(|f| self.facet_plane(f).z(x, y))
    }

    /// Highest plane, m, at (x, y) among the facets (holes excepted) whose closed triangle comes
    /// within `tol` m of it in plan; None when there is none. At a node or on an edge this is
    /// the highest of the planes meeting there: a point at that height is on or above every
    /// facet a flight from it can strike, so none is missed from underneath.
    pub(crate) fn top_height_near(&self, x: f64, y: f64, tol: f64) -> Option<f64> {
        let mut top: Option<f64> = None;
        let mut take = |f: Facet, c: &[[f64; 2]; 3]| {
            if !self.is_hole(f) && inside_tri(c, x, y, tol) {
                let z = self.facet_plane(f).z(x, y);
                top = Some(top.map_or(z, |t: f64| t.max(z)));
            }
        };
        match &self.kind {
            FloorKind::Plane(p) => return Some(p.z(x, y)),
            FloorKind::Grid(g) => {
                let c = &g.cells;
                let ux = (x - c.x0) / c.d;
                let uy = (y - c.y0) / c.d;
                let (Some(ci), Some(cj)) = (
                    CellGrid::axis_cell(ux, 0.0, c.ncx),
                    CellGrid::axis_cell(uy, 0.0, c.ncy),
                ) else {
                    return None;
                };
                // only the cells whose closed triangles can come within tol of (x, y): a
                // triangle of the column left of ci lies at x ≤ x₀ + ci d, and inside_tri
                // refuses a point farther than (1 + √2) tol beyond it (the same holds for the
                // other sides), so the cells skipped here are those it would refuse
                let margin = 4.0 * tol;
                // the cells along one axis: cell k, and a neighbour only within the margin
                let span = |u: f64, origin: f64, k: usize, n: usize| {
                    let (lo, hi) = (origin + k as f64 * c.d, origin + (k + 1) as f64 * c.d);
                    let first = if u - lo > margin {
                        k
                    } else {
                        k.saturating_sub(1)
                    };
                    let last = if hi - u > margin {
                        k
                    } else {
                        (k + 1).min(n - 1)
                    };
                    (first, last)
                };
                let (i0, i1) = span(x, c.x0, ci, c.ncx);
                let (j0, j1) = span(y, c.y0, cj, c.ncy);
                for nj in j0..=j1 {
                    for ni in i0..=i1 {
                        for half in 0..2 {
                            let f = g.facet(ni, nj, half);
                            take(f, &g.corners_at(f, nj, ni).0);
                        }
                    }
                }
            }
            FloorKind::Mesh(m) => {
                let c = &m.cells;
                let ci = CellGrid::axis_cell((x - c.x0) / c.d, 0.0, c.ncx)?;
                let cj = CellGrid::axis_cell((y - c.y0) / c.d, 0.0, c.ncy)?;
                for &f in m.bucket(ci, cj) {
                    take(f, &m.corners(f).0);
                }
            }
        }
        top
    }

    /// Whether facet f was removed (a corner without data): not part of the floor.
    #[inline]
    pub(crate) fn is_hole(&self, f: Facet) -> bool {
        let holes = match &self.kind {
            FloorKind::Plane(_) => return false,
            FloorKind::Grid(g) => &g.holes,
            FloorKind::Mesh(m) => &m.holes,
        };
        holes.get(f as usize).copied().unwrap_or(false)
    }

    /// The facet under (x, y), preferring the one the direction (dx, dy) moves into; None off
    /// the floor or over a hole.
    pub(crate) fn locate(&self, x: f64, y: f64, dx: f64, dy: f64) -> Option<Facet> {
        self.locate_any(x, y, dx, dy).filter(|&f| !self.is_hole(f))
    }

    /// The facet (hole or not) under (x, y), preferring the one (dx, dy) moves into.
    fn locate_any(&self, x: f64, y: f64, dx: f64, dy: f64) -> Option<Facet> {
        match &self.kind {
            FloorKind::Plane(_) => Some(0),
            FloorKind::Grid(g) => {
                let c = &g.cells;
                let ux = (x - c.x0) / c.d;
                let uy = (y - c.y0) / c.d;
                let ci = CellGrid::axis_cell(ux, dx, c.ncx)?;
                let cj = CellGrid::axis_cell(uy, dy, c.ncy)?;
                let (fx, fy) = (ux - ci as f64, uy - cj as f64);
                let half = if fx > fy || (fx == fy && dx > dy) {
                    0
                } else {
                    1
                };
                Some(g.facet(ci, cj, half))
            }
            FloorKind::Mesh(m) => {
                let c = &m.cells;
                let ci = CellGrid::axis_cell((x - c.x0) / c.d, dx, c.ncx)?;
                let cj = CellGrid::axis_cell((y - c.y0) / c.d, dy, c.ncy)?;
                let eps = 1e-9 * c.d;
                let n = (dx * dx + dy * dy).sqrt();
                let (qx, qy) = if n > 0.0 {
                    (x + eps * dx / n, y + eps * dy / n)
                } else {
                    (x, y)
                };
                let cand = m.bucket(ci, cj);
                for tol in [0.0, 1e-9 * c.d] {
                    for &f in cand {
                        if inside_tri(&m.corners(f).0, qx, qy, tol) {
                            return Some(f);
                        }
                    }
                }
                for &f in cand {
                    if inside_tri(&m.corners(f).0, x, y, 1e-9 * c.d) {
                        return Some(f);
                    }
                }
                None
            }
        }
    }

    /// First strike of the parabola p + v t + ½ (0, 0, −g) t² on the floor within t ≤ t_max.
    /// A strike on a hole's facet (its height filled in from the data around it) is a landing
    /// in the hole: the rock leaves the floor there ([`FlightEnd::Leaves`]); a flight passing
    /// over a hole above that surface goes on.
    pub(crate) fn flight(
        &self,
        p: &Vector3<f64>,
        v: &Vector3<f64>,
        g: f64,
        t_max: f64,
    ) -> FlightEnd {
        match self.flight_any(p, v, g, t_max) {
            FlightEnd::Hit { t, facet } if self.is_hole(facet) => FlightEnd::Leaves { t },
            e => e,
        }
    }

    fn flight_any(&self, p: &Vector3<f64>, v: &Vector3<f64>, g: f64, t_max: f64) -> FlightEnd {
        // rounding of the start point's height against a facet's plane (a few ulps of its
        // coordinates), far below the invariant's 1e-9 tolerance
        let h_round = 1e-12 * (1.0 + p.x.abs().max(p.y.abs()).max(p.z.abs()));
        let root = |pl: &FacetPlane| -> Option<(f64, bool)> {
            let h0 = pl.height(p);
            let b = pl.height_rate(v);
            let r = descent_root(h0, b, g)?;
            // a strike: the height decreases through zero (not a graze at the start)
            let slope = b - g * r;
            // A start on the plane (to rounding) not moving away from it is a strike now, if the
            // motion goes on over the facet (checked a little ahead, see `ahead`): a rock at rest
            // on a facet grazes it at t = 0 (h = −g t²/2), and a start a rounding error below
            // the plane, sinking further, has its root h0/|b| in the past, which is long for a
            // slow rock (a rock bounced off a node at 6 mm/s into a steeper facet 9e-16 m below
            // the node's height had its root 3.6e-12 s back: refused as past, it fell through).
            if slope >= -1e-12 * (1.0 + b.abs()) {
                return (h0.abs() <= h_round && b <= 1e-12).then_some((0.0, true));
            }
            if r < -1e-12 && h0 >= -h_round {
                return Some((0.0, true));
            }
            Some((r, false))
        };
        // where a strike at the start is tested against a facet: a step of 1e-6 of a cell
        // along the horizontal motion (on the start point itself when there is none), so that a
        // rock leaving a facet across its edge does not strike it again
        let ahead = |d: f64| -> (f64, f64) {
            let hv = v.x.hypot(v.y);
            if hv > 0.0 {
                (p.x + 1e-6 * d * v.x / hv, p.y + 1e-6 * d * v.y / hv)
            } else {
                (p.x, p.y)
            }
        };
        match &self.kind {
            FloorKind::Plane(pl) => match root(pl) {
                Some((t, _)) if t <= t_max => FlightEnd::Hit { t, facet: 0 },
                _ => FlightEnd::Clear,
            },
            // In each cell of the walk, the candidates are its facets and those of the cells
            // whose boundary the path runs within `near` of; a root counts when its point lies in
            // the facet (closed, with a rounding tolerance), not in the past and not after the cell's
            // window. A root before the window is a strike all the same (the window's start is formed
            // from a crossing time that is ill-conditioned when the path runs along a line), so
            // no strike can fall between two cells' windows.
            FloorKind::Grid(gr) => {
                if let Some(hit) = gr.patch_flight(p, v, g, t_max) {
                    return hit;
                }
                let tol = 1e-9 * gr.cells.d;
                let near = 1e-6 * gr.cells.d;
                let path = (p.x, p.y, v.x, v.y);
                gr.cells.walk(p.x, p.y, v.x, v.y, t_max, |ci, cj, t0, t1| {
                    let mut best: Option<(f64, Facet)> = None;
                    let (cells, n) = gr.cells.near_cells(ci, cj, path, t0, t1, near);
                    for &(ni, nj) in &cells[..n] {
                        for half in 0..2 {
                            let f = gr.facet(ni, nj, half);
                            let pl = gr.plane(f);
                            if let Some((r, now)) = root(&pl)
                                && r >= -1e-12
                                && r <= t1 + 1e-12 * (1.0 + t1)
                                && best.is_none_or(|b| r < b.0)
                            {
                                let (c, _) = gr.corners_at(f, nj, ni);
                                let (qx, qy) = if now {
                                    ahead(gr.cells.d)
                                } else {
                                    (p.x + v.x * r, p.y + v.y * r)
                                };
                                if inside_tri(&c, qx, qy, tol) {
                                    best = Some((r.max(0.0), f));
                                }
                            }
                        }
                    }
                    best
                })
            }
            FloorKind::Mesh(m) => {
                let tol = 1e-9 * m.cells.d;
                let near = 1e-6 * m.cells.d;
                let path = (p.x, p.y, v.x, v.y);
                m.cells.walk(p.x, p.y, v.x, v.y, t_max, |ci, cj, t0, t1| {
                    let mut best: Option<(f64, Facet)> = None;
                    let (cells, n) = m.cells.near_cells(ci, cj, path, t0, t1, near);
                    for &(ni, nj) in &cells[..n] {
                        for &f in m.bucket(ni, nj) {
                            let pl = m.plane(f);
                            if let Some((r, now)) = root(&pl)
                                && r >= -1e-12
                                && r <= t1 + 1e-12 * (1.0 + t1)
                                && best.is_none_or(|b| r < b.0)
                            {
                                let (qx, qy) = if now {
                                    ahead(m.cells.d)
                                } else {
                                    (p.x + v.x * r, p.y + v.y * r)
                                };
                                if inside_tri(&m.corners(f).0, qx, qy, tol) {
                                    best = Some((r.max(0.0), f));
                                }
                            }
                        }
                    }
                    best
                })
            }
        }
    }

    /// First exit of the planar motion p + v t + ½ a t² from facet f through one of its edges
    /// within t ≤ t_max: the time, the facet across that edge (None: off the floor) and the
    /// edge's end points in plan.
    #[inline]
    pub(crate) fn slide_exit(
        &self,
        f: Facet,
        p: &Vector3<f64>,
        v: &Vector3<f64>,
        a: &Vector3<f64>,
        t_max: f64,
    ) -> Option<(f64, Option<Facet>, [[f64; 2]; 2])> {
        let (corners, ij) = match &self.kind {
            FloorKind::Plane(_) => return None,
            FloorKind::Grid(g) => {
                let (i, j) = g.cell_of(f);
                (g.corners_at(f, i, j).0, (i, j))
            }
            FloorKind::Mesh(m) => (m.corners(f).0, (0, 0)),
        };
        let mut best: Option<(f64, usize)> = None;
        for k in 0..3 {
            let e0 = corners[k];
            let e1 = corners[(k + 1) % 3];
            let (sx, sy) = (e1[1] - e0[1], -(e1[0] - e0[0]));
            let f0 = sx * (p.x - e0[0]) + sy * (p.y - e0[1]);
            let f1 = sx * v.x + sy * v.y;
            let f2 = sx * a.x + sy * a.y;
            if let Some(t) = outward_root(f0, f1, f2)
                && t <= t_max
                && best.is_none_or(|b| t < b.0)
            {
                best = Some((t, k));
            }
        }
        best.map(|(t, k)| {
            let next = match &self.kind {
                FloorKind::Grid(g) => g.neighbor_at(f, ij.0, ij.1, k),
                FloorKind::Mesh(m) => {
                    let n = m.nbr[f as usize][k];
                    (n != NONE).then_some(n)
                }
                FloorKind::Plane(_) => None,
            };
            // a removed facet across the edge is no floor
            let next = next.filter(|&n| !self.is_hole(n));
            (t, next, [corners[k], corners[(k + 1) % 3]])
        })
    }
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

/// Smallest t ≥ 0 where f0 + f1 t + ½ f2 t² reaches 0 while increasing (leaving the half-plane
/// f ≤ 0); t = 0 when already on or past the line and moving out.
#[inline]
pub(crate) fn outward_root(f0: f64, f1: f64, f2: f64) -> Option<f64> {
    if f0 >= 0.0 && (f1 > 0.0 || (f1 == 0.0 && f2 > 0.0)) {
        return Some(0.0);
    }
    if f1 <= 0.0 && f2 <= 0.0 {
        // never increasing for t > 0: no outward crossing (saves the square root)
        return None;
    }
    if f2 == 0.0 {
        return (f1 > 0.0).then(|| (-f0 / f1).max(0.0));
    }
    let disc = f1 * f1 - 2.0 * f2 * f0;
    if disc < 0.0 {
        // never on the line: past it (f0 > 0) it stays past it, i.e. it is out from the start
        // (moving inwards a moment, then turned back out before reaching the line)
        return (f0 >= 0.0).then_some(0.0);
    }
    let s = disc.sqrt();
    let q = -(f1 + f1.signum() * s);
    let mut roots = [f64::NAN; 2];
    if q != 0.0 {
        roots = [q / f2, 2.0 * f0 / q];
    } else if f0 == 0.0 {
        roots = [0.0, 0.0];
    }
    roots
        .into_iter()
        .filter(|&r| r > 0.0 && f1 + f2 * r > 0.0)
        .fold(None, |acc: Option<f64>, r| {
            Some(acc.map_or(r, |b| b.min(r)))
        })
}

/// A floor triangle with its vertex ids (unique per floor) and corners, for block contacts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct FloorTriangle {
    /// The facet.
    pub(crate) facet: Facet,
    /// Floor-wide ids of the three corners.
    pub(crate) ids: [u32; 3],
    /// Corners [x, y, z], m, counter-clockwise seen from above.
    pub(crate) corners: [Vector3<f64>; 3],
}

impl Floor {
    /// Height (m) of the floor's level at a point (x, y) off the floor: over a hole, its facet's
    /// height filled in from the data around it (the surface a flight lands in the hole on);
    /// beyond a grid's extent, the plane of the facet at the nearest point of the extent,
    /// continued; None on the floor, and beyond a contour floor's extent.
    pub(crate) fn level_off_floor(&self, x: f64, y: f64) -> Option<f64> {
        if self.locate(x, y, 0.0, 0.0).is_some() {
            return None;
        }
        if let Some(f) = self.locate_any(x, y, 0.0, 0.0) {
            return Some(self.facet_plane(f).z(x, y));
        }
        let FloorKind::Grid(g) = &self.kind else {
            return None;
        };
        let c = &g.cells;
        let (xc, yc) = (x.clamp(c.x0, c.x_max()), y.clamp(c.y0, c.y_max()));
        let f = self.locate_any(xc, yc, 0.0, 0.0)?;
        Some(self.facet_plane(f).z(x, y))
    }

    /// Appends to `out` the triangles whose plan bounding boxes may overlap the plan box
    /// [x_min, x_max, y_min, y_max] (each once; nothing for the plane).
    pub(crate) fn triangles_in(&self, b: [f64; 4], out: &mut Vec<FloorTriangle>) {
        let range = |c: &CellGrid, lo: f64, hi: f64, d0: f64, n: usize| -> Option<(usize, usize)> {
            let a = ((lo - d0) / c.d).floor();
            let z = ((hi - d0) / c.d).floor();
            if z < 0.0 || a >= n as f64 {
                return None;
            }
            Some((a.max(0.0) as usize, (z as usize).min(n - 1)))
        };
        match &self.kind {
            FloorKind::Plane(_) => {}
            FloorKind::Grid(g) => {
                let c = &g.cells;
                let (Some((j0, j1)), Some((i0, i1))) = (
                    range(c, b[0], b[1], c.x0, c.ncx),
                    range(c, b[2], b[3], c.y0, c.ncy),
                ) else {
                    return;
                };
                for i in i0..=i1 {
                    for j in j0..=j1 {
                        for half in 0..2 {
                            let f = g.facet(j, i, half);
                            if g.holes.get(f as usize).copied().unwrap_or(false) {
                                continue;
                            }
                            let (cs, zs) = g.corners_at(f, i, j);
                            let id = |di: usize, dj: usize| ((i + di) * g.nx + j + dj) as u32;
                            let ids = if half == 0 {
                                [id(0, 0), id(0, 1), id(1, 1)]
                            } else {
                                [id(0, 0), id(1, 1), id(1, 0)]
                            };
                            out.push(FloorTriangle {
                                facet: f,
                                ids,
                                corners: [0, 1, 2].map(|k| Vector3::new(cs[k][0], cs[k][1], zs[k])),
                            });
                        }
                    }
                }
            }
            FloorKind::Mesh(m) => {
                let c = &m.cells;
                let (Some((j0, j1)), Some((i0, i1))) = (
                    range(c, b[0], b[1], c.x0, c.ncx),
                    range(c, b[2], b[3], c.y0, c.ncy),
                ) else {
                    return;
                };
                let start = out.len();
                for i in i0..=i1 {
                    for j in j0..=j1 {
                        for &f in m.bucket(j, i) {
                            if m.holes.get(f as usize).copied().unwrap_or(false) {
                                continue;
                            }
                            let t = m.tris[f as usize];
                            out.push(FloorTriangle {
                                facet: f,
                                ids: t,
                                corners: t.map(|k| {
                                    let q = m.xyz[k as usize];
                                    Vector3::new(q[0], q[1], q[2])
                                }),
                            });
                        }
                    }
                }
                out[start..].sort_by_key(|t| t.facet);
                let mut tail = out.split_off(start);
                tail.dedup_by_key(|t| t.facet);
                out.extend(tail);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn descent_root_is_the_flight_time() {
        // from the floor with vertical height rate b: 2b/g
        let r = descent_root(0.0, 3.0, 9.81).unwrap();
        assert!((r - 6.0 / 9.81).abs() < 1e-15);
        // dropped from h at rest: √(2h/g)
        let r = descent_root(3.27, 0.0, 9.81).unwrap();
        assert!((r - (2.0 * 3.27 / 9.81_f64).sqrt()).abs() < 1e-15);
        assert!(descent_root(-1.0, -1.0, 9.81).is_none());
    }

    #[test]
    fn outward_root_of_a_point_past_the_line_turning_back_out_is_zero() {
        // a rock a rounding step past an edge, moving inwards a moment, accelerated outwards:
        // it never reaches the line again, so it has left at t = 0 (was: no exit, and the rock
        // slid on the facet's plane beyond the facet, below the floor)
        assert_eq!(outward_root(9e-17, -5.4e-9, 2.78), Some(0.0));
        assert_eq!(outward_root(1.0, -1.0, 1.0), Some(0.0));
        // past the line, coming in and out again: f = 1 − t + 0.2 t² leaves at (1 + √0.2)/0.4
        let t = outward_root(1.0, -1.0, 0.4).unwrap();
        assert!((t - (1.0 + 0.2f64.sqrt()) / 0.4).abs() < 1e-12, "{t}");
    }

    #[test]
    fn outward_root_picks_the_leaving_crossing() {
        // f = −1 + 0 t + ½·2 t²: leaves at t = 1
        assert!((outward_root(-1.0, 0.0, 2.0).unwrap() - 1.0).abs() < 1e-15);
        // moving in and decelerating back out: f = −t + ½ t² … roots 0 (entering) and 2
        assert!((outward_root(0.0, -1.0, 1.0).unwrap() - 2.0).abs() < 1e-15);
        // moving in for ever
        assert!(outward_root(-1.0, -1.0, 0.0).is_none());
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
    fn a_slow_flight_starting_a_rounding_error_below_a_facet_strikes_it_at_once() {
        // the grid z = −x; the start 1e-15 m (rounding) below it, sinking 0.25 mm/s relative
        // to it: the root lies 4e-12 s in the past, a strike now, not a fall through the floor
        let h = vec![vec![0.0, -1.0, -2.0]; 3];
        let f = Floor::grid(0.7, [0.0, 0.0], 1.0, &h).unwrap();
        let p = Vector3::new(1.3, 0.6, -1.3 - 1e-15);
        let v = Vector3::new(0.0, 0.0, -2.5e-4);
        match f.flight(&p, &v, 9.81, 1.0) {
            FlightEnd::Hit { t, .. } => assert_eq!(t, 0.0),
            e => panic!("{e:?}"),
        }
        // clearly below (1e-6 m) is not a rounding error: no strike from underneath
        let p = Vector3::new(1.3, 0.6, -1.3 - 1e-6);
        assert!(!matches!(
            f.flight(&p, &v, 9.81, 1.0),
            FlightEnd::Hit { .. }
        ));
    }

    #[test]
    fn a_rock_at_rest_on_a_facet_strikes_it_at_once_and_one_leaving_it_does_not() {
        // a convex grid: z = −x up to x = 1, then z = 1 − 2x
        let h = vec![vec![0.0, -1.0, -3.0]; 3];
        let f = Floor::grid(0.7, [0.0, 0.0], 1.0, &h).unwrap();
        // at rest exactly on the floor (a graze at t = 0): a strike now, not a fall through it
        let p = Vector3::new(0.4, 0.3, -0.4);
        match f.flight(&p, &Vector3::zeros(), 9.81, 1.0) {
            FlightEnd::Hit { t, .. } => assert_eq!(t, 0.0),
            e => panic!("{e:?}"),
        }
        // taking off at the convex edge x = 1 along the upper facet: no strike on it at t = 0,
        // the landing is on the steeper facet beyond
        let p = Vector3::new(1.0, 0.3, -1.0);
        let v = Vector3::new(1.0, 0.0, -1.0);
        match f.flight(&p, &v, 9.81, 10.0) {
            FlightEnd::Hit { t, .. } => assert!(t > 0.05, "{t}"),
            e => panic!("{e:?}"),
        }
    }

    #[test]
    fn the_top_plane_near_a_valley_line_is_the_floor_beside_it() {
        // a V-shaped valley along x = 1: z = 1 − x, then z = x − 1
        let h = vec![vec![1.0, 0.0, 1.0]; 3];
        let f = Floor::grid(0.5, [0.0, 0.0], 1.0, &h).unwrap();
        // 1e-10 m past the valley line: the floor there is the rising facet's plane (+1e-10);
        // the facet left behind, extended, is 1e-10 below it
        let top = f.top_height_near(1.0 + 1e-10, 0.5, 2e-9).unwrap();
        assert!((top - 1e-10).abs() < 1e-16, "{top}");
        assert_eq!(f.height_at(1.0 + 1e-10, 0.5), Some(top));
        // away from every edge only the facet's own plane counts
        assert_eq!(f.top_height_near(0.5, 0.25, 2e-9), Some(0.5));
        // off the floor: none
        assert_eq!(f.top_height_near(-1.0, 0.5, 2e-9), None);
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
