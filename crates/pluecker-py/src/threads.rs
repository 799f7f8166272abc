//! The number of threads the batches use in this process: rayon's global pool by default (one thread
//! per core, or `RAYON_NUM_THREADS`), or a pool of a set size (`set_num_threads`), so that several
//! processes on one machine — Dask workers, say — can share its cores without oversubscribing them.
//! Every solve runs inside [`install`].

use crate::convert::Integer;
use crate::errors::{internal, invalid_argument, to_py_err, InvalidOptionError, PlueckerError};
use pluecker::Error;
use pyo3::prelude::*;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::{Arc, RwLock};

/// The pool set by `set_num_threads`; `None`: rayon's global pool.
static POOL: RwLock<Option<Arc<rayon::ThreadPool>>> = RwLock::new(None);

fn current() -> Option<Arc<rayon::ThreadPool>> {
    POOL.read().map_or(None, |p| p.clone())
}

/// Runs `f` in the pool of this process (module docs).
pub fn install<T: Send>(f: impl FnOnce() -> T + Send) -> T {
    match current() {
        Some(pool) => pool.install(f),
        None => f(),
    }
}

/// The most threads a pool may have per core (`std::thread::available_parallelism`): more only
/// oversubscribes the cores, and a mistyped count (`10**6`) would try to start that many threads.
pub const MAX_THREADS_PER_CORE: usize = 4;

/// The fewest threads the cap allows whatever the core count, so that a small machine can still run a
/// pool the size of a larger one (to reproduce its scheduling, say).
pub const MIN_THREAD_CAP: usize = 64;

/// The cores available to this process (`std::thread::available_parallelism`, 1 when unknown).
fn cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// The largest `n` that `set_num_threads` accepts: `max(MIN_THREAD_CAP, MAX_THREADS_PER_CORE × cores)`.
pub fn thread_cap() -> usize {
    MIN_THREAD_CAP.max(MAX_THREADS_PER_CORE.saturating_mul(cores()))
}

/// set_num_threads(n, /)
/// --
///
/// Sets the number of threads the batches of this process use (``triangulate_points``,
/// ``estimate_poses``, …): an integer from 1 to ``max(64, 4 × the cores available)``, or ``None`` for
/// the default (one per core, or the ``RAYON_NUM_THREADS`` environment variable). Takes effect for the
/// next call. Any other value (0, a negative or larger count, a bool) raises ``InvalidOptionError``
/// naming ``n``.
#[pyfunction]
#[pyo3(signature = (n, /))]
pub fn set_num_threads(py: Python<'_>, n: Option<Integer>) -> PyResult<()> {
    let pool = match n {
        None => None,
        Some(n) => {
            let cap = thread_cap();
            let n = n.in_range("n", 1, cap as i128).map_err(|e| {
                // The limit as it is on this machine, from its own core count.
                let cores = cores();
                InvalidOptionError::new_err(format!(
                    "set_num_threads: {} (the limit on this machine, with {cores} core{}: the larger of \
                     {MIN_THREAD_CAP} and {MAX_THREADS_PER_CORE} per core), or None for the default",
                    e.value(py),
                    if cores == 1 { "" } else { "s" }
                ))
            })? as usize;
            Some(Arc::new(
                rayon::ThreadPoolBuilder::new()
                    .num_threads(n)
                    .thread_name(|i| format!("pluecker-{i}"))
                    .build()
                    .map_err(|e| invalid_argument("set_num_threads", format!("cannot start {n} threads: {e}")))?,
            ))
        }
    };
    *POOL
        .write()
        .map_err(|_| PlueckerError::new_err("set_num_threads: the pool lock is poisoned"))? = pool;
    Ok(())
}

/// get_num_threads()
/// --
///
/// The number of threads the batches of this process use (see ``set_num_threads``).
#[pyfunction]
pub fn get_num_threads() -> usize {
    current().map_or_else(rayon::current_num_threads, |p| p.current_num_threads())
}

/// Like [`crate::errors::guarded`], with the GIL released for the duration of the call (every solve goes here).
pub fn solve<T, F>(py: Python<'_>, f: F) -> PyResult<T>
where
    T: Send,
    F: FnOnce() -> Result<T, Error> + Send,
{
    match py.allow_threads(move || install(move || catch_unwind(AssertUnwindSafe(f)))) {
        Ok(result) => result.map_err(to_py_err),
        Err(payload) => Err(internal(payload)),
    }
}
