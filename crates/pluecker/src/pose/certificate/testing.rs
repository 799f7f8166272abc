//! Hooks for the tests of the proof (not part of the API): the steps of `certify` one by one, on
//! any pose and at any level, so that the tests can check each against an independent oracle.

use super::lens::{Slack, Surrogate};
use super::local_bound::{LocalModel, RaySlack, Whitening};
use super::problem::{Problem, SearchStart};
use super::search::{localise, InsideBall, RecordedCells, RotationSearch};
use crate::camera::Camera;
use crate::camera::Intrinsics;
use crate::certificate::CertifyOptions;
use crate::optim::Objective;
use crate::pose::correspondences::Correspondences;
use crate::pose::reprojection::{Pose, ReprojectionCost};
use nalgebra::{SMatrix, Vector3};

pub use super::local_bound::{CurvatureParts, EndpointParts, LineParts, PointParts, SightParts};
pub use super::search::KeptCell;
pub use super::SublevelSetOutcome;

/// The whole test in its own units (`f = ½ Σ r²`, px²), at any `pose` and cost `cost` (`½ Σ r²`):
/// what `certify` proves before its outcome becomes the shared certificate in `Σ r²`.
pub fn certify(
    camera: &Intrinsics,
    lens: Option<&Camera>,
    corr: &Correspondences,
    pose: &Pose,
    cost: f64,
    options: &CertifyOptions,
) -> SublevelSetOutcome {
    super::sublevel_set_test(camera, lens, corr, pose, cost, options)
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
pub fn depth_bounds(camera: &Intrinsics, corr: &Correspondences, level: f64) -> std::result::Result<Vec<f64>, String> {
    Problem::new(camera, corr, level)?
        .root()
        .map(|root| root.depths.clone())
        .ok_or_else(|| "no depth bounds: the search starts from the object's distance".into())
}

/// Where the search starts from the object's distance at the level `level` (px²): the pivot `c`
/// and the bound `D` with `‖R c + t‖ ≤ D` on every pose with cost at most `level` and the points in
/// front (`None`: the search starts from step 1's depth bounds).
pub fn object_distance(
    camera: &Intrinsics,
    corr: &Correspondences,
    level: f64,
) -> std::result::Result<Option<(Vector3<f64>, f64)>, String> {
    Ok(match Problem::new(camera, corr, level)?.start {
        SearchStart::ObjectDistance { pivot, distance } => Some((pivot, distance)),
        SearchStart::DepthBounds(_) => None,
    })
}

/// Steps 1-3 around `centre` (any pose, not necessarily a minimum) for the sublevel set of
/// `level` (px², any value, e.g. above the optimum), on the same branch and bound as `certify`
/// with the incumbent `level` and no gap: boxes are split until they are pruned (bound at least
/// `level`, or behind the camera), lie inside the whitened ball of radius `target`, or reach the
/// half-width `min_half`; the last two are recorded and closed.
pub fn rotation_search(
    camera: &Intrinsics,
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
    let mut record = RecordedCells::new(min_half);
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
    super::local_bound::local_lower_bound(f_hat, gradient, lambda, k, rho, &[(rho, RaySlack::NONE)])
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

/// [`CurvatureParts`] at `pose` for the ball of whitened `radius` (depth bounds as in
/// [`local_bound`]).
pub fn curvature_parts(
    camera: &Intrinsics,
    corr: &Correspondences,
    pose: &Pose,
    level: f64,
    radius: f64,
) -> std::result::Result<CurvatureParts, String> {
    let cost = ReprojectionCost::of(camera, corr).cost(pose);
    let problem = Problem::new(camera, corr, cost.max(level))?;
    let (whitening, model) = LocalModel::at(&problem, pose, None)?;
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
    pub camera: Intrinsics,
    pub corr: Correspondences,
    pub delta: f64,
}

/// [`LensSurrogate`] of `corr` (observed pixels of `lens`) at `pose` for the level `cost`.
pub fn lens_surrogate(
    lens: &Camera,
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
    lens: &Camera,
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
    lens: &Camera,
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
    lens: &Camera,
    corr: &Correspondences,
    pose: &Pose,
    radius: f64,
) -> std::result::Result<LocalBound, String> {
    let cost = ReprojectionCost::through_lens(lens, corr)
        .map_err(|e| e.to_string())?
        .cost(pose);
    let surrogate = Surrogate::new(lens, corr, pose, cost)?;
    let problem = Problem::new(&surrogate.camera, &surrogate.corr, surrogate.slack.to_surrogate(cost))?;
    let (whitening, model) = LocalModel::at(&problem, pose, Some(&surrogate))?;
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
    camera: &Intrinsics,
    corr: &Correspondences,
    pose: &Pose,
    level: f64,
    radius: f64,
) -> std::result::Result<LocalBound, String> {
    let cost = ReprojectionCost::of(camera, corr).cost(pose);
    let problem = Problem::new(camera, corr, cost.max(level))?;
    let (whitening, model) = LocalModel::at(&problem, pose, None)?;
    let curvature = model
        .curvature
        .bound(radius)
        .ok_or("a depth or a projected line may vanish in the ball")?;
    Ok(LocalBound {
        whitening: whitening.t,
        curvature,
        raw_bound: super::local_bound::local_lower_bound(
            model.cost,
            model.gradient,
            model.lambda_min,
            curvature,
            radius,
            &[(radius, RaySlack::NONE)],
        ),
    })
}
