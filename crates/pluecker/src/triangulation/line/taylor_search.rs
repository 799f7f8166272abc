//! The Taylor certificate of a line: interval branch and bound over the two-view chart.
//!
//! **Domain.** Every line cheaper than the local line `𝓛̂` lies in the ball `‖z‖² ≤ f(𝓛̂)` of the
//! chart of [`super::two_view_chart`], which covers every 3-D line not through a camera centre
//! (lines through a centre have no image there, so no cost). The search box is that ball's bounding
//! box in the branching coordinates `w`. Lines closer to a camera centre than
//! [`super::two_view_chart::CENTRE_CLEARANCE`] (1 %) of `𝓛̂`'s distance from it are left out: their
//! image in that view can be any line through one point, so eq. 19 there reaches values that no line
//! seen as a segment has (regions proved inside that tube are discarded; a local step ending there
//! is not an upper bound). The estimate is `𝓛̂` unless a cheaper line of the domain is found; the
//! certificate's domain is reported ([`crate::triangulation::CertificateKind::domain`]).
//!
//! **Bound per region** ([`crate::global::taylor_bound`]): the larger of the zeroth-order interval
//! bound `Σ mig([rᵥₖ])²` (with the projective test near a view's pole) and the second-order Taylor
//! bound with the Gershgorin curvature of the interval Hessian; and the **convex-hull bound**: when
//! the interval Hessian is positive definite (`⪰ μI`) on the box hull of the region and `𝓛̂`
//! (`w = 0`), `f ≥ f(0) − ‖∇f(0)‖²/(2μ)` on the region. Often the whole search box is convex and the
//! certificate is proved at the root.
//!
//! **Stationarity.** A global minimiser is cheaper than `𝓛̂` (or is `𝓛̂`), so it lies strictly inside
//! the ball where the cost is smooth (denominators non-zero); off the boundary of the centre tubes it
//! is a stationary point. A region proved clear of every tube whose interval gradient excludes 0 in
//! some coordinate holds none and is discarded (Hansen's monotonicity test). Regions where a
//! denominator may vanish keep infinite derivative enclosures and are never discarded this way. So
//! a search that discards every region has proved that no line of the domain is cheaper than `𝓛̂`:
//! the bound is then `f(𝓛̂)`.
//!
//! **Upper bounds.** A region whose centre is cheaper than the incumbent starts a short local
//! minimisation there; a cheaper line found replaces the incumbent (the local method stopped in a
//! wrong minimum). Splitting: the widest axis at the midpoint. No conic program is solved.

use super::two_view_chart::{Clearance, TwoViewChart};
use super::{LineObjective, LineProblem};
use crate::geometry::plucker::{self, OrthonormalLine};
use crate::global::branch_and_bound::{branch_and_bound, Bound, BoundingOracle, BranchAndBoundOptions, Region};
use crate::global::taylor_bound::{bound_over_box, cost_and_gradient, ROUNDING_MARGIN};
use crate::optim::{trust_region, TrustRegionOptions};
use crate::triangulation::certificate::{certificate_of, optimal_start};
use crate::triangulation::conditioning::Similarity;
use crate::triangulation::fraction::{self, FractionalResidual};
use crate::triangulation::{Certificate, CertificateKind, Report, TriangulationOptions};
use nalgebra::{Vector4, Vector6};

/// The node cap of the Taylor search when `certify.max_nodes` is `None`: its nodes cost
/// microseconds (interval arithmetic, no conic program), so the cap is 25 times the conic searches'
/// ([`crate::triangulation::CONIC_MAX_NODES`]).
pub const MAX_NODES: usize = 50_000;

/// Trust-region iterations of the local step from a region's centre.
const NODE_LOCAL_ITERATIONS: usize = 20;

