//! Quadric triangulation (Josephson & Kahl 2008, sections 2.3, 3, 4): exact recovery (also of a flat
//! quadric, the paper's real-data case), cost ordering and certificates, the soundness of the bound,
//! cheirality and bad input.

use nalgebra::{Matrix3, Matrix3x4, Matrix4, Rotation3, Vector3};
use pluecker::geometry::quadric::{project_dual, Ellipse, Ellipsoid};
use pluecker::rng::Rng;
use pluecker::triangulation::fitting::fit_conic;
use pluecker::triangulation::quadric::{triangulate_quadric, triangulate_quadric_points, Matrix5};
use pluecker::triangulation::quadric::residual::ConicFrame;
use pluecker::triangulation::scenes::quadric_scene;
use pluecker::triangulation::{CertificateKind, Method, Status, TriangulationOptions};
use pluecker::Error;

fn opts(method: Method) -> TriangulationOptions {
    TriangulationOptions {
        method,
        max_nodes: 200,
        ..Default::default()
    }
}

fn outlines(cameras: &[Matrix3x4<f64>], e: &Ellipsoid) -> Vec<Matrix3<f64>> {
    cameras
        .iter()
        .map(|p| project_dual(p, &e.dual()).try_inverse().unwrap())
        .collect()
}

/// Eq. 19 at a world dual quadric, recomputed from the image conics (section 3.1, eq. 18).
fn quadric_cost(
    cameras: &[Matrix3x4<f64>],
    conics: &[Matrix3<f64>],
    covariances: &[Matrix5],
    dual: &Matrix4<f64>,
) -> f64 {
    cameras
        .iter()
        .zip(conics)
        .zip(covariances)
        .map(|((p, c), cov)| {
            let r = ConicFrame::of_conic(c).unwrap().residual(&project_dual(p, dual));
            r.dot(&(cov.try_inverse().unwrap() * r))
        })
        .sum()
}

#[test]
fn noise_free_ellipsoids_are_recovered_by_every_method() {
    for (views, seed) in [(3, 1u64), (5, 2)] {
        let scene = quadric_scene(views, 0.8, seed);
        let conics = outlines(&scene.cameras, &scene.ellipsoid);
        for method in Method::ALL {
            let r = triangulate_quadric(&scene.cameras, &conics, None, &opts(method)).unwrap();
            let e = &scene.ellipsoid;
            assert!(
                (r.centre - e.centre).norm() < 1e-7,
                "{} {}",
                method.as_str(),
                (r.centre - e.centre).norm()
            );
            assert!(
                (r.semi_axes - e.semi_axes).norm() < 1e-7,
                "{} {:?}",
                method.as_str(),
                r.semi_axes
            );
            for k in 0..3 {
                assert!((r.axes.column(k).dot(&e.axes.column(k)).abs() - 1.0).abs() < 1e-6);
            }
            assert!(
                r.report.cost < 1e-12 && r.report.status == Status::Success,
                "{:?}",
                r.report
            );
            assert!((r.dual[(3, 3)] + 1.0).abs() < 1e-12);
            assert!((r.primal.unwrap() * r.dual - Matrix4::identity()).norm() < 1e-6);
        }
    }
}

#[test]
fn a_disc_is_recovered_as_a_flat_ellipsoid() {
    // The paper's real conics are planar (section 5.1): a disc of radii 0.4 and 0.25.
    let scene = quadric_scene(4, 0.8, 3);
    let disc = Ellipsoid {
        centre: Vector3::new(0.05, -0.1, 0.0),
        axes: Rotation3::new(Vector3::new(0.4, -0.3, 0.2)).into_inner(),
        semi_axes: Vector3::new(0.4, 0.25, 0.0),
    };
    let conics = outlines(&scene.cameras, &disc);
    for method in [Method::Linear, Method::Local] {
        let r = triangulate_quadric(&scene.cameras, &conics, None, &opts(method)).unwrap();
        assert!((r.centre - disc.centre).norm() < 1e-6, "{}", method.as_str());
        assert!(
            (r.semi_axes.xy() - disc.semi_axes.xy()).norm() < 1e-6 && r.semi_axes.z < 1e-4,
            "{:?}",
            r.semi_axes
        );
        assert!(r.report.cost < 1e-9, "{:?}", r.report);
    }
}

