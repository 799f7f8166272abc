//! `triangulate_lines` and `triangulate_quadrics`: many line or quadric tracks solved by the core's
//! batches (`pluecker::triangulation::{line_batch, quadric_batch}`, rayon) with the GIL released, and
//! their results `pluecker.LineTriangulations` / `pluecker.QuadricTriangulations`, column arrays with
//! the per-track report columns of their base class `pluecker.BatchReport`.
//!
//! The numpy arrays go to the core as flat row-major slices, one copy each. Cameras are `(v, 3, 4)`,
//! shared by every track, or `(n, v, 3, 4)`, one set per track. A track the core rejects gets an
//! error status and a message and never stops the others. With a `progress` callable the batch runs
//! on a worker thread while the calling thread reports the count of finished tracks to it.

use crate::errors::{guarded, invalid_argument, shape_error, solve, to_py_err};
use crate::triangulation::{options, renamed};
use crate::triangulation_arrays::{read, read_any, read_mask, shape_string, Dim};
use nalgebra::Matrix3x4;
use numpy::ndarray::{ArrayD, IxDyn};
use numpy::{IntoPyArray, PyArray1, PyArrayDyn};
use pluecker::triangulation::batch::TrackCameras;
use pluecker::triangulation::line::LineTriangulation;
use pluecker::triangulation::line_batch::{triangulate_lines as core_lines, ImageLines, LineTracks};
use pluecker::triangulation::quadric::QuadricTriangulation;
use pluecker::triangulation::quadric_batch::{triangulate_quadrics as core_quadrics, QuadricTracks};
use pluecker::triangulation::{CertificateKind, Method, Report, Status, TriangulationOptions};
use crate::triangulation_batch::{error_status, strings};
use crate::triangulation_line::LINE_NAMES;
use crate::triangulation_quadric::QUADRIC_NAMES;
use pluecker::Error;
use pyo3::prelude::*;
use std::panic::{catch_unwind, resume_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Duration;

/// A float64 array of `shape` from row-major `values`.
fn array<'py>(py: Python<'py>, values: &[f64], shape: &[usize]) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let array = ArrayD::from_shape_vec(IxDyn(shape), values.to_vec())
        .map_err(|e| pyo3::exceptions::PyRuntimeError::new_err(e.to_string()))?;
    Ok(array.into_pyarray(py))
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
    /// `(track, message)` of every rejected track.
    errors: Vec<(usize, String)>,
}

impl PyBatchReport {
    fn with_capacity(method: Method, n: usize) -> Self {
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
            errors: Vec::new(),
        }
    }

    fn push(&mut self, report: &Report) {
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
    }

    /// A rejected track: NaN cost, no certificate, the error's status and message (`"track t: ..."`,
    /// the core's own `"track t: "` not repeated).
    fn push_error(&mut self, track: usize, err: Error) {
        self.cost.push(f64::NAN);
        self.lower_bound.push(0.0);
        self.relative_gap.push(1.0);
        self.certified.push(false);
        self.certificate.push(CertificateKind::None.as_str());
        self.status.push(error_status(&err));
        self.nodes.push(0);
        self.iterations.push(0);
        self.time_seconds.push(0.0);
        let prefix = format!("track {track}: ");
        let text = err.to_string().replacen(&prefix, "", 1);
        self.errors.push((track, format!("{prefix}{text}")));
    }

    fn len(&self) -> usize {
        self.status.len()
    }

    fn repr(&self, class: &str) -> String {
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
        self.repr("BatchReport")
    }
}

/// The results of `triangulate_lines`: Plücker coordinates, points and directions per track.
#[pyclass(frozen, extends = PyBatchReport, name = "LineTriangulations", module = "pluecker")]
#[derive(Debug, Default)]
pub struct PyLineTriangulations {
    plucker: Vec<f64>,
    point: Vec<f64>,
    direction: Vec<f64>,
}

impl PyLineTriangulations {
    fn build(method: Method, results: Vec<pluecker::Result<LineTriangulation>>) -> (PyBatchReport, Self) {
        let mut report = PyBatchReport::with_capacity(method, results.len());
        let mut lines = PyLineTriangulations::default();
        for (t, result) in results.into_iter().enumerate() {
            match result {
                Ok(r) => {
                    report.push(&r.report);
                    lines.plucker.extend_from_slice(r.plucker.as_slice());
                    lines.point.extend_from_slice(r.point.as_slice());
                    lines.direction.extend_from_slice(r.direction.as_slice());
                }
                Err(e) => {
                    report.push_error(t, renamed(e, LINE_NAMES));
                    lines.plucker.extend([f64::NAN; 6]);
                    lines.point.extend([f64::NAN; 3]);
                    lines.direction.extend([f64::NAN; 3]);
                }
            }
        }
        (report, lines)
    }
}

