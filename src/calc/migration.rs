//! `/v1/migration`: one run down the face, or the nominal run and a seeded Monte Carlo
//! ensemble (items: the runs).

use super::{Calculation, Ensemble, Report, Stage};
use crate::physics::migration::{
    self, Method, MigrationCase, MigrationResult, RunRecords, RunSummary, compare, maps,
};
use crate::physics::{Control, PhysicsError};

/// The migration calculation.
#[derive(Debug, Clone, Copy)]
pub struct Migration;

impl Calculation for Migration {
    type Case = MigrationCase;
    type Result = MigrationResult;
    type Error = PhysicsError;

    fn solve(
        case: &MigrationCase,
        control: &Control,
    ) -> Result<Report<MigrationResult>, PhysicsError> {
        let mut r = migration::run(case, control)?;
        if case.output.compare_methods {
            r.comparison = Some(compare_methods(case, &r, control)?);
        }
        Ok(report(case, r))
    }
}

/// The other method on `case` (the same ensemble, the runs `r` used) and the comparison of its
/// answer with `r` (the agreement, the floor's relief and class: [`compare::MethodComparison`]).
///
/// # Errors
/// The other method's run's: the request is answered for both methods or refused.
pub fn compare_methods(
    case: &MigrationCase,
    r: &MigrationResult,
    control: &Control,
) -> Result<compare::MethodComparison, PhysicsError> {
    let other = compare::other_case(case, r.statistics.as_ref().map(|s| s.runs));
    let o = migration::run(&other, control)?;
    let floor = migration::build_floor(case)?;
    compare::compare(case, &floor, r, &o)
}

impl Ensemble for Migration {
    type Part = Vec<RunSummary>;

    fn items(case: &MigrationCase) -> u64 {
        case.monte_carlo.map_or(0, |mc| mc.runs)
    }

    fn part(
        case: &MigrationCase,
        range: std::ops::Range<u64>,
        control: &Control,
    ) -> Result<Vec<RunSummary>, PhysicsError> {
        Ok(migration::run_part(case, range, false, control)?.1)
    }
}

/// The runs of `range` of `case` with the cells each run's path entered on the map grid of
/// `case.output.maps` (empty without one), in run order: a shard's part of a migration with maps.
///
/// # Errors
/// As [`Migration::solve`].
pub fn part_with_maps(
    case: &MigrationCase,
    range: std::ops::Range<u64>,
    control: &Control,
) -> Result<(Vec<RunSummary>, Vec<maps::RunCells>), PhysicsError> {
    let (_, runs, cells) =
        migration::run_part_mapped(case, range, false, case.output.maps.as_ref(), control)?;
    Ok((runs, cells))
}

/// The report of `case` from the records of its runs (computed here or read back from the
/// parts of a sharded computation): the nominal run is run here, the statistics are those of
/// the records, so any split gives the bytes of [`Migration::solve`].
///
/// # Errors
/// The nominal run's, or those of reading the records.
pub fn merge<R: RunRecords + ?Sized>(
    case: &MigrationCase,
    records: &R,
    control: &Control,
) -> Result<Report<MigrationResult>, MergeError<R::Error>> {
    let (nominal, _) =
        migration::run_part(case, 0..0, true, control).map_err(MergeError::Physics)?;
    let mut r = nominal.ok_or(MergeError::Physics(PhysicsError::Numerical(
        "no nominal run".into(),
    )))?;
    if let Some(mc) = &case.monte_carlo {
        migration::attach_ensemble(&mut r, mc, case.output.runs_csv, records)
            .map_err(MergeError::Records)?;
    }
    Ok(report(case, r))
}

/// The failure of a merge: the nominal run's or the records'.
#[derive(Debug, Clone, PartialEq)]
pub enum MergeError<E> {
    /// The nominal run failed.
    Physics(PhysicsError),
    /// The records could not be read.
    Records(E),
}

/// The report of a solved migration of `case`: its plan and its warnings (taken out of the
/// result).
#[must_use]
pub fn report(case: &MigrationCase, mut r: MigrationResult) -> Report<MigrationResult> {
    let mc = case.monte_carlo.is_some();
    let trajectory = r.trajectory.is_some();
    let mut plan = match case.method {
        Method::RigidBlock => vec![
            Stage::ran(
                "migration",
                if mc {
                    "rigid-block DEM, seeded Monte Carlo ensemble (contact steps, closed-form free flights)"
                } else {
                    "rigid-block DEM, one deterministic run (contact steps, closed-form free flights)"
                },
            ),
            if trajectory {
                Stage::ran("trajectory", "sampled during the run")
            } else {
                Stage::skipped("trajectory", "output.trajectory is false")
            },
        ],
        Method::LumpedMass => vec![
            Stage::ran(
                "migration",
                if mc {
                    "energy tracking method, seeded Monte Carlo ensemble (closed-form flights and slides)"
                } else {
                    "energy tracking method, one deterministic run (closed-form flights and slides)"
                },
            ),
            if trajectory {
                Stage::ran("trajectory", "sampled from the closed forms")
            } else {
                Stage::skipped("trajectory", "output.trajectory is false")
            },
        ],
    };
    plan.push(if r.comparison.is_some() {
        Stage::ran(
            "comparison",
            "the other method on the same case and ensemble, and whether the two agree",
        )
    } else {
        Stage::skipped("comparison", "output.compare_methods is false")
    });
    Report {
        warnings: std::mem::take(&mut r.warnings),
        result: r,
        plan,
    }
}
