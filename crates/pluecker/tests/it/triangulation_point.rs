//! Point triangulation (Josephson & Kahl 2008): exact recovery, the cost, covariance weighting,
//! soundness of both certificates against sampling and multi-start minimisation, low parallax,
//! bad input, and the batch.

use nalgebra::{Matrix2, Matrix3, Matrix3x4, Vector2, Vector3, Vector4};
use pluecker::rng::Rng;
use pluecker::synthetic::triangulation_scene;
use pluecker::triangulation::point::testing::convexity_test;
use pluecker::triangulation::point::testing::{global_point, GlobalSettings, GlobalStatus, Relaxation};
use pluecker::triangulation::point::testing::{in_front, point_views, PointView};
use pluecker::triangulation::point::triangulate_point;
use pluecker::triangulation::point::{triangulate_points, DensePointTracks, LinearPoints, SparsePointTracks};
use pluecker::triangulation::testing::depth_normalized;
use pluecker::triangulation::Csr;
use pluecker::triangulation::{CertificateKind, Method, Status, TriangulationOptions};
use pluecker::Error;

use crate::common::oracle_triangulation as oracle;

fn options(method: Method) -> TriangulationOptions {
    let mut options = TriangulationOptions::default();
    options.method = method;
    options
}

fn project(p: &Matrix3x4<f64>, x: &Vector3<f64>) -> Vector2<f64> {
    let h = p * Vector4::new(x.x, x.y, x.z, 1.0);
    Vector2::new(h.x / h.z, h.y / h.z)
}

fn views_of(cameras: &[Matrix3x4<f64>], obs: &[Vector2<f64>], covs: Option<&[Matrix2<f64>]>) -> Vec<PointView> {
    let ps: Vec<Matrix3x4<f64>> = cameras.iter().map(depth_normalized).collect();
    let ls: Vec<Matrix2<f64>> = match covs {
        None => vec![Matrix2::identity(); cameras.len()],
        Some(c) => c
            .iter()
            .map(|c| c.cholesky().unwrap().l().try_inverse().unwrap())
            .collect(),
    };
    point_views(&ps, obs, &ls)
}

#[test]
fn noise_free_points_are_recovered_exactly_by_every_method() {
    for (views, seed) in [(2, 1), (3, 2), (10, 3)] {
        let scene = triangulation_scene(views, 0.4, seed);
        for method in Method::ALL.iter().copied() {
            let r = triangulate_point(&scene.cameras, &scene.observations, None, &options(method)).unwrap();
            assert_eq!(r.report.status, Status::Success, "{views} views {method:?}");
            // Points ~5 units away, pixel-exact data: agreement to ~1e-9 relative (DLT conditioning).
            assert!(
                (r.point - scene.point).norm() < 1e-8,
                "{views} views {method:?}: {}",
                (r.point - scene.point).norm()
            );
            assert!(r.report.cost < 1e-12);
            if method == Method::Optimal {
                assert!(r.report.certified(), "{views} views: {:?}", r.report);
            }
        }
    }
}

#[test]
fn cost_is_the_squared_pixel_error_without_covariance() {
    let scene = triangulation_scene(4, 0.3, 7);
    let obs = scene.noisy(1.0, &mut Rng::new(7));
    let r = triangulate_point(&scene.cameras, &obs, None, &options(Method::Local)).unwrap();
    let pixel_error: f64 = scene
        .cameras
        .iter()
        .zip(&obs)
        .map(|(p, u)| (project(p, &r.point) - u).norm_squared())
        .sum();
    assert!((r.report.cost - pixel_error).abs() < 1e-10 * pixel_error);
}

#[test]
fn covariance_weighting_pulls_the_estimate_and_is_scale_covariant() {
    let scene = triangulation_scene(2, 0.3, 11);
    let obs = scene.noisy(2.0, &mut Rng::new(11));
    let plain = triangulate_point(&scene.cameras, &obs, None, &options(Method::Optimal)).unwrap();
    // View 0 measured 100x more precisely along x: its x-residual must shrink.
    let covs = [Matrix2::new(1e-4, 0.0, 0.0, 1.0), Matrix2::identity()];
    let weighted = triangulate_point(&scene.cameras, &obs, Some(&covs), &options(Method::Optimal)).unwrap();
    let x_error = |x: &Vector3<f64>| (project(&scene.cameras[0], x) - obs[0]).x.abs();
    assert!(
        x_error(&weighted.point) < 0.05 * x_error(&plain.point),
        "{} vs {}",
        x_error(&weighted.point),
        x_error(&plain.point)
    );
    // The weighted cost is the Mahalanobis norm at the estimate.
    let mahalanobis: f64 = scene
        .cameras
        .iter()
        .zip(&obs)
        .zip(&covs)
        .map(|((p, u), c)| {
            let e = project(p, &weighted.point) - u;
            e.dot(&(c.try_inverse().unwrap() * e))
        })
        .sum();
    assert!((weighted.report.cost - mahalanobis).abs() < 1e-9 * mahalanobis);
    // Scaling every covariance by 4 keeps the point and divides the cost by 4.
    let scaled: Vec<Matrix2<f64>> = covs.iter().map(|c| c * 4.0).collect();
    let again = triangulate_point(&scene.cameras, &obs, Some(&scaled), &options(Method::Optimal)).unwrap();
    assert!((again.point - weighted.point).norm() < 1e-6 * weighted.point.norm());
    assert!((4.0 * again.report.cost - weighted.report.cost).abs() < 1e-8 * weighted.report.cost);
}

