//! The contact phase of a heavily damped column by an exponential integrator (ETDRK4, Cox &
//! Matthews 2002), whose step is set by the contact force's time scale, not by the damping rate.
//!
//! While in contact, the rock and the column obey y′ = Ly + β·P(δ(y)): L is the exact linear part
//! (u′ = u̇, w′ = ẇ, ẇ′ = −M⁻¹Kw − M⁻¹Cẇ) and the contact force P, a scalar, drives the fixed
//! vector β = [0, −1/m, 0, M⁻¹φ(½)]. The integrator propagates L exactly through e^{τL} and
//! φₖ(τL)β ([`phi_action`]), so a damping rate of 2·10⁷ /s (c = 1e9 N·s/m²) costs nothing: the
//! explicit Dormand–Prince, stable only for h·rate ≤ 3.3, needs ~7 000 steps per contact there.
//! The dissipated energy D = ∫ẇᵀCẇ dt and the work W = ∫P·φᵀẇ dt of the contact force on the
//! column come from the corrected trapezoid rule h/2·(f₀ + f₁) + h²/12·(f₀′ − f₁′) on the step's
//! end states (their exact slopes give f′; error O(h⁵), the order of the step), so both stay
//! independent quadratures and the column's balance E_col + D = W checks the integration.
//!
//! Error control by step doubling (one step of h against two of h/2, the weighted RMS norm of
//! the Dormand–Prince stepper); the accepted state is the single step's, so the dense output — a
//! step of θh from the step's start, exact in L — is continuous at θ = 1. Events (separation,
//! maxima of approach, extrema of w_mid and of the curvatures) are detected on cubic Hermite
//! interpolants and located on that dense output; history samples are taken from it.
//!
//! Used while in contact when the damping rate would bound Dormand–Prince's contact steps
//! ([`exponential_contact_pays`]); the free flight stays with its exact propagator.

use nalgebra::{DMatrix, DVector};

use super::estimate::DOPRI5_STABILITY_LIMIT;
use super::flight::{Sink, hermite};
use super::pass::Pass;
use super::system::{Functional, ROCK_DISPLACEMENT, ROCK_VELOCITY, System, apply};
use super::{capacity_exceeded, extremum_slot};
use crate::physics::control::Control;
use crate::physics::error::{PhysicsError, PhysicsResult};
use crate::physics::numeric::expo::{PhiAction, phi_action};
use crate::physics::numeric::ode::{OdeSystem, find_roots};

/// Dormand–Prince contact steps (t_c·rate/3.307) above which the exponential integrator takes
/// the contact phases: it needs a few dozen steps per contact at any damping, each a few
/// exponentials of the (2n + 5)-square augmented matrix.
const EXPONENTIAL_CONTACT_STEPS: f64 = 300.0;

/// Largest damping rate × contact time (dimensionless) given to the exponential integrator:
/// 5 times the documented maximum (c = 1e9 N·s/m² on the default column, rate ≈ 2·10⁷ /s over
/// t_c ≈ 1.1 ms, about 2·10⁴), the range its tests cover. Beyond it (an almost massless column
/// of a vanishing wall, rate·t_c ~ 10¹⁰) its step control does not converge in reasonable time,
/// and the run stays with Dormand–Prince, whose step estimate refuses it up front.
const EXPONENTIAL_CONTACT_MAX_STIFFNESS: f64 = 1e5;

/// Whether the exponential integrator should take the contact phases of a column with damping
/// rate `rate` (1/s) over contacts of duration `contact_time` (s): when Dormand–Prince's
/// stability limit h·rate ≤ 3.307 alone would cost more than [`EXPONENTIAL_CONTACT_STEPS`],
/// up to rate·t_c = [`EXPONENTIAL_CONTACT_MAX_STIFFNESS`].
pub(super) fn exponential_contact_pays(rate: f64, contact_time: f64) -> bool {
    let stiffness = rate * contact_time;
    stiffness / DOPRI5_STABILITY_LIMIT > EXPONENTIAL_CONTACT_STEPS
        && stiffness <= EXPONENTIAL_CONTACT_MAX_STIFFNESS
}

