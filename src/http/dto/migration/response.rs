//! The migration response: arrival, energy budget, events, trajectory, statistics, the
//! rigid block's numbers, and the runs CSV.

use super::*;
use crate::calc::Report;
use crate::http::dto::common::{plan_of, warnings_of};

/// The state at the end of the (nominal) run.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct ArrivalDto {
    /// Motion at the end: flight, slide, roll or stopped.
    pub phase: String,
    /// Why the run ended: lower_end, at_rest, end_time or left_floor (in a scene also support).
    pub stop_reason: String,
    /// Time since release, s.
    pub time_s: f64,
    /// Speed, m/s.
    pub speed_m_s: f64,
    /// Velocity along the (mean) plane's down-dip direction, m/s.
    pub along_dip_velocity_m_s: f64,
    /// Velocity along the (mean) plane's outward normal, m/s.
    pub normal_velocity_m_s: f64,
    /// Along-dip position, m.
    pub along_dip_m: f64,
    /// Height of the centre above its resting height, m.
    pub normal_offset_m: f64,
    /// Position [x, y, z], m.
    pub position_m: [f64; 3],
    /// Angular speed, rad/s.
    pub angular_speed_rad_s: f64,
    /// Kinetic energy, translation + rotation, J.
    pub kinetic_energy_j: f64,
    /// Rotational kinetic energy, J.
    pub rotational_energy_j: f64,
}

/// Energy bookkeeping of the (nominal) run.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, ToSchema)]
pub struct EnergyDto {
    /// Kinetic + potential energy at release (potential zero at the lower end), J.
    pub total_start_j: f64,
    /// Lost in impacts, J.
    pub impacts_j: f64,
    /// Lost to friction, J.
    pub friction_j: f64,
    /// Lost at transitions (start of sliding or rolling, edges), J.
    pub transition_j: f64,
    /// Lost to contact and local damping (rigid block), J.
    pub damping_j: f64,
    /// Elastic energy still in the contact springs at the end (rigid block; else 0), J.
    pub stored_j: f64,
    /// Taken by a scene's barriers, J (omitted when none took any).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub barriers_j: Option<f64>,
    /// KE + PE + stored + losses − total at start, J: negative, energy lost without being
    /// booked; positive, energy created (rounding for the lumped mass; the scheme's error for the
    /// rigid block, warned above its bound).
    pub residual_j: f64,
}

/// An event of the (nominal) run.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct EventDto {
    /// Time, s.
    pub time_s: f64,
    /// impact, slide_start, roll_start, take_off or stop.
    pub kind: String,
    /// Position [x, y, z], m.
    pub position_m: [f64; 3],
    /// Along-dip position, m.
    pub along_dip_m: f64,
    /// Speed before, m/s.
    pub speed_before_m_s: f64,
    /// Speed after, m/s.
    pub speed_after_m_s: f64,
    /// Energy lost in the event, J.
    pub energy_lost_j: f64,
    /// Largest total normal contact force during the contact, N (rigid-block impacts).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub peak_contact_force_n: Option<f64>,
    /// Code of the floor's zone under the event's position (only with `face.zones`): for an
    /// impact, the material whose restitution it used.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub zone: Option<i64>,
}

/// Sampled trajectory: equal-length arrays.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct TrajectoryDto {
    /// Times, s.
    pub time_s: Vec<f64>,
    /// Positions [x, y, z], m.
    pub position_m: Vec<[f64; 3]>,
    /// Along-dip positions, m.
    pub along_dip_m: Vec<f64>,
    /// Heights above the floor along its normal, m.
    pub height_m: Vec<f64>,
    /// Velocities [vx, vy, vz], m/s.
    pub velocity_m_s: Vec<[f64; 3]>,
    /// Speeds, m/s.
    pub speed_m_s: Vec<f64>,
    /// Angular velocities, rad/s.
    pub angular_velocity_rad_s: Vec<[f64; 3]>,
    /// Orientation quaternions [w, x, y, z], body to world (rigid block).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub orientation_wxyz: Option<Vec<[f64; 4]>>,
    /// Kinetic energies (translation + rotation), J.
    pub kinetic_energy_j: Vec<f64>,
    /// Rotational energies, J.
    pub rotational_energy_j: Vec<f64>,
    /// Potential energies (zero at the lower end), J.
    pub potential_energy_j: Vec<f64>,
    /// Energy dissipated so far (impacts, friction, transitions, damping), J.
    pub dissipated_energy_j: Vec<f64>,
}

/// Histogram: 21 edges, 20 equal bins from min to max.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct HistogramDto {
    /// Bin edges.
    pub edges: Vec<f64>,
    /// Counts per bin.
    pub counts: Vec<u64>,
}

