//! `/v1/spalling`: coal-wall spalling statistics by face zone (paper Table 1).

use super::{Calculation, Report, Stage, Warning};
use crate::physics::spalling::{SpallingResult, Undefined, ZoneCounts, spalling_statistics};
use crate::physics::{Control, PhysicsError};

/// A spalling case: the zones' names and counts.
#[derive(Debug, Clone, PartialEq)]
pub struct Case {
    /// Zone names, in order.
    pub names: Vec<String>,
    /// Counts per zone, in order.
    pub counts: Vec<ZoneCounts>,
    /// The counts come from an event log (not given per zone).
    pub from_events: bool,
}

/// The spalling calculation.
#[derive(Debug, Clone, Copy)]
pub struct Spalling;

impl Calculation for Spalling {
    type Case = Case;
    type Result = SpallingResult;
    type Error = PhysicsError;

    fn solve(case: &Case, _control: &Control) -> Result<Report<SpallingResult>, PhysicsError> {
        let r = spalling_statistics(&case.counts);
        let plan = vec![Stage::ran(
            "spalling",
            if case.from_events {
                "event log counted into zones; shares, P(A|B), P(A|C), Wilson 95 % intervals"
            } else {
                "zone counts; shares, P(A|B), P(A|C), Wilson 95 % intervals"
            },
        )];
        let warnings = r
            .undefined
            .iter()
            .map(|&(at, u)| undefined_warning(&case.names, at, u))
            .collect();
        Ok(Report {
            result: r,
            plan,
            warnings,
        })
    }
}

/// The `zero_denominator` warning of a percentage left undefined in zone `at` (None: the total).
fn undefined_warning(names: &[String], at: Option<usize>, u: Undefined) -> Warning {
    let zone = at.map_or("total", |i| names[i].as_str());
    let message = match u {
        Undefined::Share(event) => format!(
            "zone `{zone}`: the share of {event} is null: the event never occurs in any zone"
        ),
        Undefined::Conditional("spalling") => format!(
            "zone `{zone}`: high_given_spalling_pct and low_given_spalling_pct are null: no spalling counted"
        ),
        Undefined::Conditional(event) => format!(
            "zone `{zone}`: the probability given {event} (and its interval) is null: no {event} events counted"
        ),
    };
    Warning {
        code: "zero_denominator",
        message,
    }
}
