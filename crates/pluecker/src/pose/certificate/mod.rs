//! Certification of the pose: a proved lower bound on the reprojection cost over every rotation and
//! translation that keeps the object points and the segments' object endpoints in front of the
//! camera (steps 1-4 below need only the points in front; the search without depth bounds uses the
//! endpoints too). This module works with
//! `f = ½ Σ r²` (px²); the result reports `Σ r² = 2f`. With per-observation covariances
//! ([`super::ObservationNoise`]) the residuals are whitened (in standard deviations) and every step
//! below holds for that cost: a point's whitening `Wᵢ` enters through `Wᵢ K₂` in place of `K₂`, a
//! segment endpoint's covariance `C = L Lᵀ` through `G_e = Lᵀ G` in place of `G`.
//!
//! The *sublevel-set test*. Let `f̂` be the cost of the returned local minimum `(R̂, t̂)` and `S` the
//! set of poses, points in front, with `f ≤ f̂`. Every pose of `S` has every residual `‖rᵢ‖ ≤ ε₀ = √(2f̂)`.
//! Steps 1-3 show that `S` lies in a small ball around `(R̂, t̂)`; step 4 bounds `f` from below on
//! that ball.
//!
//! 1. **Depth bounds.** A residual `e` of point `i` is a normalised-plane error of at least `e / sᵢ`
//!    (`sᵢ` the least singular value of `Wᵢ K₂`, `K₂` the 2x2 block of `K`, `Wᵢ = I` without
//!    covariances), and the gnomonic projection only stretches distances, so on `S` every object point
//!    is within the angle `αᵢ = ε₀ / sᵢ` of its observed ray `bᵢ`. Two points `i, j` seen `γᵢⱼ` apart
//!    are then at distances `‖xᵢ‖ ≤ dᵢⱼ / sin(γᵢⱼ ∓ (αᵢ + αⱼ))` from the camera (law of sines); `Dᵢ`
//!    is the least such bound over a few partners `j`.
//! 2. **A quadratic minorant.** A point's residual is `rᵢ = Wᵢ K₂ (π(xᵢ) − ūᵢ) = Aᵢ xᵢ / x_z` exactly,
//!    with `Aᵢ = Wᵢ K₂ [1 0 −ū₁; 0 1 −ū₂]` (`ūᵢ` the normalised observed point), so where the point is
//!    in front and `x_z ≤ ‖xᵢ‖ ≤ Dᵢ` its squared residual is at least `wᵢ ‖Aᵢ xᵢ‖²`, `wᵢ = 1 / Dᵢ²`:
//!    the whitened residual itself, anisotropy and the gnomonic stretch included, only the depth
//!    replaced by its bound. It is quadratic in `t` for a fixed rotation. The segments enter box by
//!    box (step 3).
//! 3. **Rotation search** on the shared branch and bound (`global::branch_and_bound`, the
//!    search of the triangulation certificates; the oracle is `RotationSearch`). Over a box of
//!    rotation vectors `ω` (`R = exp(ω) R̂`) with half-diagonal `θ`, every rotation is within the angle
//!    `θ` of the centre's `R_c`, so each residual `Aᵢ xᵢ` of the minorant moves by at most
//!    `‖Aᵢ‖ θ ‖Xᵢ‖`. With `Q(t)` the minorant at `R_c` and `η² = Σ wᵢ ‖Aᵢ‖² ‖Xᵢ‖²`, a pose of `S` in the box has
//!    `√Q(t) ≤ √(2f) + θ η` (Minkowski), so `f ≥ ½ (√q_min − θ η)₊²` (`q_min = min_t Q`) on the box's
//!    poses of `S`, and every other pose has `f > f̂`. Where that falls short of `f̂`, the minorant
//!    linearised in the rotation gives a second bound: a rotation of the box is `exp(φ) R_c` with
//!    `‖φ‖ ≤ θ`, its first-order part `[φ]ₓ R_c` enters the minorant exactly (a convex quadratic in
//!    `φ` once `t` is minimised out, bounded below over the ball `‖φ‖ ≤ θ` by its Lagrangian dual),
//!    and only the rest costs `(e^θ − 1 − θ) η` (`ScaledMinorant::linear_bound`). The larger of the two is
//!    the box's bound: small boxes pay `O(θ²)` instead of `O(θ)`. Where both fall short, the
//!    segments' residuals join the minorant at `R_c` (`Problem::lines_bound`): an endpoint's residual
//!    `n / w` has the numerator `n = ēᵀ R_c (a × d) + tᵀ (R_c d × ē)`, linear in `t`, and `w` is at most
//!    `‖G_e‖ ‖d‖` times the line's largest distance from the camera over the box, so `n² / W²` adds to
//!    `Q`; over the box `n` moves by at most `θ (‖ē‖ ‖a × d‖ + ‖d‖ ‖ē × t‖)`, with `t` within the
//!    points' ellipsoid below. Where that Minkowski bound falls short too, the quadratic with the
//!    segments is linearised in the rotation as the points' alone are: with `R = exp(φ) R_c` and
//!    `t = t* + Δ` (`‖Δ‖` within the points' ellipsoid's reach), an endpoint's numerator is within
//!    `θ ‖d‖ ‖ē × Δ‖ + (e^θ − 1 − θ)(‖ē‖ ‖a × d‖ + ‖d‖ ‖ē × t*‖)` of its part linear in `(φ, Δ)`, a
//!    point's within `(e^θ − 1 − θ) ‖Aᵢ‖ ‖Xᵢ‖`, and the weighted sum of squares of the linear parts,
//!    minimised over `Δ` and bounded below over `‖φ‖ ≤ θ` by its Lagrangian dual, less those rests
//!    (Minkowski), bounds `√(2f)` (`Problem::linear_lines_bound`): the segments' large first-order
//!    drifts, which partly cancel, enter exactly. The quadratic with the segments' terms gives a
//!    second ellipsoid of the box's translations, `Q_total(t) ≤ (√(2f̂) + θ η_total)²`; the one that
//!    reaches less far is kept (`LinesBound::ellipsoid`). A box whose bound
//!    reaches `f̂` holds no pose of `S` and is pruned; so is a box where some point is behind the camera
//!    for every `t` of the ellipsoid `Q(t) ≤ β² = (√(2f̂) + θ η)²`, which holds the translations of its
//!    poses of `S`. A box inside the ball `‖Δ‖_W ≤ ρ` of the local metric `‖Δ‖²_W = Δᵀ JᵀJ Δ`
//!    (`Δ = (ω, t − t̂)`, `J` the Jacobian at the pose), measured by the triangle inequality over its
//!    centre, its rotation spread and the translation ellipsoid, is bounded by step 4 as well. Boxes are
//!    split into their eight octants, least bound first, until every open box's bound is within
//!    the gap of `f̂`. Each box hands its octants tighter depth bounds: the largest distance each point
//!    reaches over the box's poses of `S` (the octants' poses of `S` are among them). If they raise
//!    every weight at least by `κ`, then `κ Q` is a minorant for them (`ScaledMinorant`); the form is rebuilt
//!    only when the weights grow unevenly, and handed down only where it bounds at least as well as
//!    `κ Q` (a point that came much closer than the others raises `η` more than `√q_min`).
//! 4. **Local bound along whitened rays.** Write `Δ = s T v` with `‖v‖ = 1` and `Tᵀ JᵀJ T = I`, so that
//!    `s = ‖Δ‖_W` and the linearised residual moves by one pixel per unit of `s` in every direction.
//!    Along a ray the rotation is `exp(s a_ω) R̂` (`a = T v`) and a camera-frame point moves as
//!    `p' = a_ω × R_s y + a_τ`, `p'' = a_ω × (a_ω × R_s y)`. Two identities keep the second derivative
//!    small in whitened steps, where the naive bound is dominated by the well-determined directions:
//!    for a point, `D²π[p', p'] = −2 (p'_z / p_z) Dπ[p']`, so `r'' = W K₂ Dπ[p''] − 2 (p'_z / p_z) r'`;
//!    for a line endpoint, `r = n / w` (`n = ēᵀ m`, `w = ‖G_e m_xy‖`, `m = A × B`) and
//!    `r'' = (n'' − r w'') / w − 2 (w' / w) r'`, with `n''(0)` an exact quadratic form in `v` and
//!    `n'''` bounded also about either end `X` of the segment, `n = Dᵀ (ē × X)` (`D = B − A`), where a
//!    step along the line of sight (the depth, poorly determined on narrow fields of view) does not
//!    move `ē × X` (`sight_parts`). Bounding
//!    each part over the ball gives `‖r''‖ ≤ K` (`RayCurvature`), hence
//!    `‖r(s)‖ ≥ ‖r̂ + s J T v‖ − ½ K s²` and `‖r̂ + s J T v‖² ≥ 2f̂ − 2‖Tᵀg‖ s + λ_min s²`. The least
//!    value of the square of the right-hand side over `s ≤ ρ`, halved, is the lower bound.
//!
//! The least bound over the search's leaves (step 4's over the ball of the largest radius a box inside it
//! reached, or a box's Minkowski bound) is the raw bound. So `lower_bound ≤ f` for every pose that keeps
//! the points in front; the answer is certified when
//! `(f̂ − lower_bound) / max(f̂, 1e-12 px²) ≤ max_relative_gap` (exact data, at the rounding level,
//! counts as exact).
//!
//! **Through a lens** (`lens`) the steps above run on a whitened pinhole problem, the linearisation
//! of each observation at the answer, whose sublevel set at a slightly higher level holds every pose
//! as good as the answer; step 4 then bounds the exact cost through the lens, its difference from the
//! pinhole problem bounded by interval enclosures of the distortion's Jacobian over nested balls.
//!
//! **A rig's cameras** ([`certify_rig`]): the pose is the rig's, `x_rig = R X + t`, and camera `k`
//! sees `x_k = R_k x_rig + c_k = R_k (x_rig + e_k)` (`e_k = R_kᵀ c_k`). Every step above holds with each
//! point and segment in its own camera ([`problem`]'s module docs): its residual map is `Aᵢ R_k` and its
//! distance `‖R Xᵢ + t + e_k‖`, so step 2's minorant is `Σ wᵢ ‖Aᵢ R_k (R Xᵢ + t + e_k)‖²`, a quadratic
//! in `(vec R, 1, t)` whose rotation drift is bounded by the same `η`; step 1 pairs points of one camera
//! or of two (the distance between their centres added to the points'); a segment's numerator is the
//! single camera's at the translation `t + e_k` with its endpoints' rays turned by `R_kᵀ`; and step 4
//! runs on each camera's residuals at its own pose, whose whitened rays are the rig's turned by
//! `diag(R_k, R_k)`. Pinhole cameras with depth bounds only (no search without depth bounds, no lens).
//!
//! **Without depth bounds** (lines alone, or fewer than two points seen more than `αᵢ + αⱼ` apart;
//! `SearchStart::ObjectDistance`) steps 1-3 change: the camera's distance from a pivot of the object is bounded from
//! the directions of the observations (`pose::object_distance`), and each box of rotations is bounded
//! from the residuals at its centre rotation with the translations in an ellipsoid handed down box by box
//! (`Problem::ball_bound`); boxes with a point or segment endpoint behind the camera are pruned. With
//! points and segments, a search with depth bounds that does not close its gap is followed by this one,
//! and the better proved bound is kept. The test fails honestly (`certified = false`, with the reason)
//! when the residuals are too large for the curvature (`K` too large on every ball tried), when the
//! search hits `max_nodes` (another minimum nearly as good, or weak data), or when the observations bound
//! neither the depths nor the object's distance (image lines that all meet in one point).
//!
//! **Where each step lives.** [`problem`]: the data and step 1 (depth bounds, or the object's
//! distance); [`minorant`]: step 2 and its bounds over a box; [`box_bound`]: step 3's bounds of a box
//! with the segments and without depth bounds; [`search`]: step 3's rotation search; [`local_bound`]:
//! step 4; [`lens`]: the certificate through a lens; this file: the entry point [`certify`], which
//! hands the pipelines the crate's [`Certificate`] in `Σ r²` (every cost and bound inside is
//! `f = ½ Σ r²`); [`testing`]: the steps one by one for the tests of the proof
//! (`pluecker::testing::pose_certificate`).

