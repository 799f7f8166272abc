//! The one error type of the core crate.
//!
//! Every fallible public function returns `Result<_, Error>`. Each variant names *what* is wrong and
//! *where* (which argument, which index), so that the Python layer can map it to a specific
//! `ValueError` subclass with a useful message without re-deriving anything.

use std::fmt;

/// What went wrong, with enough structure to act on.
#[derive(Debug, Clone, PartialEq)]
pub enum Error {
    /// An array has the wrong length or two arrays that must match do not.
    Shape {
        what: String,
        expected: String,
        actual: String,
    },
    /// A NaN or infinite value; `what` names the argument and `index` the first offending row.
    NonFinite { what: String, index: usize },
    /// Fewer correspondences than the method needs.
    TooFewCorrespondences {
        method: String,
        required: String,
        actual: String,
    },
    /// The data cannot determine the pose: collinear points, parallel lines, a zero-length segment, ...
    Degenerate { what: String },
    /// The camera intrinsics cannot be inverted (zero focal length, non-finite values).
    SingularCamera { what: String },
    /// An option is out of its documented range.
    InvalidOption { name: String, reason: String },
    /// The call was stopped ([`crate::interrupt`]) before this problem (a batch track) was solved.
    Interrupted { reason: crate::interrupt::StopReason },
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Shape { what, expected, actual } => {
                write!(f, "{what}: expected {expected}, got {actual}")
            }
            Error::NonFinite { what, index } => {
                write!(f, "{what}: non-finite value (NaN or inf) in row {index}")
            }
            Error::TooFewCorrespondences {
                method,
                required,
                actual,
            } => {
                write!(f, "method '{method}' needs {required}, got {actual}")
            }
            Error::Degenerate { what } => write!(f, "degenerate configuration: {what}"),
            Error::SingularCamera { what } => write!(f, "singular camera: {what}"),
            Error::InvalidOption { name, reason } => write!(f, "invalid option '{name}': {reason}"),
            Error::Interrupted { reason } => write!(f, "not solved: {}", reason.describe()),
        }
    }
}

impl std::error::Error for Error {}

/// Shorthand used throughout the crate.
pub type Result<T> = std::result::Result<T, Error>;
