//! [`Camera`]: the one camera of pose and triangulation, a [`CameraModel`] and its parameters, checked;
//! its projection through the distortion (the pinhole models' fast path inside), the unprojection by
//! Newton's method and the covariance of undistorted points.

use super::distortion::{division, equidistant, eucm, fov, polynomial, radial, scaled, tangential, thin_prism};
use super::fold::fold_radius;
use super::model::{CameraModel, FOV_SERIES_BOUND, MAX_UNPROJECTION_ITERATIONS, UNPROJECTION_TOLERANCE_PX};
use crate::camera::bounds::{domain, Coefficients, Distortion, Domain};
use crate::camera::Intrinsics;
use crate::camera_pose::Pose;
use crate::error::{number, Error, Result};
use nalgebra::{Matrix2, Matrix2x3, Matrix3, Matrix3x4, Vector2, Vector3};

/// A camera: one of the [`CameraModel`]s (COLMAP's, with PINHOLE one of them, or `SKEWED_PINHOLE`) and
/// its parameters in COLMAP's order, checked. Its pixels are the observed ones: through a lens with
/// distortion, `u = K D(x_cam / z)`; for the pinhole models `u = K x_cam / z`, computed on a fast path.
///
/// ```
/// use pluecker::camera::{Camera, CameraModel};
/// let lens = Camera::new(CameraModel::SimpleRadial, &[800.0, 320.0, 240.0, -0.1]).unwrap();
/// let pinhole = Camera::pinhole(800.0, 800.0, 320.0, 240.0, 0.0).unwrap();
/// assert_eq!(pinhole.model(), CameraModel::Pinhole);
/// assert_eq!(lens.intrinsics(), pinhole.intrinsics());
/// ```
///
/// With the `serde` feature a camera is written as its model (by name) and parameters,
/// `{"model": "SIMPLE_RADIAL", "params": [800.0, 320.0, 240.0, -0.1]}`, and read back through
/// [`Camera::new`]: its checks apply, and an invalid camera is an error with its message.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(try_from = "CameraParts", into = "CameraParts")
)]
pub struct Camera {
    pub(super) model: CameraModel,
    pub(super) params: Vec<f64>,
    /// The pinhole part `K`, checked once ([`Camera::intrinsics`]).
    pub(super) pinhole: Intrinsics,
    /// The radius `|n|` where the radial distortion stops increasing ([`fold_radius`]); `∞` when it never does.
    pub(super) fold_radius: f64,
    /// The distortion the certificates' enclosures cover ([`covered_distortion`]) and the disc where it
    /// is proved one-to-one ([`crate::camera::bounds::domain`], a scan for the tangential terms): computed
    /// once here, as they depend on the camera alone, and read by every observation's bound.
    pub(super) bounds: Option<(Distortion, Option<Domain>)>,
}

/// What a [`Camera`] is written as with the `serde` feature: its model and parameters.
#[cfg(feature = "serde")]
#[derive(serde::Serialize, serde::Deserialize)]
struct CameraParts {
    model: CameraModel,
    params: Vec<f64>,
}

#[cfg(feature = "serde")]
impl From<Camera> for CameraParts {
    fn from(camera: Camera) -> CameraParts {
        CameraParts {
            model: camera.model,
            params: camera.params,
        }
    }
}

#[cfg(feature = "serde")]
impl TryFrom<CameraParts> for Camera {
    type Error = Error;
    fn try_from(parts: CameraParts) -> Result<Camera> {
        Camera::new(parts.model, &parts.params)
    }
}

