//! The part of a scene's answer a sharded computation's part 0 stores, and the runs CSV.

use super::*;
use crate::physics::migration::LineAction;

/// The part of a scene's answer its ensemble does not change (from
/// [`scene::solve_nominal`]), as the part 0 of a sharded computation stores it: the plan's
/// release and migration stages, the scene's own warnings, and the migration response of the
/// nominal run and the impacts serialized by the code that serializes them in the answer (the
/// nominal run and its strikes are not computed again); for a scene without an ensemble, the
/// whole answer.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SceneHead {
    /// The whole answer (a scene without an ensemble), UTF-8 JSON.
    complete: Option<String>,
    /// Plan stages: stage, ran, reason.
    plan: Vec<(String, bool, String)>,
    /// The scene's own warnings: code, message.
    warnings: Vec<(String, String)>,
    /// The migration response of the nominal run (its runs_csv a placeholder when asked for).
    migration: Option<String>,
    /// Its warnings (listed after the scene's in the answer).
    migration_warnings: Vec<(String, String)>,
    /// The impacts.
    impacts: String,
    /// The allowed impacts (without design speeds), when asked for.
    #[serde(default)]
    allowed: Option<Vec<Vec<StoredLimit>>>,
    /// The nominal impact went past the contact capacity.
    pub nominal_capacity: bool,
}

impl SceneHead {
    /// The head of `r` (from [`scene::solve_nominal`]; `ensemble`: an ensemble follows).
    ///
    /// Errors: a non-finite number in a piece (as the service's answer would).
    pub fn new(
        report: &Report<SceneReport>,
        ensemble: bool,
        case: &SceneCase,
        ctx: &SceneContext,
        inputs: &SceneRequest,
    ) -> Result<Self, ApiError> {
        let text = |b: Vec<u8>| String::from_utf8(b).map_err(ApiError::internal);
        let r = &report.result;
        let mut head = Self {
            complete: None,
            plan: report
                .plan
                .iter()
                .map(|s| (s.stage.to_string(), s.ran, s.reason.clone()))
                .collect(),
            warnings: report
                .warnings
                .iter()
                .map(|w| (w.code.to_string(), w.message.clone()))
                .collect(),
            migration: None,
            migration_warnings: Vec::new(),
            impacts: String::new(),
            allowed: r.allowed.as_deref().map(store),
            nominal_capacity: scene::nominal_capacity(r),
        };
        if !ensemble {
            let resp = SceneResponse::new(report.clone(), case, ctx.clone(), inputs.clone());
            head.complete = Some(text(to_json_bytes(&resp)?)?);
            return Ok(head);
        }
        if let Some(m) = &r.migration {
            let mut resp = MigrationResponse::new(
                calc::migration::report(&case.migration, m.clone()),
                ctx.migration.clone(),
            );
            if inputs.migration_output.runs_csv {
                resp.runs_csv = Some(placeholder("runs-csv"));
            }
            head.migration_warnings = resp
                .warnings
                .iter()
                .map(|w| (w.code.clone(), w.message.clone()))
                .collect();
            head.migration = Some(text(to_json_bytes(&resp)?)?);
        }
        let impacts: Vec<SceneImpactDto> = r
            .impacts
            .iter()
            .map(|o| impact_dto(case, ctx, inputs, o))
            .collect();
        head.impacts = text(to_json_bytes(&impacts)?)?;
        Ok(head)
    }

    /// The answer's bytes: the stored pieces with the ensemble's `tail` (None: the head is the
    /// whole answer).
    ///
    /// Errors: a head that does not fit the tail; a non-finite number in the tail.
    pub fn finish(
        self,
        tail: Option<scene::EnsembleReport>,
        case: &SceneCase,
        inputs: SceneRequest,
    ) -> Result<Vec<u8>, ApiError> {
        let tail = match (tail, self.complete) {
            (None, Some(c)) => return Ok(c.into_bytes()),
            (Some(t), None) => t,
            _ => {
                return Err(ApiError::internal(
                    "the stored nominal part does not fit the ensemble",
                ));
            }
        };
        let mut plan: Vec<PlanStep> = self
            .plan
            .iter()
            .map(|(stage, ran, reason)| {
                if *ran {
                    PlanStep::ran(stage, reason.clone())
                } else {
                    PlanStep::skipped(stage, reason.clone())
                }
            })
            .collect();
        plan.extend(plan_of(&tail.plan));
        let warning = |(code, message): &(String, String)| super::super::Warning {
            code: code.clone(),
            message: message.clone(),
        };
        let mut warnings: Vec<super::super::Warning> = self.warnings.iter().map(warning).collect();
        warnings.extend(warnings_of(&tail.warnings));
        warnings.extend(self.migration_warnings.iter().map(warning));
        let meta = Meta::new(plan);
        let mut allowed = self
            .allowed
            .as_deref()
            .map(restore)
            .transpose()
            .map_err(|e| ApiError::internal(format!("the stored allowed impacts: {e}")))?;
        if let Some(a) = allowed.as_mut() {
            let guards = crate::physics::design::guard_allowances(case)
                .map_err(|e| ApiError::internal(format!("the stored allowed impacts: {e}")))?;
            for (a, g) in a.iter_mut().zip(guards) {
                a.guard = g;
            }
            calc::scene::design_speeds(a, &tail.statistics);
        }
        let resp = SceneResponse {
            plan: meta.plan,
            migration: self.migration.as_ref().map(|_| Piece::Stored(0)),
            impacts: Piece::Stored(1),
            statistics: Some(statistics_dto(&tail.statistics, case)),
            comparison: tail
                .comparison
                .as_ref()
                .map(|c| c.iter().map(|m| comparison_dto(case, m)).collect()),
            allowed_impacts: allowed.as_ref().map(|a| allowed_dto(case, a)),
            maps: None,
            warnings,
            inputs,
            model_version: meta.model_version,
            design: None,
        };
        let mut bytes = to_json_bytes(&resp)?;
        if let Some(m) = self.migration {
            let m = match (&tail.runs, resp.inputs.migration_output.runs_csv) {
                (Some(runs), true) => {
                    let csv =
                        serde_json::to_vec(&runs_csv(case, runs)).map_err(ApiError::internal)?;
                    splice(m.as_bytes(), "runs-csv", &csv)?
                }
                _ => m.into_bytes(),
            };
            bytes = splice(&bytes, "piece-0", &m)?;
        }
        splice(&bytes, "piece-1", self.impacts.as_bytes())
    }
}

