//! `pluecker.BatchReport`: the per-track report columns shared by every batch result
//! (`PointTriangulations`, `LineTriangulations`, `QuadricTriangulations` extend it), and the one way
//! these results are filled from the core's per-track results ([`collect`]).
//!
//! A track the core rejected gets a NaN cost, no certificate, a status naming the error kind
//! ([`error_status`]) and a message; its estimate columns are NaN.

use crate::triangulation::renamed;
use numpy::PyArray1;
use pluecker::triangulation::{CertificateKind, Method, Report, Status};
use pluecker::chi_square::ResidualTest;
use pluecker::interrupt::StopReason;
use pluecker::Error;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use crate::convert::strict_json_dict;
use crate::pickle::{pack_struct, reduce, Pack, Reader};
use pyo3::types::PyTuple;


/// The status of a track the core rejected, by error kind (shared by every batch result).
pub(crate) fn error_status(err: &Error) -> &'static str {
    match err {
        Error::TooFewCorrespondences { .. } => "too_few_views",
        Error::NonFinite { .. } => "non_finite",
        Error::Degenerate { .. } => "degenerate",
        Error::SingularCamera { .. } => "singular_camera",
        Error::Shape { .. } => "invalid_input",
        Error::InvalidOption { .. } => "invalid_option",
        Error::Interrupted { reason } => Status::stopped(*reason).as_str(),
    }
}

/// Why track of `status` and `cost` was not started, if the batch was stopped before it (its cost is
/// NaN; a track stopped while being solved keeps the cost it reached).
fn not_started(status: &str, cost: f64) -> Option<StopReason> {
    if !cost.is_nan() {
        None
    } else if status == Status::Interrupted.as_str() {
        Some(StopReason::Requested)
    } else if status == Status::TimeBudget.as_str() {
        Some(StopReason::TimeBudget)
    } else {
        None
    }
}

