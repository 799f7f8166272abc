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

/// Number of rotations in the grid.
const GRID_SIZE: usize = 60;
/// Number of distinct products `vᵢvⱼ` (`i ≤ j`) of the 9 entries of a rotation matrix.
const PRODUCTS: usize = 45;

/// The grid of start rotations, with what scoring them needs laid out for batch evaluation: every
/// quadratic form `vᵀ A v` (`v` = a rotation flattened row-major) is `Σₖ aₖ pₖ(v)` over the 45
/// products `pₖ = vᵢvⱼ` (`i ≤ j`, `aₖ = Aᵢⱼ` doubled off the diagonal), and the products are stored
/// product-major, so all 60 forms are 45 vectorisable passes over 60 numbers.
struct Grid {
    /// Unit quaternions.
    quaternions: Vec<Vector4<f64>>,
    /// Rotation matrices flattened row-major.
    rotations: Vec<SMatrix<f64, 9, 1>>,
    /// `entries[i][g]`: entry `i` of rotation `g`.
    entries: [[f64; GRID_SIZE]; 9],
    /// `products[k][g]`: product `k` of rotation `g`.
    products: [[f64; GRID_SIZE]; PRODUCTS],
}

impl Grid {
    /// `vᵀ A v` for every grid rotation `v`, `A` symmetric 9x9.
    fn quadratic_forms(&self, a: &SMatrix<f64, 9, 9>) -> [f64; GRID_SIZE] {
        let mut scores = [0.0; GRID_SIZE];
        let mut k = 0;
        for i in 0..9 {
            for j in i..9 {
                let c = if i == j { a[(i, i)] } else { a[(i, j)] + a[(j, i)] };
                for (score, p) in scores.iter_mut().zip(&self.products[k]) {
                    *score += c * p;
                }
                k += 1;
            }
        }
        scores
    }

    /// `w · v` for every grid rotation `v`.
    fn linear_forms(&self, w: &SMatrix<f64, 1, 9>) -> [f64; GRID_SIZE] {
        let mut values = [0.0; GRID_SIZE];
        for i in 0..9 {
            for (value, e) in values.iter_mut().zip(&self.entries[i]) {
                *value += w[i] * e;
            }
        }
        values
    }
}

/// The 60 rotations of the 600-cell (its 120 unit quaternions up to sign).
fn rotation_grid() -> &'static Grid {
    static GRID: OnceLock<Grid> = OnceLock::new();
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
            [0, 1, 2, 3],
            [0, 2, 3, 1],
            [0, 3, 1, 2],
            [1, 0, 3, 2],
            [1, 2, 0, 3],
            [1, 3, 2, 0],
            [2, 0, 1, 3],
            [2, 1, 3, 0],
            [2, 3, 0, 1],
            [3, 0, 2, 1],
            [3, 1, 0, 2],
            [3, 2, 1, 0],
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
        let quaternions: Vec<Vector4<f64>> = quats
            .into_iter()
            .filter(|q| q[0] > 1e-12 || (q[0].abs() <= 1e-12 && first_nonzero_positive(q)))
            .collect();
        let rotations: Vec<SMatrix<f64, 9, 1>> = quaternions
            .iter()
            .map(|q| {
                let r = to_rotation_matrix(q);
                SMatrix::<f64, 9, 1>::from_fn(|i, _| r[(i / 3, i % 3)])
            })
            .collect();
        let mut entries = [[0.0; GRID_SIZE]; 9];
        let mut products = [[0.0; GRID_SIZE]; PRODUCTS];
        for (g, v) in rotations.iter().enumerate() {
            let mut k = 0;
            for i in 0..9 {
                entries[i][g] = v[i];
                for j in i..9 {
                    products[k][g] = v[i] * v[j];
                    k += 1;
                }
            }
        }
        Grid {
            quaternions,
            rotations,
            entries,
            products,
        }
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
    let rotation = |i: usize| Matrix3::from_row_slice(grid.rotations[i].as_slice());
    let mut picked: Vec<usize> = Vec::with_capacity(k);
    for i in order {
        if picked.len() == k {
            break;
        }
        if picked
            .iter()
            .all(|&p| rotation_distance(&rotation(p), &rotation(i)) > DISTINCT_STARTS)
        {
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
    let grid = rotation_grid();
    // Depth of the centroid at rotation v with its best translation: (R c)_z + t_z = w · v, where
    // w = (third row of to_t) + (0, …, 0, c) since the third row of R is v₆..₈.
    let w = SMatrix::<f64, 1, 9>::from_fn(|_, j| to_t[(2, j)] + if j >= 6 { centroid[j - 6] } else { 0.0 });
    let depths = grid.linear_forms(&w);
    let mut scores = grid.quadratic_forms(&reduced);
    for (score, depth) in scores.iter_mut().zip(depths) {
        if !(depth > 0.0) {
            *score += f64::MAX / 4.0;
        }
    }
    diverse_best(&scores, k)
        .into_iter()
        .map(|i| {
            let v = &grid.rotations[i];
            DualQuaternion::from_rotation_translation(&Matrix3::from_row_slice(v.as_slice()), &(to_t * v))
        })
        .collect()
}

/// Starts of the rotation-only estimator (eq. 14): up to `k` distinct grid rotations of least cost
/// under its 9x9 Gram matrix.
pub fn rotation_starts(gram9: &SMatrix<f64, 9, 9>, k: usize) -> Vec<Vector4<f64>> {
    let grid = rotation_grid();
    diverse_best(&grid.quadratic_forms(gram9), k)
        .into_iter()
        .map(|i| grid.quaternions[i])
        .collect()
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
        assert_eq!(grid.quaternions.len(), GRID_SIZE);
        let mats: Vec<Matrix3<f64>> = grid.quaternions.iter().map(to_rotation_matrix).collect();
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
            let nearest = mats
                .iter()
                .map(|m| rotation_distance(m, &r))
                .fold(f64::INFINITY, f64::min);
            assert!(nearest <= 0.777, "{nearest}");
        }
    }

    #[test]
    fn batched_forms_equal_the_direct_ones() {
        let mut rng = Rng::new(45);
        let m = SMatrix::<f64, 9, 9>::from_fn(|_, _| rng.normal());
        let a = m * m.transpose();
        let w = SMatrix::<f64, 1, 9>::from_fn(|_, _| rng.normal());
        let grid = rotation_grid();
        let (quadratic, linear) = (grid.quadratic_forms(&a), grid.linear_forms(&w));
        for (g, v) in grid.rotations.iter().enumerate() {
            let direct = v.dot(&(a * v));
            // Sums of ~81 terms of size ≤ max|A| (|v| = 3): round-off of a few ulps of that.
            assert!((quadratic[g] - direct).abs() <= 1e-13 * a.amax() * 81.0, "{g}");
            assert!((linear[g] - (w * v)[0]).abs() <= 1e-14 * w.amax() * 9.0, "{g}");
        }
    }
}
