//! The free flight in modal coordinates: the free column z′ = Az (z = [w, ẇ]) diagonalised once
//! per pass, A = V·Λ·V⁻¹, so a flight step is q ← e^{Λh}⊙q (one complex product per mode) and
//! every linear functional of the state (δ, w_mid, the curvatures, their rates and slopes) is a
//! dot product with precomputed modal coefficients: O(n) per step instead of the dense
//! propagator's three (2n)² products.
//!
//! The eigen-decomposition is that of the energy-balanced matrix S·A·S⁻¹ (S = diag(√Kⱼ, √Mⱼⱼ),
//! so |z̃|² is about twice the column's energy and a lightly damped column's eigenvectors are
//! nearly orthonormal): a complex Schur form T = QᴴÃQ, the eigenvectors of the triangular T by
//! back substitution, V = QY. The damping C = c·l·I is not proportional to M (rotary inertia
//! couples the modes through M), so the modes are complex and damped by their own rates, and
//! over-damped modes have real eigenvalues: all are treated alike. A decomposition that would
//! lose accuracy is refused ([`ModalFlight::new`] returns `None` when ‖V⁻¹V − I‖ or the
//! eigen-residual ‖ÃV − VΛ‖/‖Ã‖ exceed 1e-11, or cond₁(V) exceeds 1e3: a near-critical, nearly
//! defective mode, whose dissipated-energy form would lose accuracy as cond(V)²·ε), and the pass keeps the dense exact propagator of [`super::flight`].
//!
//! The energy dissipated by the column's damping over a flight of duration τ from q₀ stays an
//! independent quadrature of its own (so the column's balance E_col + D = W still checks the
//! propagation): D(τ) = Σᵢⱼ Hᵢⱼ q₀ᵢ q₀ⱼ (e^{(λᵢ+λⱼ)τ} − 1)/(λᵢ + λⱼ) with Hᵢⱼ = Σₗ cₗ·Pₗᵢ·Pₗⱼ
//! (P the ẇ rows of V in physical units), the divided difference taken as τ·φ₁((λᵢ+λⱼ)τ) by its
//! series when |(λᵢ+λⱼ)τ| < 0.5 (an undamped pair has λᵢ + λⱼ = 0).
//!
//! The step, the events and the samples are those of the dense flight ([`super::flight`]): 8
//! steps per period of the highest mode, re-contact and the extrema of w_mid and of the
//! curvatures detected on cubic Hermite interpolants of each step and located (values taken) on
//! the exact modal state e^{Λθh}⊙q.

#![allow(clippy::needless_range_loop)] // index loops over several parallel arrays

use nalgebra::{Complex, DMatrix, Schur};

use super::extremum_slot;
use super::flight::{FlightContext, Sink, count_flight_step, hermite, refuse_unreachable};
use super::system::{Functional, ROCK_DISPLACEMENT, ROCK_VELOCITY, StateLayout};
use crate::physics::error::PhysicsResult;
use crate::physics::numeric::ode::{Dopri5, find_roots};

type C64 = Complex<f64>;

/// Largest accepted ‖V⁻¹V − I‖ and eigen-residual ‖ÃV − VΛ‖/‖Ã‖ of the modal decomposition.
const DECOMPOSITION_RESIDUAL: f64 = 1e-11;
/// Largest accepted 1-norm condition number of the eigenvector matrix V: the dissipated energy
/// is a quadratic form in the modal coordinates, whose rounding grows like cond(V)²·ε, so 1e3
/// keeps it near 1e-10 of the column's energy (a mode within 1e-6 of critical damping has
/// nearly parallel eigenvectors and is refused).
const DECOMPOSITION_CONDITION: f64 = 1e3;

