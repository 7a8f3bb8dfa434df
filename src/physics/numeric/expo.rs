//! The matrix exponential and the φ-functions of a linear operator acting on one fixed vector,
//! for exponential integrators of y′ = Ly + b·p(t) (Hochbruck & Ostermann, *Exponential
//! integrators*, Acta Numerica 19, 2010, §2).
//!
//! φ₀(z) = eᶻ, φₖ₊₁(z) = (φₖ(z) − 1/k!)/z, so that ∫₀^τ e^{(τ−s)L} b·(s^{k−1}/(k−1)!) ds =
//! τᵏ φₖ(τL) b. All four come from one exponential of the augmented matrix
//! [[τL, b, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1], [0, 0, 0, 0]] (Saad 1992; Al-Mohy & Higham 2011,
//! Theorem 2.1): its first block row is [e^{τL}, φ₁(τL)b, φ₂(τL)b, φ₃(τL)b]. No difference
//! 1 − e^{−x} or (φₖ − 1/k!)/z is ever formed, so heavily damped (τ·rate ≫ 1) and nearly static
//! (τ‖L‖ ≪ 1) operators lose no digits to cancellation; the exponential is nalgebra's scaling and
//! squaring Padé approximant, whose squarings only multiply decaying or bounded factors here.
//!
//! The operator is balanced by a diagonal similarity S⁻¹LS (`scale`) before the exponential, so
//! that states whose components differ by orders of magnitude (displacements and velocities of
//! stiff modes) keep their relative accuracy; the results are transformed back.

use nalgebra::{DMatrix, DVector};

/// e^{τL} and φ₁(τL)b, φ₂(τL)b, φ₃(τL)b of one operator L, one vector b and one span τ.
#[derive(Debug, Clone, PartialEq)]
pub struct PhiAction {
    /// The propagator e^{τL} (dimensionless in the units of the state).
    pub exp: DMatrix<f64>,
    /// φ₁(τL)b, φ₂(τL)b, φ₃(τL)b (units of b).
    pub phi_b: [DVector<f64>; 3],
}

