//! Pose through a lens with distortion, and with per-observation covariances (issue 12 §1, §5).
//!
//! The scenes are [`visible_scene`]'s (640 x 480, f = 600 px) seen through an OPENCV or OPENCV_FISHEYE
//! camera of the same pinhole part; the noise is Gaussian in the observed (distorted) pixels. The
//! statistical checks use the normalised estimation error squared (NEES) of the 6-vector
//! `(log(R R̂ᵀ), t − t̂)` under the returned covariance: its mean over trials is 6 for an efficient
//! estimator with a correct covariance, and the mean of `n` trials has standard deviation `√(12 / n)`.

use nalgebra::{Matrix2, Matrix6, Vector2, Vector3, Vector6};
use pluecker::camera::{Camera, CameraModel};
use pluecker::geometry::testing::log_so3;
use pluecker::pose::{
    estimate_pose, Correspondences, ObservationNoise, PoseOptions, PoseResult, RansacOptions, Status,
};
use pluecker::rng::Rng;
use pluecker::synthetic::{visible_scene, Scene};
use pluecker::Error;

pub(super) fn opencv() -> Camera {
    Camera::new(
        CameraModel::OpenCv,
        &[600.0, 600.0, 320.0, 240.0, -0.28, 0.07, 5e-4, -3e-4],
    )
    .unwrap()
}

pub(super) fn fisheye() -> Camera {
    Camera::new(
        CameraModel::OpenCvFisheye,
        &[600.0, 600.0, 320.0, 240.0, 0.05, -0.02, 0.01, -0.002],
    )
    .unwrap()
}

/// The scene's structure observed through `lens`, with Gaussian noise of `sigma(i)` px on observation
/// `i` (points first, then the segment endpoints).
fn observe(scene: &Scene, lens: &Camera, sigma: &dyn Fn(usize) -> f64, rng: &mut Rng) -> Correspondences {
    let c = &scene.correspondences;
    let mut index = 0;
    let mut pixel = |x: &Vector3<f64>| {
        let s = sigma(index);
        index += 1;
        lens.project(&scene.to_camera(x)) + Vector2::new(rng.normal(), rng.normal()) * s
    };
    Correspondences {
        points2d: c.points3d.iter().map(&mut pixel).collect(),
        points3d: c.points3d.clone(),
        lines2d: c.lines3d.iter().map(|s| [pixel(&s[0]), pixel(&s[1])]).collect(),
        lines3d: c.lines3d.clone(),
        noise: None,
    }
}

/// NEES of the result against the scene's pose (`None` without a covariance).
fn nees(result: &PoseResult, scene: &Scene) -> Option<f64> {
    let cov: Matrix6<f64> = result.covariance?;
    let dw = log_so3(&(scene.rotation * result.pose.rotation.transpose()));
    let dt = scene.translation - result.pose.translation;
    let e = Vector6::new(dw.x, dw.y, dw.z, dt.x, dt.y, dt.z);
    Some((e.transpose() * cov.try_inverse()? * e)[0])
}

pub(super) fn with_sigma(sigma: f64) -> PoseOptions {
    let mut options = PoseOptions::default();
    options.sigma_px = Some(sigma);
    options
}

/// Mean NEES over `trials` seeds of `estimate`.
fn mean_nees(trials: u64, estimate: impl Fn(&Scene, &mut Rng) -> PoseResult) -> f64 {
    let mut total = 0.0;
    for seed in 0..trials {
        let scene = visible_scene(600.0, 30, 4, false, 100 + seed);
        let result = estimate(&scene, &mut Rng::new(seed));
        assert_eq!(result.report.status, Status::Success, "seed {seed}");
        total += nees(&result, &scene).expect("a covariance");
    }
    total / trials as f64
}

