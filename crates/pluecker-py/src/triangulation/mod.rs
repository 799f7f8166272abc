//! Triangulation bindings: the options ([`PyTriangulationOptions`]), the shared report of one
//! triangulation ([`report`]) and of a batch ([`batch`]), and one module per primitive ([`point`],
//! [`line`], [`quadric`]) with its single and batch function, as the core has them; [`fitting`]
//! gives the image lines and conics with their covariances.

pub mod batch;
pub mod fitting;
pub mod line;
pub mod point;
pub mod quadric;
pub mod report;
pub mod rows;

use crate::convert::{Integer, Real};
use crate::errors::to_py_err;
use crate::fields::options_class;
use pluecker::triangulation::{LineBound, Method, QuadricBound, TriangulationOptions};
use pluecker::Error;
use pyo3::prelude::*;

/// Options of every triangulation function, the core's `TriangulationOptions` (every default is the
/// core's). A `method=` given to the function itself wins over `options.method`.
#[pyclass(name = "TriangulationOptions", module = "pluecker")]
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PyTriangulationOptions {
    inner: TriangulationOptions,
}

impl PyTriangulationOptions {
    fn validate(&self) -> PyResult<()> {
        self.inner.validate().map_err(to_py_err)
    }
}

options_class! {
    PyTriangulationOptions {
        /// Estimator, one of `TRIANGULATION_METHODS`: `linear`, `local` or `optimal` (certified).
        method: String = |o| o.inner.method.as_str(), |o, v| Method::parse(&v).map(|m| o.inner.method = m).map_err(to_py_err);
        /// Branch and bound stops when `(upper − lower) / upper` is at most this.
        max_relative_gap: Real = |o| o.inner.max_relative_gap, |o, v| v.get("max_relative_gap").map(|x| o.inner.max_relative_gap = x);
        /// The paper's γ: search only where the whitened error is at most γ in every view; `None`: from the local solution, losing nothing.
        max_reprojection_error: Option<Real> = |o| o.inner.max_reprojection_error,
            |o, v| v.map(|r| r.get("max_reprojection_error")).transpose().map(|g| o.inner.max_reprojection_error = g);
        /// Branch and bound with conic relaxations (points, quadrics, `line_bound="relaxation"`) gives up (status `gap_not_closed`) after this many nodes.
        max_nodes: Integer = |o| o.inner.max_nodes, |o, v| v.count("max_nodes", 1).map(|n| o.inner.max_nodes = n);
        /// Points and lines: reject observations whose whitened error (pixels without `cov`) exceeds this, by a consensus over view pairs, and solve on the rest (`inliers` of the result); `None`: use every observation.
        outlier_threshold: Option<Real> = |o| o.inner.outlier_threshold,
            |o, v| v.map(|r| r.get("outlier_threshold")).transpose().map(|g| o.inner.outlier_threshold = g);
        /// Lines, method `optimal`: the lower bound, `taylor` (interval Taylor bounds over the two-view chart; certificate `taylor_branch_and_bound` over every line) or `relaxation` (the paper's SOCP relaxation, eqs. 21-27; certificate `branch_and_bound` over the eq. 27 strips).
        line_bound: String = |o| o.inner.line_bound.as_str(), |o, v| LineBound::parse(&v).map(|m| o.inner.line_bound = m).map_err(to_py_err);
        /// Quadrics, method `optimal`: the lower bound, `convexity` (the convexity test, certificate `convexity_test` over every ellipsoid no principal plane cuts; the relaxation when it cannot decide) or `relaxation` (the paper's SOCP relaxation only; certificate `branch_and_bound` over an a-priori box).
        quadric_bound: String = |o| o.inner.quadric_bound.as_str(), |o, v| QuadricBound::parse(&v).map(|m| o.inner.quadric_bound = m).map_err(to_py_err);
        /// Node cap of the Taylor bound of lines (microseconds per node, so separate from `max_nodes`).
        max_taylor_nodes: Integer = |o| o.inner.max_taylor_nodes, |o, v| v.count("max_taylor_nodes", 1).map(|n| o.inner.max_taylor_nodes = n);
        /// Iteration cap of the local minimisation (method `local`, and the upper bounds of `optimal`).
        local_max_iterations: Integer = |o| o.inner.local.stopping.max_iterations,
            |o, v| v.count("local_max_iterations", 1).map(|n| o.inner.local.stopping.max_iterations = n);
    }
}

/// The core's options of a triangulation function's `options=` and `method=` (which wins).
pub(crate) fn options_arg(
    method: Option<&str>,
    options: Option<PyRef<'_, PyTriangulationOptions>>,
) -> PyResult<TriangulationOptions> {
    let mut opts = options.map_or_else(TriangulationOptions::default, |o| o.inner.clone());
    if let Some(method) = method {
        opts.method = Method::parse(method).map_err(to_py_err)?;
    }
    Ok(opts)
}

/// Core argument names → Python argument names of the point functions.
pub const POINT_NAMES: &[(&str, &str)] = &[("cameras", "P"), ("observations", "x"), ("covariances", "cov")];

/// `name` with a leading core argument name replaced by its Python name (`"cameras[2]: ..."` →
/// `"P[2]: ..."`), so that errors raised by the core name what the Python caller passed.
fn rename(text: &str, names: &[(&str, &str)]) -> String {
    for (core, python) in names {
        if let Some(rest) = text.strip_prefix(core) {
            if rest.is_empty() || rest.starts_with(['[', ':', ' ']) {
                return format!("{python}{rest}");
            }
        }
    }
    text.to_string()
}

/// A core error with its argument names translated by `names` (see [`rename`]).
pub fn renamed(err: Error, names: &[(&str, &str)]) -> Error {
    match err {
        Error::Shape { what, expected, actual } => Error::Shape {
            what: rename(&what, names),
            expected,
            actual,
        },
        Error::NonFinite { what, index } => Error::NonFinite {
            what: rename(&what, names),
            index,
        },
        Error::Degenerate { what } => Error::Degenerate {
            what: rename(&what, names),
        },
        Error::SingularCamera { what } => Error::SingularCamera {
            what: rename(&what, names),
        },
        other => other,
    }
}

/// `sigma`, a pixel noise, unless it is not a positive finite number: then an error naming `sigma`.
pub(crate) fn positive_sigma(sigma: f64) -> PyResult<f64> {
    if sigma.is_finite() && sigma > 0.0 {
        Ok(sigma)
    } else {
        Err(crate::errors::invalid_argument(
            "sigma",
            format!(
                "must be a positive finite number of pixels, got {}",
                pluecker::error::number(sigma)
            ),
        ))
    }
}
