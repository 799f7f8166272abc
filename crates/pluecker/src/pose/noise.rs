//! Per-observation noise of the pose: 2x2 covariances of image points and segment endpoints, and the
//! first-order account of a lens's distortion. Josephson & Kahl 2008 weight each observation by its
//! covariance (eq. 18, the Mahalanobis distance); this module applies the same weighting to the pose.
//!
//! With an [`ObservationNoise`] on the [`Correspondences`], the residuals of
//! [`super::reprojection::ReprojectionCost`] become:
//! - a point: `W_i (π(R X + t) − u_i)`, where `W_i` whitens the pixel residual (`W_iᵀ W_i = Σ_i⁻¹`);
//! - a segment endpoint `e`: `(l·ẽ) / √(l₁₂ᵀ C_e l₁₂)`, where `l` is the projected line in pixels,
//!   `l₁₂` its first two entries and `C_e` the endpoint's covariance: its distance to the line in
//!   standard deviations across the line. With `C_e = I` this is the plain pixel distance.
//!
//! ## Distortion ([`undistort`])
//! The pose stages (minimal solvers, RANSAC, the algebraic methods) work on the observations mapped
//! through the exact unprojection of the [`LensCamera`] into the pixels of its pinhole part
//! `K = [fx 0 cx; 0 fy cy; 0 0 1]` (the *undistorted* pixels ū). A residual `r̄` there is one of
//! `J r̄` in the observed, distorted pixels to first order, with `J = ∂u/∂ū` the distortion's Jacobian at
//! the observation. So the noise becomes `W = L⁻¹ J` for a point (with `Σ = L Lᵀ` the observed
//! covariance, the identity when none is given) and `C_e = J⁻¹ Σ J⁻ᵀ` for an endpoint, and the
//! refinement minimises the reprojection error in the distorted pixels:
//! - for points, linearised at the observation; the neglected term is `½ r̄ᵀ ∇²u r̄`, second order in
//!   the residual (below 1e-3 px for a 1 px residual on the OPENCV and fisheye cameras of the tests);
//! - for segments, the distance of each observed endpoint to the *curved* image of the 3-D line,
//!   approximated by the distance to its tangent at the point nearest the endpoint: the distorted image
//!   of a line is a curve, and a segment's endpoints are the only part of it that is used.
//!
//! RANSAC scores hypotheses with the same whitened errors ([`super::robust::scoring`]), so its
//! thresholds are distorted pixels too (to first order), also where the undistortion stretches the
//! image tenfold (the edge of a fisheye); with covariances they are standard deviations. (PoseLib and
//! OpenCV apply one threshold in undistorted, normalised coordinates instead.)

use super::correspondences::Correspondences;
use crate::camera::Camera;
use crate::camera_model::LensCamera;
use crate::error::{Error, Result};
use nalgebra::{Matrix2, Vector2};

/// Per-observation noise, in the pixels of the correspondences it belongs to.
#[derive(Debug, Clone, PartialEq)]
pub struct ObservationNoise {
    /// Per point, the whitening `W_i` (2x2): residual in the data's pixels → whitened residual.
    pub points: Vec<Matrix2<f64>>,
    /// Per segment, the covariance `C_e` (2x2) of each endpoint in the data's pixels, in the same
    /// whitened units.
    pub lines: Vec<[Matrix2<f64>; 2]>,
    /// True when the covariances are the user's (residuals in standard deviations: the noise level is
    /// 1, not estimated); false when they only carry a distortion's Jacobians (residuals in observed
    /// pixels, the noise level estimated or given by `sigma_px` as without covariances).
    pub absolute: bool,
}

/// The inverse Cholesky factor `L⁻¹` of a symmetric positive-definite 2x2 covariance (`(L⁻¹)ᵀ L⁻¹ =
/// Σ⁻¹`), or an error naming `what` and `index` for a non-finite, asymmetric or non-positive-definite one.
fn whitening(cov: &Matrix2<f64>, what: &str, index: usize) -> Result<Matrix2<f64>> {
    check_covariance(cov, what, index)?;
    let l = cov.cholesky().map(|c| c.l()).ok_or_else(|| not_positive(what, index))?;
    l.try_inverse().ok_or_else(|| not_positive(what, index))
}

