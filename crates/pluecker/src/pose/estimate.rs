//! The plain (non-robust) pose pipeline, stage by stage:
//!
//! 1. validation and conditioning ([`super::correspondences`]);
//! 2. the algebraic solve of the chosen method from its default starts ([`super::initialization`]) and
//!    the user's, with the cheirality restart (this module);
//! 3. starting candidates for the refinement besides the algebraic answer: the minimal solvers' poses
//!    ([`super::candidates`]);
//! 4. the reprojection refinement from every candidate, and the choice among the local minima found,
//!    with the runner-up and the ambiguity test ([`super::refinement`]);
//! 5. the certificate of global optimality, on request ([`super::certificate`]);
//! 6. the result: status, error, covariance ([`super::result`]).
//!
//! The robust pipeline ([`super::robust::pipeline`]) shares stages 4-6.

use super::algebraic::{gram, solve_translation, JointCost, RotationCost};
use super::candidates::{behind_camera_cost, is_exhaustive, minimal_hypotheses};
use super::certificate::{self, certify, Verdict};
use super::correspondences::{constraints, object_points, Conditioning, Correspondences, PointSpread};
use super::initialization::{joint_starts, mirrored, rotation_starts};
use super::lens::Observations;
use super::linear::faugeras_toscani;
use super::refinement::search;
use super::reprojection::{count_behind, Pose, ReprojectionCost};
use super::result::{assemble, is_finite, status_of_stages, PipelineOutcome};
use super::{stage, CostKind, Method, PoseOptions, PoseResult, StageReport, Status, STEP_TOLERANCE_BEFORE_REFINEMENT};
use crate::camera::Camera;
use crate::camera::Intrinsics;
use crate::error::Result;
use crate::geometry::dual_quaternion::DualQuaternion;
use crate::geometry::quaternion::rotation_distance;
use crate::optim::{
    levenberg_marquardt, newton, trust_region, Objective, Subproblem, Summary, Termination, TrustRegionOptions,
};
use nalgebra::{Matrix3, SVector, Vector3, Vector4};
use std::borrow::Cow;
use std::time::Instant;

/// A dual-quaternion iterate back to a rigid motion in the world frame.
fn to_world(x: &SVector<f64, 8>, cond: &Conditioning) -> Pose {
    let (rot, t) = DualQuaternion::from_vector(x).to_rotation_translation();
    Pose::new(rot, cond.pose_to_world(&rot, &t))
}

/// The user's starting pose in the conditioned frame, if any.
fn user_start(opts: &PoseOptions, cond: &Conditioning) -> Option<DualQuaternion> {
    opts.initial_pose.as_ref().map(|p| {
        DualQuaternion::from_rotation_translation(&p.rotation, &cond.pose_from_world(&p.rotation, &p.translation))
    })
}

/// What the restart logic needs to know about the object (in the frame of the cost).
struct Shape<'c> {
    /// The correspondences in that frame: every 3-D point and segment endpoint is checked.
    corr: &'c Correspondences,
    /// The shape of the world points (the conditioning only shifts and scales it).
    world: &'c PointSpread,
    /// Centroid.
    centroid: Vector3<f64>,
    /// Standard deviations along the principal axes, largest first.
    spread: Vector3<f64>,
}

impl<'c> Shape<'c> {
    /// The shape of `corr`, the correspondences conditioned by `cond`, from that of the world points.
    fn of(corr: &'c Correspondences, world: &'c PointSpread, cond: &Conditioning) -> Shape<'c> {
        Shape {
            corr,
            world,
            centroid: cond.apply(&world.centroid),
            spread: world.spread / cond.scale,
        }
    }

    /// Axis of least spread, for the mirror pose.
    fn axis(&self) -> Vector3<f64> {
        self.world.least_axis()
    }

    /// How many default starts this object gets.
    fn default_starts(&self) -> usize {
        if self.spread[2] < PLANARITY * self.spread[0] {
            MULTI_STARTS
        } else {
            1
        }
    }

    /// True when the iterate `x` is a plausible answer: close to a rigid motion (`|r·r − 1| < ½`; the
    /// penalty is soft, and the collapsed stationary point `r → 0` of eqs. 13/22 has cost λ/2) with every
    /// object point in front of the camera.
    fn in_front(&self, x: &SVector<f64, 8>) -> bool {
        let r_norm2 = x.fixed_rows::<4>(0).norm_squared();
        if !x.iter().all(|v| v.is_finite()) || (r_norm2 - 1.0).abs() >= 0.5 {
            return false;
        }
        let pose: Pose = DualQuaternion::from_vector(x).to_rotation_translation().into();
        count_behind(object_points(self.corr).copied(), &pose) == 0
    }
}

