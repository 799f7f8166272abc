//! Camera models with lens distortion, with COLMAP's names, model ids and parameter orders
//! (`colmap/sensor/models.h`), so that a COLMAP camera's `model` and `params` mean the same here.
//!
//! A model maps a camera-frame point `x_cam` (in front: `z > 0`) to pixels in three steps:
//! 1. normalised coordinates `n = (x/z, y/z)`;
//! 2. the distortion `d = D(n)`, in normalised units (identity for the pinhole models);
//! 3. pixels `u = (fx d₁ + cx, fy d₂ + cy)` (`fx = fy = f` for the models with one focal length).
//!
//! | id | model | parameters | distortion `D(n)`, with `r² = n·n` |
//! |---|---|---|---|
//! | 0 | `SIMPLE_PINHOLE` | f, cx, cy | none |
//! | 1 | `PINHOLE` | fx, fy, cx, cy | none |
//! | 2 | `SIMPLE_RADIAL` | f, cx, cy, k | `n (1 + k r²)` |
//! | 3 | `RADIAL` | f, cx, cy, k1, k2 | `n (1 + k1 r² + k2 r⁴)` |
//! | 4 | `OPENCV` | fx, fy, cx, cy, k1, k2, p1, p2 | `n (1 + k1 r² + k2 r⁴) + t(n)` |
//! | 5 | `OPENCV_FISHEYE` | fx, fy, cx, cy, k1, k2, k3, k4 | `m (1 + k1 θ² + k2 θ⁴ + k3 θ⁶ + k4 θ⁸)` |
//! | 6 | `FULL_OPENCV` | fx, fy, cx, cy, k1, k2, p1, p2, k3, k4, k5, k6 | `n (1 + k1 r² + k2 r⁴ + k3 r⁶) / (1 + k4 r² + k5 r⁴ + k6 r⁶) + t(n)` |
//! | 7 | `FOV` | fx, fy, cx, cy, omega | `n atan(2 r tan(ω/2)) / (ω r)` (with COLMAP's series, below) |
//! | 8 | `SIMPLE_RADIAL_FISHEYE` | f, cx, cy, k | `m (1 + k θ²)` |
//! | 9 | `RADIAL_FISHEYE` | f, cx, cy, k1, k2 | `m (1 + k1 θ² + k2 θ⁴)` |
//! | 10 | `THIN_PRISM_FISHEYE` | fx, fy, cx, cy, k1, k2, p1, p2, k3, k4, sx1, sy1 | `m (1 + k1 θ² + k2 θ⁴ + k3 θ⁶ + k4 θ⁸) + t(m) + θ² (sx1, sy1)` |
//! | 11 | `RAD_TAN_THIN_PRISM_FISHEYE` | fx, fy, cx, cy, k0, k1, k2, k3, k4, k5, p0, p1, s0, s1, s2, s3 | `v + t(v)|_{p1 := p1, p2 := p0} + (s0 ρ² + s1 ρ⁴, s2 ρ² + s3 ρ⁴)`, `v = m (1 + k0 θ² + k1 θ⁴ + … + k5 θ¹²)`, `ρ = |v|` |
//! | 12 | `SIMPLE_DIVISION` | f, cx, cy, k | `2 n / (1 + √(1 − 4 k r²))` |
//! | 13 | `DIVISION` | fx, fy, cx, cy, k | `2 n / (1 + √(1 − 4 k r²))` |
//! | 14 | `SIMPLE_FISHEYE` | f, cx, cy | `m` |
//! | 15 | `FISHEYE` | fx, fy, cx, cy | `m` |
//! | 16 | `EUCM` | fx, fy, cx, cy, alpha, beta | `n / (α √(1 + β r²) + 1 − α)` |
//!
//! `t(n) = (2 p1 n₁n₂ + p2 (r² + 2n₁²), p1 (r² + 2n₂²) + 2 p2 n₁n₂)` is the tangential term (of its
//! argument). The fisheye models distort the equidistant coordinates `m = n θ / r`, `θ = atan r`, the
//! angle of the ray to the optical axis (`|m| = θ`). The division models are defined in COLMAP by their
//! unprojection `n = d / (1 + k |d|²)`; `D` is its inverse on the branch through the principal point, the
//! projection COLMAP computes. FOV follows COLMAP's projection exactly, including its two series: for
//! `ω² < 1e-4`, `D(n) = n (1 + ω² r² / 3 − ω² / 12)` (COLMAP's expression, which is the series of the
//! *undistortion*; it differs from the closed form by `O(ω²)`, and COLMAP's own unprojection does not
//! invert it), and for `r² < 1e-4`, `D(n) = n (2 tan(ω/2) / ω) (1 − 4 tan²(ω/2) r² / 3)`, which jumps to the
//! closed form at `r = 0.01` by `(2 r tan(ω/2))⁵ / (5ω)`: 3e-11 in normalised units for `ω = 1`,
//! 1e-4 for `ω = 3` (pixels in that gap have no preimage, and their unprojection is an error).
//! COLMAP's bundle adjustment minimises reprojection errors through this projection, so it is the one a
//! COLMAP model is consistent with.
//!
//! `EQUIRECTANGULAR` (COLMAP's id 17) is not a model here: it is spherical, sees behind the camera where
//! `n = (x/z, y/z)` does not exist, and has no focal length; [`CameraModel::parse`] refuses it by name.
//!
//! **Unprojection** inverts the distortion by Newton's method on `D(n) = d`, with the analytic Jacobian,
//! from the closed-form inverse where the model has one (division, EUCM, FOV, the fisheyes' `tan θ`).
//! It stops when the residual, in pixels, is below [`UNPROJECTION_TOLERANCE_PX`] (1e-10 px). The answer
//! must be in the invertible region: the Jacobian of `D` must have a positive determinant there, so
//! that the distortion is locally one-to-one and keeps the orientation, and it must lie inside the
//! fold radius ([`fold_radius`]), the first radius where the radial distortion stops increasing. A
//! strong barrel distortion folds the image beyond that radius: pixels past the fold have no preimage
//! on the branch through the principal point (a polynomial such as RADIAL's may rise again further
//! out, where Newton's method would otherwise find a preimage on the outer branch) and are rejected
//! with [`Error::Degenerate`] naming the point.

