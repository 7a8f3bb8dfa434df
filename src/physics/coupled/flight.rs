//! The free flight of the rock beside the freely vibrating column: the column is linear there,
//! z′ = Az with z = [w, ẇ], and is propagated exactly ([`FreeFlight`]: Φ = e^{Ah} and the
//! dissipation Gramian from Van Loan's block exponential, doubled for heavily damped columns),
//! 8 steps per period of the highest mode. Re-contact and the extrema of w_mid and of the
//! curvatures are detected on cubic Hermite interpolants of each step and located on the exact
//! propagator; history samples are taken from it.

#![allow(clippy::needless_range_loop)] // index loops over several parallel arrays

use nalgebra::{DMatrix, DVector};

use super::CoupledResult;
use super::extremum_slot;
use super::system::{Functional, ROCK_DISPLACEMENT, ROCK_VELOCITY, StateLayout, System};
use crate::physics::control::Control;
use crate::physics::error::{PhysicsError, PhysicsResult};
use crate::physics::numeric::ode::{Dopri5, find_roots};

/// Exact propagator of the free column (no contact): z = [w, ẇ], z′ = A z.
///
/// Φ = e^{Ah} and the dissipation Gramian G = ∫₀ʰ e^{Aᵀs} Q e^{As} ds (Q = diag(0, C)) come
/// from one matrix exponential each (Van Loan's block form), so a step costs a mat-vec and a
/// quadratic form; within a step the state is the Taylor series of e^{Aτ}z (‖Aτ‖ ≲ 0.8).
pub(super) struct FreeFlight {
    pub(super) a: DMatrix<f64>,
    pub(super) phi: DMatrix<f64>,
    pub(super) gram: DMatrix<f64>,
    pub(super) h: f64,
    pub(super) c: Vec<f64>,
    pub(super) n: usize,
    /// Largest modal damping rate (M⁻¹C)ᵢᵢ, 1/s.
    pub(super) damping_rate: f64,
}

/// Largest damping rate × time span (dimensionless) over which the free column is propagated by
/// one block exponential (Van Loan) or by a Taylor series: the transposed block of Van Loan's
/// form grows like e^{rate·τ}, so longer spans are built by doubling.
pub(super) const TAYLOR_DAMPING_LIMIT: f64 = 2.0;

