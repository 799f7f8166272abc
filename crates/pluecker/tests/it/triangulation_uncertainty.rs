//! The covariances of triangulated points, lines and quadrics (`triangulation::uncertainty`) against
//! Monte Carlo: for each primitive, N seeded noisy draws of the observations from their covariances,
//! re-triangulated, each error expressed in the chart of the covariance at the true primitive.
//!
//! **The statistical test** ([`check_monte_carlo`]). With the predicted covariance `Σ` (k x k) computed
//! from the noise-free observations (so at the truth) and `Σ = C Cᵀ`, the whitened errors
//! `yₙ = C⁻¹ eₙ` are i.i.d. `N(0, I_k)` under the first-order model. Then, each at 4 standard
//! deviations of its sampling distribution under that model:
//! - mean squared Mahalanobis distance `d̄² = (1/N) Σ ‖yₙ‖²`: mean `k`, std `√(2k/N)`;
//! - whitened empirical covariance about the truth `W = (1/N) Σ yₙyₙᵀ` (so a bias counts as error):
//!   each diagonal entry mean 1, std `√(2/N)`; each off-diagonal entry mean 0, std `1/√N`;
//! - whitened mean `ȳ` (the bias): each entry mean 0, std `1/√N`.
//!
//! A covariance wrong by a factor `1 + ε` in any chart direction fails once `ε` exceeds about
//! `4√(2/N)` (0.13 at N = 1000, 0.09 at N = 2000). The noise levels are chosen so that the first-order
//! model holds: the `O(σ²)` bias of each case is stated at the case and is well below `1/√N` in
//! whitened units. With fixed seeds the tests are deterministic; a 4-sigma bound on each of the at most
//! 55 statistics of a case would fail by chance with probability below 1 % for a correct covariance.

use nalgebra::{DMatrix, DVector, Matrix2, Matrix3, Matrix3x4, SMatrix, Vector2};
use pluecker::geometry::plucker::LineChart;
use pluecker::geometry::testing::centre_shape;
use pluecker::rng::Rng;
use pluecker::synthetic::triangulation_scene;
use pluecker::triangulation::fitting::fit_conic;
use pluecker::triangulation::line::{lines_from_segments, triangulate_line, LineObservations};
use pluecker::triangulation::point::triangulate_point;
use pluecker::triangulation::point::{triangulate_points, DensePointTracks, LinearPoints};
use pluecker::triangulation::quadric::{triangulate_quadric, Matrix5, QuadricObservations};
use pluecker::triangulation::scenes::{line_scene, quadric_scene};
use pluecker::triangulation::{Method, Status, TriangulationOptions};

fn opts(method: Method) -> TriangulationOptions {
    let mut options = TriangulationOptions::default();
    options.method = method;
    options
}

/// The test of the module docs on `errors` (one chart error per draw) against `predicted`; panics
/// with the statistic that fails.
fn check_monte_carlo(name: &str, errors: &[DVector<f64>], predicted: &DMatrix<f64>) {
    let k = predicted.nrows();
    let n = errors.len() as f64;
    let c = predicted
        .clone()
        .cholesky()
        .expect("a positive definite prediction")
        .l();
    let whitened: Vec<DVector<f64>> = errors
        .iter()
        .map(|e| c.solve_lower_triangular(e).expect("C is invertible"))
        .collect();
    let d2 = whitened.iter().map(|y| y.norm_squared()).sum::<f64>() / n;
    let bound = 4.0 * (2.0 * k as f64 / n).sqrt();
    eprintln!("{name}: N = {n}, mean d² = {d2:.3} (k = {k} ± {bound:.3})");
    assert!(
        (d2 - k as f64).abs() <= bound,
        "{name}: mean d² = {d2:.3}, expected {k} ± {bound:.3}"
    );
    let mut w = DMatrix::<f64>::zeros(k, k);
    let mut mean = DVector::<f64>::zeros(k);
    for y in &whitened {
        w += y * y.transpose() / n;
        mean += y / n;
    }
    for i in 0..k {
        let diagonal = 4.0 * (2.0 / n).sqrt();
        assert!(
            (w[(i, i)] - 1.0).abs() <= diagonal,
            "{name}: W[{i},{i}] = {:.3} (±{diagonal:.3})\n{w:.3}",
            w[(i, i)]
        );
        assert!(
            mean[i].abs() <= 4.0 / n.sqrt(),
            "{name}: whitened bias {i} = {:.3}",
            mean[i]
        );
        for j in 0..i {
            assert!(
                w[(i, j)].abs() <= 4.0 / n.sqrt(),
                "{name}: W[{i},{j}] = {:.3}\n{w:.3}",
                w[(i, j)]
            );
        }
    }
}