#[test]
fn distortion_is_modelled_and_the_covariance_is_right() {
    // 100 trials: the mean NEES is 6 ± 0.35 (1σ); [5, 7] is about ±3σ.
    for lens in [opencv(), fisheye()] {
        let modelled = mean_nees(100, |scene, rng| {
            let corr = observe(scene, &lens, &|_| 1.0, rng);
            estimate_pose(&lens, &corr, &with_sigma(1.0)).unwrap()
        });
        assert!(
            (5.0..7.0).contains(&modelled),
            "{:?}: mean NEES {modelled}",
            lens.model()
        );
        // The same pixels taken as a pinhole camera's: the distortion shows as a bias far outside the
        // covariance (the failure that issue 12 reports).
        let ignored = mean_nees(20, |scene, rng| {
            let corr = observe(scene, &lens, &|_| 1.0, rng);
            estimate_pose(&lens.without_distortion(), &corr, &with_sigma(1.0)).unwrap()
        });
        eprintln!(
            "{:?}: mean NEES {modelled:.3} modelled, {ignored:.0} ignored",
            lens.model()
        );
        assert!(
            ignored > 100.0,
            "{:?}: ignoring the distortion gave NEES {ignored}",
            lens.model()
        );
    }
}

#[test]
fn the_refined_pose_minimises_the_exact_distorted_pixel_error() {
    // Points only: the exact cost ½ Σ ‖u(R X + t) − u_obs‖² is defined without any approximation. One
    // Gauss-Newton step on it from the returned pose must be negligible against the pose's standard
    // deviation (5 % of it, in the Mahalanobis norm): the first-order whitening costs no accuracy.
    for lens in [opencv(), fisheye()] {
        for seed in 0..10 {
            let scene = visible_scene(600.0, 30, 0, false, 200 + seed);
            let corr = observe(&scene, &lens, &|_| 1.0, &mut Rng::new(seed));
            let result = estimate_pose(&lens, &corr, &with_sigma(1.0)).unwrap();
            let (r, t) = (result.pose.rotation, result.pose.translation);
            let (mut jtj, mut jtr) = (Matrix6::<f64>::zeros(), Vector6::<f64>::zeros());
            for (x, u) in corr.points3d.iter().zip(&corr.points2d) {
                let rx = r * x;
                let (p, d) = lens.project_with_jacobian(&(rx + t));
                let res = p - u;
                // Left perturbation exp(ω) R: ∂x_cam/∂ω = −[R X]×, ∂x_cam/∂t = I.
                let mut j = nalgebra::SMatrix::<f64, 2, 6>::zeros();
                j.fixed_view_mut::<2, 3>(0, 0)
                    .copy_from(&(d * -pluecker::geometry::testing::skew(&rx)));
                j.fixed_view_mut::<2, 3>(0, 3).copy_from(&d);
                jtj += j.transpose() * j;
                jtr += j.transpose() * res;
            }
            let step = jtj.cholesky().unwrap().solve(&-jtr);
            let cov = result.covariance.unwrap();
            let mahalanobis = (step.transpose() * cov.try_inverse().unwrap() * step)[0].sqrt();
            assert!(
                mahalanobis < 0.05,
                "{:?} seed {seed}: step of {mahalanobis} σ",
                lens.model()
            );
        }
    }
}

