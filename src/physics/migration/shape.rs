//! Rigid-block shapes of the DEM (physics.md §C.3): cube, cuboid, sphere, the convex hull of
//! given points and random polyhedra by the ellipsoid method, each with its own mass, centre of
//! mass and inertia tensor.
//!
//! **Hull.** An incremental 3-D convex hull (O(n²), n ≤ 1000 points): start from the four most
//! spread points, then add each point outside the current hull, removing the triangles it sees
//! and joining it to their horizon. A point counts as outside when it lies more than
//! 1e-10·(hull size) beyond a face plane, so near-coplanar input gives a clean hull. Coplanar
//! triangles are merged into polygonal faces afterwards (a cube has 6 faces of 4 vertices).
//!
//! **Mass properties** by tetrahedra from an interior point o: each outward triangle (a, b, c)
//! forms a tetrahedron of signed volume V = (a − o)·((b − o) × (c − o))/6 whose second moment
//! about o is C = V/20 (aaᵀ + bbᵀ + ccᵀ + ssᵀ), s = a + b + c (vectors from o). The centre of
//! mass is the volume-weighted tetrahedron centroid; C is shifted to it by the parallel-axis rule
//! and the inertia tensor is ρ (tr C · 1 − C).
//!
//! **Body frame.** Vertices are stored relative to the centre of mass in the principal axes of
//! inertia (when the tensor is already diagonal the input axes are kept, so a cube keeps its
//! faces on the axes), so Euler's equations take the diagonal moments.

use nalgebra::{Matrix3, SymmetricEigen, UnitQuaternion, Vector3};

use super::monte_carlo::{run_stream, uniform01};
use crate::physics::error::{Param, PhysicsError, PhysicsResult};
use crate::physics::material::{Rock, RockShape};

/// A planar face of a polyhedral block, in the body frame.
#[derive(Debug, Clone, PartialEq)]
pub struct BlockFace {
    /// Outward unit normal.
    pub normal: Vector3<f64>,
    /// Distance of the face plane from the centre of mass, m (n·x = offset on the face).
    pub offset: f64,
    /// Indices of the face's vertices (any order).
    pub vertices: Vec<usize>,
    /// Area, m².
    pub area: f64,
}

/// A rigid block with its mass properties, in its principal body frame (origin at the centre of
/// mass).
#[derive(Debug, Clone, PartialEq)]
pub struct BlockShape {
    /// Hull vertices relative to the centre of mass, principal axes, m (empty for a sphere).
    pub vertices: Vec<Vector3<f64>>,
    /// Faces of the hull (coplanar triangles merged).
    pub faces: Vec<BlockFace>,
    /// Edges of the hull between different faces, as vertex index pairs.
    pub edges: Vec<[usize; 2]>,
    /// The two faces that meet at each edge (indices into `faces`).
    pub edge_faces: Vec<[usize; 2]>,
    /// Radius of a sphere, m (None: a polyhedron).
    pub sphere_radius: Option<f64>,
    /// Volume, m³.
    pub volume: f64,
    /// Mass, kg.
    pub mass: f64,
    /// Principal moments of inertia about the body axes x, y, z, kg·m².
    pub inertia: Vector3<f64>,
    /// Largest distance of a block point from the centre of mass, m.
    pub r_max: f64,
    /// Smallest dimension: the smallest width between parallel support planes over the face
    /// normals (a sphere: its diameter), m.
    pub smallest_dimension: f64,
    /// Index of the largest face (the face the block rests on at release; 0 for a sphere).
    pub largest_face: usize,
    /// The rotation from the principal body axes to the axes the shape was given in (its
    /// vertices' or dimensions' frame; identity for a sphere).
    pub given_axes: UnitQuaternion<f64>,
}

impl BlockShape {
    /// Principal moments sorted ascending [I₁, I₂, I₃], kg·m².
    pub fn principal_moments(&self) -> [f64; 3] {
        let mut m = [self.inertia.x, self.inertia.y, self.inertia.z];
        m.sort_by(f64::total_cmp);
        m
    }

