//! Logarithmic line contact (`paper`, `johnson`; physics.md §A.5): the closed-form maxima on
//! the W₋₁ branch, with G formed in double-double near the branch point.

use std::f64::consts::{E, PI};

use super::mass_dd;
use super::modulus::{effective_modulus_dd, effective_modulus_f64};
use crate::physics::error::{PhysicsError, PhysicsResult};
use crate::physics::material::{ContactLaw, ImpactCase};
use crate::physics::numeric::double_double::{DoubleDouble, two_prod};
use crate::physics::numeric::lambert::{branch_u_far, branch_u_log, branch_u_parts};

/// e⁴ in double-double (the johnson law's G = e⁴mv²/(8πLE*R²)).
const E_FOURTH: DoubleDouble = DoubleDouble {
    hi: 54.598_150_033_144_236,
    lo: 2.874_157_801_584_411_5e-15,
};

/// The log law's capacity force P_cap and reference force P_ref = e·P_cap, N, from E* (Pa), the
/// contact length L (m) and the column radius R (m): the one definition of both.
///
/// `paper`: P_cap = πE*L³/R, P_ref = e·P_cap; `johnson` (any other law): P_cap = 4πLE*R/e²,
/// P_ref = 4πLE*R/e (each formed directly, as physics.md §A.5 prints it).
#[must_use]
pub fn log_law_forces(law: ContactLaw, e_star: f64, length: f64, radius: f64) -> (f64, f64) {
    let (es, l, r) = (e_star, length, radius);
    match law {
        ContactLaw::Paper => {
            let p_cap = PI * es * l * l * l / r;
            (p_cap, E * p_cap)
        }
        _ => (4.0 * PI * l * es * r / (E * E), 4.0 * PI * l * es * r / E),
    }
}

/// The closed-form solution of a log-law impact, with the quantities the duration needs.
#[derive(Debug, Clone, Copy)]
pub(super) struct LogSolution {
    /// k = πLE*, N/m.
    pub(super) k: f64,
    /// P_ref, N.
    pub(super) p_ref: f64,
    /// Energy parameter G.
    pub(super) g: f64,
    /// u = −(1 + W₋₁(−G/e)).
    pub(super) u: f64,
    /// Pmax, N.
    pub(super) p_max: f64,
    /// δmax, m.
    pub(super) d_max: f64,
    /// P_cap = P_ref/e, N.
    pub(super) p_cap: f64,
    /// e^{−u/4}.
    pub(super) exp_quarter_u: f64,
}

/// Solves ½mv² = E(Pmax) on W₋₁ for a line law.
///
/// Far from the branch point (G < 0.5, where Pmax has condition (1 + u)/(2u) < 0.8 in G) G is
/// formed in plain f64; otherwise, and whenever a factor leaves [1e-290, 1e290], in
/// double-double with 1 − G taken before rounding.
pub(super) fn solve_log(case: &ImpactCase) -> PhysicsResult<LogSolution> {
    if let Some(s) = solve_log_far(case) {
        return Ok(s);
    }
    let e_star = effective_modulus_dd(&case.rock, &case.column, case.contact.modulus);
    solve_log_dd(case, e_star)
}