#[test]
fn noisy_ellipsoids_are_certified_and_costs_ordered() {
    for seed in 0..5u64 {
        let views = 3 + seed as usize;
        let scene = quadric_scene(views, 0.8, 10 + seed);
        let mut rng = Rng::new(20 + seed);
        let points = scene.noisy_outline_points(63, 1.0, &mut rng);
        let run = |m| triangulate_quadric_points(&scene.cameras, &points, 1.0, &opts(m)).unwrap();
        let (linear, local, optimal) = (run(Method::Linear), run(Method::Local), run(Method::Optimal));
        let tol = 1e-9 * (1.0 + linear.report.cost);
        assert!(local.report.cost <= linear.report.cost + tol, "seed {seed}");
        assert!(optimal.report.cost <= local.report.cost + tol, "seed {seed}");
        let c = optimal.report.certificate;
        assert_eq!(c.kind, CertificateKind::BranchAndBound);
        assert!(
            c.certified && c.lower_bound <= optimal.report.cost,
            "seed {seed}: {:?}",
            optimal.report
        );
        assert_eq!(optimal.report.status, Status::Success);
        // The estimate fits at least as well as the truth.
        let fits: Vec<_> = points.iter().map(|p| fit_conic(p, 1.0).unwrap()).collect();
        let conics: Vec<Matrix3<f64>> = fits.iter().map(|f| f.conic).collect();
        let covariances: Vec<Matrix5> = fits.iter().map(|f| f.covariance).collect();
        let truth = quadric_cost(&scene.cameras, &conics, &covariances, &scene.ellipsoid.dual());
        assert!(
            optimal.report.cost <= truth + tol,
            "seed {seed}: {} > {truth}",
            optimal.report.cost
        );
        let recomputed = quadric_cost(&scene.cameras, &conics, &covariances, &optimal.dual);
        assert!((recomputed - optimal.report.cost).abs() < 1e-7 * (1.0 + recomputed));
    }
}

#[test]
fn certified_bound_is_below_the_cost_of_nearby_ellipsoids() {
    let scene = quadric_scene(4, 0.8, 30);
    let mut rng = Rng::new(31);
    let points = scene.noisy_outline_points(63, 1.0, &mut rng);
    let optimal = triangulate_quadric_points(&scene.cameras, &points, 1.0, &opts(Method::Optimal)).unwrap();
    let c = optimal.report.certificate;
    assert!(c.certified);
    let fits: Vec<_> = points.iter().map(|p| fit_conic(p, 1.0).unwrap()).collect();
    let conics: Vec<Matrix3<f64>> = fits.iter().map(|f| f.conic).collect();
    let covariances: Vec<Matrix5> = fits.iter().map(|f| f.covariance).collect();
    for k in 0..300 {
        let scale = 10f64.powi(-(k % 4) - 1) * 0.2;
        let moved = Ellipsoid {
            centre: optimal.centre + Vector3::new(rng.normal(), rng.normal(), rng.normal()) * scale,
            axes: optimal.axes
                * Rotation3::new(Vector3::new(rng.normal(), rng.normal(), rng.normal()) * scale).into_inner(),
            semi_axes: optimal.semi_axes + Vector3::new(rng.normal(), rng.normal(), rng.normal()) * scale,
        };
        let cost = quadric_cost(&scene.cameras, &conics, &covariances, &moved.dual());
        assert!(
            cost >= c.lower_bound - 1e-9,
            "cost {cost} below the bound {}",
            c.lower_bound
        );
    }
}

#[test]
fn too_small_gamma_is_infeasible() {
    let scene = quadric_scene(4, 0.8, 40);
    let mut rng = Rng::new(41);
    let points = scene.noisy_outline_points(63, 1.0, &mut rng);
    let o = TriangulationOptions {
        max_reprojection_error: Some(1e-3),
        ..opts(Method::Optimal)
    };
    let r = triangulate_quadric_points(&scene.cameras, &points, 1.0, &o).unwrap();
    assert_eq!(r.report.status, Status::Infeasible);
    assert!(!r.report.certificate.certified);
}