#[test]
fn robust_pose_through_a_lens_rejects_outliers() {
    let lens = opencv();
    for seed in 0..10 {
        let scene = visible_scene(600.0, 40, 0, false, 300 + seed);
        let mut rng = Rng::new(seed);
        let mut corr = observe(&scene, &lens, &|_| 1.0, &mut rng);
        // 30 % of the points replaced by random pixels at least 40 px from the truth.
        let mut outlier = [false; 40];
        for i in (0..40).step_by(3) {
            let truth = corr.points2d[i];
            while (corr.points2d[i] - truth).norm() < 40.0 {
                corr.points2d[i] = Vector2::new(rng.uniform_in(0.0, 640.0), rng.uniform_in(0.0, 480.0));
            }
            outlier[i] = true;
        }
        let mut ransac = RansacOptions::default();
        ransac.seed = seed;
        let mut opts = PoseOptions::default();
        opts.ransac = Some(ransac);
        opts.sigma_px = Some(1.0);
        let result = estimate_pose(&lens, &corr, &opts).unwrap();
        assert_eq!(result.report.status, Status::Success, "seed {seed}");
        for (i, _) in outlier.iter().enumerate().filter(|(_, &o)| o) {
            assert!(!result.inliers_points[i], "seed {seed}: outlier {i} kept");
        }
        let kept = result.inliers_points.iter().filter(|&&k| k).count();
        assert!(kept >= 25, "seed {seed}: {kept} of 26 inliers kept");
        let e = nees(&result, &scene).unwrap();
        // One trial's NEES is χ²₆: above 22.5 with probability 1e-3.
        assert!(e < 22.5, "seed {seed}: NEES {e}");
    }
}

#[test]
fn per_observation_covariances_weight_the_pose() {
    // Half the observations have σ = 0.3 px, half σ = 3 px along a random direction and 0.3 across it.
    let pinhole = Camera::new(CameraModel::Pinhole, &[600.0, 600.0, 320.0, 240.0]).unwrap();
    let (mut weighted_nees, mut weighted_err, mut plain_err) = (0.0, 0.0, 0.0);
    let trials = 100;
    for seed in 0..trials {
        let scene = visible_scene(600.0, 30, 4, false, 400 + seed);
        let mut rng = Rng::new(seed);
        let n = 30 + 8;
        let covs: Vec<Matrix2<f64>> = (0..n)
            .map(|i| {
                if i % 2 == 0 {
                    Matrix2::identity() * 0.09
                } else {
                    let a = rng.uniform_in(0.0, std::f64::consts::PI);
                    let d = Vector2::new(a.cos(), a.sin());
                    d * d.transpose() * 9.0 + Matrix2::identity() * 0.09
                }
            })
            .collect();
        // Draw the noise of observation i from covs[i] (Cholesky factor times a standard normal).
        let factors: Vec<Matrix2<f64>> = covs.iter().map(|c| c.cholesky().unwrap().l()).collect();
        let c = &scene.correspondences;
        let mut k = 0;
        let mut pixel = |x: &Vector3<f64>| {
            let u = pinhole.project(&scene.to_camera(x)) + factors[k] * Vector2::new(rng.normal(), rng.normal());
            k += 1;
            u
        };
        let corr = Correspondences {
            points2d: c.points3d.iter().map(&mut pixel).collect(),
            points3d: c.points3d.clone(),
            lines2d: c.lines3d.iter().map(|s| [pixel(&s[0]), pixel(&s[1])]).collect(),
            lines3d: c.lines3d.clone(),
            noise: None,
        };
        let line_covs: Vec<[Matrix2<f64>; 2]> = (0..4).map(|i| [covs[30 + 2 * i], covs[31 + 2 * i]]).collect();
        let noise = ObservationNoise::from_covariances(&covs[..30], &line_covs).unwrap();
        let weighted = estimate_pose(
            &scene.camera,
            &Correspondences {
                noise: Some(noise),
                ..corr.clone()
            },
            &PoseOptions::default(),
        )
        .unwrap();
        assert_eq!(weighted.report.status, Status::Success, "seed {seed}");
        assert_eq!(weighted.details.sigma_px, Some(1.0), "covariances are absolute");
        weighted_nees += nees(&weighted, &scene).unwrap() / trials as f64;
        let plain = estimate_pose(&scene.camera, &corr, &PoseOptions::default()).unwrap();
        let error = |r: &PoseResult| (r.pose.translation - scene.translation).norm_squared();
        weighted_err += error(&weighted);
        plain_err += error(&plain);
    }
    assert!((5.0..7.0).contains(&weighted_nees), "mean NEES {weighted_nees}");
    // Weighting by the covariances must beat the unweighted pose clearly (about 3x here).
    let ratio = (weighted_err / plain_err).sqrt();
    eprintln!("covariances: mean NEES {weighted_nees:.2}, RMS translation error ratio {ratio:.3}");
    assert!(ratio < 0.6, "RMS translation error ratio weighted / plain = {ratio}");
}

