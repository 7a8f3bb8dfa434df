//! The step count of a coupled run before integrating ([`estimate_steps`]): a lower bound no
//! pass goes below, which refuses at once what cannot finish within the step limit, and the
//! expected count; from the stiffest active mode, the largest damping rate, the window and the
//! rigid contact duration.

use nalgebra::{DMatrix, DVector};

use super::CoupledInput;
use super::exponential;
use crate::physics::beam::Galerkin;
use crate::physics::error::{PhysicsError, PhysicsResult};

/// The largest contact step as a fraction of the contact time scale (the rigid contact
/// duration): 1/20.
pub(super) const CONTACT_MAX_STEP_FRACTION: f64 = 1.0 / 20.0;

/// Largest |hλ| at which Dormand–Prince 5(4) is stable on the negative real axis (3.307); on
/// the imaginary axis the bound is about 1, so this is the most generous for any mode.
pub(super) const DOPRI5_STABILITY_LIMIT: f64 = 3.307;

/// The number of integrator steps one pass over the window needs, before integrating.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepEstimate {
    /// Highest angular frequency ω_max of the active (symmetric) modes, rad/s.
    pub omega_max: f64,
    /// Largest modal damping rate (M⁻¹C)ᵢᵢ of the active modes, 1/s.
    pub damping_rate: f64,
    /// A bound no pass goes below: T·ω_max/3.307 over the window T, plus, while in contact (at
    /// least half the rigid contact duration t_c), ½t_c·(rate − ω_max)/3.307 for a damping
    /// rate above ω_max. In flight the exact propagator steps at ω_max·h = π/4 whatever the
    /// damping; in contact the explicit integrator is stable only for |hλ| ≤ 3.307, with
    /// |λ| ≥ ω_max for the stiffest mode and |λ| ≥ rate for the most damped one. When that
    /// damping term would exceed 300 steps, the exponential integrator takes the contacts
    /// instead, with steps of at most t_c/20: the contact term is then ½t_c/(t_c/20) = 10.
    pub lower_bound: f64,
    /// The expected count: 8 steps per period of the stiffest mode over the window (the flight
    /// propagator's rate, modal or dense alike, which the contact phases take about as well),
    /// T·8·ω_max/(2π), plus
    /// t_c·(rate − ω_max)/3.307 in contact when the damping rate is above ω_max (40 for the
    /// exponential contact integrator, twice its count at the largest step t_c/20).
    pub expected: f64,
}

/// Estimates the steps of one pass of [`solve_coupled`](super::solve_coupled) from the stiffest active mode, the
/// largest damping rate, the window length and the rigid contact duration, without
/// integrating.
///
/// # Errors
/// `Numerical` when the mass matrix is not positive definite.
///
/// # References
/// Hairer & Wanner, *Solving ODEs II*, §IV.2 (stability regions of explicit Runge–Kutta methods).
pub fn estimate_steps(input: &CoupledInput) -> PhysicsResult<StepEstimate> {
    let omega_max = 2.0 * std::f64::consts::PI * highest_active_frequency(&input.galerkin)?;
    let damping_rate = largest_damping_rate(&input.galerkin)?;
    let t = input.end_time;
    let contact = input.time_scale.min(t);
    let flight_bound = t * omega_max / DOPRI5_STABILITY_LIMIT;
    let flight = t * 8.0 * omega_max / (2.0 * std::f64::consts::PI);
    let (lower_bound, expected) = if exponential::exponential_contact_pays(damping_rate, contact) {
        // The exponential contact steps are at most t_c/20 (the largest step): at least 10 in
        // half a contact; about 40 per contact at the usual tolerances.
        (
            flight_bound + 0.5 * contact / CONTACT_MAX_STEP_FRACTION,
            flight + 2.0 * contact / CONTACT_MAX_STEP_FRACTION,
        )
    } else {
        let excess = (damping_rate - omega_max).max(0.0) / DOPRI5_STABILITY_LIMIT;
        (
            flight_bound + 0.5 * contact * excess,
            flight + contact * excess,
        )
    };
    Ok(StepEstimate {
        omega_max,
        damping_rate,
        lower_bound,
        expected,
    })
}

/// Largest modal damping rate (M⁻¹C)ᵢᵢ of the active modes, 1/s.
pub(super) fn largest_damping_rate(g: &Galerkin) -> PhysicsResult<f64> {
    let active = active_modes(g);
    let n = active.len();
    let mass = DMatrix::from_fn(n, n, |i, j| g.mass[(active[i], active[j])]);
    let minv = mass
        .cholesky()
        .map(|c| c.inverse())
        .ok_or_else(|| PhysicsError::Numerical("mass matrix not positive definite".into()))?;
    Ok((0..n)
        .map(|i| minv[(i, i)] * g.damping[(active[i], active[i])])
        .fold(0.0f64, f64::max))
}

/// The symmetric modes (0-based even indices) of a Galerkin model: the antisymmetric ones have
/// φ(½) = 0 and are never excited by a midpoint impact.
pub(super) fn active_modes(g: &Galerkin) -> Vec<usize> {
    (0..g.modes.len()).step_by(2).collect()
}

/// Highest undamped frequency of the active modes, Hz (their own mass and stiffness matrices).
pub(super) fn highest_active_frequency(g: &Galerkin) -> PhysicsResult<f64> {
    let active = active_modes(g);
    let n = active.len();
    let mass = DMatrix::from_fn(n, n, |i, j| g.mass[(active[i], active[j])]);
    if mass.clone().cholesky().is_none() {
        return Err(PhysicsError::Numerical(
            "mass matrix not positive definite".into(),
        ));
    }
    let stiffness = DVector::from_iterator(n, active.iter().map(|&i| g.stiffness[(i, i)]));
    Ok(
        crate::physics::beam::generalized_frequencies(&mass, &DMatrix::from_diagonal(&stiffness))
            .last()
            .copied()
            .unwrap_or(0.0),
    )
}
