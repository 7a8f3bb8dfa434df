//! Dormand–Prince 5(4) explicit Runge–Kutta integrator with step-size control and 4th-order
//! dense output (Hairer, Nørsett & Wanner, *Solving ODEs I*, 2nd ed., §II.4–II.6, code DOPRI5).
//!
//! The integrator takes one accepted step at a time so that the caller can look for events
//! on the dense output between the two ends of the step and restart after a discontinuity.

#![allow(clippy::needless_range_loop)] // index loops over several parallel arrays

/// A first-order system y′ = f(t, y).
pub trait OdeSystem {
    /// Evaluates f(t, y) into `dy`; returns `false` when y lies outside the system's domain
    /// (the step is then rejected and retried with a smaller step).
    fn rhs(&self, t: f64, y: &[f64], dy: &mut [f64]) -> bool;
}

/// Why the integrator stopped.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum OdeError {
    /// The step size fell below 1e-14 relative to t (or the system rejects every state near t).
    StepTooSmall {
        /// Time reached, s.
        t: f64,
    },
}

const C2: f64 = 1.0 / 5.0;
const C3: f64 = 3.0 / 10.0;
const C4: f64 = 4.0 / 5.0;
const C5: f64 = 8.0 / 9.0;
const A21: f64 = 1.0 / 5.0;
const A31: f64 = 3.0 / 40.0;
const A32: f64 = 9.0 / 40.0;
const A41: f64 = 44.0 / 45.0;
const A42: f64 = -56.0 / 15.0;
const A43: f64 = 32.0 / 9.0;
const A51: f64 = 19372.0 / 6561.0;
const A52: f64 = -25360.0 / 2187.0;
const A53: f64 = 64448.0 / 6561.0;
const A54: f64 = -212.0 / 729.0;
const A61: f64 = 9017.0 / 3168.0;
const A62: f64 = -355.0 / 33.0;
const A63: f64 = 46732.0 / 5247.0;
const A64: f64 = 49.0 / 176.0;
const A65: f64 = -5103.0 / 18656.0;
const A71: f64 = 35.0 / 384.0;
const A73: f64 = 500.0 / 1113.0;
const A74: f64 = 125.0 / 192.0;
const A75: f64 = -2187.0 / 6784.0;
const A76: f64 = 11.0 / 84.0;
const E1: f64 = 71.0 / 57600.0;
const E3: f64 = -71.0 / 16695.0;
const E4: f64 = 71.0 / 1920.0;
const E5: f64 = -17253.0 / 339200.0;
const E6: f64 = 22.0 / 525.0;
const E7: f64 = -1.0 / 40.0;
const D1: f64 = -12715105075.0 / 11282082432.0;
const D3: f64 = 87487479700.0 / 32700410799.0;
const D4: f64 = -10690763975.0 / 1880347072.0;
const D5: f64 = 701980252875.0 / 199316789632.0;
const D6: f64 = -1453857185.0 / 822651844.0;
const D7: f64 = 69997945.0 / 29380423.0;

/// Dormand–Prince 5(4) stepper with error control and dense output.
#[derive(Debug, Clone)]
pub struct Dopri5 {
    /// Relative tolerance (dimensionless).
    pub rtol: f64,
    /// Absolute tolerance per component (units of the component).
    pub atol: Vec<f64>,
    /// Largest step allowed, s (default ∞).
    pub max_step: f64,
    /// Step size to try next, s.
    pub h: f64,
    /// Accepted steps so far.
    pub steps: u64,
    /// Rejected steps so far.
    pub rejected: u64,
    /// Right-hand-side evaluations so far.
    pub evaluations: u64,
    /// Estimated local error (weighted RMS norm, ≤ 1 when accepted) of the last step.
    pub last_error: f64,
    k: [Vec<f64>; 7],
    ytmp: Vec<f64>,
    ynew: Vec<f64>,
    fsal_valid: bool,
    /// Error norm of the last accepted step (PI control).
    err_old: f64,
    /// Dense-output coefficients of the last accepted step.
    rcont: [Vec<f64>; 5],
    t_old: f64,
    h_old: f64,
}