/// Φ = e^{Aτ} and the dissipation Gramian G(τ) = ∫₀^τ e^{Aᵀs} Q e^{As} ds (Q = diag(0, C)) of
/// the free column z′ = Az, z = [w, ẇ], for any τ ≥ 0 and any damping.
///
/// Van Loan's block exponential exp([[−Aᵀ, Q], [0, A]]·τ₀) gives both at τ₀ = τ/2ˢ, with s the
/// least such that rate·τ₀ ≤ 2 (`rate` the largest modal damping rate, 1/s); then s doublings
/// Φ(2τ₀) = Φ(τ₀)², G(2τ₀) = G(τ₀) + Φ(τ₀)ᵀG(τ₀)Φ(τ₀). Every factor of the doublings decays, so
/// a heavily damped column (rate·τ up to 10⁴ and beyond) never forms the growing e^{−Aᵀτ}
/// whose product with a decaying factor would overflow or cancel. With s = 0 this is exactly
/// the single block exponential.
pub(super) fn propagator_and_gramian(
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
    pub(super) fn new(minv: &DMatrix<f64>, k: &[f64], c: &[f64], omega_max: f64) -> Self {
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
    pub(super) fn taylor_converges(&self, tau: f64) -> bool {
        self.damping_rate * tau <= TAYLOR_DAMPING_LIMIT
    }

    /// e^{Aτ}z into `out` without allocating (`term`, `next`: scratch of length 2n); stops when
    /// the Taylor term is below 1e-17 of the sum in both halves (w and ẇ), at most 40 terms
    /// (when the damping rate·τ exceeds 2: Φ(τ)z from [`propagator_and_gramian`], allocating).
    pub(super) fn propagate_into(
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
    pub(super) fn taylor(&self, z: &[f64], tau: f64, dissipation: bool) -> (DVector<f64>, f64) {
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

/// Records one history sample (result, time, state, in contact).
pub(super) type Recorder<'a> = dyn Fn(&mut CoupledResult, f64, &[f64], bool) + 'a;
/// Applies a functional to a state.
pub(super) type Apply<'a> = dyn Fn(&[(usize, f64)], &[f64]) -> f64 + 'a;

/// Where a phase of the coupled solve writes: the result, and the index of the next history
/// sample to take.
pub(super) struct Sink<'a> {
    /// The result being written.
    pub(super) res: &'a mut CoupledResult,
    /// Index of the next history sample time to take.
    pub(super) next_sample: &'a mut usize,
}

/// What a free flight runs in: the system, the window's end (s), the history sample times (s)
/// and how a sample is recorded, the control, the step budget and the bound on |w_mid| (m) of a
/// column state.
#[derive(Clone, Copy)]
pub(super) struct FlightContext<'a> {
    /// The coupled system.
    pub(super) sys: &'a System,
    /// End of the window, s.
    pub(super) t_end: f64,
    /// History sample times, s.
    pub(super) samples: &'a [f64],
    /// Records a history sample.
    pub(super) record: &'a Recorder<'a>,
    /// Cancel and time limit.
    pub(super) control: &'a Control,
    /// Step budget of the whole solve.
    pub(super) max_steps: u64,
    /// Bound on |w_mid| (m) of a column state.
    pub(super) amplitude_bound: &'a dyn Fn(&[f64]) -> f64,
}

/// The functionals a flight tracks: w_mid and the two curvatures, their rates, and how one is
/// applied to a state.
pub(super) struct Tracked<'a> {
    /// Applies a functional to a state.
    pub(super) apply: &'a Apply<'a>,
    /// w_mid (m), the clamp and midpoint curvatures (1/m).
    pub(super) values: [&'a Functional; 3],
    /// Their rates.
    pub(super) rates: [&'a Functional; 3],
}

/// Cubic Hermite interpolant on θ ∈ [0, 1] from end values and end slopes (per unit θ).
pub(super) fn hermite(g0: f64, d0: f64, g1: f64, d1: f64, th: f64) -> f64 {
    let t2 = th * th;
    let t3 = t2 * th;
    (2.0 * t3 - 3.0 * t2 + 1.0) * g0
        + (t3 - 2.0 * t2 + th) * d0
        + (-2.0 * t3 + 3.0 * t2) * g1
        + (t3 - t2) * d1
}

/// z ← M x for a column-major square matrix M of side x.len() (no allocation).
pub(super) fn matvec_col_major(m: &[f64], x: &[f64], out: &mut [f64]) {
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
    pub(super) fn derivative(&self, layout: StateLayout, y: &[f64], d: &mut [f64]) {
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
    pub(super) fn state_at(
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
    pub(super) fn step_exact(
        &self,
        layout: StateLayout,
        y0: &[f64],
        y1: &mut [f64],
        gz: &mut [f64],
    ) {
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
    pub(super) fn locate_recontact(
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
pub(super) struct FlightScratch {
    pub(super) y0: Vec<f64>,
    pub(super) y1: Vec<f64>,
    pub(super) dy0: Vec<f64>,
    pub(super) dy1: Vec<f64>,
    pub(super) gz: Vec<f64>,
    pub(super) ye: Vec<f64>,
    pub(super) tb1: Vec<f64>,
    pub(super) tb2: Vec<f64>,
}

impl FlightScratch {
    pub(super) fn new(layout: StateLayout) -> Self {
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

/// Extrema of w_mid and of the curvatures within θ ∈ [0, th_end] of a flight step of size h
/// (states and slopes in `s`): roots of the rates detected on cubic Hermite interpolants, the
/// values taken on the exact propagator.
pub(super) fn flight_extrema(
    ff: &FreeFlight,
    layout: StateLayout,
    res: &mut CoupledResult,
    tracked: &Tracked<'_>,
    s: &mut FlightScratch,
    h: f64,
    th_end: f64,
) {
    let Tracked {
        apply,
        values,
        rates,
    } = tracked;
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
/// steps (of `h`, s) exceed the limit. Once the rock recedes (u̇ ≤ 0) beyond the reach of the
/// column's energy (u < −√(2·E_col·reach), E_col never grows in flight), it never touches the
/// column again: the rest of the window is the propagator's fixed steps, counted exactly.
pub(super) fn refuse_unreachable(
    y: &[f64],
    h: f64,
    t: f64,
    t_end: f64,
    steps: u64,
    max_steps: u64,
    amplitude_bound: &dyn Fn(&[f64]) -> f64,
) -> PhysicsResult<()> {
    if y[ROCK_VELOCITY] <= 0.0 && y[ROCK_DISPLACEMENT] < -amplitude_bound(y) * (1.0 + 1e-9) {
        let remaining = ((t_end - t) / h).ceil();
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

/// Counts one flight step into `st` at time `t` (s): polls the control every 1000 steps and
/// refuses the pass at the step limit (the estimate scaled to the window's end `t_end`).
pub(super) fn count_flight_step(
    st: &mut Dopri5,
    t: f64,
    t_end: f64,
    control: &Control,
    max_steps: u64,
) -> PhysicsResult<()> {
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
    Ok(())
}

/// Free flight of the rock beside the freely vibrating column, from (t, y) until re-contact
/// (δ ↑ 0, returns `true`) or `t_end`, by the exact propagator; records extrema and samples.
pub(super) fn free_flight(
    ff: &FreeFlight,
    cx: FlightContext<'_>,
    tracked: &Tracked<'_>,
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
    let mut s = FlightScratch::new(layout);
    ff.derivative(layout, y, &mut s.dy0);
    let mut steps_in_flight = 0u64;
    loop {
        if t >= t_end {
            return Ok((false, t));
        }
        // Checked on entry and every 64 steps.
        if steps_in_flight.is_multiple_of(64) {
            refuse_unreachable(y, ff.h, t, t_end, st.steps, max_steps, amplitude_bound)?;
        }
        steps_in_flight += 1;
        count_flight_step(st, t, t_end, control, max_steps)?;
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
        flight_extrema(ff, layout, res, tracked, &mut s, h, th_end);
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
            let v = (tracked.apply)(tracked.values[k], y_end).abs();
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
