//! The input of pose estimation, its validation, and the similarity that conditions it.

use super::algebraic::{LineConstraint, PointConstraint};
use super::noise::ObservationNoise;
use super::Method;
use crate::camera::Intrinsics;
use crate::error::{Error, Result};
use crate::geometry::lines::{lines_from_point_pairs, ObjectLine};
use nalgebra::{DMatrix, Matrix3, SVector, Vector2, Vector3};

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
    /// Per-observation covariances (or a lens's distortion, [`super::lens::undistort`]) that weight
    /// the reprojection residuals. `None`: isotropic pixel noise, the plain reprojection error.
    pub noise: Option<ObservationNoise>,
}

/// Relative size below which a spread of points or directions counts as degenerate.
pub(crate) const DEGENERACY_TOLERANCE: f64 = 1e-9;

fn check_finite<'a, I: IntoIterator<Item = &'a f64>>(what: &str, rows: impl Iterator<Item = I>) -> Result<()> {
    for (index, row) in rows.enumerate() {
        if row.into_iter().any(|v| !v.is_finite()) {
            return Err(Error::NonFinite {
                what: what.into(),
                index,
            });
        }
    }
    Ok(())
}

/// [`Error::InvalidOption`] naming the 3-D argument whose coordinates overflow double precision when
/// squared and summed (the centroid, spread and costs of every method need `Σ ‖X‖²`): a segment 1e300
/// long is out of range, not zero-length.
fn check_squares_finite(c: &Correspondences) -> Result<()> {
    let sum = |points: &mut dyn Iterator<Item = &Vector3<f64>>| points.map(|p| p.norm_squared()).sum::<f64>();
    let out_of_range = |name: &str, largest: f64| Error::InvalidOption {
        name: name.into(),
        reason: format!(
            "coordinates up to {largest:e} overflow double precision when squared and summed; rescale the 3-D data"
        ),
    };
    let largest = |points: &mut dyn Iterator<Item = &Vector3<f64>>| points.map(|p| p.amax()).fold(0.0, f64::max);
    if !sum(&mut c.points3d.iter()).is_finite() {
        return Err(out_of_range("points3d", largest(&mut c.points3d.iter())));
    }
    if !sum(&mut c.lines3d.iter().flatten()).is_finite() {
        return Err(out_of_range("lines3d", largest(&mut c.lines3d.iter().flatten())));
    }
    if !sum(&mut object_points(c)).is_finite() {
        return Err(out_of_range("points3d / lines3d", largest(&mut object_points(c))));
    }
    Ok(())
}

/// The shape of a point set: centroid, RMS distance to it, and principal axes.
#[derive(Debug, Clone, Copy)]
pub(crate) struct PointSpread {
    /// Mean of the points.
    pub centroid: Vector3<f64>,
    /// Root-mean-square distance to the centroid.
    pub rms_radius: f64,
    /// Standard deviations along the principal axes, largest first, from the closed-form eigenvalues
    /// of the scatter matrix (absolute error a few ulps of the largest eigenvalue).
    pub spread: Vector3<f64>,
    /// `Σ (p − c)(p − c)ᵀ`.
    scatter: Matrix3<f64>,
}

/// Above this ratio of closed-form standard deviations a spread is certainly not degenerate; at or
/// below it the singular values of the centred points decide. The closed form loses up to half the
/// digits near repeated eigenvalues (two near-zero ones for collinear points): errors of order √ε λ_max
/// in an eigenvalue, 1e-4 in a ratio of standard deviations.
const CLEARLY_SPREAD: f64 = 1e-2;

impl PointSpread {
    /// Unit axis of least spread (an eigen-decomposition: only the restarts need it).
    pub fn least_axis(&self) -> Vector3<f64> {
        let eig = self.scatter.symmetric_eigen();
        eig.eigenvectors.column(eig.eigenvalues.imin()).into_owned()
    }

    /// Whether the `k`-th standard deviation of `points` (the points of this shape) is at most
    /// `tolerance` times the largest. Clear cases are settled by the closed form; the others by the
    /// singular values of the centred points, accurate to ε relative to the largest — the scatter
    /// matrix squares the ratio, and its eigenvalues cannot resolve ratios of deviations below √ε.
    pub(crate) fn degenerate<'p>(
        &self,
        points: impl Iterator<Item = &'p Vector3<f64>>,
        k: usize,
        tolerance: f64,
    ) -> bool {
        if self.spread[k] > CLEARLY_SPREAD * self.spread[0] {
            return false;
        }
        let centred: Vec<f64> = points
            .map(|p| p - self.centroid)
            .flat_map(|d| [d.x, d.y, d.z])
            .collect();
        let mut s = DMatrix::from_row_slice(centred.len() / 3, 3, &centred).singular_values();
        s.as_mut_slice().sort_by(|a, b| b.total_cmp(a));
        s[k] <= tolerance * s[0]
    }
}

