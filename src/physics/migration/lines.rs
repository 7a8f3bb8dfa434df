//! Lines across the face where a run's state is recorded (collectors, like RocFall's data
//! collectors) and where a barrier may act on the rock (api.md `POST /v1/scene`, `barriers`
//! and `collectors`).
//!
//! A line stands at an along-dip position of the mean plane, across the whole face or an
//! across-range. The rock reaches it when the along-dip position of its centre (the lumped
//! mass's point) first reaches the line's, during the drop as after it, like a spanning
//! support; a rock whose across position is then outside the range does not reach it. Lines
//! are taken in along-dip order, each at most once per run; a line up-slope of the rock's start
//! is never reached.
//!
//! A barrier of height h and energy rating R acts on a rock that reaches its line with its
//! lowest point less than h above the floor: a rock whose kinetic energy (translational and
//! rotational) is within R is stopped there and its run ends; a faster one passes with R of its
//! kinetic energy taken (every velocity, translational and angular, scaled by √(1 − R/E));
//! a rock at or above h passes untouched (overtopped).

/// A barrier on a line: its height above the floor and its energy rating.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Barrier {
    /// Height above the floor, m.
    pub height: f64,
    /// Energy rating: the kinetic energy it can take, J.
    pub rating: f64,
}

/// A line across the face (a collector; with a barrier, a protection device).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Line {
    /// Along-dip position in the mean plane, m.
    pub along_dip: f64,
    /// Across range [from, to] of the line, m (None: the whole face).
    pub across: Option<(f64, f64)>,
    /// The barrier standing on the line (None: the line only records).
    pub barrier: Option<Barrier>,
}

impl Line {
    /// True when a rock at across position `y` (m) reaches the line.
    #[must_use]
    pub fn spans(&self, y: f64) -> bool {
        self.across.is_none_or(|(a, b)| y >= a && y <= b)
    }
}

/// What a line did to a rock that reached it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LineAction {
    /// No barrier: the rock passed and was recorded.
    Passed,
    /// The rock's lowest point passed at or above the barrier's height.
    Overtopped,
    /// The barrier took all the rock's kinetic energy: the run ended there.
    Stopped,
    /// The rock passed with the barrier's rating taken from its kinetic energy.
    BrokenThrough,
}

/// The rock's state where it reached a line.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Crossing {
    /// Time, s.
    pub time: f64,
    /// Across position of the centre, m.
    pub across: f64,
    /// Speed of the centre before the line acted, m/s.
    pub speed: f64,
    /// Translational kinetic energy before the line acted, J.
    pub translational_energy: f64,
    /// Rotational kinetic energy before the line acted, J.
    pub rotational_energy: f64,
    /// Height of the rock's lowest point above the floor, m (0 on the floor).
    pub passing_height: f64,
    /// What the line did.
    pub action: LineAction,
}

impl Crossing {
    /// Kinetic energy before the line acted, J.
    #[must_use]
    pub fn kinetic_energy(&self) -> f64 {
        self.translational_energy + self.rotational_energy
    }
}

/// What `line` does to a rock whose lowest point passes `passing_height` (m) above the floor
/// with kinetic energy `energy` (J): the action and the factor on every velocity (0 when
/// stopped, √(1 − R/E) when broken through, 1 otherwise).
#[must_use]
pub fn act(line: &Line, passing_height: f64, energy: f64) -> (LineAction, f64) {
    match line.barrier {
        None => (LineAction::Passed, 1.0),
        Some(b) if passing_height >= b.height => (LineAction::Overtopped, 1.0),
        Some(b) if energy <= b.rating => (LineAction::Stopped, 0.0),
        Some(b) => (
            LineAction::BrokenThrough,
            // E > R ≥ 0 here, so the factor is in (0, 1]
            (1.0 - b.rating / energy).max(0.0).sqrt(),
        ),
    }
}

