//! Design values at each support (data collectors): over the runs of an ensemble that reached a
//! support entry, the state of the rock when it reached it — impact speed, kinetic energy
//! (total, translational, rotational) and the height of its lowest point above the floor — each
//! as a summary with its value at the design percentile and a distribution-free 95 % interval of
//! that percentile from order statistics ([`stats::quantile`]).
//!
//! A run ends at the first support it reaches, so the state at the end of a run that stopped at
//! an entry is the state on reaching it. Every run that reached the entry counts, also one past
//! the contact capacity (the arrival does not depend on the column).

use super::SceneRun;
use crate::physics::stats::quantile::quantile_interval_ranks;
use crate::physics::stats::{self, Summary};

/// Default design percentile (api.md `design_percentile`): the 95th.
pub const DESIGN_PERCENTILE: f64 = 0.95;

/// Confidence level of the design value's interval.
pub const DESIGN_CONFIDENCE: f64 = 0.95;

/// Number of design-value columns of a support entry (see [`reach_columns`]).
pub const REACH_COLUMNS: usize = 5;

/// The support entry a run reached (within the contact capacity or not) and its design-value
/// columns, in the order of [`DesignValues`]: impact speed (m/s), kinetic energy (J),
/// translational kinetic energy (J), rotational kinetic energy (J), passing height (m). None
/// when the run reached no support.
#[must_use]
pub fn reach_columns(r: &SceneRun) -> Option<(usize, [f64; REACH_COLUMNS])> {
    let k = r.summary.support?;
    let s = &r.summary;
    Some((
        k,
        [
            s.impact_speed,
            s.kinetic_energy,
            s.translational_energy,
            s.rotational_energy,
            s.passing_height,
        ],
    ))
}

/// One quantity at a support: its summary, its value at the design percentile and the
/// distribution-free 95 % interval of that percentile, in the unit of the quantity.
#[derive(Debug, Clone, PartialEq)]
pub struct DesignValue {
    /// Summary over the runs that reached the entry.
    pub summary: Summary,
    /// The design percentile of the values (type 7, as the summary's percentiles).
    pub value: f64,
    /// Equal-tailed 95 % confidence interval of the design percentile: the order statistics
    /// X₍ₗ₎, X₍ᵤ₎ of [`quantile_interval_ranks`] (binomial, exact coverage ≥ 95 % whatever the
    /// distribution); a side is None when too few runs reached the entry for it.
    pub ci95: [Option<f64>; 2],
}

/// The design values of a support entry over the runs that reached it.
#[derive(Debug, Clone, PartialEq)]
pub struct DesignValues {
    /// The design percentile p, in (0, 1).
    pub percentile: f64,
    /// Impact speed towards the support, m/s.
    pub impact_speed: DesignValue,
    /// Kinetic energy on reaching (translation + rotation), J.
    pub kinetic_energy: DesignValue,
    /// Translational kinetic energy on reaching, J.
    pub translational_energy: DesignValue,
    /// Rotational kinetic energy on reaching, J.
    pub rotational_energy: DesignValue,
    /// Height of the rock's lowest point above the floor on reaching, m.
    pub passing_height: DesignValue,
}

/// The order statistics a design value of `n` values at percentile `p` reads, found once per
/// support entry (the binomial ranks cost a bisection on the CDF each).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DesignRanks {
    /// The 0-based ranks of the sorted column: those of the summary ([`stats::order_ranks`]),
    /// the two around the design percentile and the interval's two, ascending, without repeats.
    /// Empty for n = 0.
    pub all: Vec<u64>,
    /// The interval's 1-based ranks [l, u] ([`quantile_interval_ranks`] at 95 %).
    pub interval: [Option<u64>; 2],
}

/// The ranks [`design_value`] reads for `n` values at percentile `p`.
#[must_use]
pub fn design_ranks(n: u64, p: f64) -> DesignRanks {
    if n == 0 {
        return DesignRanks {
            all: Vec::new(),
            interval: [None, None],
        };
    }
    let interval = quantile_interval_ranks(n, p, DESIGN_CONFIDENCE);
    let mut all = stats::order_ranks(n);
    let lo = ((n - 1) as f64 * p).floor() as u64;
    all.extend([lo.min(n - 1), (lo + 1).min(n - 1)]);
    all.extend(interval.iter().flatten().map(|k| k - 1));
    all.sort_unstable();
    all.dedup();
    DesignRanks { all, interval }
}

