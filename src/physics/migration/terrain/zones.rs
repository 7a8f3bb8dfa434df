//! Floors of several materials (api.md `face.zones`): a map of integer codes over the floor, as
//! a code grid or as polygons (later polygons win where they overlap), each code naming a
//! [`Material`] with its own friction, restitution and rigid-block contact parameters.
//!
//! [`Zones`] is built once per case in the face frame: polygons (and a code grid's cell edges)
//! given in map coordinates are moved into it with the floor's [`MapFrame`]. A point's material
//! is one table look-up on a code grid and a bounding-box test plus a crossing-number test per
//! polygon otherwise. Materials with equal parameters form one class; the boundaries between
//! classes are kept as plan segments, so that a slide piece can be cut where it crosses one
//! ([`Zones::cut`]: the smallest outward root of a quadratic per segment, as a piece is cut at a
//! facet's edge). A map whose materials are all equal has no boundary, and a run on it is the
//! one-material run bit for bit.

use std::cell::Cell;

use super::map::MapFrame;
use super::slide::outward_root;
use crate::physics::error::{Param, PhysicsError, PhysicsResult};
use crate::physics::migration::monte_carlo::Distribution;

/// Largest number of materials of a zone map.
pub const MAX_MATERIALS: usize = 64;
/// Largest number of polygons of a zone map.
pub const MAX_POLYGONS: usize = 1000;
/// Largest number of vertices of all the polygons of a zone map together.
pub const MAX_POLYGON_VERTICES: usize = 10_000;
/// Largest number of cells of a code grid.
pub const MAX_CODE_CELLS: usize = 1 << 20;

/// The rigid block's contact parameters on one material (physics.md §C.3).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlockContact {
    /// Normal contact stiffness kₙ, N/m (linear law).
    pub normal_stiffness: f64,
    /// Shear contact stiffness kₛ, N/m (linear law).
    pub shear_stiffness: f64,
    /// Critical damping ratio β of the contact dashpot.
    pub critical_damping_ratio: f64,
    /// β drawn once per run in an ensemble (None: β for every run).
    pub critical_damping_ratio_distribution: Option<Distribution>,
    /// Coulomb friction μ of the block's contacts.
    pub friction_coefficient: f64,
    /// μ drawn once per run in an ensemble (None: μ for every run).
    pub friction_coefficient_distribution: Option<Distribution>,
}

/// One material of the floor: its code and its contact parameters, SI (dimensionless here).
#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    /// The integer code that marks it on the zone map.
    pub code: i64,
    /// A name for people (not used in the calculation).
    pub name: Option<String>,
    /// Coulomb friction μ of the lumped mass (single runs, and ensembles without a draw).
    pub friction_coefficient: f64,
    /// μ drawn once per run in an ensemble (None: μ for every run).
    pub friction_coefficient_distribution: Option<Distribution>,
    /// Normal restitution e_n of a single run.
    pub restitution_normal: f64,
    /// Tangential restitution e_t of a single run.
    pub restitution_tangential: f64,
    /// e_n drawn at every impact of an ensemble and clipped to [0, 1].
    pub restitution_normal_distribution: Distribution,
    /// e_t drawn at every impact of an ensemble, after e_n, and clipped to [0, 1].
    pub restitution_tangential_distribution: Distribution,
    /// The rigid block's contact parameters.
    pub block: BlockContact,
}

impl Material {
    /// Whether `other` has the same parameters (code and name aside).
    fn same_as(&self, other: &Material) -> bool {
        self.friction_coefficient == other.friction_coefficient
            && self.friction_coefficient_distribution == other.friction_coefficient_distribution
            && self.restitution_normal == other.restitution_normal
            && self.restitution_tangential == other.restitution_tangential
            && self.restitution_normal_distribution == other.restitution_normal_distribution
            && self.restitution_tangential_distribution == other.restitution_tangential_distribution
            && self.block == other.block
    }
}

/// One polygon of a zone map: its code and its vertices [x, y] (m, in the floor's frame; closed
/// implicitly, at least 3, not self-intersecting).
#[derive(Debug, Clone, PartialEq)]
pub struct ZonePolygon {
    /// The code inside it.
    pub code: i64,
    /// Its vertices [x, y], m.
    pub points: Vec<[f64; 2]>,
}