/// The lines a run can reach, in order: the index of the first line at or down-slope of
/// `start` (m) in `lines` (sorted by along-dip position).
#[must_use]
pub fn first_reachable(lines: &[Line], start: f64) -> usize {
    lines.partition_point(|l| l.along_dip < start)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::super::{EventKind, Method, MigrationCase, StopReason, run};
    use super::*;
    use crate::physics::control::Control;

    /// A rock released on the plane at rest with no drop: it slides from the release point,
    /// friction work μ m g cos θ per metre whatever its speed.
    pub(crate) fn slide(method: Method) -> MigrationCase {
        let mut c = MigrationCase {
            method,
            ..MigrationCase::default()
        };
        c.release.drop_height = 0.0;
        c.release.along_dip = 5.0;
        c.face.length = 60.0;
        c.output.events = true;
        c
    }

    /// A line across the whole face at `along_dip` (m), with `barrier` on it.
    pub(crate) fn line(along_dip: f64, barrier: Option<Barrier>) -> Line {
        Line {
            along_dip,
            across: None,
            barrier,
        }
    }

    /// Lines without a barrier record and change nothing; a barrier rated above the rock's
    /// energy stops it on its line, the account closed with the energy it took; one rated R
    /// below the rock's energy takes exactly R off the sliding rock's energy at the lower end
    /// (the friction work on the plane does not depend on the speed).
    #[test]
    fn a_sliding_rock_meets_collectors_and_barriers_as_their_closed_forms_say() {
        let c = Control::unlimited();
        let base = slide(Method::LumpedMass);
        let free = run(&base, &c).unwrap();
        let mut with = base.clone();
        with.lines = vec![line(20.0, None), line(40.0, None)];
        let r = run(&with, &c).unwrap();
        // the pieces are cut at the lines: the same run to rounding
        same_arrival(&r.arrival, &free.arrival);
        assert_eq!(r.energy.barriers, 0.0);

        let mut stop = base.clone();
        stop.lines = vec![line(
            30.0,
            Some(Barrier {
                height: 1.0,
                rating: 1e12,
            }),
        )];
        let r = run(&stop, &c).unwrap();
        assert_eq!(r.arrival.stop_reason, StopReason::Barrier);
        assert!(
            (r.arrival.along_dip - 30.0).abs() < 1e-9,
            "{}",
            r.arrival.along_dip
        );
        assert_eq!(r.arrival.speed, 0.0);
        assert!(r.energy.barriers > 0.0);
        assert!(r.energy.residual.abs() < 1e-9 * r.energy.total_start);
        let events = r.events.unwrap();
        assert!(events.iter().any(|e| e.kind == EventKind::Barrier));

        // the same barrier rated half the energy the rock brings to it
        let m = free.mass;
        let th = base.face.dip_deg.to_radians();
        let a = 9.81 * (th.sin() - base.face.friction_coefficient * th.cos());
        let e_at = m * a * 25.0;
        let mut through = stop.clone();
        through.lines[0].barrier = Some(Barrier {
            height: 1.0,
            rating: 0.5 * e_at,
        });
        let r = run(&through, &c).unwrap();
        assert_eq!(r.arrival.stop_reason, StopReason::LowerEnd);
        let want = free.arrival.kinetic_energy - 0.5 * e_at;
        assert!(
            (r.arrival.kinetic_energy - want).abs() < 1e-9 * want,
            "{} vs {want}",
            r.arrival.kinetic_energy
        );
        assert!((r.energy.barriers - 0.5 * e_at).abs() < 1e-9 * e_at);
        assert!(r.energy.residual.abs() < 1e-9 * r.energy.total_start);
        // a sliding rock passes at height 0: a barrier of height 0 is overtopped by everything
        let mut low = stop;
        low.lines[0].barrier = Some(Barrier {
            height: 0.0,
            rating: 1e12,
        });
        same_arrival(&run(&low, &c).unwrap().arrival, &free.arrival);
    }

    fn same_arrival(a: &super::super::Arrival, b: &super::super::Arrival) {
        assert_eq!((a.stop_reason, a.phase), (b.stop_reason, b.phase));
        for (x, y) in [
            (a.time, b.time),
            (a.speed, b.speed),
            (a.along_dip, b.along_dip),
            (a.kinetic_energy, b.kinetic_energy),
        ] {
            assert!((x - y).abs() <= 1e-12 * y.abs().max(1.0), "{x} vs {y}");
        }
    }

    fn barrier(height: f64, rating: f64) -> Line {
        Line {
            along_dip: 10.0,
            across: Some((-1.0, 2.0)),
            barrier: Some(Barrier { height, rating }),
        }
    }

    #[test]
    fn a_barrier_stops_within_its_rating_and_takes_the_rating_past_it() {
        let l = barrier(1.0, 500.0);
        assert_eq!(act(&l, 0.2, 500.0), (LineAction::Stopped, 0.0));
        assert_eq!(act(&l, 1.0, 50.0), (LineAction::Overtopped, 1.0));
        let (a, f) = act(&l, 0.0, 2000.0);
        assert_eq!(a, LineAction::BrokenThrough);
        // the energy left is E − R
        assert!((2000.0 * f * f - 1500.0).abs() < 1e-9);
        let free = Line { barrier: None, ..l };
        assert_eq!(act(&free, 0.0, 1e9), (LineAction::Passed, 1.0));
    }

    #[test]
    fn a_line_spans_its_range_and_lines_start_down_slope() {
        let l = barrier(1.0, 1.0);
        assert!(l.spans(-1.0) && l.spans(2.0) && !l.spans(2.0001));
        let lines = [5.0, 10.0, 10.0, 20.0].map(|s| Line {
            along_dip: s,
            across: None,
            barrier: None,
        });
        assert_eq!(first_reachable(&lines, 0.0), 0);
        assert_eq!(first_reachable(&lines, 10.0), 1);
        assert_eq!(first_reachable(&lines, 10.5), 3);
        assert_eq!(first_reachable(&lines, 25.0), 4);
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig { cases: 256, ..Default::default() })]

        /// Over the documented ranges (dip, friction, drop, release, line position, barrier
        /// height and rating from the smallest to the largest), a barrier never creates energy
        /// and takes at most its rating, the account stays closed, and a rock it stops rests on
        /// its line at rest; both methods (the rigid block on fewer, shorter faces).
        #[test]
        fn a_barrier_takes_at_most_its_rating_and_keeps_the_account(
            dip in 35.0f64..=55.0,
            mu in 0.05f64..=1.0,
            drop in 0.0f64..=5.0,
            release in 0.0f64..=20.0,
            at in 0.0f64..=1.0,
            height in proptest::prop_oneof![proptest::strategy::Just(1e-9), 1e-6f64..=100.0],
            rating_exp in -3.0f64..=12.0,
            rigid in proptest::bool::weighted(0.1),
        ) {
            let mut c = slide(if rigid { Method::RigidBlock } else { Method::LumpedMass });
            c.face.dip_deg = dip;
            c.face.friction_coefficient = mu;
            c.face.length = if rigid { 30.0 } else { 60.0 };
            c.release.drop_height = drop;
            c.release.along_dip = release;
            let rating = 10f64.powf(rating_exp);
            let along = release + at * (c.face.length - release);
            c.lines = vec![line(along, Some(Barrier { height, rating }))];
            let ctl = Control::unlimited();
            let r = run(&c, &ctl).unwrap();
            let e = &r.energy;
            let total = e.total_start;
            // at most the rating, to the rounding of the energy in play
            proptest::prop_assert!(
                e.barriers >= 0.0 && e.barriers <= rating * (1.0 + 1e-12) + 1e-12 * total,
                "{e:?}"
            );
            let mut free = c;
            free.lines.clear();
            let f = run(&free, &ctl).unwrap();
            // the rigid block's residual stays within what its own property tests bound (0.2 %
            // of the energy in play), the lumped mass's is rounding
            let tol = if rigid { 2.0 * f.energy.residual.abs() + 2e-3 * total } else { 1e-9 * total };
            proptest::prop_assert!(e.residual.abs() <= tol, "{e:?} vs free {:?}", f.energy);
            if r.arrival.stop_reason == StopReason::Barrier {
                proptest::prop_assert_eq!(r.arrival.speed, 0.0);
                let reach = if rigid { 0.01 } else { 1e-9 };
                proptest::prop_assert!((r.arrival.along_dip - along).abs() <= reach * along.max(1.0),
                    "stopped at {} for a line at {along}", r.arrival.along_dip);
            }
        }
    }
}
