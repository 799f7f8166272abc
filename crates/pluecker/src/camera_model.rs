//! Camera models with lens distortion, with COLMAP's names and parameter orders (`colmap/sensor/models.h`),
//! so that a COLMAP camera's `model` and `params` mean the same here.
//!
//! A model maps a camera-frame point `x_cam` (in front: `z > 0`) to pixels in three steps:
//! 1. normalised coordinates `n = (x/z, y/z)`;
//! 2. the distortion `d = D(n)`, in normalised units (identity for the pinhole models);
//! 3. pixels `u = (fx d₁ + cx, fy d₂ + cy)`.
//!
//! | model | parameters | distortion `D(n)`, with `r² = n·n` |
//! |---|---|---|
//! | `SIMPLE_PINHOLE` | f, cx, cy | none |
//! | `PINHOLE` | fx, fy, cx, cy | none |
//! | `SIMPLE_RADIAL` | f, cx, cy, k | `n (1 + k r²)` |
//! | `RADIAL` | f, cx, cy, k1, k2 | `n (1 + k1 r² + k2 r⁴)` |
//! | `OPENCV` | fx, fy, cx, cy, k1, k2, p1, p2 | `n (1 + k1 r² + k2 r⁴) + t(n)` |
//! | `FULL_OPENCV` | fx, fy, cx, cy, k1, k2, p1, p2, k3, k4, k5, k6 | `n (1 + k1 r² + k2 r⁴ + k3 r⁶) / (1 + k4 r² + k5 r⁴ + k6 r⁶) + t(n)` |
//! | `OPENCV_FISHEYE` | fx, fy, cx, cy, k1, k2, k3, k4 | `n θ (1 + k1 θ² + k2 θ⁴ + k3 θ⁶ + k4 θ⁸) / r`, `θ = atan r` |
//!
//! `t(n) = (2 p1 n₁n₂ + p2 (r² + 2n₁²), p1 (r² + 2n₂²) + 2 p2 n₁n₂)` is the tangential term.
//!
//! **Unprojection** inverts the distortion by Newton's method on `D(n) = d`, with the analytic Jacobian.
//! It stops when the residual, in pixels, is below [`UNPROJECTION_TOLERANCE_PX`] (1e-10 px). The answer
//! must be in the invertible region: the Jacobian of `D` must have a positive determinant there, so
//! that the distortion is locally one-to-one and keeps the orientation, and it must lie inside the
//! fold radius ([`fold_radius`]), the first radius where the radial distortion stops increasing. A
//! strong barrel distortion folds the image beyond that radius: pixels past the fold have no preimage
//! on the branch through the principal point (a polynomial such as RADIAL's may rise again further
//! out, where Newton's method would otherwise find a preimage on the outer branch) and are rejected
//! with [`Error::Degenerate`] naming the point.

use crate::error::{number, Error, Result};
use nalgebra::{Matrix2, Vector2, Vector3};

/// The camera models, with COLMAP's names (see the module table for their parameters).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum CameraModel {
    SimplePinhole,
    Pinhole,
    SimpleRadial,
    Radial,
    OpenCv,
    FullOpenCv,
    OpenCvFisheye,
}

impl CameraModel {
    /// Every model, in COLMAP's order of model ids (0-6: the same ids as COLMAP's).
    pub const ALL: [CameraModel; 7] = [
        CameraModel::SimplePinhole,
        CameraModel::Pinhole,
        CameraModel::SimpleRadial,
        CameraModel::Radial,
        CameraModel::OpenCv,
        CameraModel::OpenCvFisheye,
        CameraModel::FullOpenCv,
    ];

