//! Coupled impact model: the rock as a point mass on the nonlinear contact law, driving n exact
//! beam modes of the column, integrated adaptively with event location (physics.md §B.7).
//!
//! State y = [u, u̇, w_s…, ẇ_s…, D, W] with u the rock displacement (towards the column, m),
//! w_s the symmetric modal amplitudes (modes 1, 3, 5, …; the antisymmetric ones have φ(½) = 0,
//! are not coupled to them by the mass matrix and stay at rest), D = ∫ẇᵀCẇ dt the energy
//! dissipated by the column's damping (J) and W = ∫P·Φᵀẇ dt the work of the contact force on the
//! column (J), each integrated as a state of its own. The column's balance E_col + D = W is
//! checked relative to the transferred energy, not to the rock's, and the modal states are
//! error-controlled on the column's own energy scale (refined when the transfer is small).
//!
//! The parts, one per file: `system.rs` (the state's layout, the right-hand side and the linear
//! functionals of the state), `flight.rs` (the exact propagator of the free column and the flight
//! loop), `modal.rs` (the same flight in modal coordinates, O(n) per step), `pass.rs` (one integration over the window: the walk through contact and flight phases,
//! event location, history samples and the energy balances), `exponential.rs` (the contact phase
//! of a heavily damped column), `estimate.rs` (the step count before integrating) and this file
//! (the public types and [`solve_coupled`], which runs the passes).

#![allow(clippy::needless_range_loop)] // index loops over several parallel arrays

use super::beam::Galerkin;
use super::contact::ForceLaw;
pub use super::contact::contact_energy;
use super::control::Control;
use super::error::{PhysicsError, PhysicsResult};

mod estimate;
mod exponential;
mod flight;
mod modal;
mod pass;
mod system;
#[cfg(test)]
mod tests;

pub use estimate::{StepEstimate, estimate_steps};
use pass::run_pass;

/// Inputs of a coupled impact run.
#[derive(Debug, Clone)]
pub struct CoupledInput {
    /// Rock mass m, kg.
    pub rock_mass: f64,
    /// Impact speed v (towards the column), m/s.
    pub velocity: f64,
    /// Contact force law P(δ).
    pub law: ForceLaw,
    /// Galerkin matrices of modes 1…n (exact shapes).
    pub galerkin: Galerkin,
    /// Column length l, m (for curvatures w″ = Σwᵢφᵢ″/l²).
    pub column_length: f64,
    /// End of the window, s.
    pub end_time: f64,
    /// Time scale of one contact (the rigid contact duration), s; bounds the step size.
    pub time_scale: f64,
    /// Displacement scale (the rigid maximum approach), m; sets the absolute tolerances.
    pub displacement_scale: f64,
    /// Relative tolerance of the integrator.
    pub tolerance: f64,
    /// History sample times, s, ascending, each in [0, end_time]; empty for no history.
    pub sample_times: Vec<f64>,
    /// Largest number of integrator steps allowed.
    pub max_steps: u64,
}

/// Histories of a coupled run, equal-length arrays (SI units).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CoupledHistory {
    /// Sample times, s.
    pub time: Vec<f64>,
    /// Column midpoint deflection w_mid = Σφᵢ(½)wᵢ, m.
    pub midpoint_displacement: Vec<f64>,
    /// Column kinetic energy ½ẇᵀMẇ, J.
    pub kinetic_energy: Vec<f64>,
    /// Column strain energy ½wᵀKw, J.
    pub strain_energy: Vec<f64>,
    /// Energy dissipated by the column's damping ∫ẇᵀCẇdt, J.
    pub dissipated_energy: Vec<f64>,
    /// Rock displacement u (towards the column), m.
    pub rock_displacement: Vec<f64>,
    /// Rock kinetic energy ½mu̇², J.
    pub rock_kinetic_energy: Vec<f64>,
    /// Contact force P(δ), N.
    pub contact_force: Vec<f64>,
    /// Energy stored in the contact ∫P dδ, J.
    pub contact_energy: Vec<f64>,
}

