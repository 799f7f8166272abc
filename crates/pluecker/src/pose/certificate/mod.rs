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
//!    and only the rest costs `(e^θ − 1 − θ) η` (`Scaled::linear_bound`). The larger of the two is
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
//!    every weight at least by `κ`, then `κ Q` is a minorant for them (`Scaled`); the form is rebuilt
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
//! **Without depth bounds** (lines alone, or fewer than two points seen more than `αᵢ + αⱼ` apart;
//! `Start::Ball`) steps 1-3 change: the camera's distance from a pivot of the object is bounded from
//! the directions of the observations (`pose::object_distance`), and each box of rotations is bounded
//! from the residuals at its centre rotation with the translations in an ellipsoid handed down box by box
//! (`Problem::ball_bound`); boxes with a point or segment endpoint behind the camera are pruned. With
//! points and segments, a search with depth bounds that does not close its gap is followed by this one,
//! and the better proved bound is kept. The test fails honestly (`certified = false`, with the reason)
//! when the residuals are too large for the curvature (`K` too large on every ball tried), when the
//! search hits `max_nodes` (another minimum nearly as good, or weak data), or when the observations bound
//! neither the depths nor the object's distance (image lines that all meet in one point).

mod lens;

use super::correspondences::Correspondences;
use super::object_distance::{distance_bound, Sight};
use super::reprojection::{Pose, ReprojectionCost};
use super::Status;
use crate::camera::linearisation::spectral_norm;
use crate::camera::Camera;
use crate::camera::LensCamera;
use crate::certificate::CertifyOptions;
use crate::geometry::quaternion::{exp_so3, skew};
use crate::global::branch_and_bound::{
    branch_and_bound, Bound, BoundingOracle, BranchAndBoundOptions, Corner, Region, SubRegions,
};
use crate::global::{relative_gap, CERTIFICATE_COST_FLOOR};
use crate::interrupt::{stop_reason, StopReason};
use crate::optim::Objective;
use lens::{Slack, Surrogate};
use nalgebra::{Matrix2, Matrix3, SMatrix, SVector, Vector3};
use std::cell::OnceCell;
use std::rc::Rc;

/// The default cap on the boxes the rotation search bounds (its branch-and-bound nodes;
/// [`crate::certificate::CertifyOptions::max_nodes`] `None`).
pub const MAX_CELLS: usize = 20_000;
/// The default cap where the search starts from the object's distance (lines alone,
/// or too few points): its boxes are pruned later (20 000-90 000 boxes on the 10-segment benchmark
/// scenes, 2-8 µs each).
pub const MAX_CELLS_FROM_DISTANCE: usize = 100_000;
/// The default cap of the search with depth bounds on a scene with segments, which the search
/// without them follows where it fails ([`certify`]). A failing first search only delays the
/// second, whose boxes cost more: planar scenes with 100 correspondences need up to ~10 000 boxes of
/// the first (Rust benchmark, f = 800 px, 50 points + 50 segments: 6 ms at 10 000 or 20 000, 23 ms at
/// 4 000), while scenes whose first search fails lose ~10 % (f = 15000 px, 5 + 5: 12 ms at 4 000,
/// 16 ms at 10 000, 28 ms at 20 000).
pub const MAX_CELLS_BEFORE_FALLBACK: usize = 10_000;

/// Why a pose is not certified when [`crate::pose::PoseOptions::certify`] is `None`.
pub(crate) const NOT_REQUESTED: &str = "not requested (PoseOptions.certify is None)";

/// Why noise that carries a lens's Jacobians (the first-order noise of undistorted pixels) is not
/// certified: the cost is in the distorted pixels, which [`certify`] is given with the lens.
const FIRST_ORDER_NOISE: &str = "not attempted: the noise is the first-order noise of undistorted pixels; \
    the certificate bounds the cost in the observed pixels, through the lens";

/// The certificate stage of both pipelines (with and without RANSAC): not requested without
/// `certify`, not attempted for a pose whose `status` is not a success, else `run` with the options
/// (it calls [`certify`] on the data the pose was fitted to).
pub(crate) fn stage(
    certify: Option<&CertifyOptions>,
    status: Status,
    run: impl FnOnce(&CertifyOptions) -> Certification,
) -> Certification {
    match certify {
        None => Certification::none(NOT_REQUESTED),
        Some(_) if status != Status::Success => {
            Certification::none(format!("not attempted: status {}", status.as_str()))
        }
        Some(options) => run(options),
    }
}

/// The certificate stage's outcome, in the units of this module (`f = ½ Σ r²`, px²); the result
/// assembly ([`crate::pose::PoseResult`]) turns it into the shared [`crate::certificate::Certificate`]
/// in `Σ r²`.
#[derive(Debug, Clone, PartialEq)]
pub struct Certification {
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

impl Certification {
    /// No bound, for `reason`.
    pub fn none(reason: impl Into<String>) -> Self {
        Certification {
            certified: false,
            lower_bound: f64::NAN,
            raw_lower_bound: f64::NAN,
            relative_gap: f64::NAN,
            nodes: 0,
            reason: Some(reason.into()),
        }
    }
}

/// Partners per point for its depth bound (the widest-apart in the image of a small spread set).
const DEPTH_PARTNERS: usize = 16;
/// The rotation search rebuilds a box's minorant for its octants when the tightened depth bounds
/// raise the weights `wᵢ ∝ 1/Dᵢ²` on average by this factor more than the least of them, which a
/// scale of the minorant takes up ([`Scaled`]): a rebuild costs about as much as ten boxes' bounds,
/// and without rebuilds the f = 15000 px scenes lose certificates.
const REBUILD_GAIN: f64 = 1.2;
/// At most this many segments, the longest in the image, enter the box bound
/// ([`Problem::lines_bound`]): each costs per box about as much as the rest of the bound, a few
/// already constrain the rotation where the points are few, and fewer terms only weaken the minorant.
/// (With all 50 segments of the 50-point + 50-segment benchmark rows, the searches that fail took
/// 2.5-3.3 times as long for one or two more certificates in 50.)
const BOX_BOUND_SEGMENTS: usize = 8;
/// Boxes of rotations within this angle of the answer's are bounded with every segment where there
/// are no depth bounds ([`Start::Ball`], [`Problem::segments_in`]): there the translation ellipsoid
/// decides whether a box lies inside the whitened ball of step 4. With depth bounds every box keeps
/// [`BOX_BOUND_SEGMENTS`]: every segment near the answer there saved nodes at f = 250-800 px but cost
/// 3.5 times as much per node at f = 15000 px (50 points + 50 segments, 20 scenes of
/// `bench/profile_pose.py`: median 10 → 17-22 ms for the same nodes), and the linearised bound
/// ([`Problem::linear_lines_bound`]) with the longest segments alone already did better than before
/// on every row.
const NEAR_ANSWER: f64 = 0.5;
/// At most this many segments, the longest in the image, enter the bound of a box where there are no
/// depth bounds ([`Start::Ball`]): there they are the bound, not an addition to it.
const BALL_SEGMENTS: usize = 32;

/// The indices of the (at most) `count` longest observed segments, longest first.
fn longest_segments(corr: &Correspondences, count: usize) -> Vec<usize> {
    let mut order: Vec<usize> = (0..corr.n_lines()).collect();
    let length = |i: usize| (corr.lines2d[i][1] - corr.lines2d[i][0]).norm();
    order.sort_by(|&i, &j| length(j).total_cmp(&length(i)));
    order.truncate(count);
    order
}

/// Intervals of the one-dimensional minimisation of the local bound.
const LOCAL_INTERVALS: usize = 256;

/// The data of the test, prepared once (conditioned frame, centred on the object).
struct Problem<'c> {
    corr: &'c Correspondences,
    /// Per point, `W K₂`: the whitening `W` of its noise (the identity without covariances) times
    /// the 2x2 block `K₂` of `K`, which maps a normalised-plane error to the whitened residual.
    point_maps: Vec<Matrix2<f64>>,
    /// Per point, its part `Aᵢᵀ Aᵢ` of step 2's minorant ([`PointForm`]).
    forms: Vec<PointForm>,
    /// What the rotation search starts from: step 1's depth bounds, or the object's distance.
    start: Start,
    /// `K⁻¹` (normalised endpoints `ē = K⁻¹ ẽ`).
    k_inv: Matrix3<f64>,
    /// Per segment endpoint, `G_e = Lᵀ G` and its norm: `G` is the upper-left 2x2 block of `K⁻ᵀ` (a
    /// line moment `m` projects to a pixel line whose normal is `G m_xy`) and `L Lᵀ` the endpoint's
    /// covariance (the identity without covariances), so that the endpoint's residual is
    /// `ēᵀ m / ‖G_e m_xy‖`.
    endpoint_maps: Vec<[EndpointMap; 2]>,
    /// The parts of the box bound with segments ([`LineForm`]), longest segment first: the first
    /// `box_segments` enter every box's bound ([`BOX_BOUND_SEGMENTS`], or [`BALL_SEGMENTS`] without
    /// depth bounds), all of them the bounds of boxes near the answer without depth bounds.
    lines: Vec<LineForm>,
    box_segments: usize,
    /// Unit bearings of the points.
    bearings: Vec<Vector3<f64>>,
    /// `‖Xᵢ‖` (object coordinates).
    norms: Vec<f64>,
    /// A cone of the bearings: their normalised mean `a`, `δ = max ‖bᵢ − a‖` and `max ‖Xᵢ‖`. Every
    /// `bᵢ · (R Xᵢ + t) ≥ a · t − δ ‖t‖ − max ‖Xᵢ‖`: where that is positive no point is behind.
    bearing_cone: (Vector3<f64>, f64, f64),
}

/// What the rotation search starts from.
enum Start {
    /// Step 1's depth bounds, and the minorant for them (the search tightens them box by box:
    /// [`RotationSearch`]).
    Points(Rc<Minorant>),
    /// Without depth bounds (lines alone, or fewer than two points seen far enough apart): the
    /// pivot `c` (an object point) is at most `distance` from the camera on `S`
    /// ([`super::object_distance`]), so the translation of a pose of `S` whose rotation is within
    /// `θ` of `R_c` lies in the ball of centre `−R_c c` and radius `distance + θ ‖c‖`; every box is
    /// bounded from the residuals at its centre rotation ([`Problem::ball_quadratic`]) and hands its
    /// octants a smaller ellipsoid of translations ([`Translations`]).
    Ball { pivot: Vector3<f64>, distance: f64 },
}

/// An ellipsoid `{centre + L z : ‖z‖ ≤ 1}` (`shape = L Lᵀ`) that holds the translation of every pose
/// of `S` in a box (the search without depth bounds hands it down box by box), and its largest
/// semi-axis `radius = √λ_max(shape)`.
#[derive(Clone)]
struct Translations {
    centre: Vector3<f64>,
    shape: Matrix3<f64>,
    radius: f64,
}

impl Translations {
    /// The ball of centre `centre` and radius `radius`.
    fn round(centre: Vector3<f64>, radius: f64) -> Translations {
        Translations {
            centre,
            shape: Matrix3::identity() * (radius * radius),
            radius,
        }
    }
}

/// A point's part of step 2's minorant: `H = AᵀA` for the 2x3 map `A` with `r = A x / x_z` (the
/// point's whitened residual at the camera-frame position `x`), and `λ_max(H) = ‖A‖²`.
struct PointForm {
    /// `H = AᵀA`.
    h: Matrix3<f64>,
    norm2: f64,
}

/// A segment's part of the box bound with lines ([`Problem::lines_bound`]): its object endpoint `a`,
/// direction `d = b − a` and moment `a × d` (with norms), and per observed endpoint `ē = K⁻¹ ẽ`,
/// `‖ē‖` and `‖G_e‖`.
struct LineForm {
    a: Vector3<f64>,
    b: Vector3<f64>,
    d: Vector3<f64>,
    moment: Vector3<f64>,
    norms: [f64; 4],
    ends: [(Vector3<f64>, f64, f64); 2],
}

impl LineForm {
    /// Segment `index` of `corr`.
    fn new(corr: &Correspondences, index: usize, maps: &[EndpointMap; 2], k_inv: &Matrix3<f64>) -> Self {
        let (a, b) = (corr.lines3d[index][0], corr.lines3d[index][1]);
        let seen = corr.lines2d[index];
        let d = b - a;
        let moment = a.cross(&d);
        LineForm {
            a,
            b,
            d,
            moment,
            norms: [a.norm(), b.norm(), d.norm(), moment.norm()],
            ends: std::array::from_fn(|k| {
                let e = k_inv * Vector3::new(seen[k].x, seen[k].y, 1.0);
                (e, e.norm(), maps[k].1)
            }),
        }
    }
}

/// The translations of [`Problem::line_terms`]: within `spread` of `t_star` and, given `shape`, in
/// the ellipsoid `{t* + L z : ‖z‖ ≤ 1}` (`shape = L Lᵀ`, largest semi-axis `spread`).
#[derive(Clone, Copy)]
struct TranslationSet<'a> {
    t_star: &'a Vector3<f64>,
    spread: f64,
    shape: Option<&'a Matrix3<f64>>,
}

/// A segment endpoint's term of [`Problem::lines_bound`] for a box: the weight `1 / W²`, the residual
/// numerator `n = α + βᵀ t` at the box's centre rotation, and `drift` with `|Δn| ≤ θ drift` over the
/// box ([`Problem::line_terms`]).
#[derive(Clone)]
struct LineTerm {
    weight: f64,
    alpha: f64,
    beta: Vector3<f64>,
    drift: f64,
    /// `ē`, and the parts of `drift` for another translation: `‖ē‖ ‖a × d‖` and `‖d‖`.
    e: Vector3<f64>,
    moment_part: f64,
    d_norm: f64,
    /// `r (a × d)` and `r d` at the box's centre rotation `r`.
    rm: Vector3<f64>,
    rd: Vector3<f64>,
}

impl LineTerm {
    /// `γ = r m × ē + r d × (ē × t)`: the numerator's first-order change `φᵀ γ` under the rotation
    /// `exp(φ) r` at the translation `t` ([`Problem::linear_ball_bound`]).
    fn gamma(&self, t: &Vector3<f64>) -> Vector3<f64> {
        self.rm.cross(&self.e) + self.rd.cross(&self.e.cross(t))
    }

    /// The numerator's drift over the rotations `exp(φ) r`, `‖φ‖ ≤ θ`, at translations `t* + Δ`:
    /// `|n(exp(φ) r, t* + Δ) − n(r, t* + Δ)| ≤ spin + θ ‖d‖ ‖ē × Δ‖`. The difference is
    /// `ēᵀ (R − r) m + ēᵀ (t* × (R − r) d) + ēᵀ (Δ × (R − r) d)` (`R = exp(φ) r`, `m = a × d`), the
    /// last at most `‖(R − r) d‖ ‖ē × Δ‖ ≤ θ ‖d‖ ‖ē × Δ‖`. With `a = ‖ē‖ ‖m‖ + ‖d‖ ‖ē × t*‖`, `spin`
    /// bounds the first two: the lesser of `θ a` (each rotated vector moves by at most `θ` times its
    /// norm) and `θ ‖γ‖ + ρ a` (`ρ = e^θ − 1 − θ`: the first-order part `φᵀ γ(t*)` exactly, the rest of
    /// `exp(φ)` costing `ρ` times the norms; `Problem::linear_ball_bound`). Returns `(a, spin, θ)`.
    fn spin(&self, theta: f64, t_star: &Vector3<f64>) -> (f64, f64, f64) {
        let rho = rotation_rest(theta);
        let drift = self.moment_part + self.d_norm * self.e.cross(t_star).norm();
        let first_order = self.gamma(t_star).norm();
        (drift, (theta * drift).min(theta * first_order + rho * drift), theta)
    }

    /// The bound `θ ‖d‖ cross + ρ (‖ē‖ ‖m‖ + ‖d‖ ‖ē × t*‖)` (`ρ = e^θ − 1 − θ`) on
    /// `|n − (α + βᵀ t + φᵀ γ(t*))|` at the rotation `exp(φ) r`, `‖φ‖ ≤ θ`, and the translation
    /// `t = t* + Δ` with `‖ē × Δ‖ ≤ cross` ([`Problem::linear_lines_bound`]).
    fn linear_rest(&self, theta: f64, t_star: &Vector3<f64>, cross: f64) -> f64 {
        theta * self.d_norm * cross
            + rotation_rest(theta) * (self.moment_part + self.d_norm * self.e.cross(t_star).norm())
    }

    /// `‖d‖² [ē]ₓᵀ [ē]ₓ`: `Δᵀ (this) Δ = ‖d‖² ‖ē × Δ‖²`, the square of the drift's part in `Δ` per unit
    /// of `θ` ([`Self::spin`]).
    fn coupling(&self) -> Matrix3<f64> {
        let e = &self.e;
        (Matrix3::identity() * e.norm_squared() - e * e.transpose()) * (self.d_norm * self.d_norm)
    }
}

/// A segment endpoint's `G_e` and `‖G_e‖` ([`Problem::endpoint_maps`]).
type EndpointMap = (Matrix2<f64>, f64);

fn norm2x2(m: &Matrix2<f64>) -> (f64, f64) {
    let s = m.singular_values();
    (s.min(), s.max())
}

/// The depth bound of every point for its angle bound `αᵢ` (`None` when some point has no partner
/// seen far enough apart).
fn depth_bounds(corr: &Correspondences, bearings: &[Vector3<f64>], alphas: &[f64]) -> Option<Vec<f64>> {
    let n = bearings.len();
    // Partners: an even spread of the points.
    let step = (n / DEPTH_PARTNERS).max(1);
    let partners: Vec<usize> = (0..n).step_by(step).take(DEPTH_PARTNERS).collect();
    let pair = |i: usize, j: usize| -> f64 {
        let gamma = bearings[i].angle(&bearings[j]);
        let (lo, hi) = (gamma - alphas[i] - alphas[j], gamma + alphas[i] + alphas[j]);
        if i == j || lo <= 0.0 || hi >= std::f64::consts::PI {
            return f64::INFINITY;
        }
        (corr.points3d[i] - corr.points3d[j]).norm() / lo.sin().min(hi.sin())
    };
    (0..n)
        .map(|i| {
            let mut best = partners.iter().map(|&j| pair(i, j)).fold(f64::INFINITY, f64::min);
            // Every point as a partner when the spread set did not give a bound.
            if !best.is_finite() {
                best = (0..n).map(|j| pair(i, j)).fold(f64::INFINITY, f64::min);
            }
            best.is_finite().then_some(best)
        })
        .collect()
}

