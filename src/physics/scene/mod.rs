//! The whole chain along the face (api.md `POST /v1/scene`): release → migration → impact on the
//! first support reached → column energy → design checks, for one run or a seeded ensemble.
//!
//! Every stage calls the function its own endpoint uses — [`migration::run`] and
//! `migration::ensemble_run` (the same streams as `/v1/migration`), [`contact::solve_impact`]
//! and [`column::solve_column`] — so a stage's numbers are bit-identical to that endpoint's on
//! the same inputs. Stages the case does not need are skipped and the plan says why.
//!
//! Draws only a scene makes (release point from the spalling zones, release across the face,
//! the rock's side length and density) come from a stream of their own per run, seeded by
//! (seed, run index, 1), in that order: zone choice and position (when zones are given), across,
//! side length, density.
//!
//! A scene is solved in two parts: [`solve_nominal`] (the nominal run and its strikes, or the
//! whole report without an ensemble), then the runs of an index range ([`ensemble_part`]) and
//! [`ensemble_report`] over their records ([`SceneRecords`]: in memory, or read from the parts
//! of a sharded computation). The statistics sum in run order, the summation order of the
//! contract, so any split of the runs gives the same bits.

use super::column::{self, ColumnCase, ColumnDetail, ColumnModel, ColumnResult};
use super::contact::{self, ImpactResult};
use super::control::Control;
use super::design::EntryAllowed;
use super::error::{Param, PhysicsError};
use super::material::{Column, ImpactCase, Rock, RockShape};
use super::migration::shape::BlockShape;
use super::migration::{
    self, Distribution, Method, MigrationCase, MigrationResult, MonteCarlo, RunSummary, StopReason,
    SupportStop, monte_carlo,
};
use super::plan::Stage;
use super::stats::interval::{Z_95, wilson_interval};
use super::stats::rate::{Frequency, ReleaseRate, frequency};
use super::stats::{self, Summary};
use super::validity::Warning;

pub mod barrier_design;
mod collectors;
pub mod design_search;
mod devices;
mod ensemble;
pub mod target;
use ensemble::compare_single;
#[cfg(test)]
mod tests;

pub use collectors::{
    DESIGN_CONFIDENCE, DESIGN_PERCENTILE, DesignRanks, DesignValue, DesignValues, REACH_COLUMNS,
    design_ranks, design_value, reach_columns,
};
pub use devices::{BarrierStatistics, DeviceStatistics, crossing_columns, scene_lines};
pub use ensemble::{
    ENTRY_COLUMNS, EnsembleReport, SceneRecords, ensemble_cells, ensemble_part,
    ensemble_part_mapped, ensemble_report, entry_columns, outcomes_of,
};

/// Impact speed below which a support counts as reached without an impact, m/s.
pub const NO_IMPACT_SPEED: f64 = 1e-6;
/// Largest impact speed `/v1/impact` takes, m/s; faster counts as capacity exceeded.
pub const MAX_IMPACT_SPEED: f64 = 1000.0;
/// The paper's Table 1 spalling shares of the upper, middle and lower thirds of the face.
pub const TABLE1_SHARES: [f64; 3] = [0.233, 0.583, 0.184];

/// One entry of the expanded support list: a spanning support or one column of a support.
#[derive(Debug, Clone, PartialEq)]
pub struct SupportEntry {
    /// Support number (from 1).
    pub support: u32,
    /// Column of that support (from 0).
    pub column_index: u32,
    /// Along-dip position in the mean plane, m.
    pub along_dip: f64,
    /// Across position of the column axis, m (None: the support spans the face).
    pub across: Option<f64>,
    /// The support's column (struck at its midpoint).
    pub column: Column,
}

/// A zone of release points along the dip, drawn with probability ∝ weight, uniform inside.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReleaseZone {
    /// Upper edge, m.
    pub from: f64,
    /// Lower edge, m.
    pub to: f64,
    /// Relative weight (≥ 0).
    pub weight: f64,
}

/// The design limits checked for every impact; `None` is not checked.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DesignLimits {
    /// Percentile of the design values at each support, in (0, 1) (default 0.95).
    pub design_percentile: f64,
    /// Largest bending-stress utilisation σ/σ_y (default 1).
    pub stress_utilisation: Option<f64>,
    /// Largest contact force, N.
    pub max_force: Option<f64>,
    /// Largest absorbed energy, J.
    pub absorbed_energy: Option<f64>,
    /// Probability of exceedance a support may have (ensemble verdict; default 0).
    pub acceptable_probability: f64,
}

impl Default for DesignLimits {
    fn default() -> Self {
        Self {
            design_percentile: DESIGN_PERCENTILE,
            stress_utilisation: Some(1.0),
            max_force: None,
            absorbed_energy: None,
            acceptable_probability: 0.0,
        }
    }
}

