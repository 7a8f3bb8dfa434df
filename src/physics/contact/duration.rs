//! Contact duration against a rigid column (physics.md §A.6, §A.7): the log laws' J(u₀) by
//! adaptive quadrature (the reference) and by fitted series (the fast path), and the Hertz factor.

use std::f64::consts::FRAC_PI_2;

use super::ImpactDetail;
use crate::physics::numeric::lambert::{branch_u_parts, u_minus_ln1p};
use crate::physics::numeric::quadrature::{Integral, QuadOptions, integrate};
use crate::physics::numeric::series::{chebyshev, horner};

/// t_c·v/δmax of a Hertz impact against a rigid body: (4/5)·B(2/5, 1/2), dimensionless.
///
/// Full precision from mpmath (`4/5*beta(2/5, 1/2)` at 40 digits). physics.md §A.7 prints the
/// value as 2.9432372…, a transposition: the Beta function, the reference and case P04 all give
/// 2.9432751843….
#[allow(clippy::excessive_precision)] // mpmath digits kept as computed
pub const HERTZ_DURATION_FACTOR: f64 = 2.943_275_184_324_704_657_381_787_300_083;

/// Relative error goal of the contact-duration quadrature (physics.md §A.6 asks for 1e-10).
pub const DURATION_REL_TOL: f64 = 1e-11;

/// J(u₀) = ∫₀^{π/2} sin θ · exp((u(G sin²θ) − u₀)/2) dθ, where u₀ = u(G): the log-law contact
/// duration against a rigid column is t_c = (2 m v / Pmax)·J (dimensionless), by adaptive
/// quadrature: the reference for the fast [`line_duration_factor`].
///
/// G enters only through u₀, so G below the f64 range (u₀ up to ~1e300) is handled: the
/// integrand is formed from y = −ln(G sin²θ) = y₀ − ln sin²θ, and near the branch point from
/// 1 − G sin²θ = (1 − G) + G cos²θ.
///
/// # Examples
/// ```
/// // At G → 0 the law tends to a linear spring with log corrections; J stays O(1).
/// let j = gangue::physics::contact::line_duration_integral(17.432_269_118_399_564 - 1.0);
/// assert!(j.converged && j.value > 1.0 && j.value < 2.0);
/// ```
///
/// # Special cases
/// * `u0 == 0` (G = 1): finite; the integrand has a √-type corner at θ = π/2.
/// * Non-finite or negative `u0`: value NaN is never produced; such input gives J = 1 (the
///   linear-spring limit is not reached, but the caller never passes it).
///
/// # References
/// physics.md §A.6 (parametrisation E(P) = ½mv² sin²θ). Instead of the breakpoints 1e-6,
/// 1e-3 near θ = 0 the piece (0, 0.1] is integrated in σ = −ln θ, where it is smooth.
#[must_use]
pub fn line_duration_integral(u0: f64) -> Integral {
    line_duration_quadrature(u0, DURATION_REL_TOL)
}

/// [`line_duration_integral`] with the relative error goal `rel_tol`.
fn line_duration_quadrature(u0: f64, rel_tol: f64) -> Integral {
    if !(u0 >= 0.0 && u0.is_finite()) {
        return Integral {
            value: 1.0,
            error: 0.0,
            evaluations: 0,
            intervals: 0,
            converged: false,
        };
    }
    let y0 = u_minus_ln1p(u0);
    let q0 = -(-y0).exp_m1(); // 1 − G, accurate near G = 1
    let g = 1.0 - q0;
    let a = 1.0 + u0;
    let f = |theta: f64| {
        let (sin, cos) = theta.sin_cos();
        let c2 = cos * cos;
        let ln_s2 = if c2 < 0.5 {
            (-c2).ln_1p()
        } else {
            2.0 * sin.ln()
        };
        let du = if u0 < 64.0 {
            let y = y0 - ln_s2;
            let q = q0 + g * c2;
            let u = if y > 0.0 { branch_u_parts(q, y) } else { 0.0 };
            u - u0
        } else {
            // Large u₀ (G ≲ 1e-26): u(G sin²θ) − u₀ = Δ solves Δ − ln(1 + Δ/(1 + u₀)) = −ln sin²θ,
            // well conditioned (slope ≥ 64/65), instead of a difference of two large numbers.
            let c = -ln_s2;
            let mut d = c + (c / a).ln_1p();
            for _ in 0..20 {
                let step = (d - (d / a).ln_1p() - c) * (a + d) / (u0 + d);
                d -= step;
                if step.abs() <= 1e-16 * d {
                    break;
                }
            }
            d
        };
        sin * (0.5 * du).exp()
    };
    let options = QuadOptions {
        abs_tol: 0.0,
        rel_tol,
        max_intervals: 1000,
    };
    // θ ∈ (0, 0.1]: θ = e^{−σ} turns the √ln singularity at 0 into a smooth, exponentially
    // decaying integrand on σ ∈ [ln 10, 40] (the rest is below 1e-34).
    let near_zero = integrate(
        |sigma: f64| {
            let theta = (-sigma).exp();
            f(theta) * theta
        },
        &[std::f64::consts::LN_10, 6.0, 40.0],
        options,
    );
    let mut points = [0.1, 0.0, 0.0, FRAC_PI_2];
    let mut n = 1;
    // Near the branch point the integrand varies on the scale √(1 − G) below π/2.
    let w = q0.sqrt();
    for scale in [10.0, 1.0] {
        let p = FRAC_PI_2 - scale * w;
        if p > points[n - 1] && p < FRAC_PI_2 {
            points[n] = p;
            n += 1;
        }
    }
    points[n] = FRAC_PI_2;
    let rest = integrate(f, &points[..=n], options);
    Integral {
        value: near_zero.value + rest.value,
        error: near_zero.error + rest.error,
        evaluations: near_zero.evaluations + rest.evaluations,
        intervals: near_zero.intervals + rest.intervals,
        converged: near_zero.converged && rest.converged,
    }
}