use crate::camera::Camera;
use crate::error::{number, Error, Result};
use crate::lens_bounds::{domain, Coefficients, Distortion, Domain};
use nalgebra::{Matrix2, Matrix2x3, Vector2, Vector3};

/// The camera models, with COLMAP's names (see the module table for their parameters); the
/// discriminant is COLMAP's model id.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, strum::IntoStaticStr, strum::EnumString, strum::VariantArray)]
#[strum(serialize_all = "SCREAMING_SNAKE_CASE")]
pub enum CameraModel {
    /// `f, cx, cy`: one focal length, no distortion.
    SimplePinhole = 0,
    /// `fx, fy, cx, cy`: no distortion.
    Pinhole = 1,
    /// `f, cx, cy, k`: one radial term.
    SimpleRadial = 2,
    /// `f, cx, cy, k1, k2`: two radial terms.
    Radial = 3,
    /// `fx, fy, cx, cy, k1, k2, p1, p2`: OpenCV's radial and tangential terms.
    #[strum(serialize = "OPENCV")]
    OpenCv = 4,
    /// `fx, fy, cx, cy, k1, k2, k3, k4`: OpenCV's equidistant fisheye.
    #[strum(serialize = "OPENCV_FISHEYE")]
    OpenCvFisheye = 5,
    /// `fx, fy, cx, cy, k1, k2, p1, p2, k3, k4, k5, k6`: OpenCV's rational model.
    #[strum(serialize = "FULL_OPENCV")]
    FullOpenCv = 6,
    /// `fx, fy, cx, cy, omega`: the field-of-view model.
    Fov = 7,
    /// `f, cx, cy, k`: equidistant fisheye with one radial term.
    SimpleRadialFisheye = 8,
    /// `f, cx, cy, k1, k2`: equidistant fisheye with two radial terms.
    RadialFisheye = 9,
    /// `fx, fy, cx, cy, k1, k2, p1, p2, k3, k4, sx1, sy1`: fisheye with tangential and thin-prism terms.
    ThinPrismFisheye = 10,
    /// COLMAP's `RAD_TAN_THIN_PRISM_FISHEYE` (16 parameters).
    RadTanThinPrismFisheye = 11,
    /// `f, cx, cy, k`: one-parameter division model.
    SimpleDivision = 12,
    /// `fx, fy, cx, cy, k`: division model.
    Division = 13,
    /// `f, cx, cy`: equidistant fisheye without distortion terms.
    SimpleFisheye = 14,
    /// `fx, fy, cx, cy`: equidistant fisheye without distortion terms.
    Fisheye = 15,
    /// `fx, fy, cx, cy, alpha, beta`: the enhanced unified camera model.
    Eucm = 16,
}

impl CameraModel {
    /// Every model, in COLMAP's order of model ids (`ALL[i] as usize == i`, COLMAP's ids).
    pub const ALL: &'static [CameraModel] = <CameraModel as strum::VariantArray>::VARIANTS;

    /// COLMAP's name of the model.
    pub fn as_str(&self) -> &'static str {
        self.into()
    }

    /// The model of a COLMAP name; `Error::InvalidOption` naming the known ones otherwise, and saying
    /// why for COLMAP's `EQUIRECTANGULAR`.
    pub fn parse(name: &str) -> Result<CameraModel> {
        if name == "EQUIRECTANGULAR" {
            return Err(Error::InvalidOption {
                name: "model".into(),
                reason: "camera model 'EQUIRECTANGULAR' is not supported: it is a spherical (360°) model, \
                         which sees behind the camera where normalised coordinates (x/z, y/z) do not exist, \
                         and has no focal length; only COLMAP's perspective models are"
                    .into(),
            });
        }
        crate::names::parse("model", "camera model", name)
    }

    /// The parameter names, in COLMAP's order.
    pub fn parameter_names(&self) -> &'static [&'static str] {
        match self {
            CameraModel::SimplePinhole | CameraModel::SimpleFisheye => &["f", "cx", "cy"],
            CameraModel::Pinhole | CameraModel::Fisheye => &["fx", "fy", "cx", "cy"],
            CameraModel::SimpleRadial | CameraModel::SimpleRadialFisheye | CameraModel::SimpleDivision => {
                &["f", "cx", "cy", "k"]
            }
            CameraModel::Radial | CameraModel::RadialFisheye => &["f", "cx", "cy", "k1", "k2"],
            CameraModel::OpenCv => &["fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2"],
            CameraModel::OpenCvFisheye => &["fx", "fy", "cx", "cy", "k1", "k2", "k3", "k4"],
            CameraModel::FullOpenCv => &["fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6"],
            CameraModel::Fov => &["fx", "fy", "cx", "cy", "omega"],
            CameraModel::ThinPrismFisheye => {
                &["fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3", "k4", "sx1", "sy1"]
            }
            CameraModel::RadTanThinPrismFisheye => &[
                "fx", "fy", "cx", "cy", "k0", "k1", "k2", "k3", "k4", "k5", "p0", "p1", "s0", "s1", "s2", "s3",
            ],
            CameraModel::Division => &["fx", "fy", "cx", "cy", "k"],
            CameraModel::Eucm => &["fx", "fy", "cx", "cy", "alpha", "beta"],
        }
    }

    /// Whether the model has one focal length `f` (`fx = fy = f`), first, then `cx, cy`.
    fn has_one_focal_length(&self) -> bool {
        matches!(
            self,
            CameraModel::SimplePinhole
                | CameraModel::SimpleRadial
                | CameraModel::Radial
                | CameraModel::SimpleRadialFisheye
                | CameraModel::RadialFisheye
                | CameraModel::SimpleDivision
                | CameraModel::SimpleFisheye
        )
    }

    /// Whether the model distorts the equidistant coordinates `m = n θ / r` (see the module docs).
    fn is_fisheye(&self) -> bool {
        matches!(
            self,
            CameraModel::OpenCvFisheye
                | CameraModel::SimpleRadialFisheye
                | CameraModel::RadialFisheye
                | CameraModel::ThinPrismFisheye
                | CameraModel::RadTanThinPrismFisheye
                | CameraModel::SimpleFisheye
                | CameraModel::Fisheye
        )
    }
}

