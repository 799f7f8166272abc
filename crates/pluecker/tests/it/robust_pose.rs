//! The robust pipeline (`PoseOptions::ransac`, LO-RANSAC over points and lines) and the pose
//! covariance of every `estimate_pose` call, end to end. Seeds are fixed per test and printed on failure.
//!
//! Outliers replace an observation by a uniformly random one in the 640 x 480 image (a random pixel, or
//! a random segment of at least 40 px). "Truly inlier" means: within threshold at the *true* pose. A
//! robust answer may disagree with that only for features whose true-pose error is within
//! [`MASK_MARGIN_PX`] of the threshold: the estimated pose differs from the truth by the estimation error,
//! which moves each predicted feature by about σ/√(n/6) ≈ 0.3 px here (1 px noise, ≥ 20 inliers).

use nalgebra::{Matrix6, Vector2, Vector3, Vector6};
use pluecker::geometry::{rotation_distance, testing::log_so3};
use pluecker::pose::ReprojectionCost;
use pluecker::pose::{
    estimate_pose, Correspondences, CovarianceSource, PoseOptions, PoseResult, RansacOptions, RansacStop, Status,
};
use pluecker::rng::Rng;
use pluecker::synthetic::{random_scene, Scene, SceneKind};
use pluecker::{Camera, Error};
use std::time::Duration;

/// Features whose error at the true pose is within this of the threshold may be classified either way.
const MASK_MARGIN_PX: f64 = 1.5;
const THRESHOLD_PX: f64 = 4.0;

fn robust(seed: u64) -> PoseOptions {
    let mut ransac = RansacOptions::default();
    ransac.seed = seed;
    let mut options = PoseOptions::default();
    options.ransac = Some(ransac);
    options
}

/// A random segment of the image at least 40 px long.
fn random_segment(rng: &mut Rng) -> [Vector2<f64>; 2] {
    loop {
        let mut point = || Vector2::new(rng.uniform_in(0.0, 640.0), rng.uniform_in(0.0, 480.0));
        let s = [point(), point()];
        if (s[0] - s[1]).norm() > 40.0 {
            return s;
        }
    }
}

/// A `General` scene with 1 px noise where a fraction `ratio` of the points and of the lines (chosen at
/// random) are replaced by random observations.
fn scene_with_outliers(n_points: usize, n_lines: usize, ratio: f64, seed: u64) -> (Scene, Correspondences) {
    let scene = random_scene(SceneKind::General, n_points, n_lines, seed);
    let mut rng = Rng::new(seed ^ 0x5eed);
    let mut corr = scene.noisy(1.0, true, &mut rng);
    let bad_points = (ratio * n_points as f64).round() as usize;
    let bad_lines = (ratio * n_lines as f64).round() as usize;
    for i in rng.sample_indices(n_points, bad_points) {
        corr.points2d[i] = Vector2::new(rng.uniform_in(0.0, 640.0), rng.uniform_in(0.0, 480.0));
    }
    for i in rng.sample_indices(n_lines, bad_lines) {
        corr.lines2d[i] = random_segment(&mut rng);
    }
    (scene, corr)
}

/// Pose error in the tangent space of the covariance: `(log(R R₀ᵀ), t − t₀)`.
fn tangent_error(result: &PoseResult, scene: &Scene) -> Vector6<f64> {
    let w = log_so3(&(result.pose.rotation * scene.rotation.transpose()));
    let dt = result.pose.translation - scene.translation;
    Vector6::new(w.x, w.y, w.z, dt.x, dt.y, dt.z)
}

/// Checks the masks against the truth (see the module docs) and returns the number of true inliers.
fn check_masks(result: &PoseResult, scene: &Scene, corr: &Correspondences, label: &str) -> usize {
    let truth = ReprojectionCost::of(&scene.camera.intrinsics(), corr)
        .errors(&pluecker::Pose::new(scene.rotation, scene.translation));
    let mask: Vec<bool> = result
        .inliers_points
        .iter()
        .chain(&result.inliers_lines)
        .copied()
        .collect();
    assert_eq!(mask.len(), truth.len(), "{label}");
    for (k, (&m, &e)) in mask.iter().zip(&truth).enumerate() {
        if (e - THRESHOLD_PX).abs() > MASK_MARGIN_PX {
            assert_eq!(
                m,
                e <= THRESHOLD_PX,
                "{label}: feature {k} true error {e:.2} px, mask {m}"
            );
        }
    }
    truth.iter().filter(|&&e| e <= THRESHOLD_PX).count()
}

/// `eᵀ Σ⁻¹ e` with the result's covariance.
fn mahalanobis2(result: &PoseResult, e: &Vector6<f64>) -> f64 {
    let cov: Matrix6<f64> = result.covariance.expect("a covariance");
    (e.transpose() * cov.try_inverse().unwrap() * e)[0]
}

/// 99.9999 % quantile of χ²₆ (P(χ²₆ > 37.9) = 1e-6): a bound on one draw's Mahalanobis distance.
const CHI2_6_SURE: f64 = 37.9;