/// The free column in modal coordinates, z = Re(P·q), q(t) = e^{Λt}⊙q(0).
pub(super) struct ModalFlight {
    /// Eigenvalues λᵢ of A, 1/s.
    lam: Vec<C64>,
    /// e^{λᵢh} of the full step.
    step: Vec<C64>,
    /// Step length h, s (1/8 of the shortest period).
    pub(super) h: f64,
    /// z = P·q (physical units), 2n × 2n.
    to_z: DMatrix<C64>,
    /// q = P⁻¹·z, 2n × 2n.
    to_q: DMatrix<C64>,
    /// Hᵢⱼ = Σₗ cₗ·Pₗᵢ·P_{n+l, j}: the dissipation form of the modal coordinates.
    diss: DMatrix<C64>,
}

/// A linear functional a·u + b·u̇ + Σ gⱼzⱼ of the flight state in modal coordinates: its value
/// a·u + b·u̇ + Re Σ mᵢqᵢ and its slope a·u̇ + Re Σ mᵢλᵢqᵢ (u̇ constant in flight).
pub(super) struct ModalFunctional {
    u: f64,
    ud: f64,
    m: Vec<C64>,
    ml: Vec<C64>,
}

impl ModalFunctional {
    /// The value at (u + u̇τ, u̇, e^{Λτ}⊙q) for eigenvalues `lam` (1/s), τ in s.
    fn value_after(&self, u: f64, ud: f64, q: &[C64], lam: &[C64], tau: f64) -> f64 {
        let column: f64 = self
            .m
            .iter()
            .zip(q)
            .zip(lam)
            .map(|((m, qi), l)| {
                let x = qi * (l * tau).exp();
                m.re * x.re - m.im * x.im
            })
            .sum();
        self.u * (u + ud * tau) + self.ud * ud + column
    }
}

/// (e^{xτ} − 1)/x, τ when x = 0: by the series of τ·φ₁(xτ) when |xτ| < 0.5.
fn divided_exp(x: C64, tau: f64) -> C64 {
    let z = x * tau;
    if z.norm() < 0.5 {
        // φ₁(z) = Σ zᵏ/(k+1)!, 18 terms: 0.5¹⁸/19! < 1e-22.
        let mut term = C64::new(1.0, 0.0);
        let mut sum = term;
        for k in 1..18 {
            term = term * z / (k + 1) as f64;
            sum += term;
        }
        sum * tau
    } else {
        (z.exp() - 1.0) / x
    }
}

