//! Ask for a proof that a pose is the global minimum of the reprojection error, and read it.
//!
//! `cargo run --release -p pluecker --example certified_pose` prints the pose's cost Σ r² (px²), the
//! certificate's proved lower bound on the cost of every pose that keeps the points in front of the
//! camera, the relative gap between the two (below the requested 1e-3), `certified: true` and the
//! status `success`. A pose whose gap stays above `max_relative_gap` gets the status `gap_not_closed`.

// Options are set field by field on their defaults, the form that also works once they are
// `#[non_exhaustive]` (a struct literal with `..Default::default()` does not).
#![allow(clippy::field_reassign_with_default)]

use pluecker::nalgebra::{Rotation3, Vector2, Vector3};
use pluecker::{estimate_pose, Camera, CertifyOptions, Correspondences, PoseOptions};

fn main() -> pluecker::Result<()> {
    let camera = Camera::pinhole(800.0, 800.0, 320.0, 240.0, 0.0)?;
    let rotation = Rotation3::from_scaled_axis(Vector3::new(0.3, 0.1, -0.2)).into_inner();
    let translation = Vector3::new(-0.2, 0.1, 5.0);

    // Twelve points with a deterministic ±0.5 px of noise (use your own correspondences instead).
    let mut data = Correspondences::default();
    for k in 0..12 {
        let a = k as f64;
        let x = Vector3::new((0.9 * a).sin(), (1.3 * a).cos(), 0.5 * (0.7 * a).sin());
        let noise = 0.5 * Vector2::new((1.7 * a).sin(), (2.3 * a).cos());
        data.points2d
            .push(camera.project(&(rotation * x + translation)) + noise);
        data.points3d.push(x);
    }

    // The certificate is on request: `certify: Some(..)`, here with the default gap and node cap.
    let mut certify = CertifyOptions::default();
    certify.max_relative_gap = 1e-3;
    let mut options = PoseOptions::default();
    options.certify = Some(certify);
    let result = estimate_pose(&camera, &data, &options)?;

    println!("cost: {:.4} px²", result.report.cost);
    match &result.report.certificate {
        Some(c) => {
            println!(
                "lower bound: {:.4} px² ({}, {} nodes)",
                c.lower_bound,
                c.kind.as_str(),
                c.nodes
            );
            println!("relative gap: {:.2e}", c.relative_gap);
            println!("certified: {}", c.certified);
        }
        // No bound could be computed; the details say why.
        None => println!("no certificate: {:?}", result.details.uncertified_reason),
    }
    println!("status: {}", result.report.status.as_str());
    Ok(())
}
