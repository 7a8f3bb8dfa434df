//! The migration case: the face and its floor, the release, the method's options, the Monte Carlo
//! ensemble, the output options and the supports that stop a run (api.md `POST /v1/migration`,
//! `POST /v1/scene`), SI units, with their defaults.

use super::lines::Line;
use super::lumped_mass::Motion;
use super::monte_carlo::Distribution;
use super::rigid_block::RigidBlockOptions;
use super::terrain::{ContourLine, MapFrame, Zones};
use crate::physics::material::Rock;

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
    /// Materials of the floor by zone (default none: one material, the fields above and the
    /// ensemble's and rigid block's own).
    pub zones: Option<Zones>,
}

/// The documented defaults of a migration case (api.md `POST /v1/migration`): the `Default`s
/// below and the request fields' defaults are these constants.
pub mod defaults {
    /// Dip θ, degrees.
    pub const DIP_DEG: f64 = 45.0;
    /// Face length along the dip S, m.
    pub const FACE_LENGTH: f64 = 120.0;
    /// Coulomb friction μ, dimensionless.
    pub const FRICTION_COEFFICIENT: f64 = 0.2;
    /// Normal restitution e_n, dimensionless.
    pub const RESTITUTION_NORMAL: f64 = 0.3;
    /// Tangential restitution e_t, dimensionless.
    pub const RESTITUTION_TANGENTIAL: f64 = 0.8;
    /// Monte Carlo runs.
    pub const RUNS: u64 = 200;
    /// Monte Carlo seed.
    pub const SEED: u64 = 42;
}

