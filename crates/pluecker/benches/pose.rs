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
//! Run: `cargo bench -p pluecker --bench pose` (a few minutes on 2 cores), or append `-- --quick` for a
//! rough pass, or `-- pipeline/100` to filter.

use criterion::{black_box, criterion_group, criterion_main, BenchmarkId, Criterion};
use pluecker::geometry::quaternion::rotation_distance;
use pluecker::pose::{estimate_pose, Correspondences, Method, PoseOptions, Status};
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
    Problem { name: "30-lines", n_points: 0, n_lines: 30, seed: 11 },
    Problem { name: "100-points", n_points: 100, n_lines: 0, seed: 12 },
    Problem { name: "50-points-20-lines", n_points: 50, n_lines: 20, seed: 13 },
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
    group.sample_size(30).measurement_time(Duration::from_secs(2)).warm_up_time(Duration::from_millis(500));
    for problem in &PROBLEMS {
        let (scene, corr) = noisy_problem(problem);
        let camera = scene.camera;
        for method in Method::ALL {
            let opts = PoseOptions { method, refine, ..Default::default() };
            let id = format!("{group_name}/{}/{}", problem.name, method.as_str());
            match estimate_pose(&camera, &corr, &opts) {
                Err(e) => {
                    eprintln!("setup {id}: skipped ({e})");
                    continue;
                }
                Ok(r) => {
                    let rotation_error = rotation_distance(&r.rotation, &scene.rotation);
                    let failed = r.status != Status::Success || rotation_error.is_nan() || rotation_error > FAILED_ROTATION_RAD;
                    eprintln!(
                        "setup {id}: {} status {} iterations {} rotation error {rotation_error:.2e} rad translation error {:.2e}",
                        if failed { "FAILED" } else { "ok" },
                        r.status.as_str(),
                        r.iterations,
                        (r.translation - scene.translation).norm(),
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

criterion_group!(benches, estimator, pipeline);
criterion_main!(benches);