/// Two runs of one solver as one: iterations and evaluations add up, the kept run gives the end.
fn merged(first: &Summary, second: &Summary, keep_second: bool) -> Summary {
    let kept = if keep_second { second } else { first };
    Summary {
        iterations: first.iterations + second.iterations,
        evaluations: first.evaluations + second.evaluations,
        initial_cost: first.initial_cost,
        final_cost: kept.final_cost,
        termination: kept.termination,
    }
}

/// Runs `solve` from `x0`; if it ends with object points behind the camera (or far from a rigid
/// motion), runs it once more from the mirrored pose (see [`super::initialization`]). Returns the
/// answer in front if there is one (else the cheaper), the summed work, and whether it is in front.
fn with_cheirality_restart(
    x0: SVector<f64, 8>,
    shape: &Shape,
    solve: &impl Fn(SVector<f64, 8>) -> (SVector<f64, 8>, Summary),
) -> (SVector<f64, 8>, Summary, bool) {
    let (x, summary) = solve(x0);
    if shape.in_front(&x) {
        return (x, summary, true);
    }
    let (rot, t) = DualQuaternion::from_vector(&x).to_rotation_translation();
    let (x2, summary2) = solve(mirrored(&rot, &t, &shape.axis()).to_vector());
    let in_front = shape.in_front(&x2);
    if in_front || summary2.final_cost < summary.final_cost {
        (x2, merged(&summary, &summary2, true), in_front)
    } else {
        (x, merged(&summary, &summary2, false), false)
    }
}

/// The starts of one estimate: the user's (if any) and the default ones. All are tried and the
/// cheapest valid answer wins, so a poor user guess cannot make the result worse than no guess.
fn starts(user: Option<SVector<f64, 8>>, defaults: Vec<SVector<f64, 8>>) -> Vec<SVector<f64, 8>> {
    user.into_iter().chain(defaults).collect()
}

/// Number of default starts for a near-planar object and for the rotation cost of eq. 14 (see
/// [`super::initialization`]); the joint costs of other objects get one. Planar targets have a second
/// local minimum whose algebraic cost can be the lower one; eq. 14 from few lines has local minima.
const MULTI_STARTS: usize = 3;
/// An object is near-planar when its least spread is below this fraction of its largest spread.
const PLANARITY: f64 = 0.1;
/// Answers from other starts whose algebraic cost is within this factor of the best are refined too,
/// and the reprojection error decides (planar scenes have two minima of similar algebraic cost).
const ALTERNATIVE_COST_FACTOR: f64 = 4.0;

/// What the estimator (before refinement) found.
#[derive(Debug, Clone)]
pub struct Estimate {
    /// The best pose, world frame.
    pub pose: Pose,
    /// Stage reports.
    pub stages: Vec<StageReport>,
    /// Intrinsics estimated by the linear method.
    pub camera: Option<Intrinsics>,
    /// Other distinct answers worth refining (world frame), cheapest first.
    pub alternatives: Vec<Pose>,
    /// False when the best answer is not a plausible pose: object points behind the camera, or an
    /// iterate far from a rigid motion (`|r·r − 1| ≥ ½`, e.g. plain Newton's stop at `r = 0`).
    pub valid: bool,
}

