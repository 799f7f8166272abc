//! Points: `triangulate_point` (one point from its views) with its result `pluecker.PointTriangulation`,
//! and `triangulate_points` (many tracks seen by one set of cameras, solved by the core's batch with
//! the GIL released) with `pluecker.PointTriangulations`, the arrays of their points beside the
//! per-track report columns of `pluecker.BatchReport` ([`super::batch`]).
//!
//! The batch's numpy arrays go to the core as flat row-major slices (`DensePointTracks`), one copy each.
//! A track the core rejects (NaN in a visible view, fewer than two visible views, a covariance that
//! is not positive definite, ...) gets an error status and a message and never stops the others.
//! Method `linear` takes the core's allocation-free path (`streaming::linear_points_into`), written
//! into the same preallocated columns.

use super::batch::{
    self, column, per_observation, rows, sparse_form, unstarted, write_row_major, EstimateColumns, InlierColumns,
    PyBatchReport, ReportRow, Sink,
};
use super::observation_rows::SortedRows;
use super::report::PyTriangulationReport;
use super::{options_arg, PyTriangulationOptions};
use crate::convert::{check_finite, covariances2, read, read_mask, same_count, shape_string, Dim, Integer, Real};
use crate::errors::{shape_error, to_py_err};
use crate::interrupt::{self, batch_result, run_interruptible};
use crate::pickle::reduce;
use crate::properties::{result_class, Array};
use nalgebra::{Matrix3, Vector2, Vector3};
use pluecker::triangulation::point::{triangulate_point as core_triangulate_point, PointTriangulation};
use pluecker::triangulation::point::{DensePointTracks, SparsePointTracks};
use pluecker::triangulation::streaming::{linear_points_into, points_into as core_points, LinearTrack};
use pluecker::triangulation::{CostKind, Method, Report};
use pluecker::Error;
use pyo3::prelude::*;
use pyo3::types::PyTuple;
use rayon::prelude::*;
use std::sync::atomic::Ordering;
use std::time::Instant;

/// A triangulated point: the estimate `X` and the report fields of `TriangulationReport`.
#[pyclass(frozen, extends = PyTriangulationReport, name = "PointTriangulation", module = "pluecker")]
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct PyPointTriangulation {
    point: Vector3<f64>,
    covariance: Option<Matrix3<f64>>,
    inliers: Option<Vec<bool>>,
}

impl PyPointTriangulation {
    /// The Python object of a core result.
    pub fn create(py: Python<'_>, result: PointTriangulation) -> PyResult<Py<PyPointTriangulation>> {
        let init = PyClassInitializer::from(PyTriangulationReport { inner: result.report }).add_subclass(
            PyPointTriangulation {
                point: result.point,
                covariance: result.covariance,
                inliers: result.inliers,
            },
        );
        Py::new(py, init)
    }
}

result_class! {
    PyPointTriangulation: PyTriangulationReport {
        /// The point, world frame.
        point = |p| p.point;
        /// Its 3x3 covariance (first order, from the observation covariances); `None` when singular.
        covariance = |p| p.covariance;
        /// With `options.outlier_threshold`: (v,) the views the point was solved from; else `None`.
        inliers = |p| p.inliers.clone();
    }

    /// Pickle support (also `copy.deepcopy`): see `pickle.rs`.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        reduce(slf.py(), "PointTriangulation", &(slf.as_super().get(), slf.get()))
    }

    fn __repr__(slf: &Bound<'_, Self>) -> String {
        let x = slf.get().point;
        format!(
            "PointTriangulation(X=[{:.6}, {:.6}, {:.6}], {})",
            x.x,
            x.y,
            x.z,
            slf.as_super().get().repr_fields()
        )
    }
}

/// `(n, 2)` finite pixels, one row per camera.
fn pixels(name: &str, obj: &Bound<'_, PyAny>, views: usize) -> PyResult<Vec<Vector2<f64>>> {
    let (shape, values) = read(name, obj, &[Dim::Free("n"), Dim::Fixed(2)])?;
    same_count(name, shape[0], views)?;
    check_finite(name, &values, 2)?;
    Ok(values.chunks_exact(2).map(|r| Vector2::new(r[0], r[1])).collect())
}

