//! Lines: `triangulate_line` (one 3-D line from its images) with `pluecker.LineTriangulation`, and
//! `triangulate_lines` (many tracks, solved by the core's batch with the GIL released) with
//! `pluecker.LineTriangulations`, column arrays beside the per-track report columns of
//! `pluecker.BatchReport` ([`super::batch`]).
//!
//! Image lines are `(…, 3)` homogeneous lines or `(…, 2, 2)` segments; cameras of a batch are
//! shared `(v, 3, 4)` or per track `(n, v, 3, 4)` ([`super::batch::Cameras`]).

use super::batch::{
    self, column, per_observation, rows, sparse_form, unstarted, write_row_major, Cameras, EstimateColumns,
    InlierColumns, PyBatchReport, Sink,
};
use super::observation_rows::SortedRows;
use super::report::PyTriangulationReport;
use super::{options_arg, positive_sigma, sigma_variance, PyTriangulationOptions};
use crate::convert::{
    check_finite, covariances2, optional_real, read_any, read_mask, same_count, shape_string, Integer, Real,
};
use crate::errors::{invalid_argument, shape_error};
use crate::interrupt::{self, batch_result, run_interruptible};
use crate::pickle::reduce;
use crate::properties::{result_class, Array, Field};
use nalgebra::{Matrix2, Matrix2x3, Matrix4, Vector2, Vector3, Vector6};
use pluecker::geometry::plucker::LineChart;
use pluecker::interrupt::StopReason;
use pluecker::triangulation::line::{
    lines_from_segments, triangulate_line as core_triangulate_line, LineObservations, LineTriangulation,
};
use pluecker::triangulation::line::{DenseLineTracks, ImageLines, SparseLineTracks, SparseSegmentTracks};
use pluecker::triangulation::streaming::lines_into as core_lines;
use pluecker::triangulation::{CostKind, Report, TriangulationOptions};
use pyo3::prelude::*;
use pyo3::types::PyTuple;
use rayon::prelude::*;

/// A triangulated 3-D line: Plücker coordinates, a point, a unit direction, and the report fields.
#[pyclass(frozen, extends = PyTriangulationReport, name = "LineTriangulation", module = "pluecker")]
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct PyLineTriangulation {
    plucker: Vector6<f64>,
    point: Vector3<f64>,
    direction: Vector3<f64>,
    chart: LineChart,
    covariance: Option<Matrix4<f64>>,
    inliers: Option<Vec<bool>>,
}

impl PyLineTriangulation {
    pub fn create(py: Python<'_>, result: LineTriangulation) -> PyResult<Py<PyLineTriangulation>> {
        let init = PyClassInitializer::from(PyTriangulationReport { inner: result.report }).add_subclass(
            PyLineTriangulation {
                plucker: *result.plucker.coordinates(),
                point: result.point,
                direction: result.direction,
                chart: result.chart,
                covariance: result.covariance,
                inliers: result.inliers,
            },
        );
        Py::new(py, init)
    }
}

result_class! {
    PyLineTriangulation: PyTriangulationReport {
        /// Plücker coordinates `(l12, l13, l14, l23, l42, l34)` of the line, unit norm (eq. 4 holds).
        plucker = |l| l.plucker;
        /// The point of the line closest to the world origin.
        point = |l| l.point;
        /// Unit direction of the line.
        direction = |l| l.direction;
        /// Rows `e1`, `e2`: the axes of the 4-parameter chart in which `covariance` is expressed.
        chart_axes = |l| chart_axes(&l.chart);
        /// 4x4 covariance of the line in its chart (first order); `None` when singular.
        covariance = |l| l.covariance;
        /// With `options.outlier_threshold`: (v,) the views the line was solved from; else `None`.
        inliers = |l| l.inliers.clone();
    }

    /// The 6x6 covariance of the unit Plücker coordinates (`LineChart::plucker_covariance`).
    fn plucker_covariance(&self, py: Python<'_>) -> PyResult<PyObject> {
        self.covariance.map(|c| self.chart.plucker_covariance(&c)).get(py)
    }

    /// The 6x6 covariance of `(point, direction)` (`LineChart::point_direction_covariance`).
    fn point_direction_covariance(&self, py: Python<'_>) -> PyResult<PyObject> {
        self.covariance.map(|c| self.chart.point_direction_covariance(&c)).get(py)
    }

    /// Pickle support (also `copy.deepcopy`): see `pickle.rs`.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        reduce(slf.py(), "LineTriangulation", &(slf.as_super().get(), slf.get()))
    }

    fn __repr__(slf: &Bound<'_, Self>) -> String {
        let me = slf.get();
        let (p, d) = (me.point, me.direction);
        format!(
            "LineTriangulation(point=[{:.6}, {:.6}, {:.6}], direction=[{:.6}, {:.6}, {:.6}], {})",
            p.x,
            p.y,
            p.z,
            d.x,
            d.y,
            d.z,
            slf.as_super().get().repr_fields()
        )
    }
}