/// Results of a coupled run.
#[derive(Debug, Clone, PartialEq)]
pub struct CoupledResult {
    /// Largest contact force over all maxima of approach, N.
    pub max_force: f64,
    /// Largest approach over all maxima of approach, m.
    pub max_contact_deformation: f64,
    /// Largest |w_mid| over the window, m.
    pub max_midpoint_displacement: f64,
    /// Largest |w″| at the clamps (x = 0, 1) over the window, 1/m.
    pub max_curvature_clamp: f64,
    /// Largest |w″| at the midpoint over the window, 1/m.
    pub max_curvature_midpoint: f64,
    /// Number of contacts (the first included).
    pub contact_count: u32,
    /// Duration of the first contact, s; `None` when the rock is still in contact at the end.
    pub first_contact_duration: Option<f64>,
    /// Rock velocity at the first separation (or the end), m/s, positive towards the column.
    pub rebound_velocity: f64,
    /// Column energy ½ẇᵀMẇ + ½wᵀKw at the first separation (or the end), J.
    pub column_energy_after_contact: f64,
    /// Rock velocity at the end, m/s.
    pub rock_velocity_end: f64,
    /// Column energy at the end, J.
    pub column_energy_end: f64,
    /// Energy dissipated by damping over the window, J.
    pub damping_energy: f64,
    /// Contact energy at the end, J.
    pub contact_energy_end: f64,
    /// |rock KE + contact + column + dissipated − initial KE| / initial KE at the end.
    pub energy_residual: f64,
    /// |column energy + dissipated − work of the contact force on the column| / the column's
    /// energy scale, at the end (the column's own balance, relative to the transferred energy).
    pub column_energy_residual: f64,
    /// The column's energy scale: the largest of the work done on it, its energy plus the
    /// dissipated energy at the end, and its energy at the first separation, J.
    pub column_energy_scale: f64,
    /// Estimated relative error: the larger of the two residuals.
    pub estimated_error: f64,
    /// Integration passes run (refinements when the estimate exceeded [`ACCURACY_TARGET`]).
    pub passes: u32,
    /// End of the window, s.
    pub end_time: f64,
    /// Accepted integrator steps.
    pub steps: u64,
    /// Rejected integrator steps.
    pub rejected_steps: u64,
    /// Relative tolerance used.
    pub tolerance: f64,
    /// Histories at the requested times (empty when none were asked).
    pub history: CoupledHistory,
}

/// Runs the coupled impact (physics.md §B.7) over [0, end_time].
///
/// Events located on the dense output: separation (δ ↓ 0, terminal), re-contact (δ ↑ 0,
/// terminal), maxima of approach (δ̇ ↓ 0 in contact), extrema of w_mid and of the curvature at
/// the clamp and the midpoint. A terminal event ends the step there and the integration restarts
/// with the other right-hand side, so no step straddles the switch of the contact law.
///
/// In contact: Dormand–Prince 5(4) with dense output at relative tolerance `tolerance`. In
/// flight (no contact force, a linear system): exact propagation at 1/8 of the shortest period,
/// in modal coordinates (A = VΛV⁻¹ once per pass, O(n) per step, the dissipated energy a
/// closed-form quadrature over the flight; `modal.rs`) when that decomposition is accurate,
/// otherwise by the dense propagator e^{Ah} with the dissipated energy from Van Loan's Gramian
/// (`flight.rs`); events there are detected on cubic Hermite interpolants and located on the
/// exact state (heavily damped columns, up to c = 1e9 N·s/m², are propagated exactly in flight
/// too).
///
/// # Special cases
/// * The Hertz law has no capacity; the log laws stop at δ_cap.
/// * A first contact that lasts past `end_time` leaves `first_contact_duration` at `None` and
///   reports the rebound velocity and column energy at the end.
/// * History samples at t = 0 are the initial state (rock at the column, at speed v).
///
/// # Errors
/// * `CapacityExceeded` when the approach reaches the log law's capacity δ_cap.
/// * `TooManySteps` past `max_steps`; `Cancelled`/`TimedOut` from `control`.
///
/// # References
/// physics.md §B.7.
pub fn solve_coupled(input: &CoupledInput, control: &Control) -> PhysicsResult<CoupledResult> {
    solve_coupled_with(
        input,
        control,
        ContactIntegrator::Auto,
        FlightPropagator::Auto,
    )
}

/// Which integrator takes the contact phases ([`solve_coupled_with`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ContactIntegrator {
    /// The exponential integrator when the damping rate would bound Dormand–Prince's steps
    /// (more than 300 of them per contact for stability alone), Dormand–Prince otherwise.
    Auto,
    /// Dormand–Prince always (the reference of the comparison tests).
    DormandPrince,
}

/// Which propagator takes the free flights ([`solve_coupled_with`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FlightPropagator {
    /// The modal propagator (O(n) per step) when its decomposition is accurate, the dense
    /// exact propagator otherwise.
    Auto,
    /// The dense exact propagator always (the reference of the comparison tests).
    Dense,
}

