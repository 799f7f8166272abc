//! numpy → nalgebra for the triangulation functions: stacks of cameras `(n, 3, 4)`, observations
//! `(n, 2)` / `(n, v, 2)`, covariances `(n, 2, 2)`, conics `(n, 3, 3)`, visibility masks `(n, v)`.
//!
//! Arrays are read in one pass from a contiguous float64 buffer when the caller hands one over (the
//! batch functions must cost well under a microsecond per track), otherwise after one
//! `numpy.ascontiguousarray(obj, dtype=float64)`. Shapes are checked against the expected one and
//! reported as `"x: expected shape (n, 2), got (4, 3)"`; NaN/inf checks are left to the callers,
//! because a batch accepts NaN where a track is not visible.

use crate::convert::{describe, float_array, row_major_values};
pub use crate::convert::{shape_string, Dim};
use crate::errors::{invalid_argument, non_finite, shape_error};
use nalgebra::{Matrix2, Matrix3, Matrix3x4, SMatrix};
use numpy::{PyArrayDyn, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;

fn check_shape(name: &str, shape: &[usize], spec: &[Dim]) -> PyResult<()> {
    let fits = shape.len() == spec.len()
        && shape.iter().zip(spec).all(|(n, d)| match d {
            Dim::Free(_) => true,
            Dim::Fixed(m) => n == m,
        });
    if fits {
        Ok(())
    } else {
        Err(shape_error(name, &describe(spec), shape_string(shape)))
    }
}

/// The shape and the row-major values of `obj`, after checking the shape against `spec`.
pub fn read(name: &str, obj: &Bound<'_, PyAny>, spec: &[Dim]) -> PyResult<(Vec<usize>, Vec<f64>)> {
    let array = float_array(name, obj)?;
    let shape = array.shape().to_vec();
    check_shape(name, &shape, spec)?;
    Ok((shape, row_major_values(name, &array)?))
}

/// The shape and row-major values of `obj`, any shape (the caller dispatches on it).
pub fn read_any(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<(Vec<usize>, Vec<f64>)> {
    let array = float_array(name, obj)?;
    let shape = array.shape().to_vec();
    Ok((shape, row_major_values(name, &array)?))
}

/// A boolean mask of `shape`: a bool array, or an integer array holding only 0 and 1 (any other
/// integer is an `InvalidOptionError` naming its index: `-1` must not count as visible).
pub fn read_mask(name: &str, obj: &Bound<'_, PyAny>, shape: &[usize]) -> PyResult<Vec<bool>> {
    let np = obj.py().import("numpy")?;
    let array = np.call_method1("asarray", (obj,)).map_err(|e| {
        PyTypeError::new_err(format!(
            "{name}: expected a boolean array; numpy could not convert the input: {e}"
        ))
    })?;
    let kind: String = array.getattr("dtype")?.getattr("kind")?.extract()?;
    if !matches!(kind.as_str(), "b" | "i" | "u") {
        let dtype = array.getattr("dtype")?;
        return Err(PyTypeError::new_err(format!(
            "{name}: expected a boolean array, got dtype {dtype}"
        )));
    }
    let actual: Vec<usize> = array.getattr("shape")?.extract()?;
    if actual != shape {
        return Err(shape_error(
            name,
            &format!("shape {}", shape_string(shape)),
            shape_string(&actual),
        ));
    }
    if kind != "b" {
        check_zero_one(name, &array)?;
    }
    let array = np.call_method1("ascontiguousarray", (array, "bool"))?;
    let array = array.downcast_into::<PyArrayDyn<bool>>()?;
    let readonly = array
        .try_readonly()
        .map_err(|e| PyTypeError::new_err(format!("{name}: {e}")))?;
    Ok(match readonly.as_slice() {
        Ok(slice) => slice.to_vec(),
        Err(_) => readonly.as_array().iter().copied().collect(),
    })
}

/// `InvalidOptionError` unless the integer array `array` holds only 0 and 1.
fn check_zero_one(name: &str, array: &Bound<'_, PyAny>) -> PyResult<()> {
    use pyo3::basic::CompareOp::Ne;
    let outside = array.rich_compare(0, Ne)?.call_method1("__and__", (array.rich_compare(1, Ne)?,))?;
    let np = array.py().import("numpy")?;
    let bad = np.call_method1("argwhere", (outside,))?;
    if bad.len()? == 0 {
        return Ok(());
    }
    let index: Vec<usize> = bad.get_item(0)?.call_method0("tolist")?.extract()?;
    let value = array.get_item(pyo3::types::PyTuple::new(array.py(), &index)?)?;
    let at: Vec<String> = index.iter().map(|i| i.to_string()).collect();
    Err(invalid_argument(
        name,
        format!("expected True/False or 0/1, got {value} at [{}]", at.join(", ")),
    ))
}

/// Row-major chunks of `R x C` as nalgebra matrices.
pub fn matrices<const R: usize, const C: usize>(values: &[f64]) -> Vec<SMatrix<f64, R, C>> {
    values
        .chunks_exact(R * C)
        .map(SMatrix::<f64, R, C>::from_row_slice)
        .collect()
}

/// The first row of `values` (rows of `row_len` numbers) that holds a NaN or inf.
pub fn first_non_finite_row(values: &[f64], row_len: usize) -> Option<usize> {
    values
        .chunks(row_len.max(1))
        .position(|r| r.iter().any(|v| !v.is_finite()))
}

/// `(n, R, C)` finite matrices, one per view (cameras, covariances, conics).
pub fn matrix_stack<const R: usize, const C: usize>(
    name: &str,
    obj: &Bound<'_, PyAny>,
) -> PyResult<Vec<SMatrix<f64, R, C>>> {
    let (_, values) = read(name, obj, &[Dim::Free("n"), Dim::Fixed(R), Dim::Fixed(C)])?;
    if let Some(row) = first_non_finite_row(&values, R * C) {
        return Err(non_finite(name, row));
    }
    Ok(matrices::<R, C>(&values))
}

/// `(n, 3, 4)` cameras.
pub fn cameras(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<Vec<Matrix3x4<f64>>> {
    matrix_stack::<3, 4>(name, obj)
}

/// `(n, 2, 2)` covariances, one per view, or none.
pub fn covariances2(name: &str, obj: Option<&Bound<'_, PyAny>>, views: usize) -> PyResult<Option<Vec<Matrix2<f64>>>> {
    let Some(obj) = obj else { return Ok(None) };
    let covs = matrix_stack::<2, 2>(name, obj)?;
    same_count(name, covs.len(), views)?;
    Ok(Some(covs))
}

/// `(n, 3, 3)` conics.
pub fn conics(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<Vec<Matrix3<f64>>> {
    matrix_stack::<3, 3>(name, obj)
}

/// A `ShapeError` unless an argument has one row per camera.
pub fn same_count(name: &str, rows: usize, views: usize) -> PyResult<()> {
    if rows == views {
        Ok(())
    } else {
        Err(shape_error(
            name,
            &format!("{views} rows (one per camera in P)"),
            rows.to_string(),
        ))
    }
}
