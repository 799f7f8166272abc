//! The known cameras of a triangulation: validation, centres and depths.
//!
//! A camera is a 3x4 matrix `P = [M | p₄]` mapping a world point to pixels, `λ (u, v, 1)ᵀ = P (X, 1)ᵀ`
//! (eq. 1), and a point is **in front** of it when `λ = (P X̃)₃ > 0` for the matrix as given. Its
//! positive scale is arbitrary; its sign is not: `P` and `−P` see opposite half-spaces. For
//! `P = K [R | t]` with `K₃₃ > 0` this is `z_cam > 0`, the pose convention, whatever the signs of
//! `fx`, `fy` (the pose paper's `α_u = −1730.3`) and of `det R` (a left-handed world frame, as in the
//! raw VGG files). Hartley & Zisserman's `sign(det M) (P X̃)₃` (eq. 6.15) is the same test when
//! `det M > 0`, and wrong for those cameras, whose `det M` is negative with every point in front.
//! The depth of a point is `depth(P, X) = (P X̃)₃ / ‖m³‖`, positive in front and in world units.
//! Only finite cameras (`det M ≠ 0`) are accepted.
//!
//! A [`View`] is the other form of a known camera: the camera itself ([`Camera`], a pinhole or any
//! of COLMAP's models) and its pose. Through a lens with distortion the observations are the image's
//! own (distorted) pixels; `P = K [R | t]` is the view of a pinhole camera.

use crate::camera::Camera;
use crate::camera_pose::Pose;
use crate::error::{Error, Result};
use nalgebra::{Matrix3, Matrix3x4, Vector3, Vector4};

/// A known camera with its pose, `x_cam = R X_world + t` (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct View {
    /// The camera: a pinhole or any of COLMAP's models.
    pub camera: Camera,
    /// Its pose.
    pub pose: Pose,
}

impl View {
    /// The view of `camera` at `pose`.
    pub fn new(camera: Camera, pose: Pose) -> View {
        View { camera, pose }
    }

    /// The pinhole view of a finite 3x4 projection `P = s K [R | t]` (any positive scale `s`): `K`
    /// upper triangular with `K₃₃ = 1` and `fy > 0`, `R` a rotation (`det R = +1`), so that a point is
    /// in front of the view exactly when it is in front of `P` (module docs). A `P` whose left block has
    /// `det M < 0` (a left-handed world frame) gives `fx < 0`, a mirrored axis. PINHOLE when the skew
    /// is within rounding of 0 (`|skew| ≤ 1e-12 max(|fx|, |fy|)`, taken as 0), else SKEWED_PINHOLE. `Error::NonFinite` / `Error::SingularCamera` as the
    /// cameras' validation (`what` names the argument).
    pub fn from_projection(p: &Matrix3x4<f64>, what: &str) -> Result<View> {
        validate_cameras(std::slice::from_ref(p), what)?;
        let m: Matrix3<f64> = p.fixed_view::<3, 3>(0, 0).into_owned();
        let (m1, m2, m3) = (m.row(0).transpose(), m.row(1).transpose(), m.row(2).transpose());
        // Rows of M = s K R, from the last: m₃ = s r₃, m₂ = s (fy r₂ + cy r₃),
        // m₁ = s (fx r₁ + skew r₂ + cx r₃), with r₁ = r₂ × r₃ (a rotation).
        let s = m3.norm();
        let r3 = m3 / s;
        let cy = m2.dot(&r3);
        let fy_r2 = m2 - cy * r3;
        let fy = fy_r2.norm();
        let r2 = fy_r2 / fy;
        let r1 = r2.cross(&r3);
        let (cx, skew) = (m1.dot(&r3), m1.dot(&r2));
        let fx = m1.dot(&r1);
        // The rounding of a zero skew: the decomposition of K [R | t] with skew 0 leaves ~1e-16 fx.
        let skew = if skew.abs() <= SKEW_ROUNDING * fx.abs().max(fy) {
            0.0
        } else {
            skew
        };
        let rotation = Matrix3::from_rows(&[r1.transpose(), r2.transpose(), r3.transpose()]);
        let k = Matrix3::new(fx, skew, cx, 0.0, fy, cy, 0.0, 0.0, s) / s;
        let singular = || Error::SingularCamera {
            what: format!("{what}: K of P is singular"),
        };
        let translation = k.try_inverse().ok_or_else(singular)? * (p.column(3) / s);
        let camera = Camera::from_matrix(&k).map_err(|e| match e {
            Error::SingularCamera { what: why } => Error::SingularCamera {
                what: format!("{what}: {why}"),
            },
            other => other,
        })?;
        Ok(View::new(camera, Pose::new(rotation, translation)))
    }

