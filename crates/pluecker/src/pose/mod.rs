//! Intrinsics pose from 2-D/3-D point and line correspondences (exterior orientation, PnP / PnL / PnPL).
//!
//! [`estimate_pose`] runs one of the estimators of Phong & Horaud 1995 and its baselines on points,
//! lines, or both, and by default refines the answer on the reprojection error so that it is the
//! maximum-likelihood pose under Gaussian pixel noise. Convention: `x_cam = R X_world + t`. The camera
//! is any [`crate::Camera`]: through a lens with distortion the refinement minimises the exact error
//! in the observed pixels (`lens` says what each stage works on).

pub(crate) mod algebraic;
pub(crate) mod candidates;
// The certificate is requested through `PoseOptions::certify` and reported as the crate's
// `Certificate`; its test hooks are `crate::testing::pose_certificate`.
pub(crate) mod certificate;
pub(crate) mod correspondences;
mod estimate;
pub mod generalized;
pub(crate) mod initialization;
pub(crate) mod lens;
pub(crate) mod linear;
pub mod minimal;
pub(crate) mod noise;
pub(crate) mod object_distance;
pub(crate) mod refinement;
pub(crate) mod reprojection;
mod result;
pub(crate) mod robust;

#[doc(no_inline)]
pub use crate::certificate::{Certificate, CertifyOptions};
#[doc(no_inline)]
pub use crate::cost_kind::CostKind;
pub use correspondences::Correspondences;
pub use estimate::estimate_pose;
pub use generalized::{estimate_rig_pose, ObservingCameras};
pub use noise::ObservationNoise;
pub use refinement::refine_pose;
pub use reprojection::{pose_covariance, ReprojectionCost};
pub use robust::{RansacOptions, RansacReport, RansacStop};

/// Stages and helpers the Python bindings and the integration tests call directly; not part of the
/// user-facing API.
#[doc(hidden)]
pub mod testing {
    pub use super::lens::undistort;
    pub use super::reprojection::covariance_from_information;
}

use crate::camera::Intrinsics;
use crate::chi_square::ResidualTest;
use crate::error::{Error, Result};
use crate::optim::levenberg_marquardt::LevenbergMarquardtOptions;
use crate::optim::Summary;
use crate::optim::{StoppingCriteria, Termination, TrustRegionOptions};
use crate::Report;
use nalgebra::{Matrix3, Matrix6, Vector3};
use reprojection::Pose;
use std::time::Instant;

/// The estimators. All of them accept points, lines, or both (the linear one uses points only).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, strum::IntoStaticStr, strum::EnumString, strum::VariantArray)]
#[strum(serialize_all = "kebab-case")]
pub enum Method {
    /// Rotation and translation together: eqs. 13 + 22 by the trust region with Hebden's step
    /// (section 4.1). The default.
    TrustRegion,
    /// Rotation from eq. 14 by the same trust region, then translation from eq. 15 by linear least
    /// squares. Points are paired into lines for the rotation (Figure 2) and used as they are for
    /// the translation.
    RotationThenTranslation,
    /// Eqs. 13 + 22 with the exact Hessian and the Moré-Sorensen step (section 4.2).
    TrustRegionExact,
    /// Plain Newton on eqs. 13 + 22 (the paper's baseline; may diverge).
    Newton,
    /// Levenberg-Marquardt on eqs. 13 + 22 (the paper's baseline).
    LevenbergMarquardt,
    /// Faugeras-Toscani linear calibration from ≥ 6 non-coplanar points; also estimates intrinsics.
    Linear,
}

impl Method {
    /// Every method, in the order above.
    pub const ALL: &'static [Method] = <Method as strum::VariantArray>::VARIANTS;

    /// The kebab-case name used by Python and the command line.
    pub fn as_str(&self) -> &'static str {
        self.into()
    }

    /// Parses [`Method::as_str`] names.
    pub fn parse(name: &str) -> Result<Method> {
        crate::names::parse("method", "method", name)
    }
}

