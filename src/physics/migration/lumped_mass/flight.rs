//! Flight: the closed-form parabola to the first strike, the lower end, the end time or a
//! support, and the impact (restitution, landing, the rebound's apex).

use super::*;

impl Run<'_, '_> {
    /// One flight: the parabola up to its first strike of the floor, the lower end, the end
    /// time, a column or the floor's edge; a strike is an impact.
    pub(super) fn flight_step(
        &mut self,
        draw: &mut impl FnMut() -> (f64, f64),
        t_left: f64,
        s_left: f64,
        diss0: f64,
    ) -> StepEnd {
        let (floor, g, gv, dip, su) = (self.floor, self.g, self.gv, self.dip, self.su);
        let s = &self.s;
        let t_s = reach_time(s_left, s.v.dot(&dip), gv.dot(&dip));
        let t_lim = t_s.min(t_left);
        // t_s is formed from the whole flight; whether a strike comes before the lower
        // end is decided by its point, measured from the last floor point (local terms)
        let t_q = if t_s < t_left {
            (t_s * (1.0 + 1e-9)).min(t_left)
        } else {
            t_lim
        };
        let mut past_end = None;
        let end = match floor.flight(&s.p, &s.v, g, t_q) {
            FlightEnd::Hit { t, facet } => {
                let q = s.p + s.v * t + gv * (0.5 * t * t);
                let zq = floor.facet_plane(facet).z(q.x, q.y);
                let dq = Vector3::new(q.x - s.r.x, q.y - s.r.y, zq - s.r.z);
                if s.s_r + dq.dot(&dip) < su.length {
                    FlightEnd::Hit { t, facet }
                } else {
                    past_end = Some(t);
                    FlightEnd::Clear
                }
            }
            FlightEnd::Leaves { t } if t > t_lim => FlightEnd::Clear,
            e => e,
        };
        let dt = match end {
            FlightEnd::Hit { t, .. } | FlightEnd::Leaves { t } => t,
            FlightEnd::Clear => past_end.map_or(t_lim, |t| t.min(t_lim)),
        };
        // a column reached inside the flight ends it there
        let col = self.column_reach(&s.v, &gv, dt);
        let dt = col.map_or(dt, |c| c.0);
        let p_start = s.p;
        self.push_segment(|s| Segment {
            t0: s.t,
            dt,
            p0: s.p,
            v0: s.v,
            a: gv,
            fric: Vector3::zeros(),
            diss0,
            rolling: None,
            spin: s.spin,
            on_floor: false,
        });
        let s = &mut self.s;
        s.p += s.v * dt + gv * (0.5 * dt * dt);
        s.v += gv * dt;
        s.t += dt;
        // the rebound's apex counts only when this flight lasted until it
        if let Some((h, t_apex)) = s.apex.take()
            && s.t >= t_apex
        {
            s.max_bounce = s.max_bounce.max(h);
        }
        if let Some((_, k)) = col {
            self.hit = Some(k);
            return Some((Phase::Flight, StopReason::Support));
        }
        match end {
            FlightEnd::Leaves { .. } => Some((Phase::Flight, StopReason::LeftFloor)),
            FlightEnd::Clear => {
                if t_s <= t_left || past_end.is_some() {
                    return Some((Phase::Flight, StopReason::LowerEnd));
                }
                Some((Phase::Flight, StopReason::EndTime))
            }
            FlightEnd::Hit { facet, .. } => {
                self.impact(facet, p_start, draw);
                None
            }
        }
    }

    /// An impact on `facet` at the end of a flight from `p_start`: the rock is put on the floor,
    /// the restitution (e_n, e_t) drawn and applied in the facet's frame, and a rebound slower
    /// than the stop speed starts the ground phase.
    pub(super) fn impact(
        &mut self,
        facet: Facet,
        p_start: Vector3<f64>,
        draw: &mut impl FnMut() -> (f64, f64),
    ) {
        let (floor, g, dip, su) = (self.floor, self.g, self.dip, self.su);
        let s = &mut self.s;
        let pl = floor.facet_plane(facet);
        let n = pl.normal();
        let z = pl.z(s.p.x, s.p.y);
        set_height(s, z, g, 1.0);
        // on the floor's surface itself: a strike accepted a rounding
        // tolerance outside the struck facet may lie under a neighbour's plane (a plane floor
        // is one facet, whose height the rock has just been given: nothing to check)
        if !floor.is_single_facet()
            && let Some(top) = floor_surface_above(floor, &s.p)
        {
            set_height(s, top, g, 1.0);
        }
        s.on_surface = Some(s.p);
        if (s.p - p_start).norm() <= self.catch.len {
            self.catch.hops += 1;
        } else {
            self.catch.hops = 0;
        }
        s.s_r += (s.p - s.r).dot(&dip);
        s.r = s.p;
        let vn = s.v.dot(&n);
        // a flight of the ground phase (a take-off at a convex edge, or a re-contact's rebound)
        // ends in a re-contact; the release's and the bouncing phase's flights in an impact
        // (§C.2 step 2)
        if s.flight_from == FlightFrom::TakeOff {
            self.recontact(facet, n, vn.min(0.0), draw);
            return;
        }
        let vt = s.v - n * vn;
        if let Some(z) = self.zones {
            z.current.set(z.zones.material_index(s.p.x, s.p.y));
        }
        let (en, et) = draw();
        s.impacts += 1;
        let speed_before = s.v.norm();
        let lost =
            0.5 * ((1.0 - en * en) * vn * vn + (1.0 - et * et) * vt.norm_squared()) + s.spin.0;
        s.e_imp += lost;
        s.spin = (0.0, Vector3::zeros());
        let r = -en * vn;
        let rebound = vt * et + n * r;
        self.push_event(|s| EventRec {
            t: s.t,
            kind: EventKind::Impact,
            p: s.p,
            speed_before,
            speed_after: rebound.norm(),
            lost,
        });
        let s = &mut self.s;
        if r < su.v_stop || r < MIN_REBOUND {
            s.rebound_cutoff |= r >= su.v_stop;
            s.e_trans += 0.5 * r * r;
            s.v = vt * et;
            let ke_before = rebound.norm();
            self.enter_ground(facet);
            if let Some(rr) = self.rec.as_deref_mut()
                && let Some(ev) = rr.events.last_mut()
            {
                ev.speed_before = ke_before;
                ev.lost += 0.5 * r * r;
            }
        } else {
            s.v = rebound;
            s.flight_from = FlightFrom::Rebound;
            s.apex = Some((r * r / (2.0 * g * n.z), s.t + r / (g * n.z)));
        }
    }

