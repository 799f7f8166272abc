//! `pluecker.TriangulationReport`: what one triangulation did (`pluecker::triangulation::Report`),
//! the base class of the point, line and quadric results, which add their estimate.

use crate::fields::result_class;
use crate::pickle::{pack_struct, reduce, Pack, Reader};
use pluecker::triangulation::{Report, Status};
use pyo3::prelude::*;
use pyo3::types::PyTuple;

/// What one triangulation did: method, status, the cost of eq. 19 at the estimate, the certificate
/// of global optimality, iterations and time.
#[pyclass(frozen, subclass, name = "TriangulationReport", module = "pluecker")]
#[derive(Debug, Clone)]
pub struct PyTriangulationReport {
    pub inner: Report,
}

impl PyTriangulationReport {
    /// `key=value` pairs of the report for the subclasses' `__repr__`.
    pub fn repr_fields(&self) -> String {
        let r = &self.inner;
        format!(
            "method='{}', status='{}', cost={:.6e}, certified={}, certificate='{}', relative_gap={:.3e}, nodes={}",
            r.method.as_str(),
            r.status.as_str(),
            r.cost,
            if r.certificate.certified { "True" } else { "False" },
            r.certificate.kind.as_str(),
            r.certificate.relative_gap,
            r.certificate.nodes
        )
    }
}

result_class! {
    PyTriangulationReport {
        /// The method that ran: `linear`, `local` or `optimal`.
        method = |r| r.inner.method.as_str();
        /// `success`, or why not: `gap_not_closed` (branch and bound hit `max_nodes`), `not_converged`, `behind_camera`,
        /// `at_infinity` (no finite estimate: NaN), `infeasible` (nothing within `max_reprojection_error`),
        /// `numerical_failure`; in batches also `interrupted`, `time_budget` and the rejection statuses.
        status = |r| r.inner.status.as_str();
        /// `status == 'success'`.
        success = |r| r.inner.status == Status::Success;
        /// The cost of eq. 19 (sum of squared whitened reprojection errors) at the estimate.
        cost = |r| r.inner.cost;
        /// Proved lower bound on the cost over every estimate in front of the cameras (0 without a certificate).
        lower_bound = |r| r.inner.certificate.lower_bound;
        /// The bound as proved, before `lower_bound`'s cap at the cost (NaN without a bound, inf for an empty search set).
        raw_lower_bound = |r| r.inner.certificate.raw_lower_bound;
        /// `(cost − lower_bound) / cost`.
        relative_gap = |r| r.inner.certificate.relative_gap;
        /// Whether the estimate is proved globally optimal to within the gap.
        certified = |r| r.inner.certificate.certified;
        /// How it was proved: `none`, `convexity_test` or `branch_and_bound`.
        certificate = |r| r.inner.certificate.kind.as_str();
        /// Branch-and-bound nodes.
        nodes = |r| r.inner.certificate.nodes;
        /// Conic-solver iterations summed over the nodes.
        solver_iterations = |r| r.inner.certificate.solver_iterations;
        /// Iterations of the local minimisation.
        iterations = |r| r.inner.iterations;
        /// Why the local minimisation stopped.
        termination = |r| r.inner.termination.as_str();
        /// Wall time, seconds.
        time_seconds = |r| r.inner.time_seconds;
        /// χ² test of `cost` against the given covariances (identity: 1 px), `dof` = residuals − parameters;
        /// `consistent == False` flags an outlier, a wrong camera or noise beyond the stated one. `None` when `dof` is 0.
        residual_test = |r| r.inner.residual_test();
    }

    /// Pickle support (also `copy.deepcopy`): see `pickle.rs`.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        reduce(py, "TriangulationReport", &[self])
    }

    fn __repr__(&self) -> String {
        format!("TriangulationReport({})", self.repr_fields())
    }
}

pack_struct!(PyTriangulationReport { inner });