#[test]
fn optimal_is_no_worse_than_local_which_is_no_worse_than_linear() {
    for seed in 0..40 {
        let views = 2 + (seed as usize % 6);
        let parallax = [0.5f64, 0.05, 0.01][seed as usize % 3];
        let scene = triangulation_scene(views, parallax, seed);
        let obs = scene.noisy(1.0, &mut Rng::new(100 + seed));
        let cost = |m| {
            triangulate_point(&scene.cameras, &obs, None, &options(m))
                .unwrap()
                .report
        };
        let (linear, local, optimal) = (cost(Method::Linear), cost(Method::Local), cost(Method::Optimal));
        assert_ne!(optimal.status, Status::BehindCamera);
        assert!(optimal.cost <= local.cost * (1.0 + 1e-12), "seed {seed}");
        if linear.status == Status::Success {
            assert!(
                local.cost <= linear.cost * (1.0 + 1e-12),
                "seed {seed}: {} > {}",
                local.cost,
                linear.cost
            );
        }
    }
}

/// Random anisotropic covariances (condition number up to 100).
fn random_covariances(views: usize, rng: &mut Rng) -> Vec<Matrix2<f64>> {
    (0..views)
        .map(|_| {
            let (a, b, angle) = (
                rng.uniform_in(0.3, 3.0),
                rng.uniform_in(0.3, 3.0),
                rng.uniform_in(0.0, 3.2),
            );
            let r = nalgebra::Rotation2::new(angle).into_inner();
            r * Matrix2::new(a * a, 0.0, 0.0, b * b) * r.transpose()
        })
        .collect()
}

#[test]
fn convexity_certificate_is_never_contradicted_by_sampling_or_multistart() {
    // The raw bound of the convexity test at the local solution against the oracle's costs: at the
    // answer, at random points around it and at the many-start minimum (all computed without the
    // library's point code).
    let mut passed = 0;
    for seed in 0..60u64 {
        let views = [2usize, 3, 5, 8][seed as usize % 4];
        let parallax = [0.3f64, 0.02, 0.008, 0.0035][(seed / 4) as usize % 4];
        let scene = triangulation_scene(views, parallax, 300 + seed);
        let mut rng = Rng::new(seed);
        let obs = scene.noisy(1.5, &mut rng);
        // Odd seeds: random anisotropic covariances.
        let covs = random_covariances(views, &mut rng);
        let covs = (seed % 2 == 1).then_some(covs.as_slice());
        let r = triangulate_point(&scene.cameras, &obs, covs, &options(Method::Local)).unwrap();
        if r.report.status != Status::Success {
            continue;
        }
        let vs = views_of(&scene.cameras, &obs, covs);
        let test = convexity_test(&vs, &r.point);
        if !test.passed {
            continue;
        }
        passed += 1;
        let data = oracle::PointData::new(&scene.cameras, &obs, covs);
        // The oracle's cost of the answer, rounded like any sum of a few squares (1e-12 relative).
        let at_answer = data.cost(&r.point);
        assert!(test.lower_bound <= at_answer * (1.0 + 1e-12), "seed {seed}");
        // Random points around the estimate (scaled by its distance to the first camera) in front
        // of every camera never beat the bound.
        let scale = (r.point - pluecker::triangulation::testing::centre(&scene.cameras[0])).norm();
        for _ in 0..400 {
            let step =
                Vector3::new(rng.normal(), rng.normal(), rng.normal()) * scale * 10f64.powf(rng.uniform_in(-5.0, -0.5));
            let x = r.point + step;
            if data.in_front(&x) {
                assert!(data.cost(&x) >= test.lower_bound * (1.0 - 1e-12), "seed {seed}");
            }
        }
        let (_, best) = data.many_start_minimum(&r.point, 300, &mut rng);
        assert!(
            best >= test.lower_bound * (1.0 - 1e-9),
            "seed {seed}: multistart {best} < bound {}",
            test.lower_bound
        );
    }
    // Rate guard (not the check): 54 of 60 pass at the time of writing; below 30 the loop above
    // checks too little to mean anything.
    eprintln!("{passed} of 60 local solutions pass the convexity test");
    assert!(passed > 30, "the test passed only {passed} times");
}

