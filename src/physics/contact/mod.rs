//! Contact of the rock block on the column (physics.md §A), one algorithm per file:
//! [`modulus`] (E*), [`log_law`] (the logarithmic line laws `paper`, `johnson` on the W₋₁
//! branch), [`hertz`] (Hertz point contact), [`duration`] (contact duration),
//! [`force_law`](mod@force_law) (P(δ), capacity, stored energy) and
//! [`force_curve`](mod@force_curve). This file holds the case checks, the result types and the
//! entry points [`impact_maxima`] and [`solve_impact`].

use std::f64::consts::{E, PI};

use super::error::{Param, PhysicsError, PhysicsResult};
use super::material::{ContactLaw, ImpactCase, ModulusConvention, Rock, RockShape};
use super::numeric::double_double::DoubleDouble;

pub mod duration;
pub mod force_curve;
pub mod force_law;
pub mod hertz;
mod hertz_fit;
pub mod log_law;
pub mod modulus;

pub use duration::{
    DURATION_REL_TOL, HERTZ_DURATION_FACTOR, contact_duration, line_duration_factor,
    line_duration_integral,
};
pub use force_curve::{ForceCurve, force_curve, impact_force_curve};
pub use force_law::{ForceLaw, contact_energy, force_law};
pub use hertz::{HertzGeometry, hertz_geometry};
pub use log_law::log_law_forces;
pub use modulus::effective_modulus;

use hertz::hertz_max_deformation;
use log_law::solve_log;
use modulus::effective_modulus_f64;

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

impl ImpactResult {
    /// Maximum approach δmax, m.
    #[must_use]
    pub fn max_deformation(&self) -> f64 {
        match &self.detail {
            ImpactDetail::Line(l) => l.max_deformation,
            ImpactDetail::Hertz(h) => h.max_deformation,
        }
    }

    /// Maximum contact force Pmax, N.
    #[must_use]
    pub fn max_force(&self) -> f64 {
        match &self.detail {
            ImpactDetail::Line(l) => l.max_force,
            ImpactDetail::Hertz(h) => h.max_force,
        }
    }

    /// Maximum contact pressure p₀, Pa.
    #[must_use]
    pub fn max_pressure(&self) -> f64 {
        match &self.detail {
            ImpactDetail::Line(l) => l.max_pressure,
            ImpactDetail::Hertz(h) => h.max_pressure,
        }
    }
}

fn check_positive(field: Param, value: f64) -> PhysicsResult<()> {
    if is_positive_finite(value) {
        Ok(())
    } else {
        Err(PhysicsError::invalid(
            field,
            value,
            "must be a positive finite number",
        ))
    }
}

fn check_poisson(field: Param, value: f64) -> PhysicsResult<()> {
    if (0.0..0.5).contains(&value) {
        Ok(())
    } else {
        Err(PhysicsError::invalid(field, value, "must be in [0, 0.5)"))
    }
}

/// x > 0 and finite, as two comparisons (NaN fails both; `is_finite` costs a bit test more).
#[inline]
fn is_positive_finite(x: f64) -> bool {
    x > 0.0 && x < f64::INFINITY
}

/// Whether every input [`check_case`] looks at is valid: the same conditions as one boolean
/// expression, so the common valid case forms no `Result` per field.
fn case_is_valid(case: &ImpactCase) -> bool {
    let positive = is_positive_finite;
    let poisson = |x: f64| (0.0..0.5).contains(&x);
    let (rock, column) = (&case.rock, &case.column);
    positive(case.velocity)
        && positive(rock.side_length)
        && positive(rock.density)
        && positive(rock.elastic_modulus)
        && poisson(rock.poisson_ratio)
        && positive(column.contact_radius)
        && (case.contact.modulus != ModulusConvention::TwoBody
            || (positive(column.elastic_modulus) && poisson(column.poisson_ratio)))
        && match (&rock.shape, case.contact.law) {
            (RockShape::Sphere { radius }, ContactLaw::HertzPoint) => positive(*radius),
            (RockShape::Sphere { .. }, _) => false,
            (_, ContactLaw::HertzPoint) => positive(rock.corner_radius),
            _ => true,
        }
}

/// Keeps the contact solvers total on any case (the web layer checks the documented ranges
/// first).
pub(super) fn check_case(case: &ImpactCase) -> PhysicsResult<()> {
    if case_is_valid(case) {
        return Ok(());
    }
    check_case_fields(case)
}

/// The rule that a sphere touches the column at a point, so only the Hertz point law is
/// defined for it: the message when `sphere` and `law` break it.
///
/// # Errors
/// The rule's message for a sphere with a line-contact law.
pub fn sphere_law_rule(sphere: bool, law: ContactLaw) -> Result<(), &'static str> {
    if sphere && law != ContactLaw::HertzPoint {
        Err("a sphere touches the column at a point: only hertz_point is defined")
    } else {
        Ok(())
    }
}

