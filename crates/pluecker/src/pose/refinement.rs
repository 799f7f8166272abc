//! The reprojection refinement stage: minimises the reprojection error ([`ReprojectionCost`]) from
//! each starting candidate with the trust region of section 4.1 (Hebden steps on `JᵀJ`), collects the
//! distinct local minima reached, and chooses the answer among them.
//!
//! Starts, in order: the algebraic estimator's answer and its near-best alternatives, then the minimal
//! solvers' poses ([`super::candidates`]) ranked by their cost. A minimal pose is refined when its cost
//! is below [`PROMISING_FACTOR`] times the best minimum so far (one that expensive is far from any good
//! minimum) and it is more than [`SAME_BASIN`] rad ([`SAME_BASIN_SMALL`] for 4-6 correspondences) from
//! every minimum found (a pose that close starts in a basin already explored). With many
//! correspondences the samples are solved one at a time, and the first whose poses confirm the best
//! minimum (one with every point in front) ends the search; the reserve samples are used only while no
//! minimum has every point in front (see [`search`]).
//!
//! Choice (see [`Minima::choose`]): the cheapest minimum with every object point in front of the
//! camera, unless a minimum with points behind is cheaper by more than the ambiguity margin (then the
//! data are best explained behind the camera, and the status says so). The runner-up is the cheapest
//! other minimum in front; the answer is *ambiguous* when it is within the margin
//! `Δ(Σ r²) ≤ ambiguity_threshold · σ²` of the answer.

use super::candidates::SPREAD_SAMPLES;
use super::correspondences::Conditioning;
use super::reprojection::{Pose, ReprojectionCost};
use super::{stage, CostKind, PoseOptions, StageReport};
use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::geometry::quaternion::{exp_so3, log_so3, rotation_distance};
use crate::optim::Objective;
use crate::optim::{trust_region, Subproblem, Summary, Termination};
use crate::pose::Correspondences;
use std::time::Instant;

/// Minimal poses are refined only when their cost is below a multiple of the best minimum so far (or of
/// `½ m` px², `m` residuals, when that is larger: the cost of 1 px of noise, for near-exact data): this
/// constant over the number of correspondences, and at least [`PROMISING_FACTOR_MIN`]. The refinement from a pose of cost `c` ends below `c`, so a pose cheaper than the best minimum
/// certainly leads to a better one; the margin admits the poses of the true basin, whose three
/// correspondences fit exactly and the others only as well as the noise lets them. Measured on the
/// scenes of `crates/pluecker-bench/benches/global_pose.rs` (100 per row): the cheapest minimal pose from which the
/// refinement reached the best minimum cost at most 104 times that minimum (lines only, f = 250 and
/// 15000 px, 10 lines), at most 7.3 times with 100 points, while the median minimal pose cost 10⁴ times
/// more: the fewer the correspondences, the less the cost of the best minimum averages the noise of the
/// minimal pose's extrapolation. Hence 300 at 10 correspondences, 30 at 100.
pub const PROMISING_FACTOR: f64 = 3000.0;
/// The least multiple of [`PROMISING_FACTOR`]'s rule.
pub const PROMISING_FACTOR_MIN: f64 = 20.0;
/// A minimal pose within this rotation distance (rad) of a minimum found is taken to be in its basin
/// and not refined. A minimal pose from 1 px noise is typically a few mrad from the minimum of its
/// basin, and up to a few hundredths at narrow fields of view.
pub const SAME_BASIN: f64 = 0.05;
/// The same when every triple is a sample (4-6 correspondences): minima of so few data can be close
/// together (two exact fits 0.01 rad apart are common), and the refinements are cheap.
pub const SAME_BASIN_SMALL: f64 = 1e-4;
/// Two refined minima are the same when their rotations differ by less than this (rad) and their
/// translations by less than this fraction of the object's size (conditioned units).
pub const SAME_MINIMUM: f64 = 1e-6;
/// Two refined minima closer than [`SAME_BASIN_SMALL`] are also the same when no barrier separates
/// them: the cost at the geodesic midpoint exceeds the larger of the two by at most this fraction. A
/// flat valley (4-5 planar points, a narrow field of view) leaves the refinement's stopping point
/// undetermined along it by up to ~1e-5 at costs equal to ~1e-11; distinct minima have a barrier.
pub const NO_BARRIER: f64 = 1e-9;

