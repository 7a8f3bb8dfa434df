//! The triangulated floor (TIN): vertices (m), counter-clockwise triangles with their
//! neighbours and a bucket grid for point and line queries; contour lines (elevation and plan
//! points, m), their resampling and Delaunay triangulation ([`Floor::contours`]) and the memory
//! estimate of a contour floor (bytes).

use spade::{DelaunayTriangulation, HasPosition, Point2, Triangulation};

use super::facet::{FacetPlane, plane_of};
use super::walk::CellGrid;
use super::{Facet, Floor, FloorKind, MAX_TABLED_FACETS, MeanPlane, NONE};
use crate::physics::error::{Param, PhysicsError, PhysicsResult};

/// Triangulated contour set with a bucket grid for point and line queries.
#[derive(Debug, Clone)]
pub(crate) struct MeshFloor {
    pub(super) xyz: Vec<[f64; 3]>,
    pub(super) tris: Vec<[u32; 3]>,
    pub(super) nbr: Vec<[u32; 3]>,
    pub(super) cells: CellGrid,
    bucket_start: Vec<u32>,
    bucket_items: Vec<u32>,
    pub(super) bbox: [f64; 4],
    /// The facets' planes, precomputed unless there are more than [`MAX_TABLED_FACETS`].
    planes: Vec<FacetPlane>,
    /// Facets removed because a corner had no data (empty: none removed).
    pub(super) holes: Vec<bool>,
}

impl MeshFloor {
    #[inline]
    pub(super) fn plane(&self, f: Facet) -> FacetPlane {
        match self.planes.get(f as usize) {
            Some(p) => *p,
            None => {
                let (c, z) = self.corners(f);
                plane_of(&c, &z)
            }
        }
    }

    #[inline]
    pub(super) fn corners(&self, f: Facet) -> ([[f64; 2]; 3], [f64; 3]) {
        let t = self.tris[f as usize];
        let p = t.map(|k| self.xyz[k as usize]);
        (p.map(|q| [q[0], q[1]]), p.map(|q| q[2]))
    }

    pub(super) fn bucket(&self, ci: usize, cj: usize) -> &[u32] {
        let b = cj * self.cells.ncx + ci;
        &self.bucket_items[self.bucket_start[b] as usize..self.bucket_start[b + 1] as usize]
    }
}

impl MeshFloor {
    /// A mesh from its vertices, counter-clockwise triangles, their neighbours across edge k
    /// (corner k to k + 1; [`NONE`] on the boundary) and removed facets (empty: none), with the
    /// bucket grid for point and line queries.
    pub(super) fn new(
        xyz: Vec<[f64; 3]>,
        tris: Vec<[u32; 3]>,
        nbr: Vec<[u32; 3]>,
        holes: Vec<bool>,
    ) -> Self {
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

/// A resampled contour point (m), placed in plan by the triangulation, carrying its height.
struct HPoint {
    x: f64,
    y: f64,
    z: f64,
    /// Index of its contour line.
    line: usize,
}

impl HasPosition for HPoint {
    type Scalar = f64;
    fn position(&self) -> Point2<f64> {
        Point2::new(self.x, self.y)
    }
}

impl Floor {
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
                            line: c,
                        });
                    }
                }
                pts.push(HPoint {
                    x: p[0],
                    y: p[1],
                    z: line.elevation,
                    line: c,
                });
            }
        }
        if pts.len() > 50_000_000 {
            return Err(PhysicsError::invalid(
                Param::FloorResolution,
                resolution,
                "the resampled contours have more than 5e7 points: use a coarser resampling resolution",
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
        let mut line_of = Vec::with_capacity(tri.num_vertices());
        for v in tri.vertices() {
            let d = v.data();
            xyz.push([d.x, d.y, d.z]);
            line_of.push(d.line);
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
        let holes = outside_the_contours(&tris, &nbr, &line_of);
        let (sin, cos) = dip.sin_cos();
        Ok(Floor {
            kind: FloorKind::Mesh(MeshFloor::new(xyz, tris, nbr, holes)),
            mean: MeanPlane {
                x0: x_min,
                z_ref: z_at_min,
                cos,
                sin,
            },
        })
    }
}

/// The triangles outside the contours' data, as removed facets (empty: none).
///
/// A Delaunay triangulation fills the convex hull of its points: beyond the outermost contours
/// (up the dip of the highest, down the dip of the lowest, in the bays of a curved contour on
/// the hull) it joins points of one contour line, so those triangles are level, a floor no data
/// give (released at the top of a 45° face, a rock landed on such a level apron and stayed
/// there). Every triangle whose three corners lie on one contour line and that is reached from
/// the hull's boundary through such triangles is removed: the floor there is beyond its edge.
/// Triangles of one line inside the data (at a contour's sharp bend between other lines) are
/// kept. Nothing is removed when that would remove every triangle.
fn outside_the_contours(tris: &[[u32; 3]], nbr: &[[u32; 3]], line_of: &[usize]) -> Vec<bool> {
    let one_line = |t: &[u32; 3]| {
        let l = line_of[t[0] as usize];
        t.iter().all(|&v| line_of[v as usize] == l)
    };
    let mut removed = vec![false; tris.len()];
    let mut stack: Vec<usize> = (0..tris.len())
        .filter(|&i| nbr[i].contains(&NONE) && one_line(&tris[i]))
        .collect();
    let mut any = false;
    while let Some(i) = stack.pop() {
        if removed[i] {
            continue;
        }
        removed[i] = true;
        any = true;
        for &j in &nbr[i] {
            if j != NONE && !removed[j as usize] && one_line(&tris[j as usize]) {
                stack.push(j as usize);
            }
        }
    }
    if !any || removed.iter().all(|&r| r) {
        return Vec::new();
    }
    removed
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A top contour bowed down the dip (an arc between (0, ±6) through (0.6, 0)) above a
    /// straight one: the triangulation joins the arc's points across its chord into level
    /// triangles at the top contour's elevation, beyond the data. They are removed: the point
    /// between the chord and the arc is off the floor, every remaining facet slopes, and the
    /// floor below the top contour is kept.
    #[test]
    fn no_level_apron_beyond_the_highest_contour() {
        let arc: Vec<[f64; 2]> = (0..=24)
            .map(|k| {
                let y = -6.0 + 0.5 * f64::from(k);
                [0.6 * (1.0 - (y / 6.0).powi(2)), y]
            })
            .collect();
        let lines = vec![
            ContourLine {
                elevation: 0.0,
                points: arc,
            },
            ContourLine {
                elevation: -3.0,
                points: vec![[3.0, -6.0], [3.0, 6.0]],
            },
        ];
        let floor = Floor::contours(45f64.to_radians(), &lines, 0.5).unwrap();
        // between the chord x = 0 and the arc, at y = 0: up the dip of the top contour
        assert!(floor.locate(0.3, 0.0, 0.0, 0.0).is_none());
        // below the top contour: floor, sloping
        let f = floor
            .locate(1.5, 0.0, 0.0, 0.0)
            .expect("floor below the top contour");
        assert!(floor.facet_plane(f).normal().z < 0.99);
        let FloorKind::Mesh(m) = &floor.kind else {
            panic!("a mesh")
        };
        assert!(m.holes.iter().any(|&h| h));
        for (i, t) in m.tris.iter().enumerate() {
            let level = t
                .iter()
                .all(|&v| m.xyz[v as usize][2] == m.xyz[t[0] as usize][2]);
            assert!(!level || m.holes[i], "level facet {i} kept: {t:?}");
        }
    }
}
