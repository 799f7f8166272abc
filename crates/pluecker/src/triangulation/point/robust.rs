//! Outlier observations in a point track: a consensus over the track's views, then the certified
//! optimum of eq. 19 on the inliers ([`TriangulationOptions::outlier_threshold`]).
//!
//! 1. **Consensus.** Every pair of views (or [`MAX_PAIRS`] of them, drawn with a fixed seed, for long
//!    tracks) gives a two-view point: the linear point, or, when that does not fit both views of the
//!    pair within `τ`, the local minimum of eq. 19 over the pair started from it (the linear point
//!    weighs the views by depth, so a pair whose optimum fits can look inconsistent at it). Its MSAC
//!    score is `Σ_j min(r_j², τ²)` over all views, with `r_j` the whitened residual of eq. 18 in view
//!    `j` (`τ²` for a view the point is behind). The lowest score wins. A single outlier in a track of
//!    3 or more views cannot win: any pair of inliers explains every inlier view. Two observations in
//!    one image give no two-view point (their linear point is the camera centre) and are skipped.
//! 2. **Optimum on the inliers.** The views with `r_j ≤ τ` (and in front) are solved by the chosen
//!    method, certificate included; the inliers are then re-selected at that point, and the solve
//!    repeated while they change (at most [`MAX_ROUNDS`] times).
//!
//! The certificate then proves the optimum *on the inlier views*: which views those are is a
//! decision of the consensus, not part of what is certified. Fewer than 2 inliers is
//! [`Status::TooFewInliers`].

use super::cost::PointView;
use super::linear::{accumulate_dlt, solve_dlt, LinearPoint, WorldFrame};
use super::{local_solution, solve_views, PointTriangulation};
use crate::rng::Rng;
use crate::triangulation::{Report, Status, TriangulationOptions};
use nalgebra::{Matrix4, Vector3};
use std::time::Instant;

/// Pairs of views tried by the consensus at most: all of them up to 21 views.
pub const MAX_PAIRS: usize = 210;
/// Re-selections of the inliers at the optimum at most.
pub const MAX_ROUNDS: usize = 3;

/// `(‖r_j‖², in front)` of `x` in `view`.
fn squared_error(view: &PointView, x: &Vector3<f64>) -> f64 {
    if view.depth(x) > 0.0 {
        view.residual(x).norm_squared()
    } else {
        f64::INFINITY
    }
}

/// The inlier mask of `x`: `‖r_j‖ ≤ τ` and in front.
fn inliers_at(views: &[PointView], x: &Vector3<f64>, tau2: f64) -> Vec<bool> {
    views.iter().map(|v| squared_error(v, x) <= tau2).collect()
}

/// The pairs of views the consensus tries: all when there are at most [`MAX_PAIRS`], else that many
/// distinct pairs drawn with a seed fixed by the track length (reproducible).
pub(crate) fn pairs(n: usize) -> Vec<(usize, usize)> {
    let all = n * (n - 1) / 2;
    if all <= MAX_PAIRS {
        return (0..n).flat_map(|a| (a + 1..n).map(move |b| (a, b))).collect();
    }
    let mut rng = Rng::new(n as u64);
    let mut chosen = std::collections::HashSet::with_capacity(MAX_PAIRS);
    while chosen.len() < MAX_PAIRS {
        let (a, b) = (rng.below(n), rng.below(n));
        if a != b {
            chosen.insert((a.min(b), a.max(b)));
        }
    }
    let mut out: Vec<_> = chosen.into_iter().collect();
    out.sort_unstable();
    out
}

/// The point of the pair of views `(a, b)` for the consensus (module docs): the linear point, or the
/// pair's local minimum from it when the linear point does not fit both views within `τ`; `None`
/// when there is no finite point in front of both.
fn pair_point(
    views: &[PointView],
    (a, b): (usize, usize),
    frame: &WorldFrame,
    tau2: f64,
    opts: &TriangulationOptions,
) -> Option<Vector3<f64>> {
    let pair = [views[a], views[b]];
    let mut g = Matrix4::zeros();
    accumulate_dlt(&mut g, &pair[0], frame);
    accumulate_dlt(&mut g, &pair[1], frame);
    let linear = solve_dlt(&g, frame);
    let LinearPoint::Finite(x) = linear else {
        return None;
    };
    let fits = |x: &Vector3<f64>| pair.iter().all(|v| squared_error(v, x) <= tau2);
    if !pair.iter().all(|v| v.depth(&x) > 0.0) {
        return None;
    }
    if fits(&x) {
        return Some(x);
    }
    let (optimum, _, _) = local_solution(&pair, frame, linear, opts)?;
    Some(if pair.iter().all(|v| v.depth(&optimum) > 0.0) && fits(&optimum) {
        optimum
    } else {
        x
    })
}

/// The consensus of step 1: the inlier mask of the best two-view point (`None` when no pair gives a
/// finite point in front of its two views).
pub(crate) fn consensus(
    views: &[PointView],
    frame: &WorldFrame,
    tau2: f64,
    opts: &TriangulationOptions,
) -> Option<Vec<bool>> {
    let mut best: Option<(f64, Vector3<f64>)> = None;
    for pair in pairs(views.len()) {
        let Some(x) = pair_point(views, pair, frame, tau2, opts) else {
            continue;
        };
        let score: f64 = views.iter().map(|v| squared_error(v, &x).min(tau2)).sum();
        if best.map_or(true, |(s, _)| score < s) {
            best = Some((score, x));
        }
    }
    best.map(|(_, x)| inliers_at(views, &x, tau2))
}

/// The track `views` with outliers rejected at the whitened threshold `tau` (module docs); the
/// result's `inliers` has one flag per view.
pub(crate) fn solve_views_robust(
    views: &[PointView],
    frame: &WorldFrame,
    opts: &TriangulationOptions,
    tau: f64,
    started: Instant,
) -> PointTriangulation {
    let tau2 = tau * tau;
    let too_few = |mask: Vec<bool>| {
        let mut report = Report::new(opts.method);
        report.status = Status::TooFewInliers;
        report.time_seconds = started.elapsed().as_secs_f64();
        PointTriangulation {
            point: Vector3::repeat(f64::NAN),
            covariance: None,
            report,
            inliers: Some(mask),
        }
    };
    let mut mask = match consensus(views, frame, tau2, opts) {
        Some(mask) if mask.iter().filter(|&&m| m).count() >= 2 => mask,
        other => return too_few(other.unwrap_or_else(|| vec![false; views.len()])),
    };
    let mut result;
    let mut rounds = 0;
    loop {
        let subset: Vec<PointView> = views.iter().zip(&mask).filter(|(_, &m)| m).map(|(v, _)| *v).collect();
        result = solve_views(&subset, frame, opts, started);
        rounds += 1;
        if !result.point.iter().all(|v| v.is_finite()) || rounds == MAX_ROUNDS {
            break;
        }
        let next = inliers_at(views, &result.point, tau2);
        if next == mask || next.iter().filter(|&&m| m).count() < 2 {
            break;
        }
        mask = next;
    }
    result.inliers = Some(mask);
    result
}
