//! Pose through a lens with distortion: the two forms of the observations that the pipeline uses
//! (`Observations`), the observed (distorted) pixels mapped into the pixels of the lens's pinhole
//! part with first-order noise ([`undistort`]), and the entry of [`super::estimate_pose`] for a camera
//! that distorts (`ThroughLens`).
//!
//! The algebraic methods, the minimal solvers and RANSAC's scoring work on the observations mapped
//! through the exact unprojection of the [`Camera`] into the pixels of its pinhole part
//! `K = [fx 0 cx; 0 fy cy; 0 0 1]` (the *undistorted* pixels ū). A residual `r̄` there is one of
//! `J r̄` in the observed, distorted pixels to first order, with `J = ∂u/∂ū` the distortion's Jacobian at
//! the observation. So their noise becomes `W = L⁻¹ J` for a point (with `Σ = L Lᵀ` the observed
//! covariance, the identity when none is given) and `C_e = J⁻¹ Σ J⁻ᵀ` for an endpoint: RANSAC's
//! thresholds are distorted pixels to first order, also where the undistortion stretches the image
//! tenfold (the edge of a fisheye); with covariances they are standard deviations. (PoseLib and OpenCV
//! apply one threshold in undistorted, normalised coordinates instead.)
//!
//! The reprojection refinement, and everything the result reports (cost, errors, `sigma_px`,
//! covariance), use the exact cost in the observed pixels instead
//! ([`super::reprojection::ReprojectionCost::exact`]): points through the exact projection
//! `u = K D(x_cam / z)`, segment endpoints by their distance to the curved image of the projected line.
//! Only the test for a better pose behind the camera (`candidates::behind_camera_cost`) keeps
//! the first-order cost: the projection through a lens is not defined behind the camera, and that test
//! asks for a factor of 100 between the two costs.
//!
//! The certificate of global optimality bounds the exact cost in the observed pixels too
//! ([`super::certificate`], through a whitened pinhole problem linearised at the answer whose error is
//! bounded by interval enclosures of the distortion's Jacobian), over the poses whose projections stay
//! inside the disc where the lens is proved one-to-one.

use super::correspondences::{Conditioning, Correspondences};
use super::noise::ObservationNoise;
use super::reprojection::ReprojectionCost;
use super::robust::scoring::subset;
use super::PoseOptions;
use super::PoseResult;
use crate::camera::Camera;
use crate::camera::Intrinsics;
use crate::error::{Error, Result};
use nalgebra::{Matrix2, Vector2};
use std::borrow::Cow;

/// The observations `corr` (distorted pixels of `lens`) as undistorted pixels of [`Camera::pinhole`],
/// with the noise that makes residuals there first-order residuals in the distorted pixels (see the
/// module docs): the input of the stages before the refinement for a camera with distortion. `noise`, when
/// given, holds the covariances of the observed (distorted) pixels, as
/// [`ObservationNoise::from_covariances`] makes them. `Error::Degenerate` names an observation outside
/// the invertible region of the distortion.
pub fn undistort(
    lens: &Camera,
    corr: &Correspondences,
    noise: Option<&ObservationNoise>,
) -> Result<(Intrinsics, Correspondences)> {
    let camera = lens.intrinsics();
    if let Some(n) = noise {
        n.check_counts(corr.n_points(), corr.n_lines())?;
    }
    // A finite pixel, else an error naming the argument; errors of the undistortion name it too.
    let finite = |u: &Vector2<f64>, what: &str, index: usize| -> Result<()> {
        if u.x.is_finite() && u.y.is_finite() {
            Ok(())
        } else {
            Err(Error::NonFinite {
                what: what.into(),
                index,
            })
        }
    };
    let named = |what: &'static str| {
        move |e| match e {
            Error::Degenerate { what: why } => Error::Degenerate {
                what: format!("{what}: {why}"),
            },
            other => other,
        }
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
        finite(u, "points2d", i)?;
        let (ubar, j) = lens.undistort(u, i).map_err(named("points2d"))?;
        undistorted.points2d.push(ubar);
        let w = noise.map_or_else(Matrix2::identity, |n| n.points[i]);
        points.push(w * j);
    }
    let mut lines = Vec::with_capacity(corr.n_lines());
    for (i, s) in corr.lines2d.iter().enumerate() {
        let mut ends = [Vector2::zeros(); 2];
        let mut pair = [Matrix2::identity(); 2];
        for k in 0..2 {
            finite(&s[k], "lines2d", i)?;
            let cov = noise.map_or_else(Matrix2::identity, |n| n.lines[i][k]);
            let (ubar, c) = lens
                .undistort_with_covariance(&s[k], &cov, i)
                .map_err(named("lines2d"))?;
            ends[k] = ubar;
            pair[k] = c.ok_or_else(|| singular("lines2d", i))?;
        }
        undistorted.lines2d.push(ends);
        lines.push(pair);
    }
    undistorted.noise = Some(ObservationNoise {
        points,
        lines,
        absolute: noise.is_some_and(|n| n.absolute),
    });
    Ok((camera, undistorted))
}

