//! Ensembles that stop when their answer is precise enough: the fixed run counts at which a
//! precision target is checked, and the targets themselves.
//!
//! The checks happen at run counts that depend only on the request (1 000 · 2ᵏ, then the
//! maximum), never on timing, so an ensemble that stops early is still a deterministic function
//! of the request: the same bytes on every machine and thread count.

use super::interval::{Z_95, wilson_interval};
use super::percentile_sorted;
use super::quantile::quantile_interval;

/// Run count of the first precision check.
pub const FIRST_CHECK_RUNS: u64 = 1_000;

/// The run counts at which a target is checked for an ensemble of at most `max_runs` runs:
/// 1 000, 2 000, 4 000, … below `max_runs`, then `max_runs` itself (ascending, at least one).
#[must_use]
pub fn checkpoints(max_runs: u64) -> Vec<u64> {
    let mut out = Vec::new();
    let mut n = FIRST_CHECK_RUNS;
    while n < max_runs {
        out.push(n);
        n = n.saturating_mul(2);
    }
    out.push(max_runs.max(1));
    out
}

/// Half-width of the 95 % Wilson interval of `successes` out of `trials`, as a fraction
/// (`None` without trials).
#[must_use]
pub fn probability_half_width(successes: u64, trials: u64) -> Option<f64> {
    let [lo, hi] = wilson_interval(successes as f64, trials as f64, Z_95)?;
    Some(0.5 * (hi - lo))
}

/// Whether every proportion `successes[i]` / `trials` has a 95 % Wilson interval no wider than
/// ± `half_width` (a fraction). False without trials.
#[must_use]
pub fn probabilities_precise(successes: &[u64], trials: u64, half_width: f64) -> bool {
    successes
        .iter()
        .all(|&s| probability_half_width(s, trials).is_some_and(|h| h <= half_width))
}

/// Relative half-width of the 95 % distribution-free interval of the p-quantile of the
/// ascending `sorted` values: (upper − lower) / 2 divided by |the type-7 percentile|. `None`
/// when a bound does not exist (too few values) or the percentile is 0.
#[must_use]
pub fn percentile_relative_half_width(sorted: &[f64], p: f64) -> Option<f64> {
    let [Some(lo), Some(hi)] = quantile_interval(sorted, p, 0.95) else {
        return None;
    };
    let centre = percentile_sorted(sorted, p).abs();
    (centre > 0.0).then(|| 0.5 * (hi - lo) / centre)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checkpoints_double_from_a_thousand_and_end_at_the_maximum() {
        assert_eq!(checkpoints(200), vec![200]);
        assert_eq!(checkpoints(1_000), vec![1_000]);
        assert_eq!(checkpoints(5_000), vec![1_000, 2_000, 4_000, 5_000]);
        assert_eq!(checkpoints(8_000), vec![1_000, 2_000, 4_000, 8_000]);
        assert_eq!(checkpoints(0), vec![1]);
        let big = checkpoints(u64::MAX);
        assert_eq!(*big.last().unwrap(), u64::MAX);
        assert!(big.windows(2).all(|w| w[0] < w[1]));
    }

    #[test]
    fn wilson_half_width_at_zero_is_the_rule_of_three_over_two() {
        // p̂ = 0: upper bound z²/(n + z²), half of it ≈ 1.92/n
        let h = probability_half_width(0, 10_000).unwrap();
        let z2 = Z_95 * Z_95;
        assert!((h - 0.5 * z2 / (10_000.0 + z2)).abs() < 1e-15);
        assert!(probability_half_width(0, 0).is_none());
        assert!(probabilities_precise(&[0, 10, 20], 10_000, 0.005));
        assert!(!probabilities_precise(&[0, 5_000], 10_000, 0.005)); // ±0.0098 at p̂ = 0.5
        assert!(probabilities_precise(&[], 1, 0.1));
    }

    #[test]
    fn percentile_width_shrinks_like_one_over_root_n() {
        // values i/n, i = 1..n (a uniform sample): the 95 % interval of the median spans about
        // ±1.96·√(p(1 − p)/n) in value, relative to 0.5
        for &n in &[1_000_usize, 4_000, 16_000] {
            let xs: Vec<f64> = (1..=n).map(|i| i as f64 / n as f64).collect();
            let r = percentile_relative_half_width(&xs, 0.5).unwrap();
            let expected = Z_95 * (0.25 / n as f64).sqrt() / 0.5;
            assert!(
                (r / expected - 1.0).abs() < 0.05,
                "n {n}: {r} vs {expected}"
            );
        }
        assert!(percentile_relative_half_width(&[1.0; 10], 0.99).is_none());
        assert!(percentile_relative_half_width(&[0.0; 100], 0.5).is_none());
    }
}
