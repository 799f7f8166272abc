//! [`Intrinsics`]: the pinhole part `K` of a camera; its projection, pixels ↔ normalised coordinates.
//!
//! Conventions used throughout pluecker:
//! - a world point `X_world` maps to the camera frame by `x_cam = R X_world + t`;
//! - the camera looks down its +z axis; a point is in front of the camera when `z > 0`;
//! - pixels are `u = K x_cam / z` with
//!   `K = [[fx, skew, cx], [0, fy, cy], [0, 0, 1]]`;
//! - normalised image coordinates are `(x, y) = (X/Z, Y/Z)`, i.e. `K⁻¹ (u, v, 1)`.
//!
//! The paper's own camera (Phong & Horaud 1995, section 2 and Table 1) has `α_u = fx < 0`: a mirrored
//! image axis. Nothing here assumes positive focal lengths; only a zero (singular) one is rejected.

use crate::camera_pose::Pose;
use crate::error::{number, Error, Result};
use nalgebra::{Matrix3, Matrix3x4, Vector2, Vector3};

/// The pinhole part `K` of a camera ([`crate::camera::Camera::intrinsics`]), pixels. `fx` and `fy` may be
/// negative (mirrored axes), never zero.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Intrinsics {
    /// Focal length along u, pixels (the paper's α_u).
    pub fx: f64,
    /// Focal length along v, pixels (the paper's α_v).
    pub fy: f64,
    /// Principal point u, pixels (u_0).
    pub cx: f64,
    /// Principal point v, pixels (v_0).
    pub cy: f64,
    /// Skew, pixels (0 for square-pixel sensors).
    pub skew: f64,
}

/// Smallest |fx|, |fy| accepted: below this the camera is treated as singular.
const MIN_FOCAL: f64 = 1e-9;

impl Intrinsics {
    /// Intrinsics from the five parameters; fails if any is non-finite or a focal length is zero.
    pub fn new(fx: f64, fy: f64, cx: f64, cy: f64, skew: f64) -> Result<Self> {
        let c = Intrinsics { fx, fy, cx, cy, skew };
        c.validate()?;
        Ok(c)
    }

    /// Intrinsics from a 3x3 calibration matrix `K`; its last row must be `(0, 0, 1)` up to scale
    /// (the matrix is divided by `K[2,2]`) and `K[1,0]` must be 0.
    pub fn from_matrix(k: &Matrix3<f64>) -> Result<Self> {
        if k.iter().any(|v| !v.is_finite()) {
            return Err(Error::SingularCamera {
                what: "K has a non-finite entry".into(),
            });
        }
        let w = k[(2, 2)];
        if w.abs() < 1e-300 {
            return Err(Error::SingularCamera {
                what: "K[2,2] is zero".into(),
            });
        }
        let k = k / w;
        let tol = 1e-9 * k.abs().max();
        if k[(2, 0)].abs() > tol || k[(2, 1)].abs() > tol || k[(1, 0)].abs() > tol {
            return Err(Error::SingularCamera {
                what: format!(
                    "K must be upper triangular with last row (0, 0, 1); got K[1,0]={}, K[2,0]={}, K[2,1]={}",
                    k[(1, 0)],
                    k[(2, 0)],
                    k[(2, 1)]
                ),
            });
        }
        Intrinsics::new(k[(0, 0)], k[(1, 1)], k[(0, 2)], k[(1, 2)], k[(0, 1)])
    }