impl<'c> Problem<'c> {
    fn new(camera: &Camera, corr: &'c Correspondences, f_hat: f64) -> std::result::Result<Self, String> {
        Self::build(camera, corr, f_hat, true)
    }

    /// The data of the test without depth bounds ([`Start::Ball`]) even where the points give them.
    fn without_depths(camera: &Camera, corr: &'c Correspondences, f_hat: f64) -> std::result::Result<Self, String> {
        Self::build(camera, corr, f_hat, false)
    }

    /// The data of the test, with step 1's depth bounds where `use_depths` and the points give them.
    fn build(
        camera: &Camera,
        corr: &'c Correspondences,
        f_hat: f64,
        use_depths: bool,
    ) -> std::result::Result<Self, String> {
        let k = camera.matrix();
        let k2 = Matrix2::new(camera.fx, camera.skew, 0.0, camera.fy);
        let k_inv = k.try_inverse().ok_or("singular camera")?;
        let g = k_inv.transpose().fixed_view::<2, 2>(0, 0).into_owned();
        let (point_maps, endpoint_maps): (Vec<Matrix2<f64>>, Vec<[EndpointMap; 2]>) = match &corr.noise {
            None => {
                let g_norm = norm2x2(&g).1;
                (vec![k2; corr.n_points()], vec![[(g, g_norm); 2]; corr.n_lines()])
            }
            // Noise that carries a lens's Jacobians: the cost is in the distorted pixels.
            Some(noise) if !noise.absolute => return Err(FIRST_ORDER_NOISE.into()),
            Some(noise) => {
                let endpoint = |c: &Matrix2<f64>| -> std::result::Result<EndpointMap, String> {
                    // The residual's scale is √(l₁₂ᵀ C l₁₂): only the symmetric part of C enters.
                    let l = (0.5 * (c + c.transpose()))
                        .cholesky()
                        .ok_or("not attempted: a covariance is not positive definite")?
                        .l();
                    let map = l.transpose() * g;
                    Ok((map, norm2x2(&map).1))
                };
                (
                    noise.points.iter().map(|w| w * k2).collect(),
                    noise
                        .lines
                        .iter()
                        .map(|[c0, c1]| Ok([endpoint(c0)?, endpoint(c1)?]))
                        .collect::<std::result::Result<_, String>>()?,
                )
            }
        };
        // A whitened error e is a normalised-plane error of at least e / sᵢ (sᵢ the least singular
        // value of Wᵢ K₂): the angle bound of point i.
        let eps0 = (2.0 * f_hat).sqrt();
        let alphas: Vec<f64> = point_maps.iter().map(|m| eps0 / norm2x2(m).0).collect();
        let bearings: Vec<Vector3<f64>> = corr
            .points2d
            .iter()
            .map(|u| (k_inv * Vector3::new(u.x, u.y, 1.0)).normalize())
            .collect();
        let depths = if !use_depths {
            Err("the search without depth bounds was asked for".to_string())
        } else if corr.n_points() < 2 {
            Err("the depth bounds need at least two points".to_string())
        } else if !alphas.iter().all(|alpha| *alpha < 0.25) {
            Err(format!("residuals too large ({eps0:.3e} px) for the angle bounds"))
        } else {
            depth_bounds(corr, &bearings, &alphas)
                .ok_or_else(|| "no two points are seen far enough apart to bound the depths".to_string())
        };
        // A point's residual is Wᵢ K₂ (π(x) − ūᵢ) = Aᵢ x / x_z with Aᵢ = Wᵢ K₂ Eᵢ,
        // Eᵢ = [1 0 −ū₁; 0 1 −ū₂] (ūᵢ the normalised observed point).
        let forms: Vec<PointForm> = (point_maps.iter().zip(&corr.points2d))
            .map(|(map, u)| {
                let n = k_inv * Vector3::new(u.x, u.y, 1.0);
                let e = SMatrix::<f64, 2, 3>::new(1.0, 0.0, -n.x / n.z, 0.0, 1.0, -n.y / n.z);
                let a = map * e;
                let h = a.transpose() * a;
                PointForm {
                    h,
                    norm2: largest_eigenvalue(&h),
                }
            })
            .collect();
        let (start, segments) = match depths {
            Ok(depths) => (
                Start::Points(Rc::new(Minorant::build(&corr.points3d, &bearings, &forms, depths))),
                BOX_BOUND_SEGMENTS,
            ),
            Err(why) => {
                let (pivot, distance) = object_distance(corr, &bearings, &alphas, &endpoint_maps, &k_inv, eps0)
                    .ok_or_else(|| {
                        format!("not proved: {why}, and the observations do not bound the object's distance")
                    })?;
                (Start::Ball { pivot, distance }, BALL_SEGMENTS)
            }
        };
        Ok(Problem {
            corr,
            point_maps,
            forms,
            k_inv,
            lines: longest_segments(corr, corr.n_lines())
                .into_iter()
                .map(|i| LineForm::new(corr, i, &endpoint_maps[i], &k_inv))
                .collect(),
            box_segments: segments,
            endpoint_maps,
            bearing_cone: bearing_cone(&bearings, &corr.points3d),
            bearings,
            norms: corr.points3d.iter().map(|x| x.norm()).collect(),
            start,
        })
    }

    /// Step 1's minorant (`None` without depth bounds).
    fn root(&self) -> Option<&Rc<Minorant>> {
        match &self.start {
            Start::Points(root) => Some(root),
            Start::Ball { .. } => None,
        }
    }

    /// Step 2's minorant for the depth bounds `depths`.
    fn minorant(&self, depths: Vec<f64>) -> Minorant {
        Minorant::build(&self.corr.points3d, &self.bearings, &self.forms, depths)
    }

    /// The segments' terms of [`Self::lines_bound`] for the rotations within the angle `θ` of `r`
    /// and the translations within `spread` of `t_star` (and, given `shape`, in the ellipsoid
    /// `{t* + L z : ‖z‖ ≤ 1}`, `shape = L Lᵀ`, whose largest semi-axis is `spread`). A segment endpoint's residual is
    /// `r_e = n / w` with `n = ēᵀ ((R a + t) × R d) = ēᵀ R (a × d) + tᵀ (R d × ē)` (`d = b − a`),
    /// linear in `t` for a fixed rotation, and
    /// `w = ‖G_e m_xy‖ ≤ ‖G_e‖ ‖m‖ ≤ W`, with two bounds on the moment `m = R (a × d) + t × R d` of the
    /// camera-frame line: it is at most its distance from the camera times `‖d‖`, and
    /// `‖d‖ min(‖R a + t‖, ‖R b + t‖)` is bounded over the rotations and translations as the points'
    /// distances are; and it moves from its value `m_c` at `(r, t*)` by at most
    /// `θ (‖a × d‖ + ‖d‖ ‖t‖) + ‖(t − t*) × r d‖`. So `r_e² ≥ n² / W²`. Between `r` and a rotation
    /// `R'`, `n` moves by at most `θ (‖ē‖ ‖a × d‖ + ‖d‖ ‖ē × t‖)` (`‖(R' − r) y‖ ≤ θ ‖y‖`), with
    /// `‖ē × t‖ ≤ ‖ē × t*‖ + ‖ē‖ spread`, or `‖ē × t*‖ + ‖[ē]ₓ L‖` with the spectral norm below the
    /// Frobenius norm `√(‖ē‖² tr(shape) − ēᵀ shape ē)` (an ellipsoid elongated along the line of
    /// sight moves `ē × t` little).
    fn line_terms(
        &self,
        segments: usize,
        (r, theta): (&Matrix3<f64>, f64),
        TranslationSet { t_star, spread, shape }: TranslationSet,
    ) -> Vec<LineTerm> {
        let mut terms = Vec::with_capacity(2 * segments.min(self.lines.len()));
        for line in self.lines.iter().take(segments) {
            let [a_norm, b_norm, d_norm, m_norm] = line.norms;
            let reach = |x: &Vector3<f64>, norm: f64| (r * x + t_star).norm() + theta * norm + spread;
            let distance = reach(&line.a, a_norm).min(reach(&line.b, b_norm));
            let (rd, rm) = (r * line.d, r * line.moment);
            let moment = (d_norm * distance).min(
                (rm + t_star.cross(&rd)).norm()
                    + theta * (m_norm + d_norm * (t_star.norm() + spread))
                    + Self::cross_extent(&rd, d_norm, spread, shape),
            );
            for &(e, e_norm, g_norm) in &line.ends {
                terms.push(LineTerm {
                    weight: (g_norm * moment).powi(-2),
                    alpha: e.dot(&rm),
                    beta: rd.cross(&e),
                    drift: e_norm * m_norm
                        + d_norm * (e.cross(t_star).norm() + Self::cross_extent(&e, e_norm, spread, shape)),
                    e,
                    moment_part: e_norm * m_norm,
                    d_norm,
                    rm,
                    rd,
                });
            }
        }
        terms
    }

    /// The largest `‖ē × Δt‖` over the translation steps `Δt` of [`Self::line_terms`]'s set.
    fn cross_extent(e: &Vector3<f64>, e_norm: f64, spread: f64, shape: Option<&Matrix3<f64>>) -> f64 {
        let round = e_norm * spread;
        shape.map_or(round, |shape| {
            let frobenius2 = e_norm * e_norm * shape.trace() - e.dot(&(shape * e));
            round.min(frobenius2.max(0.0).sqrt() * (1.0 + 1e-12))
        })
    }

    /// A lower bound of `f` on the poses of `S` whose rotation is within the angle `θ` of `r` and
    /// whose translation is within `spread` of `t_star`, from the minorant `scaled` (its minimiser
    /// `t_star` and minimum `q_min` at `r`, [`Scaled::at`]'s, so that `κ Q(r, t) = q_min +
    /// (t − t*)ᵀ κ C (t − t*)`) with the segments' residuals added
    /// ([`Self::line_terms`]): `Q_total(R, t) = κ Q(R, t) + Σ (α + βᵀ t)² / W²` at `r` is a minorant
    /// of `2f` quadratic in `t`, and over the rotations its square root moves by at most
    /// `θ η_total`, `η_total² = κ η² + Σ drift² / W²` (Minkowski over all the terms), so
    /// `f ≥ ½ (√q_min − θ η_total)₊²` as for the points alone (`by_growth`). The first `segments`
    /// segments enter. `None` where the quadratic does not fix the translation.
    ///
    /// Where that falls short of `wanted` (`None`: not tried), the quadratic linearised in the
    /// rotation gives a second bound (`by_linear`), as [`Self::linear_ball_bound`] does without depth bounds: a rotation of
    /// the box is `exp(φ) r` (`‖φ‖ ≤ θ`, `exp(φ) = I + [φ]ₓ + E`, `‖E y‖ ≤ ρ ‖y‖`,
    /// `ρ = e^θ − 1 − θ`) and a translation `t* + Δ` with `‖Δ‖ ≤ spread`. A point's
    /// `Aᵢ (exp(φ) yᵢ + t)` is within `ρ ‖Aᵢ‖ ‖Xᵢ‖` of its linear part (the points' rest `ρ √κ η`),
    /// and a segment endpoint's numerator
    /// `n = α + βᵀ t + φᵀ γ + ēᵀ E r m + ēᵀ (t* × E r d) + ēᵀ (Δ × (R − r) d)` within
    /// `θ ‖d‖ ‖ē × Δ‖ + ρ (‖ē‖ ‖m‖ + ‖d‖ ‖ē × t*‖)` of `α + βᵀ t + φᵀ γ` (`‖ē × Δ‖` at most the
    /// set's [`Self::cross_extent`]). Minkowski over all the weighted terms gives
    /// `√(2f) ≥ √L(φ, Δ) − rest` with `L` the weighted sum of squares of the linear parts, and
    /// `√L ≥ √least` with [`Self::linear_part`]'s bound of its minimum over `Δ` and `‖φ‖ ≤ θ`. So
    /// `f ≥ ½ (√least − rest)₊²`: the rotation's first-order effect, in which the segments' drifts
    /// are large and partly cancel, enters exactly.
    #[allow(clippy::too_many_arguments)]
    fn lines_bound(
        &self,
        scaled: &Scaled,
        r: &Matrix3<f64>,
        theta: f64,
        (t_star, q_min): (&Vector3<f64>, f64),
        spread: f64,
        segments: usize,
        wanted: Option<f64>,
    ) -> Option<LinesBound> {
        let c = scaled.minorant.c * scaled.scale;
        let mut quadratic = Quadratic {
            c,
            g: -(c * t_star),
            c0: q_min + t_star.dot(&(c * t_star)),
            eta2: scaled.minorant.eta.powi(2) * scaled.scale,
        };
        let set = TranslationSet {
            t_star,
            spread,
            shape: None,
        };
        let terms = self.line_terms(segments, (r, theta), set);
        terms.iter().for_each(|term| quadratic.add_line(term));
        let (t_lines, q_lines, c_inv) = quadratic.minimum()?;
        let eta = quadratic.eta2.sqrt();
        let by_growth = minkowski(q_lines, theta * eta);
        let by_linear = match wanted {
            Some(wanted) if by_growth < wanted => {
                self.linear_lines_bound(scaled, (r, theta), set, &terms, &c_inv, (q_lines, wanted))
            }
            _ => 0.0,
        };
        Some(LinesBound {
            lower: by_growth.max(by_linear),
            by_growth,
            by_linear,
            t_star: t_lines,
            q_min: q_lines,
            c: quadratic.c,
            c_inv,
            eta,
        })
    }

    /// [`Self::lines_bound`]'s linearised bound (`by_linear`) for the translation set `set` (its
    /// points' `t*` and `spread`), the segments' `terms` and the quadratic's `C⁻¹` and minimum
    /// `q_lines`; 0 where even
    /// `½ (√q_lines − rest)₊²`, which it cannot exceed, falls short of `wanted`.
    fn linear_lines_bound(
        &self,
        scaled: &Scaled,
        (r, theta): (&Matrix3<f64>, f64),
        set: TranslationSet,
        terms: &[LineTerm],
        c_inv: &Matrix3<f64>,
        (q_lines, wanted): (f64, f64),
    ) -> f64 {
        let lines_rest2: f64 = (terms.iter())
            .map(|term| {
                let cross = Self::cross_extent(&term.e, term.e.norm(), set.spread, None);
                term.weight * term.linear_rest(theta, set.t_star, cross).powi(2)
            })
            .sum();
        let rest = (scaled.second_order_rest(theta).powi(2) + lines_rest2).sqrt();
        if minkowski(q_lines, rest) < wanted {
            return 0.0;
        }
        let points = (self.corr.points3d.iter().zip(scaled.depths())).map(|(x, d)| (r * x, 1.0 / (d * d)));
        let least = self.linear_part(terms, points, set.t_star, c_inv, theta).least;
        minkowski(least.max(0.0), rest)
    }

    /// The segments that enter the bound of `cell`: every one near the answer, where the translation
    /// ellipsoid decides whether the box lies inside the whitened ball; the longest `box_segments`
    /// elsewhere.
    fn segments_in(&self, cell: &Cell) -> usize {
        if cell.centre.norm() + cell.half.norm() <= NEAR_ANSWER {
            self.lines.len()
        } else {
            self.box_segments
        }
    }

    /// The bound of a box without depth bounds ([`Start::Ball`]) whose poses of `S` have their
    /// rotations within `θ` of `r` and their translations in `ball`.
    ///
    /// Every point is at most `Dᵢ = ‖r Xᵢ + centre‖ + θ ‖Xᵢ‖ + radius` from the camera, so its term
    /// `‖Aᵢ (R Xᵢ + t)‖² / Dᵢ²` (step 2) and the segments' terms `(α + βᵀ t)² / W²`
    /// ([`Self::line_terms`]) are a minorant of `2f`; at `r` it is the quadratic
    /// `Q(t) = q_min + Δᵀ C Δ`, `Δ = t − t*`. Over the rotations a point's term moves by at most
    /// `θ ‖Aᵢ‖ ‖Xᵢ‖ / Dᵢ`, and a segment endpoint's by `θ (‖ē‖ ‖a × d‖ + ‖d‖ ‖ē × t‖) / W` with
    /// `‖ē × t‖ ≤ ‖ē × t*‖ + ‖ē × Δ‖`. By Minkowski over all the terms,
    /// `√(2f) ≥ √(q_min + Δᵀ C Δ) − θ (η₀ + √(Δᵀ N Δ))` with `η₀` the terms' drifts at `t*` and
    /// `N = Σ ‖d‖² [ē]ₓᵀ [ē]ₓ / W²`. With `μ` the least eigenvalue of `C` relative to `N`
    /// (`Δᵀ C Δ ≥ μ x²`, `x = √(Δᵀ N Δ)`), `√(2f) ≥ v(x) − θ η₀`, `v(x) = √(q_min + μ x²) − θ x`, a
    /// convex function whose least value over `x ≤ x_ball` (the ball's reach) is the bound. The
    /// translations of the box's poses of `S` have `v(x) ≤ β = √(2f̂) + θ η₀`, so `x ≤ x_max` and
    /// `Δᵀ C Δ ≤ (β + θ x_max)² − q_min`: an ellipsoid. The drift of the segments is paid against the
    /// quadratic's own growth, not against the ball, which only weighs the terms.
    fn ball_bound(
        &self,
        segments: usize,
        r: &Matrix3<f64>,
        theta: f64,
        ball: &Translations,
        f_hat: f64,
    ) -> Option<BoxBound> {
        let mut quadratic = Quadratic {
            c: Matrix3::zeros(),
            g: Vector3::zeros(),
            c0: 0.0,
            eta2: 0.0,
        };
        let mut depths = Vec::with_capacity(self.forms.len());
        let mut rotated = Vec::with_capacity(self.forms.len());
        for ((x, form), norm) in self.corr.points3d.iter().zip(&self.forms).zip(&self.norms) {
            let y = r * x;
            let depth = (y + ball.centre).norm() + theta * norm + ball.radius;
            let w = 1.0 / (depth * depth);
            let hy = form.h * y;
            quadratic.c += form.h * w;
            quadratic.g += hy * w;
            quadratic.c0 += w * y.dot(&hy);
            quadratic.eta2 += w * form.norm2 * norm * norm;
            depths.push(depth);
            rotated.push((y, w));
        }
        let points_eta2 = quadratic.eta2;
        let set = TranslationSet {
            t_star: &ball.centre,
            spread: ball.radius,
            shape: Some(&ball.shape),
        };
        let terms = self.line_terms(segments, (r, theta), set);
        terms.iter().for_each(|term| quadratic.add_line(term));
        let (t_star, q_min, c_inv) = quadratic.minimum()?;
        // Per segment endpoint, its drift at t*: θ aₖ with aₖ = ‖ē‖ ‖m‖ + ‖d‖ ‖ē × t*‖, or
        // θ ‖γₖ‖ + ρ aₖ with the exact first-order part γₖ ([`Self::linear_ball_bound`]); the lesser.
        let mut step = theta;
        let mut eta0_2 = points_eta2;
        let mut spin2 = points_eta2 * theta * theta;
        let mut n = Matrix3::zeros();
        for term in &terms {
            let (drift, spin, its_step) = term.spin(theta, &t_star);
            step = step.max(its_step);
            eta0_2 += term.weight * drift * drift;
            spin2 += term.weight * spin * spin;
            n += term.coupling() * term.weight;
        }
        let eta0 = eta0_2.sqrt();
        let (mu, n_max) = relative_floor(&c_inv, &n);
        // The ball's reach in x: ‖Δ‖ ≤ ‖t* − centre‖ + radius.
        let x_ball = n_max.max(0.0).sqrt() * ((t_star - ball.centre).norm() + ball.radius);
        let spin = spin2.sqrt();
        let v = |x: f64| (q_min + mu * x * x).sqrt() - step * x;
        let x_least = if step * step < mu {
            (q_min * step * step / (mu * (mu - step * step))).sqrt().min(x_ball)
        } else {
            x_ball
        };
        let least = if mu.is_finite() { v(x_least) } else { q_min.sqrt() };
        let by_growth = 0.5 * (least - spin).max(0.0).powi(2);
        let mut by_linear = 0.0;
        if by_growth < f_hat {
            let linear = Linearised {
                terms: &terms,
                points: &rotated,
                t_star: &t_star,
                c_inv: &c_inv,
                n: &n,
                mu,
                eta0,
            };
            by_linear = self.linear_ball_bound(&linear, theta);
        }
        // The largest x with v(x) ≤ β: the larger root of (μ − s²) x² − 2 β s x + q_min − β²
        // (s = θ; x_ball where that does not bound x).
        let beta = (2.0 * f_hat).sqrt() + spin;
        let x_max = if !mu.is_finite() {
            0.0
        } else if step * step < mu {
            let (a, b) = (mu - step * step, beta * step);
            let disc = (b * b - a * (q_min - beta * beta)).max(0.0);
            ((b + disc.sqrt()) / a).min(x_ball)
        } else {
            x_ball
        };
        let slack = ((beta + step * x_max).powi(2) - q_min).max(0.0);
        Some(BoxBound {
            lower: by_growth.max(by_linear),
            by_growth,
            by_linear,
            t_star,
            c: quadratic.c,
            c_inv,
            slack,
            depths,
            growth: Growth { q_min, n, spin, eta0 },
        })
    }
}