/// The convexity test is a sufficient test at any chart origin, not only at a minimiser: centred at
/// points moved away from the local solution (along the ill-determined depth and across it, by a few
/// standard deviations), a passing test's bound must stay below the global minimum found by the
/// oracle's many-start search. There the minorant's gradient term is not zero, so its curvature
/// decides the bound: a minorant more curved than the cost shows here, not at the minimiser.
#[test]
fn convexity_test_centred_away_from_the_minimiser_bounds_the_global_minimum() {
    let (mut passed, mut informative) = (0, 0);
    for seed in 0..40u64 {
        let views = [2usize, 3, 5][seed as usize % 3];
        let parallax = [0.3f64, 0.05, 0.01, 0.004][(seed / 3) as usize % 4];
        let scene = triangulation_scene(views, parallax, 700 + seed);
        let mut rng = Rng::new(seed + 77);
        let sigma = [0.5, 2.0, 5.0][seed as usize % 3];
        let obs = scene.noisy(sigma, &mut rng);
        let covs = random_covariances(views, &mut rng);
        let covs = (seed % 2 == 0).then_some(covs.as_slice());
        let data = oracle::PointData::new(&scene.cameras, &obs, covs);
        let (x_min, f_min) = data.many_start_minimum(&scene.point, 200, &mut rng);
        let vs = views_of(&scene.cameras, &obs, covs);
        let ray = (x_min - pluecker::triangulation::testing::centre(&scene.cameras[0])).normalize();
        for k in 0..12 {
            let along = rng.normal() * 10f64.powf(rng.uniform_in(-3.0, -0.5));
            let across =
                Vector3::new(rng.normal(), rng.normal(), rng.normal()) * 10f64.powf(rng.uniform_in(-4.0, -1.5));
            let depth = (x_min - pluecker::triangulation::testing::centre(&scene.cameras[0])).norm();
            let x = x_min + (ray * along + across) * depth;
            if !data.in_front(&x) {
                continue;
            }
            let test = convexity_test(&vs, &x);
            if !test.passed {
                continue;
            }
            passed += 1;
            let f_x = data.cost(&x);
            assert!(test.lower_bound <= f_x * (1.0 + 1e-12), "seed {seed} start {k}");
            // Costs of a few squares rounded to 1e-12 relative; the bound is widened by its own margin.
            assert!(
                test.lower_bound <= f_min * (1.0 + 1e-12),
                "seed {seed} start {k}: bound {} above the global minimum {f_min} (cost at the chart origin {f_x})",
                test.lower_bound
            );
            if f_x > 1.01 * f_min {
                informative += 1;
            }
        }
    }
    // Rate guards: at the time of writing 371 origins pass the test, 348 of them 1 % above the minimum.
    eprintln!("{passed} chart origins pass the test, {informative} of them 1 % above the minimum");
    assert!(
        passed >= 100 && informative >= 50,
        "{passed} passed, {informative} informative"
    );
}

#[test]
fn low_parallax_goes_to_branch_and_bound_which_certifies_in_front_of_the_cameras() {
    let mut by_bnb = 0;
    for seed in 0..12u64 {
        let scene = triangulation_scene(10, 0.2f64.to_radians(), seed);
        let obs = scene.noisy(1.0, &mut Rng::new(seed + 1000));
        let r = triangulate_point(&scene.cameras, &obs, None, &options(Method::Optimal)).unwrap();
        assert_eq!(r.report.status, Status::Success, "seed {seed}: {:?}", r.report);
        let c = r.report.certificate.expect("a search ran");
        let data = oracle::PointData::new(&scene.cameras, &obs, None);
        assert!(data.in_front(&r.point));
        let cost = data.cost(&r.point);
        assert!(
            (cost - r.report.cost).abs() <= 1e-9 * cost,
            "seed {seed}: {cost} vs {}",
            r.report.cost
        );
        // The raw bound is below the answer's cost and the many-start minimum, and the gap
        // recomputed from them closed.
        let (_, best) = data.many_start_minimum(&r.point, 300, &mut Rng::new(seed));
        assert!(c.raw_lower_bound <= cost * (1.0 + 1e-12), "seed {seed}: {c:?}");
        assert!(best >= c.raw_lower_bound * (1.0 - 1e-9), "seed {seed}: {best} < {c:?}");
        assert!(
            c.certified && oracle::gap(cost, c.raw_lower_bound) <= 1e-3 * (1.0 + 1e-9),
            "seed {seed}: {c:?}"
        );
        assert!(
            cost <= best * (1.0 + 1e-3) + 1e-9,
            "seed {seed}: {cost} vs multistart {best}"
        );
        if c.kind == CertificateKind::BranchAndBound {
            by_bnb += 1;
            assert!(c.nodes >= 1);
        }
    }
    // Rate guard: 0.2° of parallax over 10 views is the regime the convexity test is known to give
    // up on (measured: 6 of 12 go to branch and bound); if none does, this test no longer exercises
    // branch and bound, though the checks above stay valid.
    eprintln!("{by_bnb} of 12 by branch and bound");
    assert!(
        by_bnb >= 4,
        "only {by_bnb} of 12 low-parallax points needed branch and bound"
    );
}

