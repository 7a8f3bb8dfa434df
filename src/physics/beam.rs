//! Clamped–clamped Rayleigh beam: mode shapes, Galerkin matrices, the single-mode (paper) model
//! and its closed-form free vibration with energy bookkeeping (physics.md §B.1–§B.6).
//!
//! Coordinates: x = s/l ∈ [0, 1] along the column; modal amplitudes wᵢ in m, so that the
//! deflection is w(s, t) = Σ φᵢ(s/l) wᵢ(t).

use std::f64::consts::{FRAC_PI_2, PI};

use nalgebra::DMatrix;

use super::error::{Param, PhysicsError, PhysicsResult};
use super::material::{Column, Damping, Section};
use super::numeric::quadrature::gauss_legendre;

/// Largest number of exact modes the Galerkin model supports.
pub const MAX_MODES: usize = 50;

/// λ₁ of the paper's printed constants (physics.md §B.4): the exact root rounded to 3 decimals.
pub const PAPER_LAMBDA: f64 = 4.73;

/// Which mode-1 shape and constants the single-mode model uses (physics.md §B.4).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ModeShapes {
    /// Exact clamped–clamped mode: λ₁ = 4.7300…, ∫φ² = 1, ∫φ′² = σλ(σλ − 2), ∫φ″² = λ⁴.
    Exact,
    /// The paper's printed constants (λ = 4.73, ∫φφ⁗ as stiffness, φ(½) = 1.588).
    Paper,
    /// λ = 3π/2 with ∫φ², ∫φ′², ∫φ″² of that (inexact) shape.
    Approx,
}

/// i-th root (i ≥ 1) of cos λ · cosh λ = 1, the clamped–clamped eigenvalue λᵢ (dimensionless).
///
/// Written as λ = (2i+1)π/2 + ε with (−1)^{i+1} sin ε = sech λ, solved by fixed-point
/// iteration, so that no digits are lost in cos λ for large i.
///
/// # Examples
/// ```
/// let l1 = gangue::physics::beam::clamped_root(1);
/// assert!((l1 - 4.730040744862704).abs() < 1e-14);
/// ```
///
/// # Special cases
/// * `i = 0` is treated as `i = 1`.
/// * For i ≥ 20, sech λ < 1e-40 and the root is (2i+1)π/2 to the last bit.
///
/// # References
/// physics.md §B.3.
#[must_use]
pub fn clamped_root(i: usize) -> f64 {
    let i = i.max(1);
    let base = (2 * i + 1) as f64 * FRAC_PI_2;
    let sign = if i % 2 == 1 { 1.0 } else { -1.0 };
    let mut eps = 0.0_f64;
    for _ in 0..60 {
        let lam = base + eps;
        // sech λ = 2e^{−λ}/(1 + e^{−2λ}), no overflow.
        let em = (-lam).exp();
        let sech = 2.0 * em / (1.0 + em * em);
        let next = (sign * sech).asin();
        if (next - eps).abs() <= 1e-17 * base {
            eps = next;
            break;
        }
        eps = next;
    }
    base + eps
}

/// A clamped–clamped shape function φ(x) = cosh λx − cos λx − σ(sinh λx − sin λx) of a given λ.
///
/// Evaluated in the overflow-free form ½(1−σ)e^{λx} + ½(1+σ)e^{−λx} − cos λx + σ sin λx with
/// ½(1−σ)e^{λx} = ((cos λ − sin λ − e^{−λ})/(1 − e^{−2λ} − 2e^{−λ} sin λ))·e^{λ(x−1)}.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BeamMode {
    /// The eigenvalue λ (dimensionless).
    pub lambda: f64,
    /// σ = (cosh λ − cos λ)/(sinh λ − sin λ) (dimensionless).
    pub sigma: f64,
    /// ½(1 − σ)·e^{λ}, finite for every λ (dimensionless).
    half_one_minus_sigma_e: f64,
}

impl BeamMode {
    /// The exact i-th clamped–clamped mode (i ≥ 1).
    #[must_use]
    pub fn clamped(i: usize) -> Self {
        Self::with_lambda(clamped_root(i))
    }

    /// The shape function of the given λ > 0 (exact only when λ is a root of cos λ cosh λ = 1).
    #[must_use]
    pub fn with_lambda(lambda: f64) -> Self {
        let em = (-lambda).exp();
        let (s, c) = lambda.sin_cos();
        // sinh λ − sin λ = (e^{λ}/2)(1 − e^{−2λ} − 2e^{−λ} sin λ)
        let den = 1.0 - em * em - 2.0 * em * s;
        let sigma = (1.0 + em * em - 2.0 * em * c) / den;
        // (1 − σ)e^{λ}/2 = (cos λ − sin λ − e^{−λ}) / (1 − e^{−2λ} − 2e^{−λ} sin λ)
        let half_one_minus_sigma_e = (c - s - em) / den;
        Self {
            lambda,
            sigma,
            half_one_minus_sigma_e,
        }
    }

    /// The three exponential/trigonometric parts at x: (½(1−σ)e^{λx}, ½(1+σ)e^{−λx}, cos λx, sin λx).
    fn parts(&self, x: f64) -> (f64, f64, f64, f64) {
        let l = self.lambda;
        let a = self.half_one_minus_sigma_e * (l * (x - 1.0)).exp();
        let b = 0.5 * (1.0 + self.sigma) * (-l * x).exp();
        let (s, c) = (l * x).sin_cos();
        (a, b, c, s)
    }

    /// φ(x), dimensionless.
    ///
    /// # Examples
    /// ```
    /// let m = gangue::physics::beam::BeamMode::clamped(1);
    /// assert!((m.shape(0.5) - 1.588146262064605).abs() < 1e-14);
    /// ```
    #[must_use]
    pub fn shape(&self, x: f64) -> f64 {
        let (a, b, c, s) = self.parts(x);
        a + b - c + self.sigma * s
    }

    /// dφ/dx (derivative in x = s/l), dimensionless.
    #[must_use]
    pub fn slope(&self, x: f64) -> f64 {
        let (a, b, c, s) = self.parts(x);
        self.lambda * (a - b + s + self.sigma * c)
    }

    /// d²φ/dx², dimensionless; the beam curvature is wᵢ·φ″(x)/l².
    #[must_use]
    pub fn curvature(&self, x: f64) -> f64 {
        let (a, b, c, s) = self.parts(x);
        self.lambda * self.lambda * (a + b + c - self.sigma * s)
    }
}