/// Options of [`estimate_pose`]; every field has a documented default.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct PoseOptions {
    /// Estimator. Default [`Method::TrustRegion`].
    pub method: Method,
    /// Penalty λ on `r·r = 1` and `r·s = 0` (eqs. 13-15, 22). Paper: 50. Default `50.0`.
    pub penalty: f64,
    /// Solve the algebraic stage in a centred, unit-scale object frame. Default true.
    pub normalize: bool,
    /// Follow the estimator with a minimisation of the reprojection error (pixel distances for points,
    /// endpoint-to-projected-line distances for lines). Default true.
    pub refine: bool,
    /// An extra starting pose for the iterative methods, world frame. It is tried first, and
    /// the default starts too (see `pose::initialization`); the cheapest valid answer wins. Default `None`:
    /// no guess from the user is needed.
    pub initial_pose: Option<crate::camera_pose::Pose>,
    /// Trust-region settings of the algebraic stage: the paper's values (section 4.1), and a step
    /// tolerance of 1e-10 on top of its k.2 tests. When the refinement follows (`refine`), the stage
    /// also stops at steps shorter than [`STEP_TOLERANCE_BEFORE_REFINEMENT`]. `subproblem` is set by
    /// `method`.
    pub trust_region: TrustRegionOptions,
    /// Levenberg-Marquardt settings (method `levenberg-marquardt`).
    pub levenberg_marquardt: LevenbergMarquardtOptions,
    /// Stopping tests of plain Newton (method `newton`). Default: 50 iterations.
    pub newton: StoppingCriteria,
    /// Trust-region settings of the reprojection refinement. Default: Hebden steps, initial radius 0.1,
    /// 50 iterations, stop after a step shorter than 1e-5 (radians / object radii): two orders of
    /// magnitude below the error that 1 px of noise causes in the benchmark scenes (0.7-3.5 mrad); the
    /// short step is taken, and Gauss-Newton's next one on a small-residual problem would be shorter
    /// still by about the ratio of noise to signal.
    pub refinement: TrustRegionOptions,
    /// Robust estimation: `Some` runs LO-RANSAC over points and lines (`robust`) instead of `method`'s
    /// estimator, then the reprojection refinement (when `refine`) on the final inliers. The minimal
    /// solvers generate the hypotheses, so `method` is not used (it is echoed in the result). Default
    /// `None`: every correspondence is an inlier.
    pub ransac: Option<RansacOptions>,
    /// Standard deviation of the pixel noise on every image point and segment endpoint, for
    /// [`PoseResult::covariance`]. `None` estimates it from the residuals. Default `None`.
    pub sigma_px: Option<f64>,
    /// The answer is [`Status::Ambiguous`] when another local minimum with every object point in front
    /// has a sum of squared residuals `Σ r²` within `ambiguity_threshold · σ²` of the answer's (a
    /// likelihood-ratio test: the data cannot tell the two apart at that level). `σ` is `sigma_px`
    /// when given, else the larger of the estimate `σ̂` (see [`PoseDetails::sigma_px`]) and 1 px.
    /// Default `9.0` (three standard deviations of the difference). `0` turns the flag off for exact
    /// ties only.
    pub ambiguity_threshold: f64,
    /// The global-optimality certificate (the sublevel-set test, [`crate::CertificateKind::SublevelSet`]):
    /// `None` skips it (the result's `report.certificate` is then `None`). With `Some`, a pose that is not
    /// proved (no bound, or a gap above `max_relative_gap`) has status [`Status::GapNotClosed`] where
    /// it would have been [`Status::Success`]. `max_nodes: None` caps the rotation cells at 20 000
    /// (100 000 for lines alone or fewer than two points; with points and segments, 10 000 for the
    /// search with depth bounds, then 100 000 for the one without them where the first fails).
    /// Default `None`: it is on request.
    pub certify: Option<CertifyOptions>,
}

