//! Lines across the face met by the block (collectors and barriers, see
//! [`super::super::lines`]): a line is reached when the along-dip position of the centre first
//! reaches it, in line order, each at most once, never one beyond the run's end length.
//!
//! Where the crossing is recorded:
//!
//! * **in a free flight**, at the exact time the parabola reaches the line (the state flown
//!   there in closed form); a barrier that acts cuts the flight there;
//! * **in a stepped phase**, at the end of the step whose drift reached it: the step-end state
//!   with its velocities brought to its time (the leapfrog's half-step velocities plus half a
//!   step of the last acceleration, as the run's report does), so within one step's travel
//!   past the line; a barrier acts on that same state;
//! * **in a settled slide skipped in closed form**, in the state the stepped leapfrog would have
//!   at the end of the step that reaches the line (the skip is the steps' closed form), so a
//!   collector (or a barrier of height 0, which every block overtops) does not change the
//!   skip; the skip ends two steps before any other barrier's line (as before the lower end),
//!   whose crossing is stepped.
//!
//! A collector, an overtopped barrier or a line the block passes outside its across range
//! changes nothing: the run takes the same steps to the same bits as without it. A barrier
//! that stops the block ends the run there (`StopReason::Barrier`, its kinetic energy booked as
//! the barrier's when the run is finished); one broken through scales every velocity
//! (translational and angular, brought to the state's time first: the leapfrog then restarts
//! from it as after a flight) by √(1 − R/E), so the kinetic energy drops by the rating R. In
//! contact, the shear springs are first carried over the drift since their last force
//! evaluation with the velocities the block had on it, so their work is booked as the steps
//! would book it.

use super::super::lines::act;
use super::*;

/// Whether a barrier stands on `line` that may act on a block: a barrier of height 0 is
/// overtopped by every block (the passing height is never negative), a collector.
fn may_act(line: &Line) -> bool {
    line.barrier.is_some_and(|b| b.height > 0.0)
}