#[test]
fn both_relaxations_give_valid_bounds_below_random_feasible_points() {
    let scene = triangulation_scene(4, 0.2f64.to_radians(), 5);
    let obs = scene.noisy(1.0, &mut Rng::new(5));
    let local = triangulate_point(&scene.cameras, &obs, None, &options(Method::Local)).unwrap();
    let vs = views_of(&scene.cameras, &obs, None);
    let data = oracle::PointData::new(&scene.cameras, &obs, None);
    let mut rng = Rng::new(55);
    let (_, best) = data.many_start_minimum(&local.point, 200, &mut rng);
    for relaxation in [Relaxation::Fractional, Relaxation::Secant, Relaxation::Both] {
        let settings = GlobalSettings {
            max_relative_gap: 1e-3,
            max_nodes: 400,
            local: TriangulationOptions::default().local,
            relaxation,
        };
        let g = global_point(&vs, &local.point, local.report.cost, &[], &settings);
        assert_eq!(g.status, GlobalStatus::Converged, "{relaxation:?}");
        let cost = data.cost(&g.point);
        assert!(cost <= data.cost(&local.point) * (1.0 + 1e-12));
        assert!(g.raw_lower_bound <= cost * (1.0 + 1e-12) && g.raw_lower_bound <= best * (1.0 + 1e-12));
        assert!(
            oracle::gap(cost, g.raw_lower_bound) <= 1e-3 * (1.0 + 1e-9),
            "{relaxation:?}: {g:?}"
        );
        // Points along the poorly determined depth direction and around it.
        let ray = local.point - pluecker::triangulation::testing::centre(&scene.cameras[0]);
        for _ in 0..2000 {
            let x = local.point
                + ray * rng.uniform_in(-0.9, 20.0)
                + Vector3::new(rng.normal(), rng.normal(), rng.normal()) * 1e-3;
            if data.in_front(&x) {
                assert!(data.cost(&x) >= g.raw_lower_bound * (1.0 - 1e-12), "{relaxation:?}");
            }
        }
    }
}

/// Branch and bound started from a point that is not a minimum (the local solution moved along the
/// depth direction, so its cost is 1.2 to 10 times the minimum): the search set is the enclosure
/// of that point's sublevel set, centred away from the minimiser. The search must find the minimum
/// the oracle's many-start search finds, and its raw bound must stay below it; the certified gap is
/// recomputed from the oracle's cost and the raw bound.
#[test]
fn branch_and_bound_from_a_point_that_is_not_a_minimum_finds_and_bounds_the_global_one() {
    let mut converged = 0;
    for seed in 0..16u64 {
        let views = [2usize, 3, 6, 10][seed as usize % 4];
        let parallax = [0.1f64, 0.01, 0.2f64.to_radians()][seed as usize % 3];
        let scene = triangulation_scene(views, parallax, 900 + seed);
        let mut rng = Rng::new(seed + 5);
        let obs = scene.noisy(1.0, &mut rng);
        let data = oracle::PointData::new(&scene.cameras, &obs, None);
        let (x_min, f_min) = data.many_start_minimum(&scene.point, 200, &mut rng);
        let ray = x_min - pluecker::triangulation::testing::centre(&scene.cameras[0]);
        let ratio = [1.2, 2.0, 10.0][seed as usize % 3];
        // The first point along the ray (outwards) whose cost reaches `ratio` times the minimum.
        let Some(start) = (1..4000)
            .map(|k| x_min + ray * (1e-4 * 1.005f64.powi(k)))
            .find(|x| data.cost(x) >= ratio * f_min.max(1e-6))
        else {
            continue;
        };
        if !data.in_front(&start) {
            continue;
        }
        let vs = views_of(&scene.cameras, &obs, None);
        let start_cost = data.cost(&start);
        let settings = GlobalSettings {
            max_relative_gap: 1e-3,
            max_nodes: 2000,
            local: TriangulationOptions::default().local,
            relaxation: Relaxation::Secant,
        };
        let g = global_point(&vs, &start, start_cost, &[], &settings);
        assert!(
            g.raw_lower_bound <= f_min * (1.0 + 1e-12),
            "seed {seed}: raw bound {} above the minimum {f_min} ({g:?})",
            g.raw_lower_bound
        );
        // The start is not the minimum (its cost is `ratio` times it): whatever the node cap, the
        // search reports a cheaper point than the one it started from.
        let found = data.cost(&g.point);
        assert!(
            found < start_cost * (1.0 - 1e-6),
            "seed {seed}: the search kept its start ({found} vs {start_cost}); the minimum costs {f_min}"
        );
        if g.status == GlobalStatus::Converged {
            converged += 1;
            let cost = data.cost(&g.point);
            assert!(
                cost <= f_min * (1.0 + 1e-3) + 1e-12,
                "seed {seed}: found {cost}, minimum {f_min}"
            );
            assert!(
                oracle::gap(cost, g.raw_lower_bound) <= 1e-3 * (1.0 + 1e-9),
                "seed {seed}: {g:?}"
            );
        }
    }
    // Rate guard: 13 of 16 converge within 2000 nodes at the time of writing; fewer than 8 means the checks above
    // saw too few finished searches.
    eprintln!("{converged} of 16 searches converged");
    assert!(converged >= 8, "{converged}");
}

