//! Tests of the camera models: projection, unprojection, fold radius, distortion Jacobians.

use super::model::*;
use super::*;
use crate::error::Error;
use crate::rng::Rng;
use nalgebra::{Matrix2, Vector2, Vector3};

#[test]
fn a_lens_whose_pinhole_part_is_not_a_camera_is_refused() {
    // Its pinhole part must be a `Camera`: `pinhole()` never fails on a lens that was made.
    for f in [0.0, 1e-300, 1e300] {
        let err = Camera::new(CameraModel::SimpleRadial, &[f, 320.0, 240.0, -0.1]).unwrap_err();
        assert!(matches!(err, Error::SingularCamera { .. }), "{err}");
        assert!(
            err.to_string()
                .starts_with("singular camera: SIMPLE_RADIAL: focal lengths"),
            "{err}"
        );
    }
    let lens = Camera::new(CameraModel::Pinhole, &[1e-9, 1e150, 0.0, 0.0]).unwrap();
    assert_eq!((lens.intrinsics().fx, lens.intrinsics().fy), (1e-9, 1e150));
}

/// A camera of each model, in COLMAP's id order, with COLMAP-like distortion (moderate barrel, small
/// tangential and thin-prism terms; the fisheyes' distortion is 5-10 % at 80° off axis).
fn cameras() -> Vec<Camera> {
    let params: [(CameraModel, &[f64]); 18] = [
        (CameraModel::SimplePinhole, &[800.0, 320.0, 240.0]),
        (CameraModel::Pinhole, &[800.0, 790.0, 320.0, 240.0]),
        (CameraModel::SimpleRadial, &[800.0, 320.0, 240.0, -0.1]),
        (CameraModel::Radial, &[800.0, 320.0, 240.0, -0.1, 0.02]),
        (
            CameraModel::OpenCv,
            &[800.0, 790.0, 320.0, 240.0, -0.2, 0.05, 1e-3, -5e-4],
        ),
        (
            CameraModel::OpenCvFisheye,
            &[400.0, 395.0, 320.0, 240.0, 0.05, -0.01, 0.002, -3e-4],
        ),
        (
            CameraModel::FullOpenCv,
            &[
                800.0, 790.0, 320.0, 240.0, -0.2, 0.05, 1e-3, -5e-4, 0.01, 0.02, -0.01, 0.005,
            ],
        ),
        (CameraModel::Fov, &[400.0, 395.0, 320.0, 240.0, 0.9]),
        (CameraModel::SimpleRadialFisheye, &[400.0, 320.0, 240.0, 0.05]),
        (CameraModel::RadialFisheye, &[400.0, 320.0, 240.0, 0.05, -0.01]),
        (
            CameraModel::ThinPrismFisheye,
            &[
                400.0, 395.0, 320.0, 240.0, 0.05, -0.01, 1e-3, -5e-4, 0.002, -3e-4, 2e-3, -1e-3,
            ],
        ),
        (
            CameraModel::RadTanThinPrismFisheye,
            &[
                400.0, 395.0, 320.0, 240.0, 0.05, -0.01, 0.002, -3e-4, 1e-5, -1e-6, 1e-3, -5e-4, 2e-3, -1e-3, 3e-4,
                -2e-4,
            ],
        ),
        (CameraModel::SimpleDivision, &[800.0, 320.0, 240.0, -0.2]),
        (CameraModel::Division, &[800.0, 790.0, 320.0, 240.0, -0.2]),
        (CameraModel::SimpleFisheye, &[400.0, 320.0, 240.0]),
        (CameraModel::Fisheye, &[400.0, 395.0, 320.0, 240.0]),
        (CameraModel::Eucm, &[400.0, 395.0, 320.0, 240.0, 0.6, 1.1]),
        (CameraModel::SkewedPinhole, &[-800.0, 790.0, 320.0, 240.0, 12.5]),
    ];
    assert_eq!(params.map(|(m, _)| m).as_slice(), CameraModel::ALL);
    params.iter().map(|(m, p)| Camera::new(*m, p).unwrap()).collect()
}

