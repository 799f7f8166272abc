//! `_ExitDeadline`: the `pluecker` command's promise that Ctrl-C ends it within a grace period, also
//! while Python cannot act on the signal.
//!
//! Python runs its SIGINT handler on the main thread, between bytecodes: a call that holds the GIL
//! for seconds without checking signals (pycolmap reading or writing a model, numpy sorting millions
//! of rows on the main thread) holds Ctrl-C up for as long. The command line (`pluecker.cli.run`)
//! hands this guard the read end of a pipe whose write end is Python's wakeup fd
//! (`signal.set_wakeup_fd`): Python's C-level handler writes the signal's number there as the
//! signal arrives, whatever the interpreter is doing. A thread of its own, which never takes the GIL,
//! reads it; `grace` after a SIGINT, unless the command has [`ExitDeadline::stand_down`] by then
//! (it caught the `KeyboardInterrupt` and prints the line itself), it writes `message` to standard
//! error and ends the process with `_exit(status)`: no Python clean-up runs (`finally` blocks),
//! which is what a stop that cannot wait costs. What the command is writing is not left behind: the
//! paths it registered ([`ExitDeadline::remove_on_exit`], the temporary folders and files of its
//! outputs and the parent folders it made for them) are removed first, newest first.
//!
//! POSIX only (the module has no `_ExitDeadline` elsewhere). `_hold_gil_for_tests` gives the tests a
//! call that holds the GIL at a known moment.

use pyo3::prelude::*;
use std::fs::File;
use std::io::{ErrorKind, Read, Write};
#[cfg(feature = "test-hooks")]
use std::mem::ManuallyDrop;
use std::os::fd::FromRawFd;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use crate::convert::{seconds_arg, Real};

/// SIGINT's number on every POSIX system.
const SIGINT: u8 = 2;

extern "C" {
    /// Ends the process at once (no `atexit` handlers, no C++ static destructors).
    fn _exit(status: std::os::raw::c_int) -> !;
}

/// _ExitDeadline(fd, grace, message, status)
/// --
///
/// Ends the process with ``status`` after printing ``message`` to standard error ``grace`` seconds
/// after a SIGINT is read from the file descriptor ``fd`` (the read end of the pipe given to
/// ``signal.set_wakeup_fd``, owned from now on), unless ``stand_down()`` was called first. The
/// ``pluecker`` command's guard (``pluecker.cli.run``); not for library code.
#[pyclass(module = "pluecker._core", name = "_ExitDeadline", frozen)]
pub struct ExitDeadline {
    /// Whether the command stood down; held (never released) by the watcher once it ends the process.
    stood_down: Arc<Mutex<bool>>,
    /// What to remove before a forced exit ([`ExitDeadline::remove_on_exit`]), in registration order.
    scratch: Arc<Mutex<Vec<Scratch>>>,
}

/// A path of the command's unfinished output: removed whole (a temporary folder or file), or only if
/// empty (a parent folder made for the output).
#[derive(Debug, Clone, PartialEq)]
struct Scratch {
    path: PathBuf,
    whole: bool,
}

impl Scratch {
    fn remove(&self) {
        let path: &Path = &self.path;
        let _ = if !self.whole {
            std::fs::remove_dir(path)
        } else if path.is_dir() {
            std::fs::remove_dir_all(path)
        } else {
            std::fs::remove_file(path)
        };
    }
}

#[pymethods]
impl ExitDeadline {
    #[new]
    fn new(fd: i32, grace: Real, message: String, status: i32) -> PyResult<Self> {
        let grace = seconds_arg("grace", grace.get("grace")?)?;
        // Safe: the caller hands over an open descriptor it no longer uses (documented above).
        let signals = unsafe { File::from_raw_fd(fd) };
        let stood_down = Arc::new(Mutex::new(false));
        let scratch = Arc::new(Mutex::new(Vec::new()));
        let (watched, to_remove) = (Arc::clone(&stood_down), Arc::clone(&scratch));
        std::thread::Builder::new()
            .name("pluecker-exit-deadline".into())
            .spawn(move || watch(signals, grace, message, status, &watched, &to_remove))?;
        Ok(ExitDeadline { stood_down, scratch })
    }

    /// Registers ``path`` to be removed if the deadline ends the process: whole (``whole=True``: a
    /// temporary folder or file of an unfinished output), or only when empty (a parent folder made
    /// for the output).
    #[pyo3(signature = (path, whole))]
    fn remove_on_exit(&self, py: Python<'_>, path: PathBuf, whole: bool) {
        py.allow_threads(|| lock(&self.scratch).push(Scratch { path, whole }));
    }

    /// Withdraws a registration of ``path`` (the output was published or cleaned up).
    fn keep(&self, py: Python<'_>, path: PathBuf) {
        py.allow_threads(|| lock(&self.scratch).retain(|s| s.path != path));
    }

    /// The command answers Ctrl-C itself from now on: the deadline no longer ends the process. Waits
    /// (for ever) if the deadline is ending it at this moment.
    fn stand_down(&self, py: Python<'_>) {
        py.allow_threads(|| *lock(&self.stood_down) = true);
    }
}

fn lock<T>(mutex: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    mutex.lock().unwrap_or_else(|p| p.into_inner())
}

/// Reads signal numbers until a SIGINT (or the end of the pipe: the command closed its write end),
/// then ends the process `grace` later unless the command stood down, after removing `scratch`
/// (newest first).
fn watch(
    mut signals: File,
    grace: Duration,
    message: String,
    status: i32,
    stood_down: &Mutex<bool>,
    scratch: &Mutex<Vec<Scratch>>,
) {
    let mut bytes = [0u8; 64];
    loop {
        match signals.read(&mut bytes) {
            Ok(0) => return,
            Ok(read) if bytes[..read].contains(&SIGINT) => break,
            Ok(_) => continue,
            Err(e) if e.kind() == ErrorKind::Interrupted => continue,
            Err(_) => return,
        }
    }
    std::thread::sleep(grace);
    let stood_down = lock(stood_down);
    if *stood_down {
        return;
    }
    for path in lock(scratch).iter().rev() {
        path.remove();
    }
    let _ = std::io::stderr().write_all(message.as_bytes());
    // Safe: a plain C call; the lock stays held, so `stand_down` cannot return before the exit.
    unsafe { _exit(status) }
}

/// _hold_gil_for_tests(fd, seconds, /)
/// --
///
/// Test hook: writes one byte to the file descriptor ``fd`` (left open), then holds the GIL for
/// ``seconds`` without checking signals, as a long call into a library does.
#[cfg(feature = "test-hooks")]
#[pyfunction]
pub(crate) fn _hold_gil_for_tests(_py: Python<'_>, fd: i32, seconds: Real) -> PyResult<()> {
    let seconds = seconds_arg("seconds", seconds.get("seconds")?)?;
    // Safe: `fd` is the caller's and stays open (never dropped here).
    let mut out = ManuallyDrop::new(unsafe { File::from_raw_fd(fd) });
    out.write_all(b"x")?;
    std::thread::sleep(seconds);
    Ok(())
}