/// A design limit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Limit {
    /// Bending-stress utilisation σ/σ_y.
    StressUtilisation,
    /// Contact force, N.
    MaxForce,
    /// Absorbed energy, J.
    AbsorbedEnergy,
}

impl DesignLimits {
    /// The limits that are checked, with their allowed values, in api.md order.
    #[must_use]
    pub fn active(&self) -> Vec<(Limit, f64)> {
        [
            (Limit::StressUtilisation, self.stress_utilisation),
            (Limit::MaxForce, self.max_force),
            (Limit::AbsorbedEnergy, self.absorbed_energy),
        ]
        .into_iter()
        .filter_map(|(l, v)| v.map(|v| (l, v)))
        .collect()
    }
}

/// Scene-only draws of an ensemble (distributions as in `/v1/migration`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SceneDraws {
    /// Cube side (or the shape's side length), m.
    pub side_length: Option<Distribution>,
    /// Rock density, kg/m³.
    pub density: Option<Distribution>,
    /// Release across the face y, m.
    pub release_across: Option<Distribution>,
}

impl SceneDraws {
    /// True when a draw changes something between runs.
    #[must_use]
    pub fn any(&self) -> bool {
        self.side_length.is_some() || self.density.is_some() || self.release_across.is_some()
    }
}

/// A scene (api.md `POST /v1/scene`), SI units.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneCase {
    /// The migration case (its `supports` are set by the scene; its `monte_carlo` is the
    /// ensemble's migration part).
    pub migration: MigrationCase,
    /// The expanded support entries.
    pub supports: Vec<SupportEntry>,
    /// The column stage's template: model, modes, shapes, history; its impact holds the contact
    /// model (rock, column and speed are set per impact).
    pub column: ColumnCase,
    /// Strike every entry at this speed instead of migrating, m/s.
    pub impact_velocity: Option<f64>,
    /// Release zones along the dip (ensemble draws), if any.
    pub release_zones: Option<Vec<ReleaseZone>>,
    /// Scene-only draws.
    pub draws: SceneDraws,
    /// Design limits.
    pub limits: DesignLimits,
    /// Run both migration methods and compare.
    pub compare_methods: bool,
    /// Rocks released per year, or counted over a period (None: no frequencies).
    pub release_rate: Option<ReleaseRate>,
    /// Per entry, the energy rating of a guard on its column, J (None: no guard).
    pub guards: Vec<Option<f64>>,
    /// Compute each support's allowed impact per design limit ([`allowed_for_entries`](super::design::allowed_for_entries)).
    pub allowed_impacts: bool,
    /// Per device (barriers, then collectors, each in request order), the index of its line in
    /// `migration.lines` ([`scene_lines`]).
    pub device_lines: Vec<usize>,
    /// Stop the ensemble when a statistic is precise enough (None: run every run).
    pub target: Option<target::SceneTarget>,
    /// The design search for guards over the ensemble's runs (None: not asked for).
    pub design: Option<design_search::DesignAsk>,
}

impl SceneCase {
    /// A scene of `migration` with these support entries and column stage, and every other
    /// input at its default: no scene draws, release zones, guards, devices, design search or
    /// target; the default design limits; allowed impacts not computed.
    #[must_use]
    pub fn new(migration: MigrationCase, supports: Vec<SupportEntry>, column: ColumnCase) -> Self {
        let guards = vec![None; supports.len()];
        Self {
            migration,
            supports,
            column,
            impact_velocity: None,
            release_zones: None,
            draws: SceneDraws::default(),
            limits: DesignLimits::default(),
            compare_methods: false,
            release_rate: None,
            guards,
            allowed_impacts: false,
            device_lines: Vec::new(),
            design: None,
            target: None,
        }
    }
}

/// The failure of a scene: the stage's error and the support entry it concerns (its fields are
/// then relative to that entry's support object).
#[derive(Debug, Clone, PartialEq)]
pub struct SceneError {
    /// Index into [`SceneCase::supports`] when the error concerns one entry.
    pub entry: Option<usize>,
    /// The error.
    pub error: PhysicsError,
}

impl From<PhysicsError> for SceneError {
    fn from(error: PhysicsError) -> Self {
        Self { entry: None, error }
    }
}

/// Result of a scene.
pub type SceneResult<T> = Result<T, SceneError>;

/// One design check of an impact.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Check {
    /// The limit.
    pub limit: Limit,
    /// The value (None: past the contact capacity).
    pub value: Option<f64>,
    /// The allowed value.
    pub allowed: f64,
    /// value / allowed (None with the value, or when the ratio overflows).
    pub utilisation: Option<f64>,
    /// value > allowed, or the capacity exceeded.
    pub exceeded: bool,
}

