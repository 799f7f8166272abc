//! Branch and bound for a point (Josephson & Kahl 2008, section 4), when the convexity test of
//! [`super::certificate`] cannot decide.
//!
//! **Coordinates.** The box is over the whitened coordinates `y` of the mean-depth chart around the
//! local solution `X̂` ([`super::chart`]): per view the numerator `aᵢ(y)` and the denominator
//! `ζᵢ(y)` of the fraction `‖rᵢ‖² = ‖aᵢ‖²/ζᵢ²` are affine, points at infinity are finite (`w = 0`),
//! and the denominators' intervals over a box follow exactly from it (interval arithmetic on affine
//! functions). Branching on three coordinates therefore refines every view's denominator — the
//! paper's remark that three branching dimensions suffice for a point (section 4.2). The axis to
//! split is the one contributing most to the widest relative denominator interval `(Uᵢ − Lᵢ)/Lᵢ`;
//! the split is at the relaxed minimiser kept inside the middle half of the interval.
//!
//! **Search set.** Every point at least as good as `X̂` lies in `S_{ε₀}` (each view's error is at
//! most `ε₀ = √f(X̂)`: the paper's γ of section 4.3.1, taken from the incumbent so that nothing
//! cheaper is left out) and in the enclosure `K` of `crate::global::convexity::enclosure`
//! (`S_{ε₀}` cut by an ellipsoid); points outside cost more than `f(X̂)`. The search runs over
//! `K ∩ S_{ε₀} ∩ {w ≥ 0}`, so a lower bound below `f(X̂)` is a lower bound over every point in front
//! of the cameras.
//!
//! **Initial box (sections 4.3.1, eq. 26).** The bounding box of `K` and its depth bounds
//! `ζᵢ ∈ [1 − κ_d, 1 + κ_d]` when the enclosure exists; otherwise six SOCPs give the extent of the
//! search set along each axis: their primal values suggest a box `B` (enlarged by 5 %), their dual
//! bounds over the set `∩ B` prove the extent, and when that lies strictly inside `B` the convex set
//! lies in `B` (leaving `B` it would cross its boundary inside the proved extent). Views whose
//! denominator interval reaches below `½` get their own eq. 26 solve `min ζᵢ`.
//!
//! **Bound (section 4.1).** One SOCP per node over `y` and per view a variable `rᵢ ≥ ‖rᵢ(y)‖²`'s
//! relaxation, minimising `Σ rᵢ` under the search-set constraints (`w ≥ 0`, the ellipsoid of `K`,
//! and the per-view cones of `S_{ε₀}` only when there is no ellipsoid: dropping constraints keeps a
//! relaxation valid), with [`Relaxation`] choosing
//! the relaxation of each fraction: the paper's eqs. 21-22 (`‖aᵢ‖² ≤ tᵢζᵢ`, `rᵢ ≥ convenv(tᵢ/ζᵢ)` over
//! `tᵢ ∈ [0, uᵢ]`, `ζᵢ ∈ [Lᵢ, Uᵢ]`, `uᵢ = min(ε₀²Uᵢ, max over the box corners of ‖aᵢ‖²/ζᵢ)`), or the
//! secant `‖aᵢ‖² ≤ rᵢ((Uᵢ + Lᵢ)ζᵢ − UᵢLᵢ)`, which is the convex envelope of `‖a‖²/ζ²` over the slab
//! `ζ ∈ [L, U]` (`ζ² ≤ (U + L)ζ − UL` there, with equality at both ends; its relative gap is
//! `(ζ − L)(U − ζ)/ζ²`, quadratic in the interval), or both. The bound is the dual bound of
//! [`crate::global::socp`], valid despite the solver's tolerance. The upper bound comes from a
//! local minimisation started at the relaxed minimiser.

use super::certificate::a_priori_kappa;
use super::chart::{Chart, ChartKind, ChartView};
use super::cost::{in_front, point_cost, PointObjective, PointView};
use crate::global::branch_and_bound::{branch_and_bound, Bound, BoundingOracle, BranchAndBoundOptions, Region};
use crate::global::convexity::{enclosure, Enclosure};
use crate::global::envelopes::{add_fraction_envelope, add_quadratic_over_linear, FractionBox};
use crate::global::socp::{Affine, Socp, SocpStatus};
use crate::global::CERTIFICATE_COST_FLOOR;
use crate::interrupt::StopReason;
use crate::optim::{trust_region, TrustRegionOptions};
use nalgebra::Vector3;

