//! The kernel shared by the minimal solvers with lines: every rotation `R` that satisfies three linear
//! constraints, the first of them rank one,
//!
//! `aᵀ R b = 0`, `⟨M₂, R⟩ = c₂`, `⟨M₃, R⟩ = c₃` (`⟨M, R⟩ = Σⱼₖ Mⱼₖ Rⱼₖ`, so `⟨a bᵀ, R⟩ = aᵀ R b`).
//!
//! For one camera `c₂ = c₃ = 0` ([`rotations`]); the rays of a rig do not meet in one centre, and the
//! offsets of its cameras leave constants `cᵢ` ([`affine_rotations`], the generalised solvers of
//! [`super::generalized`]). A constant only enters the entry of `Kᵢ` that multiplies `1 · 1` below.
//!
//! A line gives `nᵀ R d = 0` (its direction `d` lies in its interpretation plane, normal `n`), two
//! points on rays `y₁, y₂` give `(y₁ × y₂)ᵀ R (X₂ − X₁) = 0`, and eliminating a translation or a depth
//! (which enter linearly) gives a general `⟨M, R⟩ = 0`; see the solvers.
//!
//! **Elimination.** With rotations `Q₁` (`Q₁ a = e_z`) and `Q₂` (`Q₂ b = e_x`), every rotation with
//! `aᵀ R b = 0` is `R = Q₁ᵀ R_z(α) R_x(β) Q₂` for exactly one pair of angles: `R_z(α) R_x(β) e_x =
//! (cos α, sin α, 0)` ranges over the unit vectors orthogonal to `e_z`, and `β` is the rotation about
//! that vector (Dhome, Richetin, Lapresté & Rives, IEEE PAMI 11(12), 1989, and Chen, ICCV 1990, align
//! the first line the same way). Each remaining constraint is bilinear in `(cos α, sin α, 1)` and
//! `(cos β, sin β, 1)`: `(cos α, sin α, 1) Kᵢ (cos β, sin β, 1)ᵀ = 0` with `Kᵢ[p][q] = ⟨Q₁ Mᵢ Q₂ᵀ,
//! Zₚ X_q⟩` (`R_z = cos α Z_c + sin α Z_s + Z₁`, `R_x = cos β X_c + sin β X_s + X₁`). For fixed `β`
//! the vector `(cos α, sin α, 1)` is orthogonal to `r₂ = K₂ w` and `r₃ = K₃ w` (`w = (cos β, sin β,
//! 1)`), so it is parallel to `v = r₂ × r₃`, and `cos²α + sin²α = 1` is
//!
//! `f(β) = v_x² + v_y² − v_z² = 0`,
//!
//! a trigonometric polynomial of degree 4 in `β`. With `τ = tan(β/2)`, `(1 + τ²)⁴ f` is a polynomial of
//! degree 8 in `τ`, and `cot(β/2)` gives its reversal: the real roots with `|τ| ≤ 1` and those with
//! `|cot(β/2)| ≤ 1` cover every `β` on bounded intervals (no root escapes to infinity at `β = π`).
//! They are found by `real_roots_in`; each gives `α` from `v`.
//!
//! **At most 8 solutions:** the degree in `τ`. It is attained by three general rank-one constraints
//! (P3L has 8 solutions, Dhome et al. 1989); special constraints have fewer real ones (see the
//! solvers). Eight is also the degree of `SO(3)` in `ℝ³ˣ³`, so no elimination can do better for
//! three general linear constraints.
//!
//! **Polishing.** Each candidate takes up to `POLISH_STEPS` verified Newton steps on the three
//! constraints themselves (left increments `R ← exp([δ]×) R`; the system is square) and is kept if its
//! residuals are at most `RESIDUAL_TOLERANCE`. This brings the accuracy from that of the polynomial's
//! coefficients (which lose digits to cancellation) to the conditioning of the constraints.
//!
//! **Degenerate cases.** When the constraints leave a continuum of rotations (e.g. three parallel
//! lines whose planes share a line, or a constraint that vanishes), `f` vanishes identically or `v`
//! does at its roots, and no rotation is returned; when they have no solution (three parallel lines
//! with independent planes) `f` has no real root.

use super::input::unit;
use super::polynomial::{multiply, real_roots_in};
use nalgebra::{Matrix3, Rotation3, Vector3};

/// Verified Newton steps on the constraints (each kept only if it lowers the largest residual).
const POLISH_STEPS: usize = 6;

