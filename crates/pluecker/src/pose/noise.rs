//! Per-observation noise of the pose: 2x2 covariances of image points and segment endpoints, and the
//! first-order account of a lens's distortion. Josephson & Kahl 2008 weight each observation by its
//! covariance (eq. 18, the Mahalanobis distance); this module applies the same weighting to the pose.
//!
//! With an [`ObservationNoise`] on the [`Correspondences`](super::Correspondences), the residuals of
//! [`super::reprojection::ReprojectionCost`] become:
//! - a point: `W_i (π(R X + t) − u_i)`, where `W_i` whitens the pixel residual (`W_iᵀ W_i = Σ_i⁻¹`);
//! - a segment endpoint `e`: `(l·ẽ) / √(l₁₂ᵀ C_e l₁₂)`, where `l` is the projected line in pixels,
//!   `l₁₂` its first two entries and `C_e` the endpoint's covariance: its distance to the line in
//!   standard deviations across the line. With `C_e = I` this is the plain pixel distance.
//!
//! Through a lens ([`super::lens`]) the noise also carries the distortion's Jacobians.

use crate::covariance::whitening;
use crate::error::{Error, Result};
use nalgebra::Matrix2;

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

impl ObservationNoise {
    /// The noise of covariances (pixels², in the frame of the correspondences): one 2x2 per point and
    /// one per segment endpoint, checked and whitened as triangulation's are
    /// ([`crate::covariance::whitening`]). Errors name the argument
    /// (`point_covariances`, `line_covariances`) and the index.
    pub fn from_covariances(points: &[Matrix2<f64>], lines: &[[Matrix2<f64>; 2]]) -> Result<ObservationNoise> {
        let points = points
            .iter()
            .enumerate()
            .map(|(i, c)| whitening(c, "point_covariances", i))
            .collect::<Result<Vec<_>>>()?;
        for (i, pair) in lines.iter().enumerate() {
            for c in pair {
                whitening(c, "line_covariances", i)?;
            }
        }
        Ok(ObservationNoise {
            points,
            lines: lines.to_vec(),
            absolute: true,
        })
    }

    /// `Error::Shape` unless there is one entry per point and per segment (`n_points`, `n_lines`).
    pub fn check_counts(&self, n_points: usize, n_lines: usize) -> Result<()> {
        for (what, have, want) in [
            ("point_covariances", self.points.len(), n_points),
            ("line_covariances", self.lines.len(), n_lines),
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

#[cfg(test)]
mod tests {
    use super::*;

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
}
