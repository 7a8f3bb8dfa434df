//! Contact of the rock block on the column: logarithmic line-contact laws (`paper`, `johnson`)
//! on the W₋₁ branch, Hertz point contact, capacity, contact duration (physics.md §A).

use std::f64::consts::{E, FRAC_PI_2, PI};

use super::elliptic::complete_elliptic_parts;
use super::error::{PhysicsError, PhysicsResult};
use super::lambert::{branch_u_far, branch_u_log, branch_u_parts, u_minus_ln1p};
use super::material::{Column, ContactLaw, ImpactCase, ModulusConvention, Rock, RockShape};
use super::quadrature::{Integral, QuadOptions, integrate};

/// Result of a normal impact against a rigid column.
#[derive(Debug, Clone, PartialEq)]
pub struct ImpactResult {
    /// Rock mass m, kg.
    pub mass: f64,
    /// Rock kinetic energy ½mv², J.
    pub kinetic_energy: f64,
    /// Effective modulus E*, Pa.
    pub effective_modulus: f64,
    /// Contact radius R of the column, m.
    pub contact_radius: f64,
    /// The law used.
    pub law: ContactLaw,
    /// The modulus convention used.
    pub modulus: ModulusConvention,
    /// Law-specific maxima.
    pub detail: ImpactDetail,
    /// Contact duration against a rigid column, s.
    pub contact_duration: f64,
}

/// Law-specific part of an [`ImpactResult`].
#[derive(Debug, Clone, PartialEq)]
pub enum ImpactDetail {
    /// Logarithmic line contact (`paper`, `johnson`).
    Line(LineImpact),
    /// Hertz point contact.
    Hertz(HertzImpact),
}

/// Maxima of a logarithmic line-contact impact (physics.md §A.5).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LineImpact {
    /// Dimensionless energy parameter G ∈ [0, 1] (rounded; 0 or subnormal only when the true G is
    /// below the f64 range, v ≲ 1e-140 — W, δ and P are then computed from ln G).
    pub energy_parameter: f64,
    /// W = W₋₁(−G/e) = −1 − u.
    pub lambert_w: f64,
    /// u = −(1 + W) ≥ 0.
    pub u: f64,
    /// Maximum approach δmax, m.
    pub max_deformation: f64,
    /// Maximum force Pmax, N.
    pub max_force: f64,
    /// Contact half-width a, m.
    pub half_width: f64,
    /// Maximum contact pressure p₀, Pa.
    pub max_pressure: f64,
    /// Largest storable energy E_cap, J.
    pub energy_capacity: f64,
    /// Approach at the capacity δ_cap, m.
    pub deformation_capacity: f64,
    /// Force at the capacity P_cap, N.
    pub force_capacity: f64,
}

/// Maxima of a Hertz point-contact impact (physics.md §A.7).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HertzImpact {
    /// Maximum approach δmax, m.
    pub max_deformation: f64,
    /// Maximum force Pmax, N.
    pub max_force: f64,
    /// Hertz stiffness κ in P = κδ^{3/2}, N/m^{3/2}.
    pub stiffness: f64,
    /// Equivalent radius R_e = √(R′R″), m.
    pub equivalent_radius: f64,
    /// δmax by the equivalent-radius form, m.
    pub max_deformation_equivalent_radius: f64,
    /// Contact-ellipse axis ratio b/a ≤ 1.
    pub axis_ratio: f64,
    /// Contact-ellipse semi-axes [a, b] at Pmax, m.
    pub semi_axes: [f64; 2],
    /// Maximum contact pressure 3P/(2πab), Pa.
    pub max_pressure: f64,
}

/// Force–approach law P(δ), usable by the coupled column model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ForceLaw {
    /// δ(P) = P/k · ln(P_ref/P): k = πLE*, N/m; P_ref, N.
    Log {
        /// k = π L E*, N/m.
        k: f64,
        /// Reference force P_ref, N.
        p_ref: f64,
    },
    /// P = κ δ^{3/2}.
    Hertz {
        /// κ, N/m^{3/2}.
        kappa: f64,
    },
}

/// t_c·v/δmax of a Hertz impact against a rigid body: (4/5)·B(2/5, 1/2), dimensionless.
///
/// Full precision from mpmath (`4/5*beta(2/5, 1/2)` at 40 digits). physics.md §A.7 prints the
/// value as 2.9432372…, a transposition: the Beta function, the reference and case P04 all give
/// 2.9432751843….
#[allow(clippy::excessive_precision)] // mpmath digits kept as computed
pub const HERTZ_DURATION_FACTOR: f64 = 2.943_275_184_324_704_657_381_787_300_083;

/// Relative error goal of the contact-duration quadrature (physics.md §A.6 asks for 1e-10).
pub const DURATION_REL_TOL: f64 = 1e-11;

// ---------------------------------------------------------------------------------------------
// Double-double arithmetic for G: near the branch point P has condition (1+u)/(2u) in G, so G is
// formed from the inputs with ~1e-30 relative error and 1 − G is taken before rounding.

#[derive(Debug, Clone, Copy)]
struct Dd {
    hi: f64,
    lo: f64,
}

const DD_PI: Dd = Dd {
    hi: PI,
    lo: 1.224_646_799_147_353_2e-16,
};
const DD_E4: Dd = Dd {
    hi: 54.598_150_033_144_236,
    lo: 2.874_157_801_584_411_5e-15,
};

#[inline]
fn two_sum(a: f64, b: f64) -> Dd {
    let s = a + b;
    let bb = s - a;
    Dd {
        hi: s,
        lo: (a - (s - bb)) + (b - bb),
    }
}

#[inline]
fn fast_two_sum(a: f64, b: f64) -> Dd {
    let s = a + b;
    Dd {
        hi: s,
        lo: b - (s - a),
    }
}