/// e^{τL} and φₖ(τL)b (k = 1, 2, 3) from one exponential of the augmented matrix, with L
/// balanced by the diagonal similarity S = diag(`scale`) (each entry > 0; all ones for none).
///
/// # Panics
/// When `l` is not square or `b`, `scale` do not match its size (programming errors).
#[must_use]
pub fn phi_action(l: &DMatrix<f64>, b: &DVector<f64>, scale: &[f64], tau: f64) -> PhiAction {
    let m = l.nrows();
    assert!(l.ncols() == m && b.len() == m && scale.len() == m);
    let mut aug = DMatrix::zeros(m + 3, m + 3);
    // S⁻¹(τL)S and S⁻¹b: the exponential of the balanced block is S⁻¹e^{τL}S.
    for j in 0..m {
        for i in 0..m {
            aug[(i, j)] = tau * l[(i, j)] * scale[j] / scale[i];
        }
        aug[(j, m)] = b[j] / scale[j];
    }
    aug[(m, m + 1)] = 1.0;
    aug[(m + 1, m + 2)] = 1.0;
    let e = aug.exp();
    let exp = DMatrix::from_fn(m, m, |i, j| e[(i, j)] * scale[i] / scale[j]);
    let col = |k: usize| DVector::from_fn(m, |i, _| e[(i, m + k)] * scale[i]);
    PhiAction {
        exp,
        phi_b: [col(0), col(1), col(2)],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The damped oscillator q̈ + γq̇ + ω²q = f in the state [q, q̇], every regime, against the
    /// same quantities evaluated with mpmath at 50 digits (`expm` of the augmented matrix,
    /// mp.dps = 50; script in the comment below). Relative accuracy 1e-12 of each entry's
    /// scale (the largest entry of its column).
    ///
    /// ```text
    /// from mpmath import mp, matrix, expm
    /// mp.dps = 50
    /// def ref(w, g, tau):
    ///     a = matrix(5, 5); a[0,1] = tau; a[1,0] = -w*w*tau; a[1,1] = -g*tau
    ///     a[1,2] = 1; a[2,3] = 1; a[3,4] = 1
    ///     e = expm(a); return [[e[i, j] for j in range(5)] for i in range(2)]
    /// ```
    #[test]
    #[allow(clippy::excessive_precision)] // the mpmath values as printed, 20 digits
    fn oscillator_phi_functions_match_mpmath() {
        // (ω rad/s, γ 1/s, τ s, expected first two rows of the augmented exponential)
        let cases: [(f64, f64, f64, [[f64; 5]; 2]); 6] = [
            // undamped, ωτ = 3
            (
                3e3,
                0.0,
                1e-3,
                [
                    [
                        -9.8999249660044545727e-1,
                        4.7040002686622407367e-5,
                        2.2111027740004949525e-4,
                        1.0588444414593084363e-4,
                        3.0987746955550056083e-5,
                    ],
                    [
                        -4.233600241796016663e+2,
                        -9.8999249660044545727e-1,
                        4.7040002686622407367e-2,
                        2.2111027740004949525e-1,
                        1.0588444414593084363e-1,
                    ],
                ],
            ),
            // light damping, ζ = 0.01
            (
                2.5e4,
                500.0,
                1e-4,
                [
                    [
                        -7.7545211255194744052e-1,
                        2.3352906975035908653e-5,
                        2.8407233800831159048e-5,
                        1.2036277013587605343e-5,
                        3.3585523757583137095e-6,
                    ],
                    [
                        -1.4595566859397442908e+4,
                        -7.8712856603946539484e-1,
                        2.3352906975035908653e-1,
                        2.8407233800831159048e-1,
                        1.2036277013587605343e-1,
                    ],
                ],
            ),
            // critically damped, γ = 2ω
            (
                1e3,
                2e3,
                2e-3,
                [
                    [
                        4.0600584970983807568e-1,
                        2.7067056647322538379e-4,
                        2.9699707514508096216e-4,
                        1.3533528323661269189e-4,
                        4.0415447977117067566e-5,
                    ],
                    [
                        -2.7067056647322538379e+2,
                        -1.3533528323661269189e-1,
                        1.3533528323661269189e-1,
                        1.4849853757254048108e-1,
                        6.7667641618306345947e-2,
                    ],
                ],
            ),
            // nearly critical, ζ = 1 + 1e-9
            (
                1e3,
                2e3 * (1.0 + 1e-9),
                2e-3,
                [
                    [
                        4.060058500707321641e-1,
                        2.7067056629277833962e-4,
                        2.9699707496463391795e-4,
                        1.3533528316517442218e-4,
                        4.0415447958331815168e-5,
                    ],
                    [
                        -2.7067056629277833962e+2,
                        -1.3533528305616564772e-1,
                        1.3533528314638916981e-1,
                        1.4849853748231695898e-1,
                        6.766764158258721109e-2,
                    ],
                ],
            ),
            // heavily damped column (c = 1e9: rate 2e7 /s, γτ = 2000)
            (
                2.5e4,
                2e7,
                1e-4,
                [
                    [
                        9.968814304947181647e-1,
                        4.9844149406341045841e-8,
                        4.9897112084509364738e-8,
                        2.49490690519887166e-8,
                        8.3143654300891897219e-9,
                    ],
                    [
                        -3.1152593378963153651e+1,
                        -1.5576321027521210574e-6,
                        4.9844149406341045841e-4,
                        4.9897112084509364738e-4,
                        2.49490690519887166e-4,
                    ],
                ],
            ),
            // tiny span, τ‖L‖ = 1e-6
            (
                1e3,
                10.0,
                1e-9,
                [
                    [
                        9.999999999995e-1,
                        9.9999999499983335e-10,
                        4.9999999833329167083e-10,
                        1.666666662499916675e-10,
                        4.1666666583331944583e-11,
                    ],
                    [
                        -9.9999999499983335e-4,
                        9.9999998999950005e-1,
                        9.9999999499983335e-1,
                        4.9999999833329167083e-1,
                        1.666666662499916675e-1,
                    ],
                ],
            ),
        ];
        for (w, g, tau, exp) in cases {
            let l = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, -w * w, -g]);
            let b = DVector::from_column_slice(&[0.0, 1.0]);
            // balanced: displacement scaled by 1/ω
            let pa = phi_action(&l, &b, &[1.0 / w, 1.0], tau);
            let got = [
                [
                    pa.exp[(0, 0)],
                    pa.exp[(0, 1)],
                    pa.phi_b[0][0],
                    pa.phi_b[1][0],
                    pa.phi_b[2][0],
                ],
                [
                    pa.exp[(1, 0)],
                    pa.exp[(1, 1)],
                    pa.phi_b[0][1],
                    pa.phi_b[1][1],
                    pa.phi_b[2][1],
                ],
            ];
            for j in 0..5 {
                // the scale of column j in the balanced sense: |row 0|·ω ~ |row 1|
                let s = (exp[0][j].abs() * w).max(exp[1][j].abs());
                for i in 0..2 {
                    let sc = if i == 0 { s / w } else { s };
                    assert!(
                        (got[i][j] - exp[i][j]).abs() <= 1e-12 * sc,
                        "ω {w}, γ {g}, τ {tau}: entry ({i},{j}) {} vs {}",
                        got[i][j],
                        exp[i][j]
                    );
                }
            }
        }
    }
}