/// Triangulates one point from its pixels in two or more views (Josephson & Kahl 2008, eq. 19).
///
/// `cameras`, when given, holds each view's `Camera` (any model):
/// `projections[i]` is then `K [R | t]` of its pinhole part, `observations` the observed (distorted)
/// pixels and `covariances` their covariances, and the cost is the reprojection error in those pixels through the exact projection
/// (certificate `lens_convexity_test` through a lens).
#[pyfunction]
#[pyo3(signature = (cameras, observations, covariances = None, *, options = None))]
pub fn triangulate_point(
    py: Python<'_>,
    cameras: &Bound<'_, PyAny>,
    observations: &Bound<'_, PyAny>,
    covariances: Option<&Bound<'_, PyAny>>,
    options: Option<PyRef<'_, PyTriangulationOptions>>,
) -> PyResult<Py<PyPointTriangulation>> {
    let opts = options_arg(options)?;
    let (cams, views) = crate::view::known_cameras(cameras)?;
    let obs = pixels("observations", observations, cams.len())?;
    let covs = covariances2("covariances", covariances, cams.len())?;
    // Ctrl-C stops its branch and bound: `KeyboardInterrupt` with the estimate reached as `partial`.
    let outcome = interrupt::run_single(py, move || match &views {
        Some(views) => core_triangulate_point(views, &obs, covs.as_deref(), &opts),
        None => core_triangulate_point(&cams, &obs, covs.as_deref(), &opts),
    })?;
    interrupt::object_or_partial(py, outcome.pending, PyPointTriangulation::create(py, outcome.value)?)
}

/// The results of `triangulate_points`: the columns of its base class `pluecker.BatchReport` and
/// each track's point (NaN for a rejected track).
#[pyclass(frozen, extends = PyBatchReport, name = "PointTriangulations", module = "pluecker")]
#[derive(Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct PyPointTriangulations {
    /// Row-major `(n, 3)` points, world frame.
    x: Vec<f64>,
    /// Row-major `(n, 3, 3)` covariances, NaN where there is none.
    covariance: Vec<f64>,
    /// Robust only: the inlier masks, laid out as the observations were given (`(n, v)` or `(m,)`).
    inliers: InlierColumns,
}

/// One track's entries of the point columns, written in place.
pub(crate) struct PointRow<'a> {
    x: &'a mut [f64],
    covariance: &'a mut [f64],
}

impl PointRow<'_> {
    /// The point and its covariance (left NaN when there is none).
    fn write(self, x: &Vector3<f64>, covariance: Option<&Matrix3<f64>>) {
        self.x.copy_from_slice(x.as_slice());
        write_row_major(self.covariance, covariance);
    }
}

impl EstimateColumns for PyPointTriangulations {
    type Track = PointTriangulation;
    const COST_KIND: CostKind = CostKind::Reprojection;
    type Row<'a> = PointRow<'a>;

    fn unstarted(py: Python<'_>, n: usize) -> PyResult<Self> {
        Ok(PyPointTriangulations {
            x: column(py, f64::NAN, n, 3)?,
            covariance: column(py, f64::NAN, n, 9)?,
            inliers: InlierColumns::default(),
        })
    }

    fn rows_mut(&mut self) -> impl IndexedParallelIterator<Item = PointRow<'_>> {
        (self.x.par_chunks_mut(3))
            .zip(self.covariance.par_chunks_mut(9))
            .map(|(x, covariance)| PointRow { x, covariance })
    }

    fn write(row: PointRow<'_>, track: PointTriangulation) -> (Report, Option<Vec<bool>>) {
        row.write(&track.point, track.covariance.as_ref());
        (track.report, track.inliers)
    }

    fn set_inliers(&mut self, inliers: InlierColumns) {
        self.inliers = inliers;
    }
}

/// A track of the linear fast path into its rows: no certificate, timed later
/// ([`PyBatchReport::time_solved`]).
fn write_linear(sink: &Sink, t: usize, (report, point): (ReportRow, PointRow), result: Result<LinearTrack, Error>) {
    match result {
        Ok(track) => {
            point.write(&track.point, track.covariance.as_ref());
            report.uncertified(track.cost, track.status.as_str(), 0.0, track.residual_dof);
        }
        Err(e) => sink.reject(t, report, e),
    }
}

