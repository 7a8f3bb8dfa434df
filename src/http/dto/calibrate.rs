//! `POST /v1/calibrate`: request, response and validation of the back-analysis of a migration
//! ensemble's parameters from field observations.

use serde::{Deserialize, Serialize};
use serde_json::{Value, json};
use utoipa::ToSchema;

use super::common::Bound::{Closed, Open};
use super::common::{Checker, Meta, NumberField, PlanStep, RockDto, Warning, non_null};
use super::migration::{
    FACE_CRITICAL_DAMPING, FACE_FRICTION, FACE_RESTITUTION_NORMAL, FACE_RESTITUTION_TANGENTIAL,
    FloorDto, MethodDto, MigrationRequest, MonteCarloDto, ReleaseDto,
};
use super::study::OrderedMap;
use crate::calc::Report;
use crate::calc::calibrate::{
    Bounds, CalibrationCase, CalibrationError, CalibrationResult, CollectorObservation,
    EvaluationStage, Objective, Observed, Parameter, Search,
};
use crate::config::Config;
use crate::http::dto::param::request_pointer;
use crate::http::error::{ApiError, num};

/// Most observed runs (and releases) of a calibration, and most values of a collector's array.
pub const MAX_OBSERVATIONS: usize = 10_000;

/// Most observed collectors of a calibration.
pub const MAX_COLLECTORS: usize = 16;

/// Largest |value| of an observed runout or stopping coordinate, m (the longest face's length).
pub const MAX_OBSERVED_M: f64 = 10_000.0;

/// Largest observed speed (m/s) or passing height (m) at a collector.
pub const MAX_COLLECTOR_VALUE: f64 = 1000.0;

/// Grid points per parameter and round: [4, 21] (3 would not shrink the box: 2/(3 − 1) = 1).
pub const POINTS: (u64, u64) = (4, 21);

/// Refinement rounds: [0, 10].
pub const REFINEMENTS: (u64, u64) = (0, 10);

/// A parameter the calibration can move.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, ToSchema)]
#[serde(rename_all = "snake_case")]
pub enum CalibrationParameterName {
    /// Normal restitution e_n (lumped mass), in [0, 1]: the centre of
    /// `monte_carlo.restitution_normal` (its width kept) and `face.restitution_normal`.
    RestitutionNormal,
    /// Tangential restitution e_t (lumped mass), in [0, 1]: as e_n.
    RestitutionTangential,
    /// Coulomb friction μ of the lumped mass, in [0, 2]: the centre of
    /// `monte_carlo.friction_coefficient` when μ is drawn (its width kept), and
    /// `face.friction_coefficient`.
    FrictionCoefficient,
    /// Critical damping ratio β of the contact dashpot (rigid block), in [0, 1): the centre of
    /// `monte_carlo.critical_damping_ratio` when drawn, and `face.critical_damping_ratio`.
    CriticalDampingRatio,
    /// Coulomb friction μ of the rigid block, in [0, 2]: as `friction_coefficient`.
    RigidBlockFrictionCoefficient,
}

impl CalibrationParameterName {
    fn parameter(self) -> Parameter {
        match self {
            Self::RestitutionNormal => Parameter::RestitutionNormal,
            Self::RestitutionTangential => Parameter::RestitutionTangential,
            Self::FrictionCoefficient => Parameter::FrictionCoefficient,
            Self::CriticalDampingRatio => Parameter::CriticalDampingRatio,
            Self::RigidBlockFrictionCoefficient => Parameter::RigidBlockFrictionCoefficient,
        }
    }

    /// The field whose range bounds the parameter's box (the migration request's own).
    fn field(self) -> NumberField {
        match self {
            Self::RestitutionNormal => FACE_RESTITUTION_NORMAL,
            Self::RestitutionTangential => FACE_RESTITUTION_TANGENTIAL,
            Self::FrictionCoefficient | Self::RigidBlockFrictionCoefficient => FACE_FRICTION,
            Self::CriticalDampingRatio => FACE_CRITICAL_DAMPING,
        }
    }
}