/// Summary statistics of one quantity over an ensemble.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct SummaryDto {
    /// Mean.
    pub mean: f64,
    /// Sample standard deviation (N − 1); null for one value.
    pub std: Option<f64>,
    /// Minimum.
    pub min: f64,
    /// 5th percentile (Hyndman–Fan type 7).
    pub p05: f64,
    /// Median.
    pub p50: f64,
    /// 95th percentile.
    pub p95: f64,
    /// 99th percentile.
    pub p99: f64,
    /// Maximum.
    pub max: f64,
    /// Histogram.
    pub histogram: HistogramDto,
}

impl From<&Summary> for SummaryDto {
    fn from(s: &Summary) -> Self {
        Self {
            mean: s.mean,
            std: s.std,
            min: s.min,
            p05: s.p05,
            p50: s.p50,
            p95: s.p95,
            p99: s.p99,
            max: s.max,
            histogram: HistogramDto {
                edges: s.histogram.edges.clone(),
                counts: s.histogram.counts.clone(),
            },
        }
    }
}

/// Monte Carlo statistics.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct StatisticsDto {
    /// Number of runs.
    pub runs: u64,
    /// Seed.
    pub seed: u64,
    /// Fraction of runs that reached the lower end.
    pub reached_fraction: f64,
    /// Arrival speed over the runs that reached the lower end (null if none did), m/s.
    pub speed_m_s: Option<SummaryDto>,
    /// Arrival down-dip velocity over the runs that reached the lower end (null if none did),
    /// m/s.
    pub along_dip_velocity_m_s: Option<SummaryDto>,
    /// Arrival kinetic energy over the runs that reached the lower end, J.
    pub kinetic_energy_j: Option<SummaryDto>,
    /// Arrival time over the runs that reached the lower end, s.
    pub time_s: Option<SummaryDto>,
    /// Number of impacts over all runs.
    pub impact_count: SummaryDto,
    /// Final along-dip position minus the release's, over all runs, m.
    pub runout_m: SummaryDto,
    /// Largest bounce height over all runs, m.
    pub max_bounce_height_m: SummaryDto,
    /// What `monte_carlo.target` gave: the runs used, whether the target was met.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub target: Option<crate::http::dto::target::ArrivalTargetOutcomeDto>,
}

/// What the rigid-block method reports besides the common outputs.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct RigidBlockOutDto {
    /// Time step used, s.
    pub time_step_s: f64,
    /// Critical time step Δt_crit, s.
    pub critical_time_step_s: f64,
    /// Time steps of the nominal run (closed-form free flights count as none).
    pub steps: u64,
    /// Block mass, kg.
    pub mass_kg: f64,
    /// Principal moments of inertia, ascending, kg·m².
    pub principal_inertia_kg_m2: [f64; 3],
}

/// Result of a migration.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct MigrationResponse {
    /// The method run.
    pub method: MethodDto,
    /// Rock mass, kg.
    pub mass_kg: f64,
    /// State at the end of the (nominal) run.
    pub arrival: ArrivalDto,
    /// Number of impacts.
    pub impact_count: u64,
    /// Where the ground phase (slide or roll) began, m (null: it never did).
    pub slide_start_along_dip_m: Option<f64>,
    /// Where the rock stopped, m (null: it did not stop).
    pub stop_along_dip_m: Option<f64>,
    /// Largest apex above the struck floor after the first impact, m: only apexes the rock reached
    /// before its flight or run ended (a flight cut short by the lower end has none).
    pub max_bounce_height_m: f64,
    /// Energy bookkeeping.
    pub energy: EnergyDto,
    /// Events of the (nominal) run (when `output.events`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub events: Option<Vec<EventDto>>,
    /// Sampled trajectory (when `output.trajectory`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub trajectory: Option<TrajectoryDto>,
    /// Monte Carlo statistics.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub statistics: Option<StatisticsDto>,
    /// Per-run summaries as CSV (when `output.runs_csv`), one line per run from run 0:
    /// `run,time_s,speed_m_s,kinetic_energy_j,impact_count,runout_m,max_bounce_height_m,stop_reason,along_dip_velocity_m_s`;
    /// in a scene then `support,column_index,impact_velocity_m_s,max_force_n,absorbed_energy_j,stress_utilisation,capacity_exceeded`
    /// (empty when no support was reached); then, in both,
    /// `release_along_dip_m,release_across_m` (the release point as drawn: the floor point under
    /// the rock; a scene draws it in its release zones and across distribution),
    /// `side_length_m,density_kg_m3` (the rock as drawn; the request's when nothing is drawn),
    /// `stop_along_dip_m,stop_across_m` (where the run ended: the rock's centre projected on the
    /// face; the lumped mass's point), `translational_energy_j,rotational_energy_j` (kinetic
    /// energy there, J; at a support, on reaching it); in a scene last `passing_height_m` (the
    /// height of the rock's lowest point above the floor on reaching the support, m; empty when
    /// none was reached). The lumped mass's runout is `stop_along_dip_m − release_along_dip_m`
    /// on a plane floor; the rigid block's is measured from its centre at release (on a plane
    /// drop_height·sin θ up the dip of the floor point). Numbers in shortest round-trip form.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub runs_csv: Option<String>,
    /// Time step, steps and mass properties (rigid block).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rigid_block: Option<RigidBlockOutDto>,
    /// Per-cell maps of the ensemble (when `output.maps`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub maps: Option<super::super::maps::MapsOutDto>,
    /// Both methods on the case, whether they agree and, where not, why (when
    /// `output.compare_methods`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub method_comparison: Option<super::MethodComparisonDto>,
    /// Named warnings, among them `release_moved` (the rigid block overhung the floor's edge at
    /// the release point and was placed where every corner is over the floor: by how much) and
    /// `left_floor` (the run left the floor: where, and past which boundary).
    pub warnings: Vec<Warning>,
    /// Stages run or skipped.
    pub plan: Vec<PlanStep>,
    /// The fully resolved request.
    pub inputs: MigrationRequest,
    /// Version of the service and its models.
    pub model_version: String,
}

