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

mod exponential;

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
    /// Curvature coefficients at the clamp φᵢ″(0)/l², 1/m².
    curv0: Vec<f64>,
    /// Curvature coefficients at the midpoint φᵢ″(½)/l², 1/m².
    curvm: Vec<f64>,
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

impl System {
    /// The coupled system of a run over the active (symmetric) modes, with its mass matrix M
    /// (kg) and M⁻¹ (1/kg).
    ///
    /// # Errors
    /// `Numerical` when the mass matrix is not positive definite.
    fn new(input: &CoupledInput) -> PhysicsResult<(Self, DMatrix<f64>, DMatrix<f64>)> {
        let g = &input.galerkin;
        // Symmetric modes only: the others are never excited.
        let active = active_modes(g);
        let n = active.len();
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
            curv0: active
                .iter()
                .map(|&i| g.modes[i].curvature(0.0) / (l * l))
                .collect(),
            curvm: active
                .iter()
                .map(|&i| g.modes[i].curvature(0.5) / (l * l))
                .collect(),
            n,
            layout: StateLayout { n },
            in_contact: std::cell::Cell::new(true),
        };
        Ok((sys, mass, minv))
    }

    /// Absolute tolerances of the state at relative tolerance `tol`: tol·δ-scale for u,
    /// tol·v for u̇, tol·√(2E/Kᵢ) for wᵢ, tol·√(2E/Mᵢᵢ) for ẇᵢ and tol·E for the dissipated
    /// energy and the work, E = `energy_scale` (J).
    fn absolute_tolerances(
        &self,
        input: &CoupledInput,
        mass: &DMatrix<f64>,
        tol: f64,
        energy_scale: f64,
    ) -> Vec<f64> {
        let layout = self.layout;
        let mut atol = vec![tol * input.displacement_scale; layout.len()];
        atol[ROCK_VELOCITY] = tol * input.velocity;
        for j in 0..self.n {
            atol[layout.modal_displacement(j)] = tol * (2.0 * energy_scale / self.k[j]).sqrt();
            atol[layout.modal_velocity(j)] = tol * (2.0 * energy_scale / mass[(j, j)]).sqrt();
        }
        atol[layout.dissipated()] = tol * energy_scale;
        atol[layout.work()] = tol * energy_scale;
        atol
    }

    /// The linear functionals of the state as (index, coefficient) pairs: δ, w_mid, the
    /// curvatures at the clamp and the midpoint, each with its rate.
    fn functionals(&self) -> Functionals {
        let layout = self.layout;
        let n = self.n;
        let on = |slot: fn(StateLayout, usize) -> usize, coef: &[f64], sign: f64| -> Functional {
            (0..n).map(|j| (slot(layout, j), sign * coef[j])).collect()
        };
        let with = |head: usize, rest: Functional| -> Functional {
            std::iter::once((head, 1.0)).chain(rest).collect()
        };
        Functionals {
            delta: with(
                ROCK_DISPLACEMENT,
                on(StateLayout::modal_displacement, &self.phi, -1.0),
            ),
            delta_rate: with(
                ROCK_VELOCITY,
                on(StateLayout::modal_velocity, &self.phi, -1.0),
            ),
            wmid: on(StateLayout::modal_displacement, &self.phi, 1.0),
            wmid_rate: on(StateLayout::modal_velocity, &self.phi, 1.0),
            c0: on(StateLayout::modal_displacement, &self.curv0, 1.0),
            c0_rate: on(StateLayout::modal_velocity, &self.curv0, 1.0),
            cm: on(StateLayout::modal_displacement, &self.curvm, 1.0),
            cm_rate: on(StateLayout::modal_velocity, &self.curvm, 1.0),
        }
    }

    /// The column's kinetic ½ẇᵀMẇ and strain ½wᵀKw energies of state y, J.
    fn column_energy(&self, mass: &DMatrix<f64>, y: &[f64]) -> (f64, f64) {
        let layout = self.layout;
        let wd = DVector::from_fn(self.n, |i, _| y[layout.modal_velocity(i)]);
        let kin = 0.5 * wd.dot(&(mass * &wd));
        let strain: f64 = (0..self.n)
            .map(|j| {
                let w = y[layout.modal_displacement(j)];
                0.5 * self.k[j] * w * w
            })
            .sum();
        (kin, strain)
    }
}

/// The linear functionals of a run's state (see [`System::functionals`]).
struct Functionals {
    delta: Functional,
    delta_rate: Functional,
    wmid: Functional,
    wmid_rate: Functional,
    c0: Functional,
    c0_rate: Functional,
    cm: Functional,
    cm_rate: Functional,
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
    /// Largest modal damping rate (M⁻¹C)ᵢᵢ, 1/s.
    damping_rate: f64,
}

/// Largest damping rate × time span (dimensionless) over which the free column is propagated by
/// one block exponential (Van Loan) or by a Taylor series: the transposed block of Van Loan's
/// form grows like e^{rate·τ}, so longer spans are built by doubling.
const TAYLOR_DAMPING_LIMIT: f64 = 2.0;

