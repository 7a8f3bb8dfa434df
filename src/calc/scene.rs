//! `/v1/scene`: release → migration → impact on the first support reached → column → design
//! checks, for one run or the nominal run and a seeded ensemble (items: the runs).

use super::{Calculation, Ensemble, Report};
use crate::physics::Control;
use crate::physics::migration::MonteCarlo;
use crate::physics::scene::{
    self, EnsembleReport, SceneCase, SceneError, SceneRecords, SceneReport, SceneRun,
};

/// The scene calculation.
#[derive(Debug, Clone, Copy)]
pub struct Scene;

impl Calculation for Scene {
    type Case = SceneCase;
    type Result = SceneReport;
    type Error = SceneError;

    fn solve(case: &SceneCase, control: &Control) -> Result<Report<SceneReport>, SceneError> {
        Ok(report(scene::solve(case, control)?))
    }
}

impl Ensemble for Scene {
    /// The runs, and with `compare_methods` those of the other method.
    type Part = (Vec<SceneRun>, Option<Vec<SceneRun>>);

    fn items(case: &SceneCase) -> u64 {
        ensemble(case).map_or(0, |mc| mc.runs)
    }

    fn part(
        case: &SceneCase,
        range: std::ops::Range<u64>,
        control: &Control,
    ) -> Result<Self::Part, SceneError> {
        match ensemble(case) {
            Some(mc) => scene::ensemble_part(case, &mc, range, control),
            None => Ok((Vec::new(), None)),
        }
    }
}

/// The ensemble of a scene, if it has one (not with `impact_velocity`).
#[must_use]
pub fn ensemble(case: &SceneCase) -> Option<MonteCarlo> {
    case.impact_velocity
        .is_none()
        .then_some(case.migration.monte_carlo)
        .flatten()
}

/// What is not an item: the nominal run with its strikes (the whole scene without an
/// ensemble), computed once (by shard 0 of a sharded computation).
///
/// # Errors
/// As [`Scene::solve`].
pub fn nominal(case: &SceneCase, control: &Control) -> Result<Report<SceneReport>, SceneError> {
    Ok(report(scene::solve_nominal(case, control)?.0))
}

/// The ensemble's part of the report from the records of all runs (computed here or read back
/// from parts), and with `compare_methods` those of the other method; `nominal_capacity`: the
/// nominal impact went past the contact capacity; `keep_runs`: keep the runs for the CSV.
///
/// # Errors
/// Those of reading the records.
pub fn merge<R: SceneRecords + ?Sized>(
    case: &SceneCase,
    nominal_capacity: bool,
    records: &R,
    other: Option<&R>,
    keep_runs: bool,
) -> Result<Option<EnsembleReport>, R::Error> {
    ensemble(case)
        .map(|mc| scene::ensemble_report(case, &mc, nominal_capacity, records, other, keep_runs))
        .transpose()
}

/// A scene's report: its plan and its warnings taken out of the physics report.
fn report(mut r: SceneReport) -> Report<SceneReport> {
    Report {
        plan: std::mem::take(&mut r.plan),
        warnings: std::mem::take(&mut r.warnings),
        result: r,
    }
}
