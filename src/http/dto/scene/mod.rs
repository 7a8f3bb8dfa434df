//! `POST /v1/scene`: request, response, validation. The request and its checks are here; the
//! answer in `response.rs`, the stored part 0 and the runs CSV in `head.rs`.

mod head;
mod response;

pub use head::{SceneHead, runs_csv};
pub use response::*;

use serde::{Deserialize, Serialize};
use serde_json::{Value, json};
use utoipa::ToSchema;

use super::column::{ColumnModelDto, ColumnOutputDto, ColumnRequest, ColumnResponse, GalerkinDto};
use super::common::{
    Checker, ColumnDto, ContactDto, LawDto, Meta, PlanStep, RockDto, ShapeKind, plan_of,
    warnings_of,
};
use super::devices::{BarrierDto, CollectorDto, resolve_devices};
use super::impact::{ImpactRequest, ImpactResponse};
use super::migration::monte_carlo_dto;
use super::migration::{
    DistributionDto, FaceDto, LumpedMassDto, MethodDto, MigrationOutputDto, MigrationRequest,
    MigrationResponse, MonteCarloDto, ReleaseDto, RigidBlockDto, SummaryDto,
};
use super::param::{Layout, scene_pointer};
use super::protection::{
    AllowedImpactsDto, FrequencyDto, GuardDto, GuardStatisticsDto, ReleaseRateDto, StoredLimit,
    allowed_dto, limit_name, resolve_guards, restore, store,
};
use crate::calc::{self, Report};
use crate::config::Config;
use crate::http::error::{ApiError, FieldError, num};
use crate::http::runner::to_json_bytes;
use crate::physics::migration::Method;
use crate::physics::scene::{
    self, Check, DesignLimits, Limit, MethodSummary, Outcomes, Probability, ReleaseZone, SceneCase,
    SceneDraws, SceneError, SceneReport, SceneRun, SceneStatistics, Strike, SupportEntry,
    TABLE1_SHARES,
};
use crate::physics::stats::rate::ReleaseRate;

/// A support along the face: spanning (`across_m` null) or one column at (`along_dip_m`,
/// `across_m`) in the mean plane.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema, Default)]
#[serde(deny_unknown_fields, default)]
pub struct SupportDto {
    /// Along-dip position in the mean plane, m, in [0, face.length_m] (default: the lower end).
    /// The rock reaches a spanning support when its along-dip position passes the support's,
    /// a column when its distance in the mean plane from the axis falls to the reach; during
    /// the drop its along-dip position runs from release.along_dip_m − drop_height_m·sin θ to
    /// release.along_dip_m, so either kind standing there is reached in the fall.
    #[schema(minimum = 0.0, maximum = 10000.0, example = 60.0)]
    #[serde(deserialize_with = "super::common::non_null")]
    pub along_dip_m: Option<f64>,
    /// Across position y of the column axis, m, in [−1000, 1000] (null: the support spans the
    /// face).
    #[schema(default = json!(null), minimum = -1000.0, maximum = 1000.0, example = json!(null))]
    pub across_m: Option<f64>,
    /// The support's column (struck at its midpoint).
    pub column: ColumnDto,
}

/// Supports in rows, numbered from the lower end as the paper's Table 1 (#1–#62).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields, default)]
pub struct SupportRowsDto {
    /// Along-dip position of support #1 (the lowest), m.
    #[schema(default = 118.5, minimum = 0.0, maximum = 10000.0, example = 118.5)]
    pub lowest_along_dip_m: f64,
    /// Spacing between supports along the dip, m, in (0, 10000]; support k stands at
    /// lowest_along_dip_m − (k − 1)·spacing_m.
    #[schema(
        default = 1.5,
        exclusive_minimum = 0.0,
        maximum = 10000.0,
        example = 1.5
    )]
    pub spacing_m: f64,
    /// Number of supports, in [1, 10000].
    #[schema(default = 62, minimum = 1, maximum = 10000, example = 62)]
    pub count: u32,
    /// Across positions of each support's columns, m, each in [−1000, 1000] (1 to 16 of them).
    #[schema(default = json!([0.9]), example = json!([0.9]))]
    pub across_m: Vec<f64>,
    /// The columns of every support.
    pub column: ColumnDto,
}