/// One calibrated parameter and its box.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct CalibrationParameterDto {
    /// The parameter; it must apply to the base's method (lumped mass: restitution_normal,
    /// restitution_tangential, friction_coefficient; rigid block: critical_damping_ratio,
    /// rigid_block_friction_coefficient).
    #[schema(example = "friction_coefficient")]
    pub name: CalibrationParameterName,
    /// Lower end of the box, inside the parameter's own range (restitution [0, 1], friction
    /// [0, 2], damping ratio [0, 1)).
    #[schema(example = 0.3)]
    pub min: f64,
    /// Upper end of the box, above `min` and inside the parameter's own range.
    #[schema(example = 0.8)]
    pub max: f64,
}

/// The release (and rock) of one observed run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema, Default)]
#[serde(deny_unknown_fields, default)]
pub struct CalibrationReleaseDto {
    /// The release, as in `/v1/migration` (omitted fields: their defaults, not the base's).
    pub release: ReleaseDto,
    /// The rock of this run (null: the base's rock).
    #[schema(default = json!(null))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rock: Option<RockDto>,
}

/// What a collector line across the whole face saw.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct CollectorObservationDto {
    /// Along-dip position of the line in the face's mean plane, m, in (0, face.length_m).
    #[schema(example = 60.0)]
    pub along_dip_m: f64,
    /// Speeds of the rocks that passed the line, m/s, each in [0, 1000]; at most 10 000
    /// (default empty: not observed).
    #[serde(default)]
    #[schema(example = json!([8.1, 9.4, 7.7]))]
    pub speed_m_s: Vec<f64>,
    /// Heights of the rocks' lowest points above the floor where they passed the line, m, each
    /// in [0, 1000]; at most 10 000 (default empty: not observed).
    #[serde(default)]
    #[schema(example = json!([0.0, 0.4, 1.2]))]
    pub passing_height_m: Vec<f64>,
}

/// The field observations: exactly one of `runout_m`, `stop_points_m`, `horizontal_runout_m`
/// (1 to 10 000 observed runs), and optionally collectors.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema, Default)]
#[serde(deny_unknown_fields, default)]
pub struct ObservedDto {
    /// Runouts: the stop's along-dip position minus the release's, in the face's mean plane, m,
    /// each in [−10 000, 10 000].
    #[serde(skip_serializing_if = "Option::is_none", deserialize_with = "non_null")]
    #[schema(example = json!([42.0, 55.5, 61.2]))]
    pub runout_m: Option<Vec<f64>>,
    /// Stopping points [along_dip_m, across_m] in the face's frame, m, each coordinate in
    /// [−10 000, 10 000].
    #[serde(skip_serializing_if = "Option::is_none", deserialize_with = "non_null")]
    #[schema(example = json!([[42.0, 0.3], [55.5, -1.1]]))]
    pub stop_points_m: Option<Vec<[f64; 2]>>,
    /// Horizontal distances from the release point to the stop point, m, each in [0, 10 000].
    /// Computed on the face's mean plane: √((runout · cos θ)² + (Δ across)²).
    #[serde(skip_serializing_if = "Option::is_none", deserialize_with = "non_null")]
    #[schema(example = json!([30.0, 39.1]))]
    pub horizontal_runout_m: Option<Vec<f64>>,
    /// Collectors (lines across the whole face) and what passed them, at most 16 (null: none).
    #[schema(default = json!(null), example = json!([{"along_dip_m": 60.0, "speed_m_s": [8.1, 9.4], "passing_height_m": [0.0, 0.4]}]))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub collectors: Option<Vec<CollectorObservationDto>>,
}

/// The objective minimised.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, ToSchema, Default)]
#[serde(rename_all = "snake_case")]
pub enum ObjectiveDto {
    /// Two-sample Kolmogorov–Smirnov distance sup |F_obs − F_sim| (stop points: the mean of
    /// the along-dip and across distances).
    #[default]
    Ks,
    /// Mean |Q_sim(p) − Q_obs(p)| over p = 0.05, 0.10, …, 0.95 (type 7), over the observed
    /// spread Q_obs(0.95) − Q_obs(0.05).
    QuantileLoss,
}

/// The grid search.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields, default)]
pub struct SearchDto {
    /// Grid points per parameter and round, in [4, 21]: a grid of points^d over the box.
    #[schema(default = 5, minimum = 4, maximum = 21, example = 5)]
    pub points: u32,
    /// Rounds after the first, in [0, 10]: each a grid of points^d over the box shrunk by
    /// 2/(points − 1) around the best so far (± one step of the previous grid).
    #[schema(default = 3, minimum = 0, maximum = 10, example = 3)]
    pub refinements: u32,
}

