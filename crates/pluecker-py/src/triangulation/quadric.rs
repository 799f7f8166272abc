//! Quadrics: `triangulate_quadric` (an ellipsoid from its outline conics) with
//! `pluecker.QuadricTriangulation`, and `triangulate_quadrics` (many tracks, solved by the core's
//! batch with the GIL released) with `pluecker.QuadricTriangulations`, column arrays beside the
//! per-track report columns of `pluecker.BatchReport` ([`super::batch`]).

use super::batch::{
    self, column, per_observation, rows, sparse_form, unstarted, write_row_major, Cameras, EstimateColumns,
    PyBatchReport, Sink,
};
use super::observation_rows::SortedRows;
use super::report::PyTriangulationReport;
use super::{options_arg, PyTriangulationOptions};
use crate::convert::{self, matrix_stack, read, read_mask, same_count, Dim, Integer, Real};
use crate::interrupt::{self, batch_result, run_interruptible};
use crate::pickle::reduce;
use crate::properties::{result_class, Array};
use nalgebra::{Matrix3, Matrix4, Vector3};
use pluecker::triangulation::quadric::{
    triangulate_quadric as core_triangulate_quadric, QuadricObservations, QuadricTriangulation,
};
use pluecker::triangulation::quadric::{DenseQuadricTracks, SparseQuadricTracks};
use pluecker::triangulation::streaming::quadrics_into as core_quadrics;
use pluecker::triangulation::uncertainty::QuadricCovariance;
use pluecker::triangulation::{CostKind, Report};
use pyo3::prelude::*;
use pyo3::types::PyTuple;
use rayon::prelude::*;

/// A triangulated ellipsoid: dual and primal quadric, centre, axes, semi-axes, and the report fields.
#[pyclass(frozen, extends = PyTriangulationReport, name = "QuadricTriangulation", module = "pluecker")]
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct PyQuadricTriangulation {
    dual: Matrix4<f64>,
    primal: Option<Matrix4<f64>>,
    centre: Vector3<f64>,
    axes: Matrix3<f64>,
    semi_axes: Vector3<f64>,
    covariance: Option<QuadricCovariance>,
}

impl PyQuadricTriangulation {
    pub fn create(py: Python<'_>, r: QuadricTriangulation) -> PyResult<Py<PyQuadricTriangulation>> {
        let init =
            PyClassInitializer::from(PyTriangulationReport { inner: r.report }).add_subclass(PyQuadricTriangulation {
                dual: r.dual,
                primal: r.primal,
                centre: r.centre,
                axes: r.axes,
                semi_axes: r.semi_axes,
                covariance: r.covariance,
            });
        Py::new(py, init)
    }
}

result_class! {
    PyQuadricTriangulation: PyTriangulationReport {
        /// The dual quadric `Q` (4x4, symmetric), the estimate of eq. 19.
        Q = |q| q.dual;
        /// The primal quadric `Q⁻¹` (4x4); `None` when `Q` is singular.
        primal = |q| q.primal;
        /// Centre of the ellipsoid, world frame.
        centre = |q| q.centre;
        /// Principal axes of the ellipsoid, one per column.
        axes = |q| q.axes;
        /// Semi-axis lengths along `axes`, world units.
        semi_axes = |q| q.semi_axes;
        /// 9x9 covariance of the quadric's parameters (first order); `None` when singular.
        covariance = |q| q.covariance;
    }

    /// Pickle support (also `copy.deepcopy`): see `pickle.rs`.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        reduce(slf.py(), "QuadricTriangulation", &(slf.as_super().get(), slf.get()))
    }

    fn __repr__(slf: &Bound<'_, Self>) -> String {
        let me = slf.get();
        let (c, s) = (me.centre, me.semi_axes);
        format!(
            "QuadricTriangulation(centre=[{:.6}, {:.6}, {:.6}], semi_axes=[{:.6}, {:.6}, {:.6}], {})",
            c.x,
            c.y,
            c.z,
            s.x,
            s.y,
            s.z,
            slf.as_super().get().repr_fields()
        )
    }
}

/// Triangulates an ellipsoid from its outline conics in three or more views (Josephson & Kahl 2008).
///
/// `cameras`: (n, 3, 4) matrices `P`, or `View`s; a view through a lens with distortion is refused
/// (`InvalidOptionError` naming `cameras`), since the outline seen through it is not a conic; pinholes and
/// lenses without distortion are solved as their `K [R | t]`.
#[pyfunction]
#[pyo3(signature = (cameras, conics, covariances = None, *, options = None))]
pub fn triangulate_quadric(
    py: Python<'_>,
    cameras: &Bound<'_, PyAny>,
    conics: &Bound<'_, PyAny>,
    covariances: Option<&Bound<'_, PyAny>>,
    options: Option<PyRef<'_, PyTriangulationOptions>>,
) -> PyResult<Py<PyQuadricTriangulation>> {
    let opts = options_arg(options)?;
    let cams = crate::view::pinhole_projections(cameras)?;
    let observed = convert::conics("conics", conics)?;
    same_count("conics", observed.len(), cams.len())?;
    let covs = match covariances {
        Some(c) => {
            let covs = matrix_stack::<5, 5>("covariances", c)?;
            same_count("covariances", covs.len(), cams.len())?;
            Some(covs)
        }
        None => None,
    };
    // Ctrl-C stops its branch and bound: `KeyboardInterrupt` with the estimate reached as `partial`.
    let outcome = interrupt::run_single(py, move || {
        core_triangulate_quadric(&cams, QuadricObservations::Conics(&observed, covs.as_deref()), &opts)
    })?;
    interrupt::object_or_partial(py, outcome.pending, PyQuadricTriangulation::create(py, outcome.value)?)
}