/// Where the codes are.
#[derive(Debug, Clone, PartialEq)]
pub enum ZoneShape {
    /// A grid of square cells (ESRI ASCII): `codes[i * ncols + j]` is the code of the cell
    /// centred at (x_center + j d, y_center + i d), row 0 the southernmost; None: no data.
    CodeGrid {
        /// x of the centre of column 0, m.
        x_center: f64,
        /// y of the centre of row 0, m.
        y_center: f64,
        /// Cell size d, m.
        cell: f64,
        /// Number of columns.
        ncols: usize,
        /// Number of rows.
        nrows: usize,
        /// Codes, row-major from the south.
        codes: Vec<Option<i64>>,
    },
    /// Polygons, later ones winning where they overlap.
    Polygons(Vec<ZonePolygon>),
}

/// A zone map as given: the shape in the floor's own frame (map coordinates when the floor has
/// a map frame), the code where the shape gives none, and the materials.
#[derive(Debug, Clone, PartialEq)]
pub struct ZonesSpec {
    /// The codes' shape.
    pub shape: ZoneShape,
    /// Code outside every polygon, on a cell without data and off the code grid.
    pub outside_code: i64,
    /// The materials, one per code, in the order given.
    pub materials: Vec<Material>,
}

/// A boundary segment between classes, in the face frame, with its plan box.
#[derive(Debug, Clone, PartialEq)]
struct Segment {
    q0: [f64; 2],
    q1: [f64; 2],
    bbox: [f64; 4],
}

/// A polygon in the face frame with its material and plan box.
#[derive(Debug, Clone, PartialEq)]
struct Poly {
    material: u16,
    points: Vec<[f64; 2]>,
    bbox: [f64; 4],
}

/// How a point's material is found.
#[derive(Debug, Clone, PartialEq)]
enum Lookup {
    /// A code grid, by cell (in the floor's frame: `frame` moves a face point there first).
    Grid {
        /// West and south edges of the grid, m.
        x0: f64,
        y0: f64,
        cell: f64,
        ncols: usize,
        nrows: usize,
        /// Material per cell, row-major from the south.
        material: Vec<u16>,
        frame: Option<MapFrame>,
    },
    /// Polygons in the face frame, tested last to first.
    Polygons(Vec<Poly>),
}

/// A zone map built for a case (see the module notes).
#[derive(Debug, Clone, PartialEq)]
pub struct Zones {
    /// The spec as given (echoed, and the codes' source).
    spec: ZonesSpec,
    /// Material of the outside code.
    outside: u16,
    lookup: Lookup,
    /// Boundaries between classes, face frame (empty when every material is alike).
    segments: Vec<Segment>,
    /// Per material, its class: the first material with the same parameters.
    class: Vec<u16>,
}

fn bbox_of(points: &[[f64; 2]]) -> [f64; 4] {
    points.iter().fold(
        [
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ],
        |b, p| {
            [
                b[0].min(p[0]),
                b[1].max(p[0]),
                b[2].min(p[1]),
                b[3].max(p[1]),
            ]
        },
    )
}

fn segment(q0: [f64; 2], q1: [f64; 2]) -> Segment {
    Segment {
        q0,
        q1,
        bbox: bbox_of(&[q0, q1]),
    }
}

/// Even–odd crossing test of (x, y) against the closed polygon `pts`.
fn inside_polygon(pts: &[[f64; 2]], x: f64, y: f64) -> bool {
    let mut inside = false;
    let mut j = pts.len() - 1;
    for i in 0..pts.len() {
        let (a, b) = (pts[i], pts[j]);
        if (a[1] > y) != (b[1] > y) && x < (b[0] - a[0]) * (y - a[1]) / (b[1] - a[1]) + a[0] {
            inside = !inside;
        }
        j = i;
    }
    inside
}

