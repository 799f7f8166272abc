//! Quaternions as plain 4-vectors `(r0, rx, ry, rz)`, with the product matrices of
//! Phong & Horaud 1995, eqs. 8-9.
//!
//! `Q(a) b` is the product `a b` (left multiplication by `a`), `W(b) a` is the same product seen as a
//! right multiplication by `b`, hence the identity `Q(a) b = W(b) a` (eq. 11). A 3-vector `v` is the
//! purely imaginary quaternion `(0, v)`. For a unit quaternion `r`, `W(r)ᵀ Q(r) = diag(1, R)` (eq. 6).

use nalgebra::{Matrix3, Matrix4, Vector3, Vector4};

/// The purely imaginary quaternion `(0, v)`.
pub fn pure(v: &Vector3<f64>) -> Vector4<f64> {
    Vector4::new(0.0, v.x, v.y, v.z)
}

/// The vector (imaginary) part.
pub fn vector_part(q: &Vector4<f64>) -> Vector3<f64> {
    Vector3::new(q[1], q[2], q[3])
}

/// `Q(r)` of eq. 8: `Q(r) b = r b`.
pub fn q_matrix(r: &Vector4<f64>) -> Matrix4<f64> {
    let (r0, x, y, z) = (r[0], r[1], r[2], r[3]);
    Matrix4::new(
        r0, -x, -y, -z, //
        x, r0, -z, y, //
        y, z, r0, -x, //
        z, -y, x, r0,
    )
}

/// `W(r)` of eq. 9: `W(r) a = a r`.
pub fn w_matrix(r: &Vector4<f64>) -> Matrix4<f64> {
    let (r0, x, y, z) = (r[0], r[1], r[2], r[3]);
    Matrix4::new(
        r0, -x, -y, -z, //
        x, r0, z, -y, //
        y, -z, r0, x, //
        z, y, -x, r0,
    )
}

/// The Hamilton product `a b`.
pub fn multiply(a: &Vector4<f64>, b: &Vector4<f64>) -> Vector4<f64> {
    q_matrix(a) * b
}

/// The conjugate `(a0, -a)`.
pub fn conjugate(a: &Vector4<f64>) -> Vector4<f64> {
    Vector4::new(a[0], -a[1], -a[2], -a[3])
}

/// `R̃(r)`: the lower-right 3x3 block of `W(r)ᵀ Q(r)` (eq. 6) for *any* 4-vector `r`.
///
/// It is homogeneous quadratic in `r` and equals `|r|² R(r/|r|)`; for a unit `r` it is the rotation.
/// The dual-quaternion costs are written in terms of it (see `pose::algebraic`).
pub fn scaled_rotation(r: &Vector4<f64>) -> Matrix3<f64> {
    let (w, x, y, z) = (r[0], r[1], r[2], r[3]);
    let (ww, xx, yy, zz) = (w * w, x * x, y * y, z * z);
    Matrix3::new(
        ww + xx - yy - zz,
        2.0 * (x * y - w * z),
        2.0 * (x * z + w * y),
        2.0 * (x * y + w * z),
        ww - xx + yy - zz,
        2.0 * (y * z - w * x),
        2.0 * (x * z - w * y),
        2.0 * (y * z + w * x),
        ww - xx - yy + zz,
    )
}

/// The rotation matrix of a non-zero quaternion (normalised first).
pub fn to_rotation_matrix(r: &Vector4<f64>) -> Matrix3<f64> {
    scaled_rotation(r) / r.norm_squared()
}

/// The unit quaternion of a rotation matrix, with `r0 ≥ 0` (Shepperd's method, stable for all angles).
pub fn from_rotation_matrix(m: &Matrix3<f64>) -> Vector4<f64> {
    let tr = m.trace();
    let q = if tr > m[(0, 0)].max(m[(1, 1)]).max(m[(2, 2)]) {
        let s = 2.0 * (1.0 + tr).sqrt();
        Vector4::new(
            0.25 * s,
            (m[(2, 1)] - m[(1, 2)]) / s,
            (m[(0, 2)] - m[(2, 0)]) / s,
            (m[(1, 0)] - m[(0, 1)]) / s,
        )
    } else if m[(0, 0)] >= m[(1, 1)] && m[(0, 0)] >= m[(2, 2)] {
        let s = 2.0 * (1.0 + m[(0, 0)] - m[(1, 1)] - m[(2, 2)]).sqrt();
        Vector4::new(
            (m[(2, 1)] - m[(1, 2)]) / s,
            0.25 * s,
            (m[(0, 1)] + m[(1, 0)]) / s,
            (m[(0, 2)] + m[(2, 0)]) / s,
        )
    } else if m[(1, 1)] >= m[(2, 2)] {
        let s = 2.0 * (1.0 + m[(1, 1)] - m[(0, 0)] - m[(2, 2)]).sqrt();
        Vector4::new(
            (m[(0, 2)] - m[(2, 0)]) / s,
            (m[(0, 1)] + m[(1, 0)]) / s,
            0.25 * s,
            (m[(1, 2)] + m[(2, 1)]) / s,
        )
    } else {
        let s = 2.0 * (1.0 + m[(2, 2)] - m[(0, 0)] - m[(1, 1)]).sqrt();
        Vector4::new(
            (m[(1, 0)] - m[(0, 1)]) / s,
            (m[(0, 2)] + m[(2, 0)]) / s,
            (m[(1, 2)] + m[(2, 1)]) / s,
            0.25 * s,
        )
    };
    let q = q.normalize();
    if q[0] < 0.0 {
        -q
    } else {
        q
    }
}

