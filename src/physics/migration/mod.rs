//! Rockfall migration down the face (physics.md §C, api.md `POST /v1/migration`).
//!
//! [`run`] is the single entry: it builds the floor, runs the nominal trajectory (with events and
//! a sampled trajectory when asked) and, with [`MigrationCase::monte_carlo`], a seeded ensemble
//! with its statistics. Only the lumped-mass energy tracking method exists so far; the rigid-block
//! DEM (physics.md §C.3) is named in [`Method`] so that it can be added beside it.
//!
//! Coordinates (api.md): x horizontal down-dip, y along strike, z up; the plane floor is
//! z = −x tan θ; `along_dip` is measured in the face's mean plane from its upper end; potential
//! energy is m g (z − z_end) with z_end the mean plane's height at `along_dip` = length.

mod lumped_mass;
pub mod monte_carlo;
mod rigid_block;
pub mod shape;
pub mod stats;
mod terrain;

use std::sync::Arc;

use nalgebra::Vector3;
use rayon::prelude::*;

pub use lumped_mass::{EventKind, MAX_TURN, MIN_REBOUND, Motion, Phase, StopReason};
pub use monte_carlo::Distribution;
pub use rigid_block::{
    ContactModel, FLOOR_MODULUS_PA, FLOOR_POISSON, REST_SPEED_M_S, REST_TIME_S, RigidBlockOptions,
    RigidBlockReport, bounce_restitution,
};
pub use stats::{Histogram, Summary};
pub use terrain::{
    CONTOUR_BYTES_PER_POINT, ContourLine, GRID_BYTES_PER_POINT, MapFrame, contour_points,
    grid_bytes,
};

use self::lumped_mass::{Recording, RunOut, Setup, simulate};
use self::terrain::Floor;
use super::control::Control;
use super::error::{Param, PhysicsError, PhysicsResult};
use super::material::{Rock, RockShape};

/// Migration method.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Method {
    /// Point mass, energy tracking method (physics.md §C.2).
    #[default]
    LumpedMass,
    /// Rigid polyhedral block, DEM (physics.md §C.3); not available yet.
    RigidBlock,
}

/// Floor of the face.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum FloorSpec {
    /// The plane z = −x tan θ (from `dip_deg` and `length_m`).
    #[default]
    Plane,
    /// Height grid: `heights[i][j]` is z at (x₀ + j d, y₀ + i d), m; NaN marks a node without
    /// data (the facets touching it are removed: a hole).
    Grid {
        /// [x₀, y₀], m (default [0, 0]).
        origin: [f64; 2],
        /// Spacing d, m.
        spacing: f64,
        /// Rows of heights, m (row i at y₀ + i d).
        heights: Vec<Vec<f64>>,
    },
    /// Contour polylines, resampled at most `resolution` apart and Delaunay-triangulated.
    Contours {
        /// The contour lines.
        contours: Vec<ContourLine>,
        /// Largest spacing of resampled points, m (default 1).
        resolution: f64,
    },
    /// A grid or contour floor given in map coordinates, placed on the face by a rigid transform.
    Mapped {
        /// The floor in map coordinates (a grid or contours).
        floor: Box<FloorSpec>,
        /// Where the face's origin is and where its down-dip axis points.
        map: MapFrame,
    },
}

/// The working face.
#[derive(Debug, Clone, PartialEq)]
pub struct Face {
    /// Dip θ, degrees (default 45).
    pub dip_deg: f64,
    /// Face length along dip S, m (default 120).
    pub length: f64,
    /// Floor (default plane).
    pub floor: FloorSpec,
    /// Coulomb friction μ (default 0.2).
    pub friction_coefficient: f64,
    /// Normal restitution e_n (default 0.3).
    pub restitution_normal: f64,
    /// Tangential restitution e_t (default 0.8).
    pub restitution_tangential: f64,
}

impl Default for Face {
    fn default() -> Self {
        Self {
            dip_deg: 45.0,
            length: 120.0,
            floor: FloorSpec::Plane,
            friction_coefficient: 0.2,
            restitution_normal: 0.3,
            restitution_tangential: 0.8,
        }
    }
}

/// Where and how the rock is released.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Release {
    /// Vertical lift above the floor point, m (default 3.27).
    pub drop_height: f64,
    /// Along-dip position of the floor point, m (default 0).
    pub along_dip: f64,
    /// Across-face position y of the floor point, m (default 0).
    pub across: f64,
    /// Initial speed along the floor's down-dip direction, m/s (default 0).
    pub speed: f64,
}

impl Default for Release {
    fn default() -> Self {
        Self {
            drop_height: 3.27,
            along_dip: 0.0,
            across: 0.0,
            speed: 0.0,
        }
    }
}

/// Options of the lumped-mass method.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LumpedMassOptions {
    /// Ground motion (default slide).
    pub motion: Motion,
    /// Normal rebound speed below which the ground phase starts, m/s (default 0.5).
    pub stop_normal_speed: f64,
}

impl Default for LumpedMassOptions {
    fn default() -> Self {
        Self {
            motion: Motion::Slide,
            stop_normal_speed: 0.5,
        }
    }
}

/// A seeded Monte Carlo ensemble.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MonteCarlo {
    /// Number of runs (default 200).
    pub runs: u64,
    /// Seed (default 42).
    pub seed: u64,
    /// e_n, drawn at every impact and clipped to [0, 1] (default U[0.2, 0.4]).
    pub restitution_normal: Distribution,
    /// e_t, drawn at every impact after e_n and clipped to [0, 1] (default U[0.7, 0.9]).
    pub restitution_tangential: Distribution,
    /// μ, drawn once per run and clipped to [0, 2], counted in a `friction_clipped` warning
    /// (default: the face's μ for every run).
    pub friction_coefficient: Option<Distribution>,
}

impl Default for MonteCarlo {
    fn default() -> Self {
        Self {
            runs: 200,
            seed: 42,
            restitution_normal: Distribution::Uniform { min: 0.2, max: 0.4 },
            restitution_tangential: Distribution::Uniform { min: 0.7, max: 0.9 },
            friction_coefficient: None,
        }
    }
}