#[test]
fn recovers_the_pose_at_0_50_and_80_percent_outliers_with_points_and_lines() {
    for (ratio, seed) in [(0.0, 1u64), (0.5, 2), (0.8, 3)] {
        for (np, nl) in [(100, 0), (100, 30)] {
            let (scene, corr) = scene_with_outliers(np, nl, ratio, seed);
            let mut opts = robust(seed);
            opts.sigma_px = Some(1.0);
            let label = format!("ratio {ratio} seed {seed} {np} points {nl} lines");
            let r = estimate_pose(&scene.camera, &corr, &opts).unwrap();
            assert_eq!(r.report.status, Status::Success, "{label}: {r:?}");
            let report = r.details.ransac.as_ref().unwrap();
            assert_eq!(report.stop, RansacStop::Confidence, "{label}");
            let inliers = check_masks(&r, &scene, &corr, &label);
            assert!(inliers >= (0.15 * (np + nl) as f64) as usize, "{label}");
            // The refined pose is within the covariance's own 1e-6 tail of the truth.
            let d2 = mahalanobis2(&r, &tangent_error(&r, &scene));
            assert!(d2 < CHI2_6_SURE, "{label}: d² = {d2}");
            assert_eq!(r.details.covariance_source, Some(CovarianceSource::Given));
            assert_eq!(
                r.details.stages.iter().map(|s| s.name.as_str()).collect::<Vec<_>>(),
                ["ransac", "refinement"]
            );
        }
    }
}

/// Depends on the line solvers (P3L, 1P2L, 2P1L): 5 points and 30 lines, 40 % outliers of each. With
/// the point solver alone, samples of three points are all-inlier with probability 0.6³ and the
/// 5 points are too few to reach `min_inliers` on their own; the lines must produce hypotheses.
#[test]
fn lines_heavy_scene_needs_the_line_solvers() {
    let (scene, corr) = scene_with_outliers(5, 30, 0.4, 21);
    let r = estimate_pose(&scene.camera, &corr, &robust(21)).unwrap();
    assert_eq!(r.report.status, Status::Success, "{r:?}");
    check_masks(&r, &scene, &corr, "lines-heavy");
    assert!(r.inliers_lines.iter().filter(|&&m| m).count() >= 15);
    assert!(rotation_distance(&r.pose.rotation, &scene.rotation) < 0.02);
}

#[test]
fn same_seed_gives_the_same_result() {
    let (scene, corr) = scene_with_outliers(80, 20, 0.5, 5);
    let a = estimate_pose(&scene.camera, &corr, &robust(17)).unwrap();
    let b = estimate_pose(&scene.camera, &corr, &robust(17)).unwrap();
    assert_eq!(
        (a.pose.rotation, a.pose.translation),
        (b.pose.rotation, b.pose.translation)
    );
    assert_eq!(
        (&a.inliers_points, &a.inliers_lines),
        (&b.inliers_points, &b.inliers_lines)
    );
    let (ra, rb) = (a.details.ransac.unwrap(), b.details.ransac.unwrap());
    assert_eq!(
        (ra.iterations, ra.models_scored, ra.score),
        (rb.iterations, rb.models_scored, rb.score)
    );
}

/// The report's MSAC score is the result's cost convention, `Σ min(eᵢ², τ²)` in px², at the pose the
/// sampling stage ended on: recomputed here from that pose and the pixels (points only, so each `eᵢ`
/// is a plain reprojection distance), and equal to the `msac` stage's final cost.
#[test]
fn the_msac_score_is_a_sum_of_truncated_squares() {
    let (scene, corr) = scene_with_outliers(60, 0, 0.3, 11);
    let result = estimate_pose(&scene.camera, &corr, &robust(3)).unwrap();
    let report = result.details.ransac.unwrap();
    let stage = result
        .details
        .stages
        .iter()
        .find(|s| s.cost_kind == pluecker::CostKind::Msac)
        .unwrap();
    let tau2 = RansacOptions::default().point_threshold.powi(2);
    let k = scene.camera.intrinsics().matrix();
    let oracle: f64 = corr
        .points2d
        .iter()
        .zip(&corr.points3d)
        .map(|(u, x)| {
            let p = k * (stage.rotation * x + stage.translation);
            let e2 = (Vector2::new(p.x / p.z, p.y / p.z) - u).norm_squared();
            if p.z > 0.0 {
                e2.min(tau2)
            } else {
                tau2
            }
        })
        .sum();
    // Relative rounding of a sum of 60 terms of at most τ² = 16 px².
    assert!(
        (report.score - oracle).abs() <= 1e-9 * oracle.max(1.0),
        "{} vs {oracle}",
        report.score
    );
    assert_eq!(report.score, stage.final_cost);
}