/// The field-by-field checks of [`check_case`], naming the first invalid field (out of line: the
/// valid case never forms their `Result`s).
#[cold]
#[inline(never)]
fn check_case_fields(case: &ImpactCase) -> PhysicsResult<()> {
    check_positive(Param::ImpactVelocity, case.velocity)?;
    check_positive(Param::RockSideLength, case.rock.side_length)?;
    check_positive(Param::RockDensity, case.rock.density)?;
    check_positive(Param::RockElasticModulus, case.rock.elastic_modulus)?;
    check_poisson(Param::RockPoissonRatio, case.rock.poisson_ratio)?;
    check_positive(Param::ColumnContactRadius, case.column.contact_radius)?;
    if case.contact.modulus == ModulusConvention::TwoBody {
        check_positive(Param::ColumnElasticModulus, case.column.elastic_modulus)?;
        check_poisson(Param::ColumnPoissonRatio, case.column.poisson_ratio)?;
    }
    match (&case.rock.shape, case.contact.law) {
        (RockShape::Sphere { radius }, ContactLaw::HertzPoint) => {
            check_positive(Param::RockRadius, *radius)?
        }
        (RockShape::Sphere { .. }, law) => {
            sphere_law_rule(true, law)
                .map_err(|m| PhysicsError::invalid(Param::ContactLaw, f64::NAN, m))?;
        }
        (_, ContactLaw::HertzPoint) => {
            check_positive(Param::RockCornerRadius, case.rock.corner_radius)?
        }
        _ => {}
    }
    Ok(())
}

/// Rock mass in double-double: ρL³ for a cube, else the shape's own mass.
pub(super) fn mass_dd(rock: &Rock) -> DoubleDouble {
    match rock.shape {
        RockShape::Cube => {
            let l = rock.side_length;
            DoubleDouble::new(rock.density) * l * l * l
        }
        _ => DoubleDouble::new(rock.mass()),
    }
}

/// The radius of the touching corner, m: r_c, or the radius of a sphere.
pub(super) fn corner_radius(case: &ImpactCase) -> f64 {
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
/// [`force_law()`].
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
            // κ, δ and P are powers and products of E* (condition ≤ 1): plain f64 (≤ 4 ulp)
            // costs nothing in accuracy; `force_law` forms κ from the same E*.
            let es = effective_modulus_f64(&case.rock, &case.column, case.contact.modulus);
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
                // (5mv²/(4κ_eq))^{2/5} = δ·(κ/κ_eq)^{2/5}, the ratio fitted with κ
                max_deformation_equivalent_radius: d * h.deformation_ratio_equivalent_radius,
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
    let contact_duration = contact_duration(&detail, mass, v);
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

#[cfg(test)]
#[allow(clippy::field_reassign_with_default)] // cases read as "the default, except …"
mod tests {
    use super::*;
    use crate::physics::material::ContactModel;
    use std::f64::consts::FRAC_PI_2;

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
        let Err(PhysicsError::InvalidInput { param, .. }) = solve_impact(&c) else {
            panic!()
        };
        assert_eq!(param, Param::ContactLaw);
        c.contact.law = ContactLaw::HertzPoint;
        let r = solve_impact(&c).unwrap();
        assert!(rel(r.mass, 2500.0 * 4.0 / 3.0 * PI * 1e-3) < 1e-15);
        let ImpactDetail::Hertz(h) = r.detail else {
            panic!()
        };
        // r_c = the sphere's radius, not the default corner radius.
        let g = hertz_geometry(r.effective_modulus, 0.1, 0.125, true);
        assert!(rel(h.stiffness, g.stiffness) < 1e-15, "{h:?} {g:?}");
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

    /// The one-expression validity test and the field-by-field checks accept exactly the same
    /// cases: every field drawn valid or invalid (zero, negative, NaN, ∞, ν ≥ 0.5), both shapes,
    /// laws and conventions.
    #[test]
    fn fast_validity_test_agrees_with_the_field_checks() {
        use proptest::prelude::*;
        let value = prop_oneof![
            4 => 1e-300f64..1e300,
            1 => Just(0.0),
            1 => Just(-1.0),
            1 => Just(f64::NAN),
            1 => Just(f64::INFINITY),
            1 => Just(5e-324),
        ];
        let nu = prop_oneof![
            4 => 0.0f64..0.5,
            1 => Just(0.5),
            1 => Just(-1e-300),
            1 => Just(f64::NAN),
            1 => Just(0.499_999_999_999_999_94),
        ];
        let mut runner =
            proptest::test_runner::TestRunner::new(proptest::test_runner::Config::with_cases(4000));
        runner
            .run(
                &(
                    proptest::collection::vec(value, 8),
                    (nu.clone(), nu),
                    (0usize..3, 0usize..2, any::<bool>()),
                ),
                |(v, (nu_r, nu_c), (law, shape, two_body))| {
                    let mut c = ImpactCase::default();
                    c.velocity = v[0];
                    c.rock.side_length = v[1];
                    c.rock.density = v[2];
                    c.rock.elastic_modulus = v[3];
                    c.rock.poisson_ratio = nu_r;
                    c.rock.corner_radius = v[4];
                    c.column.contact_radius = v[5];
                    c.column.elastic_modulus = v[6];
                    c.column.poisson_ratio = nu_c;
                    c.contact.law = [
                        ContactLaw::Paper,
                        ContactLaw::Johnson,
                        ContactLaw::HertzPoint,
                    ][law];
                    if shape == 1 {
                        c.rock.shape = RockShape::Sphere { radius: v[7] };
                    }
                    c.contact.modulus = if two_body {
                        ModulusConvention::TwoBody
                    } else {
                        ModulusConvention::Paper
                    };
                    prop_assert_eq!(case_is_valid(&c), check_case_fields(&c).is_ok(), "{:?}", c);
                    Ok(())
                },
            )
            .unwrap();
    }
}
