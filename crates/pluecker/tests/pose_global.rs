//! The default pose is the global minimum of the reprojection error (or says it is ambiguous), and a
//! certified pose's lower bound is never beaten (issue 9).

use nalgebra::Vector3;
use pluecker::optim::Objective;
use pluecker::pose::certificate::certify;
use pluecker::pose::reprojection::ReprojectionCost;
use pluecker::pose::{estimate_pose, refine_pose, Correspondences, PoseOptions, Status};
use pluecker::rng::Rng;
use pluecker::synthetic::{visible_scene, Scene};

/// The lowest cost in front of the camera that the refinement reaches from the truth and from
/// `starts` random rotations (object centroid at its true depth on the axis).
fn best_known(scene: &Scene, corr: &Correspondences, starts: usize, rng: &mut Rng) -> f64 {
    let cost = ReprojectionCost::of(&scene.camera, corr);
    let opts = PoseOptions::default();
    let all: Vec<Vector3<f64>> = corr
        .points3d
        .iter()
        .chain(corr.lines3d.iter().flatten())
        .copied()
        .collect();
    let centroid = all.iter().sum::<Vector3<f64>>() / all.len() as f64;
    let depth = (scene.rotation * centroid + scene.translation).z;
    let mut best = f64::INFINITY;
    let mut candidates = vec![pluecker::Pose::new(scene.rotation, scene.translation)];
    for _ in 0..starts {
        let r = rng.rotation();
        candidates.push(pluecker::Pose::new(r, Vector3::new(0.0, 0.0, depth) - r * centroid));
    }
    for start in candidates {
        let (pose, _) = refine_pose(&scene.camera, corr, &start, &opts);
        if cost.points_behind(&pose) == 0 {
            best = best.min(cost.cost(&pose));
        }
    }
    best
}

/// The rows of issue 9's table where the old pipeline missed most often, 25 scenes each, 1 px noise.
#[test]
fn the_default_pipeline_reaches_the_best_known_minimum_or_says_it_is_ambiguous() {
    let rows: [(f64, usize, usize, bool); 9] = [
        (4000.0, 60, 0, false),
        (4000.0, 30, 20, false),
        (4000.0, 6, 0, false),
        (4000.0, 0, 6, false),
        (4000.0, 0, 20, false),
        (800.0, 4, 0, false),
        (800.0, 6, 0, false),
        (250.0, 0, 4, false),
        (4000.0, 3, 3, true),
    ];
    let opts = PoseOptions::default();
    for (f, np, nl, planar) in rows {
        for seed in 0..25 {
            let scene = visible_scene(f, np, nl, planar, seed);
            let mut rng = Rng::new(100 + seed);
            let corr = scene.noisy(1.0, true, &mut rng);
            let result = estimate_pose(&scene.camera, &corr, &opts).unwrap();
            let cost = ReprojectionCost::of(&scene.camera, &corr).cost(&result.pose());
            let best = best_known(&scene, &corr, 20, &mut rng);
            let missed = cost > best * (1.0 + 1e-6) + 1e-9;
            let row = format!("f={f} {np}p+{nl}l planar={planar} seed {seed}: cost {cost} best {best}");
            if np + nl >= 6 {
                assert!(!missed, "{row}: missed the best known minimum");
            } else {
                assert!(
                    !missed || result.status != Status::Success,
                    "{row}: a miss that says success"
                );
            }
            if let Some((_, second)) = result.second_best {
                assert!(second >= cost - 1e-9, "{row}: the runner-up {second} is cheaper");
                assert_eq!(result.ambiguous, result.status == Status::Ambiguous);
            }
        }
    }
}