/// Chebyshev coefficients of J in t = 1/(1 + u₀) on [0, 0.7] (u₀ ≥ 3/7), fitted to the
/// quadrature at 22 nodes; the dropped tail is below 1e-14.
#[allow(clippy::excessive_precision)] // fitted digits kept as computed
const J_CHEB_FAR: [f64; 19] = [
    1.9663157342398527,
    0.4008195013385695,
    0.005633190634473297,
    0.00036769258182111177,
    3.923764359151347e-05,
    5.369424194399321e-06,
    8.542281458957423e-07,
    1.503468048038379e-07,
    2.8448868816255413e-08,
    5.684244307569874e-09,
    1.1849109976031452e-09,
    2.555241069240372e-10,
    5.665552875329509e-11,
    1.2856614762700826e-11,
    2.9730157729607693e-12,
    6.995212490065487e-13,
    1.6781525664038616e-13,
    4.089657905255577e-14,
    8.922155943351258e-15,
];

/// Chebyshev coefficients of J in t on [0.7, 0.9] (1/9 ≤ u₀ ≤ 3/7), 20 nodes.
#[allow(clippy::excessive_precision)] // fitted digits kept as computed
const J_CHEB_MID: [f64; 16] = [
    2.4978366982390763,
    0.1255564400762125,
    0.0009421055363318942,
    4.3996756141728715e-05,
    3.7870994397781746e-06,
    4.411197915832332e-07,
    6.137184449528377e-08,
    9.58913202175893e-09,
    1.6254289914030552e-09,
    2.9262876566349406e-10,
    5.517886147998752e-11,
    1.079427658368104e-11,
    2.173572433150639e-12,
    4.496403249731884e-13,
    9.672262990534364e-14,
    2.3780977187470855e-14,
];

