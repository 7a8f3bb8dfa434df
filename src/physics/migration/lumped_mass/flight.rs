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
        // the release's landing is the procedure's first impact (§C.2 step 2); a take-off's
        // landing slower along the normal than the stop speed is a touch-down, a rebound's
        // below a fraction of it ([`FlightFrom`])
        let touch_down_below = match s.flight_from {
            FlightFrom::Release => 0.0,
            FlightFrom::Rebound => REBOUND_TOUCH_DOWN * su.v_stop,
            FlightFrom::TakeOff => su.v_stop,
        };
        if -vn < touch_down_below {
            self.touch_down(facet, n, vn);
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

    /// A touch-down on `facet` (unit normal `n`) at normal speed `vn` (m/s, ≤ 0) below the stop
    /// speed: not an impact but a re-attachment ([`Run::reattach`]), the ground phase going on
    /// from here. A rolling rock also keeps its angular momentum about the contact point, so
    /// its rolling speed is (v + 0.4 u)/1.4 with u the surface speed of its spin in flight; the
    /// loss |v − u|²/7 (zero when the spin matches) is booked as transition.
    pub(super) fn touch_down(&mut self, facet: Facet, n: Vector3<f64>, vn: f64) {
        let (roll, radius) = (self.roll, self.su.radius);
        let speed_before = self.s.v.norm();
        let spin_in_flight = std::mem::replace(&mut self.s.spin, (0.0, Vector3::zeros()));
        let mut lost = self.reattach(&n, vn);
        if roll {
            let s = &mut self.s;
            let u = spin_in_flight.1.cross(&n) * radius;
            let u = u - n * u.dot(&n);
            let v_after = (s.v + u * 0.4) / 1.4;
            let spin_loss =
                0.5 * s.v.norm_squared() + spin_in_flight.0 - 0.7 * v_after.norm_squared();
            s.e_trans += spin_loss;
            s.v = v_after;
            lost += spin_loss;
        }
        self.ground_phase(facet, speed_before, lost);
    }
}
