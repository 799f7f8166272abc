//! The input of pose estimation, its validation, and the similarity that conditions it.

use super::algebraic::{LineConstraint, PointConstraint};
use super::Method;
use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::geometry::lines::{interpretation_plane_normal, lines_from_point_pairs, ObjectLine};
use nalgebra::{Matrix3, Vector2, Vector3};

/// 2-D/3-D correspondences. Image quantities are pixels, object quantities world coordinates
/// (any length unit; the translation comes out in the same unit).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Correspondences {
    /// Observed image points, pixels, one per row of `points3d`.
    pub points2d: Vec<Vector2<f64>>,
    /// Object points, world frame.
    pub points3d: Vec<Vector3<f64>>,
    /// Observed image segments (two pixel endpoints), one per row of `lines3d`.
    pub lines2d: Vec<[Vector2<f64>; 2]>,
    /// Object segments (two world endpoints). The endpoints need not correspond to the image ones:
    /// only the 3-D line through them is used.
    pub lines3d: Vec<[Vector3<f64>; 2]>,
}

/// Relative size below which a spread of points or directions counts as degenerate.
const DEGENERACY_TOLERANCE: f64 = 1e-9;

fn check_finite<'a, I: IntoIterator<Item = &'a f64>>(what: &str, rows: impl Iterator<Item = I>) -> Result<()> {
    for (index, row) in rows.enumerate() {
        if row.into_iter().any(|v| !v.is_finite()) {
            return Err(Error::NonFinite { what: what.into(), index });
        }
    }
    Ok(())
}

/// The principal axes of a point set: its centroid, the standard deviations along the axes (largest
/// first) and the unit axis of least spread.
pub(crate) fn principal_axes(points: &[Vector3<f64>]) -> (Vector3<f64>, Vector3<f64>, Vector3<f64>) {
    let n = points.len().max(1) as f64;
    let c = points.iter().sum::<Vector3<f64>>() / n;
    let scatter: Matrix3<f64> = points.iter().map(|p| (p - c) * (p - c).transpose()).sum();
    let eig = scatter.symmetric_eigen();
    let least_axis = eig.eigenvectors.column(eig.eigenvalues.imin()).into_owned();
    let mut s = eig.eigenvalues.map(|v| v.max(0.0).sqrt());
    s.as_mut_slice().sort_by(|a, b| b.total_cmp(a));
    (c, s, least_axis)
}

/// Standard deviations of `points` along their principal axes, largest first.
fn spread(points: &[Vector3<f64>]) -> Vector3<f64> {
    principal_axes(points).1
}

impl Correspondences {
    /// Number of point correspondences.
    pub fn n_points(&self) -> usize {
        self.points2d.len()
    }

    /// Number of line correspondences.
    pub fn n_lines(&self) -> usize {
        self.lines2d.len()
    }

    /// Checks shapes, finiteness, zero-length segments, counts for `method`, and the degenerate
    /// configurations no method can solve (all points collinear; all lines parallel or concurrent).
    pub fn validate(&self, method: Method) -> Result<()> {
        if self.points2d.len() != self.points3d.len() {
            return Err(Error::Shape {
                what: "points2d / points3d".into(),
                expected: "the same number of rows".into(),
                actual: format!("{} and {}", self.points2d.len(), self.points3d.len()),
            });
        }
        if self.lines2d.len() != self.lines3d.len() {
            return Err(Error::Shape {
                what: "lines2d / lines3d".into(),
                expected: "the same number of segments".into(),
                actual: format!("{} and {}", self.lines2d.len(), self.lines3d.len()),
            });
        }
        check_finite("points2d", self.points2d.iter().map(|p| p.iter()))?;
        check_finite("points3d", self.points3d.iter().map(|p| p.iter()))?;
        check_finite("lines2d", self.lines2d.iter().map(|s| s[0].iter().chain(s[1].iter())))?;
        check_finite("lines3d", self.lines3d.iter().map(|s| s[0].iter().chain(s[1].iter())))?;
        for (i, s) in self.lines2d.iter().enumerate() {
            if (s[0] - s[1]).norm() <= DEGENERACY_TOLERANCE * (1.0 + s[0].norm()) {
                return Err(Error::Degenerate { what: format!("lines2d[{i}] is a zero-length segment") });
            }
        }
        for (i, s) in self.lines3d.iter().enumerate() {
            if (s[0] - s[1]).norm() <= DEGENERACY_TOLERANCE * (1.0 + s[0].norm()) {
                return Err(Error::Degenerate { what: format!("lines3d[{i}] is a zero-length segment") });
            }
        }
        let (np, nl) = (self.n_points(), self.n_lines());
        let too_few = |required: &str| Error::TooFewCorrespondences {
            method: method.as_str().into(),
            required: required.into(),
            actual: format!("{np} points and {nl} lines"),
        };
        match method {
            Method::Linear => {
                if np < 6 {
                    return Err(too_few("at least 6 points (lines are not used)"));
                }
                let s = spread(&self.points3d);
                if s[2] <= DEGENERACY_TOLERANCE * s[0] {
                    return Err(Error::Degenerate {
                        what: "points3d are coplanar; the linear (Faugeras-Toscani) method needs non-coplanar points"
                            .into(),
                    });
                }
            }
            Method::RotationThenTranslation => {
                if nl + np / 2 < 3 {
                    return Err(too_few("at least 3 lines, counting each pair of points as a line (Figure 2)"));
                }
            }
            _ => {
                if np + nl < 3 {
                    return Err(too_few("at least 3 correspondences (points and lines together)"));
                }
            }
        }
        if nl == 0 {
            let s = spread(&self.points3d);
            if s[1] <= DEGENERACY_TOLERANCE * s[0] {
                return Err(Error::Degenerate { what: "all points3d are collinear".into() });
            }
        }
        if np == 0 {
            self.check_line_configuration()?;
        }
        Ok(())
    }