result_class! {
    PyPointTriangulations: PyBatchReport {
        /// Per track: the point, world frame, shape (n, 3) (NaN for a rejected track).
        point = |b| Array::rows(b.x.clone(), &[3]);
        /// Per track: its 3x3 covariance, shape (n, 3, 3) (NaN where there is none).
        covariance = |b| Array::rows(b.covariance.clone(), &[3, 3]);
        /// With `options.outlier_threshold`: which observations each point was solved from, shaped as
        /// the observations were given ((n, v) dense, (m,) in the rows form with `track=`, `image=`; false
        /// where not visible or rejected); else `None`.
        inliers = |b| b.inliers.mask();
    }

    fn __repr__(slf: &Bound<'_, Self>) -> String {
        slf.as_super().get().repr("PointTriangulations")
    }

    /// Pickle support (also `copy.deepcopy`): see `pickle.rs`.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        reduce(slf.py(), "PointTriangulations", &(slf.as_super().get(), slf.get()))
    }
}

/// Observations (tracks x views) up to which a `linear` or `local` batch runs on the calling thread
/// ([`interrupt::run_interruptible`]'s `short`).
const SHORT_BATCH: usize = 4096;

/// Triangulates many point tracks seen by the same cameras, in parallel (Josephson & Kahl 2008, eq. 19).
#[pyfunction]
#[pyo3(signature = (cameras, observations, visible = None, covariances = None, *, options = None, progress = None, time_budget = None, track = None, image = None, n_tracks = None))]
#[allow(clippy::too_many_arguments)]
pub fn triangulate_points(
    py: Python<'_>,
    cameras: &Bound<'_, PyAny>,
    observations: &Bound<'_, PyAny>,
    visible: Option<&Bound<'_, PyAny>>,
    covariances: Option<&Bound<'_, PyAny>>,
    options: Option<PyRef<'_, PyTriangulationOptions>>,
    progress: Option<&Bound<'_, PyAny>>,
    time_budget: Option<Real>,
    track: Option<&Bound<'_, PyAny>>,
    image: Option<&Bound<'_, PyAny>>,
    n_tracks: Option<Integer>,
) -> PyResult<Py<PyPointTriangulations>> {
    if let Some((track, image)) = sparse_form(track, image, visible, n_tracks, crate::view::is_views(cameras))? {
        return point_observations(
            py,
            cameras,
            track,
            image,
            observations,
            covariances,
            options,
            progress,
            time_budget,
            n_tracks,
        );
    }
    let budget = crate::convert::time_budget(time_budget)?;
    let opts = options_arg(options)?;
    // Views were refused above (they take the rows form): the matrices.
    let cams = crate::convert::cameras("cameras", cameras)?;
    let v = cams.len();
    if v < 2 {
        return Err(to_py_err(Error::TooFewCorrespondences {
            method: opts.method.as_str().into(),
            required: "2 cameras".into(),
            actual: format!("{v} camera(s) in cameras"),
        }));
    }
    let (shape, pixels) = read(
        "observations",
        observations,
        &[Dim::Free("n"), Dim::Free("v"), Dim::Fixed(2)],
    )?;
    if shape[1] != v {
        return Err(shape_error(
            "observations",
            &format!("shape (n, {v}, 2) (one column per camera)"),
            shape_string(&shape),
        ));
    }
    let n = shape[0];
    let mask = visible.map(|m| read_mask("visible", m, &[n, v])).transpose()?;
    let covariances = covariances
        .map(|c| per_observation("covariances", c, n, v, [2, 2]))
        .transpose()?;
    // The linear and local solves of a few thousand observations end within milliseconds.
    let short = opts.method != Method::Optimal && n * v <= SHORT_BATCH;
    let (mut report, mut columns) = unstarted::<PyPointTriangulations>(py, opts.method, n)?;
    let outcome = run_interruptible(py, progress, budget, short, move |done| {
        let tracks = DensePointTracks {
            observations: &pixels,
            visible: mask.as_deref(),
            covariances: covariances.as_deref(),
        };
        let sink = Sink::default();
        if opts.method == Method::Linear {
            let started = Instant::now();
            let write = |t, row, r| write_linear(&sink, t, row, r);
            let stopped = linear_points_into(&cams, &tracks, Some(done), rows(&mut report, &mut columns), write)?;
            // The fast path does not time tracks one by one: each solved one gets the batch's mean.
            let written = done.load(Ordering::Relaxed).max(1);
            report.time_solved(started.elapsed().as_secs_f64() / written as f64);
            return Ok(sink.finish(report, columns, n, stopped));
        }
        let write = |t, row, r| sink.write::<PyPointTriangulations>(t, row, r);
        let stopped = core_points(&cams, tracks, &opts, Some(done), rows(&mut report, &mut columns), write)?;
        let (report, mut columns) = sink.finish(report, columns, n, stopped);
        if opts.outlier_threshold.is_some() {
            // Track t's views are its visible ones, in camera order.
            let visible = mask.as_deref();
            (columns.inliers).scatter(vec![n, v], |t| InlierColumns::dense_positions(visible, v, t));
        }
        Ok((report, columns))
    })?;
    batch_result(py, outcome)
}

