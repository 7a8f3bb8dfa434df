//! Contact of the rock block on the column: logarithmic line-contact laws (`paper`, `johnson`)
//! on the W₋₁ branch, Hertz point contact, capacity, contact duration (physics.md §A).

use super::error::PhysicsResult;
use super::material::{ContactLaw, ImpactCase, ModulusConvention};

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
    /// Dimensionless energy parameter G ∈ (0, 1].
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

/// Solves the impact (maxima, capacity, duration). Errors with `CapacityExceeded` when G > 1.
pub fn solve_impact(_case: &ImpactCase) -> PhysicsResult<ImpactResult> {
    todo!("contact solver")
}

impl ForceLaw {
    /// Contact force P(δ) at approach δ ≥ 0, N; 0 for δ ≤ 0. For the log laws this is the W₋₁
    /// inverse P = kδ/(1 + u(e·kδ/P_ref)); past the capacity δ_cap it returns `None`.
    pub fn force(&self, delta: f64) -> Option<f64> {
        if delta <= 0.0 {
            return Some(0.0);
        }
        match *self {
            ForceLaw::Log { k, p_ref } => {
                let g = std::f64::consts::E * k * delta / p_ref;
                super::lambert::branch_u(g).map(|u| k * delta / (1.0 + u))
            }
            ForceLaw::Hertz { kappa } => Some(kappa * delta * delta.sqrt()),
        }
    }

    /// Approach at the capacity δ_cap = P_ref/(e k), m; `None` for Hertz (unbounded).
    pub fn deformation_capacity(&self) -> Option<f64> {
        match *self {
            ForceLaw::Log { k, p_ref } => Some(p_ref / (std::f64::consts::E * k)),
            ForceLaw::Hertz { .. } => None,
        }
    }
}

/// Effective modulus E* of the contact, Pa (physics.md §A.2).
pub fn effective_modulus(
    _rock: &super::material::Rock,
    _column: &super::material::Column,
    _convention: ModulusConvention,
) -> f64 {
    todo!("effective modulus")
}

/// The force–approach law of a case.
pub fn force_law(_case: &ImpactCase) -> PhysicsResult<ForceLaw> {
    todo!("force law")
}

/// `n` points of P(δ) equally spaced in δ from 0 to `max_deformation`: (δ, P) in (m, N).
pub fn force_curve(_law: &ForceLaw, _max_deformation: f64, _n: usize) -> (Vec<f64>, Vec<f64>) {
    todo!("force curve")
}
