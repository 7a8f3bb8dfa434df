//! Whether a result lies inside the validity of its models, as named warnings with documented
//! thresholds (the service answers anyway; the warning says how far to trust the numbers).
//!
//! | code | warned when | why |
//! |---|---|---|
//! | `contact_pressure_above_yield` | p₀ > σ_y of the column | the contact laws are elastic: above yield the column's surface deforms plastically and the elastic p₀, δmax, Pmax no longer describe it |
//! | `approach_above_tenth_of_radius` | δmax > 0.1·R (R the column's contact radius) | the laws assume an approach small against the curvature radius (half-space theory); at δ ~ R/10 the geometry has changed |
//! | `near_capacity` | G > 0.9 (log laws) | the impact stores most of the energy the law can hold; force, half-width and pressure are ill-conditioned there |
//! | `stress_utilisation_above_one` | σ_max/σ_y > 1 | the column model is a linear-elastic beam: past yield it bends plastically and the stresses, energies and decay are not those of an elastic column |
//!
//! Each threshold is strict: a value equal to it is not warned. The thresholds are the
//! constants below; the codes are stable (api.md, warnings).

use super::contact::{ImpactDetail, ImpactResult};
use super::material::ImpactCase;

/// A named warning attached to a result.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Warning {
    /// Stable code, e.g. `energy_ratio_above_one`.
    pub code: &'static str,
    /// Human-readable explanation.
    pub message: String,
}

/// Code of the warning that the maximum contact pressure exceeds the column's yield stress.
pub const CONTACT_PRESSURE_ABOVE_YIELD: &str = "contact_pressure_above_yield";
/// Code of the warning that the maximum approach exceeds a tenth of the contact radius.
pub const APPROACH_ABOVE_TENTH_OF_RADIUS: &str = "approach_above_tenth_of_radius";
/// Code of the warning that the largest bending stress exceeds the yield stress.
pub const STRESS_UTILISATION_ABOVE_ONE: &str = "stress_utilisation_above_one";

/// Largest approach δmax relative to the column's contact radius R the elastic contact laws are
/// trusted for (dimensionless): 0.1.
pub const MAX_APPROACH_TO_RADIUS: f64 = 0.1;

/// Largest stress utilisation σ_max/σ_y of a linear-elastic column (dimensionless): 1.
pub const MAX_STRESS_UTILISATION: f64 = 1.0;

/// Warnings on a contact with maximum pressure `max_pressure` (Pa) and maximum approach
/// `max_deformation` (m) against a column of yield stress `yield_stress` (Pa) and contact radius
/// `contact_radius` (m).
#[must_use]
pub fn contact_warnings(
    max_pressure: f64,
    max_deformation: f64,
    yield_stress: f64,
    contact_radius: f64,
) -> Vec<Warning> {
    let mut out = Vec::new();
    if max_pressure > yield_stress {
        out.push(Warning {
            code: CONTACT_PRESSURE_ABOVE_YIELD,
            message: format!(
                "the maximum contact pressure {max_pressure:.4e} Pa exceeds the column's yield \
                 stress {yield_stress:.4e} Pa ({:.3} ×): the elastic contact law is outside its \
                 validity; the column's surface yields and the contact maxima are not reliable",
                max_pressure / yield_stress
            ),
        });
    }
    let limit = MAX_APPROACH_TO_RADIUS * contact_radius;
    if max_deformation > limit {
        out.push(Warning {
            code: APPROACH_ABOVE_TENTH_OF_RADIUS,
            message: format!(
                "the maximum approach {max_deformation:.4e} m exceeds a tenth of the contact \
                 radius ({limit:.4e} m): the contact law assumes an approach small against the \
                 radius; the result is outside its validity"
            ),
        });
    }
    out
}

/// Code of the warning that a log-law impact stores most of the energy its law can hold.
pub const NEAR_CAPACITY: &str = "near_capacity";

/// Energy parameter G above which a log-law impact is warned as near the law's capacity
/// (dimensionless): 0.9.
pub const NEAR_CAPACITY_ENERGY_PARAMETER: f64 = 0.9;

/// Warnings of an impact against a rigid column: near the law's capacity (G > 0.9), then the
/// validity of the contact (pressure and approach).
#[must_use]
pub fn impact_warnings(case: &ImpactCase, result: &ImpactResult) -> Vec<Warning> {
    let mut out = Vec::new();
    if let ImpactDetail::Line(l) = &result.detail
        && l.energy_parameter > NEAR_CAPACITY_ENERGY_PARAMETER
    {
        out.push(Warning {
            code: NEAR_CAPACITY,
            message: format!(
                "G = {:.6} is within 10 % of the law's capacity (G = 1): the impact stores most of \
                 the energy the law can hold; force, half-width and pressure are ill-conditioned \
                 there (only the approach is well-conditioned)",
                l.energy_parameter
            ),
        });
    }
    out.extend(contact_warnings(
        result.max_pressure(),
        result.max_deformation(),
        case.column.yield_stress,
        result.contact_radius,
    ));
    out
}

