//! Hertz point contact of a rounded corner (or a sphere) on the column (physics.md §A.7): the
//! elliptical contact's stiffness from the complete elliptic integrals, solved for the logit of
//! the ellipse parameter.

use std::f64::consts::PI;

use crate::physics::numeric::elliptic::{CompleteElliptic, complete_elliptic_parts};
use crate::physics::numeric::roots::brent;
use crate::physics::numeric::series::chebyshev;

/// Geometry and stiffness of the Hertz point contact of a rounded corner on the cylinder.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HertzGeometry {
    /// κ in P = κδ^{3/2} as used (exact or equivalent radius), N/m^{3/2}.
    pub stiffness: f64,
    /// κ of the equivalent-radius form (4/3)E*√R_e, N/m^{3/2}.
    pub stiffness_equivalent_radius: f64,
    /// R_e = √(R′R″) = r_c √(R/(R + r_c)), m.
    pub equivalent_radius: f64,
    /// Squared eccentricity m_e = 1 − (b/a)² of the contact ellipse (0 for the equivalent
    /// radius form), dimensionless.
    pub eccentricity_squared: f64,
    /// b/a ≤ 1 (1 for the equivalent-radius form), dimensionless.
    pub axis_ratio: f64,
    /// a²/δ: the major semi-axis at approach δ is a = √(factor·δ), m.
    pub semi_axis_factor: f64,
}

/// ln of B/A − 1 = r_c/R as a function of the logit x = ln(m/(1 − m)) of the ellipse parameter,
/// and the AGM parts at that m.
pub(super) fn hertz_log_ratio(x: f64) -> (f64, f64, f64, CompleteElliptic) {
    let m = 1.0 / (1.0 + (-x).exp());
    let m1 = 1.0 / (1.0 + x.exp());
    let r = complete_elliptic_parts(m, m1);
    // B/A − 1 = m (1/2 − t(1 − m/2)) / (m₁ s), free of cancellation on the whole domain.
    let num = 0.5 - r.t * (1.0 - 0.5 * m);
    (m.ln() + num.ln() - m1.ln() - r.s.ln(), m, m1, r)
}

/// Chebyshev series of x − ln(r_c/R), x the logit of m_e at the root, on ln(r_c/R) ∈ [−12, 0]
/// (14 nodes, 70-digit roots); absolute error ≤ 2.1e-6, only a starting value for Brent.
#[allow(clippy::excessive_precision)] // fitted digits kept as computed
const HERTZ_LOGIT_NEG: [f64; 14] = [
    0.31062743824974826,
    0.041473298196510515,
    0.030677925688700924,
    0.01862755118564038,
    0.009247569419128009,
    0.0036587800034619056,
    0.0010475983573366551,
    0.00011927351210627315,
    -8.982224714138802e-05,
    -7.892460551883751e-05,
    -3.744103258251522e-05,
    -1.1712907954101815e-05,
    -1.6174788226198348e-06,
    5.550887800252955e-07,
];

/// As [`HERTZ_LOGIT_NEG`] on ln(r_c/R) ∈ [0, 8]; absolute error ≤ 5.3e-7.
#[allow(clippy::excessive_precision)] // fitted digits kept as computed
const HERTZ_LOGIT_POS: [f64; 14] = [
    1.056731780838059,
    0.6432562630740906,
    -0.033653636997375204,
    -0.024171897352840296,
    0.011098920524885718,
    -0.001440225883972904,
    -0.0007522759457308752,
    0.0004728044963852992,
    -9.469475506203504e-05,
    -2.2734570304078217e-05,
    2.208468419842965e-05,
    -6.255732426681457e-06,
    -3.846865846404304e-07,
    9.901827148911524e-07,
];

/// The logit of m_e at the root from [`HERTZ_LOGIT_NEG`], [`HERTZ_LOGIT_POS`] for
/// ln(r_c/R) = `target` ∈ [−12, 8]; `None` outside.
pub(super) fn hertz_logit_guess(target: f64) -> Option<f64> {
    if (-12.0..=0.0).contains(&target) {
        Some(target + chebyshev(&HERTZ_LOGIT_NEG, (target + 6.0) / 6.0))
    } else if (0.0..=8.0).contains(&target) {
        Some(target + chebyshev(&HERTZ_LOGIT_POS, (target - 4.0) / 4.0))
    } else {
        None
    }
}

