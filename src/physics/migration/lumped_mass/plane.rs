//! The run loop of a plane floor without zones, lines or columns: the same closed-form pieces,
//! booking and invariants as [`Run::step`], with what the plane makes constant taken once (one
//! facet, its plane, no edges, holes, creases or floor-surface corners) and what such a case
//! lacks (materials, lines, columns) left out. Every operation that forms a value is the general
//! loop's, in the same order, so the answers are the same bits (checked by the tests below).

use super::*;
use crate::physics::migration::terrain::{plane_flight, start_rounding};

impl Run<'_, '_> {
    /// The plane of the floor when this run can take the plane loop: a plane floor, one
    /// material, no lines and no column among the supports (a spanning support only ends the
    /// run at the lower end, see [`Run::finish`]).
    pub(super) fn plane_only(&self) -> Option<FacetPlane> {
        match &self.floor.kind {
            FloorKind::Plane(pl)
                if self.zones.is_none() && self.su.lines.is_empty() && !self.has_columns =>
            {
                Some(*pl)
            }
            _ => None,
        }
    }

    /// [`Run::step`] on the plane `pl` ([`Run::plane_only`]).
    #[inline]
    pub(super) fn step_plane(
        &mut self,
        pl: &FacetPlane,
        draw: &mut impl FnMut() -> (f64, f64),
        control: Option<&Control>,
    ) -> PhysicsResult<StepEnd> {
        self.steps += 1;
        if self.steps.is_multiple_of(4096)
            && let Some(c) = control
        {
            c.check()?;
        }
        if self.steps > self.su.max_steps {
            return Err(too_many_steps(self.steps, self.su.max_steps));
        }
        // invariant: never below the floor (the plane is everywhere, so the rock is never on
        // the ground off it)
        check_above_height(Some(pl.z(self.s.p.x, self.s.p.y)), &self.s.p, self.s.t)?;
        if self.is_caught_in_place() {
            return Ok(self.leave_trap_plane());
        }
        let (s, dip) = (&mut self.s, self.dip);
        if s.ground.is_some() {
            // measure along the dip from the last floor point (local terms)
            s.s_r += (s.p - s.r).dot(&dip);
            s.r = s.p;
        } else if s.on_surface != Some(s.p) {
            // a flight starts on or above the plane ([`floor_surface_above`])
            let top = pl.z(s.p.x, s.p.y);
            if top - s.p.z > start_rounding(&s.p) {
                set_height(s, top, self.g, 1.0);
            }
        }
        let t_left = self.su.end_time.map_or(f64::INFINITY, |te| te - s.t);
        let along = s.s_r + (s.p - s.r).dot(&dip);
        let s_left = self.su.length - along;
        let moving = match s.ground {
            None => Phase::Flight,
            Some(_) if self.roll => Phase::Roll,
            Some(_) => Phase::Slide,
        };
        if s_left <= 0.0 {
            return Ok(Some((moving, StopReason::LowerEnd)));
        }
        if t_left <= 0.0 {
            return Ok(Some((moving, StopReason::EndTime)));
        }
        let diss0 = s.e_imp + s.e_fric + s.e_trans + s.e_barrier;
        Ok(match (s.ground, s.crease) {
            (None, _) => self.flight_plane(pl, draw, t_left, s_left, diss0),
            (Some(_), Some(c)) => self.crease_step_plane(c, t_left, s_left, moving),
            (Some(_), None) => self.ground_plane(pl, t_left, s_left, diss0, moving),
        })
    }

