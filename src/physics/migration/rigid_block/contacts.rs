//! Contact detection of the block on the floor: the vertices of a polyhedron against the
//! facets under them, floor peaks and convex creases against its faces and edges, a sphere
//! against the mesh; the closest point on a triangle.

use super::super::terrain::inside_tri;
use super::*;

impl Model<'_> {
    /// Contacts of the block at (c, R), appended to `out`; true when a block vertex is off the
    /// floor below the floor's level there (see [`Model::vertex_face_contacts`]).
    pub(super) fn contacts(
        &self,
        c: &Vector3<f64>,
        r: &Matrix3<f64>,
        tris: &mut Vec<FloorTriangle>,
        out: &mut Vec<Geo>,
    ) -> bool {
        out.clear();
        let sh = &self.shape;
        match &self.floor.kind {
            FloorKind::Plane(pl) => {
                let n = pl.normal();
                let nz = n.z;
                if let Some(rad) = sh.sphere_radius {
                    let d = pl.height(c) * nz - rad;
                    if d < 0.0 {
                        out.push(Geo {
                            key: 0,
                            feature: 0,
                            p: c - n * rad,
                            n,
                            u: -d,
                        });
                    }
                    return false;
                }
                // cheap reject: the centre farther than r_max
                if pl.height(c) * nz > sh.r_max {
                    return false;
                }
                for (i, b) in sh.vertices.iter().enumerate() {
                    let p = c + r * b;
                    let d = pl.height(&p) * nz;
                    if d < 0.0 {
                        out.push(Geo {
                            key: i as u64,
                            feature: i as u64,
                            p,
                            n,
                            u: -d,
                        });
                    }
                }
                false
            }
            _ => self.contacts_mesh(c, r, tris, out),
        }
    }

    /// Contacts of the block (centre `c`, orientation `r`) with a mesh floor: vertex–face,
    /// and, unless the floor under the block is one flat patch, face–vertex (floor peaks) and
    /// edge–edge (convex creases); `tris` is scratch for the floor triangles near the block.
    /// True when a block vertex is off the floor below its level (the block leaves the floor).
    pub(super) fn contacts_mesh(
        &self,
        c: &Vector3<f64>,
        r: &Matrix3<f64>,
        tris: &mut Vec<FloorTriangle>,
        out: &mut Vec<Geo>,
    ) -> bool {
        let sh = &self.shape;
        let fl = self.floor;
        // clear of the floor under the centre by more than r_max (1 + s): no contact
        let under = fl.locate(c.x, c.y, 0.0, 0.0).map(|f| fl.facet_plane(f));
        if let Some(pl) = under
            && pl.height(c) > self.clear_drop
        {
            return false;
        }
        if let Some(rad) = sh.sphere_radius {
            self.sphere_mesh_contacts(c, rad, tris, out);
            return false;
        }
        let world: Vec<Vector3<f64>> = sh.vertices.iter().map(|b| c + r * b).collect();
        let off_floor = self.vertex_face_contacts(&world, under.as_ref(), tris, out);
        // floor features inside the block's plan box (padded)
        let (mut x0, mut x1, mut y0, mut y1) = (
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        );
        let mut z_min = f64::INFINITY;
        for p in &world {
            x0 = x0.min(p.x);
            x1 = x1.max(p.x);
            y0 = y0.min(p.y);
            y1 = y1.max(p.y);
            z_min = z_min.min(p.z);
        }
        tris.clear();
        let pad = 1e-9 * (1.0 + sh.r_max);
        fl.triangles_in([x0 - pad, x1 + pad, y0 - pad, y1 + pad], tris);
        // a flat patch has no floor peak and no convex crease: its contacts are the vertex–face
        // ones found above (this skips the quadratic searches below on planar floor regions)
        if tris.is_empty() || one_flat_patch(tris, sh.r_max) {
            return off_floor;
        }
        // the block's faces in the world frame: (outward normal, offset)
        let faces_w: Vec<(Vector3<f64>, f64)> = sh
            .faces
            .iter()
            .map(|f| {
                let n = r * f.normal;
                (n, f.offset + n.dot(c))
            })
            .collect();
        floor_peak_contacts(tris, z_min, &faces_w, out);
        self.crease_contacts(tris, &world, &faces_w, out);
        off_floor
    }

    /// Vertex–face contacts: each block vertex (`world`: their positions) below the facet
    /// under it, its overlap the distance to the floor's surface and its normal the direction
    /// to the nearest surface point (see [`Model::depth_below_surface`]); `tris`: scratch.
    ///
    /// Returns true when a vertex off the floor (beyond its edge or over a hole) is below the
    /// floor's level there: a hole's surface filled in from the data around it, beyond a grid's
    /// edge the nearest facet's plane continued, beyond a contour floor's the plane of the
    /// facet under the centre (`under`). Such a vertex has no floor to push it up: the block
    /// leaves the floor there, as a point mass does at its edge (physics.md §C.2, api.md
    /// `left_floor`). Carried on, the vertex would come back over the floor already deep, its
    /// spring's ½kₙU² created from nothing.
    pub(super) fn vertex_face_contacts(
        &self,
        world: &[Vector3<f64>],
        under: Option<&super::super::terrain::FacetPlane>,
        tris: &mut Vec<FloorTriangle>,
        out: &mut Vec<Geo>,
    ) -> bool {
        let fl = self.floor;
        let mut off_floor = false;
        for (i, p) in world.iter().enumerate() {
            let Some(f) = fl.locate(p.x, p.y, 0.0, 0.0) else {
                let level = fl
                    .level_off_floor(p.x, p.y)
                    .or(under.map(|pl| pl.z(p.x, p.y)));
                off_floor |= level.is_some_and(|z| p.z < z);
                continue;
            };
            let pl = fl.facet_plane(f);
            let height = pl.height(p);
            if height < 0.0 {
                let (u, n) = self.depth_below_surface(p, f, -height, tris);
                out.push(Geo {
                    key: i as u64,
                    feature: i as u64,
                    p: *p,
                    n,
                    u,
                });
            }
        }
        off_floor
    }

    /// Depth (m) of the point `p`, `depth` m vertically below facet `f` (the facet under it),
    /// below the floor's surface, and the unit normal pushing it out: the distance to the
    /// nearest surface point and the direction to it. Away from the facet's edges (its plan
    /// triangle holds the disc of radius `depth` around p) that is the distance to the facet's
    /// plane along its normal; near an edge the nearest point may lie on a neighbour or on the
    /// crease itself. So the overlap is continuous as a vertex passes from facet to facet in
    /// plan (the distance to the surface is), and the spring's ½kₙU² is the potential of its
    /// force: measured against the plane of the facet under it alone, the overlap would jump
    /// by the ratio of the two facets' normals' z at a crease, and the energy with it.
    /// `tris`: scratch for the triangles near p.
    pub(super) fn depth_below_surface(
        &self,
        p: &Vector3<f64>,
        f: super::super::terrain::Facet,
        depth: f64,
        tris: &mut Vec<FloorTriangle>,
    ) -> (f64, Vector3<f64>) {
        let fl = self.floor;
        let pl = fl.facet_plane(f);
        let n = pl.normal();
        let d = depth * n.z;
        // every surface point within `depth` of p lies over the facet: its plane's distance
        let inside = fl
            .facet_corners(f)
            .is_none_or(|(c, _)| inside_tri(&c, p.x, p.y, -depth));
        if inside {
            return (d, n);
        }
        tris.clear();
        fl.triangles_in([p.x - depth, p.x + depth, p.y - depth, p.y + depth], tris);
        let mut best = (d, n);
        let mut best_dist = f64::INFINITY;
        for t in tris.iter() {
            let (q, feat) = closest_on_triangle(p, &t.corners);
            let e = (q - p).norm();
            if e >= best_dist {
                continue;
            }
            best_dist = e;
            let nt = triangle_normal(t);
            best = if feat == TriFeature::Face && nt.dot(&n) >= 1.0 - 1e-12 {
                // inside the facet or a coplanar neighbour: its plane's distance, as away
                // from the edges
                (d, n)
            } else if e > 0.0 {
                (e, (q - p) / e)
            } else {
                (0.0, n)
            };
        }
        best
    }

    /// Edge–edge contacts: block edges (vertices at `world`) crossed by the convex floor
    /// creases of `tris` (a crease whose far vertex lies below the other facet's plane).
    pub(super) fn crease_contacts(
        &self,
        tris: &[FloorTriangle],
        world: &[Vector3<f64>],
        faces_w: &[(Vector3<f64>, f64)],
        out: &mut Vec<Geo>,
    ) {
        let sh = &self.shape;
        let inside = |x: &Vector3<f64>| inside_depth(faces_w, x);
        let mut seen: Vec<(u32, u32)> = Vec::new();
        for (ti, t) in tris.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (t.ids[k], t.ids[(k + 1) % 3]);
                let key = (a.min(b), a.max(b));
                if seen.contains(&key) {
                    continue;
                }
                // the other triangle of this edge
                let Some(t2) = tris
                    .iter()
                    .enumerate()
                    .find(|(j, u)| *j != ti && u.ids.contains(&a) && u.ids.contains(&b))
                    .map(|(_, u)| u)
                else {
                    continue;
                };
                seen.push(key);
                let (pa, pb) = (t.corners[k], t.corners[(k + 1) % 3]);
                let n1 = triangle_normal(t);
                let n2 = triangle_normal(t2);
                // convex crease: the far vertex of t2 lies below t's plane
                let far = (0..3)
                    .find(|&j| t2.ids[j] != a && t2.ids[j] != b)
                    .map(|j| t2.corners[j]);
                let Some(far) = far else { continue };
                if n1.dot(&(far - pa)) >= -1e-9 * (far - pa).norm() || n1.dot(&n2) > 1.0 - 1e-12 {
                    continue;
                }
                for (ei, e) in sh.edges.iter().enumerate() {
                    let (qa, qb) = (world[e[0]], world[e[1]]);
                    let [fa, fb] = sh.edge_faces[ei];
                    let cones = [n1, n2, faces_w[fa].0, faces_w[fb].0];
                    if let Some(geo) = edge_contact(&qa, &qb, &pa, &pb, &cones, &inside) {
                        let h = (u64::from(key.0).wrapping_mul(0x9E37_79B9_7F4A_7C15)
                            ^ u64::from(key.1))
                            & ((1 << 40) - 1);
                        let key = (2 << 62) | ((ei as u64) << 40) | h;
                        out.push(Geo {
                            key,
                            feature: key,
                            ..geo
                        });
                    }
                }
            }
        }
    }

    /// Contacts of a sphere (centre c, radius `rad`) with a mesh floor: every facet within reach,
    /// each touched at its closest point to the centre (inside the facet, on an edge or at a
    /// corner), normal from that point to the centre. An edge or corner touch counts once, and
    /// not at all when a facet sharing that edge or corner is strictly closer (a flat or concave
    /// seam is felt through the faces beside it; a convex crease or peak through its edge or
    /// corner). The deepest contact carries the sphere's shear spring from facet to facet (key
    /// 0); the others have springs of their own floor feature.
    pub(super) fn sphere_mesh_contacts(
        &self,
        c: &Vector3<f64>,
        rad: f64,
        tris: &mut Vec<FloorTriangle>,
        out: &mut Vec<Geo>,
    ) {
        tris.clear();
        self.floor
            .triangles_in([c.x - rad, c.x + rad, c.y - rad, c.y + rad], tris);
        // (floor feature by corner ids, distance, closest point) of every facet within reach
        let mut near: Vec<([u32; 3], f64, Vector3<f64>)> = Vec::with_capacity(tris.len());
        let mut best = Vec::with_capacity(tris.len());
        for t in tris.iter() {
            let (q, feat) = closest_on_triangle(c, &t.corners);
            let d = (c - q).norm();
            best.push(d);
            if d >= rad || d <= 0.0 {
                continue;
            }
            // the feature's corner ids, sorted, u32::MAX for none
            let mut ids = match feat {
                TriFeature::Face => t.ids,
                TriFeature::Edge(a, b) => [t.ids[a], t.ids[b], u32::MAX],
                TriFeature::Corner(k) => [t.ids[k], u32::MAX, u32::MAX],
            };
            ids.sort_unstable();
            near.push((ids, d, q));
        }
        // faces before edges before corners, nearest first
        near.sort_by(|x, y| {
            let dim = |ids: &[u32; 3]| ids.iter().filter(|&&k| k == u32::MAX).count();
            dim(&x.0).cmp(&dim(&y.0)).then(x.1.total_cmp(&y.1))
        });
        let first = out.len();
        let mut taken: Vec<[u32; 3]> = Vec::new();
        for (ids, d, q) in &near {
            if taken.contains(ids) {
                continue;
            }
            taken.push(*ids);
            // an edge or corner touch is shadowed by a strictly closer facet sharing it
            let corners: Vec<u32> = ids.iter().copied().filter(|&k| k != u32::MAX).collect();
            let shadowed = corners.len() < 3
                && tris.iter().zip(&best).any(|(t, bd)| {
                    corners.iter().all(|k| t.ids.contains(k))
                        && *bd < d * (1.0 - 1e-12)
                        && covers(tris, t, &corners, rad)
                });
            if shadowed {
                continue;
            }
            let n = (c - q) / *d;
            let p = c - n * rad;
            // the same touch seen from two facets (a point on or next to their common seam)
            // counts once. "Next to": within 1e-5 r, where the shadowing above cannot tell
            // the facets' distances apart (they differ by δ²/2r, below its relative 1e-12 for a
            // point δ < 1.4e-6 r off a flat seam); at 1e-9 r a sphere rolling along a flat
            // grid's seam line had its touch doubled there, switching off at full depth, and
            // lost 1 % of its energy unbooked, dt-independent.
            if out[first..].iter().any(|g| (g.p - p).norm() <= 1e-5 * rad) {
                continue;
            }
            let h = ids.iter().fold(0u64, |h, &k| {
                (h ^ u64::from(k)).wrapping_mul(0x9E37_79B9_7F4A_7C15)
            });
            out.push(Geo {
                key: (3 << 62) | (h >> 2),
                feature: (3 << 62) | (h >> 2),
                p,
                n,
                u: rad - d,
            });
        }
        // the deepest contact carries the sphere's own spring
        if let Some(k) = (first..out.len()).max_by(|&i, &j| out[i].u.total_cmp(&out[j].u)) {
            out[k].key = 0;
        }
    }
}

