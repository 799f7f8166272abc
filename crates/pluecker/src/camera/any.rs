//! [`AnyCamera`]: the pinhole [`Camera`] or a [`LensCamera`].

use super::lens::LensCamera;
use crate::camera::Camera;
use crate::error::Result;
use nalgebra::{Matrix2x3, Vector2, Vector3};

/// The one camera type of pose and triangulation: the pinhole [`Camera`] (with skew) or a
/// [`LensCamera`] of any of COLMAP's models (whose pixels are the observed, distorted ones).
#[derive(Debug, Clone, PartialEq)]
pub enum AnyCamera {
    /// No distortion: `u = K x_cam / z`.
    Pinhole(Camera),
    /// A COLMAP camera model: `u = K D(x_cam / z)` with the model's distortion `D`.
    Lens(LensCamera),
}

impl From<Camera> for AnyCamera {
    fn from(camera: Camera) -> Self {
        AnyCamera::Pinhole(camera)
    }
}

impl From<&Camera> for AnyCamera {
    fn from(camera: &Camera) -> Self {
        AnyCamera::Pinhole(*camera)
    }
}

impl From<LensCamera> for AnyCamera {
    fn from(camera: LensCamera) -> Self {
        AnyCamera::Lens(camera)
    }
}

impl From<&LensCamera> for AnyCamera {
    fn from(camera: &LensCamera) -> Self {
        AnyCamera::Lens(camera.clone())
    }
}

impl From<&AnyCamera> for AnyCamera {
    fn from(camera: &AnyCamera) -> Self {
        camera.clone()
    }
}

impl AnyCamera {
    /// The pinhole part `K` (the lens's focal lengths and principal point, no skew, for a
    /// [`LensCamera`]).
    pub fn pinhole(&self) -> Result<Camera> {
        match self {
            AnyCamera::Pinhole(camera) => Ok(*camera),
            AnyCamera::Lens(lens) => lens.pinhole(),
        }
    }

    /// The lens when the camera distorts (a [`LensCamera`] of a model other than the pinholes).
    pub fn distortion(&self) -> Option<&LensCamera> {
        match self {
            AnyCamera::Lens(lens) if !lens.is_pinhole() => Some(lens),
            _ => None,
        }
    }

    /// Pixels of the camera-frame point `x_cam` (`z > 0`) and the Jacobian `∂u/∂x_cam` (2x3), through
    /// the exact projection.
    pub fn project(&self, x_cam: &Vector3<f64>) -> (Vector2<f64>, Matrix2x3<f64>) {
        match self {
            AnyCamera::Pinhole(camera) => {
                let z = x_cam.z;
                let n = Vector2::new(x_cam.x / z, x_cam.y / z);
                let dn_dx = Matrix2x3::new(1.0 / z, 0.0, -n.x / z, 0.0, 1.0 / z, -n.y / z);
                (camera.normalized_to_pixel(&n), camera.pixel_jacobian() * dn_dx)
            }
            AnyCamera::Lens(lens) => lens.project(x_cam),
        }
    }
}
