//! Pose bindings: `estimate_pose` ([`estimate_pose`]), its options ([`options`]) and result
//! ([`result`]), the minimal solvers and the refinement one by one ([`minimal`]), the reprojection
//! error and covariance at a given pose ([`reprojection`]), and the dual-quaternion forms of a pose
//! ([`geometry`]).

// A test hook (`_pose_rotation_search`), in builds with the feature `test-hooks` only.
#[cfg(feature = "test-hooks")]
pub mod certificate;
pub mod geometry;
pub mod minimal;
pub mod options;
pub mod reprojection;
pub mod result;

use crate::convert::{check_finite, matrix_stack, points, read_any, segments, shape_string};
use crate::errors::{guarded, invalid_argument, shape_error};
use crate::interrupt::{object_or_partial, run_interruptible, run_single};
use crate::rig::PyRig;
use crate::triangulation::observation_rows::indices;
use nalgebra::Matrix2;
use options::PyPoseOptions;
use pluecker::pose::ObservationNoise;
use pluecker::pose::{Correspondences, ObservingCameras, PoseOptions};
use pluecker::{Camera, Rig};
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

/// The `line_covariances=` argument: one 2x2 covariance per segment for both endpoints `(M, 2, 2)`, or
/// one per endpoint `(M, 2, 2, 2)`.
fn line_covariances(obj: &Bound<'_, PyAny>) -> PyResult<Vec<[Matrix2<f64>; 2]>> {
    const NAME: &str = "line_covariances";
    let (shape, values) = read_any(NAME, obj)?;
    let per_endpoint = match shape.as_slice() {
        [_, 2, 2] => false,
        [_, 2, 2, 2] => true,
        _ => {
            return Err(shape_error(
                NAME,
                "shape (M, 2, 2) or (M, 2, 2, 2)",
                shape_string(&shape),
            ))
        }
    };
    let stride = if per_endpoint { 8 } else { 4 };
    check_finite(NAME, &values, stride)?;
    let matrix = |v: &[f64]| Matrix2::new(v[0], v[1], v[2], v[3]);
    Ok(values
        .chunks(stride)
        .map(|v| {
            if per_endpoint {
                [matrix(&v[..4]), matrix(&v[4..])]
            } else {
                [matrix(v); 2]
            }
        })
        .collect())
}

/// The noise of the covariance arguments, when either is given (the other defaults to the identity:
/// 1 px² isotropic).
fn observation_noise(
    corr: &Correspondences,
    point_covariances: Option<&Bound<'_, PyAny>>,
    line_covariances_arg: Option<&Bound<'_, PyAny>>,
) -> PyResult<Option<ObservationNoise>> {
    if point_covariances.is_none() && line_covariances_arg.is_none() {
        return Ok(None);
    }
    let points = match point_covariances {
        Some(obj) => matrix_stack::<2, 2>("point_covariances", obj)?,
        None => vec![Matrix2::identity(); corr.n_points()],
    };
    let lines = match line_covariances_arg {
        Some(obj) => line_covariances(obj)?,
        None => vec![[Matrix2::identity(); 2]; corr.n_lines()],
    };
    let noise = guarded(|| ObservationNoise::from_covariances(&points, &lines))?;
    guarded(|| noise.check_counts(corr.n_points(), corr.n_lines()))?;
    Ok(Some(noise))
}

/// The `camera=` argument: a `Camera` (any model), or a `pycolmap.Camera` taken as it is.
fn any_camera(camera: &Bound<'_, PyAny>) -> PyResult<Camera> {
    crate::camera::coerce("camera", camera)
}

/// Correspondences from which `estimate_pose` runs on a worker thread, so that Ctrl-C stops it
/// within about 0.1 s also in the stages that do not poll (fewer take milliseconds there, and run on
/// the calling thread).
const SHORT_POSE: usize = 1000;

/// The `camera=` argument of `estimate_pose`: one camera, or a rig with the camera of each
/// observation.
enum Sensor {
    Camera(Camera),
    Rig(Rig, ObservingCameras),
}