/// True when the facets of `tris` around the edge or corner `corners` (ids) lie on or below
/// the plane of facet `t`, one of them: the floor there is flat or convex as seen from `t`,
/// whose half-space holds it, so a touch of that edge or corner is already felt through `t`
/// (`rad`: the sphere's radius, m, for the rounding tolerance). Across a concave seam or into
/// a pit the floor rises above `t`'s plane and the touch is a contact of its own: shadowing it
/// there would drop a closed contact (or switch one on) deep inside the sphere.
pub(super) fn covers(tris: &[FloorTriangle], t: &FloorTriangle, corners: &[u32], rad: f64) -> bool {
    let mut n = triangle_normal(t);
    if n.z < 0.0 {
        n = -n;
    }
    let o = t.corners[0];
    let tol = 1e-12 * (1.0 + rad + o.norm());
    tris.iter()
        .filter(|t2| corners.iter().all(|k| t2.ids.contains(k)))
        .all(|t2| t2.corners.iter().all(|y| n.dot(&(y - o)) <= tol))
}

/// Depth inside the block and nearest face of a point, or None outside.
pub(super) type InsideFn<'a> = dyn Fn(&Vector3<f64>) -> Option<(f64, usize)> + 'a;

/// Unit normal of a floor triangle, oriented by the order of its corners.
pub(super) fn triangle_normal(t: &FloorTriangle) -> Vector3<f64> {
    (t.corners[1] - t.corners[0])
        .cross(&(t.corners[2] - t.corners[0]))
        .normalize()
}