/// Triangulates the point tracks of observations given one per row, as COLMAP lists them: observation
/// `k` is the pixel `observations[k]` (m, 2) of track `track[k]` in image `image[k]` (an index into
/// `projections` (v, 3, 4)), with the covariance `covariances[k]` (m, 2, 2) when given. Memory grows with the observations, not with
/// tracks × images. Track `t` of the result is `t` of `track` (`0..n_tracks`, by default
/// `max(track) + 1`, both below or at the `m` rows given, else `InvalidOptionError`: the result never
/// outgrows the input; a track id without observations is rejected as too few views); each is solved as
/// `triangulate_points` would.
///
/// `cameras`, when given, holds the camera of each image (v,), a `Camera` or a `Camera` of any of
/// COLMAP's models: then `projections[j]` is `K [R | t]` of that camera's pinhole part at the image's
/// pose, `observations` are the observed (distorted) pixels and `covariances` their covariances, and the cost is the reprojection
/// error in those pixels through the exact projection; `optimal` certifies that cost (certificate
/// `lens_convexity_test`) where it can prove it, and is `gap_not_closed` where it cannot.
#[allow(clippy::too_many_arguments)]
pub(crate) fn point_observations(
    py: Python<'_>,
    cameras: &Bound<'_, PyAny>,
    track: &Bound<'_, PyAny>,
    image: &Bound<'_, PyAny>,
    observations: &Bound<'_, PyAny>,
    covariances: Option<&Bound<'_, PyAny>>,
    options: Option<PyRef<'_, PyTriangulationOptions>>,
    progress: Option<&Bound<'_, PyAny>>,
    time_budget: Option<Real>,
    n_tracks: Option<Integer>,
) -> PyResult<Py<PyPointTriangulations>> {
    let budget = crate::convert::time_budget(time_budget)?;
    let opts = options_arg(options)?;
    let (cams, views) = crate::view::known_cameras(cameras)?;
    let rows = SortedRows::read(track, image, n_tracks)?;
    let m = rows.len();
    let pixels = rows.per_row("observations", observations, &[2])?;
    let covariances = covariances
        .map(|c| rows.per_row("covariances", c, &[2, 2]))
        .transpose()?;
    let n = rows.tracks();
    let (mut report, mut columns) = unstarted::<PyPointTriangulations>(py, opts.method, n)?;
    let outcome = run_interruptible(py, progress, budget, false, move |done| {
        let sparse = SparsePointTracks {
            csr: rows.csr(),
            observations: &pixels,
            covariances: covariances.as_deref(),
        };
        let sink = Sink::default();
        let out = batch::rows(&mut report, &mut columns);
        let write =
            |t, row, r: Result<_, Error>| sink.write::<PyPointTriangulations>(t, row, r.map_err(|e| rows.restate(e)));
        let stopped = match &views {
            Some(views) => core_points(views, sparse, &opts, Some(done), out, write),
            None => core_points(&cams, sparse, &opts, Some(done), out, write),
        }?;
        let (report, mut columns) = sink.finish(report, columns, n, stopped);
        if opts.outlier_threshold.is_some() {
            // Track t's observations are its sorted rows, each back at its row as given.
            columns.inliers.scatter(vec![m], |t| rows.rows_of(t));
        }
        Ok((report, columns))
    })?;
    batch_result(py, outcome)
}