/// What to report besides the arrival.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OutputOptions {
    /// Sample the nominal trajectory (default false).
    pub trajectory: bool,
    /// Sample interval, s (default 0.01).
    pub sample_interval: f64,
    /// Report the nominal run's events (default true).
    pub events: bool,
    /// Per-run summaries and their CSV (Monte Carlo; default false).
    pub runs_csv: bool,
    /// Largest number of trajectory samples (the service's limit, default 1 000 000).
    pub max_samples: usize,
}

impl Default for OutputOptions {
    fn default() -> Self {
        Self {
            trajectory: false,
            sample_interval: 0.01,
            events: true,
            runs_csv: false,
            max_samples: 1_000_000,
        }
    }
}

/// A migration request (api.md `POST /v1/migration`), SI units.
#[derive(Debug, Clone, PartialEq)]
pub struct MigrationCase {
    /// Method (default lumped mass).
    pub method: Method,
    /// Gravity g, m/s² (default 9.81).
    pub gravity: f64,
    /// The face.
    pub face: Face,
    /// The rock (its shape's own mass is used).
    pub rock: Rock,
    /// The release.
    pub release: Release,
    /// Lumped-mass options.
    pub lumped_mass: LumpedMassOptions,
    /// Rigid-block options (contact law, time step, β distribution).
    pub rigid_block: RigidBlockOptions,
    /// Stop at this time instead of the lower end, s (default none).
    pub end_time: Option<f64>,
    /// Monte Carlo ensemble (default none).
    pub monte_carlo: Option<MonteCarlo>,
    /// Output options.
    pub output: OutputOptions,
    /// Largest number of events (flights, impacts, slide pieces) per run (default 1e7).
    pub max_steps_per_run: u64,
    /// Supports that end a run when reached (api.md `POST /v1/scene`; default none).
    pub supports: Vec<SupportStop>,
}

/// A support that ends a run when the rock reaches it (api.md `POST /v1/scene`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SupportStop {
    /// Along-dip position in the mean plane, m.
    pub along_dip: f64,
    /// Across position y of a column's axis in the mean plane, m (None: spans the face).
    pub across: Option<f64>,
    /// Column: distance from the axis at which the rock reaches it (outer radius + the rock's
    /// bounding radius), m.
    pub reach: f64,
}

impl MigrationCase {
    /// Along-dip position where a run ends at the latest (the face length, or the nearest
    /// spanning support at or below the release), m, and that support's index.
    #[must_use]
    pub fn stop_length(&self) -> (f64, Option<usize>) {
        let mut best = (self.face.length, None);
        for (i, s) in self.supports.iter().enumerate() {
            if s.across.is_none()
                && s.along_dip >= self.release.along_dip
                && (s.along_dip < best.0 || (s.along_dip == best.0 && best.1.is_none()))
            {
                best = (s.along_dip, Some(i));
            }
        }
        best
    }
}

/// Impact speed at a support, m/s: spanning, the down-dip velocity; a column, the velocity in the
/// mean plane towards its axis (positive when approaching).
pub(crate) fn support_impact_speed(
    mean: &terrain::MeanPlane,
    stop: &SupportStop,
    p: &Vector3<f64>,
    v: &Vector3<f64>,
) -> f64 {
    let vu = v.dot(&mean.dip_dir());
    match stop.across {
        None => vu,
        Some(y) => {
            let (du, dw) = (stop.along_dip - mean.along(p), y - p.y);
            let d = du.hypot(dw);
            if d > 0.0 {
                (vu * du + v.y * dw) / d
            } else {
                vu.hypot(v.y)
            }
        }
    }
}

/// First time τ in [0, dt] at which a piece p(τ) = p + v τ + ½ a τ² reaches one of the columns
/// (distance in the mean plane from its axis ≤ its reach), and that column's index.
pub(crate) fn first_column_reach(
    mean: &terrain::MeanPlane,
    supports: &[SupportStop],
    p: &Vector3<f64>,
    v: &Vector3<f64>,
    a: &Vector3<f64>,
    dt: f64,
) -> Option<(f64, usize)> {
    let dip = mean.dip_dir();
    let (u0, vu, au) = (mean.along(p), v.dot(&dip), a.dot(&dip));
    let mut best: Option<(f64, usize)> = None;
    for (k, s) in supports.iter().enumerate() {
        let Some(y) = s.across else { continue };
        let (cu, cw) = (u0 - s.along_dip, p.y - y);
        let (bu, bw) = (vu, v.y);
        let (qu, qw) = (0.5 * au, 0.5 * a.y);
        let horizon = best.map_or(dt, |b| b.0);
        // quick rejection: the piece cannot come within reach before `horizon`
        let near =
            cu.hypot(cw) - (bu.hypot(bw) * horizon + qu.hypot(qw) * horizon * horizon) - s.reach;
        if near > 1e-9 * (1.0 + cu.hypot(cw)) {
            continue;
        }
        // |C + B τ + Q τ²|² − R², a quartic in τ (ascending coefficients)
        let r2 = s.reach * s.reach;
        let c = [
            cu * cu + cw * cw - r2,
            2.0 * (bu * cu + bw * cw),
            bu * bu + bw * bw + 2.0 * (qu * cu + qw * cw),
            2.0 * (qu * bu + qw * bw),
            qu * qu + qw * qw,
        ];
        if let Some(t) = first_root_nonpositive(&c, horizon)
            && best.is_none_or(|b| t < b.0)
        {
            best = Some((t, k));
        }
    }
    best
}

fn poly_eval(c: &[f64], t: f64) -> f64 {
    c.iter().rev().fold(0.0, |acc, &x| acc * t + x)
}

/// Real roots of the polynomial `c` (ascending coefficients) in (lo, hi), sorted, found by
/// isolating them between the roots of its derivative (monotone pieces) and bisecting.
fn poly_roots(c: &[f64], lo: f64, hi: f64) -> Vec<f64> {
    if c.len() < 2 {
        return Vec::new();
    }
    let d: Vec<f64> = c
        .iter()
        .enumerate()
        .skip(1)
        .map(|(i, &x)| x * i as f64)
        .collect();
    let mut pts = vec![lo];
    pts.extend(poly_roots(&d, lo, hi));
    pts.push(hi);
    let mut out = Vec::new();
    for w in pts.windows(2) {
        let (a, b) = (w[0], w[1]);
        let (fa, fb) = (poly_eval(c, a), poly_eval(c, b));
        if fa == 0.0 && a > lo {
            out.push(a);
        } else if (fa < 0.0) != (fb < 0.0) && fb != 0.0 {
            out.push(bisect(c, a, b, fa));
        }
    }
    out
}