    /// Checks that the intrinsics are finite and invertible: `|fx|, |fy| ≥ 1e-9` px, and
    /// `det K = fx fy` finite, so that `K⁻¹` is representable in double precision.
    pub fn validate(&self) -> Result<()> {
        let p = [self.fx, self.fy, self.cx, self.cy, self.skew];
        if p.iter().any(|v| !v.is_finite()) {
            return Err(Error::SingularCamera {
                what: format!("non-finite intrinsics [{}]", p.map(number).join(", ")),
            });
        }
        // Formatted only for an error: this check runs for every camera built on a hot path.
        let shown = || (number(self.fx), number(self.fy));
        if self.fx.abs() < MIN_FOCAL || self.fy.abs() < MIN_FOCAL {
            let (fx, fy) = shown();
            return Err(Error::SingularCamera {
                what: format!("focal lengths must be non-zero (at least {MIN_FOCAL:e} px), got fx={fx}, fy={fy}"),
            });
        }
        if !(self.fx * self.fy).is_finite() {
            let (fx, fy) = shown();
            return Err(Error::SingularCamera {
                what: format!(
                    "focal lengths too large: det K = fx fy overflows double precision, got fx={fx}, fy={fy}"
                ),
            });
        }
        Ok(())
    }

    /// The calibration matrix `K`.
    pub fn matrix(&self) -> Matrix3<f64> {
        Matrix3::new(self.fx, self.skew, self.cx, 0.0, self.fy, self.cy, 0.0, 0.0, 1.0)
    }

    /// Pixel `(u, v)` → normalised `(x, y)` with `(x, y, 1) ∝ K⁻¹ (u, v, 1)`.
    pub fn pixel_to_normalized(&self, u: &Vector2<f64>) -> Vector2<f64> {
        let y = (u.y - self.cy) / self.fy;
        let x = (u.x - self.cx - self.skew * y) / self.fx;
        Vector2::new(x, y)
    }

    /// Unit normal of the interpretation plane of the image segment `a`–`b` (pixels), in the camera
    /// frame: the plane through the centre of projection and the segment (Phong & Horaud 1995, eq. 3).
    ///
    /// Fails with [`Error::Degenerate`] when the endpoints coincide (their viewing rays less than
    /// 1e-12 rad apart, scale-free).
    pub fn interpretation_plane_normal(&self, a: &Vector2<f64>, b: &Vector2<f64>) -> Result<Vector3<f64>> {
        crate::geometry::lines::interpretation_plane_normal(self.pixel_to_normalized(a), self.pixel_to_normalized(b))
    }

    /// Normalised `(x, y)` → pixel `(u, v)`.
    pub fn normalized_to_pixel(&self, x: &Vector2<f64>) -> Vector2<f64> {
        Vector2::new(self.fx * x.x + self.skew * x.y + self.cx, self.fy * x.y + self.cy)
    }

    /// The 3x4 camera matrix `P = K [R | t]` of this camera at `pose` (`x_cam = R X_world + t`): it maps
    /// world points to pixels, `λ (u, v, 1)ᵀ = P (X, 1)ᵀ` with `λ = z_cam`, the known camera of
    /// [`crate::triangulation`]. The bridge from a pose estimate to triangulation.
    pub fn projection(&self, pose: &Pose) -> Matrix3x4<f64> {
        let mut rt = Matrix3x4::zeros();
        rt.fixed_view_mut::<3, 3>(0, 0).copy_from(&pose.rotation);
        rt.set_column(3, &pose.translation);
        self.matrix() * rt
    }

    /// Pixel of a camera-frame point, `u = K x_cam / z`. The caller checks `z > 0` when it matters.
    pub fn project(&self, x_cam: &Vector3<f64>) -> Vector2<f64> {
        self.normalized_to_pixel(&Vector2::new(x_cam.x / x_cam.z, x_cam.y / x_cam.z))
    }

