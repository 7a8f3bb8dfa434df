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

#![allow(clippy::needless_range_loop)] // index loops over several parallel arrays

use nalgebra::{DMatrix, DVector};

use super::beam::Galerkin;
use super::contact::ForceLaw;
pub use super::contact::contact_energy;
use super::control::Control;
use super::error::{PhysicsError, PhysicsResult};
use super::ode::{Dopri5, OdeError, OdeSystem, find_roots};

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

/// Position of the rock displacement u (towards the column, m) in the coupled state.
const ROCK_DISPLACEMENT: usize = 0;
/// Position of the rock velocity u̇ (m/s) in the coupled state.
const ROCK_VELOCITY: usize = 1;

/// Positions in the coupled state y = [u, u̇, w₁…wₙ, ẇ₁…ẇₙ, D, W] of n active (symmetric)
/// modes: named accessors instead of index arithmetic.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct StateLayout {
    /// Number of active modes n.
    n: usize,
}

impl StateLayout {
    /// Length of the state, 4 + 2n.
    fn len(self) -> usize {
        4 + 2 * self.n
    }

    /// Position of the modal displacement wⱼ, m.
    fn modal_displacement(self, j: usize) -> usize {
        2 + j
    }

    /// Position of the modal velocity ẇⱼ, m/s.
    fn modal_velocity(self, j: usize) -> usize {
        2 + self.n + j
    }

    /// The column block z = [w, ẇ] (the free propagator's state).
    fn column(self) -> std::ops::Range<usize> {
        2..2 + 2 * self.n
    }

    /// Position of the energy dissipated by the column's damping D, J.
    fn dissipated(self) -> usize {
        2 + 2 * self.n
    }

    /// Position of the work of the contact force on the column W, J.
    fn work(self) -> usize {
        3 + 2 * self.n
    }
}

struct System {
    m: f64,
    law: ForceLaw,
    phi: Vec<f64>,
    /// M⁻¹ row-major, n × n.
    minv: Vec<f64>,
    k: Vec<f64>,
    c: Vec<f64>,
    n: usize,
    layout: StateLayout,
    in_contact: std::cell::Cell<bool>,
}

impl System {
    fn delta(&self, y: &[f64]) -> f64 {
        let layout = self.layout;
        let mut d = y[ROCK_DISPLACEMENT];
        for j in 0..self.n {
            d -= self.phi[j] * y[layout.modal_displacement(j)];
        }
        d
    }
}

impl OdeSystem for System {
    fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) -> bool {
        let n = self.n;
        let layout = self.layout;
        let p = if self.in_contact.get() {
            match self.law.force(self.delta(y)) {
                Some(p) if p.is_finite() => p,
                _ => return false,
            }
        } else {
            0.0
        };
        dy[ROCK_DISPLACEMENT] = y[ROCK_VELOCITY];
        dy[ROCK_VELOCITY] = -p / self.m;
        let mut f = [0.0f64; 32];
        let mut dis = 0.0;
        let mut mid_rate = 0.0;
        for j in 0..n {
            let wd = y[layout.modal_velocity(j)];
            f[j] = self.phi[j] * p - self.c[j] * wd - self.k[j] * y[layout.modal_displacement(j)];
            dis += self.c[j] * wd * wd;
            mid_rate += self.phi[j] * wd;
            dy[layout.modal_displacement(j)] = wd;
        }
        let f = &f[..n];
        for (i, row) in self.minv.chunks_exact(n).enumerate() {
            dy[layout.modal_velocity(i)] = row.iter().zip(f).map(|(a, b)| a * b).sum();
        }
        dy[layout.dissipated()] = dis;
        dy[layout.work()] = p * mid_rate;
        true
    }
}

/// Exact propagator of the free column (no contact): z = [w, ẇ], z′ = A z.
///
/// Φ = e^{Ah} and the dissipation Gramian G = ∫₀ʰ e^{Aᵀs} Q e^{As} ds (Q = diag(0, C)) come
/// from one matrix exponential each (Van Loan's block form), so a step costs a mat-vec and a
/// quadratic form; within a step the state is the Taylor series of e^{Aτ}z (‖Aτ‖ ≲ 0.8).
struct FreeFlight {
    a: DMatrix<f64>,
    phi: DMatrix<f64>,
    gram: DMatrix<f64>,
    h: f64,
    c: Vec<f64>,
    n: usize,
}

impl FreeFlight {
    fn new(minv: &DMatrix<f64>, k: &[f64], c: &[f64], omega_max: f64) -> Self {
        let n = k.len();
        let mut a = DMatrix::zeros(2 * n, 2 * n);
        for i in 0..n {
            a[(i, n + i)] = 1.0;
            for j in 0..n {
                a[(n + i, j)] = -minv[(i, j)] * k[j];
                a[(n + i, n + j)] = -minv[(i, j)] * c[j];
            }
        }
        // Eight steps per period of the highest mode (the caller uses this propagator only when
        // the damping rate is below 2/h, so that the in-step Taylor series converge quickly).
        let h = 2.0 * std::f64::consts::PI / omega_max / 8.0;
        let phi = (&a * h).exp();
        let mut big = DMatrix::zeros(4 * n, 4 * n);
        for i in 0..2 * n {
            for j in 0..2 * n {
                big[(i, j)] = -a[(j, i)] * h;
                big[(2 * n + i, 2 * n + j)] = a[(i, j)] * h;
            }
        }
        for i in 0..n {
            big[(n + i, 3 * n + i)] = c[i] * h;
        }
        let e = big.exp();
        let f12 = e.view((0, 2 * n), (2 * n, 2 * n)).into_owned();
        let f22 = e.view((2 * n, 2 * n), (2 * n, 2 * n)).into_owned();
        let gram = f22.transpose() * f12;
        let gram = (&gram + gram.transpose()) * 0.5;
        Self {
            a,
            phi,
            gram,
            h,
            c: c.to_vec(),
            n,
        }
    }