/// True when the triangles `tris` lie on one plane (to rounding, for a block of bounding
/// radius `r_max`, m): a flat patch with no peak and no crease.
pub(super) fn one_flat_patch(tris: &[FloorTriangle], r_max: f64) -> bool {
    let (n0, o0) = (triangle_normal(&tris[0]), tris[0].corners[0]);
    let tol = 1e-12 * (1.0 + r_max + o0.norm());
    tris.iter().all(|t| {
        triangle_normal(t).dot(&n0) >= 1.0 - 1e-12
            && t.corners.iter().all(|x| n0.dot(&(x - o0)).abs() <= tol)
    })
}

/// Depth (m) of the point `x` inside the block of world-frame faces `faces_w` (outward
/// normal, offset) and its nearest face, or None outside.
pub(super) fn inside_depth(
    faces_w: &[(Vector3<f64>, f64)],
    x: &Vector3<f64>,
) -> Option<(f64, usize)> {
    let mut best = (f64::INFINITY, 0usize);
    for (k, (n, off)) in faces_w.iter().enumerate() {
        let d = off - n.dot(x);
        if d <= 0.0 {
            return None;
        }
        if d < best.0 {
            best = (d, k);
        }
    }
    Some(best)
}

/// Face–vertex contacts: floor vertices of `tris` (not below the block's lowest vertex at
/// `z_min`, m) inside the block (faces `faces_w`) that poke towards its nearest face (every
/// neighbour lower along that face's normal).
pub(super) fn floor_peak_contacts(
    tris: &[FloorTriangle],
    z_min: f64,
    faces_w: &[(Vector3<f64>, f64)],
    out: &mut Vec<Geo>,
) {
    let mut done: Vec<u32> = Vec::new();
    for t in tris {
        for k in 0..3 {
            let id = t.ids[k];
            let x = t.corners[k];
            if x.z < z_min || done.contains(&id) {
                continue;
            }
            done.push(id);
            let Some((depth, face)) = inside_depth(faces_w, &x) else {
                continue;
            };
            let nf = faces_w[face].0;
            // a peak towards the face: every neighbour lower along the face normal
            let mut peak = true;
            let mut any = false;
            for t2 in tris {
                for k2 in 0..3 {
                    if t2.ids[k2] == id {
                        for y in [t2.corners[(k2 + 1) % 3], t2.corners[(k2 + 2) % 3]] {
                            any = true;
                            let e = x - y;
                            if (-nf).dot(&e) <= 1e-6 * e.norm() {
                                peak = false;
                            }
                        }
                    }
                }
            }
            if peak && any {
                out.push(Geo {
                    key: (1 << 62) | u64::from(id),
                    feature: (1 << 62) | u64::from(id),
                    p: x,
                    n: -nf,
                    u: depth,
                });
            }
        }
    }
}

