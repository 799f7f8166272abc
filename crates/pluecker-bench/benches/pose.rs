//! Time of every pose estimator, alone and followed by the reprojection refinement.
//!
//! Problems: 30 lines, 100 points, 50 points + 20 lines, each a `SceneKind::General` random scene with
//! 1 px Gaussian pixel noise on every image point and segment endpoint (fixed seeds, so every run times
//! the same inputs). Two groups:
//! - `estimator/<problem>/<method>`: the algebraic stage only (`refine: false`);
//! - `pipeline/<problem>/<method>`: the default pipeline, estimator + refinement (`refine: true`).
//!
//! A combination the method cannot take (the linear method on lines only) is skipped when
//! `estimate_pose` returns `Err` at setup. Every other one is timed, and at setup one line per
//! combination goes to stderr with its status, iterations and rotation / translation error against the
//! truth, so that a fast wrong answer cannot pass unnoticed (`FAILED` marks a status other than
//! `success` or a rotation error above 0.1 rad).
//!
//! A third group, `robust/<outliers>`, times the robust pipeline (`PoseOptions::ransac`, LO-RANSAC then
//! the refinement on the inliers, default options, seed 0) on 100 points + 30 lines with 1 px noise where
//! 0, 25, 50 or 75 % of the points and of the lines are replaced by random observations (a random pixel,
//! a random segment of at least 40 px) in the 640 x 480 image; its setup line adds the samples drawn,
//! the inliers found and the number of true inliers missed or outliers kept.
//!
//! Run: `cargo bench -p pluecker-bench --bench pose` (a few minutes on 2 cores), or append `-- --quick` for a
//! rough pass, or `-- pipeline/100` to filter.

// `!(x > 0.0)` is true for NaN: the NaN guard used throughout (a NaN must take the failing branch).
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use criterion::{black_box, criterion_group, criterion_main, BenchmarkId, Criterion};
use nalgebra::Vector2;
use pluecker::geometry::rotation_distance;
use pluecker::pose::ReprojectionCost;
use pluecker::pose::{estimate_pose, Correspondences, Method, PoseOptions, RansacOptions, Status};
use pluecker::rng::Rng;
use pluecker::synthetic::{random_scene, Scene, SceneKind};
use std::time::Duration;

/// A benchmark problem: a name for the report and the counts of each correspondence kind.
struct Problem {
    name: &'static str,
    n_points: usize,
    n_lines: usize,
    seed: u64,
}

const PROBLEMS: [Problem; 3] = [
    Problem {
        name: "30-lines",
        n_points: 0,
        n_lines: 30,
        seed: 11,
    },
    Problem {
        name: "100-points",
        n_points: 100,
        n_lines: 0,
        seed: 12,
    },
    Problem {
        name: "50-points-20-lines",
        n_points: 50,
        n_lines: 20,
        seed: 13,
    },
];

/// Pixel noise, standard deviation.
const SIGMA_PX: f64 = 1.0;

/// Rotation error (rad) above which a setup answer is flagged as failed.
const FAILED_ROTATION_RAD: f64 = 0.1;

fn noisy_problem(problem: &Problem) -> (Scene, Correspondences) {
    let scene = random_scene(SceneKind::General, problem.n_points, problem.n_lines, problem.seed);
    let corr = scene.noisy(SIGMA_PX, true, &mut Rng::new(problem.seed));
    (scene, corr)
}

fn bench_group(c: &mut Criterion, group_name: &str, refine: bool) {
    let mut group = c.benchmark_group(group_name);
    group
        .sample_size(30)
        .measurement_time(Duration::from_secs(2))
        .warm_up_time(Duration::from_millis(500));
    for problem in &PROBLEMS {
        let (scene, corr) = noisy_problem(problem);
        let camera = scene.camera;
        for &method in Method::ALL {
            let mut opts = PoseOptions::default();
            opts.method = method;
            opts.refine = refine;
            let id = format!("{group_name}/{}/{}", problem.name, method.as_str());
            match estimate_pose(&camera, &corr, &opts) {
                Err(e) => {
                    eprintln!("setup {id}: skipped ({e})");
                    continue;
                }
                Ok(r) => {
                    let rotation_error = rotation_distance(&r.pose.rotation, &scene.rotation);
                    let failed = r.report.status != Status::Success
                        || rotation_error.is_nan()
                        || rotation_error > FAILED_ROTATION_RAD;
                    eprintln!(
                        "setup {id}: {} status {} iterations {} rotation error {rotation_error:.2e} rad translation error {:.2e}",
                        if failed { "FAILED" } else { "ok" },
                        r.report.status.as_str(),
                        r.report.iterations,
                        (r.pose.translation - scene.translation).norm(),
                    );
                }
            }
            group.bench_with_input(BenchmarkId::new(problem.name, method.as_str()), &opts, |b, opts| {
                b.iter(|| estimate_pose(black_box(&camera), black_box(&corr), opts))
            });
        }
    }
    group.finish();
}