    /// e^{Aτ}z into `out` without allocating (`term`, `next`: scratch of length 2n); stops when
    /// the Taylor term is below 1e-17 of the sum in both halves (w and ẇ), at most 40 terms.
    fn propagate_into(
        &self,
        z: &[f64],
        tau: f64,
        out: &mut [f64],
        term: &mut [f64],
        next: &mut [f64],
    ) {
        let zl = 2 * self.n;
        let a = self.a.as_slice();
        out.copy_from_slice(z);
        term.copy_from_slice(z);
        for k in 1..40 {
            next.fill(0.0);
            for (j, &tj) in term.iter().enumerate() {
                if tj != 0.0 {
                    for (o, &aij) in next.iter_mut().zip(&a[j * zl..(j + 1) * zl]) {
                        *o += aij * tj;
                    }
                }
            }
            let f = tau / k as f64;
            let (mut tw, mut tv, mut ow, mut ov) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
            for i in 0..zl {
                term[i] = next[i] * f;
                out[i] += term[i];
                if i < self.n {
                    tw = tw.max(term[i].abs());
                    ow = ow.max(out[i].abs());
                } else {
                    tv = tv.max(term[i].abs());
                    ov = ov.max(out[i].abs());
                }
            }
            if k >= 4 && tw <= 1e-17 * ow && tv <= 1e-17 * ov {
                break;
            }
        }
    }

    /// e^{Aτ}z and (when `dissipation`) ∫₀^τ ẇᵀCẇ ds for 0 ≤ τ ≤ h, by 30 Taylor terms.
    fn taylor(&self, z: &[f64], tau: f64, dissipation: bool) -> (DVector<f64>, f64) {
        const TERMS: usize = 30;
        let n = self.n;
        let mut terms: Vec<DVector<f64>> = Vec::with_capacity(TERMS);
        terms.push(DVector::from_column_slice(z));
        for k in 1..TERMS {
            let next = (&self.a * &terms[k - 1]) * (tau / k as f64);
            terms.push(next);
        }
        let mut out = DVector::zeros(2 * n);
        for t in terms.iter().rev() {
            out += t;
        }
        let mut d = 0.0;
        if !dissipation {
            return (out, 0.0);
        }
        for (j, tj) in terms.iter().enumerate() {
            for (k, tk) in terms.iter().enumerate() {
                let mut s = 0.0;
                for i in 0..n {
                    s += self.c[i] * tj[n + i] * tk[n + i];
                }
                d += s / (j + k + 1) as f64;
            }
        }
        (out, d * tau)
    }
}

/// A linear functional Σ aᵢ·y_{idxᵢ} of the state, as (index, coefficient) pairs.
type Functional = Vec<(usize, f64)>;
/// Records one history sample (result, time, state, in contact).
type Recorder<'a> = dyn Fn(&mut CoupledResult, f64, &[f64], bool) + 'a;
/// Applies a functional to a state.
type Apply<'a> = dyn Fn(&[(usize, f64)], &[f64]) -> f64 + 'a;

/// Cubic Hermite interpolant on θ ∈ [0, 1] from end values and end slopes (per unit θ).
fn hermite(g0: f64, d0: f64, g1: f64, d1: f64, th: f64) -> f64 {
    let t2 = th * th;
    let t3 = t2 * th;
    (2.0 * t3 - 3.0 * t2 + 1.0) * g0
        + (t3 - 2.0 * t2 + th) * d0
        + (-2.0 * t3 + 3.0 * t2) * g1
        + (t3 - t2) * d1
}

/// Runs the coupled impact (physics.md §B.7) over [0, end_time].
///
/// Events located on the dense output: separation (δ ↓ 0, terminal), re-contact (δ ↑ 0,
/// terminal), maxima of approach (δ̇ ↓ 0 in contact), extrema of w_mid and of the curvature at
/// the clamp and the midpoint. A terminal event ends the step there and the integration restarts
/// with the other right-hand side, so no step straddles the switch of the contact law.
///
/// In contact: Dormand–Prince 5(4) with dense output at relative tolerance `tolerance`. In
/// flight (no contact force, a linear system): the exact propagator e^{Ah} at 1/8 of the
/// shortest period, with the dissipated energy from Van Loan's Gramian; events there are
/// detected on cubic Hermite interpolants and located on the Taylor series of e^{Aτ}. Heavily
/// damped columns ((M⁻¹C)ᵢᵢ·h > 2) stay with the adaptive integrator in flight too.
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
    let mut res = run_pass(input, control, input.tolerance, ke0)?;
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
        res = run_pass(input, control, tol, scale)?;
        passes += 1;
    }
    res.passes = passes;
    Ok(res)
}

/// Largest |hλ| at which Dormand–Prince 5(4) is stable on the negative real axis (3.307); on
/// the imaginary axis the bound is about 1, so this is the most generous for any mode.
const DOPRI5_STABILITY_LIMIT: f64 = 3.307;

/// The number of integrator steps one pass over the window needs, before integrating.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepEstimate {
    /// Highest angular frequency ω_max of the active (symmetric) modes, rad/s.
    pub omega_max: f64,
    /// A bound no pass goes below: T·ω_max/3.307. In flight the exact propagator steps at
    /// ω_max·h = π/4, and in contact (or in flight with heavy damping) the explicit integrator
    /// is stable only for |hλ| ≤ 3.307 with |λ| ≥ ω_max for the stiffest mode.
    pub lower_bound: f64,
    /// The expected count: 8 steps per period of the stiffest mode over the window (the flight
    /// propagator's rate, which the contact phases take about as well), T·8·ω_max/(2π).
    pub expected: f64,
}