/// The chart axes `e₁`, `e₂` of a line's covariance as the rows of a 2x3 matrix.
pub(crate) fn chart_axes(chart: &LineChart) -> Matrix2x3<f64> {
    Matrix2x3::from_rows(&[chart.axes[0].transpose(), chart.axes[1].transpose()])
}

/// Homogeneous image lines and, when they come from segments without `covariances`, their covariances.
type HomogeneousLines = (Vec<Vector3<f64>>, Option<Vec<Matrix2<f64>>>);

/// The image lines of `triangulate_line`: `(n, 3)` homogeneous lines, or `(n, 2, 2)` segments whose
/// lines (and, without `covariances`, covariances from endpoint noise `sigma`) come from
/// `lines_from_segments`.
fn image_lines(obj: &Bound<'_, PyAny>, views: usize, have_cov: bool, sigma: Option<f64>) -> PyResult<HomogeneousLines> {
    let (shape, values) = read_any("lines", obj)?;
    match shape.as_slice() {
        [n, 3] => {
            same_count("lines", *n, views)?;
            if sigma.is_some() {
                return Err(invalid_argument(
                    "sigma",
                    "applies to segments (n, 2, 2) only; give covariances for homogeneous lines",
                ));
            }
            check_finite("lines", &values, 3)?;
            Ok((values.chunks_exact(3).map(Vector3::from_row_slice).collect(), None))
        }
        [n, 2, 2] => {
            same_count("lines", *n, views)?;
            if have_cov && sigma.is_some() {
                return Err(invalid_argument("sigma", "give covariances or sigma, not both"));
            }
            let sigma = positive_sigma(sigma.unwrap_or(1.0))?;
            let segments: Vec<[Vector2<f64>; 2]> = values
                .chunks_exact(4)
                .map(|s| [Vector2::new(s[0], s[1]), Vector2::new(s[2], s[3])])
                .collect();
            let (lines, covs) = lines_from_segments(&segments, sigma).map_err(crate::errors::to_py_err)?;
            Ok((lines, if have_cov { None } else { Some(covs) }))
        }
        _ => Err(shape_error(
            "lines",
            "shape (n, 3) (homogeneous lines) or (n, 2, 2) (segments)",
            shape_string(&shape),
        )),
    }
}

/// The segments `(n, 2, 2)` of a call with `cameras` (the images' own pixels; finiteness is the
/// core's check, naming the row).
fn lens_segments(obj: &Bound<'_, PyAny>, views: usize) -> PyResult<Vec<[Vector2<f64>; 2]>> {
    let (shape, values) = read_any("lines", obj)?;
    match shape.as_slice() {
        [n, 2, 2] => {
            same_count("lines", *n, views)?;
            Ok(values
                .chunks_exact(4)
                .map(|s| [Vector2::new(s[0], s[1]), Vector2::new(s[2], s[3])])
                .collect())
        }
        _ => Err(shape_error(
            "lines",
            "segments of shape (n, 2, 2) with cameras (a line's image through a lens is a curve, not a homogeneous line)",
            shape_string(&shape),
        )),
    }
}

/// The endpoint covariances of a call with `cameras`: `covariances` of shape `(*lead, 2, 2, 2)` (each
/// segment's two endpoints), or `σ² I` from `sigma` (not both), or `None` (the identity).
fn endpoint_covariances(
    covariances: Option<&Bound<'_, PyAny>>,
    sigma: Option<f64>,
    lead: &[usize],
) -> PyResult<Option<Vec<[Matrix2<f64>; 2]>>> {
    if covariances.is_some() && sigma.is_some() {
        return Err(invalid_argument("sigma", "give covariances or sigma, not both"));
    }
    if let Some(sigma) = sigma {
        let variance = sigma_variance(sigma)?;
        let n: usize = lead.iter().product();
        return Ok(Some(vec![[Matrix2::identity() * variance; 2]; n]));
    }
    let Some(covariances) = covariances else {
        return Ok(None);
    };
    let (shape, values) = read_any("covariances", covariances)?;
    let mut expected = lead.to_vec();
    expected.extend([2, 2, 2]);
    if shape != expected {
        return Err(shape_error(
            "covariances",
            &format!(
                "shape ({}, 2, 2, 2) with cameras (the covariances of each segment's two endpoints)",
                lead.iter().map(|d| d.to_string()).collect::<Vec<_>>().join(", ")
            ),
            shape_string(&shape),
        ));
    }
    Ok(Some(
        values
            .chunks_exact(8)
            .map(|c| [Matrix2::from_row_slice(&c[..4]), Matrix2::from_row_slice(&c[4..])])
            .collect(),
    ))
}

