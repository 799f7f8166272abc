//! Long calls that Ctrl-C, a progress callback or a time budget can stop.
//!
//! [`run_interruptible`] runs the core's work on a worker thread with the GIL released, under a
//! [`Stop`] ([`pluecker::interrupt`]) that the core's long loops poll. The calling thread wakes every
//! [`POLL`]: it takes the GIL, runs Python's signal handlers (`PyErr_CheckSignals`) and calls the
//! progress callback. A `KeyboardInterrupt` (or any exception from a handler or the callback)
//! raises the stop; the worker ends at its next poll, within a track, an interior-point iteration of
//! a conic solve or a RANSAC iteration, and the work's value (for a batch: the finished tracks, the
//! others with status `interrupted`) comes back together with the pending exception, for the caller
//! to attach as `exception.partial` and raise ([`object_or_partial`]).
//!
//! [`run_single`] runs a single call (one point, line, quadric or pose) on the calling thread itself,
//! sparing the worker thread's start: the stop's own check ([`Stop::with_check`]) runs Python's
//! signal handlers from the core's polls (branch-and-bound nodes, conic-solver iterations, rotation
//! cells, RANSAC samples), at most once per [`POLL`], when the caller is Python's main thread (the
//! only one that runs them). A call that never reaches a poll is short and sees a signal when it ends.
//!
//! Before that, a call sets up on the calling thread with the GIL held, polling Ctrl-C between chunks
//! ([`crate::setup_poll`]); the tests stop a call at a known poll with [`crate::test_hook`].

