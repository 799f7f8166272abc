//! Which side of a camera is "in front" (issue 10). The convention is eq. 1 as written:
//! `λ (u, v, 1)ᵀ = P (X, 1)ᵀ` with `λ = (P X̃)₃ > 0` for the matrix as given, so that `K [R | t]` sees
//! the points with `z_cam > 0` whatever the signs of the focal lengths and the handedness of the
//! world frame. Every primitive and method must agree with it: mirroring the images (`fx → −fx`) or
//! the world (`det M < 0`, as in the raw VGG files) changes nothing, and data best explained behind
//! the cameras never come back as a certified success.

use nalgebra::{Matrix3, Matrix3x4, Matrix4, Vector2, Vector3, Vector4};
use pluecker::geometry::plucker;
use pluecker::rng::Rng;
use pluecker::synthetic::{paper_calibration_object, paper_pose, triangulation_scene};
use pluecker::triangulation::fitting::fit_conic;
use pluecker::triangulation::line::{lines_from_segments, triangulate_line, LineObservations};
use pluecker::triangulation::point::{triangulate_point, PointTriangulation};
use pluecker::triangulation::point::{triangulate_points, DensePointTracks, LinearPoints};
use pluecker::triangulation::quadric::{triangulate_quadric, QuadricObservations};
use pluecker::triangulation::scenes::{line_scene, quadric_scene};
use pluecker::triangulation::{Method, Report, Status, TriangulationOptions};

fn opts(method: Method) -> TriangulationOptions {
    let mut options = TriangulationOptions::default();
    options.method = method;
    options.certify.max_nodes = Some(300);
    options
}

fn project(p: &Matrix3x4<f64>, x: &Vector3<f64>) -> Vector2<f64> {
    let h = p * x.push(1.0);
    h.xy() / h.z
}

/// The mirror of the images about the column `u = 0`, `u' = −u`: `F K [R | t]` is the camera with
/// `−fx` and `−cx`. It fixes the pixel origin, so the residuals of lines and conics (whose
/// normalisations of section 3.1 are anchored there) are unchanged too.
fn mirror_image() -> Matrix3<f64> {
    Matrix3::from_diagonal(&Vector3::new(-1.0, 1.0, 1.0))
}

fn mirror_pixel(u: &Vector2<f64>) -> Vector2<f64> {
    Vector2::new(-u.x, u.y)
}

/// The mirror of the world, `Z → −Z`: `P S` sees `S X` where `P` saw `X`, and `det M` changes sign.
fn mirror_world() -> Matrix4<f64> {
    Matrix4::from_diagonal(&Vector4::new(1.0, 1.0, -1.0, 1.0))
}

/// Status and certificate agree: certified exactly when an optimal solve succeeded.
fn assert_consistent(report: &Report, what: &str) {
    if report.certified() {
        assert_eq!(
            report.status,
            Status::Success,
            "{what}: certified but {:?}",
            report.status
        );
    }
    if report.method == Method::Optimal && report.status == Status::Success {
        assert!(report.certified(), "{what}: optimal success without a certificate");
    }
}

/// Three cameras `K [R | t + d]` with the paper's intrinsics (`α_u = −1730.3`, so `det K < 0`) and
/// pose, `d` moving the centre by 5 cm; the first point of the paper's object, 78 cm in front.
fn paper_cameras() -> (Vec<Matrix3x4<f64>>, Vector3<f64>) {
    let (camera, rotation, translation) = paper_pose();
    let k = camera.intrinsics().matrix();
    assert!(k.determinant() < 0.0);
    let cameras = [
        Vector3::zeros(),
        Vector3::new(5.0, 0.0, 0.0),
        Vector3::new(0.0, 5.0, 0.0),
    ]
    .iter()
    .map(|d| {
        let mut rt = Matrix3x4::zeros();
        rt.fixed_view_mut::<3, 3>(0, 0).copy_from(&rotation);
        rt.set_column(3, &(translation + d));
        k * rt
    })
    .collect();
    (cameras, paper_calibration_object().correspondences.points3d[0])
}

