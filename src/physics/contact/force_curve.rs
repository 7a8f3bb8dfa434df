//! The force–approach curve P(δ) of an impact, from 0 to δmax (physics.md §A.5, §A.7).

use super::force_law::{ForceLaw, force_law};
use super::{ImpactResult, check_case};
use crate::physics::error::PhysicsResult;
use crate::physics::material::ImpactCase;

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
#[must_use]
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
        let p = law
            .force(d)
            .unwrap_or_else(|| law.force_capacity().unwrap_or(0.0));
        deltas.push(d);
        forces.push(p);
    }
    (deltas, forces)
}

/// The force–approach curve of an impact: equal-length arrays δ (m) and P(δ) (N).
#[derive(Debug, Clone, PartialEq)]
pub struct ForceCurve {
    /// Approach δ, m, from 0 to δmax.
    pub deformation: Vec<f64>,
    /// Force P(δ), N.
    pub force: Vec<f64>,
}

/// `points` points of P(δ) of the solved impact `result` of `case`, from 0 to its δmax.
///
/// # Errors
/// `InvalidInput` as [`force_law`].
pub fn impact_force_curve(
    case: &ImpactCase,
    result: &ImpactResult,
    points: usize,
) -> PhysicsResult<ForceCurve> {
    check_case(case)?;
    let law = force_law(case)?;
    let (deformation, force) = force_curve(&law, result.max_deformation(), points);
    Ok(ForceCurve { deformation, force })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn curve_of_the_default_impact_ends_at_its_maxima() {
        let case = ImpactCase::default();
        let r = super::super::solve_impact(&case).unwrap();
        let c = impact_force_curve(&case, &r, 11).unwrap();
        assert_eq!(c.deformation.len(), 11);
        assert_eq!(c.force.len(), 11);
        assert_eq!(c.deformation[0], 0.0);
        assert_eq!(c.deformation[10], r.max_deformation());
        assert!((c.force[10] / r.max_force() - 1.0).abs() < 1e-9);
        assert!(c.force.windows(2).all(|w| w[1] >= w[0]), "P(δ) increases");
    }

    #[test]
    fn curve_past_the_capacity_is_clamped_to_it() {
        let law = ForceLaw::Log {
            k: 1.0,
            p_ref: std::f64::consts::E,
        };
        let cap = law.deformation_capacity().unwrap();
        let (d, p) = force_curve(&law, 2.0 * cap, 3);
        assert_eq!(d[2], cap);
        assert!((p[2] - 1.0).abs() < 1e-12);
        assert_eq!(force_curve(&law, 1.0, 0), (vec![], vec![]));
        assert_eq!(force_curve(&law, 1.0, 1), (vec![0.0], vec![0.0]));
    }
}