impl Dopri5 {
    /// A stepper for `dim` components with relative tolerance `rtol`, absolute tolerances `atol`
    /// and first trial step `h0` (s).
    #[must_use]
    pub fn new(rtol: f64, atol: Vec<f64>, h0: f64) -> Self {
        let dim = atol.len();
        let z = || vec![0.0; dim];
        Self {
            rtol,
            atol,
            max_step: f64::INFINITY,
            h: h0,
            steps: 0,
            rejected: 0,
            evaluations: 0,
            last_error: 0.0,
            k: [z(), z(), z(), z(), z(), z(), z()],
            ytmp: z(),
            ynew: z(),
            fsal_valid: false,
            err_old: 1e-4,
            rcont: [z(), z(), z(), z(), z()],
            t_old: 0.0,
            h_old: 0.0,
        }
    }

    /// Forgets the stored derivative (call after the right-hand side changed discontinuously).
    pub fn reset(&mut self) {
        self.fsal_valid = false;
    }

    /// Stage evaluations of one step of size h from (t, y); the 5th-order result goes to
    /// `ynew`; returns the error norm, or `None` when a stage left the system's domain.
    fn attempt<S: OdeSystem>(&mut self, sys: &S, t: f64, y: &[f64], h: f64) -> Option<f64> {
        let n = y.len();
        if !self.fsal_valid {
            let (k0, _) = self.k.split_at_mut(1);
            self.evaluations += 1;
            if !sys.rhs(t, y, &mut k0[0]) {
                return None;
            }
            self.fsal_valid = true;
        }
        macro_rules! stage {
            ($dst:expr, $c:expr, [$(($a:expr, $j:expr)),*]) => {{
                for i in 0..n {
                    self.ytmp[i] = y[i] + h * (0.0 $(+ $a * self.k[$j][i])*);
                }
                let mut out = std::mem::take(&mut self.k[$dst]);
                self.evaluations += 1;
                let ok = sys.rhs(t + $c * h, &self.ytmp, &mut out);
                self.k[$dst] = out;
                if !ok {
                    return None;
                }
            }};
        }
        stage!(1, C2, [(A21, 0)]);
        stage!(2, C3, [(A31, 0), (A32, 1)]);
        stage!(3, C4, [(A41, 0), (A42, 1), (A43, 2)]);
        stage!(4, C5, [(A51, 0), (A52, 1), (A53, 2), (A54, 3)]);
        stage!(5, 1.0, [(A61, 0), (A62, 1), (A63, 2), (A64, 3), (A65, 4)]);
        for i in 0..n {
            self.ynew[i] = y[i]
                + h * (A71 * self.k[0][i]
                    + A73 * self.k[2][i]
                    + A74 * self.k[3][i]
                    + A75 * self.k[4][i]
                    + A76 * self.k[5][i]);
        }
        {
            let mut out = std::mem::take(&mut self.k[6]);
            self.evaluations += 1;
            let ok = sys.rhs(t + h, &self.ynew, &mut out);
            self.k[6] = out;
            if !ok {
                return None;
            }
        }
        let mut sum = 0.0;
        for i in 0..n {
            let e = h
                * (E1 * self.k[0][i]
                    + E3 * self.k[2][i]
                    + E4 * self.k[3][i]
                    + E5 * self.k[4][i]
                    + E6 * self.k[5][i]
                    + E7 * self.k[6][i]);
            let sk = self.atol[i] + self.rtol * y[i].abs().max(self.ynew[i].abs());
            let r = e / sk;
            sum += r * r;
        }
        Some((sum / n as f64).sqrt())
    }

