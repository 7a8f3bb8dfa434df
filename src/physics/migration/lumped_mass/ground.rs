//! Ground motion: slides and rolls on a facet and along a crease in closed form, the
//! transitions at their edges, and a rock stuck at a crease or vertex set going again.

use super::*;

impl Run<'_, '_> {
    /// One piece along the crease `c` (a concave edge holding the rock): constant acceleration
    /// along the edge line up to its end, the lower end, the end time, a column or a stop.
    pub(super) fn crease_step(
        &mut self,
        c: Crease,
        t_left: f64,
        s_left: f64,
        moving: Phase,
    ) -> StepEnd {
        let (floor, gv, dip, mu, roll) = (self.floor, self.gv, self.dip, self.mu, self.roll);
        let g = self.g;
        let ke_factor = self.ke_factor;
        let s = &mut self.s;
        let ve = s.v.dot(&c.e);
        // the motion is along the crease line: a velocity part across it (left by a
        // correction at a vertex) is removed as a booked transition, never dropped
        let across = s.v.norm_squared() - ve * ve;
        if across > 0.0 {
            s.e_trans += 0.5 * ke_factor * across;
            s.v = c.e * ve;
        }
        let ge = gv.dot(&c.e);
        let (ae, dir) = if roll {
            (ge * (5.0 / 7.0), 0.0)
        } else {
            let dir = if ve.abs() <= REST_SPEED {
                s.e_fric += 0.5 * s.v.norm_squared();
                s.v = Vector3::zeros();
                if ge.abs() <= mu * c.n_tot * (1.0 + 1e-12) || ge.abs() <= 1e-12 * g {
                    return Some((Phase::Stopped, StopReason::AtRest));
                }
                ge.signum()
            } else {
                ve.signum()
            };
            (ge - dir * mu * c.n_tot, dir)
        };
        let ve = s.v.dot(&c.e);
        let t_s = reach_time(s_left, ve * c.e.dot(&dip), ae * c.e.dot(&dip));
        let mut t_max = t_s.min(t_left);
        let mut stop_at = f64::INFINITY;
        if !roll && ae * dir < 0.0 {
            stop_at = ve.abs() / ae.abs();
        }
        t_max = t_max.min(stop_at);
        t_max = zone_cut(
            self.zones,
            &s.p,
            &s.v,
            &dip,
            (&(c.e * ve), &(c.e * ae)),
            t_max,
        );
        let len = (c.ends[1] - c.ends[0]).dot(&c.e);
        // on the edge: a rounding error past an end would never cross it again
        let u0 = (s.p - c.ends[0]).dot(&c.e).clamp(0.0, len);
        let t_end_edge = super::super::terrain::outward_root(u0 - len, ve, ae)
            .into_iter()
            .chain(super::super::terrain::outward_root(-u0, -ve, -ae))
            .fold(f64::INFINITY, f64::min);
        let mut at_vertex = t_end_edge <= t_max;
        let mut dt = if at_vertex { t_end_edge } else { t_max };
        let col = self.column_reach(&(c.e * ve), &(c.e * ae), dt);
        if let Some((tc, _)) = col {
            dt = tc;
            at_vertex = false;
        }
        let du = ve * dt + 0.5 * ae * dt * dt;
        self.s.undecelerated = ae * ve >= 0.0;
        self.push_segment(|s| Segment {
            t0: s.t,
            dt,
            p0: s.p,
            v0: c.e * ve,
            a: c.e * ae,
            fric: c.e * (dir * mu * c.n_tot),
            // what this branch booked before the piece (a removed velocity part,
            // a rest) is part of its start
            diss0: s.e_imp + s.e_fric + s.e_trans + s.e_barrier,
            // rolling along the crease: the spin axis is horizontal-most normal to it
            rolling: roll.then(|| crease_up(&c.e)),
            spin: (0.0, Vector3::zeros()),
            on_floor: true,
        });
        let s = &mut self.s;
        s.p += c.e * du;
        s.v = c.e * (ve + ae * dt);
        s.t += dt;
        if !roll {
            s.e_fric += dir * mu * c.n_tot * du;
        }
        if let Some((_, k)) = col {
            self.hit = Some(k);
            return Some((moving, StopReason::Support));
        }
        if at_vertex {
            s.crease = None;
            let d3 = if s.v.norm() > 0.0 { s.v } else { c.e * ae };
            match floor.locate(s.p.x, s.p.y, d3.x, d3.y) {
                None => return Some((moving, StopReason::LeftFloor)),
                Some(fb) => {
                    self.change_facet(fb, None);
                }
            }
            return None;
        }
        if dt == t_s && t_s <= t_left {
            return Some((moving, StopReason::LowerEnd));
        }
        if dt == t_left {
            return Some((moving, StopReason::EndTime));
        }
        if dt == stop_at {
            s.e_fric += 0.5 * s.v.norm_squared();
            s.v = Vector3::zeros();
        }
        None
    }

