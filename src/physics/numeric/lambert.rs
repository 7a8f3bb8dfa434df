//! The lower Lambert W branch near its branch point, in the well-conditioned variable u.
//!
//! With W = W₋₁(−G/e) and u = −(1 + W) ≥ 0, the defining equation becomes (1 + u)e^{−u} = G.
//! Working in u (never in z = −G/e) keeps every digit near the branch point G → 1, where
//! 1 + e·z cancels catastrophically (physics.md §A.5).

/// u ≥ 0 solving (1 + u)·e^{−u} = G for G ∈ [0, 1]; `None` for G > 1 or NaN.
///
/// G = 1 gives u = 0 (the branch point, W = −1); G = 0 gives u = +∞.
///
/// # Examples
/// ```
/// let u = gangue::physics::numeric::lambert::branch_u(0.5).unwrap();
/// assert!(((1.0 + u) * (-u).exp() - 0.5).abs() < 1e-15);
/// ```
///
/// # Special cases
/// * `G > 1` or NaN: `None` (no real solution on the physical branch).
/// * `G == 1`: `Some(0.0)`.
/// * `G == 0`: `Some(f64::INFINITY)`.
/// * `1 − G < 1e-12`: the branch-point series alone (u ≈ √(2(1−G)) …), relative error ≲ 1e-16.
/// * Elsewhere one Halley step (a second only as a safeguard) from a starting value good to
///   3e-7: the branch-point series, a series in √(2y), a Chebyshev fit or the asymptotic series.
///
/// # References
/// physics.md §A.5 (series: the standard branch-point expansion of W₋₁, Corless et al. 1996,
/// "On the Lambert W function", Adv. Comput. Math. 5, 329–359, doi:10.1007/BF02124750).
#[must_use]
pub fn branch_u(g: f64) -> Option<f64> {
    if !(0.0..=1.0).contains(&g) {
        return None;
    }
    if g == 1.0 {
        return Some(0.0);
    }
    if g == 0.0 {
        return Some(f64::INFINITY);
    }
    Some(branch_u_parts(1.0 - g, -g.ln()))
}

/// u ≥ 0 solving u − ln(1 + u) = y, i.e. (1 + u)e^{−u} = G with y = −ln G ≥ 0 given directly.
///
/// Use this when G itself underflows (G < 1e-308 needs y > 709): δ, P and the contact duration
/// stay finite and correct because they depend on G only through u.
///
/// # Examples
/// ```
/// // G = e^{-2000} is not representable, its logarithm is.
/// let u = gangue::physics::numeric::lambert::branch_u_log(2000.0).unwrap();
/// assert!((u - u.ln_1p() - 2000.0).abs() < 1e-12);
/// ```
///
/// # Special cases
/// * `y < 0` or NaN: `None` (G > 1).
/// * `y == 0`: `Some(0.0)` (the branch point); `y == +∞`: `Some(+∞)`.
///
/// # References
/// physics.md §A.5.
#[must_use]
pub fn branch_u_log(y: f64) -> Option<f64> {
    if y.is_nan() || y < 0.0 {
        return None;
    }
    if y == 0.0 {
        return Some(0.0);
    }
    if y == f64::INFINITY {
        return Some(f64::INFINITY);
    }
    Some(branch_u_parts(-(-y).exp_m1(), y))
}

/// Core of [`branch_u`]: u from q = 1 − G and y = −ln G, both given (q is used only near the
/// branch point, where it must be accurate). Requires 0 < q ≤ 1 and 0 < y < ∞, consistent.
///
/// # Special cases
/// * `q < 1e-12`: the branch-point series alone.
///
/// # References
/// physics.md §A.5.
#[must_use]
pub fn branch_u_parts(q: f64, y: f64) -> f64 {
    let mut u = if q < 2e-3 {
        let s = (2.0 * q).sqrt();
        let series = s
            * (1.0
                + s * (1.0 / 3.0
                    + s * (11.0 / 72.0
                        + s * (43.0 / 540.0
                            + s * (769.0 / 17280.0
                                + s * (221.0 / 8505.0
                                    + s * (680863.0 / 43545600.0 + s * (1963.0 / 204120.0))))))));
        if q < 1e-12 {
            return series;
        }
        series
    } else {
        initial_u(y)
    };
    // Halley on f(u) = u − ln(1 + u) − y: f' = u/(1 + u), f'' = 1/(1 + u)². Cubic convergence:
    // once a step is below 1e-6·u the next error is below 1e-16·u, so that step is the last.
    for _ in 0..50 {
        let f = u_minus_ln1p(u) - y;
        let u2 = 2.0 * u * u;
        // Halley's step 2ff′/(2f′² − ff″) = 2f·u(1 + u)/(2u² − f), one division, while the
        // correction factor 1/(1 − f/(2u²)) stays in [0.5, 2]; else the clamped form.
        let mut next = if f.abs() <= 0.5 * u2 {
            u - 2.0 * f * u * (1.0 + u) / (u2 - f)
        } else {
            u - f * (1.0 + u) / u / (1.0 - f / u2).clamp(0.5, 2.0)
        };
        if next <= 0.0 {
            next = 0.5 * u;
        }
        let du = (next - u).abs();
        u = next;
        if du <= 1e-6 * u {
            break;
        }
    }
    u
}