/// Certified points over the regimes of the convexity test: the raw bound (convexity test or branch
/// and bound) against the oracle's cost at the answer and its many-start minimum, and the gap
/// recomputed from them.
#[test]
fn certified_points_have_raw_bounds_below_every_cost_found() {
    let mut certified = 0;
    for seed in 0..24u64 {
        let views = [2usize, 3, 5, 8][seed as usize % 4];
        let parallax = [0.3f64, 0.02, 0.005][(seed / 4) as usize % 3];
        let scene = triangulation_scene(views, parallax, 1300 + seed);
        let mut rng = Rng::new(seed);
        let obs = scene.noisy([0.5, 3.0][seed as usize % 2], &mut rng);
        let covs = random_covariances(views, &mut rng);
        let covs = (seed % 3 == 0).then_some(covs.as_slice());
        let r = triangulate_point(&scene.cameras, &obs, covs, &options(Method::Optimal)).unwrap();
        let c = r.report.certificate.expect("a search ran");
        if !c.certified {
            continue;
        }
        certified += 1;
        let data = oracle::PointData::new(&scene.cameras, &obs, covs);
        let cost = data.cost(&r.point);
        assert!((cost - r.report.cost).abs() <= 1e-9 * cost.max(1e-12), "seed {seed}");
        let (_, best) = data.many_start_minimum(&r.point, 150, &mut rng);
        assert!(
            c.raw_lower_bound <= cost * (1.0 + 1e-12),
            "seed {seed}: {c:?}, cost {cost}"
        );
        assert!(
            c.raw_lower_bound <= best * (1.0 + 1e-12),
            "seed {seed}: {c:?}, minimum {best}"
        );
        assert!(
            oracle::gap(cost, c.raw_lower_bound) <= 1e-3 * (1.0 + 1e-9),
            "seed {seed}: {c:?}"
        );
        assert!(
            c.lower_bound == c.raw_lower_bound.min(r.report.cost),
            "seed {seed}: {c:?}"
        );
    }
    // Rate guard: 23 of 24 at the time of writing; fewer than 18 means certification broke and the
    // checks above saw too little.
    eprintln!("{certified} of 24 certified");
    assert!(certified >= 18, "{certified}");
}

#[test]
fn a_point_whose_rays_diverge_is_reported_behind_the_cameras() {
    // Observations of a point behind the cameras (the rays diverge in front): the DLT finds it
    // behind. Every point in front costs more than the best point at infinity, so local and
    // optimal say so (issue 10: they used to return a far point, optimal a certified success).
    let scene = triangulation_scene(3, 0.3, 21);
    let behind = scene.point + (scene.point - pluecker::triangulation::testing::centre(&scene.cameras[0])) * -2.0;
    let obs: Vec<Vector2<f64>> = scene.cameras.iter().map(|p| project(p, &behind)).collect();
    let vs = views_of(&scene.cameras, &obs, None);
    let linear = triangulate_point(&scene.cameras, &obs, None, &options(Method::Linear)).unwrap();
    assert_eq!(linear.report.status, Status::BehindCamera);
    for method in [Method::Local, Method::Optimal] {
        let r = triangulate_point(&scene.cameras, &obs, None, &options(method)).unwrap();
        assert_eq!(r.report.status, Status::BehindCamera, "{method:?}: {:?}", r.report);
        assert!(!r.report.certified());
        assert!(
            !in_front(&vs, &r.point) && (r.point - behind).norm() < 1e-8,
            "{method:?}: {}",
            r.point
        );
    }
}

#[test]
fn parallel_rays_are_at_infinity_for_the_linear_method() {
    let k = Matrix3::new(800.0, 0.0, 320.0, 0.0, 800.0, 240.0, 0.0, 0.0, 1.0);
    let camera = |cx: f64| {
        let mut rt = Matrix3x4::identity();
        rt[(0, 3)] = -cx;
        k * rt
    };
    let cameras = [camera(0.0), camera(1.0)];
    let obs = [Vector2::new(300.0, 200.0), Vector2::new(300.0, 200.0)];
    let r = triangulate_point(&cameras, &obs, None, &options(Method::Linear)).unwrap();
    assert_eq!(r.report.status, Status::AtInfinity);
    assert!(r.point.iter().all(|v| v.is_nan()));
}