/// Whether the closed polygon `pts` has two edges that meet other than at their shared vertex
/// (exact orientation predicates): the index of the first such pair, or None.
#[must_use]
pub fn self_intersection(pts: &[[f64; 2]]) -> Option<(usize, usize)> {
    let n = pts.len();
    let c = |p: [f64; 2]| robust::Coord { x: p[0], y: p[1] };
    let orient = |a: [f64; 2], b: [f64; 2], p: [f64; 2]| {
        let o = robust::orient2d(c(a), c(b), c(p));
        if o > 0.0 {
            1
        } else if o < 0.0 {
            -1
        } else {
            0
        }
    };
    let on = |a: [f64; 2], b: [f64; 2], p: [f64; 2]| {
        p[0] >= a[0].min(b[0])
            && p[0] <= a[0].max(b[0])
            && p[1] >= a[1].min(b[1])
            && p[1] <= a[1].max(b[1])
    };
    let cross = |a: [f64; 2], b: [f64; 2], p: [f64; 2], q: [f64; 2]| {
        let (o1, o2) = (orient(a, b, p), orient(a, b, q));
        let (o3, o4) = (orient(p, q, a), orient(p, q, b));
        (o1 != o2 && o3 != o4)
            || (o1 == 0 && on(a, b, p))
            || (o2 == 0 && on(a, b, q))
            || (o3 == 0 && on(p, q, a))
            || (o4 == 0 && on(p, q, b))
    };
    let boxes: Vec<[f64; 4]> = (0..n)
        .map(|i| bbox_of(&[pts[i], pts[(i + 1) % n]]))
        .collect();
    for i in 0..n {
        for j in i + 1..n {
            let adjacent = j == i + 1 || (i == 0 && j == n - 1);
            let (bi, bj) = (boxes[i], boxes[j]);
            if bi[1] < bj[0] || bj[1] < bi[0] || bi[3] < bj[2] || bj[3] < bi[2] {
                continue;
            }
            let (a, b) = (pts[i], pts[(i + 1) % n]);
            let (p, q) = (pts[j], pts[(j + 1) % n]);
            if adjacent {
                // neighbours share a vertex: they overlap only when collinear and folding back
                let (shared, ea, eb) = if j == i + 1 { (b, a, q) } else { (a, b, p) };
                if orient(ea, shared, eb) == 0 {
                    let d1 = [ea[0] - shared[0], ea[1] - shared[1]];
                    let d2 = [eb[0] - shared[0], eb[1] - shared[1]];
                    if d1[0] * d2[0] + d1[1] * d2[1] > 0.0 {
                        return Some((i, j));
                    }
                }
                continue;
            }
            if cross(a, b, p, q) {
                return Some((i, j));
            }
        }
    }
    None
}

