//! The data as the robust loop sees it, prepared once per call, and the MSAC score of a hypothesis.
//!
//! Errors are in pixels, as in [`crate::pose::reprojection::ReprojectionCost::errors`]:
//! - a point: `e = ‖π(R X + t) − u‖` with `π(x_cam) = K x_cam / z`;
//! - a line: the RMS of the distances of the two observed segment endpoints to the projection of the
//!   3-D line, `e² = (d₁² + d₂²) / 2` (so a line is an inlier when its endpoints are, on average, within
//!   the line threshold of the projected line).
//!
//! A point (a line) with an object point (either object endpoint) at depth `z ≤ 0` has an infinite
//! error: it is an outlier of that pose.
//!
//! With per-observation noise on the correspondences ([`crate::pose::noise`]) the errors are whitened as
//! the reprojection cost's are: `e = ‖W r‖` for a point and each endpoint distance divided by its standard
//! deviation across the line. Through a lens without covariances that makes them distorted pixels (to
//! first order), so the thresholds keep their meaning at the edge of a fisheye; with covariances they
//! are in standard deviations.
//!
//! The MSAC score (Torr & Zisserman 2000) of a pose is `½ Σᵢ min(eᵢ², τᵢ²)`, with `τᵢ` the point or the
//! line threshold: the reprojection cost with each residual capped at its threshold. Lower is better.
//!
//! The points and the lines are stored in a random order drawn once per call (the *slots*), and each
//! hypothesis is verified from a random slot onwards, wrapping around: the correspondences verified
//! first are a random subset, as the sequential test of [`super::sprt`] assumes, and not the same
//! subset for every hypothesis (a good model whose first few slots happen to be outliers would
//! otherwise be rejected every time).

use super::super::candidates::feature;
use super::super::correspondences::Correspondences;
use super::super::minimal::Feature;
use super::super::reprojection::Pose;
use super::sprt::SprtTest;
use crate::camera::Intrinsics;
use crate::error::Result;
use crate::rng::Rng;
use nalgebra::{Matrix2, Matrix3, Vector2, Vector3};

/// Points per batch of the scoring loop.
const LANES: usize = 4;

/// Thresholds of the inlier test, pixels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Thresholds {
    /// Squared point threshold `τ_p²`, px².
    pub point2: f64,
    /// Squared line threshold `τ_l²`, px² (on the mean of the two squared endpoint distances).
    pub line2: f64,
}

/// One point as the scorer needs it: object point (frame of the data) and observed pixel.
#[derive(Debug, Clone, Copy)]
struct ScoredPoint {
    object: [f64; 3],
    pixel: [f64; 2],
}

/// One line: two object points and the two observed pixel endpoints, homogeneous.
#[derive(Debug, Clone, Copy)]
struct ScoredLine {
    object: [Vector3<f64>; 2],
    endpoints: [Vector3<f64>; 2],
}

/// The whitening of a point without noise (unused on the fast path).
const UNIT: [f64; 4] = [1.0, 0.0, 0.0, 1.0];
/// The endpoint covariances of a line without noise (unused on the fast path).
const UNIT_COVARIANCES: [Matrix2<f64>; 2] = [Matrix2::new(1.0, 0.0, 0.0, 1.0); 2];

/// A random order of `n` items: `index[slot]` is the item in a slot, `slot[item]` its inverse.
#[derive(Debug, Clone)]
struct Order {
    index: Vec<usize>,
    slot: Vec<usize>,
}

/// Uniform in `0..n` (`n ≥ 1`; 0 for `n = 0`) by a multiply-shift of 64 random bits (Lemire 2019):
/// no division, bias below `n / 2⁶⁴`.
#[inline(always)]
pub(crate) fn below(rng: &mut Rng, n: usize) -> usize {
    ((rng.next_u64() as u128 * n as u128) >> 64) as usize
}

