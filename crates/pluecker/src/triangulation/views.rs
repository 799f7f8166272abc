//! The known cameras of a triangulation: validation, centres and depths.
//!
//! A camera is a 3x4 matrix `P = [M | p₄]` mapping a world point to pixels, `λ (u, v, 1)ᵀ = P (X, 1)ᵀ`
//! (eq. 1). Its scale and sign are arbitrary; the depth of a point is
//! `depth(P, X) = sign(det M) (P X̃)₃ / ‖m³‖` (Hartley & Zisserman, eq. 6.15), positive in front of
//! the camera and in the unit of the world. Only finite cameras (`det M ≠ 0`) are accepted.

use crate::error::{Error, Result};
use nalgebra::{Matrix3, Matrix3x4, Vector3, Vector4};

/// Relative size of `det M` (against `‖M‖³`) below which a camera is rejected as singular.
const MIN_RELATIVE_DET: f64 = 1e-12;

/// Checks every camera: finite entries and a finite centre (`det M ≠ 0`).
pub fn validate_cameras(cameras: &[Matrix3x4<f64>], what: &str) -> Result<()> {
    for (i, p) in cameras.iter().enumerate() {
        if p.iter().any(|v| !v.is_finite()) {
            return Err(Error::NonFinite { what: what.into(), index: i });
        }
        let m: Matrix3<f64> = p.fixed_view::<3, 3>(0, 0).into_owned();
        let norm = m.norm();
        if !(m.determinant().abs() > MIN_RELATIVE_DET * norm * norm * norm) {
            return Err(Error::SingularCamera {
                what: format!("{what}[{i}]: the left 3x3 block of P is singular (a camera at infinity or a zero matrix)"),
            });
        }
    }
    Ok(())
}

/// The centre `C` of a finite camera, `P (C, 1)ᵀ = 0`.
pub fn centre(p: &Matrix3x4<f64>) -> Vector3<f64> {
    let m: Matrix3<f64> = p.fixed_view::<3, 3>(0, 0).into_owned();
    let p4: Vector3<f64> = p.column(3).into_owned();
    -(m.try_inverse().unwrap_or_else(Matrix3::zeros) * p4)
}

/// The depth of world point `x` in front of camera `p` (see the module docs), world units.
pub fn depth(p: &Matrix3x4<f64>, x: &Vector3<f64>) -> f64 {
    let m: Matrix3<f64> = p.fixed_view::<3, 3>(0, 0).into_owned();
    let w = p.row(2).dot(&Vector4::new(x.x, x.y, x.z, 1.0).transpose());
    m.determinant().signum() * w / m.row(2).norm()
}

/// The camera scaled so that its third row gives the depth: `P / (sign(det M) ‖m³‖)`. Then
/// `(P X̃)₃ = depth(P, X)` and the pixels are unchanged.
pub fn depth_normalized(p: &Matrix3x4<f64>) -> Matrix3x4<f64> {
    let m: Matrix3<f64> = p.fixed_view::<3, 3>(0, 0).into_owned();
    p / (m.determinant().signum() * m.row(2).norm())
}

/// Largest distance between two camera centres: zero parallax when it is (relatively) zero.
pub fn baseline(cameras: &[Matrix3x4<f64>]) -> f64 {
    let centres: Vec<Vector3<f64>> = cameras.iter().map(centre).collect();
    let mut widest: f64 = 0.0;
    for (i, a) in centres.iter().enumerate() {
        for b in &centres[i + 1..] {
            widest = widest.max((a - b).norm());
        }
    }
    widest
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera(scale: f64) -> Matrix3x4<f64> {
        // K [R | t] with R = I, t = (0.5, 0, 4), then scaled (the sign of P is arbitrary).
        let k = Matrix3::new(800.0, 0.0, 320.0, 0.0, 800.0, 240.0, 0.0, 0.0, 1.0);
        let rt = Matrix3x4::new(1.0, 0.0, 0.0, 0.5, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 4.0);
        k * rt * scale
    }

    #[test]
    fn depth_and_centre_do_not_depend_on_the_scale_of_p() {
        let x = Vector3::new(0.1, -0.2, 1.0);
        for scale in [1.0, -3.0, 1e-4] {
            let p = camera(scale);
            assert!((depth(&p, &x) - 5.0).abs() < 1e-12);
            assert!((centre(&p) - Vector3::new(-0.5, 0.0, -4.0)).norm() < 1e-12);
            let pn = depth_normalized(&p);
            assert!(((pn * Vector4::new(x.x, x.y, x.z, 1.0))[2] - 5.0).abs() < 1e-12);
        }
        assert!(validate_cameras(&[camera(1.0)], "P").is_ok());
        assert!(validate_cameras(&[Matrix3x4::zeros()], "P").is_err());
    }
}