/// Triangulates one 3-D line from its images in two or more views (Josephson & Kahl 2008, eq. 19).
///
/// `cameras`, when given, holds each view's `Camera` (any model):
/// `projections[i]` is then `K [R | t]` of its pinhole part, `lines` are segments (n, 2, 2) whose
/// endpoints are the observed (distorted) pixels, and `covariances` (n, 2, 2, 2) the covariances of each segment's two endpoints in those
/// pixels (else `sigma` px per coordinate, 1 by default). Through a distorting lens the cost is the
/// segments' reprojection error through the exact projection (the endpoints' distances to the line's
/// curved images, `cost_kind` `reprojection`), minimised locally and never certified (`optimal` reports
/// `gap_not_closed`); without distortion it is the pinhole problem of the segments, eq. 19 on their line
/// residuals (`line_residual`), with its certificate.
#[pyfunction]
#[pyo3(signature = (cameras, lines, covariances = None, *, sigma = None, options = None))]
#[allow(clippy::too_many_arguments)]
pub fn triangulate_line(
    py: Python<'_>,
    cameras: &Bound<'_, PyAny>,
    lines: &Bound<'_, PyAny>,
    covariances: Option<&Bound<'_, PyAny>>,
    sigma: Option<Real>,
    options: Option<PyRef<'_, PyTriangulationOptions>>,
) -> PyResult<Py<PyLineTriangulation>> {
    let opts = options_arg(options)?;
    let (cams, views) = crate::view::known_cameras(cameras)?;
    let sigma = optional_real("sigma", sigma)?;
    if let Some(views) = views {
        let segments = lens_segments(lines, views.len())?;
        let covariances = endpoint_covariances(covariances, sigma, &[views.len()])?;
        let outcome = interrupt::run_single(py, move || {
            core_triangulate_line(
                &views,
                LineObservations::SegmentEndpoints(&segments, covariances.as_deref()),
                &opts,
            )
        })?;
        return interrupt::object_or_partial(py, outcome.pending, PyLineTriangulation::create(py, outcome.value)?);
    }
    let (image, from_segments) = image_lines(lines, cams.len(), covariances.is_some(), sigma)?;
    let covs = match covariances2("covariances", covariances, cams.len())? {
        Some(c) => Some(c),
        None => from_segments,
    };
    // Ctrl-C stops its branch and bound: `KeyboardInterrupt` with the estimate reached as `partial`.
    let outcome = interrupt::run_single(py, move || {
        core_triangulate_line(&cams, LineObservations::Lines(&image, covs.as_deref()), &opts)
    })?;
    interrupt::object_or_partial(py, outcome.pending, PyLineTriangulation::create(py, outcome.value)?)
}

/// The results of `triangulate_lines`: Plücker coordinates, points and directions per track.
#[pyclass(frozen, extends = PyBatchReport, name = "LineTriangulations", module = "pluecker")]
#[derive(Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct PyLineTriangulations {
    plucker: Vec<f64>,
    point: Vec<f64>,
    direction: Vec<f64>,
    chart_axes: Vec<f64>,
    covariance: Vec<f64>,
    /// Robust only: the inlier masks, laid out as the observations were given (`(n, v)` or `(m,)`).
    inliers: InlierColumns,
}

/// One track's entries of the line columns, written in place.
pub(crate) struct LineRow<'a> {
    plucker: &'a mut [f64],
    point: &'a mut [f64],
    direction: &'a mut [f64],
    chart_axes: &'a mut [f64],
    covariance: &'a mut [f64],
}

impl EstimateColumns for PyLineTriangulations {
    type Track = LineTriangulation;
    const COST_KIND: CostKind = CostKind::LineResidual;
    type Row<'a> = LineRow<'a>;