/// What the search needs of a pose's reprojection cost besides the objective itself: the single
/// camera's [`ReprojectionCost`] and the rig's ([`super::generalized::RigReprojectionCost`]) search
/// their minima the same way.
pub(crate) trait PoseCost: Objective<6, Point = Pose> {
    /// The number of scalar residuals: two per point and two per segment.
    fn residual_count(&self) -> usize;
    /// The cost `½ Σ r²` at `pose` when it is below `bound`, else `None` (may stop summing early).
    fn cost_below(&self, pose: &Pose, bound: f64) -> Option<f64>;
    /// The object points and segment endpoints behind their camera at `pose`.
    fn points_behind(&self, pose: &Pose) -> usize;
}

impl PoseCost for ReprojectionCost<'_> {
    fn residual_count(&self) -> usize {
        ReprojectionCost::residual_count(self)
    }
    fn cost_below(&self, pose: &Pose, bound: f64) -> Option<f64> {
        ReprojectionCost::cost_below(self, pose, bound)
    }
    fn points_behind(&self, pose: &Pose) -> usize {
        ReprojectionCost::points_behind(self, pose)
    }
}

/// One local minimum of the reprojection error, in the conditioned frame of the search.
#[derive(Debug, Clone, Copy)]
pub struct LocalMinimum {
    /// The pose, conditioned frame.
    pub pose: Pose,
    /// `½ Σ r²`, px².
    pub cost: f64,
    /// Object points and segment endpoints behind the camera at `pose`.
    pub behind: usize,
    /// Why the refinement that reached it stopped.
    pub termination: Termination,
}

impl LocalMinimum {
    /// Whether the refinement's last stop was a convergence test.
    pub fn converged(&self) -> bool {
        self.termination.converged()
    }
}

/// The distinct minima found, and the refinement's summed work.
#[derive(Debug, Clone)]
pub struct Minima {
    /// Distinct minima, in the order found.
    pub found: Vec<LocalMinimum>,
    /// Iterations and cost evaluations summed over every refinement run.
    iterations: usize,
    evaluations: usize,
    /// Cost at the start of the first run (the algebraic answer).
    initial_cost: f64,
    /// When the stage started.
    started: Instant,
}

/// The answer among the minima and its runner-up (indices into [`Minima::found`]).
#[derive(Debug, Clone, Copy)]
pub struct Choice {
    pub best: usize,
    pub second: Option<usize>,
    pub ambiguous: bool,
}

impl Minima {
    fn new() -> Self {
        Minima {
            found: vec![],
            iterations: 0,
            evaluations: 0,
            initial_cost: f64::NAN,
            started: Instant::now(),
        }
    }

    /// The stage report of the chosen minimum `best` (world frame through `cond`), with the work of
    /// every refinement run.
    pub fn report(&self, best: usize, cond: &Conditioning) -> StageReport {
        let m = &self.found[best];
        let world = Pose::new(
            m.pose.rotation,
            cond.pose_to_world(&m.pose.rotation, &m.pose.translation),
        );
        let total = Summary {
            iterations: self.iterations,
            evaluations: self.evaluations,
            initial_cost: self.initial_cost,
            final_cost: m.cost,
            termination: m.termination,
        };
        stage("refinement", CostKind::Reprojection, &world, &total, self.started)
    }

    /// The best cost found so far (infinite when none).
    pub fn best_cost(&self) -> f64 {
        self.found.iter().map(|m| m.cost).fold(f64::INFINITY, f64::min)
    }

    fn near(&self, pose: &Pose, radius: f64) -> bool {
        self.found
            .iter()
            .any(|m| rotation_distance(&m.pose.rotation, &pose.rotation) < radius)
    }

    fn add(&mut self, m: LocalMinimum, summary: &Summary, cost: &impl PoseCost) {
        if self.iterations == 0 && self.evaluations == 0 {
            self.initial_cost = summary.initial_cost;
        }
        self.iterations += summary.iterations;
        self.evaluations += summary.evaluations;
        let same = self.found.iter().position(|f| same_minimum(f, &m, cost));
        match same {
            Some(i) if self.found[i].cost <= m.cost => {}
            Some(i) => self.found[i] = m,
            None => self.found.push(m),
        }
    }