/// A polished rotation is kept if each constraint (with `a`, `b` unit and `M₂`, `M₃` of unit Frobenius
/// norm, so residuals are relative) holds to this. Genuine solutions reach rounding level, ~1e-16,
/// after the quadratically converging polish; candidates from tangencies that are not real solutions
/// stay far above it.
const RESIDUAL_TOLERANCE: f64 = 1e-9;

/// `f ≡ 0` (a continuum of rotations) when every coefficient of the degree-8 polynomial is at most this.
/// The coefficients are sums of a few hundred products of four entries of `K₂`, `K₃`, which are bounded
/// by 1 (unit-norm constraints rotated): rounding leaves at most ~1e-13 where they cancel exactly; a
/// configuration whose polynomial is that small is within ~1e-13 of degenerate in every coefficient.
const CONTINUUM_TOLERANCE: f64 = 1e-12;

/// Two polished rotations closer than this (Frobenius) are one solution found twice.
const DUPLICATE_TOLERANCE: f64 = 1e-9;

/// Every rotation `R` (3x3, acting as `x_cam = R X_world + t` does in the solvers) with `aᵀ R b = 0`,
/// `⟨m[0], R⟩ = 0` and `⟨m[1], R⟩ = 0`: zero to eight of them (see the [module documentation](self)).
/// `a`, `b` and the `m` may have any non-zero scale. A zero or non-finite input, or constraints that
/// leave a continuum of rotations, give none.
pub fn rotations(a: &Vector3<f64>, b: &Vector3<f64>, m: [Matrix3<f64>; 2]) -> Vec<Matrix3<f64>> {
    affine_rotations(a, b, m, [0.0; 2])
}

/// Every rotation `R` with `aᵀ R b = 0`, `⟨m[0], R⟩ = c[0]` and `⟨m[1], R⟩ = c[1]`: [`rotations`] with
/// constants (module documentation). A non-finite constant gives none.
pub fn affine_rotations(a: &Vector3<f64>, b: &Vector3<f64>, m: [Matrix3<f64>; 2], c: [f64; 2]) -> Vec<Matrix3<f64>> {
    let (Some(a), Some(b)) = (unit(a), unit(b)) else {
        return Vec::new();
    };
    let (a, b) = (&a, &b);
    let mut unit_m = [Matrix3::zeros(); 2];
    let mut unit_c = [0.0; 2];
    for ((u, uc), (mi, ci)) in unit_m.iter_mut().zip(&mut unit_c).zip(m.iter().zip(c)) {
        let norm = mi.norm();
        if !(norm > 0.0 && norm.is_finite() && ci.is_finite()) {
            return Vec::new();
        }
        (*u, *uc) = (mi / norm, ci / norm);
    }
    let constraints = Constraints {
        a: *a,
        b: *b,
        m: unit_m,
        c: unit_c,
    };
    let q1 = frame_with_row(a, 2);
    let q2 = frame_with_row(b, 0);
    let k: [Matrix3<f64>; 2] = std::array::from_fn(|i| {
        let mut ki = coefficient_matrix(&(q1 * unit_m[i] * q2.transpose()));
        ki[(2, 2)] -= unit_c[i];
        ki
    });
    let polynomial = resultant(&k);
    // `f` is a sum of products of four entries of the `K` (each at most 1 in magnitude): coefficients
    // that all vanish to rounding mean a continuum of rotations, and its "roots" would be noise.
    if polynomial.iter().all(|c| c.abs() <= CONTINUUM_TOLERANCE) {
        return Vec::new();
    }
    let reversed: Vec<f64> = polynomial.iter().rev().copied().collect();
    // β from τ = tan(β/2) in [−1, 1] and from u = cot(β/2) in [−1, 1], as (cos β, sin β).
    let half_angles = real_roots_in(&polynomial, -1.0, 1.0)
        .into_iter()
        .map(|t| ((1.0 - t * t) / (1.0 + t * t), 2.0 * t / (1.0 + t * t)))
        .chain(
            real_roots_in(&reversed, -1.0, 1.0)
                .into_iter()
                .map(|u| ((u * u - 1.0) / (u * u + 1.0), 2.0 * u / (u * u + 1.0))),
        );
    let mut out: Vec<Matrix3<f64>> = Vec::with_capacity(8);
    for (cb, sb) in half_angles {
        let w = Vector3::new(cb, sb, 1.0);
        let v = (k[0] * w).cross(&(k[1] * w));
        let planar = v.x.hypot(v.y);
        if !(planar > 0.0 && planar.is_finite()) || v.z == 0.0 {
            continue;
        }
        let (ca, sa) = (v.x / planar * v.z.signum(), v.y / planar * v.z.signum());
        let rz = Matrix3::new(ca, -sa, 0.0, sa, ca, 0.0, 0.0, 0.0, 1.0);
        let rx = Matrix3::new(1.0, 0.0, 0.0, 0.0, cb, -sb, 0.0, sb, cb);
        let Some(r) = constraints.polish(q1.transpose() * rz * rx * q2) else {
            continue;
        };
        if !out.iter().any(|s| (s - r).norm() <= DUPLICATE_TOLERANCE) {
            out.push(r);
        }
    }
    out
}