/// A box's ellipsoid `(t − centre)ᵀ C (t − centre) ≤ slack` that holds the translations of its poses
/// of `S`, its reach `spread ≥ max ‖t − centre‖` over it, and whether it comes from the quadratic with
/// the segments' terms ([`LinesBound::ellipsoid`]) rather than the points' minorant.
#[derive(Clone, Copy)]
struct Ellipsoid {
    centre: Vector3<f64>,
    c: Matrix3<f64>,
    slack: f64,
    spread: f64,
    with_segments: bool,
}

/// [`Problem::lines_bound`]: the bound, and the quadratic `Q_total(t) = q_min + (t − t*)ᵀ C (t − t*)`
/// at the box's centre rotation with `η_total` (`eta`). The poses of `S` in the box (their
/// translations within the points' ellipsoid) have `√Q_total ≤ √(2f̂) + θ η_total`: a second
/// ellipsoid that holds their translations.
struct LinesBound {
    lower: f64,
    // The two bounds apart: read by the unit tests, which check each.
    #[cfg_attr(not(test), allow(dead_code))]
    by_growth: f64,
    #[cfg_attr(not(test), allow(dead_code))]
    by_linear: f64,
    t_star: Vector3<f64>,
    q_min: f64,
    c: Matrix3<f64>,
    c_inv: Matrix3<f64>,
    eta: f64,
}

impl LinesBound {
    /// The ellipsoid `(t − t*)ᵀ C (t − t*) ≤ slack` of the translations with
    /// `√Q_total(t) ≤ √(2f̂) + θ η_total`, and its reach `spread = max ‖t − t*‖` over it.
    fn ellipsoid(&self, f_hat: f64, theta: f64) -> (f64, f64) {
        let beta = (2.0 * f_hat).sqrt() + theta * self.eta;
        let slack = (beta * beta - self.q_min).max(0.0);
        (slack, (slack * largest_eigenvalue(&self.c_inv)).sqrt())
    }
}

/// `μ` with `Δᵀ C Δ ≥ μ Δᵀ N Δ` for every `Δ` (`C` given by its inverse, `N` positive definite), and
/// `λ_max(N)`: `μ = λ_min(L⁻¹ C L⁻ᵀ) = 1 / λ_max(Lᵀ C⁻¹ L)` for `N = L Lᵀ`, lowered for rounding by
/// [`largest_eigenvalue`]'s raise. `(+∞, 0)` when `N` is not positive definite (no segments).
fn relative_floor(c_inv: &Matrix3<f64>, n: &Matrix3<f64>) -> (f64, f64) {
    match n.cholesky() {
        Some(chol) => {
            let l = chol.l();
            (
                1.0 / largest_eigenvalue(&(l.transpose() * c_inv * l)),
                largest_eigenvalue(n),
            )
        }
        None => (f64::INFINITY, 0.0),
    }
}

/// What [`Problem::linear_ball_bound`] reads of [`Problem::ball_bound`]'s work: the segments'
/// terms, the points' `r Xᵢ` and weights, the quadratic's minimiser and `C⁻¹`, `N`, `μ` and `η₀`.
struct Linearised<'a> {
    terms: &'a [LineTerm],
    points: &'a [(Vector3<f64>, f64)],
    t_star: &'a Vector3<f64>,
    c_inv: &'a Matrix3<f64>,
    n: &'a Matrix3<f64>,
    mu: f64,
    eta0: f64,
}

/// [`Problem::ball_bound`]'s result: the bound (the larger of the two: the minorant's growth against
/// the drift, and the linearised minorant, computed only where the first falls short of `f̂`), the
/// ellipsoid `(t − t*)ᵀ C (t − t*) ≤ slack` (`C⁻¹` given) that holds the translations of the box's
/// poses of `S`, and the points' depth bounds.
struct BoxBound {
    lower: f64,
    // The two bounds apart: read by the unit tests, which check each.
    #[cfg_attr(not(test), allow(dead_code))]
    by_growth: f64,
    #[cfg_attr(not(test), allow(dead_code))]
    by_linear: f64,
    t_star: Vector3<f64>,
    c: Matrix3<f64>,
    c_inv: Matrix3<f64>,
    slack: f64,
    depths: Vec<f64>,
    #[cfg_attr(not(test), allow(dead_code))]
    growth: Growth,
}

/// The parts of [`Problem::ball_bound`]'s bounds that the unit tests check the algebra on: `q_min`,
/// `N` and the drifts at `t*` (`spin` for the growth bound, `η₀` the linearised one's rest per `ρ`).
#[cfg_attr(not(test), allow(dead_code))]
struct Growth {
    q_min: f64,
    n: Matrix3<f64>,
    spin: f64,
    eta0: f64,
}

impl Problem<'_> {
    /// [`Problem::ball_bound`]'s minorant linearised in the rotation, as [`Scaled::linear_bound`] does
    /// with depth bounds (0 where it cannot be computed). A rotation of the box is `exp(φ) r`,
    /// `‖φ‖ ≤ θ`, `exp(φ) = I + [φ]ₓ + E` with `‖E y‖ ≤ ρ ‖y‖`, `ρ = e^θ − 1 − θ`; write `t = t* + Δ`.
    /// A segment endpoint's numerator is then
    /// `n = α + βᵀ t + φᵀ γ + ēᵀ E r m + ēᵀ (t* × E r d) + ēᵀ (Δ × (R − r) d)` with
    /// `γ = r m × ē + r d × (ē × t*)` (`m = a × d`, `R = exp(φ) r`), so it is within
    /// `θ ‖d‖ ‖ē × Δ‖ + ρ (‖ē‖ ‖m‖ + ‖d‖ ‖ē × t*‖)` of the linear `α + βᵀ t + φᵀ γ`; a point's
    /// `Aᵢ (exp(φ) yᵢ + t)` (`yᵢ = r Xᵢ`) is within `ρ ‖Aᵢ‖ ‖Xᵢ‖` of `Aᵢ (yᵢ + t − [yᵢ]ₓ φ)`. With
    /// `L(φ, Δ)` the weighted sum of squares of the linear parts (a quadratic in `(φ, Δ)`), Minkowski
    /// gives `√(2f) ≥ √L − θ √(Δᵀ N Δ) − ρ η₀`. Minimised over `Δ`,
    /// `L = L_min(φ) + (Δ − Δ*(φ))ᵀ C (Δ − Δ*(φ))` with `Δ*(φ) = −C⁻¹ (B φ + h_Δ)` linear in `φ`, and
    /// `√(Δᵀ N Δ) ≤ y + s`, `y = √((Δ − Δ*)ᵀ N (Δ − Δ*))`, `s ≤ ‖N^½ C⁻¹ B‖ θ + ‖N^½ C⁻¹ h_Δ‖`; as in
    /// [`Problem::ball_bound`], `√(L_min + μ y²) − θ y ≥ √L_min √(1 − θ² / μ)`. `L_min(φ)`
    /// is a convex quadratic, bounded below over the ball `‖φ‖ ≤ θ` by
    /// [`ball_minimum_lower_bound`]. So
    /// `√(2f) ≥ √(min L_min) √(1 − θ² / μ) − θ s − ρ η₀`.
    fn linear_ball_bound(&self, lin: &Linearised, theta: f64) -> f64 {
        let rho = rotation_rest(theta);
        let step = theta;
        if !(step * step < lin.mu) {
            return 0.0;
        }
        let linear = self.linear_part(lin.terms, lin.points.iter().copied(), lin.t_star, lin.c_inv, theta);
        // s: ‖N^½ C⁻¹ B‖ θ + ‖N^½ C⁻¹ h_Δ‖ (norms through N: ‖N^½ v‖² = vᵀ N v).
        let coupling = largest_eigenvalue(&(linear.cb.transpose() * lin.n * linear.cb))
            .max(0.0)
            .sqrt();
        let s = coupling * theta + linear.offset.dot(&(lin.n * linear.offset)).max(0.0).sqrt();
        let root = linear.least.max(0.0).sqrt() * (1.0 - step * step / lin.mu).sqrt();
        0.5 * (root - step * s - rho * lin.eta0).max(0.0).powi(2)
    }

    /// The linear parts of a box's minorant at its centre rotation `r` ([`Self::linear_ball_bound`],
    /// [`Self::lines_bound`]): a rotation of the box is `exp(φ) r`, `‖φ‖ ≤ θ`, and a translation
    /// `t_ref + Δ`; a segment endpoint's numerator has the linear part `α + βᵀ t_ref + βᵀ Δ + φᵀ γ`
    /// (`γ` at `t_ref`, [`LineTerm::gamma`]) and a point's `Aᵢ (yᵢ + t)` (`yᵢ = r Xᵢ`) the linear
    /// part `Aᵢ (yᵢ + t_ref + Δ − [yᵢ]ₓ φ)`. Their weighted sum of squares is a convex quadratic
    /// `L(φ, Δ)`; `C⁻¹` is the inverse of its `Δ` block (the quadratic's own). Minimised over `Δ`,
    /// `L = L_min(φ) + (Δ − Δ*(φ))ᵀ C (Δ − Δ*(φ))`, `Δ*(φ) = −C⁻¹ (B φ + h_Δ)`, and `least` bounds
    /// `L_min` from below over the ball `‖φ‖ ≤ θ` ([`ball_minimum_lower_bound`]).
    fn linear_part(
        &self,
        terms: &[LineTerm],
        points: impl Iterator<Item = (Vector3<f64>, f64)>,
        t_ref: &Vector3<f64>,
        c_inv: &Matrix3<f64>,
        theta: f64,
    ) -> LinearPart {
        // L(z) = L₀ + 2 hᵀ z + zᵀ M z, z = (φ, Δ), M = [M_φφ Bᵀ; B C]: C is the quadratic's own
        // (its inverse given), so only M_φφ, B, h and L₀ are summed.
        let (mut m_pp, mut b) = (Matrix3::zeros(), Matrix3::zeros());
        let (mut h_p, mut h_d) = (Vector3::zeros(), Vector3::zeros());
        let mut l0 = 0.0;
        for term in terms {
            let gamma = term.gamma(t_ref);
            let value = term.alpha + term.beta.dot(t_ref);
            let (w_gamma, w_beta) = (gamma * term.weight, term.beta * term.weight);
            m_pp += w_gamma * gamma.transpose();
            b += w_beta * gamma.transpose();
            h_p += w_gamma * value;
            h_d += w_beta * value;
            l0 += value * value * term.weight;
        }
        for ((y, w), form) in points.zip(&self.forms) {
            // The camera-frame point's linear part is J z with J = [−[y]ₓ | I]: JᵀHJ has the blocks
            // [y]ₓᵀ H [y]ₓ, −H [y]ₓ (B) and H, and JᵀH p the parts [y]ₓ H p and H p.
            let (y_cross, wh) = (skew(&y), form.h * w);
            let wh_cross = wh * y_cross;
            let hp = wh * (y + t_ref);
            m_pp -= y_cross * wh_cross;
            b -= wh_cross;
            h_p += y_cross * hp;
            h_d += hp;
            l0 += (y + t_ref).dot(&hp);
        }
        let schur = m_pp - b.transpose() * c_inv * b;
        let g = h_p - b.transpose() * (c_inv * h_d);
        let q0 = l0 - h_d.dot(&(c_inv * h_d));
        LinearPart {
            least: ball_minimum_lower_bound(q0, &g, &(0.5 * (schur + schur.transpose())), theta),
            cb: c_inv * b,
            offset: c_inv * h_d,
        }
    }
}

/// [`Problem::linear_part`]: the lower bound `least` of `L_min(φ)` over `‖φ‖ ≤ θ`, and the parts of
/// `Δ*(φ) = −(C⁻¹ B φ + C⁻¹ h_Δ)`.
struct LinearPart {
    least: f64,
    cb: Matrix3<f64>,
    offset: Vector3<f64>,
}

/// A minorant of `2f` at a box's centre rotation as a quadratic `tᵀ C t + 2 gᵀ t + c₀` in the
/// translation, and `η²`: over the box's rotations (within `θ` of the centre's) its square root moves
/// by at most `θ η` (Minkowski over its terms).
struct Quadratic {
    c: Matrix3<f64>,
    g: Vector3<f64>,
    c0: f64,
    eta2: f64,
}

impl Quadratic {
    /// Adds a segment endpoint's term `(α + βᵀ t)² / W²` ([`Problem::line_terms`]).
    fn add_line(&mut self, term: &LineTerm) {
        self.c += term.beta * term.beta.transpose() * term.weight;
        self.g += term.beta * (term.alpha * term.weight);
        self.c0 += term.alpha * term.alpha * term.weight;
        self.eta2 += term.weight * term.drift * term.drift;
    }

    /// The minimiser `t*`, the minimum `q_min` (clamped at 0) and `C⁻¹` (`None` when `C` is singular:
    /// the quadratic does not fix the translation).
    fn minimum(&self) -> Option<(Vector3<f64>, f64, Matrix3<f64>)> {
        let c_inv = self.c.try_inverse()?;
        let t_star = -(c_inv * self.g);
        Some((t_star, (self.c0 + self.g.dot(&t_star)).max(0.0), c_inv))
    }
}

/// A bound on the sine of the angle between the ray of an observed segment endpoint `ē = K⁻¹ ẽ` and
/// the interpretation plane (normal `m`) of every pose where the endpoint's residual
/// `ēᵀ m / ‖G_e m_xy‖` is at most `residual` in magnitude: `|ēᵀ m| ≤ residual ‖G_e‖ ‖m‖`, so the sine
/// `|ēᵀ m| / (‖ē‖ ‖m‖)` is at most `residual ‖G_e‖ / ‖ē‖` (`g_norm = ‖G_e‖`), and at most 1.
fn endpoint_sine(residual: f64, g_norm: f64, e: &Vector3<f64>) -> f64 {
    (residual * g_norm / e.norm()).min(1.0)
}

/// The pivot of the object (the mean of its points and segment midpoints) and the bound on its
/// distance from the camera on `S` ([`super::object_distance`]; `None` without one). A point is
/// within its angle bound `αᵢ` of its observed ray (step 1). A segment endpoint `ē` whose residual
/// `ēᵀ m / ‖G_e m_xy‖` is at most `ε₀` is within the angle whose sine is `ε₀ ‖G_e‖ / ‖ē‖` of the
/// interpretation plane (normal `m`), as `‖G_e m_xy‖ ≤ ‖G_e‖ ‖m‖`.
fn object_distance(
    corr: &Correspondences,
    bearings: &[Vector3<f64>],
    alphas: &[f64],
    endpoint_maps: &[[EndpointMap; 2]],
    k_inv: &Matrix3<f64>,
    eps0: f64,
) -> Option<(Vector3<f64>, f64)> {
    let count = corr.n_points() + corr.n_lines();
    if count == 0 {
        return None;
    }
    let pivot = (corr.points3d.iter().sum::<Vector3<f64>>()
        + corr.lines3d.iter().map(|[a, b]| (a + b) * 0.5).sum::<Vector3<f64>>())
        / count as f64;
    let rays = (corr.points3d.iter().zip(bearings).zip(alphas))
        .filter(|(_, alpha)| **alpha < std::f64::consts::FRAC_PI_2)
        .map(|((x, b), alpha)| Sight::Ray {
            direction: *b,
            tolerance: *alpha,
            offset: (x - pivot).norm(),
        });
    let planes = (corr.lines3d.iter().zip(&corr.lines2d).zip(endpoint_maps))
        .filter(|(([a, b], _), _)| (b - a).norm() > 0.0)
        .map(|(([a, b], seen), maps)| {
            let d = b - a;
            let ends = [0, 1].map(|k| k_inv * Vector3::new(seen[k].x, seen[k].y, 1.0));
            Sight::Plane {
                ends,
                sines: [0, 1].map(|k| endpoint_sine(eps0, maps[k].1, &ends[k])),
                offset: (a - pivot).cross(&d).norm() / d.norm(),
            }
        });
    let sights: Vec<Sight> = rays.chain(planes).collect();
    distance_bound(&sights).map(|distance| (pivot, distance))
}

