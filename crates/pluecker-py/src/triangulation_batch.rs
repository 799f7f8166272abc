//! `triangulate_points`: many point tracks seen by one set of cameras, solved in parallel with the GIL
//! released, and `pluecker.PointTriangulations`, the arrays of their results.
//!
//! Every track is solved by the core's `triangulate_point` on its visible views; a track the core
//! rejects (NaN in a visible view, fewer than two visible views, a covariance that is not positive
//! definite, ...) gets an error status and message and never stops the others. The tracks are split
//! into one contiguous chunk per available core (`std::thread::scope`).

use crate::errors::{shape_error, solve};
use crate::triangulation::{options, renamed, POINT_NAMES};
use crate::triangulation_arrays::{cameras, read, read_mask, shape_string, Dim};
use nalgebra::{Matrix2, Matrix3x4, Vector2};
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2};
use pluecker::triangulation::point::triangulate_point;
use pluecker::triangulation::views::validate_cameras;
use pluecker::triangulation::{CertificateKind, Status, TriangulationOptions};
use pluecker::Error;
use pyo3::prelude::*;
use pyo3::types::PyList;
use std::time::Instant;

/// The outcome of one track, flattened for the arrays.
#[derive(Debug, Clone)]
struct TrackResult {
    x: [f64; 3],
    cost: f64,
    lower_bound: f64,
    relative_gap: f64,
    certified: bool,
    certificate: &'static str,
    status: &'static str,
    nodes: usize,
    iterations: usize,
    time_seconds: f64,
    message: String,
}

/// The status of a track the core rejected, by error kind.
fn error_status(err: &Error) -> &'static str {
    match err {
        Error::TooFewCorrespondences { .. } => "too_few_views",
        Error::NonFinite { .. } => "non_finite",
        Error::Degenerate { .. } => "degenerate",
        Error::SingularCamera { .. } => "singular_camera",
        Error::Shape { .. } => "invalid_input",
        Error::InvalidOption { .. } => "invalid_option",
    }
}

/// One track: its visible views handed to the core.
fn solve_track(
    cams: &[Matrix3x4<f64>],
    x: &[f64],
    visible: Option<&[bool]>,
    cov: Option<&[f64]>,
    opts: &TriangulationOptions,
    track: usize,
) -> TrackResult {
    let started = Instant::now();
    let seen: Vec<usize> = (0..cams.len()).filter(|&j| visible.map_or(true, |v| v[j])).collect();
    let all = seen.len() == cams.len();
    let chosen: Vec<Matrix3x4<f64>>;
    let cam_slice: &[Matrix3x4<f64>] = if all {
        cams
    } else {
        chosen = seen.iter().map(|&j| cams[j]).collect();
        &chosen
    };
    let obs: Vec<Vector2<f64>> = seen.iter().map(|&j| Vector2::new(x[2 * j], x[2 * j + 1])).collect();
    let covs: Option<Vec<Matrix2<f64>>> =
        cov.map(|c| seen.iter().map(|&j| Matrix2::from_row_slice(&c[4 * j..4 * j + 4])).collect());
    match triangulate_point(cam_slice, &obs, covs.as_deref(), opts) {
        Ok(r) => {
            let c = &r.report.certificate;
            TrackResult {
                x: [r.point.x, r.point.y, r.point.z],
                cost: r.report.cost,
                lower_bound: c.lower_bound,
                relative_gap: c.relative_gap,
                certified: c.certified,
                certificate: c.kind.as_str(),
                status: r.report.status.as_str(),
                nodes: c.nodes,
                iterations: r.report.iterations,
                time_seconds: r.report.time_seconds,
                message: String::new(),
            }
        }
        Err(e) => {
            let e = renamed(e, POINT_NAMES);
            TrackResult {
                x: [f64::NAN; 3],
                cost: f64::NAN,
                lower_bound: 0.0,
                relative_gap: 1.0,
                certified: false,
                certificate: CertificateKind::None.as_str(),
                status: error_status(&e),
                nodes: 0,
                iterations: 0,
                time_seconds: started.elapsed().as_secs_f64(),
                message: format!("track {track}: {e}"),
            }
        }
    }
}

/// Every track, in parallel chunks.
fn solve_all(
    cams: &[Matrix3x4<f64>],
    x: &[f64],
    visible: Option<&[bool]>,
    cov: Option<&[f64]>,
    opts: &TriangulationOptions,
    n: usize,
) -> Vec<TrackResult> {
    let v = cams.len();
    let run = |range: std::ops::Range<usize>| -> Vec<TrackResult> {
        range
            .map(|i| {
                solve_track(
                    cams,
                    &x[2 * v * i..2 * v * (i + 1)],
                    visible.map(|m| &m[v * i..v * (i + 1)]),
                    cov.map(|c| &c[4 * v * i..4 * v * (i + 1)]),
                    opts,
                    i,
                )
            })
            .collect()
    };
    let threads = std::thread::available_parallelism().map_or(1, |t| t.get()).min(n.div_ceil(64)).max(1);
    if threads == 1 {
        return run(0..n);
    }
    let chunk = n.div_ceil(threads);
    std::thread::scope(|scope| {
        let handles: Vec<_> =
            (0..threads).map(|t| scope.spawn(move || run(t * chunk..((t + 1) * chunk).min(n)))).collect();
        handles.into_iter().flat_map(|h| h.join().expect("a triangulation thread panicked")).collect()
    })
}

