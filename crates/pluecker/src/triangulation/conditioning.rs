//! Input checks and world conditioning shared by line and quadric triangulation.
//!
//! Every solver works in a conditioned world frame `X_c = s R (X − o)` (a similarity `H`), where the
//! cameras are `P H⁻¹` scaled by [`depth_normalized`] and the primitive is a few units from the
//! origin. Image residuals are unchanged: `P H⁻¹ H X = P X` for points, and lines and dual quadrics
//! transform so that their images are unchanged too (eq. 5: `L' = H L Hᵀ`; duals: `L' = H L Hᵀ`).

use super::views::{baseline, centre, depth_normalized, validate_cameras};
use super::Method;
use crate::error::{Error, Result};
use nalgebra::{Matrix3, Matrix3x4, Matrix4, Vector3};

/// Centres closer than this, relative to their distance from the origin (at least 1), coincide.
const SAME_CENTRE: f64 = 1e-10;

/// The similarity `X_c = scale · rotation · (X − origin)` of the world.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Similarity {
    /// The world point mapped to the origin.
    pub origin: Vector3<f64>,
    /// The scale `s > 0`.
    pub scale: f64,
    /// The rotation `R` (world axes to conditioned axes).
    pub rotation: Matrix3<f64>,
}

impl Similarity {
    /// Origin at the centroid of the camera centres, unit = their RMS distance from it.
    pub(crate) fn of_cameras(cameras: &[Matrix3x4<f64>]) -> Similarity {
        let centres: Vec<Vector3<f64>> = cameras.iter().map(centre).collect();
        let origin = centres.iter().sum::<Vector3<f64>>() / centres.len() as f64;
        let rms = (centres.iter().map(|c| (c - origin).norm_squared()).sum::<f64>() / centres.len() as f64).sqrt();
        Similarity::around(origin, if rms > 0.0 { rms } else { 1.0 })
    }

    /// The identity.
    pub fn identity() -> Similarity {
        Similarity::around(Vector3::zeros(), 1.0)
    }

    /// Origin at `origin`, unit `length` (positive), axes kept.
    pub fn around(origin: Vector3<f64>, length: f64) -> Similarity {
        Similarity {
            origin,
            scale: 1.0 / length,
            rotation: Matrix3::identity(),
        }
    }

    /// `H` (4x4): homogeneous world points to conditioned points.
    pub fn matrix(&self) -> Matrix4<f64> {
        let mut h = Matrix4::identity();
        h.fixed_view_mut::<3, 3>(0, 0).copy_from(&(self.rotation * self.scale));
        h.fixed_view_mut::<3, 1>(0, 3)
            .copy_from(&(-self.rotation * self.origin * self.scale));
        h
    }

    /// `H⁻¹`.
    pub(crate) fn inverse_matrix(&self) -> Matrix4<f64> {
        let mut h = Matrix4::identity();
        h.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&(self.rotation.transpose() / self.scale));
        h.fixed_view_mut::<3, 1>(0, 3).copy_from(&self.origin);
        h
    }

    /// The camera in the conditioned frame, `P H⁻¹`, depth-normalised ([`depth_normalized`]).
    pub fn camera(&self, p: &Matrix3x4<f64>) -> Matrix3x4<f64> {
        depth_normalized(&(p * self.inverse_matrix()))
    }

    /// A conditioned point back in the world (the tests' round trip).
    #[cfg(test)]
    pub fn to_world(self, x: &Vector3<f64>) -> Vector3<f64> {
        self.rotation.transpose() * x / self.scale + self.origin
    }
}

/// Checks counts and cameras: at least `min_views` cameras, one observation per camera, finite
/// non-singular cameras, and not all centres the same (no parallax: [`Error::Degenerate`]).
pub(crate) fn check_views(
    cameras: &[Matrix3x4<f64>],
    observations: usize,
    min_views: usize,
    what: &str,
    method: Method,
) -> Result<()> {
    if cameras.len() < min_views {
        return Err(Error::TooFewCorrespondences {
            method: method.as_str().into(),
            required: format!("{min_views} views"),
            actual: format!("{} view(s)", cameras.len()),
        });
    }
    if observations != cameras.len() {
        return Err(Error::Shape {
            what: what.into(),
            expected: format!("{} (one per camera)", cameras.len()),
            actual: format!("{observations}"),
        });
    }
    validate_cameras(cameras, "cameras")?;
    let scale = cameras.iter().map(|p| centre(p).norm()).fold(1.0, f64::max);
    if baseline(cameras) <= SAME_CENTRE * scale {
        return Err(Error::Degenerate {
            what: "cameras: all camera centres coincide (no parallax)".into(),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector4;

    #[test]
    fn similarity_and_inverse_agree_and_keep_projections() {
        let rotation = nalgebra::Rotation3::new(Vector3::new(0.3, -0.2, 1.0)).into_inner();
        let s = Similarity {
            origin: Vector3::new(1.0, -2.0, 3.0),
            scale: 0.25,
            rotation,
        };
        assert!((s.matrix() * s.inverse_matrix() - Matrix4::identity()).norm() < 1e-12);
        let x = Vector3::new(0.3, 0.4, 7.0);
        let xc = s.matrix() * Vector4::new(x.x, x.y, x.z, 1.0);
        assert!((s.to_world(&xc.xyz()) - x).norm() < 1e-12);
        let p = Matrix3x4::new(800.0, 0.0, 320.0, 10.0, 0.0, 800.0, 240.0, 5.0, 0.0, 0.0, 1.0, 2.0);
        let (u, v) = (p * Vector4::new(x.x, x.y, x.z, 1.0), s.camera(&p) * xc);
        assert!((u.xy() / u.z - v.xy() / v.z).norm() < 1e-9);
        assert!(v.z > 0.0, "depth-normalised: positive depth in front");
    }
}