/// Bisection on a monotone piece [a, b] with f(a) of sign `fa`: the smallest point found where
/// the sign has changed.
fn bisect(c: &[f64], mut a: f64, mut b: f64, fa: f64) -> f64 {
    for _ in 0..200 {
        let m = 0.5 * (a + b);
        if m <= a || m >= b {
            break;
        }
        let fm = poly_eval(c, m);
        if (fm < 0.0) == (fa < 0.0) && fm != 0.0 {
            a = m;
        } else {
            b = m;
        }
    }
    b
}

/// First τ in [0, t1] where the polynomial `c` is ≤ 0, if any.
pub(crate) fn first_root_nonpositive(c: &[f64], t1: f64) -> Option<f64> {
    if poly_eval(c, 0.0) <= 0.0 {
        return Some(0.0);
    }
    if t1.is_nan() || t1 <= 0.0 {
        return None;
    }
    let d: Vec<f64> = c
        .iter()
        .enumerate()
        .skip(1)
        .map(|(i, &x)| x * i as f64)
        .collect();
    let mut pts = vec![0.0];
    pts.extend(poly_roots(&d, 0.0, t1));
    pts.push(t1);
    for w in pts.windows(2) {
        let (a, b) = (w[0], w[1]);
        if poly_eval(c, b) <= 0.0 {
            return Some(bisect(c, a, b, poly_eval(c, a)));
        }
    }
    None
}

impl Default for MigrationCase {
    fn default() -> Self {
        Self {
            method: Method::LumpedMass,
            gravity: 9.81,
            face: Face::default(),
            rock: Rock::default(),
            release: Release::default(),
            lumped_mass: LumpedMassOptions::default(),
            rigid_block: RigidBlockOptions::default(),
            end_time: None,
            monte_carlo: None,
            output: OutputOptions::default(),
            max_steps_per_run: 10_000_000,
            supports: Vec::new(),
        }
    }
}

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
    /// The support reached (index into [`MigrationCase::supports`]) when the run ended there.
    pub support: Option<usize>,
    /// Speed towards the support reached, m/s (see [`SupportStop`]).
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
    /// The support reached (index into [`MigrationCase::supports`]), if the run ended there.
    pub support: Option<usize>,
    /// Speed towards the support reached, m/s (0 when none was).
    pub impact_speed: f64,
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
}

/// A named warning (api.md `warnings`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Warning {
    /// Machine-readable code.
    pub code: &'static str,
    /// Explanation.
    pub message: String,
}

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
}

/// Everything a run needs that does not change between Monte Carlo runs.
struct Prepared {
    floor: Arc<Floor>,
    mass: f64,
    g: f64,
    p0: Vector3<f64>,
    v0: Vector3<f64>,
    on_floor: Option<u32>,
    release_along: f64,
    /// Floor point under the release, m.
    base: Vector3<f64>,
    z_end: f64,
    e0: f64,
}

fn prepare(case: &MigrationCase) -> PhysicsResult<Prepared> {
    prepare_on(case, build_floor(case)?)
}

/// The floor of `case.face`, built once: it depends on the face only, so the runs of an
/// ensemble whose release or rock vary share it (see [`ensemble_run`]).
///
/// Errors: those of building the floor (memory, crossing contours, map origin off the floor).
pub(crate) fn build_floor(case: &MigrationCase) -> PhysicsResult<Arc<Floor>> {
    let face = &case.face;
    let dip = face.dip_deg.to_radians();
    Ok(Arc::new(match &face.floor {
        FloorSpec::Plane => Floor::plane(dip),
        FloorSpec::Grid {
            origin,
            spacing,
            heights,
        } => Floor::grid(dip, *origin, *spacing, heights)?,
        FloorSpec::Contours {
            contours,
            resolution,
        } => Floor::contours(dip, contours, *resolution)?,
        FloorSpec::Mapped { floor, map } => match &**floor {
            FloorSpec::Grid {
                origin,
                spacing,
                heights,
            } => Floor::grid_in_map(dip, *origin, *spacing, heights, map)?,
            FloorSpec::Contours {
                contours,
                resolution,
            } => Floor::contours_in_map(dip, contours, *resolution, map)?,
            _ => {
                return Err(PhysicsError::invalid(
                    Param::FloorMap,
                    0.0,
                    "map coordinates apply to grid and contour floors",
                ));
            }
        },
    }))
}

