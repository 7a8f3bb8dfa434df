//! `POST /v1/scene`: the answer — impacts, statistics per support, comparison — built from
//! the report.

use super::*;
use crate::http::dto::devices::DeviceStatisticsDto;

/// True when the scene has barriers (the outcomes then give the share they stopped).
fn has_barriers(case: &SceneCase) -> bool {
    case.migration.lines.iter().any(|l| l.barrier.is_some())
}

/// One design check of an impact.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct CheckDto {
    /// `stress_utilisation`, `max_force_n` or `absorbed_energy_j`.
    pub limit: String,
    /// The value (omitted past the contact capacity).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub value: Option<f64>,
    /// The allowed value.
    pub allowed: f64,
    /// value / allowed (omitted past the contact capacity, or when it overflows a double).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub utilisation: Option<f64>,
    /// value > allowed, or past the contact capacity.
    pub exceeded: bool,
}

impl From<&Check> for CheckDto {
    fn from(c: &Check) -> Self {
        Self {
            limit: limit_name(c.limit).into(),
            value: c.value,
            allowed: c.allowed,
            utilisation: c.utilisation,
            exceeded: c.exceeded,
        }
    }
}

/// An impact on a support entry.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct SceneImpactDto {
    /// Support number (from 1).
    pub support: u32,
    /// Column of that support (from 0).
    pub column_index: u32,
    /// Along-dip position, m.
    pub along_dip_m: f64,
    /// Across position of the column, m (null: spanning support).
    pub across_m: Option<f64>,
    /// The impact speed, m/s.
    pub impact_velocity_m_s: f64,
    /// `struck`, `no_impact` (below 1e-6 m/s, or held by the support's guard: all values 0) or
    /// `capacity_exceeded`.
    pub outcome: String,
    /// What the support's guard did: `held` (the impact energy within its rating) or
    /// `broken_through` (omitted without a guard).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub guard: Option<String>,
    /// The speed the column was struck at behind the guard, m/s (omitted without a guard).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub column_impact_velocity_m_s: Option<f64>,
    /// Largest speed the contact law takes, m/s (past the capacity only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_velocity_m_s: Option<f64>,
    /// The `/v1/impact` response for this impact (struck only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub impact: Option<ImpactResponse>,
    /// The `/v1/column` response for this impact (struck only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub column: Option<ColumnResponse>,
    /// The design checks.
    pub checks: Vec<CheckDto>,
    /// `ok` or `exceeded`.
    pub verdict: String,
    /// The nominal run of an ensemble.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub nominal: Option<bool>,
}

/// Fractions of all runs by how they ended (summing to 1).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, ToSchema)]
pub struct OutcomesDto {
    /// Ended at a support.
    pub support: f64,
    /// Reached the lower end.
    pub lower_end: f64,
    /// Came to rest.
    pub at_rest: f64,
    /// Left the floor.
    pub left_floor: f64,
    /// Reached the end time.
    pub end_time: f64,
    /// Stopped by a barrier (only with `barriers`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub barrier: Option<f64>,
}

impl From<&Outcomes> for OutcomesDto {
    fn from(o: &Outcomes) -> Self {
        Self {
            support: o.support,
            lower_end: o.lower_end,
            at_rest: o.at_rest,
            left_floor: o.left_floor,
            end_time: o.end_time,
            barrier: None,
        }
    }
}

/// A probability with its Wilson 95 % interval (z = 1.959963984540054).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, ToSchema)]
pub struct ProbabilityDto {
    /// Fraction of all runs.
    pub probability: f64,
    /// Wilson score interval [lo, hi].
    pub ci95: [f64; 2],
}

impl From<&Probability> for ProbabilityDto {
    fn from(p: &Probability) -> Self {
        Self {
            probability: p.probability,
            ci95: p.ci95,
        }
    }
}