fn phase_name(p: Phase) -> &'static str {
    match p {
        Phase::Flight => "flight",
        Phase::Slide => "slide",
        Phase::Roll => "roll",
        Phase::Stopped => "stopped",
    }
}

fn event_name(k: EventKind) -> &'static str {
    match k {
        EventKind::Impact => "impact",
        EventKind::SlideStart => "slide_start",
        EventKind::RollStart => "roll_start",
        EventKind::TakeOff => "take_off",
        EventKind::Stop => "stop",
        EventKind::Barrier => "barrier",
    }
}

/// The api.md name of a stop reason.
#[must_use]
pub fn stop_name(s: StopReason) -> &'static str {
    match s {
        StopReason::LowerEnd => "lower_end",
        StopReason::AtRest => "at_rest",
        StopReason::EndTime => "end_time",
        StopReason::LeftFloor => "left_floor",
        StopReason::Support => "support",
        StopReason::Barrier => "barrier",
    }
}

/// Header of api.md's per-run CSV columns (the first columns of every runs CSV).
pub const RUNS_CSV_HEADER: &str = "run,time_s,speed_m_s,kinetic_energy_j,impact_count,runout_m,max_bounce_height_m,stop_reason,along_dip_velocity_m_s";

/// Header of the columns every runs CSV (migration and scene) appends after its documented ones:
/// the release point as drawn (along the dip and across, m), the rock's side length (m) and
/// density (kg/m³) as drawn (the case's when nothing is drawn), where the run ended (the rock's
/// centre projected on the face, m) and the translational and rotational kinetic energy there
/// (J; at a support, when reaching it).
pub const RUNS_CSV_RUN_COLUMNS: &str = "release_along_dip_m,release_across_m,side_length_m,density_kg_m3,stop_along_dip_m,stop_across_m,translational_energy_j,rotational_energy_j";

/// Run `i`'s values of [`RUNS_CSV_HEADER`]'s columns (no line end).
#[must_use]
pub fn runs_csv_documented_fields(i: usize, r: &RunSummary) -> String {
    format!(
        "{i},{},{},{},{},{},{},{},{}",
        r.time,
        r.speed,
        r.kinetic_energy,
        r.impact_count,
        r.runout,
        r.max_bounce_height,
        stop_name(r.stop_reason),
        r.along_dip_velocity
    )
}

/// A run's values of [`RUNS_CSV_RUN_COLUMNS`] (no leading comma, no line end).
#[must_use]
pub fn runs_csv_run_fields(r: &RunSummary) -> String {
    format!(
        "{},{},{},{},{},{},{},{}",
        r.release_along_dip,
        r.release_across,
        r.side_length,
        r.density,
        r.stop_along_dip,
        r.stop_across,
        r.translational_energy,
        r.rotational_energy
    )
}

/// CSV of per-run summaries: api.md's header, then [`RUNS_CSV_RUN_COLUMNS`]; numbers in
/// shortest round-trip form, runs numbered from 0 (the run index of the random stream).
#[must_use]
pub fn runs_csv(runs: &[RunSummary]) -> String {
    let mut s = format!("{RUNS_CSV_HEADER},{RUNS_CSV_RUN_COLUMNS}\n");
    for (i, r) in runs.iter().enumerate() {
        s.push_str(&runs_csv_documented_fields(i, r));
        s.push(',');
        s.push_str(&runs_csv_run_fields(r));
        s.push('\n');
    }
    s
}