    /// One step of exactly `h` without error control (for convergence tests); the result is
    /// written to `y` and the dense output of the step is stored.
    ///
    /// # Errors
    /// `StepTooSmall` when a stage leaves the system's domain.
    pub fn fixed_step<S: OdeSystem>(
        &mut self,
        sys: &S,
        t: f64,
        y: &mut [f64],
        h: f64,
    ) -> Result<(), OdeError> {
        self.fsal_valid = false;
        let err = self
            .attempt(sys, t, y, h)
            .ok_or(OdeError::StepTooSmall { t })?;
        self.last_error = err;
        self.accept(t, y, h);
        Ok(())
    }

    fn accept(&mut self, t: f64, y: &mut [f64], h: f64) {
        let n = y.len();
        for i in 0..n {
            let ydiff = self.ynew[i] - y[i];
            let bspl = h * self.k[0][i] - ydiff;
            self.rcont[0][i] = y[i];
            self.rcont[1][i] = ydiff;
            self.rcont[2][i] = bspl;
            self.rcont[3][i] = ydiff - h * self.k[6][i] - bspl;
            self.rcont[4][i] = h
                * (D1 * self.k[0][i]
                    + D3 * self.k[2][i]
                    + D4 * self.k[3][i]
                    + D5 * self.k[4][i]
                    + D6 * self.k[5][i]
                    + D7 * self.k[6][i]);
        }
        y.copy_from_slice(&self.ynew);
        // FSAL: the last stage is the first of the next step.
        self.k.swap(0, 6);
        self.t_old = t;
        self.h_old = h;
        self.steps += 1;
    }

    /// Advances (t, y) by one accepted step, not past `t_end`; returns the new t.
    ///
    /// Error norm: RMS of errᵢ/(atolᵢ + rtol·max(|y₀ᵢ|, |y₁ᵢ|)); PI step-size control.
    /// A right-hand side that reports a state outside its domain rejects the step (h ÷ 4).
    ///
    /// # References
    /// Hairer, Nørsett & Wanner, *Solving ODEs I*, §II.4 (control), §II.6 (dense output).
    ///
    /// # Errors
    /// `StepTooSmall` when the step size underflows (1e-14·max(|t|, |h₀|)).
    pub fn step<S: OdeSystem>(
        &mut self,
        sys: &S,
        t: f64,
        y: &mut [f64],
        t_end: f64,
    ) -> Result<f64, OdeError> {
        let min_h = 1e-14 * t.abs().max(t_end.abs()).max(f64::MIN_POSITIVE);
        loop {
            let mut h = self.h.min(self.max_step);
            let last = t + h >= t_end || t + 1.01 * h >= t_end;
            if last {
                h = t_end - t;
            }
            if h < min_h && !last {
                return Err(OdeError::StepTooSmall { t });
            }
            match self.attempt(sys, t, y, h) {
                None => {
                    self.rejected += 1;
                    self.fsal_valid = false;
                    self.h = 0.25 * h;
                    if self.h < min_h {
                        return Err(OdeError::StepTooSmall { t });
                    }
                }
                Some(err) if err <= 1.0 => {
                    // PI step control (Hairer & Wanner's DOPRI5: exponents 0.2 − 0.75β and β,
                    // β = 0.04), which damps the accept/reject oscillation of the plain rule.
                    let err_c = err.max(1e-10);
                    let fac = (0.9 * err_c.powf(-0.17) * self.err_old.powf(0.04)).clamp(0.2, 10.0);
                    self.err_old = err_c;
                    self.last_error = err;
                    self.accept(t, y, h);
                    self.h = h * fac;
                    return Ok(if last { t_end } else { t + h });
                }
                Some(err) => {
                    self.rejected += 1;
                    let fac = if err.is_finite() {
                        (0.9 * err.powf(-0.17)).clamp(0.1, 0.9)
                    } else {
                        0.1
                    };
                    self.h = h * fac;
                    if self.h < min_h {
                        return Err(OdeError::StepTooSmall { t });
                    }
                }
            }
        }
    }

    /// Start time and size (s) of the last accepted step.
    #[must_use]
    pub fn last_step(&self) -> (f64, f64) {
        (self.t_old, self.h_old)
    }