    /// The landing of a flight of the ground phase on `facet` (unit normal `n`) at normal speed
    /// `vn` (m/s, ≤ 0): a re-contact. Its normal speed is restituted with the drawn e_n, as at
    /// any landing, but its tangential change is the Coulomb impulse of a rigid-body impact with
    /// friction, bounded by the paper's e_t: |Δv_t| = min((1 − e_t)|v_t|, μ J_n) with J_n the
    /// normal speed change the floor delivers, |vₙ| + v_kept ([`kept_rebound`]: the rebound the
    /// rock flies on, 0 when it stays on the floor). The loss is continuous in vₙ and tends to 0
    /// with it, so hopping over relief far below the rock's scale costs what sliding over it
    /// costs, while a landing at a normal speed of metres per second loses what an impact loses.
    /// A rolling rock has no slip: it keeps its tangential speed and, on staying, its angular
    /// momentum about the contact point (rolling speed (v + 0.4 u)/1.4 with u the surface speed
    /// of its spin in flight; the loss |v − u|²/7 is booked as transition). A landing at the stop
    /// speed or faster counts as an impact.
    pub(super) fn recontact(
        &mut self,
        facet: Facet,
        n: Vector3<f64>,
        vn: f64,
        draw: &mut impl FnMut() -> (f64, f64),
    ) {
        let (g, su, roll) = (self.g, self.su, self.roll);
        if let Some(z) = self.zones {
            z.current
                .set(z.zones.material_index(self.s.p.x, self.s.p.y));
        }
        let mu = self.mu_here();
        let (en, et) = draw();
        let s = &mut self.s;
        let speed_before = s.v.norm();
        let vt = s.v - n * vn;
        let vtn = vt.norm();
        let r = -en * vn;
        let kept = kept_rebound(r, su.v_stop);
        // the normal energy not flown on: restitution's loss (impact), what the switch to the
        // ground phase takes (transition)
        let e_normal = 0.5 * (1.0 - en * en) * vn * vn;
        let e_switch = 0.5 * (r * r - kept * kept);
        s.e_imp += e_normal;
        s.e_trans += e_switch;
        let mut lost = e_normal + e_switch;
        let vt_after = if roll || vtn == 0.0 {
            vt
        } else {
            let dv = ((1.0 - et) * vtn).min(mu * (-vn + kept));
            let after = (vtn - dv).max(0.0);
            let l = 0.5 * (vtn * vtn - after * after);
            s.e_fric += l;
            lost += l;
            vt * (after / vtn)
        };
        let on = kept >= MIN_REBOUND;
        s.rebound_cutoff |= kept > 0.0 && !on;
        let counted = on || (su.v_stop > 0.0 && -vn >= su.v_stop);
        if counted {
            s.impacts += 1;
        }
        if on {
            s.v = vt_after + n * kept;
            s.apex = Some((kept * kept / (2.0 * g * n.z), s.t + kept / (g * n.z)));
        } else {
            s.e_trans += 0.5 * kept * kept;
            lost += 0.5 * kept * kept;
            s.v = vt_after;
        }
        if counted {
            let after = s.v.norm();
            self.push_event(|s| EventRec {
                t: s.t,
                kind: EventKind::Impact,
                p: s.p,
                speed_before,
                speed_after: after,
                lost,
            });
        }
        if on {
            return;
        }
        let spin_in_flight = std::mem::replace(&mut self.s.spin, (0.0, Vector3::zeros()));
        if roll {
            let s = &mut self.s;
            let u = spin_in_flight.1.cross(&n) * su.radius;
            let u = u - n * u.dot(&n);
            let v_after = (s.v + u * 0.4) / 1.4;
            let spin_loss =
                0.5 * s.v.norm_squared() + spin_in_flight.0 - 0.7 * v_after.norm_squared();
            s.e_trans += spin_loss;
            s.v = v_after;
            lost += spin_loss;
        }
        if counted {
            // the impact's event holds the loss
            let before = self.s.v.norm();
            self.ground_phase(facet, before, 0.0);
        } else {
            self.ground_phase(facet, speed_before, lost);
        }
    }
}

/// The normal speed (m/s) a re-contact of the ground phase flies on after restituting `r`
/// (m/s): none below the stop speed `v_stop` (the switch to the ground phase, §C.2 step 2.4),
/// all of it from 2 `v_stop`, and 2 (r − v_stop) between, so that neither the landing's loss
/// (its friction impulse grows with the rebound) nor the path jumps where the rebound crosses
/// the stop speed. With a stop speed of 0 every rebound is flown (down to [`MIN_REBOUND`]).
pub(super) fn kept_rebound(r: f64, v_stop: f64) -> f64 {
    if r >= 2.0 * v_stop {
        r
    } else if r > v_stop {
        2.0 * (r - v_stop)
    } else {
        0.0
    }
}
