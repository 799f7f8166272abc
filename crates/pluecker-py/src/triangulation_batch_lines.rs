//! `triangulate_lines` and `triangulate_quadrics`: many line or quadric tracks solved by the core's
//! batches (`pluecker::triangulation::{line::batch, quadric::batch}`, rayon) with the GIL released, and
//! their results `pluecker.LineTriangulations` / `pluecker.QuadricTriangulations`, column arrays with
//! the per-track report columns of their base class `pluecker.BatchReport`
//! ([`crate::triangulation_batch_report`], which also fills them from the core's results).
//!
//! The numpy arrays go to the core as flat row-major slices, one copy each. Cameras are `(v, 3, 4)`,
//! shared by every track, or `(n, v, 3, 4)`, one set per track. A track the core rejects gets an
//! error status and a message and never stops the others. The batch runs on a worker thread while
//! the calling thread checks for Ctrl-C and reports the count of finished tracks to `progress`
//! ([`crate::interrupt`]).

use crate::errors::{invalid_argument, shape_error, to_py_err};
use crate::interrupt::{self, batch_result, run_interruptible};
use crate::triangulation::{options, renamed};
use crate::triangulation_arrays::{read, read_any, read_mask, shape_string, Dim};
use crate::triangulation_batch_report::{batch_dict, collect, PyBatchReport, TrackColumns};
use crate::triangulation_line::{chart_axes, LINE_NAMES};
use crate::triangulation_quadric::QUADRIC_NAMES;
use nalgebra::Matrix3x4;
use numpy::ndarray::{ArrayD, IxDyn};
use numpy::{IntoPyArray, PyArrayDyn};
use pluecker::triangulation::tracks::TrackCameras;
use pluecker::triangulation::line::LineTriangulation;
use pluecker::triangulation::line::batch::{triangulate_lines as core_lines, ImageLines, LineTracks};
use pluecker::triangulation::quadric::QuadricTriangulation;
use pluecker::triangulation::quadric::batch::{triangulate_quadrics as core_quadrics, QuadricTracks};
use pluecker::triangulation::{Method, Report, TriangulationOptions};
use pluecker::Error;
use crate::convert::{optional_real, Integer, Real};
use pyo3::prelude::*;
use crate::pickle::{pack_struct, reduce, Pack, Reader};
use pyo3::types::PyTuple;


/// A float64 array of `shape` from row-major `values`.
fn array<'py>(py: Python<'py>, values: &[f64], shape: &[usize]) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let array = ArrayD::from_shape_vec(IxDyn(shape), values.to_vec())
        .map_err(|e| pyo3::exceptions::PyRuntimeError::new_err(e.to_string()))?;
    Ok(array.into_pyarray(py))
}

/// The results of `triangulate_lines`: Plücker coordinates, points and directions per track.
#[pyclass(frozen, extends = PyBatchReport, name = "LineTriangulations", module = "pluecker")]
#[derive(Debug, Default)]
pub struct PyLineTriangulations {
    plucker: Vec<f64>,
    point: Vec<f64>,
    direction: Vec<f64>,
    chart_axes: Vec<f64>,
    covariance: Vec<f64>,
}

impl TrackColumns for PyLineTriangulations {
    type Track = LineTriangulation;
    const NAMES: &'static [(&'static str, &'static str)] = LINE_NAMES;

    fn push(&mut self, track: LineTriangulation) -> Report {
        self.plucker.extend_from_slice(track.plucker.as_slice());
        self.point.extend_from_slice(track.point.as_slice());
        self.direction.extend_from_slice(track.direction.as_slice());
        self.chart_axes.extend(row_major(&chart_axes(&track.chart)));
        push_covariance(&mut self.covariance, track.covariance.as_ref());
        track.report
    }