/// Keeps the cheapest valid run, sums the work of all, and lists the near-best distinct others.
fn select(
    runs: Vec<(SVector<f64, 8>, Summary, bool)>,
    score: impl Fn(&SVector<f64, 8>, &Summary) -> f64,
) -> (SVector<f64, 8>, Summary, Vec<SVector<f64, 8>>, bool) {
    let mut ranked: Vec<(f64, bool, SVector<f64, 8>, Summary)> = runs
        .into_iter()
        .map(|(x, s, valid)| (score(&x, &s), valid, x, s))
        .collect();
    ranked.sort_by(|a, b| (!a.1).cmp(&!b.1).then(a.0.total_cmp(&b.0)));
    let total_iterations = ranked.iter().map(|r| r.3.iterations).sum();
    let total_evaluations = ranked.iter().map(|r| r.3.evaluations).sum();
    let (best_score, best_valid, best, mut summary) = ranked[0].clone();
    summary.iterations = total_iterations;
    summary.evaluations = total_evaluations;
    let best_rot = DualQuaternion::from_vector(&best).to_rotation_translation().0;
    let mut alternatives: Vec<SVector<f64, 8>> = Vec::new();
    for (cost, valid, x, _) in ranked.iter().skip(1) {
        let rot = DualQuaternion::from_vector(x).to_rotation_translation().0;
        let distinct = rotation_distance(&rot, &best_rot) > 1e-3
            && alternatives
                .iter()
                .all(|a| rotation_distance(&DualQuaternion::from_vector(a).to_rotation_translation().0, &rot) > 1e-3);
        if *valid && distinct && *cost <= ALTERNATIVE_COST_FACTOR * best_score + 1e-300 {
            alternatives.push(*x);
        }
    }
    (best, summary, alternatives, best_valid)
}

/// The data every stage shares, computed once per call: the world points' shape, the conditioning
/// and the conditioned correspondences.
struct Prepared {
    shape: PointSpread,
    cond: Conditioning,
    conditioned: Correspondences,
}

impl Prepared {
    fn new(corr: &Correspondences, shape: PointSpread, opts: &PoseOptions) -> Prepared {
        let cond = if opts.normalize {
            Conditioning::of_shape(&shape)
        } else {
            Conditioning::identity()
        };
        Prepared {
            shape,
            cond,
            conditioned: cond.correspondences(corr),
        }
    }
}