mod box_bound;
mod lens;
mod local_bound;
mod minorant;
mod problem;
mod search;
#[doc(hidden)]
pub mod testing;

use super::correspondences::Correspondences;
use super::reprojection::Pose;
use super::Status;
use crate::camera::Camera;
use crate::camera::Intrinsics;
use crate::certificate::Primitive;
use crate::certificate::{Certificate, CertificateKind, CertifyOptions};
use crate::global::CERTIFICATE_COST_FLOOR;
use lens::{Slack, Surrogate};
use local_bound::{LocalModel, RaySlack};
use problem::{CameraPart, Problem, SearchStart};
use search::{localise, BallBound, InsideBall, RotationSearch};

/// The default cap on the boxes the rotation search bounds (its branch-and-bound nodes;
/// [`crate::certificate::CertifyOptions::max_nodes`] `None`).
pub(crate) const MAX_CELLS: usize = 20_000;
/// The default cap where the search starts from the object's distance (lines alone,
/// or too few points): its boxes are pruned later (20 000-90 000 boxes on the 10-segment benchmark
/// scenes, 2-8 µs each).
pub(crate) const MAX_CELLS_FROM_DISTANCE: usize = 100_000;
/// The default cap of the search with depth bounds on a scene with segments, which the search
/// without them follows where it fails ([`certify`]). A failing first search only delays the
/// second, whose boxes cost more: planar scenes with 100 correspondences need up to ~10 000 boxes of
/// the first (Rust benchmark, f = 800 px, 50 points + 50 segments: 6 ms at 10 000 or 20 000, 23 ms at
/// 4 000), while scenes whose first search fails lose ~10 % (f = 15000 px, 5 + 5: 12 ms at 4 000,
/// 16 ms at 10 000, 28 ms at 20 000).
pub(crate) const MAX_CELLS_BEFORE_FALLBACK: usize = 10_000;