struct TaylorOracle<'a> {
    chart: &'a TwoViewChart,
    /// Every view's residual in the conditioned frame (for the local steps).
    views: &'a [FractionalResidual<2, 6>],
    incumbent: f64,
    /// The relative gap at which regions are discarded.
    gap: f64,
    /// The cost and gradient at `w = 0` (the local line), for the convex-hull bound.
    at_local: (f64, Vector4<f64>),
    local: TrustRegionOptions,
}

impl TaylorOracle<'_> {
    fn local_step(&self, w: &Vector4<f64>) -> Option<(f64, Vector6<f64>)> {
        let start = OrthonormalLine::from_plucker(&self.chart.line(w))?;
        let objective = LineObjective { views: self.views };
        let line = trust_region::minimize(&objective, start, &self.local).0.to_plucker();
        let cost = fraction::cost(self.views, &line);
        (cost.is_finite() && self.chart.is_clear(&line)).then_some((cost, line))
    }
}

impl TaylorOracle<'_> {
    /// The bound that discards a region: within the gap of the incumbent.
    fn target(&self) -> f64 {
        self.incumbent * (1.0 - self.gap)
    }

    /// The convex-hull bound: when the cost is convex (`∇²f ⪰ μI`, `μ > 0`) on the box hull `H` of
    /// `region` and the local line `w = 0`, then `f(w) ≥ f(0) + ∇f(0)·w + ½μ‖w‖² ≥ f(0) − ‖∇f(0)‖²/(2μ)`
    /// on `H ⊇ region`. `0` otherwise.
    fn hull_bound(&self, region: &Region) -> f64 {
        let lower: Vec<f64> = region.lower.iter().map(|&v| v.min(0.0)).collect();
        let upper: Vec<f64> = region.upper.iter().map(|&v| v.max(0.0)).collect();
        let mu = bound_over_box(&self.chart.views, &lower, &upper, f64::INFINITY).curvature;
        if mu.is_nan() || mu <= 0.0 {
            return 0.0;
        }
        let (f0, g0) = self.at_local;
        let bound = f0 - g0.norm_squared() / (2.0 * mu);
        (bound - ROUNDING_MARGIN * f0).max(0.0)
    }
}

impl BoundingOracle for TaylorOracle<'_> {
    type Candidate = Vector6<f64>;
    type Inherited = ();

    fn bound(&mut self, region: &Region) -> Bound<Vector6<f64>> {
        let empty = Bound::Empty { solver_iterations: 0 };
        let clearance = self.chart.clearance(&region.lower, &region.upper);
        if clearance == Clearance::Inside {
            return empty;
        }
        let b = bound_over_box(&self.chart.views, &region.lower, &region.upper, self.target());
        // A minimiser of the domain off its boundary is stationary (module docs).
        if !b.may_be_stationary && clearance == Clearance::Clear {
            return empty;
        }
        let mut lower = b.lower;
        if lower < self.incumbent {
            lower = lower.max(self.hull_bound(region));
        }
        let centre = region.centre();
        let candidate = if b.centre_cost < self.incumbent * (1.0 - 1e-9) {
            let found = self.local_step(&Vector4::from_column_slice(&centre));
            if let Some((cost, _)) = found {
                self.incumbent = self.incumbent.min(cost);
            }
            found
        } else {
            None
        };
        Bound::Bounded {
            lower,
            relaxed_minimizer: Some(centre),
            candidate,
            solver_iterations: 0,
        }
    }
}