/// 20 points uniform in [-1, 1]² × [4, 6] seen by `Camera(400, 400, 320, 240)` at the identity pose,
/// with `sigma` px of Gaussian noise: clean data.
fn clean_points(sigma: f64, seed: u64) -> (Camera, Correspondences) {
    let camera = Camera::pinhole(400.0, 400.0, 320.0, 240.0, 0.0).unwrap();
    let mut rng = Rng::new(seed);
    let points3d: Vec<Vector3<f64>> = (0..20)
        .map(|_| {
            Vector3::new(
                rng.uniform_in(-1.0, 1.0),
                rng.uniform_in(-1.0, 1.0),
                rng.uniform_in(4.0, 6.0),
            )
        })
        .collect();
    let points2d = points3d
        .iter()
        .map(|x| {
            let (u, v) = (400.0 * x.x / x.z + 320.0, 400.0 * x.y / x.z + 240.0);
            Vector2::new(u + sigma * rng.normal(), v + sigma * rng.normal())
        })
        .collect();
    let corr = Correspondences {
        points2d,
        points3d,
        ..Default::default()
    };
    (camera, corr)
}

/// Clean data and a threshold far above the noise: every point an inlier of every reasonable pose.
/// A point threshold of 100 px (the window of the 20 points is about 200 px wide, so a random pixel
/// agrees with any pose by chance: δ = 1) used to run 100,000 samples to the iteration cap and end
/// `not_converged` with the right pose; a line threshold of 1e300 without any line did the same (it
/// widened the points' chance window to p = 0). The sequential test could not reject anything, but
/// its `α = 1 / A = 1` told the stopping rule that every sample was a miss.
#[test]
fn clean_data_with_a_wide_threshold_stops_at_once() {
    let (camera, corr) = clean_points(0.5, 7);
    let wide: [(f64, f64); 6] = [
        (100.0, 4.0),
        (50.0, 4.0),
        (4.0, 1e300),
        (1e300, 4.0),
        (1e6, 1e6),
        (4.0, 4.0),
    ];
    for (point_threshold, line_threshold) in wide {
        let mut opts = robust(0);
        let ransac = opts.ransac.as_mut().unwrap();
        ransac.point_threshold = point_threshold;
        ransac.line_threshold = line_threshold;
        let r = estimate_pose(&camera, &corr, &opts).unwrap();
        let report = r.details.ransac.as_ref().unwrap();
        let label = format!("thresholds {point_threshold} / {line_threshold}: {report:?}");
        assert_eq!(r.report.status, Status::Success, "{label}");
        assert_eq!(report.stop, RansacStop::Confidence, "{label}");
        // Every point an inlier: P = 1, one sample suffices (two when the first is degenerate).
        assert!(report.iterations <= 3, "{label}");
        assert!(report.score.is_finite(), "{label}");
        assert_eq!(r.inliers_points.iter().filter(|&&m| m).count(), 20, "{label}");
        // The pose of 20 points at 0.5 px: within a few milliradians and hundredths of a unit.
        assert!(
            rotation_distance(&r.pose.rotation, &nalgebra::Matrix3::identity()) < 0.01,
            "{label}"
        );
        assert!(r.pose.translation.norm() < 0.05, "{label}");
    }
}

/// Pixel error of each point at `(rotation, translation)`, written out here (`u = K (R X + t) / z`,
/// f = 400 px, principal point (320, 240), no skew); infinite behind the camera.
fn pixel_errors(rotation: &nalgebra::Matrix3<f64>, translation: &Vector3<f64>, corr: &Correspondences) -> Vec<f64> {
    corr.points3d
        .iter()
        .zip(&corr.points2d)
        .map(|(x, u)| {
            let c = rotation * x + translation;
            let projected = Vector2::new(400.0 * c.x / c.z + 320.0, 400.0 * c.y / c.z + 240.0);
            if c.z > 0.0 {
                (projected - u).norm()
            } else {
                f64::INFINITY
            }
        })
        .collect()
}

/// One near point (depth 0.05, at pixel (450, 330)) among 179 far ones (depth 5-30, uniform in the
/// 640 x 480 image) seen at the identity pose with 1 px noise, then 77 wrong matches (30 %): random
/// pixels of random far points. The near point alone fixes the camera centre along a direction that
/// the far points barely constrain (it moves by 400 δc / 0.05 px when the centre moves by δc).
fn near_point_scene(seed: u64) -> (Camera, Correspondences) {
    let camera = Camera::pinhole(400.0, 400.0, 320.0, 240.0, 0.0).unwrap();
    let mut rng = Rng::new(seed);
    let mut pixel = || Vector2::new(rng.uniform_in(0.0, 640.0), rng.uniform_in(0.0, 480.0));
    let pixels: Vec<Vector2<f64>> = std::iter::once(Vector2::new(450.0, 330.0))
        .chain((0..179 + 77).map(|_| pixel()))
        .collect();
    let mut corr = Correspondences::default();
    for (i, u) in pixels.iter().enumerate() {
        let depth = if i == 0 { 0.05 } else { rng.uniform_in(5.0, 30.0) };
        corr.points3d
            .push(Vector3::new((u.x - 320.0) / 400.0, (u.y - 240.0) / 400.0, 1.0) * depth);
        corr.points2d.push(if i < 180 {
            u + Vector2::new(rng.normal(), rng.normal())
        } else {
            Vector2::new(rng.uniform_in(0.0, 640.0), rng.uniform_in(0.0, 480.0))
        });
    }
    (camera, corr)
}

