//! Double-double arithmetic: an unevaluated sum hi + lo of two f64 carrying about 106 bits.
//!
//! Used where a quantity must be formed with ~1e-30 relative error before one rounding, e.g.
//! the energy parameter G of the log contact laws, whose 1 − G is taken before rounding near the
//! branch point (physics.md §A.5). Dekker's and Knuth's error-free transformations; no fused
//! multiply–add is assumed.

use std::f64::consts::PI;
use std::ops::{Add, Div, Mul, Neg};

/// A double-double number hi + lo with |lo| ≤ ½ulp(hi) (dimension of whatever it holds).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DoubleDouble {
    /// Leading part (the value rounded to f64).
    pub hi: f64,
    /// Trailing part.
    pub lo: f64,
}

/// s + e = a + b exactly (Knuth's two-sum, any magnitudes).
#[inline]
#[must_use]
pub fn two_sum(a: f64, b: f64) -> DoubleDouble {
    let s = a + b;
    let bb = s - a;
    DoubleDouble {
        hi: s,
        lo: (a - (s - bb)) + (b - bb),
    }
}

/// s + e = a + b exactly when |a| ≥ |b| (Dekker's fast two-sum).
#[inline]
#[must_use]
pub fn fast_two_sum(a: f64, b: f64) -> DoubleDouble {
    let s = a + b;
    DoubleDouble {
        hi: s,
        lo: b - (s - a),
    }
}

/// a = hi + lo with each half holding at most 26 significant bits (Dekker's split).
#[inline]
fn split(a: f64) -> (f64, f64) {
    let t = 134_217_729.0 * a; // 2^27 + 1 (Dekker)
    let hi = t - (t - a);
    (hi, a - hi)
}

/// p + e = a·b exactly (Dekker's two-product, barring overflow).
#[inline]
#[must_use]
pub fn two_prod(a: f64, b: f64) -> DoubleDouble {
    let p = a * b;
    let (ah, al) = split(a);
    let (bh, bl) = split(b);
    DoubleDouble {
        hi: p,
        lo: ((ah * bh - p) + ah * bl + al * bh) + al * bl,
    }
}

impl DoubleDouble {
    /// π to double-double precision.
    pub const PI: DoubleDouble = DoubleDouble {
        hi: PI,
        lo: 1.224_646_799_147_353_2e-16,
    };

    /// The exact f64 `x`.
    #[must_use]
    pub fn new(x: f64) -> Self {
        DoubleDouble { hi: x, lo: 0.0 }
    }

    /// The value rounded to f64.
    #[must_use]
    pub fn to_f64(self) -> f64 {
        self.hi + self.lo
    }
}

impl Mul for DoubleDouble {
    type Output = DoubleDouble;
    /// Product with another double-double.
    fn mul(self, o: DoubleDouble) -> DoubleDouble {
        let p = two_prod(self.hi, o.hi);
        fast_two_sum(p.hi, p.lo + (self.hi * o.lo + self.lo * o.hi))
    }
}

impl Mul<f64> for DoubleDouble {
    type Output = DoubleDouble;
    /// Product with an f64.
    fn mul(self, o: f64) -> DoubleDouble {
        self * DoubleDouble::new(o)
    }
}

impl Add for DoubleDouble {
    type Output = DoubleDouble;
    /// Sum with another double-double.
    fn add(self, o: DoubleDouble) -> DoubleDouble {
        let s = two_sum(self.hi, o.hi);
        fast_two_sum(s.hi, s.lo + self.lo + o.lo)
    }
}

impl Neg for DoubleDouble {
    type Output = DoubleDouble;
    /// Negation (exact).
    fn neg(self) -> DoubleDouble {
        DoubleDouble {
            hi: -self.hi,
            lo: -self.lo,
        }
    }
}

impl Div for DoubleDouble {
    type Output = DoubleDouble;
    /// Quotient by another double-double (three correction steps).
    fn div(self, o: DoubleDouble) -> DoubleDouble {
        let q1 = self.hi / o.hi;
        let r = self + -(o * q1);
        let q2 = r.hi / o.hi;
        let r = r + -(o * q2);
        let q3 = r.hi / o.hi;
        fast_two_sum(q1, q2) + DoubleDouble::new(q3)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn error_free_transformations_are_exact() {
        // 1 + 2⁻⁶⁰ is not an f64: the sum keeps the tail.
        let s = two_sum(1.0, 2f64.powi(-60));
        assert_eq!((s.hi, s.lo), (1.0, 2f64.powi(-60)));
        let f = fast_two_sum(1.0, 2f64.powi(-60));
        assert_eq!((f.hi, f.lo), (1.0, 2f64.powi(-60)));
        // (1 + 2⁻³⁰)² = 1 + 2⁻²⁹ + 2⁻⁶⁰: the product's tail is 2⁻⁶⁰.
        let a = 1.0 + 2f64.powi(-30);
        let p = two_prod(a, a);
        assert_eq!((p.hi, p.lo), (1.0 + 2f64.powi(-29), 2f64.powi(-60)));
    }

    #[test]
    fn one_third_times_three_is_one_to_double_double_precision() {
        let third = DoubleDouble::new(1.0) / DoubleDouble::new(3.0);
        let one = third * 3.0 + DoubleDouble::new(-1.0);
        assert!(one.to_f64().abs() < 1e-31, "{one:?}");
        assert_eq!(third.to_f64(), 1.0 / 3.0);
        assert_eq!((-third).to_f64(), -1.0 / 3.0);
    }

    #[test]
    fn pi_tail_is_the_next_digits() {
        // π − fl(π) = 1.2246467991473532e-16 (mpmath).
        let p = DoubleDouble::PI;
        assert_eq!(p.hi, PI);
        assert!((p.lo / 1.224_646_799_147_353_2e-16 - 1.0).abs() < 1e-15);
    }
}