/// u on s = √(2y) ∈ [1, √60] (y ∈ [0.5, 30]) as a polynomial in x = (2s − 1 − √60)/(√60 − 1):
/// a 10-node Chebyshev fit to 30-digit roots (relative error ≤ 2.5e-8), converted to powers
/// of x for Estrin's scheme.
#[allow(clippy::excessive_precision)] // fitted digits kept as computed
const U_POLY: [f64; 10] = [
    12.136918094045562,
    15.9653002614115,
    5.357881166634381,
    0.1111145015966909,
    -0.039434742785393335,
    0.014050652180935241,
    -0.0048766481903520275,
    0.001660597051693102,
    -0.0005589232114616039,
    0.00012629377681179222,
];

/// A starting value for u(y) with relative error ≤ 3e-7, so that one Halley step reaches full
/// precision (its error is about (1 + 1/(u(1 + u)))·e³ for a relative error e).
///
/// * y ≤ 0.5: the series of the inverse of u − ln(1 + u) = s²/2 in s = √(2y), 8 terms
///   (1, 1/3, 1/36, −1/270, 1/4320, 1/17010, −139/5443200, 1/204120).
/// * y ≤ 30: [`U_POLY`].
/// * Beyond: the asymptotic series of −W₋₁ in a = 1 + y, L = ln a (de Bruijn), to 1/a³.
fn initial_u(y: f64) -> f64 {
    if y <= 0.5 {
        let s = (2.0 * y).sqrt();
        s * (1.0
            + s * (1.0 / 3.0
                + s * (1.0 / 36.0
                    + s * (-1.0 / 270.0
                        + s * (1.0 / 4320.0
                            + s * (1.0 / 17010.0
                                + s * (-139.0 / 5443200.0 + s * (1.0 / 204120.0))))))))
    } else if y <= 30.0 {
        // x = (2s − (1 + √60))/(√60 − 1), by multiplications.
        let x = (2.0 * y).sqrt() * 0.296_473_447_200_502_84 - 1.296_473_447_200_502_8;
        let c = &U_POLY;
        let x2 = x * x;
        let x4 = x2 * x2;
        let p01 = c[0] + c[1] * x;
        let p23 = c[2] + c[3] * x;
        let p45 = c[4] + c[5] * x;
        let p67 = c[6] + c[7] * x;
        let p89 = c[8] + c[9] * x;
        (p01 + p23 * x2) + x4 * ((p45 + p67 * x2) + x4 * p89)
    } else {
        let a = 1.0 + y;
        let l = a.ln();
        let r = 1.0 / a;
        y + l + l * r * (1.0 + r * (0.5 * (2.0 - l) + r * ((2.0 * l * l - 9.0 * l + 6.0) / 6.0)))
    }
}

/// u and e^{−u/4} for G < 0.5 given 1/G and y = −ln G, without a logarithm in the iteration.
///
/// Halley steps as in [`branch_u_parts`], with f = −ln R, R = (1 + u)e^{−u}/G formed from
/// e^{−u/4} (R − 1 is O(1e-5) from the starting value, so ln R is a short series), and
/// e^{−u/4} carried along by its Taylor factor. Falls back to [`branch_u_parts`] and one exp.
pub(crate) fn branch_u_far(inv_g: f64, y: f64) -> (f64, f64) {
    let mut u = initial_u(y);
    let mut e4 = (-0.25 * u).exp();
    for _ in 0..4 {
        let e2 = e4 * e4;
        let r = (1.0 + u) * (e2 * e2) * inv_g - 1.0;
        if r.abs() > 1e-4 {
            break;
        }
        let f = -(r * (1.0 - r * (0.5 - r * (1.0 / 3.0 - 0.25 * r))));
        let u2 = 2.0 * u * u;
        let du = -2.0 * f * u * (1.0 + u) / (u2 - f);
        let q = 0.25 * du;
        e4 *= 1.0 - q * (1.0 - q * (0.5 - q / 6.0));
        u += du;
        if du.abs() <= 1e-6 * u {
            return (u, e4);
        }
    }
    let u = branch_u_parts(1.0 - 1.0 / inv_g, y);
    (u, (-0.25 * u).exp())
}