/// The largest angle off axis of the test points of a model: 80° for the models that see that far
/// (fisheyes, FOV, EUCM, the barrel division model), 30° for the polynomial ones, whose fold is near.
fn widest_angle(model: CameraModel) -> f64 {
    let wide = model.is_fisheye()
        || matches!(
            model,
            CameraModel::Fov | CameraModel::Eucm | CameraModel::SimpleDivision | CameraModel::Division
        );
    (if wide { 80.0f64 } else { 30.0f64 }).to_radians()
}

/// Normalised coordinates at the given angle off axis, in direction `phi`.
fn at_angle(theta: f64, phi: f64) -> Vector2<f64> {
    Vector2::new(phi.cos(), phi.sin()) * theta.tan()
}

#[test]
fn the_jacobians_match_finite_differences() {
    let mut rng = Rng::new(41);
    for cam in cameras() {
        for _ in 0..50 {
            let x = Vector3::new(
                rng.uniform_in(-0.5, 0.5),
                rng.uniform_in(-0.4, 0.4),
                rng.uniform_in(1.0, 3.0),
            );
            let (_, j) = cam.project_with_jacobian(&x);
            for k in 0..3 {
                let h = 1e-6;
                let mut xp = x;
                xp[k] += h;
                let mut xm = x;
                xm[k] -= h;
                let numeric = (cam.project(&xp) - cam.project(&xm)) / (2.0 * h);
                // Central differences: O(h²) truncation and O(ε |u| / h) rounding, about 1e-7 px per unit.
                assert!(
                    (numeric - j.column(k)).norm() < 1e-5 * (1.0 + j.column(k).norm()),
                    "{:?}",
                    cam.model()
                );
            }
        }
    }
}

#[test]
fn the_distortion_jacobians_match_finite_differences_from_the_axis_to_wide_angles() {
    let mut rng = Rng::new(43);
    for cam in cameras() {
        let widest = widest_angle(cam.model());
        // Near the axis (every radius from 1e-9, both sides of FOV's series bound r = 0.01), then
        // uniformly in angle up to the widest.
        let mut points: Vec<Vector2<f64>> = [1e-9, 1e-7, 1e-5, 1e-3, 5e-3, 9.9e-3, 1.01e-2, 0.05]
            .iter()
            .map(|&r| Vector2::new(r * 0.6, -r * 0.8))
            .collect();
        points.extend((0..200).map(|_| at_angle(rng.uniform_in(0.0, widest), rng.uniform_in(0.0, 6.3))));
        for n in points {
            let (_, j) = cam.distort(&n);
            // A step relative to |n| (down to 1e-4 of it, so that it stays on one side of FOV's
            // bound at |n| = 0.01 ± 1e-4), and 1e-7 in absolute terms away from the axis.
            let h = (1e-4 * n.norm()).min(1e-7);
            for k in 0..2 {
                let mut np = n;
                np[k] += h;
                let mut nm = n;
                nm[k] -= h;
                let numeric = (cam.distort(&np).0 - cam.distort(&nm).0) / (2.0 * h);
                // Truncation O(h² |D⁽³⁾|) ≤ 1e-14 and rounding O(ε |D| / h): |D| ≤ 2
                // over h = min(1e-4 |n|, 1e-7) gives at most 4e-16 / 1e-7 = 4e-9 here.
                let error = (numeric - j.column(k)).norm();
                assert!(
                    error < 2e-8 * (1.0 + j.column(k).norm()),
                    "{:?} at n = {n:?}: ∂D/∂n{k} = {} vs {numeric} ({error:e})",
                    cam.model(),
                    j.column(k)
                );
            }
        }
    }
}