/// Edge–edge contact of block edge (qa, qb) with floor crease (pa, pb): the common
/// perpendicular when both closest points are interior, the floor point inside the block and
/// the normal inside both edges' normal cones (`cones`: the crease's two facet normals, then
/// the block edge's two face normals).
pub(super) fn edge_contact(
    qa: &Vector3<f64>,
    qb: &Vector3<f64>,
    pa: &Vector3<f64>,
    pb: &Vector3<f64>,
    cones: &[Vector3<f64>; 4],
    inside: &InsideFn<'_>,
) -> Option<Geo> {
    let [n1, n2, b1, b2] = *cones;
    let up = n1 + n2;
    let d1 = qb - qa;
    let d2 = pb - pa;
    let mut n = d1.cross(&d2);
    let nn = n.norm();
    if nn <= 1e-9 * d1.norm() * d2.norm() {
        return None;
    }
    n /= nn;
    if n.dot(&up) < 0.0 {
        n = -n;
    }
    // A genuine edge–edge contact pushes along a normal in both edges' normal cones: between
    // the crease's two facet normals, and (reversed) between the block edge's two face normals.
    let between = |a: &Vector3<f64>, b: &Vector3<f64>, x: &Vector3<f64>| {
        let s = a.cross(b);
        a.cross(x).dot(&s) >= 0.0 && x.cross(b).dot(&s) >= 0.0
    };
    if !between(&n1, &n2, &n) || !between(&b1, &b2, &(-n)) {
        return None;
    }
    // closest points
    let r = qa - pa;
    let (a, e, f) = (d1.dot(&d1), d2.dot(&d2), d2.dot(&r));
    let (b, c) = (d1.dot(&d2), d1.dot(&r));
    let den = a * e - b * b;
    if den <= 0.0 {
        return None;
    }
    let s = (b * f - c * e) / den;
    let t = (a * f - b * c) / den;
    if !(s > 0.0 && s < 1.0 && t > 0.0 && t < 1.0) {
        return None;
    }
    let p_block = qa + d1 * s;
    let p_floor = pa + d2 * t;
    let depth = (p_floor - p_block).dot(&n);
    if depth <= 0.0 {
        return None;
    }
    inside(&p_floor)?;
    Some(Geo {
        key: 0,
        feature: 0,
        p: p_block,
        n,
        u: depth,
    })
}