    /// [`Run::flight_step`] on the plane `pl`: the parabola to its strike of the plane, the
    /// lower end or the end time.
    #[inline]
    fn flight_plane(
        &mut self,
        pl: &FacetPlane,
        draw: &mut impl FnMut() -> (f64, f64),
        t_left: f64,
        s_left: f64,
        diss0: f64,
    ) -> StepEnd {
        let (g, gv, dip, su) = (self.g, self.gv, self.dip, self.su);
        let s = &self.s;
        let t_s = reach_time(s_left, s.v.dot(&dip), gv.dot(&dip));
        let t_lim = t_s.min(t_left);
        // whether a strike comes before the lower end is decided by its point, measured from
        // the last floor point (local terms), as in [`Run::flight_step`]
        let t_q = if t_s < t_left {
            (t_s * (1.0 + 1e-9)).min(t_left)
        } else {
            t_lim
        };
        let mut past_end = None;
        let hit = match plane_flight(pl, &s.p, &s.v, g, t_q) {
            FlightEnd::Hit { t, .. } => {
                let q = s.p + s.v * t + gv * (0.5 * t * t);
                let zq = pl.z(q.x, q.y);
                let dq = Vector3::new(q.x - s.r.x, q.y - s.r.y, zq - s.r.z);
                if s.s_r + dq.dot(&dip) < su.length {
                    Some(t)
                } else {
                    past_end = Some(t);
                    None
                }
            }
            _ => None,
        };
        let dt = match hit {
            Some(t) => t,
            None => past_end.map_or(t_lim, |t| t.min(t_lim)),
        };
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
        match hit {
            Some(_) => {
                self.impact_plane(pl, p_start, draw);
                None
            }
            None if t_s <= t_left || past_end.is_some() => {
                Some((Phase::Flight, StopReason::LowerEnd))
            }
            None => Some((Phase::Flight, StopReason::EndTime)),
        }
    }

    /// [`Run::impact`] on the plane `pl` (facet 0, one material): the rock put on the plane,
    /// the restitution drawn and applied in its frame, a rebound slower than the stop speed
    /// starting the ground phase.
    #[inline]
    fn impact_plane(
        &mut self,
        pl: &FacetPlane,
        p_start: Vector3<f64>,
        draw: &mut impl FnMut() -> (f64, f64),
    ) {
        let (g, dip, su) = (self.g, self.dip, self.su);
        let s = &mut self.s;
        let n = pl.normal();
        let z = pl.z(s.p.x, s.p.y);
        // the plane is the floor's surface: nothing above it to check
        set_height(s, z, g, 1.0);
        s.on_surface = Some(s.p);
        if (s.p - p_start).norm() <= self.catch.len {
            self.catch.hops += 1;
        } else {
            self.catch.hops = 0;
        }
        s.s_r += (s.p - s.r).dot(&dip);
        s.r = s.p;
        let vn = s.v.dot(&n);
        if s.flight_from == FlightFrom::TakeOff {
            self.recontact_plane(n, vn.min(0.0), draw);
            return;
        }
        let vt = s.v - n * vn;
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
            self.rebound_to_ground(r, vt * et, rebound);
        } else {
            s.v = rebound;
            s.flight_from = FlightFrom::Rebound;
            s.apex = Some((r * r / (2.0 * g * n.z), s.t + r / (g * n.z)));
        }
    }

    /// A rebound slower than the stop speed (normal part `r`, m/s; `rebound` the velocity it
    /// would have had): its normal part booked as transition, the ground phase started with the
    /// tangential part `vt` (as [`Run::impact`]). Out of line, as are the other branches a
    /// flight takes at most once per run, so that the flight's own values keep their registers.
    #[inline(never)]
    fn rebound_to_ground(&mut self, r: f64, vt: Vector3<f64>, rebound: Vector3<f64>) {
        let s = &mut self.s;
        s.rebound_cutoff |= r >= self.su.v_stop;
        s.e_trans += 0.5 * r * r;
        s.v = vt;
        let ke_before = rebound.norm();
        self.enter_ground(0);
        if let Some(rr) = self.rec.as_deref_mut()
            && let Some(ev) = rr.events.last_mut()
        {
            ev.speed_before = ke_before;
            ev.lost += 0.5 * r * r;
        }
    }

    /// [`Run::recontact`] on the plane (facet 0), out of line (see [`Run::rebound_to_ground`]).
    #[inline(never)]
    fn recontact_plane(&mut self, n: Vector3<f64>, vn: f64, draw: &mut impl FnMut() -> (f64, f64)) {
        self.recontact(0, n, vn, draw);
    }

    /// [`Run::leave_trap`], out of line and cold: a rock caught in place is rare.
    #[cold]
    #[inline(never)]
    fn leave_trap_plane(&mut self) -> StepEnd {
        self.leave_trap()
    }

    /// [`Run::crease_step`], out of line and cold: on a plane only a trap's exit sets a crease.
    #[cold]
    #[inline(never)]
    fn crease_step_plane(&mut self, c: Crease, t_left: f64, s_left: f64, moving: Phase) -> StepEnd {
        self.crease_step(c, t_left, s_left, moving)
    }

    /// [`Run::ground_step`] on the plane `pl`: constant acceleration up to the lower end, the
    /// end time, the stop of the speed along the friction direction or a turn of
    /// [`MAX_TURN`] (a plane has no edge to reach).
    #[inline]
    fn ground_plane(
        &mut self,
        pl: &FacetPlane,
        t_left: f64,
        s_left: f64,
        diss0: f64,
        moving: Phase,
    ) -> StepEnd {
        let (g, gv, dip, mu, roll) = (self.g, self.gv, self.dip, self.mu, self.roll);
        let ke_factor = self.ke_factor;
        let s = &mut self.s;
        let n = pl.normal();
        let gn = g * n.z;
        let gt = gv + n * (g * n.z);
        // the piece moves in the plane: a velocity part along its normal beyond rounding is
        // removed as a booked transition
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
                turn_at = MAX_TURN * speed.max(REST_SPEED) / aperp;
            }
            s.undecelerated = ad >= 0.0;
        } else {
            s.undecelerated = a.dot(&s.v) >= 0.0;
        }
        t_max = t_max.min(stop_at).min(turn_at);
        let dt = t_max;
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
}