/// Residual of the unprojection, pixels, below which Newton's method stops.
pub const UNPROJECTION_TOLERANCE_PX: f64 = 1e-10;

/// Newton iterations of the unprojection before it gives up (it converges quadratically: a handful
/// are used in the invertible region).
const MAX_UNPROJECTION_ITERATIONS: usize = 100;

/// Below this `ω²` COLMAP's FOV projection uses its series in `ω`, and below this `r²` its series in `r`.
const FOV_SERIES_BOUND: f64 = 1e-4;

/// A camera of one of the [`CameraModel`]s: intrinsics and distortion, checked.
#[derive(Debug, Clone, PartialEq)]
pub struct LensCamera {
    model: CameraModel,
    params: Vec<f64>,
    /// The pinhole part, checked once ([`LensCamera::pinhole`]).
    pinhole: Camera,
    /// The radius `|n|` where the radial distortion stops increasing ([`fold_radius`]); `∞` when it never does.
    fold_radius: f64,
    /// The distortion the certificates' enclosures cover ([`covered_distortion`]) and the disc where it
    /// is proved one-to-one ([`crate::lens_bounds::domain`], a scan for the tangential terms): computed
    /// once here, as they depend on the camera alone, and read by every observation's bound.
    bounds: Option<(Distortion, Option<Domain>)>,
}