/// What an impact on an entry gave.
#[derive(Debug, Clone, PartialEq)]
pub enum Strike {
    /// Reached below [`NO_IMPACT_SPEED`]: no impact, all values 0.
    NoImpact,
    /// Past `/v1/impact`'s speed range or the contact law's capacity.
    CapacityExceeded {
        /// Largest speed the law takes, m/s (None: the speed range itself was passed).
        max_velocity: Option<f64>,
    },
    /// The impact and column stages ran.
    Solved {
        /// The impact case (the rock as a cube).
        impact_case: Box<ImpactCase>,
        /// The impact.
        impact: Box<ImpactResult>,
        /// The column case.
        column_case: Box<ColumnCase>,
        /// The column.
        column: Box<ColumnResult>,
    },
}

/// Values an impact gives for the statistics and checks.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StrikeValues {
    /// δmax (decoupled) or the largest contact deformation (coupled), m.
    pub max_deformation: f64,
    /// Pmax (decoupled) or the coupled `max_force_n`, N.
    pub max_force: f64,
    /// Absorbed energy (decoupled) or column energy after the contact (coupled), J.
    pub absorbed_energy: f64,
    /// Bending-stress utilisation σ/σ_y.
    pub stress_utilisation: f64,
}

impl Strike {
    /// The values of the strike (None past the capacity; zeros without an impact).
    #[must_use]
    pub fn values(&self) -> Option<StrikeValues> {
        match self {
            Strike::NoImpact => Some(StrikeValues::default()),
            Strike::CapacityExceeded { .. } => None,
            Strike::Solved { impact, column, .. } => {
                let (d, f, e) = match &column.detail {
                    ColumnDetail::Decoupled(dd) => {
                        (dd.max_deformation, dd.max_force, dd.absorbed_energy)
                    }
                    ColumnDetail::Coupled(c) => (
                        c.max_contact_deformation,
                        c.max_force,
                        c.column_energy_after_contact,
                    ),
                };
                let _ = impact;
                Some(StrikeValues {
                    max_deformation: d,
                    max_force: f,
                    absorbed_energy: e,
                    stress_utilisation: column.stress_utilisation,
                })
            }
        }
    }
}

/// The checks of a strike against the limits.
#[must_use]
pub fn checks(limits: &DesignLimits, strike: &Strike) -> Vec<Check> {
    let v = strike.values();
    limits
        .active()
        .into_iter()
        .map(|(limit, allowed)| {
            let value = v.map(|v| match limit {
                Limit::StressUtilisation => v.stress_utilisation,
                Limit::MaxForce => v.max_force,
                Limit::AbsorbedEnergy => v.absorbed_energy,
            });
            Check {
                limit,
                value,
                allowed,
                // a limit near 0 can make the ratio overflow: then it is not reported
                utilisation: value.map(|x| x / allowed).filter(|u| u.is_finite()),
                exceeded: value.is_none_or(|x| x > allowed),
            }
        })
        .collect()
}

/// What a support's guard did to a rock that reached it.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Guard {
    /// No guard on the entry.
    #[default]
    None,
    /// The rock's impact energy was within the rating: the column was not loaded.
    Held,
    /// The rock's impact energy passed the rating: the column took the rest.
    BrokenThrough,
}

/// The guard of entry `k` against a rock of mass `mass` (kg) reaching it at `v` (m/s): what it
/// did and the speed the column then takes, m/s. The guard takes up to its rating R of the
/// rock's impact energy ½mv²; past it the column is struck at √(v² − 2R/m).
#[must_use]
pub fn behind_guard(case: &SceneCase, k: usize, mass: f64, v: f64) -> (Guard, f64) {
    match case.guards.get(k).copied().flatten() {
        None => (Guard::None, v),
        Some(rating) => {
            // v² − 2R/m: with R = 0 the speed is v itself (√(v²) rounds back to v exactly)
            let left = v * v - 2.0 * rating / mass;
            if left <= 0.0 {
                (Guard::Held, 0.0)
            } else {
                (Guard::BrokenThrough, left.sqrt())
            }
        }
    }
}

/// [`strike`] behind entry `k`'s guard ([`behind_guard`]): a held rock is no impact; one that
/// broke through strikes at the speed left. Returns what the guard did, the speed the column
/// took (m/s) and the strike.
///
/// Errors: as [`strike`].
pub fn guarded_strike(
    case: &SceneCase,
    k: usize,
    rock: &Rock,
    mass: f64,
    v: f64,
    control: &Control,
) -> SceneResult<(Guard, f64, Strike)> {
    let (guard, speed) = behind_guard(case, k, mass, v);
    let s = match guard {
        Guard::Held => Strike::NoImpact,
        _ => strike(case, k, rock, speed, control)?,
    };
    Ok((guard, speed, s))
}

/// An impact of a single run (or of `impact_velocity`) with its checks.
#[derive(Debug, Clone, PartialEq)]
pub struct ImpactOutcome {
    /// Index into [`SceneCase::supports`].
    pub entry: usize,
    /// The impact speed, m/s.
    pub velocity: f64,
    /// What the impact gave.
    pub strike: Strike,
    /// The checks.
    pub checks: Vec<Check>,
    /// Some check exceeded.
    pub exceeded: bool,
    /// The nominal run of an ensemble.
    pub nominal: bool,
    /// What the entry's guard did.
    pub guard: Guard,
    /// The speed the column took behind the guard, m/s (the impact speed without one).
    pub column_speed: f64,
}

