//! The coupled state and its right-hand side: the positions of the state y = [u, u̇, w, ẇ, D, W]
//! ([`StateLayout`]), the system of a run over the active (symmetric) modes ([`System`]: rock
//! mass, contact law, M⁻¹, K, C, φ(½) and the curvature coefficients), its ODE right-hand side in
//! contact and in flight, and the linear functionals of the state (δ, w_mid, the curvatures at
//! the clamp and the midpoint, each with its rate).

#![allow(clippy::needless_range_loop)] // index loops over several parallel arrays

use nalgebra::{DMatrix, DVector};

use super::CoupledInput;
use super::estimate::active_modes;
use crate::physics::contact::ForceLaw;
use crate::physics::error::{PhysicsError, PhysicsResult};
use crate::physics::numeric::ode::OdeSystem;

/// Position of the rock displacement u (towards the column, m) in the coupled state.
pub(super) const ROCK_DISPLACEMENT: usize = 0;
/// Position of the rock velocity u̇ (m/s) in the coupled state.
pub(super) const ROCK_VELOCITY: usize = 1;

/// Positions in the coupled state y = [u, u̇, w₁…wₙ, ẇ₁…ẇₙ, D, W] of n active (symmetric)
/// modes: named accessors instead of index arithmetic.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct StateLayout {
    /// Number of active modes n.
    pub(super) n: usize,
}

impl StateLayout {
    /// Length of the state, 4 + 2n.
    pub(super) fn len(self) -> usize {
        4 + 2 * self.n
    }

    /// Position of the modal displacement wⱼ, m.
    pub(super) fn modal_displacement(self, j: usize) -> usize {
        2 + j
    }

    /// Position of the modal velocity ẇⱼ, m/s.
    pub(super) fn modal_velocity(self, j: usize) -> usize {
        2 + self.n + j
    }

    /// The column block z = [w, ẇ] (the free propagator's state).
    pub(super) fn column(self) -> std::ops::Range<usize> {
        2..2 + 2 * self.n
    }

    /// Position of the energy dissipated by the column's damping D, J.
    pub(super) fn dissipated(self) -> usize {
        2 + 2 * self.n
    }

    /// Position of the work of the contact force on the column W, J.
    pub(super) fn work(self) -> usize {
        3 + 2 * self.n
    }
}

pub(super) struct System {
    pub(super) m: f64,
    pub(super) law: ForceLaw,
    pub(super) phi: Vec<f64>,
    /// M⁻¹ row-major, n × n.
    pub(super) minv: Vec<f64>,
    pub(super) k: Vec<f64>,
    pub(super) c: Vec<f64>,
    /// Curvature coefficients at the clamp φᵢ″(0)/l², 1/m².
    pub(super) curv0: Vec<f64>,
    /// Curvature coefficients at the midpoint φᵢ″(½)/l², 1/m².
    pub(super) curvm: Vec<f64>,
    pub(super) n: usize,
    pub(super) layout: StateLayout,
    pub(super) in_contact: std::cell::Cell<bool>,
}

impl System {
    pub(super) fn delta(&self, y: &[f64]) -> f64 {
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
    pub(super) fn new(input: &CoupledInput) -> PhysicsResult<(Self, DMatrix<f64>, DMatrix<f64>)> {
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
    pub(super) fn absolute_tolerances(
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
    pub(super) fn functionals(&self) -> Functionals {
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
    pub(super) fn column_energy(&self, mass: &DMatrix<f64>, y: &[f64]) -> (f64, f64) {
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
pub(super) struct Functionals {
    pub(super) delta: Functional,
    pub(super) delta_rate: Functional,
    pub(super) wmid: Functional,
    pub(super) wmid_rate: Functional,
    pub(super) c0: Functional,
    pub(super) c0_rate: Functional,
    pub(super) cm: Functional,
    pub(super) cm_rate: Functional,
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

/// A linear functional Σ aᵢ·y_{idxᵢ} of the state, as (index, coefficient) pairs.
pub(super) type Functional = Vec<(usize, f64)>;

/// Applies a linear functional Σ aᵢ·y_{idxᵢ} to a state.
pub(super) fn apply(f: &[(usize, f64)], y: &[f64]) -> f64 {
    f.iter().map(|&(i, a)| a * y[i]).sum::<f64>()
}
