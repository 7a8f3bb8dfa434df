//! Distribution-free confidence intervals of a quantile from order statistics.
//!
//! For n independent draws of a continuous quantity with p-quantile ξₚ, the number B of draws
//! below ξₚ is Binomial(n, p), so P(X₍ₗ₎ ≤ ξₚ ≤ X₍ᵤ₎) = P(l ≤ B ≤ u − 1) whatever the
//! distribution (X₍ₖ₎ is the k-th smallest, 1-based). The ranks are chosen with equal tails:
//! l is the largest rank with P(B ≤ l − 1) ≤ α/2 and u the smallest with
//! P(B ≤ u − 1) ≥ 1 − α/2, so the coverage is at least 1 − α (exactly, not asymptotically).
//!
//! # References
//! W. J. Conover (1999), *Practical Nonparametric Statistics*, 3rd ed., §3.2 (confidence
//! interval for a quantile); G. J. Hahn & W. Q. Meeker (1991), *Statistical Intervals*, §5.2.

use statrs::distribution::{Binomial, DiscreteCDF};

/// 1-based order-statistic ranks `[l, u]` of an equal-tailed confidence interval of the
/// p-quantile from `n` values at confidence `level` (e.g. 0.95).
///
/// Each bound is `None` when no order statistic achieves its tail: too few values for the
/// level (a lower bound needs P(B = 0) = (1 − p)ⁿ ≤ α/2, an upper one pⁿ ≤ α/2). `None` for
/// both when `n` is 0 or `p`, `level` lie outside (0, 1).
#[must_use]
pub fn quantile_interval_ranks(n: u64, p: f64, level: f64) -> [Option<u64>; 2] {
    if n == 0 || !(p > 0.0 && p < 1.0 && level > 0.0 && level < 1.0) {
        return [None, None];
    }
    let Ok(b) = Binomial::new(p, n) else {
        return [None, None];
    };
    let tail = 0.5 * (1.0 - level);
    // l − 1 = the largest k with P(B ≤ k) ≤ tail; the CDF is non-decreasing, so bisect on k.
    let lower = if b.cdf(0) > tail {
        None
    } else {
        let (mut lo, mut hi) = (0_u64, n); // cdf(lo) ≤ tail < cdf(hi) = 1
        while hi - lo > 1 {
            let mid = lo + (hi - lo) / 2;
            if b.cdf(mid) <= tail {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        Some(lo + 1)
    };
    // u − 1 = the smallest k with P(B ≤ k) ≥ 1 − tail; u ≤ n needs k ≤ n − 1.
    let upper = if b.cdf(n - 1) < 1.0 - tail {
        None
    } else {
        let (mut lo, mut hi) = (0_u64, n - 1); // answer in [0, n − 1], cdf(hi) ≥ 1 − tail
        if b.cdf(0) >= 1.0 - tail {
            hi = 0;
        }
        while hi - lo > 1 {
            let mid = lo + (hi - lo) / 2;
            if b.cdf(mid) >= 1.0 - tail {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        Some(hi + 1)
    };
    [lower, upper]
}

/// Equal-tailed distribution-free confidence interval `[lower, upper]` of the p-quantile of
/// the ascending `sorted` values at confidence `level`, in the unit of the data: the order
/// statistics of [`quantile_interval_ranks`], `None` on a side with too few values.
#[must_use]
pub fn quantile_interval(sorted: &[f64], p: f64, level: f64) -> [Option<f64>; 2] {
    let [l, u] = quantile_interval_ranks(sorted.len() as u64, p, level);
    let at = |rank: u64| sorted.get(usize::try_from(rank - 1).ok()?).copied();
    [l.and_then(at), u.and_then(at)]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// P(B ≤ k) for B ~ Binomial(n, p) by direct summation of the probabilities in log space
    /// (an independent implementation of the CDF, for small n).
    fn cdf_by_sum(n: u64, p: f64, k: u64) -> f64 {
        let ln_choose = |n: u64, k: u64| -> f64 {
            (1..=k)
                .map(|i| ((n - k + i) as f64).ln() - (i as f64).ln())
                .sum()
        };
        (0..=k)
            .map(|j| (ln_choose(n, j) + j as f64 * p.ln() + (n - j) as f64 * (1.0 - p).ln()).exp())
            .sum()
    }

    #[test]
    fn ranks_are_the_extreme_ones_with_the_tail_probabilities() {
        for &n in &[1_u64, 5, 20, 59, 100, 299, 500] {
            for &p in &[0.05, 0.5, 0.9, 0.95, 0.99] {
                let [l, u] = quantile_interval_ranks(n, p, 0.95);
                let cdf = |k: u64| cdf_by_sum(n, p, k);
                match l {
                    Some(l) => {
                        assert!(cdf(l - 1) <= 0.025 + 1e-12, "n {n} p {p} l {l}");
                        assert!(
                            l == n || cdf(l) > 0.025 - 1e-12,
                            "n {n} p {p}: l not largest"
                        );
                    }
                    None => assert!(cdf(0) > 0.025 - 1e-12, "n {n} p {p}: a lower rank exists"),
                }
                match u {
                    Some(u) => {
                        assert!(cdf(u - 1) >= 0.975 - 1e-12, "n {n} p {p} u {u}");
                        assert!(
                            u == 1 || cdf(u - 2) < 0.975 + 1e-12,
                            "n {n} p {p}: u not least"
                        );
                    }
                    None => assert!(
                        cdf(n - 1) < 0.975 + 1e-12,
                        "n {n} p {p}: an upper rank exists"
                    ),
                }
                if let (Some(l), Some(u)) = (l, u) {
                    assert!(l < u);
                    let coverage = cdf(u - 1) - if l >= 1 { cdf(l - 1) } else { 0.0 };
                    assert!(coverage >= 0.95 - 1e-12, "n {n} p {p}: coverage {coverage}");
                }
            }
        }
    }

    #[test]
    fn textbook_values() {
        // Median of 20 values at 95 %: ranks 6 and 15 (Conover 1999, table A3 / P(B ≤ 5) = 0.0207).
        assert_eq!(quantile_interval_ranks(20, 0.5, 0.95), [Some(6), Some(15)]);
        // The 95th percentile needs 59 values for a one-sided 95 % bound by the maximum
        // (0.95^59 = 0.0485 ≤ 0.05); two-sided at 95 % it needs 0.95^n ≤ 0.025, n ≥ 72.
        assert_eq!(quantile_interval_ranks(71, 0.95, 0.95)[1], None);
        assert_eq!(quantile_interval_ranks(72, 0.95, 0.95)[1], Some(72));
    }

    #[test]
    fn coverage_by_simulation_is_at_least_the_level() {
        // uniform draws: ξ₀.₉ = 0.9; count how often the interval of 200 draws covers it
        let mut st = 11_u64;
        let mut next = || {
            st = st
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (st >> 11) as f64 / (1_u64 << 53) as f64
        };
        let trials = 4000;
        let mut covered = 0;
        for _ in 0..trials {
            let mut xs: Vec<f64> = (0..200).map(|_| next()).collect();
            xs.sort_by(f64::total_cmp);
            let [lo, hi] = quantile_interval(&xs, 0.9, 0.95);
            if lo.unwrap() <= 0.9 && 0.9 <= hi.unwrap() {
                covered += 1;
            }
        }
        // exact coverage ≥ 0.95; 4000 trials: standard error 0.0034
        assert!(covered as f64 / trials as f64 > 0.94, "{covered}/{trials}");
    }

    #[test]
    fn degenerate_inputs_have_no_interval() {
        assert_eq!(quantile_interval_ranks(0, 0.5, 0.95), [None, None]);
        assert_eq!(quantile_interval_ranks(10, 0.0, 0.95), [None, None]);
        assert_eq!(quantile_interval_ranks(10, 0.5, 1.0), [None, None]);
        assert_eq!(quantile_interval(&[], 0.5, 0.95), [None, None]);
    }
}
