//! `method_comparison` of a migration answer (`output.compare_methods`): both methods on the
//! case, whether they agree, and where they do not, the documented reason and which to trust.

use serde::Serialize;
use utoipa::ToSchema;

use super::MethodDto;
use crate::physics::migration::Method;
use crate::physics::migration::compare::{
    FloorClass, LARGE_RELIEF, MethodArrival, MethodComparison, REACHED_TOLERANCE, Reason,
    SMOOTH_RELIEF, SPEED_TOLERANCE,
};

/// One method's arrival over the compared runs.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct MethodArrivalDto {
    /// The method.
    pub method: MethodDto,
    /// Runs compared (1 without an ensemble).
    pub runs: u64,
    /// Mean arrival speed of the runs that reached the lower end, m/s (null: none did).
    pub speed_mean_m_s: Option<f64>,
    /// Its 95 % interval, m/s (mean ± 1.96 s/√n; null for a single run).
    pub speed_ci95_m_s: Option<[f64; 2]>,
    /// Share of the runs that reached the lower end.
    pub reached_fraction: f64,
    /// Its Wilson 95 % interval (null for a single run).
    pub reached_ci95: Option<[f64; 2]>,
}

/// Both methods on the case (`output.compare_methods`).
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct MethodComparisonDto {
    /// The requested method's arrival, then the other's (the same case and ensemble).
    pub methods: Vec<MethodArrivalDto>,
    /// (other − requested) / requested mean arrival speed (null: one of them never arrived).
    pub speed_difference: Option<f64>,
    /// The two agree: the mean arrival speeds differ by less than their difference's 95 %
    /// interval or by at most `speed_tolerance`, and the shares reaching the lower end by less
    /// than their combined interval or by at most `reached_tolerance`.
    pub agree: bool,
    /// Relative speed difference within which the methods agree whatever their intervals.
    pub speed_tolerance: f64,
    /// Difference of the shares reaching the lower end within which they agree.
    pub reached_tolerance: f64,
    /// The floor's relief at the rock's scale: RMS height about the least-squares plane of each
    /// 5 m plan tile, m (0 on the plane).
    pub floor_relief_m: f64,
    /// The rock's size: the diameter of the sphere of its volume, m.
    pub rock_size_m: f64,
    /// `plane`; `smooth` (relief below 2 % of the rock's size: survey noise, rounding, a curved
    /// face); `relief_below_rock_size` (below 20 % of it, bumps from trough to crest below
    /// about half the rock); `relief_above_rock_size`.
    pub floor: String,
    /// What the two differ by on this case: `shape` (a smooth floor: the rock's shape and
    /// rotation), `relief_below_rock_size`, `relief_above_rock_size`, or `stopping` (the shares
    /// reaching the lower end differ: how the rock moves decides whether it stops).
    pub reason: String,
    /// Why the two differ on such a floor (or would), and which one to trust for what.
    pub note: String,
}

/// The wire name of a floor class.
fn floor_name(c: FloorClass) -> &'static str {
    match c {
        FloorClass::Plane => "plane",
        FloorClass::Smooth => "smooth",
        FloorClass::ReliefBelowRockSize => "relief_below_rock_size",
        FloorClass::ReliefAboveRockSize => "relief_above_rock_size",
    }
}

/// The wire name of a reason.
fn reason_name(r: Reason) -> &'static str {
    match r {
        Reason::Shape => "shape",
        Reason::ReliefBelowRockSize => "relief_below_rock_size",
        Reason::ReliefAboveRockSize => "relief_above_rock_size",
        Reason::Stopping => "stopping",
    }
}

/// The documented reason the two methods differ for `r` (or would, where they agree), and which
/// to trust for what (VALIDATION.md "The two methods side by side").
fn note(r: Reason, agree: bool) -> String {
    let reason = match r {
        Reason::Shape => format!(
            "On a smooth floor (relief with an RMS below {:.0} % of the rock's size) the two \
             differ only by the rock's shape: the rigid block's corners bounce and it turns and \
             rolls, the lumped mass's bounces follow e_n and e_t and it slides (or rolls as a \
             sphere). Measured on the plane and on survey noise of a centimetre they agree within \
             1-3 % where the rocks run to the lower end. Use either for arrival speeds; the lumped \
             mass for large ensembles (it is thousands of times faster); the rigid block for a \
             block's bounce heights and rotation.",
            100.0 * SMOOTH_RELIEF
        ),
        Reason::ReliefBelowRockSize => format!(
            "The relief is smaller than the rock (an RMS below {:.0} % of its size): the rigid \
             block bridges bumps smaller than itself and touches only their crests, while the \
             lumped mass is a point that lands on every facet (each landing costs the Coulomb \
             impulse of the normal speed it brings). Where they differ, trust the rigid block for \
             the arrival and bounce heights of a block of this size.",
            100.0 * LARGE_RELIEF
        ),
        Reason::ReliefAboveRockSize => "The relief is of the rock's size or larger: bumps, \
             steps and benches deflect both methods, and their paths part where the rock's shape \
             and orientation decide which way it goes (a point mass has neither; a rigid sphere \
             rolls over benches a sliding point loses speed on). Compare ensembles, not single \
             runs; trust the rigid block for a block of known shape, and calibrate the lumped \
             mass's e_n, e_t (POST /v1/calibrate) before using it for statistics here."
            .to_string(),
        Reason::Stopping => "The shares of runs reaching the lower end differ: where rocks come \
             to rest, how the rock moves decides whether it stops. The lumped mass slides with \
             Coulomb friction (or rolls as a sphere with lumped_mass.motion roll); the rigid \
             block slides, tumbles or rolls as its shape lets it, and a sphere or a rounded block \
             rolls on without loss (no rolling resistance is modelled yet), so it runs further. A \
             sliding point is the short side, unsafe for a block that tumbles or rolls: take the \
             rigid block (or the lumped mass with motion roll for round blocks) for runout and \
             reach, and back-analyse field runouts (POST /v1/calibrate) before trusting either."
            .to_string(),
    };
    if agree {
        format!("The two methods agree on this case. {reason}")
    } else {
        format!("The two methods do not agree on this case. {reason}")
    }
}

impl From<&MethodArrival> for MethodArrivalDto {
    fn from(a: &MethodArrival) -> Self {
        Self {
            method: match a.method {
                Method::LumpedMass => MethodDto::LumpedMass,
                Method::RigidBlock => MethodDto::RigidBlock,
            },
            runs: a.runs,
            speed_mean_m_s: a.speed_mean,
            speed_ci95_m_s: a.speed_interval,
            reached_fraction: a.reached_fraction,
            reached_ci95: a.reached_interval,
        }
    }
}

impl From<&MethodComparison> for MethodComparisonDto {
    fn from(c: &MethodComparison) -> Self {
        Self {
            methods: c.methods.iter().map(Into::into).collect(),
            speed_difference: c.speed_difference,
            agree: c.agree,
            speed_tolerance: SPEED_TOLERANCE,
            reached_tolerance: REACHED_TOLERANCE,
            floor_relief_m: c.relief,
            rock_size_m: c.rock_size,
            floor: floor_name(c.floor).into(),
            reason: reason_name(c.reason).into(),
            note: note(c.reason, c.agree),
        }
    }
}