#[test]
fn models_have_colmap_ids_and_names() {
    // COLMAP's ids (colmap/sensor/models.h, CameraModelId), independent of the order of ALL.
    let colmap = [
        "SIMPLE_PINHOLE",
        "PINHOLE",
        "SIMPLE_RADIAL",
        "RADIAL",
        "OPENCV",
        "OPENCV_FISHEYE",
        "FULL_OPENCV",
        "FOV",
        "SIMPLE_RADIAL_FISHEYE",
        "RADIAL_FISHEYE",
        "THIN_PRISM_FISHEYE",
        "RAD_TAN_THIN_PRISM_FISHEYE",
        "SIMPLE_DIVISION",
        "DIVISION",
        "SIMPLE_FISHEYE",
        "FISHEYE",
        "EUCM",
    ];
    for (id, name) in colmap.iter().enumerate() {
        let model = CameraModel::parse(name).unwrap();
        assert_eq!(model.colmap_id(), Some(id as u32), "{name}");
        assert_eq!(CameraModel::ALL[id], model);
        assert_eq!(model.as_str(), *name);
    }
    let err = CameraModel::parse("EQUIRECTANGULAR").unwrap_err();
    assert!(
        matches!(&err, Error::InvalidOption { name, reason } if name == "model"
            && reason.contains("'EQUIRECTANGULAR' is not supported")
            && reason.contains("behind the camera")),
        "{err}"
    );
}

#[test]
fn projection_agrees_with_opencv() {
    // Reference pixels from OpenCV 5.0.0, an independent implementation: `cv2.projectPoints` with
    // distCoeffs (k1, k2, p1, p2) and the rational (k1, k2, p1, p2, k3, k4, k5, k6), and
    // `cv2.fisheye.projectPoints` with (k1, k2, k3, k4), of the points below at the identity pose.
    let points = [
        Vector3::new(0.3, -0.2, 1.5),
        Vector3::new(-0.4, 0.25, 2.0),
        Vector3::new(0.05, 0.1, 1.0),
    ];
    // (model, parameters, expected pixels of the three points).
    type Case<'a> = (CameraModel, &'a [f64], [[f64; 2]; 3]);
    let cases: [Case; 3] = [
        (
            CameraModel::OpenCv,
            &[800.0, 790.0, 320.0, 240.0, -0.2, 0.05, 1e-3, -5e-4],
            [
                [478.08003950617285, 135.96107028806586],
                [161.66099687500002, 337.7550648193359],
                [359.9013125, 318.8248421875],
            ],
        ),
        (
            CameraModel::FullOpenCv,
            &[
                800.0, 790.0, 320.0, 240.0, -0.2, 0.05, 1e-3, -5e-4, 0.01, 0.02, -0.01, 0.005,
            ],
            [
                [477.9028916767527, 136.07769260910078],
                [161.83182374163687, 337.6496326125835],
                [359.89140261979446, 318.805270174094],
            ],
        ),
        (
            CameraModel::OpenCvFisheye,
            &[400.0, 395.0, 320.0, 240.0, 0.05, -0.01, 0.002, -3e-4],
            [
                [398.7265990991503, 188.1716555930594],
                [241.22721516597178, 288.6175781397518],
                [339.92960115866975, 279.3609622883728],
            ],
        ),
    ];
    for (model, params, expected) in cases {
        let cam = Camera::new(model, params).unwrap();
        for (x, e) in points.iter().zip(expected) {
            let (u, _) = cam.project_with_jacobian(x);
            assert!((u - Vector2::new(e[0], e[1])).norm() < 1e-9, "{model:?}: {u} vs {e:?}");
        }
    }
}

