//! Helpers shared by the integration tests: projections, noisy segments and visibility masks of the
//! batch tests (`use crate::common;` in each test module that uses them), and the triangulation oracle.
#![allow(dead_code)]

pub mod oracle_triangulation;

use nalgebra::{Matrix3, Matrix3x4, Vector2, Vector3};
use pluecker::geometry::{project_dual, Ellipsoid};
use pluecker::rng::Rng;
use pluecker::triangulation::line::{DenseLineTracks, ImageLines};

/// The pixel of the world point `x` in the camera `p`.
pub fn project(p: &Matrix3x4<f64>, x: &Vector3<f64>) -> Vector2<f64> {
    let u = p * x.push(1.0);
    u.xy() / u.z
}

/// The outlines (point conics) of the ellipsoid `e` in the `cameras`.
pub fn outlines(cameras: &[Matrix3x4<f64>], e: &Ellipsoid) -> Vec<Matrix3<f64>> {
    cameras
        .iter()
        .map(|p| project_dual(p, &e.dual()).try_inverse().unwrap())
        .collect()
}

/// `n` random segments near the origin seen by `cameras`, with endpoint noise of `sigma` px: the flat
/// `(n, v, 2, 2)` endpoints.
pub fn noisy_segments(cameras: &[Matrix3x4<f64>], n: usize, sigma: f64, rng: &mut Rng) -> Vec<f64> {
    let mut out = Vec::with_capacity(4 * n * cameras.len());
    for _ in 0..n {
        let mid = Vector3::new(rng.normal(), rng.normal(), rng.normal()) * 0.2;
        let half = rng.unit_vector3() * rng.uniform_in(0.4, 0.8);
        for p in cameras {
            for end in [mid + half, mid - half] {
                let u = project(p, &end);
                out.extend([u.x + sigma * rng.normal(), u.y + sigma * rng.normal()]);
            }
        }
    }
    out
}

/// Line tracks of flat segment `endpoints` with endpoint noise `sigma`, every view visible, no covariances.
pub fn segment_tracks(endpoints: &[f64], sigma: f64) -> DenseLineTracks<'_> {
    DenseLineTracks {
        lines: ImageLines::Segments { endpoints, sigma },
        visible: None,
        covariances: None,
    }
}

/// The visible views of track `t` under a flat `(n, v)` mask.
pub fn seen(visible: &[bool], v: usize, t: usize) -> Vec<usize> {
    (0..v).filter(|&j| visible[t * v + j]).collect()
}

pub fn segment(endpoints: &[f64], v: usize, t: usize, j: usize) -> [Vector2<f64>; 2] {
    let s = &endpoints[4 * (t * v + j)..][..4];
    [Vector2::new(s[0], s[1]), Vector2::new(s[2], s[3])]
}

/// A random visibility mask with at least `min` views per track.
pub fn mask(n: usize, v: usize, min: usize, rng: &mut Rng) -> Vec<bool> {
    let mut visible = vec![false; n * v];
    for t in 0..n {
        let count = min + rng.below(v - min + 1);
        for j in rng.sample_indices(v, count) {
            visible[t * v + j] = true;
        }
    }
    visible
}