/// One run of an ensemble with its strike.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneRun {
    /// The migration summary (support and impact speed included).
    pub summary: RunSummary,
    /// Values of the strike (None: no support reached, or past the capacity).
    pub values: Option<StrikeValues>,
    /// Past the capacity at the support reached.
    pub capacity_exceeded: bool,
    /// Per active limit (in [`DesignLimits::active`] order), exceeded at the support reached.
    pub exceeded: Vec<bool>,
    /// What the guard of the support reached did.
    pub guard: Guard,
    /// Per line of the scene's migration (barriers, then collectors), where the run reached it.
    pub crossings: migration::Crossings,
}

impl SceneRun {
    /// The run struck its support past some checked limit (or past the contact capacity).
    #[must_use]
    pub fn overloaded(&self) -> bool {
        self.exceeded.iter().any(|&x| x)
    }
}

/// Per support entry of `case`, the runs that overloaded it ([`SceneRun::overloaded`]).
#[must_use]
pub fn overloads(case: &SceneCase, runs: &[SceneRun]) -> Vec<u64> {
    let mut c = vec![0u64; case.supports.len()];
    for r in runs {
        if let Some(k) = r.summary.support
            && r.overloaded()
        {
            c[k] += 1;
        }
    }
    c
}

/// Fractions of all runs by how they ended (summing to 1).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Outcomes {
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
    /// Stopped by a barrier.
    pub barrier: f64,
}

/// A probability with its Wilson 95 % interval.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Probability {
    /// k / n.
    pub probability: f64,
    /// Wilson score interval, z = 1.959963984540054.
    pub ci95: [f64; 2],
}

fn probability(k: u64, n: u64) -> Probability {
    Probability {
        probability: k as f64 / n.max(1) as f64,
        ci95: wilson_interval(k as f64, n as f64, Z_95).unwrap_or([0.0, 1.0]),
    }
}

/// What a guard did over all runs of an ensemble.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GuardStatistics {
    /// The guard's energy rating, J.
    pub rating: f64,
    /// Runs whose rock the guard held (within the rating), over all runs.
    pub held: Probability,
    /// Runs whose rock broke through it, over all runs.
    pub broken_through: Probability,
}

/// Statistics of one entry over an ensemble.
#[derive(Debug, Clone, PartialEq)]
pub struct EntryStatistics {
    /// Fraction of all runs that ended at this entry.
    pub reached_fraction: f64,
    /// Fraction of all runs that ended here past the capacity.
    pub capacity_exceeded_fraction: f64,
    /// Impact speed over the runs that reached the entry within capacity, m/s.
    pub impact_velocity: Option<Summary>,
    /// δmax, m.
    pub max_deformation: Option<Summary>,
    /// Pmax, N.
    pub max_force: Option<Summary>,
    /// Absorbed energy, J.
    pub absorbed_energy: Option<Summary>,
    /// Stress utilisation.
    pub stress_utilisation: Option<Summary>,
    /// The design values over the runs that reached the entry (None: no run did).
    pub design_values: Option<DesignValues>,
    /// Per active limit: the probability over all runs of striking this entry past the limit.
    pub exceedance: Vec<(Limit, Probability)>,
    /// Some exceedance probability above the acceptable one.
    pub exceeded: bool,
    /// Expected strikes of this entry past some limit per year (with a release rate).
    pub overloads_per_year: Option<Frequency>,
    /// What the entry's guard did over all runs (None: no guard).
    pub guard: Option<GuardStatistics>,
}

/// Ensemble statistics of a scene.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneStatistics {
    /// Number of runs.
    pub runs: u64,
    /// Seed.
    pub seed: u64,
    /// How the runs ended.
    pub outcomes: Outcomes,
    /// Per entry.
    pub entries: Vec<EntryStatistics>,
    /// Probability that a run overloads some support.
    pub any_exceeded: Probability,
    /// Expected overloads of some support per year (with a release rate).
    pub any_overloads_per_year: Option<Frequency>,
    /// Per device (barriers, then collectors), what it saw.
    pub devices: Vec<DeviceStatistics>,
    /// What the ensemble's target gave (None: no target).
    pub target: Option<target::TargetOutcome>,
}

/// One entry of a method in a comparison: reached fraction, median impact speed (None: never
/// reached within capacity), exceedance probability per active limit.
pub type ComparedEntry = (f64, Option<f64>, Vec<(Limit, f64)>);

