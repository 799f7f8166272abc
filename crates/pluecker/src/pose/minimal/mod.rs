//! Minimal solvers for the absolute camera pose: the finitely many poses `(R, t)`, `x_cam = R X_world + t`,
//! that explain exactly the smallest number of correspondences that fixes the six degrees of freedom.
//!
//! They are the hypothesis generators of a robust (RANSAC) estimator: each returns every real solution
//! it finds, possibly none, and never fails loudly — a degenerate sample simply yields no pose, so the
//! caller draws another one. Inputs are camera-frame quantities, not pixels: unit bearings for points
//! (see [`p3p()`] for how to get them from pixels with [`crate::camera::Intrinsics`]) and unit normals of
//! interpretation planes for lines ([`crate::camera::Intrinsics::interpretation_plane_normal`]).
//!
//! | solver      | data              | max. solutions | method                                 | reference                                          |
//! |-------------|-------------------|----------------|----------------------------------------|----------------------------------------------------|
//! | [`p3p()`]   | 3 points          | 4              | cubic + line pair (closed form)        | Persson & Nordberg, *Lambda Twist*, ECCV 2018      |
//! | [`p2p1l()`] | 2 points + 1 line | 4              | degree-8 polynomial in `tan(β/2)`      | Ramalingam, Bouaziz & Sturm, ICRA 2011             |
//! | [`p1p2l()`] | 1 point + 2 lines | 4              | degree-8 polynomial in `tan(β/2)`      | Ramalingam, Bouaziz & Sturm, ICRA 2011             |
//! | [`p3l()`]   | 3 lines           | 8              | degree-8 polynomial in `tan(β/2)`      | Dhome et al., IEEE PAMI 1989; Chen, ICCV 1990      |
//!
//! For a rig (a generalised camera, rig frame: rays with their own origins, interpretation planes
//! through their cameras' centres), [`solve_generalized`] dispatches a sample of three [`RigFeature`]s:
//!
//! | solver       | data              | max. solutions | method                                         | reference                                               |
//! |--------------|-------------------|----------------|------------------------------------------------|---------------------------------------------------------|
//! | [`gp3p()`]   | 3 points          | 8              | octic in one depth, Newton on the distances    | Nistér & Stewénius, J. Math. Imaging Vis. 2007 (problem) |
//! | [`gp2p1l()`] | 2 points + 1 line | 8              | degree-8 polynomial, affine constraints on `R` | Miraldo, Dias & Ramalingam, ECCV 2018 (problem)         |
//! | [`gp1p2l()`] | 1 point + 2 lines | 8              | degree-8 polynomial, affine constraints on `R` | Miraldo, Dias & Ramalingam, ECCV 2018 (problem)         |
//! | [`gp3l()`]   | 3 lines           | 8              | P3L's rotations, translation from the planes   | Dhome et al. 1989; Chen 1990                            |
//!
//! The three solvers with lines share one kernel (`rotation_constraints`): the rotation from three
//! linear constraints on `R` (one of them a line's `nᵀ R d = 0`), the translation and depths then
//! being linear; the counts of 4 for the mixed solvers are the up-to-8 algebraic rotations less those
//! that put a point behind the camera (see each solver's documentation).
//!
//! [`solve`] dispatches a sample of any mix of three [`Feature`]s to the solver for that mix.

mod generalized;
mod gp3p;
mod input;
mod p1p2l;
mod p2p1l;
mod p3l;
mod p3p;
mod polynomial;
mod rotation_constraints;

pub use generalized::{gp1p2l, gp2p1l, gp3l, solve_generalized, RigFeature};
pub use gp3p::gp3p;
pub use p1p2l::p1p2l;
pub use p2p1l::p2p1l;
pub use p3l::p3l;
pub use p3p::p3p;

use nalgebra::Vector3;

#[doc(no_inline)]
pub use crate::camera_pose::Pose;

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
/// for its mix of points and lines, in any order: [`p3p()`], [`p2p1l()`], [`p1p2l()`] or [`p3l()`], each
/// given its points and its lines in the order they appear in `sample`. Degenerate or invalid samples
/// give an empty vector.
pub fn solve(sample: &[Feature; 3]) -> Vec<Pose> {
    let mut bearings = Vec::with_capacity(3);
    let mut points = Vec::with_capacity(3);
    let mut normals = Vec::with_capacity(3);
    let mut endpoints = Vec::with_capacity(3);
    for feature in sample {
        match *feature {
            Feature::Point { bearing, point } => {
                bearings.push(bearing);
                points.push(point);
            }
            Feature::Line { normal, endpoints: e } => {
                normals.push(normal);
                endpoints.push(e);
            }
        }
    }
    match normals.len() {
        0 => p3p(
            &[bearings[0], bearings[1], bearings[2]],
            &[points[0], points[1], points[2]],
        ),
        1 => p2p1l(
            &[bearings[0], bearings[1]],
            &[points[0], points[1]],
            &normals[0],
            &endpoints[0],
        ),
        2 => p1p2l(
            &bearings[0],
            &points[0],
            &[normals[0], normals[1]],
            &[endpoints[0], endpoints[1]],
        ),
        _ => p3l(
            &[normals[0], normals[1], normals[2]],
            &[endpoints[0], endpoints[1], endpoints[2]],
        ),
    }
}

#[cfg(test)]
mod testing;
#[cfg(test)]
mod tests;
