//! Outlier observations in a point track: a consensus over the track's views, then the certified
//! optimum of eq. 19 on the inliers ([`TriangulationOptions::outlier_threshold`]).
//!
//! 1. **Consensus.** Every pair of views (or [`MAX_PAIRS`] of them, drawn with a fixed seed, for long
//!    tracks) gives a two-view point: the linear point, or, when that does not fit both views of the
//!    pair within `τ`, the local minimum of eq. 19 over the pair started from it (the linear point
//!    weighs the views by depth, so a pair whose optimum fits can look inconsistent at it). Its MSAC
//!    score is `Σ_j min(r_j², τ²)` over all views, with `r_j` the whitened residual of eq. 18 in view
//!    `j` (`τ²` for a view the point is behind). The lowest score among the points with at least two
//!    views within `τ` wins (any point when none has two). A single outlier in a track of
//!    3 or more views cannot win: any pair of inliers explains every inlier view. Two observations in
//!    one image give no two-view point (their linear point is the camera centre) and are skipped.
//!    The pairs run through the sampling loop shared with the robust pose (`crate::consensus`), every
//!    pair in order, without an adaptive stop.
//! 2. **Optimum on the inliers.** The views with `r_j ≤ τ` (and in front) are solved by the chosen
//!    method, certificate included; the inliers are then re-selected at that point, and the solve
//!    repeated while they change (at most [`MAX_ROUNDS`] times).
//!
//! **Through a lens** ([`super::lens`]) the linear and local stages run on the first-order views
//! (undistorted pixels), but every decision is taken in the images' own pixels: `r_j` is the exact
//! whitened residual of the observed (distorted) pixel ([`super::lens::LensView`]), in the score, in
//! "fits" and in the re-selection; and when neither the linear point nor the pair's first-order
//! minimum fits the pair within `τ` there, the pair's point is refined on the pair's exact cost (the
//! undistortion stretches the image up to 10x at an 80° fisheye edge or near a SIMPLE_RADIAL fold, and
//! the stretch changes across a residual: first-order residuals there are off by 10-30 %, so a pair
//! that fits exactly can misfit at its first-order points). The exact stage of
//! `super::lens::through_lenses` then re-selects the inliers at the exact optimum. Both kinds of
//! track go through the one routine here, by `RobustTrack`.
//!
//! The certificate then proves the optimum *on the inlier views*: which views those are is a
//! decision of the consensus, not part of what is certified. Fewer than 2 inliers is
//! [`Status::TooFewInliers`]: none of the points tried (each pair's linear point and minima) has two
//! views within `τ`.

use super::cost::PointView;
use super::linear::{accumulate_dlt, solve_dlt, LinearPoint, WorldFrame};
use super::{local_solution, solve_views, PointTriangulation};
use crate::consensus::{self, msac, Estimator, Stats};
use crate::optim::Summary;
use crate::rng::Rng;
use crate::triangulation::{CostKind, Report, Status, TriangulationOptions};
use nalgebra::{Matrix4, Vector3};
use std::time::{Duration, Instant};

/// Pairs of views tried by the consensus at most: all of them up to 21 views.
pub const MAX_PAIRS: usize = 210;
/// Re-selections of the inliers at the optimum at most.
pub const MAX_ROUNDS: usize = 3;

/// The exact stage's re-selection (points and lines through a lens): the inliers become the views
/// within `τ` at the optimum `x` (`squared(j, x)` the squared whitened residual of view `j`), and
/// `solve(flags, x)` re-solves on them from `x` while they change, at most [`MAX_ROUNDS`] times; the
/// solves' iterations add to `summary`, whose termination becomes the last solve's. Stops early when
/// fewer than two views would be left or `solve` gives up (`None`). Returns the last optimum.
pub(crate) fn reselect_at_optimum<X>(
    flags: &mut Vec<bool>,
    mut x: X,
    tau: f64,
    summary: &mut Summary,
    squared: impl Fn(usize, &X) -> f64,
    mut solve: impl FnMut(&[bool], &X) -> Option<(X, Summary)>,
) -> X {
    for _ in 0..MAX_ROUNDS {
        let next: Vec<bool> = (0..flags.len()).map(|j| squared(j, &x) <= tau * tau).collect();
        if next == *flags || next.iter().filter(|&&m| m).count() < 2 {
            break;
        }
        *flags = next;
        let Some((again, work)) = solve(flags, &x) else {
            break;
        };
        summary.iterations += work.iterations;
        summary.termination = work.termination;
        x = again;
    }
    x
}

