//! What a migration reports: the nominal run's arrival, energy budget, events and sampled
//! trajectory, the per-run summaries and statistics of an ensemble, and its warnings.

use super::Method;
use super::lumped_mass::{EventKind, Phase, StopReason};
use super::rigid_block::RigidBlockReport;
use crate::physics::stats::Summary;

/// State at the end of the nominal run (api.md `arrival`).
#[derive(Debug, Clone, PartialEq)]
pub struct Arrival {
    /// Motion at the end.
    pub phase: Phase,
    /// Why the run ended.
    pub stop_reason: StopReason,
    /// Time since release, s.
    pub time: f64,
    /// Speed, m/s.
    pub speed: f64,
    /// Velocity along the mean plane's down-dip direction, m/s.
    pub along_dip_velocity: f64,
    /// Velocity along the mean plane's outward normal, m/s.
    pub normal_velocity: f64,
    /// Along-dip position, m.
    pub along_dip: f64,
    /// Height above the floor along its normal, m (0 on the floor).
    pub normal_offset: f64,
    /// Position [x, y, z], m.
    pub position: [f64; 3],
    /// Angular speed, rad/s (rolling sphere or its spin in flight; else 0).
    pub angular_speed: f64,
    /// Kinetic energy, translation + rotation, J.
    pub kinetic_energy: f64,
    /// Rotational kinetic energy, J.
    pub rotational_energy: f64,
    /// The support reached (index into [`MigrationCase::supports`](super::MigrationCase::supports)) when the run ended there.
    pub support: Option<usize>,
    /// Speed towards the support reached, m/s (see [`SupportStop`](super::SupportStop)).
    pub impact_speed: Option<f64>,
}

/// Energy budget of the nominal run, J.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EnergyBudget {
    /// Kinetic + potential energy at release, J.
    pub total_start: f64,
    /// Lost in impacts (restitution), J.
    pub impacts: f64,
    /// Work of sliding friction, J.
    pub friction: f64,
    /// Lost at transitions (normal rebound below the stop speed, roll spin-up, edge projection), J.
    pub transition: f64,
    /// Damping (rigid block only; 0 here), J.
    pub damping: f64,
    /// Elastic energy still in the contact springs (rigid block only; 0 here), J.
    pub stored: f64,
    /// Taken by barriers (api.md `POST /v1/scene`), J.
    pub barriers: f64,
    /// KE + PE + losses − total_start at the end, J (rounding only).
    pub residual: f64,
}

/// One event of the nominal run (api.md `events`).
#[derive(Debug, Clone, PartialEq)]
pub struct Event {
    /// Time, s.
    pub time: f64,
    /// Kind.
    pub kind: EventKind,
    /// Position [x, y, z], m.
    pub position: [f64; 3],
    /// Along-dip position, m.
    pub along_dip: f64,
    /// Speed before, m/s.
    pub speed_before: f64,
    /// Speed after, m/s.
    pub speed_after: f64,
    /// Energy lost at the event, J.
    pub energy_lost: f64,
    /// Largest total normal contact force during the contact, N (rigid block impacts).
    pub peak_contact_force: Option<f64>,
    /// Code of the floor's zone under the event's position (None: the floor has no zones).
    pub zone: Option<i64>,
}

/// Trajectory sampled from the closed forms (api.md `trajectory`), equal-length arrays.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Trajectory {
    /// Times, s.
    pub time: Vec<f64>,
    /// Positions [x, y, z], m.
    pub position: Vec<[f64; 3]>,
    /// Along-dip positions, m.
    pub along_dip: Vec<f64>,
    /// Heights above the floor along its normal, m.
    pub height: Vec<f64>,
    /// Velocities, m/s.
    pub velocity: Vec<[f64; 3]>,
    /// Speeds, m/s.
    pub speed: Vec<f64>,
    /// Angular velocities, rad/s (zero for the sliding point mass).
    pub angular_velocity: Vec<[f64; 3]>,
    /// Orientation quaternions [w, x, y, z] body → world (rigid block; empty otherwise).
    pub orientation: Vec<[f64; 4]>,
    /// Kinetic energy, translation + rotation, J.
    pub kinetic_energy: Vec<f64>,
    /// Rotational energy, J.
    pub rotational_energy: Vec<f64>,
    /// Potential energy m g (z − z_end), J.
    pub potential_energy: Vec<f64>,
    /// Energy dissipated so far (impacts, friction, transitions), J.
    pub dissipated_energy: Vec<f64>,
}

