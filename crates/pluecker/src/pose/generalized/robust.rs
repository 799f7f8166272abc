//! The rig's pose with outliers: the one consensus loop (`crate::consensus`) over samples of three
//! correspondences, points and segments seen by any cameras, solved by the generalised minimal solver
//! of their mix ([`crate::pose::minimal::solve_generalized`]: gP3P, gP2P1L, gP1P2L, gP3L).
//!
//! Each model is scored by MSAC (`½ Σ min(eᵢ², τᵢ²)`, Torr & Zisserman 2000) over every point and
//! segment, `eᵢ` the reprojection error in its own camera's pixels through its lens (the
//! [`RigReprojectionCost`]'s errors; a segment's is the RMS of its two endpoint distances) and `τᵢ` the
//! point or line threshold of [`RansacOptions`]. A model that beats the record is re-fitted as the
//! single camera's are (LO+, Lebeda, Matas & Chum 2012): the trust region on the inliers within
//! [`LO_THRESHOLD_MULTIPLIER`] times the thresholds, then within smaller multiples down to the
//! thresholds over [`LOCAL_ROUNDS`] rounds, each fit scored on all the data. The loop stops on the
//! adaptive bound for the inlier fraction `w` of all correspondences (`P = w³`), capped at
//! [`RansacOptions::min_inlier_ratio`], or on the iteration cap or the time budget; the best model
//! with at least [`RansacOptions::min_inliers`] inliers is then refined on its inliers, re-selected
//! until the set is stable (as for one camera).
//!
//! The best model must also beat chance as for one camera ([`RansacReport::required_inliers`]): an
//! outlier falls within its threshold with the probability of `sprt::chance_probabilities` over the
//! window of its camera's observations, the largest of the cameras' taken for all (the most inliers
//! chance can give). Not yet for a rig: the sequential test (SPRT).

use super::cost::{RigObservations, RigReprojectionCost};
use super::problem::{certify, finish, Conditioned};
use super::ObservingCameras;
use crate::camera_pose::Pose;
use crate::consensus::{self, truncated, Estimator, Stats};
use crate::error::{Error, Result};
use crate::optim::{trust_region, Objective, Summary, Termination, TrustRegionOptions};
use crate::pose::candidates::random_triple;
use crate::pose::certificate::{self, Verdict};
use crate::pose::refinement::{search, PoseCost};
use crate::pose::result::{status_with_behind, PipelineOutcome};
use crate::pose::robust::pipeline::best_refinement;
use crate::pose::robust::scoring::subset;
use crate::pose::robust::sprt::chance_probabilities;
use crate::pose::robust::{
    local_optimization_options, required_inliers, RansacOptions, RansacReport, LOCAL_ROUNDS, LO_THRESHOLD_MULTIPLIER,
};
use crate::pose::{stage, Correspondences, CostKind, PoseOptions, PoseResult, Status};
use crate::rig::Rig;
use crate::rng::Rng;
use nalgebra::{Matrix3, Vector2, Vector3};
use std::time::Instant;

/// The loop's view of one robust rig problem (conditioned frame).
struct RigConsensus<'a> {
    data: &'a Conditioned,
    cameras: &'a ObservingCameras,
    cost: &'a RigReprojectionCost<'a>,
    ransac: &'a RansacOptions,
    /// The trust region of the local optimisation, as the single camera's.
    lo: TrustRegionOptions,
    rng: Rng,
    local_optimizations: usize,
    errors_evaluated: usize,
}

impl RigConsensus<'_> {
    /// The squared threshold of correspondence `k` (points first, then segments), times `scale²`.
    fn tau2(&self, k: usize, scale: f64) -> f64 {
        let tau = if k < self.data.corr.n_points() {
            self.ransac.point_threshold
        } else {
            self.ransac.line_threshold
        };
        (scale * tau).powi(2)
    }

    /// The errors of every correspondence at `pose`.
    fn errors(&mut self, pose: &Pose) -> Vec<f64> {
        self.errors_evaluated += self.data.corr.n_points() + self.data.corr.n_lines();
        self.cost.errors(pose)
    }

    /// The MSAC score `½ Σ min(e², τ²)` of `errors`.
    fn score_of(&self, errors: &[f64]) -> f64 {
        errors
            .iter()
            .enumerate()
            .map(|(k, e)| 0.5 * truncated(e * e, self.tau2(k, 1.0)))
            .sum()
    }

    /// The inliers of `errors` within `scale` times the thresholds: (points, segments).
    fn inliers(&self, errors: &[f64], scale: f64) -> (Vec<bool>, Vec<bool>) {
        let np = self.data.corr.n_points();
        let within: Vec<bool> = errors
            .iter()
            .enumerate()
            .map(|(k, e)| e * e <= self.tau2(k, scale))
            .collect();
        (within[..np].to_vec(), within[np..].to_vec())
    }

    /// The local optimisation's trust region on the inliers `(points, lines)` from `pose`.
    fn fit(&self, pose: &Pose, points: &[bool], lines: &[bool]) -> Option<Pose> {
        let inliers = subset(&self.data.corr, points, lines);
        let cameras = self.cameras.subset(points, lines);
        let observations = RigObservations::new(&self.data.rig, &inliers, &cameras).ok()?;
        let cost = RigReprojectionCost::new(&self.data.rig, &observations).ok()?;
        let (fitted, _) = trust_region::minimize(&cost, *pose, &self.lo);
        fitted.rotation.iter().all(|v| v.is_finite()).then_some(fitted)
    }
}