/// The estimator named by `opts.method`, without refinement, on prepared data (inputs validated) with
/// the trust-region settings `tr` (`opts.trust_region`, or looser before a refinement); `started` is
/// when the caller's clock started.
fn estimator(
    camera: &Intrinsics,
    corr: &Correspondences,
    prepared: &Prepared,
    opts: &PoseOptions,
    tr: &TrustRegionOptions,
    started: Instant,
) -> Result<Estimate> {
    if opts.method == Method::Linear {
        let cal = faugeras_toscani(&corr.points2d, &corr.points3d)?;
        let pose = Pose::new(cal.rotation, cal.translation);
        let cost = ReprojectionCost::new(cal.camera, &corr.points2d, &corr.points3d, &[], &[]).cost(&pose);
        let summary = Summary {
            iterations: 0,
            evaluations: 1,
            initial_cost: cost,
            final_cost: cost,
            termination: Termination::ClosedForm,
        };
        return Ok(Estimate {
            pose,
            stages: vec![stage("linear", CostKind::Reprojection, &pose, &summary, started)],
            camera: Some(cal.camera),
            alternatives: vec![],
            valid: true,
        });
    }
    let (cond, cc) = (prepared.cond, &prepared.conditioned);
    let shape = Shape::of(cc, &prepared.shape, &cond);
    let mut tr = *tr;
    if opts.method == Method::RotationThenTranslation {
        let (points, lines) = constraints(camera, cc, true)?;
        let rotation_cost = RotationCost::new(&lines, opts.penalty);
        let translation_gram = gram(&points, &lines[..cc.n_lines()], false);
        tr.subproblem = Subproblem::Hebden;
        // Eq. 14 by the trust region, then eq. 15; both together form one solve of the restart logic.
        let solve = |x0: SVector<f64, 8>| {
            let r0: Vector4<f64> = x0.fixed_rows::<4>(0).into_owned();
            let (r, summary) = trust_region::minimize(&rotation_cost, r0, &tr);
            let r = normalized_or_identity(&r);
            let s = solve_translation(&translation_gram, &r, opts.penalty).unwrap_or_else(Vector4::zeros);
            let mut x = SVector::<f64, 8>::zeros();
            x.fixed_rows_mut::<4>(0).copy_from(&r);
            x.fixed_rows_mut::<4>(4).copy_from(&s);
            (x, summary)
        };
        let default_starts: Vec<SVector<f64, 8>> = rotation_starts(&rotation_cost.gram, MULTI_STARTS)
            .into_iter()
            .map(|r| DualQuaternion { r, s: Vector4::zeros() }.to_vector())
            .collect();
        let user = user_start(opts, &cond).map(|q| {
            DualQuaternion {
                r: q.r,
                s: Vector4::zeros(),
            }
            .to_vector()
        });
        let runs = starts(user, default_starts)
            .into_iter()
            .map(|x0| with_cheirality_restart(x0, &shape, &solve))
            .collect();
        // Candidates are ranked by the joint cost (eqs. 13 + 22), which sees rotation and translation.
        let (point_cons, line_cons) = constraints(camera, cc, false)?;
        let joint = JointCost {
            gram: gram(&point_cons, &line_cons, true),
            lambda: opts.penalty,
        };
        let (x, summary, others, valid) = select(runs, |x, _| joint.cost(x));
        let pose = to_world(&x, &cond);
        let rotation_report = stage("rotation", CostKind::Algebraic, &pose, &summary, started);
        let t_started = Instant::now();
        let translation_cost = JointCost {
            gram: translation_gram,
            lambda: opts.penalty,
        }
        .cost(&x);
        let closed = Summary {
            iterations: 0,
            evaluations: 1,
            initial_cost: translation_cost,
            final_cost: translation_cost,
            termination: Termination::ClosedForm,
        };
        let translation_report = stage("translation", CostKind::Algebraic, &pose, &closed, t_started);
        let alternatives = others.iter().map(|x| to_world(x, &cond)).collect();
        return Ok(Estimate {
            pose,
            stages: vec![rotation_report, translation_report],
            camera: None,
            alternatives,
            valid,
        });
    }
    let (points, lines) = constraints(camera, cc, false)?;
    let cost = JointCost {
        gram: gram(&points, &lines, true),
        lambda: opts.penalty,
    };
    let mut default_starts: Vec<SVector<f64, 8>> = joint_starts(&cost.gram, &shape.centroid, shape.default_starts())
        .iter()
        .map(|q| q.to_vector())
        .collect();
    if default_starts.is_empty() {
        default_starts.push(DualQuaternion::identity().to_vector());
    }
    if opts.method == Method::TrustRegionExact {
        tr.subproblem = Subproblem::MoreSorensen;
    }
    let solve = |x0: SVector<f64, 8>| match opts.method {
        Method::Newton => newton::minimize(&cost, x0, &opts.newton),
        Method::LevenbergMarquardt => levenberg_marquardt::minimize(&cost, x0, &opts.levenberg_marquardt),
        _ => trust_region::minimize(&cost, x0, &tr),
    };
    let user = user_start(opts, &cond).map(|q| q.to_vector());
    let runs = starts(user, default_starts)
        .into_iter()
        .map(|x0| with_cheirality_restart(x0, &shape, &solve))
        .collect();
    let (x, summary, others, valid) = select(runs, |_, s| s.final_cost);
    let pose = if x.iter().all(|v| v.is_finite()) && x.fixed_rows::<4>(0).norm() > 0.0 {
        to_world(&x, &cond)
    } else {
        Pose::new(Matrix3::from_element(f64::NAN), Vector3::from_element(f64::NAN))
    };
    let alternatives = others.iter().map(|x| to_world(x, &cond)).collect();
    Ok(Estimate {
        pose,
        stages: vec![stage(
            opts.method.as_str(),
            CostKind::Algebraic,
            &pose,
            &summary,
            started,
        )],
        camera: None,
        alternatives,
        valid,
    })
}

