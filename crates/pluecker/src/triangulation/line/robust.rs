//! Outlier observations in a line track ([`TriangulationOptions::outlier_threshold`]), as for points
//! ([`crate::triangulation::point::robust`]):
//!
//! 1. **Consensus.** Every pair of views (or [`MAX_PAIRS`] seeded ones) gives the line where its two
//!    back-projected planes meet (the linear method on two views); its MSAC score is
//!    `Σ_j min(‖r_j‖², τ²)` over all views, with `r_j` the whitened residual of eq. 18 in view `j`. The
//!    lowest score wins; its two views fit it exactly, so at least two inliers always remain.
//! 2. **Optimum on the inliers.** The views with `‖r_j‖ ≤ τ` are solved by the chosen method; the
//!    inliers are re-selected at that line and the solve repeated while they change (at most
//!    [`MAX_ROUNDS`] times).
//!
//! A certificate then proves the optimum on the inlier views.

use super::{linear_line, triangulate_line_views, LineProblem, LineTriangulation};
use crate::error::Result;
use crate::triangulation::conditioning::Similarity;
use crate::triangulation::fraction::{self, FractionalResidual};
use crate::triangulation::point::robust::{pairs, MAX_ROUNDS};
use crate::triangulation::TriangulationOptions;
use nalgebra::Vector6;

pub use crate::triangulation::point::robust::MAX_PAIRS;

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
        .map(|v| fraction::cost(std::slice::from_ref(v), line))
        .collect()
}

/// The inlier mask of the best two-view line (step 1); `None` when no pair determines a line.
fn consensus(problem: &LineProblem, views: &[FractionalResidual<2, 6>], tau2: f64) -> Option<Vec<bool>> {
    let mut best: Option<(f64, Vec<f64>)> = None;
    for (a, b) in pairs(problem.cameras.len()) {
        let Ok(line) = linear_line(&subproblem(problem, [a, b].into_iter())) else {
            continue;
        };
        let errors = squared_errors(views, &line);
        let score: f64 = errors
            .iter()
            .map(|e| if e.is_finite() { e.min(tau2) } else { tau2 })
            .sum();
        if best.as_ref().map_or(true, |(s, _)| score < *s) {
            best = Some((score, errors));
        }
    }
    best.map(|(_, errors)| errors.iter().map(|&e| e <= tau2).collect())
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
