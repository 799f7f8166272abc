//! The number of threads the batches use in this process: rayon's global pool by default (one thread
//! per core, or `RAYON_NUM_THREADS`), or a pool of a set size (`set_num_threads`), so that several
//! processes on one machine — Dask workers, say — can share its cores without oversubscribing them.
//! Every solve runs inside [`install`].

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
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

/// set_num_threads(n, /)
/// --
///
/// Sets the number of threads the batches of this process use (``triangulate_points``,
/// ``estimate_poses``, …): ``n >= 1``, or ``None`` for the default (one per core, or the
/// ``RAYON_NUM_THREADS`` environment variable). Takes effect for the next call.
#[pyfunction]
#[pyo3(signature = (n, /))]
pub fn set_num_threads(n: Option<usize>) -> PyResult<()> {
    let pool = match n {
        None => None,
        Some(0) => {
            return Err(PyValueError::new_err(
                "set_num_threads: n must be at least 1, or None for the default",
            ))
        }
        Some(n) => Some(Arc::new(
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .thread_name(|i| format!("pluecker-{i}"))
                .build()
                .map_err(|e| PyValueError::new_err(format!("set_num_threads: cannot start {n} threads: {e}")))?,
        )),
    };
    *POOL
        .write()
        .map_err(|_| PyValueError::new_err("set_num_threads: the pool lock is poisoned"))? = pool;
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