/// Eigenvalues of a symmetric 3x3 matrix, largest first, in closed form (the trigonometric solution
/// of the characteristic cubic).
fn symmetric_eigenvalues(m: &Matrix3<f64>) -> Vector3<f64> {
    let off = m[(0, 1)].powi(2) + m[(0, 2)].powi(2) + m[(1, 2)].powi(2);
    let q = m.trace() / 3.0;
    let diagonal = m.diagonal().map(|v| v - q);
    let p = ((diagonal.norm_squared() + 2.0 * off) / 6.0).sqrt();
    if !(p > 0.0) {
        let mut d = m.diagonal();
        d.as_mut_slice().sort_by(|a, b| b.total_cmp(a));
        return d;
    }
    let b = (m - Matrix3::from_diagonal_element(q)) / p;
    let phi = (0.5 * b.determinant()).clamp(-1.0, 1.0).acos() / 3.0;
    let largest = q + 2.0 * p * phi.cos();
    let smallest = q + 2.0 * p * (phi + 2.0 * std::f64::consts::FRAC_PI_3).cos();
    Vector3::new(largest, 3.0 * q - largest - smallest, smallest)
}

/// The centroid, RMS radius and principal axes of a (non-empty) point set.
pub(crate) fn principal_axes<'p>(points: impl Iterator<Item = &'p Vector3<f64>> + Clone) -> PointSpread {
    let n = points.clone().count().max(1) as f64;
    let centroid = points.clone().fold(Vector3::zeros(), |a, p| a + p) / n;
    let mut m = [0.0; 6]; // xx, xy, xz, yy, yz, zz
    for p in points {
        let d = p - centroid;
        for (k, (i, j)) in [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)].into_iter().enumerate() {
            m[k] += d[i] * d[j];
        }
    }
    let scatter = Matrix3::new(m[0], m[1], m[2], m[1], m[3], m[4], m[2], m[4], m[5]);
    let spread = symmetric_eigenvalues(&scatter).map(|v| v.max(0.0).sqrt());
    PointSpread {
        centroid,
        rms_radius: ((m[0] + m[3] + m[5]) / n).sqrt(),
        spread,
        scatter,
    }
}