/// Secant iteration for the logit of m_e from the fitted `x0`, the first slope from the fit
/// itself; stops, like [`brent`], once the step is below 2ε·max(|x|, 1), and returns m, 1 − m
/// and the AGM parts at that point. `None` if that takes more than 5 evaluations (the caller
/// then brackets and uses Brent).
pub(super) fn hertz_root_secant(target: f64, x0: f64) -> Option<(f64, f64, CompleteElliptic)> {
    // dx/d(target) of the fit, by a central difference (the fit is smooth; 1e-4 is enough).
    let h = 1e-3;
    let lo = hertz_logit_guess((target - h).max(-12.0))?;
    let hi = hertz_logit_guess((target + h).min(8.0))?;
    let mut slope = 1.0 / ((hi - lo) / ((target + h).min(8.0) - (target - h).max(-12.0)));
    let mut x = x0;
    let mut prev: Option<(f64, f64)> = None;
    for _ in 0..5 {
        let (lr, m, m1, parts) = hertz_log_ratio(x);
        let gx = lr - target;
        if let Some((xp, gp)) = prev
            && gx != gp
        {
            slope = (gx - gp) / (x - xp);
        }
        let step = gx / slope;
        if !step.is_finite() {
            return None;
        }
        if step.abs() <= 2.0 * f64::EPSILON * x.abs().max(1.0) {
            return Some((m, m1, parts));
        }
        prev = Some((x, gx));
        x -= step;
    }
    None
}

/// Hertz point-contact geometry of a rounded corner of radius `corner_radius` (m) on a cylinder
/// of radius `contact_radius` (m), with E* `e_star` (Pa).
///
/// Curvatures A = 1/(2r_c) along the axis and B = (1/r_c + 1/R)/2 across it. `exact`: the
/// elliptical Hertz κ = (2πE*/(3K))√((K − E)/(K m_e A)) with m_e solving
/// B/A = [E/(1 − m_e) − K]/[K − E]; else κ = (4/3)E*√R_e.
///
/// # Examples
/// ```
/// let h = gangue::physics::contact::hertz_geometry(5.299_557_486_949_84e9, 0.02, 0.125, true);
/// assert!((h.stiffness / 963_336_672.040_085_3 - 1.0).abs() < 1e-12); // case P04
/// ```
///
/// # Special cases
/// * r_c/R → 0 (circular contact): below r_c/R = e^{−40}, m_e = 4r_c/(3R) from the leading
///   term (the next is O(m_e²)); κ → (4/3)E*√R_e. r_c/R underflowing to 0 gives m_e = 0.
/// * r_c/R large (m_e → 1): solved for the logit of m_e, so 1 − m_e keeps full precision and
///   K follows ln(4/√(1 − m_e)).
/// * e^{−12} ≤ r_c/R ≤ e^8: secant steps from a fitted starting value (good to 3e-6 in the
///   logit); elsewhere, or if they stall, a widening bracket and Brent.
///
/// # References
/// physics.md §A.7; K. L. Johnson, *Contact Mechanics* (CUP 1985) §4.2 and §3.4.
#[must_use]
pub fn hertz_geometry(
    e_star: f64,
    corner_radius: f64,
    contact_radius: f64,
    exact: bool,
) -> HertzGeometry {
    let rc = corner_radius;
    let r = contact_radius;
    let re = rc * (r / (rc + r)).sqrt();
    let kappa_eq = 4.0 / 3.0 * e_star * re.sqrt();
    if !exact {
        return HertzGeometry {
            stiffness: kappa_eq,
            stiffness_equivalent_radius: kappa_eq,
            equivalent_radius: re,
            eccentricity_squared: 0.0,
            axis_ratio: 1.0,
            semi_axis_factor: re,
        };
    }
    let target = rc.ln() - r.ln(); // ln(B/A − 1)
    let secant = hertz_logit_guess(target).and_then(|x0| hertz_root_secant(target, x0));
    let (m, m1, parts) = if let Some(found) = secant {
        found
    } else if target < -40.0 {
        let m = (target + (4.0f64 / 3.0).ln()).exp();
        (m, 1.0 - m, complete_elliptic_parts(m, 1.0 - m))
    } else {
        // Initial guess from the asymptotes, then a widening bracket and Brent in x.
        let rho = target.exp();
        let fitted = hertz_logit_guess(target);
        let x0 = if let Some(x) = fitted {
            x
        } else if rho < 0.5 {
            let m = 4.0 * rho / 3.0;
            (m / (1.0 - m * 0.8)).ln()
        } else {
            let mut m1 = (1.0 / rho).min(0.5);
            for _ in 0..3 {
                m1 = (1.0 / (rho * ((4.0 / m1.sqrt()).ln() - 1.0).max(0.5))).min(0.5);
            }
            ((1.0 - m1) / m1).ln()
        };
        let mut g = |x: f64| hertz_log_ratio(x).0 - target;
        // The fit is good to 2.1e-6 in x: a bracket of ±1e-5 holds the root.
        let mut step = if fitted.is_some() { 1e-5 } else { 0.25 };
        let (mut lo, mut hi) = (x0 - step, x0 + step);
        let (mut glo, mut ghi) = (g(lo), g(hi));
        for _ in 0..60 {
            if glo <= 0.0 && ghi >= 0.0 {
                break;
            }
            step *= 2.0;
            if glo > 0.0 {
                hi = lo;
                ghi = glo;
                lo -= step;
                glo = g(lo);
            } else {
                lo = hi;
                glo = ghi;
                hi += step;
                ghi = g(hi);
            }
        }
        let x = brent(&mut g, lo, hi, glo, ghi);
        let (_, m, m1, parts) = hertz_log_ratio(x);
        (m, m1, parts)
    };
    // (K − E)/(K m A) = 2 r_c s.
    let factor = 2.0 * rc * parts.s;
    let kappa = 2.0 * PI * e_star / (3.0 * parts.k) * factor.sqrt();
    HertzGeometry {
        stiffness: kappa,
        stiffness_equivalent_radius: kappa_eq,
        equivalent_radius: re,
        eccentricity_squared: m,
        axis_ratio: m1.sqrt(),
        semi_axis_factor: factor,
    }
}