fn not_positive(what: &str, index: usize) -> Error {
    Error::Degenerate {
        what: format!("{what}[{index}] is not a positive-definite covariance"),
    }
}

/// Finite, symmetric (to 1e-9 relative) and positive definite.
fn check_covariance(cov: &Matrix2<f64>, what: &str, index: usize) -> Result<()> {
    if cov.iter().any(|v| !v.is_finite()) {
        return Err(Error::NonFinite {
            what: what.into(),
            index,
        });
    }
    let asymmetric = (cov[(0, 1)] - cov[(1, 0)]).abs() > 1e-9 * cov.amax();
    if asymmetric || !(cov[(0, 0)] > 0.0 && cov.determinant() > 0.0) {
        return Err(not_positive(what, index));
    }
    Ok(())
}

impl ObservationNoise {
    /// The noise of covariances (pixels², in the frame of the correspondences): one 2x2 per point and
    /// one per segment endpoint. Errors name the argument (`point_covariances`, `line_covariances`)
    /// and the index of a covariance that is not finite, symmetric and positive definite.
    pub fn from_covariances(points: &[Matrix2<f64>], lines: &[[Matrix2<f64>; 2]]) -> Result<ObservationNoise> {
        let points = points
            .iter()
            .enumerate()
            .map(|(i, c)| whitening(c, "point_covariances", i))
            .collect::<Result<Vec<_>>>()?;
        for (i, pair) in lines.iter().enumerate() {
            for c in pair {
                check_covariance(c, "line_covariances", i)?;
            }
        }
        Ok(ObservationNoise {
            points,
            lines: lines.to_vec(),
            absolute: true,
        })
    }

    /// `Error::Shape` unless there is one entry per point and per segment of `corr`.
    pub fn check_counts(&self, corr: &Correspondences) -> Result<()> {
        for (what, have, want) in [
            ("point_covariances", self.points.len(), corr.n_points()),
            ("line_covariances", self.lines.len(), corr.n_lines()),
        ] {
            if have != want {
                return Err(Error::Shape {
                    what: what.into(),
                    expected: format!("{want} rows, one per correspondence"),
                    actual: format!("{have}"),
                });
            }
        }
        Ok(())
    }

    /// The entries selected by the masks (RANSAC's inliers).
    pub(crate) fn subset(&self, points: &[bool], lines: &[bool]) -> ObservationNoise {
        fn pick<T: Copy>(values: &[T], mask: &[bool]) -> Vec<T> {
            values.iter().zip(mask).filter(|(_, &m)| m).map(|(v, _)| *v).collect()
        }
        ObservationNoise {
            points: pick(&self.points, points),
            lines: pick(&self.lines, lines),
            absolute: self.absolute,
        }
    }
}

/// The pinhole part of `lens`: its focal lengths and principal point, no skew.
pub fn pinhole_part(lens: &LensCamera) -> Result<Camera> {
    let ((fx, fy), (cx, cy)) = (lens.focal(), lens.principal_point());
    Camera::new(fx, fy, cx, cy, 0.0)
}

