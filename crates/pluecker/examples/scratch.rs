use pluecker::pose::candidates::minimal_hypotheses;
use pluecker::pose::{estimate_pose, PoseOptions};
use pluecker::rng::Rng;
use pluecker::synthetic::visible_scene;
use std::time::Instant;
fn main() {
    let f: f64 = std::env::args().nth(1).and_then(|a| a.parse().ok()).unwrap_or(800.0);
    let np: usize = std::env::args().nth(2).and_then(|a| a.parse().ok()).unwrap_or(100);
    let nl: usize = std::env::args().nth(3).and_then(|a| a.parse().ok()).unwrap_or(0);
    let opts = PoseOptions::default();
    let (mut th, mut te, mut nh, mut stages_it) = (0.0, 0.0, 0, 0);
    let mut refinements = 0usize;
    let n = 200;
    for seed in 0..n {
        let scene = visible_scene(f, np, nl, false, seed);
        let corr = scene.noisy(1.0, true, &mut Rng::new(seed + 7));
        let t0 = Instant::now();
        for _ in 0..10 { nh += minimal_hypotheses(&scene.camera, &corr).flatten().count(); }
        th += t0.elapsed().as_secs_f64() / 10.0;
        let t0 = Instant::now();
        let mut r = None;
        for _ in 0..10 { r = Some(estimate_pose(&scene.camera, &corr, &opts).unwrap()); }
        te += t0.elapsed().as_secs_f64() / 10.0;
        let r = r.unwrap();
        stages_it += r.stages.last().unwrap().iterations;
        refinements += r.stages.len();
    }
    let n = n as f64;
    println!("hypotheses {:.1} µs ({:.1} per call), estimate {:.1} µs, refinement iterations {:.1}, stages {:.1}", th / n * 1e6, nh as f64 / n / 10.0, te / n * 1e6, stages_it as f64 / n, refinements as f64 / n);
}
