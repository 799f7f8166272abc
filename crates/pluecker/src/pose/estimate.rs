//! The pose pipeline: validation → algebraic estimator (or linear baseline) → reprojection refinement.

use super::algebraic::{gram, solve_translation, JointCost, RotationCost};
use super::correspondences::{constraints, Conditioning, Correspondences};
use super::linear::faugeras_toscani;
use super::reprojection::{Pose, ReprojectionCost};
use super::{Method, PoseOptions, PoseResult, StageReport, Status};
use crate::camera::Camera;
use crate::error::Result;
use crate::geometry::dual_quaternion::DualQuaternion;
use crate::geometry::quaternion::{axis_angle, from_rotation_matrix, to_rotation_matrix};
use crate::optim::{levenberg_marquardt, newton, trust_region, Objective, Subproblem, Summary, Termination};
use nalgebra::{Matrix3, SVector, Vector3, Vector4};
use std::time::Instant;

fn stage(name: &str, cost_kind: &'static str, pose: &Pose, summary: &Summary, started: Instant) -> StageReport {
    StageReport {
        name: name.into(),
        cost_kind,
        rotation: pose.0,
        translation: pose.1,
        iterations: summary.iterations,
        initial_cost: summary.initial_cost,
        final_cost: summary.final_cost,
        termination: summary.termination,
        time_seconds: started.elapsed().as_secs_f64(),
    }
}

/// A dual-quaternion iterate back to a rigid motion in the world frame.
fn to_world(x: &SVector<f64, 8>, cond: &Conditioning) -> Pose {
    let (rot, t) = DualQuaternion::from_vector(x).to_rotation_translation();
    (rot, cond.pose_to_world(&rot, &t))
}

/// The starting iterate in the conditioned frame: the user's pose, or the identity motion.
fn start(opts: &PoseOptions, cond: &Conditioning) -> DualQuaternion {
    match &opts.initial_pose {
        Some((rot, t)) => DualQuaternion::from_rotation_translation(rot, &cond.pose_from_world(rot, t)),
        None => DualQuaternion::identity(),
    }
}

/// Runs the estimator named by `opts.method` without refinement. Returns the pose (world frame), the
/// stage reports, and the intrinsics the linear method estimates. Inputs are assumed validated.
pub fn algebraic_stage(
    camera: &Camera,
    corr: &Correspondences,
    opts: &PoseOptions,
) -> Result<(Pose, Vec<StageReport>, Option<Camera>)> {
    let started = Instant::now();
    if opts.method == Method::Linear {
        let cal = faugeras_toscani(&corr.points2d, &corr.points3d)?;
        let pose = (cal.rotation, cal.translation);
        let cost = ReprojectionCost::new(cal.camera, &corr.points2d, &corr.points3d, &[], &[]).cost(&pose);
        let summary = Summary { iterations: 0, evaluations: 1, initial_cost: cost, final_cost: cost, termination: Termination::ClosedForm };
        return Ok((pose, vec![stage("linear", "reprojection", &pose, &summary, started)], Some(cal.camera)));
    }
    let cond = if opts.normalize { Conditioning::of(corr) } else { Conditioning::identity() };
    let cc = cond.correspondences(corr);
    let x0 = start(opts, &cond);
    let mut tr = opts.trust_region;
    if opts.method == Method::RotationThenTranslation {
        let (points, lines) = constraints(camera, &cc, true)?;
        let rotation_cost = RotationCost::new(&lines, opts.lambda);
        tr.subproblem = Subproblem::Hebden;
        let (r, summary) = trust_region::minimize(&rotation_cost, x0.r, &tr);
        let r = normalized_or_identity(&r);
        let rot_pose = (to_rotation_matrix(&r), Vector3::zeros());
        let rotation_report = stage("rotation", "algebraic", &rot_pose, &summary, started);
        let t_started = Instant::now();
        let g = gram(&points, &lines[..cc.n_lines()], false);
        let s = solve_translation(&g, &r, opts.lambda).unwrap_or_else(Vector4::zeros);
        let mut x = SVector::<f64, 8>::zeros();
        x.fixed_rows_mut::<4>(0).copy_from(&r);
        x.fixed_rows_mut::<4>(4).copy_from(&s);
        let translation_cost = JointCost { gram: g, lambda: opts.lambda }.cost(&x);
        let pose = to_world(&x, &cond);
        let summary = Summary {
            iterations: 0,
            evaluations: 1,
            initial_cost: translation_cost,
            final_cost: translation_cost,
            termination: Termination::ClosedForm,
        };
        let translation_report = stage("translation", "algebraic", &pose, &summary, t_started);
        return Ok((pose, vec![rotation_report, translation_report], None));
    }
    let (points, lines) = constraints(camera, &cc, false)?;
    let cost = JointCost { gram: gram(&points, &lines, true), lambda: opts.lambda };
    let x0 = x0.to_vector();
    let (x, summary) = match opts.method {
        Method::TrustRegion => trust_region::minimize(&cost, x0, &tr),
        Method::TrustRegionExact => {
            tr.subproblem = Subproblem::MoreSorensen;
            trust_region::minimize(&cost, x0, &tr)
        }
        Method::Newton => newton::minimize(&cost, x0, &opts.newton),
        Method::LevenbergMarquardt => levenberg_marquardt::minimize(&cost, x0, &opts.levenberg_marquardt),
        Method::RotationThenTranslation | Method::Linear => unreachable!("handled above"),
    };
    let pose = if x.iter().all(|v| v.is_finite()) && x.fixed_rows::<4>(0).norm() > 0.0 {
        to_world(&x, &cond)
    } else {
        (Matrix3::from_element(f64::NAN), Vector3::from_element(f64::NAN))
    };
    Ok((pose, vec![stage(opts.method.as_str(), "algebraic", &pose, &summary, started)], None))
}

