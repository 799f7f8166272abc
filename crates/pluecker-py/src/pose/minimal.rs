//! The minimal solvers and the reprojection refinement, callable one by one as PoseLib's are
//! (`pluecker::pose::minimal`, `pluecker::pose::refine_pose`).
//!
//! The solvers take camera-frame quantities: unit bearings of image points and unit normals of the
//! interpretation planes of image segments, which `Camera.bearings` and `Camera.plane_normals` give
//! from pixels. Each returns every real pose `x_cam = R X_world + t` that explains its sample exactly,
//! as a list of `(R, t)`: possibly empty (a degenerate sample), never an error for valid arrays.

use crate::camera::PyCamera;
use crate::convert::pose_from_parts;
use crate::convert::{points, segments};
use crate::errors::shape_error;
use crate::pose::correspondences;
use crate::pose::options::PyPoseOptions;
use crate::pose::result::PyPoseStage;
use crate::properties::Field;
use crate::threads::solve;
use nalgebra::{SVector, Vector3};
use pluecker::pose::generalized::Ray;
use pluecker::pose::minimal;
use pluecker::pose::refine_pose as core_refine_pose;
use pluecker::Pose;
use pyo3::prelude::*;
use pyo3::types::PyList;

/// Exactly `N` rows of `D` finite numbers, shape `(N, D)`.
fn rows<const N: usize, const D: usize>(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<[SVector<f64, D>; N]> {
    let rows = points::<D>(name, Some(obj))?;
    rows.try_into()
        .map_err(|r: Vec<_>| shape_error(name, &format!("shape ({N}, {D})"), format!("{} rows", r.len())))
}

/// Exactly `N` pairs of 3-D points, shape `(N, 2, 3)`.
fn pairs<const N: usize>(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<[[Vector3<f64>; 2]; N]> {
    let pairs = segments::<3>(name, Some(obj))?;
    pairs
        .try_into()
        .map_err(|p: Vec<_>| shape_error(name, &format!("shape ({N}, 2, 3)"), format!("{} segments", p.len())))
}

/// The poses as a list of `(R, t)`.
fn pose_list<'py>(py: Python<'py>, poses: Vec<Pose>) -> PyResult<Bound<'py, PyList>> {
    let items = poses.into_iter().map(|p| p.get(py)).collect::<PyResult<Vec<_>>>()?;
    PyList::new(py, items)
}

/// P3P (Lambda Twist, Persson & Nordberg 2018): the poses that put the three world `points` (3, 3) on
/// the camera-frame rays `bearings` (3, 3) at positive depth; at most 4.
#[pyfunction]
pub fn p3p<'py>(
    py: Python<'py>,
    bearings: &Bound<'py, PyAny>,
    points: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyList>> {
    let (y, x) = (rows::<3, 3>("bearings", bearings)?, rows::<3, 3>("points", points)?);
    pose_list(py, solve(py, move || Ok(minimal::p3p(&y, &x)))?)
}

/// gP3P, the generalised P3P of a rig: the poses `x_rig = R X_world + t` that put the three world
/// `points` (3, 3) on the three rays of the rig's frame through `origins` (3, 3) along `directions`
/// (3, 3, any non-zero length) at positive depth; at most 8 (core `pose::minimal::gp3p`).
#[pyfunction]
pub fn gp3p<'py>(
    py: Python<'py>,
    origins: &Bound<'py, PyAny>,
    directions: &Bound<'py, PyAny>,
    points: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyList>> {
    let (o, d) = (
        rows::<3, 3>("origins", origins)?,
        rows::<3, 3>("directions", directions)?,
    );
    let x = rows::<3, 3>("points", points)?;
    let rays = std::array::from_fn(|i| Ray {
        origin: o[i],
        direction: d[i],
    });
    pose_list(py, solve(py, move || Ok(minimal::gp3p(&rays, &x)))?)
}