impl Default for SearchDto {
    fn default() -> Self {
        Self {
            points: 5,
            refinements: 3,
        }
    }
}

/// Back-analysis: the migration parameters whose seeded ensemble reproduces field observations.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct CalibrateRequest {
    /// The base migration request: face, rock, method, release and `monte_carlo` {runs, seed,
    /// distributions} (null: the default ensemble, 200 runs, seed 42). `monte_carlo.target` and
    /// `output.maps` are refused; the rest of `output` is not used.
    #[serde(default)]
    pub base: MigrationRequest,
    /// One release (and rock) per observed run, as many as the observed runs (null: the base's
    /// release and rock for every run). Each release runs `monte_carlo.runs` runs, run i of
    /// release k drawing from the stream of run k·runs + i of the seed; the runs are pooled.
    #[schema(default = json!(null), example = json!([{"release": {"along_dip_m": 0.0, "across_m": 0.5}}, {"release": {"along_dip_m": 2.0, "across_m": -1.0}}]))]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub releases: Option<Vec<CalibrationReleaseDto>>,
    /// The field observations.
    pub observed: ObservedDto,
    /// The calibrated parameters, 1 to 3, distinct.
    #[schema(example = json!([{"name": "friction_coefficient", "min": 0.3, "max": 0.8}]))]
    pub parameters: Vec<CalibrationParameterDto>,
    /// The objective.
    #[serde(default)]
    #[schema(default = "ks", example = "ks")]
    pub objective: ObjectiveDto,
    /// The grid search.
    #[serde(default)]
    pub search: SearchDto,
}

/// Renames a base request's field pointer for release item `k`: its release and (when the item
/// carries one) its rock are the item's, the rest the base's.
fn release_item_pointer(field: &str, k: usize, own_rock: bool) -> String {
    if field.starts_with("/release") || (own_rock && field.starts_with("/rock")) {
        format!("/releases/{k}{field}")
    } else {
        format!("/base{field}")
    }
}

impl CalibrateRequest {
    /// Range checks, defaults and conversion; `self` becomes the resolved request (`inputs`).
    ///
    /// # Errors
    /// 422 naming the base's field, the observation, the parameter or the search at fault.
    pub fn resolve(&mut self, config: &Config) -> Result<CalibrationCase, ApiError> {
        if self.base.monte_carlo.is_none() {
            self.base.monte_carlo = Some(MonteCarloDto::default());
        }
        let base = self.base.resolve(config).map_err(|e| e.nest("/base"))?;
        let mut ck = Checker::new();
        if let Some(t) = self
            .base
            .monte_carlo
            .as_ref()
            .and_then(|m| m.target.as_ref())
        {
            ck.push(
                "/base/monte_carlo/target",
                serde_json::to_value(t).unwrap_or(Value::Null),
                "a calibration runs monte_carlo.runs runs at every point: no target",
            );
        }
        if let Some(m) = &self.base.output.maps {
            ck.push(
                "/base/output/maps",
                serde_json::to_value(m).unwrap_or(Value::Null),
                "a calibration makes no maps",
            );
        }
        let observed = self.check_observed(&mut ck);
        let collectors = self.check_collectors(&mut ck);
        let parameters = self.check_parameters(&mut ck);
        ck.count(
            "/search/points",
            u64::from(self.search.points),
            POINTS.0,
            POINTS.1,
            "points",
        );
        ck.count(
            "/search/refinements",
            u64::from(self.search.refinements),
            REFINEMENTS.0,
            REFINEMENTS.1,
            "rounds",
        );
        let releases = self.resolve_releases(config, observed.as_ref(), &mut ck)?;
        ck.finish()?;
        let case = CalibrationCase {
            base,
            releases,
            observed: observed.ok_or_else(|| ApiError::internal("observed not resolved"))?,
            collectors,
            parameters,
            objective: match self.objective {
                ObjectiveDto::Ks => Objective::Ks,
                ObjectiveDto::QuantileLoss => Objective::QuantileLoss,
            },
            search: Search {
                points: self.search.points,
                refinements: self.search.refinements,
            },
        };
        check_work(&case, config)?;
        Ok(case)
    }

