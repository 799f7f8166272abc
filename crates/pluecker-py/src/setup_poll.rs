//! The set-up of a call on the calling thread with the GIL held (reading its arrays, sorting its rows,
//! allocating its results), a chunk of [`SETUP_CHUNK`] values at a time, with Python's signal handlers
//! run between chunks ([`setup_poll`]): Ctrl-C while a batch of millions of tracks is converted or
//! allocated raises `KeyboardInterrupt` at once, with `partial = None` (nothing was solved).

use crate::errors::with_partial;
use crate::test_hook::Hook;
use pyo3::prelude::*;

/// Values (array entries, rows, result entries) a call's set-up handles between two polls
/// ([`setup_poll`]): 8 MB of float64, a few milliseconds of copying.
pub(crate) const SETUP_CHUNK: usize = 1 << 20;

/// The poll of a call's set-up, between two chunks of [`SETUP_CHUNK`] values: runs Python's signal
/// handlers (on the main thread; elsewhere nothing). Ctrl-C raises `KeyboardInterrupt` with
/// `partial = None`: the call has not solved anything yet.
pub(crate) fn setup_poll(py: Python<'_>) -> PyResult<()> {
    Hook::setup_poll();
    py.check_signals().map_err(|e| with_partial(py, e, py.None()))
}

/// `step(range)` for the chunks of [`SETUP_CHUNK`] values of `0..len`, in order, with a
/// [`setup_poll`] after each; the first error ends it.
pub(crate) fn in_chunks(
    py: Python<'_>,
    len: usize,
    mut step: impl FnMut(std::ops::Range<usize>) -> PyResult<()>,
) -> PyResult<()> {
    let mut start = 0;
    while start < len {
        let end = len.min(start + SETUP_CHUNK);
        step(start..end)?;
        setup_poll(py)?;
        start = end;
    }
    Ok(())
}