/// Estimates the steps of one pass of [`solve_coupled`] from the stiffest active mode and the
/// window length, without integrating.
///
/// # Errors
/// `Numerical` when the mass matrix is not positive definite.
///
/// # References
/// Hairer & Wanner, *Solving ODEs II*, §IV.2 (stability regions of explicit Runge–Kutta methods).
pub fn estimate_steps(input: &CoupledInput) -> PhysicsResult<StepEstimate> {
    let omega_max = 2.0 * std::f64::consts::PI * highest_active_frequency(&input.galerkin)?;
    let t = input.end_time;
    Ok(StepEstimate {
        omega_max,
        lower_bound: t * omega_max / DOPRI5_STABILITY_LIMIT,
        expected: t * 8.0 * omega_max / (2.0 * std::f64::consts::PI),
    })
}

/// The symmetric modes (0-based even indices) of a Galerkin model: the antisymmetric ones have
/// φ(½) = 0 and are never excited by a midpoint impact.
fn active_modes(g: &Galerkin) -> Vec<usize> {
    (0..g.modes.len()).step_by(2).collect()
}

/// Highest undamped frequency of the active modes, Hz (their own mass and stiffness matrices).
fn highest_active_frequency(g: &Galerkin) -> PhysicsResult<f64> {
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
        super::beam::generalized_frequencies(&mass, &DMatrix::from_diagonal(&stiffness))
            .last()
            .copied()
            .unwrap_or(0.0),
    )
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