    /// One closed-form piece of sliding or rolling on facet f: constant acceleration up to a
    /// facet edge (then [`Run::edge_transition`]), the lower end, the end time, a column, the
    /// stop of the speed along the friction direction or a turn of [`MAX_TURN`].
    pub(super) fn ground_step(
        &mut self,
        f: Facet,
        t_left: f64,
        s_left: f64,
        diss0: f64,
        moving: Phase,
    ) -> StepEnd {
        let (floor, g, gv, dip, mu, roll) =
            (self.floor, self.g, self.gv, self.dip, self.mu, self.roll);
        let ke_factor = self.ke_factor;
        let s = &mut self.s;
        let pl = floor.facet_plane(f);
        let n = pl.normal();
        let gn = g * n.z;
        let gt = gv + n * (g * n.z);
        // the closed-form piece moves in the facet's plane: a velocity part along its
        // normal beyond rounding is removed as a booked transition (energy is never
        // lost without being counted, nor the rock carried off the facet)
        let vn = s.v.dot(&n);
        if vn.abs() > 1e-9 * s.v.norm() {
            s.e_trans += 0.5 * ke_factor * vn * vn;
            s.v -= n * vn;
        }
        let speed = s.v.norm();
        let (a, fdir) = if roll {
            if speed <= REST_SPEED && gt.norm() <= 1e-12 * g {
                s.v = Vector3::zeros();
                return Some((Phase::Stopped, StopReason::AtRest));
            }
            (gt * (5.0 / 7.0), Vector3::zeros())
        } else {
            let fdir = if speed <= REST_SPEED {
                s.e_fric += 0.5 * speed * speed;
                s.v = Vector3::zeros();
                let gtn = gt.norm();
                if gtn <= mu * gn * (1.0 + 1e-12) || gtn <= 1e-12 * g {
                    return Some((Phase::Stopped, StopReason::AtRest));
                }
                gt / gtn
            } else {
                s.v / speed
            };
            (gt - fdir * (mu * gn), fdir)
        };
        // candidate ends of this constant-acceleration piece
        let t_s = reach_time(s_left, s.v.dot(&dip), a.dot(&dip));
        let mut t_max = t_s.min(t_left);
        let mut stop_at = f64::INFINITY;
        let mut turn_at = f64::INFINITY;
        if !roll {
            let ad = a.dot(&fdir);
            if ad < 0.0 {
                stop_at = s.v.dot(&fdir) / -ad;
            }
            let aperp = (a - fdir * ad).norm();
            if aperp > 1e-12 * g {
                // |v| is `speed`, or 0 after a rest above (both give REST_SPEED here)
                turn_at = MAX_TURN * speed.max(REST_SPEED) / aperp;
            }
            s.undecelerated = ad >= 0.0;
        } else {
            s.undecelerated = a.dot(&s.v) >= 0.0;
        }
        t_max = t_max.min(stop_at).min(turn_at);
        t_max = zone_cut(self.zones, &s.p, &s.v, &dip, (&s.v, &a), t_max);
        // on a coplanar patch of a grid, one piece to the patch's boundary
        let mut exit = floor.slide_exit_merged(f, &s.p, &s.v, &a, t_max);
        let mut dt = exit.map_or(t_max, |e| e.0);
        let col = self.column_reach(&self.s.v, &a, dt);
        if let Some((tc, _)) = col {
            dt = tc;
            exit = None;
        }
        let fric = fdir * (mu * gn);
        self.push_segment(|s| Segment {
            t0: s.t,
            dt,
            p0: s.p,
            v0: s.v,
            a,
            fric,
            diss0,
            rolling: roll.then_some(n),
            spin: (0.0, Vector3::zeros()),
            on_floor: true,
        });
        let s = &mut self.s;
        let dp = s.v * dt + a * (0.5 * dt * dt);
        s.p += dp;
        s.v += a * dt;
        s.t += dt;
        if !roll {
            s.e_fric += fric.dot(&dp);
        }
        if dt == 0.0 {
            self.zero_steps += 1;
        } else {
            self.zero_steps = 0;
        }
        if exit.is_none() && floor.in_patch(f) {
            // a piece across a coplanar patch that ends inside it: on the facet under the rock
            // (to rounding, its plane is f's)
            if let Some(fq) = floor.locate(s.p.x, s.p.y, s.v.x, s.v.y)
                && fq != f
            {
                s.ground = Some(fq);
                let z = floor.facet_plane(fq).z(s.p.x, s.p.y);
                set_floor_height(s, floor, z, g, ke_factor);
            }
        }
        if let Some((_, k)) = col {
            self.hit = Some(k);
            return Some((moving, StopReason::Support));
        }
        if let Some((_, next, edge)) = exit {
            return self.edge_transition(n, a, next, edge, moving);
        }
        if dt == t_s && t_s <= t_left {
            return Some((moving, StopReason::LowerEnd));
        }
        if dt == t_left {
            return Some((moving, StopReason::EndTime));
        }
        if dt == stop_at {
            // the speed along the friction direction is zero: keep the rest
            let vd = s.v.dot(&fdir);
            let before = s.v.norm_squared();
            s.v -= fdir * vd;
            s.e_fric += 0.5 * (before - s.v.norm_squared());
        }
        None
    }

