//! Reprojection errors and the pose covariance (Cramér-Rao bound) at a given pose.

use crate::camera::PyCamera;
use crate::convert::pose_from_parts;
use crate::convert::{matrix_to_py, Real};
use crate::errors::{degenerate, invalid_argument};
use crate::pose::correspondences;
use crate::threads::solve;
use numpy::{PyArray1, PyArray2};
use pluecker::pose::testing::covariance_from_information;
use pluecker::pose::{pose_covariance as covariance, ReprojectionCost};
use pyo3::prelude::*;

/// The pixel noise `pose_covariance` assumes when `sigma_px` is not given: the covariance per px².
const UNIT_SIGMA_PX: f64 = 1.0;

/// The 6x6 covariance `σ² (JᵀJ)⁻¹` of `(ω, t)` at the pose `(R, t)`: the rotation as the tangent
/// `ω` of `exp(ω) R` (radians, camera frame), then the translation (world units); `σ = sigma_px`
/// pixels (`None`: 1 px).
#[pyfunction]
#[pyo3(signature = (camera, R, t, points2d = None, points3d = None, lines2d = None, lines3d = None, sigma_px = None))]
#[allow(non_snake_case, clippy::too_many_arguments)]
pub fn pose_covariance<'py>(
    py: Python<'py>,
    camera: &Bound<'py, PyCamera>,
    R: &Bound<'py, PyAny>,
    t: &Bound<'py, PyAny>,
    points2d: Option<&Bound<'py, PyAny>>,
    points3d: Option<&Bound<'py, PyAny>>,
    lines2d: Option<&Bound<'py, PyAny>>,
    lines3d: Option<&Bound<'py, PyAny>>,
    sigma_px: Option<Real>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let sigma_px = sigma_px.map_or(Ok(UNIT_SIGMA_PX), |s| s.get("sigma_px"))?;
    let camera = camera.get().inner.clone();
    let pose = pose_from_parts("R", R, "t", t)?;
    if !(sigma_px.is_finite() && sigma_px > 0.0) {
        return Err(invalid_argument(
            "sigma_px",
            format!(
                "must be a positive finite number, got {}",
                pluecker::testing::number(sigma_px)
            ),
        ));
    }
    let c = correspondences(points2d, points3d, lines2d, lines3d)?;
    // The information matrix is computed again only to explain a failure.
    let cov = solve(py, move || {
        let cost = ReprojectionCost::exact(&camera, &c)?;
        Ok(covariance(&cost, &pose, sigma_px).ok_or_else(|| cost.information(&pose)))
    })?;
    let cov = cov.map_err(|information| {
        if information.iter().any(|v| !v.is_finite()) {
            return degenerate(
                "the information matrix JᵀJ is not finite at this pose (a 3-D point or endpoint on the camera plane z = 0?)",
            );
        }
        if let Some(unit) = covariance_from_information(&information, 1.0) {
            return invalid_argument(
                "sigma_px",
                format!(
                    "σ² (JᵀJ)⁻¹ {} double precision at σ = {} px (its largest entry at σ = 1 px is {:.3e})",
                    if sigma_px > 1.0 { "overflows" } else { "underflows" },
                    pluecker::testing::number(sigma_px),
                    unit.amax()
                ),
            );
        }
        let eig = information.symmetric_eigenvalues();
        degenerate(format!(
            "the information matrix JᵀJ is singular (eigenvalues from {:.3e} to {:.3e}): the correspondences do not determine the pose",
            eig.min(),
            eig.max()
        ))
    })?;
    Ok(matrix_to_py(py, &cov))
}

/// Per-correspondence reprojection errors in pixels at the pose `(R, t)`: points first, then lines.
#[pyfunction]
#[pyo3(signature = (camera, R, t, points2d = None, points3d = None, lines2d = None, lines3d = None))]
#[allow(non_snake_case, clippy::too_many_arguments)]
pub fn reprojection_errors<'py>(
    py: Python<'py>,
    camera: &Bound<'py, PyCamera>,
    R: &Bound<'py, PyAny>,
    t: &Bound<'py, PyAny>,
    points2d: Option<&Bound<'py, PyAny>>,
    points3d: Option<&Bound<'py, PyAny>>,
    lines2d: Option<&Bound<'py, PyAny>>,
    lines3d: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let camera = camera.get().inner.clone();
    let pose = pose_from_parts("R", R, "t", t)?;
    let c = correspondences(points2d, points3d, lines2d, lines3d)?;
    let errors = solve(py, move || Ok(ReprojectionCost::exact(&camera, &c)?.errors(&pose)))?;
    Ok(PyArray1::from_vec(py, errors))
}
