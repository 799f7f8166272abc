//! How often the default pose pipeline misses the global minimum of the reprojection error,
//! quickly, in Rust: for each row of seeded `visible_scene`s with 1 px noise, the best known minimum is
//! the cheapest of the default answer, the refinement from the true pose and from `--starts` random
//! starts. Development tool; the benchmark with peers is `bench/compare_global_pose.py`.
//!
//!     cargo bench -p pluecker-bench --bench global_pose -- [scenes] [starts] [row filter]
//!
//! `CERTIFY=1` certifies every answer (`MAX_NODES=n` sets the node cap); `NODES=1` prints each scene's
//! certificate nodes to stderr, `WHY=1` the reason of each uncertified answer.

use nalgebra::Vector3;
use pluecker::optim::Objective;
use pluecker::pose::ReprojectionCost;
use pluecker::pose::{estimate_pose, refine_pose, PoseOptions};
use pluecker::rng::Rng;
use pluecker::synthetic::visible_scene;
use pluecker::Pose;
use std::time::Instant;

fn main() {
    // `cargo bench` appends `--bench` to the arguments.
    let given: Vec<String> = std::env::args().skip(1).filter(|a| a != "--bench").collect();
    let args: Vec<usize> = given.iter().filter_map(|a| a.parse().ok()).collect();
    let scenes = args.first().copied().unwrap_or(150);
    let starts = args.get(1).copied().unwrap_or(30);
    let filter = given.into_iter().find(|a| a.parse::<usize>().is_err());
    let mut rows: Vec<(f64, usize, usize, bool)> = vec![];
    for f in [250.0, 800.0, 4000.0, 15000.0] {
        for n in [4usize, 6, 10, 100] {
            rows.push((f, n, 0, false));
            rows.push((f, 0, n, false));
            rows.push((f, n.div_ceil(2), n / 2, false));
        }
    }
    for f in [800.0, 4000.0] {
        for n in [4usize, 6, 10, 100] {
            rows.push((f, n, 0, true));
            rows.push((f, n.div_ceil(2), n / 2, true));
        }
    }
    println!("| row | misses | of those success | of those ambiguous | certified | median µs | p95 µs |");
    println!("|---|---|---|---|---|---|---|");
    let mut opts = PoseOptions::default();
    if std::env::var("CERTIFY").is_ok() {
        let mut certify = pluecker::CertifyOptions::default();
        certify.max_nodes = std::env::var("MAX_NODES").ok().and_then(|v| v.parse().ok());
        opts.certify = Some(certify);
    }
    for (f, np, nl, planar) in rows {
        let name = format!("f={f} {np}p+{nl}l{}", if planar { " planar" } else { "" });
        if filter.as_ref().is_some_and(|s| !name.contains(s.as_str())) {
            continue;
        }
        let (mut misses, mut miss_success, mut miss_ambiguous, mut certified) = (0, 0, 0, 0);
        let mut times = vec![];
        for seed in 0..scenes as u64 {
            let scene = visible_scene(f, np, nl, planar, seed);
            let mut rng = Rng::new(1000 + seed);
            let corr = scene.noisy(1.0, true, &mut rng);
            let started = Instant::now();
            let Ok(result) = estimate_pose(&scene.camera, &corr, &opts) else {
                continue;
            };
            times.push(started.elapsed().as_secs_f64() * 1e6);
            if std::env::var("NODES").is_ok() {
                eprintln!("nodes {seed} {:?}", result.report.certificate.as_ref().map(|c| c.nodes));
            }
            let cost = ReprojectionCost::exact(&scene.camera, &corr).unwrap();
            let mine = cost.cost(&result.pose);
            let mut best = mine;
            let truth = Pose::new(scene.rotation, scene.translation);
            let centroid = corr
                .points3d
                .iter()
                .chain(corr.lines3d.iter().flat_map(|s| s.iter()))
                .fold(Vector3::zeros(), |a, p| a + p)
                / (np + 2 * nl) as f64;
            let depth = (scene.rotation * centroid + scene.translation).z;
            let mut candidates = vec![truth];
            for _ in 0..starts {
                let r = rng.rotation();
                candidates.push(Pose::new(r, Vector3::new(0.0, 0.0, depth) - r * centroid));
            }
            for start in candidates {
                let (pose, _) = refine_pose(&scene.camera, &corr, &start, &opts).expect("a pinhole camera");
                let c = cost.cost(&pose);
                if c.is_finite() && cost.points_behind(&pose) == 0 {
                    best = best.min(c);
                }
            }
            if result.report.certificate.is_some_and(|c| c.certified) {
                certified += 1;
            } else if std::env::var("WHY").is_ok() {
                println!(
                    "  seed {seed}: {} {}",
                    result.report.status.as_str(),
                    result.details.uncertified_reason.as_deref().unwrap_or("")
                );
            }
            if mine > best * (1.0 + 1e-6) + 1e-9 {
                misses += 1;
                if result.report.status.as_str() == "success" {
                    miss_success += 1;
                }
                if result.report.status == pluecker::Status::Ambiguous {
                    miss_ambiguous += 1;
                }
                if std::env::var("VERBOSE").is_ok() {
                    println!(
                        "  seed {seed}: {} cost {mine:.4} best {best:.4}",
                        result.report.status.as_str()
                    );
                }
            }
        }
        times.sort_by(f64::total_cmp);
        let q = |p: f64| {
            times
                .get(((times.len() as f64 - 1.0) * p) as usize)
                .copied()
                .unwrap_or(f64::NAN)
        };
        println!(
            "| {name} | {misses}/{} | {miss_success} | {miss_ambiguous} | {certified} | {:.1} | {:.1} |",
            times.len(),
            q(0.5),
            q(0.95)
        );
    }
}