/// Views whose denominator can fall below this value get an eq. 26 solve.
const WEAK_DEPTH: f64 = 0.5;
/// Relative enlargement of the suggested initial box.
const BOX_MARGIN: f64 = 0.05;

/// The relaxation of each fraction in the node SOCP (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Relaxation {
    /// Eqs. 21-22: the envelope of `t/s` over the box of `(t, s)`.
    Fractional,
    /// The secant (convex envelope of `‖a‖²/ζ²` over the slab).
    Secant,
    /// Both constraints on the same `rᵢ`.
    Both,
}

/// The relaxation used by `optimal`. Measured on ten 0.2°-parallax scenes each (1 px noise, gap
/// 1e-3): the secant needs 2, 2.6 and 3 nodes on average at 5, 10 and 20 views, eqs. 21-22 need 14,
/// 20 and 24 nodes with SOCPs about four times larger; both together need the secant's nodes at the
/// larger SOCPs' price. Every choice gives valid bounds (test `both_relaxations_give_valid_bounds…`).
pub(crate) const DEFAULT_RELAXATION: Relaxation = Relaxation::Secant;

/// How the search ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GlobalStatus {
    /// The gap closed.
    Converged,
    /// The node cap was reached first.
    NodeLimit,
    /// The call was stopped first ([`crate::interrupt`]).
    Stopped(StopReason),
    /// The search set is unbounded or reaches a camera's principal plane: no box, no certificate.
    Unbounded,
    /// A conic solve of the initial box failed, the chart is singular, or the solver declared
    /// empty a search set that holds the incumbent (a numerical artefact: nothing is proved).
    Failed,
}

/// The outcome of [`global_point`].
#[derive(Debug, Clone, PartialEq)]
pub struct GlobalPoint {
    /// The best point found (the local solution unless a node improved on it).
    pub point: Vector3<f64>,
    /// Its cost (eq. 19).
    pub cost: f64,
    /// A valid lower bound of the cost over the search set (0 when none was proved), capped at `cost`.
    pub lower_bound: f64,
    /// The bound the search proved over its box, before the cap (NaN when nothing was proved).
    pub raw_lower_bound: f64,
    /// How it ended.
    pub status: GlobalStatus,
    /// Nodes whose bound was computed.
    pub nodes: usize,
    /// Interior-point iterations, summed (initial box included).
    pub solver_iterations: usize,
}

/// The affine rows of one view over the variables `y`.
fn numerator(v: &ChartView, y: &[usize; 3]) -> [Affine; 2] {
    let row = |k: usize| Affine {
        terms: (0..3).map(|j| (y[j], v.g[(k, j)])).collect(),
        constant: v.a0[k],
    };
    [row(0), row(1)]
}

fn denominator(v: &ChartView, y: &[usize; 3]) -> Affine {
    Affine {
        terms: (0..3).map(|j| (y[j], v.d[j])).collect(),
        constant: 1.0,
    }
}

/// The exact range of `ζ` over a box.
fn denominator_range(v: &ChartView, region: &Region) -> (f64, f64) {
    let (mut lo, mut hi) = (1.0, 1.0);
    for k in 0..3 {
        let (a, b) = (v.d[k] * region.lower[k], v.d[k] * region.upper[k]);
        lo += a.min(b);
        hi += a.max(b);
    }
    (lo, hi)
}

/// `max ‖a‖²/ζ` over the corners of a box on which `ζ > 0` (a convex function peaks at a corner).
fn numerator_peak(v: &ChartView, region: &Region) -> f64 {
    (0..8)
        .map(|corner| {
            let y = Vector3::from_fn(|k, _| {
                if corner & (1 << k) == 0 {
                    region.lower[k]
                } else {
                    region.upper[k]
                }
            });
            v.numerator(&y).norm_squared() / v.denominator(&y)
        })
        .fold(0.0, f64::max)
}

