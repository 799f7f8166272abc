//! Outlier observations in a line track ([`TriangulationOptions::outlier_threshold`]), as for points
//! ([`crate::triangulation::point::robust`]):
//!
//! 1. **Consensus.** Every pair of views (or [`MAX_PAIRS`] seeded ones) gives the line where its two
//!    back-projected planes meet (the linear method on two views); its MSAC score is
//!    `Σ_j min(‖r_j‖², τ²)` over all views, with `r_j` the whitened residual of eq. 18 in view `j`. The
//!    lowest score wins; its two views fit it exactly, so at least two inliers always remain. The pairs
//!    run through the sampling loop shared with the robust pose (`crate::consensus`).
//! 2. **Optimum on the inliers.** The views with `‖r_j‖ ≤ τ` are solved by the chosen method; the
//!    inliers are re-selected at that line and the solve repeated while they change (at most
//!    [`MAX_ROUNDS`] times).
//!
//! A certificate then proves the optimum on the inlier views.

use super::{linear_line, triangulate_line_views, LineProblem, LineTriangulation};
use crate::consensus::{self, msac, Estimator, Stats};
use crate::error::Result;
use crate::triangulation::conditioning::Similarity;
use crate::triangulation::fractional_residual::{self, FractionalResidual};
#[cfg(doc)]
use crate::triangulation::point::robust::MAX_PAIRS;
use crate::triangulation::point::robust::{pairs, MAX_ROUNDS};
use crate::triangulation::TriangulationOptions;
use nalgebra::Vector6;
use std::time::Duration;

/// The problem of the views `keep` of `problem`.
fn subproblem(problem: &LineProblem, keep: impl Iterator<Item = usize> + Clone) -> LineProblem {
    LineProblem {
        cameras: keep.clone().map(|j| problem.cameras[j]).collect(),
        frames: keep.clone().map(|j| problem.frames[j]).collect(),
        whitenings: keep.map(|j| problem.whitenings[j]).collect(),
    }
}

/// `‖r_j‖²` of `line` (world Plücker coordinates) in every view (`views`: [`LineProblem::views`] in
/// the world frame).
fn squared_errors(views: &[FractionalResidual<2, 6>], line: &Vector6<f64>) -> Vec<f64> {
    views
        .iter()
        .map(|v| fractional_residual::cost(std::slice::from_ref(v), line))
        .collect()
}

/// The line track's part of the sampling loop ([`crate::consensus`]): the pairs of [`pairs`] in order,
/// each pair's line where its two back-projected planes meet, scored by its MSAC score.
struct PairConsensus<'a> {
    problem: &'a LineProblem,
    views: &'a [FractionalResidual<2, 6>],
    tau2: f64,
    pairs: std::vec::IntoIter<(usize, usize)>,
}

impl Estimator for PairConsensus<'_> {
    type Sample = (usize, usize);
    type Model = Vector6<f64>;
    type Score = f64;

    fn sample(&mut self) -> Option<(usize, usize)> {
        self.pairs.next()
    }

    fn models(&mut self, &(a, b): &(usize, usize)) -> Vec<Vector6<f64>> {
        linear_line(&subproblem(self.problem, [a, b].into_iter()))
            .into_iter()
            .collect()
    }

    fn score(&mut self, line: &Vector6<f64>, _: &(usize, usize), _: Option<f64>, _: &Stats) -> Option<f64> {
        Some(msac(squared_errors(self.views, line), self.tau2).0)
    }
}

/// The inlier mask of the best two-view line (step 1); `None` when no pair determines a line.
fn consensus(problem: &LineProblem, views: &[FractionalResidual<2, 6>], tau2: f64) -> Option<Vec<bool>> {
    let mut estimator = PairConsensus {
        problem,
        views,
        tau2,
        pairs: pairs(problem.cameras.len()).into_iter(),
    };
    let outcome = consensus::run(&mut estimator, &consensus::Options::exhaustive(), || Duration::ZERO);
    outcome
        .best
        .map(|(line, _)| squared_errors(views, &line).iter().map(|&e| e <= tau2).collect())
}

/// The track of `problem` with outliers rejected at the whitened threshold `tau` (module docs); the
/// result's `inliers` has one flag per view. Without any pair of views that determines a line, the
/// error of the whole track's linear method ([`linear_line`]).
pub(crate) fn triangulate_line_robust(
    problem: &LineProblem,
    opts: &TriangulationOptions,
    tau: f64,
) -> Result<LineTriangulation> {
    let tau2 = tau * tau;
    let views = problem.views(&Similarity::identity());
    let Some(mut mask) = consensus(problem, &views, tau2) else {
        return linear_line(problem).and_then(|_| triangulate_line_views(problem, opts));
    };
    let mut rounds = 0;
    loop {
        let kept = subproblem(problem, (0..mask.len()).filter(|&j| mask[j]));
        let mut result = triangulate_line_views(&kept, opts)?;
        rounds += 1;
        let next: Vec<bool> = squared_errors(&views, result.plucker.coordinates())
            .iter()
            .map(|&e| e <= tau2)
            .collect();
        if rounds == MAX_ROUNDS || next == mask || next.iter().filter(|&&m| m).count() < 2 {
            result.inliers = Some(mask);
            return Ok(result);
        }
        mask = next;
    }
}