impl Default for SupportRowsDto {
    fn default() -> Self {
        Self {
            lowest_along_dip_m: 118.5,
            spacing_m: 1.5,
            count: 62,
            across_m: vec![0.9],
            column: ColumnDto::default(),
        }
    }
}

/// Named release zones.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, ToSchema)]
#[serde(rename_all = "snake_case")]
pub enum ReleaseZonesName {
    /// The paper's Table 1 spalling shares: upper third 23.3 %, middle 58.3 %, lower 18.4 %.
    Table1,
}

/// A zone of release points along the dip (uniform inside, chosen with probability ∝ weight).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct ReleaseZoneDto {
    /// Upper edge, m, in [0, face.length_m).
    #[schema(example = 0.0)]
    pub from_along_dip_m: f64,
    /// Lower edge, m, in [from_along_dip_m, face.length_m).
    #[schema(example = 40.0)]
    pub to_along_dip_m: f64,
    /// Relative weight, in [0, 1e9] (at least one > 0).
    #[schema(example = 23.3)]
    pub weight: f64,
}

/// Release zones: `"table1"` or a list of zones.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(untagged)]
pub enum ReleaseZonesDto {
    /// A named set of zones.
    Named(ReleaseZonesName),
    /// Given zones.
    Zones(Vec<ReleaseZoneDto>),
}

/// The design limits; each that is not null is checked for every impact.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields, default)]
pub struct DesignLimitsDto {
    /// Largest bending-stress utilisation σ/σ_y, in (0, 100] (null: not checked).
    #[schema(default = 1.0, exclusive_minimum = 0.0, maximum = 100.0, example = 1.0)]
    pub stress_utilisation: Option<f64>,
    /// Rated force: largest contact force, N, in (0, 1e12] (null: not checked).
    #[schema(default = json!(null), exclusive_minimum = 0.0, maximum = 1e12, example = 2e6)]
    pub max_force_n: Option<f64>,
    /// Design energy: largest absorbed energy, J, in (0, 1e12] (null: not checked).
    #[schema(default = json!(null), exclusive_minimum = 0.0, maximum = 1e12, example = 500.0)]
    pub absorbed_energy_j: Option<f64>,
    /// Probability of exceedance a support may have, in [0, 1] (ensemble verdict).
    #[schema(default = 0.0, minimum = 0.0, maximum = 1.0, example = 0.01)]
    pub acceptable_probability: f64,
}

impl Default for DesignLimitsDto {
    fn default() -> Self {
        Self {
            stress_utilisation: Some(1.0),
            max_force_n: None,
            absorbed_energy_j: None,
            acceptable_probability: 0.0,
        }
    }
}

monte_carlo_dto! {
    /// A scene's seeded Monte Carlo ensemble: `/v1/migration`'s draws plus the scene's own.
    pub struct SceneMonteCarloDto {
        /// The rock's side length, m, bounds in [0.01, 5] (scene stream; the paper's study range
        /// is 0.2–0.3 m). A sphere's radius and a cuboid's edges scale with it.
        pub side_length_m: Option<DistributionDto>,
        /// The rock's density, kg/m³, bounds in [100, 20000] (scene stream; the paper's 2000–3000).
        pub density_kg_m3: Option<DistributionDto>,
        /// The release across the face y, m, bounds in [−1000, 1000] (scene stream).
        pub release_across_m: Option<DistributionDto>,
        /// Stop when a statistic is precise enough: checked at 1000, 2000, 4000, … runs and
        /// at `runs`, which is then the most runs allowed (null: run every run).
        pub target: Option<super::target::SceneTargetDto>,
    }
}