/// δmax = (5mv²/(4κ))^{2/5}, m: one power when 5mv²/(4κ) is a normal number, else without
/// forming v² (v may be 1e-300).
pub(super) fn hertz_max_deformation(mass: f64, v: f64, kappa: f64) -> f64 {
    let x = 1.25 * mass * (v * v) / kappa;
    if x.is_normal() && (1e-290..=1e290).contains(&(v * v)) {
        x.powf(0.4)
    } else {
        (1.25 * mass / kappa).powf(0.4) * v.powf(0.8)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equivalent_radius_form_is_the_circular_hertz_law() {
        // κ = (4/3)E*√R_e with R_e = r_c√(R/(R + r_c)).
        let (es, rc, r) = (5.3e9, 0.02, 0.125);
        let h = hertz_geometry(es, rc, r, false);
        let re = rc * (r / (r + rc)).sqrt();
        assert!((h.equivalent_radius / re - 1.0).abs() < 1e-15);
        assert!((h.stiffness / (4.0 / 3.0 * es * re.sqrt()) - 1.0).abs() < 1e-15);
        assert_eq!((h.axis_ratio, h.eccentricity_squared), (1.0, 0.0));
    }

    #[test]
    fn exact_form_tends_to_the_circular_one_for_a_small_corner() {
        // r_c/R → 0: the contact becomes circular and the exact κ tends to (4/3)E*√R_e.
        let h = hertz_geometry(1.0, 1e-9, 1.0, true);
        assert!((h.stiffness / h.stiffness_equivalent_radius - 1.0).abs() < 1e-8);
        assert!(h.axis_ratio > 0.999_999);
    }

    #[test]
    fn max_deformation_is_continuous_across_its_two_forms() {
        // (5mv²/(4κ))^{2/5}: the direct power and the v^{4/5} form agree where both apply.
        let (m, kappa) = (67.5f64, 1e9f64);
        let v = 1e-145f64; // v² = 1e-290: the edge of the direct form
        let direct = (1.25 * m * (v * v) / kappa).powf(0.4);
        let split = (1.25 * m / kappa).powf(0.4) * v.powf(0.8);
        assert!((direct / split - 1.0).abs() < 1e-13);
        assert!((hertz_max_deformation(m, v, kappa) / split - 1.0).abs() < 1e-13);
        assert!(hertz_max_deformation(m, 1e-300, kappa) > 0.0);
    }
}