/// The distortion of `model` with `params` in the form of [`crate::lens_bounds`], or `None` when its
/// enclosures do not cover it: thin-prism or tangential terms of the fisheyes, a rational FULL_OPENCV,
/// FOV (whose projection in COLMAP is piecewise, with a jump).
fn covered_distortion(model: CameraModel, p: &[f64]) -> Option<Distortion> {
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
        CameraModel::SimplePinhole | CameraModel::Pinhole => Some(Polynomial(Coefficients::new())),
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

/// `v g` and its Jacobian `g I + 2 g' v vᵀ`, for a radial factor `g(|v|²)` with derivative `g' = dg/d|v|²`.
fn scaled(v: &Vector2<f64>, g: f64, dg: f64) -> (Vector2<f64>, Matrix2<f64>) {
    (v * g, Matrix2::identity() * g + v * v.transpose() * (2.0 * dg))
}

/// `g(s) = 1 + c₁ s + c₂ s² + …` for `coefficients = [c₁, c₂, …]`, and `g'(s)` (Horner's scheme).
fn polynomial(coefficients: &[f64], s: f64) -> (f64, f64) {
    let (mut p, mut dp) = (0.0, 0.0);
    for c in coefficients.iter().rev() {
        dp = p + s * dp;
        p = c + s * p;
    }
    (1.0 + s * p, p + s * dp)
}

/// The radial polynomial distortion `v g(|v|²)`, `g` = [`polynomial`]`(coefficients)`, and its Jacobian.
fn radial(v: &Vector2<f64>, coefficients: &[f64]) -> (Vector2<f64>, Matrix2<f64>) {
    let (g, dg) = polynomial(coefficients, v.norm_squared());
    scaled(v, g, dg)
}

/// The tangential term `t(v)` of the module docs and its Jacobian.
fn tangential(v: &Vector2<f64>, p1: f64, p2: f64) -> (Vector2<f64>, Matrix2<f64>) {
    let (x, y) = (v.x, v.y);
    let r2 = x * x + y * y;
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
}

/// The thin-prism term `(s0 ρ² + s1 ρ⁴, s2 ρ² + s3 ρ⁴)`, `ρ = |v|`, and its Jacobian (rows
/// `(2 s0 + 4 s1 ρ²) vᵀ` and `(2 s2 + 4 s3 ρ²) vᵀ`).
fn thin_prism(v: &Vector2<f64>, s: [f64; 4]) -> (Vector2<f64>, Matrix2<f64>) {
    let q = v.norm_squared();
    let (a, b) = (2.0 * s[0] + 4.0 * s[1] * q, 2.0 * s[2] + 4.0 * s[3] * q);
    (
        Vector2::new(q * (s[0] + s[1] * q), q * (s[2] + s[3] * q)),
        Matrix2::new(a * v.x, a * v.y, b * v.x, b * v.y),
    )
}

/// The equidistant fisheye coordinates `m = n θ / r`, `θ = atan r`, and `∂m/∂n`.
fn equidistant(n: &Vector2<f64>) -> (Vector2<f64>, Matrix2<f64>) {
    let r2 = n.norm_squared();
    let r = r2.sqrt();
    if r < 1e-8 {
        // θ / r = 1 − r²/3 + …, which is 1 in double precision; the Jacobian is the identity to O(r²).
        return (*n, Matrix2::identity());
    }
    let theta = r.atan();
    // m = n s(r), s = θ / r: ∂m/∂n = s I + (s'(r) / r) n nᵀ with s' = (r θ'(r) − θ) / r², θ' = 1 / (1 + r²).
    // The cancellation in s' costs an absolute error ε / r² in s' / r, multiplied by |n nᵀ| = r².
    let s = theta / r;
    let ds = (r / (1.0 + r2) - theta) / r2;
    (n * s, Matrix2::identity() * s + n * n.transpose() * (ds / r))
}

/// COLMAP's FOV distortion (module docs, with its two series) and its Jacobian.
fn fov(n: &Vector2<f64>, omega: f64) -> (Vector2<f64>, Matrix2<f64>) {
    let s = n.norm_squared();
    let w2 = omega * omega;
    if w2 < FOV_SERIES_BOUND {
        return scaled(n, w2 * s / 3.0 - w2 / 12.0 + 1.0, w2 / 3.0);
    }
    let t = (omega / 2.0).tan();
    if s < FOV_SERIES_BOUND {
        let g = -2.0 * t * (4.0 * s * t * t - 3.0) / (3.0 * omega);
        return scaled(n, g, -8.0 * t * t * t / (3.0 * omega));
    }
    let r = s.sqrt();
    let a = (2.0 * r * t).atan();
    let g = a / (r * omega);
    // dg/dr = (2 t r / (1 + 4 t² r²) − a) / (ω r²), and dg/ds = (dg/dr) / (2r).
    let dg_dr = (2.0 * t * r / (1.0 + 4.0 * t * t * s) - a) / (omega * s);
    scaled(n, g, dg_dr / (2.0 * r))
}

/// The division model's projection `2 n / (1 + √(1 − 4 k r²))` and its Jacobian (NaN where `4 k r² > 1`:
/// no point there projects).
fn division(n: &Vector2<f64>, k: f64) -> (Vector2<f64>, Matrix2<f64>) {
    let q = (1.0 - 4.0 * k * n.norm_squared()).sqrt();
    // g = 2 / (1 + q), q' = dq/ds = −2k / q: g' = 4k / (q (1 + q)²).
    scaled(n, 2.0 / (1.0 + q), 4.0 * k / (q * (1.0 + q) * (1.0 + q)))
}

/// EUCM's projection `n / (α √(1 + β r²) + 1 − α)` and its Jacobian.
fn eucm(n: &Vector2<f64>, alpha: f64, beta: f64) -> (Vector2<f64>, Matrix2<f64>) {
    let q = (1.0 + beta * n.norm_squared()).sqrt();
    let g = 1.0 / (alpha * q + 1.0 - alpha);
    // g' = −α q' g², q' = β / (2q).
    scaled(n, g, -alpha * beta / (2.0 * q) * g * g)
}

impl LensCamera {
    /// The camera of `model` with `params` in COLMAP's order. `Error::Shape` for a wrong count,
    /// `Error::NonFinite` for NaN/inf, `Error::SingularCamera` when its pinhole part is not a
    /// [`Camera`] (a zero focal length, `fx fy` overflowing).
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
        // Its pinhole part must be a camera (non-zero focal lengths, `K` invertible).
        let (fx, fy, cx, cy) = if model.has_one_focal_length() {
            (params[0], params[0], params[1], params[2])
        } else {
            (params[0], params[1], params[2], params[3])
        };
        let pinhole = Camera::new(fx, fy, cx, cy, 0.0).map_err(|e| match e {
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
        let camera = LensCamera {
            model,
            params: params.to_vec(),
            pinhole,
            fold_radius: fold,
            bounds,
        };
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
        if self.model.has_one_focal_length() {
            (p[0], p[0])
        } else {
            (p[0], p[1])
        }
    }

    /// `(cx, cy)`, pixels.
    pub fn principal_point(&self) -> (f64, f64) {
        let p = &self.params;
        if self.model.has_one_focal_length() {
            (p[1], p[2])
        } else {
            (p[2], p[3])
        }
    }

    /// The radius `|n|` of normalised coordinates where the radial distortion stops increasing
    /// ([`fold_radius`]; `∞` when it never does): inside it the lens maps one-to-one.
    pub fn fold_radius(&self) -> f64 {
        self.fold_radius
    }

    /// The distortion in the form the certificates' interval enclosures cover ([`crate::lens_bounds`]),
    /// or `None` when they do not cover it (thin-prism or tangential terms of the fisheyes, a rational
    /// FULL_OPENCV, FOV).
    pub(crate) fn covered_distortion(&self) -> Option<&Distortion> {
        self.bounds.as_ref().map(|(d, _)| d)
    }

    /// The disc where the covered distortion is proved one-to-one ([`crate::lens_bounds::domain`]);
    /// `None` when it is not covered or the disc is empty.
    pub(crate) fn one_to_one_domain(&self) -> Option<Domain> {
        self.bounds.as_ref().and_then(|(_, domain)| *domain)
    }

    /// The pinhole part: the focal lengths and principal point, no skew (the camera of undistorted pixels).
    pub fn pinhole(&self) -> Result<Camera> {
        Ok(self.pinhole)
    }

    /// Whether the model has no distortion (the pinhole fast path applies).
    pub fn is_pinhole(&self) -> bool {
        matches!(self.model, CameraModel::SimplePinhole | CameraModel::Pinhole)
    }

    /// The distortion `D(n)` of normalised coordinates (see the module table) and its Jacobian `∂D/∂n`.
    pub fn distort(&self, n: &Vector2<f64>) -> (Vector2<f64>, Matrix2<f64>) {
        let p = &self.params;
        match self.model {
            CameraModel::SimplePinhole | CameraModel::Pinhole => (*n, Matrix2::identity()),
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
    fn distort_fisheye(&self, m: &Vector2<f64>) -> (Vector2<f64>, Matrix2<f64>) {
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
    fn newton_start(&self, d: &Vector2<f64>) -> Vector2<f64> {
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
        // sqrt of the sum of squares rather than hypot (several times slower): a diverging step's
        // overflow to ∞ fails the tolerance all the same.
        let pixel_error = |e: &Vector2<f64>| ((e.x * fx).powi(2) + (e.y * fy).powi(2)).sqrt();
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

    /// [`LensCamera::undistort`] of a pixel `u` with covariance `cov_px` (pixels²): the undistorted
    /// pixel `ū` and, to first order, the covariance there, `J⁻¹ Σ J⁻ᵀ` with `J = ∂u/∂ū` (`None` where
    /// `J` is singular). The first-order form of an observation that the pose and the line
    /// triangulation through a lens hand to their pinhole stages. Errors as [`LensCamera::unproject`].
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
        let (fx, fy) = self.focal();
        let inv = (Matrix2::new(fx, 0.0, 0.0, fy) * jd).try_inverse()?;
        Some(inv * cov_px * inv.transpose())
    }
}

/// The radius `r*` of normalised coordinates where the radial part of the distortion of `model` stops
/// increasing (`∞` when it increases everywhere): the first positive zero of `dρ/dr` for the radial map
/// `ρ(r) = r g(r²)`, or of the rational model's denominator, or for the fisheyes the first zero of
/// `dθ_d/dθ` in `θ = atan r < π/2`, or where the projection stops existing (division, EUCM). Beyond it
/// the distortion folds back, and a pixel whose Newton solution lies there has no preimage on the
/// branch through the principal point ([`LensCamera::unproject`]).
///
/// In `s = r²` the zeros are those of polynomials: `1 + 3k s` (SIMPLE_RADIAL), `1 + 3k₁ s + 5k₂ s²`
/// (RADIAL, OPENCV), `(1 + 3k₁ s + 5k₂ s² + 7k₃ s³) den(s) − num(s) (2k₄ s + 4k₅ s² + 6k₆ s³)` and
/// `den(s)` (FULL_OPENCV, `g = num / den`), and in `t = θ²` `1 + 3k₁ t + 5k₂ t² + …`, the odd
/// multiples of the radial coefficients (every fisheye: `θ_d = θ (1 + k₁ θ² + …)`; SIMPLE_FISHEYE and
/// FISHEYE have `θ_d = θ`, increasing: `∞`). Tangential and thin-prism terms are not part of it (the
/// Jacobian test of the unprojection covers them where they fold). The others, in closed form:
/// - FOV: `ρ = atan(2 r tan(ω/2)) / ω` increases for `0 < |ω| < π` (`∞`), decreases at once otherwise
///   (`0`); COLMAP's series in `ω` increases (`ρ' = 1 − ω²/12 + ω² r² > 0` for `ω² < 1e-4`), and its
///   series in `r`, `ρ' ∝ 1 − 4 tan²(ω/2) r²`, turns at `r = 1 / (2 |tan(ω/2)|)` if that is below
///   its range `r < 0.01`.
/// - division: `ρ' = 2 / (q (1 + q))`, `q = √(1 − 4k r²)`, is positive wherever the projection exists:
///   `∞` for `k ≤ 0`, `1 / (2 √k)` (the edge of its domain, where `ρ' = ∞`) for `k > 0`.
/// - EUCM: `ρ' = (α / q + 1 − α) / den²`, `q = √(1 + β r²)`, `den = α q + 1 − α`: the first `r > 0`
///   where `q = 0` (the edge of the domain), `den = 0` (a pole, `q = (α − 1) / α`) or the numerator
///   vanishes (`q = α / (α − 1)`); `∞` for COLMAP's valid range `0 ≤ α ≤ 1`, `β > 0`.
pub fn fold_radius(model: CameraModel, params: &[f64]) -> f64 {
    let p = params;
    let radius_of_s = |s: Option<f64>| s.map_or(f64::INFINITY, f64::sqrt);
    // 1 + 3k₁ t + 5k₂ t² + …: the derivative of t ↦ √t (1 + k₁ t + k₂ t² + …) times 2√t.
    let odd_slope = |k: &[f64]| {
        std::iter::once(1.0)
            .chain(k.iter().enumerate().map(|(i, c)| (2 * i + 3) as f64 * c))
            .collect::<Vec<f64>>()
    };
    let fisheye = |k: &[f64]| match first_positive_root(&odd_slope(k)) {
        Some(t) if t.sqrt() < std::f64::consts::FRAC_PI_2 => t.sqrt().tan(),
        _ => f64::INFINITY,
    };
    match model {
        CameraModel::SimplePinhole | CameraModel::Pinhole => f64::INFINITY,
        CameraModel::SimpleRadial => radius_of_s(first_positive_root(&odd_slope(&p[3..4]))),
        CameraModel::Radial => radius_of_s(first_positive_root(&odd_slope(&p[3..5]))),
        CameraModel::OpenCv => radius_of_s(first_positive_root(&odd_slope(&p[4..6]))),
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
        CameraModel::OpenCvFisheye => fisheye(&p[4..8]),
        CameraModel::SimpleRadialFisheye => fisheye(&p[3..4]),
        CameraModel::RadialFisheye => fisheye(&p[3..5]),
        CameraModel::ThinPrismFisheye => fisheye(&[p[4], p[5], p[8], p[9]]),
        CameraModel::RadTanThinPrismFisheye => fisheye(&p[4..10]),
        CameraModel::SimpleFisheye | CameraModel::Fisheye => f64::INFINITY,
        CameraModel::Fov => {
            let omega = p[4];
            if omega * omega < FOV_SERIES_BOUND {
                return f64::INFINITY;
            }
            let t = (omega / 2.0).tan();
            // |ω| ≥ 0.01 here, so t / ω is a number whenever t is finite.
            if !t.is_finite() || t / omega <= 0.0 {
                return 0.0;
            }
            let turn = 1.0 / (2.0 * t.abs());
            if turn * turn < FOV_SERIES_BOUND {
                turn
            } else {
                f64::INFINITY
            }
        }
        CameraModel::SimpleDivision | CameraModel::Division => {
            let k = p[p.len() - 1];
            if k > 0.0 {
                0.5 / k.sqrt()
            } else {
                f64::INFINITY
            }
        }
        CameraModel::Eucm => {
            let (alpha, beta) = (p[4], p[5]);
            // r² of a value of q = √(1 + β r²), when it is reached at some r > 0.
            let s_of_q = |q: f64| {
                let s = (q * q - 1.0) / beta;
                (q >= 0.0 && s > 0.0 && s.is_finite()).then_some(s)
            };
            [
                s_of_q(0.0),
                s_of_q((alpha - 1.0) / alpha),
                s_of_q(alpha / (alpha - 1.0)),
            ]
            .into_iter()
            .flatten()
            .min_by(f64::total_cmp)
            .map_or(f64::INFINITY, f64::sqrt)
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

/// The one camera type of pose and triangulation: the pinhole [`Camera`] (with skew) or a
/// [`LensCamera`] of any of COLMAP's models (whose pixels are the observed, distorted ones).
#[derive(Debug, Clone, PartialEq)]
pub enum AnyCamera {
    /// No distortion: `u = K x_cam / z`.
    Pinhole(Camera),
    /// A COLMAP camera model: `u = K D(x_cam / z)` with the model's distortion `D`.
    Lens(LensCamera),
}

impl From<Camera> for AnyCamera {
    fn from(camera: Camera) -> Self {
        AnyCamera::Pinhole(camera)
    }
}

impl From<&Camera> for AnyCamera {
    fn from(camera: &Camera) -> Self {
        AnyCamera::Pinhole(*camera)
    }
}

impl From<LensCamera> for AnyCamera {
    fn from(camera: LensCamera) -> Self {
        AnyCamera::Lens(camera)
    }
}

impl From<&LensCamera> for AnyCamera {
    fn from(camera: &LensCamera) -> Self {
        AnyCamera::Lens(camera.clone())
    }
}

impl From<&AnyCamera> for AnyCamera {
    fn from(camera: &AnyCamera) -> Self {
        camera.clone()
    }
}

impl AnyCamera {
    /// The pinhole part `K` (the lens's focal lengths and principal point, no skew, for a
    /// [`LensCamera`]).
    pub fn pinhole(&self) -> Result<Camera> {
        match self {
            AnyCamera::Pinhole(camera) => Ok(*camera),
            AnyCamera::Lens(lens) => lens.pinhole(),
        }
    }

    /// The lens when the camera distorts (a [`LensCamera`] of a model other than the pinholes).
    pub fn distortion(&self) -> Option<&LensCamera> {
        match self {
            AnyCamera::Lens(lens) if !lens.is_pinhole() => Some(lens),
            _ => None,
        }
    }

    /// Pixels of the camera-frame point `x_cam` (`z > 0`) and the Jacobian `∂u/∂x_cam` (2x3), through
    /// the exact projection.
    pub fn project(&self, x_cam: &Vector3<f64>) -> (Vector2<f64>, Matrix2x3<f64>) {
        match self {
            AnyCamera::Pinhole(camera) => {
                let z = x_cam.z;
                let n = Vector2::new(x_cam.x / z, x_cam.y / z);
                let dn_dx = Matrix2x3::new(1.0 / z, 0.0, -n.x / z, 0.0, 1.0 / z, -n.y / z);
                (camera.normalized_to_pixel(&n), camera.pixel_jacobian() * dn_dx)
            }
            AnyCamera::Lens(lens) => lens.project(x_cam),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    #[test]
    fn a_lens_whose_pinhole_part_is_not_a_camera_is_refused() {
        // Its pinhole part must be a `Camera`: `pinhole()` never fails on a lens that was made.
        for f in [0.0, 1e-300, 1e300] {
            let err = LensCamera::new(CameraModel::SimpleRadial, &[f, 320.0, 240.0, -0.1]).unwrap_err();
            assert!(matches!(err, Error::SingularCamera { .. }), "{err}");
            assert!(
                err.to_string()
                    .starts_with("singular camera: SIMPLE_RADIAL: focal lengths"),
                "{err}"
            );
        }
        let lens = LensCamera::new(CameraModel::Pinhole, &[1e-9, 1e150, 0.0, 0.0]).unwrap();
        assert!(lens.pinhole().is_ok());
    }

    /// A camera of each model, in COLMAP's id order, with COLMAP-like distortion (moderate barrel, small
    /// tangential and thin-prism terms; the fisheyes' distortion is 5-10 % at 80° off axis).
    fn cameras() -> Vec<LensCamera> {
        let params: [(CameraModel, &[f64]); 17] = [
            (CameraModel::SimplePinhole, &[800.0, 320.0, 240.0]),
            (CameraModel::Pinhole, &[800.0, 790.0, 320.0, 240.0]),
            (CameraModel::SimpleRadial, &[800.0, 320.0, 240.0, -0.1]),
            (CameraModel::Radial, &[800.0, 320.0, 240.0, -0.1, 0.02]),
            (
                CameraModel::OpenCv,
                &[800.0, 790.0, 320.0, 240.0, -0.2, 0.05, 1e-3, -5e-4],
            ),
            (
                CameraModel::OpenCvFisheye,
                &[400.0, 395.0, 320.0, 240.0, 0.05, -0.01, 0.002, -3e-4],
            ),
            (
                CameraModel::FullOpenCv,
                &[
                    800.0, 790.0, 320.0, 240.0, -0.2, 0.05, 1e-3, -5e-4, 0.01, 0.02, -0.01, 0.005,
                ],
            ),
            (CameraModel::Fov, &[400.0, 395.0, 320.0, 240.0, 0.9]),
            (CameraModel::SimpleRadialFisheye, &[400.0, 320.0, 240.0, 0.05]),
            (CameraModel::RadialFisheye, &[400.0, 320.0, 240.0, 0.05, -0.01]),
            (
                CameraModel::ThinPrismFisheye,
                &[
                    400.0, 395.0, 320.0, 240.0, 0.05, -0.01, 1e-3, -5e-4, 0.002, -3e-4, 2e-3, -1e-3,
                ],
            ),
            (
                CameraModel::RadTanThinPrismFisheye,
                &[
                    400.0, 395.0, 320.0, 240.0, 0.05, -0.01, 0.002, -3e-4, 1e-5, -1e-6, 1e-3, -5e-4, 2e-3, -1e-3, 3e-4,
                    -2e-4,
                ],
            ),
            (CameraModel::SimpleDivision, &[800.0, 320.0, 240.0, -0.2]),
            (CameraModel::Division, &[800.0, 790.0, 320.0, 240.0, -0.2]),
            (CameraModel::SimpleFisheye, &[400.0, 320.0, 240.0]),
            (CameraModel::Fisheye, &[400.0, 395.0, 320.0, 240.0]),
            (CameraModel::Eucm, &[400.0, 395.0, 320.0, 240.0, 0.6, 1.1]),
        ];
        assert_eq!(params.map(|(m, _)| m).as_slice(), CameraModel::ALL);
        params.iter().map(|(m, p)| LensCamera::new(*m, p).unwrap()).collect()
    }

    /// The largest angle off axis of the test points of a model: 80° for the models that see that far
    /// (fisheyes, FOV, EUCM, the barrel division model), 30° for the polynomial ones, whose fold is near.
    fn widest_angle(model: CameraModel) -> f64 {
        let wide = model.is_fisheye()
            || matches!(
                model,
                CameraModel::Fov | CameraModel::Eucm | CameraModel::SimpleDivision | CameraModel::Division
            );
        (if wide { 80.0f64 } else { 30.0f64 }).to_radians()
    }

    /// Normalised coordinates at the given angle off axis, in direction `phi`.
    fn at_angle(theta: f64, phi: f64) -> Vector2<f64> {
        Vector2::new(phi.cos(), phi.sin()) * theta.tan()
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
    fn the_distortion_jacobians_match_finite_differences_from_the_axis_to_wide_angles() {
        let mut rng = Rng::new(43);
        for cam in cameras() {
            let widest = widest_angle(cam.model());
            // Near the axis (every radius from 1e-9, both sides of FOV's series bound r = 0.01), then
            // uniformly in angle up to the widest.
            let mut points: Vec<Vector2<f64>> = [1e-9, 1e-7, 1e-5, 1e-3, 5e-3, 9.9e-3, 1.01e-2, 0.05]
                .iter()
                .map(|&r| Vector2::new(r * 0.6, -r * 0.8))
                .collect();
            points.extend((0..200).map(|_| at_angle(rng.uniform_in(0.0, widest), rng.uniform_in(0.0, 6.3))));
            for n in points {
                let (_, j) = cam.distort(&n);
                // A step relative to |n| (down to 1e-4 of it, so that it stays on one side of FOV's
                // bound at |n| = 0.01 ± 1e-4), and 1e-7 in absolute terms away from the axis.
                let h = (1e-4 * n.norm()).min(1e-7);
                for k in 0..2 {
                    let mut np = n;
                    np[k] += h;
                    let mut nm = n;
                    nm[k] -= h;
                    let numeric = (cam.distort(&np).0 - cam.distort(&nm).0) / (2.0 * h);
                    // Truncation O(h² |D⁽³⁾|) ≤ 1e-14 and rounding O(ε |D| / h): |D| ≤ 2
                    // over h = min(1e-4 |n|, 1e-7) gives at most 4e-16 / 1e-7 = 4e-9 here.
                    let error = (numeric - j.column(k)).norm();
                    assert!(
                        error < 2e-8 * (1.0 + j.column(k).norm()),
                        "{:?} at n = {n:?}: ∂D/∂n{k} = {} vs {numeric} ({error:e})",
                        cam.model(),
                        j.column(k)
                    );
                }
            }
        }
    }

    #[test]
    fn models_have_colmap_ids_and_names() {
        // COLMAP's ids (colmap/sensor/models.h, CameraModelId), independent of the order of ALL.
        let colmap = [
            "SIMPLE_PINHOLE",
            "PINHOLE",
            "SIMPLE_RADIAL",
            "RADIAL",
            "OPENCV",
            "OPENCV_FISHEYE",
            "FULL_OPENCV",
            "FOV",
            "SIMPLE_RADIAL_FISHEYE",
            "RADIAL_FISHEYE",
            "THIN_PRISM_FISHEYE",
            "RAD_TAN_THIN_PRISM_FISHEYE",
            "SIMPLE_DIVISION",
            "DIVISION",
            "SIMPLE_FISHEYE",
            "FISHEYE",
            "EUCM",
        ];
        for (id, name) in colmap.iter().enumerate() {
            let model = CameraModel::parse(name).unwrap();
            assert_eq!(model as usize, id, "{name}");
            assert_eq!(CameraModel::ALL[id], model);
            assert_eq!(model.as_str(), *name);
        }
        let err = CameraModel::parse("EQUIRECTANGULAR").unwrap_err();
        assert!(
            matches!(&err, Error::InvalidOption { name, reason } if name == "model"
                && reason.contains("'EQUIRECTANGULAR' is not supported")
                && reason.contains("behind the camera")),
            "{err}"
        );
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
        // (model, parameters, expected pixels of the three points).
        type Case<'a> = (CameraModel, &'a [f64], [[f64; 2]; 3]);
        let cases: [Case; 3] = [
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
            let widest = widest_angle(cam.model());
            let (fx, fy) = cam.focal();
            let mut points: Vec<Vector2<f64>> = (0..200)
                .map(|_| at_angle(rng.uniform_in(0.0, widest), rng.uniform_in(0.0, 6.3)))
                .collect();
            points.extend([0.0, 1e-9, 1e-5, 5e-3, 0.0101].map(|r| Vector2::new(r * 0.6, -r * 0.8)));
            points.push(at_angle(widest, 2.0));
            for (i, x) in points.into_iter().enumerate() {
                let (u, _) = cam.project(&Vector3::new(x.x, x.y, 1.0));
                let n = cam
                    .unproject(&u, i)
                    .unwrap_or_else(|e| panic!("{:?} at {:.1}°: {e}", cam.model(), x.norm().atan().to_degrees()));
                let (back, _) = cam.project(&Vector3::new(n.x, n.y, 1.0));
                assert!(
                    (back - u).norm() <= 1e-10 * 1.5,
                    "{:?}: {:e} px",
                    cam.model(),
                    (back - u).norm()
                );
                // A residual of 1e-10 px moves n by at most ‖(diag(f) ∂D/∂n)⁻¹‖ 1e-10 (33x more at 80°
                // off axis than at the centre for an equidistant fisheye: dr/dθ = 1 / cos² θ).
                let (_, j) = cam.distort(&n);
                let sensitivity = (Matrix2::new(fx, 0.0, 0.0, fy) * j).try_inverse().unwrap().norm();
                assert!(
                    (n - x).norm() < 2.0 * sensitivity * 1.5e-10 + 1e-15 * (1.0 + x.norm()),
                    "{:?}: {:e} at |n| = {}",
                    cam.model(),
                    (n - x).norm(),
                    x.norm()
                );
            }
        }
    }

    #[test]
    fn pixels_without_a_preimage_are_refused_by_every_model() {
        // Pixels at 4 and 50 focal lengths from the principal point, far beyond the image of the half
        // space z > 0 for the models whose image is bounded: ρ < θ_d(90°) < 2 for these fisheyes,
        // 1 / (α √β) = 1.6 for EUCM, π / (2ω) = 1.75 for FOV, 2.2 = 1/√|k| for the barrel division model.
        for cam in cameras() {
            let bounded = cam.model().is_fisheye()
                || matches!(
                    cam.model(),
                    CameraModel::Fov | CameraModel::Eucm | CameraModel::SimpleDivision | CameraModel::Division
                );
            if !bounded {
                continue;
            }
            let (fx, fy) = cam.focal();
            let (cx, cy) = cam.principal_point();
            for scale in [4.0, 50.0] {
                let u = Vector2::new(cx + scale * fx * 0.6, cy - scale * fy * 0.8);
                let err = cam.unproject(&u, 9).unwrap_err();
                assert!(
                    matches!(&err, Error::Degenerate { what } if what.starts_with("pixel 9")),
                    "{:?}: {err}",
                    cam.model()
                );
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
        let cases: [(CameraModel, &[f64]); 14] = [
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
            (CameraModel::SimpleRadialFisheye, &[400.0, 320.0, 240.0, -0.3]),
            (CameraModel::RadialFisheye, &[400.0, 320.0, 240.0, -0.1, -0.05]),
            (
                CameraModel::ThinPrismFisheye,
                &[400.0, 395.0, 320.0, 240.0, -0.2, 0.01, 0.0, 0.0, -0.01, 0.001, 0.0, 0.0],
            ),
            (
                CameraModel::RadTanThinPrismFisheye,
                &[
                    400.0, 395.0, 320.0, 240.0, -0.2, 0.01, -0.01, 0.001, 1e-4, -1e-5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
                ],
            ),
            // tan(ω/2) = 92.6: COLMAP's series in r turns at r = 0.0054, inside its range r < 0.01.
            (CameraModel::Fov, &[400.0, 395.0, 320.0, 240.0, 3.12]),
            // k > 0: the projection exists for r < 1/(2√k) only.
            (CameraModel::SimpleDivision, &[800.0, 320.0, 240.0, 0.2]),
            // α > 1: ρ turns where q = α / (α − 1) = 3, r = √8.
            (CameraModel::Eucm, &[400.0, 395.0, 320.0, 240.0, 1.5, 1.0]),
            // α < 0: a pole where q = (α − 1) / α = 3, r = √8.
            (CameraModel::Eucm, &[400.0, 395.0, 320.0, 240.0, -0.5, 1.0]),
            // β < 0: the projection exists for r² < −1/β = 2 only.
            (CameraModel::Eucm, &[400.0, 395.0, 320.0, 240.0, 0.5, -0.5]),
        ];
        for (model, params) in cases {
            let cam = LensCamera::new(model, params).unwrap();
            let rho = |r: f64| cam.distort(&Vector2::new(r, 0.0)).0.x;
            let step = 1e-4;
            let turn = (1..200_000)
                .map(|i| i as f64 * step)
                .find(|&r| rho(r + step).partial_cmp(&rho(r)) != Some(std::cmp::Ordering::Greater))
                .expect("each case folds below r = 20");
            // The scan finds the turn to within one step (the maximum is flat: ρ' changes sign there; past
            // the edge of a domain or a pole ρ is NaN or negative, which is no increase either).
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
        for &m in CameraModel::ALL {
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