/// The unit quaternion `(cos φ/2, sin φ/2 axis)` of a rotation by `angle` radians about `axis`
/// (normalised first).
pub fn from_axis_angle(axis: &Vector3<f64>, angle: f64) -> Vector4<f64> {
    let a = axis.normalize();
    let (s, c) = (0.5 * angle).sin_cos();
    Vector4::new(c, s * a.x, s * a.y, s * a.z)
}

/// Unit axis and angle in `[0, π]` of a non-zero quaternion. For the identity the axis is `(0, 0, 1)`.
pub fn axis_angle(r: &Vector4<f64>) -> (Vector3<f64>, f64) {
    let r = if r[0] < 0.0 { -r.normalize() } else { r.normalize() };
    let v = vector_part(&r);
    let s = v.norm();
    if s < 1e-15 {
        return (Vector3::z(), 0.0);
    }
    (v / s, 2.0 * s.atan2(r[0]))
}

/// Rotation vector (axis × angle, radians) → rotation matrix (Rodrigues' formula).
pub fn exp_so3(w: &Vector3<f64>) -> Matrix3<f64> {
    let theta = w.norm();
    if theta < 1e-12 {
        return Matrix3::identity() + skew(w);
    }
    // The unit quaternion (cos θ/2, sin θ/2 · w/θ), unit to rounding: no normalisation needed.
    let (s, c) = (0.5 * theta).sin_cos();
    let v = w * (s / theta);
    scaled_rotation(&Vector4::new(c, v.x, v.y, v.z))
}

/// Rotation matrix → rotation vector (axis × angle, angle in `[0, π]`).
pub fn log_so3(m: &Matrix3<f64>) -> Vector3<f64> {
    let (axis, angle) = axis_angle(&from_rotation_matrix(m));
    axis * angle
}

/// The cross-product matrix `[v]ₓ` with `[v]ₓ w = v × w`.
pub fn skew(v: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}

/// The angle in radians between two rotations, `|log(R_a R_bᵀ)|`.
pub fn rotation_distance(a: &Matrix3<f64>, b: &Matrix3<f64>) -> f64 {
    log_so3(&(a * b.transpose())).norm()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    fn random_quaternion(rng: &mut Rng) -> Vector4<f64> {
        Vector4::new(rng.normal(), rng.normal(), rng.normal(), rng.normal())
    }

    #[test]
    fn eq11_q_of_a_times_b_equals_w_of_b_times_a() {
        let mut rng = Rng::new(11);
        for _ in 0..100 {
            let (a, b) = (random_quaternion(&mut rng), random_quaternion(&mut rng));
            assert!((q_matrix(&a) * b - w_matrix(&b) * a).norm() < 1e-12);
            // The product agrees with nalgebra's Hamilton product.
            let na = nalgebra::Quaternion::new(a[0], a[1], a[2], a[3]);
            let nb = nalgebra::Quaternion::new(b[0], b[1], b[2], b[3]);
            let p = na * nb;
            assert!((multiply(&a, &b) - Vector4::new(p.w, p.i, p.j, p.k)).norm() < 1e-12);
        }
    }

    #[test]
    fn eq6_w_transpose_q_is_diag_norm_and_scaled_rotation() {
        let mut rng = Rng::new(6);
        for _ in 0..100 {
            let r = random_quaternion(&mut rng);
            let m = w_matrix(&r).transpose() * q_matrix(&r);
            let rt = scaled_rotation(&r);
            assert!((m[(0, 0)] - r.norm_squared()).abs() < 1e-12);
            for i in 0..3 {
                assert!(m[(0, i + 1)].abs() < 1e-12 && m[(i + 1, 0)].abs() < 1e-12);
                for j in 0..3 {
                    assert!((m[(i + 1, j + 1)] - rt[(i, j)]).abs() < 1e-12);
                }
            }
            let rot = to_rotation_matrix(&r);
            assert!((rot * rot.transpose() - Matrix3::identity()).norm() < 1e-12);
            assert!((rot.determinant() - 1.0).abs() < 1e-12);
            // Sandwich product r v r̄ rotates v.
            let v = Vector3::new(rng.normal(), rng.normal(), rng.normal());
            let rn = r.normalize();
            let rotated = multiply(&multiply(&rn, &pure(&v)), &conjugate(&rn));
            assert!((vector_part(&rotated) - rot * v).norm() < 1e-12);
        }
    }

    #[test]
    fn rotation_matrix_axis_angle_round_trips() {
        let mut rng = Rng::new(3);
        for i in 0..200 {
            let axis = rng.unit_vector3();
            // Include angles near 0 and near π, where naive conversions break.
            let angle = match i % 4 {
                0 => 1e-9,
                1 => std::f64::consts::PI - 1e-9,
                _ => rng.uniform_in(0.0, std::f64::consts::PI),
            };
            let r = from_axis_angle(&axis, angle);
            let m = to_rotation_matrix(&r);
            let back = from_rotation_matrix(&m);
            assert!((back - r).norm() < 1e-7 || (back + r).norm() < 1e-7, "angle {angle}");
            assert!((to_rotation_matrix(&back) - m).norm() < 1e-12);
            let (a2, ang2) = axis_angle(&r);
            assert!((ang2 - angle).abs() < 1e-9);
            if angle > 1e-6 {
                assert!((a2 - axis).norm() < 1e-6);
            }
            assert!((exp_so3(&log_so3(&m)) - m).norm() < 1e-9);
        }
    }
}