impl Order {
    /// A uniformly random permutation (Fisher-Yates).
    fn random(n: usize, rng: &mut Rng) -> Order {
        let mut index: Vec<usize> = (0..n).collect();
        for i in (1..n).rev() {
            index.swap(i, below(rng, i + 1));
        }
        let mut slot = vec![0; n];
        for (s, &i) in index.iter().enumerate() {
            slot[i] = s;
        }
        Order { index, slot }
    }
}

/// The outcome of scoring one hypothesis ([`Prepared::evaluate`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Verdict {
    /// Every error evaluated: the MSAC score.
    Score(f64),
    /// The partial score exceeded the bound: the hypothesis cannot beat the best model.
    Beaten,
    /// Rejected by the sequential test after `evaluated` correspondences per kind (points, lines; the
    /// sample's own excluded), `consistent` of them within threshold.
    Rejected {
        evaluated: [usize; 2],
        consistent: [usize; 2],
    },
}

/// The sample's correspondences in the verification order of one hypothesis, to leave them out of
/// the sequential test: per entry the kind (0 points, 1 lines), the rank from the start slot, and
/// whether it is consistent.
struct SampleRanks {
    ranks: [(usize, usize, bool); 3],
}

impl SampleRanks {
    /// `(evaluated, consistent)` sample correspondences of `kind` among the first `done` verified.
    #[inline(always)]
    fn among(&self, kind: usize, done: usize) -> (usize, usize) {
        let mut out = (0, 0);
        for &(k, rank, consistent) in &self.ranks {
            if k == kind && rank < done {
                out.0 += 1;
                out.1 += consistent as usize;
            }
        }
        out
    }

    /// The ranks of the entries of `kind` in increasing order, with whether each is consistent,
    /// padded with `usize::MAX`.
    fn sorted(&self, kind: usize) -> [(usize, bool); 4] {
        let mut out = [(usize::MAX, false); 4];
        let mut n = 0;
        for &(k, rank, consistent) in &self.ranks {
            if k == kind {
                out[n] = (rank, consistent);
                n += 1;
            }
        }
        out[..n].sort_unstable();
        out
    }
}

/// The running `ln λ` of one hypothesis (see [`super::sprt`]): per correspondence verified, the
/// increment of its kind, less those of the sample's own correspondences once they are passed.
struct RunningTest<'a> {
    test: &'a SprtTest,
    log_lambda: f64,
    /// Per kind, the sample's ranks (sorted, padded) and the next one not yet passed.
    pending: [[(usize, bool); 4]; 2],
    next: [usize; 2],
}

impl RunningTest<'_> {
    /// Adds `count` verified correspondences of `kind`, `consistent` of them, `done` verified so far.
    #[inline(always)]
    fn add(&mut self, kind: usize, count: usize, consistent: usize, done: usize) {
        let (a, b) = (self.test.consistent[kind], self.test.inconsistent[kind]);
        self.log_lambda += consistent as f64 * a + (count - consistent) as f64 * b;
        while self.pending[kind][self.next[kind]].0 < done {
            self.log_lambda -= if self.pending[kind][self.next[kind]].1 { a } else { b };
            self.next[kind] += 1;
        }
    }

    fn rejects(&self) -> bool {
        self.log_lambda > self.test.log_a
    }
}