/// The constraints of the search set (module docs) on the variables `y`: `w ≥ 0`, the per-view
/// cones of `S_γ` when `gamma` is given (`γ = ε₀`), the ellipsoid of `K` when `enclosure` is.
fn add_search_set(p: &mut Socp, chart: &Chart, y: &[usize; 3], gamma: Option<f64>, enclosure: Option<&Enclosure<3>>) {
    let w = Affine {
        terms: (0..3).map(|j| (y[j], -chart.w_gradient[j])).collect(),
        constant: 1.0,
    };
    p.nonneg(w);
    for v in chart.views.iter().filter(|_| gamma.is_some()) {
        p.second_order(denominator(v, y).scaled(gamma.unwrap_or(0.0)), &numerator(v, y));
    }
    if let Some(k) = enclosure {
        let rows: Vec<Affine> = chart.views.iter().flat_map(|v| numerator(v, y)).collect();
        p.second_order(Affine::constant(k.q_bound()), &rows);
    }
}

/// The bounding oracle of the module docs.
struct PointOracle<'a> {
    views: &'a [PointView],
    chart: Chart,
    enclosure: Option<Enclosure<3>>,
    /// Denominator bounds valid on the whole search set.
    root_depths: Vec<(f64, f64)>,
    gamma: f64,
    relaxation: Relaxation,
    local: TrustRegionOptions,
    max_relative_gap: f64,
    /// Whether the nodes carry the per-view cones of `S_γ` (needed without the enclosure; otherwise
    /// the ellipsoid of `K` bounds every view and the cones are left out of the relaxation, which
    /// stays valid and is measured 30 % cheaper at 20 views).
    view_cones: bool,
}

impl PointOracle<'_> {
    /// Per view `(L, U, ζ > 0 on the whole box)`, or `None` if an interval is empty.
    fn depth_intervals(&self, region: &Region) -> Option<Vec<(f64, f64, bool)>> {
        let mut out = Vec::with_capacity(self.chart.views.len());
        for (v, &(root_lo, root_hi)) in self.chart.views.iter().zip(&self.root_depths) {
            let (lo, hi) = denominator_range(v, region);
            let (l, u) = (lo.max(root_lo), hi.min(root_hi));
            if l > u {
                return None;
            }
            out.push((l, u, lo > 0.0));
        }
        Some(out)
    }

    /// The local minimisation from the chart point `y`, kept if it ends in front of every camera.
    fn polish(&self, y: &[f64]) -> Option<(f64, Vector3<f64>)> {
        let x0 = self.chart.point(&Vector3::new(y[0], y[1], y[2]))?;
        let (x, _) = trust_region::minimize(&PointObjective { views: self.views }, x0, &self.local);
        in_front(self.views, &x).then(|| (point_cost(self.views, &x), x))
    }
}

