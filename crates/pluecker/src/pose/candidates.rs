//! Starting candidates of the pose pipeline, beside the algebraic estimator's answer: the poses of the
//! minimal solvers ([`super::minimal`]) on a few well-spread samples of three correspondences.
//!
//! Why: the reprojection error has several local minima where the data are weak — a narrow field of
//! view (the near-affine "Necker" twin), few correspondences, planar objects, lines only — and the
//! algebraic stage followed by the refinement converges to one of them. A minimal sample whose three
//! correspondences are exact up to noise has among its (at most 4 or 8) poses one in the basin of the
//! true pose, whatever the other minima; its twin, when one exists, comes out of the same polynomial.
//! So the global minimum is searched over every minimum the refinement reaches from these poses.
//!
//! Which samples: with at most [`EXHAUSTIVE_TRIPLES`] triples of correspondences every triple is used
//! (4-6 correspondences: every minimum of every sample); otherwise the triples of [`SAMPLE_POOL`]
//! seeded random draws in decreasing image footprint (a wide triangle in the image conditions the
//! minimal problem best): the first [`SPREAD_SAMPLES`] are the main samples, the rest a reserve that
//! the search uses only while no minimum has every point in front of the camera. The draws are seeded
//! ([`crate::rng::Rng`], seed 0): the same data give the same candidates.

use super::correspondences::{object_points, Correspondences};
use super::minimal::{solve, Feature};
use super::reprojection::{count_behind, Pose, ReprojectionCost};
use crate::camera::Intrinsics;
use crate::error::Result;
use crate::rng::Rng;
use nalgebra::{Matrix3, Vector2, Vector3};

/// Up to this many triples of correspondences, every triple is a sample (C(6, 3) = 20).
pub const EXHAUSTIVE_TRIPLES: usize = 20;
/// Main samples when the triples are more than [`EXHAUSTIVE_TRIPLES`].
pub const SPREAD_SAMPLES: usize = 4;
/// Random triples among which the [`SPREAD_SAMPLES`] widest are the main samples (the others, the
/// reserve, in decreasing footprint).
pub const SAMPLE_POOL: usize = 24;

/// The image position that stands for each correspondence in the spread measure (points first, then
/// lines): a point's pixel, a segment's midpoint.
pub fn positions(corr: &Correspondences) -> Vec<Vector2<f64>> {
    let points = corr.points2d.iter().copied();
    points.chain(corr.lines2d.iter().map(|s| 0.5 * (s[0] + s[1]))).collect()
}

/// Correspondence `k` of `corr` (points first, then lines) as a minimal-solver feature: a camera-frame
/// bearing, or the unit normal of the interpretation plane (an error for a zero-length segment).
pub fn feature(camera: &Intrinsics, k_inv: &Matrix3<f64>, corr: &Correspondences, k: usize) -> Result<Feature> {
    if k < corr.n_points() {
        let u = corr.points2d[k];
        return Ok(Feature::Point {
            bearing: k_inv * Vector3::new(u.x, u.y, 1.0),
            point: corr.points3d[k],
        });
    }
    let l = k - corr.n_points();
    let s2 = &corr.lines2d[l];
    Ok(Feature::Line {
        normal: camera.interpretation_plane_normal(&s2[0], &s2[1])?,
        endpoints: corr.lines3d[l],
    })
}

/// Twice the image area of the triangle of three positions.
fn footprint(p: &[Vector2<f64>], s: &[usize; 3]) -> f64 {
    let (a, b, c) = (p[s[0]], p[s[1]], p[s[2]]);
    ((b - a).perp(&(c - a))).abs()
}

/// Three distinct indices below `n` (≥ 3), uniformly.
pub(crate) fn random_triple(rng: &mut Rng, n: usize) -> [usize; 3] {
    let i = rng.below(n);
    let mut j = rng.below(n - 1);
    if j >= i {
        j += 1;
    }
    let mut k = rng.below(n - 2);
    for m in [i.min(j), i.max(j)] {
        if k >= m {
            k += 1;
        }
    }
    [i, j, k]
}

/// Whether there are few enough correspondences for every triple to be a sample.
pub fn is_exhaustive(n: usize) -> bool {
    n * n.saturating_sub(1) * n.saturating_sub(2) / 6 <= EXHAUSTIVE_TRIPLES
}

/// The samples, as indices into [`positions`], main samples first, then the reserve (see the module
/// documentation).
pub fn samples(positions: &[Vector2<f64>]) -> Vec<[usize; 3]> {
    samples_by(positions.len(), |s| footprint(positions, s))
}

/// The samples of `n` correspondences ranked by `footprint` (larger first): every triple when they
/// are few, else the seeded pool (module documentation).
pub fn samples_by(n: usize, footprint: impl Fn(&[usize; 3]) -> f64) -> Vec<[usize; 3]> {
    if n < 3 {
        return vec![];
    }
    if is_exhaustive(n) {
        let mut all = Vec::with_capacity(EXHAUSTIVE_TRIPLES);
        for i in 0..n {
            for j in i + 1..n {
                for k in j + 1..n {
                    all.push([i, j, k]);
                }
            }
        }
        return all;
    }
    let mut rng = Rng::new(0);
    let mut pool: Vec<(f64, [usize; 3])> = (0..SAMPLE_POOL)
        .map(|_| {
            let mut s = random_triple(&mut rng, n);
            s.sort_unstable();
            (footprint(&s), s)
        })
        .collect();
    pool.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    pool.dedup_by(|a, b| a.1 == b.1);
    pool.into_iter().map(|(_, s)| s).collect()
}

