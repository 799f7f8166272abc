//! The default start of the iterative estimators: no guess from the user.
//!
//! The paper starts its trust region anywhere (section 6: "the final result is independent of the
//! initialisation"). Measured on its own cost that is not quite so: eqs. 13/22 have a second local
//! minimum, the *mirror* pose that puts the object behind the camera (`x_cam ≈ −x_cam_true`; exact
//! for planar objects, where it has the same cost), and far starts can wander for hundreds of
//! iterations. Two cheap devices remove both problems without asking the user for anything:
//!
//! 1. **Start from the best of 60 rotations.** For a fixed rotation the translation part of the cost is
//!    linear least squares, so it can be minimised out exactly: with `G = [[A, B], [Bᵀ, C]]` split
//!    after the 9 rotation entries of `y = [vec R̃; t̃]`, the best `t̃` is `−C⁻¹Bᵀ vec R` and the cost is
//!    `vec Rᵀ (A − B C⁻¹ Bᵀ) vec R`. That is evaluated at the 60 rotations of the 600-cell (every
//!    rotation is within about 45° of one of them). The estimator runs from the cheapest grid rotation
//!    whose translation puts the object in front of the camera, with that translation. For a
//!    near-planar object it runs from the three cheapest at least 72° apart; the distinct answers are
//!    ranked by cost, and any within a factor of the best are refined on the reprojection error, which
//!    decides. This catches the second minimum of planar scenes, whose algebraic cost can be the lower
//!    one.
//! 2. **Cheirality restart.** If the estimator converges with object points behind the camera (or far
//!    from a rigid motion: the collapsed stationary point `r → 0`), it is restarted once from the
//!    mirrored pose `(R Rπ(n), −t)`, `n` the object's axis of least spread (for which `Rπ(n)` reverses
//!    the object's other two axes), and the answer in front is kept.
//!
//! A start given by the user is tried in addition to these, and the cheapest valid answer wins.

use super::algebraic::Gram;
use crate::geometry::dual_quaternion::DualQuaternion;
use crate::geometry::quaternion::{from_axis_angle, rotation_distance, to_rotation_matrix};
use nalgebra::{Matrix3, SMatrix, Vector3, Vector4};
use std::sync::OnceLock;

/// The 60 rotations of the 600-cell (its 120 unit quaternions up to sign), as rotation matrices
/// flattened row-major, with their quaternions.
fn rotation_grid() -> &'static [(Vector4<f64>, SMatrix<f64, 9, 1>)] {
    static GRID: OnceLock<Vec<(Vector4<f64>, SMatrix<f64, 9, 1>)>> = OnceLock::new();
    GRID.get_or_init(|| {
        let phi = 0.5 * (1.0 + 5f64.sqrt());
        let mut quats: Vec<Vector4<f64>> = Vec::with_capacity(120);
        for i in 0..4 {
            for s in [-1.0, 1.0] {
                quats.push(Vector4::from_fn(|k, _| if k == i { s } else { 0.0 }));
            }
        }
        for m in 0..16 {
            quats.push(Vector4::from_fn(|k, _| if m >> k & 1 == 1 { -0.5 } else { 0.5 }));
        }
        // Even permutations of ½(±φ, ±1, ±1/φ, 0).
        let even_perms = [
            [0, 1, 2, 3], [0, 2, 3, 1], [0, 3, 1, 2], [1, 0, 3, 2], [1, 2, 0, 3], [1, 3, 2, 0],
            [2, 0, 1, 3], [2, 1, 3, 0], [2, 3, 0, 1], [3, 0, 2, 1], [3, 1, 0, 2], [3, 2, 1, 0],
        ];
        let base = [phi, 1.0, 1.0 / phi, 0.0];
        for perm in even_perms {
            for signs in 0..8 {
                let mut q = Vector4::zeros();
                for (j, &slot) in perm.iter().enumerate() {
                    let sign = if j < 3 && signs >> j & 1 == 1 { -1.0 } else { 1.0 };
                    q[slot] = 0.5 * sign * base[j];
                }
                quats.push(q);
            }
        }
        quats
            .into_iter()
            .filter(|q| q[0] > 1e-12 || (q[0].abs() <= 1e-12 && first_nonzero_positive(q)))
            .map(|q| {
                let r = to_rotation_matrix(&q);
                (q, SMatrix::<f64, 9, 1>::from_fn(|i, _| r[(i / 3, i % 3)]))
            })
            .collect()
    })
}

fn first_nonzero_positive(q: &Vector4<f64>) -> bool {
    q.iter().find(|v| v.abs() > 1e-12).is_some_and(|v| *v > 0.0)
}

/// Minimum angle between two starts of [`joint_starts`] and [`rotation_starts`]: one grid step (72°).
const DISTINCT_STARTS: f64 = 1.25;

