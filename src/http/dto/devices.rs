//! `POST /v1/scene`: barriers and collectors — lines across the face where a barrier stops or
//! slows the rock and a collector records it — and what each saw over the ensemble.

use serde::{Deserialize, Serialize};
use serde_json::{Value, json};
use utoipa::ToSchema;

use super::common::Checker;
use super::design_values::DesignValueDto;
use crate::http::error::num;
use crate::physics::migration::{Barrier, Line};
use crate::physics::scene::{BarrierStatistics, DesignValues, DeviceStatistics};

/// Most barriers, and most collectors, a scene takes.
pub const MAX_DEVICES: usize = 1000;
/// Largest barrier height, m.
pub const MAX_BARRIER_HEIGHT: f64 = 100.0;
/// Largest barrier energy rating, J.
pub const MAX_BARRIER_RATING: f64 = 1e12;
/// Largest |across| of a line's range, m (as the release across the face).
pub const MAX_ACROSS: f64 = 1000.0;

/// A barrier across the face: a rock reaching its line with its lowest point below the height
/// is stopped when its kinetic energy (translation and rotation) is within the rating, and
/// otherwise passes with the rating taken from its kinetic energy; a rock at or above the height
/// passes untouched. A barrier ends a run as a support does.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct BarrierDto {
    /// Along-dip position of its line, m, in [0, face length].
    #[schema(minimum = 0.0, example = 40.0)]
    pub along_dip_m: f64,
    /// Across range [from, to] it spans, m, each in [−1000, 1000] with from ≤ to (null: the
    /// whole face).
    #[schema(default = json!(null), example = json!([-1.5, 1.5]))]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub across_m: Option<[f64; 2]>,
    /// Height above the floor, m, in (0, 100].
    #[schema(exclusive_minimum = 0.0, maximum = 100.0, example = 1.0)]
    pub height_m: f64,
    /// Energy rating: the kinetic energy it takes, J, in [0, 1e12].
    #[schema(minimum = 0.0, maximum = 1e12, example = 20000.0)]
    pub energy_rating_j: f64,
}

/// A data collector: a line across the face where each run's state is recorded (speed,
/// energies, passing height), changing nothing.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct CollectorDto {
    /// Along-dip position of its line, m, in [0, face length].
    #[schema(minimum = 0.0, example = 30.0)]
    pub along_dip_m: f64,
    /// Across range [from, to] it spans, m, each in [−1000, 1000] with from ≤ to (null: the
    /// whole face).
    #[schema(default = json!(null), example = json!(null))]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub across_m: Option<[f64; 2]>,
}

/// Checks a line's position and range (`at`: its object's pointer); the line when valid.
fn line(at: &str, along: f64, across: Option<[f64; 2]>, length: f64, ck: &mut Checker) -> Line {
    ck.closed(
        &format!("{at}/along_dip_m"),
        along,
        0.0,
        length,
        "m (on the face)",
    );
    if let Some([a, b]) = across {
        let ok = ck.closed(&format!("{at}/across_m/0"), a, -MAX_ACROSS, MAX_ACROSS, "m")
            & ck.closed(&format!("{at}/across_m/1"), b, -MAX_ACROSS, MAX_ACROSS, "m");
        if ok && b < a {
            ck.push(
                format!("{at}/across_m/1"),
                num(b),
                format!("must be at least across_m[0] = {a}"),
            );
        }
    }
    Line {
        along_dip: along,
        across: across.map(|[a, b]| (a, b)),
        barrier: None,
    }
}