impl Zones {
    /// Builds the zone map of `spec` for a floor placed by `map` (None: the shape is in face
    /// coordinates already).
    ///
    /// Errors: a code of the shape or the outside code without a material, or two materials with
    /// one code ([`Param::FaceZones`]); the wire checks these first and names the field.
    pub fn new(spec: ZonesSpec, map: Option<MapFrame>) -> PhysicsResult<Self> {
        let materials = &spec.materials;
        if materials.is_empty() || materials.len() > MAX_MATERIALS {
            return Err(PhysicsError::invalid(
                Param::FaceZones,
                materials.len() as f64,
                format!("a zone map needs 1 to {MAX_MATERIALS} materials"),
            ));
        }
        let index = |code: i64| -> PhysicsResult<u16> {
            materials
                .iter()
                .position(|m| m.code == code)
                .map(|i| i as u16)
                .ok_or_else(|| {
                    PhysicsError::invalid(
                        Param::FaceZones,
                        code as f64,
                        format!("code {code} has no material"),
                    )
                })
        };
        for (i, m) in materials.iter().enumerate() {
            if materials[..i].iter().any(|o| o.code == m.code) {
                return Err(PhysicsError::invalid(
                    Param::FaceZones,
                    m.code as f64,
                    format!("code {} has two materials", m.code),
                ));
            }
        }
        let class: Vec<u16> = materials
            .iter()
            .map(|m| {
                materials
                    .iter()
                    .position(|o| o.same_as(m))
                    .map_or(0, |i| i as u16)
            })
            .collect();
        let one_class = class.iter().all(|&c| c == class[0]);
        let outside = index(spec.outside_code)?;
        let to_face = |p: [f64; 2]| map.map_or(p, |f| f.to_face(p));
        let mut segments = Vec::new();
        let lookup = match &spec.shape {
            ZoneShape::CodeGrid {
                x_center,
                y_center,
                cell,
                ncols,
                nrows,
                codes,
            } => {
                let (ncols, nrows, d) = (*ncols, *nrows, *cell);
                let material = codes
                    .iter()
                    .map(|c| c.map_or(Ok(outside), index))
                    .collect::<PhysicsResult<Vec<u16>>>()?;
                let (x0, y0) = (x_center - 0.5 * d, y_center - 0.5 * d);
                if !one_class {
                    let cls = |i: isize, j: isize| -> u16 {
                        if i < 0 || j < 0 || i >= nrows as isize || j >= ncols as isize {
                            class[outside as usize]
                        } else {
                            class[material[i as usize * ncols + j as usize] as usize]
                        }
                    };
                    let x = |j: isize| x0 + j as f64 * d;
                    let y = |i: isize| y0 + i as f64 * d;
                    // vertical grid lines x = x(j), j in 0..=ncols: runs of differing cells
                    for j in 0..=ncols as isize {
                        let mut start: Option<isize> = None;
                        for i in 0..=nrows as isize {
                            let differs = i < nrows as isize && cls(i, j - 1) != cls(i, j);
                            match (differs, start) {
                                (true, None) => start = Some(i),
                                (false, Some(s)) => {
                                    segments.push(segment(
                                        to_face([x(j), y(s)]),
                                        to_face([x(j), y(i)]),
                                    ));
                                    start = None;
                                }
                                _ => {}
                            }
                        }
                    }
                    for i in 0..=nrows as isize {
                        let mut start: Option<isize> = None;
                        for j in 0..=ncols as isize {
                            let differs = j < ncols as isize && cls(i - 1, j) != cls(i, j);
                            match (differs, start) {
                                (true, None) => start = Some(j),
                                (false, Some(s)) => {
                                    segments.push(segment(
                                        to_face([x(s), y(i)]),
                                        to_face([x(j), y(i)]),
                                    ));
                                    start = None;
                                }
                                _ => {}
                            }
                        }
                    }
                }
                Lookup::Grid {
                    x0,
                    y0,
                    cell: d,
                    ncols,
                    nrows,
                    material,
                    frame: map,
                }
            }
            ZoneShape::Polygons(polys) => {
                let mut out = Vec::with_capacity(polys.len());
                for p in polys {
                    let points: Vec<[f64; 2]> = p.points.iter().map(|&q| to_face(q)).collect();
                    if !one_class {
                        for k in 0..points.len() {
                            segments.push(segment(points[k], points[(k + 1) % points.len()]));
                        }
                    }
                    out.push(Poly {
                        material: index(p.code)?,
                        bbox: bbox_of(&points),
                        points,
                    });
                }
                Lookup::Polygons(out)
            }
        };
        Ok(Zones {
            spec,
            outside,
            lookup,
            segments,
            class,
        })
    }

    /// The materials, in the order given.
    #[must_use]
    pub fn materials(&self) -> &[Material] {
        &self.spec.materials
    }

    /// The zone map as given.
    #[must_use]
    pub fn spec(&self) -> &ZonesSpec {
        &self.spec
    }

    /// Whether every material has the same parameters (no boundary cuts anything).
    #[must_use]
    pub fn is_uniform(&self) -> bool {
        self.segments.is_empty()
    }

    /// Index of the material under the face point (x, y), m.
    #[must_use]
    pub fn material_index(&self, x: f64, y: f64) -> usize {
        match &self.lookup {
            Lookup::Grid {
                x0,
                y0,
                cell,
                ncols,
                nrows,
                material,
                frame,
            } => {
                let [mx, my] = frame.map_or([x, y], |f| f.to_map([x, y]));
                let (fj, fi) = (((mx - x0) / cell).floor(), ((my - y0) / cell).floor());
                if fj >= 0.0 && fi >= 0.0 && fj < *ncols as f64 && fi < *nrows as f64 {
                    material[fi as usize * ncols + fj as usize] as usize
                } else {
                    self.outside as usize
                }
            }
            Lookup::Polygons(polys) => polys
                .iter()
                .rev()
                .find(|p| {
                    x >= p.bbox[0]
                        && x <= p.bbox[1]
                        && y >= p.bbox[2]
                        && y <= p.bbox[3]
                        && inside_polygon(&p.points, x, y)
                })
                .map_or(self.outside as usize, |p| p.material as usize),
        }
    }