impl ModalFlight {
    /// The modal form of the free column with M⁻¹ `minv` (1/kg), stiffnesses `k` (N/m),
    /// dampings `c` (N·s/m) and mass diagonal `mass_diag` (kg), stepping at 1/8 of the period
    /// of `omega_max` (rad/s); `None` when the decomposition is not accurate enough (see the
    /// module documentation).
    pub(super) fn new(
        minv: &DMatrix<f64>,
        k: &[f64],
        c: &[f64],
        mass_diag: &[f64],
        omega_max: f64,
    ) -> Option<Self> {
        let n = k.len();
        let zl = 2 * n;
        // S = diag(√Kⱼ, √Mⱼⱼ); Ã = S·A·S⁻¹.
        let s: Vec<f64> = k.iter().chain(mass_diag).map(|v| v.sqrt()).collect();
        if s.iter().any(|v| !(v.is_finite() && *v > 0.0)) {
            return None;
        }
        let mut a = DMatrix::<f64>::zeros(zl, zl);
        for i in 0..n {
            a[(i, n + i)] = 1.0;
            for j in 0..n {
                a[(n + i, j)] = -minv[(i, j)] * k[j];
                a[(n + i, n + j)] = -minv[(i, j)] * c[j];
            }
        }
        let at = DMatrix::from_fn(zl, zl, |i, j| C64::new(s[i] * a[(i, j)] / s[j], 0.0));
        let norm_a = at.iter().map(|v| v.norm()).fold(0.0f64, f64::max);
        if !(norm_a.is_finite() && norm_a > 0.0) {
            return None;
        }
        let (q, t) = Schur::try_new(at.clone(), f64::EPSILON, 100 * zl)?.unpack();
        let lam: Vec<C64> = (0..zl).map(|i| t[(i, i)]).collect();
        // Eigenvectors of the upper triangular T: Y upper triangular, Yₖₖ = 1.
        let smin = norm_a * f64::EPSILON * 16.0;
        let mut y = DMatrix::<C64>::zeros(zl, zl);
        for kk in 0..zl {
            y[(kk, kk)] = C64::new(1.0, 0.0);
            for j in (0..kk).rev() {
                let mut sum = C64::new(0.0, 0.0);
                for l in j + 1..=kk {
                    sum += t[(j, l)] * y[(l, kk)];
                }
                let mut d = t[(j, j)] - lam[kk];
                if d.norm() < smin {
                    d = C64::new(smin, 0.0);
                }
                y[(j, kk)] = -sum / d;
            }
        }
        let mut v = q * y;
        for j in 0..zl {
            let nrm = v.column(j).iter().map(|x| x.norm_sqr()).sum::<f64>().sqrt();
            if !(nrm.is_finite() && nrm > 0.0) {
                return None;
            }
            for i in 0..zl {
                v[(i, j)] /= nrm;
            }
        }
        let vinv = v.clone().try_inverse()?;
        // Accuracy of the decomposition.
        let one_norm = |m: &DMatrix<C64>| {
            (0..m.ncols())
                .map(|j| m.column(j).iter().map(|x| x.norm()).sum::<f64>())
                .fold(0.0f64, f64::max)
        };
        if one_norm(&v) * one_norm(&vinv) > DECOMPOSITION_CONDITION {
            return None;
        }
        let ident = &vinv * &v;
        let mut worst = 0.0f64;
        for i in 0..zl {
            for j in 0..zl {
                let e = if i == j { 1.0 } else { 0.0 };
                worst = worst.max((ident[(i, j)] - e).norm());
            }
        }
        let av = &at * &v;
        for j in 0..zl {
            for i in 0..zl {
                worst = worst.max((av[(i, j)] - v[(i, j)] * lam[j]).norm() / norm_a);
            }
        }
        if worst.is_nan()
            || worst > DECOMPOSITION_RESIDUAL
            || lam.iter().any(|l| l.re > 1e-9 * norm_a)
        {
            return None;
        }
        // Physical units: z = S⁻¹·V·q, q = V⁻¹·S·z.
        let to_z = DMatrix::from_fn(zl, zl, |i, j| v[(i, j)] / s[i]);
        let to_q = DMatrix::from_fn(zl, zl, |i, j| vinv[(i, j)] * s[j]);
        let diss = DMatrix::from_fn(zl, zl, |i, j| {
            let mut sum = C64::new(0.0, 0.0);
            for l in 0..n {
                sum += to_z[(n + l, i)] * to_z[(n + l, j)] * c[l];
            }
            sum
        });
        let h = 2.0 * std::f64::consts::PI / omega_max / 8.0;
        let step = lam.iter().map(|l| (l * h).exp()).collect();
        Some(Self {
            lam,
            step,
            h,
            to_z,
            to_q,
            diss,
        })
    }

    /// The modal form of a functional of the full state (`layout`).
    pub(super) fn functional(&self, layout: StateLayout, f: &Functional) -> ModalFunctional {
        let zl = 2 * layout.n;
        let cols = layout.column();
        let mut g = vec![0.0; zl];
        let (mut u, mut ud) = (0.0, 0.0);
        for &(i, a) in f {
            if i == ROCK_DISPLACEMENT {
                u += a;
            } else if i == ROCK_VELOCITY {
                ud += a;
            } else if cols.contains(&i) {
                g[i - cols.start] += a;
            }
        }
        let m: Vec<C64> = (0..zl)
            .map(|j| (0..zl).map(|i| self.to_z[(i, j)] * g[i]).sum())
            .collect();
        let ml = m.iter().zip(&self.lam).map(|(a, l)| a * l).collect();
        ModalFunctional { u, ud, m, ml }
    }