fn normalized_or_identity(r: &Vector4<f64>) -> Vector4<f64> {
    let n = r.norm();
    if n.is_finite() && n > 0.0 {
        r / n
    } else {
        Vector4::new(1.0, 0.0, 0.0, 0.0)
    }
}

/// Estimates the pose `x_cam = R X_world + t` of a calibrated camera from point and/or line
/// correspondences (see [`Method`] and [`PoseOptions`]).
///
/// `camera` is a [`Camera`] of any of its models: a pinhole, or one of COLMAP's models with a lens,
/// whose pixels (`corr`) are the observed, distorted ones (see `lens` for what each stage then works
/// on).
///
/// With `refine` (the default) the answer is the cheapest local minimum of the reprojection error that
/// the refinement reaches from the algebraic answer and from the minimal solvers' poses (see
/// `pose::refinement`); the result names the runner-up and says when it is nearly as good
/// ([`Status::Ambiguous`]), and with [`PoseOptions::certify`] carries a certificate of global optimality
/// (through a lens, of the exact cost in the observed pixels). Through a lens the
/// reprojection error is the exact one in the observed pixels
/// ([`super::reprojection::ReprojectionCost::exact`]), and so are the result's cost, errors and
/// `sigma_px`.
///
/// Errors on invalid input (shapes, NaN/inf, too few correspondences, degenerate configurations,
/// singular camera, bad options, a pixel outside the invertible region of a lens without RANSAC). A
/// solver that fails returns `Ok` with a non-`Success` status.
///
/// With per-observation noise on `corr` ([`super::ObservationNoise`], covariances of the observed pixels) every
/// stage after the algebraic one uses the whitened residuals; user covariances are absolute, so
/// `sigma_px` defaults to 1 (standard deviations) instead of the estimate from the residuals.
pub fn estimate_pose(camera: &Camera, corr: &Correspondences, opts: &PoseOptions) -> Result<PoseResult> {
    let started = Instant::now();
    let pinhole = camera.intrinsics();
    pinhole.validate()?;
    opts.validate()?;
    let opts = &with_noise_level(opts, corr);
    match camera.distortion() {
        Some(lens) => {
            let through = super::lens::ThroughLens::new(lens, corr, opts)?;
            Ok(through.expand(run(&through.observations(), opts, started)?))
        }
        None => run(&Observations::pinhole(&pinhole, corr), opts, started),
    }
}

/// `opts` with `sigma_px = 1` when the correspondences carry the user's covariances and no
/// `sigma_px` is given: the residuals are then in standard deviations, their noise level is 1.
pub(crate) fn with_noise_level<'o>(opts: &'o PoseOptions, corr: &Correspondences) -> Cow<'o, PoseOptions> {
    if corr.noise.as_ref().is_some_and(|n| n.absolute) && opts.sigma_px.is_none() {
        Cow::Owned(PoseOptions {
            sigma_px: Some(1.0),
            ..opts.clone()
        })
    } else {
        Cow::Borrowed(opts)
    }
}

