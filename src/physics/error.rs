//! Errors a solver can return; the web layer maps each to a problem type.

use std::fmt;

/// Result of a physics computation.
pub type PhysicsResult<T> = Result<T, PhysicsError>;

/// Why a computation produced no answer.
#[derive(Debug, Clone, PartialEq)]
pub enum PhysicsError {
    /// An input outside the model's validity; `field` is a JSON Pointer into the request
    /// (e.g. `/face/friction_coefficient`), `value` the offending value.
    InvalidInput {
        /// JSON Pointer of the offending request field.
        field: String,
        /// The offending value.
        value: f64,
        /// What is wrong and what would be valid.
        message: String,
    },
    /// The impact energy exceeds what the logarithmic contact law can store (G > 1).
    CapacityExceeded {
        /// Dimensionless energy parameter G of the case (> 1).
        energy_parameter: f64,
        /// Largest impact speed the law can take with the other inputs unchanged, m/s.
        max_velocity_m_s: f64,
        /// What happened.
        message: String,
    },
    /// A stepping solver would need more steps than the configured limit.
    TooManySteps {
        /// Estimated number of steps.
        estimated: f64,
        /// The limit in force.
        limit: f64,
    },
    /// The caller cancelled the computation (client gone).
    Cancelled,
    /// The computation passed its time limit.
    TimedOut,
    /// A numerical failure that valid input should never reach (a bug).
    Numerical(String),
}

impl PhysicsError {
    /// Shorthand for [`PhysicsError::InvalidInput`].
    pub fn invalid(field: impl Into<String>, value: f64, message: impl Into<String>) -> Self {
        Self::InvalidInput {
            field: field.into(),
            value,
            message: message.into(),
        }
    }
}

impl fmt::Display for PhysicsError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::InvalidInput {
                field,
                value,
                message,
            } => write!(f, "{field} = {value}: {message}"),
            Self::CapacityExceeded { message, .. } => f.write_str(message),
            Self::TooManySteps { estimated, limit } => {
                write!(f, "about {estimated:.3e} steps needed, limit {limit:.3e}")
            }
            Self::Cancelled => f.write_str("cancelled"),
            Self::TimedOut => f.write_str("time limit reached"),
            Self::Numerical(m) => write!(f, "numerical failure: {m}"),
        }
    }
}

impl std::error::Error for PhysicsError {}

/// `x` with `digits` significant digits for a message a person reads: plain decimals for
/// 1e-4 ≤ |x| < 1e7 (0.05454154, 2.335413), scientific notation beyond (1.234568e-9).
pub fn significant(x: f64, digits: usize) -> String {
    let digits = digits.max(1);
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let e = x.abs().log10().floor();
    if (-4.0..7.0).contains(&e) {
        let decimals = (digits as f64 - 1.0 - e).max(0.0) as usize;
        format!("{x:.decimals$}")
    } else {
        let p = digits - 1;
        format!("{x:.p$e}")
    }
}

#[cfg(test)]
mod tests {
    use super::significant;

    #[test]
    fn messages_show_plain_decimals_in_the_everyday_range() {
        assert_eq!(significant(0.05454154012, 7), "0.05454154");
        assert_eq!(significant(2.3354127, 7), "2.335413");
        assert_eq!(significant(995_000.0, 3), "995000");
        assert_eq!(significant(-12.5, 3), "-12.5");
        assert_eq!(significant(1.2345678e-9, 7), "1.234568e-9");
        assert_eq!(significant(3.0e12, 2), "3.0e12");
        assert_eq!(significant(0.0, 7), "0");
    }
}