use crate::errors::{guarded, with_partial};
use crate::test_hook::Hook;
use crate::threads::solve;
use crate::triangulation::batch::PyBatchReport;
use pluecker::interrupt::{with_stop, Stop};
use pluecker::Error;
use pyo3::prelude::*;
use pyo3::sync::GILOnceCell;
use std::panic::{catch_unwind, resume_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::mpsc::{self, RecvTimeoutError};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// How often the calling thread checks for signals and reports progress.
const POLL: Duration = Duration::from_millis(50);

/// Python's signal handlers run from the polls of a single call on the calling thread ([`run_single`]).
struct SignalWatch {
    started: Instant,
    /// Nanoseconds after `started` of the next check.
    next: AtomicU64,
    /// Polls so far: the clock is read at every [`CLOCK_EVERY`]-th only (a poll can come every
    /// fraction of a microsecond, e.g. the rotation cells of a pose certificate).
    polls: AtomicU64,
    /// Whether the calling thread is Python's main thread, the only one that runs signal handlers
    /// (elsewhere the watch never takes the GIL).
    main: bool,
    /// The exception a handler raised (`KeyboardInterrupt`).
    raised: Mutex<Option<PyErr>>,
}

/// Polls of a single call per reading of the clock ([`SignalWatch::due`]).
const CLOCK_EVERY: u64 = 16;

extern "C" {
    /// CPython's identifier of the calling thread (`threading.get_ident()`); no GIL needed.
    fn PyThread_get_thread_ident() -> std::os::raw::c_ulong;
}

/// `threading.main_thread().ident`, read once.
static MAIN_THREAD: GILOnceCell<Option<u64>> = GILOnceCell::new();

impl SignalWatch {
    fn new(py: Python<'_>) -> SignalWatch {
        let main = MAIN_THREAD.get_or_init(py, || {
            let ident = py
                .import("threading")
                .and_then(|t| t.call_method0("main_thread")?.getattr("ident"));
            ident.and_then(|i| i.extract::<u64>()).ok()
        });
        // Safe: a plain C call of the interpreter's API.
        let this = unsafe { PyThread_get_thread_ident() } as u64;
        SignalWatch {
            started: Instant::now(),
            next: AtomicU64::new(POLL.as_nanos() as u64),
            polls: AtomicU64::new(0),
            main: *main == Some(this),
            raised: Mutex::new(None),
        }
    }

    /// Whether a check is due: once per [`POLL`], the first one a [`POLL`] after the start (a
    /// shorter call never takes the GIL).
    fn due(&self) -> bool {
        if self.polls.fetch_add(1, Ordering::Relaxed) % CLOCK_EVERY != 0 {
            return false;
        }
        let now = self.started.elapsed().as_nanos() as u64;
        let next = self.next.load(Ordering::Relaxed);
        now >= next
            && (self.next)
                .compare_exchange(next, now + POLL.as_nanos() as u64, Ordering::Relaxed, Ordering::Relaxed)
                .is_ok()
    }

    /// Runs the signal handlers (with the GIL) when due, or `now`; `true` when one raised.
    fn check(&self, now: bool) -> bool {
        if !self.main || !(now || self.due()) {
            return false;
        }
        Python::with_gil(|py| match py.check_signals() {
            Ok(()) => false,
            Err(e) => {
                if let Ok(mut raised) = self.raised.lock() {
                    raised.get_or_insert(e);
                }
                true
            }
        })
    }

    fn take(&self) -> Option<PyErr> {
        self.raised.lock().ok()?.take()
    }
}

/// The stop of one call: its time budget, the test hook if armed, and the signal watch of a single
/// call.
fn call_stop(time_budget: Option<Duration>, watch: Option<Arc<SignalWatch>>) -> Arc<Stop> {
    let stop = Stop::with_time_budget(time_budget);
    let hook = Hook::take(stop.deadline());
    if hook.is_none() && watch.is_none() {
        return Arc::new(stop);
    }
    Arc::new(stop.with_check(move || {
        let interrupted = hook.as_ref().is_some_and(Hook::poll);
        // The hook's simulated Ctrl-C is checked at once, so that a test knows where the call stops.
        watch.as_ref().is_some_and(|w| w.check(interrupted))
    }))
}

/// Runs a single call's `work` on this thread with the GIL released, under a stop whose polls run
/// Python's signal handlers (module docs); they run once more when it ends. A core error is raised,
/// as is a panic (`PlueckerError("internal error: ...")`); an exception from a handler wins over both
/// and otherwise comes back as [`Outcome::pending`], beside the value (a stopped branch and bound
/// or rotation search says so in its status or certificate).
pub(crate) fn run_single<T, F>(py: Python<'_>, work: F) -> PyResult<Outcome<T>>
where
    T: Send,
    F: FnOnce() -> Result<T, Error> + Send,
{
    let watch = Arc::new(SignalWatch::new(py));
    let stop = call_stop(None, Some(Arc::clone(&watch)));
    let value = py.allow_threads(|| catch_unwind(AssertUnwindSafe(|| with_stop(stop, work))));
    let pending = watch.take().or_else(|| py.check_signals().err());
    let value = guarded(|| value.unwrap_or_else(|payload| resume_unwind(payload)));
    match (value, pending) {
        (Err(_), Some(e)) => Err(e),
        (value, pending) => value.map(|value| Outcome { value, pending }),
    }
}

/// The Python object of a call's result; raised as `exception.partial` instead when the call was
/// stopped by an exception (`pending`: Ctrl-C, or what a progress callback raised).
pub(crate) fn object_or_partial<C: pyo3::PyClass>(
    py: Python<'_>,
    pending: Option<PyErr>,
    object: Py<C>,
) -> PyResult<Py<C>> {
    match pending {
        Some(e) => Err(with_partial(py, e, object.into_any())),
        None => Ok(object),
    }
}

/// What an interruptible call produced: the work's value, and the exception that stopped it early
/// (`KeyboardInterrupt`, or whatever the progress callback raised), if any.
pub(crate) struct Outcome<T> {
    pub value: T,
    pub pending: Option<PyErr>,
}

/// Runs `work` on a worker thread under a stop with `time_budget`, while this thread checks Python
/// signals and calls `progress(done)` with the count of finished tracks (when it changed, and once
/// at the end); `work` gets the counter to increment. A core error of the whole call is raised, as
/// is a panic (`PlueckerError("internal error: ...")`); a pending exception wins over both.
///
/// `short`: the caller knows the work takes well under [`POLL`] (a small linear batch). Without
/// `progress` and `time_budget` it then runs on this thread, sparing the worker thread's start (its
/// cost: docs/benchmarks.md, "Figures behind code comments"), and sees Ctrl-C only when it ends.
pub(crate) fn run_interruptible<T, F>(
    py: Python<'_>,
    progress: Option<&Bound<'_, PyAny>>,
    time_budget: Option<Duration>,
    short: bool,
    work: F,
) -> PyResult<Outcome<T>>
where
    T: Send,
    F: FnOnce(&AtomicUsize) -> Result<T, Error> + Send,
{
    if short && progress.is_none() && time_budget.is_none() {
        let value = solve(py, move || work(&AtomicUsize::new(0)))?;
        return Ok(Outcome { value, pending: None });
    }
    let callback = progress.map(|p| p.clone().unbind());
    let stop = call_stop(time_budget, None);
    let done = AtomicUsize::new(0);
    let mut pending: Option<PyErr> = None;
    let joined = py.allow_threads(|| {
        std::thread::scope(|scope| {
            let (sender, receiver) = mpsc::channel();
            let (done, worker_stop) = (&done, Arc::clone(&stop));
            scope.spawn(move || {
                let out = crate::threads::install(|| {
                    catch_unwind(AssertUnwindSafe(|| with_stop(worker_stop, || work(done))))
                });
                // The receiver outlives the scope: sending cannot fail.
                let _ = sender.send(out);
            });
            let mut reported = None;
            loop {
                let received = receiver.recv_timeout(POLL);
                if pending.is_none() {
                    Python::with_gil(|py| {
                        let now = done.load(Ordering::Relaxed);
                        let checked = py.check_signals().and_then(|()| match &callback {
                            Some(callback) if reported != Some(now) => {
                                reported = Some(now);
                                callback.call1(py, (now,)).map(drop)
                            }
                            _ => Ok(()),
                        });
                        if let Err(e) = checked {
                            stop.request();
                            pending = Some(e);
                        }
                    });
                }
                match received {
                    Ok(out) => break out,
                    Err(RecvTimeoutError::Timeout) => continue,
                    // Only if the worker died without sending, which `catch_unwind` rules out.
                    Err(RecvTimeoutError::Disconnected) => {
                        break Err(Box::new("the worker thread ended without a result") as Box<dyn std::any::Any + Send>)
                    }
                }
            }
        })
    });
    let value = guarded(|| joined.unwrap_or_else(|payload| resume_unwind(payload)));
    match (value, pending) {
        (Err(_), Some(e)) => Err(e),
        (value, pending) => value.map(|value| Outcome { value, pending }),
    }
}

/// The Python object of a batch's results; raised as `exception.partial` instead when the batch was
/// stopped by an exception.
pub(crate) fn batch_result<C>(py: Python<'_>, outcome: Outcome<(PyBatchReport, C)>) -> PyResult<Py<C>>
where
    C: pyo3::PyClass<BaseType = PyBatchReport>,
{
    let Outcome {
        value: (report, results),
        pending,
    } = outcome;
    let object = Py::new(py, PyClassInitializer::from(report).add_subclass(results))?;
    object_or_partial(py, pending, object)
}