    fn unstarted(py: Python<'_>, n: usize) -> PyResult<Self> {
        Ok(PyLineTriangulations {
            plucker: column(py, f64::NAN, n, 6)?,
            point: column(py, f64::NAN, n, 3)?,
            direction: column(py, f64::NAN, n, 3)?,
            chart_axes: column(py, f64::NAN, n, 6)?,
            covariance: column(py, f64::NAN, n, 16)?,
            inliers: InlierColumns::default(),
        })
    }

    fn rows_mut(&mut self) -> impl IndexedParallelIterator<Item = LineRow<'_>> {
        let lines = (self.plucker.par_chunks_mut(6))
            .zip(self.point.par_chunks_mut(3))
            .zip(self.direction.par_chunks_mut(3));
        let uncertainty = (self.chart_axes.par_chunks_mut(6)).zip(self.covariance.par_chunks_mut(16));
        lines
            .zip(uncertainty)
            .map(|(((plucker, point), direction), (chart_axes, covariance))| LineRow {
                plucker,
                point,
                direction,
                chart_axes,
                covariance,
            })
    }

    fn write(row: LineRow<'_>, track: LineTriangulation) -> (Report, Option<Vec<bool>>) {
        row.plucker.copy_from_slice(track.plucker.coordinates().as_slice());
        row.point.copy_from_slice(track.point.as_slice());
        row.direction.copy_from_slice(track.direction.as_slice());
        write_row_major(row.chart_axes, Some(&chart_axes(&track.chart)));
        write_row_major(row.covariance, track.covariance.as_ref());
        (track.report, track.inliers)
    }

    fn set_inliers(&mut self, inliers: InlierColumns) {
        self.inliers = inliers;
    }
}

result_class! {
    PyLineTriangulations: PyBatchReport {
        /// Per track: Plücker coordinates, shape (n, 6) (NaN for a rejected track).
        plucker = |b| Array::rows(b.plucker.clone(), &[6]);
        /// Per track: the point of the line closest to the origin, shape (n, 3).
        point = |b| Array::rows(b.point.clone(), &[3]);
        /// Per track: unit direction, shape (n, 3).
        direction = |b| Array::rows(b.direction.clone(), &[3]);
        /// Per track: the chart axes of `covariance`, shape (n, 2, 3).
        chart_axes = |b| Array::rows(b.chart_axes.clone(), &[2, 3]);
        /// Per track: 4x4 covariance in the chart, shape (n, 4, 4) (NaN where there is none).
        covariance = |b| Array::rows(b.covariance.clone(), &[4, 4]);
        /// With `options.outlier_threshold`: which observations each line was solved from, shaped as the
        /// observations were given ((n, v) dense, (m,) in the rows form with `track=`, `image=`; false
        /// where not visible or rejected); else `None`.
        inliers = |b| b.inliers.mask();
    }

    fn __repr__(slf: &Bound<'_, Self>) -> String {
        slf.as_super().get().repr("LineTriangulations")
    }

    /// Pickle support (also `copy.deepcopy`): see `pickle.rs`.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        reduce(slf.py(), "LineTriangulations", &(slf.as_super().get(), slf.get()))
    }
}

/// Whether the `lines` of a batch (shape `(*lead, 3)` or `(*lead, 2, 2)` with `lead` leading axes:
/// 2 for `(n, v, ...)`, 1 for one row per observation) are segments, with the checks of `sigma`: it
/// applies to segments only, and not together with `covariances`.
fn segments_or_lines(shape: &[usize], lead: usize, sigma: Option<f64>, have_cov: bool) -> PyResult<bool> {
    let axes = if lead == 2 { "n, v" } else { "m" };
    let tail = shape.get(lead..).unwrap_or(&[]);
    let segments = match (shape.len() - tail.len() == lead, tail) {
        (true, [3]) => false,
        (true, [2, 2]) => true,
        _ => {
            return Err(shape_error(
                "lines",
                &format!("shape ({axes}, 3) (homogeneous lines) or ({axes}, 2, 2) (segments)"),
                shape_string(shape),
            ))
        }
    };
    if sigma.is_some() && !segments {
        return Err(invalid_argument(
            "sigma",
            format!("applies to segments ({axes}, 2, 2) only; give covariances for homogeneous lines"),
        ));
    }
    if sigma.is_some() && have_cov {
        return Err(invalid_argument("sigma", "give covariances or sigma, not both"));
    }
    Ok(segments)
}