#[test]
fn bad_noise_and_pixels_beyond_the_lens_are_named_errors() {
    let scene = visible_scene(600.0, 10, 0, false, 1);
    let lens = opencv();
    let corr = observe(&scene, &lens, &|_| 0.0, &mut Rng::new(1));
    let short = ObservationNoise::from_covariances(&[Matrix2::identity(); 9], &[]).unwrap();
    let with_short = Correspondences {
        noise: Some(short),
        ..corr.clone()
    };
    let err = estimate_pose(&lens, &with_short, &PoseOptions::default()).unwrap_err();
    assert!(matches!(err, Error::Shape { .. }), "{err}");
    // SIMPLE_RADIAL with k = −0.28 folds at r² = 1 / (3 |k|): no pixel beyond a distorted radius of
    // (2/3) r ≈ 0.73 focal lengths comes from a point in front; 0.8 is outside the invertible region.
    let radial = Camera::new(CameraModel::SimpleRadial, &[600.0, 320.0, 240.0, -0.28]).unwrap();
    let mut far = observe(&scene, &radial, &|_| 0.0, &mut Rng::new(1));
    far.points2d[4] = Vector2::new(320.0 + 0.8 * 600.0, 240.0);
    let err = estimate_pose(&radial, &far, &PoseOptions::default()).unwrap_err();
    assert!(
        err.to_string().contains("points2d") && err.to_string().contains("pixel 4"),
        "{err}"
    );
    // Through a lens, exact data are certified by the certificate through the lens, of its own kind.
    let mut opts = PoseOptions::default();
    opts.certify = Some(Default::default());
    let result = estimate_pose(&lens, &corr, &opts).unwrap();
    let certificate = result.report.certificate.expect("a bound on exact data");
    assert!(certificate.certified && certificate.kind == pluecker::CertificateKind::LensSublevelSet);
    assert_eq!(result.report.status, Status::Success);
}

#[test]
fn with_ransac_a_pixel_beyond_the_lens_is_an_outlier_not_an_error() {
    // A fisheye of f = 300 px: no point in front of the camera projects beyond θ_d(π/2) ≈ 1.67 focal
    // lengths from the centre, where a random mismatch can still land.
    let lens = Camera::new(
        CameraModel::OpenCvFisheye,
        &[300.0, 300.0, 320.0, 240.0, 0.05, -0.01, 0.002, -3e-4],
    )
    .unwrap();
    let scene = visible_scene(600.0, 30, 2, false, 9);
    let mut corr = observe(&scene, &lens, &|_| 0.5, &mut Rng::new(9));
    corr.points2d[7] = Vector2::new(320.0 + 1.8 * 300.0, 240.0);
    corr.lines2d[1][0] = Vector2::new(320.0, 240.0 - 1.8 * 300.0);
    assert!(estimate_pose(&lens, &corr, &PoseOptions::default()).is_err());
    let mut opts = PoseOptions::default();
    opts.ransac = Some(RansacOptions::default());
    let result = estimate_pose(&lens, &corr, &opts).unwrap();
    assert_eq!(result.report.status, Status::Success);
    assert_eq!(result.inliers_points.len(), 30);
    assert_eq!(result.inliers_lines.len(), 2);
    assert!(!result.inliers_points[7] && !result.inliers_lines[1]);
    assert!(result.inliers_points.iter().filter(|&&k| k).count() >= 28 && result.inliers_lines[0]);
}