    /// The material under the face point (x, y), m.
    #[must_use]
    pub fn material_at(&self, x: f64, y: f64) -> &Material {
        &self.spec.materials[self.material_index(x, y)]
    }

    /// The code under the face point (x, y), m.
    #[must_use]
    pub fn code_at(&self, x: f64, y: f64) -> i64 {
        self.material_at(x, y).code
    }

    /// The point a hair (1e-9 of its coordinates' size) from p along the plan direction d: where
    /// a material is read for a motion starting at p on a boundary.
    #[must_use]
    pub fn probe(p: [f64; 2], d: [f64; 2]) -> [f64; 2] {
        let n = d[0].hypot(d[1]);
        if n == 0.0 || !n.is_finite() {
            return p;
        }
        let h = 1e-9 * (1.0 + p[0].abs().max(p[1].abs())) / n;
        [p[0] + d[0] * h, p[1] + d[1] * h]
    }

    /// First time in (0, t_max] at which the plan motion p + v t + ½ a t² (m, m/s, m/s²) crosses
    /// a boundary between classes, leaving the side the point `probe` is on (see
    /// [`Zones::probe`]); None when it crosses none.
    #[must_use]
    pub fn cut(
        &self,
        p: [f64; 2],
        v: [f64; 2],
        a: [f64; 2],
        probe: [f64; 2],
        t_max: f64,
    ) -> Option<f64> {
        if self.segments.is_empty() || t_max <= 0.0 {
            return None;
        }
        // the piece's plan box (to ∞ for an endless piece)
        let range = |p: f64, v: f64, a: f64| {
            let end = |t: f64| p + v * t + 0.5 * a * t * t;
            if !t_max.is_finite() {
                return if a > 0.0 || (a == 0.0 && v > 0.0) {
                    [p.min(end(-v / a.max(f64::MIN_POSITIVE))), f64::INFINITY]
                } else if a < 0.0 || v < 0.0 {
                    [
                        f64::NEG_INFINITY,
                        p.max(end(-v / a.min(-f64::MIN_POSITIVE))),
                    ]
                } else {
                    [p, p]
                };
            }
            let mut lo = p.min(end(t_max));
            let mut hi = p.max(end(t_max));
            if a != 0.0 {
                let ts = -v / a;
                if ts > 0.0 && ts < t_max {
                    lo = lo.min(end(ts));
                    hi = hi.max(end(ts));
                }
            }
            let pad = 1e-9 * (1.0 + lo.abs().max(hi.abs()));
            [lo - pad, hi + pad]
        };
        let (bx, by) = (range(p[0], v[0], a[0]), range(p[1], v[1], a[1]));
        let mut best: Option<f64> = None;
        for s in &self.segments {
            if s.bbox[1] < bx[0] || s.bbox[0] > bx[1] || s.bbox[3] < by[0] || s.bbox[2] > by[1] {
                continue;
            }
            let (q0, q1) = (s.q0, s.q1);
            let (nx, ny) = (q1[1] - q0[1], -(q1[0] - q0[0]));
            let side = nx * (probe[0] - q0[0]) + ny * (probe[1] - q0[1]);
            if side == 0.0 {
                continue;
            }
            let sg = -side.signum();
            let f0 = sg * (nx * (p[0] - q0[0]) + ny * (p[1] - q0[1]));
            let f1 = sg * (nx * v[0] + ny * v[1]);
            let f2 = sg * (nx * a[0] + ny * a[1]);
            let Some(t) = outward_root(f0, f1, f2) else {
                continue;
            };
            if t <= 0.0 || t > t_max || best.is_some_and(|b| t >= b) {
                continue;
            }
            // on the segment itself, not on its line beyond an end
            let x = [
                p[0] + v[0] * t + 0.5 * a[0] * t * t,
                p[1] + v[1] * t + 0.5 * a[1] * t * t,
            ];
            let (ex, ey) = (q1[0] - q0[0], q1[1] - q0[1]);
            let u = ((x[0] - q0[0]) * ex + (x[1] - q0[1]) * ey) / (ex * ex + ey * ey);
            if (-1e-12..=1.0 + 1e-12).contains(&u) {
                best = Some(t);
            }
        }
        best
    }
}