impl Model<'_> {
    /// The next line the block can reach (a line beyond the run's end length never is).
    fn reachable_line(&self, run: &Run) -> Option<Line> {
        self.lines
            .get(run.next_line)
            .copied()
            .filter(|l| l.along_dip <= self.length)
    }

    /// The block reached the next line in the state `st` (velocities at its own time): the
    /// crossing recorded when the line spans the centre's across position. Returns the
    /// barrier's action and velocity factor when it acts on the block (stops it or is broken
    /// through).
    fn meet_line(&self, run: &mut Run, st: &State) -> Option<(LineAction, f64)> {
        let k = run.next_line;
        run.next_line += 1;
        let line = self.lines[k];
        if !line.spans(st.c.y) {
            return None;
        }
        let (kt, kr, _) = self.energy(st);
        let passing_height = self.lowest_point_height(st);
        let (action, f) = act(&line, passing_height, kt + kr);
        run.crossings[k] = Some(Crossing {
            time: st.t,
            across: st.c.y,
            speed: st.v.norm(),
            translational_energy: kt,
            rotational_energy: kr,
            passing_height,
            action,
        });
        matches!(action, LineAction::Stopped | LineAction::BrokenThrough).then_some((action, f))
    }

    /// The lines reached in the free flight from `st` (velocities at its time) within `tau`
    /// (s), each recorded at the exact time the centre reaches it. Returns the state where the
    /// first barrier that acts stands, with its action and velocity factor.
    pub(super) fn lines_in_flight(
        &self,
        run: &mut Run,
        st: &State,
        tau: f64,
    ) -> Option<(State, LineAction, f64)> {
        while let Some(line) = self.reachable_line(run) {
            let t = self.along_reach(st, line.along_dip, tau)?;
            let sx = self.fly(st, t);
            if let Some((action, f)) = self.meet_line(run, &sx) {
                return Some((sx, action, f));
            }
        }
        None
    }

    /// The lines the last step's drift reached, recorded in the step-end state; a barrier
    /// broken through scales the velocities there. Returns `StopReason::Barrier` when a
    /// barrier stopped the block (the run's end books its energy, see [`Model::finish`]).
    pub(super) fn lines_in_step(&self, run: &mut Run, cfg: &RunSettings) -> Option<StopReason> {
        let along = self.mean.along(&run.st.c);
        while let Some(line) = self.reachable_line(run)
            && along >= line.along_dip
        {
            let sx = self.synced(&run.st, run.half_step, &run.acc, &run.ang_acc);
            let Some((action, f)) = self.meet_line(run, &sx) else {
                continue;
            };
            if action == LineAction::Stopped {
                return Some(StopReason::Barrier);
            }
            self.carry_springs(run, cfg);
            self.break_through(run, f, cfg.log_events);
            // the slide settles anew before it is skipped again (the skip steps from half-step
            // velocities; these are at the state's time)
            run.steady_since = None;
        }
        None
    }

    /// The lines a settled slide skipped over `n_skip` steps (velocity `v_t`, acceleration
    /// `a_t`, see [`Model::skip_settled_slide`]) reaches, each recorded in the state the
    /// leapfrog has at the end of the step that reaches it. Barriers end the skip before
    /// their line ([`Model::skip_end`]): only lines no barrier can act on are met here.
    pub(super) fn lines_in_skip(
        &self,
        run: &mut Run,
        n_skip: u64,
        v_t: &Vector3<f64>,
        a_t: &Vector3<f64>,
    ) {
        let dt = self.dt;
        let st = run.st;
        // after k steps: the skip's own closed form, velocities brought to the step's end
        let at = |k: f64| State {
            t: st.t + k * dt,
            c: st.c + v_t * (k * dt) + a_t * (0.5 * dt * dt * k * (k + 1.0)),
            v: st.v + a_t * ((k + 0.5) * dt),
            ..st
        };
        let d = self.mean.dip_dir();
        let along0 = self.mean.along(&st.c);
        let (b, c) = (d.dot(v_t) * dt, 0.5 * d.dot(a_t) * dt * dt);
        let nf = n_skip as f64;
        while let Some(line) = self.reachable_line(run)
            && !may_act(&line)
        {
            let k = steps_to_travel(b, c, line.along_dip - along0)
                .ceil()
                .max(1.0);
            // past the skip, or never (an infinite or NaN count)
            if k.partial_cmp(&nf)
                .is_none_or(|o| o == std::cmp::Ordering::Greater)
            {
                break;
            }
            let mut sx = at(k);
            if self.mean.along(&sx.c) < line.along_dip && k < nf {
                // the real root rounded below the step that reaches it
                sx = at(k + 1.0);
            }
            let _ = self.meet_line(run, &sx);
        }
    }

    /// The along-dip position (m) a skipped settled slide stops two steps short of: the line
    /// of the first barrier that may act on the block it can still reach, else the run's end
    /// length.
    pub(super) fn skip_end(&self, run: &Run) -> f64 {
        self.lines
            .get(run.next_line..)
            .unwrap_or_default()
            .iter()
            .take_while(|l| l.along_dip <= self.length)
            .find(|l| may_act(l))
            .map_or(self.length, |l| l.along_dip)
    }

    /// The shear springs carried over the drift since their last force evaluation (with the
    /// velocities the block had on it, as [`Model::stored_at_end`] carries them to a run's
    /// end), their work booked, and the velocities brought to the state's time: the state a
    /// barrier can act on, from which the leapfrog restarts as after a flight.
    fn carry_springs(&self, run: &mut Run, cfg: &RunSettings<'_>) {
        let lagged = run.st;
        let st = self.synced(&run.st, run.half_step, &run.acc, &run.ang_acc);
        if !run.springs.is_empty() {
            let mut carried = Vec::with_capacity(run.springs.len());
            let (stored, slip) = self.stored_at_end(run, &lagged, &st, cfg, Some(&mut carried));
            run.springs = carried;
            run.stored = stored;
            run.friction += slip;
        }
        run.st = st;
        run.half_step = None;
        run.drift_h = 0.0;
    }

    /// A barrier broken through: every velocity of the state (at its own time) scaled by `f`,
    /// the kinetic energy it lost booked as the barrier's, and a `barrier` event logged when
    /// `events`.
    pub(super) fn break_through(&self, run: &mut Run, f: f64, events: bool) {
        let st = &mut run.st;
        let (kt, kr, _) = self.energy(st);
        let before = st.v.norm();
        st.v *= f;
        st.w *= f;
        let (kt1, kr1, _) = self.energy(st);
        let lost = (kt + kr) - (kt1 + kr1);
        run.barrier += lost;
        if events {
            let ev = self.event(
                st.t,
                EventKind::Barrier,
                &st.c,
                EventChange {
                    before,
                    after: st.v.norm(),
                    lost,
                    peak: None,
                },
            );
            run.events.push(ev);
        }
    }
}

