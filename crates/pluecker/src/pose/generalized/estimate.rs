//! [`estimate_rig_pose`]: the pose of a rig from points and segments seen by its cameras (the
//! pipeline of the module docs of [`super`]).

use super::cost::{RigObservations, RigReprojectionCost};
use super::linear::linear_pose;
use super::problem::{certify, finish, Conditioned};
use super::{robust, ObservingCameras};
use crate::camera_pose::Pose;
use crate::error::{Error, Result};
use crate::pose::candidates::is_exhaustive;
use crate::pose::certificate;
use crate::pose::estimate::{ambiguity_sigma2, with_noise_level};
use crate::pose::refinement::search;
use crate::pose::result::{is_finite, status_with_behind, PipelineOutcome};
use crate::pose::{estimate_pose, Correspondences, Method, PoseOptions, PoseResult, Status};
use crate::rig::{tangent_map, Rig};
use std::time::Instant;

/// The pose `rig_from_world` (`x_rig = R X_world + t`) of `rig` from the points and segments of
/// `corr`, each seen by the camera `cameras` names, with `opts` as for one camera
/// ([`crate::pose::estimate_pose`]): the same [`PoseResult`], its pose the rig's, its covariance in the
/// rig's tangent `(ω, t)` (rig frame), its cost `Σ r²` over every camera's (whitened) pixels.
///
/// Observations all in one camera are that camera's problem ([`super`]'s module docs): its answer,
/// its statuses and its certificate, the pose moved into the rig's frame; with one camera at the
/// identity the result is the camera's exactly. `opts.method` is then that camera's estimator; for
/// several cameras the starts are the rig's own (it is echoed in the report), and every start is
/// refined whatever `opts.refine` says (the rig has no algebraic estimator whose answer could be
/// returned as it is).
///
/// Errors name the argument and row: a camera index out of range or missing
/// ([`ObservingCameras::check`]), a pixel its camera's lens cannot unproject, the checks of
/// [`Correspondences::validate`], and too few points to start from ([`Error::TooFewCorrespondences`]:
/// several cameras need 3 points, or one camera that saw enough for its own pose).
pub fn estimate_rig_pose(
    rig: &Rig,
    corr: &Correspondences,
    cameras: &ObservingCameras,
    opts: &PoseOptions,
) -> Result<PoseResult> {
    let started = Instant::now();
    opts.validate()?;
    corr.validated(Method::TrustRegion)?;
    let observations = RigObservations::new(rig, corr, cameras)?;
    if let [share] = observations.shares.as_slice() {
        return one_camera(rig, share.camera, corr, opts);
    }
    let opts = with_noise_level(opts, corr);
    match &opts.ransac {
        Some(ransac) => robust::estimate(rig, corr, cameras, &opts, ransac, started),
        None => several_cameras(rig, corr, cameras, &observations, &opts, started),
    }
}

/// The pose of a rig whose observations camera `k` saw alone: that camera's pipeline, moved into the
/// rig's frame.
fn one_camera(rig: &Rig, k: usize, corr: &Correspondences, opts: &PoseOptions) -> Result<PoseResult> {
    let sensor = rig.sensor_from_rig()[k];
    let mut own = opts.clone();
    own.initial_pose = opts.initial_pose.map(|p| sensor.compose(&p));
    let result = estimate_pose(&rig.cameras()[k], corr, &own)?;
    Ok(into_rig_frame(result, &sensor))
}

/// A camera's result as its rig's: `rig_from_world = sensor_from_rig⁻¹ ∘ sensor_from_world` for the
/// pose, the stages and the runner-up, and the covariance `Bᵀ C B` (`B = diag(R_k, R_k)`, the map of
/// the rig's tangent to the camera's: [`super::cost`]). Costs and certificates do not change.
fn into_rig_frame(mut result: PoseResult, sensor: &Pose) -> PoseResult {
    let back = sensor.inverse();
    result.pose = back.compose(&result.pose);
    for stage in &mut result.details.stages {
        let moved = back.compose(&Pose::new(stage.rotation, stage.translation));
        (stage.rotation, stage.translation) = (moved.rotation, moved.translation);
    }
    if let Some((pose, _)) = &mut result.details.second_best {
        *pose = back.compose(pose);
    }
    if let Some(c) = &mut result.covariance {
        let b = tangent_map(&sensor.rotation);
        *c = b.transpose() * *c * b;
    }
    result
}

