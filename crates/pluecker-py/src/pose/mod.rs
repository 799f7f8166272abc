//! Pose bindings: `estimate_pose` ([`estimate_pose`]), its options ([`options`]) and result
//! ([`result`]), the minimal solvers and the refinement one by one ([`minimal`]), the reprojection
//! error and covariance at a given pose ([`reprojection`]), and the dual-quaternion forms of a pose
//! ([`geometry`]).

pub mod geometry;
pub mod minimal;
pub mod options;
pub mod reprojection;
pub mod result;

use crate::camera::PyCamera;
use crate::convert::{points, segments};
use crate::errors::shape_error;
use crate::interrupt::{run_interruptible, with_partial};
use options::{PyPoseOptions, PyRansacOptions};
use pluecker::pose::Correspondences;
use pyo3::prelude::*;
use result::PyPoseResult;

/// The four correspondence arrays, converted and checked (shapes, finiteness, matching counts).
pub fn correspondences(
    points2d: Option<&Bound<'_, PyAny>>,
    points3d: Option<&Bound<'_, PyAny>>,
    lines2d: Option<&Bound<'_, PyAny>>,
    lines3d: Option<&Bound<'_, PyAny>>,
) -> PyResult<Correspondences> {
    let c = Correspondences {
        points2d: points::<2>("points2d", points2d)?,
        points3d: points::<3>("points3d", points3d)?,
        lines2d: segments::<2>("lines2d", lines2d)?,
        lines3d: segments::<3>("lines3d", lines3d)?,
        noise: None,
    };
    if c.points2d.len() != c.points3d.len() {
        let actual = format!("{} and {} rows", c.points2d.len(), c.points3d.len());
        return Err(shape_error("points2d / points3d", "the same number of rows", actual));
    }
    if c.lines2d.len() != c.lines3d.len() {
        let actual = format!("{} and {} segments", c.lines2d.len(), c.lines3d.len());
        return Err(shape_error("lines2d / lines3d", "the same number of segments", actual));
    }
    Ok(c)
}

/// The `ransac=` argument: `RansacOptions`, `True` (the defaults), or `False`/`None` (not robust).
fn ransac_arg(ransac: Option<&Bound<'_, PyAny>>) -> PyResult<Option<pluecker::pose::RansacOptions>> {
    let Some(ransac) = ransac else { return Ok(None) };
    if let Ok(options) = ransac.downcast::<PyRansacOptions>() {
        return Ok(Some(options.borrow().inner));
    }
    match ransac.extract::<bool>() {
        Ok(robust) => Ok(robust.then(Default::default)),
        Err(_) => Err(pyo3::exceptions::PyTypeError::new_err(format!(
            "ransac: expected RansacOptions, True, False or None, got {}",
            ransac.get_type().name()?
        ))),
    }
}

/// Correspondences from which `estimate_pose` runs on a worker thread, so that Ctrl-C stops it
/// within about 0.1 s (fewer take milliseconds, and run on the calling thread).
const SHORT_POSE: usize = 1000;

/// Estimates the pose `x_cam = R X_world + t` from point and/or line correspondences, optionally
/// robustly (LO-RANSAC), with its covariance.
///
/// `options`: `PoseOptions` (default `PoseOptions()`); `method`, when given, wins over
/// `options.method`. `ransac`: `RansacOptions` or `True` (its defaults) estimates robustly.
#[pyfunction]
#[pyo3(signature = (camera, points2d = None, points3d = None, lines2d = None, lines3d = None, method = None, *, options = None, ransac = None))]
#[allow(clippy::too_many_arguments)]
pub fn estimate_pose(
    py: Python<'_>,
    camera: &Bound<'_, PyCamera>,
    points2d: Option<&Bound<'_, PyAny>>,
    points3d: Option<&Bound<'_, PyAny>>,
    lines2d: Option<&Bound<'_, PyAny>>,
    lines3d: Option<&Bound<'_, PyAny>>,
    method: Option<&str>,
    options: Option<PyRef<'_, PyPoseOptions>>,
    ransac: Option<&Bound<'_, PyAny>>,
) -> PyResult<Py<PyPoseResult>> {
    let camera = camera.get().inner;
    let options = options.map_or_else(PyPoseOptions::default, |o| o.clone());
    let options = match method {
        Some(m) => options.with_method(m)?,
        None => options,
    };
    let opts = options.core(ransac_arg(ransac)?);
    let corr = correspondences(points2d, points3d, lines2d, lines3d)?;
    // A pose from fewer correspondences ends within milliseconds (see `interrupt::run_interruptible`).
    let short = corr.n_points() + corr.n_lines() < SHORT_POSE;
    let outcome = run_interruptible(py, None, None, short, move |_| {
        pluecker::estimate_pose(&camera, &corr, &opts)
    })?;
    let result = Py::new(py, PyPoseResult::wrap(outcome.value))?;
    match outcome.pending {
        // Ctrl-C: the pose reached so far (RANSAC stopped with `ransac.stop == "interrupted"`).
        Some(e) => Err(with_partial(py, e, result.into_any())),
        None => Ok(result),
    }
}