/// One method's part of a comparison.
#[derive(Debug, Clone, PartialEq)]
pub struct MethodSummary {
    /// The method.
    pub method: Method,
    /// How the runs ended (single run: 1 for its outcome).
    pub outcomes: Outcomes,
    /// Per entry: reached fraction, median impact speed (None: never reached), exceedance
    /// probabilities per active limit.
    pub entries: Vec<ComparedEntry>,
}

/// Everything a scene reports.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneReport {
    /// The plan.
    pub plan: Vec<Stage>,
    /// The migration of the nominal run (None with `impact_velocity`).
    pub migration: Option<MigrationResult>,
    /// Impacts: per entry with `impact_velocity`, the single run's, or the nominal run's.
    pub impacts: Vec<ImpactOutcome>,
    /// Ensemble statistics.
    pub statistics: Option<SceneStatistics>,
    /// The ensemble's runs (for the CSV).
    pub runs: Option<Vec<SceneRun>>,
    /// Both methods side by side.
    pub comparison: Option<Vec<MethodSummary>>,
    /// Per entry: the allowed impacts and the design speed's margins (None: not asked for).
    pub allowed: Option<Vec<EntryAllowed>>,
    /// Warnings of the scene (the migration's are in its result).
    pub warnings: Vec<Warning>,
    /// Per-cell maps of the ensemble (with `migration_output.maps`).
    pub maps: Option<migration::maps::Maps>,
    /// The design search for guards (with [`SceneCase::design`]).
    pub design: Option<design_search::DesignSearch>,
    /// The barrier search's answer (with `design.barriers`).
    pub barrier_design: Option<barrier_design::BarrierDesign>,
}

/// Bounding radius of a rock (largest distance of a point from its centre of mass), m, and its
/// mass, kg.
pub fn rock_extent(rock: &Rock) -> Result<(f64, f64), PhysicsError> {
    let b = BlockShape::of_rock(rock)?;
    Ok((b.r_max, b.mass))
}

/// The rock as it enters the impact: itself when a cube, else the cube of equal mass and density.
#[must_use]
pub fn impact_rock(rock: &Rock, mass: f64) -> Rock {
    if rock.shape == RockShape::Cube {
        return rock.clone();
    }
    let l = (mass / rock.density).cbrt();
    Rock {
        shape: RockShape::Cube,
        side_length: l,
        corner_radius: rock.corner_radius.min(l / 2.0),
        ..rock.clone()
    }
}

/// Strikes `entry` at `speed` with `rock` (already a cube): the impact and column stages.
///
/// Errors (other than the capacity, which is a result): a column shorter than the contact
/// length, and the column stage's own (too many steps, cancel, time limit), tagged with the entry.
pub fn strike(
    case: &SceneCase,
    entry: usize,
    rock: &Rock,
    speed: f64,
    control: &Control,
) -> SceneResult<Strike> {
    let tag = |error: PhysicsError| SceneError {
        entry: Some(entry),
        error,
    };
    if speed.is_nan() || speed < NO_IMPACT_SPEED {
        return Ok(Strike::NoImpact);
    }
    if speed > MAX_IMPACT_SPEED {
        return Ok(Strike::CapacityExceeded { max_velocity: None });
    }
    let e = &case.supports[entry];
    if e.column.length < rock.side_length {
        return Err(tag(PhysicsError::invalid(
            Param::ColumnLength,
            e.column.length,
            format!(
                "must be at least the contact length L = {} m of the rock that strikes it",
                rock.side_length
            ),
        )));
    }
    let impact_case = ImpactCase {
        velocity: speed,
        rock: rock.clone(),
        column: e.column.clone(),
        contact: case.column.impact.contact,
    };
    let impact = match contact::solve_impact(&impact_case) {
        Ok(r) => r,
        Err(PhysicsError::CapacityExceeded {
            max_velocity_m_s, ..
        }) => {
            return Ok(Strike::CapacityExceeded {
                max_velocity: Some(max_velocity_m_s),
            });
        }
        Err(err) => return Err(tag(err)),
    };
    let column_case = ColumnCase {
        impact: impact_case.clone(),
        ..case.column.clone()
    };
    match column::solve_column_solved(&column_case, &impact, control) {
        Ok(c) => Ok(Strike::Solved {
            impact_case: Box::new(impact_case),
            impact: Box::new(impact),
            column_case: Box::new(column_case),
            column: Box::new(c),
        }),
        Err(PhysicsError::CapacityExceeded {
            max_velocity_m_s, ..
        }) => Ok(Strike::CapacityExceeded {
            max_velocity: Some(max_velocity_m_s),
        }),
        Err(err) => Err(tag(err)),
    }
}

fn outcome(
    case: &SceneCase,
    entry: usize,
    velocity: f64,
    (guard, column_speed, strike): (Guard, f64, Strike),
    nominal: bool,
) -> ImpactOutcome {
    let checks = checks(&case.limits, &strike);
    ImpactOutcome {
        entry,
        velocity,
        exceeded: checks.iter().any(|c| c.exceeded),
        checks,
        strike,
        nominal,
        guard,
        column_speed,
    }
}

