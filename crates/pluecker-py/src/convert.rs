//! numpy ↔ nalgebra. Inputs: any real array-like, converted to float64, its shape checked against
//! the expected one and every row checked for NaN/inf, each failure naming the argument (and row).
//! Outputs: fresh row-major float64 arrays the caller owns.
//!
//! Every array argument of the module is read here, copied from a contiguous float64 buffer when the
//! caller hands one over (the batch functions must cost well under a microsecond per track),
//! otherwise converted by `numpy.asarray(rows, dtype=float64, order="C")` a block of rows at a
//! time; either way a chunk of [`crate::setup_poll::SETUP_CHUNK`] values at a time, Python's signal
//! handlers running between chunks, so that Ctrl-C is not held up by a large argument
//! ([`crate::setup_poll::setup_poll`]). Shapes are checked against the expected one and reported as
//! `"x: expected shape (n, 2), got (4, 3)"`.

use crate::errors::{invalid_argument, non_finite, shape_error};
use crate::setup_poll::{in_chunks, setup_poll, SETUP_CHUNK};
use nalgebra::{Matrix2, Matrix3, Matrix3x4, SMatrix, SVector};
use numpy::ndarray::{Array2, Array3};
use numpy::{
    Element, IntoPyArray, PyArray1, PyArray2, PyArray3, PyArrayDyn, PyArrayMethods, PyUntypedArray,
    PyUntypedArrayMethods,
};
use pluecker::Pose;
use pyo3::exceptions::{PyMemoryError, PyOverflowError, PyTypeError};
use pyo3::prelude::*;
use pyo3::types::{IntoPyDict, PyBool, PyDict, PyFloat, PyList, PySlice, PyTuple};
use std::time::Duration;

/// One axis of an expected shape: a named free length (`N` rows) or a fixed one.
#[derive(Clone, Copy, Debug)]
pub enum Dim {
    Free(&'static str),
    Fixed(usize),
}

/// An expected shape as the error messages print it: `shape (N, 2)`.
pub fn describe(spec: &[Dim]) -> String {
    let parts: Vec<String> = spec
        .iter()
        .map(|a| match a {
            Dim::Free(name) => (*name).to_string(),
            Dim::Fixed(n) => n.to_string(),
        })
        .collect();
    format!("shape {}", python_tuple(&parts))
}

fn python_tuple(parts: &[String]) -> String {
    match parts.len() {
        1 => format!("({},)", parts[0]),
        _ => format!("({})", parts.join(", ")),
    }
}

/// A shape as Python prints it.
pub fn shape_string(shape: &[usize]) -> String {
    python_tuple(&shape.iter().map(|n| n.to_string()).collect::<Vec<_>>())
}

/// `obj` as a numpy array of real numbers (the array itself when it is one); a `TypeError` naming
/// `name` if it is not one.
fn real_array<'py>(name: &str, obj: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyUntypedArray>> {
    let np = obj.py().import("numpy")?;
    let array = np.call_method1("asarray", (obj,)).map_err(|e| {
        PyTypeError::new_err(format!(
            "{name}: expected an array of real numbers; numpy could not convert the input: {e}"
        ))
    })?;
    let dtype = array.getattr("dtype")?;
    let kind: String = dtype.getattr("kind")?.extract()?;
    if !matches!(kind.as_str(), "i" | "u" | "f") {
        return Err(PyTypeError::new_err(format!(
            "{name}: expected an array of real numbers, got dtype {dtype}"
        )));
    }
    Ok(array.downcast_into::<PyUntypedArray>()?)
}

