//! The calculation layer: one interface over physics types for every endpoint.
//!
//! A calculation takes a physics case and a [`Control`] and returns a [`Report`]: the result,
//! the stages of its plan (ran or skipped, and why) and its named warnings. Ensembles (the
//! Monte Carlo runs of a migration or a scene) are also split into items: [`Ensemble::items`]
//! counts them, [`Ensemble::part`] computes a range of them, and each calculation's `merge`
//! turns the records of all parts (in memory or read back from part files) into the report.
//! Callers — the HTTP routes, batch items, shards and the command line, the benches — call
//! this layer, never a route; nothing here knows about requests, JSON or HTTP.

pub mod calibrate;
pub mod column;
pub mod impact;
pub mod migration;
pub mod scene;
pub mod spalling;
pub mod study;

use crate::physics::Control;
pub use crate::physics::plan::Stage;
pub use crate::physics::validity::Warning;

/// What a calculation answers: its result, its plan and its warnings.
#[derive(Debug, Clone, PartialEq)]
pub struct Report<R> {
    /// The result in physics terms (SI units).
    pub result: R,
    /// The stages run or skipped, in order.
    pub plan: Vec<Stage>,
    /// Named warnings about the result, in order.
    pub warnings: Vec<Warning>,
}

/// One calculation: a case in, a report out.
pub trait Calculation {
    /// The physics case.
    type Case;
    /// The result of the report.
    type Result;
    /// The error of a failed calculation.
    type Error;

    /// Solves `case`, polling `control` for cancellation and the deadline.
    ///
    /// # Errors
    /// The calculation's own (invalid input found by physics, capacity, time limit, …).
    fn solve(case: &Self::Case, control: &Control) -> Result<Report<Self::Result>, Self::Error>;
}

/// A calculation over work items with global indices 0..N (any split gives the same items).
pub trait Ensemble: Calculation {
    /// The records of a range of items.
    type Part;

    /// The number of items of `case` (0: no ensemble).
    fn items(case: &Self::Case) -> u64;

    /// The items of `case` with global indices in `range`, in index order.
    ///
    /// # Errors
    /// As [`Calculation::solve`], the first error in index order.
    fn part(
        case: &Self::Case,
        range: std::ops::Range<u64>,
        control: &Control,
    ) -> Result<Self::Part, Self::Error>;
}