/// The distortion of `model` with `params` in the form of [`crate::camera::bounds`], or `None` when its
/// enclosures do not cover it: thin-prism or tangential terms of the fisheyes, a rational FULL_OPENCV,
/// FOV (whose projection in COLMAP is piecewise, with a jump).
pub(super) fn covered_distortion(model: CameraModel, p: &[f64]) -> Option<Distortion> {
    let zero = |range: &[f64]| range.iter().all(|&v| v == 0.0);
    use Distortion::{Fisheye, Polynomial, Tangential};
    let with_tangential = |radial: Coefficients, p1: f64, p2: f64| {
        if p1 == 0.0 && p2 == 0.0 {
            Polynomial(radial)
        } else {
            Tangential(radial, p1, p2)
        }
    };
    match model {
        CameraModel::SimplePinhole | CameraModel::Pinhole | CameraModel::SkewedPinhole => {
            Some(Polynomial(Coefficients::new()))
        }
        CameraModel::SimpleRadial => Some(Polynomial(Coefficients::from_slice(&p[3..4]))),
        CameraModel::Radial => Some(Polynomial(Coefficients::from_slice(&p[3..5]))),
        CameraModel::OpenCv => Some(with_tangential(Coefficients::from_slice(&p[4..6]), p[6], p[7])),
        CameraModel::FullOpenCv if zero(&p[9..12]) => Some(with_tangential(
            Coefficients::from_slice(&[p[4], p[5], p[8]]),
            p[6],
            p[7],
        )),
        CameraModel::SimpleFisheye | CameraModel::Fisheye => Some(Fisheye(Coefficients::new())),
        CameraModel::SimpleRadialFisheye => Some(Fisheye(Coefficients::from_slice(&p[3..4]))),
        CameraModel::RadialFisheye => Some(Fisheye(Coefficients::from_slice(&p[3..5]))),
        CameraModel::OpenCvFisheye => Some(Fisheye(Coefficients::from_slice(&p[4..8]))),
        CameraModel::ThinPrismFisheye if zero(&p[6..8]) && zero(&p[10..12]) => {
            Some(Fisheye(Coefficients::from_slice(&[p[4], p[5], p[8], p[9]])))
        }
        CameraModel::RadTanThinPrismFisheye if zero(&p[10..16]) => Some(Fisheye(Coefficients::from_slice(&p[4..10]))),
        CameraModel::SimpleDivision => Some(Distortion::Division(p[3])),
        CameraModel::Division => Some(Distortion::Division(p[4])),
        CameraModel::Eucm => Some(Distortion::Eucm(p[4], p[5])),
        _ => None,
    }
}

impl Camera {
    /// The camera of `model` with `params` in COLMAP's order. `Error::Shape` for a wrong count,
    /// `Error::NonFinite` for NaN/inf, `Error::SingularCamera` when its pinhole part is not an
    /// invertible `K` ([`Intrinsics`]: a zero focal length, `fx fy` overflowing).
    pub fn new(model: CameraModel, params: &[f64]) -> Result<Camera> {
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
        // Its pinhole part must be a camera (non-zero focal lengths, `K` invertible).
        let (fx, fy, cx, cy) = if model.has_one_focal_length() {
            (params[0], params[0], params[1], params[2])
        } else {
            (params[0], params[1], params[2], params[3])
        };
        let skew = if model == CameraModel::SkewedPinhole {
            params[4]
        } else {
            0.0
        };
        let pinhole = Intrinsics::new(fx, fy, cx, cy, skew).map_err(|e| match e {
            Error::SingularCamera { what } => Error::SingularCamera {
                what: format!("{}: {what}", model.as_str()),
            },
            other => other,
        })?;
        let fold = fold_radius(model, params);
        let bounds = covered_distortion(model, params).map(|d| {
            let one_to_one = domain(&d, fold);
            (d, one_to_one)
        });
        let camera = Camera {
            model,
            params: params.to_vec(),
            pinhole,
            fold_radius: fold,
            bounds,
        };
        Ok(camera)
    }

    /// The pinhole camera `K = [[fx, skew, cx], [0, fy, cy], [0, 0, 1]]`: PINHOLE when `skew` is 0,
    /// else SKEWED_PINHOLE. `fx`, `fy` may be negative (a mirrored axis), never zero.
    pub fn pinhole(fx: f64, fy: f64, cx: f64, cy: f64, skew: f64) -> Result<Camera> {
        if skew == 0.0 {
            Camera::new(CameraModel::Pinhole, &[fx, fy, cx, cy])
        } else {
            Camera::new(CameraModel::SkewedPinhole, &[fx, fy, cx, cy, skew])
        }
    }

    /// The pinhole camera of a 3x3 calibration matrix `K` (as [`Intrinsics::from_matrix`]: upper
    /// triangular, its last row `(0, 0, 1)` up to scale): PINHOLE, or SKEWED_PINHOLE with a skew.
    pub fn from_matrix(k: &Matrix3<f64>) -> Result<Camera> {
        let k = Intrinsics::from_matrix(k)?;
        Camera::pinhole(k.fx, k.fy, k.cx, k.cy, k.skew)
    }

    /// The model.
    pub fn model(&self) -> CameraModel {
        self.model
    }

    /// The parameters, in COLMAP's order.
    pub fn params(&self) -> &[f64] {
        &self.params
    }

