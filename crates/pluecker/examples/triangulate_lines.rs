//! Triangulate a 3-D line from its image segments in two or more views with known cameras.
//!
//! `cargo run --release -p pluecker --example triangulate_lines` prints the line (its point closest to
//! the origin and its unit direction, within 0.01 of the line through (-0.3, -0.6, 5) and (0.2, 0.7, 6)
//! the data were made from), its Plücker coordinates, the status `success`, the cost Σ r² (whitened
//! px², about 0.6 for the ±0.5 px of noise) and its certificate (`taylor_branch_and_bound`, certified).

use pluecker::nalgebra::{Matrix3x4, Rotation3, Vector2, Vector3};
use pluecker::triangulation::line::{triangulate_line, LineObservations};
use pluecker::triangulation::TriangulationOptions;
use pluecker::{Camera, Pose};

fn main() -> pluecker::Result<()> {
    // Three views' projections P = K [R | t].
    let camera = Camera::pinhole(800.0, 800.0, 320.0, 240.0, 0.0)?;
    let projections: Vec<Matrix3x4<f64>> = (0..3)
        .map(|j| {
            let rotation =
                Rotation3::from_scaled_axis(Vector3::new(0.1 * j as f64, -0.15 * j as f64, 0.0)).into_inner();
            camera.projection(&Pose::new(rotation, Vector3::new(-(j as f64), 0.6 * j as f64, 0.0)))
        })
        .collect();

    // Each view's segment: two pixel endpoints of the line's image (here of two 3-D points of the
    // line, with ±0.5 px of noise; the endpoints need not be the same 3-D points in every view).
    let (a, b) = (Vector3::new(-0.3, -0.6, 5.0), Vector3::new(0.2, 0.7, 6.0));
    let pixel = |p: &Matrix3x4<f64>, x: &Vector3<f64>, k: usize| {
        let h = p * x.push(1.0);
        Vector2::new(h.x / h.z, h.y / h.z) + 0.5 * Vector2::new((1.7 * k as f64).sin(), (2.3 * k as f64).cos())
    };
    let lines: Vec<[Vector2<f64>; 2]> = projections
        .iter()
        .enumerate()
        .map(|(j, p)| [pixel(p, &a, 2 * j), pixel(p, &b, 2 * j + 1)])
        .collect();

    // `sigma`: the endpoints' noise in pixels, which weights each view by its segment's length.
    let sigma = 1.0;
    let options = TriangulationOptions::default(); // method `optimal`: certified
    let line = triangulate_line(&projections, LineObservations::Segments(&lines, sigma), &options)?;

    println!("point: {:.4?}", line.point.as_slice());
    println!("direction: {:.4?}", line.direction.as_slice());
    println!("Plücker coordinates: {:.4?}", line.plucker.coordinates().as_slice());
    println!("status: {}, cost: {:.4}", line.report.status.as_str(), line.report.cost);
    if let Some(c) = &line.report.certificate {
        println!("certificate: {}, certified {}", c.kind.as_str(), c.certified);
    }
    Ok(())
}
