//! P3L: the absolute pose from three 2-D/3-D line correspondences (Dhome, Richetin, Lapresté & Rives,
//! "Determination of the attitude of 3-D objects from a single perspective view", IEEE PAMI 11(12),
//! 1989; H. H. Chen, "Pose determination from line-to-plane correspondences: existence condition and
//! closed-form solutions", ICCV 1990; the rotation-first structure of Phong & Horaud 1995, eqs. 14-15).
//!
//! **Equations.** Line `i` has the unit normal `nᵢ` of its interpretation plane (camera frame) and an
//! object line through `cᵢ` with unit direction `dᵢ` (world frame). Both of its object points lie on the
//! plane, `nᵢ · (R Pₖ + t) = 0`, which splits into
//!
//! - the rotation constraints `nᵢᵀ R dᵢ = 0`, `i = 1, 2, 3` (Phong & Horaud eq. 14), and
//! - the translation, linear once `R` is known: `nᵢᵀ t = −nᵢᵀ R cᵢ` (eq. 15), a 3x3 system `N t = h`.
//!
//! **Method.** The three rank-one rotation constraints go to the shared kernel
//! [`rotations`](super::rotation_constraints): the first line is aligned with the axes, leaving two
//! angles, and eliminating one gives a polynomial of degree 8 in `tan(β/2)` whose real roots are
//! isolated by the roots of its derivatives (no eigenvalue problem, no random restart); each root is
//! polished by Newton steps on the three constraints. The translation then solves `N t = h` (with the
//! world origin moved to the centroid of the `cᵢ`, so that `R cᵢ` carries no large offset).
//!
//! **At most 8 solutions**: the degree of the polynomial, and attained — Dhome et al. and Chen show
//! that three lines can have eight real poses. No depth test is applied: a line seen in an image does
//! not tell on which side of the camera it is (the interpretation plane contains both half-lines), so
//! every real solution is returned.
//!
//! **Degenerate cases.** Invalid input (non-finite values, a zero normal, coincident object points):
//! no pose. Three parallel object lines: `R d` must be orthogonal to three normals; with independent
//! normals there is no solution and with coplanar ones a continuum — either way no pose (never a
//! panic). Two parallel lines are fine (`R d ∥ n₁ × n₂`, then a rotation about it: up to 4 poses).
//! Image lines through one image point (coplanar normals, `det N = 0`): the translation along that
//! point's ray is not fixed, no pose; near it the translation's error grows like `1 / |det N|`. Three
//! object lines through one point give concurrent image lines, so this case too. Coincident
//! interpretation planes (two equal image lines, the camera centre in the plane of two object lines)
//! make `N` singular too: no pose when it is exactly singular, otherwise members of the family picked
//! by rounding, which still satisfy the constraints. Noise-free parallel lines have concurrent image
//! lines (the vanishing point), a continuum again; noisy ones independent normals and no solution.

use super::generalized::gp3l;
use super::Pose;
use nalgebra::Vector3;

/// Every real pose `(R, t)`, `x_cam = R X_world + t`, that puts each object line `i` (through the two
/// world points `endpoints[i]`) on the interpretation plane whose camera-frame normal is `normals[i]`:
/// zero to eight poses (see the [module documentation](super)).
///
/// A normal is any non-zero multiple of `(u₁, v₁, 1) × (u₂, v₂, 1)` for two normalised image points of
/// the image line (`(uᵢ, vᵢ)` from [`crate::camera::Intrinsics::pixel_to_normalized`]), e.g.
/// [`crate::camera::Intrinsics::interpretation_plane_normal`]. Invalid or degenerate input gives an empty
/// vector, never a panic.
///
/// ```
/// use nalgebra::{Rotation3, Vector3};
/// use pluecker::pose::minimal::p3l;
///
/// let rotation = Rotation3::from_euler_angles(0.1, -0.2, 0.3).into_inner();
/// let translation = Vector3::new(0.2, -0.1, 4.0);
/// let lines = [
///     [Vector3::new(0.0, 0.0, 0.0), Vector3::new(1.0, 0.0, 0.0)],
///     [Vector3::new(0.0, 1.0, 0.0), Vector3::new(0.0, 1.0, 1.0)],
///     [Vector3::new(1.0, 0.0, 1.0), Vector3::new(1.0, 1.0, 0.5)],
/// ];
/// let normals = lines.map(|[p, q]| (rotation * p + translation).cross(&(rotation * q + translation)));
/// let poses = p3l(&normals, &lines);
/// assert!(poses.len() <= 8);
/// assert!(poses.iter().any(|p| (p.rotation - rotation).norm() < 1e-9 && (p.translation - translation).norm() < 1e-9));
/// ```
pub fn p3l(normals: &[Vector3<f64>; 3], endpoints: &[[Vector3<f64>; 2]; 3]) -> Vec<Pose> {
    // One camera is a rig whose planes all pass through the origin.
    gp3l(normals, &[Vector3::zeros(); 3], endpoints)
}

#[cfg(test)]
mod tests;
