//! `triangulate_points`: many point tracks seen by one set of cameras, solved by the core's batch
//! (`pluecker::triangulation::batch`, rayon) with the GIL released, and `pluecker.PointTriangulations`,
//! the arrays of their results.
//!
//! The numpy arrays go to the core as flat row-major slices (`PointTracks`), one copy each. A track
//! the core rejects (NaN in a visible view, fewer than two visible views, a covariance that is not
//! positive definite, ...) gets an error status and a message and never stops the others. Method
//! `linear` takes the core's allocation-free path (`triangulate_points_linear`).

use crate::errors::{shape_error, solve, to_py_err};
use crate::triangulation::{options, renamed, POINT_NAMES};
use crate::triangulation_arrays::{cameras, read, read_mask, shape_string, Dim};
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2};
use pluecker::triangulation::batch::{triangulate_points as core_points, triangulate_points_linear, PointTracks};
use pluecker::triangulation::{CertificateKind, Method, Status};
use pluecker::Error;
use pyo3::prelude::*;
use pyo3::types::PyList;
use std::time::Instant;

/// The status of a track the core rejected, by error kind (shared by every batch result).
pub(crate) fn error_status(err: &Error) -> &'static str {
    match err {
        Error::TooFewCorrespondences { .. } => "too_few_views",
        Error::NonFinite { .. } => "non_finite",
        Error::Degenerate { .. } => "degenerate",
        Error::SingularCamera { .. } => "singular_camera",
        Error::Shape { .. } => "invalid_input",
        Error::InvalidOption { .. } => "invalid_option",
    }
}

/// The results of `triangulate_points`, column by column: one entry per track.
#[pyclass(frozen, name = "PointTriangulations", module = "pluecker")]
#[derive(Debug, Default)]
pub struct PyPointTriangulations {
    method: &'static str,
    x: Vec<f64>,
    cost: Vec<f64>,
    lower_bound: Vec<f64>,
    relative_gap: Vec<f64>,
    certified: Vec<bool>,
    certificate: Vec<&'static str>,
    status: Vec<&'static str>,
    nodes: Vec<i64>,
    iterations: Vec<i64>,
    time_seconds: Vec<f64>,
    /// `(track, message)` of every rejected track.
    errors: Vec<(usize, String)>,
}

impl PyPointTriangulations {
    fn with_capacity(method: Method, n: usize) -> Self {
        PyPointTriangulations {
            method: method.as_str(),
            x: Vec::with_capacity(3 * n),
            cost: Vec::with_capacity(n),
            lower_bound: Vec::with_capacity(n),
            relative_gap: Vec::with_capacity(n),
            certified: Vec::with_capacity(n),
            certificate: Vec::with_capacity(n),
            status: Vec::with_capacity(n),
            nodes: Vec::with_capacity(n),
            iterations: Vec::with_capacity(n),
            time_seconds: Vec::with_capacity(n),
            errors: Vec::new(),
        }
    }

    /// Appends a track without a certificate: a linear point, or a track the core rejected.
    fn push_bare(&mut self, x: &[f64], cost: f64, status: &'static str, seconds: f64) {
        self.x.extend_from_slice(x);
        self.cost.push(cost);
        self.lower_bound.push(0.0);
        self.relative_gap.push(1.0);
        self.certified.push(false);
        self.certificate.push(CertificateKind::None.as_str());
        self.status.push(status);
        self.nodes.push(0);
        self.iterations.push(0);
        self.time_seconds.push(seconds);
    }

    fn push_error(&mut self, track: usize, err: Error) {
        let err = renamed(err, POINT_NAMES);
        self.push_bare(&[f64::NAN; 3], f64::NAN, error_status(&err), 0.0);
        self.errors.push((track, format!("track {track}: {err}")));
    }

    fn len(&self) -> usize {
        self.status.len()
    }

    fn floats<'py>(py: Python<'py>, values: &[f64]) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, values)
    }
}

#[pymethods]
impl PyPointTriangulations {
    #[getter(X)]
    fn points<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let array = Array2::from_shape_vec((self.len(), 3), self.x.clone())
            .map_err(|e| pyo3::exceptions::PyRuntimeError::new_err(e.to_string()))?;
        Ok(array.into_pyarray(py))
    }

    #[getter]
    fn cost<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        Self::floats(py, &self.cost)
    }

    #[getter]
    fn lower_bound<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        Self::floats(py, &self.lower_bound)
    }

    #[getter]
    fn relative_gap<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        Self::floats(py, &self.relative_gap)
    }

    #[getter]
    fn time_seconds<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        Self::floats(py, &self.time_seconds)
    }

    #[getter]
    fn certified<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<bool>> {
        PyArray1::from_slice(py, &self.certified)
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
    fn status<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        strings(py, &self.status)
    }

    #[getter]
    fn certificate<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        strings(py, &self.certificate)
    }

    #[getter]
    fn messages(&self) -> Vec<String> {
        let mut out = vec![String::new(); self.len()];
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

    fn __repr__(&self) -> String {
        let success = self.status.iter().filter(|s| **s == Status::Success.as_str()).count();
        let certified = self.certified.iter().filter(|c| **c).count();
        format!(
            "PointTriangulations(method='{}', tracks={}, success={success}, certified={certified}, rejected={})",
            self.method,
            self.len(),
            self.errors.len()
        )
    }
}