/// Why a pose is not certified when [`crate::pose::PoseOptions::certify`] is `None`.
const NOT_REQUESTED: &str = "not requested (PoseOptions.certify is None)";

/// The certificate stage of both pipelines (with and without RANSAC): not requested without
/// `certify`, not attempted for a pose whose `status` is not a success, else `run` with the options
/// (it calls [`certify`] on the data the pose was fitted to).
pub(crate) fn stage(
    certify: Option<&CertifyOptions>,
    status: Status,
    run: impl FnOnce(&CertifyOptions) -> Verdict,
) -> Verdict {
    match certify {
        None => Verdict::none(NOT_REQUESTED),
        Some(_) if status != Status::Success => Verdict::none(format!("not attempted: status {}", status.as_str())),
        Some(options) => run(options),
    }
}

/// The certificate stage's outcome in the crate's convention (`Σ r²`, [`crate::certificate`]): what
/// the pose's result reports.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Verdict {
    /// The shared certificate, in `Σ r²`; `None` when no bound was computed.
    pub(crate) certificate: Option<Certificate>,
    /// Why the pose is not certified (`None` when it is).
    pub(crate) uncertified_reason: Option<String>,
}

impl Verdict {
    /// No bound, for `reason`.
    pub(crate) fn none(reason: impl Into<String>) -> Self {
        Verdict {
            certificate: None,
            uncertified_reason: Some(reason.into()),
        }
    }