    /// Number of contacts of a resting block, N_c: the vertices of the largest face (sphere 1).
    #[must_use]
    pub fn resting_contacts(&self) -> usize {
        if self.sphere_radius.is_some() {
            1
        } else {
            self.faces[self.largest_face].vertices.len()
        }
    }

    /// Σ|r|² over the largest face's vertices, m² (sphere: r²): the rotational stiffness factor.
    #[must_use]
    pub fn resting_r2(&self) -> f64 {
        match self.sphere_radius {
            Some(r) => r * r,
            None => self.faces[self.largest_face]
                .vertices
                .iter()
                .map(|&i| self.vertices[i].norm_squared())
                .sum(),
        }
    }

    /// Distance from the centre of mass to the resting face (sphere: r), m.
    #[must_use]
    pub fn rest_height(&self) -> f64 {
        match self.sphere_radius {
            Some(r) => r,
            None => self.faces[self.largest_face].offset,
        }
    }

    /// Outward normal of the resting face in the body frame (sphere: −z).
    #[must_use]
    pub fn rest_normal(&self) -> Vector3<f64> {
        match self.sphere_radius {
            Some(_) => -Vector3::z(),
            None => self.faces[self.largest_face].normal,
        }
    }

    /// Orientation of the block resting face-down on a floor of unit normal `nf`: its resting
    /// face turned to −z, then the whole tilted from z to `nf` (api.md release rule).
    #[must_use]
    pub fn resting_orientation(&self, nf: &Vector3<f64>) -> UnitQuaternion<f64> {
        let q_face = UnitQuaternion::rotation_between(&self.rest_normal(), &(-Vector3::z()))
            .unwrap_or_else(|| {
                UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI)
            });
        let q_tilt = UnitQuaternion::rotation_between(&Vector3::z(), nf)
            .unwrap_or_else(UnitQuaternion::identity);
        q_tilt * q_face
    }

    /// A sphere of radius r and density ρ.
    #[must_use]
    pub fn sphere(radius: f64, density: f64) -> Self {
        let volume = 4.0 / 3.0 * std::f64::consts::PI * radius.powi(3);
        let mass = density * volume;
        let i = 0.4 * mass * radius * radius;
        BlockShape {
            vertices: Vec::new(),
            faces: Vec::new(),
            edges: Vec::new(),
            edge_faces: Vec::new(),
            sphere_radius: Some(radius),
            volume,
            mass,
            inertia: Vector3::new(i, i, i),
            r_max: radius,
            smallest_dimension: 2.0 * radius,
            largest_face: 0,
            given_axes: UnitQuaternion::identity(),
        }
    }

    /// The convex hull of `points` (m) with density ρ (kg/m³).
    ///
    /// Errors: fewer than 4 non-coplanar points (`field` names the request field).
    pub fn hull(points: &[[f64; 3]], density: f64, field: Param) -> PhysicsResult<Self> {
        let pts: Vec<Vector3<f64>> = points
            .iter()
            .map(|p| Vector3::new(p[0], p[1], p[2]))
            .collect();
        let tris = convex_hull(&pts).ok_or_else(|| {
            PhysicsError::invalid(
                field,
                points.len() as f64,
                "the points span no volume: a block needs at least 4 points that are not coplanar",
            )
        })?;
        Ok(Self::from_triangles(&pts, &tris, density))
    }

    fn from_triangles(pts: &[Vector3<f64>], tris: &[[usize; 3]], density: f64) -> Self {
        // keep only the hull's vertices, renumbered
        let mut map = vec![usize::MAX; pts.len()];
        let mut verts: Vec<Vector3<f64>> = Vec::new();
        let tris: Vec<[usize; 3]> = tris
            .iter()
            .map(|t| {
                t.map(|i| {
                    if map[i] == usize::MAX {
                        map[i] = verts.len();
                        verts.push(pts[i]);
                    }
                    map[i]
                })
            })
            .collect();
        let o = verts.iter().sum::<Vector3<f64>>() / verts.len() as f64;
        let mut vol = 0.0;
        let mut first = Vector3::zeros();
        let mut c2 = Matrix3::zeros();
        for t in &tris {
            let (a, b, c) = (verts[t[0]] - o, verts[t[1]] - o, verts[t[2]] - o);
            let v = a.dot(&b.cross(&c)) / 6.0;
            let s = a + b + c;
            vol += v;
            first += s * (v / 4.0);
            c2 += (a * a.transpose() + b * b.transpose() + c * c.transpose() + s * s.transpose())
                * (v / 20.0);
        }
        let d = first / vol;
        let com = o + d;
        let c_com = c2 - d * d.transpose() * vol;
        let tensor = (Matrix3::identity() * c_com.trace() - c_com) * density;
        let scale = tensor.trace().abs();
        let off = tensor.m12.abs() + tensor.m13.abs() + tensor.m23.abs();
        let (rot, moments) = if off <= 1e-13 * scale {
            (
                Matrix3::identity(),
                Vector3::new(tensor.m11, tensor.m22, tensor.m33),
            )
        } else {
            let e = SymmetricEigen::new(tensor);
            let mut r = e.eigenvectors;
            if r.determinant() < 0.0 {
                r.set_column(2, &(-r.column(2)));
            }
            (r, e.eigenvalues)
        };
        // body coordinates: principal axes, origin at the centre of mass
        let verts: Vec<Vector3<f64>> = verts.iter().map(|p| rot.transpose() * (p - com)).collect();
        let r_max = verts.iter().map(|p| p.norm()).fold(0.0, f64::max);
        // merge coplanar triangles into faces
        let mut faces: Vec<BlockFace> = Vec::new();
        let mut tri_face = Vec::with_capacity(tris.len());
        for t in &tris {
            let (a, b, c) = (verts[t[0]], verts[t[1]], verts[t[2]]);
            let cr = (b - a).cross(&(c - a));
            let area = 0.5 * cr.norm();
            let n = cr.normalize();
            let off = n.dot(&a);
            let k = faces.iter().position(|f| {
                f.normal.dot(&n) > 1.0 - 1e-9 && (f.offset - off).abs() <= 1e-9 * r_max
            });
            let k = match k {
                Some(k) => {
                    let f = &mut faces[k];
                    f.area += area;
                    for &i in t {
                        if !f.vertices.contains(&i) {
                            f.vertices.push(i);
                        }
                    }
                    k
                }
                None => {
                    faces.push(BlockFace {
                        normal: n,
                        offset: off,
                        vertices: t.to_vec(),
                        area,
                    });
                    faces.len() - 1
                }
            };
            tri_face.push(k);
        }
        // edges between different faces
        let mut edges: Vec<[usize; 2]> = Vec::new();
        let mut edge_faces: Vec<[usize; 2]> = Vec::new();
        let mut seen = std::collections::HashMap::new();
        for (ti, t) in tris.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                let key = (a.min(b), a.max(b));
                match seen.get(&key) {
                    Some(&other) => {
                        if tri_face[other] != tri_face[ti] {
                            edges.push([key.0, key.1]);
                            edge_faces.push([tri_face[other], tri_face[ti]]);
                        }
                    }
                    None => {
                        seen.insert(key, ti);
                    }
                }
            }
        }
        let largest_face = (0..faces.len())
            .max_by(|&a, &b| {
                faces[a]
                    .area
                    .partial_cmp(&faces[b].area)
                    .unwrap_or(std::cmp::Ordering::Equal)
                    .then(b.cmp(&a))
            })
            .unwrap_or(0);
        let smallest_dimension = faces
            .iter()
            .map(|f| {
                let lo = verts
                    .iter()
                    .map(|p| f.normal.dot(p))
                    .fold(f64::INFINITY, f64::min);
                f.offset - lo
            })
            .fold(f64::INFINITY, f64::min);
        BlockShape {
            vertices: verts,
            faces,
            edges,
            edge_faces,
            sphere_radius: None,
            volume: vol,
            mass: density * vol,
            inertia: moments,
            r_max,
            smallest_dimension,
            largest_face,
            given_axes: UnitQuaternion::from_rotation_matrix(
                &nalgebra::Rotation3::from_matrix_unchecked(rot),
            ),
        }
    }

    /// The block of a rock (api.md `rock`): its shape with the rock's density.
    ///
    /// Errors: a degenerate polyhedron ([`Param::RockVertices`]) or a random polyhedron that gives
    /// no volume in 100 draws ([`Param::RockRandomShape`]).
    pub fn of_rock(rock: &Rock) -> PhysicsResult<Self> {
        let rho = rock.density;
        match &rock.shape {
            RockShape::Cube => Self::cuboid([rock.side_length; 3], rho),
            RockShape::Cuboid { dimensions } => Self::cuboid(*dimensions, rho),
            RockShape::Ellipsoid { dimensions } => Self::ellipsoid(*dimensions, rho),
            RockShape::Sphere { radius } => Ok(Self::sphere(*radius, rho)),
            RockShape::Polyhedron { vertices } => Self::hull(vertices, rho, Param::RockVertices),
            RockShape::RandomPolyhedron {
                semi_axes,
                vertices,
                seed,
            } => Self::random(*semi_axes, *vertices, *seed, rho),
        }
    }

    /// A cuboid with edges [a, b, c] (m) along x, y, z.
    ///
    /// Errors: [`PhysicsError::InvalidInput`] on `RockDimensions` when an edge is zero (no volume).
    pub fn cuboid(d: [f64; 3], density: f64) -> PhysicsResult<Self> {
        let mut pts = Vec::with_capacity(8);
        for i in 0..8 {
            pts.push([
                if i & 1 == 0 { -0.5 } else { 0.5 } * d[0],
                if i & 2 == 0 { -0.5 } else { 0.5 } * d[1],
                if i & 4 == 0 { -0.5 } else { 0.5 } * d[2],
            ]);
        }
        Self::hull(&pts, density, Param::RockDimensions)
    }

    /// Number of points of an [`Self::ellipsoid`].
    pub const ELLIPSOID_POINTS: usize = 64;

    /// The polyhedron of an ellipsoid with full axes `d` = [a, b, c] (m) along x, y, z: the hull
    /// of [`Self::ELLIPSOID_POINTS`] points of a Fibonacci lattice on it (point k at
    /// z = 1 − (2k + 1)/N of the unit sphere, longitude k times the golden angle, stretched by
    /// the semi-axes), scaled so that its volume is the ellipsoid's π a b c / 6 (its extents
    /// then exceed the axes by the same factor, 1.016 for N = 64).
    ///
    /// Errors: [`PhysicsError::InvalidInput`] on `RockDimensions` when an axis is zero.
    pub fn ellipsoid(d: [f64; 3], density: f64) -> PhysicsResult<Self> {
        let n = Self::ELLIPSOID_POINTS;
        let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
        let unit: Vec<[f64; 3]> = (0..n)
            .map(|k| {
                let z = 1.0 - (2.0 * k as f64 + 1.0) / n as f64;
                let r = (1.0 - z * z).max(0.0).sqrt();
                let (s, c) = (golden * k as f64).sin_cos();
                [0.5 * d[0] * r * c, 0.5 * d[1] * r * s, 0.5 * d[2] * z]
            })
            .collect();
        let first = Self::hull(&unit, density, Param::RockDimensions)?;
        let target = std::f64::consts::PI / 6.0 * d[0] * d[1] * d[2];
        let k = (target / first.volume).cbrt();
        let pts: Vec<[f64; 3]> = unit.iter().map(|p| p.map(|c| c * k)).collect();
        Self::hull(&pts, density, Param::RockDimensions)
    }

    /// A random polyhedron by the ellipsoid method (physics.md §C.3 "Further definitions"):
    /// N points (a sin φ cos λ, b sin φ sin λ, c cos φ), cos φ ~ U[−1, 1] then λ ~ U[0, 2π) per
    /// point, from the ensembles' stream (seed, 0); their hull, drawn again (same stream) up to
    /// 100 times while it spans no volume.
    pub fn random(semi_axes: [f64; 3], n: usize, seed: u64, density: f64) -> PhysicsResult<Self> {
        let mut rng = run_stream(seed, 0);
        for _ in 0..100 {
            let pts: Vec<[f64; 3]> = (0..n)
                .map(|_| {
                    let cphi = 2.0 * uniform01(&mut rng) - 1.0;
                    let lam = 2.0 * std::f64::consts::PI * uniform01(&mut rng);
                    let sphi = (1.0 - cphi * cphi).max(0.0).sqrt();
                    [
                        semi_axes[0] * sphi * lam.cos(),
                        semi_axes[1] * sphi * lam.sin(),
                        semi_axes[2] * cphi,
                    ]
                })
                .collect();
            if let Ok(s) = Self::hull(&pts, density, Param::RockRandomShape) {
                return Ok(s);
            }
        }
        Err(PhysicsError::invalid(
            Param::RockRandomVertexCount,
            n as f64,
            "100 draws gave no polyhedron with volume: use more vertices",
        ))
    }
}