#[test]
fn an_ellipsoid_behind_a_camera_is_reported() {
    // Camera 0 turned to look away from the ellipsoid (same centre, rotated by π about its y axis):
    // the outline equations (eq. 12) still hold, but the estimate lies behind that camera.
    let scene = quadric_scene(4, 0.8, 50);
    let mut cameras = scene.cameras.clone();
    let turn = Rotation3::from_axis_angle(&Vector3::y_axis(), std::f64::consts::PI).into_inner();
    let k = Matrix3::new(800.0, 0.0, 320.0, 0.0, 800.0, 240.0, 0.0, 0.0, 1.0);
    let rt = k.try_inverse().unwrap() * cameras[0];
    let r = turn * rt.fixed_view::<3, 3>(0, 0);
    let mut turned = Matrix3x4::zeros();
    turned.fixed_view_mut::<3, 3>(0, 0).copy_from(&r);
    turned.set_column(3, &(turn * rt.column(3)));
    cameras[0] = k * turned;
    let conics = outlines(&cameras, &scene.ellipsoid);
    assert!(
        Ellipse::from_primal(&conics[0]).is_some(),
        "the mirrored outline is still an ellipse"
    );
    for method in Method::ALL {
        let r = triangulate_quadric(&cameras, &conics, None, &opts(method)).unwrap();
        assert_eq!(r.report.status, Status::BehindCamera, "{}", method.as_str());
        // Status and certificate agree (issue 10: optimal said behind_camera and certified).
        assert!(!r.report.certificate.certified, "{}", method.as_str());
    }
}

#[test]
fn bad_input_is_rejected_with_the_argument_and_index() {
    let scene = quadric_scene(3, 0.8, 60);
    let conics = outlines(&scene.cameras, &scene.ellipsoid);
    let o = opts(Method::Local);
    let err = |c: &[Matrix3x4<f64>], q: &[Matrix3<f64>], cov: Option<&[Matrix5]>| {
        triangulate_quadric(c, q, cov, &o).unwrap_err()
    };
    assert!(matches!(
        err(&scene.cameras[..2], &conics[..2], None),
        Error::TooFewCorrespondences { .. }
    ));
    assert!(matches!(err(&scene.cameras, &conics[..2], None), Error::Shape { .. }));
    let mut nan = conics.clone();
    nan[1][(0, 2)] = f64::NAN;
    assert!(matches!(err(&scene.cameras, &nan, None), Error::NonFinite { ref what, index: 1 } if what == "conics"));
    let mut hyperbola = conics.clone();
    hyperbola[2] = Matrix3::from_diagonal(&Vector3::new(1.0, -1.0, -100.0));
    assert!(
        matches!(err(&scene.cameras, &hyperbola, None), Error::Degenerate { ref what } if what.contains("conics[2]"))
    );
    let mut bad_cov = vec![Matrix5::identity(); 3];
    bad_cov[0][(4, 4)] = -1.0;
    assert!(
        matches!(err(&scene.cameras, &conics, Some(&bad_cov)), Error::Degenerate { ref what } if what.contains("covariances[0]"))
    );
    let same = vec![scene.cameras[0], scene.cameras[0] * 2.0, scene.cameras[0] * -1.0];
    assert!(matches!(err(&same, &conics, None), Error::Degenerate { ref what } if what.contains("centres")));
    let mut cams = scene.cameras.clone();
    cams[2] = Matrix3x4::zeros();
    assert!(matches!(err(&cams, &conics, None), Error::SingularCamera { .. }));
    let bad = TriangulationOptions {
        max_nodes: 0,
        ..o.clone()
    };
    assert!(matches!(
        triangulate_quadric(&scene.cameras, &conics, None, &bad),
        Err(Error::InvalidOption { .. })
    ));
}