/// The supports as the migration sees them, for a rock of bounding radius `r_rock`.
#[must_use]
pub fn stops(case: &SceneCase, r_rock: f64) -> Vec<SupportStop> {
    case.supports
        .iter()
        .map(|e| SupportStop {
            along_dip: e.along_dip,
            across: e.across,
            reach: e.column.outer_diameter / 2.0 + r_rock,
        })
        .collect()
}

/// The scene-only stream of run `index`: seeded by (seed, run index, 1).
#[must_use]
pub fn scene_stream(seed: u64, index: u64) -> rand_pcg::Pcg64 {
    // as the run's stream of /v1/migration, (seed, index), with the third word 1 mixed in
    let mut sm =
        seed ^ index.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ 1u64.wrapping_mul(0xC2B2_AE3D_27D4_EB4F);
    let hi = monte_carlo::splitmix64(&mut sm) as u128;
    let lo = monte_carlo::splitmix64(&mut sm) as u128;
    let stream = monte_carlo::splitmix64(&mut sm) as u128;
    rand_pcg::Pcg64::new((hi << 64) | lo, stream)
}

/// The migration case of run `index` with its scene-only draws, and its rock's bounding radius
/// and mass.
fn run_case(
    case: &SceneCase,
    zones: Option<&[ReleaseZone]>,
    seed: u64,
    index: u64,
) -> Result<(MigrationCase, Rock, f64, f64), PhysicsError> {
    let mut m = case.migration.clone();
    m.output.events = false;
    m.output.trajectory = false;
    m.output.runs_csv = false;
    let mut rng = scene_stream(seed, index);
    if let Some(zones) = zones {
        let total: f64 = zones.iter().map(|z| z.weight).sum();
        let u = monte_carlo::uniform01(&mut rng) * total;
        let mut acc = 0.0;
        let mut pick = zones[zones.len() - 1];
        for z in zones {
            acc += z.weight;
            if u < acc && z.weight > 0.0 {
                pick = *z;
                break;
            }
        }
        let w = monte_carlo::uniform01(&mut rng);
        let s = pick.from + (pick.to - pick.from) * w;
        // a release is strictly above the lower end
        m.release.along_dip = s.min(m.face.length * (1.0 - f64::EPSILON));
    }
    if let Some(d) = &case.draws.release_across {
        m.release.across = monte_carlo::sample(d, &mut rng);
    }
    if let Some(d) = &case.draws.side_length {
        let l = monte_carlo::sample(d, &mut rng);
        scale_rock(&mut m.rock, l);
    }
    if let Some(d) = &case.draws.density {
        m.rock.density = monte_carlo::sample(d, &mut rng);
    }
    let (r, mass) = rock_extent(&m.rock)?;
    m.supports = stops(case, r);
    let rock = m.rock.clone();
    Ok((m, rock, r, mass))
}

/// The release zones clipped to the along-dip interval `span` where a release fits on the floor
/// ([`migration::release_span`]; `None`: every position does), each zone's weight scaled by the
/// share of its length kept (a zone of zero length: kept whole or dropped), and the share of
/// the total weight clipped off.
///
/// Errors: nothing of the zones left (`InvalidInput` naming the zones, with the interval).
fn clip_zones(
    zones: &[ReleaseZone],
    span: Option<(f64, f64)>,
) -> Result<(Vec<ReleaseZone>, f64), PhysicsError> {
    let Some((a, b)) = span else {
        return Ok((zones.to_vec(), 0.0));
    };
    let total: f64 = zones.iter().map(|z| z.weight).sum();
    let clipped: Vec<ReleaseZone> = zones
        .iter()
        .map(|z| {
            let (from, to) = (z.from.max(a), z.to.min(b));
            let kept = if z.to > z.from {
                ((to - from) / (z.to - z.from)).clamp(0.0, 1.0)
            } else if (a..=b).contains(&z.from) {
                1.0
            } else {
                0.0
            };
            ReleaseZone {
                from: from.clamp(a, b),
                to: to.clamp(a, b).max(from.clamp(a, b)),
                weight: if kept > 0.0 { z.weight * kept } else { 0.0 },
            }
        })
        .collect();
    let left: f64 = clipped.iter().map(|z| z.weight).sum();
    if left <= 0.0 || left.is_nan() {
        return Err(PhysicsError::invalid(
            Param::ReleaseZones,
            0.0,
            format!(
                "no release zone lies where the rock fits on the floor at the release's \
                 across position: along_dip_m in [{a:.4}, {b:.4}] m"
            ),
        ));
    }
    let share = if total > 0.0 { 1.0 - left / total } else { 0.0 };
    Ok((clipped, share.max(0.0)))
}

