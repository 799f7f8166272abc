//! `pluecker.Rig`: cameras fixed to one body, each at its pose in the body's frame (the core's
//! `Rig`). Built from `Camera`s (or pycolmap cameras) and `(R, t)` pairs; `pluecker.colmap.rig` builds
//! one from a pycolmap reconstruction's rig.

use crate::camera::{coerce, PyCamera};
use crate::convert::{points_to_py, pose_from_parts};
use crate::errors::guarded;
use crate::pickle::reduce;
use crate::pose::result::{extract_pose, PyPose};
use crate::view::PyView;
use pluecker::triangulation::View;
use pluecker::Rig;
use pyo3::prelude::*;
use pyo3::types::PyTuple;

/// Cameras fixed to one body: camera `k` at `sensor_from_rig[k]`, `x_sensor = R x_rig + t`. The pose
/// of the body, `rig_from_world` (`x_rig = R X_world + t`), places every camera:
/// `sensor_from_world[k] = sensor_from_rig[k] ∘ rig_from_world`. Immutable, `==`, picklable.
#[pyclass(frozen, eq, name = "Rig", module = "pluecker")]
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(transparent)]
pub struct PyRig {
    pub inner: Rig,
}

#[pymethods]
impl PyRig {
    /// `Rig(cameras, sensor_from_rig)`: `cameras` a sequence of `Camera`s (or pycolmap cameras),
    /// `sensor_from_rig` one pose per camera, each a `Pose` or a pair `(R, t)`. `ShapeError` without a
    /// camera or with another number of poses; `InvalidOptionError` naming `sensor_from_rig[k]` for a
    /// rotation that is not one or a translation that is not finite.
    #[new]
    #[pyo3(signature = (cameras, sensor_from_rig))]
    fn new(cameras: &Bound<'_, PyAny>, sensor_from_rig: &Bound<'_, PyAny>) -> PyResult<Self> {
        let cameras = cameras
            .try_iter()?
            .enumerate()
            .map(|(k, c)| coerce(&format!("cameras[{k}]"), &c?))
            .collect::<PyResult<Vec<_>>>()?;
        let poses = sensor_from_rig
            .try_iter()?
            .enumerate()
            .map(|(k, p)| extract_pose(&format!("sensor_from_rig[{k}]"), &p?))
            .collect::<PyResult<Vec<_>>>()?;
        guarded(|| Rig::new(cameras, poses)).map(|inner| PyRig { inner })
    }

    /// The cameras, in order.
    #[getter]
    fn cameras(&self) -> Vec<PyCamera> {
        self.inner.cameras().iter().cloned().map(PyCamera::wrap).collect()
    }

    /// Each camera's pose in the body's frame, `x_sensor = R x_rig + t`.
    #[getter]
    fn sensor_from_rig(&self) -> Vec<PyPose> {
        self.inner
            .sensor_from_rig()
            .iter()
            .map(|&inner| PyPose { inner })
            .collect()
    }

    /// (n, 3) the cameras' optical centres in the body's frame.
    #[getter]
    fn centres(&self, py: Python<'_>) -> PyObject {
        points_to_py(py, &self.inner.centres()).into_any().unbind()
    }

    /// Whether every camera has its optical centre at one point (a central camera).
    #[getter]
    fn is_central(&self) -> bool {
        self.inner.is_central()
    }

    fn __len__(&self) -> usize {
        self.inner.len()
    }

    /// Every camera's `View` when the body is at `rig_from_world = (R, t)`: the known cameras of a
    /// triangulation from the images of one frame.
    #[pyo3(signature = (R, t))]
    #[allow(non_snake_case)]
    fn views(&self, R: &Bound<'_, PyAny>, t: &Bound<'_, PyAny>) -> PyResult<Vec<PyView>> {
        let rig_from_world = pose_from_parts("R", R, "t", t)?;
        Ok((0..self.inner.len())
            .map(|k| PyView {
                inner: View::new(
                    self.inner.cameras()[k].clone(),
                    self.inner.sensor_from_world(k, &rig_from_world),
                ),
            })
            .collect())
    }

    /// Plain-Python form, as the core writes it: `{"cameras": [{"model", "params"}, ...],
    /// "sensor_from_rig": [{"rotation": rows, "translation"}, ...]}`.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let json =
            serde_json::to_string(&self.inner).map_err(|e| pyo3::exceptions::PyValueError::new_err(e.to_string()))?;
        py.import("json")?.call_method1("loads", (json,))
    }

    /// Pickle support (also `copy.deepcopy`): see `pickle.rs`.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        reduce(py, "Rig", self)
    }

    fn __repr__(&self) -> String {
        let models: Vec<&str> = self.inner.cameras().iter().map(|c| c.model().as_str()).collect();
        format!("Rig({} cameras: {})", self.inner.len(), models.join(", "))
    }
}