/// One integration over the window with relative tolerance `tol`, the column's modal states and
/// energies controlled on the energy scale `energy_scale` (J): absolute tolerances
/// tol·√(2E/Kᵢ) for wᵢ, tol·√(2E/Mᵢᵢ) for ẇᵢ and tol·E for the dissipated energy and the work.
fn run_pass(
    input: &CoupledInput,
    control: &Control,
    tol: f64,
    energy_scale: f64,
) -> PhysicsResult<CoupledResult> {
    let g = &input.galerkin;
    // Symmetric modes only: the others are never excited.
    let active = active_modes(g);
    let n = active.len();
    let layout = StateLayout { n };
    let l = input.column_length;
    let mass = DMatrix::from_fn(n, n, |i, j| g.mass[(active[i], active[j])]);
    let minv = mass
        .clone()
        .cholesky()
        .map(|c| c.inverse())
        .ok_or_else(|| PhysicsError::Numerical("mass matrix not positive definite".into()))?;
    let sys = System {
        m: input.rock_mass,
        law: input.law,
        phi: active.iter().map(|&i| g.midpoint[i]).collect(),
        minv: (0..n * n).map(|k| minv[(k / n, k % n)]).collect(),
        k: active.iter().map(|&i| g.stiffness[(i, i)]).collect(),
        c: active.iter().map(|&i| g.damping[(i, i)]).collect(),
        n,
        layout,
        in_contact: std::cell::Cell::new(true),
    };
    let curv0: Vec<f64> = active
        .iter()
        .map(|&i| g.modes[i].curvature(0.0) / (l * l))
        .collect();
    let curvm: Vec<f64> = active
        .iter()
        .map(|&i| g.modes[i].curvature(0.5) / (l * l))
        .collect();
    let dim = layout.len();
    let v = input.velocity;
    let ke0 = 0.5 * input.rock_mass * v * v;
    let ds = input.displacement_scale;
    let mut atol = vec![tol * ds; dim];
    atol[ROCK_VELOCITY] = tol * v;
    for j in 0..n {
        atol[layout.modal_displacement(j)] = tol * (2.0 * energy_scale / sys.k[j]).sqrt();
        atol[layout.modal_velocity(j)] = tol * (2.0 * energy_scale / mass[(j, j)]).sqrt();
    }
    atol[layout.dissipated()] = tol * energy_scale;
    atol[layout.work()] = tol * energy_scale;
    let t_end = input.end_time;
    let mut st = Dopri5::new(tol, atol, (input.time_scale * 1e-3).min(t_end));
    st.max_step = input.time_scale / 20.0;

    // Linear functionals of the state.
    let f_delta: Vec<(usize, f64)> = std::iter::once((ROCK_DISPLACEMENT, 1.0))
        .chain((0..n).map(|j| (layout.modal_displacement(j), -sys.phi[j])))
        .collect();
    let f_delta_rate: Vec<(usize, f64)> = std::iter::once((ROCK_VELOCITY, 1.0))
        .chain((0..n).map(|j| (layout.modal_velocity(j), -sys.phi[j])))
        .collect();
    let f_wmid: Vec<(usize, f64)> = (0..n)
        .map(|j| (layout.modal_displacement(j), sys.phi[j]))
        .collect();
    let f_wmid_rate: Vec<(usize, f64)> = (0..n)
        .map(|j| (layout.modal_velocity(j), sys.phi[j]))
        .collect();
    let f_c0: Vec<(usize, f64)> = (0..n)
        .map(|j| (layout.modal_displacement(j), curv0[j]))
        .collect();
    let f_c0_rate: Vec<(usize, f64)> = (0..n)
        .map(|j| (layout.modal_velocity(j), curv0[j]))
        .collect();
    let f_cm: Vec<(usize, f64)> = (0..n)
        .map(|j| (layout.modal_displacement(j), curvm[j]))
        .collect();
    let f_cm_rate: Vec<(usize, f64)> = (0..n)
        .map(|j| (layout.modal_velocity(j), curvm[j]))
        .collect();
    let apply = |f: &[(usize, f64)], y: &[f64]| f.iter().map(|&(i, a)| a * y[i]).sum::<f64>();

    let column_energy = |y: &[f64]| {
        let wd = DVector::from_fn(n, |i, _| y[layout.modal_velocity(i)]);
        let kin = 0.5 * wd.dot(&(&mass * &wd));
        let strain: f64 = (0..n)
            .map(|j| {
                0.5 * sys.k[j] * y[layout.modal_displacement(j)] * y[layout.modal_displacement(j)]
            })
            .sum();
        (kin, strain)
    };

    let mut y = vec![0.0; dim];
    y[ROCK_VELOCITY] = v;
    let mut t = 0.0;
    let mut res = CoupledResult::at_start(v, t_end, tol);
    let mut first_separated = false;
    let mut next_sample = 0usize;
    let samples = &input.sample_times;
    let mut ysave = vec![0.0; dim];
    let mut ytmp = vec![0.0; dim];
    let capacity_error = || capacity_exceeded(input);

    // Records a history sample from state ys at time ts.
    let record = |res: &mut CoupledResult, ts: f64, ys: &[f64], in_contact: bool| {
        let (kin, strain) = column_energy(ys);
        let d = sys.delta(ys);
        let (p, ec) = if in_contact {
            (
                input.law.force(d).unwrap_or(0.0),
                contact_energy(&input.law, d).unwrap_or(0.0),
            )
        } else {
            (0.0, 0.0)
        };
        let h = &mut res.history;
        h.time.push(ts);
        h.midpoint_displacement.push(apply(&f_wmid, ys));
        h.kinetic_energy.push(kin);
        h.strain_energy.push(strain);
        h.dissipated_energy.push(ys[layout.dissipated()]);
        h.rock_displacement.push(ys[ROCK_DISPLACEMENT]);
        h.rock_kinetic_energy
            .push(0.5 * input.rock_mass * ys[ROCK_VELOCITY] * ys[ROCK_VELOCITY]);
        h.contact_force.push(p);
        h.contact_energy.push(ec);
    };
    while next_sample < samples.len() && samples[next_sample] <= 0.0 {
        record(&mut res, samples[next_sample], &y, true);
        next_sample += 1;
    }

    // Non-terminal events and samples over the last accepted step, up to θ = 1.
    let process = |st: &Dopri5,
                   res: &mut CoupledResult,
                   next_sample: &mut usize,
                   y0: &[f64],
                   y1: &[f64],
                   in_contact: bool,
                   ytmp: &mut [f64]|
     -> PhysicsResult<()> {
        let (t0, h) = st.last_step();
        let sub = 4;
        if in_contact {
            let cr = st.functional(&f_delta_rate);
            let cd = st.functional(&f_delta);
            let g = |th: f64| Dopri5::eval_functional(&cr, th);
            for th in find_roots(
                g,
                apply(&f_delta_rate, y0),
                apply(&f_delta_rate, y1),
                -1,
                sub,
                false,
            ) {
                let d = Dopri5::eval_functional(&cd, th);
                if d > res.max_contact_deformation {
                    res.max_contact_deformation = d;
                    res.max_force = input.law.force(d).ok_or_else(capacity_error)?;
                }
            }
        }
        for (rate, val, slot) in [
            (&f_wmid_rate, &f_wmid, 0usize),
            (&f_c0_rate, &f_c0, 1),
            (&f_cm_rate, &f_cm, 2),
        ] {
            let cr = st.functional(rate);
            let g = |th: f64| Dopri5::eval_functional(&cr, th);
            let mut best = apply(val, y1).abs();
            let roots = find_roots(g, apply(rate, y0), apply(rate, y1), 0, sub, false);
            if !roots.is_empty() {
                let cv = st.functional(val);
                for th in roots {
                    best = best.max(Dopri5::eval_functional(&cv, th).abs());
                }
            }
            let target = match slot {
                0 => &mut res.max_midpoint_displacement,
                1 => &mut res.max_curvature_clamp,
                _ => &mut res.max_curvature_midpoint,
            };
            *target = target.max(best);
        }
        while *next_sample < samples.len() && samples[*next_sample] <= t0 + h {
            let ts = samples[*next_sample];
            st.dense_state(ts, ytmp);
            if ts >= t0 + h {
                ytmp.copy_from_slice(y1);
            }
            record(res, ts, ytmp, in_contact);
            *next_sample += 1;
        }
        Ok(())
    };

    // A step-size underflow is the capacity only when the approach is close to δ_cap (the log
    // law's force is unbounded there); anywhere else it is a numerical failure, never reported
    // as a capacity with an energy parameter that contradicts it.
    let map_ode = |e: OdeError, in_contact: bool, delta: f64| -> PhysicsError {
        let near_cap = input
            .law
            .deformation_capacity()
            .is_some_and(|cap| delta >= 0.9 * cap);
        match (e, input.law) {
            (OdeError::StepTooSmall { .. }, ForceLaw::Log { .. }) if in_contact && near_cap => {
                capacity_error()
            }
            (OdeError::StepTooSmall { t }, _) => {
                PhysicsError::Numerical(format!("step size underflow at t = {t:e} s"))
            }
        }
    };

    let mut in_contact = true;
    let mut switches: u64 = 0;
    let omega_max = 2.0
        * std::f64::consts::PI
        * super::beam::generalized_frequencies(
            &mass,
            &DMatrix::from_diagonal(&DVector::from_column_slice(&sys.k)),
        )
        .last()
        .copied()
        .unwrap_or(0.0);
    let mut free: Option<FreeFlight> = None;
    // φ(½)ᵀK⁻¹φ(½), m²/J: |w_mid| ≤ √(2·E_col·reach) for a column holding energy E_col
    // (Cauchy–Schwarz in the norm of K, and E_col ≥ ½wᵀKw).
    let reach: f64 = (0..n).map(|j| sys.phi[j] * sys.phi[j] / sys.k[j]).sum();
    // The exact propagator steps at 1/8 of the shortest period; its in-step Taylor series need
    // ‖Aτ‖ ≲ 1, so a damping rate (M⁻¹C)ᵢᵢ above 2/h (heavy damping) keeps the adaptive
    // integrator in flight as well.
    let damping_rate = (0..n)
        .map(|i| minv[(i, i)] * sys.c[i])
        .fold(0.0f64, f64::max);
    let exact_flight =
        omega_max > 0.0 && damping_rate * (2.0 * std::f64::consts::PI / omega_max / 8.0) <= 2.0;
    while t < t_end {
        if !in_contact && exact_flight {
            let ff = free.get_or_insert_with(|| FreeFlight::new(&minv, &sys.k, &sys.c, omega_max));
            let (recontact, t_new) = free_flight(
                ff,
                &sys,
                &mut y,
                t,
                t_end,
                &mut res,
                &mut next_sample,
                samples,
                &record,
                &apply,
                &[&f_wmid, &f_c0, &f_cm],
                &[&f_wmid_rate, &f_c0_rate, &f_cm_rate],
                &mut st,
                control,
                input.max_steps,
                &|yy: &[f64]| {
                    let (kin, strain) = column_energy(yy);
                    (2.0 * (kin + strain) * reach).sqrt()
                },
            )?;
            t = t_new;
            if recontact {
                res.contact_count += 1;
                in_contact = true;
                sys.in_contact.set(true);
                st.reset();
                st.h = st.h.max(input.time_scale * 1e-6);
            }
            continue;
        }
        if st.steps % 1000 == 999 {
            control.check()?;
        }
        if st.steps >= input.max_steps {
            return Err(PhysicsError::TooManySteps {
                estimated: st.steps as f64 * t_end / t.max(f64::MIN_POSITIVE),
                limit: input.max_steps as f64,
            });
        }
        ysave.copy_from_slice(&y);
        let t_save = t;
        let t1 = st
            .step(&sys, t, &mut y, t_end)
            .map_err(|e| map_ode(e, in_contact, sys.delta(&y)))?;
        // Terminal event: separation (δ ↓ 0) in contact, re-contact (δ ↑ 0) in flight.
        let cd = st.functional(&f_delta);
        let gd = |th: f64| Dopri5::eval_functional(&cd, th);
        let dir = if in_contact { -1 } else { 1 };
        let hit = find_roots(
            gd,
            apply(&f_delta, &ysave),
            apply(&f_delta, &y),
            dir,
            4,
            true,
        );
        let (t0, h) = st.last_step();
        // An event must move time forward (a grazing δ ≈ 0 at the very start of a step would
        // otherwise switch back and forth without progress).
        let event = hit
            .first()
            .map(|&th| t0 + th * h)
            .filter(|&te| te > t_save + 1e-13 * h.max(t_save.abs() * 1e-3));
        if let Some(te) = event {
            switches += 1;
            if switches.is_multiple_of(64) {
                control.check()?;
            }
            if switches > input.max_steps {
                return Err(PhysicsError::TooManySteps {
                    estimated: switches as f64 * t_end / t_save.max(f64::MIN_POSITIVE),
                    limit: input.max_steps as f64,
                });
            }
            // Redo the integration from the start of the step to the event exactly.
            y.copy_from_slice(&ysave);
            t = t_save;
            st.reset();
            st.h = (te - t_save).max(f64::MIN_POSITIVE);
            while t < te {
                ytmp.copy_from_slice(&y);
                let y0 = ytmp.clone();
                t = st
                    .step(&sys, t, &mut y, te)
                    .map_err(|e| map_ode(e, in_contact, sys.delta(&y)))?;
                let mut scratch = vec![0.0; dim];
                process(
                    &st,
                    &mut res,
                    &mut next_sample,
                    &y0,
                    &y,
                    in_contact,
                    &mut scratch,
                )?;
            }
            if in_contact {
                if !first_separated {
                    first_separated = true;
                    res.first_contact_duration = Some(te);
                    res.rebound_velocity = y[ROCK_VELOCITY];
                    let (kin, strain) = column_energy(&y);
                    res.column_energy_after_contact = kin + strain;
                }
            } else {
                res.contact_count += 1;
            }
            in_contact = !in_contact;
            sys.in_contact.set(in_contact);
            st.reset();
            st.h = st.h.max(input.time_scale * 1e-6);
            continue;
        }
        process(
            &st,
            &mut res,
            &mut next_sample,
            &ysave,
            &y,
            in_contact,
            &mut ytmp,
        )?;
        if in_contact {
            let d = sys.delta(&y);
            if let Some(cap) = input.law.deformation_capacity()
                && d >= cap
            {
                return Err(capacity_error());
            }
        }
        t = t1;
    }
    // Samples at exactly the end (rounding).
    while next_sample < samples.len() {
        record(&mut res, samples[next_sample], &y, in_contact);
        next_sample += 1;
    }
    let (kin, strain) = column_energy(&y);
    res.column_energy_end = kin + strain;
    res.rock_velocity_end = y[ROCK_VELOCITY];
    res.damping_energy = y[layout.dissipated()];
    res.contact_energy_end = if in_contact {
        contact_energy(&input.law, sys.delta(&y)).unwrap_or(0.0)
    } else {
        0.0
    };
    if !first_separated {
        res.rebound_velocity = y[ROCK_VELOCITY];
        res.column_energy_after_contact = kin + strain;
    }
    let total = 0.5 * input.rock_mass * y[ROCK_VELOCITY] * y[ROCK_VELOCITY]
        + res.contact_energy_end
        + res.column_energy_end
        + res.damping_energy;
    res.energy_residual = ((total - ke0) / ke0).abs();
    // The column's own balance: energy + dissipated = work done on it by the contact force.
    let work = y[layout.work()];
    let column_total = res.column_energy_end + res.damping_energy;
    res.column_energy_scale = work
        .abs()
        .max(column_total)
        .max(res.column_energy_after_contact);
    res.column_energy_residual = if res.column_energy_scale > 0.0 {
        ((column_total - work) / res.column_energy_scale).abs()
    } else {
        0.0
    };
    res.estimated_error = res.energy_residual.max(res.column_energy_residual);
    res.steps = st.steps;
    res.rejected_steps = st.rejected;
    Ok(res)
}

