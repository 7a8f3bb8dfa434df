//! `/v1/scene`: release → migration → impact on the first support reached → column → design
//! checks, for one run or the nominal run and a seeded ensemble (items: the runs).

use super::{Calculation, Ensemble, Report, Stage};
use crate::physics::Control;
use crate::physics::design::{self, EntryAllowed};
use crate::physics::migration::maps::{self, Maps, RunCells};
use crate::physics::migration::{Method, MonteCarlo};
use crate::physics::scene::target::{self, SceneTarget, TargetOutcome};
use crate::physics::scene::{
    self, EnsembleReport, SceneCase, SceneError, SceneRecords, SceneReport, SceneRun,
    SceneStatistics,
};
use crate::physics::stats::precision;

/// The scene calculation.
#[derive(Debug, Clone, Copy)]
pub struct Scene;

impl Calculation for Scene {
    type Case = SceneCase;
    type Result = SceneReport;
    type Error = SceneError;

    fn solve(case: &SceneCase, control: &Control) -> Result<Report<SceneReport>, SceneError> {
        let (mut r, mc) = nominal_report(case, control)?;
        if let Some(mut mc) = mc {
            // with a target, the runs it needs first (the runs of that many, bit for bit)
            let (early, outcome) = match &case.target {
                Some(t) => {
                    let (runs, maps, outcome) = until_precise(case, &mc, t, control)?;
                    mc.runs = outcome.runs;
                    r.maps = maps;
                    (Some(runs), Some(outcome))
                }
                None => (None, None),
            };
            let (runs, other) = match (&case.migration.output.maps, early) {
                (None, None) => scene::ensemble_part(case, &mc, 0..mc.runs, control)?,
                (_, Some(runs)) => {
                    let other = if case.compare_methods {
                        Some(other_method(case, &mc, control)?)
                    } else {
                        None
                    };
                    (runs, other)
                }
                (Some(g), None) => {
                    let (runs, other, maps) = scene::ensemble_part_mapped(case, &mc, g, control)?;
                    r.maps = Some(maps);
                    (runs, other)
                }
            };
            let capacity = scene::nominal_capacity(&r);
            let Ok(mut tail) = scene::ensemble_report(
                case,
                &mc,
                capacity,
                runs.as_slice(),
                other.as_deref(),
                false,
            );
            tail.statistics.target = outcome;
            attach(&mut r, tail);
            if let Some(ask) = &case.design {
                let d = scene::design_search::design_search(case, ask, &runs, control)?;
                r.plan.push(scene::design_search::design_stage(&d));
                r.warnings
                    .extend(scene::design_search::residual_risk_warning(case, &d));
                r.design = Some(d);
                if let Some(search) = &ask.barriers {
                    let b = scene::barrier_design::design_barriers(case, &mc, search, control)?;
                    r.plan.push(Stage::ran(
                        "design_barriers",
                        format!(
                            "greedy barrier search over {} candidates, {} ensembles of {} runs",
                            b.candidates.len(),
                            b.ensembles,
                            mc.runs
                        ),
                    ));
                    r.barrier_design = Some(b);
                }
            }
            r.runs = Some(runs);
        }
        Ok(report(r))
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

/// The runs of `case`'s own method in prefixes ([`precision::checkpoints`]) until `t`'s statistic
/// is precise enough or every run of `mc` ran, and what the target gave.
///
/// # Errors
/// As [`Scene::solve`].
pub fn until_precise(
    case: &SceneCase,
    mc: &MonteCarlo,
    t: &SceneTarget,
    control: &Control,
) -> Result<(Vec<SceneRun>, Option<Maps>, TargetOutcome), SceneError> {
    let own = SceneCase {
        compare_methods: false,
        ..case.clone()
    };
    let grid = case.migration.output.maps.as_ref();
    let mut runs: Vec<SceneRun> = Vec::new();
    let mut cells: Vec<RunCells> = Vec::new();
    let mut checked_at = Vec::new();
    let mut half_width = 0.5;
    for n in precision::checkpoints(mc.runs) {
        // progress and pace: the prefix being run (and the nominal run) is the work announced
        control.set_total(1 + n);
        let range = runs.len() as u64..n;
        match grid {
            None => runs.extend(scene::ensemble_part(&own, mc, range, control)?.0),
            Some(g) => {
                let (more, c) = scene::ensemble_cells(&own, mc, range, g, control)?;
                runs.extend(more);
                cells.extend(c);
            }
        }
        checked_at.push(n);
        half_width = target::measured_half_width(case, t, &runs);
        if half_width <= t.half_width {
            break;
        }
    }
    let outcome = TargetOutcome {
        target: *t,
        half_width,
        met: half_width <= t.half_width,
        runs: runs.len() as u64,
        max_runs: mc.runs,
        checked_at,
    };
    control.check()?;
    let maps = grid.map(|g| maps::build_maps(g, &cells));
    Ok((runs, maps, outcome))
}

/// The runs of `mc` with the other migration method (`compare_methods`).
fn other_method(
    case: &SceneCase,
    mc: &MonteCarlo,
    control: &Control,
) -> Result<Vec<SceneRun>, SceneError> {
    let mut other = case.clone();
    other.compare_methods = false;
    other.migration.method = match case.migration.method {
        Method::LumpedMass => Method::RigidBlock,
        Method::RigidBlock => Method::LumpedMass,
    };
    Ok(scene::ensemble_part(&other, mc, 0..mc.runs, control)?.0)
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
/// ensemble) and the allowed impacts, computed once (by shard 0 of a sharded computation).
///
/// # Errors
/// As [`Scene::solve`].
pub fn nominal(case: &SceneCase, control: &Control) -> Result<Report<SceneReport>, SceneError> {
    Ok(report(nominal_report(case, control)?.0))
}

/// [`scene::solve_nominal`] with the allowed impacts (their stage after the nominal ones), and
/// the ensemble still to run.
fn nominal_report(
    case: &SceneCase,
    control: &Control,
) -> Result<(SceneReport, Option<MonteCarlo>), SceneError> {
    let (mut r, mc) = scene::solve_nominal(case, control)?;
    if let Some((allowed, stage)) = allowed_impacts(case, control)? {
        r.plan.push(stage);
        r.allowed = Some(allowed);
    }
    Ok((r, mc))
}

/// Adds the ensemble's `tail` to the nominal report `r` ([`SceneReport::attach`]) and gives the
/// allowed impacts their design speeds ([`design_speeds`]).
pub fn attach(r: &mut SceneReport, tail: EnsembleReport) {
    r.attach(tail);
    if let (Some(a), Some(st)) = (r.allowed.as_mut(), r.statistics.as_ref()) {
        design_speeds(a, st);
    }
}

/// Sets each entry's design impact speed from the ensemble's statistics: its design value of
/// the impact speed (the design percentile over every run that reached it, past the contact
/// capacity too; None: none did).
pub fn design_speeds(allowed: &mut [EntryAllowed], statistics: &SceneStatistics) {
    for (a, e) in allowed.iter_mut().zip(&statistics.entries) {
        a.design_speed = e.design_values.as_ref().map(|d| d.impact_speed.value);
    }
}

/// The allowed impacts of every support entry and the plan's stage for them (None: not asked
/// for), without design speeds ([`design_speeds`] adds them from the ensemble).
///
/// # Errors
/// The chain's ([`design::allowed_for_entries`]).
pub fn allowed_impacts(
    case: &SceneCase,
    control: &Control,
) -> Result<Option<(Vec<EntryAllowed>, Stage)>, SceneError> {
    if !case.allowed_impacts {
        return Ok(None);
    }
    let limits = case.limits.active().len();
    if limits == 0 {
        let stage = Stage::skipped("allowed_impacts", "no design limit is checked");
        return Ok(Some((Vec::new(), stage)));
    }
    let allowed = design::allowed_for_entries(case, control)?;
    let columns = design::distinct_columns(case);
    let stage = Stage::ran(
        "allowed_impacts",
        format!(
            "the inverse of the chain for {limits} design limit(s) on {columns} distinct \
             column(s), the case's nominal rock, to a relative {:e}",
            design::RELATIVE_TOLERANCE
        ),
    );
    Ok(Some((allowed, stage)))
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