/// Exceedance probabilities per checked limit.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, ToSchema, Default)]
pub struct ExceedanceDto {
    /// Stress utilisation above its limit.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stress_utilisation: Option<ProbabilityDto>,
    /// Force above the rated force.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_force_n: Option<ProbabilityDto>,
    /// Absorbed energy above the design energy.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub absorbed_energy_j: Option<ProbabilityDto>,
}

/// Ensemble statistics of one support entry.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct SupportStatisticsDto {
    /// Support number (from 1).
    pub support: u32,
    /// Column of that support (from 0).
    pub column_index: u32,
    /// Along-dip position, m.
    pub along_dip_m: f64,
    /// Across position of the column, m (null: spanning support).
    pub across_m: Option<f64>,
    /// Fraction of all runs that ended at this entry.
    pub reached_fraction: f64,
    /// Fraction of all runs that ended here past the contact capacity.
    pub capacity_exceeded_fraction: f64,
    /// Impact speed over the runs that reached it within capacity, m/s (null: none did).
    pub impact_velocity_m_s: Option<SummaryDto>,
    /// δmax (coupled: largest contact deformation), m.
    pub max_deformation_m: Option<SummaryDto>,
    /// Pmax (coupled: the column's max_force_n), N.
    pub max_force_n: Option<SummaryDto>,
    /// Absorbed energy (coupled: column energy after the contact), J.
    pub absorbed_energy_j: Option<SummaryDto>,
    /// Bending-stress utilisation σ/σ_y.
    pub stress_utilisation: Option<SummaryDto>,
    /// Probability over all runs that a rock strikes this entry past each checked limit.
    pub exceedance: ExceedanceDto,
    /// `exceeded` when a probability is above acceptable_probability, else `ok`.
    pub verdict: String,
    /// Expected strikes of this support past some checked limit per year, with a 95 % interval
    /// and the return period (with `release_rate`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub overloads_per_year: Option<FrequencyDto>,
    /// What this support's guard did (with `guards`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub guard: Option<GuardStatisticsDto>,
    /// Design values: the rock's state on reaching this entry over every run that reached it
    /// (past the capacity too), each with its value at `design_percentile` and a
    /// distribution-free 95 % interval (null: no run reached it).
    pub design_values: Option<super::super::design_values::DesignValuesDto>,
}

/// Ensemble statistics of a scene.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct SceneStatisticsDto {
    /// Number of runs.
    pub runs: u64,
    /// Seed.
    pub seed: u64,
    /// How the runs ended.
    pub outcomes: OutcomesDto,
    /// Per support entry.
    pub supports: Vec<SupportStatisticsDto>,
    /// Probability that a run overloads some support.
    pub any_exceeded: ProbabilityDto,
    /// Expected overloads of some support per year (with `release_rate`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub any_overloads_per_year: Option<FrequencyDto>,
    /// Per barrier, in request order: the runs that reached it, what it did, the rock's state
    /// at its line (with `barriers`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub barriers: Option<Vec<DeviceStatisticsDto>>,
    /// Per collector, in request order: the runs that reached it and the rock's state at its
    /// line (with `collectors`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub collectors: Option<Vec<DeviceStatisticsDto>>,
    /// What `monte_carlo.target` gave: the runs used, whether the target was met.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub target: Option<crate::http::dto::target::TargetOutcomeDto>,
}

/// One entry of one method in a comparison.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct ComparedSupportDto {
    /// Support number.
    pub support: u32,
    /// Column of that support.
    pub column_index: u32,
    /// Fraction of runs that ended at this entry.
    pub reached_fraction: f64,
    /// Median impact speed, m/s (null: never reached within capacity).
    pub impact_velocity_median_m_s: Option<f64>,
    /// Exceedance probability per checked limit.
    pub exceedance: std::collections::BTreeMap<String, f64>,
}

/// One method of a comparison.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct MethodComparisonDto {
    /// `lumped_mass` or `rigid_block`.
    pub method: String,
    /// How the runs ended (a single run: 1 for its outcome).
    pub outcomes: OutcomesDto,
    /// Per support entry.
    pub supports: Vec<ComparedSupportDto>,
}

