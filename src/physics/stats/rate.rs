//! From probability to frequency: expected events per year from a release rate and a
//! probability per released rock, with a 95 % interval and the return period.
//!
//! With a given rate λ (rocks per year) the expected overloads per year are λ·p̂ and the
//! interval is λ times the Wilson 95 % interval of p. With a rate estimated from N events
//! observed over T years, λ̂ = N/T carries its own uncertainty: its exact (Garwood) Poisson
//! interval at 97.5 % and the Wilson interval of p at 97.5 % are multiplied bound by bound,
//! which covers λ·p with at least 95 % (Bonferroni: both hold with at least 1 − 2·0.025).

use statrs::distribution::{ChiSquared, ContinuousCDF};

use super::interval::{Z_95, wilson_interval};

/// Two-sided 97.5 % standard normal quantile z = Φ⁻¹(0.9875) (mpmath, 25 digits).
#[allow(clippy::excessive_precision)] // mpmath digits kept as computed
pub const Z_975: f64 = 2.241_402_727_604_945_4;

/// How many rocks are released.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ReleaseRate {
    /// A known rate, rocks per year.
    PerYear(f64),
    /// Events counted over an observation period (years): the rate is estimated from them.
    Observed {
        /// Events counted.
        events: u64,
        /// Observation period, years.
        years: f64,
    },
}

impl ReleaseRate {
    /// The rate's point value, rocks per year.
    #[must_use]
    pub fn per_year(&self) -> f64 {
        match *self {
            Self::PerYear(r) => r,
            Self::Observed { events, years } => events as f64 / years,
        }
    }
}

/// Expected events per year, with its interval and the return period.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frequency {
    /// Expected events per year, 1/year.
    pub per_year: f64,
    /// Its interval, covering with at least 95 %, 1/year.
    pub ci95: [f64; 2],
    /// Mean time between events, years (None: none expected).
    pub return_period: Option<f64>,
    /// Its interval from the rate's: [1/upper, 1/lower] (None: unbounded), years.
    pub return_period_ci95: [Option<f64>; 2],
}

/// The exact (Garwood) two-sided interval of a Poisson mean from `events` counted, at
/// confidence `level`: [χ²(α/2; 2N)/2, χ²(1 − α/2; 2N + 2)/2] with α = 1 − level (lower bound 0
/// for N = 0).
///
/// # References
/// F. Garwood (1936), "Fiducial limits for the Poisson distribution", Biometrika 28(3/4),
/// 437–442, doi:10.2307/2333958.
#[must_use]
pub fn poisson_interval(events: u64, level: f64) -> [f64; 2] {
    let a = 1.0 - level;
    let n = events as f64;
    let lo = if events == 0 {
        0.0
    } else {
        ChiSquared::new(2.0 * n).map_or(0.0, |d| d.inverse_cdf(0.5 * a) / 2.0)
    };
    let hi = ChiSquared::new(2.0 * n + 2.0)
        .map_or(f64::INFINITY, |d| d.inverse_cdf(1.0 - 0.5 * a) / 2.0);
    [lo, hi]
}