#[pymethods]
impl PyLineTriangulations {
    #[getter]
    fn plucker<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        array(py, &self.plucker, &[self.plucker.len() / 6, 6])
    }

    #[getter]
    fn point<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        array(py, &self.point, &[self.point.len() / 3, 3])
    }

    #[getter]
    fn direction<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        array(py, &self.direction, &[self.direction.len() / 3, 3])
    }

    fn __repr__(slf: &Bound<'_, Self>) -> String {
        slf.as_super().get().repr("LineTriangulations")
    }
}

/// The results of `triangulate_quadrics`: dual and primal quadrics, centres, semi-axes and axes.
#[pyclass(frozen, extends = PyBatchReport, name = "QuadricTriangulations", module = "pluecker")]
#[derive(Debug, Default)]
pub struct PyQuadricTriangulations {
    dual: Vec<f64>,
    primal: Vec<f64>,
    centre: Vec<f64>,
    semi_axes: Vec<f64>,
    axes: Vec<f64>,
}

/// Row-major entries of a matrix.
fn row_major<const R: usize, const C: usize>(m: &nalgebra::SMatrix<f64, R, C>) -> impl Iterator<Item = f64> + '_ {
    (0..R).flat_map(move |i| (0..C).map(move |j| m[(i, j)]))
}

impl PyQuadricTriangulations {
    fn build(method: Method, results: Vec<pluecker::Result<QuadricTriangulation>>) -> (PyBatchReport, Self) {
        let mut report = PyBatchReport::with_capacity(method, results.len());
        let mut q = PyQuadricTriangulations::default();
        for (t, result) in results.into_iter().enumerate() {
            match result {
                Ok(r) => {
                    report.push(&r.report);
                    q.dual.extend(row_major(&r.dual));
                    match &r.primal {
                        Some(p) => q.primal.extend(row_major(p)),
                        None => q.primal.extend([f64::NAN; 16]),
                    }
                    q.centre.extend_from_slice(r.centre.as_slice());
                    q.semi_axes.extend_from_slice(r.semi_axes.as_slice());
                    q.axes.extend(row_major(&r.axes));
                }
                Err(e) => {
                    report.push_error(t, renamed(e, QUADRIC_NAMES));
                    q.dual.extend([f64::NAN; 16]);
                    q.primal.extend([f64::NAN; 16]);
                    q.centre.extend([f64::NAN; 3]);
                    q.semi_axes.extend([f64::NAN; 3]);
                    q.axes.extend([f64::NAN; 9]);
                }
            }
        }
        (report, q)
    }

    fn tracks(&self) -> usize {
        self.centre.len() / 3
    }
}

#[pymethods]
impl PyQuadricTriangulations {
    #[getter(Q)]
    fn dual<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        array(py, &self.dual, &[self.tracks(), 4, 4])
    }

    #[getter]
    fn primal<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        array(py, &self.primal, &[self.tracks(), 4, 4])
    }

    #[getter]
    fn centre<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        array(py, &self.centre, &[self.tracks(), 3])
    }

    #[getter]
    fn semi_axes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        array(py, &self.semi_axes, &[self.tracks(), 3])
    }

    #[getter]
    fn axes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        array(py, &self.axes, &[self.tracks(), 3, 3])
    }

    fn __repr__(slf: &Bound<'_, Self>) -> String {
        slf.as_super().get().repr("QuadricTriangulations")
    }
}

/// The cameras of a batch: `(v, 3, 4)` shared or `(n, v, 3, 4)` per track; `n` is `None` when shared.
struct Cameras {
    matrices: Vec<Matrix3x4<f64>>,
    tracks: Option<usize>,
    views: usize,
}