/// The robust pose keeps a high-leverage inlier. On the scene of [`near_point_scene`] a fit to the far
/// points alone leaves the near point 26-75 px off (the camera centre 0.005-0.01 away), so the
/// threshold dropped it, on every seed: no minimal sample with the near point was drawn in the ~23
/// samples, and a sample's raw score had to beat the refined best to be refined at all. The final
/// consensus now proposes each correspondence within the threshold of its *prediction* uncertainty
/// (guided matching), and the fit with the near point scores lower (MSAC) than the fit without.
#[test]
fn a_near_high_leverage_inlier_joins_the_consensus() {
    for seed in 0..6u64 {
        let (camera, corr) = near_point_scene(seed);
        let truth = pixel_errors(&nalgebra::Matrix3::identity(), &Vector3::zeros(), &corr);
        let r = estimate_pose(&camera, &corr, &robust(seed)).unwrap();
        let errors = pixel_errors(&r.pose.rotation, &r.pose.translation, &corr);
        let label = format!(
            "seed {seed}: near point {:.1} px off, {:?}",
            errors[0], r.details.ransac
        );
        assert_eq!(r.report.status, Status::Success, "{label}");
        assert!(r.inliers_points[0] && errors[0] <= THRESHOLD_PX, "{label}");
        // Every other feature is classified as at the true pose, but within the margin.
        for (k, (&t, &inlier)) in truth.iter().zip(&r.inliers_points).enumerate() {
            if (t - THRESHOLD_PX).abs() > MASK_MARGIN_PX {
                assert_eq!(inlier, t <= THRESHOLD_PX, "{label}: point {k}, {t:.1} px at the truth");
            }
        }
    }
}

/// A local optimisation re-fits all the inliers in each of its rounds (tens of milliseconds at 10⁵
/// correspondences), so a stop of the call is polled between them and not only before each sample:
/// Ctrl-C during the set-up and the first local optimisations of a 200k-point pose took up to 0.2-0.4 s
/// to be seen (bench/interrupt_latency.py). One sample here: one poll before it, then one before
/// each of its local optimisation's 3 later rounds (before: the one poll only); with two samples
/// allowed, a stop requested at the second poll ends the local optimisation there and the loop before
/// its second sample.
#[test]
fn a_stop_is_polled_between_the_rounds_of_a_local_optimisation() {
    use pluecker::interrupt::{with_stop, Stop};
    use std::sync::atomic::{AtomicUsize, Ordering};
    use std::sync::Arc;
    let (scene, corr) = scene_with_outliers(2000, 0, 0.5, 9);
    let opts = robust(9);
    let run = |request_at: usize, samples: usize| {
        let mut opts = opts.clone();
        opts.ransac.as_mut().unwrap().max_iterations = samples;
        let polls = Arc::new(AtomicUsize::new(0));
        let counted = Arc::clone(&polls);
        let stop = Stop::new().with_check(move || counted.fetch_add(1, Ordering::Relaxed) + 1 == request_at);
        let r = with_stop(Arc::new(stop), || estimate_pose(&scene.camera, &corr, &opts).unwrap());
        (r, polls.load(Ordering::Relaxed))
    };
    let (r, polls) = run(usize::MAX, 1);
    assert_eq!(r.details.ransac.as_ref().unwrap().local_optimizations, 1);
    assert!(polls >= 4, "{polls} polls");
    let (r, polls) = run(2, 2);
    let report = r.details.ransac.unwrap();
    assert_eq!(
        (report.stop, report.iterations, polls),
        (RansacStop::Interrupted, 1, 2),
        "{report:?}"
    );
}

fn all_outliers(n_points: usize, seed: u64) -> (Camera, Correspondences) {
    let scene = random_scene(SceneKind::General, n_points, 0, seed);
    let mut rng = Rng::new(seed);
    let mut corr = scene.correspondences.clone();
    for p in corr.points2d.iter_mut() {
        *p = Vector2::new(rng.uniform_in(0.0, 640.0), rng.uniform_in(0.0, 480.0));
    }
    (scene.camera, corr)
}

#[test]
fn all_outlier_data_gives_a_status_within_the_iteration_cap() {
    let (camera, corr) = all_outliers(60, 8);
    let mut opts = robust(0);
    opts.ransac.as_mut().unwrap().max_iterations = 2000;
    let r = estimate_pose(&camera, &corr, &opts).unwrap();
    assert_eq!(r.report.status, Status::TooFewInliers, "{r:?}");
    let report = r.details.ransac.unwrap();
    assert_eq!((report.stop, report.iterations), (RansacStop::IterationCap, 2000));
    // Only the model's own sample (and at most two chance agreements) support it.
    assert!(report.inliers < 6, "{report:?}");
    assert_eq!(r.details.stages.len(), 1, "no refinement of a rejected model");
}