/// The pipeline on validated options (`camera` and `opts`), from `started`: robust or not.
pub(crate) fn run(observations: &Observations<'_>, opts: &PoseOptions, started: Instant) -> Result<PoseResult> {
    let camera = &observations.pinhole;
    let corr = observations.undistorted.as_ref();
    if let Some(robust) = &opts.ransac {
        return super::robust::pipeline::estimate_robust(observations, opts, robust, started);
    }
    let prepared = Prepared::new(corr, corr.validated(opts.method)?, opts);
    let mut tr = opts.trust_region;
    if opts.refine {
        tr.stopping.step_tolerance = tr.stopping.step_tolerance.max(STEP_TOLERANCE_BEFORE_REFINEMENT);
    }
    let Estimate {
        pose,
        mut stages,
        camera: estimated_camera,
        alternatives,
        valid,
    } = estimator(camera, corr, &prepared, opts, &tr, started)?;
    let (pose, status, second_best, certification, behind_camera_cost) = if opts.refine && is_finite(&pose) {
        let cond = &prepared.cond;
        let conditioned = &prepared.conditioned;
        let observed = observations.conditioned_observed(cond, conditioned);
        let cost = observations.cost(&observed);
        let to_cond = |p: &Pose| Pose::new(p.rotation, cond.pose_from_world(&p.rotation, &p.translation));
        let to_world = |p: &Pose| Pose::new(p.rotation, cond.pose_to_world(&p.rotation, &p.translation));
        let starts: Vec<Pose> = std::iter::once(&pose).chain(&alternatives).map(to_cond).collect();
        let n = conditioned.n_points() + conditioned.n_lines();
        let minima = search(
            &cost,
            &starts,
            minimal_hypotheses(camera, conditioned),
            is_exhaustive(n),
            opts,
        );
        let margin = 0.5 * opts.ambiguity_threshold * ambiguity_sigma2(opts.sigma_px, minima.best_cost(), 2 * n);
        let choice = minima.choose(margin).expect("at least the algebraic start was refined");
        let best = minima.found[choice.best];
        stages.push(minima.report(choice.best, cond));
        let world = to_world(&best.pose);
        let mut status = status_of_stages(&world, &stages, corr, valid, true);
        if !best.converged() && status == Status::Success {
            status = Status::NotConverged;
        }
        if choice.ambiguous && status == Status::Success {
            status = Status::Ambiguous;
        }
        // Residuals above the noise (σ = sigma_px, else 1 px): are the data better explained with
        // the points behind the camera, by more than the ambiguity margin? (Cheap, and only then.
        // Under a narrow field of view a pose behind the camera fits about as well as its twin in
        // front, rotated by π about the optical axis: the margin keeps that near-tie from counting.)
        // The reference σ here is the stated noise (1 px without sigma_px), not σ̂: a misfit inflates σ̂.
        let sigma2 = opts.sigma_px.map_or(1.0, |s| s * s);
        let behind_margin = 0.5 * opts.ambiguity_threshold * sigma2;
        let bound = (best.cost - behind_margin).min(best.cost / BEHIND_CAMERA_RATIO);
        let behind_cost = (matches!(status, Status::Success | Status::Ambiguous)
            && 2.0 * best.cost > sigma2 * (2 * n) as f64)
            .then(|| behind_camera_cost(camera, conditioned, bound))
            .flatten();
        if behind_cost.is_some() {
            status = Status::BehindCamera;
        }
        let second_best = choice
            .second
            .map(|i| (to_world(&minima.found[i].pose), minima.found[i].cost));
        let certification = certificate::stage(opts.certify.as_ref(), status, |options| {
            certify(camera, observations.lens, &observed, &best.pose, best.cost, options)
        });
        (world, status, second_best, certification, behind_cost)
    } else {
        let status = status_of_stages(&pose, &stages, corr, valid, opts.refine);
        let why = "no refinement: the pose is not a minimum of the reprojection error";
        (pose, status, None, Verdict::none(why), None)
    };
    Ok(assemble(
        observations,
        opts,
        started,
        PipelineOutcome {
            pose,
            stages,
            status,
            estimated_camera,
            used: observations.observed,
            inliers: None,
            ransac: None,
            second_best,
            certification,
            behind_camera_cost,
        },
    ))
}

/// How many times lower than the returned pose's cost the cost of a pose with every point behind the
/// camera must be for [`super::PoseDetails::behind_camera_cost`] to count: without a stated noise a mere
/// margin cannot tell a near-tie (4-5 noisy correspondences, a narrow field of view) from data that
/// only a pose behind the camera explains, whose in-front fit is worse by orders of magnitude.
const BEHIND_CAMERA_RATIO: f64 = 100.0;

/// The `σ²` of the ambiguity test (px²): `sigma_px²` when given, else the larger of 1 px² and the
/// estimate `Σ r² / (m − 6)` at the best minimum of cost `best_cost` over `m` residuals.
pub(crate) fn ambiguity_sigma2(sigma_px: Option<f64>, best_cost: f64, residuals: usize) -> f64 {
    match sigma_px {
        Some(s) => s * s,
        None if residuals > 6 => (2.0 * best_cost / (residuals - 6) as f64).max(1.0),
        None => 1.0,
    }
}