/// Outward triangles of the convex hull of `p` (indices into p), or None when the points span
/// no volume.
pub(crate) fn convex_hull(p: &[Vector3<f64>]) -> Option<Vec<[usize; 3]>> {
    let n = p.len();
    if n < 4 {
        return None;
    }
    let scale = p
        .iter()
        .map(|q| q.amax())
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    let eps = 1e-10 * scale;
    // initial tetrahedron from well-spread points
    let i0 = 0;
    let i1 = (0..n).max_by(|&a, &b| {
        (p[a] - p[i0])
            .norm_squared()
            .total_cmp(&(p[b] - p[i0]).norm_squared())
    })?;
    let e = p[i1] - p[i0];
    if e.norm() <= eps {
        return None;
    }
    let i2 = (0..n).max_by(|&a, &b| {
        e.cross(&(p[a] - p[i0]))
            .norm_squared()
            .total_cmp(&e.cross(&(p[b] - p[i0])).norm_squared())
    })?;
    let nrm = e.cross(&(p[i2] - p[i0]));
    if nrm.norm() <= eps * e.norm() {
        return None;
    }
    let i3 = (0..n).max_by(|&a, &b| {
        nrm.dot(&(p[a] - p[i0]))
            .abs()
            .total_cmp(&nrm.dot(&(p[b] - p[i0])).abs())
    })?;
    let h = nrm.dot(&(p[i3] - p[i0])) / nrm.norm();
    if h.abs() <= 1e3 * eps {
        return None;
    }
    struct Tri {
        v: [usize; 3],
        n: Vector3<f64>,
        d: f64,
    }
    let make = |a: usize, b: usize, c: usize| -> Tri {
        let nn = (p[b] - p[a]).cross(&(p[c] - p[a]));
        let nn = nn / nn.norm();
        Tri {
            v: [a, b, c],
            n: nn,
            d: nn.dot(&p[a]),
        }
    };
    let mut tris: Vec<Tri> = if h > 0.0 {
        // i3 above (i0, i1, i2): that triangle faces down
        vec![
            make(i0, i2, i1),
            make(i0, i1, i3),
            make(i1, i2, i3),
            make(i2, i0, i3),
        ]
    } else {
        vec![
            make(i0, i1, i2),
            make(i0, i3, i1),
            make(i1, i3, i2),
            make(i2, i3, i0),
        ]
    };
    let used = [i0, i1, i2, i3];
    let mut horizon: Vec<(usize, usize)> = Vec::new();
    let mut visible = Vec::new();
    for (k, pk) in p.iter().enumerate() {
        if used.contains(&k) {
            continue;
        }
        visible.clear();
        visible.extend(tris.iter().map(|t| t.n.dot(pk) - t.d > eps));
        if !visible.iter().any(|&b| b) {
            continue;
        }
        horizon.clear();
        for (t, _) in tris.iter().zip(&visible).filter(|(_, v)| **v) {
            for j in 0..3 {
                horizon.push((t.v[j], t.v[(j + 1) % 3]));
            }
        }
        // an edge of a visible triangle is on the horizon when its twin is not visible
        let dir: std::collections::HashSet<(usize, usize)> = horizon.iter().copied().collect();
        horizon.retain(|&(a, b)| !dir.contains(&(b, a)));
        let mut keep = visible.iter().map(|v| !v);
        tris.retain(|_| keep.next().unwrap_or(true));
        for &(a, b) in &horizon {
            tris.push(make(a, b, k));
        }
    }
    Some(tris.into_iter().map(|t| t.v).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cube_mass_properties_are_the_closed_forms() {
        let s = BlockShape::cuboid([0.3; 3], 2500.0).unwrap();
        assert!((s.mass - 67.5).abs() < 1e-12);
        for i in 0..3 {
            assert!(
                (s.inertia[i] - 67.5 * 0.09 / 6.0).abs() < 1e-13,
                "{:?}",
                s.inertia
            );
        }
        assert_eq!(s.vertices.len(), 8);
        assert_eq!(s.faces.len(), 6);
        assert_eq!(s.edges.len(), 12);
        assert_eq!(s.resting_contacts(), 4);
        assert!((s.resting_r2() - 3.0 * 0.09).abs() < 1e-14);
        assert!((s.smallest_dimension - 0.3).abs() < 1e-14);
    }

    #[test]
    fn cuboid_inertia_and_tetrahedron_hull() {
        let s = BlockShape::cuboid([0.2, 0.4, 0.6], 1000.0).unwrap();
        let m = 1000.0 * 0.048;
        let exp = [
            m * (0.16 + 0.36) / 12.0,
            m * (0.04 + 0.36) / 12.0,
            m * (0.04 + 0.16) / 12.0,
        ];
        for (i, e) in exp.iter().enumerate() {
            assert!((s.inertia[i] - e).abs() < 1e-12 * m);
        }
        // regular tetrahedron of edge a: V = a³/(6√2), I = m a²/20 about any axis
        let a = 1.0_f64;
        let pts = [
            [1.0, 1.0, 1.0],
            [1.0, -1.0, -1.0],
            [-1.0, 1.0, -1.0],
            [-1.0, -1.0, 1.0],
        ]
        .map(|q| q.map(|c| c * a / 8f64.sqrt()));
        let t = BlockShape::hull(&pts, 1.0, Param::RockVertices).unwrap();
        assert!((t.volume - a.powi(3) / (6.0 * 2f64.sqrt())).abs() < 1e-14);
        for i in 0..3 {
            assert!((t.inertia[i] - t.mass * a * a / 20.0).abs() < 1e-14);
        }
        assert!(
            BlockShape::hull(
                &[[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]],
                1.0,
                Param::RockVertices
            )
            .is_err()
        );
    }

    #[test]
    fn random_polyhedron_repeats_by_seed_and_lies_inside_its_ellipsoid() {
        let a = BlockShape::random([0.3, 0.2, 0.1], 60, 7, 2500.0).unwrap();
        let b = BlockShape::random([0.3, 0.2, 0.1], 60, 7, 2500.0).unwrap();
        assert_eq!(a, b);
        assert!(a.volume > 0.0 && a.volume < 4.0 / 3.0 * std::f64::consts::PI * 0.006);
        // Euler's formula on the triangulated hull: every vertex on the hull
        assert!(a.vertices.len() <= 60 && a.vertices.len() >= 4);
    }

    #[test]
    fn hull_of_a_point_cloud_contains_every_point() {
        let mut rng = run_stream(3, 0);
        let pts: Vec<Vector3<f64>> = (0..500)
            .map(|_| {
                Vector3::new(
                    uniform01(&mut rng),
                    uniform01(&mut rng),
                    uniform01(&mut rng),
                )
            })
            .collect();
        let tris = convex_hull(&pts).unwrap();
        for t in &tris {
            let n = (pts[t[1]] - pts[t[0]])
                .cross(&(pts[t[2]] - pts[t[0]]))
                .normalize();
            for q in &pts {
                assert!(n.dot(&(q - pts[t[0]])) <= 1e-9);
            }
        }
        // closed surface: V − E + F = 2
        let v: std::collections::HashSet<usize> = tris.iter().flatten().copied().collect();
        assert_eq!(
            v.len() as i64 - 3 * tris.len() as i64 / 2 + tris.len() as i64,
            2
        );
    }
}