/// Issue 10 §4: all-outlier data used to run to `max_iterations` (100,000 samples), each pose scored
/// on nearly every point, 16 s at 20,000 points, and end `not_converged` with 6-18 chance "inliers".
/// Now the `min_inlier_ratio` cap (9,206 samples at 0.1, a few more for the SPRT's α) bounds the
/// samples, the SPRT rejects each pose after a few tens of errors, and the best model must beat
/// chance (`required_inliers`). The work is asserted, not the time (see bench/robust_outliers.py).
#[test]
fn all_outlier_data_is_cheap_and_too_few_inliers() {
    for (n, seed) in [(2000, 41u64), (20_000, 42)] {
        let (camera, corr) = all_outliers(n, seed);
        let r = estimate_pose(&camera, &corr, &robust(seed)).unwrap();
        let report = r.details.ransac.as_ref().unwrap();
        let label = format!("{n} points, seed {seed}: {report:?}");
        assert_eq!(r.report.status, Status::TooFewInliers, "{label}");
        assert_eq!(report.stop, RansacStop::MinInlierRatio, "{label}");
        // ⌈ln(1e-4) / ln(1 − 0.1³ (1 − α))⌉ with α = 1/A ≤ 1/10: at most 10,230 samples.
        assert!(report.iterations >= 9206 && report.iterations <= 10_230, "{label}");
        // Each pose verified on a few tens of points, not on all of them.
        assert!(report.errors_evaluated <= 100 * report.models_scored, "{label}");
        assert!(report.sprt_rejections + 10 >= report.models_scored, "{label}");
        assert!(report.inliers < report.required_inliers, "{label}");
        assert_eq!(r.details.stages.len(), 1, "no refinement of a rejected model");
    }
}

/// The chance requirement grows with the number of correspondences (the chance agreements of a wrong
/// pose do), but never above `⌈ρ n⌉`, and it is `min_inliers` for small data: a small but genuine
/// inlier set is still accepted.
#[test]
fn required_inliers_grow_with_chance_only() {
    let required = |n: usize| {
        let (camera, corr) = all_outliers(n, 43);
        let r = estimate_pose(&camera, &corr, &robust(43)).unwrap();
        assert_eq!(r.report.status, Status::TooFewInliers, "{n}");
        r.details.ransac.unwrap().required_inliers
    };
    let (small, medium, large) = (required(60), required(2000), required(20_000));
    // c + 1 for M ≈ 17,000 poses and p = π 4² / (640 · 480): at most 6 at 60 points, 9 at 2,000 and
    // 18 at 20,000 (3 + the 0.05 / M quantile of Poisson(3.3)).
    assert_eq!(small, 6);
    assert!((8..=10).contains(&medium), "{medium}");
    assert!((16..=20).contains(&large), "{large}");
    // Small genuine inlier sets: 8 of 40 points (20 %), 12 of 60 (20 %), 150 of 1000 (15 %).
    for (n, inliers, seed) in [(40, 8, 44u64), (60, 12, 45), (1000, 150, 46)] {
        let (scene, corr) = scene_with_outliers(n, 0, 1.0 - inliers as f64 / n as f64, seed);
        let r = estimate_pose(&scene.camera, &corr, &robust(seed)).unwrap();
        let report = r.details.ransac.as_ref().unwrap();
        assert_eq!(
            r.report.status,
            Status::Success,
            "{n} points, {inliers} inliers: {report:?}"
        );
        assert!(report.required_inliers <= inliers, "{report:?}");
        check_masks(&r, &scene, &corr, &format!("{n} points"));
    }
    // Without the cap (min_inlier_ratio = 0) the requirement is min_inliers, as before.
    let (camera, corr) = all_outliers(2000, 43);
    let mut opts = robust(43);
    let ransac = opts.ransac.as_mut().unwrap();
    (ransac.min_inlier_ratio, ransac.max_iterations) = (0.0, 3000);
    let r = estimate_pose(&camera, &corr, &opts).unwrap();
    assert_eq!(r.details.ransac.unwrap().required_inliers, 6);
}

/// The loop as it was before the SPRT and the cap: every pose scored until it cannot beat the best.
/// The samples drawn for a seed are the same (the verification order has its own random stream).
fn legacy(seed: u64) -> PoseOptions {
    let mut opts = robust(seed);
    let ransac = opts.ransac.as_mut().unwrap();
    (ransac.sprt, ransac.min_inlier_ratio) = (false, 0.0);
    opts
}

