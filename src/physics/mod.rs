//! Pure, synchronous numerics: contact, column dynamics, migration, studies.
//!
//! Nothing in here knows about HTTP, JSON or async runtimes. Every solver takes plain parameter
//! structs (SI units) and a [`Control`] handle it polls for cancellation and deadlines.

pub mod beam;
pub mod column;
pub mod contact;
pub mod control;
pub mod coupled;
pub mod design;
pub mod error;
pub mod material;
pub mod migration;
pub mod numeric;
pub mod plan;
pub mod scene;
pub mod spalling;
pub mod stats;
pub mod study;
pub mod validity;

pub use control::Control;
pub use error::{Param, PhysicsError, PhysicsResult};