    /// Whether a certificate closed its gap.
    pub(crate) fn certified(&self) -> bool {
        self.certificate.is_some_and(|c| c.certified)
    }
}

/// What the sublevel-set test proved, in this module's units (`f = ½ Σ r²`, px²). `certify` turns
/// it into the shared certificate in `Σ r²` (`SublevelSetOutcome::into_verdict`, the one
/// conversion); the test hooks ([`testing::certify`]) read it as it is.
#[derive(Debug, Clone, PartialEq)]
pub struct SublevelSetOutcome {
    /// Whether the gap closed.
    pub certified: bool,
    /// The proved bound, clamped to the cost (NaN when there is none).
    pub lower_bound: f64,
    /// The bound as the search proved it (the least over its leaves, step 4's for the ball), before any
    /// clamp to the cost (NaN when there is none). A sound bound is at most the cost of every pose that
    /// keeps the points in front; `lower_bound` is `min(raw_lower_bound, cost)`.
    pub raw_lower_bound: f64,
    /// `(cost − lower_bound) / max(cost, 1e-12)` (NaN when there is no bound).
    pub relative_gap: f64,
    /// Boxes of rotations bounded by the search (0 when it did not run to its end).
    pub nodes: usize,
    /// Why the pose is not certified (`None` when it is).
    pub reason: Option<String>,
}