/// Step 2's minorant `Q(R, t) = Σ wᵢ ‖Aᵢ (R Xᵢ + t)‖²`, `wᵢ = 1 / Dᵢ²`, for one set of depth
/// bounds `Dᵢ` (a minorant of `2f` where every `‖xᵢ‖ ≤ Dᵢ`), as a quadratic form in `(vec R, t)`
/// (row-major `vec`), and `η = √(Σ wᵢ ‖Aᵢ‖² ‖Xᵢ‖²)`: over rotations within the angle `θ` of `R`, `√Q`
/// moves by at most `θ η`.
///
/// The Hessian `C` in `t` does not depend on the rotation: `C⁻¹`, its largest eigenvalue, the
/// `bᵢᵀ C⁻¹ bᵢ` and the ellipsoid's whitened extent are computed once per minorant, not per box.
struct Minorant {
    depths: Vec<f64>,
    gram: SMatrix<f64, 12, 12>,
    eta: f64,
    /// The lower-right block `C` and its inverse (`None`: the minorant does not fix `t`).
    c: Matrix3<f64>,
    c_inv: Option<Matrix3<f64>>,
    /// `λ_max(C⁻¹)`: the ellipsoid `(t − t*)ᵀ C (t − t*) ≤ slack` reaches `‖t − t*‖ ≤ √(slack λ_max)`.
    c_inv_max: f64,
    /// `bᵢᵀ C⁻¹ bᵢ`: over that ellipsoid `bᵢ · t` moves by at most `√(slack bᵢᵀ C⁻¹ bᵢ)`.
    bearing_spread: Vec<f64>,
    /// [`Whitening::ellipsoid_factor`] of `C`, once it is needed.
    extent: OnceCell<Option<f64>>,
    /// The form minimised over `t`: `min_t Q(R, t) = vec(R)ᵀ S vec(R)` with the Schur complement
    /// `S = A − B C⁻¹ Bᵀ` of the blocks `[A B; Bᵀ C]` (zero when `C` is singular; unused then).
    schur: SMatrix<f64, 9, 9>,
}

impl Minorant {
    /// The minorant for the depth bounds `depths` of the points `points` with the residual maps
    /// `forms` ([`Problem::forms`]): a point's term is `‖Aᵢ (R Xᵢ + t)‖² / Dᵢ²`.
    fn build(points: &[Vector3<f64>], bearings: &[Vector3<f64>], forms: &[PointForm], depths: Vec<f64>) -> Minorant {
        // With z = (vec R, t) (row-major vec), R Xᵢ + t = Lᵢ z, Lᵢ = [I ⊗ Xᵢᵀ, I], a point's term is
        // wᵢ zᵀ Lᵢᵀ Hᵢ Lᵢ z (Hᵢ = AᵢᵀAᵢ), whose blocks are Hᵢ ⊗ XᵢXᵢᵀ, Hᵢ ⊗ Xᵢ and Hᵢ. Both H and
        // XXᵀ are symmetric: six entries each, accumulated by hand (a search rebuilds the minorant
        // about once every ten boxes).
        const PAIRS: [(usize, usize); 6] = [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)];
        let mut outer = [[0.0f64; 6]; 6];
        let mut linear = [[0.0f64; 3]; 6];
        let mut constant = [0.0f64; 6];
        let mut eta2 = 0.0;
        for ((x, form), d) in points.iter().zip(forms).zip(&depths) {
            let w = 1.0 / (d * d);
            eta2 += w * form.norm2 * x.norm_squared();
            let wx = [w * x.x, w * x.y, w * x.z];
            let wxx = PAIRS.map(|(i, j)| wx[i] * x[j]);
            for (k, &(a, b)) in PAIRS.iter().enumerate() {
                let h = form.h[(a, b)];
                for (entry, v) in outer[k].iter_mut().zip(&wxx) {
                    *entry += h * v;
                }
                for (entry, v) in linear[k].iter_mut().zip(&wx) {
                    *entry += h * v;
                }
                constant[k] += h * w;
            }
        }
        let mut gram = SMatrix::<f64, 12, 12>::zeros();
        for (k, &(a, b)) in PAIRS.iter().enumerate() {
            for (l, &(i, j)) in PAIRS.iter().enumerate() {
                // Block (a, b) is Σ w H_ab XXᵀ, and block (b, a) the same (both symmetric).
                for (p, q) in [(a, b), (b, a)] {
                    gram[(3 * p + i, 3 * q + j)] = outer[k][l];
                    gram[(3 * p + j, 3 * q + i)] = outer[k][l];
                }
            }
            for i in 0..3 {
                for (p, q) in [(a, b), (b, a)] {
                    gram[(3 * p + i, 9 + q)] = linear[k][i];
                    gram[(9 + q, 3 * p + i)] = linear[k][i];
                }
            }
            gram[(9 + a, 9 + b)] = constant[k];
            gram[(9 + b, 9 + a)] = constant[k];
        }
        // What the bound of a box needs of `C` (the same for every box that shares the minorant).
        let c = gram.fixed_view::<3, 3>(9, 9).into_owned();
        let c_inv = c.try_inverse();
        Minorant {
            depths,
            gram,
            eta: eta2.sqrt(),
            c,
            c_inv,
            c_inv_max: c_inv.map_or(f64::NAN, |c_inv| largest_eigenvalue(&c_inv)),
            bearing_spread: c_inv.map_or_else(Vec::new, |c_inv| bearings.iter().map(|b| b.dot(&(c_inv * b))).collect()),
            extent: OnceCell::new(),
            schur: c_inv.map_or_else(SMatrix::zeros, |c_inv| {
                let b = gram.fixed_view::<9, 3>(0, 9);
                gram.fixed_view::<9, 9>(0, 0) - b * c_inv * b.transpose()
            }),
        }
    }

    /// The minorant at the rotation `r` as a quadratic in `t`: `tᵀ C t + 2 gᵀ t + c₀` (`C` is
    /// [`Self::c`]).
    fn at(&self, r: &Matrix3<f64>) -> (Vector3<f64>, f64) {
        let v = SMatrix::<f64, 9, 1>::from_fn(|i, _| r[(i / 3, i % 3)]);
        let a = self.gram.fixed_view::<9, 9>(0, 0);
        let b = self.gram.fixed_view::<9, 3>(0, 9);
        let g: Vector3<f64> = b.transpose() * v;
        let c0 = (v.transpose() * a * v)[0];
        (g, c0)
    }
}

/// A minorant for tighter depth bounds without a rebuild: if every weight may grow at least by the
/// factor `κ` (`Dᵢ' ≤ Dᵢ / √κ` for all `i`), then `κ Q` is a minorant for the depth bounds `Dᵢ'`, as
/// every term of `Q` is. `κ Q` is `Q` for the depth bounds `Dᵢ / √κ` ([`Self::depths`]).
#[derive(Clone)]
struct Scaled {
    minorant: Rc<Minorant>,
    scale: f64,
}

impl Scaled {
    /// The depth bounds `Dᵢ / √κ` for which `κ Q` is the minorant.
    fn depths(&self) -> impl Iterator<Item = f64> + Clone + '_ {
        let shrink = self.scale.sqrt();
        self.minorant.depths.iter().map(move |d| d / shrink)
    }

    /// The minorant `κ Q` at the rotation `r`: the minimiser `t*` of `κ Q(r, ·)`, its minimum
    /// `q_min` and `√κ η` (`None` when `Q` does not fix the translation). `C`, `g`, `c₀` and `q_min`
    /// scale by `κ`, `η` by `√κ`; `t*` does not move.
    fn at(&self, r: &Matrix3<f64>) -> Option<(Vector3<f64>, f64, f64)> {
        let c_inv = self.minorant.c_inv?;
        let (g, c0) = self.minorant.at(r);
        let t_star = -(c_inv * g);
        let q_min = (self.scale * (c0 - g.dot(&(c_inv * g)))).max(0.0);
        Some((t_star, q_min, self.minorant.eta * self.scale.sqrt()))
    }

    /// `(e^θ − 1 − θ) √κ η`: over the rotations `exp(φ) r`, `‖φ‖ ≤ θ`, the points' whitened residuals
    /// `√(κ wᵢ) Aᵢ (exp(φ) yᵢ + t)` (`yᵢ = r Xᵢ`) are within this of their part linear in `φ`, in the
    /// norm of the stacked vector: `exp(φ) = I + [φ]ₓ + E` with `‖E y‖ ≤ (e^θ − 1 − θ) ‖y‖`, and
    /// `η² = Σ wᵢ λ_max(Hᵢ) ‖Xᵢ‖²` ([`Self::linear_bound`], [`Problem::linear_lines_bound`]).
    fn second_order_rest(&self, theta: f64) -> f64 {
        rotation_rest(theta) * self.minorant.eta * self.scale.sqrt()
    }

    /// A lower bound of `f` on the poses of `S` whose rotation is within the angle `θ` of `r`, from the
    /// minorant linearised in the rotation (0 when `Q` does not fix the translation). Such a
    /// rotation is `exp(φ) r` with `‖φ‖ ≤ θ`, and `exp(φ) r = r + [φ]ₓ r + E` with
    /// `‖E y‖ ≤ (e^θ − 1 − θ) ‖y‖` (the exponential series from its third term). `√Q` is a seminorm
    /// of `(vec R, t)`, so `√Q(exp(φ) r, t) ≥ √Q(r + [φ]ₓ r, t) − (e^θ − 1 − θ) η`, and the first
    /// term, minimised over `t`, is `√m(φ)` with the convex quadratic
    /// `m(φ) = κ (v + Mφ)ᵀ S (v + Mφ)` (`v = vec r`, `M φ = vec([φ]ₓ r)`, `S` the Schur complement).
    /// Its minimum over the ball `‖φ‖ ≤ θ` is bounded below by the Lagrangian dual
    /// `κ (q₀ − gᵀ (H + λI)⁻¹ g − λ θ²)` at any `λ ≥ 0` with `H + λI` positive definite
    /// (`q₀ = vᵀSv`, `g = MᵀSv`, `H = MᵀSM`); `λ` is found by Newton steps on the secular equation
    /// `‖(H + λI)⁻¹ g‖ = θ`. So `f ≥ ½ (√m_min − (e^θ − 1 − θ) √κ η)₊²`: the rotation's first-order
    /// effect is taken exactly and only the second-order rest costs, where the Minkowski bound
    /// ([`Self::bound_near`]) pays `θ η` for all of it.
    ///
    /// `q_min` is [`Self::at`]'s at `r`: the minimum over the ball is at most that, so the bound is at
    /// most `½ (√q_min − rest)₊²`. Where that is below `wanted` (the level at which the bound would
    /// close the box), nothing is computed and the answer is 0.
    fn linear_bound(&self, r: &Matrix3<f64>, theta: f64, q_min: f64, wanted: f64) -> f64 {
        let rest = self.second_order_rest(theta);
        let ceiling = minkowski(q_min, rest);
        if self.minorant.c_inv.is_none() || ceiling == 0.0 || ceiling < wanted {
            return 0.0;
        }
        let s = &self.minorant.schur;
        let v = SMatrix::<f64, 9, 1>::from_fn(|i, _| r[(i / 3, i % 3)]);
        // Column k of M is vec(eₖ × each column of r): row (i, j) is (eₖ × r₍:,ⱼ₎)ᵢ.
        let m = SMatrix::<f64, 9, 3>::from_fn(|row, k| {
            let (i, j) = (row / 3, row % 3);
            let c = r.column(j);
            match (k, i) {
                (0, 1) => -c.z,
                (0, 2) => c.y,
                (1, 0) => c.z,
                (1, 2) => -c.x,
                (2, 0) => -c.y,
                (2, 1) => c.x,
                _ => 0.0,
            }
        });
        let sv = s * v;
        let q0 = v.dot(&sv);
        let g: Vector3<f64> = m.transpose() * sv;
        let h: Matrix3<f64> = m.transpose() * (s * m);
        let m_min = self.scale * ball_minimum_lower_bound(q0, &g, &h, theta);
        minkowski(m_min.max(0.0), rest)
    }

    /// The Minkowski bound `½ (√q_min − θ η)₊²` of the poses at the rotation `r` and those within the
    /// angle `θ` of it (`−∞` when `Q` does not fix the translation).
    fn bound_near(&self, r: &Matrix3<f64>, theta: f64) -> f64 {
        self.at(r)
            .map_or(f64::NEG_INFINITY, |(_, q_min, eta)| minkowski(q_min, theta * eta))
    }

    /// What a box whose poses of `S` keep the points within `reach` hands down: the depth bounds
    /// `min(reachᵢ, Dᵢ / √κ)`, met by the scale that takes up the least growth of the weights, or
    /// by a rebuilt minorant when the weights grow on average by [`REBUILD_GAIN`] more than that.
    /// (`reach` is read twice when the minorant is rebuilt, and is not stored otherwise.)
    ///
    /// A rebuilt minorant weighs most the points that came closest: that raises `q_min` but also `η`,
    /// and where one point came much closer than the others it can weaken the bound. The rebuilt
    /// minorant is handed down only where it bounds at least as well at the box's centre rotation
    /// `r_c` over the octants' half-diagonal `θ_octant` (both are valid minorants).
    fn tightened(
        &self,
        problem: &Problem,
        reach: impl Iterator<Item = f64> + Clone,
        r_c: &Matrix3<f64>,
        theta_octant: f64,
    ) -> Scaled {
        // A weight grows by (Dᵢ / √κ)² / reachᵢ² where the reach is the tighter bound, else by 1.
        let (least, sum) =
            (self.minorant.depths.iter().zip(reach.clone())).fold((f64::INFINITY, 0.0), |(least, sum), (d, r)| {
                let (d2, r2) = (d * d, self.scale * r * r);
                let growth = if r2 < d2 { d2 / r2 } else { 1.0 };
                (least.min(growth), sum + growth)
            });
        let mean = sum / self.minorant.depths.len() as f64;
        let scaled = Scaled {
            minorant: Rc::clone(&self.minorant),
            scale: self.scale * least.max(1.0),
        };
        if mean < REBUILD_GAIN * least {
            return scaled;
        }
        let rebuilt = Scaled {
            minorant: Rc::new(problem.minorant(self.depths().zip(reach).map(|(d, r)| r.min(d)).collect())),
            scale: 1.0,
        };
        if rebuilt.bound_near(r_c, theta_octant) >= scaled.bound_near(r_c, theta_octant) {
            rebuilt
        } else {
            scaled
        }
    }
}

/// A lower bound of `min q₀ + 2 gᵀφ + φᵀHφ` over the ball `‖φ‖ ≤ θ` (`H` positive semidefinite): the
/// Lagrangian dual `q₀ − gᵀ (H + λI)⁻¹ g − λ θ²`, which bounds the minimum from below at every
/// `λ ≥ 0` where `H + λI` is positive definite (weak duality), at the `λ` of a few Newton steps on
/// the secular equation `1/‖p(λ)‖ = 1/θ`, `p(λ) = (H + λI)⁻¹ g` (the dual's maximiser when the
/// constraint is active; `λ = 0` when the unconstrained minimiser lies in the ball). Lowered by a
/// relative `1e-9` of its terms for rounding; `−∞` when no `λ` tried makes `H + λI` definite.
fn ball_minimum_lower_bound(q0: f64, g: &Vector3<f64>, h: &Matrix3<f64>, theta: f64) -> f64 {
    let dual = |lambda: f64| -> Option<(f64, Vector3<f64>, f64)> {
        let chol = (h + Matrix3::identity() * lambda).cholesky()?;
        let p = chol.solve(g);
        let gp = g.dot(&p);
        if !(gp >= 0.0 && gp.is_finite()) {
            return None;
        }
        let value = q0 - gp - lambda * theta * theta;
        let rounding = 1e-9 * (q0.abs() + gp + lambda * theta * theta);
        // pᵀ (H + λI)⁻¹ p, for the Newton step.
        let curvature = p.dot(&chol.solve(&p));
        Some((value - rounding, p, curvature))
    };
    // Positive definite from the start: a tiny multiple of the trace (H is only semidefinite).
    let mut lambda = 1e-12 * h.trace().max(f64::MIN_POSITIVE);
    let mut best = f64::NEG_INFINITY;
    for _ in 0..NEWTON_STEPS {
        let Some((value, p, curvature)) = dual(lambda) else {
            break;
        };
        best = best.max(value);
        let norm = p.norm();
        if norm <= theta || !(curvature > 0.0) {
            break;
        }
        // Newton on 1/‖p(λ)‖ − 1/θ (Moré & Sorensen): increases λ monotonically towards the root.
        lambda += (norm * norm / curvature) * (norm - theta) / theta;
    }
    best
}

/// `½ (√q − rest)₊²`: a lower bound of `½ ‖v‖²` for every `v` within `rest` of a vector whose norm is
/// at least `√q` (Minkowski), the form of every box bound of the rotation search.
fn minkowski(q: f64, rest: f64) -> f64 {
    0.5 * (q.sqrt() - rest).max(0.0).powi(2)
}

/// `e^θ − 1 − θ`: `‖(exp(φ) − I − [φ]ₓ) y‖ ≤ (e^θ − 1 − θ) ‖y‖` for `‖φ‖ ≤ θ` (the exponential series
/// from its third term, `‖[φ]ₓᵏ y‖ ≤ θᵏ ‖y‖`).
fn rotation_rest(theta: f64) -> f64 {
    theta.exp() - 1.0 - theta
}

/// At most this many segment endpoints, those of the largest rates, are bounded apart in step 4's
/// curvature bound ([`RayCurvature::bound_with_parts`]; splits after 1, 2, 4, ... of them).
const APART_ENDPOINTS: usize = 16;

/// Newton steps of [`ball_minimum_lower_bound`] (every step's dual value is a valid bound).
const NEWTON_STEPS: usize = 8;

