//! Effective modulus E* of the rock–column contact (physics.md §A.2): the paper's rock-only
//! convention and the two-body convention, in double-double and in plain f64.

use crate::physics::material::{Column, ModulusConvention, Rock};
use crate::physics::numeric::double_double::{DoubleDouble, two_prod};

/// 1 − ν² in double-double.
fn one_minus_sq(nu: f64) -> DoubleDouble {
    DoubleDouble::new(1.0) + -two_prod(nu, nu)
}

pub(super) fn effective_modulus_dd(
    rock: &Rock,
    column: &Column,
    convention: ModulusConvention,
) -> DoubleDouble {
    let rock_term = one_minus_sq(rock.poisson_ratio) / DoubleDouble::new(rock.elastic_modulus);
    match convention {
        ModulusConvention::Paper => DoubleDouble::new(1.0) / rock_term,
        ModulusConvention::TwoBody => {
            let col =
                one_minus_sq(column.poisson_ratio) / DoubleDouble::new(column.elastic_modulus);
            DoubleDouble::new(1.0) / (rock_term + col)
        }
    }
}

/// Effective modulus E* of the contact, Pa (physics.md §A.2).
///
/// `Paper`: E/(1 − ν²) of the rock only; `TwoBody`: 1/E* = (1 − ν²)/E + (1 − ν_s²)/E_s.
///
/// # Examples
/// ```
/// use gangue::physics::contact::effective_modulus;
/// use gangue::physics::material::{Column, ModulusConvention, Rock};
/// let e = effective_modulus(&Rock::default(), &Column::default(), ModulusConvention::TwoBody);
/// assert!((e / 5.299_557_487e9 - 1.0).abs() < 1e-9);
/// ```
///
/// # Special cases
/// * Evaluated in double-double and rounded once: correctly rounded in practice.
///
/// # References
/// physics.md §A.2 (Johnson's convention; E′ = 2E* is not used).
#[must_use]
pub fn effective_modulus(rock: &Rock, column: &Column, convention: ModulusConvention) -> f64 {
    effective_modulus_dd(rock, column, convention).to_f64()
}

/// E* in plain f64 (within a few ulp of [`effective_modulus`]).
pub(super) fn effective_modulus_f64(
    rock: &Rock,
    column: &Column,
    convention: ModulusConvention,
) -> f64 {
    let nu = rock.poisson_ratio;
    let rock_term = (1.0 - nu * nu) / rock.elastic_modulus;
    match convention {
        ModulusConvention::Paper => rock.elastic_modulus / (1.0 - nu * nu),
        ModulusConvention::TwoBody => {
            let nus = column.poisson_ratio;
            1.0 / (rock_term + (1.0 - nus * nus) / column.elastic_modulus)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn both_conventions_match_their_closed_forms() {
        let (rock, column) = (Rock::default(), Column::default());
        // Paper: E/(1 − ν²) = 5e9/0.9216 (P01: 5 425 347 222.222 222 Pa).
        let paper = effective_modulus(&rock, &column, ModulusConvention::Paper);
        assert!((paper / 5_425_347_222.222_222 - 1.0).abs() < 1e-15);
        // Two-body: 1/E* = 0.9216/5e9 + 0.91/208e9.
        let two_body = effective_modulus(&rock, &column, ModulusConvention::TwoBody);
        let expected = 1.0 / (0.9216 / 5e9 + 0.91 / 208e9);
        assert!((two_body / expected - 1.0).abs() < 1e-15);
        // The f64 path agrees with the double-double one to a few ulp.
        for convention in [ModulusConvention::Paper, ModulusConvention::TwoBody] {
            let a = effective_modulus(&rock, &column, convention);
            let b = effective_modulus_f64(&rock, &column, convention);
            assert!((a / b - 1.0).abs() < 4.0 * f64::EPSILON, "{convention:?}");
        }
    }
}
