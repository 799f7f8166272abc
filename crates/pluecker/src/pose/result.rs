//! The last stage of every pose pipeline: the status, the reprojection error, the covariance, and the
//! search and certificate outcomes, assembled into a [`PoseResult`].
//!
//! The pipeline's stages measure the reprojection cost as `½ Σ r²` (the form the optimisers and the
//! certificate's derivation use); [`assemble`] is the one place where every reported cost becomes
//! `Σ r²`: the result's cost, the stage costs of kind `reprojection` and `msac`, the runner-up's cost
//! and the cost behind the camera. The certificate arrives in `Σ r²` already: the certificate
//! module converts its bounds where they leave it (`certificate::certify`).

use super::certificate::Verdict;
use super::correspondences::{object_points, Correspondences};
use super::lens::Observations;
use super::reprojection::{count_behind, covariance, Pose, ReprojectionCost};
use super::robust::RansacReport;
use super::{CostKind, PoseDetails, PoseOptions, PoseResult, StageReport, Status};
use crate::camera::Intrinsics;
use crate::chi_square::ResidualTest;
use crate::interrupt::stop_reason;
use crate::optim::{Linearization, Objective, Termination};
use crate::Report;
use std::time::Instant;

/// What a pipeline hands to [`assemble`].
pub(crate) struct PipelineOutcome<'c> {
    /// The returned pose, world frame (NaN if the solver failed).
    pub pose: Pose,
    /// Stage reports in order; the last one gave `pose`.
    pub stages: Vec<StageReport>,
    /// The status, decided by the pipeline (most pipelines by [`status_of_stages`]).
    pub status: Status,
    /// Intrinsics estimated by the linear method.
    pub estimated_camera: Option<Intrinsics>,
    /// The correspondences the pose was fitted to (world frame, observed pixels): all of them, or the
    /// inliers.
    pub used: &'c Correspondences,
    /// Inlier masks (points, lines) when robust; `None`: all used.
    pub inliers: Option<(Vec<bool>, Vec<bool>)>,
    /// The robust loop's report.
    pub ransac: Option<RansacReport>,
    /// The runner-up local minimum (world frame) and its cost `½ Σ r²`.
    pub second_best: Option<(Pose, f64)>,
    /// The certificate stage's outcome (its certificate already in `Σ r²`).
    pub certification: Verdict,
    /// The cost `½ Σ r²` of a pose with every object point behind the camera, when it beats `pose`.
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
    let behind = if is_finite(pose) {
        count_behind(object_points(used).copied(), pose)
    } else {
        0
    };
    status_with_behind(pose, stages, behind, valid, refine)
}

/// [`status_of_stages`] given the number of object points and segment endpoints behind the camera
/// (behind their own camera, for a rig) at `pose`.
pub(crate) fn status_with_behind(
    pose: &Pose,
    stages: &[StageReport],
    behind: usize,
    valid: bool,
    refine: bool,
) -> Status {
    let finite = is_finite(pose);
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

/// A reported cost `Σ r²` from the pipeline's `½ Σ r²`.
fn sum_of_squares(half: f64) -> f64 {
    2.0 * half
}

/// The [`PoseResult`] of a finished run; every cost converted to `Σ r²` (see the module docs), and a
/// requested certificate that does not hold turning [`Status::Success`] into
/// [`Status::GapNotClosed`] ([`Status::Interrupted`] or [`Status::TimeBudget`] when its search was
/// stopped).
pub(crate) fn assemble(
    observations: &Observations<'_>,
    opts: &PoseOptions,
    started: Instant,
    parts: PipelineOutcome<'_>,
) -> PoseResult {
    // One linearisation at the returned pose gives the reprojection error and `JᵀJ`, exact in the
    // observed pixels. The refinement uses the given camera; the linear method alone is judged at its
    // own intrinsics (for a pinhole camera: through a lens, at the given one).
    let linearization = is_finite(&parts.pose).then(|| match parts.estimated_camera {
        Some(model) if !opts.refine && observations.lens.is_none() => {
            ReprojectionCost::of(&model, parts.used).linearize(&parts.pose)
        }
        _ => observations.cost(parts.used).linearize(&parts.pose),
    });
    assemble_at(linearization, opts, started, parts)
}

/// [`assemble`] given the linearisation of the reprojection cost of `parts.used` at `parts.pose`
/// (`None` when the pose is not finite).
pub(crate) fn assemble_at(
    linearization: Option<Linearization<6>>,
    opts: &PoseOptions,
    started: Instant,
    parts: PipelineOutcome<'_>,
) -> PoseResult {
    let PipelineOutcome {
        pose,
        mut stages,
        status,
        estimated_camera,
        used,
        inliers,
        ransac,
        second_best,
        certification,
        behind_camera_cost,
    } = parts;
    let termination = stages.last().expect("at least one stage").termination;
    for stage in stages
        .iter_mut()
        .filter(|s| matches!(s.cost_kind, CostKind::Reprojection | CostKind::Msac))
    {
        stage.initial_cost = sum_of_squares(stage.initial_cost);
        stage.final_cost = sum_of_squares(stage.final_cost);
    }
    let residual_count = 2 * (used.n_points() + used.n_lines());
    let cost = sum_of_squares(linearization.as_ref().map_or(f64::NAN, |l| l.cost));
    let rms_error_px = (cost / residual_count.max(1) as f64).sqrt();
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
        .and_then(|s| ResidualTest::new(cost / (s * s), residual_count.saturating_sub(fitted)));
    let (inliers_points, inliers_lines) =
        inliers.unwrap_or_else(|| (vec![true; used.n_points()], vec![true; used.n_lines()]));
    // A requested certificate that does not hold: the gap is not closed, or the search was stopped.
    let status = if opts.certify.is_some() && status == Status::Success && !certification.certified() {
        stop_reason().map_or(Status::GapNotClosed, Status::stopped)
    } else {
        status
    };
    let mut report = Report::new(opts.method, CostKind::Reprojection);
    report.status = status;
    report.cost = cost;
    report.certificate = certification.certificate;
    report.iterations = stages.iter().map(|s| s.iterations).sum();
    report.termination = termination;
    report.test_residuals(residual_count, fitted);
    report.time_seconds = started.elapsed().as_secs_f64();
    PoseResult {
        pose,
        report,
        inliers_points,
        inliers_lines,
        covariance,
        details: PoseDetails {
            stages,
            rms_error_px,
            estimated_camera,
            ransac: ransac.map(|r| RansacReport {
                score: sum_of_squares(r.score),
                ..r
            }),
            covariance_source,
            sigma_px,
            second_best: second_best.map(|(p, c)| (p, sum_of_squares(c))),
            behind_camera_cost: behind_camera_cost.map(sum_of_squares),
            residual_test,
            uncertified_reason: certification.uncertified_reason,
        },
    }
}
