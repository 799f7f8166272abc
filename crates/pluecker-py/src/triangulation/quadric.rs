//! `triangulate_quadric` (an ellipsoid from its outline conics) and `pluecker.QuadricTriangulation`.

use crate::errors::solve;
use crate::triangulation::{options, renamed, PyTriangulationReport};
use crate::triangulation_arrays::{cameras, matrix_stack, same_count};
use nalgebra::{Matrix3, Matrix4, SMatrix, Vector3};
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2};
use pluecker::triangulation::quadric::{triangulate_quadric as core_triangulate_quadric, QuadricTriangulation};
use pluecker::triangulation::uncertainty::QuadricCovariance;
use crate::convert::{Integer, Real};
use crate::convert::strict_json_dict;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use crate::pickle::{pack_struct, reduce, Pack, Reader};
use pyo3::types::PyTuple;


/// Core argument names → Python argument names of `triangulate_quadric`.
pub(crate) const QUADRIC_NAMES: &[(&str, &str)] = &[("cameras", "P"), ("conics", "conics"), ("covariances", "cov")];

/// A fresh `(R, C)` float64 array of a matrix.
pub(crate) fn matrix_to_py<'py, const R: usize, const C: usize>(
    py: Python<'py>,
    m: &SMatrix<f64, R, C>,
) -> Bound<'py, PyArray2<f64>> {
    Array2::from_shape_fn((R, C), |(i, j)| m[(i, j)]).into_pyarray(py)
}

/// The rows of a matrix as nested lists (for `to_dict`).
pub(crate) fn rows<const R: usize, const C: usize>(m: &SMatrix<f64, R, C>) -> Vec<Vec<f64>> {
    (0..R).map(|i| (0..C).map(|j| m[(i, j)]).collect()).collect()
}

/// A triangulated ellipsoid: dual and primal quadric, centre, axes, semi-axes, and the report fields.
#[pyclass(frozen, extends = PyTriangulationReport, name = "QuadricTriangulation", module = "pluecker")]
#[derive(Debug, Clone)]
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

#[pymethods]
impl PyQuadricTriangulation {
    #[getter(Q)]
    fn dual<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        matrix_to_py::<4, 4>(py, &self.dual)
    }

    #[getter]
    fn primal<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray2<f64>>> {
        self.primal.as_ref().map(|m| matrix_to_py::<4, 4>(py, m))
    }

    #[getter]
    fn centre<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.centre.as_slice())
    }

    #[getter]
    fn axes<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        matrix_to_py::<3, 3>(py, &self.axes)
    }

    #[getter]
    fn semi_axes<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.semi_axes.as_slice())
    }

    #[getter]
    fn covariance<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray2<f64>>> {
        self.covariance.as_ref().map(|m| matrix_to_py::<9, 9>(py, m))
    }

    /// Plain-Python (JSON-serialisable) form: the report fields, `Q`, `primal`, `centre`, `axes`,
    /// `semi_axes`, `covariance`.
    fn to_dict<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyDict>> {
        let d = slf.as_super().get().report_dict(slf.py())?;
        let me = slf.get();
        d.set_item("Q", rows::<4, 4>(&me.dual))?;
        d.set_item("primal", me.primal.as_ref().map(rows::<4, 4>))?;
        d.set_item("centre", me.centre.as_slice())?;
        d.set_item("axes", rows::<3, 3>(&me.axes))?;
        d.set_item("semi_axes", me.semi_axes.as_slice())?;
        d.set_item("covariance", me.covariance.as_ref().map(rows::<9, 9>))?;
        strict_json_dict(d)
    }

    /// Pickle support (also `copy.deepcopy`): see `pickle.rs`.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        reduce(slf.py(), "QuadricTriangulation", &[slf.as_super().get(), slf.get()])
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
#[pyfunction]
#[pyo3(signature = (P, conics, cov = None, method = "optimal", *, max_relative_gap = None, max_reprojection_error = None, max_nodes = None))]
#[allow(non_snake_case, clippy::too_many_arguments)]
pub fn triangulate_quadric(
    py: Python<'_>,
    P: &Bound<'_, PyAny>,
    conics: &Bound<'_, PyAny>,
    cov: Option<&Bound<'_, PyAny>>,
    method: &str,
    max_relative_gap: Option<Real>,
    max_reprojection_error: Option<Real>,
    max_nodes: Option<Integer>,
) -> PyResult<Py<PyQuadricTriangulation>> {
    let opts = options(method, max_relative_gap, max_reprojection_error, max_nodes)?;
    let cams = cameras("P", P)?;
    let observed = crate::triangulation_arrays::conics("conics", conics)?;
    same_count("conics", observed.len(), cams.len())?;
    let covs = match cov {
        Some(c) => {
            let covs = matrix_stack::<5, 5>("cov", c)?;
            same_count("cov", covs.len(), cams.len())?;
            Some(covs)
        }
        None => None,
    };
    let result = solve(py, move || {
        core_triangulate_quadric(&cams, &observed, covs.as_deref(), &opts).map_err(|e| renamed(e, QUADRIC_NAMES))
    })?;
    PyQuadricTriangulation::create(py, result)
}

pack_struct!(PyQuadricTriangulation { dual, primal, centre, axes, semi_axes, covariance });