#[test]
fn a_point_in_front_of_cameras_with_a_negative_focal_length_is_found_by_every_method() {
    let (cameras, truth) = paper_cameras();
    let obs: Vec<Vector2<f64>> = cameras.iter().map(|p| project(p, &truth)).collect();
    for p in &cameras {
        assert!((p * truth.push(1.0)).z > 70.0, "λ is the depth, 78 cm");
    }
    for method in Method::ALL.iter().copied() {
        let r = triangulate_point(&cameras, &obs, None, &opts(method)).unwrap();
        assert_eq!(r.report.status, Status::Success, "{method:?}: {:?}", r.report);
        assert_consistent(&r.report, method.as_str());
        // Exact data, 78 cm deep over a 5 cm baseline: the DLT is exact to ~1e-12 relative.
        assert!(
            (r.point - truth).norm() < 1e-8 * truth.norm().max(78.0),
            "{method:?}: {}",
            r.point
        );
        if method == Method::Optimal {
            assert!(r.report.certified());
        }
    }
    // The batches agree.
    let flat: Vec<f64> = obs.iter().flat_map(|u| [u.x, u.y]).collect();
    let tracks = DensePointTracks {
        observations: &flat,
        visible: None,
        covariances: None,
    };
    let linear = LinearPoints::from_tracks(&cameras, &tracks).unwrap();
    assert_eq!(*linear.outcomes[0].as_ref().unwrap(), Status::Success);
    let batch = triangulate_points(&cameras, tracks, &opts(Method::Optimal), None).unwrap();
    let r = batch[0].as_ref().unwrap();
    assert_eq!(r.report.status, Status::Success);
    assert!(r.report.certified() && (r.point - truth).norm() < 1e-8 * 78.0);
}

fn same_point(a: &PointTriangulation, b: &PointTriangulation, truth_scale: f64, what: &str) {
    assert_eq!(
        a.report.status, b.report.status,
        "{what}: {:?} vs {:?}",
        a.report, b.report
    );
    assert_eq!(a.report.certified(), b.report.certified(), "{what}");
    // The mirrors are isometries of the image or the world: the same solve up to rounding.
    assert!(
        (a.report.cost - b.report.cost).abs() <= 1e-8 * a.report.cost.max(1e-6),
        "{what}: {a:?} vs {b:?}"
    );
    assert!(
        (a.point - b.point).norm() <= 1e-8 * truth_scale,
        "{what}: {} vs {}",
        a.point,
        b.point
    );
}

#[test]
fn mirrored_images_and_mirrored_worlds_give_the_same_points() {
    let s = Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, -1.0));
    for seed in 0..6u64 {
        let scene = triangulation_scene(3 + seed as usize % 3, 0.3, 100 + seed);
        let obs = scene.noisy(1.0, &mut Rng::new(seed));
        let image_mirrored: Vec<Matrix3x4<f64>> = scene.cameras.iter().map(|p| mirror_image() * p).collect();
        let mirrored_obs: Vec<Vector2<f64>> = obs.iter().map(mirror_pixel).collect();
        let world_mirrored: Vec<Matrix3x4<f64>> = scene.cameras.iter().map(|p| p * mirror_world()).collect();
        assert!(image_mirrored
            .iter()
            .chain(&world_mirrored)
            .all(|p| p.fixed_view::<3, 3>(0, 0).determinant() < 0.0));
        for method in Method::ALL.iter().copied() {
            let what = format!("seed {seed} {method:?}");
            let plain = triangulate_point(&scene.cameras, &obs, None, &opts(method)).unwrap();
            assert_eq!(plain.report.status, Status::Success, "{what}");
            let a = triangulate_point(&image_mirrored, &mirrored_obs, None, &opts(method)).unwrap();
            same_point(&plain, &a, 5.0, &format!("{what}, mirrored images"));
            let mut b = triangulate_point(&world_mirrored, &obs, None, &opts(method)).unwrap();
            b.point = s * b.point;
            same_point(&plain, &b, 5.0, &format!("{what}, mirrored world"));
            assert_consistent(&a.report, &what);
        }
    }
}

