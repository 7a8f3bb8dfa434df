//! gangue: flying-gangue (rockfall) hazard calculations for longwall faces in steeply dipping
//! coal seams — migration down the face, Hertz impact on a support column, column energy.
//!
//! [`physics`] holds the pure numerics; [`http`] the REST service; [`config`] its settings;
//! [`shard`] sharded computations merged into the service's answer.

pub mod config;
pub mod http;
pub mod physics;
pub mod shard;

pub use http::app;