/// Correspondences prepared once: the scorer's arrays (in slot order) and the minimal solvers'
/// features (in the order given).
#[derive(Debug, Clone)]
pub(crate) struct Prepared {
    camera: Intrinsics,
    /// `K⁻ᵀ`: maps a camera-frame line `a × b` to its pixel form.
    k_inv_t: Matrix3<f64>,
    /// Points and lines in slot order (verification), and in the order given (inlier masks).
    points: Vec<ScoredPoint>,
    lines: Vec<ScoredLine>,
    points_given: Vec<ScoredPoint>,
    lines_given: Vec<ScoredLine>,
    /// With noise on the correspondences ([`crate::pose::noise`]): each point's whitening `W`
    /// (row-major), in slot order and in the order given; empty without. Errors are then `‖W r‖`.
    point_whitening: Vec<[f64; 4]>,
    point_whitening_given: Vec<[f64; 4]>,
    /// With noise: each line's endpoint covariances `C` (errors are distances over `√(lᵀ C l)`), in slot
    /// order and in the order given; empty without.
    line_covariances: Vec<[Matrix2<f64>; 2]>,
    line_covariances_given: Vec<[Matrix2<f64>; 2]>,
    /// The correspondences carry noise: points are scored through `point_whitening`.
    weighted: bool,
    point_order: Order,
    line_order: Order,
    /// `[u₀, v₀, u₁, v₁]`: the bounding box of the observed pixels (points and segment endpoints).
    pub window: [f64; 4],
    /// `K⁻¹`: a pixel's bearing, for the points' features ([`Prepared::feature`]).
    k_inv: Matrix3<f64>,
    /// The lines' features, computed once (a segment's interpretation plane can fail; a point's
    /// bearing cannot, and is computed when a sample needs it: most points never are).
    line_features: Vec<Feature>,
}

impl Prepared {
    /// Prepares `corr` (already validated: finite, no zero-length segment), drawing the slot order
    /// from `rng`.
    pub fn new(camera: &Intrinsics, corr: &Correspondences, rng: &mut Rng) -> Result<Prepared> {
        let k_inv = camera.matrix().try_inverse().unwrap_or_else(Matrix3::identity);
        let point_order = Order::random(corr.n_points(), rng);
        let line_order = Order::random(corr.n_lines(), rng);
        let points_given: Vec<ScoredPoint> = corr
            .points2d
            .iter()
            .zip(&corr.points3d)
            .map(|(u, x)| ScoredPoint {
                object: [x.x, x.y, x.z],
                pixel: [u.x, u.y],
            })
            .collect();
        let lines_given: Vec<ScoredLine> = corr
            .lines2d
            .iter()
            .zip(&corr.lines3d)
            .map(|(s2, s3)| ScoredLine {
                object: *s3,
                endpoints: s2.map(|e| Vector3::new(e.x, e.y, 1.0)),
            })
            .collect();
        let line_covariances_given = corr.noise.as_ref().map_or_else(Vec::new, |n| n.lines.clone());
        let line_covariances = if line_covariances_given.is_empty() {
            Vec::new()
        } else {
            line_order.index.iter().map(|&i| line_covariances_given[i]).collect()
        };
        let point_whitening_given: Vec<[f64; 4]> = corr.noise.as_ref().map_or_else(Vec::new, |n| {
            n.points
                .iter()
                .map(|w| [w[(0, 0)], w[(0, 1)], w[(1, 0)], w[(1, 1)]])
                .collect()
        });
        let point_whitening = if point_whitening_given.is_empty() {
            Vec::new()
        } else {
            point_order.index.iter().map(|&i| point_whitening_given[i]).collect()
        };
        let points = point_order.index.iter().map(|&i| points_given[i]).collect();
        let lines = line_order.index.iter().map(|&i| lines_given[i]).collect();
        let np = corr.n_points();
        let line_features = (np..np + corr.n_lines())
            .map(|k| feature(camera, &k_inv, corr, k))
            .collect::<Result<Vec<Feature>>>()?;
        let mut window = [f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY];
        for u in corr.points2d.iter().chain(corr.lines2d.iter().flatten()) {
            window = [
                window[0].min(u.x),
                window[1].min(u.y),
                window[2].max(u.x),
                window[3].max(u.y),
            ];
        }
        Ok(Prepared {
            camera: *camera,
            k_inv_t: k_inv.transpose(),
            points,
            lines,
            points_given,
            lines_given,
            point_whitening,
            point_whitening_given,
            line_covariances,
            line_covariances_given,
            weighted: corr.noise.is_some(),
            point_order,
            line_order,
            window,
            k_inv,
            line_features,
        })
    }