/// Before vs after on seeded scenes with inliers (10-50 % outliers, points and points + lines, 100 to
/// 5,000 correspondences): the same inliers recovered and the same accuracy, for less scoring work.
#[test]
fn sprt_and_cap_keep_the_inliers_and_the_accuracy_of_the_plain_loop() {
    let (mut same_masks, mut scenes) = (0, 0);
    let (mut err_new, mut err_old) = (0.0, 0.0);
    let (mut work_new, mut work_old) = (0usize, 0usize);
    for (np, nl, ratio, seed) in [
        (100, 0, 0.1, 51u64),
        (100, 0, 0.5, 52),
        (100, 30, 0.3, 53),
        (100, 30, 0.5, 54),
        (1000, 0, 0.3, 55),
        (1000, 100, 0.5, 56),
        (5000, 0, 0.5, 57),
        (300, 0, 0.5, 58),
        (300, 60, 0.1, 59),
        (60, 20, 0.5, 60),
    ] {
        let (scene, corr) = scene_with_outliers(np, nl, ratio, seed);
        let label = format!("{np} points {nl} lines, {ratio} outliers, seed {seed}");
        let new = estimate_pose(&scene.camera, &corr, &robust(seed)).unwrap();
        let old = estimate_pose(&scene.camera, &corr, &legacy(seed)).unwrap();
        assert_eq!(new.report.status, Status::Success, "{label}: {:?}", new.details.ransac);
        assert_eq!(old.report.status, Status::Success, "{label}");
        let true_inliers = check_masks(&new, &scene, &corr, &label);
        check_masks(&old, &scene, &corr, &label);
        let count = |r: &PoseResult| r.inliers_points.iter().chain(&r.inliers_lines).filter(|&&m| m).count();
        // Inliers differ only near the threshold: within 1 % of the true inliers.
        assert!(
            count(&new) + true_inliers / 100 >= count(&old),
            "{label}: {} vs {}",
            count(&new),
            count(&old)
        );
        same_masks += usize::from(new.inliers_points == old.inliers_points && new.inliers_lines == old.inliers_lines);
        scenes += 1;
        let error = |r: &PoseResult| {
            let e = tangent_error(r, &scene);
            mahalanobis2(r, &e)
        };
        err_new += error(&new);
        err_old += error(&old);
        work_new += new.details.ransac.as_ref().unwrap().errors_evaluated;
        work_old += old.details.ransac.as_ref().unwrap().errors_evaluated;
    }
    assert!(
        same_masks >= scenes - 1,
        "{same_masks} of {scenes} scenes with the same inliers"
    );
    // The summed Mahalanobis distance of the errors (χ²₆ each, mean 6 per scene): no worse.
    assert!(err_new <= 1.05 * err_old + 1.0, "{err_new} vs {err_old}");
    assert!(2 * work_new < work_old, "errors evaluated: {work_new} vs {work_old}");
}

#[test]
fn the_time_budget_stops_a_loop_whose_cap_would_run_long() {
    let (camera, corr) = all_outliers(60, 9);
    let mut opts = robust(0);
    let ransac = opts.ransac.as_mut().unwrap();
    ransac.max_iterations = usize::MAX;
    ransac.min_inlier_ratio = 0.0; // no cap from the inlier fraction either
    ransac.time_budget = Some(Duration::from_millis(30));
    let r = estimate_pose(&camera, &corr, &opts).unwrap();
    let report = r.details.ransac.unwrap();
    assert_eq!(report.stop, RansacStop::TimeBudget);
    // A sample takes far less than a second: the loop stopped on the budget, not near the cap.
    assert!(report.iterations > 0 && report.iterations < 1_000_000_000, "{report:?}");
    assert_eq!(r.report.status, Status::TooFewInliers);
}

#[test]
fn bad_options_and_bad_data_are_errors() {
    let (scene, corr) = scene_with_outliers(20, 5, 0.2, 4);
    let with = |f: &dyn Fn(&mut RansacOptions)| {
        let mut opts = robust(0);
        f(opts.ransac.as_mut().unwrap());
        estimate_pose(&scene.camera, &corr, &opts)
    };
    for (name, result) in [
        ("point_threshold", with(&|o| o.point_threshold = 0.0)),
        ("point_threshold", with(&|o| o.point_threshold = -1.0)),
        ("line_threshold", with(&|o| o.line_threshold = f64::NAN)),
        ("confidence", with(&|o| o.confidence = 1.0)),
        ("max_iterations", with(&|o| o.max_iterations = 0)),
        ("min_inlier_ratio", with(&|o| o.min_inlier_ratio = 1.0)),
        ("min_inlier_ratio", with(&|o| o.min_inlier_ratio = -0.1)),
        ("min_inlier_ratio", with(&|o| o.min_inlier_ratio = f64::NAN)),
        ("min_inliers", with(&|o| o.min_inliers = 2)),
    ] {
        assert!(
            matches!(&result, Err(Error::InvalidOption { name: n, .. }) if n == name),
            "{name}: {result:?}"
        );
    }
    let mut sigma = robust(0);
    sigma.sigma_px = Some(0.0);
    assert!(matches!(
        estimate_pose(&scene.camera, &corr, &sigma),
        Err(Error::InvalidOption { .. })
    ));
    // Fewer correspondences than min_inliers (6), and fewer than a sample.
    for n in [2, 5] {
        let few = Correspondences {
            points2d: corr.points2d[..n].to_vec(),
            points3d: corr.points3d[..n].to_vec(),
            ..Default::default()
        };
        let r = estimate_pose(&scene.camera, &few, &robust(0));
        assert!(matches!(r, Err(Error::TooFewCorrespondences { .. })), "{n}: {r:?}");
    }
    let mut nan = corr.clone();
    nan.lines3d[3][1].y = f64::NAN;
    assert_eq!(
        estimate_pose(&scene.camera, &nan, &robust(0)).unwrap_err(),
        Error::NonFinite {
            what: "lines3d".into(),
            index: 3
        }
    );
}