impl Estimator for RigConsensus<'_> {
    type Sample = [usize; 3];
    type Model = Pose;
    type Score = f64;

    fn sample(&mut self) -> Option<[usize; 3]> {
        Some(random_triple(&mut self.rng, self.data.features.len()))
    }

    fn models(&mut self, sample: &[usize; 3]) -> Vec<Pose> {
        self.data.solve(sample)
    }

    fn score(&mut self, model: &Pose, _: &[usize; 3], record: Option<f64>, _: &Stats) -> Option<f64> {
        let errors = self.errors(model);
        let score = self.score_of(&errors);
        (score.is_finite() && record.map_or(true, |r| score < r)).then_some(score)
    }

    fn refine(&mut self, model: Pose, score: f64) -> (Pose, f64) {
        if self.ransac.local_iterations == 0 {
            return (model, score);
        }
        self.local_optimizations += 1;
        let mut best = (model, score);
        let mut pose = model;
        for round in 0..LOCAL_ROUNDS {
            let exponent = (LOCAL_ROUNDS - 1 - round) as f64 / (LOCAL_ROUNDS - 1) as f64;
            let errors = self.errors(&pose);
            let (points, lines) = self.inliers(&errors, LO_THRESHOLD_MULTIPLIER.powf(exponent));
            if points.iter().chain(&lines).filter(|&&p| p).count() < 3 {
                break;
            }
            let Some(fitted) = self.fit(&pose, &points, &lines) else {
                break;
            };
            let errors = self.errors(&fitted);
            let score = self.score_of(&errors);
            if score < best.1 {
                best = (fitted, score);
            }
            pose = fitted;
        }
        best
    }

    fn new_best(&mut self, model: &Pose, _: &Stats) -> f64 {
        let errors = self.errors(model);
        let (points, lines) = self.inliers(&errors, 1.0);
        let w = points.iter().chain(&lines).filter(|&&p| p).count() as f64 / errors.len().max(1) as f64;
        w * w * w
    }
}

/// The probabilities that an outlier point or segment agrees with a wrong pose by chance
/// (`sprt::chance_probabilities`), the largest over the cameras, each over the window of its own
/// observations.
fn chance(corr: &Correspondences, cameras: &ObservingCameras, ransac: &RansacOptions) -> [f64; 2] {
    let mut windows: Vec<Option<[f64; 4]>> = Vec::new();
    let mut widen = |k: usize, u: &Vector2<f64>| {
        if windows.len() <= k {
            windows.resize(k + 1, None);
        }
        let w = windows[k].get_or_insert([u.x, u.y, u.x, u.y]);
        *w = [w[0].min(u.x), w[1].min(u.y), w[2].max(u.x), w[3].max(u.y)];
    };
    for (i, u) in corr.points2d.iter().enumerate() {
        widen(cameras.point(i), u);
    }
    for (j, s) in corr.lines2d.iter().enumerate() {
        s.iter().for_each(|u| widen(cameras.line(j), u));
    }
    windows
        .into_iter()
        .flatten()
        .map(|w| chance_probabilities(w, ransac.point_threshold, ransac.line_threshold))
        .fold([0.0, 0.0], |a, b| [a[0].max(b[0]), a[1].max(b[1])])
}