    /// Exactly one observed quantity, 1 to [`MAX_OBSERVATIONS`] values, each in its range.
    fn check_observed(&self, ck: &mut Checker) -> Option<Observed> {
        let o = &self.observed;
        let sent = [
            o.runout_m.is_some(),
            o.stop_points_m.is_some(),
            o.horizontal_runout_m.is_some(),
        ]
        .iter()
        .filter(|&&s| s)
        .count();
        if sent != 1 {
            ck.push(
                "/observed",
                json!(sent),
                format!(
                    "give exactly one of runout_m, stop_points_m, horizontal_runout_m \
                     ({sent} given)"
                ),
            );
            return None;
        }
        let count = |ck: &mut Checker, field: &str, n: usize| {
            ck.count(
                field,
                n as u64,
                1,
                MAX_OBSERVATIONS as u64,
                "observed runs (the length of the array)",
            )
        };
        // the first value out of range is named (not every one of 10 000)
        let values = |ck: &mut Checker, field: &str, v: &[f64], lo: f64| {
            if let Some(i) = v.iter().position(|x| !(lo..=MAX_OBSERVED_M).contains(x)) {
                ck.closed(&format!("{field}/{i}"), v[i], lo, MAX_OBSERVED_M, "m");
            }
        };
        if let Some(v) = &o.runout_m {
            let f = "/observed/runout_m";
            count(ck, f, v.len());
            values(ck, f, v, -MAX_OBSERVED_M);
            return Some(Observed::Runout(v.clone()));
        }
        if let Some(v) = &o.horizontal_runout_m {
            let f = "/observed/horizontal_runout_m";
            count(ck, f, v.len());
            values(ck, f, v, 0.0);
            return Some(Observed::HorizontalRunout(v.clone()));
        }
        let p = o.stop_points_m.clone().unwrap_or_default();
        let f = "/observed/stop_points_m";
        count(ck, f, p.len());
        if let Some(i) = p.iter().position(|q| {
            q.iter()
                .any(|x| !(-MAX_OBSERVED_M..=MAX_OBSERVED_M).contains(x))
        }) {
            for (j, &x) in p[i].iter().enumerate() {
                ck.closed(
                    &format!("{f}/{i}/{j}"),
                    x,
                    -MAX_OBSERVED_M,
                    MAX_OBSERVED_M,
                    "m",
                );
            }
        }
        Some(Observed::StopPoints(p))
    }

    /// The observed collectors: at most [`MAX_COLLECTORS`], each on the face with at least one
    /// observed array of at most [`MAX_OBSERVATIONS`] values in range.
    fn check_collectors(&self, ck: &mut Checker) -> Vec<CollectorObservation> {
        let Some(cs) = &self.observed.collectors else {
            return Vec::new();
        };
        ck.count(
            "/observed/collectors",
            cs.len() as u64,
            0,
            MAX_COLLECTORS as u64,
            "collectors",
        );
        let length = self.base.face.length_m;
        let mut out = Vec::with_capacity(cs.len());
        for (i, c) in cs.iter().enumerate() {
            let at = format!("/observed/collectors/{i}");
            ck.range(
                &format!("{at}/along_dip_m"),
                c.along_dip_m,
                Open(0.0),
                Open(length),
                "m (within the face: below face.length_m)",
            );
            if c.speed_m_s.is_empty() && c.passing_height_m.is_empty() {
                ck.push(
                    at.clone(),
                    Value::Null,
                    "a collector needs speed_m_s or passing_height_m (or both)",
                );
            }
            for (name, v, unit) in [
                ("speed_m_s", &c.speed_m_s, "m/s"),
                ("passing_height_m", &c.passing_height_m, "m"),
            ] {
                let field = format!("{at}/{name}");
                ck.count(&field, v.len() as u64, 0, MAX_OBSERVATIONS as u64, "values");
                if let Some(j) = v
                    .iter()
                    .position(|x| !(0.0..=MAX_COLLECTOR_VALUE).contains(x))
                {
                    ck.range(
                        &format!("{field}/{j}"),
                        v[j],
                        Closed(0.0),
                        Closed(MAX_COLLECTOR_VALUE),
                        unit,
                    );
                }
            }
            out.push(CollectorObservation {
                along_dip: c.along_dip_m,
                speed: c.speed_m_s.clone(),
                passing_height: c.passing_height_m.clone(),
            });
        }
        out
    }