/// The answer of `POST /v1/scene`.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct SceneResponse {
    /// Stages `release`, `migration`, `impact`, `column`, `checks`, `allowed_impacts` and, with
    /// `design`, `design`: ran or skipped, and why.
    pub plan: Vec<PlanStep>,
    /// The migration response of the (nominal) run (omitted with impact_velocity_m_s).
    #[serde(skip_serializing_if = "Option::is_none")]
    #[schema(value_type = Option<MigrationResponse>)]
    pub migration: Option<Piece<MigrationResponse>>,
    /// Impacts: every support at impact_velocity_m_s, the single run's, or the nominal run's.
    #[schema(value_type = Vec<SceneImpactDto>)]
    pub impacts: Piece<Vec<SceneImpactDto>>,
    /// Ensemble statistics (Monte Carlo).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub statistics: Option<SceneStatisticsDto>,
    /// Both methods side by side (compare_methods).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub comparison: Option<Vec<MethodComparisonDto>>,
    /// Per support entry, what its column can take: the allowed impact speed and energy of the
    /// case's nominal rock per design limit, and the margin of the ensemble's design impact
    /// speed against it (omitted with `allowed_impacts: false`; empty when no limit is checked).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub allowed_impacts: Option<Vec<AllowedImpactsDto>>,
    /// Per-cell maps of the ensemble's runs, each to its stop (when `migration_output.maps`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub maps: Option<super::super::maps::MapsOutDto>,
    /// Named warnings, among them `release_zones_clipped` (the share of the release zones'
    /// weight where the rock does not fit on the floor, clipped off) and those of the migration.
    pub warnings: Vec<super::super::Warning>,
    /// The fully resolved request.
    pub inputs: SceneRequest,
    /// Version of the service and its models.
    pub model_version: String,
    /// The design search for guards: per support column, the smallest guard rating that makes
    /// it acceptable and its exceedance with it (with `design`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub design: Option<super::super::design_search::DesignSearchOutDto>,
}

/// A piece of the answer: built here, or serialized earlier by the same code (the part 0 of a
/// sharded computation stores the pieces its ensemble does not change) and written back
/// verbatim in place of a placeholder ([`Piece::Stored`]'s index) by [`SceneHead::finish`].
#[derive(Debug, Clone, PartialEq)]
pub enum Piece<T> {
    /// Built in this process.
    Built(T),
    /// The stored piece of this index (serialized as its placeholder).
    Stored(usize),
}

impl<T: Serialize> Serialize for Piece<T> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Piece::Built(t) => t.serialize(s),
            Piece::Stored(i) => s.serialize_str(&placeholder(&format!("piece-{i}"))),
        }
    }
}

/// A placeholder for bytes written in its place: a string with control characters, which the
/// service never writes (should a request echo one, [`splice`] refuses rather than guess).
pub(super) fn placeholder(name: &str) -> String {
    format!("\u{1}gangue-{name}\u{1}")
}

/// Replaces the one serialized `placeholder(name)` (a JSON string) in `json` by `with`.
pub(super) fn splice(json: &[u8], name: &str, with: &[u8]) -> Result<Vec<u8>, ApiError> {
    let mark = serde_json::to_vec(&placeholder(name)).map_err(ApiError::internal)?;
    let at: Vec<usize> = json
        .windows(mark.len())
        .enumerate()
        .filter(|(_, w)| *w == mark.as_slice())
        .map(|(i, _)| i)
        .collect();
    let [at] = at[..] else {
        return Err(ApiError::internal(format!(
            "the placeholder of {name} occurs {} times in the answer, not once",
            at.len()
        )));
    };
    let mut out = Vec::with_capacity(json.len() + with.len());
    out.extend_from_slice(&json[..at]);
    out.extend_from_slice(with);
    out.extend_from_slice(&json[at + mark.len()..]);
    Ok(out)
}