    fn push_missing(&mut self) {
        self.plucker.extend([f64::NAN; 6]);
        self.point.extend([f64::NAN; 3]);
        self.direction.extend([f64::NAN; 3]);
        self.chart_axes.extend([f64::NAN; 6]);
        push_covariance::<4>(&mut self.covariance, None);
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

    #[getter]
    fn chart_axes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        array(py, &self.chart_axes, &[self.chart_axes.len() / 6, 2, 3])
    }

    #[getter]
    fn covariance<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        array(py, &self.covariance, &[self.covariance.len() / 16, 4, 4])
    }

    fn __repr__(slf: &Bound<'_, Self>) -> String {
        slf.as_super().get().repr("LineTriangulations")
    }

    /// Plain-Python (strict JSON) form: the report columns of `BatchReport.to_dict()` and the estimates.
    fn to_dict<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, pyo3::types::PyDict>> {
        batch_dict(slf.as_any(), &["plucker", "point", "direction", "chart_axes", "covariance"])
    }

    /// Pickle support (also `copy.deepcopy`): see `pickle.rs`.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        reduce(slf.py(), "LineTriangulations", &[slf.as_super().get(), slf.get()])
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
    covariance: Vec<f64>,
}

/// Row-major entries of a matrix.
fn row_major<const R: usize, const C: usize>(m: &nalgebra::SMatrix<f64, R, C>) -> impl Iterator<Item = f64> + '_ {
    (0..R).flat_map(move |i| (0..C).map(move |j| m[(i, j)]))
}

/// Appends one track's `N x N` covariance in row-major order to a batch column, or `N²` NaNs when the
/// track has none.
pub(crate) fn push_covariance<const N: usize>(
    column: &mut Vec<f64>,
    covariance: Option<&nalgebra::SMatrix<f64, N, N>>,
) {
    match covariance {
        Some(c) => column.extend(row_major(c)),
        None => column.extend(std::iter::repeat(f64::NAN).take(N * N)),
    }
}

impl TrackColumns for PyQuadricTriangulations {
    type Track = QuadricTriangulation;
    const NAMES: &'static [(&'static str, &'static str)] = QUADRIC_NAMES;

    fn push(&mut self, track: QuadricTriangulation) -> Report {
        self.dual.extend(row_major(&track.dual));
        match &track.primal {
            Some(p) => self.primal.extend(row_major(p)),
            None => self.primal.extend([f64::NAN; 16]),
        }
        self.centre.extend_from_slice(track.centre.as_slice());
        self.semi_axes.extend_from_slice(track.semi_axes.as_slice());
        self.axes.extend(row_major(&track.axes));
        push_covariance(&mut self.covariance, track.covariance.as_ref());
        track.report
    }

    fn push_missing(&mut self) {
        self.dual.extend([f64::NAN; 16]);
        self.primal.extend([f64::NAN; 16]);
        self.centre.extend([f64::NAN; 3]);
        self.semi_axes.extend([f64::NAN; 3]);
        self.axes.extend([f64::NAN; 9]);
        push_covariance::<9>(&mut self.covariance, None);
    }
}

impl PyQuadricTriangulations {
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