/// A start from the camera that saw the most of `observations` (world frame), when it saw enough for
/// its own pose: its pose (without the robust loop or the certificate) moved into the rig's frame,
/// world frame.
fn best_camera_start(rig: &Rig, observations: &RigObservations, opts: &PoseOptions) -> Option<Pose> {
    let share = observations
        .shares
        .iter()
        .max_by_key(|s| s.corr.n_points() + s.corr.n_lines())?;
    let mut own = opts.clone();
    (own.ransac, own.certify, own.initial_pose) = (None, None, None);
    let result = estimate_pose(&rig.cameras()[share.camera], &share.corr, &own).ok()?;
    let pose = rig.sensor_from_rig()[share.camera].inverse().compose(&result.pose);
    is_finite(&pose).then_some(pose)
}

/// The rig's pose from observations of several cameras (`observations`: `corr` split by camera, world
/// frame), without outliers: every start refined, the best minimum chosen ([`super`]'s module docs).
fn several_cameras(
    rig: &Rig,
    corr: &Correspondences,
    cameras: &ObservingCameras,
    observations: &RigObservations,
    opts: &PoseOptions,
    started: Instant,
) -> Result<PoseResult> {
    let data = Conditioned::new(rig, corr, cameras)?;
    let conditioned = RigObservations::new(&data.rig, &data.corr, cameras)?;
    let cost = RigReprojectionCost::new(&data.rig, &conditioned)?;
    let mut starts: Vec<Pose> = opts.initial_pose.iter().map(|p| data.conditioned(p)).collect();
    if let Ok(pose) = linear_pose(&data.rays, &data.corr.points3d) {
        starts.push(pose);
    }
    if corr.n_lines() > 0 || corr.n_points() < 6 {
        starts.extend(best_camera_start(rig, observations, opts).map(|p| data.conditioned(&p)));
    }
    let samples = data.samples();
    let exhaustive = is_exhaustive(data.features.len());
    let minima = search(&cost, &starts, samples.iter().map(|s| data.solve(s)), exhaustive, opts);
    let margin =
        0.5 * opts.ambiguity_threshold * ambiguity_sigma2(opts.sigma_px, minima.best_cost(), cost.residual_count());
    let Some(choice) = minima.choose(margin) else {
        return Err(Error::Degenerate {
            what: "no pose of the rig explains the observations: no start was found (no sample of three \
                   correspondences has a minimal solution)"
                .into(),
        });
    };
    let best = minima.found[choice.best];
    let stages = vec![minima.report(choice.best, &data.cond)];
    let pose = data.to_world(&best.pose);
    // The stage's termination is the best minimum's: a refinement that did not converge is
    // `not_converged` there.
    let mut status = status_with_behind(&pose, &stages, best.behind, true, true);
    if choice.ambiguous && status == Status::Success {
        status = Status::Ambiguous;
    }
    let second_best = choice
        .second
        .map(|i| (data.to_world(&minima.found[i].pose), minima.found[i].cost));
    let certification = certificate::stage(opts.certify.as_ref(), status, |options| {
        certify(&data.rig, &conditioned, &best.pose, best.cost, options)
    });
    Ok(finish(
        &RigReprojectionCost::new(rig, observations)?,
        opts,
        started,
        PipelineOutcome {
            pose,
            stages,
            status,
            estimated_camera: None,
            used: corr,
            inliers: None,
            ransac: None,
            second_best,
            certification,
            behind_camera_cost: None,
        },
    ))
}