/// One box of rotation vectors `ω` (`R = exp(ω) R̂`): centre and half-widths. Every rotation of the
/// box is within the angle `θ = ‖half‖` (half the diagonal) of the centre's: the angle between
/// `exp(ω) R̂` and `exp(ω_c) R̂` is at most `‖ω − ω_c‖` (Hartley & Kahl 2009, lemma 1).
#[derive(Clone, Copy)]
struct Cell {
    centre: Vector3<f64>,
    half: Vector3<f64>,
}

impl Cell {
    fn of(region: &Region) -> Self {
        // Element by element: a slice copy of three numbers would call memcpy for every box.
        let (l, u) = (&region.lower, &region.upper);
        let lower = Vector3::new(l[0], l[1], l[2]);
        let upper = Vector3::new(u[0], u[1], u[2]);
        Cell {
            centre: (lower + upper) * 0.5,
            half: (upper - lower) * 0.5,
        }
    }
}

/// The local metric `‖Δ‖_W = √(Δᵀ W Δ)`, `W = JᵀJ` at `R̂, t̂` in the chart `(ω, τ) ↦ (exp(ω) R̂, t̂ + τ)`:
/// a whitened step `δ` is the chart step `Δ = T δ`, `T = V Λ^(-1/2)` from `W = V Λ Vᵀ`, so that the
/// linearised residual moves by one pixel per unit of `‖δ‖` in every direction.
struct Whitening {
    w: SMatrix<f64, 6, 6>,
    t: SMatrix<f64, 6, 6>,
    /// Largest rotation and translation per unit whitened step: `‖T_ω‖`, `‖T_τ‖` (row blocks).
    alpha_omega: f64,
    alpha_tau: f64,
}

impl Whitening {
    fn new(w: &SMatrix<f64, 6, 6>) -> Option<Self> {
        let eigen = w.symmetric_eigen();
        if !eigen.eigenvalues.iter().all(|l| l.is_finite() && *l > 0.0) {
            return None;
        }
        let scale = SMatrix::<f64, 6, 6>::from_diagonal(&eigen.eigenvalues.map(|l| 1.0 / l.sqrt()));
        let t = eigen.eigenvectors * scale;
        let block_norm = |rows: usize| t.fixed_view::<3, 6>(rows, 0).into_owned().singular_values().max();
        Some(Whitening {
            w: *w,
            alpha_omega: block_norm(0),
            alpha_tau: block_norm(3),
            t,
        })
    }

    /// The largest whitened length `√(sᵀ W_ωω s)` of a rotation step `s` in the box of half-widths
    /// `half` around 0: a convex function peaks at a vertex, and `±s` give the same length.
    fn box_spread(&self, half: &Vector3<f64>) -> f64 {
        let w = self.w.fixed_view::<3, 3>(0, 0);
        [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)]
            .iter()
            .map(|&(b, c)| {
                let s = half.component_mul(&Vector3::new(1.0, b, c));
                (s.transpose() * w * s)[0]
            })
            .fold(0.0f64, f64::max)
            .sqrt()
    }

    /// `‖Δ‖_W` of the chart step `(ω, τ)`.
    fn length(&self, omega: &Vector3<f64>, tau: &Vector3<f64>) -> f64 {
        let d = SVector::<f64, 6>::new(omega.x, omega.y, omega.z, tau.x, tau.y, tau.z);
        (d.transpose() * self.w * d)[0].max(0.0).sqrt()
    }

    /// The largest `‖(0, τ)‖_W` over the ellipsoid `τᵀ C τ ≤ slack` is `√(slack λ)`, with this
    /// `λ = λ_max(L⁻¹ W_ττ L⁻ᵀ)` and `C = L Lᵀ`.
    fn ellipsoid_factor(&self, c: &Matrix3<f64>) -> Option<f64> {
        let l_inv = c.cholesky()?.l().try_inverse()?;
        let w_tt = self.w.fixed_view::<3, 3>(3, 3).into_owned();
        Some(largest_eigenvalue(&(l_inv * w_tt * l_inv.transpose())))
    }
}

/// The largest eigenvalue of a symmetric 3x3 matrix, in closed form (trigonometric solution of the
/// characteristic cubic), raised by a relative `1e-9` to cover its rounding.
fn largest_eigenvalue(m: &Matrix3<f64>) -> f64 {
    let q = m.trace() / 3.0;
    let off = m[(0, 1)].powi(2) + m[(0, 2)].powi(2) + m[(1, 2)].powi(2);
    let p2 = (m[(0, 0)] - q).powi(2) + (m[(1, 1)] - q).powi(2) + (m[(2, 2)] - q).powi(2) + 2.0 * off;
    let p = (p2 / 6.0).sqrt();
    if !(p > 1e-300) {
        return q + q.abs() * 1e-9;
    }
    let b = (m - Matrix3::identity() * q) / p;
    let phi = (0.5 * b.determinant()).clamp(-1.0, 1.0).acos() / 3.0;
    let lambda = q + 2.0 * p * phi.cos();
    lambda + 1e-9 * (lambda.abs() + p)
}

/// What the test hook [`testing::rotation_search`] records: the cells kept, the cells pruned, and the
/// half-width at which cells stop being split.
struct Record {
    min_half: f64,
    cells: Vec<testing::KeptCell>,
    pruned: usize,
    behind: Vec<testing::KeptCell>,
}

impl Record {
    /// Nothing recorded yet; cells stop being split at `min_half`.
    fn new(min_half: f64) -> Self {
        Record {
            min_half,
            cells: vec![],
            pruned: 0,
            behind: vec![],
        }
    }
}

/// Step 4's bound for the cells inside the ball: the local bound over the ball of the largest cell
/// radius met so far (it holds the cell, so the bound is valid for it), recomputed only when a cell
/// reaches farther; over the ball of the target radius where that cannot be computed.
struct BallBound<'m> {
    model: &'m LocalModel<'m>,
    /// The radius and raw bound last computed (`radius` 0 before the first cell).
    radius: f64,
    bound: f64,
    /// The raw bound over the ball of the target radius (every cell inside the ball lies in it).
    at_target: f64,
}

impl BallBound<'_> {
    /// A valid lower bound of `f` over the whitened ball of `radius` (at most the target). Through a
    /// lens, the target's (it already closes the gap; a smaller ball's would cost its enclosures of
    /// the distortion's variation again).
    fn at(&mut self, radius: f64) -> f64 {
        if self.model.lens.is_some() {
            return self.at_target;
        }
        if radius > self.radius {
            match self.model.raw_bound(radius, None) {
                Some(bound) => (self.radius, self.bound) = (radius, bound),
                None => return self.at_target,
            }
        }
        self.bound
    }
}

/// What becomes of a cell inside the whitened ball of the target radius.
enum InsideBall<'m> {
    /// The certificate: the cell's bound is step 4's over the ball ([`BallBound`]).
    Bound(BallBound<'m>),
    /// The test hook: the cell is recorded and closed at the level `f̂` (no bound is claimed, and the
    /// hook reports none). So are cells split down to the hook's `min_half`.
    Record(&'m mut Record),
}

/// Steps 1-3 of the module documentation as a [`BoundingOracle`] of the shared branch and bound,
/// over boxes of rotation vectors `ω` (`R = exp(ω) R̂`) inside `[−π, π]³`. The incumbent is the local
/// answer `(R̂, t̂)` of cost `f̂`; there are no other candidates.
///
/// The bound of a box with half-diagonal `θ`, centre rotation `R_c` and minorant `Q` at `R_c` (for
/// the box's depth bounds `Dᵢ`, valid where `‖xᵢ‖ ≤ Dᵢ`, i.e. on `S`): a pose of `S` in the box has
/// `√(2f) ≥ √Q_{R}(t) ≥ √q_min − θ η` (Minkowski, `q_min = min_t Q`), so `f ≥ ½ (√q_min − θ η)₊²` on
/// the poses of `S` in the box, and every other pose has `f > f̂`. That bound is handed to the search
/// unclamped: a box with bound `≥ f̂` holds no pose of `S` and is pruned, and the least bound over
/// the leaves (at most `f̂`, the cost of the box holding the answer) is the certificate's raw bound.
/// A box where some point is behind the camera for every `t` of the translation ellipsoid
/// `Q(t) ≤ (√(2f̂) + θ η)²` (which holds the translation of every pose of `S` in the box) is empty of
/// `S`; so is a box wholly outside the ball `‖ω‖ ≤ π`, whose rotations are met elsewhere. A box inside
/// the whitened ball of radius `target` is bounded by step 4 as well ([`InsideBall`]).
///
/// What a box hands down to its octants ([`BoundingOracle::Inherited`]) are its depth bounds: the
/// largest distance each point reaches over its poses of `S`,
/// `‖R X + t‖ ≤ ‖R_c X + t*‖ + θ ‖X‖ + ‖t − t*‖` with `t` in the ellipsoid, capped by its own `Dᵢ`.
/// They hold on every pose of `S` in the box, so in each octant, and tighten the octants' minorants
/// ([`Scaled`]).
struct RotationSearch<'a, 'c> {
    problem: &'a Problem<'c>,
    whitening: &'a Whitening,
    pose: &'a Pose,
    f_hat: f64,
    target: f64,
    max_relative_gap: f64,
    /// The slack of a lens's surrogate (`lens`): the boxes are bounded, and `f_hat` is a level, of
    /// the surrogate; step 4's bounds, of the cost, enter through [`Slack::to_surrogate`].
    slack: Slack,
    inside_ball: InsideBall<'a>,
    /// Whether the box bound with segments tries the rotation's linearisation
    /// ([`Problem::linear_lines_bound`]) where its Minkowski bound falls short. Not through a lens:
    /// there it cost more than it saved on every 50-point + 50-segment row of `bench/profile_pose.py`
    /// (the strong OPENCV lens at f = 800 / 4000 / 15000 px: median 25 / 5.4 / 10 ms → 31 / 8.4 /
    /// 20 ms for about the same nodes), where without a lens it halves the time at f = 250-800 px.
    linearise_lines: bool,
    /// The largest whitened radius `‖(ω, t − t̂)‖_W` of the boxes found inside the ball.
    radius: f64,
}

impl BoundingOracle for RotationSearch<'_, '_> {
    type Candidate = ();
    /// The minorant for the depth bounds of the box's poses of `S`, or the ball of their translations
    /// (`None`: the root's).
    type Inherited = Option<Handed>;

    fn bound(&mut self, region: &Region) -> Bound<()> {
        self.bound_with(region, &None).0
    }

    fn absolute_gap(&self) -> f64 {
        self.max_relative_gap * CERTIFICATE_COST_FLOOR
    }

    /// The eight octants of the box (every axis cut at its midpoint): boxes stay cubes.
    fn subdivide(&self, region: &Region, _relaxed_minimizer: Option<&[f64]>) -> SubRegions {
        let (lo, hi) = (&region.lower, &region.upper);
        let mid = [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])];
        // Corners built in place (a clone of the parent's would cost more than the bound of a box).
        let corner = |pick: [f64; 3]| Corner::from_buf_and_len([pick[0], pick[1], pick[2], 0.0], 3);
        (0..8)
            .map(|octant: usize| {
                let upper_half = |k: usize| octant >> k & 1 == 1;
                let lower = std::array::from_fn(|k| if upper_half(k) { mid[k] } else { lo[k] });
                let upper = std::array::from_fn(|k| if upper_half(k) { hi[k] } else { mid[k] });
                Region {
                    lower: corner(lower),
                    upper: corner(upper),
                }
            })
            .collect()
    }

    fn bound_with(&mut self, region: &Region, inherited: &Option<Handed>) -> (Bound<()>, Option<Handed>) {
        let cell = Cell::of(region);
        // The box's nearest point to the origin: boxes wholly outside the ball ‖ω‖ ≤ π repeat rotations.
        let nearest = cell.centre.zip_map(&cell.half, |c, h| (c.abs() - h).max(0.0)).norm();
        if nearest > std::f64::consts::PI {
            return (Bound::Empty { solver_iterations: 0 }, None);
        }
        let r_c = exp_so3(&cell.centre) * self.pose.rotation;
        match (&self.problem.start, inherited) {
            (Start::Points(_), Some(Handed::Minorant(scaled))) => self.points_box(&cell, &r_c, scaled),
            (Start::Points(root), _) => {
                let root = Scaled {
                    minorant: Rc::clone(root),
                    scale: 1.0,
                };
                self.points_box(&cell, &r_c, &root)
            }
            (Start::Ball { pivot, distance }, inherited) => {
                // The translations of the box's poses of S: t = P − R c with ‖P‖ ≤ distance, and those
                // of the parent's ball; the smaller ball is kept.
                let from_pivot = Translations::round(-(r_c * pivot), distance + cell.half.norm() * pivot.norm());
                let ball = match inherited {
                    Some(Handed::Translations(ball)) if ball.shape.trace() <= from_pivot.shape.trace() => ball.clone(),
                    _ => from_pivot,
                };
                self.ball_box(&cell, &r_c, ball)
            }
        }
    }
}

/// What a box hands down to its octants ([`BoundingOracle::Inherited`]).
#[derive(Clone)]
enum Handed {
    /// The minorant for the depth bounds of the box's poses of `S` ([`Start::Points`]).
    Minorant(Scaled),
    /// An ellipsoid that holds the translations of the box's poses of `S` ([`Start::Ball`]).
    Translations(Translations),
}

#[cfg(test)]
impl Handed {
    /// The minorant handed down (the unit tests of the search with depth bounds).
    fn minorant(&self) -> &Scaled {
        match self {
            Handed::Minorant(scaled) => scaled,
            Handed::Translations(_) => panic!("translations, not a minorant"),
        }
    }
}

/// A box's bound, with no candidate.
fn bounded(lower: f64) -> Bound<()> {
    Bound::Bounded {
        lower,
        relaxed_minimizer: None,
        candidate: None,
        solver_iterations: 0,
    }
}

impl RotationSearch<'_, '_> {
    /// The box's bound `lower` when it proves the box empty of `S` (`lower ≥ f̂`): the search prunes it.
    fn pruned(&mut self, lower: f64) -> Option<Bound<()>> {
        if lower < self.f_hat {
            return None;
        }
        if let InsideBall::Record(r) = &mut self.inside_ball {
            r.pruned += 1;
        }
        Some(bounded(lower))
    }

    /// The bound of a box that is not split further: one inside the whitened ball of the target
    /// radius (step 4's bound joins `lower`), or, for the test hook, one at its least half-width.
    /// The box's poses of `S` have their translations within `extent` (in the local metric) of `t_star`
    /// (computed only for boxes near the answer). `None`: the box is split.
    fn settled(
        &mut self,
        cell: &Cell,
        lower: f64,
        t_star: &Vector3<f64>,
        extent: impl FnOnce() -> Option<f64>,
        kept: impl Fn(bool) -> testing::KeptCell,
    ) -> Option<Bound<()>> {
        // Whitened radius of the box: centre, rotation spread and translation ellipsoid (triangle
        // inequality over the three parts of the step).
        if cell.centre.norm() + cell.half.norm() <= 1.0 {
            if let Some(extent) = extent() {
                let radius = self.whitening.length(&cell.centre, &(t_star - self.pose.translation))
                    + self.whitening.box_spread(&cell.half)
                    + extent;
                if radius <= self.target {
                    self.radius = self.radius.max(radius);
                    let lower = match &mut self.inside_ball {
                        InsideBall::Bound(ball) => lower.max(self.slack.to_surrogate(ball.at(radius))),
                        InsideBall::Record(r) => {
                            r.cells.push(testing::KeptCell {
                                extent: Some(extent),
                                ..kept(true)
                            });
                            self.f_hat
                        }
                    };
                    return Some(bounded(lower));
                }
            }
        }
        if let InsideBall::Record(r) = &mut self.inside_ball {
            if cell.half.max() <= r.min_half {
                r.cells.push(kept(false));
                return Some(bounded(self.f_hat));
            }
        }
        None
    }