/// A numpy array of strings (dtype `<U…`).
pub(crate) fn strings<'py>(py: Python<'py>, values: &[&'static str]) -> PyResult<Bound<'py, PyAny>> {
    let list = PyList::new(py, values)?;
    py.import("numpy")?.call_method1("array", (list, "str"))
}

/// The estimate columns of a batch result class (its fields beside the [`PyBatchReport`] columns),
/// filled track by track by [`collect`].
pub(crate) trait TrackColumns: Default {
    /// The core's result of one track.
    type Track;
    /// Core argument names and the Python names they are reported under (see [`renamed`]).
    const NAMES: &'static [(&'static str, &'static str)];

    /// Appends the estimate of a solved track and hands back its report.
    fn push(&mut self, track: Self::Track) -> Report;
    /// Appends NaN estimates for a rejected track.
    fn push_missing(&mut self);

    /// The message of rejected track `t`: `"track t: ..."`, the core's own `"track t: "` not repeated.
    fn message(t: usize, err: &Error) -> String {
        let prefix = format!("track {t}: ");
        let text = err.to_string().replacen(&prefix, "", 1);
        format!("{prefix}{text}")
    }
}

/// The report columns and the estimate columns of the core's per-track `results` (track `t` is
/// `results[t]`), solved with `method`.
pub(crate) fn collect<C: TrackColumns>(method: Method, results: Vec<pluecker::Result<C::Track>>) -> (PyBatchReport, C) {
    let mut report = PyBatchReport::with_capacity(method, results.len());
    let mut columns = C::default();
    for (t, result) in results.into_iter().enumerate() {
        match result {
            Ok(track) => report.push(&columns.push(track)),
            Err(e) => report.reject(&mut columns, t, e),
        }
    }
    (report, columns)
}

/// The per-track report columns of a batch: the fields of `TriangulationReport`, one entry per track.
#[pyclass(frozen, subclass, name = "BatchReport", module = "pluecker")]
#[derive(Debug)]
pub struct PyBatchReport {
    method: &'static str,
    cost: Vec<f64>,
    lower_bound: Vec<f64>,
    relative_gap: Vec<f64>,
    certified: Vec<bool>,
    certificate: Vec<&'static str>,
    status: Vec<&'static str>,
    nodes: Vec<i64>,
    iterations: Vec<i64>,
    time_seconds: Vec<f64>,
    /// Degrees of freedom of each cost (0: no χ² test); `p_value` derives from them and `cost`.
    residual_dof: Vec<usize>,
    /// `(track, message)` of every rejected track.
    errors: Vec<(usize, String)>,
}

impl PyBatchReport {
    /// Empty columns for `n` tracks solved with `method`.
    pub(crate) fn with_capacity(method: Method, n: usize) -> Self {
        PyBatchReport {
            method: method.as_str(),
            cost: Vec::with_capacity(n),
            lower_bound: Vec::with_capacity(n),
            relative_gap: Vec::with_capacity(n),
            certified: Vec::with_capacity(n),
            certificate: Vec::with_capacity(n),
            status: Vec::with_capacity(n),
            nodes: Vec::with_capacity(n),
            iterations: Vec::with_capacity(n),
            time_seconds: Vec::with_capacity(n),
            residual_dof: Vec::with_capacity(n),
            errors: Vec::new(),
        }
    }

    /// Appends a solved track's report.
    pub(crate) fn push(&mut self, report: &Report) {
        let c = &report.certificate;
        self.cost.push(report.cost);
        self.lower_bound.push(c.lower_bound);
        self.relative_gap.push(c.relative_gap);
        self.certified.push(c.certified);
        self.certificate.push(c.kind.as_str());
        self.status.push(report.status.as_str());
        self.nodes.push(c.nodes as i64);
        self.iterations.push(report.iterations as i64);
        self.time_seconds.push(report.time_seconds);
        self.residual_dof.push(report.residual_dof);
    }

    /// Appends a track without a certificate (lower bound 0, relative gap 1, no nodes or
    /// iterations): a linear estimate of the point fast path, or a rejected track.
    pub(crate) fn push_uncertified(&mut self, cost: f64, status: &'static str, seconds: f64, residual_dof: usize) {
        self.cost.push(cost);
        self.lower_bound.push(0.0);
        self.relative_gap.push(1.0);
        self.certified.push(false);
        self.certificate.push(CertificateKind::None.as_str());
        self.status.push(status);
        self.nodes.push(0);
        self.iterations.push(0);
        self.time_seconds.push(seconds);
        self.residual_dof.push(residual_dof);
    }

    /// Appends track `t`, rejected by the core with `err` (its core argument names renamed by
    /// `C::NAMES`): NaN cost and estimates, the error's status and message, time 0.
    ///
    /// A track the call was stopped before (`Error::Interrupted`) stores no message: `messages` says
    /// it from the status, so that stopping a batch of millions of tracks stays cheap.
    pub(crate) fn reject<C: TrackColumns>(&mut self, columns: &mut C, t: usize, err: Error) {
        if let Error::Interrupted { reason } = err {
            self.push_uncertified(f64::NAN, Status::stopped(reason).as_str(), 0.0, 0);
            columns.push_missing();
            return;
        }
        let err = renamed(err, C::NAMES);
        self.push_uncertified(f64::NAN, error_status(&err), 0.0, 0);
        self.errors.push((t, C::message(t, &err)));
        columns.push_missing();
    }

    pub(crate) fn len(&self) -> usize {
        self.status.len()
    }

    /// `class(method=..., tracks=..., success=..., certified=..., rejected=...)`.
    pub(crate) fn repr(&self, class: &str) -> String {
        let success = self.status.iter().filter(|s| **s == Status::Success.as_str()).count();
        let certified = self.certified.iter().filter(|c| **c).count();
        format!(
            "{class}(method='{}', tracks={}, success={success}, certified={certified}, rejected={})",
            self.method,
            self.len(),
            self.errors.len()
        )
    }
}

#[pymethods]
impl PyBatchReport {
    #[getter]
    fn cost<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.cost)
    }

    #[getter]
    fn lower_bound<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.lower_bound)
    }

    #[getter]
    fn relative_gap<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.relative_gap)
    }

    #[getter]
    fn certified<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<bool>> {
        PyArray1::from_slice(py, &self.certified)
    }

    #[getter]
    fn certificate<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        strings(py, &self.certificate)
    }

    #[getter]
    fn status<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        strings(py, &self.status)
    }

    #[getter]
    fn nodes<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        PyArray1::from_slice(py, &self.nodes)
    }

    #[getter]
    fn iterations<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        PyArray1::from_slice(py, &self.iterations)
    }

    #[getter]
    fn time_seconds<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.time_seconds)
    }

    #[getter]
    fn p_value<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let p: Vec<f64> = self
            .cost
            .iter()
            .zip(&self.residual_dof)
            .map(|(&cost, &dof)| ResidualTest::new(cost, dof).map_or(f64::NAN, |t| t.p_value))
            .collect();
        PyArray1::from_vec(py, p)
    }

    #[getter]
    fn messages(&self) -> Vec<String> {
        let mut out: Vec<String> = self
            .status
            .iter()
            .zip(&self.cost)
            .enumerate()
            .map(|(t, (&status, cost))| match not_started(status, *cost) {
                Some(reason) => format!("track {t}: {}", Error::Interrupted { reason }),
                None => String::new(),
            })
            .collect();
        for (track, message) in &self.errors {
            out[*track] = message.clone();
        }
        out
    }

    #[getter]
    fn method(&self) -> &'static str {
        self.method
    }

    fn __len__(&self) -> usize {
        self.len()
    }

    /// Plain-Python (strict JSON) form: every report column as a list, one entry per track.
    fn to_dict<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyDict>> {
        batch_dict(slf.as_any(), &[])
    }

    /// Pickle support (also `copy.deepcopy`): see `pickle.rs`.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        reduce(py, "BatchReport", &[self])
    }

    fn __repr__(&self) -> String {
        self.repr("BatchReport")
    }
}

pack_struct!(PyBatchReport { method, cost, lower_bound, relative_gap, certified, certificate, status, nodes, iterations, time_seconds, residual_dof, errors });

/// The report columns of `NAMES` below and then the estimate `columns` of a batch result as lists,
/// NaN and inf as `None`: the `to_dict()` of every batch class (each array getter's `tolist()`).
pub(crate) fn batch_dict<'py>(result: &Bound<'py, PyAny>, columns: &[&str]) -> PyResult<Bound<'py, PyDict>> {
    const NAMES: [&str; 12] = [
        "method", "status", "cost", "lower_bound", "relative_gap", "certified", "certificate", "nodes",
        "iterations", "time_seconds", "p_value", "messages",
    ];
    let d = PyDict::new(result.py());
    for name in NAMES.iter().chain(columns) {
        let value = result.getattr(*name)?;
        let value = if value.hasattr("tolist")? { value.call_method0("tolist")? } else { value };
        d.set_item(*name, value)?;
    }
    strict_json_dict(d)
}