impl MigrationResponse {
    /// Builds the response from the calculation's report and the resolved request.
    pub fn new(report: Report<MigrationResult>, inputs: MigrationRequest) -> Self {
        let Report {
            result: r,
            plan,
            warnings,
        } = report;
        let rigid = r.rigid_block.is_some();
        let mut meta = Meta::new(plan_of(&plan));
        meta.warnings = warnings_of(&warnings);
        if inputs.face.floor.geographic {
            meta.warnings.push(Warning::new(
                "geographic_coordinates",
                "every coordinate of the GeoJSON contours lies within ±180 × ±90 and their \
                 horizontal extent is less than a hundredth of their elevation range: they look \
                 like longitude/latitude (RFC 7946), which are not metres; the floor was taken in \
                 metres as sent. Project it (e.g. to UTM) and give map.origin_m",
            ));
        }
        let a = &r.arrival;
        Self {
            method: if rigid {
                MethodDto::RigidBlock
            } else {
                MethodDto::LumpedMass
            },
            mass_kg: r.mass,
            arrival: ArrivalDto {
                phase: phase_name(a.phase).into(),
                stop_reason: stop_name(a.stop_reason).into(),
                time_s: a.time,
                speed_m_s: a.speed,
                along_dip_velocity_m_s: a.along_dip_velocity,
                normal_velocity_m_s: a.normal_velocity,
                along_dip_m: a.along_dip,
                normal_offset_m: a.normal_offset,
                position_m: a.position,
                angular_speed_rad_s: a.angular_speed,
                kinetic_energy_j: a.kinetic_energy,
                rotational_energy_j: a.rotational_energy,
            },
            impact_count: r.impact_count,
            slide_start_along_dip_m: r.slide_start_along_dip,
            stop_along_dip_m: r.stop_along_dip,
            max_bounce_height_m: r.max_bounce_height,
            energy: EnergyDto {
                total_start_j: r.energy.total_start,
                impacts_j: r.energy.impacts,
                friction_j: r.energy.friction,
                transition_j: r.energy.transition,
                damping_j: r.energy.damping,
                stored_j: r.energy.stored,
                barriers_j: (r.energy.barriers != 0.0).then_some(r.energy.barriers),
                residual_j: r.energy.residual,
            },
            events: r.events.map(|ev| {
                ev.iter()
                    .map(|e| EventDto {
                        time_s: e.time,
                        kind: event_name(e.kind).into(),
                        position_m: e.position,
                        along_dip_m: e.along_dip,
                        speed_before_m_s: e.speed_before,
                        speed_after_m_s: e.speed_after,
                        energy_lost_j: e.energy_lost,
                        peak_contact_force_n: e.peak_contact_force,
                        zone: e.zone,
                    })
                    .collect()
            }),
            trajectory: r.trajectory.map(|t| TrajectoryDto {
                time_s: t.time,
                position_m: t.position,
                along_dip_m: t.along_dip,
                height_m: t.height,
                velocity_m_s: t.velocity,
                speed_m_s: t.speed,
                angular_velocity_rad_s: t.angular_velocity,
                orientation_wxyz: (!t.orientation.is_empty()).then_some(t.orientation),
                kinetic_energy_j: t.kinetic_energy,
                rotational_energy_j: t.rotational_energy,
                potential_energy_j: t.potential_energy,
                dissipated_energy_j: t.dissipated_energy,
            }),
            statistics: r.statistics.as_ref().map(|s| StatisticsDto {
                runs: s.runs,
                seed: s.seed,
                reached_fraction: s.reached_fraction,
                speed_m_s: s.speed.as_ref().map(Into::into),
                along_dip_velocity_m_s: s.along_dip_velocity.as_ref().map(Into::into),
                kinetic_energy_j: s.kinetic_energy.as_ref().map(Into::into),
                time_s: s.time.as_ref().map(Into::into),
                impact_count: (&s.impact_count).into(),
                runout_m: (&s.runout).into(),
                max_bounce_height_m: (&s.max_bounce_height).into(),
                target: s.target.as_ref().map(Into::into),
            }),
            runs_csv: r.runs.as_deref().map(runs_csv),
            rigid_block: r.rigid_block.map(|b| RigidBlockOutDto {
                time_step_s: b.time_step,
                critical_time_step_s: b.critical_time_step,
                steps: b.steps,
                mass_kg: b.mass,
                principal_inertia_kg_m2: b.principal_inertia,
            }),
            maps: r.maps.as_ref().map(Into::into),
            method_comparison: r.comparison.as_ref().map(Into::into),
            warnings: meta.warnings,
            plan: meta.plan,
            inputs,
            model_version: meta.model_version,
        }
    }
}
