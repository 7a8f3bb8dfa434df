//! A rock caught in place: the Zeno series of hops or slides at a node or crease told from
//! motion, and the way out (the facet or crease with the largest driving acceleration, or rest).

use super::*;

/// Number of consecutive flights shorter than [`trap_length`] after which the rock is taken to
/// be caught at a concave node or crease (a Zeno series of ever smaller hops at one point).
pub(super) const TRAP_HOPS: u32 = 3;

/// Number of consecutive pieces of any kind that keep the rock within 1000 × [`trap_length`]
/// (1e-6 of the facet size) of one point after which it is taken to be caught (a Zeno series
/// of ever shorter slides or swings about a node).
pub(super) const TRAP_STILL: u32 = 64;

/// Number of times a rock may be caught at one point and sent on before it is taken to be at
/// rest there (every way out has led back to it, with ever less energy).
pub(super) const TRAP_RETURNS: u32 = 4;

/// Length, m, below which a flight is a hop in place: 1e-9 of the floor's facet size.
pub(super) fn trap_length(floor: &Floor) -> f64 {
    1e-9 * floor.cell_size()
}

/// How a rock caught at a point (a node, an edge or a facet) goes on.
#[derive(Debug, Clone, Copy)]
pub(super) enum TrapExit {
    /// No facet or crease around the point lets gravity overcome friction: at rest.
    Rest(Option<Facet>),
    /// Slides (rolls) onto this facet along the unit direction of gravity's in-plane part.
    Facet(Facet, Vector3<f64>),
    /// Slides (rolls) along this crease (a concave edge both faces slope down to).
    Crease(Facet, Crease),
}

/// Decides how a rock caught at p (on the floor) leaves: onto the facet or along the crease
/// with the largest driving acceleration (gravity's part along the motion less friction), or
/// at rest when none is positive. A point mass in a V-shaped crease moves along the crease line.
pub(super) fn resolve_trap(
    floor: &Floor,
    p: &Vector3<f64>,
    g: f64,
    mu: f64,
    roll: bool,
) -> TrapExit {
    let gv = Vector3::new(0.0, 0.0, -g);
    let tol = 1e-7 * floor.cell_size();
    let mut facets: Vec<Facet> = Vec::new();
    for k in 0..24 {
        let a = std::f64::consts::TAU * k as f64 / 24.0;
        if let Some(f) = floor.locate(p.x, p.y, a.cos(), a.sin())
            && !facets.contains(&f)
        {
            facets.push(f);
        }
    }
    let mut best: Option<(f64, TrapExit)> = None;
    let mut consider = |drive: f64, ex: TrapExit| {
        if drive > 1e-12 * g && best.is_none_or(|b| drive > b.0) {
            best = Some((drive, ex));
        }
    };
    for &f in &facets {
        let pl = floor.facet_plane(f);
        let n = pl.normal();
        let gt = gv + n * (g * n.z);
        let gtn = gt.norm();
        let corners = floor.facet_corners(f);
        if gtn > 1e-12 * g {
            let into = match &corners {
                None => true,
                Some((c, _)) => {
                    let size = (0..3)
                        .map(|k| {
                            let (a, b) = (c[k], c[(k + 1) % 3]);
                            (b[0] - a[0]).hypot(b[1] - a[1])
                        })
                        .fold(f64::INFINITY, f64::min);
                    let h = gt.x.hypot(gt.y);
                    h > 0.0 && {
                        let eps = 1e-6 * size;
                        inside_tri(c, p.x + eps * gt.x / h, p.y + eps * gt.y / h, 0.0)
                    }
                }
            };
            let drive = if roll {
                gtn * (5.0 / 7.0)
            } else {
                gtn - mu * g * n.z
            };
            if into {
                consider(drive, TrapExit::Facet(f, gt / gtn));
            }
        }
        let Some((c, z)) = corners else { continue };
        for k in 0..3 {
            let (a, b) = (c[k], c[(k + 1) % 3]);
            let (ex, ey) = (b[0] - a[0], b[1] - a[1]);
            let len = ex.hypot(ey);
            if len == 0.0 {
                continue;
            }
            let off = (ex * (p.y - a[1]) - ey * (p.x - a[0])) / len;
            let u = ((p.x - a[0]) * ex + (p.y - a[1]) * ey) / len;
            if off.abs() > tol || u < -tol || u > len + tol {
                continue;
            }
            // horizontal normal of the edge pointing out of f
            let third = c[(k + 2) % 3];
            let mut out = Vector3::new(ey, -ex, 0.0);
            if out.x * (third[0] - a[0]) + out.y * (third[1] - a[1]) > 0.0 {
                out = -out;
            }
            let mid = [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])];
            let Some(fb) = floor.locate(mid[0], mid[1], out.x, out.y) else {
                continue;
            };
            if fb == f {
                continue;
            }
            let nb = floor.facet_plane(fb).normal();
            let p3 = Vector3::new(p.x, p.y, pl.z(p.x, p.y));
            for (q, qz) in [(a, z[k]), (b, z[(k + 1) % 3])] {
                if (q[0] - p.x).hypot(q[1] - p.y) <= tol {
                    continue;
                }
                let q3 = Vector3::new(q[0], q[1], qz);
                if let Some(cr) = crease_of([p3, q3], &n, &nb, &out, &Vector3::zeros(), g) {
                    let ge = gv.dot(&cr.e);
                    let drive = if roll {
                        ge * (5.0 / 7.0)
                    } else {
                        ge - mu * cr.n_tot
                    };
                    consider(drive, TrapExit::Crease(f, cr));
                }
            }
        }
    }
    match best {
        Some((_, ex)) => ex,
        None => TrapExit::Rest(facets.first().copied()),
    }
}

