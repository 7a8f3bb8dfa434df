//! Globally adaptive Gauss–Kronrod quadrature (7-point Gauss, 15-point Kronrod) on a finite
//! interval with user breakpoints, in the manner of QUADPACK's QAGP without extrapolation.
//!
//! The interval with the largest error estimate is bisected until the summed estimate is below
//! max(abs_tol, rel_tol·|I|), or the interval budget is spent. The integrand is never evaluated
//! at an interval's end points, so integrable end-point singularities are allowed.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use crate::physics::control::Control;
use crate::physics::error::PhysicsResult;

/// Kronrod abscissae on [−1, 1] (non-negative half, descending); the odd-indexed ones are the
/// 7-point Gauss nodes. Values from QUADPACK `qk15` (Piessens et al. 1983).
#[allow(clippy::excessive_precision)] // published digits kept as printed
const XGK: [f64; 8] = [
    0.991_455_371_120_812_639_206_854_697_526_329,
    0.949_107_912_342_758_524_526_189_684_047_851,
    0.864_864_423_359_769_072_789_712_788_640_926,
    0.741_531_185_599_394_439_863_864_773_280_788,
    0.586_087_235_467_691_130_294_144_845_693_013,
    0.405_845_151_377_397_166_906_606_412_076_961,
    0.207_784_955_007_898_467_600_689_403_773_245,
    0.0,
];
/// Kronrod weights matching [`XGK`] (QUADPACK `qk15`).
#[allow(clippy::excessive_precision)] // published digits kept as printed
const WGK: [f64; 8] = [
    0.022_935_322_010_529_224_963_732_008_058_970,
    0.063_092_092_629_978_553_290_700_663_189_204,
    0.104_790_010_322_250_183_839_876_322_541_518,
    0.140_653_259_715_525_918_745_189_590_510_238,
    0.169_004_726_639_267_902_826_583_426_598_550,
    0.190_350_578_064_785_409_913_256_402_421_014,
    0.204_432_940_075_298_892_414_161_999_234_649,
    0.209_482_141_084_727_828_012_999_174_891_714,
];
/// 7-point Gauss weights for XGK[1], XGK[3], XGK[5] and the centre (QUADPACK `qk15`).
#[allow(clippy::excessive_precision)] // published digits kept as printed
const WG: [f64; 4] = [
    0.129_484_966_168_869_693_270_611_432_679_082,
    0.279_705_391_489_276_667_901_467_771_423_780,
    0.381_830_050_505_118_944_950_369_775_488_975,
    0.417_959_183_673_469_387_755_102_040_816_327,
];

/// Stopping rule of [`integrate`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QuadOptions {
    /// Absolute error goal, in the integral's unit (default 0).
    pub abs_tol: f64,
    /// Relative error goal (default 1e-10).
    pub rel_tol: f64,
    /// Largest number of subintervals (default 2000).
    pub max_intervals: usize,
}

impl Default for QuadOptions {
    fn default() -> Self {
        Self {
            abs_tol: 0.0,
            rel_tol: 1e-10,
            max_intervals: 2000,
        }
    }
}

/// Outcome of [`integrate`]: the value, its error estimate and the work done.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Integral {
    /// The integral, in the integrand's unit times the variable's.
    pub value: f64,
    /// Estimated absolute error (QUADPACK's Kronrod–Gauss estimate), same unit as `value`.
    pub error: f64,
    /// Number of integrand evaluations.
    pub evaluations: usize,
    /// Number of subintervals at the end.
    pub intervals: usize,
    /// True when the error goal was met.
    pub converged: bool,
}

#[derive(Debug, Clone, Copy)]
struct Segment {
    a: f64,
    b: f64,
    value: f64,
    error: f64,
}