    /// Feature `k` for [`super::super::minimal::solve`] (points first, then lines, in the order
    /// given), as [`feature`] makes it.
    pub fn feature(&self, k: usize) -> Feature {
        match self.points_given.get(k) {
            Some(p) => Feature::Point {
                bearing: self.k_inv * Vector3::new(p.pixel[0], p.pixel[1], 1.0),
                point: Vector3::from(p.object),
            },
            None => self.line_features[k - self.points_given.len()],
        }
    }

    pub fn n_points(&self) -> usize {
        self.points.len()
    }

    pub fn n_lines(&self) -> usize {
        self.lines.len()
    }

    /// Squared pixel error of `point` at `pose` (infinite behind the camera); with `WEIGHTED`, of the
    /// residual whitened by `w` (row-major 2x2).
    #[inline(always)]
    fn point_error2<const WEIGHTED: bool>(&self, pose: &Pose, point: &ScoredPoint, w: &[f64; 4]) -> f64 {
        let (r, t, c) = (&pose.rotation, &pose.translation, &self.camera);
        let [x, y, z] = point.object;
        let pz = r[(2, 0)] * x + r[(2, 1)] * y + r[(2, 2)] * z + t.z;
        let iz = 1.0 / pz;
        let xn = (r[(0, 0)] * x + r[(0, 1)] * y + r[(0, 2)] * z + t.x) * iz;
        let yn = (r[(1, 0)] * x + r[(1, 1)] * y + r[(1, 2)] * z + t.y) * iz;
        let mut du = c.fx * xn + c.skew * yn + c.cx - point.pixel[0];
        let mut dv = c.fy * yn + c.cy - point.pixel[1];
        if WEIGHTED {
            (du, dv) = (w[0] * du + w[1] * dv, w[2] * du + w[3] * dv);
        }
        // A select rather than an early return, so that batches of points stay branch-free.
        if pz > 0.0 {
            du * du + dv * dv
        } else {
            f64::INFINITY
        }
    }

    /// Mean squared distance of the observed endpoints of `line` to its projected line (infinite when
    /// an object endpoint is behind the camera or the line projects to a point).
    /// With `WEIGHTED`, each distance is divided by the endpoint's standard deviation across the line
    /// (`covariances`).
    #[inline(always)]
    fn line_error2<const WEIGHTED: bool>(
        &self,
        pose: &Pose,
        line: &ScoredLine,
        covariances: &[Matrix2<f64>; 2],
    ) -> f64 {
        let a = pose.rotation * line.object[0] + pose.translation;
        let b = pose.rotation * line.object[1] + pose.translation;
        if !(a.z > 0.0 && b.z > 0.0) {
            return f64::INFINITY;
        }
        let l = self.k_inv_t * a.cross(&b);
        let (d1, d2) = (l.dot(&line.endpoints[0]), l.dot(&line.endpoints[1]));
        if WEIGHTED {
            // The variance across the line of each endpoint: lᵀ C l.
            let l12 = Vector2::new(l.x, l.y);
            let (s1, s2) = (l12.dot(&(covariances[0] * l12)), l12.dot(&(covariances[1] * l12)));
            if !(s1 > 0.0 && s2 > 0.0) {
                return f64::INFINITY;
            }
            return 0.5 * (d1 * d1 / s1 + d2 * d2 / s2);
        }
        let scale2 = l.x * l.x + l.y * l.y;
        if !(scale2 > 0.0) {
            return f64::INFINITY;
        }
        0.5 * (d1 * d1 + d2 * d2) / scale2
    }

    /// Squared error of the line in slot `i`.
    #[inline(always)]
    fn slot_line_error2<const WEIGHTED: bool>(&self, pose: &Pose, i: usize) -> f64 {
        let c = if WEIGHTED {
            &self.line_covariances[i]
        } else {
            &UNIT_COVARIANCES
        };
        self.line_error2::<WEIGHTED>(pose, &self.lines[i], c)
    }