    #[getter]
    fn covariance<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        array(py, &self.covariance, &[self.tracks(), 9, 9])
    }

    fn __repr__(slf: &Bound<'_, Self>) -> String {
        slf.as_super().get().repr("QuadricTriangulations")
    }

    /// Plain-Python (strict JSON) form: the report columns of `BatchReport.to_dict()` and the estimates.
    fn to_dict<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, pyo3::types::PyDict>> {
        batch_dict(slf.as_any(), &["Q", "primal", "centre", "axes", "semi_axes", "covariance"])
    }

    /// Pickle support (also `copy.deepcopy`): see `pickle.rs`.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        reduce(slf.py(), "QuadricTriangulations", &[slf.as_super().get(), slf.get()])
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
pub(crate) fn per_observation(
    name: &str,
    obj: &Bound<'_, PyAny>,
    n: usize,
    v: usize,
    entry: [usize; 2],
) -> PyResult<Vec<f64>> {
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

/// Triangulates many 3-D lines (tracks) in parallel (Josephson & Kahl 2008, eq. 19).
#[pyfunction]
#[pyo3(signature = (P, lines, visible = None, cov = None, method = "optimal", *, sigma = None, max_relative_gap = None, max_reprojection_error = None, max_nodes = None, progress = None, time_budget = None))]
#[allow(non_snake_case, clippy::too_many_arguments)]
pub fn triangulate_lines(
    py: Python<'_>,
    P: &Bound<'_, PyAny>,
    lines: &Bound<'_, PyAny>,
    visible: Option<&Bound<'_, PyAny>>,
    cov: Option<&Bound<'_, PyAny>>,
    method: &str,
    sigma: Option<Real>,
    max_relative_gap: Option<Real>,
    max_reprojection_error: Option<Real>,
    max_nodes: Option<Integer>,
    progress: Option<&Bound<'_, PyAny>>,
    time_budget: Option<Real>,
) -> PyResult<Py<PyLineTriangulations>> {
    let budget = interrupt::time_budget(time_budget)?;
    let opts = options(method, max_relative_gap, max_reprojection_error, max_nodes)?;
    let sigma = optional_real("sigma", sigma)?;
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
    let outcome = run_interruptible(py, progress, budget, false, move |done| {
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
        let results = core_lines(cams.core(), &tracks, &opts, Some(done)).map_err(|e| renamed(e, LINE_NAMES))?;
        Ok(collect::<PyLineTriangulations>(opts.method, results))
    })?;
    batch_result(py, outcome)
}

/// Triangulates many ellipsoids (tracks) from their outline conics in parallel (Josephson & Kahl 2008).
#[pyfunction]
#[pyo3(signature = (P, conics, visible = None, cov = None, method = "optimal", *, max_relative_gap = None, max_reprojection_error = None, max_nodes = None, progress = None, time_budget = None))]
#[allow(non_snake_case, clippy::too_many_arguments)]
pub fn triangulate_quadrics(
    py: Python<'_>,
    P: &Bound<'_, PyAny>,
    conics: &Bound<'_, PyAny>,
    visible: Option<&Bound<'_, PyAny>>,
    cov: Option<&Bound<'_, PyAny>>,
    method: &str,
    max_relative_gap: Option<Real>,
    max_reprojection_error: Option<Real>,
    max_nodes: Option<Integer>,
    progress: Option<&Bound<'_, PyAny>>,
    time_budget: Option<Real>,
) -> PyResult<Py<PyQuadricTriangulations>> {
    let budget = interrupt::time_budget(time_budget)?;
    let opts: TriangulationOptions = options(method, max_relative_gap, max_reprojection_error, max_nodes)?;
    let cams = Cameras::read(P, 3, opts.method)?;
    let spec = [Dim::Free("n"), Dim::Free("v"), Dim::Fixed(3), Dim::Fixed(3)];
    let (shape, values) = read("conics", conics, &spec)?;
    cams.check_observations("conics", &shape, "3, 3")?;
    let (n, v) = (shape[0], shape[1]);
    let mask = visible.map(|m| read_mask("visible", m, &[n, v])).transpose()?;
    let covariances = cov.map(|c| per_observation("cov", c, n, v, [5, 5])).transpose()?;
    let outcome = run_interruptible(py, progress, budget, false, move |done| {
        let tracks = QuadricTracks {
            conics: &values,
            visible: mask.as_deref(),
            covariances: covariances.as_deref(),
        };
        let results = core_quadrics(cams.core(), &tracks, &opts, Some(done)).map_err(|e| renamed(e, QUADRIC_NAMES))?;
        Ok(collect::<PyQuadricTriangulations>(opts.method, results))
    })?;
    batch_result(py, outcome)
}

pack_struct!(PyLineTriangulations { plucker, point, direction, chart_axes, covariance });

pack_struct!(PyQuadricTriangulations { dual, primal, centre, semi_axes, axes, covariance });