/// Up to `k` grid indices in increasing order of score, each at least one grid step from the ones
/// before it. Ties keep grid order. One start (the common case) needs only the minimum, not a sort.
fn diverse_best(scores: &[f64], k: usize) -> Vec<usize> {
    if k == 1 {
        let best = (1..scores.len()).fold(0, |best, i| if scores[i] < scores[best] { i } else { best });
        return if scores.is_empty() { vec![] } else { vec![best] };
    }
    let grid = rotation_grid();
    let mut order: Vec<usize> = (0..scores.len()).collect();
    order.sort_by(|&a, &b| scores[a].total_cmp(&scores[b]));
    let rotation = |i: usize| Matrix3::from_row_slice(grid[i].1.as_slice());
    let mut picked: Vec<usize> = Vec::with_capacity(k);
    for i in order {
        if picked.len() == k {
            break;
        }
        if picked.iter().all(|&p| rotation_distance(&rotation(p), &rotation(i)) > DISTINCT_STARTS) {
            picked.push(i);
        }
    }
    picked
}

/// Starts of the joint estimators (eqs. 13, 22): up to `k` distinct grid rotations of least
/// translation-eliminated cost, those whose optimal translation puts `centroid` (object frame of the
/// cost) in front of the camera first, each with that translation. Empty if the translation block `C`
/// of `G` is singular.
pub fn joint_starts(gram: &Gram, centroid: &Vector3<f64>, k: usize) -> Vec<DualQuaternion> {
    let a = gram.fixed_view::<9, 9>(0, 0);
    let b = gram.fixed_view::<9, 3>(0, 9);
    let Some(c_inv) = gram.fixed_view::<3, 3>(9, 9).into_owned().try_inverse() else {
        return vec![];
    };
    let to_t: SMatrix<f64, 3, 9> = -(c_inv * b.transpose());
    let reduced = a + b * to_t;
    // Depth of the centroid at grid rotation v (row-major R) with its best translation:
    // (R c)_z + t_z = (v₆..₈ + to_t row 2) · (c, …) — only the third row of R and of to_t are needed.
    let depth_row = SMatrix::<f64, 1, 9>::from_fn(|_, j| to_t[(2, j)] + if j >= 6 { centroid[j - 6] } else { 0.0 });
    let scores: Vec<f64> = rotation_grid()
        .iter()
        .map(|(_, v)| {
            let behind = if depth_row.dot(&v.transpose()) > 0.0 { 0.0 } else { f64::MAX / 4.0 };
            behind + v.dot(&(reduced * v))
        })
        .collect();
    diverse_best(&scores, k)
        .into_iter()
        .map(|i| {
            let v = &rotation_grid()[i].1;
            DualQuaternion::from_rotation_translation(&Matrix3::from_row_slice(v.as_slice()), &(to_t * v))
        })
        .collect()
}

/// Starts of the rotation-only estimator (eq. 14): up to `k` distinct grid rotations of least cost
/// under its 9x9 Gram matrix.
pub fn rotation_starts(gram9: &SMatrix<f64, 9, 9>, k: usize) -> Vec<Vector4<f64>> {
    let grid = rotation_grid();
    let scores: Vec<f64> = grid.iter().map(|(_, v)| v.dot(&(gram9 * v))).collect();
    diverse_best(&scores, k).into_iter().map(|i| grid[i].0).collect()
}

/// The mirror pose `(R Rπ(n), −t)` of a pose that puts the object behind the camera.
pub fn mirrored(rotation: &Matrix3<f64>, translation: &Vector3<f64>, axis: &Vector3<f64>) -> DualQuaternion {
    let flip = to_rotation_matrix(&from_axis_angle(axis, std::f64::consts::PI));
    DualQuaternion::from_rotation_translation(&(rotation * flip), &-translation)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    #[test]
    fn grid_has_60_distinct_rotations_covering_so3_within_45_degrees() {
        let grid = rotation_grid();
        assert_eq!(grid.len(), 60);
        let mats: Vec<Matrix3<f64>> = grid.iter().map(|(q, _)| to_rotation_matrix(q)).collect();
        for i in 0..60 {
            for j in 0..i {
                // Neighbouring vertices are 36° apart on S³: 72° apart as rotations.
                assert!(rotation_distance(&mats[i], &mats[j]) > 1.25);
            }
        }
        // Covering radius of the 600-cell: its deepest holes (cell centres) are 22.2° from the nearest
        // vertex on S³, i.e. a rotation angle of 44.5° = 0.777 rad.
        let mut rng = Rng::new(600);
        for _ in 0..2000 {
            let r = rng.rotation();
            let nearest = mats.iter().map(|m| rotation_distance(m, &r)).fold(f64::INFINITY, f64::min);
            assert!(nearest <= 0.777, "{nearest}");
        }
    }
}
