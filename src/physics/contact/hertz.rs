//! Hertz point contact of a rounded corner (or a sphere) on the column (physics.md §A.7): the
//! elliptical contact's stiffness from the complete elliptic integrals, solved for the logit of
//! the ellipse parameter.

use std::f64::consts::PI;

use crate::physics::numeric::elliptic::{CompleteElliptic, complete_elliptic_parts};
use crate::physics::numeric::roots::brent;

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

/// Chebyshev series of x − ln(r_c/R), x the logit of m_e at the root, on ten pieces of width 2
/// covering ln(r_c/R) ∈ [−12, 8] (piece i on [−12 + 2i, −10 + 2i], 12 nodes, 40-digit roots);
/// absolute error ≤ 4.3e-12 (worst on [0, 2]), checked at 60 points per piece.
#[allow(clippy::excessive_precision)] // fitted digits kept as computed
const HERTZ_LOGIT_PIECES: [[f64; 12]; 10] = [
    [
        0.2876855966586998,
        3.1463234518230944e-06,
        7.557176349937843e-07,
        1.2341020656511452e-07,
        1.5236615442024113e-08,
        1.5109942851172977e-09,
        1.2515004079276468e-10,
        8.896260008318963e-12,
        5.536728780669311e-13,
        3.062782174721399e-14,
        1.523280570000437e-15,
        6.858465365749509e-17,
    ],
    [
        0.28770811134688323,
        2.3246033426597825e-05,
        5.583032133089161e-06,
        9.115737451937632e-07,
        1.1251000973674666e-07,
        1.1150452882787855e-08,
        9.224012687019992e-10,
        6.540667886501131e-11,
        4.050664241998533e-12,
        2.2186848151605045e-13,
        1.0815951268982453e-14,
        4.674309343198511e-16,
    ],
    [
        0.28787438434210144,
        0.00017163931714589664,
        4.119838121981673e-05,
        6.718709355726533e-06,
        8.2730210848881e-07,
        8.160971006382599e-08,
        6.688634135277203e-09,
        4.6551127033963447e-10,
        2.774747125683555e-11,
        1.4010333419387068e-12,
        5.6526926101769656e-14,
        1.386316743189524e-15,
    ],
    [
        0.289098140206189,
        0.0012613727057089665,
        0.0003014450920361732,
        4.8731061426019305e-05,
        5.8964729437432985e-06,
        5.614879745841042e-07,
        4.275671397938672e-08,
        2.5240613183688827e-09,
        9.577432202470618e-11,
        -1.0690042830003467e-12,
        -6.299722472387193e-13,
        -7.305222803731363e-14,
    ],
    [
        0.29788781152684674,
        0.008963773787618123,
        0.0020758221536115043,
        0.0003146740712745733,
        3.323563441292088e-05,
        2.2840192560430577e-06,
        4.347143016430838e-08,
        -1.3581664916312023e-08,
        -2.278513128736069e-09,
        -1.9739799994500972e-10,
        -6.976913811798089e-12,
        8.264357021801725e-13,
    ],
    [
        0.3523913251740516,
        0.05207307772770755,
        0.009880417049924362,
        0.0009311654059315599,
        -4.2663440773064205e-07,
        -1.1828168312288883e-05,
        -1.2572988086117422e-06,
        3.476146890728667e-08,
        2.1895576206160477e-08,
        1.7470145998815936e-09,
        -1.5154581225766916e-10,
        -4.268205012101035e-11,
    ],
    [
        0.5567044765103634,
        0.154342101597074,
        0.012042932756705413,
        -0.0010108494071108694,
        -0.0001396320916121408,
        1.6086242423204278e-05,
        1.8240970956517361e-06,
        -2.96681416785601e-07,
        -2.279508498222969e-08,
        5.600527779676865e-09,
        2.3791109845930993e-10,
        -1.0612061976495911e-10,
    ],
    [
        0.9142251711709846,
        0.190843058518741,
        -0.00227748010687598,
        -0.0007593244007888931,
        9.129498896045224e-05,
        -2.1885336059400746e-06,
        -7.07757259783286e-07,
        1.0355047855421237e-07,
        -4.053182807506362e-09,
        -7.144409370489641e-10,
        1.340380576493173e-10,
        -7.993867591469113e-12,
    ],
    [
        1.2625491148184356,
        0.15518352061301968,
        -0.005190910273221149,
        7.350905894864953e-05,
        1.6278424165055638e-05,
        -2.2908673464971345e-06,
        1.7254106882867474e-07,
        -6.47616049363306e-09,
        -3.051770876001513e-10,
        7.961262021780889e-11,
        -7.992046885190795e-12,
        4.863606338019136e-13,
    ],
    [
        1.5357397649732014,
        0.11927579255983112,
        -0.003702250552179598,
        0.0001299148093850282,
        -2.624053398491364e-06,
        -1.7382763218807758e-07,
        2.82898339229585e-08,
        -2.3435651432590505e-09,
        1.4036972066543283e-10,
        -5.939778014283341e-12,
        9.45298912967129e-14,
        1.2793239645219391e-14,
    ],
];