/// [`prepare`] on a floor built by [`build_floor`] from the same face.
fn prepare_on(case: &MigrationCase, floor: Arc<Floor>) -> PhysicsResult<Prepared> {
    let face = &case.face;
    let rel = &case.release;
    let mean = floor.mean;
    let y = rel.across;
    let (x, facet) = match face.floor {
        FloorSpec::Plane => (rel.along_dip * mean.cos, 0),
        _ => {
            let ext = floor.extent();
            if !(y >= ext[2] && y <= ext[3]) {
                return Err(PhysicsError::invalid(
                    Param::ReleaseAcross,
                    y,
                    format!(
                        "the release must be over the floor: y in [{}, {}] m",
                        ext[2], ext[3]
                    ),
                ));
            }
            let along_at = |x: f64| -> Option<f64> {
                let f = floor.locate(x, y, 0.0, 0.0)?;
                let z = floor.facet_plane(f).z(x, y);
                Some(mean.along(&Vector3::new(x, y, z)))
            };
            let off = || {
                PhysicsError::invalid(
                    Param::ReleaseAlongDip,
                    rel.along_dip,
                    "the release point is not on the floor at this across_m (outside it or over a hole)",
                )
            };
            // the part of the line y = across that lies over the floor (a contour set's hull
            // need not reach its bounding box)
            const SCAN: usize = 4096;
            let xs = |k: usize| ext[0] + (ext[1] - ext[0]) * k as f64 / SCAN as f64;
            let first = (0..=SCAN)
                .find(|&k| along_at(xs(k)).is_some())
                .ok_or_else(off)?;
            let last = (first..=SCAN)
                .rev()
                .find(|&k| along_at(xs(k)).is_some())
                .ok_or_else(off)?;
            let (mut lo, mut hi) = (xs(first), xs(last));
            let (flo, fhi) = (along_at(lo).ok_or_else(off)?, along_at(hi).ok_or_else(off)?);
            if rel.along_dip > fhi {
                return Err(off());
            }
            if rel.along_dip <= flo {
                // above the floor's upper edge at this across_m: start on that edge
                hi = lo;
            }
            // bisection for along = along_dip; None when it meets a point off the floor
            let bisect = |mut lo: f64, mut hi: f64| -> Option<(f64, f64)> {
                for _ in 0..200 {
                    let mid = 0.5 * (lo + hi);
                    if hi == lo || mid <= lo || mid >= hi {
                        break;
                    }
                    match along_at(mid) {
                        Some(a) if a < rel.along_dip => lo = mid,
                        Some(_) => hi = mid,
                        None => return None,
                    }
                }
                Some((lo, hi))
            };
            (lo, hi) = match bisect(lo, hi) {
                Some(b) => b,
                None => {
                    // a hole lies on the line: bisect between the last sample on the floor
                    // before along_dip and the first after it
                    let mut a = None;
                    let mut b = None;
                    for k in first..=last {
                        match along_at(xs(k)) {
                            Some(s) if s < rel.along_dip => a = Some(k),
                            Some(_) => {
                                b = Some(k);
                                break;
                            }
                            None => {}
                        }
                    }
                    let (Some(a), Some(b)) = (a, b) else {
                        return Err(off());
                    };
                    bisect(xs(a), xs(b)).ok_or_else(off)?
                }
            };
            let x = if along_at(hi).is_some_and(|a| a == rel.along_dip) {
                hi
            } else {
                lo
            };
            let f = floor
                .locate(x, y, 1.0, 0.0)
                .or_else(|| floor.locate(x, y, 0.0, 0.0));
            (x, f.ok_or_else(off)?)
        }
    };
    let pl = floor.facet_plane(facet);
    let z_floor = pl.z(x, y);
    // A drop too small to lift the rock by more than a few ulps of its coordinates (down to the
    // subnormal 5e-324 m) releases it on the floor: its flight would end within rounding of its
    // start, where no landing can be resolved.
    let lifted =
        rel.drop_height > 8.0 * f64::EPSILON * (1.0 + x.abs().max(y.abs()).max(z_floor.abs()));
    let drop = if lifted { rel.drop_height } else { 0.0 };
    let p0 = Vector3::new(x, y, z_floor + drop);
    let v0 = pl.down_dip() * rel.speed;
    let g = case.gravity;
    let z_end = mean.z_at(face.length);
    let e0 = 0.5 * rel.speed * rel.speed + g * (p0.z - z_end);
    Ok(Prepared {
        // on the plane the release's along_dip is exact; a floor's is measured
        release_along: match face.floor {
            FloorSpec::Plane => rel.along_dip,
            _ => mean.along(&Vector3::new(x, y, z_floor)),
        },
        base: Vector3::new(x, y, z_floor),
        on_floor: (drop == 0.0).then_some(facet),
        floor,
        mass: case.rock.mass(),
        g,
        p0,
        v0,
        z_end,
        e0,
    })
}

/// Radius of the rolling sphere, m: a sphere's own radius; any other shape rolls as the sphere
/// inscribed in its cube, side_length / 2. Rolling uses a solid sphere's inertia (spin-up ×5/7,
/// KE 0.7 m v²) whatever the radius, so the radius sets only the reported angular speed v / R;
/// a `roll_as_sphere` warning says so for non-spherical rocks.
fn roll_radius(rock: &Rock) -> f64 {
    match rock.shape {
        RockShape::Sphere { radius } => radius,
        _ => rock.side_length / 2.0,
    }
}

fn setup<'a>(case: &'a MigrationCase, pr: &'a Prepared) -> Setup<'a> {
    Setup {
        floor: &pr.floor,
        g: pr.g,
        motion: case.lumped_mass.motion,
        v_stop: case.lumped_mass.stop_normal_speed,
        radius: roll_radius(&case.rock),
        length: case.stop_length().0,
        span_support: case.stop_length().1,
        supports: &case.supports,
        end_time: case.end_time,
        max_steps: case.max_steps_per_run,
        p0: pr.p0,
        v0: pr.v0,
        on_floor: pr.on_floor,
        base: (pr.base, pr.release_along),
    }
}

fn v3(v: &Vector3<f64>) -> [f64; 3] {
    [v.x, v.y, v.z]
}

/// Runs a migration case: the nominal trajectory and, when asked, the Monte Carlo ensemble.
///
/// Errors: `InvalidInput` for a roll with μ < (2/7) tan θ ([`Param::FaceFriction`], or
/// [`Param::DrawnFriction`] when the drawn μ can fall below it), a release off a grid
/// or contour floor, a malformed floor, too many trajectory samples ([`Param::TrajectorySampleInterval`])
/// or the rigid-block method (not available yet); `TooManySteps` past
/// `max_steps_per_run`; `Cancelled`/`TimedOut` from the control.
///
/// # Special cases
/// A drop height of 0 starts the ground phase at once (no impact). A slide with zero acceleration
/// and zero speed is at rest at once. Normal rebounds slower than max(v_stop, [`MIN_REBOUND`])
/// end the bouncing.
///
/// # References
/// physics.md §C.1–C.2; api.md `POST /v1/migration`.
///
/// # Examples
/// ```
/// use gangue::physics::{Control, migration::{run, MigrationCase}};
/// let r = run(&MigrationCase::default(), &Control::unlimited()).unwrap();
/// assert_eq!(r.impact_count, 3);
/// assert!((r.arrival.speed - 36.35233409073599).abs() < 1e-8);
/// ```
pub fn run(case: &MigrationCase, control: &Control) -> PhysicsResult<MigrationResult> {
    let n = case.monte_carlo.map_or(0, |mc| mc.runs);
    let (r, runs) = run_part(case, 0..n, true, control)?;
    let mut r = r.expect("the nominal run was asked for");
    if let Some(mc) = &case.monte_carlo {
        let Ok(()) = attach_ensemble(&mut r, mc, case.output.runs_csv, runs.as_slice());
    }
    Ok(r)
}