/// Near the branch point, √(1 + u₀)·J = A(x) + x ln x · B(x) with x = (1 − G)/0.006 ∈ [0, 1]:
/// the logarithm comes from the odd powers of √(1 − G) in u(G). A, then B (from x¹), fitted
/// by least squares to 30-digit mpmath values of the integral at 100 points.
#[allow(clippy::excessive_precision)] // fitted digits kept as computed
const J_NEAR_A: [f64; 6] = [
    2.757470600105566,
    0.009210181118272851,
    2.6670126316120162e-05,
    1.0583389108795662e-07,
    4.69082316381477e-10,
    1.2930893129607682e-12,
];
#[allow(clippy::excessive_precision)] // fitted digits kept as computed
const J_NEAR_B: [f64; 4] = [
    -0.0010606601717287445,
    -3.447143529014187e-06,
    -1.4333451535304467e-08,
    -6.243201050409676e-11,
];
/// The scale of 1 − G in [`J_NEAR_A`], [`J_NEAR_B`].
const J_NEAR_Q: f64 = 0.006;
/// J(u₀) of [`line_duration_integral`] from a fitted approximation (used by [`super::solve_impact`]).
///
/// Relative error about 1e-15 against 30-digit mpmath values; within 1e-10 of the quadrature
/// on a dense grid over u₀ ∈ [0, 1e8] (the largest gap, 5e-11 near u₀ = 2e-5, is the
/// quadrature's own error).
///
/// # Examples
/// ```
/// use gangue::physics::contact::{line_duration_factor, line_duration_integral};
/// let u0 = 16.432_269_118_399_564;
/// assert!((line_duration_factor(u0) / line_duration_integral(u0).value - 1.0).abs() < 1e-10);
/// ```
///
/// # Special cases
/// * `u0 == +∞` (G → 0): π/2, the half sine of a linear spring.
/// * `u0 == 0` (G = 1): 2.7574706001055633 (30-digit quadrature).
/// * Negative or NaN `u0`: NaN.
///
/// # References
/// physics.md §A.6. For u₀ ≥ 1/9, Chebyshev series in t = 1/(1 + u₀), on which J is smooth up
/// to t = 0 (J = π/2 + (π ln 2/2)·t + O(t²)). Below, J·√(1 + u₀) equals the integral
/// ∫₀^{√G} e^{u(G − w²)/2} dw, analytic in 1 − G apart from a (1 − G)·ln(1 − G) term (its
/// coefficient is −√2/8), fitted in that form.
#[must_use]
pub fn line_duration_factor(u0: f64) -> f64 {
    if u0.is_nan() || u0 < 0.0 {
        return f64::NAN;
    }
    let t = 1.0 / (1.0 + u0);
    if t <= 0.7 {
        chebyshev(&J_CHEB_FAR, (2.0 * t - 0.7) / 0.7)
    } else if t <= 0.9 {
        chebyshev(&J_CHEB_MID, (2.0 * t - 1.6) / 0.2)
    } else {
        let q0 = -(-u_minus_ln1p(u0)).exp_m1();
        let x = q0 / J_NEAR_Q;
        let log_part = if x > 0.0 {
            x * x.ln() * horner(&J_NEAR_B, x)
        } else {
            0.0
        };
        (horner(&J_NEAR_A, x) + log_part) * t.sqrt()
    }
}

/// Contact duration t_c of an impact against a rigid column, s, from its maxima, the rock mass
/// `mass` (kg) and the speed `v` (m/s): (2mv/Pmax)·J(u₀) for the log laws, (4/5)B(2/5, 1/2)·δmax/v
/// for Hertz.
///
/// # Special cases
/// * Pmax below 1e-280 N (v ~ 5e-324): v/Pmax is formed from logarithms.
///
/// # References
/// physics.md §A.6, §A.7.
#[must_use]
pub fn contact_duration(detail: &ImpactDetail, mass: f64, v: f64) -> f64 {
    match detail {
        ImpactDetail::Line(l) => {
            let j = line_duration_factor(l.u);
            if l.max_force > 1e-280 {
                2.0 * mass * v / l.max_force * j
            } else {
                // v/Pmax from logarithms: at v ~ 5e-324 Pmax itself underflows.
                2.0 * mass * j * (v.ln() - l.force_capacity.ln() + 0.5 * l.u).exp()
            }
        }
        ImpactDetail::Hertz(h) => HERTZ_DURATION_FACTOR * h.max_deformation / v,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::contact::solve_impact;
    use crate::physics::material::{ContactLaw, ContactModel, ImpactCase};

    #[test]
    fn hertz_duration_is_the_beta_factor_times_delta_over_v() {
        let case = ImpactCase {
            contact: ContactModel {
                law: ContactLaw::HertzPoint,
                ..ContactModel::default()
            },
            ..ImpactCase::default()
        };
        let r = solve_impact(&case).unwrap();
        let expected = HERTZ_DURATION_FACTOR * r.max_deformation() / case.velocity;
        assert_eq!(contact_duration(&r.detail, r.mass, case.velocity), expected);
        // (4/5)·B(2/5, 1/2) = (4/5)·Γ(2/5)Γ(1/2)/Γ(9/10) (mpmath: 2.9432751843247046573).
        assert!((HERTZ_DURATION_FACTOR - 2.943_275_184_324_704_6).abs() < 1e-15);
    }

    #[test]
    fn line_duration_by_logarithms_continues_the_direct_form() {
        // Below Pmax = 1e-280 N the duration is formed from logarithms; both forms agree where
        // both are representable.
        let r = solve_impact(&ImpactCase::default()).unwrap();
        let ImpactDetail::Line(mut l) = r.detail else {
            panic!("line expected")
        };
        let direct = contact_duration(&ImpactDetail::Line(l), r.mass, 5.0);
        let j = line_duration_factor(l.u);
        let logs = 2.0 * r.mass * j * (5.0f64.ln() - l.force_capacity.ln() + 0.5 * l.u).exp();
        assert!((direct / logs - 1.0).abs() < 1e-12, "{direct} vs {logs}");
        l.max_force = 1e-300;
        assert!((contact_duration(&ImpactDetail::Line(l), r.mass, 5.0) / logs - 1.0).abs() < 1e-15);
    }
}