    /// The bound of a box with step 1's depth bounds ([`Start::Points`]; [`RotationSearch`]).
    fn points_box(&mut self, cell: &Cell, r_c: &Matrix3<f64>, scaled: &Scaled) -> (Bound<()>, Option<Handed>) {
        let problem = self.problem;
        let (minorant, scale) = (&scaled.minorant, scaled.scale);
        let theta = cell.half.norm();
        let Some((t_star, q_min, eta)) = scaled.at(r_c) else {
            return (
                Bound::Failed { solver_iterations: 0 },
                Some(Handed::Minorant(scaled.clone())),
            );
        };
        // The Minkowski bound, and the linearised one where the first falls short of f̂ and the
        // second could close the box.
        let by_minkowski = minkowski(q_min, theta * eta);
        let lower = if by_minkowski < self.f_hat {
            let wanted = self.f_hat * (1.0 - self.max_relative_gap);
            by_minkowski.max(scaled.linear_bound(r_c, theta, q_min, wanted))
        } else {
            by_minkowski
        };
        // The ellipsoid Q(t) ≤ β² holds the translations of the box's poses of S (slack ≥ 0 where
        // lower < f̂, up to rounding): they are within `spread` of t*.
        let beta = (2.0 * self.f_hat).sqrt() + theta * eta;
        let slack = (beta * beta - q_min).max(0.0);
        let slack_per_scale = slack / scale;
        let spread = (slack_per_scale * minorant.c_inv_max).max(0.0).sqrt();
        // The segments' residuals added to the minorant, where the points' alone fall short.
        let with_lines = if lower < self.f_hat && problem.box_segments > 0 && !problem.lines.is_empty() {
            let wanted = self
                .linearise_lines
                .then_some(self.f_hat * (1.0 - self.max_relative_gap));
            problem.lines_bound(
                scaled,
                r_c,
                theta,
                (&t_star, q_min),
                spread,
                problem.box_segments,
                wanted,
            )
        } else {
            None
        };
        let lower = with_lines.as_ref().map_or(lower, |l| lower.max(l.lower));
        // The translations of the box's poses of S lie in the points' ellipsoid and in the one with
        // the segments: the one with the lesser reach is kept.
        let points_ellipsoid = Ellipsoid {
            centre: t_star,
            c: minorant.c * scale,
            slack,
            spread,
            with_segments: false,
        };
        let ellipsoid = match &with_lines {
            Some(l) => match l.ellipsoid(self.f_hat, theta) {
                (slack, spread) if spread < points_ellipsoid.spread => Ellipsoid {
                    centre: l.t_star,
                    c: l.c,
                    slack,
                    spread,
                    with_segments: true,
                },
                _ => points_ellipsoid,
            },
            None => points_ellipsoid,
        };
        if !lower.is_finite() {
            return (
                Bound::Failed { solver_iterations: 0 },
                Some(Handed::Minorant(scaled.clone())),
            );
        }
        if let Some(pruned) = self.pruned(lower) {
            return (pruned, None);
        }
        let kept = |inside_ball: bool, ellipsoid: &Ellipsoid| testing::KeptCell {
            centre: cell.centre,
            half: cell.half,
            t_star: ellipsoid.centre,
            c: ellipsoid.c,
            slack: ellipsoid.slack,
            inside_ball,
            depths: scaled.depths().collect(),
            with_segments: ellipsoid.with_segments,
            extent: None,
        };
        // Cheirality: a point behind the camera for every rotation of the box and t of the ellipsoid.
        // (Only a point with `b · (R_c x + t*) ≤ −θ ‖x‖` can be: the ellipsoid's term is not negative.)
        let (axis, reach, largest) = problem.bearing_cone;
        let surely_in_front = axis.dot(&t_star) - reach * t_star.norm() > largest;
        let behind = !surely_in_front
            && (problem.corr.points3d.iter().zip(&problem.bearings))
                .zip(problem.norms.iter().zip(&minorant.bearing_spread))
                .any(|((x, b), (norm, spread))| {
                    let depth = b.dot(&(r_c * x + t_star));
                    depth <= -theta * norm && depth + (slack_per_scale * spread).max(0.0).sqrt() <= -theta * norm
                });
        if behind {
            if let InsideBall::Record(r) = &mut self.inside_ball {
                r.pruned += 1;
                // The test above is on the points' ellipsoid.
                r.behind.push(kept(false, &points_ellipsoid));
            }
            return (Bound::Empty { solver_iterations: 0 }, None);
        }
        let extent = || {
            if ellipsoid.with_segments {
                self.whitening.ellipsoid_factor(&ellipsoid.c)
            } else {
                // The points' C is the minorant's times `scale`: its factor once per minorant.
                let factor = minorant
                    .extent
                    .get_or_init(|| self.whitening.ellipsoid_factor(&minorant.c));
                factor.map(|lambda| lambda / scale)
            }
            .map(|lambda| (ellipsoid.slack * lambda).max(0.0).sqrt())
        };
        if let Some(bound) = self.settled(cell, lower, &ellipsoid.centre, extent, |inside| {
            kept(inside, &ellipsoid)
        }) {
            return (bound, None);
        }
        // The depth bounds the octants inherit, and the minorant for them (else the octants share
        // this box's).
        let reach = (problem.corr.points3d.iter().zip(&problem.norms))
            .map(|(x, norm)| (r_c * x + ellipsoid.centre).norm() + theta * norm + ellipsoid.spread);
        let handed_down = scaled.tightened(problem, reach, r_c, 0.5 * theta);
        (bounded(lower), Some(Handed::Minorant(handed_down)))
    }

    /// The bound of a box without depth bounds ([`Start::Ball`]) whose poses of `S` have their
    /// translations in `ball`: `Q` the minorant at `R_c` ([`Problem::ball_quadratic`]), a pose of `S`
    /// in the box has `√(2f) ≥ √q_min − θ η` (Minkowski, as with depth bounds), and its translation
    /// lies in the ellipsoid `Q(t) ≤ (√(2f̂) + θ η)²`, whose bounding ball the octants inherit where it
    /// is smaller than `ball`.
    fn ball_box(&mut self, cell: &Cell, r_c: &Matrix3<f64>, ball: Translations) -> (Bound<()>, Option<Handed>) {
        let theta = cell.half.norm();
        let segments = self.problem.segments_in(cell);
        let Some(BoxBound {
            lower,
            t_star,
            c,
            c_inv,
            slack,
            depths,
            ..
        }) = self.problem.ball_bound(segments, r_c, theta, &ball, self.f_hat)
        else {
            // The terms do not fix the translation: no bound, the octants are bounded again.
            return (bounded(0.0), Some(Handed::Translations(ball)));
        };
        if !lower.is_finite() {
            return (Bound::Failed { solver_iterations: 0 }, Some(Handed::Translations(ball)));
        }
        if let Some(pruned) = self.pruned(lower) {
            return (pruned, None);
        }
        let kept = |inside_ball: bool| testing::KeptCell {
            centre: cell.centre,
            half: cell.half,
            t_star,
            c,
            slack,
            inside_ball,
            depths: depths.clone(),
            with_segments: true,
            extent: None,
        };
        let extent = || {
            self.whitening
                .ellipsoid_factor(&c)
                .map(|lambda| (slack * lambda).max(0.0).sqrt())
        };
        // Cheirality: an object point or segment endpoint behind the camera (z ≤ 0) for every rotation
        // of the box and translation of the ellipsoid, whose largest t_z is t*_z + √(slack (C⁻¹)_zz).
        let t_z = t_star.z + (slack * c_inv[(2, 2)]).max(0.0).sqrt();
        let behind = (self.problem.corr.points3d.iter())
            .chain(self.problem.corr.lines3d.iter().flatten())
            .any(|x| (r_c * x).z + theta * x.norm() + t_z <= 0.0);
        if behind {
            if let InsideBall::Record(r) = &mut self.inside_ball {
                r.pruned += 1;
                r.behind.push(kept(false));
            }
            return (Bound::Empty { solver_iterations: 0 }, None);
        }
        if let Some(bound) = self.settled(cell, lower, &t_star, extent, kept) {
            return (bound, None);
        }
        // Of two ellipsoids that hold the translations, the one of least trace.
        let shape = c_inv * slack;
        let handed_down = if shape.trace() < ball.shape.trace() {
            Translations {
                centre: t_star,
                radius: largest_eigenvalue(&shape).max(0.0).sqrt(),
                shape,
            }
        } else {
            ball
        };
        (bounded(lower), Some(Handed::Translations(handed_down)))
    }
}

/// What the rotation search proved.
struct Localised {
    /// The least bound over the leaves of the search (unclamped; `+∞` when every box was proved
    /// empty of `S`).
    raw_lower_bound: f64,
    /// The largest whitened radius of the boxes inside the ball (0 when there is none).
    radius: f64,
    nodes: usize,
}

/// Runs `search` on the shared branch and bound from the root box `[−π, π]³` with the incumbent
/// `f̂`, until the gap closes (`Err` when it reaches `max_nodes` or is stopped).
/// Runs the rotation search; `Err` says why nothing is proved and how many boxes it bounded.
fn localise(search: &mut RotationSearch, max_nodes: usize) -> std::result::Result<Localised, (String, usize)> {
    let pi = std::f64::consts::PI;
    let root = Region::new(vec![-pi; 3], vec![pi; 3]);
    let opts = BranchAndBoundOptions {
        max_relative_gap: search.max_relative_gap,
        max_nodes,
        // f = ½ Σ r² ≥ 0.
        trivial_lower_bound: 0.0,
    };
    // A stop requested before the search ends it before its first box (the search polls it before
    // every split; exact data can close the gap at the root).
    let stopped = |reason: StopReason| format!("not proved: {} during the rotation search", reason.describe());
    if let Some(reason) = stop_reason() {
        return Err((stopped(reason), 0));
    }
    let result = branch_and_bound(search, root, Some((search.f_hat, ())), &opts);
    if let Some(reason) = result.stopped {
        return Err((stopped(reason), result.nodes));
    }
    if !result.converged {
        return Err((
            format!("not proved: the rotation search reached max_nodes = {max_nodes}"),
            result.nodes,
        ));
    }
    Ok(Localised {
        raw_lower_bound: result.box_lower_bound,
        radius: search.radius,
        nodes: result.nodes,
    })
}

/// [`Problem::bearing_cone`] (an empty cone, `δ = ∞`, without points or where the bearings' mean
/// vanishes).
fn bearing_cone(bearings: &[Vector3<f64>], points: &[Vector3<f64>]) -> (Vector3<f64>, f64, f64) {
    let Some(axis) = bearings.iter().sum::<Vector3<f64>>().try_normalize(1e-12) else {
        return (Vector3::z(), f64::INFINITY, 0.0);
    };
    let reach = bearings.iter().map(|b| (b - axis).norm()).fold(0.0, f64::max);
    (axis, reach, points.iter().map(|x| x.norm()).fold(0.0, f64::max))
}

/// `M` with `aᵀ M a = (a × (a × y)) · c = (a·y)(a·c) − (a·a)(y·c)`.
fn double_cross_form(y: &Vector3<f64>, c: &Vector3<f64>) -> Matrix3<f64> {
    0.5 * (y * c.transpose() + c * y.transpose()) - Matrix3::identity() * y.dot(c)
}

/// `P` with `P (a_ω, a_τ) = a_ω × y + a_τ`, the velocity of a point `R y + t` along a chart step.
fn tangent_map(y: &Vector3<f64>) -> SMatrix<f64, 3, 6> {
    let mut p = SMatrix::<f64, 3, 6>::zeros();
    p.fixed_view_mut::<3, 3>(0, 0).copy_from(&(-skew(y)));
    p.fixed_view_mut::<3, 3>(0, 3).copy_from(&Matrix3::identity());
    p
}

/// A bound on `|n'''|` along whitened rays of length `s` from an endpoint's sight: with `X` one end
/// of the segment (`‖R̂ X‖ = y`), `u = ē × X` (`‖u(0)‖ = cross`, `max ‖u'(0)‖ = speed` per unit step)
/// and `D = B − A` (`‖D‖ = length`, `D⁽ᵏ⁾ = a_ω × D⁽ᵏ⁻¹⁾`), `n = ēᵀ (A × B) = Dᵀ u` and by Leibniz
/// `n''' = D'''ᵀ u + 3 D''ᵀ u' + 3 D'ᵀ u'' + Dᵀ u'''` (one piece each), with `‖u''‖ ≤ ‖ē‖ α_ω² y`, `‖u'''‖ ≤ ‖ē‖ α_ω³ y`.
/// `u` and `u'` see only the motion across the sight, so a step along it (the depth) costs nothing.
fn sight_parts(a_w: f64, length: f64, e_norm: f64, y: f64, cross: f64, speed: f64, s: f64) -> testing::SightParts {
    // ‖u'‖ grows by at most ‖ē‖ ‖X''‖ ≤ ‖ē‖ α_ω² y per unit of s.
    let speed = speed + s * e_norm * a_w * a_w * y;
    testing::SightParts {
        speed,
        pieces: [
            a_w.powi(3) * length * (cross + s * speed),
            3.0 * a_w * a_w * length * speed,
            3.0 * a_w.powi(3) * length * e_norm * y,
            a_w.powi(3) * length * e_norm * y,
        ],
    }
}

/// `sup |x'|` on `[0, s]` for `|x''| ≤ d + c |x'|`, `|x'(0)| ≤ x0` (Grönwall).
fn gronwall(x0: f64, d: f64, c: f64, s: f64) -> f64 {
    if c > 0.0 {
        (x0 + d / c) * (c * s).exp() - d / c
    } else {
        x0 + d * s
    }
}

/// A point's part of `RayCurvature`: what does not depend on the radius.
struct PointRay {
    /// `‖y‖ = ‖R̂ X‖` and the camera-frame point `p = y + t̂`.
    y_norm: f64,
    p: Vector3<f64>,
    /// `‖e_zᵀ P T‖`: the largest depth rate at `s = 0` per unit whitened step.
    depth_rate: f64,
    /// `gᵀ g` of the residual's whitened gradient `g = W K₂ Dπ P T` (2x6), and `‖W K₂‖`.
    gram: SMatrix<f64, 6, 6>,
    map_norm: f64,
    /// `‖g‖₂` (up to rounding, above): the residual's own rate at `s = 0` per unit whitened step.
    rate: f64,
}

/// A line endpoint's part of `RayCurvature`: its residual is `n / w` with `n = ēᵀ m` and
/// `w = ‖G_e m_xy‖` ([`Problem::endpoint_maps`]).
struct EndpointRay {
    /// `w₀ = ‖G_e m_xy‖`, `‖G_e‖`, `‖G_e N(0)_xy T‖` and `|w'(0)|` per unit whitened step.
    w0: f64,
    g_norm: f64,
    q1_0: f64,
    w1_0: f64,
    /// `ē = K⁻¹ ẽ`, its norm, `‖B × ē‖` and `‖ē × A‖`.
    e_norm: f64,
    cross_b: f64,
    cross_a: f64,
    /// `‖[ē]× P_A T‖` and `‖[ē]× P_B T‖`: the largest `‖ē × A'(0)‖`, `‖ē × B'(0)‖` per unit whitened
    /// step. Far smaller than `‖ē‖ ‖A'‖` where the step moves the endpoint along its sight
    /// (the depth, poorly determined in a narrow field of view).
    sight_speed: [f64; 2],
    /// Residual and whitened gradient norm at `s = 0`, and `gᵀ g`.
    r0: f64,
    slope0: f64,
    gram: SMatrix<f64, 6, 6>,
    /// `max |vᵀ Tᵀ H T v|` over unit `v`: the exact `|n''(0)|`.
    n2_exact: f64,
}

/// A line's part of `RayCurvature`.
struct LineRay {
    /// `‖y_A‖`, `‖y_B‖`, `‖A‖`, `‖B‖`, the segment length.
    ya: f64,
    yb: f64,
    a: f64,
    b: f64,
    length: f64,
    endpoints: [EndpointRay; 2],
}

/// Step 4's curvature bound: `K` with `‖r''(s)‖ ≤ K` along every whitened ray `s ↦ x̂ + s T v`
/// (`‖v‖ = 1`, `s ≤ radius`), from data prepared once per pose ([`RayCurvature::new`]) and evaluated
/// per radius ([`RayCurvature::bound`]).
///
/// Along a ray the rotation is the one-parameter group `exp(s a_ω) R̂` (`a = T v`), so a camera-frame
/// point moves as `p' = a_ω × R_s y + a_τ`, `p'' = a_ω × (a_ω × R_s y)`. For a point residual
/// `r = W K₂ π(p)`, `D²π[p', p'] = −2 (p'_z / p_z) Dπ[p']`, hence `r'' = W K₂ Dπ[p''] − 2 (p'_z / p_z) r'`;
/// a line residual `n / w` (`n = ēᵀ m`, `w = ‖G m_xy‖`, `m = A × B`) obeys the same identity,
/// `r'' = (n'' − r w'') / w − 2 (w' / w) r'`. With `c₂` the norm of the first parts and `ρ` the rates
/// `|p'_z / p_z|` or `|w' / w|`, `‖r''‖ ≤ c₂ + 2 ‖diag(ρ) r'‖`, bounded two ways: by
/// `2 max ρ ‖r'‖` (Grönwall on `‖r'‖`, `‖r'(0)‖ ≤ μ`), or by `2 ρ_w + 2 max ρ · s K` with
/// `ρ_w² = λ_max(Σ ρ² gᵀ g)` (`g` the whitened gradients at `s = 0`, which spread `‖r'(0)‖ = 1`
/// over the residuals). In whitened steps every part is small: the large second derivatives lie
/// along the well-determined directions.
struct RayCurvature {
    alpha_omega: f64,
    alpha_tau: f64,
    mu: f64,
    points: Vec<PointRay>,
    lines: Vec<LineRay>,
}

impl RayCurvature {
    fn new(problem: &Problem, whitening: &Whitening, pose: &Pose, mu: f64) -> Option<Self> {
        let t = &whitening.t;
        let points = problem
            .corr
            .points3d
            .iter()
            .zip(&problem.point_maps)
            .map(|(x, map)| {
                let y = pose.rotation * x;
                let p = y + pose.translation;
                let d_pi =
                    SMatrix::<f64, 2, 3>::new(1.0 / p.z, 0.0, -p.x / (p.z * p.z), 0.0, 1.0 / p.z, -p.y / (p.z * p.z));
                let pt = tangent_map(&y) * t;
                let g = map * d_pi * pt;
                PointRay {
                    y_norm: y.norm(),
                    p,
                    depth_rate: pt.row(2).norm(),
                    gram: g.transpose() * g,
                    map_norm: norm2x2(map).1,
                    rate: spectral_norm(&(g * g.transpose())).sqrt() * (1.0 + 1e-12),
                }
            })
            .collect();
        let lines = problem
            .corr
            .lines2d
            .iter()
            .zip(&problem.corr.lines3d)
            .zip(&problem.endpoint_maps)
            .map(|((s2, s3), maps)| {
                // Endpoints A = R_s y_A + t: A' = a_ω × R_s y_A + a_τ = P_A a.
                let (y_a, y_b) = (pose.rotation * s3[0], pose.rotation * s3[1]);
                let (a, b) = (y_a + pose.translation, y_b + pose.translation);
                let m0 = a.cross(&b);
                // m = A × B moves as m' = N a, N = [[B]×[y_A]× − [A]×[y_B]×, [A]× − [B]×].
                let mut n0 = SMatrix::<f64, 3, 6>::zeros();
                n0.fixed_view_mut::<3, 3>(0, 0)
                    .copy_from(&(skew(&b) * skew(&y_a) - skew(&a) * skew(&y_b)));
                n0.fixed_view_mut::<3, 3>(0, 3).copy_from(&(skew(&a) - skew(&b)));
                let nt = n0 * t;
                let (p_a, p_b) = (tangent_map(&y_a), tangent_map(&y_b));
                let endpoints = std::array::from_fn(|k| {
                    let (e, (g_e, g_norm)) = (s2[k], maps[k]);
                    let w0 = (g_e * m0.xy()).norm();
                    let q_t = g_e * nt.fixed_view::<2, 6>(0, 0);
                    // w' = q̂·q' with q̂ = G_e m_xy / w.
                    let q_hat = g_e * m0.xy() / w0;
                    let w1 = q_hat.transpose() * q_t;
                    let e_bar = problem.k_inv * Vector3::new(e.x, e.y, 1.0);
                    let r0 = e_bar.dot(&m0) / w0;
                    // r' = (n' − r w') / w at s = 0.
                    let g = (e_bar.transpose() * nt - w1 * r0) / w0;
                    // n''(0) = ē·(A'' × B + A × B'' + 2 A' × B') = aᵀ H a.
                    let mut h = SMatrix::<f64, 6, 6>::zeros();
                    let rotation =
                        double_cross_form(&y_a, &b.cross(&e_bar)) + double_cross_form(&y_b, &e_bar.cross(&a));
                    h.fixed_view_mut::<3, 3>(0, 0).copy_from(&rotation);
                    let cross = p_a.transpose() * skew(&e_bar) * p_b;
                    h -= cross + cross.transpose();
                    EndpointRay {
                        w0,
                        g_norm,
                        q1_0: q_t.singular_values().max(),
                        w1_0: w1.norm(),
                        e_norm: e_bar.norm(),
                        cross_b: b.cross(&e_bar).norm(),
                        cross_a: e_bar.cross(&a).norm(),
                        sight_speed: [&p_a, &p_b].map(|p| (skew(&e_bar) * p * t).singular_values().max()),
                        r0,
                        slope0: g.norm(),
                        gram: g.transpose() * g,
                        n2_exact: (t.transpose() * h * t).symmetric_eigenvalues().abs().max(),
                    }
                });
                LineRay {
                    ya: y_a.norm(),
                    yb: y_b.norm(),
                    a: a.norm(),
                    b: b.norm(),
                    length: (b - a).norm(),
                    endpoints,
                }
            })
            .collect::<Vec<_>>();
        lines
            .iter()
            .flat_map(|l: &LineRay| &l.endpoints)
            .all(|end| end.w0 > 0.0 && end.w0.is_finite())
            .then_some(RayCurvature {
                alpha_omega: whitening.alpha_omega,
                alpha_tau: whitening.alpha_tau,
                mu,
                points,
                lines,
            })
    }