/// The whole chain along the face: release → migration → impact on the first support reached →
/// column energy → design checks.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields, default)]
pub struct SceneRequest {
    /// Migration method.
    #[schema(default = "lumped_mass", example = "lumped_mass")]
    pub method: MethodDto,
    /// Gravity g, m/s², in [0.1, 100].
    #[schema(schema_with = super::migration::gravity_schema)]
    pub gravity_m_s2: f64,
    /// The working face.
    pub face: FaceDto,
    /// The rock block.
    pub rock: RockDto,
    /// The release.
    pub release: ReleaseDto,
    /// Lumped-mass options.
    pub lumped_mass: LumpedMassDto,
    /// Rigid-block options.
    pub rigid_block: RigidBlockDto,
    /// Stop at this time, s, in (0, 1e5] (null: no time limit).
    #[schema(schema_with = super::migration::scene_end_time_schema)]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub end_time_s: Option<f64>,
    /// Monte Carlo ensemble (null: one deterministic run).
    #[schema(default = json!(null))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub monte_carlo: Option<SceneMonteCarloDto>,
    /// The contact model of the impacts.
    pub contact: ContactDto,
    /// Galerkin modes of the column stage.
    pub galerkin: GalerkinDto,
    /// Column model of the column stage.
    #[schema(default = "decoupled", example = "decoupled")]
    pub column_model: ColumnModelDto,
    /// Supports (default: one spanning support at the lower end). Give this or `support_rows`.
    #[schema(default = json!(null), example = json!([{"along_dip_m": 60.0, "across_m": null}, {"along_dip_m": 100.0, "across_m": 0.9}]))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub supports: Option<Vec<SupportDto>>,
    /// Supports in rows numbered from the lower end (null: use `supports`).
    #[schema(default = json!(null))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub support_rows: Option<SupportRowsDto>,
    /// Strike every support at this speed, m/s, in (0, 1000], instead of migrating (null:
    /// migrate).
    #[schema(default = json!(null), exclusive_minimum = 0.0, maximum = 1000.0, example = 5.0)]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub impact_velocity_m_s: Option<f64>,
    /// Release zones of the ensemble: `"table1"` or zones (null: the release as given).
    #[schema(default = json!(null))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub release_zones: Option<ReleaseZonesDto>,
    /// Design limits.
    pub design_limits: DesignLimitsDto,
    /// Percentile of the design values at each support, in [0.5, 0.999] (ensemble).
    #[schema(schema_with = super::design_values::design_percentile_schema)]
    pub design_percentile: f64,
    /// Run both migration methods and compare them.
    #[schema(default = false, example = false)]
    pub compare_methods: bool,
    /// Rocks released per year, or events counted over a period: each support's expected
    /// overloads per year and return period (needs `monte_carlo`; null: none).
    #[schema(default = json!(null), example = json!({"observed_events": 643, "observed_period_years": 0.75}))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub release_rate: Option<ReleaseRateDto>,
    /// Guards on support columns, each with an energy rating (null: none).
    #[schema(default = json!(null), example = json!([{"support": 1, "energy_rating_j": 500.0}]))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub guards: Option<Vec<GuardDto>>,
    /// Barriers across the face, each with a height and an energy rating (null: none).
    #[schema(default = json!(null), example = json!([{"along_dip_m": 40.0, "height_m": 1.0, "energy_rating_j": 20000.0}]))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub barriers: Option<Vec<BarrierDto>>,
    /// Data collectors: lines across the face where each run's state is recorded (null: none).
    #[schema(default = json!(null), example = json!([{"along_dip_m": 30.0}]))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub collectors: Option<Vec<CollectorDto>>,
    /// Report each support's allowed impact per design limit (`allowed_impacts` of the answer):
    /// the impact speed and energy of the case's rock at which the check reaches its limit.
    #[schema(default = true, example = true)]
    pub allowed_impacts: bool,
    /// Migration outputs (the nominal run's events and trajectory; the per-run CSV).
    pub migration_output: MigrationOutputDto,
    /// Column history of each impact (null: none).
    #[schema(default = json!(null))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub column_output: Option<ColumnOutputDto>,
    /// The design search for guards: the smallest energy rating of a guard on each listed
    /// support's columns that brings its exceedance probability within the acceptable one, over
    /// the ensemble's own runs (needs `monte_carlo`; null: none).
    #[schema(default = json!(null), example = json!({"acceptable_probability": 0.01, "guards": {"supports": [1, 2]}}))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub design: Option<super::design_search::DesignSearchDto>,
}