impl Run<'_, '_> {
    /// Updates the counters of hops and pieces in place; true when the rock is caught (hops or
    /// slides in place shrink geometrically and would never end).
    pub(super) fn is_caught_in_place(&mut self) -> bool {
        let (c, p) = (&mut self.catch, self.s.p);
        // squared distances against squared lengths: no square roots
        if (p - c.p_last).norm_squared() > c.len * c.len {
            c.hops = 0;
        }
        if (p - c.still_at).norm_squared() > (1e3 * c.len) * (1e3 * c.len) {
            c.still = 0;
            c.still_at = p;
        } else {
            c.still += 1;
        }
        c.p_last = p;
        c.hops >= TRAP_HOPS || c.still >= TRAP_STILL
    }

    /// Sends a rock caught at a node or crease on along the best way out ([`resolve_trap`]),
    /// keeping only its speed along it, or ends the run at rest there when there is none or
    /// every way out has led back to the same point.
    pub(super) fn leave_trap(&mut self) -> StepEnd {
        let (floor, g, mu, roll) = (self.floor, self.g, self.mu, self.roll);
        let ke_factor = self.ke_factor;
        let c = &mut self.catch;
        let s = &mut self.s;
        c.still = 0;
        // caught at a node or crease: hops or slides in place shrink geometrically and never end
        c.hops = 0;
        let kf = if s.ground.is_some() { ke_factor } else { 1.0 };
        let before = 0.5 * kf * s.v.norm_squared() + s.spin.0;
        s.spin = (0.0, Vector3::zeros());
        // caught again and again at the same point: every way out leads back to it
        if (s.p - c.anchor).norm() <= 1e-7 * floor.cell_size() {
            c.caught += 1;
        } else {
            c.anchor = s.p;
            c.caught = 1;
        }
        let exit = if c.caught > TRAP_RETURNS {
            let f = s.ground.or_else(|| floor.locate(s.p.x, s.p.y, 0.0, 0.0));
            TrapExit::Rest(f)
        } else {
            resolve_trap(floor, &s.p, g, mu, roll)
        };
        let (f, dir) = match exit {
            TrapExit::Rest(f) => {
                s.e_trans += before;
                s.v = Vector3::zeros();
                s.crease = None;
                if s.ground.is_none() {
                    s.ground = f;
                }
                return Some((Phase::Stopped, StopReason::AtRest));
            }
            TrapExit::Facet(f, dir) => {
                s.crease = None;
                (f, dir)
            }
            TrapExit::Crease(f, c) => {
                s.p = c.ends[0];
                s.crease = Some(c);
                (f, c.e)
            }
        };
        let vd = s.v.dot(&dir).max(0.0);
        s.v = dir * vd;
        s.e_trans += before - 0.5 * kf * vd * vd;
        let z = floor.facet_plane(f).z(s.p.x, s.p.y);
        set_floor_height(s, floor, z, g, kf);
        if s.ground.is_none() {
            self.enter_ground(f);
        } else {
            s.ground = Some(f);
        }
        None
    }
}