/// The optimal method with the Taylor certificate (module docs) from the local line `local`
/// (world) and its report; `None` when the two-view chart has no accepted pair (the caller then uses
/// the relaxation of [`super::optimal`]).
pub(crate) fn optimal_line_taylor(
    problem: &LineProblem,
    local: &Vector6<f64>,
    local_report: &Report,
    opts: &TriangulationOptions,
) -> Option<(Vector6<f64>, Report)> {
    let mut report = match optimal_start(local_report) {
        Ok(report) => report,
        Err(certified) => return Some((*local, certified)),
    };
    let sim = Similarity::of_cameras(&problem.cameras);
    let views = problem.views(&sim);
    let frame_local = plucker::transform(&sim.matrix(), local);
    let cost = fraction::cost(&views, &frame_local);
    // Every line that can improve on 𝓛̂ has ‖z‖² ≤ f(𝓛̂) (module docs).
    let chart = TwoViewChart::new(problem, &sim, &views, &frame_local, cost)?;
    let mut local_opts = opts.local;
    local_opts.stopping.max_iterations = NODE_LOCAL_ITERATIONS;
    let mut oracle = TaylorOracle {
        chart: &chart,
        views: &views,
        incumbent: cost,
        gap: opts.certify.max_relative_gap,
        at_local: cost_and_gradient(&chart.views, &Vector4::zeros()),
        local: local_opts,
    };
    let bb_opts = BranchAndBoundOptions {
        max_relative_gap: opts.certify.max_relative_gap,
        max_nodes: opts.certify.max_nodes_or(MAX_NODES),
        trivial_lower_bound: 0.0,
    };
    let root = chart.root(cost.sqrt());
    let mut result = branch_and_bound(&mut oracle, root, Some((cost, frame_local)), &bb_opts);
    // Regions were discarded for holding no stationary point, which only shows that no line there
    // is cheaper than the local one (module docs): the proved bound is at most its cost (and is
    // that cost when every region was discarded).
    result.box_lower_bound = result.box_lower_bound.min(cost);
    let (best_cost, best) = result.best.unwrap_or((cost, frame_local));
    report.cost = best_cost;
    let (status, certificate) = certificate_of(&result, best_cost, opts.certify.max_relative_gap);
    report.status = status;
    report.certificate = certificate.map(|c| Certificate {
        kind: CertificateKind::TaylorBranchAndBound,
        ..c
    });
    Some((plucker::transform(&sim.inverse_matrix(), &best), report))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;
    use crate::triangulation::line::residual::LineFrame;
    use crate::triangulation::line::tests::ring_cameras;
    use nalgebra::{Matrix2, Vector3};

    /// Ring cameras and the images of the line through `a` and `b` with errors of `noise` (relative
    /// to the image line's coefficients, about `noise` × 500 px): a line problem whose minimum cost is
    /// far from 0, so that bounds near it are not the trivial 0.
    fn problem(n: usize, seed: u64, noise: f64) -> (LineProblem, (Vector3<f64>, Vector3<f64>)) {
        let mut rng = Rng::new(seed);
        let cameras = ring_cameras(n, &mut rng);
        let (a, b) = (Vector3::new(0.2, -0.3, 0.1), Vector3::new(-0.3, 0.4, -0.2));
        let frames = cameras
            .iter()
            .map(|p| {
                let l = (p * a.push(1.0)).cross(&(p * b.push(1.0)));
                let l = l / l.xy().norm() + Vector3::new(rng.normal(), rng.normal(), rng.normal() * 300.0) * noise;
                LineFrame::of_line(&l).unwrap()
            })
            .collect();
        let whitenings = vec![Matrix2::identity(); n];
        (
            LineProblem {
                cameras,
                frames,
                whitenings,
            },
            (a, b),
        )
    }

    /// The least cost over a box by projected gradient descent (backtracking) from its centre: an
    /// upper bound of the box's minimum.
    fn box_minimum(chart: &TwoViewChart, lower: &[f64], upper: &[f64]) -> f64 {
        let project = |w: Vector4<f64>| Vector4::from_fn(|i, _| w[i].clamp(lower[i], upper[i]));
        let mut w = Vector4::from_fn(|i, _| 0.5 * (lower[i] + upper[i]));
        let (mut f, mut g) = cost_and_gradient(&chart.views, &w);
        let mut step = (0..4).map(|i| upper[i] - lower[i]).fold(0.0, f64::max);
        for _ in 0..2000 {
            let mut moved = false;
            while step > 1e-15 {
                let trial = project(w - g * (step / g.norm().max(1e-300)));
                let (ft, gt) = cost_and_gradient(&chart.views, &trial);
                if ft < f {
                    (w, f, g) = (trial, ft, gt);
                    step *= 2.0;
                    moved = true;
                    break;
                }
                step *= 0.5;
            }
            if !moved {
                break;
            }
        }
        f
    }

    /// The convex-hull bound of a chart centred on a line that is not a minimum (the chart's origin
    /// has a gradient, so the bound `f(0) − ‖∇f(0)‖²/(2μ)` is not the origin's cost): over boxes around
    /// the minimiser, of every size, it stays below the box's minimum reached by descent.
    #[test]
    fn the_hull_bound_is_below_the_minimum_of_boxes_around_the_minimiser() {
        let mut checked = 0;
        for seed in 0..6u64 {
            let (problem, (a, b)) = problem(4 + seed as usize % 3, 70 + seed, 10f64.powf(-3.0 + 0.3 * seed as f64));
            let sim = Similarity::of_cameras(&problem.cameras);
            let views = problem.views(&sim);
            let mut rng = Rng::new(seed);
            for _ in 0..4 {
                let off =
                    Vector3::new(rng.normal(), rng.normal(), rng.normal()) * 10f64.powf(rng.uniform_in(-3.0, -1.5));
                let world = plucker::from_points(&a, &(b + off));
                let frame_line = plucker::transform(&sim.matrix(), &world);
                let cost = fraction::cost(&views, &frame_line);
                let Some(chart) = TwoViewChart::new(&problem, &sim, &views, &frame_line, cost) else {
                    continue;
                };
                let at_local = cost_and_gradient(&chart.views, &Vector4::zeros());
                let oracle = TaylorOracle {
                    chart: &chart,
                    views: &views,
                    incumbent: cost,
                    gap: 1e-3,
                    at_local,
                    local: TriangulationOptions::default().local,
                };
                let root = chart.root(cost.sqrt());
                // The minimiser over the root box, then boxes of every size around it.
                let least = box_minimum(&chart, &root.lower, &root.upper);
                let mut w_min = Vector4::zeros();
                {
                    // Recover the minimiser by the same descent, keeping the point.
                    let project = |w: Vector4<f64>| Vector4::from_fn(|i, _| w[i].clamp(root.lower[i], root.upper[i]));
                    let (mut f, mut g) = cost_and_gradient(&chart.views, &w_min);
                    let mut step = 1.0;
                    for _ in 0..5000 {
                        let trial = project(w_min - g * (step / g.norm().max(1e-300)));
                        let (ft, gt) = cost_and_gradient(&chart.views, &trial);
                        if ft < f {
                            (w_min, f, g) = (trial, ft, gt);
                            step *= 2.0;
                        } else {
                            step *= 0.5;
                            if step < 1e-15 {
                                break;
                            }
                        }
                    }
                    assert!(f <= least * (1.0 + 1e-6) + 1e-12);
                }
                for k in 0..8 {
                    let half = 10f64.powf(-4.0 + 0.5 * k as f64) * cost.sqrt();
                    let region = Region::new(
                        (0..4)
                            .map(|i| (w_min[i] - half * rng.uniform_in(0.2, 1.0)).max(root.lower[i]))
                            .collect::<Vec<f64>>(),
                        (0..4)
                            .map(|i| (w_min[i] + half * rng.uniform_in(0.2, 1.0)).min(root.upper[i]))
                            .collect::<Vec<f64>>(),
                    );
                    let bound = oracle.hull_bound(&region);
                    let minimum = box_minimum(&chart, &region.lower, &region.upper)
                        .min(cost_and_gradient(&chart.views, &w_min).0);
                    assert!(
                        bound <= minimum * (1.0 + 1e-12),
                        "seed {seed}, box {k}: hull bound {bound} above the box minimum {minimum} (origin {})",
                        at_local.0
                    );
                    checked += usize::from(bound > 0.0);
                }
            }
        }
        assert!(checked >= 20, "only {checked} boxes had a positive hull bound");
    }
}
