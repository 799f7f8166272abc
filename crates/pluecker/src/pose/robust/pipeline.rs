//! The robust pipeline of [`crate::pose::estimate_pose`]: validation → LO-RANSAC in the conditioned
//! frame → reprojection refinement on the inliers, re-selecting the inliers at the refined pose → on
//! request, the certificate of global optimality of the cost over the final inliers.

use super::super::certificate::{self, certify};
use super::super::correspondences::{Conditioning, Correspondences};
use super::super::lens::Observations;
use super::super::refinement::refine_conditioned;
use super::super::reprojection::Pose;
use super::super::result::{assemble, status_of_stages, PipelineOutcome};
use super::super::{stage, CostKind, Method, PoseOptions, PoseResult, StageReport, Status};
use super::scoring::subset;
use super::{ransac, RansacOptions, RansacOutcome, RansacStop};
use crate::error::{Error, Result};
use crate::interrupt::stop_reason;
use crate::optim::{Objective, Summary, Termination};
use nalgebra::{Matrix3, Vector3};
use std::time::Instant;

/// At most this many refinements on the inliers: after each, the inliers are re-selected at the
/// refined pose, and the refinement is repeated on the new set until it no longer changes (or comes
/// back to a set already refined on). Of the refined candidates (a pose and the set it was refined
/// on) the one with the least MSAC score is kept, so a later round never makes the answer worse.
pub const FINAL_ROUNDS: usize = 10;

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

/// The inlier flags of the points and of the lines.
pub(crate) type Inliers = (Vec<bool>, Vec<bool>);

/// The final rounds of the robust pipeline ([`FINAL_ROUNDS`]): `round(set)` refines on `set` and
/// returns the refined pose, its MSAC score and the inliers re-selected there. Rounds go on while the
/// re-selected set is new (not one already refined on), holds at least 3 correspondences, and the
/// call is not stopped. Returns the candidate with the least score, with the set it was refined on:
/// on a stable set that no earlier round beat, the last pose and its own inliers.
pub(crate) fn best_refinement<P: Copy>(
    first: Inliers,
    mut round: impl FnMut(&Inliers) -> (P, f64, Inliers),
) -> (P, Inliers) {
    let mut refined_on = vec![first];
    let (mut best_pose, mut best_score, mut next) = round(&refined_on[0]);
    let mut best = 0;
    while refined_on.len() < FINAL_ROUNDS
        && !refined_on.contains(&next)
        && count(&next.0) + count(&next.1) >= 3
        && stop_reason().is_none()
    {
        refined_on.push(next);
        let (pose, score, reselected) = round(refined_on.last().expect("just pushed"));
        if score < best_score {
            (best_pose, best_score, best) = (pose, score, refined_on.len() - 1);
        }
        next = reselected;
    }
    (best_pose, refined_on.swap_remove(best))
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
    let conditioned_pose = |p: &Pose| Pose::new(p.rotation, cond.pose_from_world(&p.rotation, &p.translation));
    let mut pose = ransac_pose;
    if failure.is_none() && opts.refine {
        let mut refinement: Option<StageReport> = None;
        let settled = best_refinement((points, lines), |(points, lines)| {
            let inliers = subset(&observed, points, lines);
            let (refined, report) = refine_conditioned(&cond, &observations.cost(&inliers), &pose, opts);
            refinement = Some(match refinement.take() {
                None => report,
                Some(previous) => StageReport {
                    iterations: previous.iterations + report.iterations,
                    time_seconds: previous.time_seconds + report.time_seconds,
                    ..report
                },
            });
            pose = refined;
            let at = conditioned_pose(&refined);
            let score = outcome
                .data
                .score(&at, &outcome.thresholds, f64::INFINITY)
                .unwrap_or(f64::INFINITY);
            (refined, score, outcome.data.inliers(&at, &outcome.thresholds))
        });
        (pose, (points, lines)) = settled;
        stages.extend(refinement);
    }
    let used = subset(observations.observed, &points, &lines);
    let required = outcome.report.required_inliers;
    let failure = failure.or_else(|| (count(&points) + count(&lines) < required).then_some(Status::TooFewInliers));
    let status = failure.unwrap_or_else(|| status_of_stages(&pose, &stages, &used, true, opts.refine));
    // The certificate, as for the non-robust pipeline, of the cost over the final inliers.
    let certification = certificate::stage(opts.certify.as_ref(), status, |options| {
        let inliers = subset(&observed, &points, &lines);
        let at = conditioned_pose(&pose);
        let cost = observations.cost(&inliers).cost(&at);
        certify(camera, observations.lens, &inliers, &at, cost, options)
    });
    Ok(assemble(
        observations,
        opts,
        started,
        PipelineOutcome {
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

#[cfg(test)]
mod tests {
    use super::*;

    fn set(points: &[bool]) -> Inliers {
        (points.to_vec(), Vec::new())
    }

    /// A scripted run of rounds: `moves[k]` is the (score, re-selected set) of the k-th round, the
    /// "pose" the round's index; also records the sets refined on.
    fn run(first: &[bool], moves: &[(f64, &[bool])]) -> (usize, Inliers, Vec<Vec<bool>>) {
        let mut seen = Vec::new();
        let (pose, kept) = best_refinement(set(first), |s| {
            let k = seen.len();
            seen.push(s.0.clone());
            (k, moves[k].0, set(moves[k].1))
        });
        (pose, kept, seen)
    }

    const A: &[bool] = &[true, true, true, false];
    const B: &[bool] = &[true, true, true, true];
    const C: &[bool] = &[true, true, false, true];

    #[test]
    fn a_stable_set_ends_the_rounds_with_the_last_pose_and_its_own_inliers() {
        let (pose, kept, seen) = run(A, &[(5.0, B), (4.0, B)]);
        assert_eq!((pose, kept, seen), (1, set(B), vec![A.to_vec(), B.to_vec()]));
    }

    #[test]
    fn a_later_round_that_scores_worse_does_not_replace_the_best() {
        // A → B (score 3) → C (score 4) → back to B: a cycle; the best candidate is B's refinement.
        let (pose, kept, seen) = run(A, &[(5.0, B), (3.0, C), (4.0, B)]);
        assert_eq!(seen, vec![A.to_vec(), B.to_vec(), C.to_vec()]);
        assert_eq!((pose, kept), (1, set(B)));
    }

    #[test]
    fn the_first_refinement_is_kept_when_no_later_one_beats_it() {
        let (pose, kept, _) = run(A, &[(2.0, B), (3.0, C), (3.5, A)]);
        assert_eq!((pose, kept), (0, set(A)));
    }

    #[test]
    fn the_rounds_stop_at_the_cap_and_below_three_inliers() {
        // Sets that never repeat: one more correspondence each round, scores falling.
        let sets: Vec<Vec<bool>> = (0..FINAL_ROUNDS + 2)
            .map(|k| (0..40).map(|i| i < 3 + k).collect())
            .collect();
        let moves: Vec<(f64, &[bool])> = (0..FINAL_ROUNDS + 1)
            .map(|k| (10.0 - k as f64, &sets[k + 1][..]))
            .collect();
        let (pose, kept, seen) = run(&sets[0], &moves);
        assert_eq!(seen.len(), FINAL_ROUNDS);
        assert_eq!((pose, kept), (FINAL_ROUNDS - 1, set(&sets[FINAL_ROUNDS - 1])));
        let two: &[bool] = &[true, true, false, false];
        let (pose, kept, seen) = run(A, &[(1.0, two), (0.0, A)]);
        assert_eq!((pose, kept, seen.len()), (0, set(A), 1));
    }
}
