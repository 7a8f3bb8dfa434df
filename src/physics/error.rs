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
