//! A driver for profiling and regression-checking the default pose pipeline (not a benchmark: use
//! `cargo bench -p pluecker-bench --bench pose` and `bench/compare_pose.py` for reported numbers).
//!
//! ```text
//! profile_pose time  <kind> [calls] [lines]          µs per call over 200 scenes, cycled; iterations
//! profile_pose dump  <kind> <scenes> <file> [lines]  write every scene's pose to <file>
//! profile_pose check <kind> <scenes> <file> [lines]  compare with a dump, and with the truth
//! ```
//!
//! `<kind>` is `general`, `planar` or `far`; scenes are `random_scene(kind, 100, 0, seed)` (or 50 points
//! and 20 segments with `lines`) with 1 px Gaussian noise, seeds `0..scenes`, as in
//! `bench/compare_pose.py`. `check` prints the largest difference from the dumped poses in units of
//! the Cramér-Rao bound (a pure speed change should leave it far below 1), the failures (status other
//! than success, or an error above 10 bounds) and the RMS errors over the RMS bounds.
//! Run with `cargo bench -p pluecker-bench --bench profile_pose -- time general`; build with
//! `CARGO_PROFILE_BENCH_DEBUG=true cargo bench -p pluecker-bench --bench profile_pose --no-run` for
//! `perf record -g`.
//!
//! For experiments, environment variables override the default options: `ALGEBRAIC_RADIUS` and
//! `ALGEBRAIC_STEP` (initial radius and step tolerance of the algebraic trust region; with refinement
//! its step tolerance is at least `STEP_TOLERANCE_BEFORE_REFINEMENT`), `REFINE_RADIUS`, `REFINE_STEP`.

use nalgebra::{Matrix3, Vector3};
use pluecker::geometry::rotation_distance;
use pluecker::pose::{estimate_pose, Correspondences, PoseOptions, Status};
use pluecker::pose::{pose_covariance, ReprojectionCost};
use pluecker::rng::Rng;
use pluecker::synthetic::{random_scene, Scene, SceneKind};
use std::io::Write;

fn kind(name: &str) -> SceneKind {
    match name {
        "far" => SceneKind::Far,
        "planar" => SceneKind::Planar,
        "general" => SceneKind::General,
        _ => panic!("kind must be general, planar or far"),
    }
}

fn problem(kind: SceneKind, seed: u64, lines: bool) -> (Scene, Correspondences) {
    let (np, nl) = if lines { (50, 20) } else { (100, 0) };
    let scene = random_scene(kind, np, nl, seed);
    let corr = scene.noisy(1.0, true, &mut Rng::new(seed));
    (scene, corr)
}

fn options() -> PoseOptions {
    let mut o = PoseOptions::default();
    let env = |name: &str| std::env::var(name).ok().map(|v| v.parse::<f64>().expect("a number"));
    if let Some(v) = env("ALGEBRAIC_RADIUS") {
        o.trust_region.initial_radius = v;
    }
    if let Some(v) = env("ALGEBRAIC_STEP") {
        o.trust_region.stopping.step_tolerance = v;
    }
    if let Some(v) = env("REFINE_RADIUS") {
        o.refinement.initial_radius = v;
    }
    if let Some(v) = env("REFINE_STEP") {
        o.refinement.stopping.step_tolerance = v;
    }
    o
}

fn time(kind: SceneKind, calls: usize, lines: bool) {
    let problems: Vec<_> = (0..200).map(|i| problem(kind, i, lines)).collect();
    let opts = options();
    let started = std::time::Instant::now();
    let mut iterations = [0usize; 2];
    for k in 0..calls {
        let (scene, corr) = &problems[k % problems.len()];
        let r = estimate_pose(&scene.camera, corr, &opts).unwrap();
        iterations[0] += r.details.stages[0].iterations;
        iterations[1] += r.details.stages.last().unwrap().iterations;
    }
    let per_call = started.elapsed().as_secs_f64() / calls as f64;
    println!(
        "{:.2} us/call, algebraic iterations {:.2}, refinement iterations {:.2}",
        per_call * 1e6,
        iterations[0] as f64 / calls as f64,
        iterations[1] as f64 / calls as f64
    );
}

