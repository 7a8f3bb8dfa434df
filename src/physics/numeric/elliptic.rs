//! Complete elliptic integrals K(m) and E(m) of parameter m = k², by the arithmetic–geometric
//! mean, with the parameter given together with its complement m₁ = 1 − m so that both ends
//! (m → 0 and m → 1) keep every digit.
//!
//! The AGM also yields K − E as a sum of positive terms, so (K − E)/m is accurate at m → 0 where
//! the difference K − E would cancel (physics.md §A.7 needs it for the elliptical Hertz contact).

use std::f64::consts::FRAC_PI_2;

/// K, E and the cancellation-free sums of the AGM for one parameter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CompleteElliptic {
    /// K(m), dimensionless.
    pub k: f64,
    /// E(m), dimensionless.
    pub e: f64,
    /// s = (K − E)/(m K) = 1/2 + m t/2, dimensionless (1/2 at m = 0).
    pub s: f64,
    /// t = Σ_{n≥1} 2ⁿ cₙ²/m² of the AGM (1/8 at m = 0), dimensionless.
    pub t: f64,
}

/// K(m), E(m) and the AGM sums for parameter `m` with complement `m1` = 1 − m.
///
/// Pass `m1` computed independently (not as `1.0 - m`) when m is close to 1: K then follows its
/// logarithmic growth K ≈ ln(4/√m₁) to full relative precision.
///
/// # Examples
/// ```
/// use gangue::physics::numeric::elliptic::complete_elliptic_parts;
/// let r = complete_elliptic_parts(0.5, 0.5);
/// assert!((r.k - 1.854_074_677_301_372).abs() < 1e-15);
/// assert!((r.e - 1.350_643_881_047_675_5).abs() < 1e-15);
/// ```
///
/// # Special cases
/// * `m == 0`: K = E = π/2, s = 1/2, t = 1/8.
/// * `m1 == 0` (m = 1): K = +∞, E = 1, s = 1, t = 1.
/// * E near m = 1 is K(1 − m s): relative error ≲ K·ε (a few ulp on any practical m₁).
///
/// # References
/// DLMF §19.8 (AGM for K and E), <https://dlmf.nist.gov/19.8>; cₙ₊₁ = cₙ²/(4aₙ₊₁) avoids the
/// cancellation in (aₙ − bₙ)/2.
#[must_use]
pub fn complete_elliptic_parts(m: f64, m1: f64) -> CompleteElliptic {
    if m1 <= 0.0 {
        return CompleteElliptic {
            k: f64::INFINITY,
            e: 1.0,
            s: 1.0,
            t: 1.0,
        };
    }
    let mut a = 1.0_f64;
    let mut b = m1.sqrt();
    // n = 1 term: c₁ = m/(4a₁), e₁ = c₁/m = 1/(4a₁).
    let a_next = 0.5 * (a + b);
    b = (a * b).sqrt();
    a = a_next;
    let mut en = 0.25 / a; // e_n = c_n/m
    let mut weight = 2.0; // 2ⁿ
    let mut t = weight * en * en;
    for _ in 0..60 {
        let cn = en * m;
        let converged_ab = (a - b).abs() <= 4.0 * f64::EPSILON * a;
        let a_next = 0.5 * (a + b);
        b = (a * b).sqrt();
        a = a_next;
        en *= cn / (4.0 * a);
        weight *= 2.0;
        let term = weight * en * en;
        t += term;
        if converged_ab && term <= 1e-18 * t {
            break;
        }
    }
    let k = FRAC_PI_2 / a;
    let s = 0.5 + 0.5 * m * t;
    let e = k * (1.0 - m * s);
    CompleteElliptic { k, e, s, t }
}

/// Complete elliptic integrals (K(m), E(m)) for 0 ≤ m < 1.
///
/// # Examples
/// ```
/// let (k, e) = gangue::physics::numeric::elliptic::complete_elliptic(0.0);
/// assert_eq!((k, e), (std::f64::consts::FRAC_PI_2, std::f64::consts::FRAC_PI_2));
/// ```
///
/// # Special cases
/// * `m == 1`: (+∞, 1). For m close to 1 prefer [`complete_elliptic_parts`] with an exact m₁.
///
/// # References
/// DLMF §19.8.
#[must_use]
pub fn complete_elliptic(m: f64) -> (f64, f64) {
    let r = complete_elliptic_parts(m, 1.0 - m);
    (r.k, r.e)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Values from mpmath (ellipk, ellipe at 30 digits).
    #[test]
    fn against_mpmath_table() {
        let table = [
            (1e-10, 1.570_796_326_834_166_5, 1.570_796_326_755_626_7),
            (0.1, 1.612_441_348_720_219_1, 1.530_757_636_897_763),
            (0.9, 2.578_092_113_348_173, 1.104_774_732_704_073),
            (0.999_999, 8.294_051_463_601_062, 1.000_003_897_026_172),
        ];
        for (m, k, e) in table {
            let r = complete_elliptic_parts(m, 1.0 - m);
            assert!((r.k - k).abs() <= 2e-15 * k, "K({m}) = {} vs {k}", r.k);
            assert!((r.e - e).abs() <= 4e-15 * e, "E({m}) = {} vs {e}", r.e);
        }
    }

    #[test]
    fn legendre_relation() {
        // E K' + E' K − K K' = π/2 for every m.
        for m in [1e-8, 0.01, 0.3, 0.5, 0.77, 0.99, 1.0 - 1e-9] {
            let r = complete_elliptic_parts(m, 1.0 - m);
            let c = complete_elliptic_parts(1.0 - m, m);
            let lhs = r.e * c.k + c.e * r.k - r.k * c.k;
            assert!(
                (lhs - FRAC_PI_2).abs() < 2e-14 * r.k.max(c.k),
                "m = {m}: {lhs}"
            );
        }
    }

    #[test]
    fn small_m_sums_without_cancellation() {
        // (K − E)/m = K s → π/4 (1 + 3m/8 + …) as m → 0, to full precision even at m = 1e-300.
        for m in [1e-300, 1e-100, 1e-20] {
            let r = complete_elliptic_parts(m, 1.0);
            assert!((r.k * r.s - std::f64::consts::FRAC_PI_4).abs() < 2e-16);
            assert!((r.t - 0.125).abs() < 1e-16);
        }
        let m = 1e-5; // the next series term is O(m³) = 1e-15
        let r = complete_elliptic_parts(m, 1.0 - m);
        let series = std::f64::consts::FRAC_PI_4 * (1.0 + 3.0 * m / 8.0 + 15.0 * m * m / 64.0);
        assert!((r.k * r.s / series - 1.0).abs() < 1e-13);
    }

    #[test]
    fn log_asymptotics_near_one() {
        // K ≈ ln(4/√m₁) + (m₁/4)(ln(4/√m₁) − 1) for tiny m₁.
        for m1 in [1e-12, 1e-20, 1e-100] {
            let r = complete_elliptic_parts(1.0 - m1, m1);
            let l = (4.0 / m1.sqrt()).ln();
            let k = l + 0.25 * m1 * (l - 1.0);
            assert!((r.k / k - 1.0).abs() < 1e-14, "m1 = {m1}: {} vs {k}", r.k);
            assert!((r.e - 1.0).abs() < 1e-10);
        }
        assert_eq!(complete_elliptic(1.0), (f64::INFINITY, 1.0));
    }
}