/// The core's view of a batch's `values`: segments with endpoint noise `sigma`, or homogeneous lines.
fn image_lines_of(values: &[f64], segments: bool, sigma: f64) -> ImageLines<'_> {
    if segments {
        ImageLines::Segments {
            endpoints: values,
            sigma,
        }
    } else {
        ImageLines::Homogeneous(values)
    }
}

/// Triangulates many 3-D lines (tracks) in parallel (Josephson & Kahl 2008, eq. 19).
#[pyfunction]
#[pyo3(signature = (cameras, lines, visible = None, covariances = None, *, sigma = None, options = None, progress = None, time_budget = None, track = None, image = None, n_tracks = None))]
#[allow(clippy::too_many_arguments)]
pub fn triangulate_lines(
    py: Python<'_>,
    cameras: &Bound<'_, PyAny>,
    lines: &Bound<'_, PyAny>,
    visible: Option<&Bound<'_, PyAny>>,
    covariances: Option<&Bound<'_, PyAny>>,
    sigma: Option<Real>,
    options: Option<PyRef<'_, PyTriangulationOptions>>,
    progress: Option<&Bound<'_, PyAny>>,
    time_budget: Option<Real>,
    track: Option<&Bound<'_, PyAny>>,
    image: Option<&Bound<'_, PyAny>>,
    n_tracks: Option<Integer>,
) -> PyResult<Py<PyLineTriangulations>> {
    if let Some((track, image)) = sparse_form(track, image, visible, n_tracks, crate::view::is_views(cameras))? {
        return line_observations(
            py,
            cameras,
            track,
            image,
            lines,
            covariances,
            sigma,
            options,
            progress,
            time_budget,
            n_tracks,
        );
    }
    let budget = crate::convert::time_budget(time_budget)?;
    let opts = options_arg(options)?;
    let sigma = optional_real("sigma", sigma)?;
    let cams = Cameras::read(cameras, 2, opts.method)?;
    let (shape, values) = read_any("lines", lines)?;
    let segments = segments_or_lines(&shape, 2, sigma, covariances.is_some())?;
    cams.check_observations("lines", &shape, if segments { "2, 2" } else { "3" })?;
    let (n, v) = (shape[0], shape[1]);
    let mask = visible.map(|m| read_mask("visible", m, &[n, v])).transpose()?;
    let covariances = covariances
        .map(|c| per_observation("covariances", c, n, v, [2, 2]))
        .transpose()?;
    let sigma = sigma.unwrap_or(1.0);
    let (mut report, mut columns) = unstarted::<PyLineTriangulations>(py, opts.method, n)?;
    let outcome = run_interruptible(py, progress, budget, false, move |done| {
        let tracks = DenseLineTracks {
            lines: image_lines_of(&values, segments, sigma),
            visible: mask.as_deref(),
            covariances: covariances.as_deref(),
        };
        let sink = Sink::default();
        let write = |t, row, r| sink.write::<PyLineTriangulations>(t, row, r);
        let stopped = core_lines(
            cams.core(),
            tracks,
            &opts,
            Some(done),
            rows(&mut report, &mut columns),
            write,
        )?;
        let (report, mut columns) = sink.finish(report, columns, n, stopped);
        if opts.outlier_threshold.is_some() {
            let visible = mask.as_deref();
            (columns.inliers).scatter(vec![n, v], |t| InlierColumns::dense_positions(visible, v, t));
        }
        Ok((report, columns))
    })?;
    batch_result(py, outcome)
}

