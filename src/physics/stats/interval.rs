//! Binomial confidence intervals: the Wilson score interval, which stays inside [0, 1] and is
//! defined for fractional counts (Table 1 prints A∩C counts such as 4.5).

/// Two-sided 95 % standard normal quantile z = Φ⁻¹(0.975) (mpmath, 20 digits).
#[allow(clippy::excessive_precision)] // mpmath digits kept as computed
pub const Z_95: f64 = 1.959_963_984_540_054_2;

/// Wilson score interval of a proportion `successes`/`trials` at normal quantile `z`, as
/// fractions in [0, 1]: `None` when `trials` is 0 (no observation, no interval).
///
/// centre = (p̂ + z²/(2n)) / (1 + z²/n), half-width = z/(1 + z²/n) · √(p̂(1 − p̂)/n + z²/(4n²)).
/// Counts may be fractional; `successes` must lie in [0, `trials`].
///
/// # Examples
/// ```
/// use gangue::physics::stats::interval::{wilson_interval, Z_95};
/// let [lo, hi] = wilson_interval(5.0, 8.0, Z_95).unwrap();
/// assert!((lo - 0.305_742_394_603).abs() < 1e-12 && (hi - 0.863_155_714_176).abs() < 1e-12);
/// assert!(wilson_interval(0.0, 0.0, Z_95).is_none());
/// ```
///
/// # Special cases
/// * `successes = 0`: lower bound exactly 0; `successes = trials`: upper bound exactly 1.
/// * `trials = 0` or a non-finite input: `None`.
///
/// # References
/// E. B. Wilson (1927), "Probable inference, the law of succession, and statistical inference",
/// J. Am. Stat. Assoc. 22(158), 209–212, doi:10.1080/01621459.1927.10502953.
#[must_use]
pub fn wilson_interval(successes: f64, trials: f64, z: f64) -> Option<[f64; 2]> {
    if !(trials > 0.0 && trials.is_finite() && successes.is_finite() && z.is_finite()) {
        return None;
    }
    let p = (successes / trials).clamp(0.0, 1.0);
    let z2n = z * z / trials;
    let denom = 1.0 + z2n;
    let centre = (p + 0.5 * z2n) / denom;
    let half = z / denom * (p * (1.0 - p) / trials + 0.25 * z2n / trials).sqrt();
    // At p = 0 (or 1) the bound is exactly 0 (or 1) analytically; keep it so in floating point.
    let lo = if p == 0.0 {
        0.0
    } else {
        (centre - half).max(0.0)
    };
    let hi = if p == 1.0 {
        1.0
    } else {
        (centre + half).min(1.0)
    };
    Some([lo, hi])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Independent form: the interval's bounds are the roots in p of (p̂ − p)² = z² p(1 − p)/n.
    #[test]
    fn bounds_solve_the_score_equation() {
        for &(x, n) in &[
            (5.0, 8.0),
            (32.0, 65.0),
            (4.5, 22.0),
            (1.0, 1000.0),
            (17.0, 47.0),
        ] {
            let [lo, hi] = wilson_interval(x, n, Z_95).unwrap();
            let ph = x / n;
            for p in [lo, hi] {
                let lhs = (ph - p) * (ph - p);
                let rhs = Z_95 * Z_95 * p * (1.0 - p) / n;
                assert!(
                    (lhs - rhs).abs() <= 1e-14 * rhs.max(1e-300),
                    "{x}/{n}: {lhs} {rhs}"
                );
            }
            assert!(lo < ph && ph < hi);
        }
    }

    #[test]
    fn extremes_stay_in_the_unit_interval() {
        assert_eq!(wilson_interval(0.0, 10.0, Z_95).unwrap()[0], 0.0);
        assert_eq!(wilson_interval(10.0, 10.0, Z_95).unwrap()[1], 1.0);
        let [lo, hi] = wilson_interval(1e-9, 1e12, Z_95).unwrap();
        assert!((0.0..=1.0).contains(&lo) && (0.0..=1.0).contains(&hi) && lo <= hi);
        assert!(wilson_interval(1.0, 0.0, Z_95).is_none());
    }
}