    /// 1 to 3 distinct parameters of the base's method, each box inside its field's range.
    fn check_parameters(&self, ck: &mut Checker) -> Vec<Bounds> {
        let ps = &self.parameters;
        ck.count("/parameters", ps.len() as u64, 1, 3, "parameters");
        let method = match self.base.method {
            MethodDto::LumpedMass => crate::physics::migration::Method::LumpedMass,
            MethodDto::RigidBlock => crate::physics::migration::Method::RigidBlock,
        };
        let mut out = Vec::with_capacity(ps.len());
        for (i, p) in ps.iter().enumerate() {
            let at = format!("/parameters/{i}");
            let parameter = p.name.parameter();
            if ps[..i].iter().any(|q| q.name == p.name) {
                ck.push(
                    format!("{at}/name"),
                    json!(p.name),
                    "each parameter may be calibrated once",
                );
            }
            if parameter.method() != method {
                let (own, names) = match method {
                    crate::physics::migration::Method::LumpedMass => (
                        "the lumped mass",
                        "restitution_normal, restitution_tangential, friction_coefficient",
                    ),
                    crate::physics::migration::Method::RigidBlock => (
                        "the rigid block",
                        "critical_damping_ratio, rigid_block_friction_coefficient",
                    ),
                };
                ck.push(
                    format!("{at}/name"),
                    json!(p.name),
                    format!("does not apply to {own} (base.method); its parameters are {names}"),
                );
            }
            let field = p.name.field();
            let ok_min = field.check(ck, &format!("{at}/min"), p.min);
            let ok_max = field.check(ck, &format!("{at}/max"), p.max);
            if ok_min && ok_max && p.min >= p.max {
                ck.push(
                    format!("{at}/max"),
                    num(p.max),
                    format!("must be above min = {}", p.min),
                );
            }
            out.push(Bounds {
                parameter,
                min: p.min,
                max: p.max,
            });
        }
        out
    }

    /// Each release item checked as the base's release (and rock) would be, one per observed
    /// run; the items become their resolved selves.
    fn resolve_releases(
        &mut self,
        config: &Config,
        observed: Option<&Observed>,
        ck: &mut Checker,
    ) -> Result<
        Vec<(
            crate::physics::migration::Release,
            crate::physics::material::Rock,
        )>,
        ApiError,
    > {
        let Some(items) = self.releases.as_mut() else {
            return Ok(Vec::new());
        };
        if let Some(o) = observed
            && items.len() != o.len()
        {
            ck.push(
                "/releases",
                json!(items.len()),
                format!(
                    "one release per observed run: {} observed, {} releases",
                    o.len(),
                    items.len()
                ),
            );
            return Ok(Vec::new());
        }
        // the base without its floor (the releases' checks do not need it; it is built once)
        let mut light = self.base.clone();
        light.face.floor = FloorDto::default();
        let mut out = Vec::with_capacity(items.len());
        for (k, item) in items.iter_mut().enumerate() {
            let mut r = light.clone();
            r.release = std::mem::take(&mut item.release);
            let own_rock = item.rock.is_some();
            if let Some(rock) = &item.rock {
                r.rock = rock.clone();
            }
            let case = r
                .resolve(config)
                .map_err(|e| e.rename_fields(|f| release_item_pointer(f, k, own_rock)))?;
            item.release = r.release;
            if own_rock {
                item.rock = Some(r.rock);
            }
            out.push((case.release, case.rock));
        }
        Ok(out)
    }
}

/// Refuses a search whose runs pass the server's `max_runs`: the runs of one evaluation (runs ×
/// releases) naming `/base/monte_carlo/runs`, else all evaluations naming `/search/points`.
fn check_work(case: &CalibrationCase, config: &Config) -> Result<(), ApiError> {
    let per = case.runs_per_evaluation();
    let runs = case.base.monte_carlo.map_or(0, |m| m.runs);
    let limit = config.max_runs;
    if per > limit {
        return Err(ApiError::invalid(
            "/base/monte_carlo/runs",
            json!(runs),
            format!(
                "{runs} runs × {} releases = {per} runs per evaluation, more than this server's \
                 limit of {limit} runs (max_monte_carlo_runs): ask for fewer runs",
                case.releases.len().max(1)
            ),
        ));
    }
    let evaluations = case.max_evaluations();
    let total = evaluations.saturating_mul(per);
    if total > limit {
        return Err(ApiError::invalid(
            "/search/points",
            json!(case.search.points),
            format!(
                "the search would make up to {evaluations} evaluations (1 + {}^{} × {} rounds \
                 + 2 × {} for the sensitivity) of {per} runs = {total} runs, more than this \
                 server's limit of {limit} runs (max_monte_carlo_runs): ask for fewer points, \
                 refinements, parameters, runs or releases",
                case.search.points,
                case.parameters.len(),
                1 + case.search.refinements,
                case.parameters.len()
            ),
        )
        .with_extension("estimated_runs", json!(total))
        .with_extension("limit", json!(limit)));
    }
    Ok(())
}

