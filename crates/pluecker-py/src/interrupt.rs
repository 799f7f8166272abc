//! Long calls that Ctrl-C, a progress callback or a time budget can stop.
//!
//! [`run_interruptible`] runs the core's work on a worker thread with the GIL released, under a
//! [`Stop`] ([`pluecker::interrupt`]) that the core's long loops poll. The calling thread wakes every
//! [`POLL`]: it takes the GIL, runs Python's signal handlers (`PyErr_CheckSignals`) and calls the
//! progress callback. A `KeyboardInterrupt` (or any exception from a handler or the callback)
//! raises the stop; the worker ends at its next poll, within a track's branch-and-bound node or a
//! RANSAC iteration, and the work's value (for a batch: the finished tracks, the others with status
//! `interrupted`) comes back together with the pending exception, for the caller to attach as
//! `exception.partial` and raise ([`with_partial`]).

use crate::convert::{optional_real, seconds_arg, Real};
use crate::errors::{guarded, solve};
use crate::triangulation::batch::PyBatchReport;
use pluecker::interrupt::{with_stop, Stop};
use pluecker::Error;
use pyo3::prelude::*;
use std::panic::{catch_unwind, resume_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc::{self, RecvTimeoutError};
use std::sync::Arc;
use std::time::Duration;

/// How often the calling thread checks for signals and reports progress.
const POLL: Duration = Duration::from_millis(50);

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
/// cost: `bench/README.md`), and sees Ctrl-C only when it ends.
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
    let stop = Arc::new(Stop::with_time_budget(time_budget));
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

/// Sets `error.partial = partial` (the results of an interrupted batch) and returns `error`.
pub(crate) fn with_partial(py: Python<'_>, error: PyErr, partial: PyObject) -> PyErr {
    // An exception instance without a writable `__dict__` keeps its message; the results are lost.
    let _ = error.value(py).setattr("partial", partial);
    error
}

/// The `time_budget` argument of a batch (seconds, `None` for none), checked.
pub(crate) fn time_budget(arg: Option<Real>) -> PyResult<Option<Duration>> {
    optional_real("time_budget", arg)?
        .map(|s| seconds_arg("time_budget", s))
        .transpose()
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
    match pending {
        Some(e) => Err(with_partial(py, e, object.into_any())),
        None => Ok(object),
    }
}