/// Where on a triangle the closest point to a point lies.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum TriFeature {
    /// Inside the facet.
    Face,
    /// On the edge between corners (i, j).
    Edge(usize, usize),
    /// At corner i.
    Corner(usize),
}

/// The point of triangle `t` closest to `p`, and its feature (Ericson, Real-Time Collision
/// Detection §5.1.5, by the Voronoi regions of the corners and edges).
pub(super) fn closest_on_triangle(
    p: &Vector3<f64>,
    t: &[Vector3<f64>; 3],
) -> (Vector3<f64>, TriFeature) {
    let [a, b, c] = *t;
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(&ap), ac.dot(&ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return (a, TriFeature::Corner(0));
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(&bp), ac.dot(&bp));
    if d3 >= 0.0 && d4 <= d3 {
        return (b, TriFeature::Corner(1));
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (a + ab * v, TriFeature::Edge(0, 1));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(&cp), ac.dot(&cp));
    if d6 >= 0.0 && d5 <= d6 {
        return (c, TriFeature::Corner(2));
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (a + ac * w, TriFeature::Edge(0, 2));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (b + (c - b) * w, TriFeature::Edge(1, 2));
    }
    let den = 1.0 / (va + vb + vc);
    let (v, w) = (vb * den, vc * den);
    (a + ab * v + ac * w, TriFeature::Face)
}
