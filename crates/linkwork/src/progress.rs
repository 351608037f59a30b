//! Where a run is, and a request to stop it, shared by the thread that runs an analysis and a
//! thread that watches it (a progress bar, Ctrl-C).
//!
//! [`Model::run_watched`](crate::Model::run_watched) makes a [`Progress`] the running thread's
//! own for the length of the run. The analyses report every output time and every step attempt
//! of an integrator to it (`reached`), so that no analysis has to pass it along; once
//! [`Progress::stop`] has been called, the next time reached ends the run with
//! [`Error::Interrupted`], and the results up to there are kept as after any failure.
//! A sweep watches its variants through one [`Progress`]: each variant's run has a
//! [`Progress::part`] of it, which shares its request to stop, and the whole counts the
//! variants finished.
//!
//! The cost is an atomic store and load per output point and step: nothing beside a step's
//! factorization.

use crate::error::Error;
use std::cell::RefCell;
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
    /// The request to stop, shared with the parts ([`Progress::part`]).
    stop: Arc<AtomicBool>,
}

impl Progress {
    /// A run not started: at time 0 of the span `[0, 0]`.
    pub fn new() -> Arc<Progress> {
        Arc::new(Progress::default())
    }

    /// The progress of one part of this work (one variant of a sweep): its own time and steps,
    /// and this one's request to stop, so that a stop asked here stops every part running.
    pub fn part(&self) -> Arc<Progress> {
        Arc::new(Progress { stop: Arc::clone(&self.stop), ..Progress::default() })
    }

    /// Parts finished so far (the variants of a sweep).
    pub fn finished(&self) -> u64 {
        self.finished.load(Ordering::Relaxed)
    }

    /// One more part is finished.
    pub(crate) fn finish_part(&self) {
        self.finished.fetch_add(1, Ordering::Relaxed);
    }

    /// Whether a stop has been asked.
    pub fn stopped(&self) -> bool {
        self.stop.load(Ordering::Relaxed)
    }

    /// Ask the run (and every part of it) to stop at the next time it reaches.
    pub fn stop(&self) {
        self.stop.store(true, Ordering::Relaxed);
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
}

thread_local! {
    /// The progress of the run on this thread, if it is watched.
    static CURRENT: RefCell<Option<Arc<Progress>>> = const { RefCell::new(None) };
}

/// Run `f` with `progress` as this thread's current one, the previous one back afterwards (also
/// when `f` panics).
pub(crate) fn scope<T>(progress: &Arc<Progress>, f: impl FnOnce() -> T) -> T {
    struct Restore(Option<Arc<Progress>>);
    impl Drop for Restore {
        fn drop(&mut self) {
            CURRENT.set(self.0.take());
        }
    }
    let _restore = Restore(CURRENT.replace(Some(Arc::clone(progress))));
    f()
}

/// The run on this thread reached time `t`: recorded for its watcher, and
/// [`Error::Interrupted`] if the watcher asked it to stop.
pub(crate) fn reached(t: f64) -> Result<(), Error> {
    CURRENT.with_borrow(|current| match current {
        Some(p) => {
            p.time.store(t.to_bits(), Ordering::Relaxed);
            p.steps.fetch_add(1, Ordering::Relaxed);
            if p.stopped() {
                Err(Error::Interrupted { time: t })
            } else {
                Ok(())
            }
        }
        None => Ok(()),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stopped_run_is_interrupted_at_the_next_time_and_only_in_its_scope() {
        let progress = Progress::new();
        progress.begin(0.0, 2.0);
        scope(&progress, || {
            assert!(reached(0.5).is_ok());
            progress.stop();
            assert!(matches!(reached(0.75), Err(Error::Interrupted { time }) if time == 0.75));
        });
        assert_eq!((progress.time(), progress.steps(), progress.span()), (0.75, 2, (0.0, 2.0)));
        // Outside the scope nothing watches: a stop asked of another run changes nothing.
        assert!(reached(1.0).is_ok());
        assert_eq!(progress.steps(), 2);
    }

    #[test]
    fn a_stop_asked_of_the_whole_stops_its_parts() {
        let whole = Progress::new();
        let part = whole.part();
        scope(&part, || {
            assert!(reached(0.1).is_ok());
            whole.stop();
            assert!(matches!(reached(0.2), Err(Error::Interrupted { .. })));
        });
        // The part keeps its own time and steps; the whole counts parts finished.
        assert_eq!((part.time(), part.steps(), whole.steps()), (0.2, 2, 0));
        whole.finish_part();
        assert_eq!(whole.finished(), 1);
    }
}
