//! The last stage of every pose pipeline: the status, the reprojection error, the covariance, the
//! rotation forms, and the search and certificate outcomes, assembled into a [`PoseResult`].

use super::certificate::Certification;
use super::correspondences::{object_points, Correspondences};
use super::lens::Observations;
use super::reprojection::{count_behind, covariance, Pose, ReprojectionCost};
use super::robust::RansacReport;
use super::{PoseOptions, PoseResult, StageReport, Status};
use crate::camera::Camera;
use crate::chi_square::ResidualTest;
use crate::geometry::dual_quaternion::DualQuaternion;
use crate::geometry::quaternion::{axis_angle, from_rotation_matrix};
use crate::optim::{Objective, Termination};
use nalgebra::{Vector3, Vector4};
use std::time::Instant;

/// What a pipeline hands to [`assemble`].
pub(crate) struct Parts<'c> {
    /// The returned pose, world frame (NaN if the solver failed).
    pub pose: Pose,
    /// Stage reports in order; the last one gave `pose`.
    pub stages: Vec<StageReport>,
    /// The status, decided by the pipeline (most pipelines by [`status_of_stages`]).
    pub status: Status,
    /// Intrinsics estimated by the linear method.
    pub estimated_camera: Option<Camera>,
    /// The correspondences the pose was fitted to (world frame, observed pixels): all of them, or the
    /// inliers.
    pub used: &'c Correspondences,
    /// Inlier masks (points, lines) when robust; `None`: all used.
    pub inliers: Option<(Vec<bool>, Vec<bool>)>,
    /// The robust loop's report.
    pub ransac: Option<RansacReport>,
    /// The runner-up local minimum (world frame) and its cost.
    pub second_best: Option<(Pose, f64)>,
    /// The certificate stage's outcome.
    pub certification: Certification,
    /// The cost of a pose with every object point behind the camera, when it beats `pose`.
    pub behind_camera_cost: Option<f64>,
}

/// Whether `pose` is finite.
pub(crate) fn is_finite(pose: &Pose) -> bool {
    pose.rotation
        .iter()
        .chain(pose.translation.iter())
        .all(|v| v.is_finite())
}

/// The status that the stages and the pose imply: a numerical failure (non-finite pose, singular
/// Hessian, non-finite cost, or — without refinement — an algebraic answer far from a rigid motion),
/// else not converged, else points behind the camera, else success.
pub(crate) fn status_of_stages(
    pose: &Pose,
    stages: &[StageReport],
    used: &Correspondences,
    valid: bool,
    refine: bool,
) -> Status {
    let finite = is_finite(pose);
    let behind = if finite {
        count_behind(object_points(used).copied(), pose)
    } else {
        0
    };
    let solver_failed = stages
        .iter()
        .any(|s| matches!(s.termination, Termination::SingularHessian | Termination::NonFiniteCost));
    // Without refinement, an algebraic answer far from a rigid motion (e.g. a stop at r = 0) failed too.
    if !finite || solver_failed || (!refine && !valid && behind == 0) {
        Status::NumericalFailure
    } else if stages.iter().any(|s| !s.termination.converged()) {
        Status::NotConverged
    } else if behind > 0 {
        Status::BehindCamera
    } else {
        Status::Success
    }
}

/// The [`PoseResult`] of a finished run.
pub(crate) fn assemble(
    observations: &Observations<'_>,
    opts: &PoseOptions,
    started: Instant,
    parts: Parts<'_>,
) -> PoseResult {
    let Parts {
        pose,
        stages,
        status,
        estimated_camera,
        used,
        inliers,
        ransac,
        second_best,
        certification,
        behind_camera_cost,
    } = parts;
    let last = stages.last().expect("at least one stage").clone();
    let finite = is_finite(&pose);
    let residual_count = 2 * (used.n_points() + used.n_lines());
    // One linearisation at the returned pose gives the reprojection error and `JᵀJ`, exact in the
    // observed pixels. The refinement uses the given camera; the linear method alone is judged at its
    // own intrinsics (for a pinhole camera: through a lens, at the given one).
    let linearization = finite.then(|| match estimated_camera {
        Some(model) if !opts.refine && observations.lens.is_none() => {
            ReprojectionCost::of(&model, used).linearize(&pose)
        }
        _ => observations.cost(used).linearize(&pose),
    });
    let reprojection_cost = linearization.as_ref().map_or(f64::NAN, |l| l.cost);
    let rms_error_px = (2.0 * reprojection_cost / residual_count.max(1) as f64).sqrt();
    let (covariance, covariance_source, sigma_px) = covariance(linearization.as_ref(), residual_count, opts.sigma_px);
    // The χ² test needs the noise from the caller; without the refinement the linear method also
    // fitted the five intrinsics.
    let fitted = if !opts.refine && estimated_camera.is_some() {
        11
    } else {
        6
    };
    let residual_test = opts
        .sigma_px
        .and_then(|s| ResidualTest::new(2.0 * reprojection_cost / (s * s), residual_count.saturating_sub(fitted)));
    let (dual_quaternion, axis, angle) = if finite {
        let q = DualQuaternion::from_rotation_translation(&pose.rotation, &pose.translation);
        let (axis, angle) = axis_angle(&from_rotation_matrix(&pose.rotation));
        (q, axis, angle)
    } else {
        let nan4 = Vector4::from_element(f64::NAN);
        (
            DualQuaternion { r: nan4, s: nan4 },
            Vector3::from_element(f64::NAN),
            f64::NAN,
        )
    };
    let (inliers_points, inliers_lines) =
        inliers.unwrap_or_else(|| (vec![true; used.n_points()], vec![true; used.n_lines()]));
    PoseResult {
        rotation: pose.rotation,
        translation: pose.translation,
        dual_quaternion,
        axis,
        angle,
        method: opts.method,
        iterations: stages.iter().map(|s| s.iterations).sum(),
        final_cost: last.final_cost,
        termination: last.termination,
        status,
        rms_error_px,
        time_seconds: started.elapsed().as_secs_f64(),
        stages,
        estimated_camera,
        inliers_points,
        inliers_lines,
        ransac,
        covariance,
        covariance_source,
        sigma_px,
        certified: certification.certified,
        lower_bound: certification.lower_bound,
        raw_lower_bound: certification.raw_lower_bound,
        gap: certification.gap,
        certificate: certification.certificate,
        ambiguous: status == Status::Ambiguous,
        second_best,
        behind_camera_cost,
        residual_test,
    }
}