#[test]
fn unprojection_inverts_projection_to_1e_10_px() {
    let mut rng = Rng::new(42);
    for cam in cameras() {
        let widest = widest_angle(cam.model());
        let (fx, fy) = cam.focal();
        let mut points: Vec<Vector2<f64>> = (0..200)
            .map(|_| at_angle(rng.uniform_in(0.0, widest), rng.uniform_in(0.0, 6.3)))
            .collect();
        points.extend([0.0, 1e-9, 1e-5, 5e-3, 0.0101].map(|r| Vector2::new(r * 0.6, -r * 0.8)));
        points.push(at_angle(widest, 2.0));
        for (i, x) in points.into_iter().enumerate() {
            let (u, _) = cam.project_with_jacobian(&Vector3::new(x.x, x.y, 1.0));
            let n = cam
                .unproject(&u, i)
                .unwrap_or_else(|e| panic!("{:?} at {:.1}°: {e}", cam.model(), x.norm().atan().to_degrees()));
            let (back, _) = cam.project_with_jacobian(&Vector3::new(n.x, n.y, 1.0));
            assert!(
                (back - u).norm() <= 1e-10 * 1.5,
                "{:?}: {:e} px",
                cam.model(),
                (back - u).norm()
            );
            // A residual of 1e-10 px moves n by at most ‖(diag(f) ∂D/∂n)⁻¹‖ 1e-10 (33x more at 80°
            // off axis than at the centre for an equidistant fisheye: dr/dθ = 1 / cos² θ).
            let (_, j) = cam.distort(&n);
            let sensitivity = (Matrix2::new(fx, 0.0, 0.0, fy) * j).try_inverse().unwrap().norm();
            assert!(
                (n - x).norm() < 2.0 * sensitivity * 1.5e-10 + 1e-15 * (1.0 + x.norm()),
                "{:?}: {:e} at |n| = {}",
                cam.model(),
                (n - x).norm(),
                x.norm()
            );
        }
    }
}

#[test]
fn pixels_without_a_preimage_are_refused_by_every_model() {
    // Pixels at 4 and 50 focal lengths from the principal point, far beyond the image of the half
    // space z > 0 for the models whose image is bounded: ρ < θ_d(90°) < 2 for these fisheyes,
    // 1 / (α √β) = 1.6 for EUCM, π / (2ω) = 1.75 for FOV, 2.2 = 1/√|k| for the barrel division model.
    for cam in cameras() {
        let bounded = cam.model().is_fisheye()
            || matches!(
                cam.model(),
                CameraModel::Fov | CameraModel::Eucm | CameraModel::SimpleDivision | CameraModel::Division
            );
        if !bounded {
            continue;
        }
        let (fx, fy) = cam.focal();
        let (cx, cy) = cam.principal_point();
        for scale in [4.0, 50.0] {
            let u = Vector2::new(cx + scale * fx * 0.6, cy - scale * fy * 0.8);
            let err = cam.unproject(&u, 9).unwrap_err();
            assert!(
                matches!(&err, Error::Degenerate { what } if what.starts_with("pixel 9")),
                "{:?}: {err}",
                cam.model()
            );
        }
    }
}

#[test]
fn beyond_the_fold_of_a_barrel_distortion_is_an_error() {
    // D(r) = r (1 − 0.5 r²) peaks at r = 1/√1.5: pixels mapped from beyond it have no valid preimage.
    let cam = Camera::new(CameraModel::SimpleRadial, &[500.0, 0.0, 0.0, -0.5]).unwrap();
    let peak = (1.0f64 / 1.5).sqrt();
    let inside = peak * (1.0 - 0.5 * peak * peak) * 0.9 * 500.0;
    assert!(cam.unproject(&Vector2::new(inside, 0.0), 0).is_ok());
    let beyond = peak * (1.0 - 0.5 * peak * peak) * 1.05 * 500.0;
    let err = cam.unproject(&Vector2::new(beyond, 0.0), 7).unwrap_err();
    assert!(
        matches!(&err, Error::Degenerate { what } if what.starts_with("pixel 7")),
        "{err}"
    );
}