#[test]
fn degenerate_data_is_an_error_and_degenerate_samples_are_counted() {
    let camera = Camera::pinhole(800.0, 800.0, 320.0, 240.0, 0.0).unwrap();
    // Dyadic coordinates: exactly collinear in floating point.
    let line: Vec<Vector3<f64>> = (0..12)
        .map(|i| Vector3::new(0.125 * i as f64 - 0.75, 0.0625 * i as f64, 5.0 + 0.25 * i as f64))
        .collect();
    let project = |xs: &[Vector3<f64>]| xs.iter().map(|x| camera.project(x)).collect::<Vec<_>>();
    let collinear = Correspondences {
        points2d: project(&line),
        points3d: line.clone(),
        ..Default::default()
    };
    let r = estimate_pose(&camera, &collinear, &robust(0));
    assert!(matches!(r, Err(Error::Degenerate { .. })), "{r:?}");
    // Near-degenerate samples are the minimal solvers' business (P3P returns ill-conditioned poses for
    // nearly collinear points); a sample with two copies of one object point gives no pose at all.
    // Twelve correspondences of which ten are one point seen ten times, and two other points.
    let others = [Vector3::new(0.4, -0.5, 6.0), Vector3::new(-0.5, 0.6, 4.5)];
    let points3d: Vec<Vector3<f64>> = (0..12).map(|i| if i < 10 { line[0] } else { others[i - 10] }).collect();
    let repeated = Correspondences {
        points2d: project(&points3d),
        points3d,
        ..Default::default()
    };
    let mut opts = robust(0);
    let ransac = opts.ransac.as_mut().unwrap();
    (ransac.min_iterations, ransac.max_iterations) = (300, 300);
    let r = estimate_pose(&camera, &repeated, &opts).unwrap();
    let report = r.details.ransac.as_ref().unwrap();
    assert_eq!(report.iterations, 300);
    // A sample holds two copies with probability p = (C(10,2)·2 + C(10,3)) / C(12,3) = 210/220:
    // binomial count, 5 standard deviations.
    let (n, p): (f64, f64) = (300.0, 210.0 / 220.0);
    let (mean, std) = (n * p, (n * p * (1.0 - p)).sqrt());
    assert!(
        (report.degenerate_samples as f64 - mean).abs() < 5.0 * std,
        "{report:?}"
    );
    // Three distinct points: every P3P solution explains all twelve noise-free correspondences.
    assert_eq!(r.report.status, Status::Success);
    assert!(
        r.details.rms_error_px < 1e-6 && r.inliers_points.iter().all(|&m| m),
        "{r:?}"
    );
}

#[test]
fn non_robust_results_use_every_correspondence_and_carry_a_covariance() {
    let scene = random_scene(SceneKind::General, 30, 10, 6);
    let corr = scene.noisy(1.0, true, &mut Rng::new(6));
    let r = estimate_pose(&scene.camera, &corr, &PoseOptions::default()).unwrap();
    assert!(r.inliers_points.iter().all(|&m| m) && r.inliers_points.len() == 30);
    assert!(r.inliers_lines.iter().all(|&m| m) && r.inliers_lines.len() == 10);
    assert!(r.details.ransac.is_none());
    assert_eq!(r.details.covariance_source, Some(CovarianceSource::Estimated));
    // σ̂² ~ σ² χ²₇₄ / 74: within 5 standard deviations √(2/74) of 1.
    let s2 = r.details.sigma_px.unwrap().powi(2);
    assert!((s2 - 1.0).abs() < 5.0 * (2.0f64 / 74.0).sqrt(), "σ̂² = {s2}");
    let mut given = PoseOptions::default();
    given.sigma_px = Some(2.0);
    let g = estimate_pose(&scene.camera, &corr, &given).unwrap();
    assert_eq!(
        (g.details.covariance_source, g.details.sigma_px),
        (Some(CovarianceSource::Given), Some(2.0))
    );
    let ratio = g.covariance.unwrap()[(0, 0)] / r.covariance.unwrap()[(0, 0)];
    assert!((ratio - 4.0 / s2).abs() < 1e-9 * ratio);
}

/// Monte-Carlo statistics of the covariance over `draws` noisy copies of `scene` (1 px Gaussian noise;
/// `outliers` replaces a fixed random set of observations by random ones in every draw).
struct MonteCarlo {
    /// Mean of `d² = eᵀ Σ⁻¹ e` with each result's own covariance.
    mean_d2: f64,
    /// Per axis: `Σ e_k² / N` over the mean predicted variance `Σ_kk`.
    variance_ratio: [f64; 6],
    /// Mean predicted variances.
    predicted: [f64; 6],
    /// Mean of the estimated `σ̂²` (runs without a given σ).
    mean_sigma2: f64,
}