/// The observations `corr` (distorted pixels of `lens`) as undistorted pixels of [`pinhole_part`],
/// with the noise that makes residuals there first-order residuals in the distorted pixels (see the
/// module docs): the input of [`super::estimate_pose`] for a camera with distortion. `noise`, when
/// given, holds the covariances of the observed (distorted) pixels, as
/// [`ObservationNoise::from_covariances`] makes them. `Error::Degenerate` names an observation outside
/// the invertible region of the distortion.
pub fn undistort(
    lens: &LensCamera,
    corr: &Correspondences,
    noise: Option<&ObservationNoise>,
) -> Result<(Camera, Correspondences)> {
    let camera = pinhole_part(lens)?;
    if let Some(n) = noise {
        n.check_counts(corr)?;
    }
    let ((fx, fy), (cx, cy)) = (lens.focal(), lens.principal_point());
    // Undistorted pixel ū of a pixel, and J = ∂u/∂ū = diag(f) ∂D/∂n diag(f)⁻¹ there.
    let through = |u: &Vector2<f64>, what: &str, index: usize| -> Result<(Vector2<f64>, Matrix2<f64>)> {
        if !(u.x.is_finite() && u.y.is_finite()) {
            return Err(Error::NonFinite {
                what: what.into(),
                index,
            });
        }
        let n = lens.unproject(u, index).map_err(|e| match e {
            Error::Degenerate { what: why } => Error::Degenerate {
                what: format!("{what}: {why}"),
            },
            other => other,
        })?;
        let (_, jd) = lens.distort(&n);
        let f = Matrix2::new(fx, 0.0, 0.0, fy);
        let f_inv = Matrix2::new(1.0 / fx, 0.0, 0.0, 1.0 / fy);
        Ok((Vector2::new(fx * n.x + cx, fy * n.y + cy), f * jd * f_inv))
    };
    let singular = |what: &str, index: usize| Error::Degenerate {
        what: format!("{what}[{index}]: the distortion is singular there"),
    };
    let mut undistorted = Correspondences {
        points3d: corr.points3d.clone(),
        lines3d: corr.lines3d.clone(),
        ..Default::default()
    };
    let mut points = Vec::with_capacity(corr.n_points());
    for (i, u) in corr.points2d.iter().enumerate() {
        let (ubar, j) = through(u, "points2d", i)?;
        undistorted.points2d.push(ubar);
        let w = noise.map_or_else(Matrix2::identity, |n| n.points[i]);
        points.push(w * j);
    }
    let mut lines = Vec::with_capacity(corr.n_lines());
    for (i, s) in corr.lines2d.iter().enumerate() {
        let (a, ja) = through(&s[0], "lines2d", i)?;
        let (b, jb) = through(&s[1], "lines2d", i)?;
        undistorted.lines2d.push([a, b]);
        let mut pair = [Matrix2::identity(); 2];
        for (k, j) in [ja, jb].iter().enumerate() {
            let j_inv = j.try_inverse().ok_or_else(|| singular("lines2d", i))?;
            let cov = noise.map_or_else(Matrix2::identity, |n| n.lines[i][k]);
            pair[k] = j_inv * cov * j_inv.transpose();
        }
        lines.push(pair);
    }
    undistorted.noise = Some(ObservationNoise {
        points,
        lines,
        absolute: noise.is_some_and(|n| n.absolute),
    });
    Ok((camera, undistorted))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera_model::CameraModel;

    #[test]
    fn covariances_are_checked_and_whitened() {
        let cov = Matrix2::new(4.0, 1.0, 1.0, 2.0);
        let noise = ObservationNoise::from_covariances(&[cov], &[]).unwrap();
        let w = noise.points[0];
        // Wᵀ W = Σ⁻¹.
        assert!((w.transpose() * w - cov.try_inverse().unwrap()).amax() < 1e-12);
        let bad = [Matrix2::new(1.0, 0.0, 0.0, -1.0)];
        let err = ObservationNoise::from_covariances(&bad, &[]).unwrap_err();
        assert!(err.to_string().contains("point_covariances[0]"), "{err}");
        let nan = [[Matrix2::identity(), Matrix2::new(f64::NAN, 0.0, 0.0, 1.0)]];
        assert!(matches!(
            ObservationNoise::from_covariances(&[], &nan),
            Err(Error::NonFinite { index: 0, .. })
        ));
    }

    #[test]
    fn undistorted_residuals_are_distorted_pixels_to_first_order() {
        let lens = LensCamera::new(
            CameraModel::OpenCv,
            &[800.0, 780.0, 320.0, 240.0, -0.25, 0.08, 1e-3, -5e-4],
        )
        .unwrap();
        let u = Vector2::new(600.0, 420.0);
        let corr = Correspondences {
            points2d: vec![u],
            points3d: vec![nalgebra::Vector3::zeros()],
            ..Default::default()
        };
        let (camera, undistorted) = undistort(&lens, &corr, None).unwrap();
        let w = undistorted.noise.as_ref().unwrap().points[0];
        // Move the undistorted pixel by a small r̄ and compare W r̄ with the change of the distorted pixel.
        let r = Vector2::new(0.3, -0.2);
        let ubar = undistorted.points2d[0] + r;
        let x = nalgebra::Vector3::new((ubar.x - camera.cx) / camera.fx, (ubar.y - camera.cy) / camera.fy, 1.0);
        let moved = lens.project(&x).0 - u;
        assert!((w * r - moved).norm() < 1e-3 * r.norm(), "{} vs {}", w * r, moved);
    }
}