/// The entries of `array` in row-major order as `T` (numpy's `dtype`), copied a chunk of
/// [`SETUP_CHUNK`] values at a time with a [`setup_poll`] after each: straight from the buffer of a
/// C-contiguous array of `T`, otherwise through `numpy.asarray(array[a:b], dtype, order="C")` of
/// blocks of rows along the first axis. A `MemoryError` rather than an abort when the copy cannot
/// be allocated.
fn row_major<T: Element + Copy>(name: &str, array: &Bound<'_, PyUntypedArray>, dtype: &str) -> PyResult<Vec<T>> {
    let py = array.py();
    let len = array.len();
    let mut out = Vec::new();
    out.try_reserve_exact(len)
        .map_err(|_| PyMemoryError::new_err(format!("{name}: cannot allocate {len} values")))?;
    // The entries of a C-contiguous array of `T`, borrowed only while they are copied: the signal
    // handlers between chunks run Python code.
    let slice_of = |typed: &Bound<'_, PyArrayDyn<T>>, out: &mut Vec<T>, range: Option<std::ops::Range<usize>>| {
        let values = typed
            .try_readonly()
            .map_err(|e| PyTypeError::new_err(format!("{name}: {e}")))?;
        let all = values
            .as_slice()
            .map_err(|e| PyTypeError::new_err(format!("{name}: {e}")))?;
        out.extend_from_slice(range.map_or(all, |r| &all[r]));
        PyResult::Ok(())
    };
    if let Ok(typed) = array.downcast::<PyArrayDyn<T>>() {
        if typed.is_c_contiguous() {
            in_chunks(py, len, |range| slice_of(typed, &mut out, Some(range)))?;
            return Ok(out);
        }
    }
    let np = py.import("numpy")?;
    let kwargs = [("dtype", dtype), ("order", "C")].into_py_dict(py)?;
    let mut append = |block: &Bound<'_, PyAny>| {
        let converted = np.call_method("asarray", (block,), Some(&kwargs))?;
        slice_of(converted.downcast::<PyArrayDyn<T>>()?, &mut out, None)
    };
    let shape = array.shape().to_vec();
    let row = shape.iter().skip(1).product::<usize>();
    if shape.is_empty() || row == 0 {
        // A 0-d array (one value) or no values: one conversion (`asarray` keeps a 0-d shape).
        append(array.as_any())?;
        return Ok(out);
    }
    let rows_per_block = (SETUP_CHUNK / row).max(1);
    let mut first = 0;
    while first < shape[0] {
        let last = shape[0].min(first + rows_per_block);
        append(&array.get_item(PySlice::new(py, first as isize, last as isize, 1))?)?;
        setup_poll(py)?;
        first = last;
    }
    Ok(out)
}

/// The shape and the row-major values of `obj`, after checking the shape against `spec`. NaN and
/// inf are the caller's to check ([`check_finite`]): a batch accepts them where a view is not visible.
pub fn read(name: &str, obj: &Bound<'_, PyAny>, spec: &[Dim]) -> PyResult<(Vec<usize>, Vec<f64>)> {
    let (shape, values) = read_any(name, obj)?;
    check_shape(name, &shape, spec)?;
    Ok((shape, values))
}

/// `ShapeError` naming `name` unless `shape` is `spec`.
fn check_shape(name: &str, shape: &[usize], spec: &[Dim]) -> PyResult<()> {
    let fits = shape.len() == spec.len()
        && shape.iter().zip(spec).all(|(n, axis)| match axis {
            Dim::Free(_) => true,
            Dim::Fixed(m) => n == m,
        });
    if !fits {
        return Err(shape_error(name, &describe(spec), shape_string(shape)));
    }
    Ok(())
}

