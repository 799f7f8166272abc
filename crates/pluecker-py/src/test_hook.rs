//! The test hook of the interruptible calls: `_on_poll_for_tests` arms it for the next call, which at a
//! given poll simulates Ctrl-C or waits until its time budget has run out, so that the tests stop a call
//! at a known point of its work rather than after a delay; or it simulates Ctrl-C at a given poll of the
//! set-up ([`crate::setup_poll`]). Without the feature `test-hooks` nothing arms it.

#[cfg(feature = "test-hooks")]
use crate::errors::invalid_argument;
#[cfg(feature = "test-hooks")]
use pyo3::prelude::*;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::Instant;

/// What the test hook does at its poll. Without the feature `test-hooks` nothing arms a hook: the calls
/// still look for one ([`MAYBE_ARMED`], one relaxed load), and never find it.
#[derive(Debug, Clone, Copy)]
#[cfg_attr(not(feature = "test-hooks"), allow(dead_code))]
pub(crate) enum HookAction {
    /// What Python's SIGINT handler does (`PyErr_SetInterrupt`): the call then sees a
    /// `KeyboardInterrupt` exactly as after Ctrl-C.
    Interrupt,
    /// Waits until the call's time budget has run out (the poll itself still goes ahead).
    AwaitDeadline,
    /// [`HookAction::Interrupt`] at a poll of the set-up ([`crate::setup_poll::setup_poll`]), counted over every call
    /// until the next stop is made (which discards the hook if it has not acted).
    InterruptSetup,
}

/// The hook armed by `_on_poll_for_tests`, for the next call that makes a stop.
pub(crate) static ARMED: Mutex<Option<(usize, HookAction)>> = Mutex::new(None);
/// Whether [`ARMED`] may hold a hook (spares every call the lock).
pub(crate) static MAYBE_ARMED: AtomicBool = AtomicBool::new(false);
/// Set-up polls since the hook was armed ([`HookAction::InterruptSetup`]).
pub(crate) static SETUP_POLLS: AtomicUsize = AtomicUsize::new(0);

/// The test hook of one call: acts at the `at`-th poll of its stop, counted over every thread.
pub(crate) struct Hook {
    at: usize,
    action: HookAction,
    polls: AtomicUsize,
    deadline: Option<Instant>,
}

impl Hook {
    /// The armed hook, if any (disarmed: it serves one call).
    pub(crate) fn take(deadline: Option<Instant>) -> Option<Hook> {
        if !MAYBE_ARMED.swap(false, Ordering::Relaxed) {
            return None;
        }
        let (at, action) = ARMED.lock().ok()?.take()?;
        if let HookAction::InterruptSetup = action {
            return None; // the set-up it was armed for is over
        }
        Some(Hook {
            at,
            action,
            polls: AtomicUsize::new(0),
            deadline,
        })
    }

    /// Counts a poll and acts at the `at`-th; `true` when it just simulated Ctrl-C.
    pub(crate) fn poll(&self) -> bool {
        if self.polls.fetch_add(1, Ordering::Relaxed) + 1 != self.at {
            return false;
        }
        match self.action {
            HookAction::Interrupt => {
                // Safe from any thread, with or without the GIL (CPython's documentation).
                unsafe { pyo3::ffi::PyErr_SetInterrupt() };
                true
            }
            HookAction::AwaitDeadline => {
                while let Some(left) = self.deadline.and_then(|d| d.checked_duration_since(Instant::now())) {
                    std::thread::sleep(left);
                }
                false
            }
            HookAction::InterruptSetup => false,
        }
    }

    /// Counts a poll of the set-up ([`crate::setup_poll::setup_poll`]) for a hook armed with
    /// [`HookAction::InterruptSetup`], and simulates Ctrl-C at its poll.
    pub(crate) fn setup_poll() {
        if !MAYBE_ARMED.load(Ordering::Relaxed) {
            return;
        }
        let Ok(mut armed) = ARMED.lock() else { return };
        if let Some((at, HookAction::InterruptSetup)) = *armed {
            if SETUP_POLLS.fetch_add(1, Ordering::Relaxed) + 1 == at {
                *armed = None;
                MAYBE_ARMED.store(false, Ordering::Relaxed);
                // Safe from any thread, with or without the GIL (CPython's documentation).
                unsafe { pyo3::ffi::PyErr_SetInterrupt() };
            }
        }
    }
}

/// _setup_polls_for_tests()
/// --
///
/// Test hook: the polls of the set-up counted since ``_on_poll_for_tests(poll, "interrupt_setup")``
/// was last called (until the hook acted or the set-up it was armed for ended).
#[cfg(feature = "test-hooks")]
#[pyfunction]
pub(crate) fn _setup_polls_for_tests() -> usize {
    SETUP_POLLS.load(Ordering::Relaxed)
}

/// _on_poll_for_tests(poll, action, /)
/// --
///
/// Test hook: the next interruptible call, at the ``poll``-th poll of its stop (1 is the first: before
/// the first track of a batch, the first conic solve of branch and bound, ...), ``"interrupt"``s as
/// Ctrl-C does or ``"await_deadline"``s until its time budget has run out; or ``"interrupt_setup"``:
/// Ctrl-C at the ``poll``-th poll of the set-up (reading, sorting, allocating) of the calls to come,
/// until one of them makes its stop.
#[cfg(feature = "test-hooks")]
#[pyfunction]
pub(crate) fn _on_poll_for_tests(poll: usize, action: &str) -> PyResult<()> {
    let action = match action {
        "interrupt" => HookAction::Interrupt,
        "await_deadline" => HookAction::AwaitDeadline,
        "interrupt_setup" => HookAction::InterruptSetup,
        _ => {
            return Err(invalid_argument(
                "action",
                "'interrupt', 'await_deadline' or 'interrupt_setup'",
            ))
        }
    };
    if poll == 0 {
        return Err(invalid_argument("poll", "must be at least 1"));
    }
    *ARMED
        .lock()
        .map_err(|_| invalid_argument("poll", "the hook's lock is poisoned"))? = Some((poll, action));
    SETUP_POLLS.store(0, Ordering::Relaxed);
    MAYBE_ARMED.store(true, Ordering::Relaxed);
    Ok(())
}