fn estimator(c: &mut Criterion) {
    bench_group(c, "estimator", false);
}

fn pipeline(c: &mut Criterion) {
    bench_group(c, "pipeline", true);
}

/// Outlier ratios of the `robust` group.
const OUTLIER_RATIOS: [f64; 4] = [0.0, 0.25, 0.5, 0.75];
/// Inlier threshold of the `robust` group (the default), pixels.
const THRESHOLD_PX: f64 = 4.0;

/// 100 points + 30 lines, 1 px noise, a fraction `ratio` of each kind replaced by random observations.
fn outlier_problem(ratio: f64, seed: u64) -> (Scene, Correspondences) {
    let (n_points, n_lines) = (100, 30);
    let scene = random_scene(SceneKind::General, n_points, n_lines, seed);
    let mut rng = Rng::new(seed);
    let mut corr = scene.noisy(SIGMA_PX, true, &mut rng);
    let pixel = |rng: &mut Rng| Vector2::new(rng.uniform_in(0.0, 640.0), rng.uniform_in(0.0, 480.0));
    for i in rng.sample_indices(n_points, (ratio * n_points as f64).round() as usize) {
        corr.points2d[i] = pixel(&mut rng);
    }
    for i in rng.sample_indices(n_lines, (ratio * n_lines as f64).round() as usize) {
        corr.lines2d[i] = loop {
            let s = [pixel(&mut rng), pixel(&mut rng)];
            if (s[0] - s[1]).norm() > 40.0 {
                break s;
            }
        };
    }
    (scene, corr)
}

fn robust(c: &mut Criterion) {
    let mut group = c.benchmark_group("robust");
    group
        .sample_size(30)
        .measurement_time(Duration::from_secs(3))
        .warm_up_time(Duration::from_millis(500));
    let mut opts = PoseOptions::default();
    opts.ransac = Some(RansacOptions::default());
    for ratio in OUTLIER_RATIOS {
        let (scene, corr) = outlier_problem(ratio, 14);
        let name = format!("100-points-30-lines-{}pct-outliers", (100.0 * ratio).round());
        let r = estimate_pose(&scene.camera, &corr, &opts).expect("valid input");
        let truth = ReprojectionCost::exact(&scene.camera, &corr)
            .unwrap()
            .errors(&pluecker::Pose::new(scene.rotation, scene.translation));
        let mask: Vec<bool> = r.inliers_points.iter().chain(&r.inliers_lines).copied().collect();
        let missed = truth
            .iter()
            .zip(&mask)
            .filter(|(e, m)| **e <= THRESHOLD_PX && !**m)
            .count();
        let kept = truth
            .iter()
            .zip(&mask)
            .filter(|(e, m)| **e > THRESHOLD_PX && **m)
            .count();
        let rotation_error = rotation_distance(&r.pose.rotation, &scene.rotation);
        let report = r.details.ransac.as_ref().expect("robust report");
        let failed = r.report.status != Status::Success || !(rotation_error <= FAILED_ROTATION_RAD);
        eprintln!(
            "setup robust/{name}: {} status {} samples {} models {} LO {} inliers {} (true inliers missed {missed}, outliers kept {kept}) rotation error {rotation_error:.2e} rad translation error {:.2e}",
            if failed { "FAILED" } else { "ok" },
            r.report.status.as_str(),
            report.iterations,
            report.models_scored,
            report.local_optimizations,
            mask.iter().filter(|&&m| m).count(),
            (r.pose.translation - scene.translation).norm(),
        );
        group.bench_function(name, |b| {
            b.iter(|| estimate_pose(black_box(&scene.camera), black_box(&corr), &opts))
        });
    }
    group.finish();
}

criterion_group!(benches, estimator, pipeline, robust);
criterion_main!(benches);