impl Default for SceneRequest {
    fn default() -> Self {
        Self {
            method: MethodDto::LumpedMass,
            gravity_m_s2: super::migration::GRAVITY.value(),
            face: FaceDto::default(),
            rock: RockDto::default(),
            release: ReleaseDto::default(),
            lumped_mass: LumpedMassDto::default(),
            rigid_block: RigidBlockDto::default(),
            end_time_s: None,
            monte_carlo: None,
            contact: ContactDto::default(),
            galerkin: GalerkinDto::default(),
            column_model: ColumnModelDto::Decoupled,
            supports: None,
            support_rows: None,
            impact_velocity_m_s: None,
            release_zones: None,
            design_limits: DesignLimitsDto::default(),
            design_percentile: super::design_values::DESIGN_PERCENTILE_FIELD.value(),
            compare_methods: false,
            release_rate: None,
            guards: None,
            barriers: None,
            collectors: None,
            allowed_impacts: true,
            migration_output: MigrationOutputDto::default(),
            column_output: None,
            design: None,
        }
    }
}

/// What the DTO keeps to build the response and to name fields.
#[derive(Debug, Clone)]
pub struct SceneContext {
    /// The migration request as resolved (echoed in the migration response).
    pub migration: MigrationRequest,
    /// Per entry: the JSON Pointer of its support object.
    pub entry_pointer: Vec<String>,
    /// Per entry: its column as resolved (for the impact and column echoes).
    pub entry_column: Vec<ColumnDto>,
    /// The rock as it enters the impact (a cube).
    pub impact_rock: RockDto,
    /// The resolved Galerkin options.
    pub galerkin: GalerkinDto,
}

/// A scene's supports as entries, with each entry's support pointer and column as sent.
#[derive(Default)]
struct Supports {
    entries: Vec<SupportEntry>,
    pointers: Vec<String>,
    columns: Vec<ColumnDto>,
}

/// The rows of supports `rows` (face length `length`, m) as entries, row after row.
fn support_rows(rows: &mut SupportRowsDto, length: f64, ck: &mut Checker) -> Supports {
    let mut out = Supports::default();
    ck.closed(
        "/support_rows/lowest_along_dip_m",
        rows.lowest_along_dip_m,
        0.0,
        length,
        "m (within the face)",
    );
    ck.open_closed("/support_rows/spacing_m", rows.spacing_m, 0.0, 1e4, "m");
    ck.count(
        "/support_rows/count",
        u64::from(rows.count),
        1,
        10_000,
        "supports",
    );
    if !(1..=16).contains(&rows.across_m.len()) {
        ck.push(
            "/support_rows/across_m",
            json!(rows.across_m),
            "must hold 1 to 16 across positions",
        );
    }
    for (j, y) in rows.across_m.iter().enumerate() {
        ck.closed(
            &format!("/support_rows/across_m/{j}"),
            *y,
            -1000.0,
            1000.0,
            "m",
        );
    }
    let column = rows.column.resolve("/support_rows/column", ck);
    if ck.is_ok() {
        let top = rows.lowest_along_dip_m - f64::from(rows.count - 1) * rows.spacing_m;
        if top < 0.0 {
            ck.push(
                "/support_rows/count",
                json!(rows.count),
                format!(
                    "support #{} would stand at {top} m, above the face's upper end: \
                     every support must lie in [0, length_m]",
                    rows.count
                ),
            );
        }
    }
    if ck.is_ok() {
        for k in 1..=rows.count {
            let s = rows.lowest_along_dip_m - f64::from(k - 1) * rows.spacing_m;
            for (j, y) in rows.across_m.iter().enumerate() {
                out.entries.push(SupportEntry {
                    support: k,
                    column_index: j as u32,
                    along_dip: s,
                    across: Some(*y),
                    column: column.clone(),
                });
                out.pointers.push("/support_rows".to_string());
                out.columns.push(rows.column.clone());
            }
        }
    }
    out
}

