//! P2P1L: the absolute pose from two 2-D/3-D point and one line correspondence (Ramalingam, Bouaziz &
//! Sturm, "Pose estimation using both points and lines for geo-localization", ICRA 2011, who show it
//! has at most four solutions; the elimination below follows the linear-constraints-on-`R` view of
//! PoseLib's `p2p1ll`, written here from the equations).
//!
//! **Equations.** Points `j = 1, 2`: unit bearings `yⱼ`, world points `Xⱼ`, `R Xⱼ + t = λⱼ yⱼ`, `λⱼ > 0`.
//! The line: unit normal `n` of its interpretation plane, object line with unit direction `d`;
//! `n · (R Pₖ + t) = 0` for both object points. With `e = X₂ − X₁` and `m = y₁ × y₂`, subtracting the
//! point equations gives `R e = λ₂ y₂ − λ₁ y₁`, so `R e` lies in the plane of the two rays and the
//! depths are linear in `R`:
//!
//! `mᵀ R e = 0`, `λ₁ = g₁ᵀ R e`, `λ₂ = g₂ᵀ R e` with `g₁ = (m × y₂) / ‖m‖²`, `g₂ = (m × y₁) / ‖m‖²`.
//!
//! With `t = λ₁ y₁ − R X₁` and `p` the point of the line nearest `X₁`, minus `X₁`, the line gives
//! `nᵀ R d = 0` and `nᵀ R p + (nᵀ y₁) g₁ᵀ R e = 0`: three linear constraints on `R`, two of them rank
//! one. Then `λ₁, λ₂` follow and `t` is the mean of `λⱼ yⱼ − R Xⱼ`.
//!
//! **Method.** The shared kernel [`rotations`](super::rotation_constraints) with `m̂ᵀ R ê = 0` as its
//! aligned constraint: a polynomial of degree 8 in `tan(β/2)`, real roots isolated by the roots of its
//! derivatives, each polished by Newton steps on the three constraints.
//!
//! **At most 4 solutions** with both depths positive (Ramalingam et al. 2011), of up to 8 algebraic
//! rotations. Geometrically: the camera centre `C` sees the object line in a plane through it, whose
//! angles to the two rays are known (`nᵀyⱼ`), so `|C − Xⱼ| = dist(Xⱼ, plane) / |nᵀyⱼ|`; the known angle
//! between the rays then fixes `|C − X₁|² + |C − X₂|² − 2 y₁ᵀy₂ |C − X₁||C − X₂| = ‖e‖²`, a quadratic in
//! the plane's direction about the object line: two planes, each holding at most two centres (two
//! circles in a plane). The other algebraic solutions put a point behind the camera.
//!
//! **Degenerate cases.** Invalid input (non-finite, zero bearing or normal, coincident points): no
//! pose. Both points on one ray (`y₁ ∥ y₂`, `m = 0`): no pose (the depths are then not linear in `R`
//! this way; near it they lose accuracy like `1 / ‖m‖`). The object line through both points: its
//! constraints repeat the points' (`n ∥ m`, `d ∥ e`), a continuum of poses, no pose returned; near it
//! the rotation about the line is fixed only through the small offset. The object line through one of
//! the points: the plane then contains that point's ray whatever the pose, five constraints for six
//! unknowns, a continuum (no pose, or members of it picked by rounding). Coincident world points: no
//! pose.

use super::input::{finite, line_holds, point_holds, unit, Line};
use super::rotation_constraints::rotations;
use super::Pose;
use nalgebra::Vector3;

/// Every real pose `(R, t)`, `x_cam = R X_world + t`, that puts each world `points[j]` on the ray of
/// the camera-frame `bearings[j]` at positive depth and the object line through the two world points
/// `endpoints` on the interpretation plane with camera-frame normal `normal`: zero to four poses (see
/// the [module documentation](super)).
///
/// `bearings` and `normal` are any non-zero multiples (see [`super::p3p()`] and [`super::p3l()`] for
/// how to get them from pixels). Invalid or degenerate input gives an empty vector, never a panic.
///
/// ```
/// use nalgebra::{Rotation3, Vector3};
/// use pluecker::pose::minimal::p2p1l;
///
/// let rotation = Rotation3::from_euler_angles(0.1, -0.2, 0.3).into_inner();
/// let translation = Vector3::new(0.2, -0.1, 4.0);
/// let to_camera = |x: &Vector3<f64>| rotation * x + translation;
/// let points = [Vector3::new(0.5, 0.5, 0.5), Vector3::new(-0.5, 0.0, 1.0)];
/// let line = [Vector3::new(0.0, 1.0, 0.0), Vector3::new(0.0, 1.0, 1.0)];
/// let normal = to_camera(&line[0]).cross(&to_camera(&line[1]));
/// let poses = p2p1l(&points.map(|x| to_camera(&x)), &points, &normal, &line);
/// assert!(poses.len() <= 4);
/// assert!(poses.iter().any(|p| (p.rotation - rotation).norm() < 1e-9 && (p.translation - translation).norm() < 1e-9));
/// ```
pub fn p2p1l(
    bearings: &[Vector3<f64>; 2],
    points: &[Vector3<f64>; 2],
    normal: &Vector3<f64>,
    endpoints: &[Vector3<f64>; 2],
) -> Vec<Pose> {
    let (Some(y1), Some(y2)) = (unit(&bearings[0]), unit(&bearings[1])) else {
        return Vec::new();
    };
    let (Some(x1), Some(x2)) = (finite(&points[0]), finite(&points[1])) else {
        return Vec::new();
    };
    let Some(line) = Line::new(normal, endpoints) else {
        return Vec::new();
    };
    let e = x2 - x1;
    let (Some(e_unit), Some(m_unit)) = (unit(&e), unit(&y1.cross(&y2))) else {
        return Vec::new();
    };
    let m = y1.cross(&y2);
    let m_squared = m.norm_squared();
    let g1 = m.cross(&y2) / m_squared;
    let g2 = m.cross(&y1) / m_squared;
    let p = line.offset_from(&x1);
    let offset_constraint = line.normal * p.transpose() + (g1 * line.normal.dot(&y1)) * e.transpose();
    rotations(&m_unit, &e_unit, [line.direction_constraint(), offset_constraint])
        .into_iter()
        .filter_map(|r| {
            let re = r * e;
            let (depth1, depth2) = (g1.dot(&re), g2.dot(&re));
            let pose = Pose::new(r, 0.5 * ((y1 * depth1 - r * x1) + (y2 * depth2 - r * x2)));
            let holds = point_holds(&y1, &x1, &pose) && point_holds(&y2, &x2, &pose) && line_holds(&line, &pose);
            (depth1 > 0.0 && depth2 > 0.0 && holds).then_some(pose)
        })
        .collect()
}

#[cfg(test)]
mod tests;