impl Cameras {
    fn read(obj: &Bound<'_, PyAny>, min_views: usize, method: Method) -> PyResult<Cameras> {
        let (shape, values) = read_any("P", obj)?;
        let (tracks, views) = match shape.as_slice() {
            [v, 3, 4] => (None, *v),
            [n, v, 3, 4] => (Some(*n), *v),
            _ => {
                return Err(shape_error(
                    "P",
                    "shape (v, 3, 4) (shared cameras) or (n, v, 3, 4) (cameras per track)",
                    shape_string(&shape),
                ))
            }
        };
        if views < min_views {
            return Err(to_py_err(Error::TooFewCorrespondences {
                method: method.as_str().into(),
                required: format!("{min_views} cameras"),
                actual: format!("{views} camera(s) in P"),
            }));
        }
        let matrices = values.chunks_exact(12).map(Matrix3x4::from_row_slice).collect();
        Ok(Cameras {
            matrices,
            tracks,
            views,
        })
    }

    /// A shape error unless an observation array of shape `shape` has `v` views (and `n` tracks for
    /// cameras per track).
    fn check_observations(&self, name: &str, shape: &[usize], tail: &str) -> PyResult<()> {
        let tracks_fit = self.tracks.map_or(true, |n| n == shape[0]);
        if shape[1] != self.views || !tracks_fit {
            let n = self.tracks.map_or("n".to_string(), |n| n.to_string());
            let expected = format!("shape ({n}, {}, {tail}) (one column per camera in P)", self.views);
            return Err(shape_error(name, &expected, shape_string(shape)));
        }
        Ok(())
    }

    fn core(&self) -> TrackCameras<'_> {
        match self.tracks {
            None => TrackCameras::Shared(&self.matrices),
            Some(_) => TrackCameras::PerTrack {
                cameras: &self.matrices,
                views: self.views,
            },
        }
    }
}

/// `(n, v, ...)` per-observation values of `obj` (`cov`), checked against `n` tracks and `v` views.
fn per_observation(name: &str, obj: &Bound<'_, PyAny>, n: usize, v: usize, entry: [usize; 2]) -> PyResult<Vec<f64>> {
    let spec = [
        Dim::Free("n"),
        Dim::Free("v"),
        Dim::Fixed(entry[0]),
        Dim::Fixed(entry[1]),
    ];
    let (shape, values) = read(name, obj, &spec)?;
    if shape[0] != n || shape[1] != v {
        let expected = format!("shape ({n}, {v}, {}, {}) (one per observation)", entry[0], entry[1]);
        return Err(shape_error(name, &expected, shape_string(&shape)));
    }
    Ok(values)
}

/// Runs a batch with the GIL released, like [`solve`]. With a `progress` callable the batch runs on
/// a worker thread and this thread calls `progress(done)` (finished tracks) about ten times a second
/// while the count changes, and once at the end with the final count. An exception raised by
/// `progress` (e.g. `KeyboardInterrupt`) stops the reports and is raised once the batch has ended.
fn run_batch<T, F>(py: Python<'_>, progress: Option<&Bound<'_, PyAny>>, work: F) -> PyResult<T>
where
    T: Send,
    F: FnOnce(Option<&AtomicUsize>) -> Result<T, Error> + Send,
{
    let Some(callback) = progress else {
        return solve(py, move || work(None));
    };
    let callback = callback.clone().unbind();
    let done = AtomicUsize::new(0);
    let mut failure: Option<PyErr> = None;
    let joined = py.allow_threads(|| {
        std::thread::scope(|scope| {
            let caller = std::thread::current();
            let done = &done;
            let worker = scope.spawn(move || {
                let out = catch_unwind(AssertUnwindSafe(|| work(Some(done))));
                caller.unpark();
                out
            });
            let mut reported = None;
            loop {
                let finished = worker.is_finished();
                let now = done.load(Ordering::Relaxed);
                if failure.is_none() && reported != Some(now) {
                    reported = Some(now);
                    Python::with_gil(|py| {
                        if let Err(e) = callback.call1(py, (now,)) {
                            failure = Some(e);
                        }
                    });
                }
                if finished {
                    break;
                }
                std::thread::park_timeout(Duration::from_millis(100));
            }
            worker.join().unwrap_or_else(Err)
        })
    });
    if let Some(e) = failure {
        return Err(e);
    }
    guarded(|| joined.unwrap_or_else(|payload| resume_unwind(payload)))
}