/// The listed supports as entries (a support without a position stands at the lower end,
/// `length`, m).
fn support_list(list: &mut [SupportDto], length: f64, ck: &mut Checker) -> Supports {
    let mut out = Supports::default();
    if list.is_empty() || list.len() > 10_000 {
        ck.push(
            "/supports",
            json!(list.len()),
            "must hold 1 to 10000 supports",
        );
    }
    for (i, s) in list.iter_mut().enumerate() {
        let at = format!("/supports/{i}");
        let a = *s.along_dip_m.get_or_insert(length);
        ck.closed(
            &format!("{at}/along_dip_m"),
            a,
            0.0,
            length,
            "m (within the face, [0, length_m])",
        );
        if let Some(y) = s.across_m {
            ck.closed(&format!("{at}/across_m"), y, -1000.0, 1000.0, "m");
        }
        let column = s.column.resolve(&format!("{at}/column"), ck);
        out.entries.push(SupportEntry {
            support: i as u32 + 1,
            column_index: 0,
            along_dip: a,
            across: s.across_m,
            column,
        });
        out.pointers.push(at);
        out.columns.push(s.column.clone());
    }
    out
}

/// Refuses a column shorter than the contact length `side_max` (m) of the largest rock that
/// can strike it, once per support object.
fn check_contact_lengths(supports: &Supports, side_max: f64, ck: &mut Checker) {
    let pointers = &supports.pointers;
    for (k, e) in supports.entries.iter().enumerate() {
        if e.column.length < side_max && (k == 0 || pointers[k] != pointers[k - 1]) {
            ck.push(
                format!("{}/column/length_m", pointers[k]),
                num(e.column.length),
                format!(
                    "must be at least the contact length L = {side_max} m of the largest rock \
                     that can strike it"
                ),
            );
        }
    }
}

/// Given release zones on a face of `length` (m): each within the face, `to` not below
/// `from`, a weight in [0, 1e9] and one weight at least > 0.
fn release_zone_list(z: &[ReleaseZoneDto], length: f64, ck: &mut Checker) -> Vec<ReleaseZone> {
    if z.is_empty() || z.len() > 1000 {
        ck.push(
            "/release_zones",
            json!(z.len()),
            "must hold 1 to 1000 zones",
        );
    }
    for (i, zone) in z.iter().enumerate() {
        let at = format!("/release_zones/{i}");
        ck.closed_open(
            &format!("{at}/from_along_dip_m"),
            zone.from_along_dip_m,
            0.0,
            length,
            "m (below length_m)",
        );
        if ck.closed(
            &format!("{at}/to_along_dip_m"),
            zone.to_along_dip_m,
            0.0,
            length,
            "m",
        ) && zone.to_along_dip_m < zone.from_along_dip_m
        {
            ck.push(
                format!("{at}/to_along_dip_m"),
                num(zone.to_along_dip_m),
                format!(
                    "must be at least from_along_dip_m = {}",
                    zone.from_along_dip_m
                ),
            );
        }
        ck.closed(&format!("{at}/weight"), zone.weight, 0.0, 1e9, "");
    }
    if !z.is_empty() && z.iter().all(|x| x.weight == 0.0) {
        ck.push(
            "/release_zones/0/weight",
            json!(0.0),
            "at least one weight must be > 0",
        );
    }
    z.iter()
        .map(|x| ReleaseZone {
            from: x.from_along_dip_m,
            to: x.to_along_dip_m,
            weight: x.weight,
        })
        .collect()
}

