//! `monte_carlo.target` of a scene: stop the ensemble when a statistic is precise enough, and
//! what the target gave (`statistics.target`).

use serde::{Deserialize, Serialize};
use utoipa::ToSchema;

use super::common::Checker;
use crate::physics::migration::{ArrivalTarget, ArrivalTargetOutcome};
use crate::physics::scene::target::{SceneTarget, TargetOutcome, TargetStatistic};

/// The statistic a target is set on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, ToSchema)]
#[serde(rename_all = "snake_case")]
pub enum TargetStatisticDto {
    /// The probability that a run overloads some support (`statistics.any_exceeded`).
    AnyExceeded,
    /// Every probability the answer reports with an interval at a support
    /// (`statistics.supports[i]`): each design limit's exceedance, the overloads, a guard's
    /// `held` and `broken_through`; the widest of them.
    EverySupport,
}

/// Stop the ensemble at the first of 1000, 2000, 4000, … runs (and `runs` last) where the
/// statistic's Wilson 95 % interval has a half-width of at most `half_width`; `runs` is then
/// the most runs allowed. The answer is the ensemble of the runs used, bit for bit.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct SceneTargetDto {
    /// The statistic.
    #[schema(example = "any_exceeded")]
    pub statistic: TargetStatisticDto,
    /// Largest half-width of its Wilson 95 % interval, in (0, 0.5].
    #[schema(exclusive_minimum = 0.0, maximum = 0.5, example = 0.01)]
    pub half_width: f64,
}

impl SceneTargetDto {
    /// The target, its half-width checked (`at`: the object's pointer).
    pub fn resolve(&self, at: &str, ck: &mut Checker) -> Option<SceneTarget> {
        ck.open_closed(&format!("{at}/half_width"), self.half_width, 0.0, 0.5, "")
            .then_some(SceneTarget {
                statistic: match self.statistic {
                    TargetStatisticDto::AnyExceeded => TargetStatistic::AnyExceeded,
                    TargetStatisticDto::EverySupport => TargetStatistic::EverySupport,
                },
                half_width: self.half_width,
            })
    }
}

/// What the ensemble's target gave.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct TargetOutcomeDto {
    /// The target asked for.
    pub target: SceneTargetDto,
    /// The half-width of the statistic's Wilson 95 % interval with the runs used.
    pub half_width: f64,
    /// True when the half-width is within the target (false: every allowed run ran first).
    pub met: bool,
    /// Runs used (the statistics are over these).
    pub runs_used: u64,
    /// Runs allowed (`monte_carlo.runs`).
    pub max_runs: u64,
    /// The run counts at which the target was checked, in order (1000 · 2^k, and `runs`).
    pub checked_at_runs: Vec<u64>,
}

impl From<&TargetOutcome> for TargetOutcomeDto {
    fn from(o: &TargetOutcome) -> Self {
        Self {
            target: SceneTargetDto {
                statistic: match o.target.statistic {
                    TargetStatistic::AnyExceeded => TargetStatisticDto::AnyExceeded,
                    TargetStatistic::EverySupport => TargetStatisticDto::EverySupport,
                },
                half_width: o.target.half_width,
            },
            half_width: o.half_width,
            met: o.met,
            runs_used: o.runs,
            max_runs: o.max_runs,
            checked_at_runs: o.checked_at.clone(),
        }
    }
}

/// Stop a migration ensemble at the first of 1000, 2000, 4000, … runs (and `runs` last) where
/// the distribution-free 95 % interval of the arrival speed's `percentile` (over the runs that
/// reached the lower end) has a half-width of at most `relative_half_width` of its value.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct ArrivalTargetDto {
    /// The percentile p of the arrival speed, in [0.01, 0.99].
    #[schema(minimum = 0.01, maximum = 0.99, example = 0.95)]
    pub percentile: f64,
    /// Largest half-width of its 95 % interval relative to its value, in (0, 1].
    #[schema(exclusive_minimum = 0.0, maximum = 1.0, example = 0.02)]
    pub relative_half_width: f64,
}

impl ArrivalTargetDto {
    /// The target, its fields checked (`at`: the object's pointer).
    pub fn resolve(&self, at: &str, ck: &mut Checker) -> Option<ArrivalTarget> {
        let ok = ck.closed(&format!("{at}/percentile"), self.percentile, 0.01, 0.99, "")
            & ck.open_closed(
                &format!("{at}/relative_half_width"),
                self.relative_half_width,
                0.0,
                1.0,
                "",
            );
        ok.then_some(ArrivalTarget {
            percentile: self.percentile,
            relative_half_width: self.relative_half_width,
        })
    }
}

/// What a migration ensemble's target gave.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct ArrivalTargetOutcomeDto {
    /// The target asked for.
    pub target: ArrivalTargetDto,
    /// The relative half-width reached with the runs used (null: too few runs reached the
    /// lower end for the interval, or the percentile is 0).
    pub relative_half_width: Option<f64>,
    /// True when it is within the target (false: every allowed run ran first).
    pub met: bool,
    /// Runs used (the statistics are over these).
    pub runs_used: u64,
    /// Runs allowed (`monte_carlo.runs`).
    pub max_runs: u64,
    /// The run counts at which the target was checked, in order (1000 · 2^k, and `runs`).
    pub checked_at_runs: Vec<u64>,
}

impl From<&ArrivalTargetOutcome> for ArrivalTargetOutcomeDto {
    fn from(o: &ArrivalTargetOutcome) -> Self {
        Self {
            target: ArrivalTargetDto {
                percentile: o.target.percentile,
                relative_half_width: o.target.relative_half_width,
            },
            relative_half_width: o.relative_half_width,
            met: o.met,
            runs_used: o.runs,
            max_runs: o.max_runs,
            checked_at_runs: o.checked_at.clone(),
        }
    }
}