/// Summary of one Monte Carlo run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunSummary {
    /// Time at the end, s.
    pub time: f64,
    /// Speed at the end, m/s.
    pub speed: f64,
    /// Kinetic energy at the end (translation + rotation), J.
    pub kinetic_energy: f64,
    /// Number of impacts.
    pub impact_count: u64,
    /// Final along-dip position minus the release's, m.
    pub runout: f64,
    /// Largest apex height after the first impact, m.
    pub max_bounce_height: f64,
    /// Why the run ended.
    pub stop_reason: StopReason,
    /// Closed-form pieces the run took (flights, slide pieces, edge crossings).
    pub steps: u64,
    /// Velocity along the mean plane's down-dip direction at the end, m/s.
    pub along_dip_velocity: f64,
    /// The support reached (index into [`MigrationCase::supports`](super::MigrationCase::supports)), if the run ended there.
    pub support: Option<usize>,
    /// Speed towards the support reached, m/s (0 when none was).
    pub impact_speed: f64,
    /// Along-dip position of the release point as drawn (the floor point under the rock), m.
    pub release_along_dip: f64,
    /// Across-face position y of the release point as drawn, m.
    pub release_across: f64,
    /// The rock's side length as drawn (the case's when not drawn), m.
    pub side_length: f64,
    /// The rock's density as drawn (the case's when not drawn), kg/m³.
    pub density: f64,
    /// Along-dip position of the rock's centre projected on the face where the run ended, m
    /// (lumped mass: its point).
    pub stop_along_dip: f64,
    /// Across-face position y of the rock's centre where the run ended, m.
    pub stop_across: f64,
    /// Translational kinetic energy ½ m v² at the end (at a support: when reaching it), J.
    pub translational_energy: f64,
    /// Rotational kinetic energy at the end, J: the rigid block's ½ ωᵀIω; the lumped mass's
    /// rolling sphere ½ (2/5 m r²) ω² = m v²/5 while it rolls (and the spin it keeps in flight),
    /// 0 while it slides.
    pub rotational_energy: f64,
    /// Height of the rock's lowest point above the floor (along the floor's normal) at the end,
    /// m, never negative (a contact overlap counts as 0): at a support, the height at which the
    /// rock passes its line. The lumped mass's point is its lowest point (0 on the ground).
    pub passing_height: f64,
}

/// Ensemble statistics (api.md `statistics`).
#[derive(Debug, Clone, PartialEq)]
pub struct Statistics {
    /// Number of runs.
    pub runs: u64,
    /// Seed.
    pub seed: u64,
    /// Fraction of runs that reached the lower end.
    pub reached_fraction: f64,
    /// Arrival speed over the runs that reached the lower end, m/s (None if none did).
    pub speed: Option<Summary>,
    /// Arrival down-dip velocity over the runs that reached the lower end, m/s.
    pub along_dip_velocity: Option<Summary>,
    /// Arrival kinetic energy over the runs that reached the lower end, J.
    pub kinetic_energy: Option<Summary>,
    /// Arrival time over the runs that reached the lower end, s.
    pub time: Option<Summary>,
    /// Impact count over all runs.
    pub impact_count: Summary,
    /// Runout over all runs, m.
    pub runout: Summary,
    /// Largest bounce height over all runs, m.
    pub max_bounce_height: Summary,
    /// What the ensemble's target gave (None: no target).
    pub target: Option<super::ArrivalTargetOutcome>,
}

/// A named warning (api.md `warnings`): the one physics warning type.
pub use crate::physics::validity::Warning;

/// Result of a migration.
#[derive(Debug, Clone, PartialEq)]
pub struct MigrationResult {
    /// Method used.
    pub method: Method,
    /// Rock mass, kg.
    pub mass: f64,
    /// End state of the nominal run.
    pub arrival: Arrival,
    /// Impacts of the nominal run.
    pub impact_count: u64,
    /// Along-dip position where the ground phase began, m (None: never on the ground).
    pub slide_start_along_dip: Option<f64>,
    /// Along-dip position where the rock came to rest, m (None: it did not).
    pub stop_along_dip: Option<f64>,
    /// Largest apex height above the struck floor after the first impact, m: only apexes reached
    /// before the flight or the run ended.
    pub max_bounce_height: f64,
    /// Energy budget of the nominal run.
    pub energy: EnergyBudget,
    /// Events of the nominal run (when asked).
    pub events: Option<Vec<Event>>,
    /// Sampled trajectory of the nominal run (when asked).
    pub trajectory: Option<Trajectory>,
    /// Monte Carlo statistics.
    pub statistics: Option<Statistics>,
    /// Per-run summaries (Monte Carlo with `runs_csv`).
    pub runs: Option<Vec<RunSummary>>,
    /// Warnings.
    pub warnings: Vec<Warning>,
    /// Time step, steps and mass properties (rigid block only).
    pub rigid_block: Option<RigidBlockReport>,
    /// Per-cell maps of the ensemble (Monte Carlo with a map grid).
    pub maps: Option<super::maps::Maps>,
    /// Both methods on the case (with `output.compare_methods`).
    pub comparison: Option<super::compare::MethodComparison>,
}