/// Exponential (ETDRK4) stepper of the contact phase with step-doubling error control.
pub(super) struct ExpStepper {
    /// Linear part L over [u, u̇, w, ẇ], (2n + 2)-square.
    l: DMatrix<f64>,
    /// The force's direction β = [0, −1/m, 0, M⁻¹φ(½)] (per newton).
    beta: DVector<f64>,
    /// Balancing scales of the components (s for u, 1/ωᵢ for wᵢ, 1 for velocities).
    scale: Vec<f64>,
    /// Relative tolerance.
    rtol: f64,
    /// Absolute tolerances of every component of the state.
    atol: Vec<f64>,
    /// Step to try next, s.
    pub(super) h: f64,
    /// Largest step, s.
    max_step: f64,
    /// Accepted steps.
    pub(super) steps: u64,
    /// Rejected steps.
    pub(super) rejected: u64,
    /// Cached e^{τL}, φₖ(τL)β of the last spans used.
    cache: Vec<(f64, PhiAction)>,
}

/// Stage values of one step: the force P (N) at a stage.
struct Stage {
    p: f64,
}

impl ExpStepper {
    /// The stepper of `sys` with M⁻¹ `minv` (1/kg), tolerances `rtol`/`atol` (of the full
    /// state), first step `h0` and largest step `max_step` (s), `time_scale` the contact's (s).
    pub(super) fn new(
        sys: &System,
        minv: &DMatrix<f64>,
        rtol: f64,
        atol: Vec<f64>,
        h0: f64,
        max_step: f64,
        time_scale: f64,
    ) -> Self {
        let n = sys.n;
        let m = 2 + 2 * n;
        let layout = sys.layout;
        let mut l = DMatrix::zeros(m, m);
        let mut beta = DVector::zeros(m);
        let mut scale = vec![1.0; m];
        l[(ROCK_DISPLACEMENT, ROCK_VELOCITY)] = 1.0;
        beta[ROCK_VELOCITY] = -1.0 / sys.m;
        scale[ROCK_DISPLACEMENT] = time_scale;
        for i in 0..n {
            let (wi, vi) = (layout.modal_displacement(i), layout.modal_velocity(i));
            l[(wi, vi)] = 1.0;
            for j in 0..n {
                l[(vi, layout.modal_displacement(j))] = -minv[(i, j)] * sys.k[j];
                l[(vi, layout.modal_velocity(j))] = -minv[(i, j)] * sys.c[j];
                beta[vi] += minv[(i, j)] * sys.phi[j];
            }
            scale[wi] = 1.0 / (sys.k[i] * minv[(i, i)]).sqrt().max(1.0 / time_scale);
        }
        Self {
            l,
            beta,
            scale,
            rtol,
            atol,
            h: h0,
            max_step,
            steps: 0,
            rejected: 0,
            cache: Vec::with_capacity(4),
        }
    }

    /// e^{τL} and φₖ(τL)β, from the cache of the last four spans when there.
    fn phi(&mut self, tau: f64) -> PhiAction {
        if let Some((_, pa)) = self.cache.iter().find(|(t, _)| *t == tau) {
            return pa.clone();
        }
        let pa = phi_action(&self.l, &self.beta, &self.scale, tau);
        if self.cache.len() == 4 {
            self.cache.remove(0);
        }
        self.cache.push((tau, pa.clone()));
        pa
    }

    /// The force at state y, or `None` outside the law's domain.
    fn stage(sys: &System, y: &[f64]) -> Option<Stage> {
        let p = sys.law.force(sys.delta(y)).filter(|p| p.is_finite())?;
        Some(Stage { p })
    }