#[test]
fn mirrored_images_give_the_same_lines() {
    for seed in 0..2u64 {
        let scene = line_scene(3, 0.8, 200 + seed);
        let mut rng = Rng::new(seed);
        let segments = scene.noisy_segments(1.0, &mut rng);
        let mirrored: Vec<[Vector2<f64>; 2]> = segments
            .iter()
            .map(|s| [mirror_pixel(&s[0]), mirror_pixel(&s[1])])
            .collect();
        let cameras: Vec<Matrix3x4<f64>> = scene.cameras.iter().map(|p| mirror_image() * p).collect();
        let world: Vec<Matrix3x4<f64>> = scene.cameras.iter().map(|p| p * mirror_world()).collect();
        let (lines, covs) = lines_from_segments(&segments, 1.0).unwrap();
        let (mlines, mcovs) = lines_from_segments(&mirrored, 1.0).unwrap();
        for method in Method::ALL.iter().copied() {
            let what = format!("seed {seed} {method:?}");
            let plain = triangulate_line(
                &scene.cameras,
                LineObservations::Lines(&lines, Some(&covs)),
                &opts(method),
            )
            .unwrap();
            let a = triangulate_line(&cameras, LineObservations::Lines(&mlines, Some(&mcovs)), &opts(method)).unwrap();
            let b = triangulate_line(&world, LineObservations::Lines(&lines, Some(&covs)), &opts(method)).unwrap();
            let b_plucker = plucker::transform(&mirror_world(), b.plucker.coordinates()).normalize();
            for (other, line, how) in [
                (&a.report, *a.plucker.coordinates(), "images"),
                (&b.report, b_plucker, "world"),
            ] {
                assert_eq!(plain.report.status, other.status, "{what}, mirrored {how}");
                assert_eq!(plain.report.certified(), other.certified(), "{what}, mirrored {how}");
                assert!(
                    (plain.report.cost - other.cost).abs() <= 1e-6 * plain.report.cost,
                    "{what}, mirrored {how}: {} vs {}",
                    plain.report.cost,
                    other.cost
                );
                let plain_line = plain.plucker.coordinates();
                let sign = plain_line.dot(&line).signum();
                assert!((plain_line - sign * line).norm() < 1e-6, "{what}, mirrored {how}");
                assert_consistent(other, &what);
            }
        }
    }
}

#[test]
fn mirrored_images_give_the_same_quadrics() {
    let scene = quadric_scene(3, 0.8, 300);
    let mut rng = Rng::new(3);
    let points = scene.noisy_outline_points(40, 0.5, &mut rng);
    let fits: Vec<_> = points.iter().map(|p| fit_conic(p, 0.5).unwrap()).collect();
    let mirrored: Vec<_> = points
        .iter()
        .map(|p| fit_conic(&p.iter().map(mirror_pixel).collect::<Vec<_>>(), 0.5).unwrap())
        .collect();
    let cameras: Vec<Matrix3x4<f64>> = scene.cameras.iter().map(|p| mirror_image() * p).collect();
    let world: Vec<Matrix3x4<f64>> = scene.cameras.iter().map(|p| p * mirror_world()).collect();
    let conics: Vec<Matrix3<f64>> = fits.iter().map(|f| f.conic).collect();
    let covs: Vec<_> = fits.iter().map(|f| f.covariance).collect();
    let mconics: Vec<Matrix3<f64>> = mirrored.iter().map(|f| f.conic).collect();
    let mcovs: Vec<_> = mirrored.iter().map(|f| f.covariance).collect();
    for method in Method::ALL.iter().copied() {
        let plain = triangulate_quadric(
            &scene.cameras,
            QuadricObservations::Conics(&conics, Some(&covs)),
            &opts(method),
        )
        .unwrap();
        assert_ne!(plain.report.status, Status::BehindCamera, "{method:?}");
        let a = triangulate_quadric(
            &cameras,
            QuadricObservations::Conics(&mconics, Some(&mcovs)),
            &opts(method),
        )
        .unwrap();
        let b = triangulate_quadric(&world, QuadricObservations::Conics(&conics, Some(&covs)), &opts(method)).unwrap();
        let b_centre = Vector3::new(b.centre.x, b.centre.y, -b.centre.z);
        for (other, centre, how) in [(&a, a.centre, "images"), (&b, b_centre, "world")] {
            let what = format!("{method:?}, mirrored {how}");
            assert_eq!(plain.report.status, other.report.status, "{what}");
            assert_eq!(plain.report.certified(), other.report.certified(), "{what}");
            assert!(
                (plain.report.cost - other.report.cost).abs() <= 1e-6 * plain.report.cost,
                "{what}"
            );
            assert!((plain.centre - centre).norm() < 1e-6, "{what}");
            assert!((plain.semi_axes - other.semi_axes).norm() < 1e-6, "{what}");
            assert_consistent(&other.report, &what);
        }
    }
}