#[cfg(test)]
mod tests {
    //! Collectors and barriers met by the rigid block, against the closed forms of
    //! `migration::lines`' own test for the lumped mass: a block sliding on the plane from rest
    //! (friction work μ m g cos θ per metre whatever its speed) and a block dropped 3 m that
    //! meets lines in the air.
    use super::super::super::lines::Barrier;
    use super::super::super::{
        EventKind, Method, MigrationCase, MigrationResult, MonteCarlo, Phase, StopReason,
        release::build_floor, run,
    };
    use super::*;
    use crate::physics::control::Control;
    use crate::physics::migration::lines::tests::line;
    use crate::physics::migration::monte_carlo::Distribution;

    /// Relative error of the arrival's kinetic energy after a barrier broken through by a
    /// sliding block, against the free arrival's less the rating (measured 2.7e-7: the
    /// barrier acts on the step-end state, up to one step past its line, and the leapfrog
    /// restarts from it).
    const TOL_THROUGH: f64 = 1e-6;

    /// The block released at rest on the plane at 5 m ([`lines::tests::slide`]).
    fn slide() -> MigrationCase {
        super::super::super::lines::tests::slide(Method::RigidBlock)
    }

    fn barrier(along_dip: f64, height: f64, rating: f64) -> Line {
        line(along_dip, Some(Barrier { height, rating }))
    }

    fn go(case: &MigrationCase) -> MigrationResult {
        run(case, &Control::unlimited()).unwrap()
    }

