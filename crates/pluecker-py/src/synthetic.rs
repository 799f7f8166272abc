//! Seeded synthetic scenes (the paper's calibration object, random scenes) as dicts of arrays.

use crate::camera::PyCamera;
use crate::convert::{matrix_to_py, points_to_py, segments_to_py, vector_to_py, Integer};
use crate::errors::{guarded, invalid_argument};
use pluecker::synthetic::{
    check_scene_size, paper_calibration_object, random_scene as core_random_scene, Scene, SceneKind,
};
use pyo3::prelude::*;
use pyo3::types::PyDict;

const KINDS: [SceneKind; 3] = [SceneKind::General, SceneKind::Planar, SceneKind::Far];

fn scene_dict<'py>(py: Python<'py>, scene: &Scene, with_lines: bool) -> PyResult<Bound<'py, PyDict>> {
    let c = &scene.correspondences;
    let d = PyDict::new(py);
    d.set_item("camera", PyCamera::wrap(scene.camera.clone()))?;
    d.set_item("R", matrix_to_py(py, &scene.rotation))?;
    d.set_item("t", vector_to_py(py, &scene.translation))?;
    d.set_item("points2d", points_to_py(py, &c.points2d))?;
    d.set_item("points3d", points_to_py(py, &c.points3d))?;
    if with_lines {
        d.set_item("lines2d", segments_to_py(py, &c.lines2d))?;
        d.set_item("lines3d", segments_to_py(py, &c.lines3d))?;
    }
    Ok(d)
}

/// The calibration object of Phong & Horaud 1995, section 5, at the paper's pose, noise-free.
#[pyfunction]
pub fn paper_scene(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let scene = guarded(|| Ok(paper_calibration_object()))?;
    scene_dict(py, &scene, false)
}

/// A seeded random scene, noise-free.
#[pyfunction]
#[pyo3(signature = (kind, n_points, n_lines = None, seed = None))]
pub fn random_scene<'py>(
    py: Python<'py>,
    kind: &str,
    n_points: Integer,
    n_lines: Option<Integer>,
    seed: Option<Integer>,
) -> PyResult<Bound<'py, PyDict>> {
    let Some(kind) = KINDS.into_iter().find(|k| k.as_str() == kind) else {
        let names: Vec<&str> = KINDS.iter().map(|k| k.as_str()).collect();
        return Err(invalid_argument(
            "kind",
            format!("unknown scene kind '{kind}'; expected one of {}", names.join(", ")),
        ));
    };
    let n_points = n_points.count("n_points", 0)?;
    let n_lines = n_lines.map_or(Ok(0), |n| n.count("n_lines", 0))?;
    let seed = seed.map_or(Ok(0), |s| s.seed("seed"))?;
    // Sizes before allocation: a failed allocation aborts the interpreter.
    check_scene_size(n_points, n_lines).map_err(crate::errors::to_py_err)?;
    let scene = py.allow_threads(|| guarded(|| Ok(core_random_scene(kind, n_points, n_lines, seed))))?;
    scene_dict(py, &scene, true)
}