    /// The rock sliding (rolling) with acceleration `a` on a facet with normal `n` reached its
    /// edge `edge` towards facet `next` (None: off the floor): onto the next facet (projected
    /// onto it, or taking off at a convex edge), into the crease when the edge is a concave one
    /// that holds it, and — stuck on a vertex by rounding — moved on a hair.
    pub(super) fn edge_transition(
        &mut self,
        n: Vector3<f64>,
        a: Vector3<f64>,
        next: Option<Facet>,
        edge: [[f64; 2]; 2],
        moving: Phase,
    ) -> StepEnd {
        let g = self.g;
        let ke_factor = self.ke_factor;
        let Some(fb) = next else {
            return Some((moving, StopReason::LeftFloor));
        };
        if let Some(plb) = self.change_facet(fb, Some(n)) {
            let s = &mut self.s;
            let nb = plb.normal();
            let ends = edge.map(|q| Vector3::new(q[0], q[1], plb.z(q[0], q[1])));
            let d = ends[1] - ends[0];
            let out_a = Vector3::new(d.y, -d.x, 0.0);
            if let Some(c) = crease_of(ends, &n, &nb, &out_a, &s.v, g) {
                let ve = s.v.dot(&c.e);
                let before = s.v.norm_squared();
                s.v = c.e * ve;
                s.e_trans += 0.5 * ke_factor * (before - ve * ve);
                // on the edge line through the crossing point
                let u = (s.p - c.ends[0]).dot(&c.e);
                let q = c.ends[0] + c.e * u;
                s.p.x = q.x;
                s.p.y = q.y;
                set_height(s, q.z, g, ke_factor);
                s.crease = Some(c);
            }
        }
        if self.zero_steps > 16
            && let Some(c) = self.s.crease
        {
            return self.unstick_along_crease(c, n, moving);
        } else if self.zero_steps > 16 {
            return self.unstick_at_vertex(n, a, moving);
        }
        None
    }