    /// `(fx, fy)`, pixels (of [`Camera::intrinsics`]).
    pub fn focal(&self) -> (f64, f64) {
        (self.pinhole.fx, self.pinhole.fy)
    }

    /// `(cx, cy)`, pixels (of [`Camera::intrinsics`]).
    pub fn principal_point(&self) -> (f64, f64) {
        (self.pinhole.cx, self.pinhole.cy)
    }

    /// The radius `|n|` of normalised coordinates where the radial distortion stops increasing
    /// ([`fold_radius`]; `∞` when it never does): inside it the lens maps one-to-one.
    pub fn fold_radius(&self) -> f64 {
        self.fold_radius
    }

    /// The distortion in the form the certificates' interval enclosures cover ([`crate::camera::bounds`]),
    /// or `None` when they do not cover it (thin-prism or tangential terms of the fisheyes, a rational
    /// FULL_OPENCV, FOV).
    pub(crate) fn covered_distortion(&self) -> Option<&Distortion> {
        self.bounds.as_ref().map(|(d, _)| d)
    }

    /// The disc where the covered distortion is proved one-to-one ([`crate::camera::bounds::domain`]);
    /// `None` when it is not covered or the disc is empty.
    pub(crate) fn one_to_one_domain(&self) -> Option<Domain> {
        self.bounds.as_ref().and_then(|(_, domain)| *domain)
    }

    /// The pinhole part `K`: the focal lengths, principal point and skew (the camera of undistorted
    /// pixels).
    pub fn intrinsics(&self) -> Intrinsics {
        self.pinhole
    }

    /// The pinhole camera of this camera's `K` ([`Camera::pinhole`]): the camera of its undistorted
    /// pixels.
    pub fn without_distortion(&self) -> Camera {
        let k = self.pinhole;
        Camera::pinhole(k.fx, k.fy, k.cx, k.cy, k.skew).expect("K was checked when the camera was built")
    }

    /// Whether the model has no distortion (the pinhole fast path applies).
    pub fn is_pinhole(&self) -> bool {
        self.model.is_pinhole()
    }

    /// The camera itself when its model distorts (not one of the pinholes), for the code that works
    /// through a lens; `None` for the pinholes.
    pub fn distortion(&self) -> Option<&Camera> {
        (!self.is_pinhole()).then_some(self)
    }

    /// The 3x4 matrix `P = K [R | t]` of the pinhole part at `pose` ([`Intrinsics::projection`]).
    pub fn projection(&self, pose: &Pose) -> Matrix3x4<f64> {
        self.pinhole.projection(pose)
    }

    /// The distortion `D(n)` of normalised coordinates (see the module table) and its Jacobian `∂D/∂n`.
    pub fn distort(&self, n: &Vector2<f64>) -> (Vector2<f64>, Matrix2<f64>) {
        let p = &self.params;
        match self.model {
            CameraModel::SimplePinhole | CameraModel::Pinhole | CameraModel::SkewedPinhole => (*n, Matrix2::identity()),
            CameraModel::SimpleRadial => radial(n, &p[3..4]),
            CameraModel::Radial => radial(n, &p[3..5]),
            CameraModel::OpenCv => {
                let (d, j) = radial(n, &p[4..6]);
                let (t, jt) = tangential(n, p[6], p[7]);
                (d + t, j + jt)
            }
            CameraModel::FullOpenCv => {
                let s = n.norm_squared();
                let (num, dnum) = polynomial(&[p[4], p[5], p[8]], s);
                let (den, dden) = polynomial(&[p[9], p[10], p[11]], s);
                let (d, j) = scaled(n, num / den, (dnum * den - num * dden) / (den * den));
                let (t, jt) = tangential(n, p[6], p[7]);
                (d + t, j + jt)
            }
            CameraModel::Fov => fov(n, p[4]),
            CameraModel::SimpleDivision => division(n, p[3]),
            CameraModel::Division => division(n, p[4]),
            CameraModel::Eucm => eucm(n, p[4], p[5]),
            _ => {
                let (m, jm) = equidistant(n);
                let (d, jd) = self.distort_fisheye(&m);
                (d, jd * jm)
            }
        }
    }