/// The observations of a pose problem in the two forms the pipeline uses.
pub(crate) struct Observations<'c> {
    /// The pinhole camera of the algebraic stages, the minimal solvers and RANSAC's scoring: the
    /// camera itself, or a lens's pinhole part.
    pub pinhole: Intrinsics,
    /// The correspondences in the pixels of `pinhole`: the observed ones for a pinhole camera, else
    /// undistorted, with the first-order noise of [`undistort`].
    pub undistorted: Cow<'c, Correspondences>,
    /// The correspondences as observed (distorted pixels through a lens), with the caller's noise.
    pub observed: &'c Correspondences,
    /// The lens, when the camera distorts.
    pub lens: Option<&'c Camera>,
}

impl<'c> Observations<'c> {
    /// A pinhole camera's observations: both forms are `corr`.
    pub fn pinhole(camera: &Intrinsics, corr: &'c Correspondences) -> Self {
        Observations {
            pinhole: *camera,
            undistorted: Cow::Borrowed(corr),
            observed: corr,
            lens: None,
        }
    }

    /// The exact reprojection cost of `observed`, correspondences in the pixels of [`Self::observed`]
    /// (the observed ones, conditioned or a subset).
    pub fn cost<'a>(&'a self, observed: &'a Correspondences) -> ReprojectionCost<'a> {
        let mut cost = ReprojectionCost::of(&self.pinhole, observed);
        if let Some(lens) = self.lens {
            // The pinhole part was built from this lens: `through_lens` cannot fail here.
            cost = ReprojectionCost::through_lens(lens, observed).unwrap_or(cost);
        }
        cost
    }

    /// `corr` conditioned as `observed`'s form of these observations: `conditioned` itself (the
    /// conditioned undistorted correspondences) for a pinhole camera, else the observed ones through
    /// `cond`.
    pub fn conditioned_observed(
        &self,
        cond: &Conditioning,
        conditioned: &'c Correspondences,
    ) -> Cow<'c, Correspondences> {
        match self.lens {
            None => Cow::Borrowed(conditioned),
            Some(_) => Cow::Owned(cond.correspondences(self.observed)),
        }
    }
}

/// The input of [`super::estimate_pose`] for a camera with distortion: `corr` holds the observed
/// (distorted) pixels of `lens`, and `corr.noise` optionally their covariances
/// ([`ObservationNoise::from_covariances`]). The stages before the refinement run on the undistorted
/// pixels and the refinement minimises the exact error in the distorted ones ([module docs](self)). The
/// result's pixels (reprojection errors, `sigma_px`) are distorted pixels, or standard deviations with
/// covariances.
///
/// An observation outside the invertible region of the distortion (a pixel no point in front of the
/// camera projects to) is an error naming it, except with RANSAC: there it is an outlier (its inlier flag
/// false, and not counted by the RANSAC report), as a random mismatch at the edge of a fisheye is. The
/// pipeline then runs on the others ([`ThroughLens::observations`]), and [`ThroughLens::expand`] puts its
/// inlier flags back at the places of the caller's correspondences.
pub(crate) struct ThroughLens<'c> {
    lens: &'c Camera,
    /// The correspondences the pipeline sees: the caller's, or those `lens` can unproject.
    kept: Cow<'c, Correspondences>,
    /// Which of the caller's points and segments are in `kept` (empty: all of them).
    points: Vec<bool>,
    lines: Vec<bool>,
    pinhole: Intrinsics,
    undistorted: Correspondences,
}

impl<'c> ThroughLens<'c> {
    /// The observations of `corr` through `lens`, undistorted once (errors as the type docs say).
    pub fn new(lens: &'c Camera, corr: &'c Correspondences, opts: &PoseOptions) -> Result<Self> {
        if let Some(n) = corr.noise.as_ref() {
            n.check_counts(corr.n_points(), corr.n_lines())?;
        }
        // Without RANSAC a pixel beyond the lens is an error (from `undistort`); with it, an outlier.
        let (points, lines) = if opts.ransac.is_some() {
            invertible(lens, corr)
        } else {
            (vec![], vec![])
        };
        let kept = if points.iter().chain(&lines).all(|&ok| ok) {
            Cow::Borrowed(corr)
        } else {
            Cow::Owned(subset(corr, &points, &lines))
        };
        let (pinhole, undistorted) = undistort(lens, &kept, kept.noise.as_ref())?;
        Ok(ThroughLens {
            lens,
            kept,
            points,
            lines,
            pinhole,
            undistorted,
        })
    }

    /// The observations the pipeline runs on.
    pub fn observations(&self) -> Observations<'_> {
        Observations {
            pinhole: self.pinhole,
            undistorted: Cow::Borrowed(&self.undistorted),
            observed: &self.kept,
            lens: Some(self.lens),
        }
    }

    /// `result` of the kept correspondences with its inlier flags at the places of the caller's.
    pub fn expand(&self, mut result: PoseResult) -> PoseResult {
        if matches!(self.kept, Cow::Owned(_)) {
            result.inliers_points = expand(&result.inliers_points, &self.points);
            result.inliers_lines = expand(&result.inliers_lines, &self.lines);
        }
        result
    }
}

/// Which points and segments of `corr` `lens` can unproject (both endpoints for a segment).
fn invertible(lens: &Camera, corr: &Correspondences) -> (Vec<bool>, Vec<bool>) {
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
    use crate::camera::CameraModel;

    #[test]
    fn undistorted_residuals_are_distorted_pixels_to_first_order() {
        let lens = Camera::new(
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
        let moved = lens.project(&x) - u;
        assert!((w * r - moved).norm() < 1e-3 * r.norm(), "{} vs {}", w * r, moved);
    }
}