fn dynamic<const R: usize, const C: usize>(m: &SMatrix<f64, R, C>) -> DMatrix<f64> {
    DMatrix::from_fn(R, C, |i, j| m[(i, j)])
}

/// A 2x2 covariance with principal standard deviations `s1`, `s2` (px) along the angle `angle`.
fn anisotropic(s1: f64, s2: f64, angle: f64) -> Matrix2<f64> {
    let r = nalgebra::Rotation2::new(angle).into_inner();
    r * Matrix2::new(s1 * s1, 0.0, 0.0, s2 * s2) * r.transpose()
}

/// Per-view anisotropic pixel covariances (standard deviations 0.2-0.6 px) of a point track.
fn point_covariances(views: usize, rng: &mut Rng) -> Vec<Matrix2<f64>> {
    (0..views)
        .map(|_| {
            anisotropic(
                rng.uniform_in(0.3, 0.6),
                rng.uniform_in(0.2, 0.3),
                rng.uniform_in(0.0, 3.2),
            )
        })
        .collect()
}

/// `draws` triangulations of the scene's point from observations drawn from `covariances`; returns
/// the prediction at the truth and the errors (world units).
fn point_draws(
    scene: &pluecker::synthetic::TriangulationScene,
    covariances: &[Matrix2<f64>],
    draws: usize,
    rng: &mut Rng,
) -> (Matrix3<f64>, Vec<DVector<f64>>) {
    let o = opts(Method::Optimal);
    let exact = triangulate_point(&scene.cameras, &scene.observations, Some(covariances), &o).unwrap();
    assert!((exact.point - scene.point).norm() < 1e-9);
    let factors: Vec<Matrix2<f64>> = covariances.iter().map(|c| c.cholesky().unwrap().l()).collect();
    let errors = (0..draws)
        .map(|_| {
            let obs: Vec<Vector2<f64>> = scene
                .observations
                .iter()
                .zip(&factors)
                .map(|(x, l)| x + l * Vector2::new(rng.normal(), rng.normal()))
                .collect();
            let r = triangulate_point(&scene.cameras, &obs, Some(covariances), &o).unwrap();
            assert_eq!(r.report.status, Status::Success);
            DVector::from_column_slice((r.point - scene.point).as_slice())
        })
        .collect();
    (exact.covariance.expect("a finite point has a covariance"), errors)
}

/// Points, 4 views over 30° and 2 views over 1.5° of parallax, per-view anisotropic covariances
/// (0.2-0.6 px), N = 2000 each. At 1.5° the depth error is about 3 % of the depth (0.6 px at 800 px
/// focal length over a 0.026 rad parallax), so the `O(σ²)` bias along the ray, about (3 %)² of the
/// depth, is 0.03 depth standard deviations: well below the bias bound 4/√N = 0.09. The low-parallax
/// covariance is also checked to be large: its largest standard deviation against that of the same
/// two cameras at 30° (same distances and pixels, see `triangulation_scene`) is within a factor 2 of
/// `tan(15°)/tan(0.75°) ≈ 20.5`, the ratio of the depth uncertainties of a symmetric pair.
#[test]
fn point_covariance_matches_monte_carlo_at_wide_and_low_parallax() {
    let mut rng = Rng::new(401);
    let wide = triangulation_scene(4, 30f64.to_radians(), 402);
    let covs = point_covariances(4, &mut rng);
    let (predicted, errors) = point_draws(&wide, &covs, 2000, &mut rng);
    check_monte_carlo("point, 4 views, 30°", &errors, &dynamic(&predicted));

    let low = triangulation_scene(2, 1.5f64.to_radians(), 403);
    let pair = triangulation_scene(2, 30f64.to_radians(), 403);
    let covs = point_covariances(2, &mut rng);
    let (predicted_low, errors) = point_draws(&low, &covs, 2000, &mut rng);
    check_monte_carlo("point, 2 views, 1.5°", &errors, &dynamic(&predicted_low));
    let o = opts(Method::Optimal);
    let predicted_pair = triangulate_point(&pair.cameras, &pair.observations, Some(&covs), &o)
        .unwrap()
        .covariance
        .unwrap();
    let largest = |c: &Matrix3<f64>| c.symmetric_eigenvalues().max().sqrt();
    let ratio = largest(&predicted_low) / largest(&predicted_pair);
    let expected = 15f64.to_radians().tan() / 0.75f64.to_radians().tan();
    assert!(
        ratio > expected / 2.0 && ratio < expected * 2.0,
        "std ratio {ratio:.1}, expected about {expected:.1}"
    );
}