/// The three Galerkin integrals of one shape function over x ∈ [0, 1] (dimensionless).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModeIntegrals {
    /// Mass integral ∫φ².
    pub mass: f64,
    /// Rotary-inertia integral ∫φ′².
    pub rotary: f64,
    /// Stiffness integral (∫φ″², or ∫φφ⁗ for the paper's printed constants).
    pub stiffness: f64,
}

/// ∫φ², ∫φ′², ∫φ″² over [0, 1] by composite Gauss–Legendre quadrature (32 panels × 20 points).
///
/// Accurate to a few ulps for λ ≤ 200 (the integrands are entire and each panel spans less than
/// one half-wave of mode 50).
///
/// # Special cases
/// For a non-root λ (the `approx` and `paper` shapes) the integrals are those of the inexact shape.
///
/// # References
/// physics.md §B.4 (table of the first shape function's constants).
#[must_use]
pub fn mode_integrals_quadrature(mode: &BeamMode) -> ModeIntegrals {
    let nodes = gauss_legendre(20);
    let panels = 32;
    let h = 1.0 / panels as f64;
    let (mut m, mut r, mut k) = (0.0, 0.0, 0.0);
    for p in 0..panels {
        let mid = (p as f64 + 0.5) * h;
        for &(xi, wi) in &nodes {
            let x = mid + 0.5 * h * xi;
            let w = 0.5 * h * wi;
            let (f, d1, d2) = (mode.shape(x), mode.slope(x), mode.curvature(x));
            m += w * f * f;
            r += w * d1 * d1;
            k += w * d2 * d2;
        }
    }
    ModeIntegrals {
        mass: m,
        rotary: r,
        stiffness: k,
    }
}

/// Closed-form rotary integral A¹¹ᵢⱼ = ∫φᵢ′φⱼ′ of two exact modes (dimensionless).
///
/// # Special cases
/// Modes of opposite symmetry (i + j odd) give exactly 0.
///
/// # References
/// physics.md §B.4: A¹¹ᵢᵢ = σλ(σλ − 2); A¹¹ᵢⱼ = 4λᵢ²λⱼ²(σⱼλⱼ − σᵢλᵢ)(1 + sᵢsⱼ)/(λᵢ⁴ − λⱼ⁴).
#[must_use]
pub fn rotary_integral(i: usize, mi: &BeamMode, j: usize, mj: &BeamMode) -> f64 {
    let (si, sj) = (mi.sigma * mi.lambda, mj.sigma * mj.lambda);
    if i == j {
        return si * (si - 2.0);
    }
    if (i + j) % 2 == 1 {
        return 0.0;
    }
    let (li2, lj2) = (mi.lambda * mi.lambda, mj.lambda * mj.lambda);
    // 1 + sᵢsⱼ = 2 for equal symmetry; λᵢ⁴ − λⱼ⁴ = (λᵢ² − λⱼ²)(λᵢ² + λⱼ²).
    8.0 * li2 * lj2 * (sj - si) / ((li2 - lj2) * (li2 + lj2))
}

/// Mode 1 as the single-mode model uses it: its shape (for stresses), integrals and φ(½).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FirstMode {
    /// Which constants these are.
    pub shapes: ModeShapes,
    /// The shape function (λ = 4.73 for `Paper`, 3π/2 for `Approx`).
    pub mode: BeamMode,
    /// Galerkin integrals (for `Paper` the printed constants).
    pub integrals: ModeIntegrals,
    /// Midpoint value φ(½) (1.588 for `Paper`), dimensionless.
    pub midpoint_value: f64,
}

/// Mode-1 shape and constants for the chosen [`ModeShapes`].
///
/// # References
/// physics.md §B.4 (paper constants 1.000008614, 12.30251267, 500.5509646, φ(½) = 1.588).
#[must_use]
pub fn first_mode(shapes: ModeShapes) -> FirstMode {
    match shapes {
        ModeShapes::Exact => {
            let mode = BeamMode::clamped(1);
            let l = mode.lambda;
            FirstMode {
                shapes,
                mode,
                integrals: ModeIntegrals {
                    mass: 1.0,
                    rotary: rotary_integral(1, &mode, 1, &mode),
                    stiffness: l * l * l * l,
                },
                midpoint_value: mode.shape(0.5),
            }
        }
        ModeShapes::Paper => FirstMode {
            shapes,
            mode: BeamMode::with_lambda(PAPER_LAMBDA),
            integrals: ModeIntegrals {
                mass: 1.000008614,
                rotary: 12.30251267,
                stiffness: 500.5509646,
            },
            midpoint_value: 1.588,
        },
        ModeShapes::Approx => {
            let mode = BeamMode::with_lambda(3.0 * FRAC_PI_2);
            FirstMode {
                shapes,
                mode,
                integrals: mode_integrals_quadrature(&mode),
                midpoint_value: mode.shape(0.5),
            }
        }
    }
}

/// Modal mass M = μl∫φ² + (J₀/l)∫φ′² (kg) and stiffness K = (EI/l³)·stiffness integral (N/m).
fn modal_mass_stiffness(
    section: &Section,
    length: f64,
    integrals: &ModeIntegrals,
    rotary_inertia: bool,
) -> (f64, f64) {
    let j0 = if rotary_inertia {
        section.rotary_inertia
    } else {
        0.0
    };
    let m = section.mass_per_length * length * integrals.mass + j0 / length * integrals.rotary;
    let k = section.bending_stiffness / length.powi(3) * integrals.stiffness;
    (m, k)
}

/// Damping coefficient per unit length c, N·s/m², as used: the given c, or c = 2ζ₁√(K₁M₁)/l
/// from the mode-1 damping ratio with the **exact** mode 1 (rotary inertia as configured).
///
/// # Errors
/// `InvalidInput` at [`Param::ColumnDampingCoefficient`] or [`Param::ColumnDampingRatio`] for a
/// negative or non-finite value.
///
/// # References
/// physics.md §B.6.
pub fn damping_coefficient(column: &Column, rotary_inertia: bool) -> PhysicsResult<f64> {
    match column.damping {
        Damping::Coefficient(c) => {
            if !(c >= 0.0 && c.is_finite()) {
                return Err(PhysicsError::invalid(
                    Param::ColumnDampingCoefficient,
                    c,
                    "the damping coefficient must lie in [0, 1e9] N·s/m²",
                ));
            }
            Ok(c)
        }
        Damping::Ratio(z) => {
            if !(z >= 0.0 && z.is_finite()) {
                return Err(PhysicsError::invalid(
                    Param::ColumnDampingRatio,
                    z,
                    "the damping ratio must lie in [0, 10]",
                ));
            }
            let exact = first_mode(ModeShapes::Exact);
            let (m, k) = modal_mass_stiffness(
                &column.section(),
                column.length,
                &exact.integrals,
                rotary_inertia,
            );
            Ok(2.0 * z * (k * m).sqrt() / column.length)
        }
    }
}

