//! The robust pipeline of [`crate::pose::estimate_pose`]: validation → LO-RANSAC in the conditioned
//! frame → reprojection refinement on the inliers, re-selecting the inliers at the refined pose → on
//! request, the certificate of global optimality of the cost over the final inliers.

use super::super::certificate::{self, certify};
use super::super::correspondences::{Conditioning, Correspondences};
use super::super::lens::Observations;
use super::super::refinement::refine_conditioned;
use super::super::reprojection::Pose;
use super::super::result::{assemble, status_of_stages, Parts};
use super::super::{stage, CostKind, Method, PoseOptions, PoseResult, StageReport, Status};
use super::scoring::subset;
use super::{ransac, RansacOptions, RansacOutcome, RansacStop};
use crate::error::{Error, Result};
use crate::optim::{Objective, Summary, Termination};
use nalgebra::{Matrix3, Vector3};
use std::time::Instant;

/// At most this many refinements on the inliers: after each, the inliers are re-selected at the
/// refined pose, and the refinement is repeated only if they changed.
pub const FINAL_ROUNDS: usize = 3;

/// Checks the data for the robust path: the generic checks of every method (shapes, finite values,
/// zero-length segments, collinear points without lines, parallel or concurrent lines without points),
/// and at least [`RansacOptions::min_inliers`] correspondences.
fn validate(corr: &Correspondences, opts: &RansacOptions) -> Result<super::super::correspondences::PointSpread> {
    let (np, nl) = (corr.n_points(), corr.n_lines());
    let too_few = || Error::TooFewCorrespondences {
        method: "robust".into(),
        required: format!(
            "at least min_inliers = {} correspondences (points and lines together)",
            opts.min_inliers
        ),
        actual: format!("{np} points and {nl} lines"),
    };
    let shape = corr.validated(Method::TrustRegion).map_err(|e| match e {
        Error::TooFewCorrespondences { .. } => too_few(),
        e => e,
    })?;
    if np + nl < opts.min_inliers {
        return Err(too_few());
    }
    Ok(shape)
}

fn count(mask: &[bool]) -> usize {
    mask.iter().filter(|&&m| m).count()
}

/// The report of the sampling stage: cost kind `msac` (`½ Σ min(eᵢ², τᵢ²)`, px²) from the empty
/// model's score to the best one's; closed form when stopped by confidence, else an iteration cap.
fn ransac_stage(outcome: &RansacOutcome, pose: &Pose, started: Instant) -> StageReport {
    let r = &outcome.report;
    let summary = Summary {
        iterations: r.iterations,
        evaluations: r.models_scored,
        initial_cost: outcome.data.all_outlier_score(&outcome.thresholds),
        final_cost: r.score,
        termination: match r.stop {
            RansacStop::Confidence => Termination::ClosedForm,
            _ => Termination::MaxIterations,
        },
    };
    let mut report = stage("ransac", CostKind::Msac, pose, &summary, started);
    report.time_seconds = r.time_seconds;
    report
}

/// [`crate::pose::estimate_pose`] with `opts.ransac = Some(robust)`.
/// RANSAC runs on `observations`' undistorted form, the refinement on the exact cost of the observed one.
pub(crate) fn estimate_robust(
    observations: &Observations<'_>,
    opts: &PoseOptions,
    robust: &RansacOptions,
    started: Instant,
) -> Result<PoseResult> {
    let (camera, corr) = (&observations.pinhole, observations.undistorted.as_ref());
    let shape = validate(corr, robust)?;
    let cond = if opts.normalize {
        Conditioning::of_shape(&shape)
    } else {
        Conditioning::identity()
    };
    let conditioned = cond.correspondences(corr);
    let outcome = ransac(camera, &conditioned, robust, &opts.refinement)?;
    let observed = observations.conditioned_observed(&cond, &conditioned);
    let to_world = |p: &Pose| Pose::new(p.rotation, cond.pose_to_world(&p.rotation, &p.translation));
    let nan_pose = Pose::new(Matrix3::from_element(f64::NAN), Vector3::from_element(f64::NAN));
    let ransac_pose = outcome.pose.as_ref().map_or(nan_pose, to_world);
    let mut stages = vec![ransac_stage(&outcome, &ransac_pose, started)];
    let (mut points, mut lines) = (outcome.inliers_points.clone(), outcome.inliers_lines.clone());
    let failure = if outcome.pose.is_none() {
        Some(Status::NoHypothesis)
    } else if count(&points) + count(&lines) < outcome.report.required_inliers {
        Some(Status::TooFewInliers)
    } else {
        None
    };
    let mut pose = ransac_pose;
    if failure.is_none() && opts.refine {
        let mut refinement: Option<StageReport> = None;
        for _ in 0..FINAL_ROUNDS {
            let inliers = subset(&observed, &points, &lines);
            let (refined, report) = refine_conditioned(&cond, &observations.cost(&inliers), &pose, opts);
            pose = refined;
            refinement = Some(match refinement {
                None => report,
                Some(previous) => StageReport {
                    iterations: previous.iterations + report.iterations,
                    time_seconds: previous.time_seconds + report.time_seconds,
                    ..report
                },
            });
            let at = Pose::new(pose.rotation, cond.pose_from_world(&pose.rotation, &pose.translation));
            let (new_points, new_lines) = outcome.data.inliers(&at, &outcome.thresholds);
            let unchanged = new_points == points && new_lines == lines;
            (points, lines) = (new_points, new_lines);
            if unchanged || count(&points) + count(&lines) < 3 {
                break;
            }
        }
        stages.extend(refinement);
    }
    let used = subset(observations.observed, &points, &lines);
    let required = outcome.report.required_inliers;
    let failure = failure.or_else(|| (count(&points) + count(&lines) < required).then_some(Status::TooFewInliers));
    let status = failure.unwrap_or_else(|| status_of_stages(&pose, &stages, &used, true, opts.refine));
    // The certificate, as for the non-robust pipeline, of the cost over the final inliers.
    let certification = certificate::stage(opts.certify.as_ref(), status, |options| {
        let inliers = subset(&observed, &points, &lines);
        let at = Pose::new(pose.rotation, cond.pose_from_world(&pose.rotation, &pose.translation));
        let cost = observations.cost(&inliers).cost(&at);
        certify(camera, observations.lens, &inliers, &at, cost, options)
    });
    Ok(assemble(
        observations,
        opts,
        started,
        Parts {
            pose,
            stages,
            status,
            estimated_camera: None,
            used: &used,
            inliers: Some((points, lines)),
            ransac: Some(outcome.report),
            second_best: None,
            certification,
            behind_camera_cost: None,
        },
    ))
}
