//! gangue: flying-gangue (rockfall) hazard calculations for longwall faces in steeply dipping
//! coal seams — migration down the face, Hertz impact on a support column, column energy.
//!
//! [`physics`] holds the pure numerics; [`calc`] one calculation interface over physics types per
//! endpoint; [`http`] the REST service; [`config`] its settings;
//! [`shard`] sharded computations merged into the service's answer.

// No `unwrap`, `expect` or `panic!` outside tests: a request must never panic the service, and
// an invariant that cannot fail is a typed error or a restructuring (Cargo.toml holds the rest of
// the lint set; these three are here, and in main.rs, so that `#[cfg(test)]` modules, integration
// tests and benches unwrap freely).
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

pub mod calc;
pub mod config;
pub mod http;
pub mod physics;
pub mod shard;

pub use http::app;

/// The memory allocator of the service, its tests and its benches: mimalloc keeps freed pages
/// mapped for reuse, where the system allocator returns them and every large answer (a sampled
/// history, a trajectory, a CSV) pays for zero-filling fresh pages again (BENCHMARKS.md).
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;
