//! Errors a solver can return; the web layer maps each to a problem type.

use std::fmt;

/// Result of a physics computation.
pub type PhysicsResult<T> = Result<T, PhysicsError>;

/// Why a computation produced no answer.
#[derive(Debug, Clone, PartialEq)]
pub enum PhysicsError {
    /// An input outside the model's validity: `param` names the model parameter at fault (the
    /// web layer maps it to the field of the request actually sent), `value` the offending value.
    InvalidInput {
        /// The parameter at fault.
        param: Param,
        /// The offending value.
        value: f64,
        /// What is wrong and what would be valid.
        message: String,
    },
    /// The impact energy exceeds what the logarithmic contact law can store (G > 1).
    CapacityExceeded {
        /// Dimensionless energy parameter G of the case (> 1).
        energy_parameter: f64,
        /// Largest impact speed the law can take with the other inputs unchanged, m/s.
        max_velocity_m_s: f64,
        /// What happened.
        message: String,
    },
    /// A stepping solver would need more steps than the configured limit.
    TooManySteps {
        /// Estimated number of steps.
        estimated: f64,
        /// The limit in force.
        limit: f64,
    },
    /// The caller cancelled the computation (client gone).
    Cancelled,
    /// The computation passed its time limit.
    TimedOut,
    /// A numerical failure that valid input should never reach (a bug).
    Numerical(String),
}

/// How much longer than its time limit an ensemble's projected run time must be, at the pace
/// of its first runs, before it is refused ([`Control::check_pace`](super::Control::check_pace)).
pub const PACE_FACTOR: f64 = 2.0;

/// A model parameter an error concerns, in physics terms, with the indices that locate it in a
/// list. Physics never names request fields: the web layer maps each parameter to the JSON Pointer
/// of the request actually sent (a standalone request, a batch item, a scene support).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Param {
    /// Impact speed of the rock on the column, m/s.
    ImpactVelocity,
    /// Side length (contact length) of a cube rock, m.
    RockSideLength,
    /// Rock density, kg/m³.
    RockDensity,
    /// Rock Young's modulus, Pa.
    RockElasticModulus,
    /// Rock Poisson ratio.
    RockPoissonRatio,
    /// Number of runs of a Monte Carlo ensemble.
    MonteCarloRuns,
    /// Radius of a sphere rock, m.
    RockRadius,
    /// Rounded-corner radius of a cube rock (point contact), m.
    RockCornerRadius,
    /// Edge lengths of a cuboid rock, m.
    RockDimensions,
    /// Vertices of a polyhedral rock, m.
    RockVertices,
    /// The random polyhedron generator of a rock.
    RockRandomShape,
    /// Number of vertices of a random polyhedral rock.
    RockRandomVertexCount,
    /// Contact radius of the column, m.
    ColumnContactRadius,
    /// Column Young's modulus, Pa.
    ColumnElasticModulus,
    /// Column Poisson ratio.
    ColumnPoissonRatio,
    /// Column yield stress, Pa.
    ColumnYieldStress,
    /// Column length between its clamped ends, m.
    ColumnLength,
    /// Column viscous damping coefficient, N·s/m².
    ColumnDampingCoefficient,
    /// Column damping ratio of mode 1.
    ColumnDampingRatio,
    /// The contact force law.
    ContactLaw,
    /// Number of Galerkin modes.
    GalerkinModes,
    /// Mode-shape variant of the Galerkin modes.
    ModeShapes,
    /// Integration window of the coupled column model, s.
    CoupledWindow,
    /// Initial midpoint displacement of the decoupled column model, m.
    InitialMidpointDisplacement,
    /// The list of column history times.
    HistoryTimes,
    /// Column history time number `.0`, s.
    HistoryTime(usize),
    /// Duration of a uniform column history, s.
    HistoryDuration,
    /// Sample count of a uniform column history.
    HistorySamples,
    /// Sampling interval of a migration trajectory, s.
    TrajectorySampleInterval,
    /// The floor of the face as a whole.
    Floor,
    /// Map coordinates of a floor.
    FloorMap,
    /// Map origin of a floor, m.
    FloorMapOrigin,
    /// The height grid of a floor.
    FloorHeights,
    /// Row `.0` of a floor's height grid.
    FloorHeightRow(usize),
    /// Height at row `.0`, column `.1` of a floor grid, m.
    FloorHeight(usize, usize),
    /// The contour lines of a floor.
    FloorContours,
    /// Point `.1` of contour line `.0`, m.
    FloorContourPoint(usize, usize),
    /// Resampling resolution of a contour floor, m.
    FloorResolution,
    /// Across-face release position, m.
    ReleaseAcross,
    /// Along-dip release position, m.
    ReleaseAlongDip,
    /// Plan point [x, y] of the release, m.
    ReleasePoint,
    /// The release zones of a scene ensemble.
    ReleaseZones,
    /// Rock–floor friction coefficient.
    FaceFriction,
    /// The zone map of a floor of several materials (`face.zones`).
    FaceZones,
    /// The normal contact stiffness of material i of the zone map, N/m.
    ZoneNormalStiffness(usize),
    /// Distribution of the drawn friction coefficient of an ensemble.
    DrawnFriction,
    /// Normal contact stiffness of the floor, N/m.
    FaceNormalStiffness,
    /// Young's modulus of the floor in the rigid block's Hertz contact, Pa.
    FloorElasticModulus,
    /// Time step of the rigid-block integrator, s.
    RigidBlockTimeStep,
}

impl PhysicsError {
    /// Shorthand for [`PhysicsError::InvalidInput`].
    pub fn invalid(param: Param, value: f64, message: impl Into<String>) -> Self {
        Self::InvalidInput {
            param,
            value,
            message: message.into(),
        }
    }
}

impl fmt::Display for PhysicsError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::InvalidInput {
                param,
                value,
                message,
            } => write!(f, "{param:?} = {value}: {message}"),
            Self::CapacityExceeded { message, .. } => f.write_str(message),
            Self::TooManySteps { estimated, limit } => {
                write!(f, "about {estimated:.3e} steps needed, limit {limit:.3e}")
            }
            Self::Cancelled => f.write_str("cancelled"),
            Self::TimedOut => f.write_str("time limit reached"),
            Self::Numerical(m) => write!(f, "numerical failure: {m}"),
        }
    }
}

impl std::error::Error for PhysicsError {}

/// `x` with `digits` significant digits for a message a person reads: plain decimals for
/// 1e-4 ≤ |x| < 1e7 (0.05454154, 2.335413), scientific notation beyond (1.234568e-9).
#[must_use]
pub fn significant(x: f64, digits: usize) -> String {
    let digits = digits.max(1);
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let e = x.abs().log10().floor();
    if (-4.0..7.0).contains(&e) {
        let decimals = (digits as f64 - 1.0 - e).max(0.0) as usize;
        format!("{x:.decimals$}")
    } else {
        let p = digits - 1;
        format!("{x:.p$e}")
    }
}

#[cfg(test)]
mod tests {
    use super::significant;

    #[test]
    fn messages_show_plain_decimals_in_the_everyday_range() {
        assert_eq!(significant(0.05454154012, 7), "0.05454154");
        assert_eq!(significant(2.3354127, 7), "2.335413");
        assert_eq!(significant(995_000.0, 3), "995000");
        assert_eq!(significant(-12.5, 3), "-12.5");
        assert_eq!(significant(1.2345678e-9, 7), "1.234568e-9");
        assert_eq!(significant(3.0e12, 2), "3.0e12");
        assert_eq!(significant(0.0, 7), "0");
    }
}