/// Triangulates many 3-D lines (tracks) in parallel (Josephson & Kahl 2008, eq. 19).
#[pyfunction]
#[pyo3(signature = (P, lines, visible = None, cov = None, method = "optimal", *, sigma = None, max_relative_gap = None, max_reprojection_error = None, max_nodes = None, progress = None))]
#[allow(non_snake_case, clippy::too_many_arguments)]
pub fn triangulate_lines(
    py: Python<'_>,
    P: &Bound<'_, PyAny>,
    lines: &Bound<'_, PyAny>,
    visible: Option<&Bound<'_, PyAny>>,
    cov: Option<&Bound<'_, PyAny>>,
    method: &str,
    sigma: Option<f64>,
    max_relative_gap: Option<f64>,
    max_reprojection_error: Option<f64>,
    max_nodes: Option<i64>,
    progress: Option<&Bound<'_, PyAny>>,
) -> PyResult<Py<PyLineTriangulations>> {
    let opts = options(method, max_relative_gap, max_reprojection_error, max_nodes)?;
    let cams = Cameras::read(P, 2, opts.method)?;
    let (shape, values) = read_any("lines", lines)?;
    let segments = match shape.as_slice() {
        [_, _, 3] => false,
        [_, _, 2, 2] => true,
        _ => {
            return Err(shape_error(
                "lines",
                "shape (n, v, 3) (homogeneous lines) or (n, v, 2, 2) (segments)",
                shape_string(&shape),
            ))
        }
    };
    cams.check_observations("lines", &shape, if segments { "2, 2" } else { "3" })?;
    let (n, v) = (shape[0], shape[1]);
    if sigma.is_some() && !segments {
        return Err(invalid_argument(
            "sigma",
            "applies to segments (n, v, 2, 2) only; give cov for homogeneous lines",
        ));
    }
    if sigma.is_some() && cov.is_some() {
        return Err(invalid_argument("sigma", "give cov or sigma, not both"));
    }
    let mask = visible.map(|m| read_mask("visible", m, &[n, v])).transpose()?;
    let covariances = cov.map(|c| per_observation("cov", c, n, v, [2, 2])).transpose()?;
    let sigma = sigma.unwrap_or(1.0);
    let (report, results) = run_batch(py, progress, move |done| {
        let tracks = LineTracks {
            lines: if segments {
                ImageLines::Segments {
                    endpoints: &values,
                    sigma,
                }
            } else {
                ImageLines::Homogeneous(&values)
            },
            visible: mask.as_deref(),
            covariances: covariances.as_deref(),
        };
        let results = core_lines(cams.core(), &tracks, &opts, done).map_err(|e| renamed(e, LINE_NAMES))?;
        Ok(PyLineTriangulations::build(opts.method, results))
    })?;
    Py::new(py, PyClassInitializer::from(report).add_subclass(results))
}

/// Triangulates many ellipsoids (tracks) from their outline conics in parallel (Josephson & Kahl 2008).
#[pyfunction]
#[pyo3(signature = (P, conics, visible = None, cov = None, method = "optimal", *, max_relative_gap = None, max_reprojection_error = None, max_nodes = None, progress = None))]
#[allow(non_snake_case, clippy::too_many_arguments)]
pub fn triangulate_quadrics(
    py: Python<'_>,
    P: &Bound<'_, PyAny>,
    conics: &Bound<'_, PyAny>,
    visible: Option<&Bound<'_, PyAny>>,
    cov: Option<&Bound<'_, PyAny>>,
    method: &str,
    max_relative_gap: Option<f64>,
    max_reprojection_error: Option<f64>,
    max_nodes: Option<i64>,
    progress: Option<&Bound<'_, PyAny>>,
) -> PyResult<Py<PyQuadricTriangulations>> {
    let opts: TriangulationOptions = options(method, max_relative_gap, max_reprojection_error, max_nodes)?;
    let cams = Cameras::read(P, 3, opts.method)?;
    let spec = [Dim::Free("n"), Dim::Free("v"), Dim::Fixed(3), Dim::Fixed(3)];
    let (shape, values) = read("conics", conics, &spec)?;
    cams.check_observations("conics", &shape, "3, 3")?;
    let (n, v) = (shape[0], shape[1]);
    let mask = visible.map(|m| read_mask("visible", m, &[n, v])).transpose()?;
    let covariances = cov.map(|c| per_observation("cov", c, n, v, [5, 5])).transpose()?;
    let (report, results) = run_batch(py, progress, move |done| {
        let tracks = QuadricTracks {
            conics: &values,
            visible: mask.as_deref(),
            covariances: covariances.as_deref(),
        };
        let results = core_quadrics(cams.core(), &tracks, &opts, done).map_err(|e| renamed(e, QUADRIC_NAMES))?;
        Ok(PyQuadricTriangulations::build(opts.method, results))
    })?;
    Py::new(py, PyClassInitializer::from(report).add_subclass(results))
}
