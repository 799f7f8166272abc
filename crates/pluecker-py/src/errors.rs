//! The one place where errors cross into Python.
//!
//! Every [`pluecker::Error`] variant maps to one `ValueError` subclass, and every error the binding
//! itself detects (a bad shape, a NaN, an out-of-range argument) is phrased as a `pluecker::Error`
//! first, so that both kinds of message read the same. A Rust panic never reaches the interpreter:
//! [`guarded`] and [`solve`] turn it into `PlueckerError("internal error: ...")`.

use pluecker::interrupt::StopReason;
use pluecker::Error;
use pyo3::create_exception;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use std::any::Any;
use std::panic::{catch_unwind, AssertUnwindSafe};

create_exception!(
    pluecker,
    PlueckerError,
    PyValueError,
    "Base class of every error pluecker raises for bad input or a failed computation; a ValueError."
);
create_exception!(
    pluecker,
    ShapeError,
    PlueckerError,
    "An array has the wrong shape, or two arrays that must have the same number of rows do not."
);
create_exception!(
    pluecker,
    NonFiniteError,
    PlueckerError,
    "An input holds NaN or inf; the message names the argument and the first offending row."
);
create_exception!(
    pluecker,
    TooFewCorrespondencesError,
    PlueckerError,
    "Fewer correspondences than the method needs."
);
create_exception!(
    pluecker,
    DegenerateConfigurationError,
    PlueckerError,
    "The data cannot determine the answer: collinear points, parallel or concurrent lines, a zero-length segment, a singular information matrix."
);
create_exception!(
    pluecker,
    SingularCameraError,
    PlueckerError,
    "The intrinsics cannot be inverted: a zero focal length, a non-finite entry, a K that is not upper triangular."
);
create_exception!(
    pluecker,
    InvalidOptionError,
    PlueckerError,
    "An option or argument value is outside its domain: unknown method, non-positive penalty, R not a rotation, ..."
);

/// The Python exception for a core error, with the core's message.
pub fn to_py_err(err: Error) -> PyErr {
    let message = err.to_string();
    match err {
        Error::Shape { .. } => ShapeError::new_err(message),
        Error::NonFinite { .. } => NonFiniteError::new_err(message),
        Error::TooFewCorrespondences { .. } => TooFewCorrespondencesError::new_err(message),
        Error::Degenerate { .. } => DegenerateConfigurationError::new_err(message),
        Error::SingularCamera { .. } => SingularCameraError::new_err(message),
        Error::InvalidOption { .. } => InvalidOptionError::new_err(message),
        Error::Interrupted {
            reason: StopReason::Requested,
        } => pyo3::exceptions::PyKeyboardInterrupt::new_err(message),
        Error::Interrupted {
            reason: StopReason::TimeBudget,
        } => pyo3::exceptions::PyTimeoutError::new_err(message),
        // `Error` is non-exhaustive: a kind added to the core is at least a `PlueckerError` (a ValueError).
        _ => PlueckerError::new_err(message),
    }
}

/// An argument whose value (not its shape) is out of range: `"{name}: {reason}"`.
pub fn invalid_argument(name: &str, reason: impl Into<String>) -> PyErr {
    InvalidOptionError::new_err(format!("{name}: {}", reason.into()))
}

/// A wrong shape, phrased like the core's: `"{what}: expected {expected}, got {actual}"`.
pub fn shape_error(what: &str, expected: &str, actual: String) -> PyErr {
    to_py_err(Error::Shape {
        what: what.into(),
        expected: expected.into(),
        actual,
    })
}

/// A NaN or inf in row `index` of `what`.
pub fn non_finite(what: &str, index: usize) -> PyErr {
    to_py_err(Error::NonFinite {
        what: what.into(),
        index,
    })
}

/// A configuration that cannot determine the answer.
pub fn degenerate(what: impl Into<String>) -> PyErr {
    to_py_err(Error::Degenerate { what: what.into() })
}

fn panic_message(payload: &(dyn Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "a panic without a message".into()
    }
}

pub(crate) fn internal(payload: Box<dyn Any + Send>) -> PyErr {
    PlueckerError::new_err(format!(
        "internal error: {} (this is a bug in pluecker; please report it with the input that caused it)",
        panic_message(payload.as_ref())
    ))
}

/// Runs a core call with the GIL held, turning a core error into its exception and a panic into
/// `PlueckerError("internal error: ...")`.
pub fn guarded<T>(f: impl FnOnce() -> Result<T, Error>) -> PyResult<T> {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(result) => result.map_err(to_py_err),
        Err(payload) => Err(internal(payload)),
    }
}

/// Adds the exception classes to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("PlueckerError", py.get_type::<PlueckerError>())?;
    m.add("ShapeError", py.get_type::<ShapeError>())?;
    m.add("NonFiniteError", py.get_type::<NonFiniteError>())?;
    m.add(
        "TooFewCorrespondencesError",
        py.get_type::<TooFewCorrespondencesError>(),
    )?;
    m.add(
        "DegenerateConfigurationError",
        py.get_type::<DegenerateConfigurationError>(),
    )?;
    m.add("SingularCameraError", py.get_type::<SingularCameraError>())?;
    m.add("InvalidOptionError", py.get_type::<InvalidOptionError>())?;
    Ok(())
}

/// Sets `error.partial = partial` (the results of an interrupted batch) and returns `error`.
pub(crate) fn with_partial(py: Python<'_>, error: PyErr, partial: PyObject) -> PyErr {
    // An exception instance without a writable `__dict__` keeps its message; the results are lost.
    let _ = error.value(py).setattr("partial", partial);
    error
}
