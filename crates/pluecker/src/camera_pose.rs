//! The pose of a camera: the rigid motion from the world frame to the camera frame.

use crate::geometry::dual_quaternion::DualQuaternion;
use crate::geometry::quaternion::{axis_angle, from_rotation_matrix};
use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion, Vector3, Vector4};

/// The largest `|R Rᵀ − I|` entry of a rotation given as an argument ([`Pose::rotation_defect`]).
pub const ROTATION_TOLERANCE: f64 = 1e-6;

/// A camera pose `x_cam = R X_world + t`: `rotation` is `R` (a rotation matrix), `translation` is `t`
/// (world units, the world origin in the camera frame). The answer of the pose estimators, the input of
/// [`crate::camera::Camera::projection`], and the pose of the minimal solvers.
///
/// The fields are public and not checked: a pose built from a matrix that is not a rotation is the
/// caller's to avoid (the estimators and solvers only return rotations).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Pose {
    /// `R`, world to camera.
    #[cfg_attr(feature = "serde", serde(with = "crate::matrix_rows"))]
    pub rotation: Matrix3<f64>,
    /// `t`, world units.
    pub translation: Vector3<f64>,
}

impl Pose {
    /// The pose `x_cam = rotation X_world + translation`.
    pub fn new(rotation: Matrix3<f64>, translation: Vector3<f64>) -> Pose {
        Pose { rotation, translation }
    }

    /// The camera at the world origin, looking down the world's `+z`.
    pub fn identity() -> Pose {
        Pose::new(Matrix3::identity(), Vector3::zeros())
    }

    /// `x_cam = R X_world + t`.
    pub fn transform(&self, x_world: &Vector3<f64>) -> Vector3<f64> {
        self.rotation * x_world + self.translation
    }

    /// The optical centre in the world frame, `−Rᵀ t`.
    pub fn centre(&self) -> Vector3<f64> {
        -(self.rotation.transpose() * self.translation)
    }

    /// The motion from the camera frame back to the world frame, `X_world = Rᵀ x_cam − Rᵀ t`.
    pub fn inverse(&self) -> Pose {
        let rt = self.rotation.transpose();
        Pose::new(rt, -(rt * self.translation))
    }

    /// `self` after `first`: `x = self(first(X))`.
    pub fn compose(&self, first: &Pose) -> Pose {
        Pose::new(
            self.rotation * first.rotation,
            self.rotation * first.translation + self.translation,
        )
    }

    /// Why `rotation` is not a rotation matrix, in words; `None` when it is one: finite, `R Rᵀ = I`
    /// within [`ROTATION_TOLERANCE`] (entrywise) and `det R > 0`. The one test of a rotation given as
    /// an argument (Rust and Python).
    pub fn rotation_defect(rotation: &Matrix3<f64>) -> Option<String> {
        if !rotation.iter().all(|v| v.is_finite()) {
            return Some("expected a rotation matrix, got a NaN or infinite entry".into());
        }
        let orthogonality = (rotation * rotation.transpose() - Matrix3::identity()).amax();
        let det = rotation.determinant();
        (orthogonality > ROTATION_TOLERANCE || det <= 0.0).then(|| {
            format!(
                "expected a rotation matrix (R Rᵀ = I within {ROTATION_TOLERANCE:e}, det R = +1), got max |R Rᵀ − I| = \
                 {orthogonality:.3e}, det R = {det:.6}"
            )
        })
    }

    /// Whether every entry is finite.
    pub fn is_finite(&self) -> bool {
        self.rotation
            .iter()
            .chain(self.translation.iter())
            .all(|v| v.is_finite())
    }

    /// The same motion as a unit dual quaternion (Phong & Horaud 1995, eqs. 6-7), `r₀ ≥ 0`; NaN
    /// entries when the pose is not finite.
    pub fn dual_quaternion(&self) -> DualQuaternion {
        if !self.is_finite() {
            let nan = Vector4::from_element(f64::NAN);
            return DualQuaternion { r: nan, s: nan };
        }
        DualQuaternion::from_rotation_translation(&self.rotation, &self.translation)
    }

    /// The rotation as a unit axis and an angle in `[0, π]`, radians; NaN when the pose is not
    /// finite.
    pub fn axis_angle(&self) -> (Vector3<f64>, f64) {
        if !self.is_finite() {
            return (Vector3::from_element(f64::NAN), f64::NAN);
        }
        axis_angle(&from_rotation_matrix(&self.rotation))
    }

    /// The rotation vector `ω = angle · axis` (`R = exp([ω]ₓ)`), radians.
    pub fn rotation_vector(&self) -> Vector3<f64> {
        let (axis, angle) = self.axis_angle();
        axis * angle
    }
}

impl From<(Matrix3<f64>, Vector3<f64>)> for Pose {
    /// The pose of an `(R, t)` pair.
    fn from((rotation, translation): (Matrix3<f64>, Vector3<f64>)) -> Pose {
        Pose::new(rotation, translation)
    }
}

impl From<Isometry3<f64>> for Pose {
    fn from(iso: Isometry3<f64>) -> Pose {
        Pose::new(*iso.rotation.to_rotation_matrix().matrix(), iso.translation.vector)
    }
}

impl From<Pose> for Isometry3<f64> {
    /// The nearest isometry (the rotation re-orthonormalised through its quaternion).
    fn from(p: Pose) -> Isometry3<f64> {
        let rotation = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(p.rotation));
        Isometry3::from_parts(Translation3::from(p.translation), rotation)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pose() -> Pose {
        let r = *Rotation3::from_scaled_axis(Vector3::new(0.3, -0.2, 0.9)).matrix();
        Pose::new(r, Vector3::new(0.5, -1.0, 4.0))
    }

    #[test]
    fn inverse_and_compose_undo_each_other() {
        let p = pose();
        let x = Vector3::new(1.0, 2.0, -3.0);
        assert!((p.inverse().transform(&p.transform(&x)) - x).norm() < 1e-12);
        let id = p.compose(&p.inverse());
        assert!((id.rotation - Matrix3::identity()).norm() < 1e-12 && id.translation.norm() < 1e-12);
    }

    #[test]
    fn the_centre_maps_to_the_camera_origin() {
        let p = pose();
        assert!(p.transform(&p.centre()).norm() < 1e-12);
    }

    #[test]
    fn rotation_forms_agree_with_the_matrix() {
        let p = pose();
        // The rotation vector was the input of `pose()`; `from_scaled_axis` is nalgebra's, not ours.
        assert!((p.rotation_vector() - Vector3::new(0.3, -0.2, 0.9)).norm() < 1e-12);
        let (axis, angle) = p.axis_angle();
        assert!(
            (axis.norm() - 1.0).abs() < 1e-12 && (angle - Vector3::<f64>::new(0.3, -0.2, 0.9).norm()).abs() < 1e-12
        );
        let (r, t) = p.dual_quaternion().to_rotation_translation();
        assert!((r - p.rotation).norm() < 1e-12 && (t - p.translation).norm() < 1e-12);
        assert!(p.dual_quaternion().r[0] >= 0.0);
        let nan = Pose::new(Matrix3::from_element(f64::NAN), Vector3::zeros());
        assert!(nan.rotation_vector().iter().all(|v| v.is_nan()) && nan.dual_quaternion().r[0].is_nan());
    }

    #[test]
    fn isometry_round_trip() {
        let p = pose();
        let back = Pose::from(Isometry3::from(p));
        assert!((back.rotation - p.rotation).norm() < 1e-12 && (back.translation - p.translation).norm() < 1e-12);
    }
}