    /// The 2x2 Jacobian of [`Intrinsics::normalized_to_pixel`] (constant: the upper-left block of `K`).
    pub fn pixel_jacobian(&self) -> nalgebra::Matrix2<f64> {
        nalgebra::Matrix2::new(self.fx, self.skew, 0.0, self.fy)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpretation_plane_contains_the_3d_line_and_the_centre() {
        let cam = Intrinsics::new(-1730.3, 1220.7, 243.8, 241.2, 0.0).unwrap();
        let (pa, pb) = (Vector3::new(1.0, -2.0, 60.0), Vector3::new(-3.0, 4.0, 80.0));
        let n = cam
            .interpretation_plane_normal(&cam.project(&pa), &cam.project(&pb))
            .unwrap();
        assert!((n.norm() - 1.0).abs() < 1e-12);
        // Eq. 3: n · FM = 0 for every point M of the line (F is the origin of the camera frame).
        for s in [-1.0, 0.0, 0.3, 2.0] {
            let m = pa + s * (pb - pa);
            assert!(n.dot(&m).abs() < 1e-9 * m.norm());
        }
        let px = cam.project(&pa);
        assert!(cam.interpretation_plane_normal(&px, &px).is_err());
    }

    #[test]
    fn a_camera_whose_k_cannot_be_inverted_is_refused_with_short_numbers() {
        // Zero or tiny focal lengths, and focal lengths whose product det K = fx fy overflows.
        for (fx, fy) in [(0.0, 800.0), (1e-300, 1e-300), (1e300, 1e300), (1e200, -1e109)] {
            let err = Intrinsics::new(fx, fy, 320.0, 240.0, 0.0).unwrap_err();
            let text = err.to_string();
            assert!(matches!(err, Error::SingularCamera { .. }), "{text}");
            // %g-style numbers: no run of seven digits (1e-300 printed in full had 300 zeros).
            assert!(
                !text.as_bytes().windows(7).any(|w| w.iter().all(u8::is_ascii_digit)),
                "{text}"
            );
        }
        // The largest that fit: det K = 1e300.
        assert!(Intrinsics::new(1e150, -1e150, 0.0, 0.0, 0.0).is_ok());
        assert!(Intrinsics::new(1e-9, 1e-9, 0.0, 0.0, 0.0).is_ok());
    }

    #[test]
    fn pixel_normalized_round_trip_with_negative_focal_and_skew() {
        // The paper's camera (Table 1, last row) plus a skew term.
        let cam = Intrinsics::new(-1730.3, 1220.7, 243.8, 241.2, 3.5).unwrap();
        for &(u, v) in &[(0.0, 0.0), (511.0, 17.5), (243.8, 241.2), (-40.0, 900.0)] {
            let px = Vector2::new(u, v);
            let back = cam.normalized_to_pixel(&cam.pixel_to_normalized(&px));
            assert!((back - px).norm() < 1e-9);
        }
        let x_cam = Vector3::new(0.3, -0.2, 2.0);
        let k = cam.matrix() * x_cam;
        assert!((cam.project(&x_cam) - Vector2::new(k.x / k.z, k.y / k.z)).norm() < 1e-9);
        assert_eq!(Intrinsics::from_matrix(&cam.matrix()).unwrap(), cam);
    }

    #[test]
    fn the_projection_matrix_projects_as_the_pose_and_the_camera_do() {
        let cam = Intrinsics::new(-1730.3, 1220.7, 243.8, 241.2, 3.5).unwrap();
        let rotation = *nalgebra::Rotation3::from_scaled_axis(Vector3::new(0.2, -0.4, 0.1)).matrix();
        let pose = Pose::new(rotation, Vector3::new(0.3, -0.1, 6.0));
        let p = cam.projection(&pose);
        for x in [Vector3::new(0.1, 0.2, 0.3), Vector3::new(-1.0, 0.5, 2.0)] {
            let h = p * x.push(1.0);
            let expected = cam.project(&pose.transform(&x));
            assert!((Vector2::new(h.x / h.z, h.y / h.z) - expected).norm() < 1e-9);
            assert!((h.z - pose.transform(&x).z).abs() < 1e-12, "λ is the depth");
        }
    }

    #[test]
    fn singular_cameras_are_rejected() {
        assert!(matches!(
            Intrinsics::new(0.0, 1.0, 0.0, 0.0, 0.0),
            Err(Error::SingularCamera { .. })
        ));
        assert!(Intrinsics::new(f64::NAN, 1.0, 0.0, 0.0, 0.0).is_err());
        let mut k = Matrix3::identity();
        k[(2, 0)] = 1.0;
        assert!(Intrinsics::from_matrix(&k).is_err());
    }
}