/// The results of `triangulate_quadrics`: dual and primal quadrics, centres, semi-axes and axes.
#[pyclass(frozen, extends = PyBatchReport, name = "QuadricTriangulations", module = "pluecker")]
#[derive(Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct PyQuadricTriangulations {
    dual: Vec<f64>,
    primal: Vec<f64>,
    centre: Vec<f64>,
    semi_axes: Vec<f64>,
    axes: Vec<f64>,
    covariance: Vec<f64>,
}

/// One track's entries of the quadric columns, written in place.
pub(crate) struct QuadricRow<'a> {
    dual: &'a mut [f64],
    primal: &'a mut [f64],
    centre: &'a mut [f64],
    semi_axes: &'a mut [f64],
    axes: &'a mut [f64],
    covariance: &'a mut [f64],
}

impl EstimateColumns for PyQuadricTriangulations {
    type Track = QuadricTriangulation;
    const COST_KIND: CostKind = CostKind::ConicResidual;
    type Row<'a> = QuadricRow<'a>;

    fn unstarted(py: Python<'_>, n: usize) -> PyResult<Self> {
        Ok(PyQuadricTriangulations {
            dual: column(py, f64::NAN, n, 16)?,
            primal: column(py, f64::NAN, n, 16)?,
            centre: column(py, f64::NAN, n, 3)?,
            semi_axes: column(py, f64::NAN, n, 3)?,
            axes: column(py, f64::NAN, n, 9)?,
            covariance: column(py, f64::NAN, n, 81)?,
        })
    }

    fn rows_mut(&mut self) -> impl IndexedParallelIterator<Item = QuadricRow<'_>> {
        let quadrics = (self.dual.par_chunks_mut(16)).zip(self.primal.par_chunks_mut(16));
        let shapes = (self.centre.par_chunks_mut(3))
            .zip(self.semi_axes.par_chunks_mut(3))
            .zip(self.axes.par_chunks_mut(9));
        (quadrics.zip(shapes)).zip(self.covariance.par_chunks_mut(81)).map(
            |(((dual, primal), ((centre, semi_axes), axes)), covariance)| QuadricRow {
                dual,
                primal,
                centre,
                semi_axes,
                axes,
                covariance,
            },
        )
    }

    fn write(row: QuadricRow<'_>, track: QuadricTriangulation) -> (Report, Option<Vec<bool>>) {
        write_row_major(row.dual, Some(&track.dual));
        write_row_major(row.primal, track.primal.as_ref());
        row.centre.copy_from_slice(track.centre.as_slice());
        row.semi_axes.copy_from_slice(track.semi_axes.as_slice());
        write_row_major(row.axes, Some(&track.axes));
        write_row_major(row.covariance, track.covariance.as_ref());
        (track.report, None)
    }
}

result_class! {
    PyQuadricTriangulations: PyBatchReport {
        /// Per track: the dual quadric, shape (n, 4, 4) (NaN for a rejected track).
        Q = |b| Array::rows(b.dual.clone(), &[4, 4]);
        /// Per track: the primal quadric, shape (n, 4, 4) (NaN where `Q` is singular).
        primal = |b| Array::rows(b.primal.clone(), &[4, 4]);
        /// Per track: centre, shape (n, 3).
        centre = |b| Array::rows(b.centre.clone(), &[3]);
        /// Per track: principal axes (columns), shape (n, 3, 3).
        axes = |b| Array::rows(b.axes.clone(), &[3, 3]);
        /// Per track: semi-axis lengths, shape (n, 3).
        semi_axes = |b| Array::rows(b.semi_axes.clone(), &[3]);
        /// Per track: 9x9 covariance, shape (n, 9, 9) (NaN where there is none).
        covariance = |b| Array::rows(b.covariance.clone(), &[9, 9]);
    }

    fn __repr__(slf: &Bound<'_, Self>) -> String {
        slf.as_super().get().repr("QuadricTriangulations")
    }

    /// Pickle support (also `copy.deepcopy`): see `pickle.rs`.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        reduce(slf.py(), "QuadricTriangulations", &(slf.as_super().get(), slf.get()))
    }
}