#[test]
fn bad_input_gives_the_right_error() {
    let scene = triangulation_scene(3, 0.3, 4);
    let (cams, obs) = (&scene.cameras, &scene.observations);
    let opts = TriangulationOptions::default();
    let err = |c: &[Matrix3x4<f64>], o: &[Vector2<f64>], cov: Option<&[Matrix2<f64>]>| {
        triangulate_point(c, o, cov, &opts).unwrap_err()
    };
    assert!(matches!(
        err(&cams[..1], &obs[..1], None),
        Error::TooFewCorrespondences { .. }
    ));
    assert!(matches!(err(cams, &obs[..2], None), Error::Shape { what, .. } if what == "observations"));
    let mut nan = obs.clone();
    nan[2].y = f64::NAN;
    assert!(matches!(err(cams, &nan, None), Error::NonFinite { what, index: 2 } if what == "observations"));
    let mut bad_cams = cams.clone();
    bad_cams[1][(0, 3)] = f64::INFINITY;
    assert!(matches!(err(&bad_cams, obs, None), Error::NonFinite { what, index: 1 } if what == "cameras"));
    let mut singular = cams.clone();
    singular[2].fixed_view_mut::<3, 3>(0, 0).fill(0.0);
    assert!(matches!(err(&singular, obs, None), Error::SingularCamera { what } if what.contains("cameras[2]")));
    let covs = [
        Matrix2::identity(),
        Matrix2::new(1.0, 2.0, 2.0, 1.0),
        Matrix2::identity(),
    ];
    assert!(matches!(err(cams, obs, Some(&covs)), Error::Degenerate { what } if what.contains("covariances[1]")));
    assert!(matches!(err(cams, obs, Some(&covs[..2])), Error::Shape { .. }));
    // One centre, three orientations: no parallax.
    let k = Matrix3::new(800.0, 0.0, 320.0, 0.0, 800.0, 240.0, 0.0, 0.0, 1.0);
    let rotations = [Matrix3::identity(), Rng::new(1).rotation(), Rng::new(2).rotation()];
    let same_centre: Vec<Matrix3x4<f64>> = rotations
        .iter()
        .map(|r| {
            let mut rt = Matrix3x4::zeros();
            rt.fixed_view_mut::<3, 3>(0, 0).copy_from(r);
            rt.set_column(3, &(-r * Vector3::new(1.0, 2.0, 3.0)));
            k * rt
        })
        .collect();
    assert!(matches!(err(&same_centre, obs, None), Error::Degenerate { what } if what.contains("no parallax")));
    let mut bad_opts = TriangulationOptions::default();
    bad_opts.certify.max_relative_gap = -1.0;
    assert!(matches!(
        triangulate_point(cams, obs, None, &bad_opts),
        Err(Error::InvalidOption { .. })
    ));
}