/// [`solve_coupled`] with the contact integrator chosen by `contact` and the flight propagator
/// by `flight` (`Auto` and `Auto` is [`solve_coupled`]; the others are the references that tests
/// and benches measure it against).
///
/// Errors: those of [`solve_coupled`].
pub fn solve_coupled_with(
    input: &CoupledInput,
    control: &Control,
    contact: ContactIntegrator,
    flight: FlightPropagator,
) -> PhysicsResult<CoupledResult> {
    // Refuse at once what cannot finish within the step limit, instead of integrating until
    // the limit is reached.
    let estimate = estimate_steps(input)?;
    if estimate.lower_bound > input.max_steps as f64 {
        return Err(PhysicsError::TooManySteps {
            estimated: estimate.expected,
            limit: input.max_steps as f64,
        });
    }
    let ke0 = 0.5 * input.rock_mass * input.velocity * input.velocity;
    // Pass 1: modal states controlled on the scale of the rock's energy.
    let mut res = run_pass(input, control, input.tolerance, ke0, contact, flight)?;
    let mut passes = 1;
    // A small transfer leaves the modal states far below that scale: their errors are then not
    // controlled relative to what they carry. Refine on the column's own energy scale, then
    // with a tighter tolerance, until the estimate meets the accuracy target.
    while passes < 3
        && (res.estimated_error > ACCURACY_TARGET
            || (passes == 1 && res.column_energy_scale < 0.1 * ke0))
    {
        let scale = if res.column_energy_scale > 0.0 {
            res.column_energy_scale.min(ke0)
        } else {
            ke0
        };
        let tol = if passes == 1 {
            input.tolerance
        } else {
            (input.tolerance * 0.01).max(1e-13)
        };
        res = run_pass(input, control, tol, scale, contact, flight)?;
        passes += 1;
    }
    res.passes = passes;
    Ok(res)
}

impl CoupledResult {
    /// The result before the first step: rock at the column at speed `v` (m/s), nothing
    /// transferred, over the window [0, `end_time`] (s) at tolerance `tolerance`.
    fn at_start(v: f64, end_time: f64, tolerance: f64) -> Self {
        CoupledResult {
            max_force: 0.0,
            max_contact_deformation: 0.0,
            max_midpoint_displacement: 0.0,
            max_curvature_clamp: 0.0,
            max_curvature_midpoint: 0.0,
            contact_count: 1,
            first_contact_duration: None,
            rebound_velocity: v,
            column_energy_after_contact: 0.0,
            rock_velocity_end: v,
            column_energy_end: 0.0,
            damping_energy: 0.0,
            contact_energy_end: 0.0,
            energy_residual: 0.0,
            column_energy_residual: 0.0,
            column_energy_scale: 0.0,
            estimated_error: 0.0,
            passes: 1,
            end_time,
            steps: 0,
            rejected_steps: 0,
            tolerance,
            history: CoupledHistory::default(),
        }
    }
}

/// The capacity error of a coupled run whose approach reached δ_cap: G = KE/E_cap and the
/// speed at which G = 1 (infinite for Hertz, which has no capacity).
fn capacity_exceeded(input: &CoupledInput) -> PhysicsError {
    let ke0 = 0.5 * input.rock_mass * input.velocity * input.velocity;
    let (g_par, vmax) = match input.law.energy_capacity() {
        Some(e_cap) => (ke0 / e_cap, (2.0 * e_cap / input.rock_mass).sqrt()),
        None => (f64::INFINITY, f64::INFINITY),
    };
    PhysicsError::CapacityExceeded {
        energy_parameter: g_par,
        max_velocity_m_s: vmax,
        message: "the approach reached the capacity of the contact law during the coupled run"
            .into(),
    }
}

/// Relative accuracy the coupled results must meet (physics.md §G, coupled ODE): the estimated
/// error (rock balance relative to its energy, column balance relative to the transferred
/// energy) above it triggers a refinement, and a warning when refinement does not reach it.
pub const ACCURACY_TARGET: f64 = 1e-5;

/// The slot of result extremum k: 0 w_mid, 1 the clamp curvature, 2 the midpoint curvature.
fn extremum_slot(res: &mut CoupledResult, k: usize) -> &mut f64 {
    match k {
        0 => &mut res.max_midpoint_displacement,
        1 => &mut res.max_curvature_clamp,
        _ => &mut res.max_curvature_midpoint,
    }
}