/// Noise-free data with two exact-fit minima 0.3 px apart (issue 9's 3 points + 1 line example, in
/// miniature): the answer is the exact one, and it says that another is nearly as good.
#[test]
fn near_ties_are_reported_as_ambiguous_with_the_runner_up() {
    use nalgebra::Vector2;
    let camera = pluecker::Camera::new(100.0, 100.0, 320.0, 240.0, 0.0).unwrap();
    let corr = Correspondences {
        points2d: vec![
            Vector2::new(328.25225, 236.53891),
            Vector2::new(318.75583, 245.31756),
            Vector2::new(318.47324, 240.83389),
        ],
        points3d: vec![
            Vector3::new(-0.71231, -1.01011, -0.35883),
            Vector3::new(0.38466, -0.23661, 0.41702),
            Vector3::new(0.06198, -0.65361, 0.44170),
        ],
        lines2d: vec![[Vector2::new(317.01928, 245.04923), Vector2::new(319.19993, 233.70367)]],
        lines3d: vec![[
            Vector3::new(-0.28900, -0.29550, 0.56466),
            Vector3::new(-0.14120, -1.27669, 0.37747),
        ]],
        noise: None,
    };
    let result = estimate_pose(&camera, &corr, &PoseOptions::default()).unwrap();
    // The data are rounded to 1e-5 px: the exact fit is at that level, the old answer at 0.315 px.
    assert!(result.rms_error_px < 1e-4, "{}", result.rms_error_px);
    assert_eq!(result.status, Status::Ambiguous);
    let (_, second) = result.second_best.expect("the 0.315 px minimum is found too");
    assert!((0.3..0.5).contains(&second), "{second}");
    // Told that the noise is 0.01 px, the data do tell the two apart.
    let sure = PoseOptions {
        sigma_px: Some(0.01),
        ..PoseOptions::default()
    };
    assert_eq!(estimate_pose(&camera, &corr, &sure).unwrap().status, Status::Success);
}

/// A certified lower bound is below the cost of every pose found by many-start local searches, and
/// the certificate is given only where it holds: the relative gap is at most the requested one.
#[test]
fn certified_bounds_are_never_beaten() {
    let opts = PoseOptions {
        certify: Some(Default::default()),
        ..PoseOptions::default()
    };
    let mut certified = 0;
    let rows = [
        (800.0, 10, 0, false),
        (800.0, 100, 0, false),
        (800.0, 20, 10, false),
        (800.0, 50, 50, false),
        (4000.0, 30, 0, false),
        (4000.0, 10, 0, true),
        (15000.0, 100, 0, false),
    ];
    for (f, np, nl, planar) in rows {
        for seed in 0..8 {
            let scene = visible_scene(f, np, nl, planar, seed);
            let mut rng = Rng::new(500 + seed);
            let corr = scene.noisy(1.0, true, &mut rng);
            let result = estimate_pose(&scene.camera, &corr, &opts).unwrap();
            if !result.certified {
                assert!(!result.certificate.message().is_empty());
                continue;
            }
            certified += 1;
            let cost = ReprojectionCost::of(&scene.camera, &corr).cost(&result.pose());
            assert!(
                result.gap <= 1e-3 && result.lower_bound <= cost,
                "f={f} {np}p {nl}l seed {seed}"
            );
            let best = best_known(&scene, &corr, 30, &mut rng);
            assert!(
                result.lower_bound <= best * (1.0 + 1e-12),
                "f={f} {np}p {nl}l seed {seed}: bound {} beaten by {best}",
                result.lower_bound
            );
        }
    }
    // Measured with the benchmark: nearly every point scene, most of the mixed ones.
    assert!(certified >= 40, "only {certified} of 56 certified");
}