/// A numpy array of strings (dtype `<U…`).
pub(crate) fn strings<'py>(py: Python<'py>, values: &[&'static str]) -> PyResult<Bound<'py, PyAny>> {
    let list = PyList::new(py, values)?;
    py.import("numpy")?.call_method1("array", (list, "str"))
}

/// Triangulates many point tracks seen by the same cameras, in parallel (Josephson & Kahl 2008, eq. 19).
#[pyfunction]
#[pyo3(signature = (P, x, visible = None, cov = None, method = "optimal", *, max_relative_gap = None, max_reprojection_error = None, max_nodes = None))]
#[allow(non_snake_case, clippy::too_many_arguments)]
pub fn triangulate_points(
    py: Python<'_>,
    P: &Bound<'_, PyAny>,
    x: &Bound<'_, PyAny>,
    visible: Option<&Bound<'_, PyAny>>,
    cov: Option<&Bound<'_, PyAny>>,
    method: &str,
    max_relative_gap: Option<f64>,
    max_reprojection_error: Option<f64>,
    max_nodes: Option<i64>,
) -> PyResult<PyPointTriangulations> {
    let opts = options(method, max_relative_gap, max_reprojection_error, max_nodes)?;
    let cams = cameras("P", P)?;
    let v = cams.len();
    if v < 2 {
        return Err(to_py_err(Error::TooFewCorrespondences {
            method: opts.method.as_str().into(),
            required: "2 cameras".into(),
            actual: format!("{v} camera(s) in P"),
        }));
    }
    let (shape, observations) = read("x", x, &[Dim::Free("n"), Dim::Free("v"), Dim::Fixed(2)])?;
    if shape[1] != v {
        return Err(shape_error(
            "x",
            &format!("shape (n, {v}, 2) (one column per camera in P)"),
            shape_string(&shape),
        ));
    }
    let n = shape[0];
    let mask = visible.map(|m| read_mask("visible", m, &[n, v])).transpose()?;
    let covariances = match cov {
        Some(c) => {
            let (cshape, values) = read(
                "cov",
                c,
                &[Dim::Free("n"), Dim::Free("v"), Dim::Fixed(2), Dim::Fixed(2)],
            )?;
            if cshape[0] != n || cshape[1] != v {
                let expected = format!("shape ({n}, {v}, 2, 2) (one per observation)");
                return Err(shape_error("cov", &expected, shape_string(&cshape)));
            }
            Some(values)
        }
        None => None,
    };
    let method_used = opts.method;
    solve(py, move || {
        let tracks = PointTracks {
            observations: &observations,
            visible: mask.as_deref(),
            covariances: covariances.as_deref(),
        };
        let mut out = PyPointTriangulations::with_capacity(method_used, n);
        if method_used == Method::Linear {
            let started = Instant::now();
            let linear = triangulate_points_linear(&cams, &tracks).map_err(|e| renamed(e, POINT_NAMES))?;
            // The fast path does not time tracks one by one: each gets the batch's mean.
            let mean = started.elapsed().as_secs_f64() / n.max(1) as f64;
            for (t, outcome) in linear.outcomes.into_iter().enumerate() {
                match outcome {
                    Ok(status) => {
                        out.push_bare(&linear.points[3 * t..3 * t + 3], linear.costs[t], status.as_str(), mean)
                    }
                    Err(e) => out.push_error(t, e),
                }
            }
            return Ok(out);
        }
        for (t, result) in core_points(&cams, &tracks, &opts)
            .map_err(|e| renamed(e, POINT_NAMES))?
            .into_iter()
            .enumerate()
        {
            match result {
                Ok(r) => {
                    let (rep, c) = (&r.report, &r.report.certificate);
                    out.x.extend_from_slice(r.point.as_slice());
                    out.cost.push(rep.cost);
                    out.lower_bound.push(c.lower_bound);
                    out.relative_gap.push(c.relative_gap);
                    out.certified.push(c.certified);
                    out.certificate.push(c.kind.as_str());
                    out.status.push(rep.status.as_str());
                    out.nodes.push(c.nodes as i64);
                    out.iterations.push(rep.iterations as i64);
                    out.time_seconds.push(rep.time_seconds);
                }
                Err(e) => out.push_error(t, e),
            }
        }
        Ok(out)
    })
}
