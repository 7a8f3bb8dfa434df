//! `monte_carlo.target` of a scene: stop the ensemble when a statistic is precise enough, and
//! what the target gave (`statistics.target`).

use serde::{Deserialize, Serialize};
use utoipa::ToSchema;

use super::common::Checker;
use crate::physics::scene::target::{SceneTarget, TargetOutcome, TargetStatistic};

/// The statistic a target is set on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, ToSchema)]
#[serde(rename_all = "snake_case")]
pub enum TargetStatisticDto {
    /// The probability that a run overloads some support (`statistics.any_exceeded`).
    AnyExceeded,
    /// Every support's exceedance probability (some design limit, or the capacity): the widest
    /// interval over the supports.
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