/// Φ = e^{Aτ} and the dissipation Gramian G(τ) = ∫₀^τ e^{Aᵀs} Q e^{As} ds (Q = diag(0, C)) of
/// the free column z′ = Az, z = [w, ẇ], for any τ ≥ 0 and any damping.
///
/// Van Loan's block exponential exp([[−Aᵀ, Q], [0, A]]·τ₀) gives both at τ₀ = τ/2ˢ, with s the
/// least such that rate·τ₀ ≤ 2 (`rate` the largest modal damping rate, 1/s); then s doublings
/// Φ(2τ₀) = Φ(τ₀)², G(2τ₀) = G(τ₀) + Φ(τ₀)ᵀG(τ₀)Φ(τ₀). Every factor of the doublings decays, so
/// a heavily damped column (rate·τ up to 10⁴ and beyond) never forms the growing e^{−Aᵀτ}
/// whose product with a decaying factor would overflow or cancel. With s = 0 this is exactly
/// the single block exponential.
fn propagator_and_gramian(
    a: &DMatrix<f64>,
    c: &[f64],
    rate: f64,
    tau: f64,
) -> (DMatrix<f64>, DMatrix<f64>) {
    let n = c.len();
    let doublings = if rate * tau > TAYLOR_DAMPING_LIMIT {
        (rate * tau / TAYLOR_DAMPING_LIMIT).log2().ceil().max(0.0) as i32
    } else {
        0
    };
    let h = tau / f64::powi(2.0, doublings);
    let mut phi = (a * h).exp();
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
    let mut gram = (&gram + gram.transpose()) * 0.5;
    for _ in 0..doublings {
        let next = &gram + phi.transpose() * &gram * &phi;
        gram = (&next + next.transpose()) * 0.5;
        phi = &phi * &phi;
    }
    (phi, gram)
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
        let damping_rate = (0..n).map(|i| minv[(i, i)] * c[i]).fold(0.0f64, f64::max);
        // Eight steps per period of the highest mode, whatever the damping: a heavily damped
        // column ((M⁻¹C)ᵢᵢ·h > 2) has its propagator built by doubling and its in-step states
        // from the same exact construction instead of the Taylor series.
        let h = 2.0 * std::f64::consts::PI / omega_max / 8.0;
        let (phi, gram) = propagator_and_gramian(&a, c, damping_rate, h);
        Self {
            a,
            phi,
            gram,
            h,
            c: c.to_vec(),
            n,
            damping_rate,
        }
    }

    /// Whether the in-step Taylor series of e^{Aτ} is used at τ (damping rate·τ ≤ 2); above,
    /// the exact propagator of [`propagator_and_gramian`] is built for that τ.
    fn taylor_converges(&self, tau: f64) -> bool {
        self.damping_rate * tau <= TAYLOR_DAMPING_LIMIT
    }

    /// e^{Aτ}z into `out` without allocating (`term`, `next`: scratch of length 2n); stops when
    /// the Taylor term is below 1e-17 of the sum in both halves (w and ẇ), at most 40 terms
    /// (when the damping rate·τ exceeds 2: Φ(τ)z from [`propagator_and_gramian`], allocating).
    fn propagate_into(
        &self,
        z: &[f64],
        tau: f64,
        out: &mut [f64],
        term: &mut [f64],
        next: &mut [f64],
    ) {
        let zl = 2 * self.n;
        if !self.taylor_converges(tau) {
            let (phi, _) = propagator_and_gramian(&self.a, &self.c, self.damping_rate, tau);
            let zo = phi * DVector::from_column_slice(z);
            out.copy_from_slice(zo.as_slice());
            return;
        }
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

    /// e^{Aτ}z and (when `dissipation`) ∫₀^τ ẇᵀCẇ ds for 0 ≤ τ ≤ h, by 30 Taylor terms (by
    /// [`propagator_and_gramian`] when the damping rate·τ exceeds 2).
    fn taylor(&self, z: &[f64], tau: f64, dissipation: bool) -> (DVector<f64>, f64) {
        const TERMS: usize = 30;
        let n = self.n;
        if !self.taylor_converges(tau) {
            let (phi, gram) = propagator_and_gramian(&self.a, &self.c, self.damping_rate, tau);
            let zv = DVector::from_column_slice(z);
            let d = if dissipation {
                zv.dot(&(&gram * &zv))
            } else {
                0.0
            };
            return (phi * zv, d);
        }
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
/// detected on cubic Hermite interpolants and located on the Taylor series of e^{Aτ} (on the
/// exact propagator built for that span when the damping rate·τ exceeds 2: heavily damped
/// columns, up to c = 1e9 N·s/m², are propagated exactly in flight too).
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
    solve_coupled_with(input, control, ContactIntegrator::Auto)
}

/// Which integrator takes the contact phases.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum ContactIntegrator {
    /// The exponential integrator when the damping rate would bound Dormand–Prince's steps
    /// (more than 300 of them per contact for stability alone), Dormand–Prince otherwise.
    Auto,
    /// Dormand–Prince always (the reference of the comparison tests).
    #[cfg_attr(not(test), allow(dead_code))]
    DormandPrince,
}

/// [`solve_coupled`] with the contact integrator chosen by `contact`.
fn solve_coupled_with(
    input: &CoupledInput,
    control: &Control,
    contact: ContactIntegrator,
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
    let mut res = run_pass(input, control, input.tolerance, ke0, contact)?;
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
        res = run_pass(input, control, tol, scale, contact)?;
        passes += 1;
    }
    res.passes = passes;
    Ok(res)
}

/// The largest contact step as a fraction of the contact time scale (the rigid contact
/// duration): 1/20.
const CONTACT_MAX_STEP_FRACTION: f64 = 1.0 / 20.0;

/// Largest |hλ| at which Dormand–Prince 5(4) is stable on the negative real axis (3.307); on
/// the imaginary axis the bound is about 1, so this is the most generous for any mode.
const DOPRI5_STABILITY_LIMIT: f64 = 3.307;

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
    /// propagator's rate, which the contact phases take about as well), T·8·ω_max/(2π), plus
    /// t_c·(rate − ω_max)/3.307 in contact when the damping rate is above ω_max (40 for the
    /// exponential contact integrator, twice its count at the largest step t_c/20).
    pub expected: f64,
}