fn dump(kind: SceneKind, scenes: u64, path: &str, lines: bool) {
    let mut out = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    for seed in 0..scenes {
        let (scene, corr) = problem(kind, seed, lines);
        let r = estimate_pose(&scene.camera, &corr, &PoseOptions::default()).unwrap();
        let values: Vec<String> = r
            .pose
            .rotation
            .iter()
            .chain(r.pose.translation.iter())
            .map(|v| format!("{v:e}"))
            .collect();
        writeln!(out, "{}", values.join(" ")).unwrap();
    }
}

fn check(kind: SceneKind, scenes: u64, path: &str, lines: bool) {
    let reference: Vec<(Matrix3<f64>, Vector3<f64>)> = std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .map(|l| {
            let v: Vec<f64> = l.split(' ').map(|s| s.parse().unwrap()).collect();
            (
                Matrix3::from_column_slice(&v[..9]),
                Vector3::from_column_slice(&v[9..12]),
            )
        })
        .collect();
    let (mut worst_r, mut worst_t) = (0.0f64, 0.0f64);
    let (mut err_r, mut err_t, mut bound_r, mut bound_t) = (0.0, 0.0, 0.0, 0.0);
    let mut failures = 0;
    let mut iterations = [0usize; 2];
    for seed in 0..scenes {
        let (scene, corr) = problem(kind, seed, lines);
        let r = estimate_pose(&scene.camera, &corr, &options()).unwrap();
        let c = &scene.correspondences;
        let cost = ReprojectionCost::exact(&scene.camera, c).unwrap();
        let cov = pose_covariance(&cost, &pluecker::Pose::new(scene.rotation, scene.translation), 1.0).unwrap();
        let (br, bt) = (
            cov.fixed_view::<3, 3>(0, 0).trace(),
            cov.fixed_view::<3, 3>(3, 3).trace(),
        );
        let (er, et) = (
            rotation_distance(&r.pose.rotation, &scene.rotation),
            (r.pose.translation - scene.translation).norm(),
        );
        iterations[0] += r.details.stages[0].iterations;
        iterations[1] += r.details.stages.last().unwrap().iterations;
        if r.report.status != Status::Success || !(er <= 10.0 * br.sqrt() && et <= 10.0 * bt.sqrt()) {
            failures += 1;
            println!(
                "seed {seed}: status {} rotation error {er:.3e} (bound {:.3e})",
                r.report.status.as_str(),
                br.sqrt()
            );
            continue;
        }
        (err_r, err_t, bound_r, bound_t) = (err_r + er * er, err_t + et * et, bound_r + br, bound_t + bt);
        if let Some((rot, t)) = reference.get(seed as usize) {
            worst_r = worst_r.max(rotation_distance(&r.pose.rotation, rot) / br.sqrt());
            worst_t = worst_t.max((r.pose.translation - t).norm() / bt.sqrt());
        }
    }
    println!(
        "{scenes} scenes: failures {failures}; largest difference from the dump: rotation {worst_r:.2e}, translation \
         {worst_t:.2e} bounds; rms error / rms bound: rotation {:.4}, translation {:.4}; iterations {:.2} + {:.2}",
        (err_r / bound_r).sqrt(),
        (err_t / bound_t).sqrt(),
        iterations[0] as f64 / scenes as f64,
        iterations[1] as f64 / scenes as f64
    );
}

fn main() {
    // `cargo bench` appends `--bench` to the arguments.
    let args: Vec<String> = std::env::args().filter(|a| a != "--bench").collect();
    let arg = |i: usize| args.get(i).map(String::as_str);
    let lines = args.iter().any(|a| a == "lines");
    match (arg(1), arg(2)) {
        (Some("time"), Some(k)) => time(kind(k), arg(3).and_then(|s| s.parse().ok()).unwrap_or(20000), lines),
        (Some("dump"), Some(k)) => dump(kind(k), arg(3).unwrap().parse().unwrap(), arg(4).unwrap(), lines),
        (Some("check"), Some(k)) => check(kind(k), arg(3).unwrap().parse().unwrap(), arg(4).unwrap(), lines),
        _ => eprintln!("usage: profile_pose time|dump|check <general|planar|far> ..."),
    }
}
