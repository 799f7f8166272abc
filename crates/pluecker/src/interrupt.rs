//! Cooperative stopping of long calls: a flag another thread raises (a binding that saw Ctrl-C, a
//! progress callback that failed) and an optional deadline (a batch's time budget).
//!
//! A [`Stop`] is installed for the duration of a call with [`with_stop`]; the long loops of the crate
//! poll it through [`stop_reason`]:
//! - the batches ([`crate::triangulation::point::batch`], line and quadric batches), before each track: a
//!   track not yet started when the stop arrives is not solved
//!   ([`crate::Error::Interrupted`]);
//! - the node loop of [`crate::global::branch_and_bound`]: a track being solved keeps the best
//!   estimate and the lower bound reached, uncertified, with status
//!   [`crate::triangulation::Status::Interrupted`] or [`crate::triangulation::Status::TimeBudget`];
//! - the RANSAC loop ([`crate::pose::robust`], stop reason [`crate::RansacStop::Interrupted`]) and the
//!   rotation search of the pose certificate ([`crate::pose::certificate`], not proved).
//!
//! The stop is ambient (a thread-local) rather than a parameter of every solver, so that adding a
//! polled loop does not change any signature; the batches carry it into their rayon tasks. Without an
//! installed stop, [`stop_reason`] is `None` and costs a thread-local read.
//!
//! ```
//! use pluecker::interrupt::{with_stop, Stop};
//! use std::{sync::Arc, time::Duration};
//! let stop = Arc::new(Stop::with_time_budget(Some(Duration::from_secs(10))));
//! let watcher = Arc::clone(&stop); // e.g. handed to a thread that calls `watcher.request()` on Ctrl-C
//! let answer = with_stop(stop, || 6 * 7); // any pluecker call
//! assert_eq!(answer, 42);
//! ```

use std::cell::RefCell;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Why a call stopped early.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StopReason {
    /// [`Stop::request`] was called (Ctrl-C, a failed progress callback, the caller's own choice).
    Requested,
    /// The time budget of [`Stop::with_time_budget`] ran out.
    TimeBudget,
}

impl StopReason {
    /// A phrase for messages: "interrupted" or "the time budget ran out".
    pub fn describe(&self) -> &'static str {
        match self {
            StopReason::Requested => "interrupted",
            StopReason::TimeBudget => "the time budget ran out",
        }
    }
}

/// A stop signal shared between the solving threads and the thread that may raise it.
#[derive(Debug, Default)]
pub struct Stop {
    requested: AtomicBool,
    /// `None`: no time budget (or one too large to represent, which never runs out).
    deadline: Option<Instant>,
}

impl Stop {
    /// A stop that fires only on [`Stop::request`].
    pub fn new() -> Self {
        Stop::default()
    }

    /// A stop that also fires `budget` after now (`None`: no budget). A budget of zero stops at the
    /// first poll.
    pub fn with_time_budget(budget: Option<Duration>) -> Self {
        Stop {
            requested: AtomicBool::new(false),
            deadline: budget.and_then(|b| Instant::now().checked_add(b)),
        }
    }

    /// Asks every loop polling this stop to end at its next poll.
    pub fn request(&self) {
        self.requested.store(true, Ordering::Relaxed);
    }

    /// Why the calls under this stop must end, if they must (a request wins over the deadline).
    pub fn reason(&self) -> Option<StopReason> {
        if self.requested.load(Ordering::Relaxed) {
            Some(StopReason::Requested)
        } else if self.deadline.is_some_and(|d| Instant::now() >= d) {
            Some(StopReason::TimeBudget)
        } else {
            None
        }
    }
}

thread_local! {
    static CURRENT: RefCell<Option<Arc<Stop>>> = const { RefCell::new(None) };
}

/// A stop installed on this thread until dropped, which restores the previous one (also on
/// unwinding). For loops that install a stop once per task rather than once per item (a rayon
/// `map_init`).
pub(crate) struct Installed(Option<Arc<Stop>>);

impl Installed {
    /// Installs `stop` (`None`: none) on this thread.
    pub(crate) fn new(stop: Option<Arc<Stop>>) -> Installed {
        Installed(CURRENT.with(|c| c.replace(stop)))
    }
}

impl Drop for Installed {
    fn drop(&mut self) {
        let previous = self.0.take();
        CURRENT.with(|c| *c.borrow_mut() = previous);
    }
}

/// Runs `f` on this thread with `stop` installed (`None`: none), then restores the previous one.
pub fn with_stop<R>(stop: impl Into<Option<Arc<Stop>>>, f: impl FnOnce() -> R) -> R {
    let _installed = Installed::new(stop.into());
    f()
}

/// The stop installed on this thread, to carry into tasks run on other threads.
pub fn current() -> Option<Arc<Stop>> {
    CURRENT.with(|c| c.borrow().clone())
}

/// Why the current call must end, if it must: the polling point of every long loop.
pub fn stop_reason() -> Option<StopReason> {
    CURRENT.with(|c| c.borrow().as_ref().and_then(|s| s.reason()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nothing_installed_never_stops() {
        assert_eq!(stop_reason(), None);
        assert!(current().is_none());
    }

    #[test]
    fn request_is_seen_and_scoped() {
        let stop = Arc::new(Stop::new());
        let handle = Arc::clone(&stop);
        with_stop(stop, || {
            assert_eq!(stop_reason(), None);
            handle.request();
            assert_eq!(stop_reason(), Some(StopReason::Requested));
            // A nested call without a stop does not see the outer one, and the outer one comes back.
            with_stop(None, || assert_eq!(stop_reason(), None));
            assert_eq!(stop_reason(), Some(StopReason::Requested));
        });
        assert_eq!(stop_reason(), None);
    }

    #[test]
    fn deadlines() {
        let zero = Arc::new(Stop::with_time_budget(Some(Duration::ZERO)));
        with_stop(zero, || assert_eq!(stop_reason(), Some(StopReason::TimeBudget)));
        // A budget beyond what `Instant` can represent never runs out.
        let huge = Arc::new(Stop::with_time_budget(Some(Duration::MAX)));
        with_stop(huge, || assert_eq!(stop_reason(), None));
        // A request wins over an expired deadline.
        let both = Arc::new(Stop::with_time_budget(Some(Duration::ZERO)));
        both.request();
        assert_eq!(both.reason(), Some(StopReason::Requested));
    }

    #[test]
    fn restored_after_a_panic() {
        let stop = Arc::new(Stop::new());
        stop.request();
        let caught = std::panic::catch_unwind(|| with_stop(stop, || panic!("inside")));
        assert!(caught.is_err());
        assert_eq!(stop_reason(), None);
    }
}