#[test]
fn every_pixel_beyond_the_fold_of_a_radial_distortion_is_refused() {
    // RADIAL k1 = -0.5, k2 = 0.1: ρ(r) = r - 0.5 r³ + 0.1 r⁵, ρ'(r) = 1 - 1.5 r² + 0.5 r⁴ = 0 at r = 1
    // and r = √2; ρ rises to ρ(1) = 0.6, falls to ρ(√2) = 0.4√2 and rises again without bound.
    let cam = Camera::new(CameraModel::Radial, &[800.0, 320.0, 240.0, -0.5, 0.1]).unwrap();
    assert!((cam.fold_radius - 1.0).abs() < 1e-12, "{}", cam.fold_radius);
    let peak_px = 0.6 * 800.0;
    // Pixels on a ray from the principal point, every distance to 20x the peak: accepted exactly below it.
    for k in 1..=4000 {
        let radius = peak_px * k as f64 / 200.0;
        for angle in [0.0f64, 0.7, 2.0, 4.0] {
            let u = Vector2::new(320.0 + radius * angle.cos(), 240.0 + radius * angle.sin());
            match cam.unproject(&u, k) {
                Ok(n) => {
                    assert!(
                        radius <= peak_px,
                        "{radius} px is beyond the fold ({peak_px} px) yet unprojected to |n| = {}",
                        n.norm()
                    );
                    assert!(n.norm() < 1.0);
                }
                // Newton may give up just inside the fold, where ρ' → 0; never further in than 1 %.
                Err(_) => assert!(radius > 0.99 * peak_px, "{radius} px refused inside the fold"),
            }
        }
    }
    for u in [Vector2::new(1000.0, 1000.0), Vector2::new(5000.0, 5000.0)] {
        assert!(matches!(cam.unproject(&u, 3), Err(Error::Degenerate { .. })), "{u}");
    }
}

#[test]
fn the_fold_radius_of_each_model_is_where_the_radial_map_turns() {
    // Independent check: the first r (scanned finely) where ρ(r) = |D((r, 0))| stops increasing.
    let cases: [(CameraModel, &[f64]); 14] = [
        (CameraModel::SimpleRadial, &[500.0, 0.0, 0.0, -0.5]),
        (CameraModel::Radial, &[800.0, 320.0, 240.0, -0.5, 0.1]),
        (CameraModel::OpenCv, &[800.0, 790.0, 320.0, 240.0, -0.3, 0.02, 0.0, 0.0]),
        (
            CameraModel::FullOpenCv,
            &[
                800.0, 790.0, 320.0, 240.0, -0.4, 0.05, 0.0, 0.0, 0.01, 0.1, -0.01, 0.005,
            ],
        ),
        (
            CameraModel::OpenCvFisheye,
            &[400.0, 395.0, 320.0, 240.0, -0.3, 0.02, 0.0, 0.0],
        ),
        (CameraModel::SimpleRadialFisheye, &[400.0, 320.0, 240.0, -0.3]),
        (CameraModel::RadialFisheye, &[400.0, 320.0, 240.0, -0.1, -0.05]),
        (
            CameraModel::ThinPrismFisheye,
            &[400.0, 395.0, 320.0, 240.0, -0.2, 0.01, 0.0, 0.0, -0.01, 0.001, 0.0, 0.0],
        ),
        (
            CameraModel::RadTanThinPrismFisheye,
            &[
                400.0, 395.0, 320.0, 240.0, -0.2, 0.01, -0.01, 0.001, 1e-4, -1e-5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
            ],
        ),
        // tan(ω/2) = 92.6: COLMAP's series in r turns at r = 0.0054, inside its range r < 0.01.
        (CameraModel::Fov, &[400.0, 395.0, 320.0, 240.0, 3.12]),
        // k > 0: the projection exists for r < 1/(2√k) only.
        (CameraModel::SimpleDivision, &[800.0, 320.0, 240.0, 0.2]),
        // α > 1: ρ turns where q = α / (α − 1) = 3, r = √8.
        (CameraModel::Eucm, &[400.0, 395.0, 320.0, 240.0, 1.5, 1.0]),
        // α < 0: a pole where q = (α − 1) / α = 3, r = √8.
        (CameraModel::Eucm, &[400.0, 395.0, 320.0, 240.0, -0.5, 1.0]),
        // β < 0: the projection exists for r² < −1/β = 2 only.
        (CameraModel::Eucm, &[400.0, 395.0, 320.0, 240.0, 0.5, -0.5]),
    ];
    for (model, params) in cases {
        let cam = Camera::new(model, params).unwrap();
        let rho = |r: f64| cam.distort(&Vector2::new(r, 0.0)).0.x;
        let step = 1e-4;
        let turn = (1..200_000)
            .map(|i| i as f64 * step)
            .find(|&r| rho(r + step).partial_cmp(&rho(r)) != Some(std::cmp::Ordering::Greater))
            .expect("each case folds below r = 20");
        // The scan finds the turn to within one step (the maximum is flat: ρ' changes sign there; past
        // the edge of a domain or a pole ρ is NaN or negative, which is no increase either).
        assert!(
            (cam.fold_radius - turn).abs() <= 2.0 * step,
            "{model:?}: {} vs {turn}",
            cam.fold_radius
        );
    }
    for cam in cameras() {
        // The mild distortions of the other tests fold far outside their images, if at all.
        assert!(cam.fold_radius > 1.0, "{:?}: {}", cam.model(), cam.fold_radius);
    }
}