    /// COLMAP's name of the model.
    pub fn as_str(&self) -> &'static str {
        match self {
            CameraModel::SimplePinhole => "SIMPLE_PINHOLE",
            CameraModel::Pinhole => "PINHOLE",
            CameraModel::SimpleRadial => "SIMPLE_RADIAL",
            CameraModel::Radial => "RADIAL",
            CameraModel::OpenCv => "OPENCV",
            CameraModel::FullOpenCv => "FULL_OPENCV",
            CameraModel::OpenCvFisheye => "OPENCV_FISHEYE",
        }
    }

    /// The model of a COLMAP name; `Error::InvalidOption` naming the known ones otherwise.
    pub fn parse(name: &str) -> Result<CameraModel> {
        CameraModel::ALL
            .into_iter()
            .find(|m| m.as_str() == name)
            .ok_or_else(|| Error::InvalidOption {
                name: "model".into(),
                reason: format!(
                    "unknown camera model '{name}'; expected one of {}",
                    CameraModel::ALL.map(|m| m.as_str()).join(", ")
                ),
            })
    }

    /// The parameter names, in COLMAP's order.
    pub fn parameter_names(&self) -> &'static [&'static str] {
        match self {
            CameraModel::SimplePinhole => &["f", "cx", "cy"],
            CameraModel::Pinhole => &["fx", "fy", "cx", "cy"],
            CameraModel::SimpleRadial => &["f", "cx", "cy", "k"],
            CameraModel::Radial => &["f", "cx", "cy", "k1", "k2"],
            CameraModel::OpenCv => &["fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2"],
            CameraModel::FullOpenCv => &["fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6"],
            CameraModel::OpenCvFisheye => &["fx", "fy", "cx", "cy", "k1", "k2", "k3", "k4"],
        }
    }
}

/// Residual of the unprojection, pixels, below which Newton's method stops.
pub const UNPROJECTION_TOLERANCE_PX: f64 = 1e-10;

/// Newton iterations of the unprojection before it gives up (it converges quadratically: a handful
/// are used in the invertible region).
const MAX_UNPROJECTION_ITERATIONS: usize = 100;

/// A camera of one of the [`CameraModel`]s: intrinsics and distortion, checked.
#[derive(Debug, Clone, PartialEq)]
pub struct LensCamera {
    model: CameraModel,
    params: Vec<f64>,
    /// The radius `|n|` where the radial distortion stops increasing ([`fold_radius`]); `∞` when it never does.
    fold_radius: f64,
}

impl LensCamera {
    /// The camera of `model` with `params` in COLMAP's order. `Error::Shape` for a wrong count,
    /// `Error::NonFinite` for NaN/inf, `Error::SingularCamera` for a zero focal length.
    pub fn new(model: CameraModel, params: &[f64]) -> Result<LensCamera> {
        let names = model.parameter_names();
        if params.len() != names.len() {
            return Err(Error::Shape {
                what: format!("{} parameters", model.as_str()),
                expected: format!("{} values ({})", names.len(), names.join(", ")),
                actual: format!("{} values", params.len()),
            });
        }
        if let Some(index) = params.iter().position(|v| !v.is_finite()) {
            return Err(Error::NonFinite {
                what: format!("{} parameters", model.as_str()),
                index,
            });
        }
        let camera = LensCamera {
            model,
            params: params.to_vec(),
            fold_radius: fold_radius(model, params),
        };
        let (fx, fy) = camera.focal();
        if fx == 0.0 || fy == 0.0 {
            return Err(Error::SingularCamera {
                what: format!("{}: zero focal length", model.as_str()),
            });
        }
        Ok(camera)
    }

    /// The model.
    pub fn model(&self) -> CameraModel {
        self.model
    }

    /// The parameters, in COLMAP's order.
    pub fn params(&self) -> &[f64] {
        &self.params
    }

    /// `(fx, fy)`, pixels.
    pub fn focal(&self) -> (f64, f64) {
        let p = &self.params;
        match self.model {
            CameraModel::SimplePinhole | CameraModel::SimpleRadial | CameraModel::Radial => (p[0], p[0]),
            _ => (p[0], p[1]),
        }
    }

    /// `(cx, cy)`, pixels.
    pub fn principal_point(&self) -> (f64, f64) {
        let p = &self.params;
        match self.model {
            CameraModel::SimplePinhole | CameraModel::SimpleRadial | CameraModel::Radial => (p[1], p[2]),
            _ => (p[2], p[3]),
        }
    }

    /// The pinhole part: the focal lengths and principal point, no skew (the camera of undistorted pixels).
    pub fn pinhole(&self) -> Result<crate::camera::Camera> {
        let ((fx, fy), (cx, cy)) = (self.focal(), self.principal_point());
        crate::camera::Camera::new(fx, fy, cx, cy, 0.0)
    }

    /// Whether the model has no distortion (the pinhole fast path applies).
    pub fn is_pinhole(&self) -> bool {
        matches!(self.model, CameraModel::SimplePinhole | CameraModel::Pinhole)
    }

