//! Request and response types of the API (serde + utoipa schemas), their range checks, and the
//! conversions into the plain physics structs.

pub mod batch;
pub mod calibrate;
pub mod column;
pub mod common;
pub mod design_search;
pub mod design_values;
pub mod devices;
pub mod floor;
pub mod impact;
pub mod maps;
pub mod migration;
pub mod param;
pub mod protection;
pub mod scene;
pub mod spalling;
pub mod study;
pub mod target;
pub mod zones;

pub use common::{Meta, PlanStep, Warning};