impl SublevelSetOutcome {
    /// No bound, for `reason`.
    pub(crate) fn none(reason: impl Into<String>) -> Self {
        SublevelSetOutcome {
            certified: false,
            lower_bound: f64::NAN,
            raw_lower_bound: f64::NAN,
            relative_gap: f64::NAN,
            nodes: 0,
            reason: Some(reason.into()),
        }
    }

    /// The outcome in the crate's convention: the shared certificate of `kind` with the bounds in
    /// `Σ r² = 2f` (`None` without a bound) and the relative gap as proved (a ratio, the same in either
    /// unit: the test's floor on `f` is [`HALF_COST_FLOOR`]).
    fn into_verdict(self, kind: CertificateKind) -> Verdict {
        let sum_of_squares = |half: f64| 2.0 * half;
        Verdict {
            certificate: (!self.raw_lower_bound.is_nan()).then(|| {
                Certificate::new(
                    kind,
                    Primitive::Pose,
                    sum_of_squares(self.lower_bound),
                    sum_of_squares(self.raw_lower_bound),
                    self.relative_gap,
                    self.certified,
                )
                .with_effort(self.nodes, 0)
            }),
            uncertified_reason: self.reason,
        }
    }
}

/// The cost floor of the relative gap in the test's unit `f = ½ Σ r²`: the crate's gap is
/// `(cost − lower_bound) / max(cost, CERTIFICATE_COST_FLOOR)` in `Σ r² = 2f`, so the floor on `f` is
/// half of it, and the gap proved here is the one a user recomputes from the reported bounds.
pub(super) const HALF_COST_FLOOR: f64 = 0.5 * CERTIFICATE_COST_FLOOR;

/// The relative gap of costs in `½ Σ r²`: the crate's [`crate::global::relative_gap`] of `2f` and
/// `2 lower` (doubling is exact), i.e. `(f − lower) / max(f, HALF_COST_FLOOR)`.
fn half_cost_gap(f: f64, lower: f64) -> f64 {
    crate::global::relative_gap(2.0 * f, 2.0 * lower)
}

/// Radii of the whitened ball tried for the localisation, in units of `√(2f̂) + 0.1` px: the largest
/// whose local bound already closes the gap is used (a larger ball stops the search sooner).
const BALL_FACTORS: [f64; 8] = [64.0, 16.0, 6.0, 3.0, 2.0, 1.5, 1.0, 0.7];

/// Bisections (geometric) between the first of [`BALL_FACTORS`] whose local bound closes the gap and
/// the one before it.
const BALL_BISECTIONS: usize = 3;