    /// One ETDRK4 step of size `h` from y0 (full state) into `out`; `None` when a stage
    /// leaves the force law's domain.
    pub(super) fn etd4(&mut self, sys: &System, y0: &[f64], h: f64, out: &mut [f64]) -> Option<()> {
        let m = self.l.nrows();
        let half = self.phi(0.5 * h);
        let full = self.phi(h);
        let z0 = DVector::from_column_slice(&y0[..m]);
        let e2z0 = &half.exp * &z0;
        let g1h = &half.phi_b[0] * (0.5 * h);
        let mut tmp = y0.to_vec();
        let su = Self::stage(sys, y0)?;
        let a = &e2z0 + &g1h * su.p;
        tmp[..m].copy_from_slice(a.as_slice());
        let sa = Self::stage(sys, &tmp)?;
        let b = &e2z0 + &g1h * sa.p;
        tmp[..m].copy_from_slice(b.as_slice());
        let sb = Self::stage(sys, &tmp)?;
        let c = &half.exp * &a + &g1h * (2.0 * sb.p - su.p);
        tmp[..m].copy_from_slice(c.as_slice());
        let sc = Self::stage(sys, &tmp)?;
        let [g1, g2, g3] = &full.phi_b;
        let f1 = g1 - g2 * 3.0 + g3 * 4.0;
        let f2 = g2 * 2.0 - g3 * 4.0;
        let f3 = g3 * 4.0 - g2;
        let z1 = &full.exp * &z0 + (f1 * su.p + f2 * (sa.p + sb.p) + f3 * sc.p) * h;
        out[..m].copy_from_slice(z1.as_slice());
        let p1 = sys.law.force(sys.delta(out)).filter(|p| p.is_finite())?;
        let layout = sys.layout;
        // D by the corrected trapezoid h/2·(f₀ + f₁) + h²/12·(f₀′ − f₁′), f = ẇᵀCẇ, f′ = 2ẇᵀCẅ
        // with ẅ the exact slope of the state (error O(h⁵), the order of the step).
        let dis_and_slope = |z: &DVector<f64>, p: f64| {
            let acc = &self.l * z + &self.beta * p;
            (0..sys.n).fold((0.0, 0.0), |(f, df), j| {
                let v = layout.modal_velocity(j);
                (
                    f + sys.c[j] * z[v] * z[v],
                    df + 2.0 * sys.c[j] * z[v] * acc[v],
                )
            })
        };
        let (f0, df0) = dis_and_slope(&z0, su.p);
        let (f1, df1) = dis_and_slope(&z1, p1);
        out[layout.dissipated()] =
            y0[layout.dissipated()] + 0.5 * h * (f0 + f1) + h * h / 12.0 * (df0 - df1);
        // W = ∫P·φᵀẇ dt by the same rule, f′ = (dP/dδ)·δ̇·φᵀẇ + P·φᵀẅ.
        let (g0, dg0) = self.work_and_slope(sys, &z0, su.p)?;
        let (g1, dg1) = self.work_and_slope(sys, &z1, p1)?;
        out[layout.work()] = y0[layout.work()] + 0.5 * h * (g0 + g1) + h * h / 12.0 * (dg0 - dg1);
        Some(())
    }

    /// The work rate P·φᵀẇ (W) and its time derivative at the column part z of a state with
    /// force p (N); dP/dδ by a central difference of relative width 1e-5 (one-sided at the
    /// capacity), whose error only enters the O(h²) correction.
    fn work_and_slope(&self, sys: &System, z: &DVector<f64>, p: f64) -> Option<(f64, f64)> {
        let layout = sys.layout;
        let acc = &self.l * z + &self.beta * p;
        let (mut mid, mut mid_rate, mut delta, mut delta_rate) =
            (0.0, 0.0, z[ROCK_DISPLACEMENT], z[ROCK_VELOCITY]);
        for j in 0..sys.n {
            let (w, v) = (layout.modal_displacement(j), layout.modal_velocity(j));
            mid += sys.phi[j] * z[v];
            mid_rate += sys.phi[j] * acc[v];
            delta -= sys.phi[j] * z[w];
            delta_rate -= sys.phi[j] * z[v];
        }
        let dp = if delta > 0.0 {
            let eta = 1e-5 * delta;
            let hi = sys.law.force(delta + eta).filter(|q| q.is_finite());
            let lo = sys.law.force(delta - eta)?;
            match hi {
                Some(hi) => (hi - lo) / (2.0 * eta),
                None => (p - lo) / eta,
            }
        } else {
            0.0
        };
        Some((p * mid, dp * delta_rate * mid + p * mid_rate))
    }

    /// Weighted RMS norm of y1 − y2 (the Dormand–Prince stepper's norm).
    fn error_norm(&self, y0: &[f64], y1: &[f64], y2: &[f64]) -> f64 {
        let sum: f64 = (0..y0.len())
            .map(|i| {
                let sk = self.atol[i] + self.rtol * y0[i].abs().max(y1[i].abs());
                let r = (y1[i] - y2[i]) / sk;
                r * r
            })
            .sum();
        (sum / y0.len() as f64).sqrt()
    }