#[test]
fn ransac_thresholds_are_distorted_pixels_at_the_fisheye_edge() {
    // Structure filling a 140° field of view seen by a fisheye: at 70° off-axis the undistortion stretches
    // a pixel about 8.5-fold radially. With thresholds in undistorted pixels the 1 px noise there would
    // exceed 4 px; in distorted pixels only the 4 σ tail (3e-4) is lost.
    let lens = fisheye();
    let (mut kept, mut total) = (0, 0);
    for seed in 0..10 {
        let scene = visible_scene(120.0, 60, 0, false, 500 + seed);
        let corr = observe(&scene, &lens, &|_| 1.0, &mut Rng::new(seed));
        let mut ransac = RansacOptions::default();
        ransac.seed = seed;
        let mut opts = PoseOptions::default();
        opts.ransac = Some(ransac);
        opts.sigma_px = Some(1.0);
        let result = estimate_pose(&lens, &corr, &opts).unwrap();
        assert_eq!(result.report.status, Status::Success, "seed {seed}");
        kept += result.inliers_points.iter().filter(|&&k| k).count();
        total += 60;
        assert!(nees(&result, &scene).unwrap() < 22.5, "seed {seed}");
    }
    assert!(kept as f64 >= 0.99 * total as f64, "{kept} of {total} inliers kept");
}

/// The pixel of the camera-frame point `x` through an OPENCV (`[fx, fy, cx, cy, k1, k2, p1, p2]`) or
/// OPENCV_FISHEYE (`[fx, fy, cx, cy, k1, k2, k3, k4]`) camera, written here from COLMAP's definitions:
/// the oracle of the distortion for the covariance test below.
fn distorted_pixel(fisheye: bool, p: &[f64], x: &Vector3<f64>) -> Vector2<f64> {
    let (a, b) = (x.x / x.z, x.y / x.z);
    let (xd, yd) = if fisheye {
        let r = (a * a + b * b).sqrt();
        let th = r.atan();
        let th2 = th * th;
        let thd = th * (1.0 + p[4] * th2 + p[5] * th2 * th2 + p[6] * th2.powi(3) + p[7] * th2.powi(4));
        if r > 0.0 {
            (a * thd / r, b * thd / r)
        } else {
            (a, b)
        }
    } else {
        let r2 = a * a + b * b;
        let radial = 1.0 + p[4] * r2 + p[5] * r2 * r2;
        (
            a * radial + 2.0 * p[6] * a * b + p[7] * (r2 + 2.0 * a * a),
            b * radial + p[6] * (r2 + 2.0 * b * b) + 2.0 * p[7] * a * b,
        )
    };
    Vector2::new(p[0] * xd + p[2], p[1] * yd + p[3])
}