pub(super) fn statistics_dto(st: &SceneStatistics, case: &SceneCase) -> SceneStatisticsDto {
    SceneStatisticsDto {
        runs: st.runs,
        seed: st.seed,
        outcomes: OutcomesDto {
            barrier: has_barriers(case).then_some(st.outcomes.barrier),
            ..(&st.outcomes).into()
        },
        supports: st
            .entries
            .iter()
            .zip(&case.supports)
            .map(|(s, e)| {
                let mut ex = ExceedanceDto::default();
                for (l, p) in &s.exceedance {
                    let p = Some(p.into());
                    match l {
                        Limit::StressUtilisation => ex.stress_utilisation = p,
                        Limit::MaxForce => ex.max_force_n = p,
                        Limit::AbsorbedEnergy => ex.absorbed_energy_j = p,
                    }
                }
                SupportStatisticsDto {
                    support: e.support,
                    column_index: e.column_index,
                    along_dip_m: e.along_dip,
                    across_m: e.across,
                    reached_fraction: s.reached_fraction,
                    capacity_exceeded_fraction: s.capacity_exceeded_fraction,
                    impact_velocity_m_s: s.impact_velocity.as_ref().map(Into::into),
                    max_deformation_m: s.max_deformation.as_ref().map(Into::into),
                    max_force_n: s.max_force.as_ref().map(Into::into),
                    absorbed_energy_j: s.absorbed_energy.as_ref().map(Into::into),
                    stress_utilisation: s.stress_utilisation.as_ref().map(Into::into),
                    exceedance: ex,
                    verdict: if s.exceeded { "exceeded" } else { "ok" }.into(),
                    overloads_per_year: s.overloads_per_year.as_ref().map(FrequencyDto::from),
                    guard: s.guard.as_ref().map(GuardStatisticsDto::from),
                    design_values: s.design_values.as_ref().map(Into::into),
                }
            })
            .collect(),
        any_exceeded: (&st.any_exceeded).into(),
        any_overloads_per_year: st.any_overloads_per_year.as_ref().map(FrequencyDto::from),
        barriers: devices(st, case, true),
        collectors: devices(st, case, false),
        target: st.target.as_ref().map(Into::into),
    }
}

/// The statistics of the scene's barriers (or collectors), in request order (None: none given).
fn devices(
    st: &SceneStatistics,
    case: &SceneCase,
    barriers: bool,
) -> Option<Vec<DeviceStatisticsDto>> {
    let out: Vec<DeviceStatisticsDto> = st
        .devices
        .iter()
        .zip(&case.device_lines)
        .map(|(s, &k)| (s, &case.migration.lines[k]))
        .filter(|(_, l)| l.barrier.is_some() == barriers)
        .map(|(s, l)| DeviceStatisticsDto::new(l, s))
        .collect();
    (!out.is_empty()).then_some(out)
}

pub(super) fn impact_dto(
    case: &SceneCase,
    ctx: &SceneContext,
    req: &SceneRequest,
    o: &scene::ImpactOutcome,
) -> SceneImpactDto {
    let e = &case.supports[o.entry];
    let (outcome, max_velocity, impact, column) = match &o.strike {
        Strike::NoImpact => ("no_impact", None, None, None),
        Strike::CapacityExceeded { max_velocity } => {
            ("capacity_exceeded", *max_velocity, None, None)
        }
        Strike::Solved {
            impact_case,
            impact,
            column,
            ..
        } => {
            let mut rock = ctx.impact_rock.clone();
            rock.side_length_m = impact_case.rock.side_length;
            let ireq = ImpactRequest {
                velocity_m_s: o.column_speed,
                rock: rock.clone(),
                column: ctx.entry_column[o.entry].clone(),
                contact: req.contact,
                output: Default::default(),
            };
            let creq = ColumnRequest {
                velocity_m_s: o.column_speed,
                rock,
                column: ctx.entry_column[o.entry].clone(),
                contact: req.contact,
                model: req.column_model,
                galerkin: ctx.galerkin,
                initial_midpoint_displacement_m: None,
                end_time_s: None,
                output: req.column_output.clone(),
            };
            (
                "struck",
                None,
                Some(ImpactResponse::new(
                    calc::impact::report(impact_case, (**impact).clone(), None, 0),
                    ireq,
                )),
                Some(ColumnResponse::new(
                    calc::column::report((**column).clone()),
                    creq,
                )),
            )
        }
    };
    SceneImpactDto {
        support: e.support,
        column_index: e.column_index,
        along_dip_m: e.along_dip,
        across_m: e.across,
        impact_velocity_m_s: o.velocity,
        outcome: outcome.into(),
        guard: match o.guard {
            scene::Guard::None => None,
            scene::Guard::Held => Some("held".into()),
            scene::Guard::BrokenThrough => Some("broken_through".into()),
        },
        column_impact_velocity_m_s: (o.guard != scene::Guard::None).then_some(o.column_speed),
        max_velocity_m_s: max_velocity,
        impact,
        column,
        checks: o.checks.iter().map(Into::into).collect(),
        verdict: if o.exceeded { "exceeded" } else { "ok" }.into(),
        nominal: o.nominal.then_some(true),
    }
}