impl SceneRequest {
    /// Range checks, derived defaults and conversion; `self` becomes the resolved request.
    pub fn resolve(&mut self, config: &Config) -> Result<(SceneCase, SceneContext), ApiError> {
        // the migration part, checked by /v1/migration's own rules and pointers
        let mut mreq = self.migration_request();
        let migration = mreq.resolve_in(config, Layout::Scene)?;
        self.migration_output.maps = mreq.output.maps;
        self.face = mreq.face.clone();
        self.rock = mreq.rock.clone();
        let mut ck = Checker::new();
        let length = self.face.length_m;
        let supports = self.resolve_supports(length, &mut ck);
        // the impact rock: the cube itself, or the cube of equal mass and density
        let hertz = self.contact.law == LawDto::HertzPoint;
        let cube_side = match scene::rock_extent(&migration.rock) {
            Ok((_, m)) => scene::impact_rock(&migration.rock, m).side_length,
            Err(e) => return Err(ApiError::from(e)),
        };
        let impact_rock = RockDto {
            shape: ShapeKind::Cube,
            side_length_m: cube_side,
            radius_m: None,
            dimensions_m: None,
            vertices_m: None,
            random: None,
            corner_radius_m: Some(migration.rock.corner_radius.min(cube_side / 2.0)),
            ..self.rock.clone()
        };
        if hertz && self.rock.shape == ShapeKind::Cube {
            self.rock.clone().resolve("/rock", true, &mut ck);
        }
        self.check_impact_velocity(&mut ck);
        let (column_case, impact_rock) = self.resolve_column_stage(config, impact_rock, &mut ck);
        // contact lengths: each column at least the side of the cube that strikes it
        let side_max = self
            .monte_carlo
            .as_ref()
            .and_then(|m| m.side_length_m)
            .map_or(cube_side, |d| d.max.unwrap_or(cube_side).max(cube_side));
        check_contact_lengths(&supports, side_max, &mut ck);
        let mut release_zones = self.resolve_release_zones(length, &mut ck);
        let draws = self.resolve_draws(&mut ck);
        let mut limits = self.resolve_design_limits(&mut ck);
        super::design_values::check_design_percentile(&mut ck, self.design_percentile);
        limits.design_percentile = self.design_percentile;
        let release_rate = self.resolve_release_rate(&mut ck);
        self.zone_rates(release_zones.as_deref_mut(), &mut ck);
        let guards = resolve_guards(
            self.guards.as_deref().unwrap_or(&[]),
            &supports.entries,
            &mut ck,
        );
        let (barriers, collectors) = resolve_devices(
            self.barriers.as_deref().unwrap_or(&[]),
            self.collectors.as_deref().unwrap_or(&[]),
            length,
            &mut ck,
        );
        let (lines, device_lines) = scene::scene_lines(&barriers, &collectors);
        let mut migration = migration;
        migration.lines = lines;
        let target = self
            .monte_carlo
            .as_ref()
            .and_then(|m| m.target.as_ref())
            .and_then(|t| t.resolve("/monte_carlo/target", &mut ck));
        let design = super::design_search::resolve(self, &supports.entries, &mut ck);
        ck.finish()?;
        let case = SceneCase {
            target,
            device_lines,
            migration,
            supports: supports.entries,
            column: column_case,
            impact_velocity: self.impact_velocity_m_s,
            release_zones,
            draws,
            limits,
            compare_methods: self.compare_methods,
            allowed_impacts: self.allowed_impacts,
            release_rate,
            guards,
            design,
        };
        super::design_search::check_work(&case, config)?;
        let ctx = SceneContext {
            migration: mreq,
            entry_pointer: supports.pointers,
            entry_column: supports.columns,
            impact_rock,
            galerkin: self.galerkin,
        };
        Ok((case, ctx))
    }

    /// The migration part of the scene as a `/v1/migration` request.
    fn migration_request(&self) -> MigrationRequest {
        MigrationRequest {
            method: self.method,
            gravity_m_s2: self.gravity_m_s2,
            face: self.face.clone(),
            rock: self.rock.clone(),
            release: self.release,
            lumped_mass: self.lumped_mass,
            rigid_block: self.rigid_block,
            end_time_s: self.end_time_s,
            monte_carlo: self.monte_carlo.as_ref().map(MonteCarloDto::from),
            output: self.migration_output,
        }
    }

    /// The supports, listed or in rows (one form only; by default one support at the lower
    /// end of a face of `length`, m).
    fn resolve_supports(&mut self, length: f64, ck: &mut Checker) -> Supports {
        match (&mut self.supports, &mut self.support_rows) {
            (Some(_), Some(_)) => {
                ck.push(
                    "/support_rows",
                    Value::Null,
                    "give supports or support_rows, not both",
                );
                Supports::default()
            }
            (None, Some(rows)) => support_rows(rows, length, ck),
            (list, None) => {
                let list = list.get_or_insert_with(|| vec![SupportDto::default()]);
                support_list(list, length, ck)
            }
        }
    }