    /// `P = K [R | t]` of the camera's pinhole part ([`Camera::projection`]).
    pub fn projection(&self) -> Matrix3x4<f64> {
        self.camera.projection(&self.pose)
    }
}

/// Relative size of a skew (against the focal lengths) that [`View::from_projection`] takes as the
/// rounding of 0.
const SKEW_ROUNDING: f64 = 1e-12;

/// The known cameras of a triangulation: 3x4 projections `P` (world → pixels), or [`View`]s (a
/// camera, pinhole or any of COLMAP's models, and its pose; the observations are then the images' own,
/// distorted pixels). Every slice of either converts into it, so calls read
/// `triangulate_point(&projections, …)` or `triangulate_point(&views, …)`.
#[derive(Debug, Clone, Copy)]
pub enum Cameras<'a> {
    /// 3x4 matrices `P` (module docs; errors name them `projections`).
    Projections(&'a [Matrix3x4<f64>]),
    /// Cameras with their poses.
    Views(&'a [View]),
}

impl Cameras<'_> {
    /// The number of cameras.
    pub fn len(&self) -> usize {
        match self {
            Cameras::Projections(p) => p.len(),
            Cameras::Views(v) => v.len(),
        }
    }

    /// Whether there is no camera.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

macro_rules! cameras_from {
    ($item:ty, $variant:ident) => {
        impl<'a> From<&'a [$item]> for Cameras<'a> {
            fn from(cameras: &'a [$item]) -> Self {
                Cameras::$variant(cameras)
            }
        }
        impl<'a> From<&'a Vec<$item>> for Cameras<'a> {
            fn from(cameras: &'a Vec<$item>) -> Self {
                Cameras::$variant(cameras)
            }
        }
        impl<'a, const N: usize> From<&'a [$item; N]> for Cameras<'a> {
            fn from(cameras: &'a [$item; N]) -> Self {
                Cameras::$variant(cameras)
            }
        }
    };
}
cameras_from!(Matrix3x4<f64>, Projections);
cameras_from!(View, Views);

/// Relative size of `det M` (against `‖M‖³`) below which a camera is rejected as singular.
const MIN_RELATIVE_DET: f64 = 1e-12;

