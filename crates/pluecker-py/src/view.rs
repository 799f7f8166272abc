//! `pluecker.View`: a known camera of a triangulation, a `Camera` at a pose (`pluecker::triangulation::View`),
//! and the one reader of the known cameras of the triangulation functions: 3x4 matrices `P` or views.

use crate::camera::PyCamera;
use crate::convert::{matrix3x4, pose_from_parts};
use crate::errors::{guarded, invalid_argument, to_py_err};
use crate::properties::{result_class, Field};
use nalgebra::Matrix3x4;
use pluecker::triangulation::View;
use pyo3::prelude::*;
use pyo3::types::PyTuple;

/// A known camera: a `Camera` (any model) at the pose `x_cam = R X_world + t`. Its pixels are the
/// camera's observed ones (through its lens). Immutable, `==`, picklable.
#[pyclass(frozen, eq, name = "View", module = "pluecker")]
#[derive(Debug, Clone, PartialEq)]
pub struct PyView {
    pub inner: View,
}

result_class! {
    PyView {
        /// The camera.
        camera = |v| CameraField(v.inner.camera.clone());
        /// The pose `x_cam = R X_world + t`; `R, t = view.pose`.
        pose = |v| v.inner.pose;
        /// `P = K [R | t]` (3, 4) of the camera's pinhole part at the pose.
        P = |v| v.inner.projection();
    }

    #[new]
    #[pyo3(signature = (camera, R, t))]
    #[allow(non_snake_case)]
    fn new(camera: &Bound<'_, PyAny>, R: &Bound<'_, PyAny>, t: &Bound<'_, PyAny>) -> PyResult<Self> {
        let camera = crate::camera::coerce("camera", camera)?;
        Ok(PyView { inner: View::new(camera, pose_from_parts("R", R, "t", t)?) })
    }

    /// The pinhole view of a finite 3x4 matrix `P = s K [R | t]` (any positive scale `s`): `K` with
    /// `K₃₃ = 1` and `fy > 0` (a left-handed `P`, `det M < 0`, gives `fx < 0`), `R` a rotation; a point
    /// is in front of the view exactly when it is in front of `P`.
    #[staticmethod]
    #[pyo3(signature = (P))]
    #[allow(non_snake_case)]
    fn from_projection(P: &Bound<'_, PyAny>) -> PyResult<Self> {
        let p = matrix3x4("P", P)?;
        guarded(|| View::from_projection(&p, "P")).map(|inner| PyView { inner })
    }

    fn __repr__(&self) -> String {
        let c = &self.inner.camera;
        format!("View(Camera('{}', {:?}), R, t={:?})", c.model().as_str(), c.params(), self.inner.pose.translation.as_slice())
    }

    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        let py = slf.py();
        let v = &slf.get().inner;
        let camera = Py::new(py, PyCamera::wrap(v.camera.clone()))?.into_any();
        let args = PyTuple::new(py, [camera, v.pose.rotation.get(py)?, v.pose.translation.get(py)?])?;
        Ok((slf.get_type().into_any(), args))
    }
}

/// A camera as a property's value: the `Camera` object, `{model, params, …}` in `to_dict`.
struct CameraField(pluecker::Camera);

impl Field for CameraField {
    fn get(self, py: Python<'_>) -> PyResult<PyObject> {
        Ok(Py::new(py, PyCamera::wrap(self.0))?.into_any())
    }
    fn plain(self, py: Python<'_>) -> PyResult<PyObject> {
        let d = pyo3::types::PyDict::new(py);
        PyCamera::wrap(self.0).fill_dict(py, &d)?;
        Ok(d.into_any().unbind())
    }
    fn stub() -> String {
        "Camera".into()
    }
}

/// Whether `cameras` is a sequence of `View`s (the other form is an array of 3x4 matrices).
pub(crate) fn is_views(cameras: &Bound<'_, PyAny>) -> bool {
    let first = cameras.get_item(0);
    !cameras.hasattr("shape").unwrap_or(false) && first.is_ok_and(|f| f.downcast::<PyView>().is_ok())
}

/// The known cameras of a triangulation as read: their 3x4 matrices (the views' `K [R | t]`), and the
/// views when they were given.
pub(crate) type KnownCameras = (Vec<Matrix3x4<f64>>, Option<Vec<View>>);

/// The known cameras of a triangulation: `(v, 3, 4)` matrices `P` (named `cameras` in errors), or a
/// sequence of `View`s; with the views, their pinhole projections `K [R | t]` too.
pub(crate) fn known_cameras(cameras: &Bound<'_, PyAny>) -> PyResult<KnownCameras> {
    if !is_views(cameras) {
        return Ok((crate::convert::cameras("cameras", cameras)?, None));
    }
    let views = cameras
        .try_iter()?
        .enumerate()
        .map(|(j, item)| {
            let item = item?;
            let view = item.downcast::<PyView>().map_err(|_| {
                pyo3::exceptions::PyTypeError::new_err(format!(
                    "cameras[{j}]: expected a pluecker.View (as cameras[0] is), got {}",
                    item.get_type().name().map(|n| n.to_string()).unwrap_or_default()
                ))
            })?;
            Ok(view.get().inner.clone())
        })
        .collect::<PyResult<Vec<View>>>()?;
    let projections = views.iter().map(View::projection).collect();
    Ok((projections, Some(views)))
}

/// The 3x4 matrices of `cameras` for a problem solved in pinhole pixels: the matrices as given, or
/// the views' `K [R | t]` when no view distorts (`InvalidOptionError` naming `cameras` and the view that
/// does).
pub(crate) fn pinhole_projections(cameras: &Bound<'_, PyAny>) -> PyResult<Vec<Matrix3x4<f64>>> {
    let (projections, views) = known_cameras(cameras)?;
    if let Some(views) = views {
        pluecker::triangulation::quadric::refuse_distortion(&views).map_err(|e| match e {
            pluecker::Error::InvalidOption { name, reason } => invalid_argument(&name, reason),
            other => to_py_err(other),
        })?;
    }
    Ok(projections)
}