/// Estimates the steps of one pass of [`solve_coupled`] from the stiffest active mode, the
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
fn largest_damping_rate(g: &Galerkin) -> PhysicsResult<f64> {
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
    contact: ContactIntegrator,
) -> PhysicsResult<CoupledResult> {
    let (sys, mass, minv) = System::new(input)?;
    let n = sys.n;
    let layout = sys.layout;
    let dim = layout.len();
    let v = input.velocity;
    let atol = sys.absolute_tolerances(input, &mass, tol, energy_scale);
    let t_end = input.end_time;
    let mut st = Dopri5::new(tol, atol.clone(), (input.time_scale * 1e-3).min(t_end));
    st.max_step = input.time_scale * CONTACT_MAX_STEP_FRACTION;
    // A damping rate that would bound the explicit contact steps hands the contact phases to
    // the exponential integrator (its step set by the contact force alone).
    let damping_rate = (0..n)
        .map(|i| minv[(i, i)] * sys.c[i])
        .fold(0.0f64, f64::max);
    let mut exp_contact = (contact == ContactIntegrator::Auto
        && exponential::exponential_contact_pays(damping_rate, input.time_scale))
    .then(|| {
        exponential::ExpStepper::new(
            &sys,
            &minv,
            tol,
            atol,
            (input.time_scale * 1e-3).min(t_end),
            input.time_scale * CONTACT_MAX_STEP_FRACTION,
            input.time_scale,
        )
    });

    let fs = sys.functionals();
    let pass = Pass {
        input,
        sys: &sys,
        mass: &mass,
        fs: &fs,
    };

    let column_energy = |y: &[f64]| sys.column_energy(&mass, y);
    let mut walk = Walk::new(v, t_end, tol, dim);
    let samples = &input.sample_times;
    let record = |res: &mut CoupledResult, ts: f64, ys: &[f64], in_contact: bool| {
        pass.record(res, ts, ys, in_contact)
    };
    while walk.next_sample < samples.len() && samples[walk.next_sample] <= 0.0 {
        record(&mut walk.res, samples[walk.next_sample], &walk.y, true);
        walk.next_sample += 1;
    }

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
    // The exact propagator steps at 1/8 of the shortest period whatever the damping (a heavily
    // damped column has its propagator built by doubling and its in-step states exactly).
    let exact_flight = omega_max > 0.0;
    while walk.t < t_end {
        if !walk.in_contact && exact_flight {
            let ff = free.get_or_insert_with(|| FreeFlight::new(&minv, &sys.k, &sys.c, omega_max));
            let (recontact, t_new) = free_flight(
                ff,
                &sys,
                &mut walk.y,
                walk.t,
                t_end,
                &mut walk.res,
                &mut walk.next_sample,
                samples,
                &record,
                &apply,
                &[&fs.wmid, &fs.c0, &fs.cm],
                &[&fs.wmid_rate, &fs.c0_rate, &fs.cm_rate],
                &mut st,
                control,
                input.max_steps,
                &|yy: &[f64]| {
                    let (kin, strain) = column_energy(yy);
                    (2.0 * (kin + strain) * reach).sqrt()
                },
            )?;
            walk.t = t_new;
            if recontact {
                walk.switch(&pass, &mut st, t_new);
            }
            continue;
        }
        if let (true, Some(es)) = (walk.in_contact, exp_contact.as_mut()) {
            let (steps, rejected) = (es.steps, es.rejected);
            let (separated, t_new) = exponential::exponential_contact(
                es,
                &pass,
                &mut walk.y,
                walk.t,
                &mut walk.res,
                &mut walk.next_sample,
                control,
                st.steps,
            )?;
            st.steps += es.steps - steps;
            st.rejected += es.rejected - rejected;
            walk.t = t_new;
            if separated {
                walk.separate_first(&pass, t_new);
                walk.in_contact = false;
                sys.in_contact.set(false);
                st.reset();
            }
            continue;
        }
        explicit_step(&pass, &mut walk, &mut st, control)?;
    }
    // Samples at exactly the end (rounding).
    while walk.next_sample < samples.len() {
        record(
            &mut walk.res,
            samples[walk.next_sample],
            &walk.y,
            walk.in_contact,
        );
        walk.next_sample += 1;
    }
    let mut res = walk.res;
    close_balances(
        input,
        &sys,
        &mass,
        &walk.y,
        walk.in_contact,
        walk.first_separated,
        &mut res,
    );
    res.steps = st.steps;
    res.rejected_steps = st.rejected;
    Ok(res)
}

/// The mutable state of one pass's walk over the window: the state vector and its two scratch
/// copies, the time (s), the results so far, the next history sample, the phase, whether the
/// first contact has ended and the number of phase switches.
struct Walk {
    y: Vec<f64>,
    ysave: Vec<f64>,
    ytmp: Vec<f64>,
    t: f64,
    res: CoupledResult,
    next_sample: usize,
    in_contact: bool,
    first_separated: bool,
    switches: u64,
}

impl Walk {
    /// The start: the rock at speed `v` (m/s) touching the column at rest, in contact.
    fn new(v: f64, t_end: f64, tol: f64, dim: usize) -> Self {
        let mut y = vec![0.0; dim];
        y[ROCK_VELOCITY] = v;
        Walk {
            y,
            ysave: vec![0.0; dim],
            ytmp: vec![0.0; dim],
            t: 0.0,
            res: CoupledResult::at_start(v, t_end, tol),
            next_sample: 0,
            in_contact: true,
            first_separated: false,
            switches: 0,
        }
    }

    /// Books the end of the first contact at `te` (s), once: its duration, the rebound
    /// velocity and the column's energy then.
    fn separate_first(&mut self, pass: &Pass<'_>, te: f64) {
        if !self.first_separated {
            self.first_separated = true;
            self.res.first_contact_duration = Some(te);
            self.res.rebound_velocity = self.y[ROCK_VELOCITY];
            let (kin, strain) = pass.sys.column_energy(pass.mass, &self.y);
            self.res.column_energy_after_contact = kin + strain;
        }
    }