    /// The distortion `D(n)` of normalised coordinates (see the module table) and its Jacobian `∂D/∂n`.
    pub fn distort(&self, n: &Vector2<f64>) -> (Vector2<f64>, Matrix2<f64>) {
        let p = &self.params;
        let (x, y) = (n.x, n.y);
        let r2 = x * x + y * y;
        // Radial factor g(r²) and its derivative g'(r²), so that D = n g + t and ∂(n g)/∂n = g I + 2 g' n nᵀ.
        let radial = |g: f64, dg: f64| {
            let d = n * g;
            let j = Matrix2::identity() * g + n * n.transpose() * (2.0 * dg);
            (d, j)
        };
        let tangential = |p1: f64, p2: f64| {
            let t = Vector2::new(
                2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x),
                p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y,
            );
            let j = Matrix2::new(
                2.0 * p1 * y + 6.0 * p2 * x,
                2.0 * p1 * x + 2.0 * p2 * y,
                2.0 * p1 * x + 2.0 * p2 * y,
                6.0 * p1 * y + 2.0 * p2 * x,
            );
            (t, j)
        };
        match self.model {
            CameraModel::SimplePinhole | CameraModel::Pinhole => (*n, Matrix2::identity()),
            CameraModel::SimpleRadial => radial(1.0 + p[3] * r2, p[3]),
            CameraModel::Radial => radial(1.0 + p[3] * r2 + p[4] * r2 * r2, p[3] + 2.0 * p[4] * r2),
            CameraModel::OpenCv => {
                let (k1, k2, p1, p2) = (p[4], p[5], p[6], p[7]);
                let (d, j) = radial(1.0 + k1 * r2 + k2 * r2 * r2, k1 + 2.0 * k2 * r2);
                let (t, jt) = tangential(p1, p2);
                (d + t, j + jt)
            }
            CameraModel::FullOpenCv => {
                let (k1, k2, p1, p2, k3, k4, k5, k6) = (p[4], p[5], p[6], p[7], p[8], p[9], p[10], p[11]);
                let num = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
                let den = 1.0 + r2 * (k4 + r2 * (k5 + r2 * k6));
                let dnum = k1 + r2 * (2.0 * k2 + 3.0 * k3 * r2);
                let dden = k4 + r2 * (2.0 * k5 + 3.0 * k6 * r2);
                let (d, j) = radial(num / den, (dnum * den - num * dden) / (den * den));
                let (t, jt) = tangential(p1, p2);
                (d + t, j + jt)
            }
            CameraModel::OpenCvFisheye => {
                let (k1, k2, k3, k4) = (p[4], p[5], p[6], p[7]);
                let r = r2.sqrt();
                if r < 1e-8 {
                    // θ = atan r ≈ r: D(n) = n (1 + O(r²)); the Jacobian is the identity to O(r²).
                    return (*n, Matrix2::identity());
                }
                let theta = r.atan();
                let t2 = theta * theta;
                let poly = 1.0 + t2 * (k1 + t2 * (k2 + t2 * (k3 + t2 * k4)));
                let theta_d = theta * poly;
                let dtheta_d = poly + t2 * (2.0 * k1 + t2 * (4.0 * k2 + t2 * (6.0 * k3 + t2 * 8.0 * k4)));
                // D = n s(r) with s = θ_d / r; ∂D/∂n = s I + (s'(r) / r) n nᵀ, s' = (θ_d' θ' r − θ_d) / r².
                let s = theta_d / r;
                let ds = (dtheta_d / (1.0 + r2) * r - theta_d) / r2;
                (n * s, Matrix2::identity() * s + n * n.transpose() * (ds / r))
            }
        }
    }

    /// Pixels of distorted normalised coordinates `d` (their Jacobian is `diag(fx, fy)`).
    fn to_pixels(&self, d: &Vector2<f64>) -> Vector2<f64> {
        let ((fx, fy), (cx, cy)) = (self.focal(), self.principal_point());
        Vector2::new(fx * d.x + cx, fy * d.y + cy)
    }

    /// Pixels of the camera-frame point `x_cam` (`z > 0`; behind the camera the result is meaningless)
    /// and the Jacobian `∂u/∂x_cam` (2x3).
    pub fn project(&self, x_cam: &Vector3<f64>) -> (Vector2<f64>, nalgebra::Matrix2x3<f64>) {
        let z = x_cam.z;
        let n = Vector2::new(x_cam.x / z, x_cam.y / z);
        let (d, jd) = self.distort(&n);
        let (fx, fy) = self.focal();
        let dn_dx = nalgebra::Matrix2x3::new(1.0 / z, 0.0, -n.x / z, 0.0, 1.0 / z, -n.y / z);
        (self.to_pixels(&d), Matrix2::new(fx, 0.0, 0.0, fy) * jd * dn_dx)
    }

    /// The undistorted normalised coordinates `n` with `D(n) = d` for the pixel `u` (point `index` of
    /// the caller, for the error message), to [`UNPROJECTION_TOLERANCE_PX`]; `Error::Degenerate` when
    /// the pixel is outside the invertible region of the distortion.
    pub fn unproject(&self, u: &Vector2<f64>, index: usize) -> Result<Vector2<f64>> {
        let ((fx, fy), (cx, cy)) = (self.focal(), self.principal_point());
        let d = Vector2::new((u.x - cx) / fx, (u.y - cy) / fy);
        if self.is_pinhole() {
            return Ok(d);
        }
        let outside = |why: &str| Error::Degenerate {
            what: format!(
                "pixel {index} ({}, {}): outside the invertible region of the {} distortion ({why})",
                number(u.x),
                number(u.y),
                self.model.as_str()
            ),
        };
        let pixel_error = |e: &Vector2<f64>| (e.x * fx).hypot(e.y * fy);
        let mut n = d;
        for _ in 0..MAX_UNPROJECTION_ITERATIONS {
            let (dn, j) = self.distort(&n);
            let e = dn - d;
            if !(j.determinant() > 0.0) {
                return Err(outside("the distortion folds there"));
            }
            if pixel_error(&e) <= UNPROJECTION_TOLERANCE_PX {
                // A preimage past the fold radius is on an outer branch of the distortion, where it
                // increases again: the image of the inner branch never reaches this pixel.
                if n.norm() >= self.fold_radius {
                    return Err(outside(&format!(
                        "its preimage, at radius {}, lies beyond the fold of the radial distortion at radius {}",
                        number(n.norm()),
                        number(self.fold_radius)
                    )));
                }
                return Ok(n);
            }
            let step = j.lu().solve(&e).ok_or_else(|| outside("singular Jacobian"))?;
            n -= step;
            if !n.iter().all(|v| v.is_finite()) {
                return Err(outside("Newton's method diverged"));
            }
        }
        Err(outside("Newton's method did not converge"))
    }

    /// The undistorted pixel `ū = K n` of the pixel `u` (its position in the image of the pinhole part
    /// `K = [fx 0 cx; 0 fy cy; 0 0 1]`, with `n` = [`LensCamera::unproject`]) and the Jacobian
    /// `∂u/∂ū = diag(f) ∂D/∂n diag(f)⁻¹` there, which maps a small displacement of `ū` to the
    /// distorted pixels. Errors as [`LensCamera::unproject`].
    pub fn undistort(&self, u: &Vector2<f64>, index: usize) -> Result<(Vector2<f64>, Matrix2<f64>)> {
        let n = self.unproject(u, index)?;
        let (_, jd) = self.distort(&n);
        let ((fx, fy), (cx, cy)) = (self.focal(), self.principal_point());
        let f = Matrix2::new(fx, 0.0, 0.0, fy);
        let f_inv = Matrix2::new(1.0 / fx, 0.0, 0.0, 1.0 / fy);
        Ok((Vector2::new(fx * n.x + cx, fy * n.y + cy), f * jd * f_inv))
    }

    /// The 2x2 covariance of the undistorted normalised coordinates of a pixel with covariance `cov_px`,
    /// at the unprojected point `n`: `J⁻¹ Σ J⁻ᵀ` with `J = ∂u/∂n` (first order; see the module docs for
    /// when that is not enough).
    pub fn normalized_covariance(&self, n: &Vector2<f64>, cov_px: &Matrix2<f64>) -> Option<Matrix2<f64>> {
        let (_, jd) = self.distort(n);
        let (fx, fy) = self.focal();
        let inv = (Matrix2::new(fx, 0.0, 0.0, fy) * jd).try_inverse()?;
        Some(inv * cov_px * inv.transpose())
    }
}

