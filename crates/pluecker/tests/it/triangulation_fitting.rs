//! The covariances predicted by `triangulation::fitting` against the empirical covariance of the
//! residual over many seeded noisy draws (Josephson & Kahl 2008, section 3.1).
//!
//! Test statistic: with `Σ` the predicted covariance and `W` its whitening (`W Σ Wᵀ = I`), the sample
//! covariance `C` of `W r` over `M` independent draws of a Gaussian vector with covariance `I` has
//! entries with standard errors `sqrt(2/M)` (diagonal) and `sqrt(1/M)` (off-diagonal), and the sample
//! mean has standard error `sqrt(1/M)`. We allow 5 standard errors plus the size of the terms the
//! first-order propagation neglects, for a feature of size `ℓ` (segment length, least semi-axis) fitted
//! to `N` points: the estimators' bias is `O(σ²/ℓ)` against a standard deviation `O(σ/√N)`, i.e.
//! `√N σ/ℓ` standard deviations on the mean; the relative error of a first-order standard deviation is
//! `O(σ/ℓ)`, i.e. `2σ/ℓ` on a whitened variance.

use nalgebra::{SMatrix, SVector, Vector2};
use pluecker::rng::Rng;
use pluecker::triangulation::fitting::{fit_conic, fit_line, random_image_primitives, residual_samples};
use pluecker::triangulation::line::testing::LineFrame;
use pluecker::triangulation::quadric::testing::ConicFrame;
use pluecker::triangulation::testing::whitening;

/// Checks that the sample mean and covariance of `samples` whitened by `predicted` are those of a
/// standard normal vector (see the module docs), printing the seed on failure.
/// `sigma_over_size` is `σ/ℓ`, `n` the number of fitted points and `extra_bias` any further
/// second-order bias (in standard deviations) the caller derives.
fn assert_standard_normal<const D: usize>(
    samples: &[SVector<f64, D>],
    predicted: &SMatrix<f64, D, D>,
    sigma_over_size: f64,
    n: usize,
    extra_bias: f64,
    label: &str,
) {
    let mean_allowance = (n as f64).sqrt() * sigma_over_size + extra_bias;
    let cov_allowance = 2.0 * sigma_over_size;
    let m = samples.len() as f64;
    let w = whitening(predicted, "predicted", 0).unwrap();
    let z: Vec<SVector<f64, D>> = samples.iter().map(|r| w * r).collect();
    let mean = z.iter().sum::<SVector<f64, D>>() / m;
    let cov = z.iter().fold(SMatrix::<f64, D, D>::zeros(), |acc, v| {
        acc + (v - mean) * (v - mean).transpose()
    }) / (m - 1.0);
    for i in 0..D {
        assert!(
            mean[i].abs() < 5.0 / m.sqrt() + mean_allowance,
            "{label}: whitened mean[{i}] = {}",
            mean[i]
        );
        for j in 0..D {
            let (expected, se) = if i == j {
                (1.0, (2.0 / m).sqrt())
            } else {
                (0.0, (1.0 / m).sqrt())
            };
            assert!(
                (cov[(i, j)] - expected).abs() < 5.0 * se + cov_allowance,
                "{label}: whitened covariance[{i},{j}] = {} (expected {expected})\n{cov}",
                cov[(i, j)]
            );
        }
    }
}

/// The line residual's frame pivots at the foot point, `a` px along the line from the points' centroid.
/// A fit turned by `δθ` moves the offset there by `a δθ²/2` at second order, with `E[δθ²] = σ²/S`; in
/// units of the offset's conditional standard deviation `σ/√N` that is `a σ √N / (2S)`, doubled here
/// for the other second-order terms.
fn line_lever_bias(points: &[Vector2<f64>], sigma: f64) -> f64 {
    let fit = fit_line(points, 1.0).unwrap();
    let n = fit.line.xy();
    let along = Vector2::new(-n.y, n.x);
    let centroid = points.iter().sum::<Vector2<f64>>() / points.len() as f64;
    let s: f64 = points.iter().map(|p| along.dot(&(p - centroid)).powi(2)).sum();
    let a = along.dot(&centroid).abs();
    a * sigma * (points.len() as f64).sqrt() / s
}

