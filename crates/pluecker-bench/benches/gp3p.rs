//! Time per call of the generalised P3P solver (`pose::minimal::gp3p`), and its stability histogram.
//!
//! The instances are seeded noise-free rigs: three camera centres in a ball of radius 0.5 m, each seeing
//! one point 2-20 m away in a uniformly random direction, under a uniform rotation and a translation up
//! to 10 m (the distribution of the solver's own tests). Criterion times one call per instance over
//! a fixed set of 1000, so its time divided by 1000 is the mean time per call over that set; at setup
//! one line goes to stderr: how many instances have the true pose among the solutions to 1e-8 rad, the
//! mean number of solutions, and the median time of a single call over the set.
//!
//! With `GP3P_HISTOGRAM=1`, after the timing, the stability histogram over 100,000 other instances:
//! log10 of the rotation error (radians) of the returned pose closest to the truth, one bin per decade
//! from 1e-16 to 1, and the instances with no solution.
//!
//! Run: `cargo bench -p pluecker-bench --bench gp3p` (about 15 s; `-- --quick` for a rough pass), and
//! `GP3P_HISTOGRAM=1 cargo bench -p pluecker-bench --bench gp3p` for the histogram too (a few seconds
//! more).

use criterion::{black_box, criterion_group, Criterion};
use nalgebra::{Matrix3, Vector3};
use pluecker::pose::generalized::Ray;
use pluecker::pose::minimal::{gp3p, Pose};
use pluecker::rng::Rng;
use std::time::{Duration, Instant};

/// Instances timed per criterion iteration.
const SAMPLES: usize = 1000;

/// Instances of the stability histogram.
const HISTOGRAM_SAMPLES: usize = 100_000;

/// A noise-free instance and its true pose.
struct Instance {
    rays: [Ray; 3],
    points: [Vector3<f64>; 3],
    rotation: Matrix3<f64>,
}

/// A random rig (see the file's documentation).
fn instance(rng: &mut Rng) -> Instance {
    let rotation = rng.rotation();
    let translation = rng.unit_vector3() * rng.uniform_in(0.0, 10.0);
    let mut rays = [Ray {
        origin: Vector3::zeros(),
        direction: Vector3::zeros(),
    }; 3];
    let mut points = [Vector3::zeros(); 3];
    for (ray, point) in rays.iter_mut().zip(&mut points) {
        let origin = rng.unit_vector3() * (0.5 * rng.uniform().cbrt());
        let direction = rng.unit_vector3();
        let rig = origin + direction * rng.uniform_in(2.0, 20.0);
        *ray = Ray { origin, direction };
        *point = rotation.transpose() * (rig - translation);
    }
    Instance { rays, points, rotation }
}

/// The smallest rotation angle (radians) between a returned pose and the truth, ∞ if none:
/// `‖R − R*‖_F = 2√2 sin(θ/2)`, accurate for small angles.
fn rotation_error(poses: &[Pose], truth: &Matrix3<f64>) -> f64 {
    poses
        .iter()
        .map(|p| 2.0 * ((p.rotation - truth).norm() / 8f64.sqrt()).min(1.0).asin())
        .fold(f64::INFINITY, f64::min)
}

/// The median over `instances` of the time of one call (each timed alone, best of five rounds).
fn median_call_time(instances: &[Instance]) -> Duration {
    let mut times: Vec<Duration> = instances
        .iter()
        .map(|inst| {
            (0..5)
                .map(|_| {
                    let start = Instant::now();
                    black_box(gp3p(black_box(&inst.rays), black_box(&inst.points)));
                    start.elapsed()
                })
                .min()
                .unwrap_or_default()
        })
        .collect();
    times.sort();
    times[times.len() / 2]
}

fn bench_gp3p(c: &mut Criterion) {
    let mut rng = Rng::new(81);
    let instances: Vec<Instance> = (0..SAMPLES).map(|_| instance(&mut rng)).collect();
    let (mut found, mut solutions) = (0, 0);
    for inst in &instances {
        let poses = gp3p(&inst.rays, &inst.points);
        solutions += poses.len();
        found += usize::from(rotation_error(&poses, &inst.rotation) <= 1e-8);
    }
    eprintln!(
        "gp3p: truth within 1e-8 rad in {found}/{SAMPLES} instances, {:.2} solutions per instance, median \
         call {:.2} µs",
        solutions as f64 / SAMPLES as f64,
        median_call_time(&instances).as_secs_f64() * 1e6
    );
    let mut group = c.benchmark_group("minimal");
    group
        .sample_size(30)
        .measurement_time(Duration::from_secs(5))
        .warm_up_time(Duration::from_millis(500));
    group.bench_function(format!("gp3p/{SAMPLES}-instances"), |b| {
        b.iter(|| {
            for inst in &instances {
                black_box(gp3p(black_box(&inst.rays), black_box(&inst.points)));
            }
        })
    });
    group.finish();
}

/// The stability histogram (`GP3P_HISTOGRAM=1`): bin `k` of the 16 holds errors in
/// `[10^(k−16), 10^(k−15))`, the first also everything below (exact zeros included), the last also
/// everything above.
fn histogram() {
    let mut rng = Rng::new(82);
    let mut bins = [0usize; 16];
    let mut none = 0;
    let mut elapsed = Duration::ZERO;
    for _ in 0..HISTOGRAM_SAMPLES {
        let inst = instance(&mut rng);
        let start = Instant::now();
        let poses = gp3p(&inst.rays, &inst.points);
        elapsed += start.elapsed();
        let error = rotation_error(&poses, &inst.rotation);
        if !error.is_finite() {
            none += 1;
            continue;
        }
        let decade = if error > 0.0 { error.log10().floor() } else { -16.0 };
        bins[(decade + 16.0).clamp(0.0, 15.0) as usize] += 1;
    }
    let n = HISTOGRAM_SAMPLES as f64;
    println!();
    println!(
        "gp3p stability: rotation error (rad) of the closest pose, {HISTOGRAM_SAMPLES} random rigs, mean \
         call {:.2} µs",
        elapsed.as_secs_f64() * 1e6 / n
    );
    println!("| log10 error | instances | fraction | cumulative |");
    println!("|---|---|---|---|");
    let mut cumulative = 0;
    for (k, &count) in bins.iter().enumerate() {
        cumulative += count;
        let label = match k {
            0 => "< -15".to_string(),
            15 => ">= -1".to_string(),
            _ => format!("[{}, {})", k as i32 - 16, k as i32 - 15),
        };
        println!(
            "| {label} | {count} | {:.5} | {:.5} |",
            count as f64 / n,
            cumulative as f64 / n
        );
    }
    println!("| no solution | {none} | {:.5} | |", none as f64 / n);
    let below = |decade: i32| bins[..(decade + 16) as usize].iter().sum::<usize>() as f64 / n;
    println!(
        "below 1e-12: {:.5}, below 1e-8: {:.5}, below 1e-4: {:.5}, no solution: {:.5}",
        below(-12),
        below(-8),
        below(-4),
        none as f64 / n
    );
}

criterion_group!(benches, bench_gp3p);

fn main() {
    benches();
    Criterion::default().configure_from_args().final_summary();
    if std::env::var("GP3P_HISTOGRAM").is_ok_and(|v| v == "1") {
        histogram();
    }
}