/// The algebraic stage's step tolerance (in the units of the dual quaternion `x = (r, s)`, conditioned
/// frame) when the refinement follows: its answer only has to start the refinement in the basin of
/// the reprojection error's minimum, and that minimum does not move when the start is polished further.
/// 1e-5 is a hundred times below the algebraic estimator's own error at 1 px of noise. Tighter
/// tolerances cost iterations without changing the refined pose: near 1e-10 the decrease of the cost
/// is below its rounding error, and the trust region rejects steps until its radius falls below the
/// tolerance. A looser `trust_region` step tolerance is kept as it is.
pub const STEP_TOLERANCE_BEFORE_REFINEMENT: f64 = 1e-5;

impl Default for PoseOptions {
    fn default() -> Self {
        let mut refinement = TrustRegionOptions::default();
        refinement.stopping.max_iterations = 50;
        refinement.stopping.step_tolerance = 1e-5;
        refinement.initial_radius = 0.1;
        let mut trust_region = TrustRegionOptions::default();
        trust_region.stopping.step_tolerance = 1e-10;
        PoseOptions {
            method: Method::TrustRegion,
            penalty: 50.0,
            normalize: true,
            refine: true,
            initial_pose: None,
            trust_region,
            levenberg_marquardt: LevenbergMarquardtOptions::default(),
            newton: StoppingCriteria {
                max_iterations: 50,
                ..StoppingCriteria::default()
            },
            refinement,
            ransac: None,
            sigma_px: None,
            ambiguity_threshold: 9.0,
            certify: None,
        }
    }
}

impl PoseOptions {
    /// Checks the numeric options.
    pub fn validate(&self) -> Result<()> {
        let bad = |name: &str, reason: &str| {
            Err(Error::InvalidOption {
                name: name.into(),
                reason: reason.into(),
            })
        };
        if !(self.penalty.is_finite() && self.penalty > 0.0) {
            return bad("penalty", "must be a positive finite number");
        }
        self.trust_region.validate("trust_region")?;
        self.refinement.validate("refinement")?;
        self.levenberg_marquardt.validate("levenberg_marquardt")?;
        self.newton.validate("newton")?;
        if let Some(sigma) = self.sigma_px {
            if !(sigma.is_finite() && sigma > 0.0) {
                return bad("sigma_px", "must be a positive finite number of pixels");
            }
        }
        if let Some(robust) = &self.ransac {
            robust.validate()?;
        }
        if !(self.ambiguity_threshold.is_finite() && self.ambiguity_threshold >= 0.0) {
            return bad("ambiguity_threshold", "must be a finite number ≥ 0");
        }
        if let Some(certify) = &self.certify {
            certify.validate("certify")?;
        }
        if let Some(crate::camera_pose::Pose {
            rotation: r,
            translation: t,
        }) = &self.initial_pose
        {
            if crate::camera_pose::Pose::rotation_defect(r).is_some() || t.iter().any(|v| !v.is_finite()) {
                return bad(
                    "initial_pose",
                    "R must be a finite rotation matrix (orthonormal, det +1) and t finite",
                );
            }
        }
        Ok(())
    }
}

#[doc(no_inline)]
pub use crate::status::Status;