impl BoundingOracle for PointOracle<'_> {
    type Candidate = Vector3<f64>;
    type Inherited = ();

    fn bound(&mut self, region: &Region) -> Bound<Vector3<f64>> {
        let Some(intervals) = self.depth_intervals(region) else {
            return Bound::Empty { solver_iterations: 0 };
        };
        let mut p = Socp::new();
        let y = [0, 1, 2].map(|k| p.add_variable(region.lower[k], region.upper[k]));
        for (k, &yk) in y.iter().enumerate() {
            p.nonneg(Affine::var(yk).shifted(-region.lower[k]));
            p.nonneg(Affine::term(yk, -1.0).shifted(region.upper[k]));
        }
        let cones = self.view_cones.then_some(self.gamma);
        add_search_set(&mut p, &self.chart, &y, cones, self.enclosure.as_ref());
        // On the relaxed set ‖aᵢ‖ ≤ q (the ellipsoid) and, with the cones, ‖aᵢ‖ ≤ γζᵢ ≤ γUᵢ.
        let q = self.enclosure.as_ref().map_or(f64::INFINITY, |k| k.q_bound());
        let mut objective = Affine::default();
        for (v, &(lo, hi, positive)) in self.chart.views.iter().zip(&intervals) {
            let a = numerator(v, &y);
            let zeta = denominator(v, &y);
            let a_max = if self.view_cones { q.min(self.gamma * hi) } else { q };
            // The relaxation's minimiser has rᵢ = ‖aᵢ‖²/((U + L)ζ − UL) ≤ a_max²/L²: a declared
            // bound holding at the optimum is enough for the dual bound (the optimum lies inside).
            let r = p.add_variable(0.0, a_max * a_max / (lo * lo));
            if self.relaxation != Relaxation::Fractional {
                let secant = zeta.clone().scaled(hi + lo).shifted(-hi * lo);
                add_quadratic_over_linear(&mut p, &a, &secant, &Affine::var(r));
            }
            if self.relaxation != Relaxation::Secant {
                // tᵢ ≥ fᵢ = ‖aᵢ‖²/ζᵢ ≤ min(γ²Uᵢ, q²/Lᵢ): the box of eq. 22 keeps every feasible y.
                let mut t_upper = a_max * a_max / lo;
                if self.view_cones {
                    t_upper = t_upper.min(self.gamma * self.gamma * hi);
                }
                if positive {
                    t_upper = t_upper.min(numerator_peak(v, region));
                }
                let t = p.add_variable(0.0, t_upper);
                add_quadratic_over_linear(&mut p, &a, &zeta, &Affine::var(t));
                let b = FractionBox {
                    t_lower: 0.0,
                    t_upper,
                    s_lower: lo,
                    s_upper: hi,
                };
                let envelope = add_fraction_envelope(&mut p, &Affine::var(t), &zeta, &b);
                p.less_eq(&Affine::var(envelope), &Affine::var(r));
            }
            objective = objective.plus(&Affine::var(r));
        }
        p.minimize(objective);
        let sol = p.solve();
        let solver_iterations = sol.iterations;
        match sol.status {
            SocpStatus::Infeasible => Bound::Empty { solver_iterations },
            SocpStatus::Solved if sol.lower_bound.is_finite() => {
                let relaxed: Vec<f64> = (0..3)
                    .map(|k| sol.x[y[k]].clamp(region.lower[k], region.upper[k]))
                    .collect();
                let candidate = self.polish(&relaxed);
                Bound::Bounded {
                    lower: sol.lower_bound.max(0.0),
                    relaxed_minimizer: Some(relaxed),
                    candidate,
                    solver_iterations,
                }
            }
            _ => Bound::Failed { solver_iterations },
        }
    }

    fn absolute_gap(&self) -> f64 {
        self.max_relative_gap * CERTIFICATE_COST_FLOOR
    }

    fn split(&self, region: &Region, relaxed_minimizer: Option<&[f64]>) -> (usize, f64) {
        // The view with the widest relative denominator interval, then the axis that widens it most.
        let widest = self
            .chart
            .views
            .iter()
            .zip(&self.root_depths)
            .map(|(v, &(root_lo, root_hi))| {
                let (lo, hi) = denominator_range(v, region);
                let (l, u) = (lo.max(root_lo), hi.min(root_hi));
                ((u - l) / l, v)
            })
            .max_by(|a, b| a.0.total_cmp(&b.0))
            .map(|(_, v)| v);
        let contribution = |k: usize| widest.map_or(1.0, |v| v.d[k].abs()) * region.width(k);
        let mut axis = (0..3)
            .max_by(|&a, &b| contribution(a).total_cmp(&contribution(b)))
            .unwrap_or(0);
        if contribution(axis) <= 0.0 {
            axis = (0..3)
                .max_by(|&a, &b| region.width(a).total_cmp(&region.width(b)))
                .unwrap_or(0);
        }
        let at = relaxed_minimizer.map_or(0.5 * (region.lower[axis] + region.upper[axis]), |m| m[axis]);
        (axis, region.central(axis, at))
    }
}

/// The initial box and the denominator bounds on the search set.
struct Root {
    region: Region,
    depths: Vec<(f64, f64)>,
    solver_iterations: usize,
}