    /// Switches between contact and flight at the current state, an event at `te` (s): a
    /// separation or a re-contact; counts the contacts and restarts the explicit integrator.
    fn switch(&mut self, pass: &Pass<'_>, st: &mut Dopri5, te: f64) {
        if self.in_contact {
            self.separate_first(pass, te);
        } else {
            self.res.contact_count += 1;
        }
        self.in_contact = !self.in_contact;
        pass.sys.in_contact.set(self.in_contact);
        st.reset();
        st.h = st.h.max(pass.input.time_scale * 1e-6);
    }
}

/// One explicit Dormand–Prince step in contact or in flight (without the exact propagator).
/// A separation or re-contact inside the step is located on the dense output, the step redone
/// from its start to the event exactly, and the phase switched; otherwise the step's events and
/// samples are processed and the capacity of the contact law checked.
fn explicit_step(
    pass: &Pass<'_>,
    w: &mut Walk,
    st: &mut Dopri5,
    control: &Control,
) -> PhysicsResult<()> {
    let (input, sys) = (pass.input, pass.sys);
    let f_delta = &pass.fs.delta;
    let t_end = input.end_time;
    if st.steps % 1000 == 999 {
        control.check()?;
    }
    if st.steps >= input.max_steps {
        return Err(PhysicsError::TooManySteps {
            estimated: st.steps as f64 * t_end / w.t.max(f64::MIN_POSITIVE),
            limit: input.max_steps as f64,
        });
    }
    w.ysave.copy_from_slice(&w.y);
    let t_save = w.t;
    let in_contact = w.in_contact;
    let t1 = st
        .step(sys, w.t, &mut w.y, t_end)
        .map_err(|e| pass.map_ode(e, in_contact, sys.delta(&w.y)))?;
    // Terminal event: separation (δ ↓ 0) in contact, re-contact (δ ↑ 0) in flight.
    let cd = st.functional(f_delta);
    let gd = |th: f64| Dopri5::eval_functional(&cd, th);
    let dir = if in_contact { -1 } else { 1 };
    let hit = find_roots(
        gd,
        apply(f_delta, &w.ysave),
        apply(f_delta, &w.y),
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
        w.switches += 1;
        if w.switches.is_multiple_of(64) {
            control.check()?;
        }
        if w.switches > input.max_steps {
            return Err(PhysicsError::TooManySteps {
                estimated: w.switches as f64 * t_end / t_save.max(f64::MIN_POSITIVE),
                limit: input.max_steps as f64,
            });
        }
        redo_to_event(pass, w, st, t_save, te)?;
        w.switch(pass, st, te);
        return Ok(());
    }
    pass.process(
        st,
        &mut w.res,
        &mut w.next_sample,
        &w.ysave,
        &w.y,
        in_contact,
        &mut w.ytmp,
    )?;
    if in_contact
        && let Some(cap) = input.law.deformation_capacity()
        && sys.delta(&w.y) >= cap
    {
        return Err(capacity_exceeded(input));
    }
    w.t = t1;
    Ok(())
}

/// Integrates again from the start of a step (state `ysave` at `t_save`, s) to the event at
/// `te` (s) exactly, processing the events and samples of each piece.
fn redo_to_event(
    pass: &Pass<'_>,
    w: &mut Walk,
    st: &mut Dopri5,
    t_save: f64,
    te: f64,
) -> PhysicsResult<()> {
    let sys = pass.sys;
    let in_contact = w.in_contact;
    w.y.copy_from_slice(&w.ysave);
    w.t = t_save;
    st.reset();
    st.h = (te - t_save).max(f64::MIN_POSITIVE);
    let mut scratch = vec![0.0; w.y.len()];
    while w.t < te {
        w.ytmp.copy_from_slice(&w.y);
        w.t = st
            .step(sys, w.t, &mut w.y, te)
            .map_err(|e| pass.map_ode(e, in_contact, sys.delta(&w.y)))?;
        pass.process(
            st,
            &mut w.res,
            &mut w.next_sample,
            &w.ytmp,
            &w.y,
            in_contact,
            &mut scratch,
        )?;
    }
    Ok(())
}

/// What the contact integration of one pass shares: the input, the system, its mass matrix
/// and the linear functionals of the state.
struct Pass<'a> {
    input: &'a CoupledInput,
    sys: &'a System,
    mass: &'a DMatrix<f64>,
    fs: &'a Functionals,
}