    /// Squared error of line `i` in the order given.
    #[inline(always)]
    fn given_line_error2(&self, pose: &Pose, i: usize) -> f64 {
        match self.line_covariances_given.get(i) {
            Some(c) => self.line_error2::<true>(pose, &self.lines_given[i], c),
            None => self.line_error2::<false>(pose, &self.lines_given[i], &UNIT_COVARIANCES),
        }
    }

    /// Squared error of point `i` in the order given.
    #[inline(always)]
    fn given_point_error2(&self, pose: &Pose, i: usize) -> f64 {
        match self.point_whitening_given.get(i) {
            Some(w) => self.point_error2::<true>(pose, &self.points_given[i], w),
            None => self.point_error2::<false>(pose, &self.points_given[i], &UNIT),
        }
    }

    /// Squared error of the point in slot `i`.
    #[inline(always)]
    fn slot_point_error2<const WEIGHTED: bool>(&self, pose: &Pose, i: usize) -> f64 {
        let w = if WEIGHTED { &self.point_whitening[i] } else { &UNIT };
        self.point_error2::<WEIGHTED>(pose, &self.points[i], w)
    }

    /// Squared error of feature `k` (points first, then lines, in the order given).
    fn feature_error2(&self, pose: &Pose, k: usize) -> f64 {
        if k < self.points.len() {
            self.given_point_error2(pose, k)
        } else {
            self.given_line_error2(pose, k - self.points.len())
        }
    }

    /// Squared error of feature `k` (points first, then lines).
    #[cfg(test)]
    pub fn error2(&self, pose: &Pose, k: usize) -> f64 {
        self.feature_error2(pose, k)
    }

    /// The MSAC score `½ Σ min(eᵢ², τᵢ²)` of `pose`, or `None` as soon as the partial sum exceeds
    /// `bound` (the hypothesis cannot beat a model of score `bound`).
    pub fn score(&self, pose: &Pose, tau: &Thresholds, bound: f64) -> Option<f64> {
        match self.evaluate(pose, tau, bound, None, None, [0, 0]).0 {
            Verdict::Score(s) => Some(s),
            _ => None,
        }
    }

    /// Scores `pose`, verifying the points and then the lines each from its `start` slot onwards
    /// (wrapping around), with two early exits checked after every batch of points and every line:
    /// [`Verdict::Beaten`] as soon as the partial MSAC sum exceeds `bound`, and with a `test`,
    /// [`Verdict::Rejected`] as soon as its `ln λ` exceeds `ln A` (the correspondences of `sample`, the
    /// hypothesis's own, are left out of `λ`). Also returns the number of errors evaluated.
    pub fn evaluate(
        &self,
        pose: &Pose,
        tau: &Thresholds,
        bound: f64,
        test: Option<&SprtTest>,
        sample: Option<&[usize; 3]>,
        start: [usize; 2],
    ) -> (Verdict, usize) {
        let (np, nl) = (self.points.len(), self.lines.len());
        let start = [
            if np > 0 { start[0] % np } else { 0 },
            if nl > 0 { start[1] % nl } else { 0 },
        ];
        match test {
            None if self.weighted => self.verify::<false, true>(pose, tau, bound, &SprtTest::NONE, None, start),
            None => self.verify::<false, false>(pose, tau, bound, &SprtTest::NONE, None, start),
            Some(test) => {
                let skip = sample.map(|sample| SampleRanks {
                    ranks: sample.map(|k| {
                        let consistent = self.feature_error2(pose, k) <= if k < np { tau.point2 } else { tau.line2 };
                        if k < np {
                            (0, (self.point_order.slot[k] + np - start[0]) % np, consistent)
                        } else {
                            let slot = self.line_order.slot[k - np];
                            (1, (slot + nl - start[1]) % nl, consistent)
                        }
                    }),
                });
                if self.weighted {
                    self.verify::<true, true>(pose, tau, bound, test, skip.as_ref(), start)
                } else {
                    self.verify::<true, false>(pose, tau, bound, test, skip.as_ref(), start)
                }
            }
        }
    }