/// The shape and row-major values of `obj`, any shape (the caller dispatches on it).
pub fn read_any(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<(Vec<usize>, Vec<f64>)> {
    let array = real_array(name, obj)?;
    let shape = array.shape().to_vec();
    Ok((shape, row_major(name, &array, "float64")?))
}

/// `NonFiniteError` naming `name` and the first row (of `row_len` values) holding NaN or inf.
pub fn check_finite(name: &str, values: &[f64], row_len: usize) -> PyResult<()> {
    // One branch-free pass over all values (the common, finite case); the offending row only on failure.
    if values.iter().fold(true, |finite, v| finite & v.is_finite()) {
        return Ok(());
    }
    let row = values
        .chunks(row_len.max(1))
        .position(|r| r.iter().any(|v| !v.is_finite()))
        .unwrap_or(0);
    Err(non_finite(name, row))
}

/// The finite values of an array of shape `spec` whose leading axis is free; an empty 1-D array is
/// taken as zero rows.
fn read_rows(name: &str, obj: &Bound<'_, PyAny>, spec: &[Dim]) -> PyResult<Vec<f64>> {
    let (shape, values) = read_any(name, obj)?;
    if shape == [0] {
        return Ok(Vec::new());
    }
    check_shape(name, &shape, spec)?;
    check_finite(name, &values, shape[1..].iter().product())?;
    Ok(values)
}

/// The finite values of an array of the fixed shape `spec`.
fn read_fixed(name: &str, obj: &Bound<'_, PyAny>, spec: &[Dim]) -> PyResult<Vec<f64>> {
    let (shape, values) = read(name, obj, spec)?;
    check_finite(name, &values, shape[1..].iter().product())?;
    Ok(values)
}

/// An `(N, D)` array of points, `None` meaning zero rows.
pub fn points<const D: usize>(name: &str, obj: Option<&Bound<'_, PyAny>>) -> PyResult<Vec<SVector<f64, D>>> {
    let Some(obj) = obj else { return Ok(Vec::new()) };
    let values = read_rows(name, obj, &[Dim::Free("N"), Dim::Fixed(D)])?;
    Ok(values.chunks(D).map(SVector::<f64, D>::from_row_slice).collect())
}

/// An `(M, 2, D)` array of segments (two endpoints each), `None` meaning zero rows.
pub fn segments<const D: usize>(name: &str, obj: Option<&Bound<'_, PyAny>>) -> PyResult<Vec<[SVector<f64, D>; 2]>> {
    let Some(obj) = obj else { return Ok(Vec::new()) };
    let values = read_rows(name, obj, &[Dim::Free("M"), Dim::Fixed(2), Dim::Fixed(D)])?;
    Ok(values
        .chunks(2 * D)
        .map(|s| {
            [
                SVector::<f64, D>::from_row_slice(&s[..D]),
                SVector::<f64, D>::from_row_slice(&s[D..]),
            ]
        })
        .collect())
}

/// A `(3, 3)` matrix.
pub fn matrix3(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<Matrix3<f64>> {
    let values = read_fixed(name, obj, &[Dim::Fixed(3), Dim::Fixed(3)])?;
    Ok(Matrix3::from_row_slice(&values))
}

/// A `(3, 3)` matrix that may hold NaN or inf (for arguments whose validation reports them itself).
pub fn matrix3_allow_non_finite(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<Matrix3<f64>> {
    let (_, values) = read(name, obj, &[Dim::Fixed(3), Dim::Fixed(3)])?;
    Ok(Matrix3::from_row_slice(&values))
}

/// A `(3, 4)` matrix that may hold NaN or inf (for arguments whose validation reports them itself).
pub fn matrix3x4(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<nalgebra::Matrix3x4<f64>> {
    let (_, values) = read(name, obj, &[Dim::Fixed(3), Dim::Fixed(4)])?;
    Ok(nalgebra::Matrix3x4::from_row_slice(&values))
}

/// A `(D,)` vector.
pub fn vector<const D: usize>(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<SVector<f64, D>> {
    let values = read_fixed(name, obj, &[Dim::Fixed(D)])?;
    Ok(SVector::<f64, D>::from_row_slice(&values))
}

/// A matrix as an `(R, C)` array.
pub fn matrix_to_py<'py, const R: usize, const C: usize>(
    py: Python<'py>,
    m: &SMatrix<f64, R, C>,
) -> Bound<'py, PyArray2<f64>> {
    Array2::from_shape_fn((R, C), |(i, j)| m[(i, j)]).into_pyarray(py)
}

/// A vector as a `(D,)` array.
pub fn vector_to_py<'py, const D: usize>(py: Python<'py>, v: &SVector<f64, D>) -> Bound<'py, PyArray1<f64>> {
    PyArray1::from_slice(py, v.as_slice())
}

/// Points as an `(N, D)` array.
pub fn points_to_py<'py, const D: usize>(py: Python<'py>, rows: &[SVector<f64, D>]) -> Bound<'py, PyArray2<f64>> {
    Array2::from_shape_fn((rows.len(), D), |(i, j)| rows[i][j]).into_pyarray(py)
}

/// Segments as an `(M, 2, D)` array.
pub fn segments_to_py<'py, const D: usize>(
    py: Python<'py>,
    segs: &[[SVector<f64, D>; 2]],
) -> Bound<'py, PyArray3<f64>> {
    Array3::from_shape_fn((segs.len(), 2, D), |(i, k, j)| segs[i][k][j]).into_pyarray(py)
}

