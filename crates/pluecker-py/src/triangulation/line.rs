//! `triangulate_line` (one 3-D line from its images) and `pluecker.LineTriangulation`.

use crate::errors::{invalid_argument, non_finite, shape_error, solve};
use crate::triangulation::{options, renamed, PyTriangulationReport};
use crate::triangulation_arrays::{cameras, covariances2, first_non_finite_row, read_any, same_count, shape_string};
use crate::triangulation_quadric::{matrix_to_py, rows};
use nalgebra::{Matrix2, Matrix2x3, Matrix4, Vector2, Vector3, Vector6};
use numpy::{PyArray1, PyArray2};
use pluecker::geometry::plucker::LineChart;
use pluecker::triangulation::line::{
    lines_from_segments, triangulate_line as core_triangulate_line, LineTriangulation,
};
use crate::convert::{optional_real, Integer, Real};
use crate::convert::strict_json_dict;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use crate::pickle::{pack_struct, reduce, Pack, Reader};
use pyo3::types::PyTuple;


/// Core argument names → Python argument names of `triangulate_line`.
pub(crate) const LINE_NAMES: &[(&str, &str)] = &[
    ("cameras", "P"),
    ("lines", "lines"),
    ("segments", "lines"),
    ("covariances", "cov"),
];

/// A triangulated 3-D line: Plücker coordinates, a point, a unit direction, and the report fields.
#[pyclass(frozen, extends = PyTriangulationReport, name = "LineTriangulation", module = "pluecker")]
#[derive(Debug, Clone)]
pub struct PyLineTriangulation {
    plucker: Vector6<f64>,
    point: Vector3<f64>,
    direction: Vector3<f64>,
    chart: LineChart,
    covariance: Option<Matrix4<f64>>,
}

impl PyLineTriangulation {
    pub fn create(py: Python<'_>, result: LineTriangulation) -> PyResult<Py<PyLineTriangulation>> {
        let init = PyClassInitializer::from(PyTriangulationReport { inner: result.report }).add_subclass(
            PyLineTriangulation {
                plucker: result.plucker,
                point: result.point,
                direction: result.direction,
                chart: result.chart,
                covariance: result.covariance,
            },
        );
        Py::new(py, init)
    }
}

#[pymethods]
impl PyLineTriangulation {
    #[getter]
    fn plucker<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.plucker.as_slice())
    }

    #[getter]
    fn point<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.point.as_slice())
    }

    #[getter]
    fn direction<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.direction.as_slice())
    }

    #[getter]
    fn covariance<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray2<f64>>> {
        self.covariance.as_ref().map(|m| matrix_to_py::<4, 4>(py, m))
    }

    #[getter]
    fn chart_axes<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        matrix_to_py::<2, 3>(py, &chart_axes(&self.chart))
    }

    /// The 6x6 covariance of the unit Plücker coordinates (`LineChart::plucker_covariance`).
    fn plucker_covariance<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray2<f64>>> {
        self.covariance
            .as_ref()
            .map(|c| matrix_to_py::<6, 6>(py, &self.chart.plucker_covariance(c)))
    }

    /// The 6x6 covariance of `(point, direction)` (`LineChart::point_direction_covariance`).
    fn point_direction_covariance<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray2<f64>>> {
        self.covariance
            .as_ref()
            .map(|c| matrix_to_py::<6, 6>(py, &self.chart.point_direction_covariance(c)))
    }

    /// Plain-Python (JSON-serialisable) form: the report fields, `plucker`, `point`, `direction`,
    /// `chart_axes`, `covariance`.
    fn to_dict<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyDict>> {
        let d = slf.as_super().get().report_dict(slf.py())?;
        let me = slf.get();
        d.set_item("plucker", me.plucker.as_slice())?;
        d.set_item("point", me.point.as_slice())?;
        d.set_item("direction", me.direction.as_slice())?;
        d.set_item("chart_axes", rows::<2, 3>(&chart_axes(&me.chart)))?;
        d.set_item("covariance", me.covariance.as_ref().map(rows::<4, 4>))?;
        strict_json_dict(d)
    }

    /// Pickle support (also `copy.deepcopy`): see `pickle.rs`.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        reduce(slf.py(), "LineTriangulation", &[slf.as_super().get(), slf.get()])
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

