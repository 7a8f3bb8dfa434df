//! `/v1/impact`: the contact maxima of a rock on a rigid column, the force curve when asked for,
//! and the contact's validity warnings.

use super::{Calculation, Report, Stage};
use crate::physics::contact::{self, ForceCurve, ImpactResult};
use crate::physics::material::ImpactCase;
use crate::physics::{Control, PhysicsError, validity};

/// An impact calculation: the physics case and the points of the force curve (0: none).
#[derive(Debug, Clone, PartialEq)]
pub struct Case {
    /// The rock, the column, the contact law and the impact speed.
    pub impact: ImpactCase,
    /// Points of the force–approach curve P(δ) from 0 to δmax (0: no curve).
    pub curve_points: usize,
}

/// An impact's result: the maxima and the curve.
#[derive(Debug, Clone, PartialEq)]
pub struct Outcome {
    /// Maxima, capacity and duration.
    pub impact: ImpactResult,
    /// The force–approach curve, when asked for.
    pub curve: Option<ForceCurve>,
}

/// The impact calculation.
#[derive(Debug, Clone, Copy)]
pub struct Impact;

impl Calculation for Impact {
    type Case = Case;
    type Result = Outcome;
    type Error = PhysicsError;

    fn solve(case: &Case, _control: &Control) -> Result<Report<Outcome>, PhysicsError> {
        let impact = contact::solve_impact(&case.impact)?;
        let n = case.curve_points;
        let curve = if n > 0 {
            Some(contact::impact_force_curve(&case.impact, &impact, n)?)
        } else {
            None
        };
        Ok(report(&case.impact, impact, curve, n))
    }
}

/// The report of an impact of `case` already solved (`impact`), with its curve of `n` points.
#[must_use]
pub fn report(
    case: &ImpactCase,
    impact: ImpactResult,
    curve: Option<ForceCurve>,
    n: usize,
) -> Report<Outcome> {
    let mut plan = vec![Stage::ran(
        "impact",
        "closed-form maxima on the W₋₁ branch (log laws) or Hertz; duration t_c = (2mv/Pmax)·J(u₀)",
    )];
    plan.push(if curve.is_some() {
        Stage::ran("curve", format!("{n} points of P(δ) from 0 to δmax"))
    } else {
        Stage::skipped("curve", "output.curve_points = 0")
    });
    Report {
        warnings: validity::impact_warnings(case, &impact),
        result: Outcome { impact, curve },
        plan,
    }
}