    /// Stuck at a vertex on the crease `c` (the old facet's normal `n`): moves a hair along the
    /// crease line itself, or — a rise the rock cannot pay for — ends the run at rest there.
    pub(super) fn unstick_along_crease(
        &mut self,
        c: Crease,
        n: Vector3<f64>,
        moving: Phase,
    ) -> StepEnd {
        let (floor, g, gv, ke_factor) = (self.floor, self.g, self.gv, self.ke_factor);
        let s = &mut self.s;
        // stuck at a vertex on a crease: move a hair along the crease line
        // itself. Moved along the old facet's slope instead, a rock 1e-8 m
        // beside a steep crease ran parallel to it under the facet rising from
        // it (1.7e-8 m below the floor).
        let ve = s.v.dot(&c.e);
        let ext = floor.extent();
        let eps = 1e-9 * (ext[1] - ext[0]).abs().clamp(1e-3, 1e3);
        let len = (c.ends[1] - c.ends[0]).dot(&c.e);
        let along = (s.p - c.ends[0]).dot(&c.e);
        let ke = 0.5 * ke_factor * s.v.norm_squared();
        // along the motion (at rest: downhill)
        let sgn = if ve != 0.0 { ve } else { gv.dot(&c.e) }.signum();
        let rise = |sg: f64| g * ((c.ends[0] + c.e * (along + sg * eps)).z - s.p.z);
        let u = along + sgn * eps;
        let q = c.ends[0] + c.e * u;
        if (0.0..=len).contains(&u) && rise(sgn) > ke {
            // a rise it cannot pay for: trapped at the bottom of the crease,
            // at rest where it is (moved, it would book a negative
            // loss: 2.3e-5 J for a 3.4e-8 m lift)
            s.e_trans += ke;
            s.v = Vector3::zeros();
            return Some((Phase::Stopped, StopReason::AtRest));
        }
        s.p.x = q.x;
        s.p.y = q.y;
        if (0.0..=len).contains(&u) {
            set_height(s, q.z, g, ke_factor);
        } else {
            // past the crease's end: onto the facet beyond it
            s.crease = None;
            let dir = c.e * sgn;
            match floor.locate(s.p.x, s.p.y, dir.x, dir.y) {
                Some(fc) => {
                    self.change_facet(fc, Some(n));
                }
                None => return Some((moving, StopReason::LeftFloor)),
            }
        }
        self.zero_steps = 0;
        None
    }

    /// Stuck on a vertex by rounding (on a facet with normal `n`, acceleration `a`): moves a
    /// hair along the motion onto the facet there.
    pub(super) fn unstick_at_vertex(
        &mut self,
        n: Vector3<f64>,
        a: Vector3<f64>,
        moving: Phase,
    ) -> StepEnd {
        let (floor, g, ke_factor) = (self.floor, self.g, self.ke_factor);
        let s = &mut self.s;
        // stuck on a vertex by rounding: move a hair along the motion
        let dir = if s.v.norm() > 0.0 { s.v } else { a };
        let h = (dir.x * dir.x + dir.y * dir.y).sqrt();
        if h > 0.0 {
            let ext = floor.extent();
            let eps = 1e-9 * (ext[1] - ext[0]).abs().clamp(1e-3, 1e3);
            s.p.x += eps * dir.x / h;
            s.p.y += eps * dir.y / h;
        }
        match floor.locate(s.p.x, s.p.y, dir.x, dir.y) {
            Some(fc) if s.ground.is_some() && s.crease.is_none() => {
                // onto the new facet like at an edge: the velocity is projected
                // onto its plane (or the rock takes off), the loss booked
                self.change_facet(fc, Some(n));
            }
            Some(fc) => {
                if s.ground.is_some() {
                    s.ground = Some(fc);
                }
                let kf = if s.ground.is_some() { ke_factor } else { 1.0 };
                let z = floor.facet_plane(fc).z(s.p.x, s.p.y);
                set_floor_height(s, floor, z, g, kf);
            }
            None => return Some((moving, StopReason::LeftFloor)),
        }
        self.zero_steps = 0;
        None
    }
}