fn monte_carlo(scene: &Scene, opts: &PoseOptions, outlier_ratio: f64, draws: usize, seed: u64) -> MonteCarlo {
    let mut rng = Rng::new(seed);
    let c = &scene.correspondences;
    let bad_points = rng.sample_indices(c.n_points(), (outlier_ratio * c.n_points() as f64) as usize);
    let bad_lines = rng.sample_indices(c.n_lines(), (outlier_ratio * c.n_lines() as f64) as usize);
    let (mut d2, mut sq, mut predicted, mut sigma2) = (0.0, [0.0; 6], [0.0; 6], 0.0);
    for draw in 0..draws {
        let mut corr = scene.noisy(1.0, true, &mut rng);
        for &i in &bad_points {
            corr.points2d[i] = Vector2::new(rng.uniform_in(0.0, 640.0), rng.uniform_in(0.0, 480.0));
        }
        for &i in &bad_lines {
            corr.lines2d[i] = random_segment(&mut rng);
        }
        let r = estimate_pose(&scene.camera, &corr, opts).unwrap();
        assert_eq!(r.report.status, Status::Success, "seed {seed} draw {draw}");
        let e = tangent_error(&r, scene);
        d2 += mahalanobis2(&r, &e);
        let cov = r.covariance.unwrap();
        for k in 0..6 {
            sq[k] += e[k] * e[k];
            predicted[k] += cov[(k, k)];
        }
        sigma2 += r.details.sigma_px.unwrap().powi(2);
    }
    let n = draws as f64;
    MonteCarlo {
        mean_d2: d2 / n,
        variance_ratio: std::array::from_fn(|k| sq[k] / predicted[k]),
        predicted: predicted.map(|p| p / n),
        mean_sigma2: sigma2 / n,
    }
}

/// The test: with the true σ given, `d²` is χ²₆ to first order, so its mean over N draws is 6 with
/// standard deviation √(2·6/N); each axis's `Σ e_k² / Σ Σ_kk` is χ²_N / N with standard deviation
/// √(2/N). Both must hold within 4 standard deviations (N = 500: ±0.62 and ±0.25).
fn assert_covariance_matches(mc: &MonteCarlo, draws: usize, label: &str) {
    let n = draws as f64;
    assert!(
        (mc.mean_d2 - 6.0).abs() < 4.0 * (12.0 / n).sqrt(),
        "{label}: mean d² = {}",
        mc.mean_d2
    );
    for (k, ratio) in mc.variance_ratio.iter().enumerate() {
        assert!(
            (ratio - 1.0).abs() < 4.0 * (2.0 / n).sqrt(),
            "{label}: axis {k} ratio {ratio}"
        );
    }
}

const DRAWS: usize = 500;

#[test]
fn covariance_matches_monte_carlo_errors_in_a_general_and_a_low_parallax_scene() {
    let mut given = PoseOptions::default();
    given.sigma_px = Some(1.0);
    let general = random_scene(SceneKind::General, 30, 10, 31);
    let mc_general = monte_carlo(&general, &given, 0.0, DRAWS, 31);
    assert_covariance_matches(&mc_general, DRAWS, "general");
    // Far and narrow: a 10-unit box at depth 50 spans ±80 px; rotation and depth are barely separable.
    let far = random_scene(SceneKind::Far, 30, 10, 32);
    let mc_far = monte_carlo(&far, &given, 0.0, DRAWS, 32);
    assert_covariance_matches(&mc_far, DRAWS, "far");
    // ... where the covariance is large: the rotation (about the image axes; the roll about the optical
    // axis stays well fixed) and the depth trade off against each other once perspective is weak.
    let trace = |p: &[f64; 6], axes: std::ops::Range<usize>| axes.map(|k| p[k]).sum::<f64>();
    let (far_p, general_p) = (&mc_far.predicted, &mc_general.predicted);
    assert!(
        trace(far_p, 0..3) > 10.0 * trace(general_p, 0..3),
        "{far_p:?} vs {general_p:?}"
    );
    assert!(
        trace(far_p, 3..6) > 100.0 * trace(general_p, 3..6),
        "{far_p:?} vs {general_p:?}"
    );
}

#[test]
fn estimated_sigma_is_close_to_the_true_one() {
    // σ̂² = Σ r² / (m − 6) with m = 2·40 residuals: mean σ² over N draws, std σ² √(2 / ((m − 6) N)).
    let scene = random_scene(SceneKind::General, 30, 10, 33);
    let mc = monte_carlo(&scene, &PoseOptions::default(), 0.0, DRAWS, 33);
    let std = (2.0 / (74.0 * DRAWS as f64)).sqrt();
    assert!((mc.mean_sigma2 - 1.0).abs() < 4.0 * std, "mean σ̂² = {}", mc.mean_sigma2);
}

#[test]
fn robust_covariance_matches_monte_carlo_errors_on_the_inliers() {
    let mut opts = robust(34);
    opts.sigma_px = Some(1.0);
    let scene = random_scene(SceneKind::General, 60, 15, 34);
    let mc = monte_carlo(&scene, &opts, 0.3, DRAWS, 34);
    assert_covariance_matches(&mc, DRAWS, "robust, 30 % outliers");
}