/// A run's view of the zone map: each material's μ for this run (drawn or nominal) and the
/// material of the impact being resolved, which the run sets before it asks for (e_n, e_t).
#[derive(Debug)]
pub(crate) struct RunZones<'a> {
    /// The zone map.
    pub(crate) zones: &'a Zones,
    /// Per material, the lumped mass's μ in this run.
    pub(crate) mu: Vec<f64>,
    /// The material of the impact being resolved.
    pub(crate) current: Cell<usize>,
}

impl<'a> RunZones<'a> {
    /// The zone map with the per-material μ of a run.
    pub(crate) fn new(zones: &'a Zones, mu: Vec<f64>) -> Self {
        RunZones {
            zones,
            mu,
            current: Cell::new(0),
        }
    }

    /// μ of the material a motion from p (m) along the plan direction d enters.
    pub(crate) fn mu_at(&self, p: [f64; 2], d: [f64; 2]) -> f64 {
        let q = Zones::probe(p, d);
        self.mu[self.zones.material_index(q[0], q[1])]
    }
}

/// Each material's per-run value: from its distribution when it has one, drawn once per
/// *distinct* distribution in material order (equal distributions share one draw) and clipped to
/// [0, `max`], else its nominal value. `draw` samples one distribution.
pub(crate) fn per_run_values(
    items: impl Iterator<Item = (f64, Option<Distribution>)>,
    max: f64,
    mut draw: impl FnMut(&Distribution) -> f64,
) -> Vec<f64> {
    let mut drawn: Vec<(Distribution, f64)> = Vec::new();
    items
        .map(|(nominal, d)| match d {
            None => nominal,
            Some(d) => {
                if let Some(&(_, x)) = drawn.iter().find(|(e, _)| *e == d) {
                    x
                } else {
                    let x = draw(&d).clamp(0.0, max);
                    drawn.push((d, x));
                    x
                }
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    pub(crate) fn material(code: i64, mu: f64) -> Material {
        let d = Distribution::Uniform { min: 0.2, max: 0.4 };
        Material {
            code,
            name: None,
            friction_coefficient: mu,
            friction_coefficient_distribution: None,
            restitution_normal: 0.3,
            restitution_tangential: 0.8,
            restitution_normal_distribution: d,
            restitution_tangential_distribution: d,
            block: BlockContact {
                normal_stiffness: 1e8,
                shear_stiffness: 1e8,
                critical_damping_ratio: 0.35,
                critical_damping_ratio_distribution: None,
                friction_coefficient: mu,
                friction_coefficient_distribution: None,
            },
        }
    }

    fn square(code: i64, x0: f64, y0: f64, s: f64) -> ZonePolygon {
        ZonePolygon {
            code,
            points: vec![[x0, y0], [x0 + s, y0], [x0 + s, y0 + s], [x0, y0 + s]],
        }
    }

    #[test]
    fn later_polygons_win_and_the_outside_code_fills_the_rest() {
        let spec = ZonesSpec {
            shape: ZoneShape::Polygons(vec![square(2, 0.0, 0.0, 10.0), square(3, 5.0, 5.0, 10.0)]),
            outside_code: 1,
            materials: vec![material(1, 0.1), material(2, 0.2), material(3, 0.3)],
        };
        let z = Zones::new(spec, None).unwrap();
        assert_eq!(z.code_at(1.0, 1.0), 2);
        assert_eq!(z.code_at(6.0, 6.0), 3);
        assert_eq!(z.code_at(12.0, 12.0), 3);
        assert_eq!(z.code_at(12.0, 1.0), 1);
        assert_eq!(z.code_at(-1.0, 1.0), 1);
        assert!(!z.is_uniform());
    }

    #[test]
    fn a_code_grid_reads_its_cells_from_the_south() {
        // 2 rows × 3 columns, cell 2 m, centres from (1, 1): row 0 (south) is 1 1 2
        let spec = ZonesSpec {
            shape: ZoneShape::CodeGrid {
                x_center: 1.0,
                y_center: 1.0,
                cell: 2.0,
                ncols: 3,
                nrows: 2,
                codes: vec![Some(1), Some(1), Some(2), None, Some(2), Some(2)],
            },
            outside_code: 1,
            materials: vec![material(1, 0.1), material(2, 0.5)],
        };
        let z = Zones::new(spec, None).unwrap();
        assert_eq!(z.code_at(4.5, 1.0), 2);
        assert_eq!(z.code_at(3.5, 1.0), 1);
        assert_eq!(z.code_at(1.0, 3.0), 1); // no data
        assert_eq!(z.code_at(3.0, 3.0), 2);
        assert_eq!(z.code_at(7.0, 3.0), 1); // off the grid
        // a motion along y = 1 from x = 0 at 1 m/s meets the first boundary at x = 4
        let t = z.cut([0.0, 1.0], [1.0, 0.0], [0.0, 0.0], [1e-9, 1.0], 100.0);
        assert_eq!(t, Some(4.0));
        // under gravity along x from rest: ½ t² = 4
        let t = z
            .cut([0.0, 1.0], [0.0, 0.0], [1.0, 0.0], [1e-9, 1.0], 100.0)
            .unwrap();
        assert!((t - 8f64.sqrt()).abs() <= 1e-15 * t, "{t}");
        // and leaves zone 2 at x = 6 (the grid's edge, outside code 1)
        let t = z.cut([4.0, 1.0], [1.0, 0.0], [0.0, 0.0], [4.0 + 1e-9, 1.0], 100.0);
        assert_eq!(t, Some(2.0));
    }

    #[test]
    fn equal_materials_have_no_boundary() {
        let spec = ZonesSpec {
            shape: ZoneShape::Polygons(vec![square(2, 0.0, 0.0, 10.0)]),
            outside_code: 1,
            materials: vec![material(1, 0.2), material(2, 0.2)],
        };
        let z = Zones::new(spec, None).unwrap();
        assert!(z.is_uniform());
        assert_eq!(z.code_at(1.0, 1.0), 2);
        assert_eq!(
            z.cut([-1.0, 1.0], [1.0, 0.0], [0.0; 2], [-1.0, 1.0], 100.0),
            None
        );
    }

    #[test]
    fn polygons_in_map_coordinates_are_the_same_polygons_on_the_face() {
        let map = MapFrame {
            origin: [500.0, 800.0],
            dip_direction_deg: 135.0,
        };
        let in_map = square(2, 490.0, 790.0, 30.0);
        let on_face = ZonePolygon {
            code: 2,
            points: in_map.points.iter().map(|&p| map.to_face(p)).collect(),
        };
        let mk = |p: ZonePolygon, m: Option<MapFrame>| {
            Zones::new(
                ZonesSpec {
                    shape: ZoneShape::Polygons(vec![p]),
                    outside_code: 1,
                    materials: vec![material(1, 0.1), material(2, 0.5)],
                },
                m,
            )
            .unwrap()
        };
        let (a, b) = (mk(in_map, Some(map)), mk(on_face, None));
        for i in -40..40 {
            for j in -40..40 {
                let (x, y) = (f64::from(i) * 0.77, f64::from(j) * 0.81);
                assert_eq!(a.code_at(x, y), b.code_at(x, y), "({x}, {y})");
            }
        }
        // and a map point inside the square is inside on the face
        let q = map.to_face([505.0, 805.0]);
        assert_eq!(a.code_at(q[0], q[1]), 2);
    }

    #[test]
    fn self_intersections_are_found() {
        assert_eq!(self_intersection(&square(1, 0.0, 0.0, 1.0).points), None);
        let bow = [[0.0, 0.0], [1.0, 1.0], [1.0, 0.0], [0.0, 1.0]];
        assert!(self_intersection(&bow).is_some());
        // a spike folding back along its own edge
        let spike = [[0.0, 0.0], [2.0, 0.0], [1.0, 0.0], [1.0, 1.0]];
        assert!(self_intersection(&spike).is_some());
    }

    #[test]
    fn equal_distributions_share_one_draw_in_material_order() {
        let d1 = Distribution::Uniform { min: 0.1, max: 0.3 };
        let d2 = Distribution::Uniform { min: 0.5, max: 0.9 };
        let mut n = 0.0;
        let v = per_run_values(
            [
                (0.2, Some(d1)),
                (0.7, None),
                (0.2, Some(d2)),
                (0.2, Some(d1)),
            ]
            .into_iter(),
            2.0,
            |_| {
                n += 1.0;
                n
            },
        );
        assert_eq!(v, vec![1.0, 0.7, 2.0, 1.0]);
    }
}