/// Free flight of the rock beside the freely vibrating column, from (t, y) until re-contact
/// (δ ↑ 0, returns `true`) or `t_end`, by the exact propagator; records extrema and samples.
#[allow(clippy::too_many_arguments)]
fn free_flight(
    ff: &FreeFlight,
    sys: &System,
    y: &mut [f64],
    mut t: f64,
    t_end: f64,
    res: &mut CoupledResult,
    next_sample: &mut usize,
    samples: &[f64],
    record: &Recorder,
    apply: &Apply,
    values: &[&Functional; 3],
    rates: &[&Functional; 3],
    st: &mut Dopri5,
    control: &Control,
    max_steps: u64,
    amplitude_bound: &dyn Fn(&[f64]) -> f64,
) -> PhysicsResult<(bool, f64)> {
    let n = ff.n;
    let zl = 2 * n;
    let layout = StateLayout { n };
    let dim = y.len();
    let delta = |yy: &[f64]| {
        yy[ROCK_DISPLACEMENT]
            - (0..n)
                .map(|j| sys.phi[j] * yy[layout.modal_displacement(j)])
                .sum::<f64>()
    };
    // y ← M x for a column-major zl × zl matrix.
    let matvec = |m: &[f64], x: &[f64], out: &mut [f64]| {
        out.fill(0.0);
        for (j, &xj) in x.iter().enumerate() {
            if xj != 0.0 {
                for (o, &mij) in out.iter_mut().zip(&m[j * zl..(j + 1) * zl]) {
                    *o += mij * xj;
                }
            }
        }
    };
    // ẏ of the free system (u̇, 0, Az, ·): slopes of the linear functionals.
    let deriv = |yy: &[f64], d: &mut [f64]| {
        d[ROCK_DISPLACEMENT] = yy[ROCK_VELOCITY];
        d[ROCK_VELOCITY] = 0.0;
        matvec(
            ff.a.as_slice(),
            &yy[layout.column()],
            &mut d[layout.column()],
        );
        d[layout.dissipated()] = 0.0;
        d[layout.work()] = 0.0;
    };
    // State at θ of a step of size h from y0.
    let at = |y0: &[f64], h: f64, th: f64, dissipation: bool| {
        let (z, dd) = ff.taylor(&y0[layout.column()], th * h, dissipation);
        let mut out = y0.to_vec();
        out[ROCK_DISPLACEMENT] = y0[ROCK_DISPLACEMENT] + y0[ROCK_VELOCITY] * th * h;
        out[layout.column()].copy_from_slice(z.as_slice());
        out[layout.dissipated()] = y0[layout.dissipated()] + dd;
        out
    };
    let (mut y0, mut y1) = (vec![0.0; dim], vec![0.0; dim]);
    let (mut dy0, mut dy1) = (vec![0.0; dim], vec![0.0; dim]);
    let mut gz = vec![0.0; zl];
    let (mut ye, mut tb1, mut tb2) = (vec![0.0; dim], vec![0.0; zl], vec![0.0; zl]);
    deriv(y, &mut dy0);
    let mut steps_in_flight = 0u64;
    loop {
        if t >= t_end {
            return Ok((false, t));
        }
        // Once the rock recedes (u̇ ≤ 0) beyond the reach of the column's energy
        // (u < −√(2·E_col·reach), E_col never grows in flight), it never touches the column
        // again: the rest of the window is this propagator's fixed steps, counted exactly, and
        // a pass that cannot finish within the limit is refused now (checked on entry and
        // every 64 steps).
        if steps_in_flight.is_multiple_of(64)
            && y[ROCK_VELOCITY] <= 0.0
            && y[ROCK_DISPLACEMENT] < -amplitude_bound(y) * (1.0 + 1e-9)
        {
            let remaining = ((t_end - t) / ff.h).ceil();
            let total = st.steps as f64 + remaining;
            if total > max_steps as f64 {
                return Err(PhysicsError::TooManySteps {
                    estimated: total,
                    limit: max_steps as f64,
                });
            }
        }
        steps_in_flight += 1;
        st.steps += 1;
        if st.steps % 1000 == 999 {
            control.check()?;
        }
        if st.steps >= max_steps {
            return Err(PhysicsError::TooManySteps {
                estimated: st.steps as f64 * t_end / t.max(f64::MIN_POSITIVE),
                limit: max_steps as f64,
            });
        }
        let last = t + ff.h >= t_end;
        let h = if last { t_end - t } else { ff.h };
        y0.copy_from_slice(y);
        if last {
            y1.copy_from_slice(&at(&y0, h, 1.0, true));
        } else {
            y1[ROCK_DISPLACEMENT] = y0[ROCK_DISPLACEMENT] + y0[ROCK_VELOCITY] * h;
            y1[ROCK_VELOCITY] = y0[ROCK_VELOCITY];
            matvec(
                ff.phi.as_slice(),
                &y0[layout.column()],
                &mut y1[layout.column()],
            );
            matvec(ff.gram.as_slice(), &y0[layout.column()], &mut gz);
            let dd: f64 = gz
                .iter()
                .zip(&y0[layout.column()])
                .map(|(a, b)| a * b)
                .sum();
            y1[layout.dissipated()] = y0[layout.dissipated()] + dd;
            y1[layout.work()] = y0[layout.work()];
        }
        deriv(&y1, &mut dy1);
        // Re-contact: δ crossing upward; Hermite to detect, the exact series to locate.
        let (g0, g1) = (delta(&y0), delta(&y1));
        let (s0, s1) = (h * delta(&dy0), h * delta(&dy1));
        let herm = |th: f64| hermite(g0, s0, g1, s1, th);
        let mut th_end = 1.0;
        let mut recontact = false;
        if !find_roots(herm, g0, g1, 1, 4, true).is_empty() {
            let exact = |th: f64| delta(&at(&y0, h, th, false));
            if let Some(&th) = find_roots(exact, g0, g1, 1, 8, true).first() {
                th_end = th;
                recontact = true;
            }
        }
        // Extrema of w_mid and of the curvatures within [0, th_end].
        for k in 0..3 {
            let (r0, r1) = (apply(rates[k], &y0), apply(rates[k], &y1));
            let (q0, q1) = (h * apply(rates[k], &dy0), h * apply(rates[k], &dy1));
            let herm = |th: f64| hermite(r0, q0, r1, q1, th);
            let mut best: f64 = 0.0;
            for th in find_roots(herm, r0, r1, 0, 4, false) {
                if th <= th_end {
                    ff.propagate_into(
                        &y0[layout.column()],
                        th * h,
                        &mut ye[layout.column()],
                        &mut tb1,
                        &mut tb2,
                    );
                    best = best.max(apply(values[k], &ye).abs());
                }
            }
            let target = match k {
                0 => &mut res.max_midpoint_displacement,
                1 => &mut res.max_curvature_clamp,
                _ => &mut res.max_curvature_midpoint,
            };
            *target = target.max(best);
        }
        let y_rc;
        let y_end: &[f64] = if recontact {
            y_rc = at(&y0, h, th_end, true);
            &y_rc
        } else {
            &y1
        };
        let t_next = if recontact {
            t + th_end * h
        } else if last {
            t_end
        } else {
            t + h
        };
        while *next_sample < samples.len() && samples[*next_sample] <= t_next {
            let ts = samples[*next_sample];
            let ys = if ts >= t_next {
                y_end.to_vec()
            } else {
                at(&y0, h, ((ts - t) / h).clamp(0.0, 1.0), true)
            };
            record(res, ts, &ys, false);
            *next_sample += 1;
        }
        for k in 0..3 {
            let v = apply(values[k], y_end).abs();
            let target = match k {
                0 => &mut res.max_midpoint_displacement,
                1 => &mut res.max_curvature_clamp,
                _ => &mut res.max_curvature_midpoint,
            };
            *target = target.max(v);
        }
        y.copy_from_slice(y_end);
        t = t_next;
        if recontact {
            return Ok((true, t));
        }
        std::mem::swap(&mut dy0, &mut dy1);
    }
}