/// A rotation (rows orthonormal, determinant +1) whose row `row` is the unit vector `n`, so that it
/// maps `n` to the `row`-th axis.
fn frame_with_row(n: &Vector3<f64>, row: usize) -> Matrix3<f64> {
    let axis = (0..3).min_by(|&i, &j| n[i].abs().total_cmp(&n[j].abs())).unwrap_or(0);
    let u = n.cross(&Vector3::ith(axis, 1.0)).normalize();
    let v = n.cross(&u);
    // Rows (n, u, v), (v, n, u) or (u, v, n): cyclic, so right-handed (u × v = n).
    let rows = match row {
        0 => [*n, u, v],
        1 => [v, *n, u],
        _ => [u, v, *n],
    };
    Matrix3::from_rows(&rows.map(|r| r.transpose()))
}

/// `K[p][q] = ⟨M', Zₚ X_q⟩` for `R_z(α) = Σₚ (cos α, sin α, 1)ₚ Zₚ` and `R_x(β) = Σ_q (cos β, sin β, 1)_q X_q`.
fn coefficient_matrix(m: &Matrix3<f64>) -> Matrix3<f64> {
    // Zₚ X_q has few non-zero entries; written out: R_z R_x =
    // [[cα, −sα cβ, sα sβ], [sα, cα cβ, −cα sβ], [0, sβ, cβ]].
    // Rows (cos α, sin α, 1), columns (cos β, sin β, 1).
    Matrix3::new(
        m[(1, 1)],
        -m[(1, 2)],
        m[(0, 0)],
        -m[(0, 1)],
        m[(0, 2)],
        m[(1, 0)],
        m[(2, 2)],
        m[(2, 1)],
        0.0,
    )
}

/// `(1 + τ²)⁴ f(β)` as a polynomial in `τ = tan(β/2)` (degree 8, lowest first), with
/// `(1 + τ²) (cos β, sin β, 1) = (1 − τ², 2τ, 1 + τ²)`.
fn resultant(k: &[Matrix3<f64>; 2]) -> Vec<f64> {
    const W: [[f64; 3]; 3] = [[1.0, 0.0, -1.0], [0.0, 2.0, 0.0], [1.0, 0.0, 1.0]];
    // r[i][row] = Σ_q K_i[row][q] W[q]: a quadratic in τ.
    let r = k.map(|ki| {
        let mut rows = [[0.0; 3]; 3];
        for (row, out) in rows.iter_mut().enumerate() {
            for (q, wq) in W.iter().enumerate() {
                for d in 0..3 {
                    out[d] += ki[(row, q)] * wq[d];
                }
            }
        }
        rows
    });
    let cross = |i: usize, j: usize| -> Vec<f64> {
        let (p, q) = (multiply(&r[0][i], &r[1][j]), multiply(&r[0][j], &r[1][i]));
        p.iter().zip(&q).map(|(x, y)| x - y).collect()
    };
    let v = [cross(1, 2), cross(2, 0), cross(0, 1)];
    let (xx, yy, zz) = (multiply(&v[0], &v[0]), multiply(&v[1], &v[1]), multiply(&v[2], &v[2]));
    (0..xx.len()).map(|d| xx[d] + yy[d] - zz[d]).collect()
}

/// The three constraints, normalised (`a`, `b` unit, `M` unit Frobenius norm, `c` divided by the same).
struct Constraints {
    a: Vector3<f64>,
    b: Vector3<f64>,
    m: [Matrix3<f64>; 2],
    c: [f64; 2],
}