/// Expected events per year for `k` events in `n` runs per released rock and the release
/// `rate` (see the module's text for the interval).
#[must_use]
pub fn frequency(k: u64, n: u64, rate: ReleaseRate) -> Frequency {
    let p = k as f64 / n.max(1) as f64;
    let ([r_lo, r_hi], z) = match rate {
        ReleaseRate::PerYear(r) => ([r, r], Z_95),
        ReleaseRate::Observed { events, years } => {
            let [lo, hi] = poisson_interval(events, 0.975);
            ([lo / years, hi / years], Z_975)
        }
    };
    let [p_lo, p_hi] = wilson_interval(k as f64, n as f64, z).unwrap_or([0.0, 1.0]);
    let per_year = rate.per_year() * p;
    let ci95 = [r_lo * p_lo, r_hi * p_hi];
    // a return period too long for a double is unbounded, as one with nothing expected
    let inv = |x: f64| Some(1.0 / x).filter(|t| x > 0.0 && t.is_finite());
    Frequency {
        per_year,
        ci95,
        return_period: inv(per_year),
        return_period_ci95: [inv(ci95[1]), inv(ci95[0])],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ln of the Poisson probability mass, summed independently of the χ² form.
    fn poisson_cdf(n: u64, mu: f64) -> f64 {
        // P(X ≤ n) = Σ e^{−μ} μ^k / k!, terms by recurrence in log space
        let mut ln_term = -mu;
        let mut sum = ln_term.exp();
        for k in 1..=n {
            ln_term += mu.ln() - (k as f64).ln();
            sum += ln_term.exp();
        }
        sum
    }

    /// The Garwood bounds are where the Poisson tails equal α/2: P(X ≥ N; lo) = α/2 and
    /// P(X ≤ N; hi) = α/2, by direct summation of the mass function (to 1e-9).
    #[test]
    fn garwood_bounds_solve_the_poisson_tail_equations() {
        for &n in &[1_u64, 2, 5, 17, 118, 643] {
            for level in [0.95, 0.975] {
                let a = 1.0 - level;
                let [lo, hi] = poisson_interval(n, level);
                let upper_tail = 1.0 - poisson_cdf(n - 1, lo);
                let lower_tail = poisson_cdf(n, hi);
                assert!(
                    (upper_tail - a / 2.0).abs() < 1e-9,
                    "n {n}: P(X≥n; {lo}) = {upper_tail}"
                );
                assert!(
                    (lower_tail - a / 2.0).abs() < 1e-9,
                    "n {n}: P(X≤n; {hi}) = {lower_tail}"
                );
            }
        }
        // none counted: lower 0, upper −ln(α/2)
        let [lo, hi] = poisson_interval(0, 0.95);
        assert_eq!(lo, 0.0);
        assert!((hi - (-(0.025_f64).ln())).abs() < 1e-9, "{hi}");
    }

    /// Φ(Z_975) = 0.9875 against the normal CDF of statrs (its erf is good to about 5e-13
    /// here; mpmath gives 0.9875 + 4.7e-18 for the constant).
    #[test]
    fn z_975_is_the_two_sided_975_quantile() {
        let phi = 0.5 * (1.0 + statrs::function::erf::erf(Z_975 / std::f64::consts::SQRT_2));
        assert!((phi - 0.9875).abs() < 1e-12, "{phi}");
    }

    #[test]
    fn a_known_rate_scales_the_wilson_interval() {
        let f = frequency(12, 1000, ReleaseRate::PerYear(850.0));
        let [lo, hi] = wilson_interval(12.0, 1000.0, Z_95).unwrap();
        assert_eq!(f.per_year, 850.0 * 0.012);
        assert_eq!(f.ci95, [850.0 * lo, 850.0 * hi]);
        assert_eq!(f.return_period, Some(1.0 / (850.0 * 0.012)));
        assert_eq!(
            f.return_period_ci95,
            [Some(1.0 / f.ci95[1]), Some(1.0 / f.ci95[0])]
        );
        // nothing overloaded: none expected, the return period unbounded above
        let f = frequency(0, 1000, ReleaseRate::PerYear(850.0));
        assert_eq!((f.per_year, f.ci95[0], f.return_period), (0.0, 0.0, None));
        assert!(f.ci95[1] > 0.0 && f.return_period_ci95[1].is_none());
    }

    /// Observed counts widen the interval beyond the known rate's (the rate's own uncertainty,
    /// and 97.5 % for each factor), around the same point value.
    #[test]
    fn observed_counts_widen_the_interval() {
        let observed = ReleaseRate::Observed {
            events: 643,
            years: 0.75,
        };
        let known = ReleaseRate::PerYear(643.0 / 0.75);
        let (a, b) = (frequency(30, 2000, observed), frequency(30, 2000, known));
        assert_eq!(a.per_year, b.per_year);
        assert!(
            a.ci95[0] < b.ci95[0] && a.ci95[1] > b.ci95[1],
            "{a:?} vs {b:?}"
        );
    }
}