/// Every method gives a covariance at a finite point; the batch gives the single call's (every method
/// and the linear fast path); parallel rays (a point at infinity) give none.
#[test]
fn point_covariance_in_every_method_the_batch_and_at_infinity() {
    let scene = triangulation_scene(3, 20f64.to_radians(), 404);
    let mut rng = Rng::new(405);
    let obs = scene.noisy(1.0, &mut rng);
    let covs = point_covariances(3, &mut rng);
    let flat_obs: Vec<f64> = obs.iter().flat_map(|x| [x.x, x.y]).collect();
    let flat_cov: Vec<f64> = covs
        .iter()
        .flat_map(|c| [c[(0, 0)], c[(0, 1)], c[(1, 0)], c[(1, 1)]])
        .collect();
    let tracks = DensePointTracks {
        observations: &flat_obs,
        visible: None,
        covariances: Some(&flat_cov),
    };
    for method in Method::ALL.iter().copied() {
        let single = triangulate_point(&scene.cameras, &obs, Some(&covs), &opts(method)).unwrap();
        let cov = single.covariance.unwrap();
        assert!((cov - cov.transpose()).norm() == 0.0 && cov.symmetric_eigenvalues().min() > 0.0);
        let batch = triangulate_points(&scene.cameras, tracks, &opts(method), None).unwrap();
        let from_batch = batch[0].as_ref().unwrap().covariance.unwrap();
        assert!((from_batch - cov).norm() <= 1e-9 * cov.norm(), "{method:?}");
        if method == Method::Linear {
            let fast = LinearPoints::from_tracks(&scene.cameras, &tracks).unwrap();
            let fast_cov = Matrix3::from_row_slice(&fast.covariances[..9]);
            assert!((fast_cov - cov).norm() <= 1e-9 * cov.norm());
        }
    }
    // Two cameras translated sideways, same orientation, same pixel: the rays are parallel.
    let k = Matrix3::new(800.0, 0.0, 320.0, 0.0, 800.0, 240.0, 0.0, 0.0, 1.0);
    let camera = |tx: f64| k * Matrix3x4::new(1.0, 0.0, 0.0, tx, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 5.0);
    let cams = [camera(0.0), camera(1.0)];
    let same = [Vector2::new(300.0, 200.0); 2];
    for method in Method::ALL.iter().copied() {
        let r = triangulate_point(&cams, &same, None, &opts(method)).unwrap();
        // `local` stops on its iteration cap far out along the rays (parallax ~1e-6 rad), where
        // `JᵀJ` is numerically singular too.
        if method != Method::Local {
            assert_eq!(r.report.status, Status::AtInfinity, "{method:?}");
        }
        assert!(
            r.covariance.is_none(),
            "{method:?}: {:?} at {:?}",
            r.covariance,
            r.point
        );
    }
}

/// Lines from image segments whose endpoints have i.i.d. noise of `sigma` px: the residual
/// covariances of `lines_from_segments` are anisotropic (offset and angle, correlated). N = 1000 per
/// case, method `local`; with 0.5 px on segments of 60+ px the angular errors are below 1e-2 rad, so
/// the chart is linear to about 1 %.
#[test]
fn line_covariance_matches_monte_carlo() {
    let mut rng = Rng::new(411);
    let sigma = 0.5;
    for (views, spread, seed) in [(3, 0.8, 412), (2, 0.5, 413)] {
        let scene = line_scene(views, spread, seed);
        let o = opts(Method::Local);
        let (lines, covs) = lines_from_segments(&scene.segments, sigma).unwrap();
        let exact = triangulate_line(&scene.cameras, LineObservations::Lines(&lines, Some(&covs)), &o).unwrap();
        let truth = LineChart::of_line(&scene.plucker()).unwrap();
        assert!(truth.coordinates(exact.plucker.coordinates()).unwrap().norm() < 1e-9);
        let predicted = exact.covariance.expect("a covariance");
        let errors: Vec<DVector<f64>> = (0..1000)
            .map(|_| {
                let noisy = scene.noisy_segments(sigma, &mut rng);
                let (lines, covs) = lines_from_segments(&noisy, sigma).unwrap();
                let r = triangulate_line(&scene.cameras, LineObservations::Lines(&lines, Some(&covs)), &o).unwrap();
                assert_eq!(r.report.status, Status::Success);
                let e = exact.chart.coordinates(r.plucker.coordinates()).unwrap();
                DVector::from_column_slice(e.as_slice())
            })
            .collect();
        check_monte_carlo(&format!("line, {views} views"), &errors, &dynamic(&predicted));
        // The 6x6 forms have rank 4 and the chart's units: the point's covariance is at least the
        // translation block's size.
        let pd = exact.chart.point_direction_covariance(&predicted);
        assert!(
            pd.symmetric_eigenvalues()
                .iter()
                .filter(|&&v| v > 1e-9 * pd.norm())
                .count()
                == 4
        );
        let pl = exact.chart.plucker_covariance(&predicted);
        assert!(
            pl.symmetric_eigenvalues()
                .iter()
                .filter(|&&v| v > 1e-9 * pl.norm())
                .count()
                == 4
        );
    }
}