    /// Dense output of component `i` at θ = (t − t_old)/h_old ∈ [0, 1].
    #[must_use]
    pub fn dense(&self, i: usize, theta: f64) -> f64 {
        let r = &self.rcont;
        let t1 = 1.0 - theta;
        r[0][i] + theta * (r[1][i] + t1 * (r[2][i] + theta * (r[3][i] + t1 * r[4][i])))
    }

    /// Dense output of the whole state at time t within the last step.
    pub fn dense_state(&self, t: f64, out: &mut [f64]) {
        let theta = if self.h_old == 0.0 {
            0.0
        } else {
            (t - self.t_old) / self.h_old
        };
        for (i, o) in out.iter_mut().enumerate() {
            *o = self.dense(i, theta);
        }
    }

    /// The dense output of the linear functional Σ aⱼ·y_{idxⱼ} over the last step, as the five
    /// coefficients of [`Dopri5::eval_functional`].
    #[must_use]
    pub fn functional(&self, terms: &[(usize, f64)]) -> [f64; 5] {
        let mut out = [0.0; 5];
        for &(i, a) in terms {
            for (k, o) in out.iter_mut().enumerate() {
                *o += a * self.rcont[k][i];
            }
        }
        out
    }

    /// Value at θ of a functional's dense output (coefficients from [`Dopri5::functional`]).
    #[must_use]
    pub fn eval_functional(c: &[f64; 5], theta: f64) -> f64 {
        let t1 = 1.0 - theta;
        c[0] + theta * (c[1] + t1 * (c[2] + theta * (c[3] + t1 * c[4])))
    }
}

/// Roots of a scalar function g on [0, 1] where it changes sign in the requested direction
/// (`dir` > 0 upward, < 0 downward, 0 either), the first only when `first_only`.
///
/// The interval is split into `sub` pieces; in each piece with a sign change the root is found
/// by the Illinois variant of regula falsi to 1e-15 in θ.
pub fn find_roots(
    g: impl Fn(f64) -> f64,
    g0: f64,
    g1: f64,
    dir: i8,
    sub: usize,
    first_only: bool,
) -> Vec<f64> {
    let mut roots = Vec::new();
    let mut a = 0.0;
    let mut ga = g0;
    for s in 1..=sub {
        let b = s as f64 / sub as f64;
        let gb = if s == sub { g1 } else { g(b) };
        let up = ga < 0.0 && gb >= 0.0;
        let down = ga > 0.0 && gb <= 0.0;
        if (up && dir >= 0) || (down && dir <= 0) {
            roots.push(illinois(&g, a, ga, b, gb));
            if first_only {
                return roots;
            }
        }
        a = b;
        ga = gb;
    }
    roots
}