    /// One accepted step from (t, y0) not past `t_end`: the new state in `y1`, the step size
    /// returned. Step doubling: the error of a step of h is estimated against two of h/2.
    ///
    /// # Errors
    /// `Numerical` when the step size underflows (a stage keeps leaving the law's domain).
    pub(super) fn step(
        &mut self,
        sys: &System,
        t: f64,
        y0: &[f64],
        t_end: f64,
        y1: &mut [f64],
    ) -> PhysicsResult<f64> {
        let min_h = 1e-14 * t.abs().max(t_end.abs()).max(f64::MIN_POSITIVE);
        let mut mid = y0.to_vec();
        let mut two = y0.to_vec();
        loop {
            let mut h = self.h.min(self.max_step);
            if t + 1.01 * h >= t_end {
                h = t_end - t;
            }
            let err = self
                .etd4(sys, y0, h, y1)
                .and_then(|()| self.etd4(sys, y0, 0.5 * h, &mut mid))
                .and_then(|()| self.etd4(sys, &mid, 0.5 * h, &mut two))
                .map(|()| self.error_norm(y0, y1, &two));
            match err {
                Some(e) if e <= 1.0 => {
                    self.steps += 1;
                    // local error O(h⁵)
                    self.h = h * (0.9 * e.max(1e-10).powf(-0.2)).clamp(0.2, 5.0);
                    return Ok(h);
                }
                other => {
                    self.rejected += 1;
                    let fac = match other {
                        Some(e) if e.is_finite() => (0.9 * e.powf(-0.2)).clamp(0.1, 0.9),
                        Some(_) => 0.1,
                        None => 0.25,
                    };
                    self.h = h * fac;
                    if self.h < min_h {
                        return Err(PhysicsError::Numerical(format!(
                            "step size underflow at t = {t:e} s"
                        )));
                    }
                }
            }
        }
    }
}

/// The accepted step being processed: its start state and slopes, its end and size.
struct Span<'a> {
    y0: &'a [f64],
    y1: &'a [f64],
    dy0: &'a [f64],
    dy1: &'a [f64],
    h: f64,
}

impl Span<'_> {
    /// Roots of functional `f` on θ ∈ (0, `th_end`] in direction `dir`, detected on the cubic
    /// Hermite interpolant of f (slopes f(ẏ), f being linear), located on the dense output
    /// `exact`.
    fn roots(&self, f: &Functional, dir: i8, th_end: f64, exact: &dyn Fn(f64) -> f64) -> Vec<f64> {
        let (g0, g1) = (apply(f, self.y0), apply(f, self.y1));
        let (s0, s1) = (self.h * apply(f, self.dy0), self.h * apply(f, self.dy1));
        let herm = |th: f64| hermite(g0, s0, g1, s1, th);
        let coarse = find_roots(herm, g0, g1, dir, 4, false);
        let mut roots = Vec::with_capacity(coarse.len());
        // Each root of the interpolant is bracketed within ±1/8 on the exact dense output and
        // located there; when the bracket fails, the whole step is scanned on 8 pieces.
        for &r in &coarse {
            let (a, b) = ((r - 0.125).max(0.0), (r + 0.125).min(1.0));
            let ga = if a == 0.0 { g0 } else { exact(a) };
            let gb = if b == 1.0 { g1 } else { exact(b) };
            let sub = |x: f64| exact(a + x * (b - a));
            match find_roots(sub, ga, gb, dir, 1, true).first() {
                Some(&x) => roots.push(a + x * (b - a)),
                None => return Self::filtered(find_roots(exact, g0, g1, dir, 8, false), th_end),
            }
        }
        roots.dedup_by(|x, y| (*x - *y).abs() < 1e-12);
        Self::filtered(roots, th_end)
    }

    /// The roots at or before `th_end`.
    fn filtered(roots: Vec<f64>, th_end: f64) -> Vec<f64> {
        roots.into_iter().filter(|&th| th <= th_end).collect()
    }
}