/// The rig's pose with `opts.ransac = Some(ransac)` (module docs): at least 3 and
/// [`RansacOptions::min_inliers`] correspondences.
pub(super) fn estimate(
    rig: &Rig,
    corr: &Correspondences,
    cameras: &ObservingCameras,
    opts: &PoseOptions,
    ransac: &RansacOptions,
    started: Instant,
) -> Result<PoseResult> {
    let (np, nl) = (corr.n_points(), corr.n_lines());
    if np + nl < ransac.min_inliers.max(3) {
        return Err(Error::TooFewCorrespondences {
            method: "robust rig pose".into(),
            required: format!(
                "at least min_inliers = {} correspondences (points and lines together)",
                ransac.min_inliers
            ),
            actual: format!("{np} points and {nl} lines"),
        });
    }
    let data = Conditioned::new(rig, corr, cameras)?;
    let observations = RigObservations::new(&data.rig, &data.corr, cameras)?;
    let cost = RigReprojectionCost::new(&data.rig, &observations)?;
    let mut estimator = RigConsensus {
        data: &data,
        cameras,
        cost: &cost,
        ransac,
        lo: local_optimization_options(&opts.refinement, ransac),
        rng: Rng::new(ransac.seed),
        local_optimizations: 0,
        errors_evaluated: 0,
    };
    let options = consensus::Options {
        confidence: ransac.confidence,
        floor_probability: ransac.min_inlier_ratio.powi(3),
        max_iterations: ransac.max_iterations,
        min_iterations: ransac.min_iterations,
        time_budget: ransac.time_budget,
        interruptible: true,
    };
    let loop_started = Instant::now();
    let outcome = consensus::run(&mut estimator, &options, || loop_started.elapsed());
    let all_outliers = estimator.score_of(&vec![f64::INFINITY; np + nl]);
    let nan_pose = Pose::new(Matrix3::from_element(f64::NAN), Vector3::from_element(f64::NAN));
    let (model, score) = outcome.best.unwrap_or((nan_pose, all_outliers));
    let (mut points, mut lines) = if outcome.best.is_some() {
        let errors = estimator.errors(&model);
        estimator.inliers(&errors, 1.0)
    } else {
        (vec![false; np], vec![false; nl])
    };
    let count = |mask: &[bool]| mask.iter().filter(|&&m| m).count();
    let mut report = RansacReport {
        iterations: outcome.stats.iterations,
        degenerate_samples: outcome.stats.degenerate_samples,
        models_scored: outcome.stats.models_scored,
        sprt_rejections: 0,
        errors_evaluated: estimator.errors_evaluated,
        local_optimizations: estimator.local_optimizations,
        inliers: count(&points) + count(&lines),
        required_inliers: ransac.min_inliers,
        score,
        stop: outcome.stop.into(),
        time_seconds: loop_started.elapsed().as_secs_f64(),
    };
    report.required_inliers = required_inliers(ransac, &report, chance(corr, cameras, ransac), np, nl);
    let summary = Summary {
        iterations: report.iterations,
        evaluations: report.models_scored,
        initial_cost: all_outliers,
        final_cost: score,
        termination: if outcome.stop == consensus::Stop::Confidence {
            Termination::ClosedForm
        } else {
            Termination::MaxIterations
        },
    };
    let mut stages = vec![stage(
        "ransac",
        CostKind::Msac,
        &data.to_world(&model),
        &summary,
        loop_started,
    )];
    let failure = if outcome.best.is_none() {
        Some(Status::NoHypothesis)
    } else if report.inliers < report.required_inliers {
        Some(Status::TooFewInliers)
    } else {
        None
    };
    let mut pose = model;
    if failure.is_none() && opts.refine {
        let mut refinement = None;
        let settled = best_refinement((points, lines), |(points, lines)| {
            let inliers = subset(&data.corr, points, lines);
            let own = cameras.subset(points, lines);
            let fitted = RigObservations::new(&data.rig, &inliers, &own)
                .and_then(|o| {
                    let cost = RigReprojectionCost::new(&data.rig, &o)?;
                    let minima = search(&cost, &[pose], std::iter::empty(), false, opts);
                    Ok(minima
                        .choose(0.0)
                        .map(|c| (minima.found[c.best], minima.report(c.best, &data.cond))))
                })
                .ok()
                .flatten();
            let Some((minimum, stage_report)) = fitted else {
                return (pose, f64::INFINITY, (points.clone(), lines.clone()));
            };
            refinement = Some(stage_report);
            let errors = estimator.errors(&minimum.pose);
            (
                minimum.pose,
                estimator.score_of(&errors),
                estimator.inliers(&errors, 1.0),
            )
        });
        (pose, (points, lines)) = settled;
        stages.extend(refinement);
        report.inliers = count(&points) + count(&lines);
    }
    let world = data.to_world(&pose);
    let used = subset(corr, &points, &lines);
    let used_cameras = cameras.subset(&points, &lines);
    let used_observations = RigObservations::new(rig, &used, &used_cameras)?;
    let used_cost = RigReprojectionCost::new(rig, &used_observations)?;
    let behind = used_cost.points_behind(&world);
    let failure = failure.or_else(|| (report.inliers < report.required_inliers).then_some(Status::TooFewInliers));
    let status = failure.unwrap_or_else(|| status_with_behind(&world, &stages, behind, true, opts.refine));
    // The certificate of the inliers' cost at the pose, in the conditioned frame.
    let certification = certificate::stage(opts.certify.as_ref(), status, |options| {
        let inliers = subset(&data.corr, &points, &lines);
        match RigObservations::new(&data.rig, &inliers, &used_cameras)
            .and_then(|o| Ok((RigReprojectionCost::new(&data.rig, &o)?.cost(&pose), o)))
        {
            Ok((cost, observations)) => certify(&data.rig, &observations, &pose, cost, options),
            Err(e) => Verdict::none(format!("not attempted: {e}")),
        }
    });
    Ok(finish(
        &used_cost,
        opts,
        started,
        PipelineOutcome {
            pose: world,
            stages,
            status,
            estimated_camera: None,
            used: &used,
            inliers: Some((points, lines)),
            ransac: Some(report),
            second_best: None,
            certification,
            behind_camera_cost: None,
        },
    ))
}