    /// q = P⁻¹z of a column state z = [w, ẇ].
    fn to_modal(&self, z: &[f64], q: &mut [C64]) {
        for (i, qi) in q.iter_mut().enumerate() {
            *qi = (0..z.len()).map(|j| self.to_q[(i, j)] * z[j]).sum();
        }
    }

    /// z = Re(P·q).
    fn to_physical(&self, q: &[C64], z: &mut [f64]) {
        for (i, zi) in z.iter_mut().enumerate() {
            *zi = (0..q.len())
                .map(|j| {
                    let p = self.to_z[(i, j)];
                    p.re * q[j].re - p.im * q[j].im
                })
                .sum();
        }
    }

    /// e^{Λτ}⊙q into `out`.
    fn advance(&self, q: &[C64], tau: f64, out: &mut [C64]) {
        for ((o, qi), l) in out.iter_mut().zip(q).zip(&self.lam) {
            *o = qi * (l * tau).exp();
        }
    }

    /// The column state z = [w, ẇ] after τ (s) from z₀ and the energy dissipated meanwhile (J).
    #[cfg(test)]
    pub(super) fn propagate(&self, z0: &[f64], tau: f64) -> (Vec<f64>, f64) {
        let mut q0 = vec![C64::new(0.0, 0.0); z0.len()];
        self.to_modal(z0, &mut q0);
        let mut q = q0.clone();
        self.advance(&q0, tau, &mut q);
        let mut z = vec![0.0; z0.len()];
        self.to_physical(&q, &mut z);
        (z, self.dissipated(&q0, tau))
    }

    /// The energy dissipated over τ (s) from the modal state q₀, J: Σᵢⱼ Hᵢⱼq₀ᵢq₀ⱼ times the
    /// divided difference (eᵢeⱼ − 1)/(λᵢ + λⱼ), eᵢ = e^{λᵢτ} (its series where |(λᵢ + λⱼ)τ| < 0.5).
    fn dissipated(&self, q0: &[C64], tau: f64) -> f64 {
        let zl = q0.len();
        let e: Vec<C64> = self.lam.iter().map(|l| (l * tau).exp()).collect();
        let mut d = 0.0;
        for i in 0..zl {
            let mut row = C64::new(0.0, 0.0);
            for j in 0..zl {
                let x = self.lam[i] + self.lam[j];
                let divided = if (x * tau).norm() < 0.5 {
                    divided_exp(x, tau)
                } else {
                    (e[i] * e[j] - 1.0) / x
                };
                row += self.diss[(i, j)] * q0[j] * divided;
            }
            d += (q0[i] * row).re;
        }
        d
    }
}

/// The functionals a modal flight needs: δ (re-contact), and w_mid and the curvatures at the
/// clamp and the midpoint with their rates (extrema).
pub(super) struct ModalFunctionals {
    /// Approach δ = u − φ(½)ᵀw, m.
    pub(super) delta: ModalFunctional,
    /// w_mid, clamp and midpoint curvatures.
    pub(super) values: [ModalFunctional; 3],
    /// Their rates.
    pub(super) rates: [ModalFunctional; 3],
}

/// The hot sums of a flight step at one modal state, column parts only (Re Σ mᵢqᵢ): δ and its
/// slope, the three rates and their slopes, the three values.
#[derive(Clone, Copy, Default)]
struct Sums {
    delta: f64,
    delta_slope: f64,
    rate: [f64; 3],
    rate_slope: [f64; 3],
    value: [f64; 3],
}

/// The coefficients of [`Sums`] per mode, packed for one pass over the modes.
struct Packed {
    /// Per mode: δ, δ slope, rates 0–2, rate slopes 0–2, values 0–2 (11 complex coefficients).
    coef: Vec<[C64; 11]>,
}

impl Packed {
    fn new(fl: &ModalFunctionals) -> Self {
        let coef = (0..fl.delta.m.len())
            .map(|i| {
                [
                    fl.delta.m[i],
                    fl.delta.ml[i],
                    fl.rates[0].m[i],
                    fl.rates[1].m[i],
                    fl.rates[2].m[i],
                    fl.rates[0].ml[i],
                    fl.rates[1].ml[i],
                    fl.rates[2].ml[i],
                    fl.values[0].m[i],
                    fl.values[1].m[i],
                    fl.values[2].m[i],
                ]
            })
            .collect();
        Self { coef }
    }

