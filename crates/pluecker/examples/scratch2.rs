use pluecker::optim::Objective;
use pluecker::pose::candidates::minimal_hypotheses;
use pluecker::pose::reprojection::ReprojectionCost;
use pluecker::pose::{estimate_pose, refine_pose, PoseOptions};
use pluecker::geometry::quaternion::rotation_distance;
use pluecker::rng::Rng;
use pluecker::synthetic::visible_scene;
fn main() {
    let f: f64 = std::env::args().nth(1).and_then(|a| a.parse().ok()).unwrap_or(800.0);
    let np: usize = std::env::args().nth(2).and_then(|a| a.parse().ok()).unwrap_or(0);
    let nl: usize = std::env::args().nth(3).and_then(|a| a.parse().ok()).unwrap_or(6);
    let opts = PoseOptions::default();
    let mut worst_ratio_needed: f64 = 0.0;
    let mut ratios = vec![];
    for seed in 0..100 {
        let scene = visible_scene(f, np, nl, false, seed);
        let corr = scene.noisy(1.0, true, &mut Rng::new(seed + 7));
        let best = estimate_pose(&scene.camera, &corr, &opts).unwrap();
        let cost = ReprojectionCost::of(&scene.camera, &corr);
        let bc = cost.cost(&(best.rotation, best.translation));
        // which hypotheses lead to the best? the cheapest such hypothesis's ratio
        let mut cheapest_good = f64::INFINITY;
        for h in minimal_hypotheses(&scene.camera, &corr).flatten() {
            let c = cost.cost(&h);
            let (p, _) = refine_pose(&scene.camera, &corr, &h, &opts);
            if rotation_distance(&p.0, &best.rotation) < 1e-5 { cheapest_good = cheapest_good.min(c / bc.max(1e-12)); }
            ratios.push(c / bc);
        }
        worst_ratio_needed = worst_ratio_needed.max(cheapest_good);
        if cheapest_good > 50.0 { println!("seed {seed}: best reached from ratio {cheapest_good:.1}, best cost {bc:.2}"); }
    }
    ratios.sort_by(f64::total_cmp);
    println!("worst needed ratio {worst_ratio_needed:.1}; hypothesis ratio quantiles 10% {:.1} 50% {:.1} 90% {:.1}", ratios[ratios.len()/10], ratios[ratios.len()/2], ratios[9*ratios.len()/10]);
}