/// Checks every camera: finite entries and a finite centre (`det M ≠ 0`).
pub(crate) fn validate_cameras(cameras: &[Matrix3x4<f64>], what: &str) -> Result<()> {
    for (i, p) in cameras.iter().enumerate() {
        if p.iter().any(|v| !v.is_finite()) {
            return Err(Error::NonFinite {
                what: what.into(),
                index: i,
            });
        }
        let m: Matrix3<f64> = p.fixed_view::<3, 3>(0, 0).into_owned();
        let norm = m.norm();
        if !(m.determinant().abs() > MIN_RELATIVE_DET * norm * norm * norm) {
            return Err(Error::SingularCamera {
                what: format!(
                    "{what}[{i}]: the left 3x3 block of P is singular (a camera at infinity or a zero matrix)"
                ),
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
    let w = p.row(2).dot(&Vector4::new(x.x, x.y, x.z, 1.0).transpose());
    w / principal_row_norm(p)
}

/// The camera scaled so that its third row gives the depth: `P / ‖m³‖` (a positive scale, so the
/// side that is in front is kept). Then `(P X̃)₃ = depth(P, X)` and the pixels are unchanged.
pub fn depth_normalized(p: &Matrix3x4<f64>) -> Matrix3x4<f64> {
    p / principal_row_norm(p)
}

/// `‖m³‖`, the norm of the first three entries of the third row of `P` (non-zero for a finite camera).
fn principal_row_norm(p: &Matrix3x4<f64>) -> f64 {
    p.fixed_view::<1, 3>(2, 0).norm()
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
    fn depth_and_centre_do_not_depend_on_the_positive_scale_of_p() {
        let x = Vector3::new(0.1, -0.2, 1.0);
        for scale in [1.0, 3.0, 1e-4] {
            let p = camera(scale);
            assert!((depth(&p, &x) - 5.0).abs() < 1e-12);
            assert!((centre(&p) - Vector3::new(-0.5, 0.0, -4.0)).norm() < 1e-12);
            let pn = depth_normalized(&p);
            assert!(((pn * Vector4::new(x.x, x.y, x.z, 1.0))[2] - 5.0).abs() < 1e-12);
            // −P: the same centre and pixels, the opposite side in front.
            assert!((depth(&-p, &x) + 5.0).abs() < 1e-12);
            assert!((centre(&-p) - centre(&p)).norm() < 1e-12);
        }
        assert!(validate_cameras(&[camera(1.0)], "P").is_ok());
        assert!(validate_cameras(&[Matrix3x4::zeros()], "P").is_err());
    }

    #[test]
    fn a_negative_focal_length_or_a_left_handed_world_keeps_z_cam_as_the_depth() {
        // det M < 0 both ways; the depth is still z_cam = 5 (Hartley-Zisserman's sign(det M)
        // (P X̃)₃ would say −5).
        let x = Vector3::new(0.1, -0.2, 1.0);
        let flip_fx = Matrix3::from_diagonal(&Vector3::new(-1.0, 1.0, 1.0));
        let mirror_world = nalgebra::Matrix4::from_diagonal(&Vector4::new(1.0, 1.0, -1.0, 1.0));
        for p in [flip_fx * camera(1.0), camera(1.0) * mirror_world] {
            let m: Matrix3<f64> = p.fixed_view::<3, 3>(0, 0).into_owned();
            assert!(m.determinant() < 0.0);
            let seen = if p[(2, 2)] > 0.0 {
                x
            } else {
                Vector3::new(x.x, x.y, -x.z)
            };
            assert!((depth(&p, &seen) - 5.0).abs() < 1e-12, "{}", depth(&p, &seen));
        }
    }

    #[test]
    fn a_view_from_a_projection_projects_as_the_projection_does() {
        let rotation = *nalgebra::Rotation3::from_scaled_axis(Vector3::new(0.3, -0.5, 0.2)).matrix();
        let translation = Vector3::new(0.4, -0.1, 6.0);
        let mut rt = Matrix3x4::zeros();
        rt.fixed_view_mut::<3, 3>(0, 0).copy_from(&rotation);
        rt.set_column(3, &translation);
        let mirror_world = nalgebra::Matrix4::from_diagonal(&Vector4::new(1.0, 1.0, -1.0, 1.0));
        let x = Vector3::new(0.2, 0.3, -0.4);
        for (k, skew_model) in [
            (Matrix3::new(800.0, 0.0, 320.0, 0.0, 780.0, 240.0, 0.0, 0.0, 1.0), false),
            (
                Matrix3::new(-1730.3, 2.5, 243.8, 0.0, 1220.7, 241.2, 0.0, 0.0, 1.0),
                true,
            ),
        ] {
            for (p, scale) in [
                (k * rt * 3.0, 3.0),
                (k * rt * mirror_world * 0.01, 0.01),
                (-(k * rt), 1.0),
            ] {
                let view = View::from_projection(&p, "P").unwrap();
                let r = view.pose.rotation;
                assert!((r.transpose() * r - Matrix3::identity()).norm() < 1e-12);
                assert!((r.determinant() - 1.0).abs() < 1e-12);
                // The view's own P = K [R | t] is P divided by its positive scale.
                let rebuilt = view.projection();
                assert!(
                    (rebuilt - p / scale).norm() < 1e-9 * (p / scale).norm(),
                    "{rebuilt} {p}"
                );
                assert_eq!(
                    view.camera.model() == crate::camera::CameraModel::SkewedPinhole,
                    skew_model
                );
                // The same pixel and the same side in front.
                let h = p * x.push(1.0);
                let x_cam = view.pose.transform(&x);
                let u = view.camera.project(&x_cam);
                assert!((u - nalgebra::Vector2::new(h.x / h.z, h.y / h.z)).norm() < 1e-9);
                assert_eq!(x_cam.z > 0.0, h.z > 0.0);
            }
        }
        assert!(View::from_projection(&Matrix3x4::zeros(), "views[3]").is_err());
    }
}
