//! Cancellation and deadline handle polled by long-running solvers.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::Instant;

use super::error::PhysicsError;

/// Shared handle that a solver polls: set when the client disconnects or the time limit passes.
///
/// Cloning shares the same flag. Progress (`done` of `total` units) can be reported through it.
#[derive(Debug, Clone)]
pub struct Control {
    inner: Arc<Inner>,
}

#[derive(Debug)]
struct Inner {
    cancelled: AtomicBool,
    deadline: Option<Instant>,
    done: AtomicU64,
    total: AtomicU64,
}

impl Default for Control {
    fn default() -> Self {
        Self::unlimited()
    }
}

impl Control {
    /// A handle with no deadline that is never cancelled unless [`Control::cancel`] is called.
    #[must_use]
    pub fn unlimited() -> Self {
        Self::with_deadline(None)
    }

    /// A handle that reports a timeout once `deadline` has passed.
    #[must_use]
    pub fn with_deadline(deadline: Option<Instant>) -> Self {
        Self {
            inner: Arc::new(Inner {
                cancelled: AtomicBool::new(false),
                deadline,
                done: AtomicU64::new(0),
                total: AtomicU64::new(0),
            }),
        }
    }

    /// Asks the solver to stop at its next poll.
    pub fn cancel(&self) {
        self.inner.cancelled.store(true, Ordering::Relaxed);
    }

    /// True once [`Control::cancel`] has been called.
    #[must_use]
    pub fn is_cancelled(&self) -> bool {
        self.inner.cancelled.load(Ordering::Relaxed)
    }

    /// Returns an error when the work should stop: cancelled, or past the deadline.
    ///
    /// Solvers call this every few thousand steps; it costs an atomic load and, with a deadline,
    /// a clock read.
    pub fn check(&self) -> Result<(), PhysicsError> {
        if self.is_cancelled() {
            return Err(PhysicsError::Cancelled);
        }
        if let Some(d) = self.inner.deadline
            && Instant::now() >= d
        {
            return Err(PhysicsError::TimedOut);
        }
        Ok(())
    }

    /// Sets the total number of work units (for progress reports).
    pub fn set_total(&self, total: u64) {
        self.inner.total.store(total, Ordering::Relaxed);
    }

    /// Adds `n` finished work units.
    pub fn add_done(&self, n: u64) {
        self.inner.done.fetch_add(n, Ordering::Relaxed);
    }

    /// Progress so far as (done, total); total is 0 when the solver did not announce one.
    #[must_use]
    pub fn progress(&self) -> (u64, u64) {
        (
            self.inner.done.load(Ordering::Relaxed),
            self.inner.total.load(Ordering::Relaxed),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    #[test]
    fn cancel_is_seen_by_clones() {
        let c = Control::unlimited();
        let c2 = c.clone();
        assert!(c2.check().is_ok());
        c.cancel();
        assert!(matches!(c2.check(), Err(PhysicsError::Cancelled)));
    }

    #[test]
    fn deadline_in_the_past_times_out() {
        let c = Control::with_deadline(Some(Instant::now() - Duration::from_millis(1)));
        assert!(matches!(c.check(), Err(PhysicsError::TimedOut)));
    }

    #[test]
    fn progress_accumulates() {
        let c = Control::unlimited();
        c.set_total(10);
        c.add_done(3);
        c.add_done(4);
        assert_eq!(c.progress(), (7, 10));
    }
}
