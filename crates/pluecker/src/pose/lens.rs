//! Pose through a lens with distortion: the observed (distorted) pixels mapped into the pixels of the
//! lens's pinhole part, with the noise that keeps residuals in distorted pixels ([`undistort`]), and
//! [`estimate_pose_lens`].
//!
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
use super::estimate::estimate_pose;
use super::noise::ObservationNoise;
use super::robust::scoring::subset;
use super::PoseOptions;
use super::PoseResult;
use crate::camera::Camera;
use crate::camera_model::LensCamera;
use crate::error::{Error, Result};
use nalgebra::{Matrix2, Vector2};

/// The observations `corr` (distorted pixels of `lens`) as undistorted pixels of [`LensCamera::pinhole`],
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
    let camera = lens.pinhole()?;
    if let Some(n) = noise {
        n.check_counts(corr.n_points(), corr.n_lines())?;
    }
    // Undistorted pixel ū of a pixel, and J = ∂u/∂ū there, with errors naming the argument.
    let through = |u: &Vector2<f64>, what: &str, index: usize| -> Result<(Vector2<f64>, Matrix2<f64>)> {
        if !(u.x.is_finite() && u.y.is_finite()) {
            return Err(Error::NonFinite {
                what: what.into(),
                index,
            });
        }
        lens.undistort(u, index).map_err(|e| match e {
            Error::Degenerate { what: why } => Error::Degenerate {
                what: format!("{what}: {why}"),
            },
            other => other,
        })
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

/// [`estimate_pose`] for a camera with distortion: `corr` holds the observed (distorted) pixels of
/// `lens`, and `noise` optionally their covariances ([`ObservationNoise::from_covariances`]). The
/// stages run on the undistorted pixels and the refinement minimises the error in the distorted ones
/// ([module docs](self) say how, and what RANSAC's thresholds then mean). The result's pixels
/// (reprojection errors, `sigma_px`) are distorted pixels, or standard deviations with covariances.
///
/// An observation outside the invertible region of the distortion (a pixel no point in front of the
/// camera projects to) is an error naming it, except with RANSAC: there it is an outlier (its inlier flag
/// false, and not counted by the RANSAC report), as a random mismatch at the edge of a fisheye is.
pub fn estimate_pose_lens(
    lens: &LensCamera,
    corr: &Correspondences,
    noise: Option<&ObservationNoise>,
    opts: &PoseOptions,
) -> Result<PoseResult> {
    if lens.is_pinhole() {
        // No distortion: the pinhole path, with the covariances (if any) as they are.
        let corr = Correspondences {
            noise: noise.cloned(),
            ..corr.clone()
        };
        return estimate_pose(&lens.pinhole()?, &corr, opts);
    }
    // Without RANSAC a pixel beyond the lens is an error (from `undistort`); with it, an outlier.
    let (points, lines) = if opts.ransac.is_some() {
        invertible(lens, corr)
    } else {
        (vec![], vec![])
    };
    if points.iter().chain(&lines).all(|&ok| ok) {
        let (camera, undistorted) = undistort(lens, corr, noise)?;
        return estimate_pose(&camera, &undistorted, opts);
    }
    if let Some(n) = noise {
        n.check_counts(corr.n_points(), corr.n_lines())?;
    }
    let kept = subset(corr, &points, &lines);
    let kept_noise = noise.map(|n| n.subset(&points, &lines));
    let (camera, undistorted) = undistort(lens, &kept, kept_noise.as_ref())?;
    let mut result = estimate_pose(&camera, &undistorted, opts)?;
    result.inliers_points = expand(&result.inliers_points, &points);
    result.inliers_lines = expand(&result.inliers_lines, &lines);
    Ok(result)
}

/// Which points and segments of `corr` `lens` can unproject (both endpoints for a segment).
fn invertible(lens: &LensCamera, corr: &Correspondences) -> (Vec<bool>, Vec<bool>) {
    let ok = |u: &nalgebra::Vector2<f64>| lens.unproject(u, 0).is_ok();
    (
        corr.points2d.iter().map(ok).collect(),
        corr.lines2d.iter().map(|s| ok(&s[0]) && ok(&s[1])).collect(),
    )
}

/// The flags of the kept entries (`kept` true) back at their places, false at the others.
fn expand(flags: &[bool], kept: &[bool]) -> Vec<bool> {
    let mut it = flags.iter();
    kept.iter().map(|&k| k && *it.next().unwrap_or(&false)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera_model::CameraModel;

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
