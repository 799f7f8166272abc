//! `pluecker.CertifyOptions` and `pluecker.Certificate`: the core's `pluecker::certificate` types,
//! shared by pose and triangulation (same names, same fields, same defaults).

use crate::convert::{Integer, Real};
use crate::errors::to_py_err;
use crate::nested::NestedOptions;
use crate::pickle::reduce;
use crate::properties::{options_class, result_class, Field};
use pluecker::{Certificate, CertifyOptions};
use pyo3::prelude::*;
use pyo3::types::PyTuple;

/// Options of every certificate of global optimality, the core's `CertifyOptions`.
#[pyclass(name = "CertifyOptions", module = "pluecker")]
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PyCertifyOptions {
    pub(crate) inner: CertifyOptions,
}

impl NestedOptions for PyCertifyOptions {
    const CLASS: &'static str = "CertifyOptions";
}

impl PyCertifyOptions {
    fn validate(&self) -> PyResult<()> {
        self.inner.validate("certify").map_err(to_py_err)
    }
}

options_class! {
    PyCertifyOptions {
        /// Certified when `(cost − lower_bound) / max(cost, 1e-12)` is at most this, in (0, 1).
        max_relative_gap: Real = |o| o.inner.max_relative_gap,
            |o, v| v.get("max_relative_gap").map(|x| o.inner.max_relative_gap = x);
        /// Cap on the nodes (rotation cells, boxes) a search examines; `None`: each search's own cap (see the docs).
        max_nodes: Option<Integer> = |o| o.inner.max_nodes,
            |o, v| v.map(|n| n.count("max_nodes", 1)).transpose().map(|n| o.inner.max_nodes = n);
    }
}

/// A proved lower bound on the cost (`Σ r²`, squared whitened pixels) over a stated domain: the
/// core's `Certificate`.
#[pyclass(frozen, name = "Certificate", module = "pluecker")]
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
#[serde(transparent)]
pub struct PyCertificate {
    pub inner: Certificate,
}

result_class! {
    PyCertificate {
        /// Whether the estimate is proved globally optimal within `max_relative_gap` over `domain`.
        certified = |c| c.inner.certified;
        /// Proved lower bound on the cost over `domain`, capped at the cost.
        lower_bound = |c| c.inner.lower_bound;
        /// The bound as proved, before the cap at the cost (inf when the search set was proved empty).
        raw_lower_bound = |c| c.inner.raw_lower_bound;
        /// `(cost − lower_bound) / max(cost, 1e-12)`.
        relative_gap = |c| c.inner.relative_gap;
        /// How the bound was proved: `convexity_test`, `branch_and_bound`, `taylor_branch_and_bound`, `lens_convexity_test` (triangulation); `sublevel_set`, `lens_sublevel_set` (pose)
        kind = |c| c.inner.kind.as_str();
        /// What was estimated: `pose`, `point`, `line` or `quadric`.
        primitive = |c| c.inner.primitive.as_str();
        /// The set of estimates over which `lower_bound` holds, in words (set by `kind` and `primitive`).
        domain = |c| c.inner.domain();
        /// Nodes of the search (0 for a convexity test).
        nodes = |c| c.inner.nodes;
        /// Conic-solver iterations summed over the nodes.
        solver_iterations = |c| c.inner.solver_iterations;
    }

    /// Pickle support (also `copy.deepcopy`): see `pickle.rs`.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        reduce(py, "Certificate", self)
    }

    fn __repr__(&self) -> String {
        let c = &self.inner;
        format!(
            "Certificate(certified={}, kind='{}', lower_bound={:.6e}, relative_gap={:.3e}, nodes={})",
            if c.certified { "True" } else { "False" },
            c.kind.as_str(),
            c.lower_bound,
            c.relative_gap,
            c.nodes
        )
    }
}

/// A certificate as a property: the `Certificate` object, and its `to_dict()` in plain form.
impl Field for PyCertificate {
    fn get(self, py: Python<'_>) -> PyResult<PyObject> {
        Ok(Py::new(py, self)?.into_any())
    }
    fn plain(self, py: Python<'_>) -> PyResult<PyObject> {
        let d = pyo3::types::PyDict::new(py);
        self.fill_dict(py, &d)?;
        Ok(crate::convert::strict_json_dict(d)?.into_any().unbind())
    }
    fn stub() -> String {
        "Certificate".into()
    }
}

/// `Option<Certificate>` of the core as the Python property: `None` when no bound was computed.
pub(crate) fn certificate_of(certificate: Option<Certificate>) -> Option<PyCertificate> {
    certificate.map(|inner| PyCertificate { inner })
}