    /// Lines without a barrier record and change nothing (bit for bit); a barrier rated above
    /// the block's energy stops it on its line (within one step's travel past it), the account
    /// closed with the energy it took (its residual within twice the free run's); one rated R
    /// below the block's energy takes R off the kinetic energy at the lower end; one of height
    /// 0 is overtopped by the sliding block and changes nothing (bit for bit).
    #[test]
    fn a_sliding_block_meets_collectors_and_barriers_as_their_closed_forms_say() {
        let base = slide();
        let free = go(&base);
        assert_eq!(free.arrival.stop_reason, StopReason::LowerEnd);
        let mut with = base.clone();
        with.lines = vec![line(20.0, None), line(40.0, None)];
        let r = go(&with);
        assert_eq!(format!("{:?}", r.arrival), format!("{:?}", free.arrival));
        assert_eq!(format!("{:?}", r.energy), format!("{:?}", free.energy));
        assert_eq!(r.energy.barriers, 0.0);

        let th = base.face.dip_deg.to_radians();
        let a = 9.81 * (th.sin() - base.face.friction_coefficient * th.cos());
        let dt = free.rigid_block.as_ref().unwrap().time_step;
        // the speed at the line and one step's travel there
        let v_at = (2.0 * a * 25.0).sqrt();
        let mut stop = base;
        stop.lines = vec![barrier(30.0, 1.0, 1e12)];
        let r = go(&stop);
        assert_eq!(r.arrival.stop_reason, StopReason::Barrier);
        assert_eq!(r.arrival.phase, Phase::Stopped);
        let past = r.arrival.along_dip - 30.0;
        assert!(
            (0.0..=1.01 * v_at * dt).contains(&past),
            "{past} m past the line, one step {} m",
            v_at * dt
        );
        assert_eq!(r.arrival.speed, 0.0);
        assert_eq!(r.arrival.kinetic_energy, 0.0);
        assert_eq!(r.stop_along_dip, Some(r.arrival.along_dip));
        // it took the kinetic energy the slide brought to it (the closed form to 1e-5: measured
        // 3.3e-6, the static overlaps' and one step's share)
        let m = free.mass;
        let e_at = m * a * 25.0;
        assert!(
            (r.energy.barriers - e_at).abs() < 1e-5 * e_at,
            "{} vs {e_at}",
            r.energy.barriers
        );
        let allowed = free
            .energy
            .residual
            .abs()
            .max(1e-9 * free.energy.total_start);
        assert!(
            r.energy.residual.abs() <= 2.0 * allowed,
            "{} vs {}",
            r.energy.residual,
            free.energy.residual
        );
        let events = r.events.unwrap();
        let ev = events
            .iter()
            .find(|e| e.kind == EventKind::Barrier)
            .unwrap();
        assert_eq!(ev.speed_after, 0.0);
        assert_eq!(ev.energy_lost, r.energy.barriers);
        assert_eq!(events.last().unwrap().kind, EventKind::Stop);

        // the same barrier rated half the energy the block brings to it
        let mut through = stop.clone();
        through.lines[0] = barrier(30.0, 1.0, 0.5 * e_at);
        let r = go(&through);
        assert_eq!(r.arrival.stop_reason, StopReason::LowerEnd);
        let want = free.arrival.kinetic_energy - 0.5 * e_at;
        assert!(
            (r.arrival.kinetic_energy - want).abs() < TOL_THROUGH * want,
            "{} vs {want}: {:.3e}",
            r.arrival.kinetic_energy,
            (r.arrival.kinetic_energy - want) / want
        );
        assert!(
            (r.energy.barriers - 0.5 * e_at).abs() < 1e-12 * e_at,
            "{} vs {}",
            r.energy.barriers,
            0.5 * e_at
        );
        assert!(
            r.energy.residual.abs() <= 2.0 * allowed,
            "{} vs {}",
            r.energy.residual,
            free.energy.residual
        );
        let events = r.events.unwrap();
        assert!(
            events.iter().any(|e| e.kind == EventKind::Barrier
                && (e.energy_lost - 0.5 * e_at).abs() < 1e-12 * e_at)
        );

        // a sliding block passes at height 0: a barrier of height 0 is overtopped by it
        let mut low = stop;
        low.lines[0] = barrier(30.0, 0.0, 1e12);
        let r = go(&low);
        assert_eq!(format!("{:?}", r.arrival), format!("{:?}", free.arrival));
        assert_eq!(r.energy.barriers, 0.0);
    }

    /// The block dropped 3 m above the floor at 10 m: its centre starts up-slope of the release
    /// point (the fall is vertical) and crosses 9 m in the air.
    fn drop() -> MigrationCase {
        let mut c = MigrationCase {
            method: Method::RigidBlock,
            ..MigrationCase::default()
        };
        c.release.drop_height = 3.0;
        c.release.along_dip = 10.0;
        c.face.length = 40.0;
        c.output.events = true;
        c
    }

    /// A barrier in the air cuts the flight exactly on its line: stopped there, or broken
    /// through with its rating taken.
    #[test]
    fn a_falling_block_meets_a_barrier_on_its_line() {
        let base = drop();
        let free = go(&base);
        let mut stop = base.clone();
        stop.lines = vec![barrier(9.0, 5.0, 1e12)];
        let r = go(&stop);
        assert_eq!(r.arrival.stop_reason, StopReason::Barrier);
        assert_eq!(r.arrival.phase, Phase::Stopped);
        assert!(
            (r.arrival.along_dip - 9.0).abs() < 1e-9,
            "{}",
            r.arrival.along_dip
        );
        assert_eq!(r.arrival.speed, 0.0);
        assert!(r.energy.barriers > 0.0);
        // off the floor nothing else was lost: the fall's energy to rounding
        assert!(r.energy.residual.abs() < 1e-9 * r.energy.total_start);
        assert_eq!(r.energy.damping + r.energy.friction, 0.0);

        let rating = 0.25 * r.energy.barriers;
        let mut through = base;
        through.lines = vec![barrier(9.0, 5.0, rating)];
        let r = go(&through);
        assert_eq!(r.arrival.stop_reason, StopReason::LowerEnd);
        assert!((r.energy.barriers - rating).abs() < 1e-12 * rating);
        assert!(
            r.energy.residual.abs()
                <= 2.0 * free.energy.residual.abs().max(1e-9 * r.energy.total_start),
            "{} vs {}",
            r.energy.residual,
            free.energy.residual
        );
    }