/// Homogeneous image lines and, when they come from segments without `cov`, their covariances.
type ImageLines = (Vec<Vector3<f64>>, Option<Vec<Matrix2<f64>>>);

/// The image lines of `triangulate_line`: `(n, 3)` homogeneous lines, or `(n, 2, 2)` segments whose
/// lines (and, without `cov`, covariances from endpoint noise `sigma`) come from `lines_from_segments`.
fn image_lines(obj: &Bound<'_, PyAny>, views: usize, have_cov: bool, sigma: Option<f64>) -> PyResult<ImageLines> {
    let (shape, values) = read_any("lines", obj)?;
    match shape.as_slice() {
        [n, 3] => {
            same_count("lines", *n, views)?;
            if sigma.is_some() {
                return Err(invalid_argument(
                    "sigma",
                    "applies to segments (n, 2, 2) only; give cov for homogeneous lines",
                ));
            }
            if let Some(row) = first_non_finite_row(&values, 3) {
                return Err(non_finite("lines", row));
            }
            Ok((values.chunks_exact(3).map(Vector3::from_row_slice).collect(), None))
        }
        [n, 2, 2] => {
            same_count("lines", *n, views)?;
            if have_cov && sigma.is_some() {
                return Err(invalid_argument("sigma", "give cov or sigma, not both"));
            }
            let sigma = sigma.unwrap_or(1.0);
            if !(sigma.is_finite() && sigma > 0.0) {
                return Err(invalid_argument(
                    "sigma",
                    format!("must be a positive finite number of pixels, got {sigma}"),
                ));
            }
            let segments: Vec<[Vector2<f64>; 2]> = values
                .chunks_exact(4)
                .map(|s| [Vector2::new(s[0], s[1]), Vector2::new(s[2], s[3])])
                .collect();
            let (lines, covs) =
                lines_from_segments(&segments, sigma).map_err(|e| crate::errors::to_py_err(renamed(e, LINE_NAMES)))?;
            Ok((lines, if have_cov { None } else { Some(covs) }))
        }
        _ => Err(shape_error(
            "lines",
            "shape (n, 3) (homogeneous lines) or (n, 2, 2) (segments)",
            shape_string(&shape),
        )),
    }
}

/// Triangulates one 3-D line from its images in two or more views (Josephson & Kahl 2008, eq. 19).
#[pyfunction]
#[pyo3(signature = (P, lines, cov = None, method = "optimal", *, sigma = None, max_relative_gap = None, max_reprojection_error = None, max_nodes = None))]
#[allow(non_snake_case, clippy::too_many_arguments)]
pub fn triangulate_line(
    py: Python<'_>,
    P: &Bound<'_, PyAny>,
    lines: &Bound<'_, PyAny>,
    cov: Option<&Bound<'_, PyAny>>,
    method: &str,
    sigma: Option<Real>,
    max_relative_gap: Option<Real>,
    max_reprojection_error: Option<Real>,
    max_nodes: Option<Integer>,
) -> PyResult<Py<PyLineTriangulation>> {
    let opts = options(method, max_relative_gap, max_reprojection_error, max_nodes)?;
    let cams = cameras("P", P)?;
    let sigma = optional_real("sigma", sigma)?;
    let (image, from_segments) = image_lines(lines, cams.len(), cov.is_some(), sigma)?;
    let covs = match covariances2("cov", cov, cams.len())? {
        Some(c) => Some(c),
        None => from_segments,
    };
    let result = solve(py, move || {
        core_triangulate_line(&cams, &image, covs.as_deref(), &opts).map_err(|e| renamed(e, LINE_NAMES))
    })?;
    PyLineTriangulation::create(py, result)
}

pack_struct!(PyLineTriangulation { plucker, point, direction, chart, covariance });
