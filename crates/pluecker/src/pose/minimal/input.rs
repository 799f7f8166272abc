//! Validation and normalisation of a minimal solver's input, shared by the solvers with lines: unit
//! vectors from "any non-zero multiple" inputs, an object line from its two world points, and the
//! final check that a pose satisfies the original constraints.

use crate::camera_pose::Pose;
use nalgebra::Vector3;

/// `v / ‖v‖`, or `None` when `v` is zero or not finite.
pub(crate) fn unit(v: &Vector3<f64>) -> Option<Vector3<f64>> {
    let norm = v.norm();
    (norm > 0.0 && norm.is_finite() && v.iter().all(|c| c.is_finite())).then(|| v / norm)
}

/// `Some(v)` when every coordinate of `v` is finite.
pub(crate) fn finite(v: &Vector3<f64>) -> Option<Vector3<f64>> {
    v.iter().all(|c| c.is_finite()).then_some(*v)
}

/// A line correspondence, validated: the unit normal `n` of its interpretation plane (camera frame)
/// and its object line (world frame) as a unit direction `d` and the midpoint of the two given points.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Line {
    pub normal: Vector3<f64>,
    pub direction: Vector3<f64>,
    pub midpoint: Vector3<f64>,
    pub endpoints: [Vector3<f64>; 2],
}

impl Line {
    /// `None` for a zero or non-finite normal, non-finite endpoints, or coincident endpoints (a
    /// difference that is zero or not finite).
    pub fn new(normal: &Vector3<f64>, endpoints: &[Vector3<f64>; 2]) -> Option<Line> {
        let normal = unit(normal)?;
        let [p, q] = [finite(&endpoints[0])?, finite(&endpoints[1])?];
        Some(Line {
            normal,
            direction: unit(&(q - p))?,
            midpoint: 0.5 * (p + q),
            endpoints: [p, q],
        })
    }

    /// The point of the object line nearest `origin`, minus `origin`: orthogonal to the direction,
    /// so that `nᵀ R (that vector)` does not depend on how far along the line the given points are.
    pub fn offset_from(&self, origin: &Vector3<f64>) -> Vector3<f64> {
        let p = self.midpoint - origin;
        p - self.direction * self.direction.dot(&p)
    }

    /// The rank-one constraint `nᵀ R d = 0` as the matrix `n dᵀ` (`⟨n dᵀ, R⟩ = nᵀ R d`).
    pub fn direction_constraint(&self) -> nalgebra::Matrix3<f64> {
        self.normal * self.direction.transpose()
    }
}

/// A returned pose must satisfy each original constraint to this, as the sine of an angle: a point's
/// `‖y × x‖ ≤ tol ‖x‖` and each object point of a line `|n · x| ≤ tol ‖x‖` (`x` camera frame). Genuine
/// solutions reach rounding level (1e-13 at worst over the random tests); the check rejects poses
/// whose translation or depth came out of a nearly singular elimination (e.g. a depth as the ratio of
/// two vanishing quantities), which can miss by an order of one. 1e-8 rad is 1e-5 px at a focal
/// length of 1000 px.
pub(crate) const SOLUTION_TOLERANCE: f64 = 1e-8;

/// `x = R X + t` lies on the ray of the unit bearing `y`, in front ([`SOLUTION_TOLERANCE`]).
pub(crate) fn point_holds(
    y: &Vector3<f64>,
    point: &Vector3<f64>,
    Pose {
        rotation: r,
        translation: t,
    }: &super::Pose,
) -> bool {
    let x = r * point + t;
    y.dot(&x) > 0.0 && y.cross(&x).norm() <= SOLUTION_TOLERANCE * x.norm()
}

/// Both object points of `line` lie on its interpretation plane ([`SOLUTION_TOLERANCE`]).
pub(crate) fn line_holds(
    line: &Line,
    Pose {
        rotation: r,
        translation: t,
    }: &super::Pose,
) -> bool {
    line.endpoints.iter().all(|p| {
        let x = r * p + t;
        line.normal.dot(&x).abs() <= SOLUTION_TOLERANCE * x.norm()
    })
}