/// The design value of a column from its second pass (`pass`, over `n` ≥ 1 values), the ranks
/// `ranks` = [`design_ranks`]`(n, p)` and the values at `ranks.all` of the column sorted by
/// `f64::total_cmp` (same order).
#[must_use]
pub fn design_value(
    pass: &stats::SecondPass,
    n: u64,
    p: f64,
    ranks: &DesignRanks,
    values: &[f64],
) -> DesignValue {
    let at = |k: u64| values[ranks.all.partition_point(|&r| r < k)];
    let summary_values: Vec<f64> = stats::order_ranks(n).into_iter().map(at).collect();
    let h = (n - 1) as f64 * p;
    let lo = h.floor() as u64;
    let value = if lo + 1 >= n {
        at(n - 1)
    } else {
        at(lo) + (h - lo as f64) * (at(lo + 1) - at(lo))
    };
    let [l, u] = ranks.interval;
    DesignValue {
        summary: pass.finish(&summary_values),
        value,
        ci95: [l.map(|k| at(k - 1)), u.map(|k| at(k - 1))],
    }
}

#[cfg(test)]
mod tests {
    //! The design value against a sort of the values: type-7 percentile and the order
    //! statistics at ranks found by summing binomial terms directly.
    use super::*;

    /// P(B ≤ k), B ~ Binomial(n, p), by summing the terms in log space (independent of
    /// statrs; (1 − p)ⁿ alone underflows for n = 400, p = 0.9).
    fn cdf(n: u64, p: f64, k: u64) -> f64 {
        let ln_choose = |j: u64| -> f64 {
            (1..=j)
                .map(|i| ((n - j + i) as f64).ln() - (i as f64).ln())
                .sum()
        };
        (0..=k)
            .map(|j| (ln_choose(j) + j as f64 * p.ln() + (n - j) as f64 * (1.0 - p).ln()).exp())
            .sum()
    }

    #[test]
    fn design_values_match_a_sort_and_binomial_sums() {
        let mut st = 7_u64;
        for &n in &[1_u64, 2, 10, 59, 72, 150, 400] {
            for &p in &[0.5, 0.9, 0.95, 0.99] {
                let xs: Vec<f64> = (0..n)
                    .map(|_| {
                        st = st
                            .wrapping_mul(6_364_136_223_846_793_005)
                            .wrapping_add(1_442_695_040_888_963_407);
                        (st >> 11) as f64 / (1_u64 << 53) as f64 * 10.0
                    })
                    .collect();
                let mut first = stats::FirstPass::default();
                xs.iter().for_each(|&x| first.push(x));
                let mut second = first.second_pass().unwrap();
                xs.iter().for_each(|&x| second.push(x));
                let mut sorted = xs.clone();
                sorted.sort_by(f64::total_cmp);
                let ranks = design_ranks(n, p);
                let values: Vec<f64> = ranks.all.iter().map(|&k| sorted[k as usize]).collect();
                let d = design_value(&second, n, p, &ranks, &values);
                assert_eq!(d.value, stats::percentile_sorted(&sorted, p), "n {n} p {p}");
                assert_eq!(d.summary, stats::summarize(&xs).unwrap());
                // the lower bound: the largest rank l with P(B ≤ l − 1) ≤ 2.5 %
                let l = (1..=n).rev().find(|&l| cdf(n, p, l - 1) <= 0.025 + 1e-12);
                let u = (1..=n).find(|&u| cdf(n, p, u - 1) >= 0.975 - 1e-12);
                assert_eq!(d.ci95[0], l.map(|l| sorted[l as usize - 1]), "n {n} p {p}");
                assert_eq!(d.ci95[1], u.map(|u| sorted[u as usize - 1]), "n {n} p {p}");
                if let [Some(a), Some(b)] = d.ci95 {
                    assert!(a <= d.value && d.value <= b, "n {n} p {p}");
                }
            }
        }
    }
}