#[test]
fn batch_matches_single_calls_and_keeps_good_tracks_around_bad_ones() {
    let cameras = triangulation_scene(5, 0.3, 8).cameras;
    let mut rng = Rng::new(8);
    let n = 6;
    let v = cameras.len();
    let mut observations = Vec::new();
    let mut truths = Vec::new();
    for _ in 0..n {
        let x = Vector3::new(rng.normal(), rng.normal(), rng.normal()) * 0.3;
        truths.push(x);
        for p in &cameras {
            let u = project(p, &x);
            observations.extend([u.x + rng.normal(), u.y + rng.normal()]);
        }
    }
    let mut visible = vec![true; n * v];
    // Track 1: NaN in a visible view. Track 2: NaN in an invisible view (fine). Track 3: one view.
    observations[2 * (v + 3)] = f64::NAN;
    observations[2 * (2 * v + 4) + 1] = f64::NAN;
    visible[2 * v + 4] = false;
    for j in 1..v {
        visible[3 * v + j] = false;
    }
    // Track 4: a covariance that is not positive definite in view 0.
    let mut covariances = Vec::new();
    for _ in 0..n * v {
        covariances.extend([1.0, 0.0, 0.0, 1.0]);
    }
    covariances[4 * (4 * v)..4 * (4 * v) + 4].copy_from_slice(&[1.0, 3.0, 3.0, 1.0]);
    let tracks = DensePointTracks {
        observations: &observations,
        visible: Some(&visible),
        covariances: Some(&covariances),
    };
    let results = triangulate_points(&cameras, tracks, &TriangulationOptions::default(), None).unwrap();
    assert!(matches!(&results[1], Err(Error::NonFinite { what, index: 3 }) if what == "observations[1]"));
    assert!(matches!(&results[3], Err(Error::TooFewCorrespondences { .. })));
    assert!(matches!(&results[4], Err(Error::Degenerate { what }) if what.contains("covariances[4]")));
    for t in [0, 2, 5] {
        let r = results[t].as_ref().unwrap();
        assert!(r.report.certified());
        let seen: Vec<usize> = (0..v).filter(|&j| visible[t * v + j]).collect();
        let cams: Vec<Matrix3x4<f64>> = seen.iter().map(|&j| cameras[j]).collect();
        let obs: Vec<Vector2<f64>> = seen
            .iter()
            .map(|&j| Vector2::new(observations[2 * (t * v + j)], observations[2 * (t * v + j) + 1]))
            .collect();
        let single = triangulate_point(&cams, &obs, None, &TriangulationOptions::default()).unwrap();
        assert!(
            (single.point - r.point).norm() < 1e-9 * (1.0 + r.point.norm()),
            "track {t}"
        );
        assert!((r.point - truths[t]).norm() < 0.1);
    }
    let linear = LinearPoints::from_tracks(&cameras, &tracks).unwrap();
    assert_eq!(linear.outcomes.len(), n);
    assert!(linear.outcomes[1].is_err() && linear.outcomes[3].is_err() && linear.outcomes[4].is_err());
    assert!(linear.points[3..6].iter().all(|v| v.is_nan()));
    for t in [0, 2, 5] {
        assert_eq!(linear.outcomes[t], Ok(Status::Success));
        let x = Vector3::from_column_slice(&linear.points[3 * t..3 * t + 3]);
        let seen: Vec<usize> = (0..v).filter(|&j| visible[t * v + j]).collect();
        let cams: Vec<Matrix3x4<f64>> = seen.iter().map(|&j| cameras[j]).collect();
        let obs: Vec<Vector2<f64>> = seen
            .iter()
            .map(|&j| Vector2::new(observations[2 * (t * v + j)], observations[2 * (t * v + j) + 1]))
            .collect();
        let single = triangulate_point(&cams, &obs, None, &options(Method::Linear)).unwrap();
        assert!((single.point - x).norm() < 1e-9 * (1.0 + x.norm()), "track {t}");
        assert!((single.report.cost - linear.costs[t]).abs() < 1e-9 * single.report.cost);
    }
    // Whole-call errors.
    let short = DensePointTracks {
        observations: &observations[..5],
        visible: None,
        covariances: None,
    };
    assert!(matches!(
        triangulate_points(&cameras, short, &TriangulationOptions::default(), None),
        Err(Error::Shape { .. })
    ));
    let mask = DensePointTracks {
        observations: &observations,
        visible: Some(&visible[..3]),
        covariances: None,
    };
    assert!(matches!(LinearPoints::from_tracks(&cameras, &mask), Err(Error::Shape { what, .. }) if what == "visible"));
}

#[test]
fn optimal_reports_exactly_parallel_rays_at_infinity() {
    // Three cameras translated along x, all seeing the point on their optical axes: the rays are
    // parallel, eq. 19 tends to 0 at infinity and has no finite minimiser.
    let cameras: Vec<Matrix3x4<f64>> = (0..3)
        .map(|i| {
            Matrix3x4::new(
                800.0,
                0.0,
                320.0,
                800.0 * i as f64,
                0.0,
                800.0,
                240.0,
                0.0,
                0.0,
                0.0,
                1.0,
                5.0,
            )
        })
        .collect();
    let observations = vec![Vector2::new(320.0, 240.0); 3];
    let mut opts = TriangulationOptions::default();
    opts.method = Method::Optimal;
    let r = triangulate_point(&cameras, &observations, None, &opts).unwrap();
    assert_eq!(r.report.status, Status::AtInfinity, "{:?}", r.report);
    assert!(r.point.iter().all(|v| v.is_nan()));
    assert!(r.report.cost.abs() < 1e-12);
    assert!(!r.report.certified());
}

