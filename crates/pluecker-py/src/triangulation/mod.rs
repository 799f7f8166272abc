//! Triangulation bindings: the options ([`PyTriangulationOptions`]), the shared report of one
//! triangulation ([`report`]) and of a batch ([`batch`]), and one module per primitive ([`point`],
//! [`line`], [`quadric`]) with its single and batch function, as the core has them; [`fitting`]
//! gives the image lines and conics with their covariances.

pub mod batch;
pub mod fitting;
pub mod line;
pub mod observation_rows;
pub mod point;
pub mod quadric;
pub mod report;

use crate::certificate::PyCertifyOptions;
use crate::convert::{Integer, Real};
use crate::errors::to_py_err;
use crate::nested::Shared;
use crate::properties::options_class;
use pluecker::triangulation::{LineBound, Method, QuadricBound, TriangulationOptions};
use pyo3::prelude::*;

/// Options of every triangulation function, the core's `TriangulationOptions` (every default is the
/// core's). `certify` is a `CertifyOptions` object held by reference, read at call time.
#[pyclass(name = "TriangulationOptions", module = "pluecker")]
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PyTriangulationOptions {
    /// Every option but `certify` (whose copy here is not read).
    inner: TriangulationOptions,
    certify: Shared<PyCertifyOptions>,
}

impl PyTriangulationOptions {
    fn validate(&self) -> PyResult<()> {
        self.core().validate().map_err(to_py_err)
    }

    /// The core's options, with `certify` as it is now.
    pub(crate) fn core(&self) -> TriangulationOptions {
        let mut options = self.inner.clone();
        options.certify = self.certify.read().inner;
        options
    }
}

options_class! {
    PyTriangulationOptions {
        /// Estimator, one of `TRIANGULATION_METHODS`: `linear`, `local` or `optimal` (certified).
        method: String = |o| o.inner.method.as_str(), |o, v| Method::parse(&v).map(|m| o.inner.method = m).map_err(to_py_err);
        /// Method `optimal`: the certificate's gap and node cap (`max_nodes=None`: 2000 nodes of the conic branch and bounds, points, quadrics and `line_bound="relaxation"`; 50000 of the Taylor bound of lines), the object itself (`options.certify.max_nodes = 10` takes effect).
        certify: Shared<PyCertifyOptions> = |o| o.certify.clone(), |o, v| Ok::<(), PyErr>(o.certify = v);
        /// Points and lines: reject observations whose whitened error (pixels without `covariances`) exceeds this, by a consensus over view pairs, and solve on the rest (`inliers` of the result); `None`: use every observation.
        outlier_threshold: Option<Real> = |o| o.inner.outlier_threshold,
            |o, v| v.map(|r| r.get("outlier_threshold")).transpose().map(|g| o.inner.outlier_threshold = g);
        /// Lines, method `optimal`: the lower bound, `taylor` (interval Taylor bounds over the two-view chart; certificate `taylor_branch_and_bound` over every line) or `relaxation` (the paper's SOCP relaxation, eqs. 21-27; certificate `branch_and_bound` over the eq. 27 strips).
        line_bound: String = |o| o.inner.line_bound.as_str(), |o, v| LineBound::parse(&v).map(|m| o.inner.line_bound = m).map_err(to_py_err);
        /// Quadrics, method `optimal`: the lower bound, `convexity` (the convexity test, certificate `convexity_test` over every ellipsoid no principal plane cuts; the relaxation when it cannot decide) or `relaxation` (the paper's SOCP relaxation only; certificate `branch_and_bound` over an a-priori box).
        quadric_bound: String = |o| o.inner.quadric_bound.as_str(), |o, v| QuadricBound::parse(&v).map(|m| o.inner.quadric_bound = m).map_err(to_py_err);
        /// Iteration cap of the local minimisation (method `local`, and the upper bounds of `optimal`).
        local_max_iterations: Integer = |o| o.inner.local.stopping.max_iterations,
            |o, v| v.count("local_max_iterations", 1).map(|n| o.inner.local.stopping.max_iterations = n);
    }
}

/// The core's options of a triangulation function's `options=` (the defaults without one).
pub(crate) fn options_arg(options: Option<PyRef<'_, PyTriangulationOptions>>) -> PyResult<TriangulationOptions> {
    let opts = options.map_or_else(TriangulationOptions::default, |o| o.core());
    // `certify` may have been changed through its own object since it was assigned.
    opts.validate().map_err(to_py_err)?;
    Ok(opts)
}

/// `σ²` of the pixel noise `sigma` for a covariance `σ² I`, unless `sigma` is not a positive finite
/// number or `σ²` is not a normal double (it overflows, or underflows to a subnormal or zero, whose
/// inverse, the information, overflows): then an error naming `sigma`.
pub(crate) fn sigma_variance(sigma: f64) -> PyResult<f64> {
    let sigma = positive_sigma(sigma)?;
    let variance = sigma * sigma;
    if variance.is_normal() {
        return Ok(variance);
    }
    let flow = if variance.is_finite() {
        "underflows"
    } else {
        "overflows"
    };
    Err(crate::errors::invalid_argument(
        "sigma",
        format!(
            "σ = {} px: the covariance σ² I {flow} double precision",
            pluecker::testing::number(sigma)
        ),
    ))
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
                pluecker::testing::number(sigma)
            ),
        ))
    }
}
