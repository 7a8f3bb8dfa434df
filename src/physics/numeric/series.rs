//! Evaluation of fitted series: Chebyshev sums (Clenshaw) and power series (Horner).

/// Σ cₖ Tₖ(x) for x ∈ [−1, 1] by Clenshaw's recurrence (`c` non-empty).
#[inline]
#[must_use]
pub fn chebyshev(c: &[f64], x: f64) -> f64 {
    let (mut b1, mut b2) = (0.0, 0.0);
    for &coefficient in c[1..].iter().rev() {
        let b0 = 2.0 * x * b1 - b2 + coefficient;
        b2 = b1;
        b1 = b0;
    }
    x * b1 - b2 + c[0]
}

/// Σ cₖ xᵏ by Horner's rule (0 for an empty `c`).
#[inline]
#[must_use]
pub fn horner(c: &[f64], x: f64) -> f64 {
    c.iter()
        .rev()
        .fold(0.0, |acc, &coefficient| acc * x + coefficient)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chebyshev_matches_the_cosine_definition() {
        // Tₖ(cos θ) = cos kθ.
        let c = [0.5, -1.25, 0.75, 2.0, -0.125];
        for &theta in &[0.0, 0.3, 1.1, 2.0, std::f64::consts::PI] {
            let x: f64 = f64::cos(theta);
            let direct: f64 = c
                .iter()
                .enumerate()
                .map(|(k, ck)| ck * (k as f64 * theta).cos())
                .sum();
            assert!((chebyshev(&c, x) - direct).abs() < 1e-14, "{theta}");
        }
        assert_eq!(chebyshev(&[3.0], 0.7), 3.0);
    }

    #[test]
    fn horner_matches_powers() {
        let c = [1.0, -2.0, 0.5, 3.0];
        let x = 1.7f64;
        let direct = 1.0 - 2.0 * x + 0.5 * x * x + 3.0 * x * x * x;
        assert!((horner(&c, x) - direct).abs() < 1e-13);
        assert_eq!(horner(&[], x), 0.0);
    }
}
