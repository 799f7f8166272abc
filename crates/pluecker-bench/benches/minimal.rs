//! Time per call of the four minimal pose solvers (`pose::minimal`), on seeded noise-free random samples.
//!
//! Each solver is timed over the same 200 samples (features with depth 1-6 in a ±45° frustum, uniform
//! rotations, translations up to 4), one call per sample per iteration, so criterion's time divided by
//! 200 is the mean time per call over that set. At setup one line per solver goes to stderr: how many
//! samples have the true pose among the solutions to 1e-8, and the mean number of solutions — a fast
//! wrong answer cannot pass unnoticed.
//!
//! Run: `cargo bench -p pluecker-bench --bench minimal` (about a minute), `-- --quick` for a rough pass.

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use nalgebra::Vector3;
use pluecker::pose::minimal::{solve, Feature, Pose};
use pluecker::rng::Rng;
use std::time::Duration;

/// Samples per solver.
const SAMPLES: usize = 200;

/// A camera-frame point with depth in [1, 6] in the frustum `|x|, |y| ≤ z`.
fn camera_point(rng: &mut Rng) -> Vector3<f64> {
    let z = rng.uniform_in(1.0, 6.0);
    Vector3::new(z * rng.uniform_in(-1.0, 1.0), z * rng.uniform_in(-1.0, 1.0), z)
}

/// A random sample of `n_points` points then `3 − n_points` lines, and its true pose.
fn sample(rng: &mut Rng, n_points: usize) -> ([Feature; 3], Pose) {
    let (r, t) = (rng.rotation(), rng.unit_vector3() * rng.uniform_in(0.0, 4.0));
    let to_world = |c: &Vector3<f64>| r.transpose() * (c - t);
    let features = std::array::from_fn(|i| {
        if i < n_points {
            let c = camera_point(rng);
            Feature::Point {
                bearing: c,
                point: to_world(&c),
            }
        } else {
            let (a, b) = (camera_point(rng), camera_point(rng));
            Feature::Line {
                normal: a.cross(&b),
                endpoints: [to_world(&a), to_world(&b)],
            }
        }
    });
    (features, Pose::new(r, t))
}

fn bench_minimal(c: &mut Criterion) {
    let mut group = c.benchmark_group("minimal");
    group
        .sample_size(30)
        .measurement_time(Duration::from_secs(3))
        .warm_up_time(Duration::from_millis(500));
    for (name, n_points, seed) in [("p3p", 3, 71), ("p2p1l", 2, 72), ("p1p2l", 1, 73), ("p3l", 0, 74)] {
        let mut rng = Rng::new(seed);
        let samples: Vec<_> = (0..SAMPLES).map(|_| sample(&mut rng, n_points)).collect();
        let (mut found, mut solutions) = (0, 0);
        for (
            features,
            Pose {
                rotation: r,
                translation: t,
            },
        ) in &samples
        {
            let poses = solve(features);
            solutions += poses.len();
            let scale = t.norm().max(10.0);
            if poses
                .iter()
                .any(|p| (p.rotation - r).norm() <= 1e-8 && (p.translation - t).norm() <= 1e-8 * scale)
            {
                found += 1;
            }
        }
        eprintln!(
            "{name}: truth within 1e-8 in {found}/{SAMPLES} samples, {:.2} solutions per sample",
            solutions as f64 / SAMPLES as f64
        );
        group.bench_function(format!("{name}/{SAMPLES}-samples"), |b| {
            b.iter(|| {
                for (features, _) in &samples {
                    black_box(solve(black_box(features)));
                }
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench_minimal);
criterion_main!(benches);