/// A track's views as the consensus sees them (module docs): the first-order views that the linear
/// and local stages solve, each view's own residual, and the minimum of a pair's own cost. Pinhole
/// views are their own first order.
pub(crate) trait RobustTrack {
    /// The first-order views, one per observation.
    fn first_order(&self) -> &[PointView];
    /// `‖r_j(x)‖²`, the whitened residual of view `j` in its own pixels; `∞` behind the camera.
    fn squared_error(&self, j: usize, x: &Vector3<f64>) -> f64;
    /// The local minimum of the pair `(a, b)`'s own cost from `x0` (finite there), or `None` when that
    /// cost is the first-order one, whose minimum the consensus already has.
    fn refine_pair(&self, pair: (usize, usize), x0: &Vector3<f64>, opts: &TriangulationOptions)
        -> Option<Vector3<f64>>;
}

impl RobustTrack for [PointView] {
    fn first_order(&self) -> &[PointView] {
        self
    }

    fn squared_error(&self, j: usize, x: &Vector3<f64>) -> f64 {
        let view = &self[j];
        if view.depth(x) > 0.0 {
            view.residual(x).norm_squared()
        } else {
            f64::INFINITY
        }
    }

    fn refine_pair(&self, _: (usize, usize), _: &Vector3<f64>, _: &TriangulationOptions) -> Option<Vector3<f64>> {
        None
    }
}

/// The inlier mask of `x`: `‖r_j‖ ≤ τ` and in front.
fn inliers_at<T: RobustTrack + ?Sized>(track: &T, x: &Vector3<f64>, tau2: f64) -> Vec<bool> {
    (0..track.first_order().len())
        .map(|j| track.squared_error(j, x) <= tau2)
        .collect()
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
/// pair's local minimum from it (first-order, then, through a lens, exact) when the linear point does
/// not fit both views within `τ`; `None` when there is no finite point in front of both.
fn pair_point<T: RobustTrack + ?Sized>(
    track: &T,
    (a, b): (usize, usize),
    frame: &WorldFrame,
    tau2: f64,
    opts: &TriangulationOptions,
) -> Option<Vector3<f64>> {
    let first = track.first_order();
    let pair = [first[a], first[b]];
    let mut g = Matrix4::zeros();
    accumulate_dlt(&mut g, &pair[0], frame);
    accumulate_dlt(&mut g, &pair[1], frame);
    let linear = solve_dlt(&g, frame);
    let LinearPoint::Finite(x) = linear else {
        return None;
    };
    let errors = |x: &Vector3<f64>| [track.squared_error(a, x), track.squared_error(b, x)];
    let fits = |x: &Vector3<f64>| errors(x).iter().all(|&e| e <= tau2);
    if !pair.iter().all(|v| v.depth(&x) > 0.0) {
        return None;
    }
    if fits(&x) {
        return Some(x);
    }
    let (optimum, _, _) = local_solution(&pair, frame, linear, opts)?;
    let in_front = pair.iter().all(|v| v.depth(&optimum) > 0.0);
    if in_front && fits(&optimum) {
        return Some(optimum);
    }
    // Through a lens: the pair's exact minimum, from its first-order one where that is in front.
    let start = if in_front && errors(&optimum).iter().all(|e| e.is_finite()) {
        optimum
    } else {
        x
    };
    match track.refine_pair((a, b), &start, opts) {
        Some(exact) if fits(&exact) => Some(exact),
        _ => Some(x),
    }
}

/// The point track's part of the sampling loop ([`crate::consensus`]): the pairs of [`pairs`] in
/// order, each pair's point ([`pair_point`]), scored by `(fewer than two inliers, MSAC score)` so that
/// a point with two inliers beats any with fewer.
struct PairConsensus<'a, T: RobustTrack + ?Sized> {
    track: &'a T,
    frame: &'a WorldFrame,
    tau2: f64,
    opts: &'a TriangulationOptions,
    pairs: std::vec::IntoIter<(usize, usize)>,
}

impl<T: RobustTrack + ?Sized> Estimator for PairConsensus<'_, T> {
    type Sample = (usize, usize);
    type Model = Vector3<f64>;
    type Score = (bool, f64);

    fn sample(&mut self) -> Option<(usize, usize)> {
        self.pairs.next()
    }

    fn models(&mut self, &pair: &(usize, usize)) -> Vec<Vector3<f64>> {
        pair_point(self.track, pair, self.frame, self.tau2, self.opts)
            .into_iter()
            .collect()
    }

    fn score(
        &mut self,
        x: &Vector3<f64>,
        _: &(usize, usize),
        _: Option<(bool, f64)>,
        _: &Stats,
    ) -> Option<(bool, f64)> {
        let errors = (0..self.track.first_order().len()).map(|j| self.track.squared_error(j, x));
        let (score, inliers) = msac(errors, self.tau2);
        Some((inliers < 2, score))
    }
}