/// The f64 path of [`solve_log`]; `None` when G ≥ 0.5 or a factor is outside [1e-290, 1e290].
fn solve_log_far(case: &ImpactCase) -> Option<LogSolution> {
    let l = case.rock.side_length;
    let r = case.column.contact_radius;
    let v = case.velocity;
    let m = case.rock.mass();
    let es = effective_modulus_f64(&case.rock, &case.column, case.contact.modulus);
    let (p_cap, p_ref) = log_law_forces(case.contact.law, es, l, r);
    let (num, den) = match case.contact.law {
        ContactLaw::Paper => (2.0 * m * r * r * v * v, PI * es * l * l * l * l * l),
        _ => (E_FOURTH.hi * m * v * v, 8.0 * PI * l * es * r * r),
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
fn solve_log_dd(case: &ImpactCase, e_star: DoubleDouble) -> PhysicsResult<LogSolution> {
    let l = case.rock.side_length;
    let r = case.column.contact_radius;
    let v = case.velocity;
    let m = mass_dd(&case.rock);
    let es = e_star.to_f64();
    let k = PI * l * es;
    let (p_cap, p_ref) = log_law_forces(case.contact.law, es, l, r);
    // c = G/v².
    let c = match case.contact.law {
        ContactLaw::Paper => {
            // G = 2 m R² v²/(π E* L⁵)
            let num = m * 2.0 * r * r;
            let l2 = two_prod(l, l);
            let l5 = l2 * l2 * l;
            num / (DoubleDouble::PI * e_star * l5)
        }
        _ => {
            // G = e⁴ m v²/(8π L E* R²)
            let num = E_FOURTH * m;
            let den = DoubleDouble::PI * 8.0 * l * e_star * r * r;
            num / den
        }
    };
    let gdd = c * v * v;
    if gdd.hi > 1.0 || (gdd.hi == 1.0 && gdd.lo > 0.0) {
        let g = gdd.to_f64();
        return Err(PhysicsError::CapacityExceeded {
            energy_parameter: g,
            max_velocity_m_s: v / g.sqrt(),
            message: format!(
                "the impact energy exceeds the capacity of the {} contact law (G = {g:.6} > 1): \
                 the law stores at most {} J; the largest impact speed it can take with \
                 these inputs is {} m/s",
                if case.contact.law == ContactLaw::Paper {
                    "paper"
                } else {
                    "johnson"
                },
                crate::physics::error::significant(p_cap * p_cap / (4.0 * k), 7),
                crate::physics::error::significant(v / g.sqrt(), 7)
            ),
        });
    }
    let (g, u) = if gdd.hi >= 1e-250 {
        let q = (DoubleDouble::new(1.0) + -gdd).to_f64();
        if q == 0.0 {
            (1.0, 0.0)
        } else {
            let y = if q < 0.5 {
                -(-q).ln_1p()
            } else {
                -(gdd.hi.ln() + gdd.lo / gdd.hi)
            };
            (gdd.to_f64(), branch_u_parts(q, y))
        }
    } else {
        // G is at or below the underflow threshold: work from ln G = ln c + 2 ln v.
        let ln_g = c.hi.ln() + c.lo / c.hi + 2.0 * v.ln();
        let u = branch_u_log(-ln_g).unwrap_or(f64::INFINITY);
        (ln_g.exp(), u)
    };
    Ok(log_solution(k, p_ref, p_cap, g, u, (-0.25 * u).exp()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::material::ContactModel;

    #[test]
    fn capacity_approaches_are_the_papers_closed_forms() {
        // δ_cap = P_ref/(ek) with k = πLE*: paper L²/R, johnson 4R/e².
        let (es, l, r) = (5.4e9, 0.3, 0.125);
        let k = PI * l * es;
        let (p_cap, p_ref) = log_law_forces(ContactLaw::Paper, es, l, r);
        assert_eq!(p_ref, E * p_cap);
        assert!((p_ref / (E * k) / (l * l / r) - 1.0).abs() < 1e-15);
        let (p_cap, p_ref) = log_law_forces(ContactLaw::Johnson, es, l, r);
        assert!((p_ref / (E * p_cap) - 1.0).abs() < 1e-15);
        assert!((p_ref / (E * k) / (4.0 * r / (E * E)) - 1.0).abs() < 1e-15);
    }

    #[test]
    fn the_f64_and_double_double_paths_agree_far_from_the_branch_point() {
        for law in [ContactLaw::Paper, ContactLaw::Johnson] {
            for v in [0.1, 1.0, 5.0] {
                let case = ImpactCase {
                    velocity: v,
                    contact: ContactModel {
                        law,
                        ..ContactModel::default()
                    },
                    ..ImpactCase::default()
                };
                let far = solve_log_far(&case).expect("G < 0.5");
                let e_star = effective_modulus_dd(&case.rock, &case.column, case.contact.modulus);
                let dd = solve_log_dd(&case, e_star).unwrap();
                for (a, b) in [
                    (far.g, dd.g),
                    (far.u, dd.u),
                    (far.p_max, dd.p_max),
                    (far.d_max, dd.d_max),
                ] {
                    assert!((a / b - 1.0).abs() < 1e-14, "{law:?} v = {v}: {a} vs {b}");
                }
            }
        }
    }
}
