//! Image and object lines for pose estimation (Phong & Horaud 1995, section 2, eq. 3 and Figure 2).
//!
//! An image line seen by a calibrated camera defines its *interpretation plane*: the plane through the
//! centre of projection and the line. With normalised homogeneous endpoints `m₁ = (x₁, y₁, 1)`,
//! `m₂ = (x₂, y₂, 1)` its normal is `n = m₁ × m₂` (eq. 3: `aX + bY + cZ = n · FM = 0`). An object line
//! is a point `p` and a unit direction `v` in the world frame.

use crate::error::{Error, Result};
use nalgebra::{Vector2, Vector3};

/// Endpoints closer than this (relative to their size: the angle between the rays of two image
/// endpoints, or the distance of two 3-D endpoints over their magnitude) make a zero-length segment.
const MIN_SEGMENT: f64 = 1e-12;

/// `v / ‖v‖∞` (`v` itself when it is zero): the same direction with every entry in `[-1, 1]`, so that
/// squares and cross products of coordinates up to `f64::MAX` cannot overflow (a segment 1e300 long
/// is long, not zero-length).
fn max_scaled(v: &Vector3<f64>) -> Vector3<f64> {
    let m = v.amax();
    if m > 0.0 {
        v / m
    } else {
        *v
    }
}

/// Unit normal of the interpretation plane of the image segment `xa`–`xb` (normalised image
/// coordinates, `K⁻¹` applied), in the camera frame: [`crate::Intrinsics::interpretation_plane_normal`]
/// from pixels.
///
/// Fails with [`Error::Degenerate`] when the endpoints coincide: their viewing rays are less than
/// `MIN_SEGMENT` radians apart (scale-free, so neither pixels near 1e300 nor subnormal ones fool it).
pub(crate) fn interpretation_plane_normal(xa: Vector2<f64>, xb: Vector2<f64>) -> Result<Vector3<f64>> {
    let ray = |x: Vector2<f64>| max_scaled(&Vector3::new(x.x, x.y, 1.0)).normalize();
    let n = ray(xa).cross(&ray(xb));
    let norm = n.norm();
    if !(norm > MIN_SEGMENT) {
        return Err(Error::Degenerate {
            what: "zero-length image segment".into(),
        });
    }
    Ok(n / norm)
}

/// A 3-D line as a point and a unit direction (world frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ObjectLine {
    /// A point on the line: the midpoint of the segment it was built from.
    pub point: Vector3<f64>,
    /// Unit direction.
    pub direction: Vector3<f64>,
}

impl ObjectLine {
    /// The line through two distinct 3-D points; fails on a zero-length segment.
    /// The test is `‖b − a‖ ≤ MIN_SEGMENT (1 + ‖a‖ + ‖b‖)`, evaluated on coordinates scaled by their
    /// largest magnitude so that it cannot overflow.
    pub fn from_endpoints(a: &Vector3<f64>, b: &Vector3<f64>) -> Result<Self> {
        let scale = a.amax().max(b.amax()).max(1.0);
        let (a_s, b_s) = (a / scale, b / scale);
        let d = b_s - a_s;
        let len = d.norm();
        if !(len > MIN_SEGMENT * (1.0 / scale + a_s.norm() + b_s.norm())) {
            return Err(Error::Degenerate {
                what: "zero-length 3-D segment".into(),
            });
        }
        Ok(ObjectLine {
            point: 0.5 * a + 0.5 * b,
            direction: d / len,
        })
    }
}

/// Image segments (pixel endpoints) and the matching 3-D segments (world endpoints).
pub type SegmentPairs = (Vec<[Vector2<f64>; 2]>, Vec<[Vector3<f64>; 2]>);

/// Figure 2: `N` line correspondences from `2N` point correspondences, pairing points `(0,1), (2,3), …`.
///
/// Returns image segments (pixel endpoints) and 3-D segments (world endpoints); an odd last point is
/// dropped. Any three non-collinear points of the pairs give a well-posed line problem.
pub fn lines_from_point_pairs(points2d: &[Vector2<f64>], points3d: &[Vector3<f64>]) -> SegmentPairs {
    let n = points2d.len().min(points3d.len()) / 2;
    let segs2d = (0..n).map(|i| [points2d[2 * i], points2d[2 * i + 1]]).collect();
    let segs3d = (0..n).map(|i| [points3d[2 * i], points3d[2 * i + 1]]).collect();
    (segs2d, segs3d)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_zero_length_3d_segment_is_refused() {
        let pa = Vector3::new(1.0, -2.0, 60.0);
        assert!(ObjectLine::from_endpoints(&pa, &pa).is_err());
    }

    #[test]
    fn point_pairs_make_lines() {
        let p2: Vec<_> = (0..5).map(|i| Vector2::new(i as f64, 0.0)).collect();
        let p3: Vec<_> = (0..5).map(|i| Vector3::new(i as f64, 1.0, 2.0)).collect();
        let (l2, l3) = lines_from_point_pairs(&p2, &p3);
        assert_eq!(l2.len(), 2);
        assert_eq!(l3[1], [p3[2], p3[3]]);
    }
}
