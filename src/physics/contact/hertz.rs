//! Hertz point contact of a rounded corner (or a sphere) on the column (physics.md §A.7): the
//! elliptical contact's stiffness from the complete elliptic integrals: fitted over the API's
//! range of r_c/R (`contact/hertz_fit.rs`), solved for the logit of the ellipse parameter beyond.

use std::f64::consts::PI;

use crate::physics::numeric::elliptic::{CompleteElliptic, complete_elliptic_parts};
use crate::physics::numeric::roots::brent;

use super::hertz_fit::{FIT_FROM, hertz_fit};

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
    /// (κ/κ_eq)^{2/5}: the equivalent-radius form's δmax over this one's (1 when they are the
    /// same form), dimensionless.
    pub deformation_ratio_equivalent_radius: f64,
}

/// ln of B/A − 1 = r_c/R as a function of the logit x = ln(m/(1 − m)) of the ellipse parameter,
/// and the AGM parts at that m.
pub(super) fn hertz_log_ratio(x: f64) -> (f64, f64, f64, CompleteElliptic) {
    // m = 1/(1 + e^{−x}) and 1 − m = e^{−x}·m from one exponential (each within 2 ulp).
    let ex = (-x).exp();
    let m = 1.0 / (1.0 + ex);
    let m1 = if ex.is_finite() {
        ex * m
    } else {
        1.0 / (1.0 + x.exp())
    };
    let r = complete_elliptic_parts(m, m1);
    // B/A − 1 = m (1/2 − t(1 − m/2)) / (m₁ s), free of cancellation on the whole domain; with
    // ln(m/m₁) = x it takes one logarithm.
    let num = 0.5 - r.t * (1.0 - 0.5 * m);
    (x + (num / r.s).ln(), m, m1, r)
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
/// * e^{−40} ≤ r_c/R ≤ e^8 (the whole API range): the fitted logit of m_e, κ/(E*√r_c), s and
///   (κ/κ_eq)^{2/5} (`contact/hertz_fit.rs`, within 1.2e-16 of 40-digit values), no root search;
///   1 − m_e from the logit keeps full precision as m_e → 1.
/// * r_c/R > e^8: solved for the logit of m_e by a widening bracket and Brent, with K
///   following ln(4/√(1 − m_e)).
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
            deformation_ratio_equivalent_radius: 1.0,
        };
    }
    // ln(B/A − 1) = ln(r_c/R): one logarithm of the ratio when it is a normal number.
    let ratio = rc / r;
    let target = if ratio.is_normal() && ratio.is_finite() {
        ratio.ln()
    } else {
        rc.ln() - r.ln()
    };
    if let Some(fit) = hertz_fit(target) {
        // m = 1/(1 + e^{−x}) and 1 − m = e^{−x}·m from one exponential (x ≤ 9.7 here).
        let ex = (-fit.logit).exp();
        let m = 1.0 / (1.0 + ex);
        return HertzGeometry {
            stiffness: e_star * fit.stiffness_factor * rc.sqrt(),
            stiffness_equivalent_radius: kappa_eq,
            equivalent_radius: re,
            eccentricity_squared: m,
            axis_ratio: (ex * m).sqrt(),
            semi_axis_factor: 2.0 * rc * fit.s,
            deformation_ratio_equivalent_radius: fit.deformation_ratio,
        };
    }
    let (m, m1, parts) = if target < FIT_FROM {
        let m = (target + (4.0f64 / 3.0).ln()).exp();
        (m, 1.0 - m, complete_elliptic_parts(m, 1.0 - m))
    } else {
        // Beyond the fit (r_c/R > e⁸): a start from the asymptote m₁ ≈ 1/(ρ(ln(4/√m₁) − 1)),
        // then a widening bracket and Brent in x.
        let rho = target.exp();
        let mut m1 = (1.0 / rho).min(0.5);
        for _ in 0..3 {
            m1 = (1.0 / (rho * ((4.0 / m1.sqrt()).ln() - 1.0).max(0.5))).min(0.5);
        }
        let x0 = ((1.0 - m1) / m1).ln();
        let mut g = |x: f64| hertz_log_ratio(x).0 - target;
        let mut step = 0.25;
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
        deformation_ratio_equivalent_radius: (kappa / kappa_eq).powf(0.4),
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