#[test]
fn the_sparse_batch_equals_the_dense_one_and_names_bad_tracks() {
    // The same tracks in both forms: dense (n, v) with a visibility mask, and sparse (CSR over the
    // visible observations). In the dense order every result is the same, bit for bit but the wall time;
    // in another order of the images the sums run in another order, and the results agree to rounding.
    // A track naming an image beyond the cameras or seen from one image only is its own error.
    let cameras = triangulation_scene(7, 0.4, 9).cameras;
    let v = cameras.len();
    let mut rng = Rng::new(9);
    let n = 40;
    let (mut dense, mut visible, mut dense_cov) = (vec![f64::NAN; 2 * n * v], vec![false; n * v], vec![0.0; 4 * n * v]);
    let (mut offsets, mut images, mut sparse, mut sparse_cov) = (vec![0], Vec::new(), Vec::new(), Vec::new());
    for t in 0..n {
        let x = Vector3::new(rng.normal(), rng.normal(), rng.normal()) * 0.3;
        let count = 2 + rng.below(v - 1);
        let mut seen = rng.sample_indices(v, count);
        seen.sort_unstable();
        for j in seen {
            let u = project(&cameras[j], &x) + Vector2::new(rng.normal(), rng.normal());
            let s = 0.5 + rng.uniform_in(0.0, 1.0);
            let cov = [s, 0.1 * s, 0.1 * s, s];
            dense[2 * (t * v + j)..][..2].copy_from_slice(&[u.x, u.y]);
            dense_cov[4 * (t * v + j)..][..4].copy_from_slice(&cov);
            visible[t * v + j] = true;
            images.push(j);
            sparse.extend([u.x, u.y]);
            sparse_cov.extend(cov);
        }
        offsets.push(images.len());
    }
    let opts = options(Method::Optimal);
    let d = DensePointTracks {
        observations: &dense,
        visible: Some(&visible),
        covariances: Some(&dense_cov),
    };
    let s = SparsePointTracks {
        csr: Csr {
            offsets: &offsets,
            image: &images,
        },
        observations: &sparse,
        covariances: Some(&sparse_cov),
    };
    let a = triangulate_points(&cameras, d, &opts, None).unwrap();
    let b = triangulate_points(&cameras, s, &opts, None).unwrap();
    for (t, (a, b)) in a.into_iter().zip(b).enumerate() {
        let (mut a, mut b) = (a.unwrap(), b.unwrap());
        (a.report.time_seconds, b.report.time_seconds) = (0.0, 0.0);
        assert_eq!(a, b, "track {t}");
    }
    // Each track's observations reversed: the same answers to rounding.
    let (mut rev_images, mut rev_obs, mut rev_cov) = (Vec::new(), Vec::new(), Vec::new());
    for t in 0..n {
        for k in (offsets[t]..offsets[t + 1]).rev() {
            rev_images.push(images[k]);
            rev_obs.extend_from_slice(&sparse[2 * k..2 * k + 2]);
            rev_cov.extend_from_slice(&sparse_cov[4 * k..4 * k + 4]);
        }
    }
    let reversed = SparsePointTracks {
        csr: Csr {
            offsets: &offsets,
            image: &rev_images,
        },
        observations: &rev_obs,
        covariances: Some(&rev_cov),
    };
    let c = triangulate_points(&cameras, reversed, &opts, None).unwrap();
    for (t, (b, c)) in triangulate_points(&cameras, s, &opts, None)
        .unwrap()
        .into_iter()
        .zip(c)
        .enumerate()
    {
        let (b, c) = (b.unwrap(), c.unwrap());
        assert!((b.point - c.point).norm() <= 1e-8 * (1.0 + b.point.norm()), "track {t}");
        assert!(
            (b.report.cost - c.report.cost).abs() <= 1e-12 * (1.0 + b.report.cost),
            "track {t}"
        );
        assert_eq!(
            (b.report.status, b.report.certified()),
            (c.report.status, c.report.certified())
        );
    }
    // Bad tracks: an image index beyond the cameras (track 0), every observation in one image
    // (track 1: several keypoints of one image are allowed, but a point needs two distinct images).
    let mut bad_images = images.clone();
    bad_images[offsets[0]] = v;
    let first = bad_images[offsets[1]];
    bad_images[offsets[1]..offsets[2]].fill(first);
    let bad = SparsePointTracks {
        csr: Csr {
            image: &bad_images,
            ..s.csr
        },
        ..s
    };
    let r = triangulate_points(&cameras, bad, &opts, None).unwrap();
    assert!(matches!(&r[0], Err(Error::Shape { what, .. }) if *what == format!("image[{}]", offsets[0])));
    assert!(
        matches!(&r[1], Err(Error::TooFewCorrespondences { required, actual, .. })
            if required == "2 distinct images per track" && actual.starts_with("track 1: "))
    );
    assert!(r[2..].iter().all(|x| x.is_ok()));
    // Whole-call errors: offsets that do not end at the observations, or decrease.
    let short = SparsePointTracks {
        csr: Csr {
            offsets: &offsets[..n],
            ..s.csr
        },
        ..s
    };
    assert!(
        matches!(triangulate_points(&cameras, short, &opts, None), Err(Error::Shape { what, .. }) if what == "offsets")
    );
    let mut down = offsets.clone();
    down.swap(1, 2);
    let down = SparsePointTracks {
        csr: Csr {
            offsets: &down,
            ..s.csr
        },
        ..s
    };
    assert!(
        matches!(triangulate_points(&cameras, down, &opts, None), Err(Error::Shape { what, .. }) if what == "offsets")
    );
}