/// Ellipsoids (semi-axes 0.15-0.5 at 5 units) from 4 views: per view, 40 outline points with i.i.d.
/// noise of that view's `sigma` (0.2-0.5 px), the conic and its 5x5 covariance from `fit_conic`
/// (anisotropic: shape entries px², centre entries px). N = 600, method `local`, errors in the
/// `CentreShape` chart. With these σ the relative errors of the shape matrix are a few percent, so
/// its `O(σ²)` bias is below 0.05 of its standard deviation.
#[test]
fn quadric_covariance_matches_monte_carlo() {
    let scene = quadric_scene(4, 0.8, 421);
    let mut rng = Rng::new(422);
    let sigmas = [0.2, 0.3, 0.4, 0.5];
    let o = opts(Method::Local);
    let outline_points: Vec<Vec<Vector2<f64>>> = scene.outlines.iter().map(|e| e.sample(40, 0.3)).collect();
    let fit = |points: &[Vec<Vector2<f64>>]| -> (Vec<Matrix3<f64>>, Vec<Matrix5>) {
        points
            .iter()
            .zip(sigmas)
            .map(|(p, s)| {
                let f = fit_conic(p, s).unwrap();
                (f.conic, f.covariance)
            })
            .unzip()
    };
    let (conics, covs) = fit(&outline_points);
    let exact = triangulate_quadric(&scene.cameras, QuadricObservations::Conics(&conics, Some(&covs)), &o).unwrap();
    let truth = centre_shape(&scene.ellipsoid.dual()).unwrap();
    assert!((centre_shape(&exact.dual).unwrap() - truth).norm() < 1e-8);
    let predicted = exact.covariance.expect("a covariance");
    let errors: Vec<DVector<f64>> = (0..600)
        .map(|_| {
            let noisy: Vec<Vec<Vector2<f64>>> = outline_points
                .iter()
                .zip(sigmas)
                .map(|(p, s)| {
                    p.iter()
                        .map(|x| x + Vector2::new(rng.normal(), rng.normal()) * s)
                        .collect()
                })
                .collect();
            let (conics, covs) = fit(&noisy);
            let r = triangulate_quadric(&scene.cameras, QuadricObservations::Conics(&conics, Some(&covs)), &o).unwrap();
            assert_eq!(r.report.status, Status::Success);
            DVector::from_column_slice((centre_shape(&r.dual).unwrap() - truth).as_slice())
        })
        .collect();
    check_monte_carlo("quadric, 4 views", &errors, &dynamic(&predicted));
}

/// Two views of a line tilted by `ε` out of an epipolar plane (the plane `y = 0` through both centres):
/// the back-projected planes meet at a dihedral angle of order `ε`, so the poorly determined direction of
/// the line has a standard deviation `∝ 1/ε`: from `ε = 0.02` to `0.002` the largest one grows by 10
/// (asserted within a factor 2). At `ε = 1e-7` the information matrix has a condition number of order
/// `1/ε² = 1e14 > MAX_CONDITION`: no covariance, though the line is still triangulated.
#[test]
fn line_covariance_grows_near_an_epipolar_plane_and_is_none_in_it() {
    let k = Matrix3::new(800.0, 0.0, 320.0, 0.0, 800.0, 240.0, 0.0, 0.0, 1.0);
    let camera = |cx: f64| k * Matrix3x4::new(1.0, 0.0, 0.0, -cx, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 5.0);
    let cams = [camera(-1.0), camera(1.0)];
    let largest_std = |eps: f64| {
        let d = nalgebra::Vector3::new(1.0, eps, 1.0).normalize();
        let (a, b) = (d * 0.5, -d * 0.5);
        let segments: Vec<[Vector2<f64>; 2]> = cams
            .iter()
            .map(|p| {
                let project = |x: nalgebra::Vector3<f64>| {
                    let h = p * x.push(1.0);
                    Vector2::new(h.x / h.z, h.y / h.z)
                };
                [project(a), project(b)]
            })
            .collect();
        let (lines, covs) = lines_from_segments(&segments, 1.0).unwrap();
        let r = triangulate_line(
            &cams,
            LineObservations::Lines(&lines, Some(&covs)),
            &opts(Method::Local),
        )
        .unwrap();
        r.covariance.map(|c| c.symmetric_eigenvalues().max().sqrt())
    };
    let ratio = largest_std(0.002).unwrap() / largest_std(0.02).unwrap();
    eprintln!("near-epipolar std ratio {ratio:.3}");
    assert!(ratio > 5.0 && ratio < 20.0, "std ratio {ratio:.2}, expected about 10");
    assert!(largest_std(1e-7).is_none());
}