/// The radius `r*` of normalised coordinates where the radial part of the distortion of `model` stops
/// increasing (`∞` when it increases everywhere): the first positive zero of `dρ/dr` for the radial map
/// `ρ(r) = r g(r²)`, or of the rational model's denominator, or for the fisheye the first zero of
/// `dθ_d/dθ` in `θ = atan r < π/2`. Beyond it the distortion folds back, and a pixel whose Newton
/// solution lies there has no preimage on the branch through the principal point ([`LensCamera::unproject`]).
///
/// In `s = r²` the zeros are those of polynomials: `1 + 3k s` (SIMPLE_RADIAL), `1 + 3k₁ s + 5k₂ s²`
/// (RADIAL, OPENCV), `(1 + 3k₁ s + 5k₂ s² + 7k₃ s³) den(s) − num(s) (2k₄ s + 4k₅ s² + 6k₆ s³)` and
/// `den(s)` (FULL_OPENCV, `g = num / den`), and in `t = θ²` `1 + 3k₁ t + 5k₂ t² + 7k₃ t³ + 9k₄ t⁴`
/// (OPENCV_FISHEYE). Tangential terms are not part of it (the Jacobian test of the unprojection covers
/// them where they fold).
pub fn fold_radius(model: CameraModel, params: &[f64]) -> f64 {
    let p = params;
    let radius_of_s = |s: Option<f64>| s.map_or(f64::INFINITY, f64::sqrt);
    match model {
        CameraModel::SimplePinhole | CameraModel::Pinhole => f64::INFINITY,
        CameraModel::SimpleRadial => radius_of_s(first_positive_root(&[1.0, 3.0 * p[3]])),
        CameraModel::Radial => radius_of_s(first_positive_root(&[1.0, 3.0 * p[3], 5.0 * p[4]])),
        CameraModel::OpenCv => radius_of_s(first_positive_root(&[1.0, 3.0 * p[4], 5.0 * p[5]])),
        CameraModel::FullOpenCv => {
            let (k1, k2, k3, k4, k5, k6) = (p[4], p[5], p[8], p[9], p[10], p[11]);
            let num = [1.0, k1, k2, k3];
            let den = [1.0, k4, k5, k6];
            let slope = [1.0, 3.0 * k1, 5.0 * k2, 7.0 * k3];
            let den_slope = [0.0, 2.0 * k4, 4.0 * k5, 6.0 * k6];
            let mut derivative = [0.0; 7];
            for i in 0..4 {
                for j in 0..4 {
                    derivative[i + j] += slope[i] * den[j] - num[i] * den_slope[j];
                }
            }
            let fold = first_positive_root(&derivative);
            let pole = first_positive_root(&den);
            radius_of_s(match (fold, pole) {
                (Some(a), Some(b)) => Some(a.min(b)),
                (a, b) => a.or(b),
            })
        }
        CameraModel::OpenCvFisheye => {
            let (k1, k2, k3, k4) = (p[4], p[5], p[6], p[7]);
            match first_positive_root(&[1.0, 3.0 * k1, 5.0 * k2, 7.0 * k3, 9.0 * k4]) {
                Some(t) if t.sqrt() < std::f64::consts::FRAC_PI_2 => t.sqrt().tan(),
                _ => f64::INFINITY,
            }
        }
    }
}