impl Pass<'_> {
    /// Records a history sample from state ys at time ts (s).
    fn record(&self, res: &mut CoupledResult, ts: f64, ys: &[f64], in_contact: bool) {
        let (input, layout) = (self.input, self.sys.layout);
        let (kin, strain) = self.sys.column_energy(self.mass, ys);
        let d = self.sys.delta(ys);
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
        h.midpoint_displacement.push(apply(&self.fs.wmid, ys));
        h.kinetic_energy.push(kin);
        h.strain_energy.push(strain);
        h.dissipated_energy.push(ys[layout.dissipated()]);
        h.rock_displacement.push(ys[ROCK_DISPLACEMENT]);
        h.rock_kinetic_energy
            .push(0.5 * input.rock_mass * ys[ROCK_VELOCITY] * ys[ROCK_VELOCITY]);
        h.contact_force.push(p);
        h.contact_energy.push(ec);
    }

    /// Non-terminal events (maxima of approach in contact, extrema of w_mid and of the
    /// curvatures) and history samples over the last accepted step from y0 to y1, up to θ = 1.
    #[allow(clippy::too_many_arguments)]
    fn process(
        &self,
        st: &Dopri5,
        res: &mut CoupledResult,
        next_sample: &mut usize,
        y0: &[f64],
        y1: &[f64],
        in_contact: bool,
        ytmp: &mut [f64],
    ) -> PhysicsResult<()> {
        let fs = self.fs;
        let samples = &self.input.sample_times;
        let (t0, h) = st.last_step();
        let sub = 4;
        if in_contact {
            let cr = st.functional(&fs.delta_rate);
            let cd = st.functional(&fs.delta);
            let g = |th: f64| Dopri5::eval_functional(&cr, th);
            let (r0, r1) = (apply(&fs.delta_rate, y0), apply(&fs.delta_rate, y1));
            for th in find_roots(g, r0, r1, -1, sub, false) {
                let d = Dopri5::eval_functional(&cd, th);
                if d > res.max_contact_deformation {
                    res.max_contact_deformation = d;
                    res.max_force = self
                        .input
                        .law
                        .force(d)
                        .ok_or_else(|| capacity_exceeded(self.input))?;
                }
            }
        }
        for (rate, val, slot) in [
            (&fs.wmid_rate, &fs.wmid, 0usize),
            (&fs.c0_rate, &fs.c0, 1),
            (&fs.cm_rate, &fs.cm, 2),
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
            let target = extremum_slot(res, slot);
            *target = target.max(best);
        }
        while *next_sample < samples.len() && samples[*next_sample] <= t0 + h {
            let ts = samples[*next_sample];
            st.dense_state(ts, ytmp);
            if ts >= t0 + h {
                ytmp.copy_from_slice(y1);
            }
            self.record(res, ts, ytmp, in_contact);
            *next_sample += 1;
        }
        Ok(())
    }

    /// The error of a failed integrator step. A step-size underflow is the capacity only when
    /// the approach δ (m) is close to δ_cap (the log law's force is unbounded there); anywhere
    /// else it is a numerical failure, never reported as a capacity with an energy parameter
    /// that contradicts it.
    fn map_ode(&self, e: OdeError, in_contact: bool, delta: f64) -> PhysicsError {
        let law = self.input.law;
        let near_cap = law
            .deformation_capacity()
            .is_some_and(|cap| delta >= 0.9 * cap);
        match (e, law) {
            (OdeError::StepTooSmall { .. }, ForceLaw::Log { .. }) if in_contact && near_cap => {
                capacity_exceeded(self.input)
            }
            (OdeError::StepTooSmall { t }, _) => {
                PhysicsError::Numerical(format!("step size underflow at t = {t:e} s"))
            }
        }
    }
}

/// Applies a linear functional Σ aᵢ·y_{idxᵢ} to a state.
fn apply(f: &[(usize, f64)], y: &[f64]) -> f64 {
    f.iter().map(|&(i, a)| a * y[i]).sum::<f64>()
}