    /// Chooses the answer (see the module documentation); `margin` is the ambiguity margin in units of
    /// the cost `½ Σ r²`. `None` when nothing was found.
    pub fn choose(&self, margin: f64) -> Option<Choice> {
        let cheapest = |filter: &dyn Fn(&LocalMinimum) -> bool, except: Option<usize>| {
            (0..self.found.len())
                .filter(|&i| Some(i) != except && filter(&self.found[i]) && self.found[i].cost.is_finite())
                .min_by(|&a, &b| self.found[a].cost.total_cmp(&self.found[b].cost))
        };
        let in_front = |m: &LocalMinimum| m.behind == 0;
        let front = cheapest(&in_front, None);
        let any = cheapest(&|_| true, None);
        let best = match (front, any) {
            (Some(f), Some(a)) if self.found[a].cost < self.found[f].cost - margin => a,
            (Some(f), _) => f,
            (None, Some(a)) => a,
            (None, None) => {
                // Only non-finite costs: return the first, the status will say it failed.
                return (!self.found.is_empty()).then_some(Choice {
                    best: 0,
                    second: None,
                    ambiguous: false,
                });
            }
        };
        let second = cheapest(&in_front, Some(best));
        let ambiguous = second.is_some_and(|s| self.found[s].cost - self.found[best].cost <= margin);
        Some(Choice {
            best,
            second,
            ambiguous,
        })
    }
}

/// Whether the refined minima `a` and `b` are one minimum ([`SAME_MINIMUM`], or [`NO_BARRIER`]
/// between two that are closer than [`SAME_BASIN_SMALL`]).
fn same_minimum(a: &LocalMinimum, b: &LocalMinimum, cost: &impl PoseCost) -> bool {
    let (turn, shift) = (
        rotation_distance(&a.pose.rotation, &b.pose.rotation),
        (a.pose.translation - b.pose.translation).norm(),
    );
    if turn < SAME_MINIMUM && shift < SAME_MINIMUM {
        return true;
    }
    if !(turn < SAME_BASIN_SMALL && shift < SAME_BASIN_SMALL) {
        return false;
    }
    let half_turn = exp_so3(&(0.5 * log_so3(&(b.pose.rotation * a.pose.rotation.transpose()))));
    let midpoint = Pose::new(
        half_turn * a.pose.rotation,
        0.5 * (a.pose.translation + b.pose.translation),
    );
    let higher = a.cost.max(b.cost);
    cost.cost(&midpoint) <= higher * (1.0 + NO_BARRIER) + 1e-24
}

/// The refinement's trust-region settings: `opts.refinement` with Hebden steps.
fn settings(opts: &PoseOptions) -> crate::optim::TrustRegionOptions {
    let mut tr = opts.refinement;
    tr.subproblem = Subproblem::Hebden;
    tr
}

/// One refinement from `start` (conditioned frame).
fn refine_once(cost: &impl PoseCost, start: &Pose, opts: &PoseOptions) -> (LocalMinimum, Summary) {
    let (pose, summary) = trust_region::minimize(cost, *start, &settings(opts));
    let minimum = LocalMinimum {
        pose,
        cost: summary.final_cost,
        behind: cost.points_behind(&pose),
        termination: summary.termination,
    };
    (minimum, summary)
}