/// Triangulates many ellipsoids (tracks) from their outline conics in parallel (Josephson & Kahl 2008).
#[pyfunction]
#[pyo3(signature = (cameras, conics, visible = None, covariances = None, *, options = None, progress = None, time_budget = None, track = None, image = None, n_tracks = None))]
#[allow(clippy::too_many_arguments)]
pub fn triangulate_quadrics(
    py: Python<'_>,
    cameras: &Bound<'_, PyAny>,
    conics: &Bound<'_, PyAny>,
    visible: Option<&Bound<'_, PyAny>>,
    covariances: Option<&Bound<'_, PyAny>>,
    options: Option<PyRef<'_, PyTriangulationOptions>>,
    progress: Option<&Bound<'_, PyAny>>,
    time_budget: Option<Real>,
    track: Option<&Bound<'_, PyAny>>,
    image: Option<&Bound<'_, PyAny>>,
    n_tracks: Option<Integer>,
) -> PyResult<Py<PyQuadricTriangulations>> {
    if let Some((track, image)) = sparse_form(track, image, visible, n_tracks, false)? {
        return quadric_observations(
            py,
            cameras,
            track,
            image,
            conics,
            covariances,
            options,
            progress,
            time_budget,
            n_tracks,
        );
    }
    let budget = crate::convert::time_budget(time_budget)?;
    let opts = options_arg(options)?;
    let cams = Cameras::read(cameras, 3, opts.method)?;
    let spec = [Dim::Free("n"), Dim::Free("v"), Dim::Fixed(3), Dim::Fixed(3)];
    let (shape, values) = read("conics", conics, &spec)?;
    cams.check_observations("conics", &shape, "3, 3")?;
    let (n, v) = (shape[0], shape[1]);
    let mask = visible.map(|m| read_mask("visible", m, &[n, v])).transpose()?;
    let covariances = covariances
        .map(|c| per_observation("covariances", c, n, v, [5, 5]))
        .transpose()?;
    let (mut report, mut columns) = unstarted::<PyQuadricTriangulations>(py, opts.method, n)?;
    let outcome = run_interruptible(py, progress, budget, false, move |done| {
        let tracks = DenseQuadricTracks {
            conics: &values,
            visible: mask.as_deref(),
            covariances: covariances.as_deref(),
        };
        let sink = Sink::default();
        let write = |t, row, r| sink.write::<PyQuadricTriangulations>(t, row, r);
        let stopped = core_quadrics(
            cams.core(),
            tracks,
            &opts,
            Some(done),
            rows(&mut report, &mut columns),
            write,
        )?;
        Ok(sink.finish(report, columns, n, stopped))
    })?;
    batch_result(py, outcome)
}

/// Triangulates the ellipsoid tracks of outline conics given one per row, as
/// the rows form of `triangulate_points` does points: row `k` is the conic `conics[k]` (m, 3, 3) of track
/// `track[k]` in image `image[k]` (an index into `projections` (v, 3, 4)), with the covariance
/// `covariances[k]` (m, 5, 5) when given. Each track is solved as `triangulate_quadrics` would.
#[allow(clippy::too_many_arguments)]
pub(crate) fn quadric_observations(
    py: Python<'_>,
    cameras: &Bound<'_, PyAny>,
    track: &Bound<'_, PyAny>,
    image: &Bound<'_, PyAny>,
    conics: &Bound<'_, PyAny>,
    covariances: Option<&Bound<'_, PyAny>>,
    options: Option<PyRef<'_, PyTriangulationOptions>>,
    progress: Option<&Bound<'_, PyAny>>,
    time_budget: Option<Real>,
    n_tracks: Option<Integer>,
) -> PyResult<Py<PyQuadricTriangulations>> {
    let budget = crate::convert::time_budget(time_budget)?;
    let opts = options_arg(options)?;
    let cams = crate::view::pinhole_projections(cameras)?;
    let rows = SortedRows::read(track, image, n_tracks)?;
    let values = rows.per_row("conics", conics, &[3, 3])?;
    let covariances = covariances
        .map(|c| rows.per_row("covariances", c, &[5, 5]))
        .transpose()?;
    let n = rows.tracks();
    let (mut report, mut columns) = unstarted::<PyQuadricTriangulations>(py, opts.method, n)?;
    let outcome = run_interruptible(py, progress, budget, false, move |done| {
        let tracks = SparseQuadricTracks {
            csr: rows.csr(),
            conics: &values,
            covariances: covariances.as_deref(),
        };
        let sink = Sink::default();
        let write = |t, row, r: pluecker::Result<_>| {
            sink.write::<PyQuadricTriangulations>(t, row, r.map_err(|e| rows.restate(e)))
        };
        let out = batch::rows(&mut report, &mut columns);
        let stopped = core_quadrics(&cams, tracks, &opts, Some(done), out, write)?;
        Ok(sink.finish(report, columns, n, stopped))
    })?;
    batch_result(py, outcome)
}