#[cfg(test)]
mod tests_support {
    pub(super) use super::*;
    use crate::physics::material::Column;
    use std::f64::consts::{E, PI};

    /// The paper law of the base case (physics.md §A.5): k = πLE*, P_ref = e·πE*L³/R.
    pub(crate) fn paper_law() -> ForceLaw {
        let estar = 5e9 / (1.0 - 0.28f64 * 0.28);
        let (l, r) = (0.3, 0.125);
        ForceLaw::Log {
            k: PI * l * estar,
            p_ref: E * PI * estar * l.powi(3) / r,
        }
    }

    pub(crate) fn base_input(n: usize, tol: f64) -> CoupledInput {
        let col = Column::default();
        CoupledInput {
            rock_mass: 67.5,
            velocity: 5.0,
            law: paper_law(),
            galerkin: Galerkin::new(&col, n, 1.0, true).unwrap(),
            column_length: col.length,
            end_time: 50.0 * 1.1081705e-3,
            time_scale: 1.1081705e-3,
            displacement_scale: 1.79332665e-3,
            tolerance: tol,
            sample_times: vec![],
            max_steps: 10_000_000,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::tests_support::*;

    /// The free-flight propagator: Φ and the Gramian against the Taylor series at τ = h, and
    /// against a tight Dormand–Prince integration of the same linear system over 200 steps.
    #[test]
    fn free_flight_propagator_matches_integration() {
        use crate::physics::material::{Column, Damping};
        let col = Column {
            damping: Damping::Coefficient(2e4),
            ..Column::default()
        };
        let g = Galerkin::new(&col, 5, 2e4, true).unwrap();
        let act = [0usize, 2, 4];
        let mass = DMatrix::from_fn(3, 3, |i, j| g.mass[(act[i], act[j])]);
        let minv = mass.clone().cholesky().unwrap().inverse();
        let k: Vec<f64> = act.iter().map(|&i| g.stiffness[(i, i)]).collect();
        let c: Vec<f64> = act.iter().map(|&i| g.damping[(i, i)]).collect();
        let fmax = crate::physics::beam::generalized_frequencies(
            &mass,
            &DMatrix::from_diagonal(&DVector::from_column_slice(&k)),
        )[2];
        let ff = FreeFlight::new(&minv, &k, &c, 2.0 * std::f64::consts::PI * fmax);
        let z0 = [1e-3, -2e-4, 5e-5, 0.3, 1.0, -2.0];
        let (zt, dt) = ff.taylor(&z0, ff.h, true);
        let zp = &ff.phi * DVector::from_column_slice(&z0);
        let d = DVector::from_column_slice(&z0).dot(&(&ff.gram * DVector::from_column_slice(&z0)));
        for i in 0..6 {
            assert!((zt[i] - zp[i]).abs() < 1e-13 * (zp[i].abs() + 1e-3), "{i}");
        }
        assert!(((dt - d) / d).abs() < 1e-12, "{dt} vs {d}");
        let (mut out, mut t1, mut t2) = ([0.0; 6], [0.0; 6], [0.0; 6]);
        ff.propagate_into(&z0, 0.37 * ff.h, &mut out, &mut t1, &mut t2);
        let (zq, _) = ff.taylor(&z0, 0.37 * ff.h, false);
        for i in 0..6 {
            assert!((out[i] - zq[i]).abs() < 1e-14 * (zq[i].abs() + 1e-3), "{i}");
        }
        // 200 exact steps against Dormand–Prince at 1e-13.
        struct Lin<'a>(&'a DMatrix<f64>, &'a [f64]);
        impl OdeSystem for Lin<'_> {
            fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) -> bool {
                let z = DVector::from_column_slice(&y[..6]);
                let az = self.0 * &z;
                dy[..6].copy_from_slice(az.as_slice());
                dy[6] = (0..3).map(|i| self.1[i] * y[3 + i] * y[3 + i]).sum();
                true
            }
        }
        let mut z = DVector::from_column_slice(&z0);
        let mut dis = 0.0;
        for _ in 0..200 {
            dis += z.dot(&(&ff.gram * &z));
            z = &ff.phi * &z;
        }
        let t_end = 200.0 * ff.h;
        let mut y = z0.to_vec();
        y.push(0.0);
        let mut atol = vec![1e-16; 3];
        atol.extend([1e-13; 3]);
        atol.push(1e-13);
        let mut st = Dopri5::new(1e-13, atol, ff.h / 10.0);
        let sys = Lin(&ff.a, &c);
        let mut t = 0.0;
        while t < t_end {
            t = st.step(&sys, t, &mut y, t_end).unwrap();
        }
        for i in 0..6 {
            assert!(
                (y[i] - z[i]).abs() < 1e-9 * (z[i].abs() + 1e-4),
                "{i}: {} vs {}",
                y[i],
                z[i]
            );
        }
        assert!(((y[6] - dis) / dis).abs() < 1e-9, "{} vs {dis}", y[6]);
    }