impl PartialEq for Segment {
    fn eq(&self, other: &Self) -> bool {
        self.error.total_cmp(&other.error) == Ordering::Equal
    }
}
impl Eq for Segment {}
impl PartialOrd for Segment {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Segment {
    fn cmp(&self, other: &Self) -> Ordering {
        self.error.total_cmp(&other.error)
    }
}

/// One 15-point Kronrod rule on [a, b] with QUADPACK's error estimate: (value, error).
///
/// # Special cases
/// * A non-finite integrand value propagates into value and error (the caller sees it).
///
/// # References
/// Piessens, de Doncker-Kapenga, Überhuber, Kahaner, *QUADPACK* (Springer 1983), routine `qk15`.
pub fn kronrod15<F: FnMut(f64) -> f64>(f: &mut F, a: f64, b: f64) -> (f64, f64) {
    let centre = 0.5 * (a + b);
    let half = 0.5 * (b - a);
    let fc = f(centre);
    let mut resg = fc * WG[3];
    let mut resk = fc * WGK[7];
    let mut resabs = resk.abs();
    let mut fv1 = [0.0; 7];
    let mut fv2 = [0.0; 7];
    for j in 0..7 {
        let dx = half * XGK[j];
        let f1 = f(centre - dx);
        let f2 = f(centre + dx);
        fv1[j] = f1;
        fv2[j] = f2;
        resk += WGK[j] * (f1 + f2);
        resabs += WGK[j] * (f1.abs() + f2.abs());
        if j % 2 == 1 {
            resg += WG[j / 2] * (f1 + f2);
        }
    }
    let reskh = 0.5 * resk;
    let mut resasc = WGK[7] * (fc - reskh).abs();
    for j in 0..7 {
        resasc += WGK[j] * ((fv1[j] - reskh).abs() + (fv2[j] - reskh).abs());
    }
    let value = resk * half;
    let resabs = resabs * half.abs();
    let resasc = resasc * half.abs();
    let mut err = ((resk - resg) * half).abs();
    if resasc != 0.0 && err != 0.0 {
        err = resasc * (200.0 * err / resasc).powf(1.5).min(1.0);
    }
    if resabs > f64::MIN_POSITIVE / (50.0 * f64::EPSILON) {
        err = err.max(50.0 * f64::EPSILON * resabs);
    }
    (value, err)
}

/// ∫ f over `[points[0], points[last]]`, with the inner points as breakpoints;
/// the result is in the integrand's unit times the variable's.
///
/// # Examples
/// ```
/// use gangue::physics::numeric::quadrature::{integrate, QuadOptions};
/// // ∫₀¹ ln(1/x) dx = 1, an end-point singularity.
/// let r = integrate(|x: f64| -x.ln(), &[0.0, 1e-3, 1.0], QuadOptions::default());
/// assert!(r.converged && (r.value - 1.0).abs() < 1e-10);
/// ```
///
/// # Special cases
/// * Fewer than two points, or equal end points: value 0, converged.
/// * Points must be non-decreasing; zero-length pieces are skipped.
/// * The budget `max_intervals` spent: `converged = false`, best estimate returned.
///
/// # References
/// QUADPACK `qagp` (global adaptive bisection by largest error), without the ε-extrapolation.
pub fn integrate<F: FnMut(f64) -> f64>(f: F, points: &[f64], options: QuadOptions) -> Integral {
    match integrate_inner(f, points, options, None) {
        Ok(r) => r,
        Err(_) => unreachable!("no control handle, no cancellation"),
    }
}

/// [`integrate`] that polls `control` every 64 bisections and stops with its error.
///
/// # Errors
/// `Cancelled` or `TimedOut` from [`Control::check`].
///
/// # References
/// As [`integrate`].
pub fn integrate_with_control<F: FnMut(f64) -> f64>(
    f: F,
    points: &[f64],
    options: QuadOptions,
    control: &Control,
) -> PhysicsResult<Integral> {
    integrate_inner(f, points, options, Some(control))
}

fn integrate_inner<F: FnMut(f64) -> f64>(
    mut f: F,
    points: &[f64],
    options: QuadOptions,
    control: Option<&Control>,
) -> PhysicsResult<Integral> {
    let mut heap = BinaryHeap::new();
    let mut evaluations = 0;
    let mut total = 0.0;
    let mut total_err = 0.0;
    for w in points.windows(2) {
        let (a, b) = (w[0], w[1]);
        if b == a {
            continue;
        }
        let (value, error) = kronrod15(&mut f, a, b);
        evaluations += 15;
        total += value;
        total_err += error;
        heap.push(Segment { a, b, value, error });
    }
    let goal = |total: f64| options.abs_tol.max(options.rel_tol * total.abs());
    let max_intervals = options.max_intervals.max(heap.len());
    let mut bisections = 0usize;
    while total_err > goal(total) && heap.len() < max_intervals {
        let Some(seg) = heap.pop() else { break };
        let mid = 0.5 * (seg.a + seg.b);
        if !(mid > seg.a && mid < seg.b && seg.error.is_finite()) {
            // Cannot be refined (interval at f64 resolution, or a non-finite integrand).
            heap.push(seg);
            break;
        }
        let (v1, e1) = kronrod15(&mut f, seg.a, mid);
        let (v2, e2) = kronrod15(&mut f, mid, seg.b);
        evaluations += 30;
        total += v1 + v2 - seg.value;
        total_err += e1 + e2 - seg.error;
        heap.push(Segment {
            a: seg.a,
            b: mid,
            value: v1,
            error: e1,
        });
        heap.push(Segment {
            a: mid,
            b: seg.b,
            value: v2,
            error: e2,
        });
        bisections += 1;
        if bisections.is_multiple_of(64) {
            // Re-sum to keep the running totals free of drift.
            total = heap.iter().map(|s| s.value).sum();
            total_err = heap.iter().map(|s| s.error).sum();
            if let Some(c) = control {
                c.check()?;
            }
        }
    }
    let mut segs: Vec<Segment> = heap.into_vec();
    segs.sort_by(|x, y| x.a.total_cmp(&y.a));
    let value: f64 = segs.iter().map(|s| s.value).sum();
    let error: f64 = segs.iter().map(|s| s.error).sum();
    Ok(Integral {
        value,
        error,
        evaluations,
        intervals: segs.len(),
        converged: error <= goal(value),
    })
}

/// The `n` Gauss–Legendre nodes and weights (x, w) on [−1, 1], by Newton on the Legendre
/// recurrence (exact for polynomials of degree ≤ 2n − 1).
#[must_use]
pub fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    let mut out = Vec::with_capacity(n);
    for i in 1..=n {
        let mut x = (std::f64::consts::PI * (i as f64 - 0.25) / (n as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, x);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
            let dx = p1 / dp;
            x -= dx;
            if dx.abs() < 1e-16 {
                break;
            }
        }
        out.push((x, 2.0 / ((1.0 - x * x) * dp * dp)));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kronrod_is_exact_for_degree_22_and_gauss_for_13() {
        // ∫_{-1}^{1} x^n dx = 2/(n+1) for even n.
        for n in (0..=22).step_by(2) {
            let (v, _) = kronrod15(&mut |x: f64| x.powi(n), -1.0, 1.0);
            let exact = 2.0 / (n as f64 + 1.0);
            assert!((v - exact).abs() < 4e-16, "K15 n = {n}: {v} vs {exact}");
        }
        // The Gauss part alone, recovered from the weights: exact to degree 13.
        for n in (0..=12).step_by(2) {
            let mut g = WG[3] * if n == 0 { 1.0 } else { 0.0 };
            for j in [1usize, 3, 5] {
                g += 2.0 * WG[j / 2] * XGK[j].powi(n);
            }
            let exact = 2.0 / (n as f64 + 1.0);
            assert!((g - exact).abs() < 4e-16, "G7 n = {n}");
        }
        // Degree 24 is not integrated exactly: the rule is not trivially "exact".
        let (v, _) = kronrod15(&mut |x: f64| x.powi(24), -1.0, 1.0);
        assert!((v - 2.0 / 25.0).abs() > 1e-12);
    }

    #[test]
    fn smooth_integrands_to_tolerance() {
        let opts = QuadOptions {
            rel_tol: 1e-13,
            ..Default::default()
        };
        let r = integrate(f64::sin, &[0.0, std::f64::consts::PI], opts);
        assert!((r.value - 2.0).abs() < 1e-13 && r.converged);
        let r = integrate(|x: f64| (-x * x).exp(), &[-10.0, 0.0, 10.0], opts);
        assert!((r.value - std::f64::consts::PI.sqrt()).abs() < 1e-13);
    }

    #[test]
    fn end_point_singularities() {
        let opts = QuadOptions {
            rel_tol: 1e-12,
            ..Default::default()
        };
        // ∫₀¹ x^{-1/2} dx = 2.
        let r = integrate(|x: f64| 1.0 / x.sqrt(), &[0.0, 1.0], opts);
        assert!((r.value - 2.0).abs() < 1e-11, "{r:?}");
        // ∫₀¹ √(ln(1/x)) dx = Γ(3/2) = √π/2.
        let r = integrate(
            |x: f64| (-x.ln()).sqrt(),
            &[0.0, 1e-6, 1e-3, 0.1, 1.0],
            opts,
        );
        assert!(
            (r.value - std::f64::consts::PI.sqrt() / 2.0).abs() < 1e-11,
            "{r:?}"
        );
        assert!(r.error < 1e-11 && r.converged);
    }

    #[test]
    fn budget_exhaustion_is_reported() {
        let opts = QuadOptions {
            rel_tol: 1e-15,
            abs_tol: 0.0,
            max_intervals: 3,
        };
        let r = integrate(|x: f64| (1.0 / x).sin(), &[1e-6, 1.0], opts);
        assert!(!r.converged && r.intervals <= 3 && r.value.is_finite());
    }

    #[test]
    fn cancelled_control_stops() {
        let c = Control::unlimited();
        c.cancel();
        let opts = QuadOptions {
            rel_tol: 1e-15,
            abs_tol: 0.0,
            max_intervals: 100_000,
        };
        let r = integrate_with_control(|x: f64| (1.0 / x).sin(), &[1e-9, 1.0], opts, &c);
        assert!(r.is_err());
    }

    #[test]
    fn gauss_legendre_integrates_polynomials_exactly() {
        // 20 points: exact up to degree 39; ∫₋₁¹ x³⁸ dx = 2/39, weights sum to 2.
        let nodes = gauss_legendre(20);
        let sum: f64 = nodes.iter().map(|&(_, w)| w).sum();
        assert!((sum - 2.0).abs() < 1e-14);
        let x38: f64 = nodes.iter().map(|&(x, w)| w * x.powi(38)).sum();
        assert!((x38 / (2.0 / 39.0) - 1.0).abs() < 1e-13, "{x38}");
        let odd: f64 = nodes.iter().map(|&(x, w)| w * x.powi(37)).sum();
        assert!(odd.abs() < 1e-15);
    }
}
