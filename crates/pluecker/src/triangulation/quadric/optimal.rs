//! Branch and bound for quadrics (Josephson & Kahl 2008, sections 4.1.1, 4.2, 4.3.1), when the
//! convexity test of [`super::certificate`], tried first, cannot close the gap.
//!
//! **Variables.** In the conditioned frame of the local ellipsoid (origin at its centre, unit its
//! largest semi-axis) the dual quadric is normalised to `L₄₄ = +1`, so that `L = [ccᵀ − S, c; cᵀ, 1]`
//! for an ellipsoid with centre `c` and shape `S = R diag(s²) Rᵀ`, and the other 9 entries `q` of
//! `L̃` are the variables. Eq. 14 makes every view's residual numerator `Aᵢ L̃` (5 entries) and
//! denominator `gᵢ = cᵢᵀ L̃` affine in `q`; `gᵢ` is the value of the dual quadric on the camera's
//! principal plane, positive exactly when that plane misses the ellipsoid.
//!
//! **Domain.** Quadrics (any symmetric `L` with `L₄₄ = 1`: the relaxation does not impose an
//! ellipsoid, so the bound also holds over every proper quadric) whose whitened residual is at most
//! `γ` in every view with positive denominators, and whose entries lie in the a-priori box
//! `|cₖ| ≤ B`, `|(ccᵀ − S)ⱼₖ| ≤ 2B²` with `B` = [`CENTRE_FACTOR`] times the largest distance from the
//! local centre to a camera (centres within that distance, semi-axes up to `B`). `γ` is
//! `sqrt(local cost)`: every quadric cheaper than the local one satisfies it.
//!
//! **Bound.** As for points (eq. 21-22): per view `‖Aᵢ L̃‖² ≤ tᵢ gᵢ`, the fraction envelope of
//! `tᵢ/gᵢ` over `tᵢ ∈ [0, min(γ², U) Gᵢᵁ]`, `gᵢ ∈ [Gᵢᴸ, Gᵢᵁ]` (a view whose interval starts at 0
//! contributes 0), the domain cones `‖Aᵢ L̃‖ ≤ γ gᵢ`, and the cut `Σ tᵢ/Gᵢᵁ ≤ U` with `U` the local
//! cost (lines costing more cannot improve on it). The initial box of the denominators is eq. 26
//! (their least and greatest values over the relaxation), after the same bound tightening of `q`.
//! Branching splits the denominators (section 4.2: one dimension per view), the widest at the relaxed
//! minimiser; each node's relaxed `q`, made an ellipsoid, starts a short local minimisation whose cost
//! is an upper bound.

use super::certificate::convexity_bound;
use super::{nearest_ellipsoid, transform_dual, EllipsoidPoint, QuadricObjective, QuadricProblem};
use crate::certificate::Primitive;
use crate::geometry::quadric::{sym4_to_vec, vec_to_sym4, Ellipsoid};
use crate::global::branch_and_bound::{branch_and_bound, Bound, BoundingOracle, BranchAndBoundOptions, Region};
use crate::global::envelopes::add_quadratic_over_linear;
use crate::global::socp::{Affine, Socp, SocpStatus};
use crate::interrupt::stop_reason;
use crate::optim::{trust_region, TrustRegionOptions};
use crate::triangulation::certificate::{certificate_of, minimum, optimal_start, solve_fraction_relaxation};
use crate::triangulation::fractional_residual::{self, FractionalResidual};
use crate::triangulation::{Certificate, CertificateKind, QuadricBound, Report, Status, TriangulationOptions};
use nalgebra::SVector;

/// `B` of the a-priori box (module docs) as a multiple of the largest camera distance.
pub const CENTRE_FACTOR: f64 = 10.0;
/// Trust-region iterations of the local step from each node's relaxed minimiser.
const NODE_LOCAL_ITERATIONS: usize = 10;
/// Stacked positions of the centre entries `L₁₄, L₂₄, L₃₄` among the 9 variables.
const CENTRE_ENTRIES: [usize; 3] = [3, 6, 8];

/// The bound oracle of the module docs.
struct QuadricOracle<'a> {
    views: &'a [FractionalResidual<5, 10>],
    gamma: f64,
    /// Bounds of the 9 variables.
    q_lower: Vec<f64>,
    q_upper: Vec<f64>,
    /// The local cost (the cut).
    incumbent: f64,
    local: TrustRegionOptions,
}

/// The relaxation over one box of denominators.
struct Relaxation {
    p: Socp,
    q: [usize; 9],
    /// Per view: denominator, its interval, `tᵢ` (absent without denominator bounds).
    views: Vec<(Affine, (f64, f64), Option<usize>)>,
}