    /// Contact energy closed form against Gauss–Legendre quadrature of P(δ).
    #[test]
    fn contact_energy_matches_quadrature() {
        let law = paper_law();
        for dmax in [1e-6, 1e-4, 1.8e-3, 0.1] {
            let mut s = 0.0;
            let n = 4000;
            // midpoint rule on δ = dmax·x², dδ = 2dmax x dx (smooths the log singularity at 0)
            for i in 0..n {
                let x = (i as f64 + 0.5) / n as f64;
                s += law.force(dmax * x * x).unwrap() * 2.0 * dmax * x / n as f64;
            }
            let e = contact_energy(&law, dmax).unwrap();
            assert!(((e - s) / e).abs() < 1e-6, "{dmax}: {e} vs {s}");
        }
        let h = ForceLaw::Hertz { kappa: 1e10 };
        assert!((contact_energy(&h, 1e-3).unwrap() - 0.4 * 1e10 * 1e-3f64.powf(2.5)).abs() < 1e-9);
    }

    /// physics.md §B.7 table, n = 1 and 3 (P08), at 1e-5 relative; energy balance to tolerance.
    #[test]
    fn base_case_matches_reference_table() {
        let rows = [
            (
                1usize,
                [
                    0.754774, 1.40118e-3, 1.24702e-3, 1.40732e-3, -4.70516, 96.571,
                ],
            ),
            (
                3,
                [
                    0.749493, 1.39241e-3, 1.26031e-3, 1.41535e-3, -4.70578, 96.374,
                ],
            ),
        ];
        for (n, exp) in rows {
            let r = solve_coupled(&base_input(n, 1e-10), &Control::unlimited()).unwrap();
            let got = [
                r.max_force / 1e6,
                r.max_contact_deformation,
                r.max_midpoint_displacement,
                r.first_contact_duration.unwrap(),
                r.rebound_velocity,
                r.column_energy_after_contact,
            ];
            for (g, e) in got.iter().zip(exp) {
                // the table has 6 significant digits
                assert!(((g - e) / e).abs() < 1e-5, "n={n}: {got:?} vs {exp:?}");
            }
            assert_eq!(r.contact_count, 1);
            // global energy error of the integrator: within 1e3 × the local tolerance
            assert!(r.energy_residual < 1e-7, "{}", r.energy_residual);
            assert!(r.energy_residual > 0.0);
        }
    }