/// Chebyshev series of x − ln(r_c/R) in ρ = r_c/R ∈ [0, e^{−12}] (6 nodes, 40-digit roots; the
/// value at ρ = 0 is ln(4/3)); absolute error ≤ 6e-17.
#[allow(clippy::excessive_precision)] // fitted digits kept as computed
const HERTZ_LOGIT_SMALL: [f64; 6] = [
    0.28768258446869055,
    5.120166474648843e-07,
    -2.621610472813299e-13,
    1.7897438441142256e-19,
    -1.4282613802271639e-25,
    1.2698802866479667e-31,
];

/// Σ cₖ Tₖ(u) and its derivative in u, by Clenshaw's recurrence and its derivative.
#[inline]
fn chebyshev_with_slope(c: &[f64], u: f64) -> (f64, f64) {
    let (mut b1, mut b2, mut d1, mut d2) = (0.0, 0.0, 0.0, 0.0);
    for &coefficient in c[1..].iter().rev() {
        let b0 = 2.0 * u * b1 - b2 + coefficient;
        let d0 = 2.0 * b1 + 2.0 * u * d1 - d2;
        b2 = b1;
        b1 = b0;
        d2 = d1;
        d1 = d0;
    }
    (u * b1 - b2 + c[0], b1 + u * d1 - d2)
}

/// The fitted logit x of m_e at the root for ln(r_c/R) = `target` ∈ [−40, 8] and its slope
/// dx/d(target) ([`HERTZ_LOGIT_PIECES`], [`HERTZ_LOGIT_SMALL`]); `None` outside.
pub(super) fn hertz_logit_fit(target: f64) -> Option<(f64, f64)> {
    if (-12.0..=8.0).contains(&target) {
        let i = (((target + 12.0) * 0.5) as usize).min(9);
        let u = target - (-11.0 + 2.0 * i as f64);
        let (f, df) = chebyshev_with_slope(&HERTZ_LOGIT_PIECES[i], u);
        Some((target + f, 1.0 + df))
    } else if (-40.0..-12.0).contains(&target) {
        // u = 2ρ/e^{−12} − 1, du/d(target) = 2ρ/e^{−12}.
        let scaled = 2.0 * (target + 12.0).exp();
        let (f, df) = chebyshev_with_slope(&HERTZ_LOGIT_SMALL, scaled - 1.0);
        Some((target + f, 1.0 + df * scaled))
    } else {
        None
    }
}

/// The fitted logit of m_e at the root (see [`hertz_logit_fit`]).
pub(super) fn hertz_logit_guess(target: f64) -> Option<f64> {
    hertz_logit_fit(target).map(|(x, _)| x)
}

/// m, 1 − m and the AGM parts at the root for ln(r_c/R) = `target` ∈ [−40, 8]: one Newton step
/// from the fitted logit (error ≤ 4.3e-12) with the fit's own slope, then K, E, s and t carried
/// to the corrected point to first order (the neglected terms are O(Δx²) ≈ 1e-23). `None`
/// outside the fit or if the correction is larger than the fit allows (the caller then
/// brackets and uses Brent).
pub(super) fn hertz_root_newton(target: f64) -> Option<(f64, f64, CompleteElliptic)> {
    let (x0, slope) = hertz_logit_fit(target)?;
    let (lr, m0, m10, p) = hertz_log_ratio(x0);
    let dx = -(lr - target) * slope;
    if dx.is_nan() || dx.abs() > 1e-9 {
        return None;
    }
    // dm/dx = m m₁; dK/dx = K m (1 − s)/2 (from dK/dm = (E − m₁K)/(2 m m₁), E = K(1 − m s));
    // ds/dx = m (s² − t)/2; dt/dx = s² − 2t + m t (t = (2s − 1)/m).
    let dm = m0 * m10 * dx;
    let (m, m1) = (m0 + dm, m10 - dm);
    let k = p.k * (1.0 + 0.5 * m0 * (1.0 - p.s) * dx);
    let s = p.s + 0.5 * m0 * (p.s * p.s - p.t) * dx;
    let t = p.t + (p.s * p.s - 2.0 * p.t + m0 * p.t) * dx;
    let e = k * (1.0 - m * s);
    Some((m, m1, CompleteElliptic { k, e, s, t }))
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
/// * e^{−40} ≤ r_c/R ≤ e^8 (the whole API range): one Newton step from a fitted starting value
///   (good to 4.3e-12 in the logit) and one AGM; elsewhere, or if the step is larger than the
///   fit allows, a widening bracket and Brent.
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
    // ln(B/A − 1) = ln(r_c/R): one logarithm of the ratio when it is a normal number.
    let ratio = rc / r;
    let target = if ratio.is_normal() && ratio.is_finite() {
        ratio.ln()
    } else {
        rc.ln() - r.ln()
    };
    let (m, m1, parts) = if let Some(found) = hertz_root_newton(target) {
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
        // The fit is good to 4.3e-12 in x: a bracket of ±1e-5 holds the root.
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