/// The problem of a failed calibration: a physics error names the base's field, or the release
/// item's when the runs of one release raised it.
#[must_use]
pub fn calibration_error(e: CalibrationError, own_rock: &[bool]) -> ApiError {
    let k = e.release;
    ApiError::from_physics(e.error, |p| {
        let f = request_pointer(p);
        match k {
            Some(k) => release_item_pointer(&f, k, own_rock.get(k).copied().unwrap_or(false)),
            None => format!("/base{f}"),
        }
    })
}

/// Why a point was evaluated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, ToSchema)]
#[serde(rename_all = "snake_case")]
pub enum EvaluationStageDto {
    /// The base's own values.
    Base,
    /// A point of a grid (`round` 0: the whole box; then the refinements).
    Grid,
    /// A neighbour of the best, one final grid step away (the sensitivity).
    Sensitivity,
}

/// One point tried.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct EvaluationDto {
    /// Why it was tried.
    pub stage: EvaluationStageDto,
    /// The grid's round (0: the first grid over the whole box; null: not a grid point).
    pub round: Option<u32>,
    /// The parameters' values, by name.
    #[schema(value_type = HashMap<String, f64>)]
    pub values: OrderedMap<f64>,
    /// The objective there.
    pub objective: f64,
}

/// A neighbour of the best along one parameter.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, ToSchema)]
pub struct NeighbourDto {
    /// The parameter's value.
    pub value: f64,
    /// The objective there.
    pub objective: f64,
}

/// The objective around the best along one parameter.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, ToSchema)]
pub struct SensitivityDto {
    /// The best value.
    pub best: f64,
    /// The final grid step.
    pub step: f64,
    /// The objective at best − step (null: below the box).
    pub low: Option<NeighbourDto>,
    /// The objective at best + step (null: above the box).
    pub high: Option<NeighbourDto>,
    /// Finite-difference slope of the objective per unit of the parameter: central between
    /// low and high, one-sided with the best where one is outside the box (null: neither).
    pub slope: Option<f64>,
}

/// The objective at the best and at the base's values.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, ToSchema)]
pub struct ObjectiveValuesDto {
    /// The objective used.
    pub kind: ObjectiveDto,
    /// At the best values.
    pub best: f64,
    /// At the base's own values.
    pub base: f64,
}

/// An observed quantity beside its computed distributions at the best and at the base.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct FigureDto {
    /// The quantity (`runout_m`, `horizontal_runout_m`, `stop_along_dip_m`, `stop_across_m`,
    /// `collectors/{i}/speed_m_s`, `collectors/{i}/passing_height_m`), in its unit.
    pub quantity: String,
    /// The probabilities of the quantiles: 0.01, 0.02, …, 0.99.
    pub probabilities: Vec<f64>,
    /// Observed quantiles (type 7).
    pub observed_quantiles: Vec<f64>,
    /// Computed quantiles at the best.
    pub best_quantiles: Vec<f64>,
    /// Computed quantiles at the base's values.
    pub base_quantiles: Vec<f64>,
    /// Observed ECDF points [x, F(x)], every observed value.
    pub observed_ecdf: Vec<[f64; 2]>,
    /// Computed ECDF points [x, F(x)] at the best, at most 200 (equally spaced ranks).
    pub best_ecdf: Vec<[f64; 2]>,
    /// Computed ECDF points [x, F(x)] at the base's values, at most 200.
    pub base_ecdf: Vec<[f64; 2]>,
    /// This quantity's term of the objective at the best.
    pub best_term: f64,
    /// This quantity's term of the objective at the base's values.
    pub base_term: f64,
}