    /// A given impact velocity, m/s, in (0, 1000]: no migration, so no ensemble and no
    /// comparison of methods.
    fn check_impact_velocity(&self, ck: &mut Checker) {
        let Some(v) = self.impact_velocity_m_s else {
            return;
        };
        ck.open_closed("/impact_velocity_m_s", v, 0.0, 1000.0, "m/s");
        if self.monte_carlo.is_some() {
            ck.push(
                "/monte_carlo",
                Value::Null,
                "with impact_velocity_m_s there is no migration to draw an ensemble of",
            );
        }
        if self.compare_methods {
            ck.push(
                "/compare_methods",
                json!(true),
                "with impact_velocity_m_s there is no migration to compare",
            );
        }
    }

    /// The column stage, checked by `/v1/column`'s rules on a template impact of
    /// `impact_rock`: the column case and the impact rock as resolved.
    fn resolve_column_stage(
        &mut self,
        config: &Config,
        impact_rock: RockDto,
        ck: &mut Checker,
    ) -> (crate::physics::column::ColumnCase, RockDto) {
        let mut template = ColumnRequest {
            velocity_m_s: 5.0,
            rock: impact_rock,
            column: ColumnDto::default(),
            contact: self.contact,
            model: self.column_model,
            galerkin: self.galerkin,
            initial_midpoint_displacement_m: None,
            end_time_s: None,
            output: self.column_output.clone(),
        };
        let column_case = match template.resolve_in(config, Layout::Scene) {
            Ok(c) => c,
            Err(e) => {
                // the template's own column is the default: report the request's errors only
                let errs: Vec<FieldError> = e
                    .errors()
                    .iter()
                    .filter(|f| !f.field.starts_with("/column/") && f.field != "/velocity_m_s")
                    .cloned()
                    .collect();
                for f in errs {
                    ck.push(f.field, f.value, f.message);
                }
                crate::physics::column::ColumnCase::default()
            }
        };
        self.galerkin = template.galerkin;
        (column_case, template.rock)
    }

    /// The release zones (Table 1's thirds or given zones) on a face of `length` (m); they
    /// need an ensemble to be drawn from.
    fn resolve_release_zones(&self, length: f64, ck: &mut Checker) -> Option<Vec<ReleaseZone>> {
        let release_zones = match &self.release_zones {
            None => None,
            Some(ReleaseZonesDto::Named(ReleaseZonesName::Table1)) => {
                let third = length / 3.0;
                Some(
                    [
                        (0.0, third, TABLE1_SHARES[0]),
                        (third, 2.0 * third, TABLE1_SHARES[1]),
                        (2.0 * third, length, TABLE1_SHARES[2]),
                    ]
                    .map(|(from, to, weight)| ReleaseZone { from, to, weight })
                    .to_vec(),
                )
            }
            Some(ReleaseZonesDto::Zones(z)) => Some(release_zone_list(z, length, ck)),
        };
        if release_zones.is_some() && self.monte_carlo.is_none() {
            ck.push(
                "/release_zones",
                Value::Null,
                "release zones are drawn from: they need monte_carlo",
            );
        }
        release_zones
    }