/// The example: f = 800, cameras `K [I | (−c, 0, 0)]`, `c = −1, 0, 1`, and the exact images of
/// `X = (0.1, −0.2, −5)`, five units behind all three. Every point in front costs more than the
/// vanishing point of the best direction, `2 · 160² = 51200`: the infimum in front is at infinity.
#[test]
fn a_point_behind_every_camera_is_never_a_certified_success() {
    let k = Matrix3::new(800.0, 0.0, 320.0, 0.0, 800.0, 240.0, 0.0, 0.0, 1.0);
    let cameras: Vec<Matrix3x4<f64>> = [-1.0, 0.0, 1.0]
        .iter()
        .map(|c| {
            let mut rt = Matrix3x4::identity();
            rt[(0, 3)] = -c;
            k * rt
        })
        .collect();
    let behind = Vector3::new(0.1, -0.2, -5.0);
    let obs: Vec<Vector2<f64>> = cameras.iter().map(|p| project(p, &behind)).collect();
    let linear = triangulate_point(&cameras, &obs, None, &opts(Method::Linear)).unwrap();
    assert_eq!(linear.report.status, Status::BehindCamera);
    assert!((linear.point - behind).norm() < 1e-9);
    for method in [Method::Local, Method::Optimal] {
        let r = triangulate_point(&cameras, &obs, None, &opts(method)).unwrap();
        assert!(
            matches!(r.report.status, Status::BehindCamera | Status::AtInfinity),
            "{method:?}: {:?} at {}",
            r.report,
            r.point
        );
        assert!(!r.report.certified(), "{method:?}");
        assert_consistent(&r.report, method.as_str());
    }
    // The same cameras negated see the point in front (the sign of P is part of the camera).
    let negated: Vec<Matrix3x4<f64>> = cameras.iter().map(|p| -p).collect();
    let r = triangulate_point(&negated, &obs, None, &opts(Method::Optimal)).unwrap();
    assert_eq!(r.report.status, Status::Success);
    assert!(r.report.certified() && (r.point - behind).norm() < 1e-9);
}

/// A local stage stopped by its iteration cap on exact data: the cost is negligible, which certifies
/// the estimate (a sum of squares is never negative), and the status says success with it.
#[test]
fn a_certificate_of_negligible_cost_comes_with_a_success() {
    let mut o = opts(Method::Optimal);
    o.local.stopping.max_iterations = 0;
    let scene = line_scene(3, 0.8, 400);
    let lines: Vec<Vector3<f64>> = scene
        .segments
        .iter()
        .map(|s| s[0].push(1.0).cross(&s[1].push(1.0)))
        .collect();
    let r = triangulate_line(&scene.cameras, LineObservations::Lines(&lines, None), &o).unwrap();
    assert!(r.report.certified(), "{:?}", r.report);
    assert_consistent(&r.report, "line");
    let scene = quadric_scene(3, 0.8, 401);
    let conics = crate::common::outlines(&scene.cameras, &scene.ellipsoid);
    let r = triangulate_quadric(&scene.cameras, QuadricObservations::Conics(&conics, None), &o).unwrap();
    assert_consistent(&r.report, "quadric");
    let scene = triangulation_scene(3, 0.3, 402);
    let r = triangulate_point(&scene.cameras, &scene.observations, None, &o).unwrap();
    assert_consistent(&r.report, "point");
}