/// A `(3, 3)` rotation matrix: finite, `R Rᵀ = I` to 1e-6 and `det R = +1`, else `InvalidOptionError`.
pub fn rotation(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<Matrix3<f64>> {
    let r = matrix3(name, obj)?;
    match Pose::rotation_defect(&r) {
        Some(why) => Err(invalid_argument(name, why)),
        None => Ok(r),
    }
}

/// A duration argument in seconds: finite, `≥ 0` and representable as a [`Duration`] (below
/// `2⁶⁴` s, about 5.8e11 years), else `InvalidOptionError` naming `name`. `Duration::from_secs_f64`
/// panics beyond that range; this is the one conversion every seconds argument goes through.
pub fn seconds_arg(name: &str, seconds: f64) -> PyResult<Duration> {
    if !(seconds.is_finite() && seconds >= 0.0) {
        return Err(invalid_argument(
            name,
            format!(
                "must be None or a finite number of seconds ≥ 0, got {}",
                pluecker::testing::number(seconds)
            ),
        ));
    }
    Duration::try_from_secs_f64(seconds).map_err(|_| {
        invalid_argument(
            name,
            format!(
                "must be below 2**64 seconds (the longest duration the clock holds), got {}",
                pluecker::testing::number(seconds)
            ),
        )
    })
}

/// A real-number argument as Python gave it, checked (with its name) by [`Real::get`]: anything
/// `float()` accepts except a bool, which is remembered so that it can be rejected by name (a bool is
/// an `int` to Python, so `penalty=True` would otherwise run with λ = 1).
#[derive(Clone, Copy, Debug)]
pub struct Real {
    value: f64,
    from_bool: Option<bool>,
}

impl Real {
    /// A default value.
    pub const fn new(value: f64) -> Real {
        Real { value, from_bool: None }
    }

    /// The value, or `InvalidOptionError` naming `name` for a bool.
    pub fn get(self, name: &str) -> PyResult<f64> {
        match self.from_bool {
            Some(b) => Err(bool_given(name, b)),
            None => Ok(self.value),
        }
    }
}

/// `Some(real.get(name))` for an optional real argument.
pub fn optional_real(name: &str, real: Option<Real>) -> PyResult<Option<f64>> {
    real.map(|r| r.get(name)).transpose()
}

impl<'py> FromPyObject<'py> for Real {
    fn extract_bound(ob: &Bound<'py, PyAny>) -> PyResult<Self> {
        if let Some(b) = as_bool(ob)? {
            return Ok(Real {
                value: f64::NAN,
                from_bool: Some(b),
            });
        }
        Ok(Real::new(ob.extract()?))
    }
}

/// An integer argument as Python gave it (an `int`, a numpy integer, anything with `__index__`),
/// checked with its name by [`Integer::in_range`]. Values beyond the 128-bit range saturate there, so
/// the check reports them instead of a bare `OverflowError`; a bool is remembered and rejected.
#[derive(Clone, Copy, Debug)]
pub struct Integer {
    value: i128,
    beyond_i128: bool,
    from_bool: Option<bool>,
}

impl Integer {
    /// The value when `min ≤ value ≤ max`, else `InvalidOptionError` naming `name` and the range.
    pub fn in_range(self, name: &str, min: i128, max: i128) -> PyResult<i128> {
        if let Some(b) = self.from_bool {
            return Err(bool_given(name, b));
        }
        if self.beyond_i128 || self.value < min || self.value > max {
            let got = if self.beyond_i128 {
                format!("an integer beyond {}2**127", if self.value < 0 { "-" } else { "" })
            } else {
                self.value.to_string()
            };
            return Err(invalid_argument(
                name,
                format!("must be an integer from {min} to {max}, got {got}"),
            ));
        }
        Ok(self.value)
    }

    /// A count or cap: `min ≤ value < 2⁶⁴` (usize on the 64-bit targets the wheels are built for).
    pub fn count(self, name: &str, min: usize) -> PyResult<usize> {
        let max = usize::MAX as i128;
        Ok(self.in_range(name, min as i128, max)? as usize)
    }

    /// A seed: any unsigned 64-bit integer.
    pub fn seed(self, name: &str) -> PyResult<u64> {
        Ok(self.in_range(name, 0, u64::MAX as i128)? as u64)
    }
}

impl<'py> FromPyObject<'py> for Integer {
    fn extract_bound(ob: &Bound<'py, PyAny>) -> PyResult<Self> {
        if let Some(b) = as_bool(ob)? {
            return Ok(Integer {
                value: 0,
                beyond_i128: false,
                from_bool: Some(b),
            });
        }
        match ob.extract::<i128>() {
            Ok(value) => Ok(Integer {
                value,
                beyond_i128: false,
                from_bool: None,
            }),
            Err(e) if e.is_instance_of::<PyOverflowError>(ob.py()) => {
                let negative = ob.lt(0)?;
                let value = if negative { i128::MIN } else { i128::MAX };
                Ok(Integer {
                    value,
                    beyond_i128: true,
                    from_bool: None,
                })
            }
            Err(e) => Err(e),
        }
    }
}

/// `Some(b)` when `ob` is a Python or numpy bool.
fn as_bool(ob: &Bound<'_, PyAny>) -> PyResult<Option<bool>> {
    if let Ok(b) = ob.downcast::<PyBool>() {
        return Ok(Some(b.is_true()));
    }
    // numpy.bool_ (named `bool` since numpy 2) is not a Python bool but converts like one.
    let ty = ob.get_type();
    let module: String = ty.getattr("__module__")?.extract().unwrap_or_default();
    let name = ty.name()?.to_string();
    if module == "numpy" && (name == "bool" || name == "bool_") {
        return Ok(Some(ob.is_truthy()?));
    }
    Ok(None)
}

fn bool_given(name: &str, b: bool) -> PyErr {
    let b = if b { "True" } else { "False" };
    invalid_argument(name, format!("expected a number, got the bool {b}"))
}

/// `value` as strict JSON allows it: every NaN or infinite float, at any depth of dicts, lists and
/// tuples, replaced by `None` (the `to_dict()` of every result goes through here, so that
/// `json.dumps(result.to_dict(), allow_nan=False)` holds for failed results too). Dicts are changed
/// in place; lists and tuples are rebuilt as lists.
pub fn strict_json<'py>(value: Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
    let py = value.py();
    if let Ok(x) = value.downcast::<PyFloat>() {
        return Ok(if x.value().is_finite() {
            value
        } else {
            py.None().into_bound(py)
        });
    }
    if let Ok(d) = value.downcast::<PyDict>() {
        for (k, v) in d.clone().iter() {
            d.set_item(k, strict_json(v)?)?;
        }
        return Ok(value);
    }
    if value.is_instance_of::<PyList>() || value.is_instance_of::<PyTuple>() {
        let items = value
            .try_iter()?
            .map(|v| strict_json(v?))
            .collect::<PyResult<Vec<_>>>()?;
        return Ok(PyList::new(py, items)?.into_any());
    }
    Ok(value)
}