/// The consensus of step 1: the inlier mask of the best two-view point (`None` when no pair gives a
/// finite point in front of its two views).
pub(crate) fn consensus<T: RobustTrack + ?Sized>(
    track: &T,
    frame: &WorldFrame,
    tau2: f64,
    opts: &TriangulationOptions,
) -> Option<Vec<bool>> {
    let mut estimator = PairConsensus {
        track,
        frame,
        tau2,
        opts,
        pairs: pairs(track.first_order().len()).into_iter(),
    };
    let outcome = consensus::run(&mut estimator, &consensus::Options::exhaustive(), || Duration::ZERO);
    outcome.best.map(|(x, _)| inliers_at(track, &x, tau2))
}

/// The track with outliers rejected at the whitened threshold `tau` (module docs), solved on its
/// first-order views; the result's `inliers` has one flag per view.
pub(crate) fn solve_views_robust<T: RobustTrack + ?Sized>(
    track: &T,
    frame: &WorldFrame,
    opts: &TriangulationOptions,
    tau: f64,
    started: Instant,
) -> PointTriangulation {
    let tau2 = tau * tau;
    let too_few = |mask: Vec<bool>| {
        let mut report = Report::new(opts.method, CostKind::Reprojection);
        report.status = Status::TooFewInliers;
        report.time_seconds = started.elapsed().as_secs_f64();
        PointTriangulation {
            point: Vector3::repeat(f64::NAN),
            covariance: None,
            report,
            inliers: Some(mask),
        }
    };
    let views = track.first_order();
    let mut mask = match consensus(track, frame, tau2, opts) {
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
        let next = inliers_at(track, &result.point, tau2);
        if next == mask || next.iter().filter(|&&m| m).count() < 2 {
            break;
        }
        mask = next;
    }
    result.inliers = Some(mask);
    result
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix2, Matrix3, Matrix3x4, Vector2};

    /// A track whose own residuals are its first-order ones whitened by `scale[j]` more (a stand-in
    /// for lenses whose exact residuals differ from the first-order ones).
    struct RewhitenedTrack {
        first: Vec<PointView>,
        own: Vec<PointView>,
    }

    impl RobustTrack for RewhitenedTrack {
        fn first_order(&self) -> &[PointView] {
            &self.first
        }
        fn squared_error(&self, j: usize, x: &Vector3<f64>) -> f64 {
            self.own.as_slice().squared_error(j, x)
        }
        fn refine_pair(&self, _: (usize, usize), _: &Vector3<f64>, _: &TriangulationOptions) -> Option<Vector3<f64>> {
            None
        }
    }

    /// The centre of [`camera`].
    fn centre(angle: f64, distance: f64) -> Vector3<f64> {
        Vector3::new(angle.sin(), 0.2, angle.cos()) * distance
    }

    /// `K [R | −R C]`, f = 1000 px, the camera at `distance` from the origin at `angle` about the
    /// vertical, looking at the origin.
    fn camera(angle: f64, distance: f64) -> Matrix3x4<f64> {
        let centre = centre(angle, distance);
        let z = (-centre).normalize();
        let x = Vector3::y().cross(&z).normalize();
        let r = Matrix3::from_rows(&[x.transpose(), z.cross(&x).transpose(), z.transpose()]);
        let k = Matrix3::new(1000.0, 0.0, 500.0, 0.0, 1000.0, 500.0, 0.0, 0.0, 1.0);
        let mut rt = Matrix3x4::zeros();
        rt.fixed_view_mut::<3, 3>(0, 0).copy_from(&r);
        rt.set_column(3, &(-(r * centre)));
        k * rt
    }

    fn project(p: &Matrix3x4<f64>, point: &Vector3<f64>) -> Vector2<f64> {
        let h = p * point.push(1.0);
        Vector2::new(h.x / h.z, h.y / h.z)
    }

    /// `Σ_j min(‖r_j(x)‖², τ²)`, written out from the views' residuals.
    fn msac(views: &[PointView], x: &Vector3<f64>, tau2: f64) -> f64 {
        views.iter().map(|v| v.residual(x).norm_squared().min(tau2)).sum()
    }

    #[test]
    fn the_consensus_ranks_by_the_tracks_own_residuals() {
        // Views 0-1 see X, views 2-3 see Y, 0.5 apart (~100 px): two consensus pairs. X's pair is 5x
        // less consistent in first-order pixels, but its own residuals are 10x smaller: ranked by the
        // own residuals X's pair wins, ranked to first order Y's would.
        let tau2 = 16.0;
        let (x, y) = (Vector3::zeros(), Vector3::new(0.4, 0.3, -0.2));
        let cameras: Vec<_> = [0.0f64, 1.2, 2.4, 3.6].iter().map(|&a| camera(a, 5.0)).collect();
        let pixels = [
            project(&cameras[0], &x),
            project(&cameras[1], &x) + Vector2::new(5.0, -4.0),
            project(&cameras[2], &y),
            project(&cameras[3], &y) + Vector2::new(1.0, -0.8),
        ];
        let views = |scale: [f64; 4]| -> Vec<PointView> {
            (0..4)
                .map(|j| PointView::new(&cameras[j], &pixels[j], &(Matrix2::identity() * scale[j])))
                .collect()
        };
        let track = RewhitenedTrack {
            first: views([1.0; 4]),
            own: views([0.1, 0.1, 1.0, 1.0]),
        };
        let centres: Vec<Vector3<f64>> = [0.0f64, 1.2, 2.4, 3.6].iter().map(|&a| centre(a, 5.0)).collect();
        let frame = WorldFrame::from_centres(&centres);
        let opts = TriangulationOptions::default();
        let at_x = pair_point(&track, (0, 1), &frame, tau2, &opts).unwrap();
        let at_y = pair_point(&track, (2, 3), &frame, tau2, &opts).unwrap();
        // The premise, from the views' residuals: the rankings disagree.
        assert!(msac(&track.own, &at_x, tau2) < msac(&track.own, &at_y, tau2));
        assert!(msac(&track.first, &at_x, tau2) > msac(&track.first, &at_y, tau2));
        assert_eq!(
            consensus(&track, &frame, tau2, &opts),
            Some(vec![true, true, false, false])
        );
    }

    #[test]
    fn a_pair_that_fits_beats_a_point_with_a_single_inlier() {
        // Views 0-1 see the origin with residuals near τ: their pair fits, MSAC score ≈ 2·3.6² + τ².
        // View 2's observation is 800 px off, but its own residuals are 200x smaller than its
        // first-order ones (`RewhitenedTrack`): a pair with view 2 gives a point where view 2 alone fits,
        // scoring ≈ 2τ² + small, below the fitting pair. Preferring two inliers keeps the track.
        let tau2 = 16.0;
        let angles = [0.0f64, 1.0, 2.2];
        let cameras: Vec<_> = angles.iter().map(|&a| camera(a, 5.0)).collect();
        let pixels = [
            project(&cameras[0], &Vector3::zeros()) + Vector2::new(0.0, 3.6),
            project(&cameras[1], &Vector3::zeros()) + Vector2::new(0.0, -3.6),
            project(&cameras[2], &Vector3::zeros()) + Vector2::new(0.0, 800.0),
        ];
        let views = |scale: [f64; 3]| -> Vec<PointView> {
            (0..3)
                .map(|j| PointView::new(&cameras[j], &pixels[j], &(Matrix2::identity() * scale[j])))
                .collect()
        };
        let track = RewhitenedTrack {
            first: views([1.0; 3]),
            own: views([1.0, 1.0, 0.005]),
        };
        let centres: Vec<Vector3<f64>> = angles.iter().map(|&a| centre(a, 5.0)).collect();
        let frame = WorldFrame::from_centres(&centres);
        let opts = TriangulationOptions::default();
        let inliers = |x: &Vector3<f64>| {
            track
                .own
                .iter()
                .filter(|v| v.depth(x) > 0.0 && v.residual(x).norm_squared() <= tau2)
                .count()
        };
        // The premise, from the views' residuals: a point with a single inlier scores below the
        // fitting pair's point.
        let fitting = pair_point(&track, (0, 1), &frame, tau2, &opts).unwrap();
        assert_eq!(inliers(&fitting), 2);
        let lone = [(0, 2), (1, 2)]
            .iter()
            .filter_map(|&pair| pair_point(&track, pair, &frame, tau2, &opts))
            .find(|x| inliers(x) == 1 && msac(&track.own, x, tau2) < msac(&track.own, &fitting, tau2));
        assert!(lone.is_some(), "no point with a single inlier outscores the pair");
        assert_eq!(consensus(&track, &frame, tau2, &opts), Some(vec![true, true, false]));
    }
}