#[inline]
fn split(a: f64) -> (f64, f64) {
    let t = 134_217_729.0 * a; // 2^27 + 1 (Dekker)
    let hi = t - (t - a);
    (hi, a - hi)
}

#[inline]
fn two_prod(a: f64, b: f64) -> Dd {
    let p = a * b;
    let (ah, al) = split(a);
    let (bh, bl) = split(b);
    Dd {
        hi: p,
        lo: ((ah * bh - p) + ah * bl + al * bh) + al * bl,
    }
}

impl Dd {
    fn new(x: f64) -> Self {
        Dd { hi: x, lo: 0.0 }
    }
    fn mul(self, o: Dd) -> Dd {
        let p = two_prod(self.hi, o.hi);
        fast_two_sum(p.hi, p.lo + (self.hi * o.lo + self.lo * o.hi))
    }
    fn mulf(self, o: f64) -> Dd {
        self.mul(Dd::new(o))
    }
    fn add(self, o: Dd) -> Dd {
        let s = two_sum(self.hi, o.hi);
        fast_two_sum(s.hi, s.lo + self.lo + o.lo)
    }
    fn neg(self) -> Dd {
        Dd {
            hi: -self.hi,
            lo: -self.lo,
        }
    }
    fn div(self, o: Dd) -> Dd {
        let q1 = self.hi / o.hi;
        let r = self.add(o.mulf(q1).neg());
        let q2 = r.hi / o.hi;
        let r = r.add(o.mulf(q2).neg());
        let q3 = r.hi / o.hi;
        fast_two_sum(q1, q2).add(Dd::new(q3))
    }
    fn f64(self) -> f64 {
        self.hi + self.lo
    }
}

/// 1 − ν² in double-double.
fn one_minus_sq(nu: f64) -> Dd {
    Dd::new(1.0).add(two_prod(nu, nu).neg())
}

fn effective_modulus_dd(rock: &Rock, column: &Column, convention: ModulusConvention) -> Dd {
    let rock_term = one_minus_sq(rock.poisson_ratio).div(Dd::new(rock.elastic_modulus));
    match convention {
        ModulusConvention::Paper => Dd::new(1.0).div(rock_term),
        ModulusConvention::TwoBody => {
            let col = one_minus_sq(column.poisson_ratio).div(Dd::new(column.elastic_modulus));
            Dd::new(1.0).div(rock_term.add(col))
        }
    }
}

/// Effective modulus E* of the contact, Pa (physics.md §A.2).
///
/// `Paper`: E/(1 − ν²) of the rock only; `TwoBody`: 1/E* = (1 − ν²)/E + (1 − ν_s²)/E_s.
///
/// # Examples
/// ```
/// use gangue::physics::contact::effective_modulus;
/// use gangue::physics::material::{Column, ModulusConvention, Rock};
/// let e = effective_modulus(&Rock::default(), &Column::default(), ModulusConvention::TwoBody);
/// assert!((e / 5.299_557_487e9 - 1.0).abs() < 1e-9);
/// ```
///
/// # Special cases
/// * Evaluated in double-double and rounded once: correctly rounded in practice.
///
/// # References
/// physics.md §A.2 (Johnson's convention; E′ = 2E* is not used).
pub fn effective_modulus(rock: &Rock, column: &Column, convention: ModulusConvention) -> f64 {
    effective_modulus_dd(rock, column, convention).f64()
}

// ---------------------------------------------------------------------------------------------
// Input checks (the web layer checks the documented ranges first; these keep the solver total).

fn check_positive(field: &str, value: f64) -> PhysicsResult<()> {
    if value > 0.0 && value.is_finite() {
        Ok(())
    } else {
        Err(PhysicsError::invalid(
            field,
            value,
            "must be a positive finite number",
        ))
    }
}

fn check_poisson(field: &str, value: f64) -> PhysicsResult<()> {
    if (0.0..0.5).contains(&value) {
        Ok(())
    } else {
        Err(PhysicsError::invalid(field, value, "must be in [0, 0.5)"))
    }
}

fn check_case(case: &ImpactCase) -> PhysicsResult<()> {
    check_positive("/velocity_m_s", case.velocity)?;
    check_positive("/rock/side_length_m", case.rock.side_length)?;
    check_positive("/rock/density_kg_m3", case.rock.density)?;
    check_positive("/rock/elastic_modulus_pa", case.rock.elastic_modulus)?;
    check_poisson("/rock/poisson_ratio", case.rock.poisson_ratio)?;
    check_positive("/column/contact_radius_m", case.column.contact_radius)?;
    if case.contact.modulus == ModulusConvention::TwoBody {
        check_positive("/column/elastic_modulus_pa", case.column.elastic_modulus)?;
        check_poisson("/column/poisson_ratio", case.column.poisson_ratio)?;
    }
    match (&case.rock.shape, case.contact.law) {
        (RockShape::Sphere { radius }, ContactLaw::HertzPoint) => {
            check_positive("/rock/radius_m", *radius)?
        }
        (RockShape::Sphere { .. }, _) => {
            return Err(PhysicsError::invalid(
                "/contact/law",
                f64::NAN,
                "a sphere rock has no flat face for a line contact: use the hertz_point law",
            ));
        }
        (_, ContactLaw::HertzPoint) => {
            check_positive("/rock/corner_radius_m", case.rock.corner_radius)?
        }
        _ => {}
    }
    Ok(())
}

/// Rock mass in double-double: ρL³ for a cube, else the shape's own mass.
fn mass_dd(rock: &Rock) -> Dd {
    match rock.shape {
        RockShape::Cube => {
            let l = rock.side_length;
            Dd::new(rock.density).mulf(l).mulf(l).mulf(l)
        }
        _ => Dd::new(rock.mass()),
    }
}

// ---------------------------------------------------------------------------------------------
// Logarithmic line contact (§A.5)