/// The single-mode (paper) model of a column: M₁ẅ₁ + C₁ẇ₁ + K₁w₁ = 0 and derived quantities.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SingleMode {
    /// Mode 1 as used.
    pub first: FirstMode,
    /// Section properties.
    pub section: Section,
    /// Damping coefficient per unit length c as used, N·s/m².
    pub damping_coefficient: f64,
    /// Modal mass M₁, kg.
    pub mass: f64,
    /// Modal damping C₁ = c·l·∫φ², N·s/m.
    pub damping: f64,
    /// Modal stiffness K₁, N/m.
    pub stiffness: f64,
    /// Midpoint stiffness K_mid = K₁/φ(½)², N/m.
    pub midpoint_stiffness: f64,
    /// Midpoint mass M_mid = M₁/φ(½)², kg.
    pub midpoint_mass: f64,
}

impl SingleMode {
    /// Builds the mode-1 model of `column` with the given shapes and rotary inertia on/off.
    ///
    /// # Errors
    /// As [`damping_coefficient`].
    ///
    /// # References
    /// physics.md §B.1, §B.4, §B.5.
    pub fn new(column: &Column, shapes: ModeShapes, rotary_inertia: bool) -> PhysicsResult<Self> {
        let section = column.section();
        let first = first_mode(shapes);
        let c = damping_coefficient(column, rotary_inertia)?;
        let (mass, stiffness) =
            modal_mass_stiffness(&section, column.length, &first.integrals, rotary_inertia);
        let damping = c * column.length * first.integrals.mass;
        let phi2 = first.midpoint_value * first.midpoint_value;
        Ok(Self {
            first,
            section,
            damping_coefficient: c,
            mass,
            damping,
            stiffness,
            midpoint_stiffness: stiffness / phi2,
            midpoint_mass: mass / phi2,
        })
    }

    /// Free vibration from w₁(0) = `w0` (m), ẇ₁(0) = 0.
    #[must_use]
    pub fn free_vibration(&self, w0: f64) -> FreeVibration {
        FreeVibration::new(self.mass, self.damping, self.stiffness, w0)
    }
}

/// Closed-form free vibration of M ẅ + C ẇ + K w = 0, w(0) = w₀, ẇ(0) = 0, with energies.
///
/// Writing σ = ζω_n and q² = ω_n²(1 − ζ²) (negative when over-damped), the solution is
/// w = w₀·(E_C + σE_S), ẇ = −w₀ω_n²E_S with E_C = e^{−σt}·cos(qt) and E_S = e^{−σt}·sin(qt)/q
/// (cosh/sinh for q² < 0; E_C = e^{−σt}, E_S = t·e^{−σt} at ζ = 1). Each branch is evaluated in a
/// form without overflow or cancellation, so the three regimes join continuously at ζ = 1.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FreeVibration {
    /// Mass M, kg.
    pub mass: f64,
    /// Damping C, N·s/m.
    pub damping: f64,
    /// Stiffness K, N/m.
    pub stiffness: f64,
    /// Initial displacement w₀, m.
    pub w0: f64,
    /// Undamped circular frequency ω_n = √(K/M), rad/s.
    pub omega_n: f64,
    /// Damping ratio ζ = C/(2√(KM)).
    pub zeta: f64,
    /// σ = ζω_n, 1/s.
    sigma: f64,
    /// ω_d = ω_n√(1−ζ²) (ζ < 1) or β = ω_n√(ζ²−1) (ζ > 1), rad/s.
    q: f64,
}

/// Damping regime of a [`FreeVibration`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Regime {
    /// ζ < 1.
    Underdamped,
    /// ζ = 1.
    Critical,
    /// ζ > 1.
    Overdamped,
}

/// The five arrays [`FreeVibration::extend_uniform`] appends to.
#[derive(Debug)]
pub struct UniformColumns<'a> {
    /// Times, s.
    pub time: &'a mut Vec<f64>,
    /// The scaled modal displacement (the midpoint deflection for a scale φ(½)), m.
    pub displacement: &'a mut Vec<f64>,
    /// Kinetic energy ½Mẇ², J.
    pub kinetic: &'a mut Vec<f64>,
    /// Strain energy ½Kw², J.
    pub strain: &'a mut Vec<f64>,
    /// Dissipated energy ∫₀ᵗ Cẇ² dτ, J.
    pub dissipated: &'a mut Vec<f64>,
}

/// State and energies of a single-mode free vibration at one time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModalSample {
    /// Time, s.
    pub time: f64,
    /// Modal displacement w₁, m.
    pub displacement: f64,
    /// Modal velocity ẇ₁, m/s.
    pub velocity: f64,
    /// Kinetic energy ½Mẇ², J.
    pub kinetic: f64,
    /// Strain energy ½Kw², J.
    pub strain: f64,
    /// Dissipated energy ∫₀ᵗ Cẇ² dτ, J.
    pub dissipated: f64,
}

impl FreeVibration {
    /// The oscillator M, C, K (kg, N·s/m, N/m; M, K > 0, C ≥ 0) released from w₀ (m) at rest.
    #[must_use]
    pub fn new(mass: f64, damping: f64, stiffness: f64, w0: f64) -> Self {
        let omega_n = (stiffness / mass).sqrt();
        let zeta = damping / (2.0 * (stiffness * mass).sqrt());
        let sigma = zeta * omega_n;
        let q = omega_n * ((1.0 - zeta).abs() * (1.0 + zeta)).sqrt();
        Self {
            mass,
            damping,
            stiffness,
            w0,
            omega_n,
            zeta,
            sigma,
            q,
        }
    }

    /// The damping regime.
    #[must_use]
    pub fn regime(&self) -> Regime {
        if self.zeta < 1.0 {
            Regime::Underdamped
        } else if self.zeta == 1.0 {
            Regime::Critical
        } else {
            Regime::Overdamped
        }
    }

