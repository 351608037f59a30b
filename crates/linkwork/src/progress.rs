//! Where a run is, and a request to stop it: shared by the thread that runs an analysis and a
//! thread that watches it (a progress bar, Ctrl-C).
//!
//! A run is given both in its [`RunOptions`](crate::RunOptions): the analysis reports every
//! output time and every step attempt of an integrator to its [`Progress`], and at each of them
//! reads its [`StopToken`]; once the token is stopped, the run ends there with
//! [`Error::Interrupted`](crate::Error::Interrupted), and the results up to there are kept as
//! after any failure. A sweep gives every variant's run the sweep's token, and counts the
//! variants finished in its own [`Progress`].
//!
//! The cost is an atomic store and load per output point and step: nothing beside a step's
//! factorization.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;

/// The state of one run as a watcher sees it.
#[derive(Debug, Default)]
pub struct Progress {
    /// The last time reached, s (`f64` bits).
    time: AtomicU64,
    /// The analysis's start and end times, s (`f64` bits).
    start: AtomicU64,
    end: AtomicU64,
    /// Output points and step attempts so far.
    steps: AtomicU64,
    /// Parts finished: the variants of a sweep.
    finished: AtomicU64,
}

impl Progress {
    /// A run not started: at time 0 of the span `[0, 0]`.
    pub fn new() -> Arc<Progress> {
        Arc::new(Progress::default())
    }

    /// Parts finished so far (the variants of a sweep).
    pub fn finished(&self) -> u64 {
        self.finished.load(Ordering::Relaxed)
    }

    /// One more part is finished.
    pub(crate) fn finish_part(&self) {
        self.finished.fetch_add(1, Ordering::Relaxed);
    }

    /// The last time the run reached (an output time or a step attempt), s.
    pub fn time(&self) -> f64 {
        f64::from_bits(self.time.load(Ordering::Relaxed))
    }

    /// The analysis's start and end times, s, once the run has started.
    pub fn span(&self) -> (f64, f64) {
        (f64::from_bits(self.start.load(Ordering::Relaxed)), f64::from_bits(self.end.load(Ordering::Relaxed)))
    }

    /// Output points and step attempts so far.
    pub fn steps(&self) -> u64 {
        self.steps.load(Ordering::Relaxed)
    }

    /// The run covers `[start, end]` and is at `start`.
    pub(crate) fn begin(&self, start: f64, end: f64) {
        self.start.store(start.to_bits(), Ordering::Relaxed);
        self.end.store(end.to_bits(), Ordering::Relaxed);
        self.time.store(start.to_bits(), Ordering::Relaxed);
    }

    /// The run reached time `t` (an output time or a step attempt).
    pub(crate) fn reached(&self, t: f64) {
        self.time.store(t.to_bits(), Ordering::Relaxed);
        self.steps.fetch_add(1, Ordering::Relaxed);
    }
}

/// A request to stop a run (or every run of a sweep): clones share one request, so that the
/// thread that watches keeps one and the run is given another.
#[derive(Debug, Clone, Default)]
pub struct StopToken(Arc<AtomicBool>);

impl StopToken {
    /// A token not stopped.
    pub fn new() -> StopToken {
        StopToken::default()
    }

    /// Ask every run given this token (or a clone of it) to stop at the next time it reaches.
    pub fn stop(&self) {
        self.0.store(true, Ordering::Relaxed);
    }

    /// Whether a stop has been asked.
    pub fn stopped(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stop_asked_through_one_clone_is_seen_through_every_other() {
        let token = StopToken::new();
        let given = token.clone();
        assert!(!given.stopped());
        token.stop();
        assert!(given.stopped() && token.stopped());
        // A token of its own is another request.
        assert!(!StopToken::new().stopped());
    }

    #[test]
    fn progress_keeps_the_last_time_and_counts_the_times_and_parts() {
        let progress = Progress::new();
        progress.begin(0.0, 2.0);
        progress.reached(0.5);
        progress.reached(0.75);
        assert_eq!((progress.time(), progress.steps(), progress.span()), (0.75, 2, (0.0, 2.0)));
        progress.finish_part();
        assert_eq!(progress.finished(), 1);
    }
}