/// The initial box by conic solves (module docs).
fn root_by_solves(chart: &Chart, gamma: f64, enclosure: Option<&Enclosure<3>>) -> Result<Root, GlobalStatus> {
    let mut base = Socp::new();
    let y = [0, 1, 2].map(|_| base.add_variable(f64::NEG_INFINITY, f64::INFINITY));
    add_search_set(&mut base, chart, &y, Some(gamma), enclosure);
    let mut iterations = 0;
    let mut solves = Vec::with_capacity(6);
    for &yk in &y {
        for sign in [1.0, -1.0] {
            let mut p = base.clone();
            p.minimize(Affine::term(yk, sign));
            let sol = p.solve();
            iterations += sol.iterations;
            match sol.status {
                SocpStatus::Solved => solves.push((p, sol)),
                // The set holds the incumbent: an infeasibility certificate is an artefact.
                SocpStatus::Infeasible | SocpStatus::Failed => return Err(GlobalStatus::Failed),
                SocpStatus::Unbounded => return Err(GlobalStatus::Unbounded),
                SocpStatus::Stopped(reason) => return Err(GlobalStatus::Stopped(reason)),
            }
        }
    }
    // The suggested box from the primal values, then the proof that the set lies inside it.
    let (mut lower, mut upper) = ([0.0; 3], [0.0; 3]);
    for k in 0..3 {
        let (lo, hi) = (solves[2 * k].1.x[y[k]], solves[2 * k + 1].1.x[y[k]]);
        let margin = BOX_MARGIN * (hi - lo).abs() + 1e-9 * (1.0 + lo.abs().max(hi.abs()));
        lower[k] = lo - margin;
        upper[k] = hi + margin;
    }
    let mut proved = Region::new(vec![0.0; 3], vec![0.0; 3]);
    for k in 0..3 {
        for (i, (p, sol)) in solves[2 * k..2 * k + 2].iter_mut().enumerate() {
            for j in 0..3 {
                p.set_variable_bounds(y[j], lower[j], upper[j]);
            }
            let bound = p.lower_bound(&sol.z);
            if i == 0 {
                proved.lower[k] = bound;
            } else {
                proved.upper[k] = -bound;
            }
        }
        if !(proved.lower[k] > lower[k] && proved.upper[k] < upper[k]) {
            return Err(GlobalStatus::Failed);
        }
    }
    let mut depths = Vec::with_capacity(chart.views.len());
    for v in &chart.views {
        let (mut lo, hi) = denominator_range(v, &proved);
        if lo < WEAK_DEPTH {
            let mut p = base.clone();
            for (j, &yj) in y.iter().enumerate() {
                p.set_variable_bounds(yj, proved.lower[j], proved.upper[j]);
                p.nonneg(Affine::var(yj).shifted(-proved.lower[j]));
                p.nonneg(Affine::term(yj, -1.0).shifted(proved.upper[j]));
            }
            p.minimize(denominator(v, &y));
            let sol = p.solve();
            iterations += sol.iterations;
            match sol.status {
                SocpStatus::Solved => {}
                SocpStatus::Stopped(reason) => return Err(GlobalStatus::Stopped(reason)),
                _ => return Err(GlobalStatus::Failed),
            }
            lo = lo.max(sol.lower_bound);
        }
        if !(lo > 0.0) {
            return Err(GlobalStatus::Unbounded);
        }
        depths.push((lo, hi));
    }
    Ok(Root {
        region: proved,
        depths,
        solver_iterations: iterations,
    })
}

/// Settings of [`global_point`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GlobalSettings {
    /// Stop when `(upper − lower) ≤ max_relative_gap · upper`.
    pub max_relative_gap: f64,
    /// Node cap.
    pub max_nodes: usize,
    /// The local minimisation of the upper bounds.
    pub local: TrustRegionOptions,
    /// The relaxation of each fraction.
    pub relaxation: Relaxation,
}

