//! `pluecker.TriangulationReport`: what one triangulation did (`pluecker::triangulation::Report`),
//! the base class of the point, line and quadric results, which add their estimate.

use crate::certificate::certificate_of;
use crate::pickle::reduce;
use crate::properties::result_class;
use pluecker::triangulation::Report;
use pyo3::prelude::*;
use pyo3::types::PyTuple;

/// What one triangulation did: method, status, the cost of eq. 19 at the estimate, the certificate
/// of global optimality, iterations and time.
#[pyclass(frozen, subclass, name = "TriangulationReport", module = "pluecker")]
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
#[serde(transparent)]
pub struct PyTriangulationReport {
    pub inner: Report,
}

impl PyTriangulationReport {
    /// `key=value` pairs of the report for the subclasses' `__repr__`.
    pub fn repr_fields(&self) -> String {
        let r = &self.inner;
        let certificate = r.certificate.map_or_else(
            || "None".to_string(),
            |c| {
                format!(
                    "Certificate(certified={}, kind='{}', relative_gap={:.3e}, nodes={})",
                    if c.certified { "True" } else { "False" },
                    c.kind.as_str(),
                    c.relative_gap,
                    c.nodes
                )
            },
        );
        format!(
            "method='{}', status='{}', cost={:.6e}, cost_kind='{}', certificate={certificate}",
            r.method.as_str(),
            r.status.as_str(),
            r.cost,
            r.cost_kind.as_str(),
        )
    }
}

result_class! {
    PyTriangulationReport {
        /// The method that ran: `linear`, `local` or `optimal`.
        method = |r| r.inner.method.as_str();
        /// `success`, or why not: `gap_not_closed` (the certificate's search hit `certify.max_nodes`), `not_converged`, `behind_camera`,
        /// `at_infinity` (no finite estimate: NaN), `numerical_failure`; in batches also `interrupted`, `time_budget` and the rejection statuses.
        status = |r| r.inner.status.as_str();
        /// `status == 'success'`.
        success = |r| r.inner.success();
        /// The cost at the estimate, of kind `cost_kind`: eq. 19 (sum of squared whitened residuals; for points the
        /// reprojection errors), or for segments seen through a lens that distorts their reprojection cost.
        cost = |r| r.inner.cost;
        /// What `cost` measures, and what the certificate bounds: `reprojection` (points; segments
        /// through a lens that distorts: Σ squared distances of the endpoints to the curved images), `line_residual`
        /// (other lines: eq. 19 on the image lines' residuals) or `conic_residual` (quadrics).
        cost_kind = |r| r.inner.cost_kind.as_str();
        /// The proof of global optimality (`Certificate`: `certified`, `lower_bound`, `raw_lower_bound`, `relative_gap`,
        /// `kind`, `domain`, `nodes`); `None` when no bound was computed (methods `linear` and `local`, input refused
        /// before the search). A search that did not close the gap gives `certified == False` and status `gap_not_closed`.
        certificate = |r| certificate_of(r.inner.certificate);
        /// `certificate is not None and certificate.certified`.
        certified = |r| r.inner.certified();
        /// Iterations of the local minimisation.
        iterations = |r| r.inner.iterations;
        /// Why the local minimisation stopped.
        termination = |r| r.inner.termination.as_str();
        /// Wall time, seconds.
        time_seconds = |r| r.inner.time_seconds;
        /// Degrees of freedom of `cost`: whitened residuals minus fitted parameters (0 when not known).
        residual_dof = |r| r.inner.residual_dof;
        /// χ² test of `cost` against the given covariances (identity: 1 px), `dof` = residuals − parameters;
        /// `consistent == False` flags an outlier, a wrong camera or noise beyond the stated one. `None` when `dof` is 0.
        residual_test = |r| r.inner.residual_test();
    }

    /// Pickle support (also `copy.deepcopy`): see `pickle.rs`.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        reduce(py, "TriangulationReport", self)
    }

    fn __repr__(&self) -> String {
        format!("TriangulationReport({})", self.repr_fields())
    }
}