    /// The step estimate brackets what the integrator does: the lower bound is below the steps
    /// of every pass, and the expected count is within a factor 2 of the last pass's, for 1 to
    /// 50 modes (flight dominates the default window of 50 contact durations).
    #[test]
    fn step_estimate_brackets_the_steps_taken() {
        for n in [1usize, 5, 20, 50] {
            let input = base_input(n, 1e-9);
            let e = estimate_steps(&input).unwrap();
            let r = solve_coupled(&input, &Control::unlimited()).unwrap();
            let steps = r.steps as f64;
            assert!(
                e.lower_bound <= steps,
                "{n} modes: bound {} > {steps}",
                e.lower_bound
            );
            assert!(
                (0.5..2.0).contains(&(steps / e.expected)),
                "{n} modes: {steps} steps, expected {}",
                e.expected
            );
        }
    }

    /// A limit below the lower bound is refused before any step (no `TimedOut` from an
    /// expired deadline, which the first 1000 steps would meet).
    #[test]
    fn step_limit_below_the_estimate_is_refused_at_once() {
        let mut input = base_input(50, 1e-9);
        let e = estimate_steps(&input).unwrap();
        input.max_steps = (0.9 * e.lower_bound) as u64;
        let expired = Control::with_deadline(Some(std::time::Instant::now()));
        match solve_coupled(&input, &expired) {
            Err(PhysicsError::TooManySteps { estimated, limit }) => {
                assert_eq!(estimated, e.expected);
                assert_eq!(limit, input.max_steps as f64);
            }
            other => panic!("expected TooManySteps, got {other:?}"),
        }
    }

    #[test]
    fn state_layout_names_every_slot_once() {
        let layout = StateLayout { n: 3 };
        let mut slots = vec![ROCK_DISPLACEMENT, ROCK_VELOCITY];
        slots.extend((0..3).map(|j| layout.modal_displacement(j)));
        slots.extend((0..3).map(|j| layout.modal_velocity(j)));
        slots.push(layout.dissipated());
        slots.push(layout.work());
        slots.sort_unstable();
        assert_eq!(slots, (0..layout.len()).collect::<Vec<_>>());
        assert_eq!(layout.column(), 2..8);
    }
}