/// Two points and one line (Ramalingam, Bouaziz & Sturm 2011): `bearings` (2, 3) and world `points`
/// (2, 3), the camera-frame `normal` (3,) of a line's interpretation plane and two world points
/// `endpoints` (2, 3) of the line; at most 4 poses.
#[pyfunction]
pub fn p2p1l<'py>(
    py: Python<'py>,
    bearings: &Bound<'py, PyAny>,
    points: &Bound<'py, PyAny>,
    normal: &Bound<'py, PyAny>,
    endpoints: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyList>> {
    let (y, x) = (rows::<2, 3>("bearings", bearings)?, rows::<2, 3>("points", points)?);
    let (n, e) = (
        crate::convert::vector::<3>("normal", normal)?,
        rows::<2, 3>("endpoints", endpoints)?,
    );
    pose_list(py, solve(py, move || Ok(minimal::p2p1l(&y, &x, &n, &e)))?)
}

/// One point and two lines (Ramalingam, Bouaziz & Sturm 2011): a `bearing` (3,) and its world `point`
/// (3,), the interpretation-plane `normals` (2, 3) and world `endpoints` (2, 2, 3) of two lines; at
/// most 4 poses.
#[pyfunction]
pub fn p1p2l<'py>(
    py: Python<'py>,
    bearing: &Bound<'py, PyAny>,
    point: &Bound<'py, PyAny>,
    normals: &Bound<'py, PyAny>,
    endpoints: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyList>> {
    let (y, x) = (
        crate::convert::vector::<3>("bearing", bearing)?,
        crate::convert::vector::<3>("point", point)?,
    );
    let (n, e) = (rows::<2, 3>("normals", normals)?, pairs::<2>("endpoints", endpoints)?);
    pose_list(py, solve(py, move || Ok(minimal::p1p2l(&y, &x, &n, &e)))?)
}

/// Three lines (Dhome et al. 1989; Chen 1990): the interpretation-plane `normals` (3, 3) and world
/// `endpoints` (3, 2, 3) of three lines; at most 8 poses.
#[pyfunction]
pub fn p3l<'py>(
    py: Python<'py>,
    normals: &Bound<'py, PyAny>,
    endpoints: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyList>> {
    let (n, e) = (rows::<3, 3>("normals", normals)?, pairs::<3>("endpoints", endpoints)?);
    pose_list(py, solve(py, move || Ok(minimal::p3l(&n, &e)))?)
}

/// Minimises the reprojection error (pixels for points, endpoint-to-line distances for segments) from
/// the pose `(R, t)` with the trust region of Phong & Horaud 1995, section 4.1, and returns the pose
/// reached and its stage report: `(R, t, PoseStage)`. `options`: `PoseOptions` (its `normalize` and
/// `refinement` are used; `None`: the defaults). The pixels are a pinhole camera's: a `camera` that
/// distorts is an `InvalidOptionError` (`estimate_pose` with `initial_pose` refines through a lens).
#[pyfunction]
#[pyo3(signature = (camera, R, t, points2d = None, points3d = None, lines2d = None, lines3d = None, *, options = None))]
#[allow(non_snake_case, clippy::too_many_arguments)]
pub fn refine_pose<'py>(
    py: Python<'py>,
    camera: &Bound<'py, PyCamera>,
    R: &Bound<'py, PyAny>,
    t: &Bound<'py, PyAny>,
    points2d: Option<&Bound<'py, PyAny>>,
    points3d: Option<&Bound<'py, PyAny>>,
    lines2d: Option<&Bound<'py, PyAny>>,
    lines3d: Option<&Bound<'py, PyAny>>,
    options: Option<PyRef<'py, PyPoseOptions>>,
) -> PyResult<(PyObject, PyObject, PyPoseStage)> {
    let camera = camera.get().inner.clone();
    let start = pose_from_parts("R", R, "t", t)?;
    let opts = options.map_or_else(pluecker::pose::PoseOptions::default, |o| o.core());
    let corr = correspondences(points2d, points3d, lines2d, lines3d)?;
    let (pose, stage) = solve(py, move || core_refine_pose(&camera, &corr, &start, &opts))?;
    Ok((
        pose.rotation.get(py)?,
        pose.translation.get(py)?,
        PyPoseStage::wrap(stage),
    ))
}