impl QuadricOracle<'_> {
    /// `L̃` as affine expressions of the variables (`L₄₄ = 1`).
    fn stacked(q: &[usize; 9]) -> Vec<Affine> {
        let mut l: Vec<Affine> = q.iter().map(|&j| Affine::var(j)).collect();
        l.push(Affine::constant(1.0));
        l
    }

    /// The constraints of the module docs with `gᵢ ∈ [region]` (`None`: no denominator bounds, and no
    /// cut, for the first tightening pass).
    fn relaxation(&self, region: Option<&Region>) -> Relaxation {
        let mut p = Socp::new();
        let q: [usize; 9] = std::array::from_fn(|k| p.add_variable(self.q_lower[k], self.q_upper[k]));
        for (k, &j) in q.iter().enumerate() {
            p.less_eq(&Affine::constant(self.q_lower[k]), &Affine::var(j));
            p.less_eq(&Affine::var(j), &Affine::constant(self.q_upper[k]));
        }
        let l = Self::stacked(&q);
        let combine = |row: &[f64]| {
            row.iter()
                .zip(&l)
                .fold(Affine::constant(0.0), |acc, (&c, e)| acc.plus(&e.clone().scaled(c)))
        };
        let mut views = Vec::with_capacity(self.views.len());
        for (i, view) in self.views.iter().enumerate() {
            let g = combine(view.denominator.as_slice());
            let a: Vec<Affine> = (0..5)
                .map(|r| combine(&view.numerator.row(r).iter().copied().collect::<Vec<_>>()))
                .collect();
            p.second_order(g.clone().scaled(self.gamma), &a);
            let Some(r) = region else {
                views.push((g, (0.0, f64::INFINITY), None));
                continue;
            };
            let range = (r.lower[i], r.upper[i]);
            p.less_eq(&Affine::constant(range.0), &g);
            p.less_eq(&g, &Affine::constant(range.1));
            let t = p.add_variable(0.0, self.gamma.powi(2).min(self.incumbent) * range.1);
            add_quadratic_over_linear(&mut p, &a, &g, &Affine::var(t));
            views.push((g, range, Some(t)));
        }
        if region.is_some() {
            // The cut Σ tᵢ/Gᵢᵁ ≤ U (module docs).
            let cut = views
                .iter()
                .filter_map(|(_, range, t)| t.map(|t| Affine::term(t, 1.0 / range.1)))
                .fold(Affine::constant(0.0), |acc, e| acc.plus(&e));
            p.less_eq(&cut, &Affine::constant(self.incumbent));
        }
        Relaxation { p, q, views }
    }

    /// A short local minimisation from relaxed variables: the frame ellipsoid and its cost.
    fn local_step(&self, q: &[f64]) -> Option<(f64, Ellipsoid)> {
        let mut stacked = SVector::<f64, 10>::from_column_slice(&[q, &[1.0]].concat());
        stacked.neg_mut();
        let start = nearest_ellipsoid(&vec_to_sym4(&stacked))?;
        let objective = QuadricObjective { views: self.views };
        let (x, summary) = trust_region::minimize(&objective, EllipsoidPoint::of(&start), &self.local);
        let e = Ellipsoid::from_dual(&x.dual())?;
        summary.final_cost.is_finite().then_some((2.0 * summary.final_cost, e))
    }
}

impl BoundingOracle for QuadricOracle<'_> {
    type Candidate = Ellipsoid;
    type Inherited = ();

    fn bound(&mut self, region: &Region) -> Bound<Ellipsoid> {
        let Relaxation { mut p, q, views } = self.relaxation(Some(region));
        let terms = views.iter().filter_map(|(g, (lo, hi), t)| t.map(|t| (t, g, *lo, *hi)));
        let s = solve_fraction_relaxation(&mut p, terms, self.gamma.powi(2).min(self.incumbent));
        match s.status {
            SocpStatus::Infeasible => Bound::Empty {
                solver_iterations: s.iterations,
            },
            SocpStatus::Solved => {
                let qv: Vec<f64> = q.iter().map(|&j| s.x[j]).collect();
                let minimizer = views
                    .iter()
                    .enumerate()
                    .map(|(i, (g, ..))| g.eval(&s.x).clamp(region.lower[i], region.upper[i]))
                    .collect();
                Bound::Bounded {
                    lower: s.lower_bound.max(0.0),
                    relaxed_minimizer: Some(minimizer),
                    candidate: self.local_step(&qv),
                    solver_iterations: s.iterations,
                }
            }
            _ => Bound::Failed {
                solver_iterations: s.iterations,
            },
        }
    }
}