/// What a calibration found.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct CalibrateResponse {
    /// The best values, by parameter name.
    #[schema(value_type = HashMap<String, f64>)]
    pub best: OrderedMap<f64>,
    /// The base's own values (the centres of its distributions, or its fixed values).
    #[schema(value_type = HashMap<String, f64>)]
    pub base_values: OrderedMap<f64>,
    /// The objective at the best and at the base's values.
    pub objective: ObjectiveValuesDto,
    /// Every point tried, in order (a point met again is not run again).
    pub evaluations: Vec<EvaluationDto>,
    /// Per parameter, the objective one final grid step either side of the best.
    #[schema(value_type = HashMap<String, SensitivityDto>)]
    pub sensitivity: OrderedMap<SensitivityDto>,
    /// The observed and computed distributions (what the page plots).
    pub figure: Vec<FigureDto>,
    /// Runs of one evaluation: monte_carlo.runs × releases.
    pub runs_per_evaluation: u64,
    /// Named warnings: `best_on_bound`, `parameter_insensitive`, `fit_rejected`,
    /// `collector_not_reached`, `observed_without_spread`.
    pub warnings: Vec<Warning>,
    /// Stages run or skipped.
    pub plan: Vec<PlanStep>,
    /// The fully resolved request.
    pub inputs: CalibrateRequest,
    /// Version of the service and its models.
    pub model_version: String,
}

impl CalibrateResponse {
    /// Builds the response from the calculation's report and the resolved request.
    #[must_use]
    pub fn new(report: Report<CalibrationResult>, inputs: CalibrateRequest) -> Self {
        let Report {
            result: r,
            plan,
            warnings,
        } = report;
        let meta = Meta::of(&plan, &warnings);
        let names: Vec<String> = inputs
            .parameters
            .iter()
            .map(|p| p.name.parameter().name().to_string())
            .collect();
        let named = |v: &[f64]| OrderedMap(names.iter().cloned().zip(v.iter().copied()).collect());
        Self {
            best: named(&r.best),
            base_values: named(&r.base),
            objective: ObjectiveValuesDto {
                kind: inputs.objective,
                best: r.best_objective,
                base: r.base_objective,
            },
            evaluations: r
                .evaluations
                .iter()
                .map(|e| EvaluationDto {
                    stage: match e.stage {
                        EvaluationStage::Base => EvaluationStageDto::Base,
                        EvaluationStage::Grid(_) => EvaluationStageDto::Grid,
                        EvaluationStage::Sensitivity => EvaluationStageDto::Sensitivity,
                    },
                    round: match e.stage {
                        EvaluationStage::Grid(k) => Some(k),
                        _ => None,
                    },
                    values: named(&e.values),
                    objective: e.objective,
                })
                .collect(),
            sensitivity: OrderedMap(
                names
                    .iter()
                    .zip(r.sensitivity.iter().zip(&r.best))
                    .map(|(n, (s, &best))| {
                        let nb = |x: Option<crate::calc::calibrate::Neighbour>| {
                            x.map(|x| NeighbourDto {
                                value: x.value,
                                objective: x.objective,
                            })
                        };
                        (
                            n.clone(),
                            SensitivityDto {
                                best,
                                step: s.step,
                                low: nb(s.low),
                                high: nb(s.high),
                                slope: s.slope,
                            },
                        )
                    })
                    .collect(),
            ),
            figure: r
                .figure
                .into_iter()
                .map(|f| FigureDto {
                    quantity: f.quantity,
                    probabilities: f.probabilities,
                    observed_quantiles: f.observed_quantiles,
                    best_quantiles: f.best_quantiles,
                    base_quantiles: f.base_quantiles,
                    observed_ecdf: f.observed_ecdf,
                    best_ecdf: f.best_ecdf,
                    base_ecdf: f.base_ecdf,
                    best_term: f.best_term,
                    base_term: f.base_term,
                })
                .collect(),
            runs_per_evaluation: r.runs_per_evaluation,
            warnings: meta.warnings,
            plan: meta.plan,
            inputs,
            model_version: meta.model_version,
        }
    }

    /// Whether each release item carries its own rock (for naming a release's fields).
    #[must_use]
    pub fn own_rocks(req: &CalibrateRequest) -> Vec<bool> {
        req.releases
            .as_ref()
            .map(|r| r.iter().map(|i| i.rock.is_some()).collect())
            .unwrap_or_default()
    }
}