#[cfg(test)]
mod tests {
    //! The plane loop against the general loop: random plane cases (dip, friction,
    //! restitution drawn at every impact, release height, velocity and place, sliding or
    //! rolling, stop speed, end time, face length, a spanning support, a step limit) give the
    //! same outcome, events and trajectory pieces through both, compared bit for bit.
    use super::*;
    use crate::physics::migration::MigrationCase;
    use crate::physics::migration::monte_carlo::splitmix64;
    use proptest::prelude::*;

    /// A uniform number in [lo, hi) from the stream `s`.
    fn uniform(s: &mut u64, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * ((splitmix64(s) >> 11) as f64 / 9_007_199_254_740_992.0)
    }

    /// The exact bits of every number of an outcome (or error) and its recording: `{:?}` of f64
    /// is its shortest round-trip form, which tells every two distinct values apart (−0 and
    /// +0 too).
    fn bits(out: &PhysicsResult<RunOut>, rec: &Recording) -> String {
        format!("{out:?} {:?} {:?}", rec.events, rec.segments)
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 3000, ..ProptestConfig::default() })]

        #[test]
        fn the_plane_loop_gives_the_general_loops_bits(
            // the documented dip range [5°, 80°] with its ends, and the steep seams' 35–55°
            dip_deg in prop_oneof![5.0..=80.0f64, Just(5.0), Just(80.0), 35.0..55.0f64],
            mu in prop_oneof![0.0..=2.0f64, Just(0.0), Just(2.0), 0.0..1.2f64],
            roll in any::<bool>(),
            v_stop in prop_oneof![0.0..0.5f64, Just(0.0), Just(0.1)],
            drop in prop_oneof![0.0..5.0f64, Just(0.0)],
            v0 in prop::array::uniform3(-6.0..6.0f64),
            xy in prop::array::uniform2(-3.0..3.0f64),
            length in prop_oneof![1.0..150.0f64, Just(120.0)],
            end_time in prop::option::of(0.0..20.0f64),
            span in any::<bool>(),
            max_steps in prop_oneof![Just(100_000u64), 1..12u64],
            restitution in (0.0..1.0f64, 0.0..1.0f64, 0.0..0.3f64),
            seed in any::<u64>(),
            record in any::<bool>(),
        ) {
            let floor = Floor::plane(dip_deg.to_radians());
            let FloorKind::Plane(pl) = floor.kind else { unreachable!("a plane") };
            let (x, y) = (xy[0], xy[1]);
            let z = pl.z(x, y);
            let base = Vector3::new(x, y, z);
            let on_floor = drop == 0.0;
            let su = Setup {
                floor: &floor,
                g: 9.81,
                motion: if roll { Motion::Roll } else { Motion::Slide },
                v_stop,
                radius: 0.2,
                length,
                span_support: span.then_some(0),
                supports: &[],
                lines: &[],
                mass: 1.0,
                end_time,
                max_steps,
                p0: Vector3::new(x, y, z + drop),
                v0: Vector3::from(v0),
                on_floor: on_floor.then_some(0),
                base: (base, floor.mean.along(&base)),
            };
            let (en, et, spread) = restitution;
            let go = |plane_loop: bool| {
                let mut s = seed;
                let mut draw = || {
                    (
                        (en + uniform(&mut s, -spread, spread)).clamp(0.0, 1.0),
                        (et + uniform(&mut s, -spread, spread)).clamp(0.0, 1.0),
                    )
                };
                let mut rec = Recording::default();
                let out = simulate_on(
                    &su, mu, None, &mut draw, record.then_some(&mut rec), None, plane_loop,
                );
                bits(&out, &rec)
            };
            // the case takes the plane loop
            prop_assert!(Run::new(&su, mu, None).plane_only().is_some());
            let (fast, general) = (go(true), go(false));
            prop_assert_eq!(fast, general);
        }
    }

    /// The whole answer of `case` (nominal run with its events and trajectory, statistics and
    /// every run's summary), as its `{:?}`, through the plane loop or only the general loop.
    fn answer(case: &MigrationCase, plane_loop: bool) -> String {
        use std::sync::atomic::Ordering;
        GENERAL_LOOP_ONLY.store(!plane_loop, Ordering::SeqCst);
        let out = crate::physics::migration::run(case, &Control::unlimited());
        GENERAL_LOOP_ONLY.store(false, Ordering::SeqCst);
        format!("{out:?}")
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 60, ..ProptestConfig::default() })]

        /// Whole migration answers of random plane ensembles (dip, μ fixed or drawn per run,
        /// e_n and e_t drawn per impact, release drop, speed and drawn velocity, sliding or
        /// rolling, stop speed, end time, a spanning support) are the same bits through the
        /// plane loop and through the general loop alone: every run's summary, the statistics,
        /// the nominal run's events and trajectory.
        #[test]
        fn whole_plane_answers_are_the_same_through_either_loop(
            dip_deg in prop_oneof![5.0..=80.0f64, Just(5.0), Just(80.0), 35.0..55.0f64],
            mu in prop_oneof![0.0..=2.0f64, 0.0..1.0f64],
            mu_drawn in any::<bool>(),
            roll in any::<bool>(),
            stop in prop_oneof![0.0..0.3f64, Just(0.0)],
            drop in prop_oneof![0.0..5.0f64, Just(0.0)],
            speed in prop_oneof![0.0..4.0f64, Just(0.0)],
            velocity_drawn in any::<bool>(),
            end_time in prop::option::of(0.5..20.0f64),
            span in any::<bool>(),
            en in (0.0..0.6f64, 0.0..0.3f64),
            et in (0.4..0.9f64, 0.0..0.1f64),
            seed in any::<u64>(),
        ) {
            use crate::physics::migration::{
                Distribution, FloorSpec, MonteCarlo, SupportStop,
            };
            let mut c = MigrationCase::default();
            c.face.dip_deg = dip_deg;
            c.face.floor = FloorSpec::Plane;
            c.face.length = 60.0;
            c.face.friction_coefficient = mu;
            c.release.drop_height = drop;
            c.release.speed = speed;
            c.lumped_mass.stop_normal_speed = stop;
            if roll {
                c.lumped_mass.motion = Motion::Roll;
            }
            c.end_time = end_time;
            if span {
                c.supports = vec![SupportStop { along_dip: 50.0, across: None, reach: 0.0 }];
            }
            c.monte_carlo = Some(MonteCarlo {
                runs: 64,
                seed,
                restitution_normal: Distribution::Uniform { min: en.0, max: en.0 + en.1 },
                restitution_tangential: Distribution::Uniform { min: et.0, max: et.0 + et.1 },
                friction_coefficient: mu_drawn
                    .then_some(Distribution::Uniform { min: mu, max: mu + 0.3 }),
                release_velocity: velocity_drawn.then_some([
                    Distribution::Uniform { min: -1.0, max: 2.0 },
                    Distribution::Normal { mean: 0.0, std: 0.5 },
                    Distribution::Uniform { min: 0.0, max: 1.0 },
                ]),
                random_orientation: false,
            });
            c.output.events = true;
            c.output.trajectory = true;
            c.output.runs_csv = true;
            let fast = answer(&c, true);
            let general = answer(&c, false);
            prop_assert_eq!(fast, general);
        }
    }
}