/// y = −ln G = u − ln(1 + u) for u ≥ 0 (the inverse of [`branch_u_log`]), without
/// cancellation at small u.
///
/// # Examples
/// ```
/// let y = gangue::physics::numeric::lambert::u_minus_ln1p(1e-8);
/// assert!((y / 5e-17 - 1.0).abs() < 1e-7); // u²/2 − u³/3 …
/// ```
///
/// # Special cases
/// * `u == 0`: 0; `u == +∞`: +∞.
///
/// # References
/// Below u = 0.25 it uses ln(1 + u) = 2 atanh(w), w = u/(2 + u), so that
/// u − ln(1 + u) = u²/(2 + u) − 2(w³/3 + w⁵/5 + …), a sum without cancellation.
#[must_use]
pub fn u_minus_ln1p(u: f64) -> f64 {
    if u < 0.25 {
        let w = u / (2.0 + u);
        let w2 = w * w;
        // 2 Σ_{j≥1} w^{2j+1}/(2j+1): w² ≤ 0.0124, 9 terms reach 1e-17 relative.
        let mut tail = 0.0;
        for j in (1..=9).rev() {
            tail = w2 * (1.0 / (2 * j + 1) as f64 + tail);
        }
        u * u / (2.0 + u) - 2.0 * w * tail
    } else if u.is_finite() {
        u - u.ln_1p()
    } else {
        u
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn satisfies_defining_equation_over_decades() {
        for k in 1..300 {
            let g = 10f64.powf(-(k as f64));
            let u = branch_u(g).unwrap();
            // (1+u)e^{-u} = G  ⇔  u − ln(1+u) = −ln G
            let lhs = u - u.ln_1p();
            let rhs = -g.ln();
            assert!((lhs - rhs).abs() <= 1e-14 * rhs.abs().max(1.0), "G = {g}");
        }
    }

    #[test]
    fn branch_point_and_outside() {
        assert_eq!(branch_u(1.0), Some(0.0));
        assert_eq!(branch_u(0.0), Some(f64::INFINITY));
        assert_eq!(branch_u(1.0 + f64::EPSILON), None);
        assert_eq!(branch_u(f64::NAN), None);
        assert_eq!(branch_u(-1e-300), None);
    }

    #[test]
    fn near_branch_point_matches_series_leading_term() {
        let g = 1.0 - 1e-10;
        let q = 1.0 - g;
        let u = branch_u(g).unwrap();
        let s = (2.0 * q).sqrt();
        assert!((u / s - 1.0 - s / 3.0).abs() < 1e-9);
    }

    /// The starting values are good to 3e-7 over a dense grid of y, across the joints of the
    /// series, the Chebyshev fit and the asymptotic series, so one Halley step suffices; the
    /// result satisfies the defining equation to rounding.
    #[test]
    fn starting_values_and_one_step_accuracy() {
        let mut ys: Vec<f64> = (0..=4000)
            .map(|i| 10f64.powf(-3.0 + 9.0 * i as f64 / 4000.0))
            .collect();
        for joint in [0.5, 30.0] {
            ys.extend((-50..=50).map(|i| joint * (1.0 + i as f64 * 1e-12)));
        }
        let mut worst_guess = 0.0f64;
        let mut worst_residual = 0.0f64;
        for &y in &ys {
            let u = branch_u_log(y).unwrap();
            worst_guess = worst_guess.max((initial_u(y) / u - 1.0).abs());
            // |Δy| from rounding u: ulp(u)·f′(u) = ulp(u)·u/(1 + u).
            let residual = (u_minus_ln1p(u) - y).abs() / (y + u * u / (1.0 + u));
            worst_residual = worst_residual.max(residual);
        }
        assert!(worst_guess <= 3e-7, "{worst_guess:e}");
        assert!(worst_residual <= 1e-15, "{worst_residual:e}");
    }

    /// The logarithm-free iteration for G < 0.5 agrees with [`branch_u_parts`] to a few ulp of
    /// 1 + u and carries e^{−u/4} to rounding.
    #[test]
    fn far_iteration_matches() {
        let mut worst = (0.0f64, 0.0f64);
        for i in 0..=5000 {
            let g = 0.5 * 10f64.powf(-250.0 * (i as f64 / 5000.0).powi(2)) * (1.0 - 1e-12);
            let y = -g.ln();
            let (u, e4) = branch_u_far(1.0 / g, y);
            let reference = branch_u_parts(1.0 - g, y);
            worst.0 = worst
                .0
                .max((u - reference).abs() / (1.0 + reference) / f64::EPSILON);
            // exp(−u/4) of the rounded u is itself off by ~ulp(u)/4 relative.
            let scale = (4.0 + 0.5 * u) * f64::EPSILON;
            worst.1 = worst.1.max((e4 / (-0.25 * u).exp() - 1.0).abs() / scale);
        }
        assert!(worst.0 <= 8.0 && worst.1 <= 1.0, "{worst:?}");
    }
}