/// Every object point of `c`: the points, then both endpoints of every segment.
pub(crate) fn object_points(c: &Correspondences) -> impl Iterator<Item = &Vector3<f64>> + Clone {
    c.points3d.iter().chain(c.lines3d.iter().flat_map(|s| s.iter()))
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
        self.validated(method).map(|_| ())
    }

    /// [`Correspondences::validate`], returning the shape of all object points (points and segment
    /// endpoints), which the checks need and the estimators use again.
    pub(crate) fn validated(&self, method: Method) -> Result<PointSpread> {
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
        if let Some(noise) = &self.noise {
            noise.check_counts(self.n_points(), self.n_lines())?;
        }
        check_finite("points2d", self.points2d.iter().map(|p| p.iter()))?;
        check_finite("points3d", self.points3d.iter().map(|p| p.iter()))?;
        check_finite("lines2d", self.lines2d.iter().map(|s| s[0].iter().chain(s[1].iter())))?;
        check_finite("lines3d", self.lines3d.iter().map(|s| s[0].iter().chain(s[1].iter())))?;
        check_squares_finite(self)?;
        for (i, s) in self.lines2d.iter().enumerate() {
            if zero_length(&s[0], &s[1]) {
                return Err(Error::Degenerate {
                    what: format!("lines2d[{i}] is a zero-length segment"),
                });
            }
        }
        for (i, s) in self.lines3d.iter().enumerate() {
            if zero_length(&s[0], &s[1]) {
                return Err(Error::Degenerate {
                    what: format!("lines3d[{i}] is a zero-length segment"),
                });
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
                if principal_axes(self.points3d.iter()).degenerate(self.points3d.iter(), 2, DEGENERACY_TOLERANCE) {
                    return Err(Error::Degenerate {
                        what: "points3d are coplanar; the linear (Faugeras-Toscani) method needs non-coplanar points"
                            .into(),
                    });
                }
            }
            Method::RotationThenTranslation => {
                if nl + np / 2 < 3 {
                    return Err(too_few(
                        "at least 3 lines, counting each pair of points as a line (Figure 2)",
                    ));
                }
            }
            _ => {
                if np + nl < 3 {
                    return Err(too_few("at least 3 correspondences (points and lines together)"));
                }
            }
        }
        let shape = principal_axes(object_points(self));
        if nl == 0 && shape.degenerate(object_points(self), 1, DEGENERACY_TOLERANCE) {
            return Err(Error::Degenerate {
                what: "all points3d are collinear".into(),
            });
        }
        if np == 0 {
            self.check_line_configuration()?;
        }
        Ok(shape)
    }

    fn check_line_configuration(&self) -> Result<()> {
        let lines: Vec<ObjectLine> = self
            .lines3d
            .iter()
            .map(|s| ObjectLine::from_endpoints(&s[0], &s[1]))
            .collect::<Result<_>>()?;
        let d0 = lines[0].direction;
        if lines.iter().all(|l| l.direction.cross(&d0).norm() <= 1e-9) {
            return Err(Error::Degenerate {
                what: "all lines3d are parallel".into(),
            });
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
            let scale = lines
                .iter()
                .map(|l| (l.point - x).norm())
                .fold(0.0, f64::max)
                .max(1e-300);
            let far = lines.iter().map(|l| {
                let v = l.point - x;
                (v - l.direction * l.direction.dot(&v)).norm()
            });
            if far.fold(0.0, f64::max) <= 1e-9 * scale {
                return Err(Error::Degenerate {
                    what: "all lines3d pass through one point".into(),
                });
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
    /// The object's centroid, world frame.
    pub centre: Vector3<f64>,
    /// Its RMS radius about the centroid, world units.
    pub scale: f64,
}

impl Conditioning {
    /// The identity (no conditioning).
    pub fn identity() -> Self {
        Conditioning {
            centre: Vector3::zeros(),
            scale: 1.0,
        }
    }

    /// Centroid and RMS radius of every 3-D point and segment endpoint.
    pub fn of(c: &Correspondences) -> Self {
        let all = object_points(c);
        let n = all.clone().count().max(1) as f64;
        let centre = all.clone().fold(Vector3::zeros(), |a, p| a + p) / n;
        let rms = (all.map(|p| (p - centre).norm_squared()).sum::<f64>() / n).sqrt();
        Conditioning {
            centre,
            scale: if rms > 0.0 { rms } else { 1.0 },
        }
    }

    /// The conditioning of a point set whose shape is known.
    pub(crate) fn of_shape(shape: &PointSpread) -> Self {
        let rms = shape.rms_radius;
        Conditioning {
            centre: shape.centroid,
            scale: if rms > 0.0 { rms } else { 1.0 },
        }
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
        // One division, then products: the same map as `apply` to within an ulp.
        let inv = 1.0 / self.scale;
        let apply = |x: &Vector3<f64>| (x - self.centre) * inv;
        Correspondences {
            points2d: c.points2d.clone(),
            points3d: c.points3d.iter().map(apply).collect(),
            lines2d: c.lines2d.clone(),
            lines3d: c.lines3d.iter().map(|s| [apply(&s[0]), apply(&s[1])]).collect(),
            noise: c.noise.clone(),
        }
    }
}

/// `‖a − b‖ ≤ DEGENERACY_TOLERANCE (1 + ‖a‖)`, evaluated on coordinates divided by their largest
/// magnitude (at least 1) so that endpoints 1e300 apart do not overflow into a zero length.
fn zero_length<const D: usize>(a: &SVector<f64, D>, b: &SVector<f64, D>) -> bool {
    let scale = a.amax().max(b.amax()).max(1.0);
    let (a, b) = (a / scale, b / scale);
    !((a - b).norm() > DEGENERACY_TOLERANCE * (1.0 / scale + a.norm()))
}

/// The constraints of the dual-quaternion costs: normalised image points and interpretation-plane
/// normals. With `points_as_lines`, points are also paired into lines (Figure 2) and appended.
pub fn constraints(
    camera: &Intrinsics,
    c: &Correspondences,
    points_as_lines: bool,
) -> Result<(Vec<PointConstraint>, Vec<LineConstraint>)> {
    // `Intrinsics::pixel_to_normalized` with the two divisions replaced by products (hot with many points).
    let (inv_fx, inv_fy) = (1.0 / camera.fx, 1.0 / camera.fy);
    let points = c
        .points2d
        .iter()
        .zip(&c.points3d)
        .map(|(u, x)| {
            let y = (u.y - camera.cy) * inv_fy;
            PointConstraint {
                image: Vector2::new((u.x - camera.cx - camera.skew * y) * inv_fx, y),
                object: *x,
            }
        })
        .collect();
    let (extra2d, extra3d) = if points_as_lines {
        lines_from_point_pairs(&c.points2d, &c.points3d)
    } else {
        (vec![], vec![])
    };
    let lines = c
        .lines2d
        .iter()
        .chain(&extra2d)
        .zip(c.lines3d.iter().chain(&extra3d))
        .enumerate()
        .map(|(i, (s2, s3))| {
            let short = |kind: &str| short_segment(kind, i, c.lines2d.len());
            Ok(LineConstraint {
                normal: camera
                    .interpretation_plane_normal(&s2[0], &s2[1])
                    .map_err(|_| short("2d"))?,
                object: ObjectLine::from_endpoints(&s3[0], &s3[1]).map_err(|_| short("3d"))?,
            })
        })
        .collect::<Result<_>>()?;
    Ok((points, lines))
}

/// The error of constraint `i` (a segment, or past `n_lines` a pair of points, Figure 2) whose endpoints
/// coincide at the scale of the data: [`Correspondences::validate`] has rejected segments of zero
/// length, so this one is negligible next to the extent of the data (`kind` `"2d"` or `"3d"`).
fn short_segment(kind: &str, i: usize, n_lines: usize) -> Error {
    let what = if i < n_lines {
        format!("lines{kind}[{i}] is shorter than 1e-12 of the extent of the data")
    } else {
        let k = 2 * (i - n_lines);
        format!(
            "points{kind}[{k}] and points{kind}[{}] are closer than 1e-12 of the extent of the data",
            k + 1
        )
    };
    Error::Degenerate { what }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn points_only(points3d: Vec<Vector3<f64>>) -> Correspondences {
        Correspondences {
            points2d: vec![Vector2::new(1.0, 2.0); points3d.len()],
            points3d,
            ..Default::default()
        }
    }

    #[test]
    fn collinear_and_coplanar_points_are_degenerate_along_any_direction() {
        // Steps of 2/9 along a generic direction: the scatter matrix is rank one only up to round-off,
        // where the closed-form eigenvalues are least accurate.
        let direction = Vector3::new(1.0, 0.5, 0.2);
        let line: Vec<Vector3<f64>> = (0..10)
            .map(|i| Vector3::new(0.0, 0.0, 5.0) + direction * (-1.0 + 2.0 * i as f64 / 9.0))
            .collect();
        for &method in Method::ALL {
            assert!(
                matches!(
                    points_only(line.clone()).validate(method),
                    Err(Error::Degenerate { .. })
                ),
                "{method:?}"
            );
        }
        let other = Vector3::new(-0.3, 0.9, 0.4);
        let plane: Vec<Vector3<f64>> = (0..12)
            .map(|i| Vector3::new(0.0, 0.0, 5.0) + direction * (i % 4) as f64 / 3.0 + other * (i / 4) as f64 / 7.0)
            .collect();
        assert!(matches!(
            points_only(plane.clone()).validate(Method::Linear),
            Err(Error::Degenerate { .. })
        ));
        assert!(points_only(plane).validate(Method::TrustRegion).is_ok());
    }

    #[test]
    fn closed_form_spread_matches_the_eigen_decomposition() {
        let mut rng = crate::rng::Rng::new(3);
        for _ in 0..100 {
            let axes = Vector3::new(1.0, rng.uniform_in(0.3, 1.0), 1e-3 * rng.uniform());
            let rotation = rng.rotation();
            let points: Vec<Vector3<f64>> = (0..30)
                .map(|_| rotation * Vector3::new(rng.normal(), rng.normal(), rng.normal()).component_mul(&axes))
                .collect();
            let shape = principal_axes(points.iter());
            let mut exact = shape.scatter.symmetric_eigenvalues().map(|v| v.max(0.0).sqrt());
            exact.as_mut_slice().sort_by(|a, b| b.total_cmp(a));
            // Eigenvalue errors of order √ε λ_max (see CLEARLY_SPREAD), so √(1e-7) in a deviation.
            assert!(
                (shape.spread - exact).amax() <= 1e-3 * exact[0],
                "{} vs {}",
                shape.spread,
                exact
            );
            assert!((shape.least_axis().dot(&(rotation * Vector3::z())).abs() - 1.0).abs() < 1e-6);
        }
    }
}