    /// The fisheye models' distortion of the equidistant coordinates `m` (`|m| = θ`) and its Jacobian.
    pub(super) fn distort_fisheye(&self, m: &Vector2<f64>) -> (Vector2<f64>, Matrix2<f64>) {
        let p = &self.params;
        match self.model {
            CameraModel::SimpleRadialFisheye => radial(m, &p[3..4]),
            CameraModel::RadialFisheye => radial(m, &p[3..5]),
            CameraModel::OpenCvFisheye => radial(m, &p[4..8]),
            CameraModel::ThinPrismFisheye => {
                let (d, j) = radial(m, &[p[4], p[5], p[8], p[9]]);
                let (t, jt) = tangential(m, p[6], p[7]);
                let (s, js) = thin_prism(m, [p[10], 0.0, p[11], 0.0]);
                (d + t + s, j + jt + js)
            }
            CameraModel::RadTanThinPrismFisheye => {
                // The tangential and thin-prism terms act on the radially distorted v (Fisheye624).
                let (v, jv) = radial(m, &p[4..10]);
                let (t, jt) = tangential(&v, p[11], p[10]);
                let (s, js) = thin_prism(&v, [p[12], p[13], p[14], p[15]]);
                (v + t + s, (Matrix2::identity() + jt + js) * jv)
            }
            _ => (*m, Matrix2::identity()),
        }
    }

    /// Where Newton's method starts for the distorted normalised coordinates `d`: the closed-form
    /// inverse where the model has one (the first two are COLMAP's unprojections), else `d`.
    pub(super) fn newton_start(&self, d: &Vector2<f64>) -> Vector2<f64> {
        let p = &self.params;
        let start = match self.model {
            CameraModel::SimpleDivision | CameraModel::Division => {
                let k = p[p.len() - 1];
                d / (1.0 + k * d.norm_squared())
            }
            CameraModel::Eucm => {
                let (alpha, beta, s) = (p[4], p[5], d.norm_squared());
                let gamma = 1.0 - alpha;
                let root = (1.0 - (alpha - gamma) * beta * s).sqrt();
                d * ((alpha * root + gamma) / (1.0 - alpha * alpha * beta * s))
            }
            CameraModel::Fov if p[4] * p[4] >= FOV_SERIES_BOUND => {
                // The inverse of the closed form, r = tan(ρ ω) / (2 tan(ω/2)), while ρ ω < π/2.
                let rho = d.norm();
                let angle = rho * p[4];
                if rho > 0.0 && angle.abs() < 1.5 {
                    d * (angle.tan() / (2.0 * rho * (p[4] / 2.0).tan()))
                } else {
                    *d
                }
            }
            // The inverse of the equidistant map without distortion: r = tan θ, θ < 80°.
            m if m.is_fisheye() && d.norm() > 0.0 => d * (d.norm().min(1.4).tan() / d.norm()),
            _ => *d,
        };
        if start.iter().all(|v| v.is_finite()) {
            start
        } else {
            *d
        }
    }

    /// Pixels of distorted normalised coordinates `d` (their Jacobian is [`Intrinsics::pixel_jacobian`]).
    pub(super) fn to_pixels(&self, d: &Vector2<f64>) -> Vector2<f64> {
        self.pinhole.normalized_to_pixel(d)
    }

    /// Pixels of the camera-frame point `x_cam` (`z > 0`; behind the camera the result is
    /// meaningless), through the exact projection.
    pub fn project(&self, x_cam: &Vector3<f64>) -> Vector2<f64> {
        let n = Vector2::new(x_cam.x / x_cam.z, x_cam.y / x_cam.z);
        if self.is_pinhole() {
            return self.to_pixels(&n);
        }
        self.to_pixels(&self.distort(&n).0)
    }

    /// [`Camera::project`] and its Jacobian `∂u/∂x_cam` (2x3).
    pub fn project_with_jacobian(&self, x_cam: &Vector3<f64>) -> (Vector2<f64>, Matrix2x3<f64>) {
        let z = x_cam.z;
        let n = Vector2::new(x_cam.x / z, x_cam.y / z);
        let dn_dx = Matrix2x3::new(1.0 / z, 0.0, -n.x / z, 0.0, 1.0 / z, -n.y / z);
        let k = self.pinhole.pixel_jacobian();
        if self.is_pinhole() {
            return (self.to_pixels(&n), k * dn_dx);
        }
        let (d, jd) = self.distort(&n);
        (self.to_pixels(&d), k * jd * dn_dx)
    }