    /// `K` on the whitened ball of radius `s`, or `None` when a depth or a projected line may vanish
    /// there (or a per-residual slope bound cannot be confirmed).
    fn bound(&self, s: f64) -> Option<f64> {
        self.bound_with_parts(s, None)
    }

    /// [`Self::bound`], recording its per-residual parts in `parts` (the test hook
    /// [`testing::curvature_parts`] only).
    fn bound_with_parts(&self, s: f64, mut parts: Option<&mut testing::CurvatureParts>) -> Option<f64> {
        let (a_w, a_t) = (self.alpha_omega, self.alpha_tau);
        let mut direct2 = 0.0;
        let mut rate: f64 = 0.0;
        let mut weighted = SMatrix::<f64, 6, 6>::zeros();
        // Per segment endpoint: its rate ρ, |r''| ≤ direct + 2ρ σ (σ its own bound on |r'|), and
        // the terms it adds to `direct2` and `weighted`.
        let mut endpoints: Vec<(f64, f64, f64, SMatrix<f64, 6, 6>)> = Vec::new();
        for pt in &self.points {
            // |p'_z| ≤ ‖e_zᵀ P T‖ + s α_ω² ‖y‖ (the drift of a_ω × R_s y).
            let depth_rate = pt.depth_rate + s * a_w * a_w * pt.y_norm;
            let z_lo = pt.p.z - s * depth_rate;
            if !(z_lo > 0.0) {
                return None;
            }
            let pi_max = (pt.p.xy().norm() + s * (a_w * pt.y_norm + a_t)) / z_lo;
            // ‖W K₂ Dπ p''‖ ≤ ‖W K₂‖ √(1 + ‖π‖²) / z · α_ω² ‖y‖.
            let direct = pt.map_norm * (1.0 + pi_max * pi_max).sqrt() / z_lo * a_w * a_w * pt.y_norm;
            direct2 += direct * direct;
            let rho = depth_rate / z_lo;
            if let Some(p) = parts.as_deref_mut() {
                p.points.push(testing::PointParts {
                    z_lo,
                    rate: rho,
                    residual_rate: pt.rate,
                });
            }
            rate = rate.max(rho);
            weighted += pt.gram * (rho * rho);
        }
        for line in &self.lines {
            let (v_a, v_b) = (a_w * line.ya + a_t, a_w * line.yb + a_t);
            // ‖A‖, ‖B‖ anywhere on the ball: they move at most v_a, v_b per unit of s.
            let (a_max, b_max) = (line.a + s * v_a, line.b + s * v_b);
            // ‖(N(s) − N(0)) a‖ ≤ s · drift, drift ≥ sup ‖N'(σ) a‖ over σ ≤ s: the rotation block moves as
            // (a_ω × y_A)' × B + (a_ω × y_A) × B' (and A's twin), with ‖B(σ)‖ ≤ b_max, not ‖B(0)‖.
            let drift = a_w * (v_b * line.ya + b_max * a_w * line.ya + v_a * line.yb + a_max * a_w * line.yb)
                + a_t * a_w * line.length;
            // ‖m''‖: m'' = A'' × B + A × B'' + 2 A' × (a_ω × D), D = B − A = R_s (y_B − y_A).
            let m2 = a_w * a_w * (line.ya * b_max + a_max * line.yb) + 2.0 * v_a.min(v_b) * a_w * line.length;
            // m''' = A''' × B + A × B''' + 3 (A'' × (a_ω × D) + A' × (a_ω × (a_ω × D))).
            let mixed3 = 3.0 * a_w * a_w * line.length * (v_a + a_w * line.ya).min(v_b + a_w * line.yb);
            let mut ends = [testing::EndpointParts::default(); 2];
            for (end, found) in line.endpoints.iter().zip(&mut ends) {
                let q1 = end.q1_0 + s * end.g_norm * drift;
                let w_lo = end.w0 - s * q1;
                if !(w_lo > 0.0) {
                    return None;
                }
                // |w''| ≤ ‖q'‖² / w + ‖q''‖; |w'| ≤ |w'(0)| + s |w''|.
                let w2 = q1 * q1 / w_lo + end.g_norm * m2;
                let rho = (end.w1_0 + s * w2) / w_lo;
                rate = rate.max(rho);
                let n3 = a_w.powi(3)
                    * (line.ya * (end.cross_b + s * v_b * end.e_norm) + line.yb * (end.cross_a + s * v_a * end.e_norm))
                    + end.e_norm * mixed3;
                // The same n''' about either end X: n = ēᵀ (A × B) = Dᵀ u with D = B − A, u = ē × X.
                let ends = [(line.ya, end.cross_a), (line.yb, end.cross_b)];
                let sights = std::array::from_fn(|x| {
                    let (y, cross) = ends[x];
                    sight_parts(a_w, line.length, end.e_norm, y, cross, end.sight_speed[x], s)
                });
                let leibniz = n3;
                let n3 = sights
                    .iter()
                    .map(|p: &testing::SightParts| p.pieces.iter().sum())
                    .fold(leibniz, f64::min);
                let n2 = end.n2_exact + s * n3;
                *found = testing::EndpointParts {
                    w_lo,
                    w2,
                    rate: rho,
                    q1,
                    n2,
                    n2_exact: end.n2_exact,
                    n3,
                    leibniz,
                    sights,
                };
                // |r(s)| ≤ |r(0)| + s σ with σ a bound on |r'| along the ray, confirmed by Grönwall
                // on |r''| ≤ d + 2ρ |r'|, d = (|n''| + |r| |w''|) / w.
                let mut sigma = 1.2 * end.slope0 + 1e-12;
                let mut confirmed = None;
                for _ in 0..6 {
                    let direct = (n2 + (end.r0.abs() + s * sigma) * w2) / w_lo;
                    let reached = gronwall(end.slope0, direct, 2.0 * rho, s);
                    if reached <= sigma {
                        confirmed = Some((direct, reached));
                        break;
                    }
                    sigma = 1.5 * reached;
                }
                let (direct, speed) = confirmed?;
                direct2 += direct * direct;
                weighted += end.gram * (rho * rho);
                endpoints.push((rho, direct, direct + 2.0 * rho * speed, end.gram * (rho * rho)));
            }
            if let Some(p) = parts.as_deref_mut() {
                p.lines.push(testing::LineParts {
                    speed: [v_a, v_b],
                    drift,
                    m2,
                    mixed3,
                    endpoints: ends,
                });
            }
        }
        let by_rates = |rate: f64, direct2: f64, weighted: &SMatrix<f64, 6, 6>, apart: f64| {
            let (c1, c2) = (2.0 * rate, direct2.max(0.0).sqrt());
            let by_max_rate = c2 + apart + c1 * gronwall(self.mu, c2 + apart, c1, s);
            let rho_w = weighted.symmetric_eigenvalues().max().max(0.0).sqrt();
            let by_weights = if c1 * s < 1.0 {
                (c2 + apart + 2.0 * rho_w) / (1.0 - c1 * s) + apart
            } else {
                f64::INFINITY
            };
            by_max_rate.min(by_weights)
        };
        let mut k = by_rates(rate, direct2, &weighted, 0.0);
        // A few endpoints of fast-turning lines (short in the image, or seen nearly end-on) set the
        // largest rate. Bounded apart, each by its own |r''| ≤ direct + 2ρσ, they leave the others
        // a smaller rate: ‖r''‖ ≤ ‖r''_rest‖ + ‖r''_apart‖ (Minkowski), the rest bounded as above
        // with ‖r''_apart‖ in its constant part. The least over a few splits.
        if !endpoints.is_empty() {
            endpoints.sort_by(|a, b| b.0.total_cmp(&a.0));
            let point_rate = self.points_rate(s, a_w);
            let mut apart2 = 0.0;
            let (mut rest2, mut rest_weighted) = (direct2, weighted);
            for (count, &(_, direct, bound, gram)) in endpoints.iter().enumerate().take(APART_ENDPOINTS) {
                apart2 += bound * bound;
                rest2 -= direct * direct;
                rest_weighted -= gram;
                let rest_rate = endpoints.get(count + 1).map_or(0.0, |e| e.0).max(point_rate);
                if (count + 1).is_power_of_two() {
                    k = k.min(by_rates(rest_rate, rest2, &rest_weighted, apart2.sqrt()));
                }
            }
        }
        Some(k)
    }

    /// Per point, its residual's rate `‖g‖₂` at the pose: along a whitened ray of length `s` the
    /// residual moves by at most `‖g‖₂ s + ½ K s²` (`K` of [`Self::bound`]).
    fn point_rates(&self) -> Vec<f64> {
        self.points.iter().map(|pt| pt.rate).collect()
    }

    /// The largest rate `|p_z' / p_z|` of the points over the ball of radius `s` (0 without points).
    fn points_rate(&self, s: f64, a_w: f64) -> f64 {
        self.points
            .iter()
            .map(|pt| {
                let depth_rate = pt.depth_rate + s * a_w * a_w * pt.y_norm;
                depth_rate / (pt.p.z - s * depth_rate)
            })
            .fold(0.0, f64::max)
    }
}

/// Step 4: the least of `½ (√q(d) − ½ K d²)₊²` over `d ≤ rho`, `q(d) = 2f̂ − 2‖g‖d + λ d²`, by
/// [`LOCAL_INTERVALS`] intervals on each of which `q` takes its exact minimum and `d²` its maximum.
fn local_lower_bound(f_hat: f64, gradient: f64, lambda: f64, k: f64, rho: f64, slacks: &[(f64, RaySlack)]) -> f64 {
    let q = |d: f64| 2.0 * f_hat - 2.0 * gradient * d + lambda * d * d;
    let vertex = if lambda > 0.0 { gradient / lambda } else { f64::INFINITY };
    let mut least = f64::INFINITY;
    let mut slack = slacks.iter().peekable();
    for i in 0..LOCAL_INTERVALS {
        let (a, b) = (
            rho * i as f64 / LOCAL_INTERVALS as f64,
            rho * (i + 1) as f64 / LOCAL_INTERVALS as f64,
        );
        let q_min = if (a..=b).contains(&vertex) {
            q(vertex)
        } else {
            q(a).min(q(b))
        };
        // The slack of the least ball that holds this interval's steps.
        while slack.next_if(|(radius, _)| *radius < b).is_some() {}
        let Some((_, slack)) = slack.peek() else {
            return 0.0;
        };
        let h = slack.kappa * (q_min.max(0.0).sqrt() - 0.5 * k * b * b)
            - slack.eps * (slack.rate * b + 0.5 * k * b * b + b * slack.phi + slack.offset)
            - slack.rounding;
        least = least.min(0.5 * h.max(0.0).powi(2));
    }
    least
}

/// Step 4 through a lens (`lens`, step 2): along a whitened ray of length `s` the cost through the
/// lens has `√(2f) ≥ κ √(2q) − ε (μ s + ½ K s² + s Φ + offset) − rounding` (`q` the surrogate's cost);
/// [`RaySlack::NONE`] for a pinhole camera.
#[derive(Debug, Clone, Copy, PartialEq)]
struct RaySlack {
    kappa: f64,
    /// `μ ≥ ‖J T v‖`, the rate of the residuals along a unit whitened ray (1 up to rounding).
    rate: f64,
    eps: f64,
    phi: f64,
    offset: f64,
    rounding: f64,
}

impl RaySlack {
    /// The pinhole certificate: no slack.
    const NONE: RaySlack = RaySlack {
        kappa: 1.0,
        rate: 1.0,
        eps: 0.0,
        phi: 0.0,
        offset: 0.0,
        rounding: 0.0,
    };
}

/// The local model at the pose, in whitened steps: cost, gradient norm `‖Tᵀ g‖`, the least
/// eigenvalue of `Tᵀ JᵀJ T` (1 up to rounding) and the curvature bound; through a lens, the
/// surrogate whose cost they describe (`lens`).
struct LocalModel<'s> {
    cost: f64,
    gradient: f64,
    lambda_min: f64,
    curvature: RayCurvature,
    lens: Option<&'s Surrogate>,
}

impl<'s> LocalModel<'s> {
    /// The local model at `pose` (frame of `problem`) and the whitening it is expressed in.
    fn at(
        problem: &Problem,
        camera: &Camera,
        pose: &Pose,
        lens: Option<&'s Surrogate>,
    ) -> std::result::Result<(Whitening, Self), String> {
        let lin = ReprojectionCost::of(camera, problem.corr).linearize(pose);
        let whitening = Whitening::new(&lin.gauss_newton).ok_or("not proved: JᵀJ is singular at the pose")?;
        let whitened = whitening.t.transpose() * lin.gauss_newton * whitening.t;
        let eigen = whitened.symmetric_eigenvalues();
        let curvature = RayCurvature::new(problem, &whitening, pose, eigen.max().max(0.0).sqrt())
            .ok_or("not proved: a projected line vanishes at the pose")?;
        let model = LocalModel {
            cost: lin.cost,
            gradient: (whitening.t.transpose() * lin.gradient).norm(),
            lambda_min: eigen.min(),
            curvature,
            lens,
        };
        Ok((whitening, model))
    }

    /// The lower bound of step 4 over the whitened ball of `radius` (unclamped: at most the cost when
    /// sound, since the ball holds the pose), or `None` where a depth or a projected line may vanish.
    /// Through a lens, the bound with the distortion's variation over the whole ball comes first, and
    /// the nested balls only where it falls short of `wanted`.
    fn raw_bound(&self, radius: f64, wanted: Option<f64>) -> Option<f64> {
        let (k, slacks) = match self.lens {
            None => (self.curvature.bound(radius)?, vec![(radius, RaySlack::NONE)]),
            Some(lens) => {
                let mut parts = testing::CurvatureParts::default();
                let k = self.curvature.bound_with_parts(radius, Some(&mut parts))?;
                // The turn rate ‖q′‖ / w of each endpoint's whitened line normal over the ball.
                let turns: Vec<f64> = parts
                    .lines
                    .iter()
                    .flat_map(|line| line.endpoints.iter().map(|end| end.q1 / end.w_lo))
                    .collect();
                debug_assert_eq!(turns.len(), lens.n_endpoints());
                let mu = self.curvature.mu;
                let rates = self.curvature.point_rates();
                let whole = (radius, lens.ball(radius, k, mu, &rates, &turns)?);
                let coarse = local_lower_bound(self.cost, self.gradient, self.lambda_min, k, radius, &[whole]);
                if wanted.is_some_and(|w| coarse >= w) {
                    return Some(coarse);
                }
                // The distortion's variation over nested balls: the steps near the answer, where
                // the bound is least, pay only that of a small ball.
                let mut slacks = vec![whole];
                for j in 1..=NESTED_BALLS {
                    let r = radius * 0.5f64.powf(j as f64 / 2.0);
                    match lens.ball(r, k, mu, &rates, &turns) {
                        Some(slack) => slacks.push((r, slack)),
                        None => break,
                    }
                }
                slacks.reverse();
                (k, slacks)
            }
        };
        Some(local_lower_bound(
            self.cost,
            self.gradient,
            self.lambda_min,
            k,
            radius,
            &slacks,
        ))
    }
}

/// Through a lens, step 4 takes the distortion's variation over balls of the radius and of this many
/// smaller ones, each `1/√2` of the last (halving instead lost 8 of 28 certificates on the
/// bench's strong lens at f = 250 px with 10 correspondences).
const NESTED_BALLS: usize = 24;

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
/// and the certificate is that of `lens`. Never fails: a certificate that cannot be computed is
/// `certified = false` with the reason. Every cost and bound here is `½ Σ r²`;
/// [`crate::pose::PoseResult`] reports them in `Σ r²`.
pub fn certify(
    camera: &Camera,
    lens: Option<&LensCamera>,
    corr: &Correspondences,
    pose: &Pose,
    cost: f64,
    options: &CertifyOptions,
) -> Certification {
    if !(cost.is_finite() && cost >= 0.0) {
        return Certification::none("not attempted: the cost is not finite");
    }
    match lens.filter(|l| !l.is_pinhole()) {
        Some(lens) => lens::certify(lens, corr, pose, cost, options),
        None => certify_pinhole(camera, corr, pose, cost, options, None),
    }
}

