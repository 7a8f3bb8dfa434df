//! One file per endpoint family; handlers are thin: validate → solve on the blocking pool →
//! serialize.

pub mod impact;
pub mod meta;