    /// (E_C, E_S): e^{−σt}·C(t) and e^{−σt}·S(t) (S in s).
    fn kernels(&self, t: f64) -> (f64, f64) {
        let (sigma, q) = (self.sigma, self.q);
        match self.regime() {
            Regime::Underdamped => {
                let e = (-sigma * t).exp();
                let (s, c) = (q * t).sin_cos();
                let sq = if q * t == 0.0 { t } else { s / q };
                (e * c, e * sq)
            }
            Regime::Critical => {
                let e = (-sigma * t).exp();
                (e, e * t)
            }
            Regime::Overdamped => {
                // r₁ = −ω_n/(ζ + √(ζ²−1)) = −(σ − β) without cancellation; r₂ = −(σ + β).
                let r1 =
                    -self.omega_n / (self.zeta + ((self.zeta - 1.0) * (self.zeta + 1.0)).sqrt());
                let r2 = -(sigma + q);
                let e1 = (r1 * t).exp();
                let ec = 0.5 * (e1 + (r2 * t).exp());
                // e^{−σt} sinh(βt)/β = e^{r₁t}(1 − e^{−2βt})/(2β)
                let es = if q * t < 1e-300 {
                    e1 * t
                } else {
                    e1 * (-(-2.0 * q * t).exp_m1()) / (2.0 * q)
                };
                (ec, es)
            }
        }
    }

    /// Modal displacement and velocity at time t ≥ 0 (m, m/s).
    #[must_use]
    pub fn state(&self, t: f64) -> (f64, f64) {
        let (ec, es) = self.kernels(t);
        (
            self.w0 * (ec + self.sigma * es),
            -self.w0 * self.omega_n * self.omega_n * es,
        )
    }

    /// State and energies at time t ≥ 0.
    ///
    /// The dissipated energy is the closed-form ∫₀ᵗCẇ²dτ
    /// = C w₀²ω_n²·[−expm1(−2σt) − 2σE_SE_C − 2σ²E_S²]/(4σ), not U₀ − T − U.
    ///
    /// # Examples
    /// ```
    /// use gangue::physics::beam::FreeVibration;
    /// let fv = FreeVibration::new(2.0, 3.0, 800.0, 0.01);
    /// let s = fv.sample(0.3);
    /// let total = s.kinetic + s.strain + s.dissipated;
    /// assert!((total - fv.initial_energy()).abs() < 1e-12 * fv.initial_energy());
    /// ```
    ///
    /// # Special cases
    /// C = 0 gives a dissipated energy of exactly 0.
    ///
    /// # References
    /// physics.md §B.5.
    #[must_use]
    pub fn sample(&self, t: f64) -> ModalSample {
        let (ec, es) = self.kernels(t);
        let wn2 = self.omega_n * self.omega_n;
        let w = self.w0 * (ec + self.sigma * es);
        let wd = -self.w0 * wn2 * es;
        let dissipated = if self.damping == 0.0 || self.sigma == 0.0 {
            0.0
        } else {
            let s = self.sigma;
            let bracket = -(-2.0 * s * t).exp_m1() - 2.0 * s * es * ec - 2.0 * s * s * es * es;
            self.damping * self.w0 * self.w0 * wn2 * bracket / (4.0 * s)
        };
        ModalSample {
            time: t,
            displacement: w,
            velocity: wd,
            kinetic: 0.5 * self.mass * wd * wd,
            strain: 0.5 * self.stiffness * w * w,
            dissipated,
        }
    }

    /// Samples at t_k = k·duration/(n − 1), k = 0…n−1 (the last exactly at `duration`), the same
    /// quantities as [`FreeVibration::sample`] but by the addition theorems
    /// E_C(t_b+τ) = E_C(t_b)·K_C(τ) − q²E_S(t_b)·K_S(τ), E_S(t_b+τ) = E_S(t_b)·K_C(τ) + E_C(t_b)·K_S(τ):
    /// the direct formulas at the start t_b of every block of 64 samples and a table of the
    /// kernels (K_C, K_S) at τ = jΔ, j < 64, computed once. Every sample is one addition-theorem
    /// step from two directly computed values (no drift along the history; error a few ulps), and
    /// the samples of a block are independent of each other (no dependency chain).
    ///
    /// # Special cases
    /// n = 0 gives no samples; n = 1 gives t = 0 only.
    ///
    /// # References
    /// physics.md §B.5.
    #[must_use]
    pub fn sample_uniform(&self, duration: f64, n: usize) -> Vec<ModalSample> {
        let mut out = Vec::with_capacity(n);
        self.for_each_uniform(duration, n, |s| out.push(s));
        out
    }

    /// Coefficients shared by the uniform samplers: ω_d² = ω_n²(1 − ζ)(1 + ζ) in 1/s², ω_n² in
    /// 1/s², and the dissipated-energy factor c w₀² ω_n² / (4σ) in J (0 without damping).
    fn uniform_coefficients(&self) -> (f64, f64, f64) {
        let wn2 = self.omega_n * self.omega_n;
        let q2 = wn2 * (1.0 - self.zeta) * (1.0 + self.zeta);
        let dis_factor = if self.damping == 0.0 || self.sigma == 0.0 {
            0.0
        } else {
            self.damping * self.w0 * self.w0 * wn2 / (4.0 * self.sigma)
        };
        (q2, wn2, dis_factor)
    }