/// The closed-form solution of a log-law impact, with the quantities the duration needs.
#[derive(Debug, Clone, Copy)]
struct LogSolution {
    k: f64,
    p_ref: f64,
    g: f64,
    u: f64,
    p_max: f64,
    d_max: f64,
    p_cap: f64,
    /// e^{−u/4}.
    exp_quarter_u: f64,
}

/// Solves ½mv² = E(Pmax) on W₋₁ for a line law.
///
/// Far from the branch point (G < 0.5, where Pmax has condition (1 + u)/(2u) < 0.8 in G) G is
/// formed in plain f64; otherwise, and whenever a factor leaves [1e-290, 1e290], in
/// double-double with 1 − G taken before rounding.
fn solve_log(case: &ImpactCase) -> PhysicsResult<LogSolution> {
    if let Some(s) = solve_log_far(case) {
        return Ok(s);
    }
    let e_star = effective_modulus_dd(&case.rock, &case.column, case.contact.modulus);
    solve_log_dd(case, e_star)
}

/// E* in plain f64 (within a few ulp of [`effective_modulus`]).
fn effective_modulus_f64(rock: &Rock, column: &Column, convention: ModulusConvention) -> f64 {
    let nu = rock.poisson_ratio;
    let rock_term = (1.0 - nu * nu) / rock.elastic_modulus;
    match convention {
        ModulusConvention::Paper => rock.elastic_modulus / (1.0 - nu * nu),
        ModulusConvention::TwoBody => {
            let nus = column.poisson_ratio;
            1.0 / (rock_term + (1.0 - nus * nus) / column.elastic_modulus)
        }
    }
}

/// The f64 path of [`solve_log`]; `None` when G ≥ 0.5 or a factor is outside [1e-290, 1e290].
fn solve_log_far(case: &ImpactCase) -> Option<LogSolution> {
    let l = case.rock.side_length;
    let r = case.column.contact_radius;
    let v = case.velocity;
    let m = case.rock.mass();
    let es = effective_modulus_f64(&case.rock, &case.column, case.contact.modulus);
    let (num, den, p_cap, p_ref) = match case.contact.law {
        ContactLaw::Paper => {
            let p_cap = PI * es * l * l * l / r;
            (
                2.0 * m * r * r * v * v,
                PI * es * l * l * l * l * l,
                p_cap,
                E * p_cap,
            )
        }
        _ => {
            let p_cap = 4.0 * PI * l * es * r / (E * E);
            (
                DD_E4.hi * m * v * v,
                8.0 * PI * l * es * r * r,
                p_cap,
                4.0 * PI * l * es * r / E,
            )
        }
    };
    let in_range = |x: f64| (1e-290..=1e290).contains(&x);
    if !(in_range(num) && in_range(den)) {
        return None;
    }
    let g = num / den;
    if !(1e-250..0.5).contains(&g) {
        return None;
    }
    // 1/G and ln(1/G) off the division that gives G itself.
    let inv_g = den / num;
    let (u, exp_quarter_u) = branch_u_far(inv_g, inv_g.ln());
    Some(log_solution(PI * l * es, p_ref, p_cap, g, u, exp_quarter_u))
}

/// Pmax, δmax from u and e^{−u/4} (physics.md §A.5).
fn log_solution(k: f64, p_ref: f64, p_cap: f64, g: f64, u: f64, exp_quarter_u: f64) -> LogSolution {
    // e^{−u/4} serves Pmax = P_cap·(e^{−u/4})² and √Pmax (one exp instead of two).
    let p_max = if u < 1400.0 {
        p_cap * exp_quarter_u * exp_quarter_u
    } else {
        (p_cap.ln() - 0.5 * u).exp()
    };
    let d_max = p_max * (2.0 + u) / (2.0 * k);
    LogSolution {
        k,
        p_ref,
        g,
        u,
        p_max,
        d_max,
        p_cap,
        exp_quarter_u,
    }
}

/// The double-double path of [`solve_log`] with E* `e_star`.
fn solve_log_dd(case: &ImpactCase, e_star: Dd) -> PhysicsResult<LogSolution> {
    let l = case.rock.side_length;
    let r = case.column.contact_radius;
    let v = case.velocity;
    let m = mass_dd(&case.rock);
    let es = e_star.f64();
    let k = PI * l * es;
    // c = G/v², and P_cap = P_ref/e.
    let (c, p_cap, p_ref) = match case.contact.law {
        ContactLaw::Paper => {
            // G = 2 m R² v²/(π E* L⁵)
            let num = m.mulf(2.0).mulf(r).mulf(r);
            let l2 = two_prod(l, l);
            let l5 = l2.mul(l2).mulf(l);
            let den = DD_PI.mul(e_star).mul(l5);
            let p_cap = PI * es * l * l * l / r;
            (num.div(den), p_cap, E * p_cap)
        }
        _ => {
            // G = e⁴ m v²/(8π L E* R²)
            let num = DD_E4.mul(m);
            let den = DD_PI.mulf(8.0).mulf(l).mul(e_star).mulf(r).mulf(r);
            let p_cap = 4.0 * PI * l * es * r / (E * E);
            (num.div(den), p_cap, 4.0 * PI * l * es * r / E)
        }
    };
    let gdd = c.mulf(v).mulf(v);
    if gdd.hi > 1.0 || (gdd.hi == 1.0 && gdd.lo > 0.0) {
        let g = gdd.f64();
        return Err(PhysicsError::CapacityExceeded {
            energy_parameter: g,
            max_velocity_m_s: v / g.sqrt(),
            message: format!(
                "the impact energy exceeds the capacity of the {} contact law (G = {g:.6} > 1): \
                 the law stores at most {:.6e} J; the largest impact speed it can take with \
                 these inputs is {:.6e} m/s",
                if case.contact.law == ContactLaw::Paper {
                    "paper"
                } else {
                    "johnson"
                },
                p_cap * p_cap / (4.0 * k),
                v / g.sqrt()
            ),
        });
    }
    let (g, u) = if gdd.hi >= 1e-250 {
        let q = Dd::new(1.0).add(gdd.neg()).f64();
        if q == 0.0 {
            (1.0, 0.0)
        } else {
            let y = if q < 0.5 {
                -(-q).ln_1p()
            } else {
                -(gdd.hi.ln() + gdd.lo / gdd.hi)
            };
            (gdd.f64(), branch_u_parts(q, y))
        }
    } else {
        // G is at or below the underflow threshold: work from ln G = ln c + 2 ln v.
        let ln_g = c.hi.ln() + c.lo / c.hi + 2.0 * v.ln();
        let u = branch_u_log(-ln_g).unwrap_or(f64::INFINITY);
        (ln_g.exp(), u)
    };
    Ok(log_solution(k, p_ref, p_cap, g, u, (-0.25 * u).exp()))
}

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

