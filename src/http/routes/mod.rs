//! One file per endpoint family; handlers are thin: validate → solve on the blocking pool →
//! serialize.

pub mod batch;
pub mod calibrate;
pub mod column;
pub mod impact;
pub mod meta;
pub mod migration;
pub mod scene;
pub mod spalling;
pub mod study;
