//! Seeded Monte Carlo ensembles: distributions, one random stream per run, parallel runs reduced
//! in run order.
//!
//! **Generator.** Run i of seed s draws from its own PCG-64 stream (`rand_pcg::Pcg64`, O'Neill's
//! XSL-RR 128/64 LCG). Its 128-bit state and its stream constant are the first three outputs of a
//! SplitMix64 generator started at s ⊕ (i · 0x9E3779B97F4A7C15): state = (z₁ ≪ 64) | z₂,
//! stream = z₃. A uniform deviate is (next_u64 ≫ 11)·2⁻⁵³ ∈ [0, 1); a normal deviate comes from
//! Marsaglia's polar method (one deviate per accepted pair, the second discarded so that a draw
//! never depends on an earlier one). Friction is drawn first (once per run), then e_n and e_t at
//! each impact. Because the stream depends only on (seed, run index) and the results are
//! collected in run order, an ensemble gives the same bits on any number of threads.

use rand::RngCore;
use rand_pcg::Pcg64;

/// A probability distribution for an uncertain input.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Distribution {
    /// Uniform on [min, max].
    Uniform {
        /// Lower bound.
        min: f64,
        /// Upper bound.
        max: f64,
    },
    /// Normal with the given mean and standard deviation.
    Normal {
        /// Mean.
        mean: f64,
        /// Standard deviation (≥ 0).
        std: f64,
    },
    /// Normal restricted to [min, max] by resampling until inside.
    TruncatedNormal {
        /// Mean of the parent normal.
        mean: f64,
        /// Standard deviation of the parent normal (≥ 0).
        std: f64,
        /// Lower bound.
        min: f64,
        /// Upper bound.
        max: f64,
    },
}

impl Distribution {
    /// Smallest value the distribution can give (−∞ for the normal).
    #[must_use]
    pub fn lower_bound(&self) -> f64 {
        match *self {
            Distribution::Uniform { min, .. } | Distribution::TruncatedNormal { min, .. } => min,
            Distribution::Normal { std: 0.0, mean } => mean,
            Distribution::Normal { .. } => f64::NEG_INFINITY,
        }
    }
}

/// SplitMix64 step (Steele, Lea & Flood 2014), as in physics.md §C.2.
pub fn splitmix64(state: &mut u64) -> u64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The random stream of run `index` of an ensemble with `seed`.
#[must_use]
pub fn run_stream(seed: u64, index: u64) -> Pcg64 {
    let mut sm = seed ^ index.wrapping_mul(0x9E37_79B9_7F4A_7C15);
    let hi = splitmix64(&mut sm) as u128;
    let lo = splitmix64(&mut sm) as u128;
    let stream = splitmix64(&mut sm) as u128;
    Pcg64::new((hi << 64) | lo, stream)
}

/// Constant that separates a run's release stream from its stream of friction and
/// restitution draws ([`release_stream`]).
const RELEASE_STREAM: u64 = 0x5245_4C45_4153_4521;

/// The stream of run `index`'s release draws (velocity, then orientation): [`run_stream`] of
/// seed ⊕ 0x52454C4541534521, so that drawing the release leaves the run's friction and
/// restitution draws as they were (the same impacts draw the same e_n, e_t).
#[must_use]
pub fn release_stream(seed: u64, index: u64) -> Pcg64 {
    run_stream(seed ^ RELEASE_STREAM, index)
}

/// A uniformly random rotation as a unit quaternion [w, x, y, z] (Shoemake 1992: u₁, u₂, u₃
/// uniform, q = (√(1−u₁) sin 2πu₂, √(1−u₁) cos 2πu₂, √u₁ sin 2πu₃, √u₁ cos 2πu₃) as
/// [x, y, z, w]).
pub fn uniform_rotation(rng: &mut Pcg64) -> [f64; 4] {
    let (u1, u2, u3) = (uniform01(rng), uniform01(rng), uniform01(rng));
    let tau = 2.0 * std::f64::consts::PI;
    let (a, b) = ((1.0 - u1).sqrt(), u1.sqrt());
    let (s2, c2) = (tau * u2).sin_cos();
    let (s3, c3) = (tau * u3).sin_cos();
    [b * c3, a * s2, a * c2, b * s3]
}

/// The release of run `index` of `mc`: `release` with its velocity and orientation drawn
/// when the ensemble varies them (None: it does not, and `release` holds for every run).
#[must_use]
pub fn drawn_release(
    mc: &super::MonteCarlo,
    index: u64,
    release: &super::Release,
) -> Option<super::Release> {
    if mc.release_velocity.is_none() && !mc.random_orientation {
        return None;
    }
    let mut rng = release_stream(mc.seed, index);
    let mut r = *release;
    if let Some(ds) = &mc.release_velocity {
        r.velocity = Some(ds.map(|d| sample(&d, &mut rng)));
        r.speed = 0.0;
    }
    if mc.random_orientation {
        r.orientation = Some(uniform_rotation(&mut rng));
    }
    Some(r)
}

