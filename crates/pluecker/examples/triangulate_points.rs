//! Triangulate 3-D points from their pixels in two or more views with known cameras, and read the
//! certificate that each is the global minimum of the reprojection error.
//!
//! `cargo run --release -p pluecker --example triangulate_points` prints, for one point seen in three
//! views, the estimate (close to (0.3, -0.2, 5.0)), the status `success`, the cost Σ r² (px²) and its
//! certificate (`convexity_test`, relative gap 0, certified); then a batch of 1000 points solved in
//! parallel, all certified.

// Options are set field by field on their defaults, the form that also works once they are
// `#[non_exhaustive]` (a struct literal with `..Default::default()` does not).
#![allow(clippy::field_reassign_with_default)]

use pluecker::nalgebra::{Matrix3x4, Rotation3, Vector2, Vector3};
use pluecker::triangulation::point::triangulate_point;
use pluecker::triangulation::point::{triangulate_points, DensePointTracks};
use pluecker::triangulation::{Method, TriangulationOptions};
use pluecker::{Camera, Pose};

fn main() -> pluecker::Result<()> {
    // The views' projections P = K [R | t] (3x4, world to pixels); here three poses on an arc.
    let camera = Camera::pinhole(800.0, 800.0, 320.0, 240.0, 0.0)?;
    let projections: Vec<Matrix3x4<f64>> = (0..3)
        .map(|j| {
            let rotation = Rotation3::from_scaled_axis(Vector3::new(0.0, -0.1 * j as f64, 0.0)).into_inner();
            camera.projection(&Pose::new(rotation, Vector3::new(-0.5 * j as f64, 0.0, 0.0)))
        })
        .collect();
    // A pixel of `x` in view `p`, with a deterministic ±0.5 px of noise.
    let pixel = |p: &Matrix3x4<f64>, x: &Vector3<f64>, k: usize| {
        let h = p * x.push(1.0);
        Vector2::new(h.x / h.z, h.y / h.z) + 0.5 * Vector2::new((1.7 * k as f64).sin(), (2.3 * k as f64).cos())
    };

    // One point: one pixel per view, no covariances (1 px isotropic noise), method `optimal`.
    let x = Vector3::new(0.3, -0.2, 5.0);
    let observations: Vec<Vector2<f64>> = projections.iter().enumerate().map(|(j, p)| pixel(p, &x, j)).collect();
    let mut options = TriangulationOptions::default();
    options.method = Method::Optimal;
    let one = triangulate_point(&projections, &observations, None, &options)?;
    println!("X = {:.4?}", one.point.as_slice());
    println!(
        "status: {}, cost: {:.4} px²",
        one.report.status.as_str(),
        one.report.cost
    );
    if let Some(c) = &one.report.certificate {
        let kind = c.kind.as_str();
        println!(
            "certificate: {kind}, relative gap {:.1e}, certified {}",
            c.relative_gap, c.certified
        );
    }

    // Many points seen by the same views: row-major pixels, track by track, view by view.
    let n = 1000;
    let mut pixels = Vec::with_capacity(n * projections.len() * 2);
    for t in 0..n {
        let a = t as f64;
        let x = Vector3::new((0.9 * a).sin(), (1.3 * a).cos(), 5.0 + 0.5 * (0.7 * a).sin());
        for (j, p) in projections.iter().enumerate() {
            pixels.extend_from_slice(pixel(p, &x, 3 * t + j).as_slice());
        }
    }
    let tracks = DensePointTracks {
        observations: &pixels,
        visible: None,
        covariances: None,
    };
    let results = triangulate_points(&projections, tracks, &options, None)?;
    let certified = results
        .iter()
        .filter(|r| matches!(r, Ok(p) if p.report.certified()))
        .count();
    println!("batch: {certified} of {n} points certified");
    Ok(())
}