pub(super) fn comparison_dto(case: &SceneCase, m: &MethodSummary) -> MethodComparisonDto {
    MethodComparisonDto {
        method: match m.method {
            Method::LumpedMass => "lumped_mass",
            Method::RigidBlock => "rigid_block",
        }
        .into(),
        outcomes: OutcomesDto {
            barrier: has_barriers(case).then_some(m.outcomes.barrier),
            ..(&m.outcomes).into()
        },
        supports: m
            .entries
            .iter()
            .zip(&case.supports)
            .map(|((reached, median, ex), e)| ComparedSupportDto {
                support: e.support,
                column_index: e.column_index,
                reached_fraction: *reached,
                impact_velocity_median_m_s: *median,
                exceedance: ex
                    .iter()
                    .map(|(l, p)| (limit_name(*l).to_string(), *p))
                    .collect(),
            })
            .collect(),
    }
}

impl SceneResponse {
    /// Builds the response from the report, the case and the resolved request.
    #[must_use]
    #[allow(
        clippy::needless_pass_by_value,
        reason = "the route hands over the report and context it no longer needs"
    )]
    pub fn new(
        report: Report<SceneReport>,
        case: &SceneCase,
        ctx: SceneContext,
        inputs: SceneRequest,
    ) -> Self {
        let plan = plan_of(&report.plan);
        let mut warnings = warnings_of(&report.warnings);
        let r = report.result;
        let impacts = r
            .impacts
            .iter()
            .map(|o| impact_dto(case, &ctx, &inputs, o))
            .collect();
        let statistics = r.statistics.as_ref().map(|st| statistics_dto(st, case));
        let csv = match (&r.runs, inputs.migration_output.runs_csv) {
            (Some(runs), true) => Some(runs_csv(case, runs)),
            _ => None,
        };
        let migration = r.migration.clone().map(|m| {
            let mut resp = MigrationResponse::new(
                calc::migration::report(&case.migration, m),
                ctx.migration.clone(),
            );
            resp.runs_csv = csv;
            resp
        });
        if let Some(m) = &migration {
            warnings.extend(m.warnings.iter().cloned());
        }
        let comparison = r
            .comparison
            .as_ref()
            .map(|c| c.iter().map(|m| comparison_dto(case, m)).collect());
        let meta = Meta::new(plan);
        Self {
            plan: meta.plan,
            migration: migration.map(Piece::Built),
            impacts: Piece::Built(impacts),
            statistics,
            comparison,
            allowed_impacts: r.allowed.as_ref().map(|a| allowed_dto(case, a)),
            maps: r.maps.as_ref().map(Into::into),
            warnings,
            inputs,
            model_version: meta.model_version,
            design: r.design.as_ref().map(|d| {
                super::super::design_search::design_dto(case, d, r.barrier_design.as_ref())
            }),
        }
    }
}
