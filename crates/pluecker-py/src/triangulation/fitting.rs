//! `fit_line`, `fit_conic` and `fitting_residual_samples`: image primitives fitted to edge points with
//! the covariance of their residual (Josephson & Kahl 2008, section 3.1), the weights `triangulate_line`
//! and `triangulate_quadric` take.

use crate::convert::{matrix3_rows, matrix3_to_py, points as read_points, Integer, Real};
use crate::errors::{guarded, invalid_argument, solve};
use nalgebra::{SMatrix, SVector};
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2};
use pluecker::triangulation::fitting::{self, FittedConic, FittedLine};
use crate::convert::strict_json_dict;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use crate::pickle::{pack_struct, reduce, Pack, Reader};
use pyo3::types::PyTuple;


fn matrix_to_py<'py, const R: usize, const C: usize>(
    py: Python<'py>,
    m: &SMatrix<f64, R, C>,
) -> Bound<'py, PyArray2<f64>> {
    Array2::from_shape_fn((R, C), |(i, j)| m[(i, j)]).into_pyarray(py)
}

fn matrix_rows<const R: usize, const C: usize>(m: &SMatrix<f64, R, C>) -> Vec<Vec<f64>> {
    (0..R).map(|i| (0..C).map(|j| m[(i, j)]).collect()).collect()
}

fn sigma_arg(sigma: Real) -> PyResult<f64> {
    let sigma = sigma.get("sigma")?;
    if sigma.is_finite() && sigma > 0.0 {
        Ok(sigma)
    } else {
        Err(invalid_argument(
            "sigma",
            format!("must be a positive finite number of pixels, got {sigma}"),
        ))
    }
}

/// An image line fitted to points, with the covariance of its 2-entry residual.
#[pyclass(frozen, name = "FittedLine", module = "pluecker")]
#[derive(Debug, Clone)]
pub struct PyFittedLine {
    inner: FittedLine,
}

#[pymethods]
impl PyFittedLine {
    #[getter]
    fn line<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.inner.line.as_slice())
    }

    #[getter]
    fn covariance<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        matrix_to_py::<2, 2>(py, &self.inner.covariance)
    }

    #[getter]
    fn rms_distance(&self) -> f64 {
        self.inner.rms_distance
    }

    /// Plain-Python (JSON-serialisable) form.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        d.set_item("line", self.inner.line.as_slice())?;
        d.set_item("covariance", matrix_rows::<2, 2>(&self.inner.covariance))?;
        d.set_item("rms_distance", self.inner.rms_distance)?;
        strict_json_dict(d)
    }


    /// Pickle support (also `copy.deepcopy`): see `pickle.rs`.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        reduce(py, "FittedLine", &[self])
    }

    fn __repr__(&self) -> String {
        let l = self.inner.line;
        format!(
            "FittedLine(line=[{:.6}, {:.6}, {:.6}], rms_distance={:.3e})",
            l.x, l.y, l.z, self.inner.rms_distance
        )
    }
}

/// An ellipse fitted to points, with the covariance of its 5-entry residual.
#[pyclass(frozen, name = "FittedConic", module = "pluecker")]
#[derive(Debug, Clone)]
pub struct PyFittedConic {
    inner: FittedConic,
}