    /// Calls `f` with the samples of [`FreeVibration::sample_uniform`] in time order, without
    /// collecting them (callers write straight into their own arrays).
    pub fn for_each_uniform(&self, duration: f64, n: usize, mut f: impl FnMut(ModalSample)) {
        const BLOCK: usize = 64;
        if n == 0 {
            return;
        }
        if n == 1 {
            f(self.sample(0.0));
            return;
        }
        let dt = duration / (n - 1) as f64;
        let (q2, wn2, dis_factor) = self.uniform_coefficients();
        let s = self.sigma;
        let (half_m, half_k) = (0.5 * self.mass, 0.5 * self.stiffness);
        // Kernels and 1 − e^{−2στ} at τ = jΔ, j < BLOCK (only as many as there are samples).
        let len = BLOCK.min(n);
        let mut kc = [0.0; BLOCK];
        let mut ks = [0.0; BLOCK];
        let mut ka = [0.0; BLOCK];
        for j in 0..len {
            let tau = j as f64 * dt;
            (kc[j], ks[j]) = self.kernels(tau);
            ka[j] = -(-2.0 * s * tau).exp_m1();
        }
        let mut b = 0;
        while b < n {
            let tb = b as f64 * dt;
            let (ecb, esb) = self.kernels(tb);
            let mb = -(-2.0 * s * tb).exp_m1();
            let end = (b + BLOCK).min(n);
            for k in b..end {
                let j = k - b;
                let (t, ec, es, m) = if k + 1 == n {
                    let (ec, es) = self.kernels(duration);
                    (duration, ec, es, -(-2.0 * s * duration).exp_m1())
                } else {
                    (
                        k as f64 * dt,
                        ecb * kc[j] - q2 * esb * ks[j],
                        esb * kc[j] + ecb * ks[j],
                        mb + (1.0 - mb) * ka[j],
                    )
                };
                let w = self.w0 * (ec + s * es);
                let wd = -self.w0 * wn2 * es;
                let dissipated = if dis_factor == 0.0 {
                    0.0
                } else {
                    dis_factor * (m - 2.0 * s * es * ec - 2.0 * s * s * es * es)
                };
                f(ModalSample {
                    time: t,
                    displacement: w,
                    velocity: wd,
                    kinetic: half_m * wd * wd,
                    strain: half_k * w * w,
                    dissipated,
                });
            }
            b = end;
        }
    }

    /// Appends the samples of [`FreeVibration::sample_uniform`] straight to the five arrays of
    /// `out`: the times (s), `scale`·w (with `scale` = φ(½), the midpoint deflection, m), and
    /// the kinetic, strain and dissipated energies (J). Block by block (64 samples), each array
    /// is filled by a loop of its own over the block's kernels, without per-sample capacity
    /// checks; the values are bit-identical to those of [`FreeVibration::for_each_uniform`].
    ///
    /// # Special cases
    /// n = 0 appends nothing; n = 1 appends t = 0 only.
    ///
    /// # References
    /// physics.md §B.5.
    pub fn extend_uniform(&self, duration: f64, n: usize, scale: f64, out: UniformColumns<'_>) {
        const BLOCK: usize = 64;
        let UniformColumns {
            time,
            displacement,
            kinetic,
            strain,
            dissipated,
        } = out;
        for v in [
            &mut *time,
            &mut *displacement,
            &mut *kinetic,
            &mut *strain,
            &mut *dissipated,
        ] {
            v.reserve(n);
        }
        if n <= 1 {
            self.for_each_uniform(duration, n, |s| {
                time.push(s.time);
                displacement.push(scale * s.displacement);
                kinetic.push(s.kinetic);
                strain.push(s.strain);
                dissipated.push(s.dissipated);
            });
            return;
        }
        let dt = duration / (n - 1) as f64;
        let (q2, wn2, dis_factor) = self.uniform_coefficients();
        let s = self.sigma;
        let (half_m, half_k, w0) = (0.5 * self.mass, 0.5 * self.stiffness, self.w0);
        let len = BLOCK.min(n);
        let mut kc = [0.0; BLOCK];
        let mut ks = [0.0; BLOCK];
        let mut ka = [0.0; BLOCK];
        for j in 0..len {
            let tau = j as f64 * dt;
            (kc[j], ks[j]) = self.kernels(tau);
            ka[j] = -(-2.0 * s * tau).exp_m1();
        }
        let mut ec = [0.0; BLOCK];
        let mut es = [0.0; BLOCK];
        let mut mm = [0.0; BLOCK];
        let mut b = 0;
        while b < n {
            let tb = b as f64 * dt;
            let (ecb, esb) = self.kernels(tb);
            let mb = -(-2.0 * s * tb).exp_m1();
            let end = (b + BLOCK).min(n);
            let len = end - b;
            let (ec, es, mm) = (&mut ec[..len], &mut es[..len], &mut mm[..len]);
            for ((((c, e), m), (&kcj, &ksj)), &kaj) in ec
                .iter_mut()
                .zip(es.iter_mut())
                .zip(mm.iter_mut())
                .zip(kc.iter().zip(&ks))
                .zip(&ka)
            {
                *c = ecb * kcj - q2 * esb * ksj;
                *e = esb * kcj + ecb * ksj;
                *m = mb + (1.0 - mb) * kaj;
            }
            if end == n {
                // The last sample exactly at `duration`, from the direct formulas.
                (ec[len - 1], es[len - 1]) = self.kernels(duration);
                mm[len - 1] = -(-2.0 * s * duration).exp_m1();
            }
            time.extend((b..end).map(|k| k as f64 * dt));
            if end == n {
                time[n - 1] = duration;
            }
            let ecs = ec.iter().zip(es.iter());
            displacement.extend(ecs.clone().map(|(&c, &e)| scale * (w0 * (c + s * e))));
            kinetic.extend(es.iter().map(|&e| {
                let wd = -w0 * wn2 * e;
                half_m * wd * wd
            }));
            strain.extend(ecs.clone().map(|(&c, &e)| {
                let w = w0 * (c + s * e);
                half_k * w * w
            }));
            if dis_factor == 0.0 {
                dissipated.extend(std::iter::repeat_n(0.0, len));
            } else {
                dissipated.extend(ecs.zip(mm.iter()).map(|((&c, &e), &m)| {
                    dis_factor * (m - 2.0 * s * e * c - 2.0 * s * s * e * e)
                }));
            }
            b = end;
        }
    }

    /// Initial (absorbed) energy U₀ = ½Kw₀², J.
    #[must_use]
    pub fn initial_energy(&self) -> f64 {
        0.5 * self.stiffness * self.w0 * self.w0
    }

    /// Decay rate of the envelope, 1/s: ζω_n for ζ < 1, |r₁| = ω_n/(ζ + √(ζ²−1)) for ζ ≥ 1.
    #[must_use]
    pub fn decay_rate(&self) -> f64 {
        if self.zeta < 1.0 {
            self.sigma
        } else {
            self.omega_n / (self.zeta + ((self.zeta - 1.0) * (self.zeta + 1.0)).sqrt())
        }
    }

