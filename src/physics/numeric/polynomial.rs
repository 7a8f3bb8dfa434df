//! Real roots of polynomials given by their ascending coefficients: Horner evaluation, the
//! roots in an interval isolated between the roots of the derivative and bisected, and the first
//! point where a polynomial is ≤ 0 (a rock's height over a plane along a closed-form flight).

/// The polynomial `c` (ascending coefficients) at `t`, by Horner's rule.
pub(crate) fn poly_eval(c: &[f64], t: f64) -> f64 {
    c.iter().rev().fold(0.0, |acc, &x| acc * t + x)
}

/// Coefficients (ascending) of the derivative of the polynomial `c`.
fn derivative(c: &[f64]) -> Vec<f64> {
    c.iter()
        .enumerate()
        .skip(1)
        .map(|(i, &x)| x * i as f64)
        .collect()
}

/// Real roots of the polynomial `c` (ascending coefficients) in (lo, hi), sorted, found by
/// isolating them between the roots of its derivative (monotone pieces) and bisecting.
pub(crate) fn poly_roots(c: &[f64], lo: f64, hi: f64) -> Vec<f64> {
    if c.len() < 2 {
        return Vec::new();
    }
    let d = derivative(c);
    let mut pts = vec![lo];
    pts.extend(poly_roots(&d, lo, hi));
    pts.push(hi);
    let mut out = Vec::new();
    for w in pts.windows(2) {
        let (a, b) = (w[0], w[1]);
        let (fa, fb) = (poly_eval(c, a), poly_eval(c, b));
        if fa == 0.0 && a > lo {
            out.push(a);
        } else if (fa < 0.0) != (fb < 0.0) && fb != 0.0 {
            out.push(bisect(c, a, b, fa));
        }
    }
    out
}

/// Bisection on a monotone piece [a, b] with f(a) of sign `fa`: the smallest point found where
/// the sign has changed.
pub(crate) fn bisect(c: &[f64], mut a: f64, mut b: f64, fa: f64) -> f64 {
    for _ in 0..200 {
        let m = 0.5 * (a + b);
        if m <= a || m >= b {
            break;
        }
        let fm = poly_eval(c, m);
        if (fm < 0.0) == (fa < 0.0) && fm != 0.0 {
            a = m;
        } else {
            b = m;
        }
    }
    b
}

/// First τ in [0, t1] where the polynomial `c` is ≤ 0, if any.
pub(crate) fn first_root_nonpositive(c: &[f64], t1: f64) -> Option<f64> {
    if poly_eval(c, 0.0) <= 0.0 {
        return Some(0.0);
    }
    if t1.is_nan() || t1 <= 0.0 {
        return None;
    }
    let d = derivative(c);
    let mut pts = vec![0.0];
    pts.extend(poly_roots(&d, 0.0, t1));
    pts.push(t1);
    for w in pts.windows(2) {
        let (a, b) = (w[0], w[1]);
        if poly_eval(c, b) <= 0.0 {
            return Some(bisect(c, a, b, poly_eval(c, a)));
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_roots_of_a_cubic_are_found_in_order() {
        // (t − 1)(t − 2)(t − 3) = −6 + 11t − 6t² + t³
        let c = [-6.0, 11.0, -6.0, 1.0];
        let r = poly_roots(&c, 0.0, 4.0);
        assert_eq!(r.len(), 3, "{r:?}");
        for (x, want) in r.iter().zip([1.0, 2.0, 3.0]) {
            assert!((x - want).abs() <= 1e-12, "{r:?}");
        }
        assert!(poly_roots(&c, 1.5, 1.9).is_empty());
    }

    #[test]
    fn the_first_nonpositive_point_of_a_falling_height() {
        // h(τ) = 2 + τ − 5τ²: positive at 0, zero at τ = (1 + √41)/10
        let c = [2.0, 1.0, -5.0];
        let t = first_root_nonpositive(&c, 10.0).unwrap();
        assert!((t - (1.0 + 41f64.sqrt()) / 10.0).abs() <= 1e-12, "{t}");
        assert!(poly_eval(&c, t) <= 0.0);
        assert_eq!(first_root_nonpositive(&c, 0.5), None);
        assert_eq!(first_root_nonpositive(&[-1.0, 1.0], 3.0), Some(0.0));
    }
}