/// The least positive real root of `c₀ + c₁ x + … + c_d x^d` (`c₀ ≠ 0`), from the eigenvalues of its
/// companion matrix; a root is taken as real when its imaginary part is below `1e-6` of its modulus (a
/// double root that only touches zero may come out so, and is then counted: the answer errs small).
fn first_positive_root(coefficients: &[f64]) -> Option<f64> {
    let degree = coefficients.iter().rposition(|&c| c != 0.0)?;
    if degree == 0 {
        return None;
    }
    let lead = coefficients[degree];
    if coefficients[..degree].iter().any(|c| !(c / lead).is_finite()) {
        // A leading coefficient too small to divide by: its roots are beyond any double, so the
        // polynomial of one degree less has the same roots in range.
        return first_positive_root(&coefficients[..degree]);
    }
    let companion = nalgebra::DMatrix::from_fn(degree, degree, |i, j| {
        if j == degree - 1 {
            -coefficients[i] / lead
        } else if i == j + 1 {
            1.0
        } else {
            0.0
        }
    });
    companion
        .complex_eigenvalues()
        .iter()
        .filter(|z| z.re > 0.0 && z.im.abs() <= 1e-6 * z.norm())
        .map(|z| z.re)
        .min_by(f64::total_cmp)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    /// A camera of each model with COLMAP-like distortion (moderate barrel, small tangential terms).
    fn cameras() -> Vec<LensCamera> {
        let params: [(CameraModel, &[f64]); 7] = [
            (CameraModel::SimplePinhole, &[800.0, 320.0, 240.0]),
            (CameraModel::Pinhole, &[800.0, 790.0, 320.0, 240.0]),
            (CameraModel::SimpleRadial, &[800.0, 320.0, 240.0, -0.1]),
            (CameraModel::Radial, &[800.0, 320.0, 240.0, -0.1, 0.02]),
            (
                CameraModel::OpenCv,
                &[800.0, 790.0, 320.0, 240.0, -0.2, 0.05, 1e-3, -5e-4],
            ),
            (
                CameraModel::FullOpenCv,
                &[
                    800.0, 790.0, 320.0, 240.0, -0.2, 0.05, 1e-3, -5e-4, 0.01, 0.02, -0.01, 0.005,
                ],
            ),
            (
                CameraModel::OpenCvFisheye,
                &[400.0, 395.0, 320.0, 240.0, 0.05, -0.01, 0.002, -3e-4],
            ),
        ];
        params.iter().map(|(m, p)| LensCamera::new(*m, p).unwrap()).collect()
    }

    #[test]
    fn the_jacobians_match_finite_differences() {
        let mut rng = Rng::new(41);
        for cam in cameras() {
            for _ in 0..50 {
                let x = Vector3::new(
                    rng.uniform_in(-0.5, 0.5),
                    rng.uniform_in(-0.4, 0.4),
                    rng.uniform_in(1.0, 3.0),
                );
                let (_, j) = cam.project(&x);
                for k in 0..3 {
                    let h = 1e-6;
                    let mut xp = x;
                    xp[k] += h;
                    let mut xm = x;
                    xm[k] -= h;
                    let numeric = (cam.project(&xp).0 - cam.project(&xm).0) / (2.0 * h);
                    // Central differences: O(h²) truncation and O(ε |u| / h) rounding, about 1e-7 px per unit.
                    assert!(
                        (numeric - j.column(k)).norm() < 1e-5 * (1.0 + j.column(k).norm()),
                        "{:?}",
                        cam.model()
                    );
                }
            }
        }
    }

    #[test]
    fn projection_agrees_with_opencv() {
        // Reference pixels from OpenCV 5.0.0, an independent implementation: `cv2.projectPoints` with
        // distCoeffs (k1, k2, p1, p2) and the rational (k1, k2, p1, p2, k3, k4, k5, k6), and
        // `cv2.fisheye.projectPoints` with (k1, k2, k3, k4), of the points below at the identity pose.
        let points = [
            Vector3::new(0.3, -0.2, 1.5),
            Vector3::new(-0.4, 0.25, 2.0),
            Vector3::new(0.05, 0.1, 1.0),
        ];
        let cases: [(CameraModel, &[f64], [[f64; 2]; 3]); 3] = [
            (
                CameraModel::OpenCv,
                &[800.0, 790.0, 320.0, 240.0, -0.2, 0.05, 1e-3, -5e-4],
                [
                    [478.08003950617285, 135.96107028806586],
                    [161.66099687500002, 337.7550648193359],
                    [359.9013125, 318.8248421875],
                ],
            ),
            (
                CameraModel::FullOpenCv,
                &[
                    800.0, 790.0, 320.0, 240.0, -0.2, 0.05, 1e-3, -5e-4, 0.01, 0.02, -0.01, 0.005,
                ],
                [
                    [477.9028916767527, 136.07769260910078],
                    [161.83182374163687, 337.6496326125835],
                    [359.89140261979446, 318.805270174094],
                ],
            ),
            (
                CameraModel::OpenCvFisheye,
                &[400.0, 395.0, 320.0, 240.0, 0.05, -0.01, 0.002, -3e-4],
                [
                    [398.7265990991503, 188.1716555930594],
                    [241.22721516597178, 288.6175781397518],
                    [339.92960115866975, 279.3609622883728],
                ],
            ),
        ];
        for (model, params, expected) in cases {
            let cam = LensCamera::new(model, params).unwrap();
            for (x, e) in points.iter().zip(expected) {
                let (u, _) = cam.project(x);
                assert!((u - Vector2::new(e[0], e[1])).norm() < 1e-9, "{model:?}: {u} vs {e:?}");
            }
        }
    }

    #[test]
    fn unprojection_inverts_projection_to_1e_10_px() {
        let mut rng = Rng::new(42);
        for cam in cameras() {
            for i in 0..200 {
                let x = Vector3::new(rng.uniform_in(-0.4, 0.4), rng.uniform_in(-0.3, 0.3), 1.0);
                let (u, _) = cam.project(&x);
                let n = cam.unproject(&u, i).unwrap();
                let (back, _) = cam.project(&Vector3::new(n.x, n.y, 1.0));
                assert!(
                    (back - u).norm() <= 1e-10 * 1.5,
                    "{:?}: {:e} px",
                    cam.model(),
                    (back - u).norm()
                );
                assert!((n - x.xy()).norm() < 1e-12, "{:?}", cam.model());
            }
        }
    }

    #[test]
    fn beyond_the_fold_of_a_barrel_distortion_is_an_error() {
        // D(r) = r (1 − 0.5 r²) peaks at r = 1/√1.5: pixels mapped from beyond it have no valid preimage.
        let cam = LensCamera::new(CameraModel::SimpleRadial, &[500.0, 0.0, 0.0, -0.5]).unwrap();
        let peak = (1.0f64 / 1.5).sqrt();
        let inside = peak * (1.0 - 0.5 * peak * peak) * 0.9 * 500.0;
        assert!(cam.unproject(&Vector2::new(inside, 0.0), 0).is_ok());
        let beyond = peak * (1.0 - 0.5 * peak * peak) * 1.05 * 500.0;
        let err = cam.unproject(&Vector2::new(beyond, 0.0), 7).unwrap_err();
        assert!(
            matches!(&err, Error::Degenerate { what } if what.starts_with("pixel 7")),
            "{err}"
        );
    }

    #[test]
    fn every_pixel_beyond_the_fold_of_a_radial_distortion_is_refused() {
        // RADIAL k1 = -0.5, k2 = 0.1: ρ(r) = r - 0.5 r³ + 0.1 r⁵, ρ'(r) = 1 - 1.5 r² + 0.5 r⁴ = 0 at r = 1
        // and r = √2; ρ rises to ρ(1) = 0.6, falls to ρ(√2) = 0.4√2 and rises again without bound.
        let cam = LensCamera::new(CameraModel::Radial, &[800.0, 320.0, 240.0, -0.5, 0.1]).unwrap();
        assert!((cam.fold_radius - 1.0).abs() < 1e-12, "{}", cam.fold_radius);
        let peak_px = 0.6 * 800.0;
        // Pixels on a ray from the principal point, every distance to 20x the peak: accepted exactly below it.
        for k in 1..=4000 {
            let radius = peak_px * k as f64 / 200.0;
            for angle in [0.0f64, 0.7, 2.0, 4.0] {
                let u = Vector2::new(320.0 + radius * angle.cos(), 240.0 + radius * angle.sin());
                match cam.unproject(&u, k) {
                    Ok(n) => {
                        assert!(
                            radius <= peak_px,
                            "{radius} px is beyond the fold ({peak_px} px) yet unprojected to |n| = {}",
                            n.norm()
                        );
                        assert!(n.norm() < 1.0);
                    }
                    // Newton may give up just inside the fold, where ρ' → 0; never further in than 1 %.
                    Err(_) => assert!(radius > 0.99 * peak_px, "{radius} px refused inside the fold"),
                }
            }
        }
        for u in [Vector2::new(1000.0, 1000.0), Vector2::new(5000.0, 5000.0)] {
            assert!(matches!(cam.unproject(&u, 3), Err(Error::Degenerate { .. })), "{u}");
        }
    }

    #[test]
    fn the_fold_radius_of_each_model_is_where_the_radial_map_turns() {
        // Independent check: the first r (scanned finely) where ρ(r) = |D((r, 0))| stops increasing.
        let cases: [(CameraModel, &[f64]); 5] = [
            (CameraModel::SimpleRadial, &[500.0, 0.0, 0.0, -0.5]),
            (CameraModel::Radial, &[800.0, 320.0, 240.0, -0.5, 0.1]),
            (CameraModel::OpenCv, &[800.0, 790.0, 320.0, 240.0, -0.3, 0.02, 0.0, 0.0]),
            (
                CameraModel::FullOpenCv,
                &[
                    800.0, 790.0, 320.0, 240.0, -0.4, 0.05, 0.0, 0.0, 0.01, 0.1, -0.01, 0.005,
                ],
            ),
            (
                CameraModel::OpenCvFisheye,
                &[400.0, 395.0, 320.0, 240.0, -0.3, 0.02, 0.0, 0.0],
            ),
        ];
        for (model, params) in cases {
            let cam = LensCamera::new(model, params).unwrap();
            let rho = |r: f64| cam.distort(&Vector2::new(r, 0.0)).0.x;
            let step = 1e-4;
            let turn = (1..200_000)
                .map(|i| i as f64 * step)
                .find(|&r| rho(r + step) <= rho(r))
                .expect("each case folds below r = 20");
            // The scan finds the turn to within one step (the maximum is flat: ρ' changes sign there).
            assert!(
                (cam.fold_radius - turn).abs() <= 2.0 * step,
                "{model:?}: {} vs {turn}",
                cam.fold_radius
            );
        }
        for cam in cameras() {
            // The mild distortions of the other tests fold far outside their images, if at all.
            assert!(cam.fold_radius > 1.0, "{:?}: {}", cam.model(), cam.fold_radius);
        }
    }

    #[test]
    fn extreme_distortion_parameters_give_a_fold_radius_without_failing() {
        // Subnormal, huge and mixed coefficients: the companion matrix must stay finite (a non-finite
        // one could make the eigenvalue iteration run for ever).
        let extremes: [&[f64]; 6] = [
            &[800.0, 0.0, 0.0, 1.0, 1e-320],
            &[800.0, 0.0, 0.0, -1e300, 1e-320],
            &[800.0, 0.0, 0.0, 1e300, -1e300],
            &[800.0, 0.0, 0.0, -1e-300, 1e-300],
            &[800.0, 0.0, 0.0, 0.0, 0.0],
            &[800.0, 0.0, 0.0, f64::MAX, f64::MIN_POSITIVE],
        ];
        for params in extremes {
            let cam = LensCamera::new(CameraModel::Radial, params).unwrap();
            assert!(cam.fold_radius > 0.0, "{params:?}: {}", cam.fold_radius);
            let _ = cam.unproject(&Vector2::new(900.0, 100.0), 0);
        }
        let cam = LensCamera::new(CameraModel::Radial, &[800.0, 0.0, 0.0, -1e300, 1e-320]).unwrap();
        // ρ' = 1 - 3e300 r² (+ a negligible r⁴ term) vanishes at r = 1/√(3e300).
        assert!(
            (cam.fold_radius * (3e300f64).sqrt() - 1.0).abs() < 1e-12,
            "{}",
            cam.fold_radius
        );
    }

    #[test]
    fn models_parse_by_colmap_name_and_check_their_parameters() {
        for m in CameraModel::ALL {
            assert_eq!(CameraModel::parse(m.as_str()).unwrap(), m);
        }
        assert!(matches!(
            CameraModel::parse("KANNALA"),
            Err(Error::InvalidOption { .. })
        ));
        assert!(matches!(
            LensCamera::new(CameraModel::OpenCv, &[1.0; 4]),
            Err(Error::Shape { .. })
        ));
        assert!(matches!(
            LensCamera::new(CameraModel::Pinhole, &[0.0, 1.0, 0.0, 0.0]),
            Err(Error::SingularCamera { .. })
        ));
        assert!(matches!(
            LensCamera::new(CameraModel::Pinhole, &[1.0, f64::NAN, 0.0, 0.0]),
            Err(Error::NonFinite { index: 1, .. })
        ));
    }

    #[test]
    fn the_normalized_covariance_is_the_first_order_propagation() {
        // With the pinhole model it is Σ / f²; with distortion, J⁻¹ Σ J⁻ᵀ checked by Monte Carlo would be
        // the next step; here the exact linear case.
        let cam = LensCamera::new(CameraModel::Pinhole, &[800.0, 400.0, 320.0, 240.0]).unwrap();
        let c = cam
            .normalized_covariance(&Vector2::new(0.1, 0.2), &Matrix2::identity())
            .unwrap();
        assert!((c - Matrix2::new(1.0 / 640000.0, 0.0, 0.0, 1.0 / 160000.0)).norm() < 1e-18);
    }
}