/// The results of `triangulate_points`: one entry per track in every array.
#[pyclass(frozen, name = "PointTriangulations", module = "pluecker")]
#[derive(Debug)]
pub struct PyPointTriangulations {
    method: &'static str,
    tracks: Vec<TrackResult>,
}

impl PyPointTriangulations {
    fn column<'py>(&self, py: Python<'py>, f: impl Fn(&TrackResult) -> f64) -> Bound<'py, PyArray1<f64>> {
        self.tracks.iter().map(f).collect::<Vec<f64>>().into_pyarray(py)
    }
}

#[pymethods]
impl PyPointTriangulations {
    #[getter(X)]
    fn x<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        Array2::from_shape_fn((self.tracks.len(), 3), |(i, j)| self.tracks[i].x[j]).into_pyarray(py)
    }

    #[getter]
    fn cost<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.column(py, |t| t.cost)
    }

    #[getter]
    fn lower_bound<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.column(py, |t| t.lower_bound)
    }

    #[getter]
    fn relative_gap<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.column(py, |t| t.relative_gap)
    }

    #[getter]
    fn time_seconds<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.column(py, |t| t.time_seconds)
    }

    #[getter]
    fn certified<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<bool>> {
        self.tracks.iter().map(|t| t.certified).collect::<Vec<bool>>().into_pyarray(py)
    }

    #[getter]
    fn nodes<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        self.tracks.iter().map(|t| t.nodes as i64).collect::<Vec<i64>>().into_pyarray(py)
    }

    #[getter]
    fn iterations<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        self.tracks.iter().map(|t| t.iterations as i64).collect::<Vec<i64>>().into_pyarray(py)
    }

    #[getter]
    fn status<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        strings(py, self.tracks.iter().map(|t| t.status))
    }

    #[getter]
    fn certificate<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        strings(py, self.tracks.iter().map(|t| t.certificate))
    }

    #[getter]
    fn messages(&self) -> Vec<String> {
        self.tracks.iter().map(|t| t.message.clone()).collect()
    }

    #[getter]
    fn method(&self) -> &'static str {
        self.method
    }

    fn __len__(&self) -> usize {
        self.tracks.len()
    }

    fn __repr__(&self) -> String {
        let n = self.tracks.len();
        let success = self.tracks.iter().filter(|t| t.status == Status::Success.as_str()).count();
        let certified = self.tracks.iter().filter(|t| t.certified).count();
        format!("PointTriangulations(method='{}', tracks={n}, success={success}, certified={certified})", self.method)
    }
}

/// A numpy array of strings (dtype `<U…`) from `values`.
fn strings<'py>(py: Python<'py>, values: impl Iterator<Item = &'static str>) -> PyResult<Bound<'py, PyAny>> {
    let list = PyList::new(py, values.collect::<Vec<_>>())?;
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
    validate_cameras(&cams, "P").map_err(crate::errors::to_py_err)?;
    let v = cams.len();
    let (shape, xs) = read("x", x, &[Dim::Free("n"), Dim::Free("v"), Dim::Fixed(2)])?;
    if shape[1] != v {
        return Err(shape_error("x", &format!("shape (n, {v}, 2) (one column per camera in P)"), shape_string(&shape)));
    }
    let n = shape[0];
    let mask = visible.map(|m| read_mask("visible", m, &[n, v])).transpose()?;
    let covs = match cov {
        Some(c) => {
            let (cshape, values) = read("cov", c, &[Dim::Free("n"), Dim::Free("v"), Dim::Fixed(2), Dim::Fixed(2)])?;
            if cshape[0] != n || cshape[1] != v {
                return Err(shape_error("cov", &format!("shape ({n}, {v}, 2, 2) (one per observation)"), shape_string(&cshape)));
            }
            Some(values)
        }
        None => None,
    };
    if v < 2 {
        return Err(crate::errors::to_py_err(Error::TooFewCorrespondences {
            method: opts.method.as_str().into(),
            required: "2 cameras".into(),
            actual: format!("{v} camera(s) in P"),
        }));
    }
    let method_name = opts.method.as_str();
    let tracks = solve(py, move || Ok(solve_all(&cams, &xs, mask.as_deref(), covs.as_deref(), &opts, n)))?;
    Ok(PyPointTriangulations { method: method_name, tracks })
}