/// Certifies `pose` (conditioned frame of `corr`), a local minimum of cost `cost` = `½ Σ r²` (see the
/// module documentation), with the node cap `options.max_nodes` or [`MAX_CELLS`]
/// ([`MAX_CELLS_BEFORE_FALLBACK`] with segments, [`MAX_CELLS_FROM_DISTANCE`] without depth bounds;
/// each search has its own cap). Through `lens` (`Some`), `corr` holds the observed (distorted) pixels
/// and the certificate is that of `lens` (kind `lens_sublevel_set`). Never fails: a certificate that
/// cannot be computed is a verdict without one, with the reason. The cost is `½ Σ r²`, as the pose's
/// solvers measure it; the verdict's certificate is in `Σ r²`.
pub(crate) fn certify(
    camera: &Intrinsics,
    lens: Option<&Camera>,
    corr: &Correspondences,
    pose: &Pose,
    cost: f64,
    options: &CertifyOptions,
) -> Verdict {
    let kind = if lens.is_some_and(|l| !l.is_pinhole()) {
        CertificateKind::LensSublevelSet
    } else {
        CertificateKind::SublevelSet
    };
    sublevel_set_test(camera, lens, corr, pose, cost, options).into_verdict(kind)
}

/// One camera of a rig as [`certify_rig`] reads it: its index in the rig, the camera, its
/// `sensor_from_rig` (`x_camera = R_k x_rig + c_k`) and the observations it made.
pub(crate) struct RigCamera<'a> {
    pub(crate) index: usize,
    pub(crate) camera: &'a Camera,
    pub(crate) sensor_from_rig: Pose,
    pub(crate) corr: &'a Correspondences,
}

/// Certifies `pose`, the `rig_from_world` of a rig whose `cameras` made the observations (the
/// conditioned frame of [`crate::pose::generalized`]), a local minimum of cost `cost` = `½ Σ r²` over
/// every camera's residuals, with the node cap `options.max_nodes` or [`MAX_CELLS`]: the test of the
/// module docs with every point in its own camera ([`problem`]'s module docs), over every pose that
/// keeps the points in front of their cameras. Pinhole cameras only, and step 1's depth bounds are
/// needed (the search without them is written around one camera's centre): else a verdict without a
/// certificate, with the reason. The verdict's certificate is in `Σ r²`.
pub(crate) fn certify_rig(cameras: &[RigCamera], pose: &Pose, cost: f64, options: &CertifyOptions) -> Verdict {
    rig_sublevel_set_test(cameras, pose, cost, options).into_verdict(CertificateKind::SublevelSet)
}

/// [`certify_rig`] in this module's units: every cost and bound is `½ Σ r²`.
fn rig_sublevel_set_test(
    cameras: &[RigCamera],
    pose: &Pose,
    cost: f64,
    options: &CertifyOptions,
) -> SublevelSetOutcome {
    if !(cost.is_finite() && cost >= 0.0) {
        return SublevelSetOutcome::none("not attempted: the cost is not finite");
    }
    if let Some(lens) = cameras.iter().find(|c| !c.camera.is_pinhole()) {
        return SublevelSetOutcome::none(format!(
            "not available: the certificate over several cameras is proved for pinhole cameras; camera {} \
             is {}",
            lens.index,
            lens.camera.model().as_str()
        ));
    }
    // Every camera's points one camera after the other: the order of the problem's points.
    let mut all = Correspondences::default();
    for c in cameras {
        all.points2d.extend(&c.corr.points2d);
        all.points3d.extend(&c.corr.points3d);
        all.lines2d.extend(&c.corr.lines2d);
        all.lines3d.extend(&c.corr.lines3d);
    }
    let parts = cameras
        .iter()
        .map(|c| CameraPart::new(&c.camera.intrinsics(), c.corr, Some(c.sensor_from_rig)))
        .collect::<std::result::Result<Vec<_>, String>>();
    let problem = match parts.and_then(|parts| Problem::of_rig(parts, &all, cost)) {
        Ok(p) => p,
        Err(why) => return SublevelSetOutcome::none(why),
    };
    certify_problem(&problem, &problem, pose, cost, options, None)
}