impl Constraints {
    fn residuals(&self, r: &Matrix3<f64>) -> Vector3<f64> {
        Vector3::new(
            self.a.dot(&(r * self.b)),
            self.m[0].dot(r) - self.c[0],
            self.m[1].dot(r) - self.c[1],
        )
    }

    /// Rows: the derivative of each constraint along `R ← (I + [δ]×) R`. For `⟨M, [δ]× R⟩ = ⟨M Rᵀ, [δ]×⟩`
    /// with `A = M Rᵀ`, the row is `(A₂₁ − A₁₂, A₀₂ − A₂₀, A₁₀ − A₀₁)`.
    fn jacobian(&self, r: &Matrix3<f64>) -> Matrix3<f64> {
        let row = |a: Matrix3<f64>| {
            Vector3::new(a[(2, 1)] - a[(1, 2)], a[(0, 2)] - a[(2, 0)], a[(1, 0)] - a[(0, 1)]).transpose()
        };
        let first = self.a * (r * self.b).transpose();
        Matrix3::from_rows(&[
            row(first),
            row(self.m[0] * r.transpose()),
            row(self.m[1] * r.transpose()),
        ])
    }

    /// Verified Newton steps; the rotation if its residuals end within `RESIDUAL_TOLERANCE`.
    fn polish(&self, mut r: Matrix3<f64>) -> Option<Matrix3<f64>> {
        let mut residual = self.residuals(&r);
        let mut size = residual.amax();
        for _ in 0..POLISH_STEPS {
            if !(size > 0.0) {
                break;
            }
            let Some(inverse) = self.jacobian(&r).try_inverse() else {
                break;
            };
            let next = Rotation3::new(-(inverse * residual)).into_inner() * r;
            let next_residual = self.residuals(&next);
            if !(next_residual.amax() < size) {
                break;
            }
            (r, residual, size) = (next, next_residual, next_residual.amax());
        }
        (size <= RESIDUAL_TOLERANCE && r.iter().all(|v| v.is_finite())).then_some(r)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    #[test]
    fn the_parametrisation_covers_the_first_constraint_and_the_coefficients_match() {
        // For random (a, b, M, α, β): R = Q₁ᵀ R_z R_x Q₂ satisfies aᵀRb = 0, and ⟨M, R⟩ equals the
        // bilinear form of K, and f(β) the resultant polynomial, to rounding.
        let mut rng = Rng::new(6_100);
        for _ in 0..200 {
            let (a, b) = (rng.unit_vector3(), rng.unit_vector3());
            let m = [
                Matrix3::from_fn(|_, _| rng.normal()),
                Matrix3::from_fn(|_, _| rng.normal()),
            ];
            let (q1, q2) = (frame_with_row(&a, 2), frame_with_row(&b, 0));
            for q in [q1, q2] {
                assert!(
                    (q * q.transpose() - Matrix3::identity()).amax() < 1e-15 && (q.determinant() - 1.0).abs() < 1e-15
                );
            }
            let (alpha, beta) = (rng.uniform_in(-3.2, 3.2), rng.uniform_in(-3.2, 3.2));
            let r = q1.transpose()
                * Rotation3::from_axis_angle(&Vector3::z_axis(), alpha).into_inner()
                * Rotation3::from_axis_angle(&Vector3::x_axis(), beta).into_inner()
                * q2;
            assert!(a.dot(&(r * b)).abs() < 1e-15);
            let k = m.map(|mi| coefficient_matrix(&(q1 * mi * q2.transpose())));
            let (x, w) = (
                Vector3::new(alpha.cos(), alpha.sin(), 1.0),
                Vector3::new(beta.cos(), beta.sin(), 1.0),
            );
            for (ki, mi) in k.iter().zip(&m) {
                assert!((x.dot(&(ki * w)) - mi.dot(&r)).abs() < 1e-14 * mi.norm());
            }
            let v = (k[0] * w).cross(&(k[1] * w));
            let f = v.x * v.x + v.y * v.y - v.z * v.z;
            let tau = (beta / 2.0).tan();
            let p = resultant(&k);
            assert_eq!(p.len(), 9);
            let value = super::super::polynomial::evaluate(&p, tau) / (1.0 + tau * tau).powi(4);
            let scale = p.iter().map(|c| c.abs()).sum::<f64>() * (1.0 + tau.abs()).powi(8) / (1.0 + tau * tau).powi(4);
            assert!((value - f).abs() < 1e-13 * scale, "{value} {f}");
        }
    }
}