/// Minimises eq. 19 by branch and bound over the search set of the module docs, from the incumbent
/// `x_local` (in front of every camera, with cost `cost_local`: the local solution). The chart is
/// centred at the first of `x_local` and `origins` where it is well conditioned (a local solution
/// that ran off towards infinity is not; a point in front of the cameras at a moderate depth is).
pub fn global_point(
    views: &[PointView],
    x_local: &Vector3<f64>,
    cost_local: f64,
    origins: &[Vector3<f64>],
    settings: &GlobalSettings,
) -> GlobalPoint {
    let GlobalSettings {
        max_relative_gap,
        max_nodes,
        local,
        relaxation,
    } = *settings;
    let finish = |status| GlobalPoint {
        point: *x_local,
        cost: cost_local,
        lower_bound: 0.0,
        raw_lower_bound: f64::NAN,
        status,
        nodes: 0,
        solver_iterations: 0,
    };
    let chart = std::iter::once(x_local)
        .chain(origins)
        .find_map(|x| Chart::new(views, x, ChartKind::MeanDepth));
    let Some(chart) = chart else {
        return finish(GlobalStatus::Failed);
    };
    // Every point at least as good as the incumbent lies in S_γ ∩ K for γ = ε₀ (module docs).
    let gamma = cost_local.sqrt();
    let enclosure = enclosure(
        &chart.views,
        cost_local,
        gamma,
        a_priori_kappa(ChartKind::MeanDepth, chart.views.len()),
    );
    let from_enclosure = enclosure.as_ref().and_then(|k| {
        let (lo, hi) = k.bounding_box()?;
        Some(Root {
            region: Region::new(
                lo.iter().copied().collect::<Vec<f64>>(),
                hi.iter().copied().collect::<Vec<f64>>(),
            ),
            depths: vec![(1.0 - k.kappa_d, 1.0 + k.kappa_d); views.len()],
            solver_iterations: 0,
        })
    });
    let root = match from_enclosure {
        Some(root) => root,
        None => match root_by_solves(&chart, gamma, enclosure.as_ref()) {
            Ok(root) => root,
            Err(status) => return finish(status),
        },
    };
    let view_cones = enclosure.is_none();
    let mut oracle = PointOracle {
        views,
        chart,
        enclosure,
        root_depths: root.depths,
        gamma,
        relaxation,
        local,
        max_relative_gap,
        view_cones,
    };
    let opts = BranchAndBoundOptions {
        max_relative_gap,
        max_nodes,
        trivial_lower_bound: 0.0,
    };
    let result = branch_and_bound(&mut oracle, root.region, Some((cost_local, *x_local)), &opts);
    let (cost, point) = result.best.unwrap_or((cost_local, *x_local));
    // An empty search set although it holds the incumbent: a numerical artefact of the
    // infeasibility certificates, which proves nothing.
    let status = if result.box_lower_bound == f64::INFINITY {
        GlobalStatus::Failed
    } else if result.converged {
        GlobalStatus::Converged
    } else if let Some(reason) = result.stopped {
        GlobalStatus::Stopped(reason)
    } else {
        GlobalStatus::NodeLimit
    };
    if status == GlobalStatus::Failed {
        return GlobalPoint {
            nodes: result.nodes,
            solver_iterations: result.solver_iterations + root.solver_iterations,
            ..finish(status)
        };
    }
    GlobalPoint {
        point,
        cost,
        lower_bound: result.lower_bound.min(cost),
        raw_lower_bound: result.box_lower_bound,
        status,
        nodes: result.nodes,
        solver_iterations: result.solver_iterations + root.solver_iterations,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::interrupt::{with_stop, Stop};
    use crate::rng::Rng;
    use crate::synthetic::triangulation_scene;
    use crate::triangulation::point::cost::point_views;
    use crate::triangulation::views::depth_normalized;
    use nalgebra::{Matrix2, Matrix3x4};
    use std::sync::Arc;
    use std::time::Duration;

    /// The initial box by conic solves, stopped (Ctrl-C, or the time budget): its solves end at once
    /// and the search says it was stopped, not that a solve failed (`numerical_failure`).
    #[test]
    fn a_stop_during_the_solves_of_the_initial_box_is_reported_as_a_stop() {
        let scene = triangulation_scene(4, 0.3, 9);
        let obs = scene.noisy(1.0, &mut Rng::new(9));
        let ps: Vec<Matrix3x4<f64>> = scene.cameras.iter().map(depth_normalized).collect();
        let views = point_views(&ps, &obs, &[Matrix2::identity(); 4]);
        let chart = Chart::new(&views, &scene.point, ChartKind::MeanDepth).unwrap();
        let gamma = 10.0;
        assert!(root_by_solves(&chart, gamma, None).is_ok());
        let requested = Arc::new(Stop::new());
        requested.request();
        let stopped = with_stop(requested, || root_by_solves(&chart, gamma, None).err());
        assert_eq!(stopped, Some(GlobalStatus::Stopped(StopReason::Requested)));
        let expired = Arc::new(Stop::with_time_budget(Some(Duration::ZERO)));
        let stopped = with_stop(expired, || root_by_solves(&chart, gamma, None).err());
        assert_eq!(stopped, Some(GlobalStatus::Stopped(StopReason::TimeBudget)));
    }
}