/// `undistort` maps each observation to the pixels of the lens's pinhole part with the noise that
/// keeps it in distorted pixels: a segment endpoint's covariance becomes `J⁻¹ Σ J⁻ᵀ`, a point's
/// whitening `W` has `WᵀW = Jᵀ Σ⁻¹ J`, with `J = ∂u/∂ū` the derivative of the distorted pixel with
/// respect to the undistorted one. Checked against `J` by central differences of the distortion
/// written independently (`distorted_pixel`), for random covariances, on OPENCV and fisheye lenses,
/// out to the image corners (where J is far from the identity).
#[test]
fn undistorted_covariances_match_the_derivative_of_the_distortion() {
    let mut rng = Rng::new(77);
    for (lens, fisheye) in [(opencv(), false), (fisheye(), true)] {
        let params = lens.params().to_vec();
        let (fx, fy, cx, cy) = (params[0], params[1], params[2], params[3]);
        // Observations: distorted pixels of random camera-frame points over the whole image.
        let n = 12;
        let pixels: Vec<Vector2<f64>> = (0..3 * n)
            .map(|_| {
                let x = Vector3::new(rng.uniform_in(-0.5, 0.5), rng.uniform_in(-0.38, 0.38), 1.0);
                let u = distorted_pixel(fisheye, &params, &x);
                // The oracle agrees with the library's forward model (the same convention).
                assert!((u - lens.project(&x)).norm() < 1e-9, "{u} vs {}", lens.project(&x));
                u
            })
            .collect();
        let spd = |rng: &mut Rng| {
            let a = Matrix2::new(rng.normal(), rng.normal(), rng.normal(), rng.normal());
            a * a.transpose() + Matrix2::identity() * 0.2
        };
        let point_covs: Vec<Matrix2<f64>> = (0..n).map(|_| spd(&mut rng)).collect();
        let line_covs: Vec<[Matrix2<f64>; 2]> = (0..n).map(|_| [spd(&mut rng), spd(&mut rng)]).collect();
        let corr = Correspondences {
            points2d: pixels[..n].to_vec(),
            points3d: vec![Vector3::zeros(); n],
            lines2d: (0..n).map(|i| [pixels[n + 2 * i], pixels[n + 2 * i + 1]]).collect(),
            lines3d: vec![[Vector3::zeros(), Vector3::x()]; n],
            noise: None,
        };
        let noise = ObservationNoise::from_covariances(&point_covs, &line_covs).unwrap();
        let (_, undistorted) = pluecker::pose::testing::undistort(&lens, &corr, Some(&noise)).unwrap();
        let out = undistorted.noise.as_ref().unwrap();
        // J = ∂u/∂ū at the undistorted pixel ū, by central differences of the oracle.
        let jacobian = |ubar: &Vector2<f64>| {
            let u_of = |v: &Vector2<f64>| {
                distorted_pixel(fisheye, &params, &Vector3::new((v.x - cx) / fx, (v.y - cy) / fy, 1.0))
            };
            let h = 1e-4;
            let col = |d: Vector2<f64>| (u_of(&(ubar + d)) - u_of(&(ubar - d))) / (2.0 * h);
            Matrix2::from_columns(&[col(Vector2::new(h, 0.0)), col(Vector2::new(0.0, h))])
        };
        // Central differences with h = 1e-4 px: relative error ~1e-8 on J.
        let close = |a: &Matrix2<f64>, b: &Matrix2<f64>| (a - b).norm() <= 1e-6 * b.norm();
        let mut stretch: f64 = 0.0;
        for i in 0..n {
            let ubar = undistorted.points2d[i];
            // ū maps back to the observation (the undistortion is the distortion's inverse).
            let back = distorted_pixel(
                fisheye,
                &params,
                &Vector3::new((ubar.x - cx) / fx, (ubar.y - cy) / fy, 1.0),
            );
            assert!(
                (back - corr.points2d[i]).norm() < 1e-6,
                "point {i}: {back} vs {}",
                corr.points2d[i]
            );
            let j = jacobian(&ubar);
            let w = out.points[i];
            let expected = j.transpose() * point_covs[i].try_inverse().unwrap() * j;
            assert!(
                close(&(w.transpose() * w), &expected),
                "point {i}: WᵀW = {} vs {expected}",
                w.transpose() * w
            );
            for (k, (end, cov)) in undistorted.lines2d[i].iter().zip(&line_covs[i]).enumerate() {
                let j = jacobian(end);
                let j_inv = j.try_inverse().unwrap();
                let expected = j_inv * cov * j_inv.transpose();
                assert!(
                    close(&out.lines[i][k], &expected),
                    "{:?} segment {i} endpoint {k}: covariance {} vs J⁻¹ Σ J⁻ᵀ = {expected}",
                    lens.model(),
                    out.lines[i][k]
                );
                stretch = stretch.max((j.norm() / 2f64.sqrt() - 1.0).abs());
            }
        }
        // Not vacuous: J is far from the identity somewhere (J and J⁻¹ would agree otherwise).
        assert!(stretch > 0.05, "{:?}: J within {stretch} of the identity", lens.model());
    }
}