    fn check_line_configuration(&self) -> Result<()> {
        let lines: Vec<ObjectLine> =
            self.lines3d.iter().map(|s| ObjectLine::from_endpoints(&s[0], &s[1])).collect::<Result<_>>()?;
        let d0 = lines[0].direction;
        if lines.iter().all(|l| l.direction.cross(&d0).norm() <= 1e-9) {
            return Err(Error::Degenerate { what: "all lines3d are parallel".into() });
        }
        // Concurrent lines: the point nearest to all lines (least squares) lies on every one of them.
        let mut a = Matrix3::zeros();
        let mut b = Vector3::zeros();
        for l in &lines {
            let p = Matrix3::identity() - l.direction * l.direction.transpose();
            a += p;
            b += p * l.point;
        }
        if let Some(x) = a.try_inverse().map(|inv| inv * b) {
            let scale = lines.iter().map(|l| (l.point - x).norm()).fold(0.0, f64::max).max(1e-300);
            let far = lines.iter().map(|l| {
                let v = l.point - x;
                (v - l.direction * l.direction.dot(&v)).norm()
            });
            if far.fold(0.0, f64::max) <= 1e-9 * scale {
                return Err(Error::Degenerate { what: "all lines3d pass through one point".into() });
            }
        }
        Ok(())
    }
}

/// The similarity `X' = (X − centre) / scale` that centres the object and gives it unit RMS radius.
/// The algebraic costs are not invariant to the world frame; solving in this frame makes them so
/// (Hartley-style normalisation). A pose `(R, t')` found there is `(R, scale·t' − R centre)` in the world.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Conditioning {
    pub centre: Vector3<f64>,
    pub scale: f64,
}

impl Conditioning {
    /// The identity (no conditioning).
    pub fn identity() -> Self {
        Conditioning { centre: Vector3::zeros(), scale: 1.0 }
    }

    /// Centroid and RMS radius of every 3-D point and segment endpoint.
    pub fn of(c: &Correspondences) -> Self {
        let all: Vec<Vector3<f64>> = c.points3d.iter().copied().chain(c.lines3d.iter().flat_map(|s| s.iter().copied())).collect();
        let n = all.len().max(1) as f64;
        let centre = all.iter().sum::<Vector3<f64>>() / n;
        let rms = (all.iter().map(|p| (p - centre).norm_squared()).sum::<f64>() / n).sqrt();
        Conditioning { centre, scale: if rms > 0.0 { rms } else { 1.0 } }
    }

    /// World → conditioned.
    pub fn apply(&self, x: &Vector3<f64>) -> Vector3<f64> {
        (x - self.centre) / self.scale
    }

    /// A conditioned-frame pose back to the world frame.
    pub fn pose_to_world(&self, rot: &Matrix3<f64>, t: &Vector3<f64>) -> Vector3<f64> {
        self.scale * t - rot * self.centre
    }

    /// A world-frame translation to the conditioned frame.
    pub fn pose_from_world(&self, rot: &Matrix3<f64>, t: &Vector3<f64>) -> Vector3<f64> {
        (t + rot * self.centre) / self.scale
    }

    /// The correspondences with their 3-D side conditioned.
    pub fn correspondences(&self, c: &Correspondences) -> Correspondences {
        Correspondences {
            points2d: c.points2d.clone(),
            points3d: c.points3d.iter().map(|p| self.apply(p)).collect(),
            lines2d: c.lines2d.clone(),
            lines3d: c.lines3d.iter().map(|s| [self.apply(&s[0]), self.apply(&s[1])]).collect(),
        }
    }
}

/// The constraints of the dual-quaternion costs: normalised image points and interpretation-plane
/// normals. With `points_as_lines`, points are also paired into lines (Figure 2) and appended.
pub fn constraints(
    camera: &Camera,
    c: &Correspondences,
    points_as_lines: bool,
) -> Result<(Vec<PointConstraint>, Vec<LineConstraint>)> {
    let points = c
        .points2d
        .iter()
        .zip(&c.points3d)
        .map(|(u, x)| PointConstraint { image: camera.pixel_to_normalized(u), object: *x })
        .collect();
    let (extra2d, extra3d) = if points_as_lines { lines_from_point_pairs(&c.points2d, &c.points3d) } else { (vec![], vec![]) };
    let lines = c
        .lines2d
        .iter()
        .chain(&extra2d)
        .zip(c.lines3d.iter().chain(&extra3d))
        .map(|(s2, s3)| {
            Ok(LineConstraint {
                normal: interpretation_plane_normal(camera, &s2[0], &s2[1])?,
                object: ObjectLine::from_endpoints(&s3[0], &s3[1])?,
            })
        })
        .collect::<Result<_>>()?;
    Ok((points, lines))
}

