//! Dual-quaternion and screw forms of a pose (Phong & Horaud 1995, section 2.1).

use crate::convert::pose_from_parts;
use crate::convert::{matrix_to_py, vector, vector_to_py};
use crate::errors::{degenerate, guarded};
use nalgebra::SVector;
use numpy::{PyArray1, PyArray2};
use pluecker::geometry::dual_quaternion::DualQuaternion;
use pluecker::Pose;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// `(R (3, 3), t (3,))` as numpy arrays.
type PoseArrays<'py> = (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray1<f64>>);

/// `(R, t)` → the unit dual quaternion `(r0, rx, ry, rz, s0, sx, sy, sz)`.
#[pyfunction]
#[pyo3(signature = (R, t))]
#[allow(non_snake_case)]
pub fn pose_to_dual_quaternion<'py>(
    py: Python<'py>,
    R: &Bound<'py, PyAny>,
    t: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let Pose {
        rotation: rot,
        translation: t,
    } = pose_from_parts("R", R, "t", t)?;
    let q = guarded(|| Ok(DualQuaternion::from_rotation_translation(&rot, &t)))?;
    Ok(vector_to_py::<8>(py, &q.to_vector()))
}

/// The dual quaternion `(r, s)` (8,) → `(R, t)`; `r` is normalised first.
#[pyfunction]
pub fn dual_quaternion_to_pose<'py>(py: Python<'py>, q: &Bound<'py, PyAny>) -> PyResult<PoseArrays<'py>> {
    let x: SVector<f64, 8> = vector::<8>("q", q)?;
    let q = DualQuaternion::from_vector(&x);
    let n = q.r.norm();
    if !(n > 1e-12 * q.s.norm().max(1.0) && n.is_finite()) {
        return Err(degenerate(format!(
            "q: the real part (r0, rx, ry, rz) has norm {n:e}; it must be non-zero"
        )));
    }
    let (rot, t) = guarded(|| Ok(q.to_rotation_translation()))?;
    Ok((matrix_to_py(py, &rot), vector_to_py(py, &t)))
}

/// Chasles' screw of `(R, t)`: `dict(d, angle, direction, point)`.
#[pyfunction]
#[pyo3(signature = (R, t))]
#[allow(non_snake_case)]
pub fn pose_to_screw<'py>(
    py: Python<'py>,
    R: &Bound<'py, PyAny>,
    t: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyDict>> {
    let Pose {
        rotation: rot,
        translation: t,
    } = pose_from_parts("R", R, "t", t)?;
    let screw = guarded(|| Ok(DualQuaternion::from_rotation_translation(&rot, &t).to_screw()))?;
    let d = PyDict::new(py);
    d.set_item("d", screw.d)?;
    d.set_item("angle", screw.angle)?;
    d.set_item("direction", vector_to_py(py, &screw.direction))?;
    d.set_item("point", vector_to_py(py, &screw.point))?;
    Ok(d)
}
