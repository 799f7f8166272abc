//! `triangulate_point` (one point from its views) and `pluecker.PointTriangulation`.

use crate::errors::{non_finite, solve};
use crate::triangulation::{options, renamed, PyTriangulationReport, POINT_NAMES};
use crate::triangulation_arrays::{cameras, covariances2, first_non_finite_row, read, same_count, Dim};
use crate::triangulation_quadric::{matrix_to_py, rows};
use nalgebra::{Matrix3, Vector2, Vector3};
use numpy::{PyArray1, PyArray2};
use pluecker::triangulation::point::{triangulate_point as core_triangulate_point, PointTriangulation};
use crate::convert::{Integer, Real};
use crate::convert::strict_json_dict;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use crate::pickle::{pack_struct, reduce, Pack, Reader};
use pyo3::types::PyTuple;


/// A triangulated point: the estimate `X` and the report fields of `TriangulationReport`.
#[pyclass(frozen, extends = PyTriangulationReport, name = "PointTriangulation", module = "pluecker")]
#[derive(Debug, Clone)]
pub struct PyPointTriangulation {
    point: Vector3<f64>,
    covariance: Option<Matrix3<f64>>,
}

impl PyPointTriangulation {
    /// The Python object of a core result.
    pub fn create(py: Python<'_>, result: PointTriangulation) -> PyResult<Py<PyPointTriangulation>> {
        let init = PyClassInitializer::from(PyTriangulationReport { inner: result.report })
            .add_subclass(PyPointTriangulation {
                point: result.point,
                covariance: result.covariance,
            });
        Py::new(py, init)
    }
}

#[pymethods]
impl PyPointTriangulation {
    #[getter(X)]
    fn x<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.point.as_slice())
    }

    #[getter]
    fn covariance<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray2<f64>>> {
        self.covariance.as_ref().map(|m| matrix_to_py::<3, 3>(py, m))
    }

    /// Plain-Python (JSON-serialisable) form: the report fields, `X` and `covariance`.
    fn to_dict<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyDict>> {
        let d = slf.as_super().get().report_dict(slf.py())?;
        d.set_item("X", slf.get().point.as_slice())?;
        d.set_item("covariance", slf.get().covariance.as_ref().map(rows::<3, 3>))?;
        strict_json_dict(d)
    }

    /// Pickle support (also `copy.deepcopy`): see `pickle.rs`.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        reduce(slf.py(), "PointTriangulation", &[slf.as_super().get(), slf.get()])
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
pub fn observations(name: &str, obj: &Bound<'_, PyAny>, views: usize) -> PyResult<Vec<Vector2<f64>>> {
    let (shape, values) = read(name, obj, &[Dim::Free("n"), Dim::Fixed(2)])?;
    same_count(name, shape[0], views)?;
    if let Some(row) = first_non_finite_row(&values, 2) {
        return Err(non_finite(name, row));
    }
    Ok(values.chunks_exact(2).map(|r| Vector2::new(r[0], r[1])).collect())
}

/// Triangulates one point from its pixels in two or more views (Josephson & Kahl 2008, eq. 19).
#[pyfunction]
#[pyo3(signature = (P, x, cov = None, method = "optimal", *, max_relative_gap = None, max_reprojection_error = None, max_nodes = None))]
#[allow(non_snake_case, clippy::too_many_arguments)]
pub fn triangulate_point(
    py: Python<'_>,
    P: &Bound<'_, PyAny>,
    x: &Bound<'_, PyAny>,
    cov: Option<&Bound<'_, PyAny>>,
    method: &str,
    max_relative_gap: Option<Real>,
    max_reprojection_error: Option<Real>,
    max_nodes: Option<Integer>,
) -> PyResult<Py<PyPointTriangulation>> {
    let opts = options(method, max_relative_gap, max_reprojection_error, max_nodes)?;
    let cams = cameras("P", P)?;
    let obs = observations("x", x, cams.len())?;
    let covs = covariances2("cov", cov, cams.len())?;
    let result = solve(py, move || {
        core_triangulate_point(&cams, &obs, covs.as_deref(), &opts).map_err(|e| renamed(e, POINT_NAMES))
    })?;
    PyPointTriangulation::create(py, result)
}

pack_struct!(PyPointTriangulation { point, covariance });