    /// [`Prepared::evaluate`], with the sequential test compiled in or out (`TEST`).
    #[inline(always)]
    fn verify<const TEST: bool, const WEIGHTED: bool>(
        &self,
        pose: &Pose,
        tau: &Thresholds,
        bound: f64,
        test: &SprtTest,
        skip: Option<&SampleRanks>,
        start: [usize; 2],
    ) -> (Verdict, usize) {
        let (np, nl) = (self.points.len(), self.lines.len());
        // Compare doubled sums with 2·bound: one multiplication for the whole call.
        let limit = 2.0 * bound;
        let mut sum = 0.0;
        let (mut done, mut consistent) = ([0usize; 2], [0usize; 2]);
        let no_sample = SampleRanks {
            ranks: [(2, 0, false); 3],
        };
        let skip = skip.unwrap_or(&no_sample);
        let mut running = RunningTest {
            test,
            log_lambda: 0.0,
            pending: if TEST {
                [skip.sorted(0), skip.sorted(1)]
            } else {
                [[(usize::MAX, false); 4]; 2]
            },
            next: [0; 2],
        };
        // The verdict of a rejection after `done` / `consistent`, the sample's own left out.
        let rejected = |done: [usize; 2], consistent: [usize; 2]| {
            let ((sp, cp), (sl, cl)) = (skip.among(0, done[0]), skip.among(1, done[1]));
            Verdict::Rejected {
                evaluated: [done[0] - sp, done[1] - sl],
                consistent: [consistent[0] - cp, consistent[1] - cl],
            }
        };
        // Points in batches of LANES without branches inside (the compiler vectorises them), the
        // early exits tested once per batch; the slots from start[0] to the end, then from 0.
        for (from, to) in [(start[0], np), (0, start[0])] {
            let full = to - (to - from) % LANES;
            for i0 in (from..full).step_by(LANES) {
                let e2: [f64; LANES] = std::array::from_fn(|l| self.slot_point_error2::<WEIGHTED>(pose, i0 + l));
                sum += e2.iter().map(|e| e.min(tau.point2)).sum::<f64>();
                done[0] += LANES;
                if sum > limit {
                    return (Verdict::Beaten, done[0]);
                }
                if TEST {
                    let c = e2.iter().filter(|&&e| e <= tau.point2).count();
                    consistent[0] += c;
                    running.add(0, LANES, c, done[0]);
                    if running.rejects() {
                        return (rejected(done, consistent), done[0]);
                    }
                }
            }
            for i in full..to {
                let e2 = self.slot_point_error2::<WEIGHTED>(pose, i);
                sum += e2.min(tau.point2);
                let c = (e2 <= tau.point2) as usize;
                consistent[0] += c;
                done[0] += 1;
                if TEST {
                    running.add(0, 1, c, done[0]);
                }
            }
        }
        for i in (start[1]..nl).chain(0..start[1]) {
            let e2 = self.slot_line_error2::<WEIGHTED>(pose, i);
            sum += e2.min(tau.line2);
            let c = (e2 <= tau.line2) as usize;
            consistent[1] += c;
            done[1] += 1;
            if sum > limit {
                return (Verdict::Beaten, done[0] + done[1]);
            }
            if TEST {
                running.add(1, 1, c, done[1]);
                if running.rejects() {
                    return (rejected(done, consistent), done[0] + done[1]);
                }
            }
        }
        if sum > limit {
            return (Verdict::Beaten, np + nl);
        }
        (Verdict::Score(0.5 * sum), np + nl)
    }

    /// The score of the empty model (every correspondence an outlier): `½ (n_p τ_p² + n_l τ_l²)`, a
    /// kind without correspondences adding nothing (also when its `τ²` overflows to infinity).
    pub fn all_outlier_score(&self, tau: &Thresholds) -> f64 {
        let term = |n: usize, tau2: f64| if n == 0 { 0.0 } else { n as f64 * tau2 };
        0.5 * (term(self.points.len(), tau.point2) + term(self.lines.len(), tau.line2))
    }