    /// Time for the amplitude to fall to `fraction` ∈ (0, 1) of w₀, s; `None` when it never does
    /// (no damping) or when the time is not representable (damping so light that it overflows).
    ///
    /// # Special cases
    /// * ζ ≤ 1/√2: the envelope time ln(1/x)/σ of physics.md §B.5.
    /// * 1/√2 < ζ < 1: that time blended (C¹ smoothstep in ζ) into the root of the response bound
    ///   e^{−σt}·min(1/√(1−ζ²), 1 + σt) = x. The first factor is the exact amplitude of
    ///   w₀e^{−σt}(cos ω_d t + (σ/ω_d) sin ω_d t); the second bounds it by |sin ω_d t|/ω_d ≤ t and
    ///   equals the critically damped solution at ζ = 1, so the decay time is continuous through
    ///   critical damping (the plain envelope time is 30 % short there).
    /// * ζ ≥ 1: the root of w(t) = x·w₀ (w decreases monotonically), by bisection to 1e-15.
    ///
    /// # References
    /// physics.md §B.5.
    #[must_use]
    pub fn decay_time(&self, fraction: f64) -> Option<f64> {
        if !(fraction > 0.0 && fraction < 1.0) {
            return None;
        }
        let target = -fraction.ln();
        if self.zeta < 1.0 {
            if self.sigma.is_nan() || self.sigma <= 0.0 {
                return None;
            }
            // ln(1/√(1−ζ²)) = −½·ln1p(−ζ²) without cancellation for small ζ.
            let amp_log = -0.5 * (-(self.zeta * self.zeta)).ln_1p();
            let t_amp = (target + amp_log) / self.sigma;
            // Root of e^{−s}(1 + s) = x in s = σt, by Newton from the upper bound ln(1/x) + ln(1+s).
            let g = |s: f64| -s + s.ln_1p() + target;
            let mut s = target;
            for _ in 0..60 {
                let d = -1.0 + 1.0 / (1.0 + s);
                let next = s - g(s) / d;
                if (next - s).abs() <= 1e-16 * next {
                    s = next;
                    break;
                }
                s = next;
            }
            let t_crit = s / self.sigma;
            let t_bound = t_amp.min(t_crit);
            let t_plain = target / self.sigma;
            let w = near_critical_weight(self.zeta);
            let t = t_plain + w * (t_bound - t_plain);
            return t.is_finite().then_some(t);
        }
        // w(t)/w₀ − x, monotone decreasing from 1 − x > 0.
        let f = |t: f64| {
            let (ec, es) = self.kernels(t);
            ec + self.sigma * es - fraction
        };
        let rate = self.decay_rate();
        let mut hi = target / rate;
        let mut lo = 0.0;
        let mut guard = 0;
        while f(hi) > 0.0 && guard < 2000 {
            lo = hi;
            hi *= 2.0;
            guard += 1;
        }
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if f(mid) > 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
            if hi - lo <= 1e-15 * hi {
                break;
            }
        }
        Some(0.5 * (lo + hi))
    }
}

/// Galerkin matrices of the first n exact modes (physics.md §B.4).
#[derive(Debug, Clone, PartialEq)]
pub struct Galerkin {
    /// The modes 1…n.
    pub modes: Vec<BeamMode>,
    /// Mass matrix M = μl·I + (J₀/l)·A¹¹, kg.
    pub mass: DMatrix<f64>,
    /// Damping matrix C = c·l·I, N·s/m.
    pub damping: DMatrix<f64>,
    /// Stiffness matrix K = (EI/l³)·diag(λᵢ⁴), N/m.
    pub stiffness: DMatrix<f64>,
    /// Midpoint values Φᵢ = φᵢ(½), dimensionless.
    pub midpoint: Vec<f64>,
}

impl Galerkin {
    /// Builds the matrices of modes 1…n (1 ≤ n ≤ [`MAX_MODES`]) with damping coefficient
    /// c (N·s/m²) and rotary inertia on or off.
    ///
    /// # Errors
    /// `InvalidInput` at [`Param::GalerkinModes`] for n outside [1, 50].
    ///
    /// # References
    /// physics.md §B.4.
    pub fn new(
        column: &Column,
        n: usize,
        damping_coefficient: f64,
        rotary_inertia: bool,
    ) -> PhysicsResult<Self> {
        if n == 0 || n > MAX_MODES {
            return Err(PhysicsError::invalid(
                Param::GalerkinModes,
                n as f64,
                "the number of modes must lie in [1, 50]",
            ));
        }
        let s = column.section();
        let l = column.length;
        let modes: Vec<BeamMode> = (1..=n).map(BeamMode::clamped).collect();
        let j0 = if rotary_inertia {
            s.rotary_inertia
        } else {
            0.0
        };
        let mass = DMatrix::from_fn(n, n, |i, j| {
            let a11 = rotary_integral(i + 1, &modes[i], j + 1, &modes[j]);
            let a00 = if i == j { 1.0 } else { 0.0 };
            s.mass_per_length * l * a00 + j0 / l * a11
        });
        let damping = DMatrix::from_fn(
            n,
            n,
            |i, j| {
                if i == j { damping_coefficient * l } else { 0.0 }
            },
        );
        let kf = s.bending_stiffness / l.powi(3);
        let stiffness = DMatrix::from_fn(n, n, |i, j| {
            if i == j {
                kf * modes[i].lambda.powi(4)
            } else {
                0.0
            }
        });
        let midpoint = modes
            .iter()
            .enumerate()
            .map(|(i, m)| if i % 2 == 1 { 0.0 } else { m.shape(0.5) })
            .collect();
        Ok(Self {
            modes,
            mass,
            damping,
            stiffness,
            midpoint,
        })
    }

    /// Undamped natural frequencies √eig(M⁻¹K)/2π, Hz, ascending.
    ///
    /// Solved as the symmetric problem L⁻¹KL⁻ᵀ with M = LLᵀ (Cholesky), so the eigenvalues are
    /// real and accurate to rounding.
    ///
    /// # References
    /// physics.md §B.7.
    #[must_use]
    pub fn natural_frequencies(&self) -> Vec<f64> {
        generalized_frequencies(&self.mass, &self.stiffness)
    }

    /// Damping ratios ζᵢ = Cᵢᵢ/(2√(KᵢᵢMᵢᵢ)) of each mode (dimensionless).
    #[must_use]
    pub fn damping_ratios(&self) -> Vec<f64> {
        (0..self.modes.len())
            .map(|i| {
                self.damping[(i, i)] / (2.0 * (self.stiffness[(i, i)] * self.mass[(i, i)]).sqrt())
            })
            .collect()
    }
}