/// The contact phase from (t, y) until separation (δ ↓ 0, returns `true`) or `t_end`, by the
/// exponential stepper: maxima of approach, extrema of w_mid and of the curvatures, history
/// samples and the capacity check, as the Dormand–Prince contact phase does.
pub(super) fn exponential_contact(
    st: &mut ExpStepper,
    pass: &Pass,
    y: &mut [f64],
    mut t: f64,
    out: Sink<'_>,
    control: &Control,
    steps_before: u64,
) -> PhysicsResult<(bool, f64)> {
    let Sink { res, next_sample } = out;
    let (sys, input, fs) = (pass.sys, pass.input, pass.fs);
    let t_end = input.end_time;
    let samples = &input.sample_times;
    let dim = y.len();
    let (mut y1, mut dy0, mut dy1) = (vec![0.0; dim], vec![0.0; dim], vec![0.0; dim]);
    while t < t_end {
        let total = steps_before + st.steps;
        if total % 1000 == 999 {
            control.check()?;
        }
        if total >= input.max_steps {
            return Err(PhysicsError::TooManySteps {
                estimated: total as f64 * t_end / t.max(f64::MIN_POSITIVE),
                limit: input.max_steps as f64,
            });
        }
        let h = st.step(sys, t, y, t_end, &mut y1)?;
        let y0 = y.to_vec();
        if !sys.rhs(t, &y0, &mut dy0) || !sys.rhs(t + h, &y1, &mut dy1) {
            return Err(capacity_exceeded(input));
        }
        let span = Span {
            y0: &y0,
            y1: &y1,
            dy0: &dy0,
            dy1: &dy1,
            h,
        };
        let cell = std::cell::RefCell::new(&mut *st);
        // The state at θ of the step: a step of θh from its start (exact in L).
        let dense = |th: f64| -> PhysicsResult<Vec<f64>> {
            if th >= 1.0 {
                return Ok(y1.clone());
            }
            let mut out = vec![0.0; dim];
            cell.borrow_mut()
                .etd4(sys, &y0, th * h, &mut out)
                .map(|()| out)
                .ok_or_else(|| capacity_exceeded(input))
        };
        let value_at = |f: &Functional, th: f64| dense(th).map_or(f64::NAN, |v| apply(f, &v));
        // Separation: δ crossing 0 downward.
        let sep = span
            .roots(&fs.delta, -1, 1.0, &|th| value_at(&fs.delta, th))
            .first()
            .copied()
            .filter(|&th| th * h > 1e-13 * h.max(t.abs() * 1e-3));
        let th_end = sep.unwrap_or(1.0);
        // Maxima of approach: δ̇ crossing 0 downward.
        for th in span.roots(&fs.delta_rate, -1, th_end, &|th| {
            value_at(&fs.delta_rate, th)
        }) {
            let d = value_at(&fs.delta, th);
            if d > res.max_contact_deformation {
                res.max_contact_deformation = d;
                res.max_force = input.law.force(d).ok_or_else(|| capacity_exceeded(input))?;
            }
        }
        // Extrema of w_mid and of the curvatures.
        let y_end = dense(th_end)?;
        for (k, (val, rate)) in [
            (&fs.wmid, &fs.wmid_rate),
            (&fs.c0, &fs.c0_rate),
            (&fs.cm, &fs.cm_rate),
        ]
        .into_iter()
        .enumerate()
        {
            let mut best = apply(val, &y_end).abs();
            for th in span.roots(rate, 0, th_end, &|th| value_at(rate, th)) {
                best = best.max(value_at(val, th).abs());
            }
            let target = extremum_slot(res, k);
            *target = target.max(best);
        }
        let t_next = t + th_end * h;
        while *next_sample < samples.len() && samples[*next_sample] <= t_next {
            let ts = samples[*next_sample];
            let ys = if ts >= t_next {
                y_end.clone()
            } else {
                dense(((ts - t) / h).clamp(0.0, 1.0))?
            };
            pass.record(res, ts, &ys, true);
            *next_sample += 1;
        }
        y.copy_from_slice(&y_end);
        t = if sep.is_some() || th_end < 1.0 {
            t_next
        } else if t + h >= t_end {
            t_end
        } else {
            t + h
        };
        if let Some(cap) = input.law.deformation_capacity()
            && sys.delta(y) >= cap
        {
            return Err(capacity_exceeded(input));
        }
        if sep.is_some() {
            return Ok((true, t));
        }
    }
    Ok((false, t))
}