/// Uniform deviate in [0, 1) with 53 random bits.
pub fn uniform01(rng: &mut Pcg64) -> f64 {
    (rng.next_u64() >> 11) as f64 * (1.0 / 9_007_199_254_740_992.0)
}

fn standard_normal(rng: &mut Pcg64) -> f64 {
    loop {
        let u = 2.0 * uniform01(rng) - 1.0;
        let v = 2.0 * uniform01(rng) - 1.0;
        let s = u * u + v * v;
        if s > 0.0 && s < 1.0 {
            return u * (-2.0 * s.ln() / s).sqrt();
        }
    }
}

/// Draws one value of `d` from `rng`.
///
/// # Special cases
/// A truncated normal whose window holds almost no probability (more than 10 000 rejections)
/// returns a uniform draw on [min, max] instead of looping for ever.
#[inline]
pub fn sample(d: &Distribution, rng: &mut Pcg64) -> f64 {
    match *d {
        // the uniform draw (the default restitution's, two per impact) in line
        Distribution::Uniform { min, max } => min + (max - min) * uniform01(rng),
        _ => sample_normal(d, rng),
    }
}

/// [`sample`] of a normal or truncated normal distribution (out of line).
#[inline(never)]
fn sample_normal(d: &Distribution, rng: &mut Pcg64) -> f64 {
    match *d {
        Distribution::Uniform { min, max } => min + (max - min) * uniform01(rng),
        Distribution::Normal { mean, std } => mean + std * standard_normal(rng),
        Distribution::TruncatedNormal {
            mean,
            std,
            min,
            max,
        } => {
            for _ in 0..10_000 {
                let x = mean + std * standard_normal(rng);
                if (min..=max).contains(&x) {
                    return x;
                }
            }
            min + (max - min) * uniform01(rng)
        }
    }
}

#[cfg(test)]
mod tests {
    /// Uniform rotations turn a fixed axis to a uniform direction: over 40 000 draws each
    /// component of the turned z axis has mean 0 and mean square 1/3 within 4.5 standard errors
    /// (a component u of a uniform direction is uniform on [−1, 1]: var u = 1/3, var u² = 4/45), and
    /// every quaternion is a unit one.
    #[test]
    fn uniform_rotations_turn_an_axis_to_a_uniform_direction() {
        let n = 40_000;
        let mut rng = release_stream(9, 0);
        let (mut m1, mut m2) = ([0.0; 3], [0.0; 3]);
        for _ in 0..n {
            let [w, x, y, z] = uniform_rotation(&mut rng);
            assert!((w * w + x * x + y * y + z * z - 1.0).abs() < 1e-12);
            // the z axis turned by q: third column of its rotation matrix
            let col = [
                2.0 * (x * z + w * y),
                2.0 * (y * z - w * x),
                1.0 - 2.0 * (x * x + y * y),
            ];
            for k in 0..3 {
                m1[k] += col[k] / f64::from(n);
                m2[k] += col[k] * col[k] / f64::from(n);
            }
        }
        let se1 = (1.0 / (3.0 * f64::from(n))).sqrt();
        let se2 = (4.0 / (45.0 * f64::from(n))).sqrt();
        for k in 0..3 {
            assert!(m1[k].abs() < 4.5 * se1, "{m1:?}");
            assert!((m2[k] - 1.0 / 3.0).abs() < 4.5 * se2, "{m2:?}");
        }
    }

    use super::*;

    #[test]
    fn splitmix_matches_reference_sequence() {
        // physics.md §C.2 SplitMix64 from state 0: first output 0xE220A8397B1DCDAF
        let mut s = 0u64;
        assert_eq!(splitmix64(&mut s), 0xE220_A839_7B1D_CDAF);
    }

    #[test]
    fn streams_differ_by_index_and_repeat_by_seed() {
        let a = run_stream(42, 0).next_u64();
        let b = run_stream(42, 1).next_u64();
        assert_ne!(a, b);
        assert_eq!(a, run_stream(42, 0).next_u64());
    }

    #[test]
    fn distributions_have_their_moments() {
        let mut rng = run_stream(1, 2);
        let n = 200_000;
        for (d, m, sd) in [
            (
                Distribution::Uniform { min: 0.2, max: 0.4 },
                0.3,
                0.2 / 12f64.sqrt(),
            ),
            (
                Distribution::Normal {
                    mean: 1.0,
                    std: 0.5,
                },
                1.0,
                0.5,
            ),
        ] {
            let xs: Vec<f64> = (0..n).map(|_| sample(&d, &mut rng)).collect();
            let mean = xs.iter().sum::<f64>() / n as f64;
            let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
            // 5 standard errors
            assert!((mean - m).abs() < 5.0 * sd / (n as f64).sqrt(), "{mean}");
            assert!(
                (var.sqrt() - sd).abs() < 5.0 * sd / (2.0 * n as f64).sqrt(),
                "{var}"
            );
        }
        let d = Distribution::TruncatedNormal {
            mean: 0.2,
            std: 0.02,
            min: 0.19,
            max: 0.25,
        };
        assert!((0..10_000).all(|_| (0.19..=0.25).contains(&sample(&d, &mut rng))));
    }
}