/// The end-of-window results and the energy balances of a pass ending in state y: the column
/// and rock energies, the contact energy (when `in_contact`), the rebound values when no
/// separation happened, the rock's balance relative to its initial kinetic energy and the
/// column's E_col + D = W relative to the transferred energy.
fn close_balances(
    input: &CoupledInput,
    sys: &System,
    mass: &DMatrix<f64>,
    y: &[f64],
    in_contact: bool,
    first_separated: bool,
    res: &mut CoupledResult,
) {
    let layout = sys.layout;
    let ke0 = 0.5 * input.rock_mass * input.velocity * input.velocity;
    let (kin, strain) = sys.column_energy(mass, y);
    res.column_energy_end = kin + strain;
    res.rock_velocity_end = y[ROCK_VELOCITY];
    res.damping_energy = y[layout.dissipated()];
    res.contact_energy_end = if in_contact {
        contact_energy(&input.law, sys.delta(y)).unwrap_or(0.0)
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
}

/// z ← M x for a column-major square matrix M of side x.len() (no allocation).
fn matvec_col_major(m: &[f64], x: &[f64], out: &mut [f64]) {
    let zl = x.len();
    out.fill(0.0);
    for (j, &xj) in x.iter().enumerate() {
        if xj != 0.0 {
            for (o, &mij) in out.iter_mut().zip(&m[j * zl..(j + 1) * zl]) {
                *o += mij * xj;
            }
        }
    }
}

impl FreeFlight {
    /// ẏ of the free system (u̇, 0, Az, 0, 0) into `d`: the slopes of the linear functionals.
    fn derivative(&self, layout: StateLayout, y: &[f64], d: &mut [f64]) {
        d[ROCK_DISPLACEMENT] = y[ROCK_VELOCITY];
        d[ROCK_VELOCITY] = 0.0;
        matvec_col_major(
            self.a.as_slice(),
            &y[layout.column()],
            &mut d[layout.column()],
        );
        d[layout.dissipated()] = 0.0;
        d[layout.work()] = 0.0;
    }

    /// The full state at θ ∈ [0, 1] of a flight step of size h (s) from y0, the dissipated
    /// energy included when `dissipation`.
    fn state_at(
        &self,
        layout: StateLayout,
        y0: &[f64],
        h: f64,
        th: f64,
        dissipation: bool,
    ) -> Vec<f64> {
        let (z, dd) = self.taylor(&y0[layout.column()], th * h, dissipation);
        let mut out = y0.to_vec();
        out[ROCK_DISPLACEMENT] = y0[ROCK_DISPLACEMENT] + y0[ROCK_VELOCITY] * th * h;
        out[layout.column()].copy_from_slice(z.as_slice());
        out[layout.dissipated()] = y0[layout.dissipated()] + dd;
        out
    }

    /// One full step of the propagator (size `self.h`) from y0 into y1: z₁ = Φz₀ and the
    /// dissipated energy z₀ᵀGz₀ (`gz`: scratch of length 2n).
    fn step_exact(&self, layout: StateLayout, y0: &[f64], y1: &mut [f64], gz: &mut [f64]) {
        let z0 = &y0[layout.column()];
        y1[ROCK_DISPLACEMENT] = y0[ROCK_DISPLACEMENT] + y0[ROCK_VELOCITY] * self.h;
        y1[ROCK_VELOCITY] = y0[ROCK_VELOCITY];
        matvec_col_major(self.phi.as_slice(), z0, &mut y1[layout.column()]);
        matvec_col_major(self.gram.as_slice(), z0, gz);
        let dd: f64 = gz.iter().zip(z0).map(|(a, b)| a * b).sum();
        y1[layout.dissipated()] = y0[layout.dissipated()] + dd;
        y1[layout.work()] = y0[layout.work()];
    }

    /// The first re-contact (δ crossing 0 upward) within a flight step of size h from y0 to y1
    /// (slopes dy0, dy1), as θ ∈ (0, 1]: detected on the cubic Hermite interpolant of δ,
    /// located on the exact propagator.
    #[allow(clippy::too_many_arguments)]
    fn locate_recontact(
        &self,
        sys: &System,
        y0: &[f64],
        y1: &[f64],
        dy0: &[f64],
        dy1: &[f64],
        h: f64,
    ) -> Option<f64> {
        let (g0, g1) = (sys.delta(y0), sys.delta(y1));
        let (s0, s1) = (h * sys.delta(dy0), h * sys.delta(dy1));
        let herm = |th: f64| hermite(g0, s0, g1, s1, th);
        if find_roots(herm, g0, g1, 1, 4, true).is_empty() {
            return None;
        }
        let exact = |th: f64| sys.delta(&self.state_at(sys.layout, y0, h, th, false));
        find_roots(exact, g0, g1, 1, 8, true).first().copied()
    }
}

/// Scratch vectors of the flight loop (no allocation per step).
struct FlightScratch {
    y0: Vec<f64>,
    y1: Vec<f64>,
    dy0: Vec<f64>,
    dy1: Vec<f64>,
    gz: Vec<f64>,
    ye: Vec<f64>,
    tb1: Vec<f64>,
    tb2: Vec<f64>,
}

impl FlightScratch {
    fn new(layout: StateLayout) -> Self {
        let (dim, zl) = (layout.len(), 2 * layout.n);
        Self {
            y0: vec![0.0; dim],
            y1: vec![0.0; dim],
            dy0: vec![0.0; dim],
            dy1: vec![0.0; dim],
            gz: vec![0.0; zl],
            ye: vec![0.0; dim],
            tb1: vec![0.0; zl],
            tb2: vec![0.0; zl],
        }
    }
}

/// The slot of result extremum k: 0 w_mid, 1 the clamp curvature, 2 the midpoint curvature.
fn extremum_slot(res: &mut CoupledResult, k: usize) -> &mut f64 {
    match k {
        0 => &mut res.max_midpoint_displacement,
        1 => &mut res.max_curvature_clamp,
        _ => &mut res.max_curvature_midpoint,
    }
}

/// Extrema of w_mid and of the curvatures within θ ∈ [0, th_end] of a flight step of size h
/// (states and slopes in `s`): roots of the rates detected on cubic Hermite interpolants, the
/// values taken on the exact propagator.
#[allow(clippy::too_many_arguments)]
fn flight_extrema(
    ff: &FreeFlight,
    layout: StateLayout,
    res: &mut CoupledResult,
    apply: &Apply,
    values: &[&Functional; 3],
    rates: &[&Functional; 3],
    s: &mut FlightScratch,
    h: f64,
    th_end: f64,
) {
    for k in 0..3 {
        let (r0, r1) = (apply(rates[k], &s.y0), apply(rates[k], &s.y1));
        let (q0, q1) = (h * apply(rates[k], &s.dy0), h * apply(rates[k], &s.dy1));
        let herm = |th: f64| hermite(r0, q0, r1, q1, th);
        let mut best: f64 = 0.0;
        for th in find_roots(herm, r0, r1, 0, 4, false) {
            if th <= th_end {
                ff.propagate_into(
                    &s.y0[layout.column()],
                    th * h,
                    &mut s.ye[layout.column()],
                    &mut s.tb1,
                    &mut s.tb2,
                );
                best = best.max(apply(values[k], &s.ye).abs());
            }
        }
        let target = extremum_slot(res, k);
        *target = target.max(best);
    }
}

/// Refuses a pass whose rock can no longer reach the column and whose remaining fixed flight
/// steps exceed the limit. Once the rock recedes (u̇ ≤ 0) beyond the reach of the column's
/// energy (u < −√(2·E_col·reach), E_col never grows in flight), it never touches the column
/// again: the rest of the window is the propagator's fixed steps, counted exactly.
fn refuse_unreachable(
    ff: &FreeFlight,
    y: &[f64],
    t: f64,
    t_end: f64,
    steps: u64,
    max_steps: u64,
    amplitude_bound: &dyn Fn(&[f64]) -> f64,
) -> PhysicsResult<()> {
    if y[ROCK_VELOCITY] <= 0.0 && y[ROCK_DISPLACEMENT] < -amplitude_bound(y) * (1.0 + 1e-9) {
        let remaining = ((t_end - t) / ff.h).ceil();
        let total = steps as f64 + remaining;
        if total > max_steps as f64 {
            return Err(PhysicsError::TooManySteps {
                estimated: total,
                limit: max_steps as f64,
            });
        }
    }
    Ok(())
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
    let layout = sys.layout;
    let mut s = FlightScratch::new(layout);
    ff.derivative(layout, y, &mut s.dy0);
    let mut steps_in_flight = 0u64;
    loop {
        if t >= t_end {
            return Ok((false, t));
        }
        // Checked on entry and every 64 steps.
        if steps_in_flight.is_multiple_of(64) {
            refuse_unreachable(ff, y, t, t_end, st.steps, max_steps, amplitude_bound)?;
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
        s.y0.copy_from_slice(y);
        if last {
            s.y1.copy_from_slice(&ff.state_at(layout, &s.y0, h, 1.0, true));
        } else {
            ff.step_exact(layout, &s.y0, &mut s.y1, &mut s.gz);
        }
        ff.derivative(layout, &s.y1, &mut s.dy1);
        let hit = ff.locate_recontact(sys, &s.y0, &s.y1, &s.dy0, &s.dy1, h);
        let th_end = hit.unwrap_or(1.0);
        flight_extrema(ff, layout, res, apply, values, rates, &mut s, h, th_end);
        let y_rc;
        let y_end: &[f64] = if hit.is_some() {
            y_rc = ff.state_at(layout, &s.y0, h, th_end, true);
            &y_rc
        } else {
            &s.y1
        };
        let t_next = if hit.is_some() {
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
                ff.state_at(layout, &s.y0, h, ((ts - t) / h).clamp(0.0, 1.0), true)
            };
            record(res, ts, &ys, false);
            *next_sample += 1;
        }
        for k in 0..3 {
            let v = apply(values[k], y_end).abs();
            let target = extremum_slot(res, k);
            *target = target.max(v);
        }
        y.copy_from_slice(y_end);
        t = t_next;
        if hit.is_some() {
            return Ok((true, t));
        }
        std::mem::swap(&mut s.dy0, &mut s.dy1);
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

    /// The free flight of the symmetric (odd-numbered) modes among the first `modes` of `col`
    /// with damping `c_coef`: their mass matrix, stiffnesses, dampings and propagator.
    fn odd_mode_flight(
        col: &crate::physics::material::Column,
        modes: usize,
        c_coef: f64,
    ) -> (DMatrix<f64>, Vec<f64>, Vec<f64>, FreeFlight) {
        let g = Galerkin::new(col, modes, c_coef, true).unwrap();
        let act: Vec<usize> = (0..modes).step_by(2).collect();
        let n = act.len();
        let mass = DMatrix::from_fn(n, n, |i, j| g.mass[(act[i], act[j])]);
        let minv = mass.clone().cholesky().unwrap().inverse();
        let k: Vec<f64> = act.iter().map(|&i| g.stiffness[(i, i)]).collect();
        let c: Vec<f64> = act.iter().map(|&i| g.damping[(i, i)]).collect();
        let fmax = crate::physics::beam::generalized_frequencies(
            &mass,
            &DMatrix::from_diagonal(&DVector::from_column_slice(&k)),
        )[n - 1];
        let ff = FreeFlight::new(&minv, &k, &c, 2.0 * std::f64::consts::PI * fmax);
        (mass, k, c, ff)
    }

    /// The free-flight propagator: Φ and the Gramian against the Taylor series at τ = h, and
    /// against a tight Dormand–Prince integration of the same linear system over 200 steps.
    #[test]
    fn free_flight_propagator_matches_integration() {
        use crate::physics::material::{Column, Damping};
        let col = Column {
            damping: Damping::Coefficient(2e4),
            ..Column::default()
        };
        let (_, _, c, ff) = odd_mode_flight(&col, 5, 2e4);
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

    /// The heavily damped free column (c = 1e9 N·s/m², damping rate·τ up to ~4e3): the doubled
    /// propagator against a tight Dormand–Prince integration of the same linear system, and its
    /// Gramian against the energy the free column loses (E(0) − E(τ), an independent balance).
    #[test]
    fn doubled_propagator_of_a_heavily_damped_column_matches_integration_and_energy() {
        use crate::physics::material::Column;
        let col = Column::default();
        for (c_coef, modes) in [(1e9, 3usize), (3e7, 5), (1e9, 9)] {
            let (mass, k, c, ff) = odd_mode_flight(&col, modes, c_coef);
            let n = k.len();
            assert!(ff.damping_rate * ff.h > 2.0, "{c_coef}: not heavily damped");
            let energy = |z: &DVector<f64>| {
                let w = z.rows(0, n);
                let wd = z.rows(n, n);
                0.5 * wd.dot(&(&mass * wd)) + (0..n).map(|j| 0.5 * k[j] * w[j] * w[j]).sum::<f64>()
            };
            let mut z0 = DVector::zeros(2 * n);
            for j in 0..n {
                z0[j] = 1e-4 / (j + 1) as f64;
                z0[n + j] = if j % 2 == 0 { 0.5 } else { -0.3 };
            }
            for tau in [ff.h, 0.37 * ff.h] {
                let (z1, d) = ff.taylor(z0.as_slice(), tau, true);
                let lost = energy(&z0) - energy(&z1);
                assert!(d > 0.0 && z1.iter().all(|v| v.is_finite()));
                assert!(((d - lost) / d).abs() < 1e-9, "{c_coef}: {d} vs {lost}");
                let mut out = vec![0.0; 2 * n];
                let (mut t1, mut t2) = (vec![0.0; 2 * n], vec![0.0; 2 * n]);
                ff.propagate_into(z0.as_slice(), tau, &mut out, &mut t1, &mut t2);
                for i in 0..2 * n {
                    assert_eq!(out[i], z1[i]);
                }
                struct Lin<'a>(&'a DMatrix<f64>, &'a [f64], usize);
                impl OdeSystem for Lin<'_> {
                    fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) -> bool {
                        let m = 2 * self.2;
                        let az = self.0 * DVector::from_column_slice(&y[..m]);
                        dy[..m].copy_from_slice(az.as_slice());
                        dy[m] = (0..self.2)
                            .map(|i| self.1[i] * y[self.2 + i] * y[self.2 + i])
                            .sum();
                        true
                    }
                }
                let mut y: Vec<f64> = z0.iter().copied().collect();
                y.push(0.0);
                let mut atol = vec![1e-16; n];
                atol.extend(vec![1e-13; n]);
                atol.push(1e-13);
                let mut st = Dopri5::new(1e-12, atol, 1e-9);
                let sys = Lin(&ff.a, &c, n);
                let mut t = 0.0;
                while t < tau {
                    t = st.step(&sys, t, &mut y, tau).unwrap();
                }
                for i in 0..2 * n {
                    assert!(
                        (y[i] - z1[i]).abs() < 1e-8 * (z1[i].abs() + 1e-9),
                        "{c_coef} {i}: {} vs {}",
                        y[i],
                        z1[i]
                    );
                }
                assert!(((y[2 * n] - d) / d).abs() < 1e-8, "{} vs {d}", y[2 * n]);
            }
        }
    }

    /// Run time against error of the c = 1e9 N·s/m² column (3 and 9 modes, base case): the
    /// largest relative error of Pmax, column energy after contact, first contact duration and
    /// max |w_mid| against a run at tolerance 1e-12. A measurement printed for BENCHMARKS.md, not a
    /// check: `cargo test --lib heavily_damped_time_against_error -- --ignored --nocapture`.
    #[test]
    #[ignore]
    fn heavily_damped_time_against_error() {
        for n in [3usize, 9] {
            let input = |tol: f64| {
                let mut i = base_input(n, tol);
                i.galerkin =
                    Galerkin::new(&crate::physics::material::Column::default(), n, 1e9, true)
                        .unwrap();
                i
            };
            let key = |r: &CoupledResult| {
                [
                    r.max_force,
                    r.column_energy_after_contact,
                    r.first_contact_duration.unwrap(),
                    r.max_midpoint_displacement,
                ]
            };
            let reference = key(&solve_coupled(&input(1e-12), &Control::unlimited()).unwrap());
            println!("{n} modes, c = 1e9 N·s/m²");
            for tol in [1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10] {
                let inp = input(tol);
                let reps = 5;
                let t0 = std::time::Instant::now();
                let mut r = None;
                for _ in 0..reps {
                    r = Some(solve_coupled(&inp, &Control::unlimited()).unwrap());
                }
                let ms = t0.elapsed().as_secs_f64() * 1e3 / reps as f64;
                let r = r.unwrap();
                let err = key(&r)
                    .iter()
                    .zip(reference)
                    .map(|(g, e)| ((g - e) / e).abs())
                    .fold(0.0f64, f64::max);
                println!(
                    "| {tol:e} | {} | {} | {} | {ms:.2} | {err:.2e} | {:.2e} |",
                    r.steps, r.rejected_steps, r.passes, r.estimated_error
                );
            }
        }
    }

    /// The exponential contact integrator against Dormand–Prince (the integrator it replaces)
    /// run at a tolerance 1000 times tighter, on heavily damped columns where both finish:
    /// c = 1e8 and 1e9 N·s/m², 3 and 9 modes, window 50 contact durations. Pmax, the column
    /// energy after contact, the first contact duration, max |w_mid|, the clamp curvature and
    /// the dissipated energy agree within 1e-5 relative at tolerance 1e-6 (the dissipated
    /// energy, a global quadrature, is the furthest: 8e-6 at 9 modes) and within 1e-7 at
    /// tolerance 1e-8 (convergence), and the same number of contacts is found. Physical
    /// expectation: the integrator changes, the physics not.
    #[test]
    fn exponential_contact_matches_dormand_prince_on_heavily_damped_columns() {
        use crate::physics::material::Column;
        for (n, c) in [(3usize, 1e8), (3, 1e9), (9, 1e9)] {
            let input = |tol: f64| {
                let mut i = base_input(n, tol);
                i.galerkin = Galerkin::new(&Column::default(), n, c, true).unwrap();
                i
            };
            let key = |r: &CoupledResult| {
                [
                    r.max_force,
                    r.column_energy_after_contact,
                    r.first_contact_duration.unwrap(),
                    r.max_midpoint_displacement,
                    r.max_curvature_clamp,
                    r.damping_energy,
                ]
            };
            let reference = solve_coupled_with(
                &input(1e-9),
                &Control::unlimited(),
                ContactIntegrator::DormandPrince,
            )
            .unwrap();
            for (tol, bound) in [(1e-6, 1e-5), (1e-8, 1e-7)] {
                let exp = solve_coupled(&input(tol), &Control::unlimited()).unwrap();
                // the exponential integrator took the contact: fewer steps than the explicit
                // one (the flight's, 8 per period of the highest mode, are the same in both)
                assert!(
                    exp.steps < reference.steps,
                    "{n} modes, c = {c:e}: {} vs {} steps",
                    exp.steps,
                    reference.steps
                );
                assert_eq!(exp.contact_count, reference.contact_count);
                for (k, (g, e)) in key(&exp).iter().zip(key(&reference)).enumerate() {
                    assert!(
                        ((g - e) / e).abs() < bound,
                        "{n} modes, c = {c:e}, tol {tol:e}, quantity {k}: {g} vs {e}"
                    );
                }
                assert!(
                    exp.estimated_error < ACCURACY_TARGET,
                    "{}",
                    exp.estimated_error
                );
            }
        }
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
    /// 50 modes (flight dominates the default window of 50 contact durations), and for heavily
    /// damped columns (c = 1e7 and 1e9 N·s/m², where the damping rate bounds the contact steps).
    #[test]
    fn step_estimate_brackets_the_steps_taken() {
        use crate::physics::material::Column;
        for (n, c) in [
            (1usize, 1.0),
            (5, 1.0),
            (20, 1.0),
            (50, 1.0),
            (3, 1e9),
            (9, 1e9),
            (5, 1e7),
        ] {
            let mut input = base_input(n, 1e-9);
            input.galerkin = Galerkin::new(&Column::default(), n, c, true).unwrap();
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
                "{n} modes, c = {c:e}: {steps} steps, expected {}",
                e.expected
            );
        }
    }

    /// A limit below the lower bound is refused before any step (no `TimedOut` from an
    /// expired deadline, which the first 1000 steps would meet): 50 lightly damped modes
    /// (Dormand–Prince contacts) and 3 modes at c = 1e9 N·s/m² (exponential contacts, whose
    /// bound no longer carries the ~3 700 stability-limited steps of the explicit integrator).
    #[test]
    fn step_limit_below_the_estimate_is_refused_at_once() {
        use crate::physics::material::Column;
        let mut damped = base_input(3, 1e-9);
        damped.galerkin = Galerkin::new(&Column::default(), 3, 1e9, true).unwrap();
        for mut input in [base_input(50, 1e-9), damped] {
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