#[test]
fn extreme_distortion_parameters_give_a_fold_radius_without_failing() {
    // Subnormal, huge and mixed coefficients: the companion matrix must stay finite (a non-finite
    // one could make the eigenvalue iteration run for ever).
    let extremes: [&[f64]; 6] = [
        &[800.0, 0.0, 0.0, 1.0, 1e-320],
        &[800.0, 0.0, 0.0, -1e300, 1e-320],
        &[800.0, 0.0, 0.0, 1e300, -1e300],
        &[800.0, 0.0, 0.0, -1e-300, 1e-300],
        &[800.0, 0.0, 0.0, 0.0, 0.0],
        &[800.0, 0.0, 0.0, f64::MAX, f64::MIN_POSITIVE],
    ];
    for params in extremes {
        let cam = Camera::new(CameraModel::Radial, params).unwrap();
        assert!(cam.fold_radius > 0.0, "{params:?}: {}", cam.fold_radius);
        let _ = cam.unproject(&Vector2::new(900.0, 100.0), 0);
    }
    let cam = Camera::new(CameraModel::Radial, &[800.0, 0.0, 0.0, -1e300, 1e-320]).unwrap();
    // ρ' = 1 - 3e300 r² (+ a negligible r⁴ term) vanishes at r = 1/√(3e300).
    assert!(
        (cam.fold_radius * (3e300f64).sqrt() - 1.0).abs() < 1e-12,
        "{}",
        cam.fold_radius
    );
}

#[test]
fn models_parse_by_colmap_name_and_check_their_parameters() {
    for &m in CameraModel::ALL {
        assert_eq!(CameraModel::parse(m.as_str()).unwrap(), m);
    }
    assert!(matches!(
        CameraModel::parse("KANNALA"),
        Err(Error::InvalidOption { .. })
    ));
    assert!(matches!(
        Camera::new(CameraModel::OpenCv, &[1.0; 4]),
        Err(Error::Shape { .. })
    ));
    assert!(matches!(
        Camera::new(CameraModel::Pinhole, &[0.0, 1.0, 0.0, 0.0]),
        Err(Error::SingularCamera { .. })
    ));
    assert!(matches!(
        Camera::new(CameraModel::Pinhole, &[1.0, f64::NAN, 0.0, 0.0]),
        Err(Error::NonFinite { index: 1, .. })
    ));
}

#[test]
fn the_normalized_covariance_is_the_first_order_propagation() {
    // With the pinhole model it is Σ / f²; with distortion, J⁻¹ Σ J⁻ᵀ checked by Monte Carlo would be
    // the next step; here the exact linear case.
    let cam = Camera::new(CameraModel::Pinhole, &[800.0, 400.0, 320.0, 240.0]).unwrap();
    let c = cam
        .normalized_covariance(&Vector2::new(0.1, 0.2), &Matrix2::identity())
        .unwrap();
    assert!((c - Matrix2::new(1.0 / 640000.0, 0.0, 0.0, 1.0 / 160000.0)).norm() < 1e-18);
}
