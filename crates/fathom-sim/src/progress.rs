//! A progress hook for Monte Carlo work: the library reports, a binary draws.
//!
//! Library crates never print (see ARCHITECTURE.md). Long Monte Carlo batches instead
//! report [`ProgressEvent`]s to an optional [`Progress`] hook carried by the
//! [`Job`](crate::experiment::Job); the `fathom` binary implements it
//! with a progress bar on a terminal. The hook only observes: it receives no RNG, no
//! result and cannot change the order of the runs, so results are bit-identical with
//! or without it, whatever the thread count.
//!
//! Events of one batch, in order: one [`ProgressEvent::BatchStarted`], then one
//! [`ProgressEvent::RunFinished`] per run (in completion order, from whichever worker
//! thread ran it, so the hook must be `Send + Sync`), then one
//! [`ProgressEvent::BatchFinished`]. Batches of one experiment run one after another.
//!
//! ```
//! use std::sync::Arc;
//! use std::sync::atomic::{AtomicUsize, Ordering};
//! use fathom_sim::montecarlo::run_monte_carlo_with_progress;
//! use fathom_sim::progress::{Progress, ProgressEvent};
//!
//! let done = Arc::new(AtomicUsize::new(0));
//! let counter = Arc::clone(&done);
//! let hook = Progress::new(move |e| {
//!     if let ProgressEvent::RunFinished { .. } = e {
//!         counter.fetch_add(1, Ordering::Relaxed);
//!     }
//! });
//! let v: Vec<usize> = run_monte_carlo_with_progress(10, 1, Some(2), Some(&hook), "demo", |i, _| i);
//! assert_eq!(v.len(), 10);
//! assert_eq!(done.load(Ordering::Relaxed), 10);
//! ```

use std::fmt;
use std::sync::Arc;

/// What a [`Progress`] hook is told.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ProgressEvent {
    /// A Monte Carlo batch starts.
    BatchStarted {
        /// What the batch computes (e.g. `beacons`, `fusion: sensitivity ...`).
        label: String,
        /// Number of runs in the batch.
        total: usize,
    },
    /// One run of the current batch finished (successfully or not).
    RunFinished {
        /// Index of the run within its batch.
        index: usize,
    },
    /// Every run of the batch finished.
    BatchFinished {
        /// The batch's label, as in [`ProgressEvent::BatchStarted`].
        label: String,
    },
}

/// A thread-safe progress hook (a shared callback); cheap to clone.
#[derive(Clone)]
pub struct Progress(Arc<dyn Fn(ProgressEvent) + Send + Sync>);

impl Progress {
    /// A hook calling `f` for every event.
    pub fn new(f: impl Fn(ProgressEvent) + Send + Sync + 'static) -> Self {
        Self(Arc::new(f))
    }

    /// Reports `event` to the hook.
    pub fn report(&self, event: ProgressEvent) {
        (self.0)(event);
    }
}

impl fmt::Debug for Progress {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("Progress(..)")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Mutex;

    #[test]
    fn reports_to_the_callback_and_clones_share_it() {
        let seen = Arc::new(Mutex::new(Vec::new()));
        let sink = Arc::clone(&seen);
        let p = Progress::new(move |e| sink.lock().unwrap().push(e));
        let q = p.clone();
        p.report(ProgressEvent::BatchStarted {
            label: "a".into(),
            total: 2,
        });
        q.report(ProgressEvent::RunFinished { index: 1 });
        assert_eq!(seen.lock().unwrap().len(), 2);
        assert_eq!(format!("{p:?}"), "Progress(..)");
    }
}