/// Σ cₖ Tₖ(x) by Clenshaw's recurrence.
#[inline]
fn chebyshev(c: &[f64], x: f64) -> f64 {
    let (mut b1, mut b2) = (0.0, 0.0);
    for &ck in c[1..].iter().rev() {
        let b0 = 2.0 * x * b1 - b2 + ck;
        b2 = b1;
        b1 = b0;
    }
    x * b1 - b2 + c[0]
}

#[inline]
fn horner(c: &[f64], x: f64) -> f64 {
    c.iter().rev().fold(0.0, |acc, &ck| acc * x + ck)
}

/// J(u₀) of [`line_duration_integral`] from a fitted approximation (used by [`solve_impact`]).
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

// ---------------------------------------------------------------------------------------------
// Hertz point contact (§A.7)

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
fn hertz_log_ratio(x: f64) -> (f64, f64, f64, super::elliptic::CompleteElliptic) {
    let m = 1.0 / (1.0 + (-x).exp());
    let m1 = 1.0 / (1.0 + x.exp());
    let r = complete_elliptic_parts(m, m1);
    // B/A − 1 = m (1/2 − t(1 − m/2)) / (m₁ s), free of cancellation on the whole domain.
    let num = 0.5 - r.t * (1.0 - 0.5 * m);
    (m.ln() + num.ln() - m1.ln() - r.s.ln(), m, m1, r)
}

