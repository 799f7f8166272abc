//! P1P2L: the absolute pose from one 2-D/3-D point and two line correspondences (Ramalingam, Bouaziz &
//! Sturm, "Pose estimation using both points and lines for geo-localization", ICRA 2011, who show it
//! has at most four solutions; the elimination below follows the linear-constraints-on-`R` view of
//! PoseLib's `p1p2ll`, written here from the equations).
//!
//! **Equations.** The point: unit bearing `y` (camera frame) and world point `X`, `R X + t = λ y` with
//! depth `λ > 0`. Line `i = 1, 2`: unit normal `nᵢ` of its interpretation plane, object line with unit
//! direction `dᵢ` through `cᵢ`; `nᵢ · (R Pₖ + t) = 0` for both object points. With the world origin at
//! `X`, `t = λ y − R X`, and with `pᵢ` the point of line `i` nearest `X`, minus `X`, the line equations
//! are `nᵢᵀ R dᵢ = 0` and `nᵢᵀ R pᵢ + λ sᵢ = 0` with `sᵢ = nᵢᵀ y`. Eliminating `λ`:
//!
//! `n₁ᵀ R d₁ = 0`, `n₂ᵀ R d₂ = 0`, `s₂ n₁ᵀ R p₁ − s₁ n₂ᵀ R p₂ = 0`,
//!
//! three linear constraints on `R`, the first rank one. Then `λ = −Σ sᵢ nᵢᵀ R pᵢ / Σ sᵢ²` (least squares
//! over both lines, which agree at a solution) and `t = λ y − R X`.
//!
//! **Method.** The shared kernel [`rotations`](super::rotation_constraints): a polynomial of degree 8
//! in `tan(β/2)`, real roots isolated by the roots of its derivatives, each polished by Newton steps on
//! the three constraints.
//!
//! **At most 4 solutions.** All three constraints involve `R` only through `Rᵀn₁` and `Rᵀn₂`, so with
//! `H` the half-turn about `q = n₁ × n₂` (which maps `n₁ → −n₁`, `n₂ → −n₂`), `H R` solves them whenever
//! `R` does, with `λ` of the opposite sign. The up to 8 algebraic rotations come in such pairs, and the
//! depth test `λ > 0` keeps exactly one of each pair: at most four poses (Ramalingam et al. 2011).
//!
//! **Degenerate cases.** Invalid input (non-finite, zero bearing or normal, coincident object points):
//! no pose. The point on one of the lines (`X` on line `i`): then `pᵢ = 0` and, noise-free, `sᵢ = 0`,
//! the third constraint vanishes and a one-parameter family of poses remains — no pose (near it the
//! poses lose accuracy in proportion to `1 / distance`). The image point on both image lines
//! (`s₁ = s₂ = 0`): the depth is not fixed, no pose. Parallel object lines: fine (`R d ∥ ±n₁ × n₂`, then
//! a rotation about it). Coincident interpretation planes (`n₁ ∥ n₂`): `q = 0`, a continuum, no pose.
//! A pose with the point behind the camera (`λ ≤ 0`) is not returned.

use super::input::{finite, line_holds, point_holds, unit, Line};
use super::rotation_constraints::rotations;
use super::Pose;
use nalgebra::Vector3;

/// Every real pose `(R, t)`, `x_cam = R X_world + t`, that puts the world `point` on the ray of the
/// camera-frame `bearing` at positive depth and each object line `i` (through the two world points
/// `endpoints[i]`) on the interpretation plane with camera-frame normal `normals[i]`: zero to four poses
/// (see the [module documentation](super)).
///
/// `bearing` and `normals` are any non-zero multiples (see [`super::p3p()`] and [`super::p3l()`] for
/// how to get them from pixels). Invalid or degenerate input gives an empty vector, never a panic.
///
/// ```
/// use nalgebra::{Rotation3, Vector3};
/// use pluecker::pose::minimal::p1p2l;
///
/// let rotation = Rotation3::from_euler_angles(0.1, -0.2, 0.3).into_inner();
/// let translation = Vector3::new(0.2, -0.1, 4.0);
/// let to_camera = |x: &Vector3<f64>| rotation * x + translation;
/// let point = Vector3::new(0.5, 0.5, 0.5);
/// let lines = [
///     [Vector3::new(0.0, 0.0, 0.0), Vector3::new(1.0, 0.0, 0.0)],
///     [Vector3::new(0.0, 1.0, 0.0), Vector3::new(0.0, 1.0, 1.0)],
/// ];
/// let normals = lines.map(|[p, q]| to_camera(&p).cross(&to_camera(&q)));
/// let poses = p1p2l(&to_camera(&point), &point, &normals, &lines);
/// assert!(poses.len() <= 4);
/// assert!(poses.iter().any(|p| (p.rotation - rotation).norm() < 1e-9 && (p.translation - translation).norm() < 1e-9));
/// ```
pub fn p1p2l(
    bearing: &Vector3<f64>,
    point: &Vector3<f64>,
    normals: &[Vector3<f64>; 2],
    endpoints: &[[Vector3<f64>; 2]; 2],
) -> Vec<Pose> {
    let (Some(y), Some(x)) = (unit(bearing), finite(point)) else {
        return Vec::new();
    };
    let (Some(first), Some(second)) = (
        Line::new(&normals[0], &endpoints[0]),
        Line::new(&normals[1], &endpoints[1]),
    ) else {
        return Vec::new();
    };
    let lines = [first, second];
    let p = lines.map(|l| l.offset_from(&x));
    let s = lines.map(|l| l.normal.dot(&y));
    let depth_constraint = first.normal * (p[0] * s[1]).transpose() - second.normal * (p[1] * s[0]).transpose();
    let s_squared = s[0] * s[0] + s[1] * s[1];
    rotations(
        &first.normal,
        &first.direction,
        [second.direction_constraint(), depth_constraint],
    )
    .into_iter()
    .filter_map(|r| {
        let depth = -(s[0] * first.normal.dot(&(r * p[0])) + s[1] * second.normal.dot(&(r * p[1]))) / s_squared;
        let pose = Pose::new(r, y * depth - r * x);
        let holds = point_holds(&y, &x, &pose) && lines.iter().all(|l| line_holds(l, &pose));
        (depth > 0.0 && holds).then_some(pose)
    })
    .collect()
}

#[cfg(test)]
mod tests;
