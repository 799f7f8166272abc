//! Tests of the sampling loop on its own (the whole pipeline is tested in `tests/it/robust_pose.rs`).

use super::*;
use crate::synthetic::{random_scene, SceneKind};
use nalgebra::{Vector2, Vector3};

/// A noisy scene with the first `outliers` points replaced by random pixels (far from their truth).
fn scene_with_outliers(n_points: usize, outliers: usize, seed: u64) -> (crate::synthetic::Scene, Correspondences) {
    let scene = random_scene(SceneKind::General, n_points, 0, seed);
    let mut rng = Rng::new(seed + 100);
    let mut corr = scene.noisy(1.0, true, &mut rng);
    for p in corr.points2d.iter_mut().take(outliers) {
        let truth = *p;
        while (*p - truth).norm() < 50.0 {
            *p = Vector2::new(rng.uniform_in(0.0, 640.0), rng.uniform_in(0.0, 480.0));
        }
    }
    (scene, corr)
}

#[test]
fn loop_finds_the_inliers_and_stops_by_confidence() {
    let (scene, corr) = scene_with_outliers(60, 30, 7);
    let out = ransac(
        &scene.camera.intrinsics(),
        &corr,
        &RansacOptions::default(),
        &TrustRegionOptions::default(),
    )
    .unwrap();
    assert_eq!(out.report.stop, RansacStop::Confidence);
    // Outliers are at least 50 px off; inliers have 1 px Gaussian noise (P(e > 4 px) = e^{-8} each).
    assert!(out.inliers_points[..30].iter().all(|&m| !m));
    assert!(out.inliers_points[30..].iter().all(|&m| m));
    assert!(out.report.local_optimizations >= 1);
    // ε = 1/2 for points only: ⌈ln(1e-4)/ln(7/8)⌉ = 69 samples once the best model is found; the SPRT
    // keeps the pose of an all-inlier sample with probability 1 − 1/A, A ≥ 50 here (MODEL_COST C / m_S
    // with C ≈ ln 2 and m_S ≤ 2): at most ⌈ln(1e-4)/ln(1 − 0.98/8)⌉ = 71 samples.
    assert!(out.report.iterations <= 71, "{:?}", out.report);
    let Pose {
        rotation: r,
        translation: _,
    } = out.pose.unwrap();
    assert!(crate::geometry::quaternion::rotation_distance(&r, &scene.rotation) < 0.01);
    let without = RansacOptions {
        sprt: false,
        ..RansacOptions::default()
    };
    let plain = ransac(
        &scene.camera.intrinsics(),
        &corr,
        &without,
        &TrustRegionOptions::default(),
    )
    .unwrap();
    assert!(plain.report.iterations <= 69, "{:?}", plain.report);
    assert_eq!(
        (plain.inliers_points, plain.report.sprt_rejections),
        (out.inliers_points, 0)
    );
}

#[test]
fn budget_and_cap_bound_the_loop() {
    let (scene, corr) = scene_with_outliers(40, 40, 8);
    let capped = RansacOptions {
        max_iterations: 25,
        ..RansacOptions::default()
    };
    let out = ransac(
        &scene.camera.intrinsics(),
        &corr,
        &capped,
        &TrustRegionOptions::default(),
    )
    .unwrap();
    assert_eq!((out.report.stop, out.report.iterations), (RansacStop::IterationCap, 25));
    let no_time = RansacOptions {
        time_budget: Some(Duration::ZERO),
        ..RansacOptions::default()
    };
    let out = ransac(
        &scene.camera.intrinsics(),
        &corr,
        &no_time,
        &TrustRegionOptions::default(),
    )
    .unwrap();
    assert_eq!((out.report.stop, out.report.iterations), (RansacStop::TimeBudget, 0));
    assert!(out.pose.is_none() && out.inliers_points.iter().all(|&m| !m));
}

#[test]
fn same_seed_same_result_other_seed_other_samples() {
    let (scene, corr) = scene_with_outliers(50, 25, 9);
    let run = |seed| {
        let opts = RansacOptions {
            seed,
            ..RansacOptions::default()
        };
        ransac(&scene.camera.intrinsics(), &corr, &opts, &TrustRegionOptions::default()).unwrap()
    };
    let (a, b, c) = (run(3), run(3), run(4));
    assert_eq!(a.pose, b.pose);
    assert_eq!(a.report.iterations, b.report.iterations);
    assert_eq!(a.inliers_points, b.inliers_points);
    assert!(a.pose != c.pose || a.report.iterations != c.report.iterations);
}

#[test]
fn degenerate_samples_give_no_hypothesis_and_are_counted() {
    // One object point seen four times and one other point: every sample repeats an object point,
    // for which P3P has no solution.
    let camera = Intrinsics::new(800.0, 800.0, 320.0, 240.0, 0.0).unwrap();
    let (a, b) = (Vector3::new(0.1, 0.2, 5.0), Vector3::new(-0.3, 0.1, 6.0));
    let points3d = vec![a, a, a, a, b];
    let points2d = points3d.iter().map(|x| camera.project(x)).collect();
    let corr = Correspondences {
        points2d,
        points3d,
        ..Default::default()
    };
    let opts = RansacOptions {
        max_iterations: 50,
        ..RansacOptions::default()
    };
    let out = ransac(&camera, &corr, &opts, &TrustRegionOptions::default()).unwrap();
    assert!(out.pose.is_none());
    assert_eq!(out.report.stop, RansacStop::IterationCap);
    assert_eq!((out.report.degenerate_samples, out.report.models_scored), (50, 0));
}
