//! Cancellation and deadline handle polled by long-running solvers.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::Instant;

use super::error::{PACE_FACTOR, Param, PhysicsError};

/// Time an ensemble runs before its pace is judged ([`Control::check_pace`]), s.
pub const PACE_MIN_S: f64 = 1.0;

/// Shared handle that a solver polls: set when the client disconnects or the time limit passes.
///
/// Cloning shares the same flag. Progress (`done` of `total` units) can be reported through it.
#[derive(Debug, Clone)]
pub struct Control {
    inner: Arc<Inner>,
}

#[derive(Debug)]
struct Inner {
    started: Instant,
    cancelled: AtomicBool,
    /// Why the work was refused, once [`Control::check_pace`] refused it (it also cancels).
    refused: std::sync::OnceLock<PhysicsError>,
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
                started: Instant::now(),
                refused: std::sync::OnceLock::new(),
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

    /// Refuses work that cannot finish in time: with a deadline, once at least [`PACE_MIN_S`]
    /// have passed and some of the announced total is done, the run time projected at the pace
    /// so far (elapsed × total / done) is compared with the time the limit allows (deadline −
    /// start); past [`PACE_FACTOR`] times it, an `InvalidInput` on the ensemble's runs (the
    /// total) that states the projection, the limit and the ways to run it anyway.
    pub fn check_pace(&self) -> Result<(), PhysicsError> {
        let Some(deadline) = self.inner.deadline else {
            return Ok(());
        };
        let (done, total) = self.progress();
        let elapsed = self.inner.started.elapsed().as_secs_f64();
        if done == 0 || done >= total || elapsed < PACE_MIN_S {
            return Ok(());
        }
        let limit = deadline
            .saturating_duration_since(self.inner.started)
            .as_secs_f64();
        let projected = elapsed * total as f64 / done as f64;
        if projected > PACE_FACTOR * limit {
            let e = PhysicsError::invalid(
                Param::MonteCarloRuns,
                total as f64,
                format!(
                    "{total} runs would take about {projected:.0} s at the pace of the first \
                     {done} ({elapsed:.1} s), more than {PACE_FACTOR} times this server's time \
                     limit of {limit:.0} s: ask for fewer runs (or a monte_carlo.target), or run \
                     it anyway split into shards with `gangue compute` and `gangue merge` \
                     (README \"Beyond one machine\") or on a server with a longer \
                     --compute-timeout-s"
                ),
            );
            // every other part of the work stops at its next poll, with this reason
            let e = self.inner.refused.get_or_init(|| e).clone();
            self.cancel();
            return Err(e);
        }
        Ok(())
    }

    /// Returns an error when the work should stop: cancelled, or past the deadline.
    ///
    /// Solvers call this every few thousand steps; it costs an atomic load and, with a deadline,
    /// a clock read.
    pub fn check(&self) -> Result<(), PhysicsError> {
        if self.is_cancelled() {
            return Err(self
                .inner
                .refused
                .get()
                .cloned()
                .unwrap_or(PhysicsError::Cancelled));
        }
        if let Some(d) = self.inner.deadline
            && Instant::now() >= d
        {
            return Err(PhysicsError::TimedOut);
        }
        Ok(())
    }

    /// Announces `more` work units after those done so far: the total becomes done + `more`
    /// (an ensemble run in parts on one handle, e.g. the prefixes of a target).
    pub fn announce(&self, more: u64) {
        let (done, _) = self.progress();
        self.set_total(done.saturating_add(more));
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
