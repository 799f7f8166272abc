//! The one error type of the core crate.
//!
//! Every fallible public function returns `Result<_, Error>`. Each variant names *what* is wrong and
//! *where* (which argument, which index), so that the Python layer can map it to a specific
//! `ValueError` subclass with a useful message without re-deriving anything.

use std::fmt;

/// What went wrong, with enough structure to act on.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum Error {
    /// An array has the wrong length or two arrays that must match do not.
    Shape {
        /// The argument (and row, when one row is wrong).
        what: String,
        /// The expected shape or length.
        expected: String,
        /// The shape or length given.
        actual: String,
    },
    /// A NaN or infinite value; `what` names the argument and `index` the first offending row.
    NonFinite {
        /// The argument.
        what: String,
        /// The first row with a NaN or infinite value.
        index: usize,
    },
    /// Fewer correspondences than the method needs.
    TooFewCorrespondences {
        /// The method that needs them.
        method: String,
        /// What it needs, e.g. "6 points".
        required: String,
        /// What was given.
        actual: String,
    },
    /// The data cannot determine the pose: collinear points, parallel lines, a zero-length segment, ...
    Degenerate {
        /// What is degenerate, and where.
        what: String,
    },
    /// The camera intrinsics cannot be inverted (zero focal length, non-finite values).
    SingularCamera {
        /// Which camera, and why.
        what: String,
    },
    /// An option is out of its documented range.
    InvalidOption {
        /// The option's name, nested as in the options (`certify.max_nodes`).
        name: String,
        /// The documented range it is outside of.
        reason: String,
    },
    /// The call was stopped ([`crate::interrupt`]) before this problem (a batch track) was solved.
    Interrupted {
        /// Ctrl-C (or a failed progress callback), or the time budget.
        reason: crate::interrupt::StopReason,
    },
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

/// A number as messages print it: six significant digits, like C's `%g` (`1e+300`, `0.001`,
/// `-2.5`, `nan`, `inf`), so that a value such as `1e300` is not spelled out in 300 digits.
pub fn number(x: f64) -> String {
    if x.is_nan() {
        return "nan".into();
    }
    if x.is_infinite() {
        return if x > 0.0 { "inf" } else { "-inf" }.into();
    }
    if x == 0.0 {
        return "0".into();
    }
    const DIGITS: i32 = 6;
    // The decimal exponent after rounding to DIGITS significant digits (9.999995 rounds to 10).
    let scientific = format!("{:.*e}", (DIGITS - 1) as usize, x);
    let (mantissa, exponent) = scientific.split_once('e').expect("`{:e}` writes an exponent");
    let exponent: i32 = exponent.parse().expect("`{:e}` writes an integer exponent");
    let trim = |s: &str| -> String {
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s.to_string()
        }
    };
    if (-4..DIGITS).contains(&exponent) {
        trim(&format!("{:.*}", (DIGITS - 1 - exponent) as usize, x))
    } else {
        let sign = if exponent < 0 { '-' } else { '+' };
        format!("{}e{sign}{:02}", trim(mantissa), exponent.abs())
    }
}

#[cfg(test)]
mod tests {
    use super::number;

    #[test]
    fn numbers_print_with_six_significant_digits_as_percent_g() {
        let cases = [
            (1e300, "1e+300"),
            (-1e-200, "-1e-200"),
            (0.5, "0.5"),
            (2.0, "2"),
            (123456.0, "123456"),
            (1234567.0, "1.23457e+06"),
            (9.999995, "10"),
            (0.0001, "0.0001"),
            (0.00001234, "1.234e-05"),
            (1.0 / 3.0, "0.333333"),
            (0.0, "0"),
            (f64::NAN, "nan"),
            (f64::NEG_INFINITY, "-inf"),
        ];
        for (x, shown) in cases {
            assert_eq!(number(x), shown, "{x:e}");
        }
    }
}