#[pymethods]
impl PyFittedConic {
    #[getter]
    fn conic<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        matrix3_to_py(py, &self.inner.conic)
    }

    #[getter]
    fn centre<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.inner.ellipse.centre.as_slice())
    }

    #[getter]
    fn axes<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        matrix_to_py::<2, 2>(py, &self.inner.ellipse.axes)
    }

    #[getter]
    fn semi_axes<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.inner.ellipse.semi_axes.as_slice())
    }

    #[getter]
    fn covariance<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        matrix_to_py::<5, 5>(py, &self.inner.covariance)
    }

    #[getter]
    fn iterations(&self) -> usize {
        self.inner.iterations
    }

    /// Plain-Python (JSON-serialisable) form.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let e = &self.inner.ellipse;
        let d = PyDict::new(py);
        d.set_item("conic", matrix3_rows(&self.inner.conic))?;
        d.set_item("centre", e.centre.as_slice())?;
        d.set_item("axes", matrix_rows::<2, 2>(&e.axes))?;
        d.set_item("semi_axes", e.semi_axes.as_slice())?;
        d.set_item("covariance", matrix_rows::<5, 5>(&self.inner.covariance))?;
        d.set_item("iterations", self.inner.iterations)?;
        strict_json_dict(d)
    }


    /// Pickle support (also `copy.deepcopy`): see `pickle.rs`.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        reduce(py, "FittedConic", &[self])
    }

    fn __repr__(&self) -> String {
        let e = &self.inner.ellipse;
        format!(
            "FittedConic(centre=[{:.3}, {:.3}], semi_axes=[{:.3}, {:.3}], iterations={})",
            e.centre.x, e.centre.y, e.semi_axes.x, e.semi_axes.y, self.inner.iterations
        )
    }
}

/// Fits an image line to points (total least squares) and returns it with its residual covariance.
#[pyfunction]
#[pyo3(signature = (points, sigma = Real::new(1.0)), text_signature = "(points, sigma=1.0)")]
pub fn fit_line(points: &Bound<'_, PyAny>, sigma: Real) -> PyResult<PyFittedLine> {
    let pts = read_points::<2>("points", Some(points))?;
    let sigma = sigma_arg(sigma)?;
    guarded(|| fitting::fit_line(&pts, sigma)).map(|inner| PyFittedLine { inner })
}

/// Fits an ellipse to points and returns it with its residual covariance.
#[pyfunction]
#[pyo3(signature = (points, sigma = Real::new(1.0)), text_signature = "(points, sigma=1.0)")]
pub fn fit_conic(py: Python<'_>, points: &Bound<'_, PyAny>, sigma: Real) -> PyResult<PyFittedConic> {
    let pts = read_points::<2>("points", Some(points))?;
    let sigma = sigma_arg(sigma)?;
    solve(py, move || fitting::fit_conic(&pts, sigma)).map(|inner| PyFittedConic { inner })
}

fn rows_to_py<'py, const D: usize>(py: Python<'py>, rows: &[SVector<f64, D>]) -> Bound<'py, PyArray2<f64>> {
    Array2::from_shape_fn((rows.len(), D), |(i, j)| rows[i][j]).into_pyarray(py)
}

/// The residual samples of the paper's Figures 1-2 (section 3.1).
#[pyfunction]
#[pyo3(signature = (draws, size = Real::new(1000.0), sigma = Real::new(1.0), seed = Integer::new(0)), text_signature = "(draws, size=1000.0, sigma=1.0, seed=0)")]
pub fn fitting_residual_samples<'py>(
    py: Python<'py>,
    draws: Integer,
    size: Real,
    sigma: Real,
    seed: Integer,
) -> PyResult<Bound<'py, PyDict>> {
    let draws = draws.count("draws", 1)?;
    let seed = seed.seed("seed")?;
    let size = size.get("size")?;
    if !(size.is_finite() && size > 0.0) {
        return Err(invalid_argument(
            "size",
            format!("must be a positive number of pixels, got {size}"),
        ));
    }
    let sigma = sigma_arg(sigma)?;
    let samples = solve(py, move || fitting::residual_samples(draws, size, sigma, seed))?;
    let d = PyDict::new(py);
    d.set_item("line", rows_to_py(py, &samples.line))?;
    d.set_item("line_whitened", rows_to_py(py, &samples.line_whitened))?;
    d.set_item("conic", rows_to_py(py, &samples.conic))?;
    d.set_item("conic_whitened", rows_to_py(py, &samples.conic_whitened))?;
    Ok(d)
}

pack_struct!(PyFittedLine { inner });
pack_struct!(PyFittedConic { inner });
