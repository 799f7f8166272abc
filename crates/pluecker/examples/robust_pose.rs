//! Estimate a pose when some correspondences are wrong: LO-RANSAC over the minimal solvers, then the
//! reprojection refinement on the inliers.
//!
//! `cargo run --release -p pluecker --example robust_pose` prints the pose found from 30 points of
//! which 6 are mismatched (moved by 33-68 px), the status `success`, the cost Σ r² (px²) of the 24
//! inliers, the indices of the rejected points (exactly 3, 8, 13, 18, 23 and 28) and how many samples
//! RANSAC drew.

// Options are set field by field on their defaults, the form that also works once they are
// `#[non_exhaustive]` (a struct literal with `..Default::default()` does not).
#![allow(clippy::field_reassign_with_default)]

use pluecker::nalgebra::{Rotation3, Vector2, Vector3};
use pluecker::{estimate_pose, Camera, Correspondences, PoseOptions, RansacOptions};

fn main() -> pluecker::Result<()> {
    let camera = Camera::pinhole(800.0, 800.0, 320.0, 240.0, 0.0)?;
    let rotation = Rotation3::from_scaled_axis(Vector3::new(-0.1, 0.25, 0.1)).into_inner();
    let translation = Vector3::new(0.3, 0.0, 7.0);

    let mut data = Correspondences::default();
    for k in 0..30 {
        let a = k as f64;
        let x = Vector3::new((0.9 * a).sin(), (1.3 * a).cos(), 0.5 * (0.7 * a).sin());
        let mut pixel = camera.project(&(rotation * x + translation));
        pixel += 0.5 * Vector2::new((1.7 * a).sin(), (2.3 * a).cos()); // ±0.5 px of noise
        if k % 5 == 3 {
            pixel += Vector2::new(40.0 + a, -30.0 - a); // a mismatch
        }
        data.points2d.push(pixel);
        data.points3d.push(x);
    }

    // `ransac: Some(..)` makes the estimate robust. The threshold is a reprojection distance in
    // pixels; the seed makes the run reproducible.
    let mut ransac = RansacOptions::default();
    ransac.point_threshold = 3.0;
    ransac.seed = 7;
    let mut options = PoseOptions::default();
    options.ransac = Some(ransac);
    let result = estimate_pose(&camera, &data, &options)?;

    let rejected: Vec<usize> = (0..30).filter(|&k| !result.inliers_points[k]).collect();
    println!("R = {:.4}", result.pose.rotation);
    println!("t = {:.4?}", result.pose.translation.as_slice());
    println!(
        "status: {}, cost of the inliers: {:.3} px²",
        result.report.status.as_str(),
        result.report.cost
    );
    println!("rejected points: {rejected:?}");
    if let Some(report) = &result.details.ransac {
        println!("samples drawn: {}", report.iterations);
    }
    Ok(())
}