/// Runs part of a migration case: the nominal run when `nominal` (its result without ensemble
/// statistics) and the Monte Carlo runs with global indices in `range`, in run order. Run i is
/// seeded by (seed, i) whatever the range, so the runs of any split of 0..runs are the runs of
/// [`run`]; [`attach_ensemble`] makes the statistics from them. The case is checked as by [`run`]
/// whatever the part.
///
/// Errors: as [`run`].
pub fn run_part(
    case: &MigrationCase,
    range: std::ops::Range<u64>,
    nominal: bool,
    control: &Control,
) -> PhysicsResult<(Option<MigrationResult>, Vec<RunSummary>)> {
    if case.method == Method::RigidBlock {
        return rigid_block::run_part(case, range, nominal, control);
    }
    let face = &case.face;
    let dip = face.dip_deg.to_radians();
    let mu_roll = 2.0 / 7.0 * dip.tan();
    if case.lumped_mass.motion == Motion::Roll {
        if face.friction_coefficient < mu_roll {
            return Err(PhysicsError::invalid(
                Param::FaceFriction,
                face.friction_coefficient,
                format!("rolling without slip needs μ ≥ (2/7) tan θ = {mu_roll:.6}"),
            ));
        }
        if let Some(d) = case.monte_carlo.and_then(|m| m.friction_coefficient)
            && d.lower_bound() < mu_roll
        {
            return Err(PhysicsError::invalid(
                Param::DrawnFriction,
                d.lower_bound(),
                format!("rolling without slip needs every drawn μ ≥ (2/7) tan θ = {mu_roll:.6}"),
            ));
        }
    }
    let pr = prepare(case)?;
    let r = if nominal {
        Some(nominal_run(case, &pr, control)?)
    } else {
        None
    };
    let runs = match &case.monte_carlo {
        Some(mc) if !range.is_empty() => ensemble(case, &pr, mc, range, control)?,
        _ => Vec::new(),
    };
    Ok((r, runs))
}

/// The nominal run of a lumped-mass case, without ensemble statistics.
fn nominal_run(
    case: &MigrationCase,
    pr: &Prepared,
    control: &Control,
) -> PhysicsResult<MigrationResult> {
    let face = &case.face;
    let su = setup(case, pr);
    let m = pr.mass;
    let (en, et) = (face.restitution_normal, face.restitution_tangential);
    let mut rec = Recording::default();
    let want_rec = case.output.events || case.output.trajectory;
    let out = simulate(
        &su,
        face.friction_coefficient,
        &mut || (en, et),
        want_rec.then_some(&mut rec),
        Some(control),
    )?;
    let mean = pr.floor.mean;
    let mut warnings = Vec::new();
    let trajectory = if case.output.trajectory {
        Some(sample_trajectory(case, pr, &out, &rec.segments)?)
    } else {
        None
    };
    let arrival = arrival_of(case, pr, &out);
    let (imp, fric, trans) = (out.e_imp * m, out.e_fric * m, out.e_trans * m);
    let pe = m * pr.g * (out.p.z - pr.z_end);
    let total_start = m * pr.e0;
    let residual = arrival.kinetic_energy + pe + imp + fric + trans - total_start;
    if case.lumped_mass.motion == Motion::Roll
        && !matches!(case.rock.shape, RockShape::Sphere { .. })
    {
        warnings.push(Warning {
            code: "roll_as_sphere",
            message: format!(
                "rolling treats the rock as a solid sphere of radius side_length_m / 2 = {} m \
                 (the sphere inscribed in its cube): the motion and energies are a rolling \
                 sphere's whatever the shape, and the radius sets only the angular speed",
                roll_radius(&case.rock)
            ),
        });
    }
    if out.rebound_cutoff {
        warnings.push(Warning {
            code: "rebound_cutoff",
            message: format!(
                "the bounces ended at a normal rebound speed below {MIN_REBOUND:e} m/s (the \
                 stop speed asked for is lower): an infinite series of ever smaller bounces, \
                 whose total flight time is finite, is taken to end there and the rock to slide"
            ),
        });
    }
    if out.reason == StopReason::EndTime && out.undecelerated {
        warnings.push(Warning {
            code: "stop_distance_infinite",
            message: "the rock was still on the floor without deceleration at end_time: it would \
                      not stop, so stop_along_dip_m is null"
                .into(),
        });
    }
    let events = case.output.events.then(|| {
        rec.events
            .iter()
            .map(|e| Event {
                time: e.t,
                kind: e.kind,
                position: v3(&e.p),
                along_dip: mean.along(&e.p),
                speed_before: e.speed_before,
                speed_after: e.speed_after,
                energy_lost: e.lost * m,
                peak_contact_force: None,
            })
            .collect()
    });
    if case.monte_carlo.is_none() {
        control.set_total(1);
        control.add_done(1);
    }
    Ok(MigrationResult {
        method: case.method,
        mass: m,
        arrival,
        impact_count: out.impacts,
        slide_start_along_dip: out.slide_start,
        stop_along_dip: out.stop_along,
        max_bounce_height: out.max_bounce,
        energy: EnergyBudget {
            total_start,
            impacts: imp,
            friction: fric,
            transition: trans,
            damping: 0.0,
            stored: 0.0,
            residual,
        },
        events,
        trajectory,
        runs: None,
        statistics: None,
        warnings,
        rigid_block: None,
    })
}

fn height_above_floor(floor: &Floor, p: &Vector3<f64>, v: &Vector3<f64>) -> f64 {
    floor.locate(p.x, p.y, v.x, v.y).map_or(0.0, |f| {
        let pl = floor.facet_plane(f);
        pl.height(p) * pl.normal().z
    })
}