/// What one stage of the pipeline did and where it ended.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct StageReport {
    /// `"trust-region"`, `"rotation"`, `"translation"`, `"linear"`, `"ransac"`, `"refinement"`, ...
    pub name: String,
    /// What its cost measures: [`CostKind::Algebraic`] (eqs. 13-15, 22 as `½ΣΦ²`, normalised units),
    /// [`CostKind::Reprojection`] (`Σ` squared pixel residuals, px²) or [`CostKind::Msac`] (the robust
    /// loop's truncated reprojection cost `Σ min(eᵢ², τᵢ²)`, px², over all correspondences; its
    /// iterations are the samples drawn, and it ends `closed_form` when stopped by confidence,
    /// `max_iterations` on the iteration cap or the time budget).
    pub cost_kind: CostKind,
    /// Rotation at the end of the stage (world → camera).
    #[cfg_attr(feature = "serde", serde(with = "crate::matrix_rows"))]
    pub rotation: Matrix3<f64>,
    /// Translation at the end of the stage (world units).
    pub translation: Vector3<f64>,
    /// Accepted iterations.
    pub iterations: usize,
    /// Cost at the start.
    pub initial_cost: f64,
    /// Cost at the end.
    pub final_cost: f64,
    /// Why the stage stopped.
    pub termination: Termination,
    /// Wall time, seconds.
    pub time_seconds: f64,
}

/// The result of [`estimate_pose`]: the pose, its [`Report`] (whether it can be used, its cost, its
/// certificate, as every result of the crate), the correspondences used and its covariance; how it was
/// found is in [`PoseResult::details`].
///
/// Every cost is `Σ r²`, the sum of the squared (whitened) pixel residuals, two per point and two per
/// line (the endpoints' distances to the projected line), px².
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct PoseResult {
    /// The returned pose, `x_cam = R X_world + t` (NaN if the solver failed). Its rotation as a dual
    /// quaternion, an axis and angle, or a rotation vector: [`crate::camera_pose::Pose::dual_quaternion`],
    /// [`crate::camera_pose::Pose::axis_angle`], [`crate::camera_pose::Pose::rotation_vector`].
    pub pose: crate::camera_pose::Pose,
    /// What the solve did: `report.status` says whether the answer can be used (a certificate
    /// requested with [`PoseOptions::certify`] that does not hold turns [`Status::Success`] into
    /// [`Status::GapNotClosed`]; every other status takes precedence over it); `report.cost` is the
    /// reprojection cost `Σ r²` (px²) of the used correspondences at the returned pose, in the observed
    /// pixels (for `linear` without refinement: at the estimated intrinsics; NaN when the pose is not
    /// finite); `report.certificate` the proved lower bound on it over every rotation and translation
    /// that keeps the object points in front of the camera (kind `sublevel_set`), `certified` when the
    /// relative gap is within [`CertifyOptions::max_relative_gap`], `None` when no bound was computed
    /// (not requested, or not available: [`PoseDetails::uncertified_reason`]).
    #[cfg_attr(feature = "serde", serde(flatten))]
    pub report: Report<Method>,
    /// Which points were used for the returned pose: the final inliers when robust, else all true.
    pub inliers_points: Vec<bool>,
    /// Which lines were used for the returned pose: the final inliers when robust, else all true.
    pub inliers_lines: Vec<bool>,
    /// Covariance of the pose, 6x6: `σ² (JᵀJ)⁻¹` at the returned pose, `J` the Jacobian of the
    /// reprojection residuals of the used correspondences (the inliers when robust; two per point, two
    /// per line) with respect to `(ω, t)` — the rotation as the tangent vector `ω` of `exp(ω) R`
    /// (radians, camera frame), then the translation (world units). The first-order (Cramér-Rao)
    /// covariance of the maximum-likelihood pose, meaningful after the refinement. `σ` is
    /// [`PoseOptions::sigma_px`] or, without it, estimated (see [`PoseDetails::sigma_px`]). `None` when
    /// `JᵀJ` is singular (the used data do not fix the pose: see
    /// `reprojection::RELATIVE_RANK_TOLERANCE`) or not finite, when σ cannot be estimated (at most 6
    /// residuals), or when the pose is not finite. For `linear`, at the estimated intrinsics taken as
    /// exact.
    #[cfg_attr(feature = "serde", serde(with = "crate::matrix_rows::option"))]
    pub covariance: Option<Matrix6<f64>>,
    /// How the pose was found: its stages, noise and ambiguity diagnostics.
    pub details: PoseDetails,
}