    /// Inlier masks at `pose`: `eᵢ² ≤ τᵢ²` (points, lines, in the order given).
    pub fn inliers(&self, pose: &Pose, tau: &Thresholds) -> (Vec<bool>, Vec<bool>) {
        let points = self
            .points_given
            .iter()
            .enumerate()
            .map(|(i, _)| self.given_point_error2(pose, i) <= tau.point2)
            .collect();
        let lines = self
            .lines_given
            .iter()
            .enumerate()
            .map(|(i, _)| self.given_line_error2(pose, i) <= tau.line2)
            .collect();
        (points, lines)
    }

    /// True when every object point of the sample's features is in front of the camera at `pose`
    /// (depth `z > 0`): a pose that puts its own sample behind the camera is not worth scoring.
    pub fn sample_in_front(&self, pose: &Pose, sample: &[usize; 3]) -> bool {
        let depth = |x: &Vector3<f64>| pose.rotation.row(2).transpose().dot(x) + pose.translation.z;
        sample.iter().all(|&k| {
            if k < self.points.len() {
                let [x, y, z] = self.points_given[k].object;
                depth(&Vector3::new(x, y, z)) > 0.0
            } else {
                self.lines_given[k - self.points.len()]
                    .object
                    .iter()
                    .all(|x| depth(x) > 0.0)
            }
        })
    }
}

/// The correspondences of `corr` selected by the masks.
pub(crate) fn subset(corr: &Correspondences, points: &[bool], lines: &[bool]) -> Correspondences {
    fn pick<T: Copy>(values: &[T], mask: &[bool]) -> Vec<T> {
        values.iter().zip(mask).filter(|(_, &m)| m).map(|(v, _)| *v).collect()
    }
    Correspondences {
        points2d: pick::<Vector2<f64>>(&corr.points2d, points),
        points3d: pick(&corr.points3d, points),
        lines2d: pick(&corr.lines2d, lines),
        lines3d: pick(&corr.lines3d, lines),
        noise: corr.noise.as_ref().map(|n| n.subset(points, lines)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pose::reprojection::ReprojectionCost;
    use crate::rng::Rng;
    use crate::synthetic::{random_scene, SceneKind};

    #[test]
    fn errors_match_the_reprojection_cost_and_the_score_caps_them() {
        let scene = random_scene(SceneKind::General, 20, 8, 3);
        let corr = scene.noisy(2.0, true, &mut Rng::new(4));
        let prepared = Prepared::new(&scene.camera.intrinsics(), &corr, &mut Rng::new(5)).unwrap();
        let pose = Pose::new(scene.rotation, scene.translation);
        let reference = ReprojectionCost::of(&scene.camera.intrinsics(), &corr).errors(&pose);
        for (k, e) in reference.iter().enumerate() {
            let ours = prepared.error2(&pose, k).sqrt();
            assert!((ours - e).abs() <= 1e-9 * (1.0 + e), "feature {k}: {ours} vs {e}");
        }
        let tau = Thresholds {
            point2: 4.0,
            line2: 9.0,
        };
        let expected: f64 = reference
            .iter()
            .enumerate()
            .map(|(k, e)| 0.5 * (e * e).min(if k < 20 { 4.0 } else { 9.0 }))
            .sum();
        let score = prepared.score(&pose, &tau, f64::INFINITY).unwrap();
        assert!((score - expected).abs() <= 1e-9 * expected);
        // The early exit: a bound below the score stops the sum.
        assert_eq!(prepared.score(&pose, &tau, 0.5 * score), None);
        // Behind the camera everything is an outlier.
        let behind = Pose::new(scene.rotation, scene.translation - Vector3::new(0.0, 0.0, 100.0));
        let all_out = prepared.score(&behind, &tau, f64::INFINITY).unwrap();
        assert_eq!(all_out, prepared.all_outlier_score(&tau));
        let (p, l) = prepared.inliers(&behind, &tau);
        assert!(p.iter().chain(&l).all(|m| !m));
    }
}