/// [`strict_json`] of a dict.
pub fn strict_json_dict<'py>(d: Bound<'py, PyDict>) -> PyResult<Bound<'py, PyDict>> {
    strict_json(d.clone().into_any())?;
    Ok(d)
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
    row_major(name, array.downcast::<PyUntypedArray>()?, "bool")
}

/// `InvalidOptionError` unless the integer array `array` holds only 0 and 1.
fn check_zero_one(name: &str, array: &Bound<'_, PyAny>) -> PyResult<()> {
    use pyo3::basic::CompareOp::Ne;
    let outside = array
        .rich_compare(0, Ne)?
        .call_method1("__and__", (array.rich_compare(1, Ne)?,))?;
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

/// `(n, R, C)` finite matrices, one per view (cameras, covariances, conics).
pub fn matrix_stack<const R: usize, const C: usize>(
    name: &str,
    obj: &Bound<'_, PyAny>,
) -> PyResult<Vec<SMatrix<f64, R, C>>> {
    let (_, values) = read(name, obj, &[Dim::Free("n"), Dim::Fixed(R), Dim::Fixed(C)])?;
    check_finite(name, &values, R * C)?;
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
            &format!("{views} rows (one per row of projections)"),
            rows.to_string(),
        ))
    }
}

/// The pose of separate arguments `R` (named `r_name`) and `t` (named `t_name`).
pub fn pose_from_parts(r_name: &str, r: &Bound<'_, PyAny>, t_name: &str, t: &Bound<'_, PyAny>) -> PyResult<Pose> {
    Ok(Pose::new(rotation(r_name, r)?, vector::<3>(t_name, t)?))
}

impl crate::properties::Field for Pose {
    /// `(R, t)` as numpy arrays.
    fn get(self, py: Python<'_>) -> PyResult<PyObject> {
        let parts = [self.rotation.get(py)?, self.translation.get(py)?];
        Ok(PyTuple::new(py, parts)?.into_any().unbind())
    }
    fn plain(self, py: Python<'_>) -> PyResult<PyObject> {
        let parts = [self.rotation.plain(py)?, self.translation.plain(py)?];
        Ok(PyTuple::new(py, parts)?.into_any().unbind())
    }
    fn stub() -> String {
        "Tuple[NDArray[np.float64], NDArray[np.float64]]".into()
    }
}

/// The `time_budget` argument of a batch (seconds, `None` for none), checked.
pub(crate) fn time_budget(arg: Option<Real>) -> PyResult<Option<Duration>> {
    optional_real("time_budget", arg)?
        .map(|s| seconds_arg("time_budget", s))
        .transpose()
}