/// The poses of the minimal solvers on each sample of `corr` (world frame of `corr`), one group per
/// sample, lazily: a caller that is satisfied after the first samples does not pay for the others.
pub fn minimal_hypotheses<'a>(
    camera: &'a Intrinsics,
    corr: &'a Correspondences,
) -> impl Iterator<Item = Vec<Pose>> + 'a {
    let k_inv = camera.matrix().try_inverse().unwrap_or_else(Matrix3::identity);
    samples(&positions(corr)).into_iter().map(move |s| {
        let [Ok(a), Ok(b), Ok(c)] = s.map(|k| feature(camera, &k_inv, corr, k)) else {
            return vec![];
        };
        solve(&[a, b, c])
            .into_iter()
            .filter(
                |Pose {
                     rotation: r,
                     translation: t,
                 }| r.iter().chain(t.iter()).all(|v| v.is_finite()),
            )
            .collect()
    })
}

/// The cost `½ Σ r²` (px²) of the cheapest pose that the minimal solvers find, on the main samples of
/// `corr`, with every object point *behind* the camera, when it is below `bound`.
///
/// Such a pose `(R, t)` is the pose `(R, −t)` of the object reflected through the origin (`X → −X`)
/// with every point in front: `u = K x / z` does not see the sign of `x_cam`, so both give the same
/// pixels. The pose is searched in front for the reflected object. Data that such a pose explains
/// better than the best pose in front come from points behind the camera.
pub fn behind_camera_cost(camera: &Intrinsics, corr: &Correspondences, bound: f64) -> Option<f64> {
    let mut mirrored = corr.clone();
    mirrored.points3d.iter_mut().for_each(|x| *x = -*x);
    mirrored.lines3d.iter_mut().flatten().for_each(|x| *x = -*x);
    let cost = ReprojectionCost::of(camera, &mirrored);
    let groups = if is_exhaustive(mirrored.n_points() + mirrored.n_lines()) {
        usize::MAX
    } else {
        SPREAD_SAMPLES
    };
    minimal_hypotheses(camera, &mirrored)
        .take(groups)
        .flatten()
        .filter(|pose| count_behind(object_points(&mirrored).copied(), pose) == 0)
        .filter_map(|pose| cost.cost_below(&pose, bound))
        .min_by(f64::total_cmp)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::quaternion::rotation_distance;
    use crate::synthetic::visible_scene;

    #[test]
    fn small_problems_use_every_triple_and_large_ones_a_few_wide_ones() {
        let p: Vec<Vector2<f64>> = (0..6).map(|i| Vector2::new(i as f64, (i * i) as f64)).collect();
        assert_eq!(samples(&p).len(), 20);
        assert!(samples(&p[..2]).is_empty());
        let mut rng = Rng::new(3);
        let many: Vec<Vector2<f64>> = (0..100).map(|_| Vector2::new(rng.uniform(), rng.uniform())).collect();
        let all = samples(&many);
        assert_eq!(all, samples(&many), "seeded: the same data give the same samples");
        assert!(all.len() > SPREAD_SAMPLES && all.len() <= SAMPLE_POOL);
        assert!(
            all.windows(2)
                .all(|w| footprint(&many, &w[0]) >= footprint(&many, &w[1])),
            "widest first"
        );
        let chosen = &all[..SPREAD_SAMPLES];
        // The kept triples are the widest of the pool: wider than a typical random triangle (mean
        // doubled area of a random triangle in the unit square is 11/72 ≈ 0.15).
        assert!(chosen.iter().all(|s| footprint(&many, s) > 0.15), "{chosen:?}");
    }

    /// `is_exhaustive(n)` is `C(n, 3) ≤ EXHAUSTIVE_TRIPLES`, with the binomial counted here by listing
    /// the triples; and past that size the samples are the pool's few, not every triple (7 to 9
    /// correspondences would otherwise run 35 to 84 minimal solves per estimate, and the behind-camera
    /// check every one of them).
    #[test]
    fn exhaustive_exactly_when_the_triples_are_few() {
        for n in 0..40usize {
            let triples = (0..n)
                .flat_map(|i| (i + 1..n).flat_map(move |j| (j + 1..n).map(move |k| (i, j, k))))
                .count();
            assert_eq!(
                is_exhaustive(n),
                triples <= EXHAUSTIVE_TRIPLES,
                "n = {n}, {triples} triples"
            );
            if n >= 3 {
                let p: Vec<Vector2<f64>> = (0..n).map(|i| Vector2::new(i as f64, (i * i % 7) as f64)).collect();
                let expected = if triples <= EXHAUSTIVE_TRIPLES {
                    triples
                } else {
                    SAMPLE_POOL
                };
                assert!(samples(&p).len() <= expected, "n = {n}: {} samples", samples(&p).len());
            }
        }
    }

    #[test]
    fn the_true_pose_is_among_the_hypotheses_of_exact_data() {
        for (np, nl) in [(10, 0), (0, 10), (5, 5), (4, 0), (0, 4), (2, 2)] {
            for seed in 0..20 {
                let scene = visible_scene(4000.0, np, nl, false, seed);
                let hypotheses: Vec<Pose> = minimal_hypotheses(&scene.camera.intrinsics(), &scene.correspondences)
                    .flatten()
                    .collect();
                let found = hypotheses.iter().any(
                    |Pose {
                         rotation: r,
                         translation: t,
                     }| {
                        rotation_distance(r, &scene.rotation) < 1e-6 && (t - scene.translation).norm() < 1e-5
                    },
                );
                assert!(found, "{np} points, {nl} lines, seed {seed}");
            }
        }
    }
}