/// The warning for release zones reaching where the rock does not fit on the floor.
fn clipped_zones_warning(share: f64, span: (f64, f64)) -> Warning {
    Warning {
        code: "release_zones_clipped",
        message: format!(
            "{:.2} % of the release zones' weight lies where the rock does not fit on the floor \
             at the release's across position (along_dip_m outside [{:.4}, {:.4}] m: the point \
             off the floor, or the resting block overhanging its edge): the zones were clipped \
             to that interval and their releases drawn inside it",
            100.0 * share,
            span.0,
            span.1
        ),
    }
}

/// Sets the rock's side length to `l`, scaling a sphere's radius and a cuboid's edges with it.
fn scale_rock(rock: &mut Rock, l: f64) {
    let k = l / rock.side_length;
    rock.shape = match &rock.shape {
        RockShape::Sphere { radius } => RockShape::Sphere { radius: radius * k },
        RockShape::Cuboid { dimensions } => RockShape::Cuboid {
            dimensions: dimensions.map(|d| d * k),
        },
        RockShape::Ellipsoid { dimensions } => RockShape::Ellipsoid {
            dimensions: dimensions.map(|d| d * k),
        },
        s => s.clone(),
    };
    rock.side_length = l;
    rock.corner_radius = rock.corner_radius.min(l / 2.0);
}

/// True when an impact of the report went past the contact capacity (the plan says so).
#[must_use]
pub fn nominal_capacity(report: &SceneReport) -> bool {
    report
        .impacts
        .iter()
        .any(|i| matches!(i.strike, Strike::CapacityExceeded { .. }))
}

impl SceneReport {
    /// Adds what an ensemble gives (its plan stages and warnings after the nominal ones).
    pub fn attach(&mut self, tail: EnsembleReport) {
        self.plan.extend(tail.plan);
        self.warnings.extend(tail.warnings);
        self.statistics = Some(tail.statistics);
        self.runs = tail.runs;
        self.comparison = tail.comparison;
    }
}

/// Everything of a scene but its ensemble's runs: the release and migration stages of the plan,
/// the nominal run and its impact, the scene's own warnings — and, for a scene without an
/// ensemble (a single run or `impact_velocity`), the whole report. Returns the ensemble still to
/// run, if any (then [`ensemble_part`] and [`ensemble_report`] complete the report).
///
/// Errors: as `calc::scene::Scene::solve`.
pub fn solve_nominal(
    case: &SceneCase,
    control: &Control,
) -> SceneResult<(SceneReport, Option<MonteCarlo>)> {
    let mut plan = Vec::new();
    let mut warnings = Vec::new();
    let (r_rock, mass) = rock_extent(&case.migration.rock)?;
    let rock0 = impact_rock(&case.migration.rock, mass);
    if case.migration.rock.shape != RockShape::Cube {
        warnings.push(Warning {
            code: "equivalent_cube",
            message: format!(
                "the rock is not a cube: it enters the impact and column stages as the cube of \
                 equal mass and density, side {} m",
                rock0.side_length
            ),
        });
    }
    if let Some(v) = case.impact_velocity {
        plan.push(Stage::skipped(
            "release",
            "an impact velocity is given: no release",
        ));
        plan.push(Stage::skipped(
            "migration",
            "an impact velocity is given: no migration",
        ));
        let mut impacts = Vec::with_capacity(case.supports.len());
        control.set_total(case.supports.len() as u64);
        for k in 0..case.supports.len() {
            control.check()?;
            let s = guarded_strike(case, k, &rock0, mass, v, control)?;
            impacts.push(outcome(case, k, v, s, false));
            control.add_done(1);
        }
        let capacity = impacts
            .iter()
            .any(|i| matches!(i.strike, Strike::CapacityExceeded { .. }));
        push_strike_plan(case, &mut plan, impacts.len() as u64, capacity);
        let report = SceneReport {
            plan,
            migration: None,
            impacts,
            statistics: None,
            runs: None,
            comparison: None,
            allowed: None,
            warnings,
            maps: None,
            design: None,
            barrier_design: None,
        };
        return Ok((report, None));
    }
    plan.push(Stage::ran(
        "release",
        match (&case.migration.monte_carlo, &case.release_zones) {
            (Some(_), Some(_)) => "ensemble release points drawn from the release zones",
            _ => "the release of the request",
        },
    ));
    if let (Some(z), Some(_)) = (&case.release_zones, &case.migration.monte_carlo) {
        let floor = migration::build_floor(&case.migration)?;
        let span = migration::release_span(&case.migration, &floor)?;
        let (_, share) = clip_zones(z, span)?;
        if let (Some(span), true) = (span, share > 0.0) {
            warnings.push(clipped_zones_warning(share, span));
        }
    }
    let mut nominal_case = case.migration.clone();
    nominal_case.supports = stops(case, r_rock);
    let mc = nominal_case.monte_carlo.take();
    let nominal = migration::run(&nominal_case, control)?;
    // progress: the nominal run, the ensemble's runs and, in a comparison, the other method's
    // (an ensemble) or both methods' single runs
    let compare = u64::from(case.compare_methods);
    let total = match &mc {
        Some(m) => 1 + m.runs * (1 + compare),
        None => 1 + 2 * compare,
    };
    control.set_total(total);
    plan.push(Stage::ran(
        "migration",
        match (&mc, case.migration.method) {
            (Some(m), Method::LumpedMass) => format!(
                "energy tracking method: the nominal run and a seeded ensemble of {} runs, each \
                 ending at the first support reached",
                m.runs
            ),
            (Some(m), Method::RigidBlock) => format!(
                "rigid block (DEM): the nominal run and a seeded ensemble of {} runs, each \
                 ending at the first support reached",
                m.runs
            ),
            (None, Method::LumpedMass) => {
                "energy tracking method, one run ending at the first support reached".into()
            }
            (None, Method::RigidBlock) => {
                "rigid block (DEM), one run ending at the first support reached".into()
            }
        },
    ));
    let mut impacts = Vec::new();
    if let (Some(k), Some(v)) = (nominal.arrival.support, nominal.arrival.impact_speed) {
        let s = guarded_strike(case, k, &rock0, mass, v, control)?;
        impacts.push(outcome(case, k, v, s, mc.is_some()));
    }
    let mut report = SceneReport {
        plan,
        migration: None,
        impacts,
        statistics: None,
        runs: None,
        comparison: None,
        allowed: None,
        warnings,
        maps: None,
        design: None,
        barrier_design: None,
    };
    if mc.is_none() {
        // a single run: the rest of the report is the nominal run's
        if nominal.arrival.support.is_some() && nominal.arrival.time == 0.0 {
            report.warnings.push(within_reach_warning(1, 1));
        }
        let capacity = nominal_capacity(&report);
        push_strike_plan(
            case,
            &mut report.plan,
            report.impacts.len() as u64,
            capacity,
        );
        if case.compare_methods {
            report.comparison = Some(compare_single(case, &nominal_case, control, total)?);
        }
    }
    report.migration = Some(nominal);
    Ok((report, mc))
}

