//! Ensembles that stop when the answer is precise enough (api.md `POST /v1/scene`,
//! `monte_carlo.target`): the runs are taken in prefixes of fixed sizes — 1000 · 2^k, up to
//! `monte_carlo.runs` ([`checkpoints`](crate::physics::stats::precision::checkpoints)) — and after each the named statistic's Wilson 95 % interval is
//! measured; the ensemble stops at the first prefix where its half-width is at most the one
//! asked for. The prefixes do not depend on the machine or the thread count (run i is seeded by
//! (seed, i) whatever the split), so the answer is the ensemble of that many runs, bit for bit.

use super::{Guard, SceneCase, SceneRun};
use crate::physics::stats::precision::probability_half_width;

/// The statistic a target is set on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TargetStatistic {
    /// The probability that a run overloads some support.
    AnyExceeded,
    /// Every probability the answer reports with an interval at a support entry: each design
    /// limit's exceedance (the capacity among them), the overloads (some limit), a guard's held
    /// and broken-through fractions.
    EverySupport,
}

/// When an ensemble may stop.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SceneTarget {
    /// The statistic.
    pub statistic: TargetStatistic,
    /// Largest half-width of its Wilson 95 % interval (the widest of all the intervals it
    /// covers for [`TargetStatistic::EverySupport`]).
    pub half_width: f64,
}

/// What the target gave.
#[derive(Debug, Clone, PartialEq)]
pub struct TargetOutcome {
    /// The target asked for.
    pub target: SceneTarget,
    /// The half-width reached with the runs used.
    pub half_width: f64,
    /// The half-width is within the target.
    pub met: bool,
    /// Runs used.
    pub runs: u64,
    /// Runs allowed (`monte_carlo.runs`).
    pub max_runs: u64,
    /// The prefixes checked, in order.
    pub checked_at: Vec<u64>,
}

/// Half-width of the Wilson 95 % interval of k successes in n trials (0.5 without trials).
fn half_width(k: u64, n: u64) -> f64 {
    probability_half_width(k, n).unwrap_or(0.5)
}

/// The half-width of `target`'s statistic over `runs` of `case`.
#[must_use]
pub fn measured_half_width(case: &SceneCase, target: &SceneTarget, runs: &[SceneRun]) -> f64 {
    let n = runs.len() as u64;
    match target.statistic {
        TargetStatistic::AnyExceeded => {
            half_width(runs.iter().filter(|r| r.overloaded()).count() as u64, n)
        }
        TargetStatistic::EverySupport => reported_counts(case, runs)
            .into_iter()
            .map(|k| half_width(k, n))
            .fold(0.0, f64::max),
    }
}

/// Every count behind a probability the answer reports with its interval at a support entry
/// of `case` over `runs`: per entry, each active limit's exceedances, the overloads (some
/// limit), and where the entry has a guard, the runs it held and the runs that broke through.
fn reported_counts(case: &SceneCase, runs: &[SceneRun]) -> Vec<u64> {
    let e = case.supports.len();
    let l = case.limits.active().len();
    // per entry: l limits, the overloads, held, broken through
    let w = l + 3;
    let mut c = vec![0u64; e * w];
    for r in runs {
        if let Some(k) = r.summary.support {
            let row = &mut c[k * w..(k + 1) * w];
            for (x, &hit) in row.iter_mut().zip(&r.exceeded) {
                *x += u64::from(hit);
            }
            row[l] += u64::from(r.overloaded());
            row[l + 1] += u64::from(r.guard == Guard::Held);
            row[l + 2] += u64::from(r.guard == Guard::BrokenThrough);
        }
    }
    let guarded = |k: usize| case.guards.get(k).copied().flatten().is_some();
    c.chunks(w)
        .enumerate()
        .flat_map(|(k, row)| {
            let n = if guarded(k) { w } else { l + 1 };
            row[..n].to_vec()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::stats::interval::Z_95;

    #[test]
    fn the_half_width_is_the_wilson_intervals() {
        // 0 of 1000: [0, z²/(n + z²)]
        let z2 = Z_95 * Z_95;
        assert!((half_width(0, 1000) - 0.5 * z2 / (1000.0 + z2)).abs() < 1e-15);
        // symmetric at one half, about z/(2√n) wide
        let h = half_width(5000, 10_000);
        assert!((h - Z_95 * 0.5 / 100.0).abs() < 1e-4, "{h}");
        assert_eq!(half_width(0, 0), 0.5);
    }
}