/// [`certify`] in this module's units: every cost and bound is `½ Σ r²`.
fn sublevel_set_test(
    camera: &Intrinsics,
    lens: Option<&Camera>,
    corr: &Correspondences,
    pose: &Pose,
    cost: f64,
    options: &CertifyOptions,
) -> SublevelSetOutcome {
    if !(cost.is_finite() && cost >= 0.0) {
        return SublevelSetOutcome::none("not attempted: the cost is not finite");
    }
    match lens.filter(|l| !l.is_pinhole()) {
        Some(lens) => lens::certify(lens, corr, pose, cost, options),
        None => certify_pinhole(camera, corr, pose, cost, options, None),
    }
}

/// [`certify`] of a pinhole problem, or of a lens's surrogate (`lens`; `camera` and `corr` are then
/// the surrogate's, and `cost` the cost through the lens).
fn certify_pinhole(
    camera: &Intrinsics,
    corr: &Correspondences,
    pose: &Pose,
    cost: f64,
    options: &CertifyOptions,
    lens: Option<&Surrogate>,
) -> SublevelSetOutcome {
    // The level of the sublevel set that the search localises (the surrogate's, through a lens).
    let level = lens.map_or(cost, |l| l.slack.to_surrogate(cost));
    // Through a lens the search runs on step 1's weighted observations, step 4 on the surrogate's.
    let search_corr = lens.map_or(corr, |l| l.search_corr());
    let whole = match lens.map(|_| Problem::without_depths(camera, corr, level)).transpose() {
        Ok(whole) => whole,
        Err(why) => return SublevelSetOutcome::none(why),
    };
    let problem = match Problem::new(camera, search_corr, level) {
        Ok(p) => p,
        Err(why) => return SublevelSetOutcome::none(why),
    };
    let local = whole.as_ref().unwrap_or(&problem);
    let first = certify_problem(&problem, local, pose, cost, options, lens);
    // With segments, a search with depth bounds that did not close its gap is followed by the one
    // without them (bounded at each box's rotation, segments and points alike): where the points are
    // few it certifies scenes the first cannot. Both bounds are proved; the better is kept.
    if first.certified || problem.root().is_none() || corr.n_lines() == 0 {
        return first;
    }
    let second = match Problem::without_depths(camera, search_corr, level) {
        Ok(p) => certify_problem(&p, whole.as_ref().unwrap_or(&p), pose, cost, options, lens),
        Err(why) => SublevelSetOutcome::none(why),
    };
    let nodes = first.nodes + second.nodes;
    if second.certified || second.raw_lower_bound > first.raw_lower_bound {
        return SublevelSetOutcome { nodes, ..second };
    }
    SublevelSetOutcome {
        nodes,
        reason: Some(format!(
            "{}; without depth bounds: {}",
            first.reason.unwrap_or_default(),
            second.reason.unwrap_or_default()
        )),
        ..first
    }
}