/// √eig(M⁻¹K)/2π (Hz, ascending) for symmetric positive-definite M and symmetric K.
#[must_use]
pub fn generalized_frequencies(mass: &DMatrix<f64>, stiffness: &DMatrix<f64>) -> Vec<f64> {
    let n = mass.nrows();
    let Some(chol) = mass.clone().cholesky() else {
        return vec![f64::NAN; n];
    };
    let l = chol.l();
    // A = L⁻¹ K L⁻ᵀ
    let y = l
        .solve_lower_triangular(stiffness)
        .unwrap_or_else(|| DMatrix::zeros(n, n));
    let a = l
        .solve_lower_triangular(&y.transpose())
        .unwrap_or_else(|| DMatrix::zeros(n, n));
    let a = (&a + a.transpose()) * 0.5;
    let mut ev: Vec<f64> = a.symmetric_eigen().eigenvalues.iter().copied().collect();
    ev.sort_by(|x, y| x.total_cmp(y));
    ev.into_iter()
        .map(|e| e.max(0.0).sqrt() / (2.0 * PI))
        .collect()
}

/// Weight of the response bound in the decay time: 0 for ζ ≤ 1/√2, rising as a C¹ smoothstep to 1
/// at ζ = 1 (see [`FreeVibration::decay_time`]).
fn near_critical_weight(zeta: f64) -> f64 {
    let lo = std::f64::consts::FRAC_1_SQRT_2;
    let x = ((zeta - lo) / (1.0 - lo)).clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rel(a: f64, b: f64) -> f64 {
        ((a - b) / b).abs()
    }

    /// physics.md §B.3 roots, to 1e-15 relative.
    #[test]
    fn roots_match_spec() {
        let spec = [
            4.730040744862704,
            7.853204624095838,
            10.99560783800167,
            14.13716549125746,
            17.27875965739948,
        ];
        for (i, &r) in spec.iter().enumerate() {
            let l = clamped_root(i + 1);
            assert!(rel(l, r) < 2e-15, "{i}: {l} vs {r}");
            assert!(((l.cos() * l.cosh()) - 1.0).abs() < 1e-9 * l.cosh());
        }
        // Large λ: the residual of (−1)^{i+1} sin ε = sech λ.
        for i in [20, 35, 50] {
            let l = clamped_root(i);
            assert!((l - (2 * i + 1) as f64 * FRAC_PI_2).abs() < 1e-12);
        }
    }

    /// Midpoint values of §B.3 and clamped boundary conditions, for modes 1…50 (finite, BC ~ 0).
    #[test]
    fn shapes_are_stable_and_clamped() {
        let mid = [
            1.588146262064605,
            0.0,
            -1.405998464277214,
            0.0,
            1.414567511330687,
        ];
        for (i, &m) in mid.iter().enumerate() {
            let v = BeamMode::clamped(i + 1).shape(0.5);
            assert!((v - m).abs() < 1e-13, "{i}: {v}");
        }
        for i in 1..=MAX_MODES {
            let md = BeamMode::clamped(i);
            for x in [0.0, 0.25, 0.5, 0.75, 1.0] {
                assert!(md.shape(x).is_finite() && md.curvature(x).is_finite());
            }
            assert!(md.shape(0.0).abs() < 1e-14);
            assert!(md.slope(0.0).abs() < 1e-12 * md.lambda);
            assert!(md.shape(1.0).abs() < 1e-10, "{i}: {}", md.shape(1.0));
            assert!(md.slope(1.0).abs() < 1e-10 * md.lambda, "{i}");
        }
    }

    /// Closed forms of §B.4 against quadrature, modes 1…50, to 1e-11 relative.
    #[test]
    fn closed_form_integrals_match_quadrature() {
        for i in 1..=MAX_MODES {
            let md = BeamMode::clamped(i);
            let q = mode_integrals_quadrature(&md);
            assert!(rel(q.mass, 1.0) < 1e-11, "{i}: {}", q.mass);
            assert!(rel(q.stiffness, md.lambda.powi(4)) < 1e-11, "{i}");
            assert!(
                rel(q.rotary, rotary_integral(i, &md, i, &md)) < 1e-11,
                "{i}"
            );
        }
        let diag = [
            12.302618623,
            46.050120144,
            98.904801402,
            171.585655702,
            263.997980736,
        ];
        for (i, &d) in diag.iter().enumerate() {
            let md = BeamMode::clamped(i + 1);
            assert!(rel(rotary_integral(i + 1, &md, i + 1, &md), d) < 1e-10);
        }
        let (m1, m3) = (BeamMode::clamped(1), BeamMode::clamped(3));
        assert!(rel(rotary_integral(1, &m1, 3, &m3), -9.730792213) < 1e-9);
        // Off-diagonal by quadrature (same-symmetry pair 1–5 and 2–4).
        for (i, j) in [(1usize, 5usize), (2, 4), (7, 19)] {
            let (a, b) = (BeamMode::clamped(i), BeamMode::clamped(j));
            let nodes = gauss_legendre(20);
            let mut s = 0.0;
            for p in 0..64 {
                let mid = (p as f64 + 0.5) / 64.0;
                for &(xi, wi) in &nodes {
                    let x = mid + 0.5 / 64.0 * xi;
                    s += 0.5 / 64.0 * wi * a.slope(x) * b.slope(x);
                }
            }
            assert!((s - rotary_integral(i, &a, j, &b)).abs() < 1e-10 * s.abs().max(1.0));
        }
    }

    /// Table of §B.4: constants of the λ = 4.73 and 3π/2 shapes.
    #[test]
    fn inexact_shape_constants_match_table() {
        let p = mode_integrals_quadrature(&BeamMode::with_lambda(4.73));
        assert!(rel(p.mass, 1.00000861379103) < 1e-13);
        assert!(rel(p.rotary, 12.3025126561638) < 1e-13);
        assert!(rel(p.stiffness, 500.533719597156) < 1e-13);
        assert!(rel(BeamMode::with_lambda(4.73).shape(0.5), 1.5881462616806) < 1e-12);
        let a = first_mode(ModeShapes::Approx);
        assert!(rel(a.integrals.mass, 1.00368011336397) < 1e-13);
        assert!(rel(a.integrals.rotary, 12.2583206554649) < 1e-13);
        assert!(rel(a.integrals.stiffness, 487.689161551019) < 1e-13);
        assert!(rel(a.midpoint_value, 1.5880741955521) < 1e-12);
    }

    /// Euler–Bernoulli frequencies λᵢ²√(EI/(μl⁴))/2π with rotary inertia off, to 1e-12.
    #[test]
    fn frequencies_match_euler_bernoulli() {
        let col = Column::default();
        let s = col.section();
        let g = Galerkin::new(&col, 50, 1.0, false).unwrap();
        let f = g.natural_frequencies();
        for (i, fi) in f.iter().enumerate() {
            let l = clamped_root(i + 1);
            let eb =
                l * l * (s.bending_stiffness / (s.mass_per_length * col.length.powi(4))).sqrt()
                    / (2.0 * PI);
            assert!(rel(*fi, eb) < 1e-12, "{i}: {fi} vs {eb}");
        }
        // Rotary inertia lowers every frequency; P08 values for n = 3.
        let g3 = Galerkin::new(&col, 3, 1.0, true).unwrap();
        let f3 = g3.natural_frequencies();
        for (a, b) in f3
            .iter()
            .zip([892.9026290343181, 2307.892309001549, 4151.338613669198])
        {
            assert!(rel(*a, b) < 1e-11, "{a} vs {b}");
        }
    }

    /// The uniform-grid recurrence agrees with the direct closed forms in every regime.
    #[test]
    fn uniform_samples_match_direct() {
        let (m, k) = (61.85689848982988f64, 1947065540.6183121f64);
        let cc = 2.0 * (k * m).sqrt();
        for z in [0.0, 1.9e-6, 0.02, 0.7, 1.0, 1.0 + 1e-9, 3.0, 1e6] {
            let fv = FreeVibration::new(m, z * cc, k, 1e-3);
            let u0 = fv.initial_energy();
            let n = 10_001;
            let d = 0.6;
            let fast = fv.sample_uniform(d, n);
            assert_eq!(fast.len(), n);
            assert_eq!(fast[n - 1].time, d);
            for s in fast.iter().step_by(7) {
                let e = fv.sample(s.time);
                assert!(
                    (s.displacement - e.displacement).abs() < 1e-12 * 1e-3,
                    "ζ={z}"
                );
                assert!((s.kinetic - e.kinetic).abs() < 1e-11 * u0, "ζ={z}");
                assert!((s.strain - e.strain).abs() < 1e-11 * u0);
                assert!((s.dissipated - e.dissipated).abs() < 1e-11 * u0, "ζ={z}");
            }
        }
    }

    /// The array form of the uniform history equals the per-sample one bit for bit, in every
    /// regime and for sample counts around the block length.
    #[test]
    fn extend_uniform_is_bit_identical_to_for_each_uniform() {
        let (m, k) = (61.85689848982988f64, 1947065540.6183121f64);
        let cc = 2.0 * (k * m).sqrt();
        for z in [0.0, 1.9e-6, 0.7, 1.0, 3.0, 1e6] {
            let fv = FreeVibration::new(m, z * cc, k, 1e-3);
            for n in [0, 1, 2, 63, 64, 65, 129, 10_001] {
                let scale = 1.581_138_830_084_19;
                let mut cols: [Vec<f64>; 5] = Default::default();
                let [t, w, kin, str_, dis] = &mut cols;
                fv.extend_uniform(
                    0.6,
                    n,
                    scale,
                    UniformColumns {
                        time: t,
                        displacement: w,
                        kinetic: kin,
                        strain: str_,
                        dissipated: dis,
                    },
                );
                let mut i = 0;
                fv.for_each_uniform(0.6, n, |s| {
                    assert_eq!(cols[0][i].to_bits(), s.time.to_bits(), "ζ={z} n={n} i={i}");
                    assert_eq!(cols[1][i].to_bits(), (scale * s.displacement).to_bits());
                    assert_eq!(
                        cols[2][i].to_bits(),
                        s.kinetic.to_bits(),
                        "ζ={z} n={n} i={i}"
                    );
                    assert_eq!(cols[3][i].to_bits(), s.strain.to_bits());
                    assert_eq!(cols[4][i].to_bits(), s.dissipated.to_bits(), "ζ={z} n={n}");
                    i += 1;
                });
                assert!(cols.iter().all(|c| c.len() == n), "ζ={z} n={n}");
            }
        }
    }

    /// P05/P06 mode-1 coefficients (1e-9).
    #[test]
    fn single_mode_coefficients() {
        let col = Column::default();
        let e = SingleMode::new(&col, ModeShapes::Exact, true).unwrap();
        assert!(rel(e.mass, 61.85689848982988) < 1e-12);
        assert!(rel(e.stiffness, 1947065540.6183121) < 1e-12);
        assert!(rel(e.damping, 1.31) < 1e-12);
        assert!(rel(e.midpoint_stiffness, 771968495.960556) < 1e-12);
        assert!(rel(e.midpoint_mass, 24.524894460827817) < 1e-12);
        let fv = e.free_vibration(1e-3);
        assert!(rel(fv.omega_n / (2.0 * PI), 892.9278048201711) < 1e-12);
        assert!(rel(fv.zeta, 1.8873695512596619e-06) < 1e-12);
        assert!(rel(fv.decay_rate(), 0.010588956381440478) < 1e-12);
        assert!(rel(fv.decay_time(0.01).unwrap(), 434.9031217145899) < 1e-12);
        let p = SingleMode::new(&col, ModeShapes::Paper, true).unwrap();
        assert!(rel(p.mass, 61.85737793542303) < 1e-12);
        assert!(rel(p.stiffness, 1947015218.4511666) < 1e-12);
        assert!(rel(p.damping, 1.31001128434) < 1e-12);
        assert!(rel(p.midpoint_mass, 24.52960250343533) < 1e-12);
        // ζ₁ = 0.02 → c = 10 597 N·s/m², t_1% = 0.0410 s (§B.6).
        let col2 = Column {
            damping: Damping::Ratio(0.02),
            ..Column::default()
        };
        let z = SingleMode::new(&col2, ModeShapes::Paper, true).unwrap();
        assert!((z.damping_coefficient - 10597.0).abs() < 1.0);
        let ze = SingleMode::new(&col2, ModeShapes::Exact, true).unwrap();
        assert!(rel(ze.free_vibration(1.0).zeta, 0.02) < 1e-14);
        assert!((ze.free_vibration(1.0).decay_time(0.01).unwrap() - 0.0410).abs() < 1e-4);
    }
}
