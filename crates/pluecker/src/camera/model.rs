//! Camera models with lens distortion, with COLMAP's names, model ids and parameter orders
//! (`colmap/sensor/models.h`), so that a COLMAP camera's `model` and `params` mean the same here.
//!
//! A model maps a camera-frame point `x_cam` (in front: `z > 0`) to pixels in three steps:
//! 1. normalised coordinates `n = (x/z, y/z)`;
//! 2. the distortion `d = D(n)`, in normalised units (identity for the pinhole models);
//! 3. pixels `u = (fx d₁ + cx, fy d₂ + cy)` (`fx = fy = f` for the models with one focal length;
//!    `u₁ = fx d₁ + skew d₂ + cx` for `SKEWED_PINHOLE`).
//!
//! `SKEWED_PINHOLE` is not one of COLMAP's models (it has no COLMAP id): it is the general upper
//! triangular `K = [[fx, skew, cx], [0, fy, cy], [0, 0, 1]]` of a calibration or of a decomposed 3x4
//! projection matrix, with no distortion ([`crate::camera::Camera::from_matrix`]).
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
//! | — | `SKEWED_PINHOLE` | fx, fy, cx, cy, skew | none; pixels `u = (fx n₁ + skew n₂ + cx, fy n₂ + cy)` |
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
//! fold radius ([`super::fold_radius`]), the first radius where the radial distortion stops increasing. A
//! strong barrel distortion folds the image beyond that radius: pixels past the fold have no preimage
//! on the branch through the principal point (a polynomial such as RADIAL's may rise again further
//! out, where Newton's method would otherwise find a preimage on the outer branch) and are rejected
//! with [`Error::Degenerate`] naming the point.

use crate::error::{Error, Result};

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
    /// `fx, fy, cx, cy, skew`: no distortion, a skewed pixel grid (not a COLMAP model; see the module
    /// docs). Its discriminant is not a COLMAP id ([`CameraModel::colmap_id`]).
    SkewedPinhole = 1000,
}

impl CameraModel {
    /// Every model: COLMAP's, in the order of their model ids (`ALL[i].colmap_id() == Some(i)`), then
    /// `SKEWED_PINHOLE`.
    pub const ALL: &'static [CameraModel] = <CameraModel as strum::VariantArray>::VARIANTS;

    /// COLMAP's model id; `None` for `SKEWED_PINHOLE`, which COLMAP does not have.
    pub fn colmap_id(&self) -> Option<u32> {
        match self {
            CameraModel::SkewedPinhole => None,
            model => Some(*model as u32),
        }
    }

    /// Whether the model has no distortion (`D(n) = n`): the pinhole models, whose projection is
    /// `u = K x_cam / z` (the fast path of [`crate::camera::Camera`]).
    pub fn is_pinhole(&self) -> bool {
        matches!(
            self,
            CameraModel::SimplePinhole | CameraModel::Pinhole | CameraModel::SkewedPinhole
        )
    }

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
            CameraModel::SkewedPinhole => &["fx", "fy", "cx", "cy", "skew"],
        }
    }

    /// Whether the model has one focal length `f` (`fx = fy = f`), first, then `cx, cy`.
    pub(super) fn has_one_focal_length(&self) -> bool {
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
    pub(super) fn is_fisheye(&self) -> bool {
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
pub(super) const MAX_UNPROJECTION_ITERATIONS: usize = 100;

/// Below this `ω²` COLMAP's FOV projection uses its series in `ω`, and below this `r²` its series in `r`.
pub(super) const FOV_SERIES_BOUND: f64 = 1e-4;

// Written and read by name with the `serde` feature.
crate::names::serde_by_name!(CameraModel);