/// [`certify`] of a pinhole problem, or of a lens's surrogate (`lens`; `camera` and `corr` are then
/// the surrogate's, and `cost` the cost through the lens).
fn certify_pinhole(
    camera: &Camera,
    corr: &Correspondences,
    pose: &Pose,
    cost: f64,
    options: &CertifyOptions,
    lens: Option<&Surrogate>,
) -> Certification {
    // The level of the sublevel set that the search localises (the surrogate's, through a lens).
    let level = lens.map_or(cost, |l| l.slack.to_surrogate(cost));
    // Through a lens the search runs on step 1's weighted observations, step 4 on the surrogate's.
    let search_corr = lens.map_or(corr, |l| l.search_corr());
    let whole = match lens.map(|_| Problem::without_depths(camera, corr, level)).transpose() {
        Ok(whole) => whole,
        Err(why) => return Certification::none(why),
    };
    let problem = match Problem::new(camera, search_corr, level) {
        Ok(p) => p,
        Err(why) => return Certification::none(why),
    };
    let local = whole.as_ref().unwrap_or(&problem);
    let first = certify_problem(&problem, local, camera, pose, cost, options, lens);
    // With segments, a search with depth bounds that did not close its gap is followed by the one
    // without them (bounded at each box's rotation, segments and points alike): where the points are
    // few it certifies scenes the first cannot. Both bounds are proved; the better is kept.
    if first.certified || problem.root().is_none() || corr.n_lines() == 0 {
        return first;
    }
    let second = match Problem::without_depths(camera, search_corr, level) {
        Ok(p) => certify_problem(&p, whole.as_ref().unwrap_or(&p), camera, pose, cost, options, lens),
        Err(why) => Certification::none(why),
    };
    let nodes = first.nodes + second.nodes;
    if second.certified || second.raw_lower_bound > first.raw_lower_bound {
        return Certification { nodes, ..second };
    }
    Certification {
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
    camera: &Camera,
    pose: &Pose,
    cost: f64,
    options: &CertifyOptions,
    lens: Option<&Surrogate>,
) -> Certification {
    let (whitening, model) = match LocalModel::at(local, camera, pose, lens) {
        Ok(m) => m,
        Err(why) => return Certification::none(why),
    };
    let slack = lens.map_or(Slack::NONE, |l| l.slack);
    let gap_of = |lower: f64| relative_gap(cost, lower);
    let unit = (2.0 * cost).sqrt() + 0.1;
    let closing = |radius: f64| {
        model
            .raw_bound(
                radius,
                Some(cost - options.max_relative_gap * cost.max(CERTIFICATE_COST_FLOOR)),
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
        return Certification::none(match lens {
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
        Start::Points(_) if problem.corr.n_lines() > 0 => MAX_CELLS_BEFORE_FALLBACK,
        Start::Points(_) => MAX_CELLS,
        Start::Ball { .. } => MAX_CELLS_FROM_DISTANCE,
    };
    let localised = match localise(&mut search, options.max_nodes_or(cap)) {
        Ok(l) => l,
        Err((why, nodes)) => {
            return Certification {
                nodes,
                ..Certification::none(why)
            }
        }
    };
    let raw_lower_bound = slack.to_cost(localised.raw_lower_bound);
    let lower_bound = raw_lower_bound.min(cost);
    let gap = gap_of(lower_bound);
    let certified = gap <= options.max_relative_gap;
    Certification {
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

/// Hooks for the tests of the proof (not part of the API): the steps of [`certify`] one by one, on
/// any pose and at any level, so that the tests can check each against an independent oracle.
#[doc(hidden)]
pub mod testing {
    use super::*;

    /// A rotation cell that the search kept: the box `|ω − centre| ≤ half` (per axis) of rotation
    /// vectors (`R = exp(ω) R̂`), and the ellipsoid `(t − t*)ᵀ C (t − t*) ≤ slack` (`C`, `t*` the
    /// minorant's Hessian and minimiser at the box's centre, for the box's depth bounds) that holds the
    /// translation of every pose of the sublevel set whose rotation lies in the box.
    #[derive(Debug, Clone)]
    pub struct KeptCell {
        pub centre: Vector3<f64>,
        /// The half-widths of the box along the three axes.
        pub half: Vector3<f64>,
        pub t_star: Vector3<f64>,
        pub c: Matrix3<f64>,
        pub slack: f64,
        /// Whether the cell lies inside the whitened ball of the target radius (else it was left
        /// unsplit at the least half-width).
        pub inside_ball: bool,
        /// The depth bounds `Dᵢ` of the cell's minorant (handed down by its ancestors): the search
        /// claims `‖R Xᵢ + t‖ ≤ Dᵢ` for every pose of the sublevel set with its rotation in the box.
        pub depths: Vec<f64>,
        /// Whether the ellipsoid comes from a quadratic with the segments' terms (with depth bounds:
        /// where it reaches less far than the points' alone).
        pub with_segments: bool,
        /// For a cell inside the ball: the largest whitened length `‖(0, t − t*)‖_W` over its
        /// ellipsoid (`W = JᵀJ` at the centre), a part of the radius the search claims for the cell.
        pub extent: Option<f64>,
    }

    /// What [`rotation_search`] proved.
    #[derive(Debug, Clone)]
    pub struct Region {
        /// Step 1's depth bounds `Dᵢ` (the root's: the search tightens them box by box; empty when
        /// the search starts from the object's distance).
        pub depths: Vec<f64>,
        /// Whether the search started from the object's distance (no depth bounds: lines alone, or
        /// too few points). Its claims then cover the poses with the segments' object endpoints in
        /// front of the camera as well as the points, and its cells pruned as behind the camera have
        /// a point or endpoint with `z ≤ 0` (not `bᵢ · x ≤ 0`) for every pose of the cell.
        pub from_distance: bool,
        /// The cells neither pruned nor split: every pose of the sublevel set with the points in front
        /// lies in one of them (rotation in the box, translation in the ellipsoid).
        pub cells: Vec<KeptCell>,
        /// Cells pruned (by the minorant or by cheirality).
        pub pruned: usize,
        /// The cells pruned by cheirality, with their translation ellipsoids (`inside_ball` false):
        /// the search claims that for each some point `i` has `bᵢ · (R Xᵢ + t) ≤ 0` (`bᵢ` its observed
        /// ray) for every rotation of the box and every translation of the ellipsoid.
        pub behind: Vec<KeptCell>,
        /// Cells examined (bound computations of the branch and bound).
        pub nodes: usize,
        /// The largest whitened radius `‖(ω, t − t̂)‖_W` (`W = JᵀJ` at the centre) of the cells
        /// inside the ball: a bound on that of every pose of the sublevel set in those cells.
        pub radius: f64,
    }

    /// Step 1's depth bounds for the level `level` (px²): every pose with cost at most `level` and the
    /// points in front has `‖R Xᵢ + t‖ ≤ Dᵢ`.
    pub fn depth_bounds(camera: &Camera, corr: &Correspondences, level: f64) -> std::result::Result<Vec<f64>, String> {
        Problem::new(camera, corr, level)?
            .root()
            .map(|root| root.depths.clone())
            .ok_or_else(|| "no depth bounds: the search starts from the object's distance".into())
    }

    /// Where the search starts from the object's distance at the level `level` (px²): the pivot `c`
    /// and the bound `D` with `‖R c + t‖ ≤ D` on every pose with cost at most `level` and the points in
    /// front (`None`: the search starts from step 1's depth bounds).
    pub fn object_distance(
        camera: &Camera,
        corr: &Correspondences,
        level: f64,
    ) -> std::result::Result<Option<(Vector3<f64>, f64)>, String> {
        Ok(match Problem::new(camera, corr, level)?.start {
            Start::Ball { pivot, distance } => Some((pivot, distance)),
            Start::Points(_) => None,
        })
    }

    /// Steps 1-3 around `centre` (any pose, not necessarily a minimum) for the sublevel set of
    /// `level` (px², any value, e.g. above the optimum), on the same branch and bound as [`certify`]
    /// with the incumbent `level` and no gap: boxes are split until they are pruned (bound at least
    /// `level`, or behind the camera), lie inside the whitened ball of radius `target`, or reach the
    /// half-width `min_half`; the last two are recorded and closed.
    pub fn rotation_search(
        camera: &Camera,
        corr: &Correspondences,
        centre: &Pose,
        level: f64,
        target: f64,
        min_half: f64,
        max_nodes: usize,
    ) -> std::result::Result<Region, String> {
        let problem = Problem::new(camera, corr, level)?;
        let lin = ReprojectionCost::of(camera, corr).linearize(centre);
        let whitening = Whitening::new(&lin.gauss_newton).ok_or("JᵀJ is singular at the pose")?;
        let mut record = Record::new(min_half);
        let mut search = RotationSearch {
            problem: &problem,
            whitening: &whitening,
            pose: centre,
            f_hat: level,
            target,
            max_relative_gap: 0.0,
            slack: Slack::NONE,
            inside_ball: InsideBall::Record(&mut record),
            linearise_lines: true,
            radius: 0.0,
        };
        let localised = localise(&mut search, max_nodes).map_err(|(why, _)| why)?;
        Ok(Region {
            depths: problem.root().map_or_else(Vec::new, |root| root.depths.clone()),
            from_distance: problem.root().is_none(),
            cells: record.cells,
            pruned: record.pruned,
            behind: record.behind,
            nodes: localised.nodes,
            radius: localised.radius,
        })
    }

    /// Step 4's one-dimensional bound: the least of `½ (√q(d) − ½ k d²)₊²` over `d ≤ rho`,
    /// `q(d) = 2f̂ − 2 gradient d + lambda d²`.
    pub fn local_lower_bound(f_hat: f64, gradient: f64, lambda: f64, k: f64, rho: f64) -> f64 {
        super::local_lower_bound(f_hat, gradient, lambda, k, rho, &[(rho, RaySlack::NONE)])
    }

    /// Step 4 at `pose` (any pose) over the whitened ball of `radius`.
    #[derive(Debug, Clone)]
    pub struct LocalBound {
        /// `T` with `Tᵀ JᵀJ T = I`: the whitened step `v` is the chart step `(ω, τ) = T v`.
        pub whitening: SMatrix<f64, 6, 6>,
        /// `K`: a bound on `‖r''(s)‖` along every whitened ray of the ball.
        pub curvature: f64,
        /// The bound on the cost over the ball, unclamped.
        pub raw_bound: f64,
    }

    /// A point's part of `K` on the ball: along every whitened ray `s ↦ (exp(s a_ω) R̂, t̂ + s a_τ)`
    /// (`a = T v`, `‖v‖ = 1`, `s ≤ radius`) its camera-frame depth `p_z ≥ z_lo` and `|p_z' / p_z| ≤ rate`.
    #[derive(Debug, Clone, Copy)]
    pub struct PointParts {
        pub z_lo: f64,
        pub rate: f64,
        /// `‖g‖₂` at the pose: the rate of the point's whitened residual per unit whitened step.
        pub residual_rate: f64,
    }

    /// One observed endpoint's part of `K` on the ball, along the same rays: with `m = A × B`
    /// (camera-frame endpoints of the object segment) and `w = ‖G_e m_xy‖` (`G_e = Lᵀ G`, `G` the
    /// upper-left 2x2 block of `K⁻ᵀ`, `L Lᵀ` the endpoint's covariance, the identity without one),
    /// `w ≥ w_lo`, `|w''| ≤ w2`, `|w' / w| ≤ rate`, `‖q'‖ ≤ q1` (`q = G_e m_xy`), and with
    /// `ē = K⁻¹ ẽ`, `|(ēᵀ m)''| ≤ n2` and `|(ēᵀ m)'''| ≤ n3`; `n2_exact` is `max |(ēᵀ m)''(0)|` over
    /// the unit whitened directions, exactly. Within them, `w2 − ‖G_e‖ m2` bounds `‖q'‖² / w` and
    /// `n3 − ‖ē‖ mixed3` bounds `|ēᵀ (A''' × B + A × B''')|`.
    #[derive(Debug, Clone, Copy, Default)]
    pub struct EndpointParts {
        pub w_lo: f64,
        pub w2: f64,
        pub rate: f64,
        pub q1: f64,
        pub n2: f64,
        pub n2_exact: f64,
        pub n3: f64,
        /// The bound on `|n'''|` from `m''' = A''' × B + A × B''' + mixed`.
        pub leibniz: f64,
        /// The bounds on `|n'''|` about the ends `A` and `B` (see [`SightParts`]); `n3` is the least
        /// of theirs and `leibniz`.
        pub sights: [SightParts; 2],
    }

    /// `|n'''|` about one end `X` of the segment: `n = Dᵀ u` with `D = B − A` and `u = ē × X`, so
    /// `n''' = D'''ᵀ u + 3 D''ᵀ u' + 3 D'ᵀ u'' + Dᵀ u'''`. Along the rays, `speed` bounds `‖u'‖`
    /// and `pieces` bound the four terms in that order.
    #[derive(Debug, Clone, Copy, Default)]
    pub struct SightParts {
        pub speed: f64,
        pub pieces: [f64; 4],
    }

    /// A line's part of `K` on the ball, along the same rays, each a claim of its own: `speed`
    /// bounds `‖A'‖` and `‖B'‖`, `drift` bounds `‖m'(s) − m'(0)‖ / s`, `m2` bounds `‖m''‖` and
    /// `mixed3` bounds `‖3 (A'' × B' + A' × B'')‖` (all over the ball); `endpoints` are the parts of
    /// the two observed endpoints.
    #[derive(Debug, Clone, Copy)]
    pub struct LineParts {
        pub speed: [f64; 2],
        pub drift: f64,
        pub m2: f64,
        pub mixed3: f64,
        pub endpoints: [EndpointParts; 2],
    }

    /// The parts of `K` (see [`PointParts`], [`LineParts`]) and the whitening `T` of the rays.
    #[derive(Debug, Clone, Default)]
    pub struct CurvatureParts {
        pub whitening: SMatrix<f64, 6, 6>,
        pub points: Vec<PointParts>,
        pub lines: Vec<LineParts>,
    }

    /// [`CurvatureParts`] at `pose` for the ball of whitened `radius` (depth bounds as in
    /// [`local_bound`]).
    pub fn curvature_parts(
        camera: &Camera,
        corr: &Correspondences,
        pose: &Pose,
        level: f64,
        radius: f64,
    ) -> std::result::Result<CurvatureParts, String> {
        let cost = ReprojectionCost::of(camera, corr).cost(pose);
        let problem = Problem::new(camera, corr, cost.max(level))?;
        let (whitening, model) = LocalModel::at(&problem, camera, pose, None)?;
        let mut parts = CurvatureParts {
            whitening: whitening.t,
            ..Default::default()
        };
        model
            .curvature
            .bound_with_parts(radius, Some(&mut parts))
            .ok_or("a depth or a projected line may vanish in the ball")?;
        Ok(parts)
    }

    /// The surrogate of a problem through a lens (`lens`) at `pose`, for the level `cost`
    /// (`½ Σ r²`): its camera (the lens's pinhole part), the rotation search's observations (weighted
    /// by step 1) and step 1's slack: every pose of the domain with cost `f ≤ cost` has
    /// `√(2q) ≤ √(2f) + delta` (`q` the cost of those observations).
    #[derive(Debug, Clone)]
    pub struct LensSurrogate {
        pub camera: Camera,
        pub corr: Correspondences,
        pub delta: f64,
    }

    /// [`LensSurrogate`] of `corr` (observed pixels of `lens`) at `pose` for the level `cost`.
    pub fn lens_surrogate(
        lens: &LensCamera,
        corr: &Correspondences,
        pose: &Pose,
        cost: f64,
    ) -> std::result::Result<LensSurrogate, String> {
        let s = Surrogate::new(lens, corr, pose, cost)?;
        Ok(LensSurrogate {
            delta: s.slack.delta,
            corr: s.search_corr().clone(),
            camera: s.camera,
        })
    }

    pub use super::lens::PointVariation;

    /// Each point's bound of the distortion's variation over the whitened ball of `radius` about its
    /// projection at `pose` (the surrogate at `pose` for the level `cost`), and the largest as step 4
    /// takes it (`None` where a ball reaches the edge of the disc).
    pub fn lens_point_variations(
        lens: &LensCamera,
        corr: &Correspondences,
        pose: &Pose,
        cost: f64,
        radius: f64,
    ) -> std::result::Result<(Vec<PointVariation>, Option<f64>), String> {
        Ok(Surrogate::new(lens, corr, pose, cost)?.point_variations(radius))
    }

    /// Step 4's `(κ, ε)` through `lens` over the whitened ball of `radius` with the curvature bound `k`
    /// (the surrogate at `pose` for the level `cost`; segment endpoints turning at the rates `turns`).
    #[allow(clippy::too_many_arguments)]
    pub fn lens_ball(
        lens: &LensCamera,
        corr: &Correspondences,
        pose: &Pose,
        cost: f64,
        radius: f64,
        k: f64,
        turns: &[f64],
    ) -> std::result::Result<Option<(f64, f64)>, String> {
        let surrogate = Surrogate::new(lens, corr, pose, cost)?;
        let rates = vec![1.0; surrogate.corr.n_points()];
        Ok(surrogate.ball(radius, k, 1.0, &rates, turns).map(|s| (s.kappa, s.eps)))
    }

    /// Step 4 through `lens` at any `pose` (cost `½ Σ r²` through the lens, computed here): the bound
    /// of that cost over the ball of whitened `radius` (the whitening of the surrogate at `pose`).
    pub fn lens_local_bound(
        lens: &LensCamera,
        corr: &Correspondences,
        pose: &Pose,
        radius: f64,
    ) -> std::result::Result<LocalBound, String> {
        let cost = ReprojectionCost::through_lens(lens, corr)
            .map_err(|e| e.to_string())?
            .cost(pose);
        let surrogate = Surrogate::new(lens, corr, pose, cost)?;
        let problem = Problem::new(&surrogate.camera, &surrogate.corr, surrogate.slack.to_surrogate(cost))?;
        let (whitening, model) = LocalModel::at(&problem, &surrogate.camera, pose, Some(&surrogate))?;
        let curvature = model
            .curvature
            .bound(radius)
            .ok_or("a depth or a projected line may vanish in the ball")?;
        Ok(LocalBound {
            whitening: whitening.t,
            curvature,
            raw_bound: model.raw_bound(radius, None).ok_or("no bound over the ball")?,
        })
    }

    /// [`LocalBound`] at `pose` for the ball of whitened `radius`; the depth bounds are those of the
    /// level `max(cost at pose, level)`.
    pub fn local_bound(
        camera: &Camera,
        corr: &Correspondences,
        pose: &Pose,
        level: f64,
        radius: f64,
    ) -> std::result::Result<LocalBound, String> {
        let cost = ReprojectionCost::of(camera, corr).cost(pose);
        let problem = Problem::new(camera, corr, cost.max(level))?;
        let (whitening, model) = LocalModel::at(&problem, camera, pose, None)?;
        let curvature = model
            .curvature
            .bound(radius)
            .ok_or("a depth or a projected line may vanish in the ball")?;
        Ok(LocalBound {
            whitening: whitening.t,
            curvature,
            raw_bound: super::local_lower_bound(
                model.cost,
                model.gradient,
                model.lambda_min,
                curvature,
                radius,
                &[(radius, RaySlack::NONE)],
            ),
        })
    }
}

#[cfg(test)]
mod tests;