/// A local minimum that is not the global one is never certified: the test is run directly on the
/// second minimum of scenes that have one (found from random starts).
#[test]
fn a_wrong_local_minimum_is_not_certified() {
    let opts = PoseOptions::default();
    let mut tried = 0;
    let rows = [
        (800.0, 6, true),
        (4000.0, 6, true),
        (4000.0, 6, false),
        (15000.0, 10, false),
    ];
    for seed in 0..80u64 {
        let (f, n, planar) = rows[seed as usize % rows.len()];
        let scene = visible_scene(f, n, 0, planar, seed);
        let mut rng = Rng::new(900 + seed);
        let corr = scene.noisy(1.0, true, &mut rng);
        let cost = ReprojectionCost::of(&scene.camera, &corr);
        let best = best_known(&scene, &corr, 30, &mut rng);
        for _ in 0..30 {
            let r = rng.rotation();
            let (pose, _) = refine_pose(&scene.camera, &corr, &pluecker::Pose::new(r, scene.translation), &opts);
            let c = cost.cost(&pose);
            if cost.points_behind(&pose) == 0 && c > 1.5 * best + 1.0 {
                tried += 1;
                let verdict = certify(&scene.camera, &corr, &pose, c, &Default::default());
                assert!(
                    !verdict.certified,
                    "f={f} seed {seed}: certified a minimum of cost {c} above {best}"
                );
                assert!(
                    !(verdict.lower_bound > best),
                    "f={f} seed {seed}: bound {} above {best}",
                    verdict.lower_bound
                );
                break;
            }
        }
    }
    assert!(tried >= 10, "only {tried} scenes with a second minimum");
}

/// The certificate does not depend on the sign conventions of the camera: mirroring the image
/// (`fx → −fx`, `u → 2cx − u`, as the pose paper's camera with α_u < 0) and adding skew leave the
/// cost unchanged, and the certificate, lower bound and pose come out the same.
#[test]
fn certificate_holds_for_mirrored_and_skewed_cameras() {
    let opts = PoseOptions {
        certify: Some(Default::default()),
        ..PoseOptions::default()
    };
    let mut compared = 0;
    for seed in 0..12 {
        let (np, nl) = if seed % 2 == 0 { (20, 0) } else { (30, 10) };
        let scene = visible_scene(800.0, np, nl, false, seed);
        let mut rng = Rng::new(300 + seed);
        let corr = scene.noisy(1.0, true, &mut rng);
        let plain = estimate_pose(&scene.camera, &corr, &opts).unwrap();
        let cam = scene.camera;
        let mirror = |u: &nalgebra::Vector2<f64>| nalgebra::Vector2::new(2.0 * cam.cx - u.x, u.y);
        let mirrored_camera = pluecker::Camera { fx: -cam.fx, ..cam };
        let mirrored = Correspondences {
            points2d: corr.points2d.iter().map(mirror).collect(),
            lines2d: corr.lines2d.iter().map(|s| [mirror(&s[0]), mirror(&s[1])]).collect(),
            ..corr.clone()
        };
        let other = estimate_pose(&mirrored_camera, &mirrored, &opts).unwrap();
        assert_eq!(plain.certified, other.certified, "seed {seed}");
        if plain.certified {
            compared += 1;
            assert!(
                (plain.lower_bound - other.lower_bound).abs() <= 1e-6 * plain.lower_bound.max(1.0),
                "seed {seed}"
            );
            assert!(pluecker::geometry::quaternion::rotation_distance(&plain.rotation, &other.rotation) < 1e-8);
        }
        // Skew: the same pixels seen through K with skew are certified with a bound below the cost.
        let skewed_camera = pluecker::Camera { skew: 30.0, ..cam };
        let skewed = Correspondences {
            points2d: corr
                .points2d
                .iter()
                .map(|u| nalgebra::Vector2::new(u.x + 30.0 * (u.y - cam.cy) / cam.fy, u.y))
                .collect(),
            lines2d: corr
                .lines2d
                .iter()
                .map(|s| s.map(|u| nalgebra::Vector2::new(u.x + 30.0 * (u.y - cam.cy) / cam.fy, u.y)))
                .collect(),
            ..corr.clone()
        };
        let res = estimate_pose(&skewed_camera, &skewed, &opts).unwrap();
        if res.certified {
            let cost = ReprojectionCost::of(&skewed_camera, &skewed).cost(&res.pose());
            assert!(res.lower_bound <= cost, "seed {seed}");
            let best = best_known(
                &Scene {
                    camera: skewed_camera,
                    ..scene.clone()
                },
                &skewed,
                10,
                &mut rng,
            );
            assert!(
                res.lower_bound <= best * (1.0 + 1e-12),
                "seed {seed}: skewed bound beaten"
            );
        }
    }
    assert!(compared >= 6, "only {compared} certified");
}