/// How a [`PoseResult`] was found. Costs are `Σ r²`, px².
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct PoseDetails {
    /// Every stage in order; the last one gave the returned pose.
    pub stages: Vec<StageReport>,
    /// Root-mean-square reprojection error over the used correspondences, pixels: `√(cost / m)` over
    /// the `m` residuals.
    pub rms_error_px: f64,
    /// Intrinsics estimated by the linear method (`None` for the others).
    pub estimated_camera: Option<Intrinsics>,
    /// What the robust loop did (`None` unless [`PoseOptions::ransac`]).
    pub ransac: Option<RansacReport>,
    /// Where the `σ` of [`PoseResult::covariance`] came from; `None` when there is no covariance.
    pub covariance_source: Option<CovarianceSource>,
    /// The pixel noise `σ` used: the given [`PoseOptions::sigma_px`], or the estimate
    /// `σ̂ = √(Σ r² / (m − 6))` over the `m` residuals of the used correspondences (`None` if `m ≤ 6`).
    pub sigma_px: Option<f64>,
    /// The cheapest other local minimum found with every object point in front (world frame), and its
    /// cost `Σ r²` (px²); `None` when the search found no other. Within the ambiguity margin of
    /// `report.cost`, the status is [`Status::Ambiguous`].
    pub second_best: Option<(Pose, f64)>,
    /// When the residuals at the returned pose exceed the noise (`σ` = [`PoseOptions::sigma_px`], else
    /// 1 px), the minimal solvers also look for poses with every object point *behind* the camera
    /// (`candidates::behind_camera_cost`); the cost `Σ r²` (px²) of the best one that fits better
    /// than the returned pose by more than `ambiguity_threshold σ²` (the ambiguity margin, with the
    /// stated σ) and by a factor of at least 100, if any. Then `report.status` is
    /// [`Status::BehindCamera`]: the returned pose is the best found with the points in front,
    /// but the data come from points behind the camera (or a mirrored object). `None` otherwise.
    pub behind_camera_cost: Option<f64>,
    /// The χ² test of the residuals against [`PoseOptions::sigma_px`] ([`crate::chi_square`]):
    /// `Σ r² / σ²` over the `m` residuals of the used correspondences with `m − 6` degrees of freedom.
    /// `consistent == false` says the residuals are not explained by that noise (distortion left in the
    /// pixels, a wrong camera, noise larger than stated). `None` without `sigma_px` or when `m ≤ 6`.
    pub residual_test: Option<ResidualTest>,
    /// Why the pose is not certified, in words (not requested, not available for this input, the
    /// search's node cap, the gap left); `None` when it is.
    pub uncertified_reason: Option<String>,
}

/// Origin of the pixel noise level in [`PoseResult::covariance`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, strum::IntoStaticStr, strum::EnumString, strum::VariantArray)]
#[strum(serialize_all = "snake_case")]
pub enum CovarianceSource {
    /// [`PoseOptions::sigma_px`] was given.
    Given,
    /// Estimated from the residuals: `σ̂² = Σ r² / (m − 6)`.
    Estimated,
}

impl CovarianceSource {
    /// `"given"` or `"estimated"`.
    pub fn as_str(&self) -> &'static str {
        self.into()
    }
}

/// A stage report from a solver's summary; `started` is when the stage's clock started.
pub(crate) fn stage(name: &str, cost_kind: CostKind, pose: &Pose, summary: &Summary, started: Instant) -> StageReport {
    StageReport {
        name: name.into(),
        cost_kind,
        rotation: pose.rotation,
        translation: pose.translation,
        iterations: summary.iterations,
        initial_cost: summary.initial_cost,
        final_cost: summary.final_cost,
        termination: summary.termination,
        time_seconds: started.elapsed().as_secs_f64(),
    }
}

// Written and read by name with the `serde` feature.
crate::names::serde_by_name!(Method, CovarianceSource, RansacStop);