/// The barriers and collectors of a scene on a face of `length` (m) as lines, checked: each on
/// the face, its range ordered, a barrier's height in (0, 100] m and rating in [0, 1e12] J, at
/// most 1000 of each, and no two barriers at one position whose ranges overlap.
pub fn resolve_devices(
    barriers: &[BarrierDto],
    collectors: &[CollectorDto],
    length: f64,
    ck: &mut Checker,
) -> (Vec<Line>, Vec<Line>) {
    for (field, n) in [
        ("/barriers", barriers.len()),
        ("/collectors", collectors.len()),
    ] {
        if n > MAX_DEVICES {
            ck.push(
                field,
                json!(n),
                format!("at most {MAX_DEVICES} lines: {n} given"),
            );
            return (Vec::new(), Vec::new());
        }
    }
    let b: Vec<Line> = barriers
        .iter()
        .enumerate()
        .map(|(i, d)| {
            let at = format!("/barriers/{i}");
            let mut l = line(&at, d.along_dip_m, d.across_m, length, ck);
            let ok = ck.open_closed(
                &format!("{at}/height_m"),
                d.height_m,
                0.0,
                MAX_BARRIER_HEIGHT,
                "m",
            ) & ck.closed(
                &format!("{at}/energy_rating_j"),
                d.energy_rating_j,
                0.0,
                MAX_BARRIER_RATING,
                "J",
            );
            if ok {
                l.barrier = Some(Barrier {
                    height: d.height_m,
                    rating: d.energy_rating_j,
                });
            }
            l
        })
        .collect();
    // overlapping barriers: at one position with ranges that share a point (sorted, so each
    // is checked against its neighbours at that position)
    let mut order: Vec<usize> = (0..b.len()).collect();
    order.sort_by(|&i, &j| b[i].along_dip.total_cmp(&b[j].along_dip).then(i.cmp(&j)));
    let range = |l: &Line| l.across.unwrap_or((f64::NEG_INFINITY, f64::INFINITY));
    for (w, &j) in order.iter().enumerate() {
        for &i in order[..w].iter().rev() {
            if b[i].along_dip != b[j].along_dip {
                break;
            }
            let ((a0, a1), (b0, b1)) = (range(&b[i]), range(&b[j]));
            if a0 <= b1 && b0 <= a1 {
                ck.push(
                    format!("/barriers/{j}"),
                    serde_json::to_value(barriers[j]).unwrap_or(Value::Null),
                    format!(
                        "overlaps /barriers/{i} at along_dip_m = {}: barriers at one position \
                         must span separate across ranges",
                        b[j].along_dip
                    ),
                );
                break;
            }
        }
    }
    let c = collectors
        .iter()
        .enumerate()
        .map(|(i, d)| {
            line(
                &format!("/collectors/{i}"),
                d.along_dip_m,
                d.across_m,
                length,
                ck,
            )
        })
        .collect();
    (b, c)
}

/// The rock's state where it reached a line, over the runs that reached it.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct LineValuesDto {
    /// The percentile p of `design_value` (the request's `design_percentile`).
    pub design_percentile: f64,
    /// Speed of the rock's centre, m/s (before a barrier acted).
    pub speed_m_s: DesignValueDto,
    /// Kinetic energy, translation + rotation, J.
    pub kinetic_energy_j: DesignValueDto,
    /// Translational kinetic energy, J.
    pub translational_energy_j: DesignValueDto,
    /// Rotational kinetic energy, J.
    pub rotational_energy_j: DesignValueDto,
    /// Height of the rock's lowest point above the floor at the line, m (the height a barrier
    /// must exceed).
    pub passing_height_m: DesignValueDto,
}

impl From<&DesignValues> for LineValuesDto {
    fn from(d: &DesignValues) -> Self {
        Self {
            design_percentile: d.percentile,
            speed_m_s: (&d.impact_speed).into(),
            kinetic_energy_j: (&d.kinetic_energy).into(),
            translational_energy_j: (&d.translational_energy).into(),
            rotational_energy_j: (&d.rotational_energy).into(),
            passing_height_m: (&d.passing_height).into(),
        }
    }
}

/// What a barrier did over all runs (each share with its Wilson 95 % interval).
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct BarrierOutcomesDto {
    /// Rocks it stopped: kinetic energy within its rating, lowest point below its height.
    pub stopped: super::scene::ProbabilityDto,
    /// Rocks that broke through: past its rating, below its height (warning
    /// `barrier_broken_through`).
    pub broken_through: super::scene::ProbabilityDto,
    /// Rocks that passed over it: lowest point at or above its height.
    pub overtopped: super::scene::ProbabilityDto,
}

impl From<&BarrierStatistics> for BarrierOutcomesDto {
    fn from(b: &BarrierStatistics) -> Self {
        Self {
            stopped: (&b.stopped).into(),
            broken_through: (&b.broken_through).into(),
            overtopped: (&b.overtopped).into(),
        }
    }
}

/// One barrier or collector over the ensemble.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct DeviceStatisticsDto {
    /// Along-dip position of its line, m.
    pub along_dip_m: f64,
    /// Across range, m (null: the whole face).
    pub across_m: Option<[f64; 2]>,
    /// A barrier's height, m (omitted for a collector).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub height_m: Option<f64>,
    /// A barrier's energy rating, J (omitted for a collector).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub energy_rating_j: Option<f64>,
    /// Share of all runs that reached the line within its range.
    pub reached: super::scene::ProbabilityDto,
    /// What a barrier did (omitted for a collector).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub outcomes: Option<BarrierOutcomesDto>,
    /// The rock's state at the line over the runs that reached it (null: none did).
    pub values: Option<LineValuesDto>,
}

impl DeviceStatisticsDto {
    /// The statistics of the device on `line`.
    #[must_use]
    pub fn new(line: &Line, s: &DeviceStatistics) -> Self {
        Self {
            along_dip_m: line.along_dip,
            across_m: line.across.map(|(a, b)| [a, b]),
            height_m: line.barrier.map(|b| b.height),
            energy_rating_j: line.barrier.map(|b| b.rating),
            reached: (&s.reached).into(),
            outcomes: s.barrier.as_ref().map(Into::into),
            values: s.values.as_ref().map(Into::into),
        }
    }
}