/// Refines every start of `starts` (conditioned frame, the algebraic answers) and then the promising
/// minimal poses of `hypotheses`, one group per sample (see the module documentation).
///
/// When every triple is a sample (`exhaustive`) all groups are ranked together. Otherwise the groups
/// are taken in turn: the promising poses of a group are refined, and the search stops after the first
/// group with a pose within [`SAME_BASIN`] of the best minimum, when that minimum has every point in
/// front: a wide, exactly fitted sample that lands in that basin, and whose other promising poses (a
/// twin, say) led nowhere better, confirms it; the other samples are not solved. Groups after the
/// first [`SPREAD_SAMPLES`] (the reserve) are solved only while no minimum has every point in front.
pub fn search(
    cost: &impl PoseCost,
    starts: &[Pose],
    hypotheses: impl Iterator<Item = Vec<Pose>>,
    exhaustive: bool,
    opts: &PoseOptions,
) -> Minima {
    let floor = 0.5 * cost.residual_count() as f64;
    let factor = (PROMISING_FACTOR / (cost.residual_count() / 2).max(1) as f64).max(PROMISING_FACTOR_MIN);
    let mut minima = Minima::new();
    for start in starts {
        let (m, s) = refine_once(cost, start, opts);
        minima.add(m, &s, cost);
    }
    let basin = if exhaustive { SAME_BASIN_SMALL } else { SAME_BASIN };
    let refine_promising = |minima: &mut Minima, group: &[Pose]| {
        let limit = |minima: &Minima| factor * minima.best_cost().max(floor);
        let bound = limit(minima);
        let mut ranked: Vec<(f64, Pose)> = group
            .iter()
            .copied()
            .filter(|h| !minima.near(h, basin))
            .filter_map(|h| cost.cost_below(&h, bound).map(|c| (c, h)))
            .collect();
        ranked.sort_by(|a, b| a.0.total_cmp(&b.0));
        for (c, h) in ranked {
            if !(c < limit(minima)) {
                break;
            }
            if minima.near(&h, basin) {
                continue;
            }
            let (m, s) = refine_once(cost, &h, opts);
            minima.add(m, &s, cost);
        }
    };
    if exhaustive {
        let all: Vec<Pose> = hypotheses.flatten().collect();
        refine_promising(&mut minima, &all);
    } else {
        for (k, group) in hypotheses.enumerate() {
            let in_front = minima.found.iter().any(|m| m.behind == 0);
            if k >= SPREAD_SAMPLES && in_front {
                break;
            }
            refine_promising(&mut minima, &group);
            let best = minima.choose(0.0).map(|c| &minima.found[c.best]);
            if best.is_some_and(|b| {
                b.behind == 0
                    && group
                        .iter()
                        .any(|h| rotation_distance(&h.rotation, &b.pose.rotation) < SAME_BASIN)
            }) {
                break;
            }
        }
    }
    minima
}

/// Minimises the reprojection error from `initial` (world frame) with the trust region of section 4.1
/// (Hebden steps on `JᵀJ`). The search runs in the conditioned frame; the returned pose is in the world.
///
/// The pixels are taken as a pinhole's: a `camera` that distorts is [`Error::InvalidOption`] naming it
/// (through a lens, [`crate::pose::estimate_pose`] with [`PoseOptions::initial_pose`] refines the exact
/// pixel cost).
pub fn refine_pose(
    camera: &Camera,
    corr: &Correspondences,
    initial: &Pose,
    opts: &PoseOptions,
) -> Result<(Pose, StageReport)> {
    if camera.distorts() {
        return Err(Error::InvalidOption {
            name: "camera".into(),
            reason: format!(
                "a {} camera distorts; refine_pose takes pinhole pixels (estimate_pose with initial_pose \
                 refines through a lens)",
                camera.model().as_str()
            ),
        });
    }
    let camera = camera.intrinsics();
    let cond = if opts.normalize {
        Conditioning::of(corr)
    } else {
        Conditioning::identity()
    };
    Ok(refine_conditioned(
        &cond,
        &ReprojectionCost::of(&camera, &cond.correspondences(corr)),
        initial,
        opts,
    ))
}

/// [`refine_pose`] on correspondences already conditioned by `cond` (`initial` and the answer in the
/// world frame).
pub(crate) fn refine_conditioned(
    cond: &Conditioning,
    cost: &ReprojectionCost<'_>,
    initial: &Pose,
    opts: &PoseOptions,
) -> (Pose, StageReport) {
    let started = Instant::now();
    let x0 = Pose::new(
        initial.rotation,
        cond.pose_from_world(&initial.rotation, &initial.translation),
    );
    let (x, summary) = trust_region::minimize(cost, x0, &settings(opts));
    let pose = Pose::new(x.rotation, cond.pose_to_world(&x.rotation, &x.translation));
    (
        pose,
        stage("refinement", CostKind::Reprojection, &pose, &summary, started),
    )
}