/// [`certify`] on prepared data (`cost` the cost at `pose`, through the lens of `lens` when given):
/// the search over `problem`, step 4 over `local` (the same problem; through a lens the surrogate's,
/// where the search's observations are step 1's weighted ones).
fn certify_problem(
    problem: &Problem,
    local: &Problem,
    pose: &Pose,
    cost: f64,
    options: &CertifyOptions,
    lens: Option<&Surrogate>,
) -> SublevelSetOutcome {
    let (whitening, model) = match LocalModel::at(local, pose, lens) {
        Ok(m) => m,
        Err(why) => return SublevelSetOutcome::none(why),
    };
    let slack = lens.map_or(Slack::NONE, |l| l.slack);
    let gap_of = |lower: f64| half_cost_gap(cost, lower);
    let unit = (2.0 * cost).sqrt() + 0.1;
    let closing = |radius: f64| {
        model
            .raw_bound(
                radius,
                Some(cost - options.max_relative_gap * cost.max(HALF_COST_FLOOR)),
            )
            .filter(|&raw| gap_of(raw.min(cost)) <= options.max_relative_gap)
            .map(|raw| (radius, raw))
    };
    let found = BALL_FACTORS
        .iter()
        .enumerate()
        .find_map(|(k, f)| closing(f * unit).map(|at| (k, at)));
    // Between the first factor that closes and the one before it, which does not, a larger ball that
    // closes is sought by bisection (every ball whose bound closes will do; a larger one stops the
    // search sooner). Through a lens, where each bound takes the distortion's variation over up to
    // 25 nested balls, the bisection cost more than the nodes it saved (the strong OPENCV lens at
    // f = 800-4000 px, 100 points: 2.0 -> 3.9 ms median for the same nodes), so it is left out there.
    let bisections = if lens.is_some() { 0 } else { BALL_BISECTIONS };
    let found = found.map(|(k, mut best)| {
        if k > 0 {
            let mut above = BALL_FACTORS[k - 1] * unit;
            for _ in 0..bisections {
                let radius = (best.0 * above).sqrt();
                match closing(radius) {
                    Some(at) => best = at,
                    None => above = radius,
                }
            }
        }
        best
    });
    let Some((target, at_target)) = found else {
        return SublevelSetOutcome::none(match lens {
            None => format!(
                "not proved: the residuals ({:.3e} px) are too large for the curvature of the cost",
                (2.0 * cost).sqrt()
            ),
            Some(_) => format!(
                "not proved: the residuals ({:.3e} px) are too large for the curvature of the cost and \
                 the variation of the distortion",
                (2.0 * cost).sqrt()
            ),
        });
    };
    // The search's level and gap are the surrogate's: a box closes when its bound, as a bound of the
    // cost, is within the gap of the cost.
    let level = slack.to_surrogate(cost);
    let closed = slack.to_surrogate(cost * (1.0 - options.max_relative_gap));
    let search_gap = if level > 0.0 {
        (1.0 - closed / level).clamp(0.0, options.max_relative_gap)
    } else {
        options.max_relative_gap
    };
    let mut search = RotationSearch {
        problem,
        whitening: &whitening,
        pose,
        f_hat: level,
        target,
        max_relative_gap: search_gap,
        slack,
        inside_ball: InsideBall::Bound(BallBound {
            model: &model,
            radius: 0.0,
            bound: at_target,
            at_target,
        }),
        linearise_lines: lens.is_none(),
        radius: 0.0,
    };
    let cap = match problem.start {
        // A rig's search is not followed by one without depth bounds.
        SearchStart::DepthBounds(_) if !problem.lines.is_empty() && !problem.is_rig() => MAX_CELLS_BEFORE_FALLBACK,
        SearchStart::DepthBounds(_) => MAX_CELLS,
        SearchStart::ObjectDistance { .. } => MAX_CELLS_FROM_DISTANCE,
    };
    let localised = match localise(&mut search, options.max_nodes_or(cap)) {
        Ok(l) => l,
        Err((why, nodes)) => {
            return SublevelSetOutcome {
                nodes,
                ..SublevelSetOutcome::none(why)
            }
        }
    };
    let raw_lower_bound = slack.to_cost(localised.raw_lower_bound);
    let lower_bound = raw_lower_bound.min(cost);
    let gap = gap_of(lower_bound);
    let certified = gap <= options.max_relative_gap;
    SublevelSetOutcome {
        certified,
        lower_bound,
        raw_lower_bound,
        relative_gap: gap,
        nodes: localised.nodes,
        reason: (!certified).then(|| {
            format!(
                "not proved: the local bound leaves a gap of {gap:.3e} (whitened radius {:.3e}, {} rotation cells)",
                localised.radius, localised.nodes
            )
        }),
    }
}

#[cfg(test)]
mod tests;
