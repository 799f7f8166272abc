//! Cooperative stopping of long calls: a flag another thread raises (a binding that saw Ctrl-C, a
//! progress callback that failed) and an optional deadline (a batch's time budget).
//!
//! A [`Stop`] is installed for the duration of a call with [`with_stop`]; the long loops of the crate
//! poll it through [`stop_reason`]:
//! - the batches (`point::batch`, line and quadric batches), before each track: a
//!   track not yet started when the stop arrives is not solved
//!   ([`crate::Error::Interrupted`]);
//! - the node loop of `global::branch_and_bound`: a track being solved keeps the best
//!   estimate and the lower bound reached, uncertified, with status
//!   [`crate::triangulation::Status::Interrupted`] or [`crate::triangulation::Status::TimeBudget`];
//! - every conic solve (`global::socp`), before it starts and at each interior-point iteration: a
//!   stopped solve gives no bound, so that one large program (the root of a line seen in 30 views)
//!   does not hold the stop up;
//! - the RANSAC loop (`pose::robust`, stop reason [`crate::RansacStop::Interrupted`]: before each
//!   sample, between the rounds of a local optimisation, and before each fit of the final
//!   consensus) and the rotation search of the pose certificate (`pose::certificate`, not
//!   proved).
//!
//! The stop is ambient (a thread-local) rather than a parameter of every solver, so that adding a
//! polled loop does not change any signature; the batches carry it into their rayon tasks. Without an
//! installed stop, [`stop_reason`] is `None` and costs a thread-local read.
//!
//! A stop may also carry a check of its own ([`Stop::with_check`]) that every poll runs: a binding
//! whose call runs on the thread that must notice Ctrl-C (Python runs its signal handlers on the main
//! thread only) checks its signals there, rate-limited; a test learns that a poll happened, i.e. that
//! a track or a node was reached.
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
use std::panic::{RefUnwindSafe, UnwindSafe};
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

/// The check of [`Stop::with_check`]: `true` asks for the stop. Unwind-safe, as a stop shared with a
/// `catch_unwind` must be.
type Check = Box<dyn Fn() -> bool + Send + Sync + UnwindSafe + RefUnwindSafe>;

/// A stop signal shared between the solving threads and the thread that may raise it.
#[derive(Default)]
pub struct Stop {
    requested: AtomicBool,
    /// `None`: no time budget (or one too large to represent, which never runs out).
    deadline: Option<Instant>,
    check: Option<Check>,
}

impl std::fmt::Debug for Stop {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Stop")
            .field("requested", &self.requested)
            .field("deadline", &self.deadline)
            .field("check", &self.check.as_ref().map(|_| "Fn() -> bool"))
            .finish()
    }
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
            check: None,
        }
    }

    /// This stop, with `check` run by every poll that neither a request nor the deadline has
    /// answered, on the polling thread: `true` requests the stop (that poll already answers
    /// [`StopReason::Requested`]). Polls come once per track, branch-and-bound node, conic-solver
    /// iteration, RANSAC sample or rotation cell, from every solving thread: `check` must be cheap
    /// (rate-limit anything costly) and thread-safe.
    pub fn with_check(self, check: impl Fn() -> bool + Send + Sync + UnwindSafe + RefUnwindSafe + 'static) -> Self {
        Stop {
            check: Some(Box::new(check)),
            ..self
        }
    }

    /// When the time budget runs out (`None`: no budget).
    pub fn deadline(&self) -> Option<Instant> {
        self.deadline
    }

    /// Asks every loop polling this stop to end at its next poll.
    pub fn request(&self) {
        self.requested.store(true, Ordering::Relaxed);
    }

    /// Why the calls under this stop must end, if they must (a request wins over the deadline); runs
    /// the check of [`Stop::with_check`] when neither has fired.
    pub fn reason(&self) -> Option<StopReason> {
        if self.requested.load(Ordering::Relaxed) {
            Some(StopReason::Requested)
        } else if self.deadline.is_some_and(|d| Instant::now() >= d) {
            Some(StopReason::TimeBudget)
        } else if self.check.as_ref().is_some_and(|check| check()) {
            self.request();
            Some(StopReason::Requested)
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
    fn a_check_runs_at_every_poll_until_it_asks_for_the_stop() {
        use std::sync::atomic::AtomicUsize;
        let polls = Arc::new(AtomicUsize::new(0));
        let counted = Arc::clone(&polls);
        // Asks for the stop at its third run.
        let stop = Arc::new(Stop::new().with_check(move || counted.fetch_add(1, Ordering::Relaxed) == 2));
        with_stop(Arc::clone(&stop), || {
            assert_eq!(stop_reason(), None);
            assert_eq!(stop_reason(), None);
            assert_eq!(stop_reason(), Some(StopReason::Requested));
            // Once requested, the check no longer runs.
            assert_eq!(stop_reason(), Some(StopReason::Requested));
        });
        assert_eq!(polls.load(Ordering::Relaxed), 3);
        // An expired deadline answers before the check.
        let expired = Stop::with_time_budget(Some(Duration::ZERO)).with_check(|| panic!("not reached"));
        assert_eq!(expired.reason(), Some(StopReason::TimeBudget));
        assert!(expired.deadline().is_some() && Stop::new().deadline().is_none());
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