fn arrival_of(case: &MigrationCase, pr: &Prepared, out: &RunOut) -> Arrival {
    let m = pr.mass;
    let mean = pr.floor.mean;
    let ke = 0.5 * m * out.v.norm_squared() + m * out.e_rot;
    let on_floor = matches!(out.phase, Phase::Slide | Phase::Roll | Phase::Stopped);
    Arrival {
        phase: out.phase,
        stop_reason: out.reason,
        time: out.t,
        speed: robust_norm(&out.v),
        along_dip_velocity: out.v.dot(&mean.dip_dir()),
        normal_velocity: out.v.dot(&mean.normal()),
        along_dip: mean.along(&out.p),
        normal_offset: if on_floor {
            0.0
        } else {
            height_above_floor(&pr.floor, &out.p, &out.v)
        },
        position: v3(&out.p),
        angular_speed: robust_norm(&out.omega),
        kinetic_energy: ke,
        rotational_energy: m * out.e_rot,
        support: out.support,
        impact_speed: out
            .support
            .map(|k| support_impact_speed(&mean, &case.supports[k], &out.p, &out.v)),
    }
}

/// Largest friction coefficient of the face's range [0, 2]; drawn values are clipped to it.
pub(super) const MU_MAX: f64 = 2.0;

/// Euclidean norm without underflow of the squares: a speed of 1e-163 m/s (a subnormal face
/// length) is reported as such, not as 0.
fn robust_norm(v: &Vector3<f64>) -> f64 {
    let m = v.amax();
    if m == 0.0 || !m.is_finite() {
        return v.norm();
    }
    m * (v / m).norm()
}

fn sample_trajectory(
    case: &MigrationCase,
    pr: &Prepared,
    out: &RunOut,
    segs: &[lumped_mass::Segment],
) -> PhysicsResult<Trajectory> {
    let dt = case.output.sample_interval;
    let t_end = out.t;
    let n_grid = (t_end / dt).floor();
    let n = n_grid + 1.0 + if n_grid * dt < t_end { 1.0 } else { 0.0 };
    if n.is_nan() || n > case.output.max_samples as f64 {
        return Err(PhysicsError::invalid(
            Param::TrajectorySampleInterval,
            dt,
            format!(
                "the trajectory of {t_end:.6} s would need {n} samples, more than the limit {}",
                case.output.max_samples
            ),
        ));
    }
    let n = n as usize;
    let m = pr.mass;
    let g = pr.g;
    let mean = pr.floor.mean;
    let mut tr = Trajectory::default();
    let mut k = 0usize;
    for i in 0..n {
        let t = if i + 1 == n { t_end } else { i as f64 * dt };
        while k + 1 < segs.len() && segs[k].t0 + segs[k].dt < t {
            k += 1;
        }
        let (p, v, diss, rot, omega, on_floor) = match segs.get(k) {
            Some(s) => {
                let tau = (t - s.t0).clamp(0.0, s.dt);
                let p = s.p0 + s.v0 * tau + s.a * (0.5 * tau * tau);
                let v = s.v0 + s.a * tau;
                let diss = s.diss0 + s.fric.dot(&(p - s.p0));
                let (rot, om) = match s.rolling {
                    Some(nrm) => (
                        0.2 * v.norm_squared(),
                        nrm.cross(&v) / roll_radius(&case.rock),
                    ),
                    None => s.spin,
                };
                (p, v, diss, rot, om, s.on_floor)
            }
            None => (
                out.p,
                out.v,
                out.e_imp + out.e_fric + out.e_trans,
                out.e_rot,
                out.omega,
                true,
            ),
        };
        let (p, v, diss, rot, omega) = if i + 1 == n {
            (
                out.p,
                out.v,
                out.e_imp + out.e_fric + out.e_trans,
                out.e_rot,
                out.omega,
            )
        } else {
            (p, v, diss, rot, omega)
        };
        let on_floor = if i + 1 == n {
            matches!(out.phase, Phase::Slide | Phase::Roll | Phase::Stopped)
        } else {
            on_floor
        };
        tr.time.push(t);
        tr.position.push(v3(&p));
        tr.along_dip.push(mean.along(&p));
        // invariant: every sample lies on or above the floor, in flight and on the ground (the
        // solver checks events and piece ends; a piece between them is checked here)
        lumped_mass::check_above_floor(&pr.floor, &p, t)?;
        tr.height.push(if on_floor {
            0.0
        } else {
            height_above_floor(&pr.floor, &p, &v)
        });
        tr.velocity.push(v3(&v));
        tr.speed.push(robust_norm(&v));
        tr.angular_velocity.push(v3(&omega));
        tr.kinetic_energy.push(m * (0.5 * v.norm_squared() + rot));
        tr.rotational_energy.push(m * rot);
        tr.potential_energy.push(m * g * (p.z - pr.z_end));
        tr.dissipated_energy.push(m * diss);
    }
    Ok(tr)
}

fn ensemble(
    case: &MigrationCase,
    pr: &Prepared,
    mc: &MonteCarlo,
    range: std::ops::Range<u64>,
    control: &Control,
) -> PhysicsResult<Vec<RunSummary>> {
    const CHUNK: u64 = 256;
    let su = setup(case, pr);
    control.set_total(range.end - range.start);
    let one = |i: u64| lumped_one(case, pr, &su, mc, i, control);
    run_in_chunks(range, CHUNK as usize, control, one)
}

/// Run `i` of a lumped-mass ensemble: μ then (e_n, e_t) at every impact from the run's stream.
fn lumped_one(
    case: &MigrationCase,
    pr: &Prepared,
    su: &Setup<'_>,
    mc: &MonteCarlo,
    i: u64,
    control: &Control,
) -> PhysicsResult<RunSummary> {
    let mean = pr.floor.mean;
    let m = pr.mass;
    let mut rng = monte_carlo::run_stream(mc.seed, i);
    let mu = match &mc.friction_coefficient {
        Some(d) => monte_carlo::sample(d, &mut rng).clamp(0.0, MU_MAX),
        None => case.face.friction_coefficient,
    };
    let mut draw = || {
        let en = monte_carlo::sample(&mc.restitution_normal, &mut rng).clamp(0.0, 1.0);
        let et = monte_carlo::sample(&mc.restitution_tangential, &mut rng).clamp(0.0, 1.0);
        (en, et)
    };
    let o = simulate(su, mu, &mut draw, None, Some(control))?;
    Ok(RunSummary {
        time: o.t,
        speed: robust_norm(&o.v),
        kinetic_energy: m * (0.5 * o.v.norm_squared() + o.e_rot),
        impact_count: o.impacts,
        runout: mean.along(&o.p) - pr.release_along,
        max_bounce_height: o.max_bounce,
        stop_reason: o.reason,
        steps: o.steps,
        along_dip_velocity: o.v.dot(&mean.dip_dir()),
        support: o.support,
        impact_speed: o.support.map_or(0.0, |k| {
            support_impact_speed(&mean, &case.supports[k], &o.p, &o.v)
        }),
    })
}