/// Triangulates the line tracks of observations given one per row, as the rows form of `triangulate_points`
/// does points: row `k` is the line `lines[k]` ((m, 3) homogeneous, or (m, 2, 2) segments with endpoint
/// noise `sigma`) of track `track[k]` in image `image[k]` (an index into `projections` (v, 3, 4)), with
/// the covariance `covariances[k]` (m, 2, 2) when given. Each track is solved as `triangulate_lines` would.
///
/// `cameras`, when given, holds the camera of each image (v,), a `Camera` or a `Camera` of any of
/// COLMAP's models: then `projections[j]` is `K [R | t]` of that camera's pinhole part at the image's
/// pose, `lines` are segments (m, 2, 2) in the observed (distorted) pixels, `covariances` (m, 2, 2, 2) the covariances
/// of each segment's two endpoints (else `sigma`), and each track is solved as
/// `triangulate_line(..., cameras=...)` solves it: never certified through a distorting lens.
#[allow(clippy::too_many_arguments)]
pub(crate) fn line_observations(
    py: Python<'_>,
    cameras: &Bound<'_, PyAny>,
    track: &Bound<'_, PyAny>,
    image: &Bound<'_, PyAny>,
    lines: &Bound<'_, PyAny>,
    covariances: Option<&Bound<'_, PyAny>>,
    sigma: Option<Real>,
    options: Option<PyRef<'_, PyTriangulationOptions>>,
    progress: Option<&Bound<'_, PyAny>>,
    time_budget: Option<Real>,
    n_tracks: Option<Integer>,
) -> PyResult<Py<PyLineTriangulations>> {
    let budget = crate::convert::time_budget(time_budget)?;
    let opts = options_arg(options)?;
    let sigma = optional_real("sigma", sigma)?;
    let (cams, views) = crate::view::known_cameras(cameras)?;
    let rows = SortedRows::read(track, image, n_tracks)?;
    if let Some(views) = views {
        let (shape, _) = read_any("lines", lines)?;
        if shape.len() != 3 || shape[1..] != [2, 2] {
            return Err(shape_error(
                "lines",
                "segments of shape (m, 2, 2) with cameras (a line's image through a lens is a curve, not a homogeneous line)",
                shape_string(&shape),
            ));
        }
        let values = rows.per_row("lines", lines, &[2, 2])?;
        if covariances.is_some() && sigma.is_some() {
            return Err(invalid_argument("sigma", "give covariances or sigma, not both"));
        }
        let covariances = match (covariances, sigma) {
            (Some(c), _) => Some(rows.per_row("covariances", c, &[2, 2, 2])?),
            (None, Some(sigma)) => endpoint_covariances(None, Some(sigma), &[rows.len()])?.map(|c| {
                c.iter()
                    .flat_map(|pair| pair.iter().flat_map(|m| m.transpose().as_slice().to_vec()))
                    .collect()
            }),
            (None, None) => None,
        };
        let (mut report, mut columns) = unstarted::<PyLineTriangulations>(py, opts.method, rows.tracks())?;
        let outcome = run_interruptible(py, progress, budget, false, move |done| {
            let tracks = SparseSegmentTracks {
                csr: rows.csr(),
                lines: &values,
                covariances: covariances.as_deref(),
            };
            let sink = Sink::default();
            let write = |t, row, r: pluecker::Result<_>| {
                sink.write::<PyLineTriangulations>(t, row, r.map_err(|e| rows.restate(e)))
            };
            let out = batch::rows(&mut report, &mut columns);
            let stopped = core_lines(&views, tracks, &opts, Some(done), out, write)?;
            Ok(sparse_finish(&rows, &opts, sink, report, columns, stopped))
        })?;
        return batch_result(py, outcome);
    }
    let (shape, _) = read_any("lines", lines)?;
    let segments = segments_or_lines(&shape, 1, sigma, covariances.is_some())?;
    let values = rows.per_row("lines", lines, &shape[1..])?;
    let covariances = covariances
        .map(|c| rows.per_row("covariances", c, &[2, 2]))
        .transpose()?;
    let sigma = sigma.unwrap_or(1.0);
    let (mut report, mut columns) = unstarted::<PyLineTriangulations>(py, opts.method, rows.tracks())?;
    let outcome = run_interruptible(py, progress, budget, false, move |done| {
        let tracks = SparseLineTracks {
            csr: rows.csr(),
            lines: image_lines_of(&values, segments, sigma),
            covariances: covariances.as_deref(),
        };
        let sink = Sink::default();
        let write =
            |t, row, r: pluecker::Result<_>| sink.write::<PyLineTriangulations>(t, row, r.map_err(|e| rows.restate(e)));
        let out = batch::rows(&mut report, &mut columns);
        let stopped = core_lines(&cams, tracks, &opts, Some(done), out, write)?;
        Ok(sparse_finish(&rows, &opts, sink, report, columns, stopped))
    })?;
    batch_result(py, outcome)
}

/// The columns of a sparse batch written through `sink`: with an outlier threshold each observation's
/// inlier flag put back on its row.
fn sparse_finish(
    rows: &SortedRows,
    opts: &TriangulationOptions,
    sink: Sink,
    report: PyBatchReport,
    columns: PyLineTriangulations,
    stopped: Option<StopReason>,
) -> (PyBatchReport, PyLineTriangulations) {
    let (report, mut columns) = sink.finish(report, columns, rows.tracks(), stopped);
    if opts.outlier_threshold.is_some() {
        columns.inliers.scatter(vec![rows.len()], |t| rows.rows_of(t));
    }
    (report, columns)
}