impl Sensor {
    /// A `Rig` with `point_cameras` / `line_cameras` (integer arrays), or a camera without them.
    fn of(
        camera: &Bound<'_, PyAny>,
        point_cameras: Option<&Bound<'_, PyAny>>,
        line_cameras: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Sensor> {
        if let Ok(rig) = camera.downcast::<PyRig>() {
            let read = |name: &str, obj: Option<&Bound<'_, PyAny>>| obj.map_or(Ok(Vec::new()), |o| indices(name, o));
            let cameras = ObservingCameras {
                point_cameras: read("point_cameras", point_cameras)?,
                line_cameras: read("line_cameras", line_cameras)?,
            };
            return Ok(Sensor::Rig(rig.get().inner.clone(), cameras));
        }
        for (name, given) in [("point_cameras", point_cameras), ("line_cameras", line_cameras)] {
            if given.is_some() {
                return Err(invalid_argument(name, "is for a Rig: camera is a single camera"));
            }
        }
        Ok(Sensor::Camera(any_camera(camera)?))
    }

    fn estimate(&self, corr: &Correspondences, opts: &PoseOptions) -> pluecker::Result<pluecker::PoseResult> {
        match self {
            Sensor::Camera(camera) => pluecker::estimate_pose(camera, corr, opts),
            Sensor::Rig(rig, cameras) => pluecker::estimate_rig_pose(rig, corr, cameras, opts),
        }
    }
}

/// Estimates the pose `x_cam = R X_world + t` of a camera, or `x_rig = R X_world + t` of a rig, from
/// point and/or line correspondences, optionally robustly (LO-RANSAC), with its covariance.
///
/// `camera`: `Camera` (pinhole) or `Camera` (distortion; pixels are the observed, distorted ones,
/// and the refinement minimises the exact error in them: core `pose::lens`), or a `Rig` with
/// `point_cameras` (N,) and `line_cameras` (M,), the index of the camera that saw each observation
/// (core `pose::generalized`).
/// `options`: `PoseOptions` (default `PoseOptions()`): the method, `options.ransac` for robust
/// estimation and `options.certify` for the certificate are set there.
/// `point_covariances` (N, 2, 2) and `line_covariances` (M, 2, 2) or (M, 2, 2, 2): pixel² covariances
/// of the observations (core `pose::noise`).
#[pyfunction]
#[pyo3(signature = (camera, points2d = None, points3d = None, lines2d = None, lines3d = None, *, options = None, point_covariances = None, line_covariances = None, point_cameras = None, line_cameras = None))]
#[allow(clippy::too_many_arguments)]
pub fn estimate_pose(
    py: Python<'_>,
    camera: &Bound<'_, PyAny>,
    points2d: Option<&Bound<'_, PyAny>>,
    points3d: Option<&Bound<'_, PyAny>>,
    lines2d: Option<&Bound<'_, PyAny>>,
    lines3d: Option<&Bound<'_, PyAny>>,
    options: Option<PyRef<'_, PyPoseOptions>>,
    point_covariances: Option<&Bound<'_, PyAny>>,
    line_covariances: Option<&Bound<'_, PyAny>>,
    point_cameras: Option<&Bound<'_, PyAny>>,
    line_cameras: Option<&Bound<'_, PyAny>>,
) -> PyResult<Py<PyPoseResult>> {
    let sensor = Sensor::of(camera, point_cameras, line_cameras)?;
    let opts = options.map_or_else(PoseOptions::default, |o| o.core());
    let mut corr = correspondences(points2d, points3d, lines2d, lines3d)?;
    corr.noise = observation_noise(&corr, point_covariances, line_covariances)?;
    let short = corr.n_points() + corr.n_lines() < SHORT_POSE;
    let work = move || sensor.estimate(&corr, &opts);
    // Fewer correspondences: on this thread, where the polls of RANSAC and of the certificate's
    // rotation search see Ctrl-C (`interrupt::run_single`); the other stages end within milliseconds.
    let outcome = if short {
        run_single(py, work)?
    } else {
        run_interruptible(py, None, None, false, move |_| work())?
    };
    // Ctrl-C: the pose reached so far as `partial` (RANSAC stopped with `ransac.stop == "interrupted"`).
    object_or_partial(py, outcome.pending, Py::new(py, PyPoseResult::wrap(outcome.value))?)
}