    /// The undistorted normalised coordinates `n` with `D(n) = d` for the pixel `u` (point `index` of
    /// the caller, for the error message), to [`UNPROJECTION_TOLERANCE_PX`]; `Error::Degenerate` when
    /// the pixel is outside the invertible region of the distortion.
    pub fn unproject(&self, u: &Vector2<f64>, index: usize) -> Result<Vector2<f64>> {
        let d = self.pinhole.pixel_to_normalized(u);
        if self.is_pinhole() {
            return Ok(d);
        }
        let k = self.pinhole.pixel_jacobian();
        let outside = |why: &str| Error::Degenerate {
            what: format!(
                "pixel {index} ({}, {}): outside the invertible region of the {} distortion ({why})",
                number(u.x),
                number(u.y),
                self.model.as_str()
            ),
        };
        // sqrt of the sum of squares rather than hypot (several times slower): a diverging step's
        // overflow to ∞ fails the tolerance all the same.
        let pixel_error = |e: &Vector2<f64>| (k * e).norm();
        let mut n = self.newton_start(&d);
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
    /// `K`, with `n` = [`Camera::unproject`]) and the Jacobian `∂u/∂ū = F ∂D/∂n F⁻¹` there (`F` the
    /// upper-left 2x2 block of `K`), which maps a small displacement of `ū` to the distorted pixels.
    /// Errors as [`Camera::unproject`].
    pub fn undistort(&self, u: &Vector2<f64>, index: usize) -> Result<(Vector2<f64>, Matrix2<f64>)> {
        let n = self.unproject(u, index)?;
        let (_, jd) = self.distort(&n);
        let f = self.pinhole.pixel_jacobian();
        let fy_inv = 1.0 / f[(1, 1)];
        let f_inv = Matrix2::new(1.0 / f[(0, 0)], -f[(0, 1)] / f[(0, 0)] * fy_inv, 0.0, fy_inv);
        Ok((self.to_pixels(&n), f * jd * f_inv))
    }

    /// [`Camera::undistort`] of a pixel `u` with covariance `cov_px` (pixels²): the undistorted
    /// pixel `ū` and, to first order, the covariance there, `J⁻¹ Σ J⁻ᵀ` with `J = ∂u/∂ū` (`None` where
    /// `J` is singular). The first-order form of an observation that the pose and the line
    /// triangulation through a lens hand to their pinhole stages. Errors as [`Camera::unproject`].
    pub fn undistort_with_covariance(
        &self,
        u: &Vector2<f64>,
        cov_px: &Matrix2<f64>,
        index: usize,
    ) -> Result<(Vector2<f64>, Option<Matrix2<f64>>)> {
        let (ubar, j) = self.undistort(u, index)?;
        Ok((ubar, j.try_inverse().map(|j_inv| j_inv * cov_px * j_inv.transpose())))
    }

    /// Whether `D` differs from the identity: false for the pinhole models, and for the radial,
    /// OPENCV, FULL_OPENCV, division, FOV and EUCM models whose distortion parameters are all zero
    /// (each is then `D(n) = n`: FOV's series at `ω = 0`, EUCM at `α = 0`). The fisheyes always
    /// distort (`m = n θ / r` is not `n`).
    pub fn distorts(&self) -> bool {
        let pinhole_params = if self.model.has_one_focal_length() { 3 } else { 4 };
        let zero_params = self.params[pinhole_params..].iter().all(|&p| p == 0.0);
        let identity_at_zero = matches!(
            self.model,
            CameraModel::SimpleRadial
                | CameraModel::Radial
                | CameraModel::OpenCv
                | CameraModel::FullOpenCv
                | CameraModel::SimpleDivision
                | CameraModel::Division
                | CameraModel::Fov
        );
        let eucm_identity = self.model == CameraModel::Eucm && self.params[4] == 0.0;
        !(self.is_pinhole() || (identity_at_zero && zero_params) || eucm_identity)
    }

    /// The 2x2 covariance of the undistorted normalised coordinates of a pixel with covariance `cov_px`,
    /// at the unprojected point `n`: `J⁻¹ Σ J⁻ᵀ` with `J = ∂u/∂n` (first order; see the module docs for
    /// when that is not enough).
    pub fn normalized_covariance(&self, n: &Vector2<f64>, cov_px: &Matrix2<f64>) -> Option<Matrix2<f64>> {
        let (_, jd) = self.distort(n);
        let inv = (self.pinhole.pixel_jacobian() * jd).try_inverse()?;
        Some(inv * cov_px * inv.transpose())
    }
}
