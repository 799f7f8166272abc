//! Estimate a camera's pose from 2-D/3-D correspondences of points and line segments.
//!
//! `cargo run --release -p pluecker --example estimate_pose` prints the rotation R and translation t
//! (`x_cam = R X_world + t`) it finds, close to the pose the data were made with
//! (t ≈ (0.1, -0.2, 6.0)), the status `success` and the cost Σ r² in px²: a few px² for the ±0.5 px
//! of noise added to the pixels.

use pluecker::nalgebra::{Rotation3, Vector2, Vector3};
use pluecker::{estimate_pose, Camera, Correspondences, PoseOptions};

fn main() -> pluecker::Result<()> {
    // The intrinsics: fx, fy, cx, cy, skew (pixels).
    let camera = Camera::pinhole(800.0, 800.0, 320.0, 240.0, 0.0)?;

    // Data made with a known pose, plus a deterministic ±0.5 px of noise. With real data, fill the
    // correspondences from your detections and your 3-D model instead.
    let rotation = Rotation3::from_scaled_axis(Vector3::new(0.1, -0.2, 0.05)).into_inner();
    let translation = Vector3::new(0.1, -0.2, 6.0);
    let image = |x: &Vector3<f64>, k: usize| {
        let noise = 0.5 * Vector2::new((1.7 * k as f64).sin(), (2.3 * k as f64).cos());
        camera.project(&(rotation * x + translation)) + noise
    };
    let corner = |k: usize| {
        let a = k as f64;
        Vector3::new((0.9 * a).sin(), (1.3 * a).cos(), 0.5 * (0.7 * a).sin())
    };

    let mut data = Correspondences::default();
    for k in 0..8 {
        // A point: its pixel and its world coordinates.
        data.points2d.push(image(&corner(k), k));
        data.points3d.push(corner(k));
    }
    for k in 0..4 {
        // A segment: two pixel endpoints, and two world points of the 3-D line (any two).
        let (a, b) = (corner(10 + k), corner(20 + k));
        data.lines2d.push([image(&a, 30 + k), image(&b, 40 + k)]);
        data.lines3d.push([a, b]);
    }

    // The defaults: the paper's trust region from several starts, then the reprojection refinement.
    let options = PoseOptions::default();
    let result = estimate_pose(&camera, &data, &options)?;

    println!("R = {:.4}", result.pose.rotation);
    println!("t = {:.4?}", result.pose.translation.as_slice());
    println!("status: {}", result.report.status.as_str());
    println!("cost: {:.3} px² (8 points, 4 segments)", result.report.cost);
    Ok(())
}