fn illinois(g: &impl Fn(f64) -> f64, mut a: f64, mut ga: f64, mut b: f64, mut gb: f64) -> f64 {
    if gb == 0.0 {
        return b;
    }
    let mut side = 0;
    for _ in 0..200 {
        if (b - a).abs() <= 1e-15 {
            break;
        }
        let mut c = (a * gb - b * ga) / (gb - ga);
        if !(c > a.min(b) && c < a.max(b)) {
            c = 0.5 * (a + b);
        }
        let gc = g(c);
        if gc == 0.0 {
            return c;
        }
        if (gc > 0.0) == (gb > 0.0) {
            b = c;
            gb = gc;
            if side == 1 {
                ga *= 0.5;
            }
            side = 1;
        } else {
            a = c;
            ga = gc;
            if side == -1 {
                gb *= 0.5;
            }
            side = -1;
        }
    }
    0.5 * (a + b)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// y″ = −ω²y − 2ζω y′ as a first-order system.
    struct Osc {
        w: f64,
        z: f64,
    }
    impl OdeSystem for Osc {
        fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) -> bool {
            dy[0] = y[1];
            dy[1] = -self.w * self.w * y[0] - 2.0 * self.z * self.w * y[1];
            true
        }
    }

    fn exact(t: f64, w: f64) -> (f64, f64) {
        ((w * t).cos(), -w * (w * t).sin())
    }

    /// Fixed-step global error falls as h⁵ (order 5 of the propagated solution).
    #[test]
    fn convergence_order_is_five() {
        let sys = Osc { w: 1.0, z: 0.0 };
        let mut errs = Vec::new();
        for n in [20usize, 40, 80, 160] {
            let h = 10.0 / n as f64;
            let mut st = Dopri5::new(1.0, vec![1.0; 2], h);
            let mut y = [1.0, 0.0];
            for k in 0..n {
                st.fixed_step(&sys, k as f64 * h, &mut y, h).unwrap();
            }
            let (e0, _) = exact(10.0, 1.0);
            errs.push((y[0] - e0).abs());
        }
        for w in errs.windows(2) {
            let order = (w[0] / w[1]).log2();
            assert!((order - 5.0).abs() < 0.3, "order {order}, errs {errs:?}");
        }
    }

    /// Dense output: local error O(h⁵) at mid-step, i.e. order 4 interpolation.
    #[test]
    fn dense_output_order() {
        let sys = Osc { w: 1.0, z: 0.0 };
        let mut e = Vec::new();
        for h in [0.4, 0.2, 0.1] {
            let mut st = Dopri5::new(1.0, vec![1.0; 2], h);
            let mut y = [1.0, 0.0];
            st.fixed_step(&sys, 0.0, &mut y, h).unwrap();
            let mut out = [0.0; 2];
            st.dense_state(0.37 * h, &mut out);
            e.push((out[0] - (0.37 * h).cos()).abs());
        }
        for w in e.windows(2) {
            let order = (w[0] / w[1]).log2();
            assert!(order > 4.6, "local order {order}: {e:?}");
        }
    }

    /// Adaptive run of a damped oscillator against its closed form; error tracks the tolerance.
    #[test]
    fn adaptive_linear_oscillator() {
        let (w, z) = (50.0, 0.05);
        let sys = Osc { w, z };
        let wd = w * (1.0 - z * z).sqrt();
        let exact = |t: f64| (-z * w * t).exp() * ((wd * t).cos() + z * w / wd * (wd * t).sin());
        let mut last = f64::INFINITY;
        for tol in [1e-4, 1e-7, 1e-10] {
            let mut st = Dopri5::new(tol, vec![tol; 2], 1e-3);
            let mut y = [1.0, 0.0];
            let mut t = 0.0;
            let mut maxerr: f64 = 0.0;
            while t < 2.0 {
                t = st.step(&sys, t, &mut y, 2.0).unwrap();
                maxerr = maxerr.max((y[0] - exact(t)).abs());
                let (t0, h) = st.last_step();
                let mut out = [0.0; 2];
                st.dense_state(t0 + 0.5 * h, &mut out);
                maxerr = maxerr.max((out[0] - exact(t0 + 0.5 * h)).abs());
            }
            assert!(maxerr < 200.0 * tol, "tol {tol}: err {maxerr}");
            assert!(maxerr < last);
            last = maxerr;
            assert!((t - 2.0).abs() < 1e-15);
        }
    }

    #[test]
    fn roots_are_found_in_direction() {
        let g = |x: f64| (x * 10.0).sin();
        let r = find_roots(g, g(0.0 + 1e-9), g(1.0), 0, 8, false);
        assert_eq!(r.len(), 3);
        for (k, x) in r.iter().enumerate() {
            assert!((x - (k + 1) as f64 * std::f64::consts::PI / 10.0).abs() < 1e-14);
        }
        let down = find_roots(g, g(1e-9), g(1.0), -1, 8, false);
        assert_eq!(down.len(), 2);
        let first = find_roots(g, g(1e-9), g(1.0), 1, 8, true);
        assert_eq!(first.len(), 1);
        assert!((first[0] - 2.0 * std::f64::consts::PI / 10.0).abs() < 1e-14);
    }
}
