//! The force–approach law P(δ) of a contact (physics.md §A.5, §A.7): its parameters from a
//! case, its force, capacity and stored energy.

use std::f64::consts::{E, PI};

use super::hertz::hertz_geometry;
use super::log_law::log_law_forces;
use super::modulus::{effective_modulus, effective_modulus_f64};
use super::{check_case, corner_radius};
use crate::physics::error::PhysicsResult;
use crate::physics::material::{ContactLaw, ImpactCase};
use crate::physics::numeric::lambert::{branch_u, branch_u_log};

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
    let l = case.rock.side_length;
    let r = case.column.contact_radius;
    Ok(match case.contact.law {
        law @ (ContactLaw::Paper | ContactLaw::Johnson) => {
            let es = effective_modulus(&case.rock, &case.column, case.contact.modulus);
            ForceLaw::Log {
                k: PI * l * es,
                p_ref: log_law_forces(law, es, l, r).1,
            }
        }
        // The same E* (plain f64) as `impact_maxima`, so the coupled and rigid κ are identical.
        ContactLaw::HertzPoint => ForceLaw::Hertz {
            kappa: hertz_geometry(
                effective_modulus_f64(&case.rock, &case.column, case.contact.modulus),
                corner_radius(case),
                r,
                case.contact.hertz_exact,
            )
            .stiffness,
        },
    })
}

impl ForceLaw {
    /// Contact force P(δ) at approach δ ≥ 0, N; 0 for δ ≤ 0. For the log laws this is the W₋₁
    /// inverse P = kδ/(1 + u(e·kδ/P_ref)); past the capacity δ_cap (by more than the rounding of
    /// e·kδ/P_ref, 8 ulp) it returns `None`.
    #[must_use]
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
                    branch_u(g)
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
    #[must_use]
    pub fn deformation_capacity(&self) -> Option<f64> {
        match *self {
            ForceLaw::Log { k, p_ref } => Some(p_ref / (E * k)),
            ForceLaw::Hertz { .. } => None,
        }
    }

    /// A log law from its capacity: k = P_cap/δ_cap, N/m, and P_ref = e·P_cap, N (the law of a
    /// solved impact whose capacity force `force_capacity` and approach `deformation_capacity`
    /// are known).
    #[must_use]
    pub fn log_from_capacity(force_capacity: f64, deformation_capacity: f64) -> Self {
        ForceLaw::Log {
            k: force_capacity / deformation_capacity,
            p_ref: E * force_capacity,
        }
    }

    /// Force at the capacity P_cap = P_ref/e, N; `None` for Hertz (unbounded).
    #[must_use]
    pub fn force_capacity(&self) -> Option<f64> {
        match *self {
            ForceLaw::Log { p_ref, .. } => Some(p_ref / E),
            ForceLaw::Hertz { .. } => None,
        }
    }

    /// Largest energy the law stores E_cap = P_ref²/(4e²k), J; `None` for Hertz (unbounded).
    #[must_use]
    pub fn energy_capacity(&self) -> Option<f64> {
        match *self {
            ForceLaw::Log { k, p_ref } => Some(p_ref * p_ref / (4.0 * E.powi(2) * k)),
            ForceLaw::Hertz { .. } => None,
        }
    }
}

/// Energy ∫₀^δ P dδ′ stored in the contact at approach δ, J.
///
/// # Special cases
/// δ ≤ 0 gives 0; past the log law's capacity `None`.
///
/// # References
/// physics.md §A.5: E(P) = P²/(4k)·(2 ln(P_ref/P) − 1); §A.7: E = (2/5)κδ^{5/2}.
#[must_use]
pub fn contact_energy(law: &ForceLaw, delta: f64) -> Option<f64> {
    if delta <= 0.0 {
        return Some(0.0);
    }
    match *law {
        ForceLaw::Log { k, p_ref } => {
            let p = law.force(delta)?;
            if p == 0.0 {
                return Some(0.0);
            }
            // For a subnormal P the quotient P_ref/P overflows (and P²·∞ was NaN): then
            // ln P_ref − ln P, finite, and P² underflowing to 0 gives the right limit.
            let q = p_ref / p;
            let ln_q = if q.is_finite() {
                q.ln()
            } else {
                p_ref.ln() - p.ln()
            };
            Some(p * p / (4.0 * k) * (2.0 * ln_q - 1.0))
        }
        ForceLaw::Hertz { kappa } => Some(0.4 * kappa * delta * delta * delta.sqrt()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rel(a: f64, b: f64) -> f64 {
        ((a - b) / b).abs()
    }

    #[test]
    fn capacities_are_consistent_with_the_law() {
        // δ_cap = P_ref/(ek), P_cap = P(δ_cap) = P_ref/e, E_cap = ∫P dδ at δ_cap = P_cap²/(4k).
        let law = ForceLaw::Log {
            k: 3.0e9,
            p_ref: 2.0e7,
        };
        let d_cap = law.deformation_capacity().unwrap();
        let p_cap = law.force_capacity().unwrap();
        assert!(rel(law.force(d_cap).unwrap(), p_cap) < 1e-12);
        let e_cap = law.energy_capacity().unwrap();
        assert!(rel(e_cap, p_cap * p_cap / (4.0 * 3.0e9)) < 1e-14);
        assert!(rel(contact_energy(&law, d_cap).unwrap(), e_cap) < 1e-12);
        assert!(law.force(d_cap * 1.001).is_none());
        let back = ForceLaw::log_from_capacity(p_cap, d_cap);
        let ForceLaw::Log { k, p_ref } = back else {
            panic!()
        };
        assert!(rel(k, 3.0e9) < 1e-15 && rel(p_ref, 2.0e7) < 1e-15);
    }

    #[test]
    fn contact_energy_is_the_integral_of_the_force() {
        // Simpson's rule on P(δ) against the closed forms, for both laws.
        for law in [
            ForceLaw::Log {
                k: 3.0e9,
                p_ref: 2.0e7,
            },
            ForceLaw::Hertz { kappa: 1.0e9 },
        ] {
            let d = 1e-3;
            let n = 2000;
            let h = d / n as f64;
            let mut s = law.force(0.0).unwrap() + law.force(d).unwrap();
            for i in 1..n {
                let w = if i % 2 == 1 { 4.0 } else { 2.0 };
                s += w * law.force(i as f64 * h).unwrap();
            }
            let simpson = s * h / 3.0;
            assert!(
                rel(contact_energy(&law, d).unwrap(), simpson) < 1e-8,
                "{law:?}"
            );
        }
        let hertz = ForceLaw::Hertz { kappa: 1.0 };
        assert_eq!(contact_energy(&hertz, -1.0), Some(0.0));
        assert!(hertz.force_capacity().is_none() && hertz.energy_capacity().is_none());
    }
}