/// The optimal method from the local ellipsoid `local` (world) with report `local_report`: the best
/// world ellipsoid found and the report with its certificate (module docs).
pub(crate) fn optimal_quadric(
    problem: &QuadricProblem,
    local: &Ellipsoid,
    local_report: &Report,
    opts: &TriangulationOptions,
) -> (Ellipsoid, Report) {
    let mut report = match optimal_start(local_report, Primitive::Quadric) {
        Ok(report) => report,
        Err(certified) => return (*local, certified),
    };
    let cost = local_report.cost;
    let gamma = cost.sqrt();
    let sim = problem.frame_of(local);
    let frame_dual = transform_dual(&sim.matrix(), &local.dual());
    let reference = sym4_to_vec(&(-frame_dual / frame_dual[(3, 3)].abs()));
    let raw_views = problem.views(&sim);
    // The convexity test first (module docs of `super::certificate`); its bound is capped at the cost.
    let test = (opts.quadric_bound == QuadricBound::Convexity)
        .then(|| convexity_bound(&raw_views, &reference))
        .flatten()
        .and_then(|lower| {
            Certificate::of_convexity_test(Primitive::Quadric, cost, lower, opts.certify.max_relative_gap)
        });
    if let Some(certified) = test {
        report.status = Status::Success;
        report.certificate = Some(certified);
        return (*local, report);
    }
    let views: Vec<FractionalResidual<5, 10>> = raw_views.iter().map(|v| v.oriented(&reference)).collect();
    let frame_cost = fractional_residual::cost(&views, &reference);
    let reach = problem
        .cameras
        .iter()
        .map(|p| sim.camera(p))
        .map(|p| crate::triangulation::views::centre(&p).norm())
        .fold(0.0, f64::max);
    let b = CENTRE_FACTOR * reach.max(1.0);
    let (q_lower, q_upper): (Vec<f64>, Vec<f64>) = (0..9)
        .map(|k| {
            if CENTRE_ENTRIES.contains(&k) {
                (-b, b)
            } else {
                (-2.0 * b * b, 2.0 * b * b)
            }
        })
        .unzip();
    let mut node_local = opts.local;
    node_local.stopping.max_iterations = NODE_LOCAL_ITERATIONS;
    let mut oracle = QuadricOracle {
        views: &views,
        gamma,
        q_lower,
        q_upper,
        incumbent: frame_cost * (1.0 + 1e-9),
        local: node_local,
    };
    // The cones and the box hold the local ellipsoid: a relaxation found infeasible, or a denominator
    // left unbounded (a solve failed or was stopped), proves nothing: no box to search, no certificate.
    let artefact = |mut report: Report| {
        report.set_status(stop_reason().map_or(Status::NumericalFailure, Status::stopped));
        (*local, report)
    };
    // Eq. 26: the denominators' range without the cut, then the variables' and again the
    // denominators' with it.
    let mut iterations = 0;
    let mut root = Region::new(vec![0.0; views.len()], vec![0.0; views.len()]);
    for pass in 0..2 {
        let relax = oracle.relaxation(if pass == 0 { None } else { Some(&root) });
        if pass == 1 {
            for k in 0..9 {
                let var = Affine::var(relax.q[k]);
                let ((lo, a), (hi, b2)) = (minimum(&relax.p, var.clone()), minimum(&relax.p, var.scaled(-1.0)));
                iterations += a + b2;
                let (Some(lo), Some(hi)) = (lo, hi) else {
                    return artefact(report);
                };
                oracle.q_lower[k] = lo.map_or(oracle.q_lower[k], |v| v.max(oracle.q_lower[k]));
                oracle.q_upper[k] = hi.map_or(oracle.q_upper[k], |v| (-v).min(oracle.q_upper[k]));
            }
        }
        let relax = oracle.relaxation(if pass == 0 { None } else { Some(&root) });
        for (i, (g, ..)) in relax.views.iter().enumerate() {
            let ((lo, a), (hi, b2)) = (minimum(&relax.p, g.clone()), minimum(&relax.p, g.clone().scaled(-1.0)));
            iterations += a + b2;
            let (Some(lo), Some(hi)) = (lo, hi) else {
                return artefact(report);
            };
            let (old_lo, old_hi) = if pass == 0 {
                (0.0, f64::INFINITY)
            } else {
                (root.lower[i], root.upper[i])
            };
            root.lower[i] = lo.map_or(old_lo, |v| v.max(old_lo));
            root.upper[i] = hi.map_or(old_hi, |v| (-v).min(old_hi));
            if !root.upper[i].is_finite() || root.lower[i] > root.upper[i] {
                return artefact(report);
            }
        }
    }
    let bb_opts = BranchAndBoundOptions {
        max_relative_gap: opts.certify.max_relative_gap,
        max_nodes: opts.conic_max_nodes(),
        trivial_lower_bound: 0.0,
    };
    let start = Ellipsoid::from_dual(&frame_dual).unwrap_or(*local);
    let mut result = branch_and_bound(&mut oracle, root, Some((frame_cost, start)), &bb_opts);
    result.solver_iterations += iterations;
    let (best_cost, best) = result.best.unwrap_or((frame_cost, start));
    let world = Ellipsoid::from_dual(&transform_dual(&sim.inverse_matrix(), &best.dual())).unwrap_or(*local);
    report.cost = best_cost;
    let (status, certificate) = certificate_of(
        &result,
        best_cost,
        opts.certify.max_relative_gap,
        CertificateKind::BranchAndBound,
        Primitive::Quadric,
    );
    (report.status, report.certificate) = (status, certificate);
    (world, report)
}
