//! Triangulation bindings, the shared part: keyword options → `TriangulationOptions`, and the base
//! class `pluecker.TriangulationReport` whose fields every triangulation result carries (the point,
//! line and quadric results extend it).
//!
//! The functions themselves live in `triangulation_point.rs` (one point, a batch of tracks),
//! `triangulation_line.rs`, `triangulation_quadric.rs` and `triangulation_fitting.rs`; the array
//! readers in `triangulation_arrays.rs`.

use crate::result::residual_test_dict;
use crate::convert::{optional_count, optional_real, strict_json_dict, Integer, Real};
use crate::errors::to_py_err;
use pluecker::triangulation::{Method, Report, Status, TriangulationOptions};
use pluecker::Error;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use crate::pickle::{pack_struct, reduce, Pack, Reader};
use pyo3::types::PyTuple;


/// The options from the keyword arguments every triangulation function takes; each is validated
/// by the core (`TriangulationOptions::validate`) so the messages read the same from Rust and Python.
pub fn options(
    method: &str,
    max_relative_gap: Option<Real>,
    max_reprojection_error: Option<Real>,
    max_nodes: Option<Integer>,
) -> PyResult<TriangulationOptions> {
    let mut opts = TriangulationOptions {
        method: Method::parse(method).map_err(to_py_err)?,
        ..Default::default()
    };
    if let Some(gap) = optional_real("max_relative_gap", max_relative_gap)? {
        opts.max_relative_gap = gap;
    }
    opts.max_reprojection_error = optional_real("max_reprojection_error", max_reprojection_error)?;
    if let Some(nodes) = optional_count("max_nodes", max_nodes, 1)? {
        opts.max_nodes = nodes;
    }
    opts.validate().map_err(to_py_err)?;
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

/// What one triangulation did (`pluecker::triangulation::Report`): method, status, the cost of
/// eq. 19 at the estimate, the certificate of global optimality, iterations and time. The point,
/// line and quadric results are subclasses that add the estimate.
#[pyclass(frozen, subclass, name = "TriangulationReport", module = "pluecker")]
#[derive(Debug, Clone)]
pub struct PyTriangulationReport {
    pub inner: Report,
}

impl PyTriangulationReport {
    /// The report fields as a dict (the subclasses add their estimate to it).
    pub fn report_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let r = &self.inner;
        let c = &r.certificate;
        let d = PyDict::new(py);
        d.set_item("method", r.method.as_str())?;
        d.set_item("status", r.status.as_str())?;
        d.set_item("success", r.status == Status::Success)?;
        d.set_item("cost", r.cost)?;
        d.set_item("lower_bound", c.lower_bound)?;
        d.set_item("relative_gap", c.relative_gap)?;
        d.set_item("certified", c.certified)?;
        d.set_item("certificate", c.kind.as_str())?;
        d.set_item("nodes", c.nodes)?;
        d.set_item("solver_iterations", c.solver_iterations)?;
        d.set_item("iterations", r.iterations)?;
        d.set_item("termination", r.termination.as_str())?;
        d.set_item("time_seconds", r.time_seconds)?;
        d.set_item("residual_test", self.residual_test(py)?)?;
        Ok(d)
    }

    /// `key=value` pairs of the report for `__repr__`.
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

#[pymethods]
impl PyTriangulationReport {
    #[getter]
    fn method(&self) -> &'static str {
        self.inner.method.as_str()
    }

    #[getter]
    fn status(&self) -> &'static str {
        self.inner.status.as_str()
    }

    #[getter]
    fn success(&self) -> bool {
        self.inner.status == Status::Success
    }

    #[getter]
    fn cost(&self) -> f64 {
        self.inner.cost
    }

    #[getter]
    fn lower_bound(&self) -> f64 {
        self.inner.certificate.lower_bound
    }

    #[getter]
    fn relative_gap(&self) -> f64 {
        self.inner.certificate.relative_gap
    }

    #[getter]
    fn certified(&self) -> bool {
        self.inner.certificate.certified
    }

    #[getter]
    fn certificate(&self) -> &'static str {
        self.inner.certificate.kind.as_str()
    }

    #[getter]
    fn nodes(&self) -> usize {
        self.inner.certificate.nodes
    }

    #[getter]
    fn solver_iterations(&self) -> usize {
        self.inner.certificate.solver_iterations
    }

    #[getter]
    fn iterations(&self) -> usize {
        self.inner.iterations
    }

    #[getter]
    fn termination(&self) -> &'static str {
        self.inner.termination.as_str()
    }

    #[getter]
    fn time_seconds(&self) -> f64 {
        self.inner.time_seconds
    }

    #[getter]
    fn residual_test<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        self.inner.residual_test().map(|t| residual_test_dict(py, &t)).transpose()
    }

    /// Plain-Python (JSON-serialisable) form of the report fields.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        strict_json_dict(self.report_dict(py)?)
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