/// The runs of an ensemble as CSV: `/v1/migration`'s documented columns, then
/// `support,column_index,impact_velocity_m_s,max_force_n,absorbed_energy_j,stress_utilisation,capacity_exceeded`
/// (empty when no support was struck), then the run columns every runs CSV appends
/// ([`RUNS_CSV_RUN_COLUMNS`](super::super::migration::RUNS_CSV_RUN_COLUMNS): release, rock, stop
/// position, energies) and `passing_height_m` (the height of the rock's lowest point above the
/// floor when it reached the support, m; empty when no support was reached); with guards,
/// `guard` (held, broken_through or empty); with barriers or collectors, per device
/// (`barrier_1`…, then `collector_1`…) the rock's state where it reached the line — speed (m/s),
/// kinetic, translational and rotational energy (J), passing height (m) and the action (passed,
/// overtopped, stopped, broken_through), empty when it did not reach it; numbers in shortest
/// round-trip form.
#[must_use]
pub fn runs_csv(case: &SceneCase, runs: &[SceneRun]) -> String {
    use super::super::migration::{
        RUNS_CSV_HEADER, RUNS_CSV_RUN_COLUMNS, runs_csv_documented_fields, runs_csv_run_fields,
    };
    let mut out = String::with_capacity(400 * (runs.len() + 1));
    out.push_str(RUNS_CSV_HEADER);
    out.push_str(",support,column_index,impact_velocity_m_s,max_force_n,absorbed_energy_j,stress_utilisation,capacity_exceeded,");
    out.push_str(RUNS_CSV_RUN_COLUMNS);
    // with guards (only then, so that a scene without them keeps its bytes): what the guard did
    let guards = case.guards.iter().any(Option::is_some);
    out.push_str(if guards {
        ",passing_height_m,guard"
    } else {
        ",passing_height_m"
    });
    // with barriers or collectors (only then): per device, the rock's state at its line
    let devices = device_names(case);
    for name in &devices {
        for col in [
            "speed_m_s",
            "kinetic_energy_j",
            "translational_energy_j",
            "rotational_energy_j",
            "passing_height_m",
            "action",
        ] {
            out.push_str(&format!(",{name}_{col}"));
        }
    }
    out.push('\n');
    for (i, r) in runs.iter().enumerate() {
        out.push_str(&runs_csv_documented_fields(i, &r.summary));
        match r.summary.support {
            Some(k) => {
                let e = &case.supports[k];
                out.push_str(&format!(
                    ",{},{},{}",
                    e.support, e.column_index, r.summary.impact_speed
                ));
                match r.values {
                    Some(v) => out.push_str(&format!(
                        ",{},{},{},false",
                        v.max_force, v.absorbed_energy, v.stress_utilisation
                    )),
                    None => out.push_str(",,,,true"),
                }
            }
            None => out.push_str(",,,,,,,"),
        }
        out.push(',');
        out.push_str(&runs_csv_run_fields(&r.summary));
        match r.summary.support {
            Some(_) => out.push_str(&format!(",{}", r.summary.passing_height)),
            None => out.push(','),
        }
        if guards {
            out.push_str(match r.guard {
                scene::Guard::None => ",",
                scene::Guard::Held => ",held",
                scene::Guard::BrokenThrough => ",broken_through",
            });
        }
        for &k in &case.device_lines {
            match r.crossings.get(k).copied().flatten() {
                Some(c) => {
                    for x in scene::crossing_columns(&c) {
                        out.push_str(&format!(",{x}"));
                    }
                    out.push_str(match c.action {
                        LineAction::Passed => ",passed",
                        LineAction::Overtopped => ",overtopped",
                        LineAction::Stopped => ",stopped",
                        LineAction::BrokenThrough => ",broken_through",
                    });
                }
                None => out.push_str(",,,,,,"),
            }
        }
        out.push('\n');
    }
    out
}

/// The CSV column prefix of each device of `case` (barriers, then collectors): `barrier_1`,
/// `collector_1`, … numbered from 1 in request order.
fn device_names(case: &SceneCase) -> Vec<String> {
    let (mut b, mut c) = (0, 0);
    case.device_lines
        .iter()
        .map(|&k| {
            if case.migration.lines[k].barrier.is_some() {
                b += 1;
                format!("barrier_{b}")
            } else {
                c += 1;
                format!("collector_{c}")
            }
        })
        .collect()
}