    /// Through `ensemble_run`: crossings recorded where the block reached its lines, with
    /// speed and energies consistent with the fall to them; lines up-slope of the start, past
    /// the end or off the block's across position are not reached, one at the end is; a low
    /// barrier the falling
    /// block passes over is overtopped and leaves the run as it was.
    #[test]
    fn an_ensemble_run_records_its_crossings_and_overtops_a_low_barrier() {
        let c = Control::unlimited();
        let mut case = drop();
        case.output.events = false;
        case.face.length = 30.0;
        let nominal = go(&case);
        let (mass, dt) = (nominal.mass, nominal.rigid_block.unwrap().time_step);
        let mc = MonteCarlo {
            runs: 4,
            friction_coefficient: Some(Distribution::Uniform { min: 0.4, max: 0.6 }),
            ..MonteCarlo::default()
        };
        case.monte_carlo = Some(mc);
        let floor = build_floor(&case).unwrap();
        let runs = |case: &MigrationCase| {
            (0..2)
                .map(|i| super::super::super::ensemble_run(case, &floor, &mc, i, None, &c).unwrap())
                .collect::<Vec<_>>()
        };
        let free = runs(&case);
        assert!(free.iter().all(|r| r.2.is_empty()));
        let mut with = case.clone();
        with.lines = vec![
            line(5.0, None),
            barrier(9.0, 0.1, 1e12),
            line(15.0, None),
            Line {
                along_dip: 20.0,
                across: Some((2.0, 3.0)),
                barrier: None,
            },
            line(25.0, None),
            line(30.0, None),
            line(35.0, None),
        ];
        let th = case.face.dip_deg.to_radians();
        for (r, f) in runs(&with).iter().zip(&free) {
            // the run is the run without lines, bit for bit
            assert_eq!(format!("{:?}", r.0), format!("{:?}", f.0));
            let x = &r.2;
            assert_eq!(x.len(), 7);
            // up-slope of the start (the centre starts at 10 − 3 sin θ), across off the block,
            // past the end; one at the end is reached as the run ends there
            assert!(x[0].is_none() && x[3].is_none() && x[6].is_none(), "{x:?}");
            assert_eq!(x[5].unwrap().action, LineAction::Passed);
            // (recorded at the end of the step that reached it, the run's end put back to the
            // end length inside that step)
            let t_end = x[5].unwrap().time;
            assert!(
                t_end >= r.0.time && t_end <= r.0.time + dt,
                "{t_end} vs {}",
                r.0.time
            );
            let over = x[1].unwrap();
            assert_eq!(over.action, LineAction::Overtopped);
            assert!(over.passing_height > 0.1, "{over:?}");
            let m = mass;
            let mut t_last = 0.0;
            for (k, along) in [(1, 9.0), (2, 15.0), (4, 25.0)] {
                let cr = x[k].unwrap();
                assert!(cr.time > t_last);
                t_last = cr.time;
                assert!(cr.passing_height >= 0.0 && cr.across.abs() < 1e-6, "{cr:?}");
                assert!(
                    (0.5 * m * cr.speed * cr.speed - cr.translational_energy).abs()
                        <= 1e-9 * cr.translational_energy
                );
                // no more than the potential energy of the drop to the line
                let fall = m * 9.81 * (3.0 + (along - 10.0) * th.sin());
                assert!(
                    cr.kinetic_energy() <= fall * (1.0 + 1e-9) && cr.kinetic_energy() > 0.0,
                    "{} of {fall} J at {along} m",
                    cr.kinetic_energy()
                );
                if k > 1 {
                    assert_eq!(cr.action, LineAction::Passed);
                }
            }
            assert!(x[2].unwrap().time < r.0.time);
        }
        // the same barrier at the floor's height for a block that slides there stops it
        let mut stop = with;
        stop.lines[4] = barrier(25.0, 1.0, 1e12);
        for r in runs(&stop) {
            assert_eq!(r.0.stop_reason, StopReason::Barrier);
            assert_eq!(r.0.speed, 0.0);
            assert_eq!(r.2[4].unwrap().action, LineAction::Stopped);
        }
    }
}