/// Brent's method on a bracketing interval [a, b] with f(a)·f(b) ≤ 0.
fn brent<F: FnMut(f64) -> f64>(mut f: F, mut a: f64, mut b: f64, mut fa: f64, mut fb: f64) -> f64 {
    if fa == 0.0 {
        return a;
    }
    if fb == 0.0 {
        return b;
    }
    let mut c = a;
    let mut fc = fa;
    let mut d = b - a;
    let mut e = d;
    for _ in 0..200 {
        if (fb > 0.0) == (fc > 0.0) {
            c = a;
            fc = fa;
            d = b - a;
            e = d;
        }
        if fc.abs() < fb.abs() {
            a = b;
            b = c;
            c = a;
            fa = fb;
            fb = fc;
            fc = fa;
        }
        let tol = 2.0 * f64::EPSILON * b.abs().max(1.0);
        let xm = 0.5 * (c - b);
        if xm.abs() <= tol || fb == 0.0 {
            return b;
        }
        if e.abs() >= tol && fa.abs() > fb.abs() {
            let s = fb / fa;
            let (mut p, mut q);
            if a == c {
                p = 2.0 * xm * s;
                q = 1.0 - s;
            } else {
                let qq = fa / fc;
                let r = fb / fc;
                p = s * (2.0 * xm * qq * (qq - r) - (b - a) * (r - 1.0));
                q = (qq - 1.0) * (r - 1.0) * (s - 1.0);
            }
            if p > 0.0 {
                q = -q;
            } else {
                p = -p;
            }
            if 2.0 * p < (3.0 * xm * q - (tol * q).abs()).min((e * q).abs()) {
                e = d;
                d = p / q;
            } else {
                d = xm;
                e = d;
            }
        } else {
            d = xm;
            e = d;
        }
        a = b;
        fa = fb;
        b += if d.abs() > tol { d } else { tol.copysign(xm) };
        fb = f(b);
    }
    b
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
fn hertz_logit_guess(target: f64) -> Option<f64> {
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
fn hertz_root_secant(
    target: f64,
    x0: f64,
) -> Option<(f64, f64, super::elliptic::CompleteElliptic)> {
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
fn hertz_max_deformation(mass: f64, v: f64, kappa: f64) -> f64 {
    let x = 1.25 * mass * (v * v) / kappa;
    if x.is_normal() && (1e-290..=1e290).contains(&(v * v)) {
        x.powf(0.4)
    } else {
        (1.25 * mass / kappa).powf(0.4) * v.powf(0.8)
    }
}

// ---------------------------------------------------------------------------------------------
// Entry points

/// The force–approach law P(δ) of a case (physics.md §A.5, §A.7): k = πLE* and P_ref for the log
/// laws, κ for `hertz_point`.
///
/// # Errors
/// `InvalidInput` for a sphere with a line law or a non-positive input.
///
/// # Examples
/// ```
/// use gangue::physics::contact::{force_law, ForceLaw};
/// let law = force_law(&Default::default()).unwrap();
/// let ForceLaw::Log { k, p_ref } = law else { panic!() };
/// assert!((p_ref / (std::f64::consts::E * k) - 0.72).abs() < 1e-15); // δ_cap = L²/R
/// ```
///
/// # Special cases
/// * A sphere rock uses r_c = its radius.
///
/// # References
/// physics.md §A.5 (paper: P_ref = eπE*L³/R; johnson: P_ref = 4πLE*R/e), §A.7.
pub fn force_law(case: &ImpactCase) -> PhysicsResult<ForceLaw> {
    check_case(case)?;
    let es = effective_modulus(&case.rock, &case.column, case.contact.modulus);
    let l = case.rock.side_length;
    let r = case.column.contact_radius;
    Ok(match case.contact.law {
        ContactLaw::Paper => ForceLaw::Log {
            k: PI * l * es,
            p_ref: E * PI * es * l * l * l / r,
        },
        ContactLaw::Johnson => ForceLaw::Log {
            k: PI * l * es,
            p_ref: 4.0 * PI * l * es * r / E,
        },
        ContactLaw::HertzPoint => ForceLaw::Hertz {
            kappa: hertz_geometry(es, corner_radius(case), r, case.contact.hertz_exact).stiffness,
        },
    })
}

fn corner_radius(case: &ImpactCase) -> f64 {
    match case.rock.shape {
        RockShape::Sphere { radius } => radius,
        _ => case.rock.corner_radius,
    }
}

/// The closed-form maxima of an impact against a rigid column (no duration): δmax, Pmax and
/// the law-specific quantities.
///
/// # Errors
/// `CapacityExceeded` when G > 1 (with the speed at which G = 1); `InvalidInput` as
/// [`force_law`].
///
/// # Examples
/// ```
/// use gangue::physics::contact::{impact_maxima, ImpactDetail};
/// let ImpactDetail::Line(l) = impact_maxima(&Default::default()).unwrap() else { panic!() };
/// assert!((l.max_deformation / 1.793_326_647_367_473_2e-3 - 1.0).abs() < 1e-12); // P01
/// ```
///
/// # Special cases
/// * G = 1 exactly: u = 0, δmax = δ_cap.
/// * G below the f64 range (v → 1e-300): computed from ln G; `energy_parameter` is then the
///   rounded (possibly 0) G, while W, δ, P stay exact.
/// * Hertz at v → 1e-300: Pmax ∝ v^{6/5} underflows to 0 when its true value is below 1e-308.
///
/// # References
/// physics.md §A.5 (closed form on W₋₁ through u(G)), §A.7.
pub fn impact_maxima(case: &ImpactCase) -> PhysicsResult<ImpactDetail> {
    check_case(case)?;
    let r = case.column.contact_radius;
    let l = case.rock.side_length;
    match case.contact.law {
        ContactLaw::Paper | ContactLaw::Johnson => {
            let s = solve_log(case)?;
            // √Pmax directly, so that a and p₀ = √(P E*/(πRL)) survive an underflowing Pmax.
            let sqrt_p = if s.u < 1400.0 {
                s.p_cap.sqrt() * s.exp_quarter_u
            } else {
                (0.5 * s.p_cap.ln() - 0.25 * s.u).exp()
            };
            let root_r_over_k = (r / s.k).sqrt();
            let half_width = 2.0 * sqrt_p * root_r_over_k;
            Ok(ImpactDetail::Line(LineImpact {
                energy_parameter: s.g,
                lambert_w: -1.0 - s.u,
                u: s.u,
                max_deformation: s.d_max,
                max_force: s.p_max,
                half_width,
                max_pressure: sqrt_p / (root_r_over_k * PI * l),
                energy_capacity: s.p_cap * s.p_cap / (4.0 * s.k),
                deformation_capacity: s.p_ref / (E * s.k),
                force_capacity: s.p_cap,
            }))
        }
        ContactLaw::HertzPoint => {
            let es = effective_modulus(&case.rock, &case.column, case.contact.modulus);
            let mass = case.rock.mass();
            let v = case.velocity;
            let h = hertz_geometry(es, corner_radius(case), r, case.contact.hertz_exact);
            let d = hertz_max_deformation(mass, v, h.stiffness);
            let a = h.semi_axis_factor.sqrt() * d.sqrt();
            Ok(ImpactDetail::Hertz(HertzImpact {
                max_deformation: d,
                max_force: h.stiffness * d * d.sqrt(),
                stiffness: h.stiffness,
                equivalent_radius: h.equivalent_radius,
                max_deformation_equivalent_radius: if h.stiffness == h.stiffness_equivalent_radius {
                    d
                } else {
                    hertz_max_deformation(mass, v, h.stiffness_equivalent_radius)
                },
                axis_ratio: h.axis_ratio,
                semi_axes: [a, a * h.axis_ratio],
                // 3P/(2πab) = 3κ√δ/(2π·factor·(b/a)), without forming P (it may underflow).
                max_pressure: 3.0 * h.stiffness * d.sqrt()
                    / (2.0 * PI * h.semi_axis_factor * h.axis_ratio),
            }))
        }
    }
}

/// Solves the impact of the case against a rigid column: maxima, capacity and contact duration.
///
/// # Errors
/// `CapacityExceeded` when G > 1 for a log law; `InvalidInput` for a sphere with a line law or a
/// non-positive input.
///
/// # Examples
/// ```
/// let r = gangue::physics::contact::solve_impact(&Default::default()).unwrap();
/// assert!((r.contact_duration / 1.108_170_537_036_032_3e-3 - 1.0).abs() < 1e-9); // P01
/// ```
///
/// # Special cases
/// * See [`impact_maxima`]; the duration is finite and positive on the whole valid domain.
///
/// # References
/// physics.md §A.5–§A.7.
pub fn solve_impact(case: &ImpactCase) -> PhysicsResult<ImpactResult> {
    let detail = impact_maxima(case)?;
    let mass = case.rock.mass();
    let v = case.velocity;
    let contact_duration = match &detail {
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
    };
    Ok(ImpactResult {
        mass,
        kinetic_energy: 0.5 * mass * v * v,
        effective_modulus: effective_modulus(&case.rock, &case.column, case.contact.modulus),
        contact_radius: case.column.contact_radius,
        law: case.contact.law,
        modulus: case.contact.modulus,
        detail,
        contact_duration,
    })
}

/// `n` points of the force–approach curve P(δ), δ equally spaced from 0 to `max_deformation`
/// (m): (δ in m, P in N). For the log laws δ is clamped to δ_cap.
///
/// # Examples
/// ```
/// use gangue::physics::contact::{force_curve, ForceLaw};
/// let (d, p) = force_curve(&ForceLaw::Hertz { kappa: 1e9 }, 1e-3, 3);
/// assert_eq!(d, vec![0.0, 5e-4, 1e-3]);
/// assert!((p[2] - 1e9 * 1e-3f64.powf(1.5)).abs() < 1e-6);
/// ```
///
/// # Special cases
/// * `n == 0`: empty; `n == 1`: the single point (0, 0).
///
/// # References
/// physics.md §A.5 (P(δ) = kδ/(−W₋₁(−kδ/P_ref))).
pub fn force_curve(law: &ForceLaw, max_deformation: f64, n: usize) -> (Vec<f64>, Vec<f64>) {
    let cap = law.deformation_capacity().unwrap_or(f64::INFINITY);
    let mut deltas = Vec::with_capacity(n);
    let mut forces = Vec::with_capacity(n);
    for i in 0..n {
        let d = if i + 1 == n && n > 1 {
            max_deformation
        } else if n > 1 {
            max_deformation * (i as f64 / (n - 1) as f64)
        } else {
            0.0
        };
        let d = d.min(cap);
        let p = law.force(d).unwrap_or(match *law {
            ForceLaw::Log { p_ref, .. } => p_ref / E,
            ForceLaw::Hertz { .. } => 0.0,
        });
        deltas.push(d);
        forces.push(p);
    }
    (deltas, forces)
}

impl ForceLaw {
    /// Contact force P(δ) at approach δ ≥ 0, N; 0 for δ ≤ 0. For the log laws this is the W₋₁
    /// inverse P = kδ/(1 + u(e·kδ/P_ref)); past the capacity δ_cap (by more than the rounding of
    /// e·kδ/P_ref, 8 ulp) it returns `None`.
    pub fn force(&self, delta: f64) -> Option<f64> {
        if delta <= 0.0 {
            return Some(0.0);
        }
        match *self {
            ForceLaw::Log { k, p_ref } => {
                let g = E * k * delta / p_ref;
                let u = if g > 1.0 && g <= 1.0 + 8.0 * f64::EPSILON {
                    // δ_cap itself, rounded just past the branch point.
                    Some(0.0)
                } else if g >= 1e-250 {
                    super::lambert::branch_u(g)
                } else {
                    // G underflows: u from ln G.
                    branch_u_log(-((E * k / p_ref).ln() + delta.ln()))
                };
                u.map(|u| k * delta / (1.0 + u))
            }
            ForceLaw::Hertz { kappa } => Some(kappa * delta * delta.sqrt()),
        }
    }

    /// Approach at the capacity δ_cap = P_ref/(e k), m; `None` for Hertz (unbounded).
    pub fn deformation_capacity(&self) -> Option<f64> {
        match *self {
            ForceLaw::Log { k, p_ref } => Some(p_ref / (E * k)),
            ForceLaw::Hertz { .. } => None,
        }
    }
}

#[cfg(test)]
#[allow(clippy::field_reassign_with_default)] // cases read as "the default, except …"
mod tests {
    use super::*;
    use crate::physics::material::ContactModel;

    fn rel(a: f64, b: f64) -> f64 {
        ((a - b) / b).abs()
    }

    fn line(case: &ImpactCase) -> (ImpactResult, LineImpact) {
        let r = solve_impact(case).unwrap();
        let ImpactDetail::Line(l) = r.detail else {
            panic!("not a line result")
        };
        (r, l)
    }

    /// Verification case P01 (physics.md §A.8), expected values from cases.json.
    #[test]
    fn p01_paper_base() {
        let (r, l) = line(&ImpactCase::default());
        assert!(rel(r.mass, 67.5) < 1e-15);
        assert!(rel(r.kinetic_energy, 843.75) < 1e-15);
        assert!(rel(r.effective_modulus, 5_425_347_222.222_222) < 1e-15);
        assert!(rel(l.energy_parameter, 1.273_239_544_735_162_8e-6) < 1e-15);
        assert!(rel(l.lambert_w, -17.432_269_118_399_564) < 1e-15);
        assert!(rel(l.max_deformation, 0.001_793_326_647_367_473_2) < 1e-14);
        assert!(rel(l.max_force, 994_968.337_247_573_7) < 1e-14);
        assert!(rel(l.half_width, 0.009_863_710_098_875_706) < 1e-14);
        assert!(rel(l.max_pressure, 214_056_208.742_962_4) < 1e-14);
        assert!(rel(l.energy_capacity, 662_679_700.366_596_9) < 1e-14);
        assert!(rel(l.deformation_capacity, 0.72) < 1e-15);
        assert!(rel(l.force_capacity, 3_681_553_890.925_538_5) < 1e-15);
        assert!(rel(r.contact_duration, 0.001_108_170_537_036_032_3) < 1e-10);
    }

    #[test]
    fn p02_paper_two_body_low_corner() {
        let mut c = ImpactCase::default();
        c.velocity = 4.0;
        c.rock.side_length = 0.2;
        c.rock.elastic_modulus = 4e9;
        c.rock.density = 2000.0;
        c.contact.modulus = ModulusConvention::TwoBody;
        let (r, l) = line(&c);
        assert!(rel(r.mass, 16.000_000_000_000_004) < 1e-15);
        assert!(rel(r.effective_modulus, 4_259_397_295.282_717_7) < 1e-15);
        assert!(rel(l.energy_parameter, 1.868_280_088_219_986e-6) < 1e-15);
        assert!(rel(l.lambert_w, -17.025_186_070_461_633) < 1e-15);
        assert!(rel(l.max_deformation, 0.000_955_377_036_336_523_4) < 1e-14);
        assert!(rel(l.max_force, 283_695.898_135_343_74) < 1e-14);
        assert!(rel(l.half_width, 0.007_280_270_582_855_752) < 1e-14);
        assert!(rel(l.max_pressure, 124_038_259.318_168_49) < 1e-14);
        assert!(rel(l.energy_capacity, 68_512_211.208_091_78) < 1e-14);
        assert!(rel(l.deformation_capacity, 0.320_000_000_000_000_06) < 1e-15);
        assert!(rel(l.force_capacity, 856_402_640.101_147) < 1e-15);
        assert!(rel(r.contact_duration, 0.000_737_681_190_870_758_8) < 1e-10);
    }

    #[test]
    fn p03_johnson_two_body() {
        let mut c = ImpactCase::default();
        c.contact = ContactModel {
            law: ContactLaw::Johnson,
            modulus: ModulusConvention::TwoBody,
            hertz_exact: true,
        };
        let (r, l) = line(&c);
        assert!(rel(r.effective_modulus, 5_299_557_486.949_84) < 1e-15);
        assert!(rel(l.energy_parameter, 0.000_147_570_979_927_310_92) < 1e-15);
        assert!(rel(l.lambert_w, -12.333_522_216_823_81) < 1e-15);
        assert!(rel(l.max_deformation, 0.001_560_460_766_915_467_6) < 1e-14);
        assert!(rel(l.max_force, 1_169_092.019_221_179_7) < 1e-14);
        assert!(rel(l.half_width, 0.010_818_174_504_044_884) < 1e-14);
        assert!(rel(l.max_pressure, 229_326_150.752_163_74) < 1e-14);
        assert!(rel(l.energy_capacity, 5_717_587.566_441_628) < 1e-14);
        assert!(rel(l.deformation_capacity, 0.067_667_641_618_306_35) < 1e-15);
        assert!(rel(l.force_capacity, 337_980_602.231_884_54) < 1e-15);
        assert!(rel(r.contact_duration, 0.000_958_156_107_119_769) < 1e-10);
    }

    #[test]
    fn p04_hertz_point_exact() {
        let mut c = ImpactCase::default();
        c.contact.law = ContactLaw::HertzPoint;
        c.contact.modulus = ModulusConvention::TwoBody;
        c.rock.corner_radius = 0.02;
        let r = solve_impact(&c).unwrap();
        let ImpactDetail::Hertz(h) = r.detail else {
            panic!()
        };
        assert!(rel(h.stiffness, 963_336_672.040_085_3) < 1e-13);
        assert!(rel(h.max_deformation, 0.005_446_911_017_075_47) < 1e-13);
        assert!(rel(h.max_force, 387_260.778_336_077_1) < 1e-13);
        assert!(rel(h.equivalent_radius, 0.018_569_533_817_705_187) < 1e-15);
        assert!(
            rel(
                h.max_deformation_equivalent_radius,
                0.005_447_910_697_006_21
            ) < 1e-14
        );
        assert!(rel(h.axis_ratio, 0.905_800_144_462_170_7) < 1e-13);
        assert!(rel(r.contact_duration, 0.003_206_351_605_556_613_6) < 1e-13);
        // p₀ = 3P/(2πab) and the semi-axes are consistent with P.
        let [a, b] = h.semi_axes;
        assert!(rel(h.max_pressure, 3.0 * h.max_force / (2.0 * PI * a * b)) < 1e-14);
        assert!(rel(b / a, h.axis_ratio) < 1e-15);
    }

    #[test]
    fn p14_capacity_exceeded_reports_the_limit_speed() {
        let mut c = ImpactCase::default();
        c.velocity = 400.0;
        c.rock.side_length = 0.05;
        c.rock.elastic_modulus = 5e8;
        let Err(PhysicsError::CapacityExceeded {
            energy_parameter,
            max_velocity_m_s,
            ..
        }) = solve_impact(&c)
        else {
            panic!("expected capacity_exceeded")
        };
        assert!(energy_parameter > 1.0);
        // At the reported speed G = 1 (to rounding): just below it solves, just above it fails.
        c.velocity = max_velocity_m_s * (1.0 - 1e-12);
        let (_, l) = line(&c);
        assert!(l.u < 1e-5 && l.energy_parameter <= 1.0);
        c.velocity = max_velocity_m_s * (1.0 + 1e-12);
        assert!(matches!(
            solve_impact(&c),
            Err(PhysicsError::CapacityExceeded { .. })
        ));
    }

    #[test]
    fn sphere_allows_only_hertz() {
        let mut c = ImpactCase::default();
        c.rock.shape = RockShape::Sphere { radius: 0.1 };
        let Err(PhysicsError::InvalidInput { field, .. }) = solve_impact(&c) else {
            panic!()
        };
        assert_eq!(field, "/contact/law");
        c.contact.law = ContactLaw::HertzPoint;
        let r = solve_impact(&c).unwrap();
        assert!(rel(r.mass, 2500.0 * 4.0 / 3.0 * PI * 1e-3) < 1e-15);
        let ImpactDetail::Hertz(h) = r.detail else {
            panic!()
        };
        // r_c = the sphere's radius, not the default corner radius.
        let g = hertz_geometry(r.effective_modulus, 0.1, 0.125, true);
        assert_eq!(h.stiffness, g.stiffness, "{h:?} {g:?}");
    }

    #[test]
    fn force_curve_ends_at_the_maximum() {
        for law in [
            ContactLaw::Paper,
            ContactLaw::Johnson,
            ContactLaw::HertzPoint,
        ] {
            let mut c = ImpactCase::default();
            c.contact.law = law;
            let f = force_law(&c).unwrap();
            let (dmax, pmax) = match impact_maxima(&c).unwrap() {
                ImpactDetail::Line(l) => (l.max_deformation, l.max_force),
                ImpactDetail::Hertz(h) => (h.max_deformation, h.max_force),
            };
            let (d, p) = force_curve(&f, dmax, 101);
            assert_eq!((d.len(), p.len()), (101, 101));
            assert_eq!((d[0], p[0]), (0.0, 0.0));
            assert_eq!(d[100], dmax);
            assert!(rel(p[100], pmax) < 1e-14, "{law:?}");
            assert!(p.windows(2).all(|w| w[1] > w[0]));
        }
        assert!(
            force_curve(&ForceLaw::Hertz { kappa: 1.0 }, 1.0, 0)
                .0
                .is_empty()
        );
    }

    #[test]
    fn duration_integral_limits_and_cost() {
        // G → 0: P ∝ kδ/ln(…) is nearly linear, and J → π/2 (a half sine) as u₀ → ∞.
        let j = line_duration_integral(1e6);
        assert!(j.converged && (j.value - FRAC_PI_2).abs() < 1e-5, "{j:?}");
        for u in [0.0, 1e-8, 0.3, 16.4, 1500.0] {
            let j = line_duration_integral(u);
            assert!(j.converged && j.evaluations < 1000, "u = {u}: {j:?}");
        }
    }

    #[test]
    fn duration_at_the_branch_point_is_finite() {
        let j0 = line_duration_integral(0.0);
        let j1 = line_duration_integral(1e-9);
        assert!(j0.converged && j1.converged);
        assert!(j0.value.is_finite() && (j0.value - j1.value).abs() < 1e-6);
    }

    /// The fitted J against the adaptive quadrature (the reference) on a dense grid: u₀ from
    /// 1e-14 to 1e8 by 1/40 decade, 0 to 30 in steps of 0.01, and around the piece joints.
    #[test]
    fn duration_factor_matches_the_quadrature() {
        let mut grid: Vec<f64> = (0..=880)
            .map(|i| 10f64.powf(-14.0 + i as f64 / 40.0))
            .collect();
        grid.extend((0..=3000).map(|i| i as f64 * 0.01));
        for joint in [3.0 / 7.0, 1.0 / 9.0] {
            grid.extend((-20..=20).map(|i| joint * (1.0 + i as f64 * 1e-9)));
        }
        let mut worst = (0.0f64, 0.0);
        for &u0 in &grid {
            let j = line_duration_integral(u0);
            assert!(j.converged, "u0 = {u0}");
            let e = rel(line_duration_factor(u0), j.value);
            if e > worst.0 {
                worst = (e, u0);
            }
        }
        eprintln!(
            "worst relative deviation {:.2e} at u0 = {}",
            worst.0, worst.1
        );
        assert!(worst.0 <= 1e-10, "{worst:?}");
    }

    /// The exact limits: J(0) from a 30-digit quadrature, J → π/2 + (π ln 2/2)/(1 + u₀).
    #[test]
    #[allow(clippy::excessive_precision)] // mpmath digits kept as computed
    fn duration_factor_limits() {
        assert!(rel(line_duration_factor(0.0), 2.757_470_600_105_563_3) < 1e-14);
        for u0 in [1e7, 1e9, 1e15, 1e300] {
            let t = 1.0 / (1.0 + u0);
            let expected = FRAC_PI_2 + 0.5 * PI * std::f64::consts::LN_2 * t;
            assert!(rel(line_duration_factor(u0), expected) < 1e-13, "{u0}");
        }
        assert!(rel(line_duration_factor(f64::INFINITY), FRAC_PI_2) < 1e-14);
        // 30-digit mpmath quadrature (u₀ = 2.37e-5 is where the adaptive reference is worst).
        for (u0, j) in [
            (2.371_373_705_661_655_4e-5, 2.757_437_906_991_051_6),
            (0.05, 2.693_162_454_995_354_1),
            (0.3, 2.458_476_488_688_523_9),
            (2.0, 1.941_710_330_133_186_9),
            (16.432_269_118_399_564, 1.633_473_476_476_284_4),
        ] {
            assert!(rel(line_duration_factor(u0), j) < 1e-14, "{u0}");
        }
        assert!(line_duration_factor(-1e-300).is_nan() && line_duration_factor(f64::NAN).is_nan());
    }

    /// The fitted starting value of the Hertz root is within 3e-6 of the root, and the secant
    /// iteration from it agrees with Brent.
    #[test]
    fn hertz_guess_lies_in_the_first_bracket() {
        for i in 0..=2000 {
            let target = -12.0 + 20.0 * i as f64 / 2000.0;
            let h = hertz_geometry(1.0, target.exp(), 1.0, true);
            let m = h.eccentricity_squared;
            let x = (m / (h.axis_ratio * h.axis_ratio)).ln();
            let guess = hertz_logit_guess(target).unwrap();
            assert!(
                (guess - x).abs() < 3e-6,
                "ln(rc/R) = {target}: {guess} vs {x}"
            );
            // The secant iteration converges from it, to Brent's root on a wide bracket.
            let (m_secant, m1_secant, _) = hertz_root_secant(target, guess).unwrap();
            let g = |x: f64| hertz_log_ratio(x).0 - target;
            let (lo, hi) = (guess - 0.5, guess + 0.5);
            let x_brent = brent(g, lo, hi, g(lo), g(hi));
            let (_, m_brent, m1_brent, _) = hertz_log_ratio(x_brent);
            assert!(rel(m_secant, m_brent) < 1e-14, "{target}: m");
            assert!(rel(m1_secant, m1_brent) < 1e-14, "{target}: 1 − m");
        }
        assert!(hertz_logit_guess(-12.5).is_none() && hertz_logit_guess(8.5).is_none());
    }
}
