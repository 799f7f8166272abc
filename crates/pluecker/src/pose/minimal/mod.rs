//! Minimal solvers for the absolute camera pose: the finitely many poses `(R, t)`, `x_cam = R X_world + t`,
//! that explain exactly the smallest number of correspondences that fixes the six degrees of freedom.
//!
//! They are the hypothesis generators of a robust (RANSAC) estimator: each returns every real solution
//! it finds, possibly none, and never fails loudly — a degenerate sample simply yields no pose, so the
//! caller draws another one. Inputs are camera-frame quantities, not pixels: unit bearings for points
//! (see [`p3p()`] for how to get them from pixels with [`crate::camera::Camera`]) and unit normals of
//! interpretation planes for lines ([`crate::geometry::lines::interpretation_plane_normal`]).
//!
//! | solver    | data     | max. solutions | reference                                     |
//! |-----------|----------|----------------|-----------------------------------------------|
//! | [`p3p()`] | 3 points | 4              | Persson & Nordberg, *Lambda Twist*, ECCV 2018 |
//!
//! [`solve`] dispatches a sample of any mix of three [`Feature`]s to the solver for that mix.

pub mod p3p;
mod polynomial;

pub use p3p::p3p;

use nalgebra::Vector3;

/// A pose `(R, t)`: `x_cam = R X_world + t`, `R` a rotation, `t` in world units.
pub type Pose = (nalgebra::Matrix3<f64>, Vector3<f64>);

/// One 2-D/3-D correspondence as a minimal solver sees it (camera-frame image data, world-frame
/// object data).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Feature {
    /// An image point and its object point: `bearing ∥ R point + t`, with positive depth.
    Point {
        /// Direction of the ray in the camera frame (any positive multiple; normalised by the solvers).
        bearing: Vector3<f64>,
        /// Object point, world frame.
        point: Vector3<f64>,
    },
    /// An image line and its object line: both object points lie on the interpretation plane,
    /// `normal · (R endpoints[k] + t) = 0` (Phong & Horaud 1995, eq. 4 with the plane through the
    /// optical centre and the image line).
    Line {
        /// Normal of the interpretation plane (the plane through the optical centre and the image line),
        /// camera frame, any non-zero multiple.
        normal: Vector3<f64>,
        /// Two distinct points of the object line, world frame.
        endpoints: [Vector3<f64>; 2],
    },
}

/// Every real pose that explains the three correspondences of `sample` exactly, from the minimal solver
/// for its mix of points and lines (in any order). Degenerate or invalid samples give an empty vector.
pub fn solve(sample: &[Feature; 3]) -> Vec<Pose> {
    let mut bearings = [Vector3::zeros(); 3];
    let mut points = [Vector3::zeros(); 3];
    for (k, feature) in sample.iter().enumerate() {
        match *feature {
            Feature::Point { bearing, point } => {
                bearings[k] = bearing;
                points[k] = point;
            }
            // The mixed and line-only solvers are being added (issue 4); until they land a sample with a
            // line yields no hypothesis.
            Feature::Line { .. } => return Vec::new(),
        }
    }
    p3p(&bearings, &points)
}