fn normalized_or_identity(r: &Vector4<f64>) -> Vector4<f64> {
    let n = r.norm();
    if n.is_finite() && n > 0.0 {
        r / n
    } else {
        Vector4::new(1.0, 0.0, 0.0, 0.0)
    }
}

/// Minimises the reprojection error from `initial` (world frame) with the trust region of section 4.1
/// (Hebden steps on `JᵀJ`). The search runs in the conditioned frame; the returned pose is in the world.
pub fn refine_pose(camera: &Camera, corr: &Correspondences, initial: &Pose, opts: &PoseOptions) -> (Pose, StageReport) {
    let started = Instant::now();
    let cond = if opts.normalize { Conditioning::of(corr) } else { Conditioning::identity() };
    let cc = cond.correspondences(corr);
    let cost = ReprojectionCost::new(*camera, &cc.points2d, &cc.points3d, &cc.lines2d, &cc.lines3d);
    let x0 = (initial.0, cond.pose_from_world(&initial.0, &initial.1));
    let mut tr = opts.refinement;
    tr.subproblem = Subproblem::Hebden;
    let (x, summary) = trust_region::minimize(&cost, x0, &tr);
    let pose = (x.0, cond.pose_to_world(&x.0, &x.1));
    let report = stage("refinement", "reprojection", &pose, &summary, started);
    (pose, report)
}

/// Estimates the pose `x_cam = R X_world + t` of a calibrated camera from point and/or line
/// correspondences (see [`Method`] and [`PoseOptions`]).
///
/// Errors on invalid input (shapes, NaN/inf, too few correspondences, degenerate configurations,
/// singular camera, bad options). A solver that fails returns `Ok` with a non-`Success` status.
pub fn estimate_pose(camera: &Camera, corr: &Correspondences, opts: &PoseOptions) -> Result<PoseResult> {
    let started = Instant::now();
    camera.validate()?;
    opts.validate()?;
    corr.validate(opts.method)?;
    let (mut pose, mut stages, estimated_camera) = algebraic_stage(camera, corr, opts)?;
    let finite = pose.0.iter().chain(pose.1.iter()).all(|v| v.is_finite());
    if opts.refine && finite {
        let (refined, report) = refine_pose(camera, corr, &pose, opts);
        pose = refined;
        stages.push(report);
    }
    let last = stages.last().expect("at least one stage").clone();
    let scoring_camera = if opts.refine { *camera } else { estimated_camera.unwrap_or(*camera) };
    let reprojection = ReprojectionCost::new(scoring_camera, &corr.points2d, &corr.points3d, &corr.lines2d, &corr.lines3d);
    let status = if !finite || stages.iter().any(|s| matches!(s.termination, Termination::SingularHessian | Termination::NonFiniteCost)) {
        Status::NumericalFailure
    } else if stages.iter().any(|s| !s.termination.converged()) {
        Status::NotConverged
    } else if reprojection.points_behind(&pose) > 0 {
        Status::PointsBehindCamera
    } else {
        Status::Success
    };
    let rms_error_px = if finite {
        (2.0 * reprojection.cost(&pose) / reprojection.residual_count().max(1) as f64).sqrt()
    } else {
        f64::NAN
    };
    let (dual_quaternion, axis, angle) = if finite {
        let q = DualQuaternion::from_rotation_translation(&pose.0, &pose.1);
        let (axis, angle) = axis_angle(&from_rotation_matrix(&pose.0));
        (q, axis, angle)
    } else {
        let nan4 = Vector4::from_element(f64::NAN);
        (DualQuaternion { r: nan4, s: nan4 }, Vector3::from_element(f64::NAN), f64::NAN)
    };
    Ok(PoseResult {
        rotation: pose.0,
        translation: pose.1,
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
    })
}