/// The maximum contact pressure at a contact force `force` (N) on the law of `impact`, Pa: the
/// rigid-column p₀ scaled as √P (line laws, p₀ = √(P E*/(πRL))) or P^{1/3} (Hertz, p₀ ∝ P/(ab)
/// with a, b ∝ P^{1/3}).
#[must_use]
pub fn contact_pressure_at(impact: &ImpactResult, force: f64) -> f64 {
    let (p0, pmax) = (impact.max_pressure(), impact.max_force());
    if !(pmax > 0.0 && force >= 0.0) {
        return p0;
    }
    match impact.detail {
        ImpactDetail::Line(_) => p0 * (force / pmax).sqrt(),
        ImpactDetail::Hertz(_) => p0 * (force / pmax).cbrt(),
    }
}

/// The warning that the stress utilisation `utilisation` (largest bending stress / yield
/// stress) exceeds [`MAX_STRESS_UTILISATION`], if it does.
#[must_use]
pub fn stress_warning(utilisation: f64) -> Option<Warning> {
    (utilisation > MAX_STRESS_UTILISATION).then(|| Warning {
        code: STRESS_UTILISATION_ABOVE_ONE,
        message: format!(
            "the largest bending stress is {:.1} % of the yield stress: the column yields, and \
             the linear-elastic column model (stresses, energies, decay) is outside its validity",
            100.0 * utilisation
        ),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::contact::solve_impact;

    fn codes(w: &[Warning]) -> Vec<&'static str> {
        w.iter().map(|w| w.code).collect()
    }

    #[test]
    fn pressure_threshold_is_the_yield_stress() {
        let y = 345e6;
        assert!(codes(&contact_warnings(y, 0.0, y, 0.125)).is_empty());
        let above = y * (1.0 + f64::EPSILON);
        assert_eq!(
            codes(&contact_warnings(above, 0.0, y, 0.125)),
            [CONTACT_PRESSURE_ABOVE_YIELD]
        );
        let below = y * (1.0 - f64::EPSILON);
        assert!(codes(&contact_warnings(below, 0.0, y, 0.125)).is_empty());
    }

    #[test]
    fn approach_threshold_is_a_tenth_of_the_radius() {
        let r = 0.125;
        let at = MAX_APPROACH_TO_RADIUS * r;
        assert!(codes(&contact_warnings(0.0, at, 1.0, r)).is_empty());
        assert_eq!(
            codes(&contact_warnings(0.0, at * (1.0 + 1e-15), 1.0, r)),
            [APPROACH_ABOVE_TENTH_OF_RADIUS]
        );
        assert!(codes(&contact_warnings(0.0, at * (1.0 - 1e-15), 1.0, r)).is_empty());
    }

    #[test]
    fn utilisation_threshold_is_one() {
        assert!(stress_warning(1.0).is_none());
        assert!(stress_warning(1.0 - f64::EPSILON).is_none());
        let w = stress_warning(1.0 + f64::EPSILON).unwrap();
        assert_eq!(w.code, STRESS_UTILISATION_ABOVE_ONE);
        assert!(stress_warning(2.219).unwrap().message.contains("221.9 %"));
    }

    #[test]
    fn default_impact_is_inside_the_contact_validity() {
        // P01: p₀ ≈ 2.3e8 Pa < 345 MPa, δmax ≈ 1.8 mm < 12.5 mm.
        let case = ImpactCase::default();
        let r = solve_impact(&case).unwrap();
        assert!(r.max_pressure() < case.column.yield_stress);
        assert!(impact_warnings(&case, &r).is_empty());
    }

    #[test]
    fn pressure_scales_with_the_force_like_the_law() {
        let case = ImpactCase::default();
        let r = solve_impact(&case).unwrap();
        let p = r.max_force();
        assert_eq!(contact_pressure_at(&r, p), r.max_pressure());
        let quarter = contact_pressure_at(&r, 0.25 * p);
        assert!((quarter / (0.5 * r.max_pressure()) - 1.0).abs() < 1e-15);
        assert_eq!(contact_pressure_at(&r, 0.0), 0.0);
    }
}