/// Run `index` of the ensemble `mc` of `case`, alone: the summary `/v1/migration`'s ensemble of
/// the same case gives for that run (same streams). A caller may change the release, the rock or
/// the supports between runs (api.md `POST /v1/scene`), never the face: `floor` is
/// [`build_floor`] of the case's face, built once for all runs.
///
/// Errors: as [`run`].
pub(crate) fn ensemble_run(
    case: &MigrationCase,
    floor: &Arc<Floor>,
    mc: &MonteCarlo,
    index: u64,
    control: &Control,
) -> PhysicsResult<RunSummary> {
    if case.method == Method::RigidBlock {
        return rigid_block::ensemble_run(case, floor, mc, index, control);
    }
    let pr = prepare_on(case, Arc::clone(floor))?;
    let su = setup(case, &pr);
    lumped_one(case, &pr, &su, mc, index, control)
}

/// Runs `one(i)` for the global run indices i in `range` on the thread pool, `chunk` runs at a
/// time, checking `control` before each chunk and reporting progress after it. The summaries are
/// written in place in run order and the first error in run order wins, so the result does not
/// depend on the thread count, nor on how 0..runs is split into ranges (shards). Shared by every
/// migration method's ensemble.
pub(super) fn run_in_chunks(
    range: std::ops::Range<u64>,
    chunk: usize,
    control: &Control,
    one: impl Fn(u64) -> PhysicsResult<RunSummary> + Sync,
) -> PhysicsResult<Vec<RunSummary>> {
    let blank = RunSummary {
        time: 0.0,
        speed: 0.0,
        kinetic_energy: 0.0,
        impact_count: 0,
        runout: 0.0,
        max_bounce_height: 0.0,
        stop_reason: StopReason::AtRest,
        steps: 0,
        along_dip_velocity: 0.0,
        support: None,
        impact_speed: 0.0,
    };
    let mut all = vec![blank; (range.end - range.start) as usize];
    let chunks: Vec<PhysicsResult<()>> = all
        .par_chunks_mut(chunk)
        .enumerate()
        .map(|(c, out)| {
            control.check()?;
            let start = range.start + (c * chunk) as u64;
            for (i, slot) in (start..).zip(out.iter_mut()) {
                *slot = one(i)?;
            }
            control.add_done(out.len() as u64);
            Ok(())
        })
        .collect();
    for c in chunks {
        c?;
    }
    Ok(all)
}

/// Warnings of an ensemble, whatever the method: friction draws clipped to [0, 2] (μ is the first
/// draw of each run's stream), a single run (no standard deviation), no run at the lower end.
pub(super) fn ensemble_warnings(mc: &MonteCarlo, runs: u64, st: &Statistics) -> Vec<Warning> {
    let mut warnings = Vec::new();
    if let Some(d) = &mc.friction_coefficient {
        // μ is the first draw of each run's stream: count the draws outside [0, 2]
        let clipped = (0..mc.runs)
            .filter(|&i| {
                let mu = monte_carlo::sample(d, &mut monte_carlo::run_stream(mc.seed, i));
                !(0.0..=MU_MAX).contains(&mu)
            })
            .count();
        if clipped > 0 {
            warnings.push(Warning {
                code: "friction_clipped",
                message: format!(
                    "{clipped} of {} drawn friction coefficients fell outside [0, 2] and \
                     were clipped to it (a normal distribution has unbounded tails; use \
                     truncated_normal to resample instead)",
                    mc.runs
                ),
            });
        }
    }
    if runs < 2 {
        warnings.push(Warning {
            code: "single_run",
            message: "an ensemble of one run has no sample standard deviation: every \
                      std is null; ask for runs ≥ 2"
                .into(),
        });
    }
    if st.speed.is_none() {
        warnings.push(Warning {
            code: "no_run_reached_lower_end",
            message: "no run reached the lower end: speed, kinetic energy and time \
                      statistics are null"
                .into(),
        });
    }
    warnings
}

/// Number of statistics columns of an ensemble (see [`run_columns`]).
pub const STATISTICS_COLUMNS: usize = 7;

/// The statistics columns of one run, in the order of [`Statistics`]: arrival speed, down-dip
/// velocity, kinetic energy and time (None for a run that did not reach the lower end), impact count, runout, largest
/// bounce height.
#[must_use]
pub fn run_columns(r: &RunSummary) -> [Option<f64>; STATISTICS_COLUMNS] {
    let reached = r.stop_reason == StopReason::LowerEnd;
    [
        reached.then_some(r.speed),
        reached.then_some(r.along_dip_velocity),
        reached.then_some(r.kinetic_energy),
        reached.then_some(r.time),
        Some(r.impact_count as f64),
        Some(r.runout),
        Some(r.max_bounce_height),
    ]
}

/// An ensemble's run records: readable in run order as often as needed (sums are taken in run
/// order, the summation order of the contract), with the order statistics of each column. Held
/// in memory by the service; read from part files by a sharded computation's merge.
pub trait RunRecords {
    /// Error of reading the records (none in memory).
    type Error;
    /// Number of runs.
    fn runs(&self) -> u64;
    /// Calls `f` with every run record in run order.
    fn for_each_run(&self, f: &mut dyn FnMut(&RunSummary)) -> Result<(), Self::Error>;
    /// The values at the 0-based `ranks` (ascending) of column `col` of [`run_columns`] (its
    /// present values only) sorted by `f64::total_cmp`.
    fn order_values(&self, col: usize, ranks: &[u64]) -> Result<Vec<f64>, Self::Error>;
}