    /// The scene-only draws of the ensemble (side length, density, release across), bounded
    /// distributions only; the side length for a cube, sphere or cuboid rock only.
    fn resolve_draws(&self, ck: &mut Checker) -> SceneDraws {
        let draws = match &self.monte_carlo {
            None => SceneDraws::default(),
            Some(m) => SceneDraws {
                side_length: m
                    .side_length_m
                    .map(|d| d.resolve("/monte_carlo/side_length_m", 0.01, 5.0, ck)),
                density: m
                    .density_kg_m3
                    .map(|d| d.resolve("/monte_carlo/density_kg_m3", 100.0, 20000.0, ck)),
                release_across: m
                    .release_across_m
                    .map(|d| d.resolve("/monte_carlo/release_across_m", -1000.0, 1000.0, ck)),
            },
        };
        for (f, d) in [
            ("side_length_m", draws.side_length),
            ("density_kg_m3", draws.density),
            ("release_across_m", draws.release_across),
        ] {
            if matches!(
                d,
                Some(crate::physics::migration::Distribution::Normal { .. })
            ) {
                ck.push(
                    format!("/monte_carlo/{f}/distribution"),
                    json!("normal"),
                    "an unbounded normal can leave the field's range: use uniform or truncated_normal",
                );
            }
        }
        if draws.side_length.is_some()
            && !matches!(
                self.rock.shape,
                ShapeKind::Cube | ShapeKind::Sphere | ShapeKind::Cuboid | ShapeKind::Ellipsoid
            )
        {
            ck.push(
                "/monte_carlo/side_length_m",
                Value::Null,
                "the side length is drawn for a cube, sphere, cuboid or ellipsoid rock only",
            );
        }
        draws
    }

    /// The release rate (only with an ensemble: its frequencies are the rate × the ensemble's
    /// probabilities).
    fn resolve_release_rate(&self, ck: &mut Checker) -> Option<ReleaseRate> {
        let r = self.release_rate.as_ref()?;
        if self.monte_carlo.is_none() || self.impact_velocity_m_s.is_some() {
            ck.push(
                "/release_rate",
                serde_json::to_value(r).unwrap_or(Value::Null),
                "needs an ensemble (monte_carlo, without impact_velocity_m_s): overloads per \
                 year are the release rate × the ensemble's probabilities",
            );
            return None;
        }
        r.resolve("/release_rate", ck)
    }

    /// With `release_rate.rocks_per_year_by_zone`: one rate per release zone (zones needed), the
    /// rates becoming the zones' weights (the ensemble draws the zones in proportion to them).
    fn zone_rates(&self, zones: Option<&mut [ReleaseZone]>, ck: &mut Checker) {
        let Some(rates) = self
            .release_rate
            .as_ref()
            .and_then(|r| r.rocks_per_year_by_zone.as_ref())
        else {
            return;
        };
        match zones {
            Some(z) if z.len() == rates.len() => {
                for (zone, &r) in z.iter_mut().zip(rates) {
                    zone.weight = r;
                }
            }
            Some(z) => ck.push(
                "/release_rate/rocks_per_year_by_zone",
                json!(rates.len()),
                format!("one rate per release zone: {} zones", z.len()),
            ),
            None => ck.push(
                "/release_rate/rocks_per_year_by_zone",
                json!(rates.len()),
                "rates per zone need release_zones",
            ),
        }
    }

    /// The design limits: utilisation in (0, 100], force (N) and energy (J) in (0, 1e12],
    /// acceptable probability in [0, 1].
    fn resolve_design_limits(&self, ck: &mut Checker) -> DesignLimits {
        let dl = &self.design_limits;
        if let Some(v) = dl.stress_utilisation {
            ck.open_closed("/design_limits/stress_utilisation", v, 0.0, 100.0, "");
        }
        if let Some(v) = dl.max_force_n {
            ck.open_closed("/design_limits/max_force_n", v, 0.0, 1e12, "N");
        }
        if let Some(v) = dl.absorbed_energy_j {
            ck.open_closed("/design_limits/absorbed_energy_j", v, 0.0, 1e12, "J");
        }
        ck.closed(
            "/design_limits/acceptable_probability",
            dl.acceptable_probability,
            0.0,
            1.0,
            "",
        );
        DesignLimits {
            design_percentile: scene::DESIGN_PERCENTILE,
            stress_utilisation: dl.stress_utilisation,
            max_force: dl.max_force_n,
            absorbed_energy: dl.absorbed_energy_j,
            acceptable_probability: dl.acceptable_probability,
        }
    }
}

/// Maps a scene error to the problem naming the field of the request actually sent.
pub fn scene_error(e: SceneError, ctx: &SceneContext) -> ApiError {
    let support = e
        .entry
        .and_then(|k| ctx.entry_pointer.get(k))
        .map(String::as_str);
    ApiError::from_physics(e.error, |p| scene_pointer(p, support))
}