    /// The sums at q.
    fn sums(&self, q: &[C64]) -> Sums {
        let mut acc = [0.0f64; 11];
        for (c, qi) in self.coef.iter().zip(q) {
            for (a, ck) in acc.iter_mut().zip(c) {
                *a += ck.re * qi.re - ck.im * qi.im;
            }
        }
        Sums {
            delta: acc[0],
            delta_slope: acc[1],
            rate: [acc[2], acc[3], acc[4]],
            rate_slope: [acc[5], acc[6], acc[7]],
            value: [acc[8], acc[9], acc[10]],
        }
    }
}

/// The full state at the modal state q and rock (u, u̇) into `y` (D from `d`, W unchanged).
fn write_state(
    mf: &ModalFlight,
    layout: StateLayout,
    q: &[C64],
    u: f64,
    ud: f64,
    d: f64,
    y: &mut [f64],
) {
    y[ROCK_DISPLACEMENT] = u;
    y[ROCK_VELOCITY] = ud;
    mf.to_physical(q, &mut y[layout.column()]);
    y[layout.dissipated()] = d;
}

/// Free flight of the rock beside the freely vibrating column in modal coordinates, from (t, y)
/// until re-contact (δ ↑ 0, returns `true`) or `t_end`: the same steps, events and samples as
/// [`super::flight::free_flight`], each step O(n).
pub(super) fn modal_free_flight(
    mf: &ModalFlight,
    fl: &ModalFunctionals,
    cx: FlightContext<'_>,
    y: &mut [f64],
    mut t: f64,
    out: Sink<'_>,
    st: &mut Dopri5,
) -> PhysicsResult<(bool, f64)> {
    let FlightContext {
        sys,
        t_end,
        samples,
        record,
        control,
        max_steps,
        amplitude_bound,
    } = cx;
    let Sink { res, next_sample } = out;
    let layout = sys.layout;
    let zl = 2 * layout.n;
    let ud = y[ROCK_VELOCITY];
    let mut u = y[ROCK_DISPLACEMENT];
    let (t_start, d_start) = (t, y[layout.dissipated()]);
    let mut q_start = vec![C64::new(0.0, 0.0); zl];
    mf.to_modal(&y[layout.column()], &mut q_start);
    let mut q = q_start.clone();
    let mut q1 = q.clone();
    let mut qe = q.clone();
    let mut ys = y.to_vec();
    let mut steps_in_flight = 0u64;
    let packed = Packed::new(fl);
    let mut s0v = packed.sums(&q);
    // max|f⁗|/384 of each value over the flight: |qᵢ(t)| ≤ |qᵢ(t₀)| (no mode grows), so
    // Σ|mᵢ|·|λᵢ|⁴·|qᵢ(t₀)| bounds the fourth derivative for the whole flight; doubled for
    // rounding.
    let interpolation_bound: [f64; 3] = std::array::from_fn(|k| {
        let m = &fl.values[k].m;
        2.0 * (0..zl)
            .map(|i| m[i].norm() * mf.lam[i].norm().powi(4) * q_start[i].norm())
            .sum::<f64>()
            / 384.0
    });
    let finish = |q: &[C64], u: f64, t: f64, y: &mut [f64]| {
        let d = d_start + mf.dissipated(&q_start, t - t_start);
        write_state(mf, layout, q, u, ud, d, y);
    };
    loop {
        if t >= t_end {
            finish(&q, u, t, y);
            return Ok((false, t));
        }
        // Checked on entry and every 64 steps.
        if steps_in_flight.is_multiple_of(64) {
            write_state(mf, layout, &q, u, ud, 0.0, &mut ys);
            refuse_unreachable(&ys, mf.h, t, t_end, st.steps, max_steps, amplitude_bound)?;
        }
        steps_in_flight += 1;
        count_flight_step(st, t, t_end, control, max_steps)?;
        let last = t + mf.h >= t_end;
        let h = if last { t_end - t } else { mf.h };
        if last {
            mf.advance(&q, h, &mut q1);
        } else {
            for ((o, qi), e) in q1.iter_mut().zip(&q).zip(&mf.step) {
                *o = qi * e;
            }
        }
        let u1 = u + ud * h;
        let s1v = packed.sums(&q1);
        // Re-contact: δ crossing 0 upward, detected on the Hermite cubic, located exactly.
        let (du, dud) = (fl.delta.u, fl.delta.ud);
        let (g0, g1) = (
            du * u + dud * ud + s0v.delta,
            du * u1 + dud * ud + s1v.delta,
        );
        let (s0, s1) = (
            h * (du * ud + s0v.delta_slope),
            h * (du * ud + s1v.delta_slope),
        );
        let herm = |th: f64| hermite(g0, s0, g1, s1, th);
        let hit = if find_roots(herm, g0, g1, 1, 4, true).is_empty() {
            None
        } else {
            let exact = |th: f64| fl.delta.value_after(u, ud, &q, &mf.lam, th * h);
            find_roots(exact, g0, g1, 1, 8, true).first().copied()
        };
        let th_end = hit.unwrap_or(1.0);
        // Extrema of w_mid and of the curvatures within [0, th_end].
        for k in 0..3 {
            // w_mid and the curvatures have no rock part.
            let (r0, r1) = (s0v.rate[k], s1v.rate[k]);
            let (p0, p1) = (h * s0v.rate_slope[k], h * s1v.rate_slope[k]);
            let herm = |th: f64| hermite(r0, p0, r1, p1, th);
            let mut best: f64 = 0.0;
            for th in find_roots(herm, r0, r1, 0, 4, false) {
                if th <= th_end {
                    // The value's own Hermite cubic (slopes: the rates) is within
                    // h⁴/384·max|f⁗| of it: a maximum that cannot reach the largest so far
                    // needs no exact value.
                    let cubic = hermite(s0v.value[k], h * r0, s1v.value[k], h * r1, th);
                    let current = *extremum_slot(res, k);
                    if cubic.abs() + interpolation_bound[k] * h.powi(4) < current.max(best) {
                        continue;
                    }
                    let v = fl.values[k].value_after(u, ud, &q, &mf.lam, th * h);
                    best = best.max(v.abs());
                }
            }
            let target = extremum_slot(res, k);
            *target = target.max(best);
        }
        let (t_next, u_end) = if hit.is_some() {
            mf.advance(&q, th_end * h, &mut qe);
            (t + th_end * h, u + ud * th_end * h)
        } else {
            qe.copy_from_slice(&q1);
            (if last { t_end } else { t + h }, u1)
        };
        while *next_sample < samples.len() && samples[*next_sample] <= t_next {
            let ts = samples[*next_sample];
            let mut qs = vec![C64::new(0.0, 0.0); zl];
            let (us, tau) = if ts >= t_next {
                qs.copy_from_slice(&qe);
                (u_end, t_next - t_start)
            } else {
                let th = ((ts - t) / h).clamp(0.0, 1.0);
                mf.advance(&q, th * h, &mut qs);
                (u + ud * th * h, t + th * h - t_start)
            };
            let d = d_start + mf.dissipated(&q_start, tau);
            write_state(mf, layout, &qs, us, ud, d, &mut ys);
            record(res, ts, &ys, false);
            *next_sample += 1;
        }
        let se = if hit.is_some() { packed.sums(&qe) } else { s1v };
        for k in 0..3 {
            let v = se.value[k].abs();
            let target = extremum_slot(res, k);
            *target = target.max(v);
        }
        s0v = se;
        std::mem::swap(&mut q, &mut qe);
        u = u_end;
        t = t_next;
        if hit.is_some() {
            finish(&q, u, t, y);
            return Ok((true, t));
        }
    }
}