impl RunRecords for [RunSummary] {
    type Error = std::convert::Infallible;

    fn runs(&self) -> u64 {
        self.len() as u64
    }

    fn for_each_run(&self, f: &mut dyn FnMut(&RunSummary)) -> Result<(), Self::Error> {
        self.iter().for_each(f);
        Ok(())
    }

    fn order_values(&self, col: usize, ranks: &[u64]) -> Result<Vec<f64>, Self::Error> {
        let mut work: Vec<f64> = self.iter().filter_map(|r| run_columns(r)[col]).collect();
        // selection (O(n)) of the ranks asked for, in ascending order
        let mut start = 0;
        for &k in ranks {
            work[start..].select_nth_unstable_by(k as usize - start, f64::total_cmp);
            start = k as usize + 1;
        }
        Ok(ranks.iter().map(|&k| work[k as usize]).collect())
    }
}

/// Completes a nominal result (from [`run_part`]) with the ensemble's statistics, warnings and,
/// when `runs_csv`, the per-run summaries: two passes over the records in run order and the
/// order statistics of each column. The one way ensemble results are made, whether the records
/// come from threads or from the parts of a sharded computation.
///
/// Errors: those of reading the records.
pub fn attach_ensemble<R: RunRecords + ?Sized>(
    r: &mut MigrationResult,
    mc: &MonteCarlo,
    runs_csv: bool,
    records: &R,
) -> Result<(), R::Error> {
    let st = statistics_of(mc, records)?;
    r.warnings
        .extend(ensemble_warnings(mc, records.runs(), &st));
    if runs_csv {
        let mut runs = Vec::with_capacity(records.runs() as usize);
        records.for_each_run(&mut |x| runs.push(*x))?;
        r.runs = Some(runs);
    }
    r.statistics = Some(st);
    Ok(())
}

fn statistics_of<R: RunRecords + ?Sized>(
    mc: &MonteCarlo,
    records: &R,
) -> Result<Statistics, R::Error> {
    let mut first = [stats::FirstPass::default(); STATISTICS_COLUMNS];
    let mut reached = 0u64;
    records.for_each_run(&mut |r| {
        reached += u64::from(r.stop_reason == StopReason::LowerEnd);
        for (p, x) in first.iter_mut().zip(run_columns(r)) {
            if let Some(x) = x {
                p.push(x);
            }
        }
    })?;
    let mut second = first.map(|p| p.second_pass());
    records.for_each_run(&mut |r| {
        for (p, x) in second.iter_mut().zip(run_columns(r)) {
            if let (Some(p), Some(x)) = (p, x) {
                p.push(x);
            }
        }
    })?;
    let mut summaries = Vec::with_capacity(STATISTICS_COLUMNS);
    for (col, (p, f)) in second.iter().zip(&first).enumerate() {
        summaries.push(match p {
            Some(p) => Some(p.finish(&records.order_values(col, &stats::order_ranks(f.count()))?)),
            None => None,
        });
    }
    let mut s = summaries.into_iter();
    let mut next = || s.next().flatten();
    let n = records.runs();
    let (speed, along_dip_velocity, kinetic_energy, time) = (next(), next(), next(), next());
    let all = "an ensemble has at least one run";
    Ok(Statistics {
        runs: n,
        seed: mc.seed,
        reached_fraction: reached as f64 / n.max(1) as f64,
        speed,
        along_dip_velocity,
        kinetic_energy,
        time,
        impact_count: next().expect(all),
        runout: next().expect(all),
        max_bounce_height: next().expect(all),
    })
}

#[cfg(test)]
mod support_stop_tests {
    //! The column stop: the first time a quadratic piece comes within reach of a column's axis in
    //! the mean plane. Expectation: at the time found the distance equals the reach (to rounding),
    //! and no earlier time of the piece is within reach; without a time, no time of the piece is.
    use super::*;
    use proptest::prelude::*;

    fn dist(mean: &terrain::MeanPlane, s: &SupportStop, p: &Vector3<f64>) -> f64 {
        (mean.along(p) - s.along_dip).hypot(p.y - s.across.unwrap())
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]
        #[test]
        fn the_first_reach_of_a_column_is_the_first_crossing(
            dip in 5.0f64..80.0,
            x in 0.0f64..50.0, y in -3.0f64..3.0, h in 0.0f64..5.0,
            vx in -20.0f64..20.0, vy in -5.0f64..5.0, vz in -20.0f64..20.0,
            flight in any::<bool>(),
            sc in 0.0f64..80.0, yc in -3.0f64..3.0, reach in 0.005f64..3.0,
            dt in 1e-6f64..5.0,
        ) {
            let floor = terrain::Floor::plane(dip.to_radians());
            let mean = floor.mean;
            let p = Vector3::new(x, y, -x * mean.sin / mean.cos + h);
            let v = Vector3::new(vx, vy, vz);
            let a = if flight { Vector3::new(0.0, 0.0, -9.81) } else { mean.dip_dir() * 3.0 };
            let s = SupportStop { along_dip: sc, across: Some(yc), reach };
            let at = |t: f64| p + v * t + a * (0.5 * t * t);
            let found = first_column_reach(&mean, &[s], &p, &v, &a, dt);
            let scale = 1e-9 * (1.0 + reach + (v.norm() + a.norm() * dt) * dt + sc.abs());
            let end = match found {
                Some((t, k)) => {
                    prop_assert_eq!(k, 0);
                    prop_assert!((0.0..=dt).contains(&t));
                    let d = dist(&mean, &s, &at(t));
                    prop_assert!(d <= reach + scale, "distance {} at t {} > reach {}", d, t, reach);
                    if t > 0.0 {
                        prop_assert!(dist(&mean, &s, &p) > reach - scale);
                    }
                    t
                }
                None => dt,
            };
            // before the time found (nothing to sample when reached at once)
            for i in (0..400).filter(|_| end > 0.0) {
                let t = end * f64::from(i) / 400.0;
                let d = dist(&mean, &s, &at(t));
                prop_assert!(d > reach - scale, "within reach at t {} (d {}) before {}", t, d, end);
            }
        }
    }
}