/// A release within a support's reach starts against it: reached at t = 0, no impact.
fn within_reach_warning(at_start: u64, n: u64) -> Warning {
    Warning {
        code: "released_within_reach",
        message: format!(
            "{at_start} of {n} runs start within a support's reach (a column's outer radius \
             plus the rock's bounding radius, or at a spanning support): the rock starts \
             against the support and counts as reaching it with no impact (speed 0); move \
             the release or its zones off the supports"
        ),
    }
}

/// Warnings about the ensemble's migration draws, as `/v1/migration` gives them: friction drawn
/// outside [0, 2] and clipped (μ is the first draw of each run's stream), a single run.
fn draw_warnings(mc: &MonteCarlo) -> Vec<Warning> {
    let mut w = Vec::new();
    if let Some(d) = &mc.friction_coefficient {
        let clipped = (0..mc.runs)
            .filter(|&i| {
                let mu = monte_carlo::sample(d, &mut monte_carlo::run_stream(mc.seed, i));
                !(0.0..=2.0).contains(&mu)
            })
            .count();
        if clipped > 0 {
            w.push(Warning {
                code: "friction_clipped",
                message: format!(
                    "{clipped} of {} drawn friction coefficients fell outside [0, 2] and were \
                     clipped to it",
                    mc.runs
                ),
            });
        }
    }
    if mc.runs < 2 {
        w.push(Warning {
            code: "single_run",
            message: "an ensemble of one run has no sample standard deviation: every std is \
                      null; ask for runs ≥ 2"
                .into(),
        });
    }
    w
}

/// The impact, column and checks stages: `struck` strikes, `capacity` when the nominal impact
/// went past the contact capacity.
fn push_strike_plan(case: &SceneCase, plan: &mut Vec<Stage>, struck: u64, capacity: bool) {
    if struck == 0 {
        plan.push(Stage::skipped("impact", "no run reached a support"));
        plan.push(Stage::skipped("column", "no run reached a support"));
        plan.push(Stage::skipped("checks", "no run reached a support"));
        return;
    }
    plan.push(Stage::ran(
        "impact",
        format!("Hertz contact of /v1/impact for {struck} strike(s) at the first support reached"),
    ));
    plan.push(Stage::ran(
        "column",
        match case.column.model {
            ColumnModel::Decoupled => "decoupled column of /v1/column (closed form)",
            ColumnModel::Coupled => "coupled column of /v1/column (rock + contact + modes)",
        }
        .to_string()
            + if capacity {
                "; skipped for impacts past the contact capacity"
            } else {
                ""
            },
    ));
    if case.limits.active().is_empty() {
        plan.push(Stage::skipped("checks", "every design limit is null"));
    } else {
        plan.push(Stage::ran(
            "checks",
            "each design limit that is not null, for every impact",
        ));
    }
}