#[test]
fn line_fit_covariance_matches_the_empirical_one() {
    let sigma = 1.0;
    let draws = 20_000;
    for seed in [101u64, 102, 103] {
        let mut rng = Rng::new(seed);
        let (points, _) = random_image_primitives(1000.0, &mut rng);
        let true_line = points[0].push(1.0).cross(&points[20].push(1.0));
        let predicted = fit_line(&points, sigma).unwrap().covariance;
        let samples: Vec<Vector2<f64>> = (0..draws)
            .map(|_| {
                let noisy: Vec<_> = points
                    .iter()
                    .map(|p| p + Vector2::new(rng.normal(), rng.normal()) * sigma)
                    .collect();
                let fit = fit_line(&noisy, sigma).unwrap();
                LineFrame::of_line(&fit.line).unwrap().residual(&true_line)
            })
            .collect();
        let length = (points[20] - points[0]).norm();
        assert_standard_normal(
            &samples,
            &predicted,
            sigma / length,
            21,
            line_lever_bias(&points, sigma),
            &format!("line, seed {seed}"),
        );
    }
}

#[test]
fn segment_endpoint_covariance_matches_the_empirical_one() {
    // Two points only: the setting of the real-data experiments (segments with σ = 1 px endpoints).
    let (a, b) = (Vector2::new(120.0, 80.0), Vector2::new(430.0, 260.0));
    let sigma = 1.0;
    let true_line = a.push(1.0).cross(&b.push(1.0));
    let predicted = fit_line(&[a, b], sigma).unwrap().covariance;
    let mut rng = Rng::new(104);
    let samples: Vec<Vector2<f64>> = (0..20_000)
        .map(|_| {
            let na = a + Vector2::new(rng.normal(), rng.normal()) * sigma;
            let nb = b + Vector2::new(rng.normal(), rng.normal()) * sigma;
            let fit = pluecker::triangulation::fitting::line_from_segment(&na, &nb, sigma).unwrap();
            LineFrame::of_line(&fit.line).unwrap().residual(&true_line)
        })
        .collect();
    assert_standard_normal(
        &samples,
        &predicted,
        sigma / (b - a).norm(),
        2,
        line_lever_bias(&[a, b], sigma),
        "segment, seed 104",
    );
}

#[test]
fn conic_fit_covariance_matches_the_empirical_one() {
    let sigma = 1.0;
    let draws = 10_000;
    for seed in [201u64, 202] {
        let mut rng = Rng::new(seed);
        let (_, ellipse) = random_image_primitives(1000.0, &mut rng);
        let points = ellipse.sample(63, 0.0);
        let predicted = fit_conic(&points, sigma).unwrap().covariance;
        let samples: Vec<SVector<f64, 5>> = (0..draws)
            .map(|_| {
                let noisy: Vec<_> = points
                    .iter()
                    .map(|p| p + Vector2::new(rng.normal(), rng.normal()) * sigma)
                    .collect();
                let fit = fit_conic(&noisy, sigma).unwrap();
                ConicFrame::of_conic(&fit.conic).unwrap().residual(&ellipse.dual())
            })
            .collect();
        let least = ellipse.semi_axes.min();
        assert_standard_normal(
            &samples,
            &predicted,
            sigma / least,
            63,
            0.0,
            &format!("conic, seed {seed}"),
        );
    }
}

#[test]
fn figure_samples_are_standard_normal_after_whitening() {
    // Figures 1-2 pool random images; whitened by each fit's own covariance the pooled samples are
    // standard normal to first order. The allowances use the smallest sizes the generator draws
    // (segments of 200 px, semi-axes of 18 px).
    let s = residual_samples(4000, 1000.0, 1.0, 7).unwrap();
    assert_eq!(s.line.len(), 4000);
    assert_eq!(s.conic_whitened.len(), 4000);
    assert_standard_normal(
        &s.line_whitened,
        &SMatrix::<f64, 2, 2>::identity(),
        1.0 / 200.0,
        21,
        6.0 * 1414.0 / (21f64.sqrt() * 200.0 * 200.0) * 2.0,
        "figure 1",
    );
    assert_standard_normal(
        &s.conic_whitened,
        &SMatrix::<f64, 5, 5>::identity(),
        1.0 / 18.0,
        63,
        0.0,
        "figure 2",
    );
}

/// Issue 10: pixels near the underflow threshold used to make the segment draw loop forever
/// (`‖a − b‖` underflows to 0); too many draws are refused before anything is allocated.
#[test]
fn residual_samples_end_on_tiny_images_and_refuse_huge_requests() {
    match residual_samples(2, 1e-300, 1.0, 3) {
        Ok(s) => assert_eq!(s.line.len(), 2),
        Err(e) => assert!(matches!(e, pluecker::Error::Degenerate { .. }), "{e}"),
    }
    let (line, _) = random_image_primitives(1e-300, &mut Rng::new(4));
    assert!(((line[0] - line[20]) / 1e-300).norm() >= 0.2);
    let huge = residual_samples(usize::MAX, 1000.0, 1.0, 0).unwrap_err();
    assert!(
        matches!(huge, pluecker::Error::InvalidOption { ref name, .. } if name == "draws"),
        "{huge}"
    );
}