impl Default for Face {
    fn default() -> Self {
        Self {
            dip_deg: defaults::DIP_DEG,
            length: defaults::FACE_LENGTH,
            floor: FloorSpec::Plane,
            friction_coefficient: defaults::FRICTION_COEFFICIENT,
            restitution_normal: defaults::RESTITUTION_NORMAL,
            restitution_tangential: defaults::RESTITUTION_TANGENTIAL,
            zones: None,
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
    /// The floor point in plan, [x, y] m, in the floor's own coordinates (map [E, N] on a floor
    /// given in map coordinates), instead of `along_dip` and `across` (default none).
    pub point: Option<[f64; 2]>,
    /// Initial velocity [vx, vy, vz] in the face frame, m/s, instead of `speed` (default none).
    pub velocity: Option<[f64; 3]>,
    /// Rigid block: orientation [w, x, y, z], the unit quaternion turning the block's own axes
    /// (those its shape is given in) into the face frame (default none: resting face-down).
    pub orientation: Option<[f64; 4]>,
    /// Rigid block: initial angular velocity [ωx, ωy, ωz] in the face frame, rad/s (default 0).
    pub angular_velocity: Option<[f64; 3]>,
}

impl Default for Release {
    fn default() -> Self {
        Self {
            drop_height: 3.27,
            along_dip: 0.0,
            across: 0.0,
            speed: 0.0,
            point: None,
            velocity: None,
            orientation: None,
            angular_velocity: None,
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
    /// The release velocity's components [vx, vy, vz] in the face frame, m/s, drawn once per run
    /// from the run's release stream (default: the release's velocity for every run).
    pub release_velocity: Option<[Distribution; 3]>,
    /// Rigid block: a uniformly random orientation per run from the run's release stream
    /// (default false: the release's orientation for every run).
    pub random_orientation: bool,
}

impl Default for MonteCarlo {
    fn default() -> Self {
        Self {
            runs: defaults::RUNS,
            seed: defaults::SEED,
            restitution_normal: Distribution::Uniform { min: 0.2, max: 0.4 },
            restitution_tangential: Distribution::Uniform { min: 0.7, max: 0.9 },
            friction_coefficient: None,
            release_velocity: None,
            random_orientation: false,
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
    /// Per-cell maps of the ensemble on this grid (Monte Carlo; default none: no work spent).
    pub maps: Option<super::maps::MapGrid>,
    /// Run the other method on the same case and say whether the two agree (default false;
    /// see [`super::compare`]).
    pub compare_methods: bool,
}

impl Default for OutputOptions {
    fn default() -> Self {
        Self {
            trajectory: false,
            sample_interval: 0.01,
            events: true,
            runs_csv: false,
            max_samples: 1_000_000,
            maps: None,
            compare_methods: false,
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
    /// Lines across the face, sorted by along-dip position: collectors and barriers
    /// (api.md `POST /v1/scene`; default none; see [`super::lines`]).
    pub lines: Vec<Line>,
    /// Stop the ensemble when a percentile of the arrival speed is precise enough (default
    /// none: every run of `monte_carlo`).
    pub target: Option<ArrivalTarget>,
}

/// When a migration ensemble may stop (api.md `monte_carlo.target`): checked at 1000 · 2^k
/// runs and at `monte_carlo.runs` ([`checkpoints`](crate::physics::stats::precision::checkpoints)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArrivalTarget {
    /// The percentile p of the arrival speed, in (0, 1).
    pub percentile: f64,
    /// Largest half-width of its distribution-free 95 % interval relative to its value.
    pub relative_half_width: f64,
}

/// What a migration ensemble's target gave.
#[derive(Debug, Clone, PartialEq)]
pub struct ArrivalTargetOutcome {
    /// The target asked for.
    pub target: ArrivalTarget,
    /// The relative half-width reached with the runs used (None: too few runs reached the
    /// lower end for the interval, or the percentile is 0).
    pub relative_half_width: Option<f64>,
    /// The relative half-width is within the target.
    pub met: bool,
    /// Runs used.
    pub runs: u64,
    /// Runs allowed (`monte_carlo.runs`).
    pub max_runs: u64,
    /// The run counts checked, in order.
    pub checked_at: Vec<u64>,
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
    /// Along-dip position of the rock at the start, m: the release point lifted vertically by
    /// the drop, s₀ − h sin θ (the mean plane's along-dip coordinate falls by h sin θ for a
    /// vertical lift h). During the drop the rock's along-dip position runs from here to s₀.
    #[must_use]
    pub fn start_along_dip(&self) -> f64 {
        self.release.along_dip - self.release.drop_height * self.face.dip_deg.to_radians().sin()
    }

    /// Along-dip position where a run ends at the latest (the face length, or the nearest
    /// spanning support at or below the rock's start), m, and that support's index.
    ///
    /// A spanning support is reached when the rock's along-dip position passes the support's,
    /// during the drop as after it: supports stand normal to the mean plane and are modelled
    /// without a height (a column is reached by its distance in the mean plane, whatever the
    /// rock's height above the floor), so a rock falling from s₀ − h sin θ to s₀ passes a
    /// spanning support in that interval as it passes a column's axis there.
    #[must_use]
    pub fn stop_length(&self) -> (f64, Option<usize>) {
        let start = self.start_along_dip();
        let mut best = (self.face.length, None);
        for (i, s) in self.supports.iter().enumerate() {
            if s.across.is_none()
                && s.along_dip >= start
                && (s.along_dip < best.0 || (s.along_dip == best.0 && best.1.is_none()))
            {
                best = (s.along_dip, Some(i));
            }
        }
        best
    }
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
            lines: Vec::new(),
            target: None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A spanning support stands in the rock's path from the lifted start s₀ − h sin θ on:
    /// up-slope of it the support is passed by nothing, between it and s₀ it is reached in
    /// the fall, and the nearest such support ends the run.
    #[test]
    fn a_spanning_support_within_the_drop_is_in_the_rock_s_path() {
        for (dip, s0, h) in [
            (37.04, 13.7726, 4.456),
            (45.0, 50.2, 3.27),
            (10.0, 0.5, 0.0),
        ] {
            let mut case = MigrationCase::default();
            case.face.dip_deg = dip;
            case.release.along_dip = s0;
            case.release.drop_height = h;
            let start = s0 - h * f64::to_radians(dip).sin();
            assert!((case.start_along_dip() - start).abs() <= 1e-12 * s0);
            let span = |s: f64| SupportStop {
                along_dip: s,
                across: None,
                reach: 0.0,
            };
            // up-slope of the start: never reached; the face's end ends the run
            case.supports = vec![span(start - 1e-9)];
            assert_eq!(case.stop_length(), (case.face.length, None));
            // in [start, s0] (or at s0 without a drop): reached, before a support below
            let inside = if h > 0.0 { 0.5 * (start + s0) } else { s0 };
            case.supports = vec![span(s0 + 1.0), span(inside), span(start - 1e-9)];
            assert_eq!(case.stop_length(), (inside, Some(1)));
            // a column there does not end the run at its along-dip position
            case.supports[1].across = Some(0.0);
            assert_eq!(case.stop_length(), (s0 + 1.0, Some(0)));
        }
    }
}
