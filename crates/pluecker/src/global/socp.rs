//! Second-order cone programs and the adapter to the `clarabel` interior-point solver.
//!
//! A [`Socp`] is built from affine expressions ([`Affine`]) of its variables: a linear objective to
//! minimise, and blocks of constraints `e(x) ∈ K` with `K` the zero cone (equalities), the non-negative
//! orthant, or a second-order cone `‖(e₂, …, e_k)‖ ≤ e₁`. Rotated cones `‖w‖² ≤ u v, u, v ≥ 0` (the
//! quadratic-over-linear constraints of Josephson & Kahl 2008, eq. 21-22) are written as the standard
//! cone `‖(2w, u − v)‖ ≤ u + v`.
//!
//! Clarabel solves `min cᵀx s.t. A x + s = b, s ∈ K`; a constraint `e(x) = aᵀx + a₀ ∈ K` becomes the
//! row `A = −aᵀ`, `b = a₀` (so that `s = e(x)`).
//!
//! ## A lower bound that survives the solver's tolerance
//! An interior-point solution is only feasible and optimal to a tolerance (1e-8 here), so its primal
//! objective is not a lower bound of the program. [`SocpSolution::lower_bound`] is one: for any dual
//! vector `z ∈ K*` (clarabel's `z`, projected onto the dual cone — every cone here is self-dual) and
//! any feasible `x` (so `s = b − A x ∈ K` and `zᵀs ≥ 0`), with the dual residual `ρ = c + Aᵀz`,
//! `cᵀx = ρᵀx − zᵀA x = ρᵀx − bᵀz + zᵀs ≥ −bᵀz + ρᵀx`,
//! and `ρᵀx ≥ Σⱼ min(ρⱼ loⱼ, ρⱼ hiⱼ)` for the variable bounds `loⱼ ≤ xⱼ ≤ hiⱼ` that the caller declares
//! (they must hold on the feasible set, or on the part of it the bound is wanted for). The dual
//! residual `ρ` is thus paid for explicitly instead of being assumed zero; a final margin of a few
//! ulps of the summed magnitudes covers the rounding of this computation.
//!
//! ## Stopping
//! Every solve polls the stop of [`crate::interrupt`] before it starts and at every interior-point
//! iteration (clarabel's termination callback): a solve the stop ends is
//! [`SocpStatus::Stopped`], with no bound, so that one large program (the root tightening of a line
//! seen in 30 views solves about 70 of them) never holds up Ctrl-C.

use crate::interrupt::{stop_reason, StopReason};
use clarabel::algebra::CscMatrix;
use clarabel::solver::{DefaultSettings, DefaultSolver, IPSolver, SolverStatus, SupportedConeT};
use std::sync::{Arc, OnceLock};

/// An affine expression `Σ coefⱼ xⱼ + constant` of the variables of a [`Socp`].
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Affine {
    /// `(variable index, coefficient)` pairs; an index may repeat (the coefficients add up).
    pub terms: Vec<(usize, f64)>,
    /// The constant term.
    pub constant: f64,
}

impl Affine {
    /// The constant `c`.
    pub fn constant(c: f64) -> Affine {
        Affine {
            terms: Vec::new(),
            constant: c,
        }
    }

    /// The variable `x_j`.
    pub fn var(j: usize) -> Affine {
        Affine {
            terms: vec![(j, 1.0)],
            constant: 0.0,
        }
    }

    /// `coef · x_j`.
    pub fn term(j: usize, coef: f64) -> Affine {
        Affine {
            terms: vec![(j, coef)],
            constant: 0.0,
        }
    }

    /// `self + other`.
    pub fn plus(mut self, other: &Affine) -> Affine {
        self.terms.extend_from_slice(&other.terms);
        self.constant += other.constant;
        self
    }

    /// `self − other`.
    pub fn minus(mut self, other: &Affine) -> Affine {
        self.terms.extend(other.terms.iter().map(|&(j, a)| (j, -a)));
        self.constant -= other.constant;
        self
    }

    /// `a · self`.
    pub fn scaled(mut self, a: f64) -> Affine {
        for t in &mut self.terms {
            t.1 *= a;
        }
        self.constant *= a;
        self
    }

    /// `self + c`.
    pub fn shifted(mut self, c: f64) -> Affine {
        self.constant += c;
        self
    }

    /// The value at `x`.
    pub fn eval(&self, x: &[f64]) -> f64 {
        self.constant + self.terms.iter().map(|&(j, a)| a * x[j]).sum::<f64>()
    }
}

/// The cone of one block of constraint rows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Cone {
    /// Every row is zero.
    Zero,
    /// Every row is non-negative.
    Nonnegative,
    /// `‖(rows 2..k)‖ ≤ row 1`.
    SecondOrder,
}

/// How a solve ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SocpStatus {
    /// Solved to full (or reduced, "almost solved") accuracy; the bound is meaningful.
    Solved,
    /// The solver reports the program infeasible (its certificate met its tolerance).
    Infeasible,
    /// The solver reports the objective unbounded below.
    Unbounded,
    /// Iteration limit, numerical error, insufficient progress, or a setup error.
    Failed,
    /// The installed stop ([`crate::interrupt`]) fired before or during the solve: no bound.
    Stopped(StopReason),
}

/// The result of [`Socp::solve`].
#[derive(Debug, Clone)]
pub struct SocpSolution {
    /// How the solve ended.
    pub status: SocpStatus,
    /// The primal solution (clarabel's `x`; meaningful when `status` is `Solved`).
    pub x: Vec<f64>,
    /// `cᵀx + c₀` at the primal solution: near-optimal, not a bound (read by the unit tests only).
    #[cfg_attr(not(test), allow(dead_code))]
    pub primal_objective: f64,
    /// A valid lower bound of the program on the declared variable bounds (see the module docs);
    /// `−∞` unless `status` is `Solved`.
    pub lower_bound: f64,
    /// The dual vector (clarabel's `z`, one entry per constraint row), for [`Socp::lower_bound`].
    pub z: Vec<f64>,
    /// Interior-point iterations.
    pub iterations: usize,
}

/// A second-order cone program under construction; see the module docs.
#[derive(Debug, Clone, Default)]
pub struct Socp {
    lower: Vec<f64>,
    upper: Vec<f64>,
    objective: Affine,
    rows: Vec<Affine>,
    blocks: Vec<(Cone, usize)>,
}

impl Socp {
    /// An empty program.
    pub fn new() -> Socp {
        Socp::default()
    }

    /// Adds a variable with declared bounds `lo ≤ x ≤ hi` and returns its index. The bounds are not
    /// imposed as constraints; they are the caller's promise about the feasible set, used only by the
    /// lower bound (pass ±∞ when unknown: the bound is then `−∞` unless the dual residual is zero).
    pub fn add_variable(&mut self, lo: f64, hi: f64) -> usize {
        self.lower.push(lo);
        self.upper.push(hi);
        self.lower.len() - 1
    }

    /// Replaces the declared bounds of variable `j` (see [`Socp::add_variable`]).
    pub fn set_variable_bounds(&mut self, j: usize, lo: f64, hi: f64) {
        self.lower[j] = lo;
        self.upper[j] = hi;
    }

    /// The number of variables.
    pub fn variables(&self) -> usize {
        self.lower.len()
    }

    /// Sets the objective to minimise (its constant is carried into the reported values).
    pub fn minimize(&mut self, objective: Affine) {
        self.objective = objective;
    }

    fn push_block(&mut self, cone: Cone, rows: &[Affine]) {
        if rows.is_empty() {
            return;
        }
        self.rows.extend_from_slice(rows);
        match self.blocks.last_mut() {
            Some((c, n)) if *c == cone && cone != Cone::SecondOrder => *n += rows.len(),
            _ => self.blocks.push((cone, rows.len())),
        }
    }

    /// `e(x) = 0`.
    // No bound of the crate needs equality rows today; the unit tests' programs do.
    #[cfg_attr(not(test), allow(dead_code))]
    pub fn equal(&mut self, e: Affine) {
        self.push_block(Cone::Zero, &[e]);
    }

    /// `e(x) ≥ 0`.
    pub fn nonneg(&mut self, e: Affine) {
        self.push_block(Cone::Nonnegative, &[e]);
    }

    /// `a(x) ≤ b(x)`.
    pub fn less_eq(&mut self, a: &Affine, b: &Affine) {
        self.nonneg(b.clone().minus(a));
    }

    /// `‖(w₁, …, w_k)‖ ≤ t`.
    pub fn second_order(&mut self, t: Affine, w: &[Affine]) {
        let mut rows = Vec::with_capacity(w.len() + 1);
        rows.push(t);
        rows.extend_from_slice(w);
        self.push_block(Cone::SecondOrder, &rows);
    }

    /// The rotated cone `‖w‖² ≤ u v` with `u, v ≥ 0`, as `‖(2w, u − v)‖ ≤ u + v`.
    pub fn rotated_second_order(&mut self, u: &Affine, v: &Affine, w: &[Affine]) {
        let mut rows: Vec<Affine> = w.iter().map(|e| e.clone().scaled(2.0)).collect();
        rows.push(u.clone().minus(v));
        self.second_order(u.clone().plus(v), &rows);
    }

    /// Solves with clarabel's default tolerances (1e-8), silently, without presolve (no infinite
    /// bounds arise here) and without iterative refinement of the KKT solves (faster on the
    /// branch-and-bound nodes, see docs/benchmarks.md, "Figures behind code comments";
    /// the bound below does not rely on the solver's accuracy).
    pub fn solve(&self) -> SocpSolution {
        self.solve_with(DefaultSettings::<f64> {
            verbose: false,
            presolve_enable: false,
            iterative_refinement_enable: false,
            ..DefaultSettings::default()
        })
    }

    /// Solves with the given clarabel settings, polling the installed stop before the solve and at
    /// every iteration (module docs).
    pub fn solve_with(&self, settings: DefaultSettings<f64>) -> SocpSolution {
        let unsolved = |status, iterations| SocpSolution {
            status,
            x: vec![f64::NAN; self.variables()],
            primal_objective: f64::NAN,
            lower_bound: f64::NEG_INFINITY,
            z: Vec::new(),
            iterations,
        };
        if let Some(reason) = stop_reason() {
            return unsolved(SocpStatus::Stopped(reason), 0);
        }
        let Some(mut solver) = self.clarabel_solver(settings) else {
            return unsolved(SocpStatus::Failed, 0);
        };
        // The callback runs on this thread, inside `solve`, where the stop is installed.
        let stopped = Arc::new(OnceLock::new());
        let seen = Arc::clone(&stopped);
        solver.set_termination_callback(move |_| match stop_reason() {
            Some(reason) => {
                let _ = seen.set(reason);
                true
            }
            None => false,
        });
        solver.solve();
        let sol = &solver.solution;
        let iterations = sol.iterations as usize;
        let status = match sol.status {
            SolverStatus::Solved | SolverStatus::AlmostSolved => SocpStatus::Solved,
            SolverStatus::PrimalInfeasible | SolverStatus::AlmostPrimalInfeasible => SocpStatus::Infeasible,
            SolverStatus::DualInfeasible | SolverStatus::AlmostDualInfeasible => SocpStatus::Unbounded,
            SolverStatus::CallbackTerminated => {
                let reason = stopped.get().copied().unwrap_or(StopReason::Requested);
                return unsolved(SocpStatus::Stopped(reason), iterations);
            }
            _ => return unsolved(SocpStatus::Failed, iterations),
        };
        let (x, z) = (sol.x.clone(), sol.z.clone());
        if status != SocpStatus::Solved {
            let lower_bound = f64::NEG_INFINITY;
            return SocpSolution {
                status,
                x,
                primal_objective: f64::NAN,
                lower_bound,
                z,
                iterations,
            };
        }
        let primal_objective = self.objective.eval(&x);
        let lower_bound = self.lower_bound(&z);
        SocpSolution {
            status,
            x,
            primal_objective,
            lower_bound,
            z,
            iterations,
        }
    }

    /// Clarabel's solver for this program (linear objective `qᵀx`, constraints `b − A x ∈ cones`), not
    /// yet run; `None` when clarabel refuses the data.
    fn clarabel_solver(&self, settings: DefaultSettings<f64>) -> Option<DefaultSolver<f64>> {
        let n = self.variables();
        let (a, b) = self.constraint_matrix();
        let mut q = vec![0.0; n];
        for &(j, c) in &self.objective.terms {
            q[j] += c;
        }
        let cones: Vec<SupportedConeT<f64>> = self
            .blocks
            .iter()
            .map(|&(cone, k)| match cone {
                Cone::Zero => SupportedConeT::ZeroConeT(k),
                Cone::Nonnegative => SupportedConeT::NonnegativeConeT(k),
                Cone::SecondOrder => SupportedConeT::SecondOrderConeT(k),
            })
            .collect();
        DefaultSolver::new(&CscMatrix::zeros((n, n)), &q, &a, &b, &cones, settings).ok()
    }

    /// The constraint matrix `A` (CSC) and right-hand side `b` in clarabel's form.
    fn constraint_matrix(&self) -> (CscMatrix<f64>, Vec<f64>) {
        let (m, n) = (self.rows.len(), self.variables());
        let mut columns: Vec<Vec<(usize, f64)>> = vec![Vec::new(); n];
        let mut b = Vec::with_capacity(m);
        for (i, row) in self.rows.iter().enumerate() {
            for &(j, a) in &row.terms {
                match columns[j].last_mut() {
                    Some((r, v)) if *r == i => *v -= a,
                    _ => columns[j].push((i, -a)),
                }
            }
            b.push(row.constant);
        }
        let mut colptr = Vec::with_capacity(n + 1);
        let (mut rowval, mut nzval) = (Vec::new(), Vec::new());
        colptr.push(0);
        for col in &columns {
            for &(i, v) in col {
                rowval.push(i);
                nzval.push(v);
            }
            colptr.push(rowval.len());
        }
        (CscMatrix::new(m, n, colptr, rowval, nzval), b)
    }

    /// The weak-duality bound of the module docs for a dual vector `z` (projected onto `K*`) and the
    /// current declared variable bounds: a lower bound of the objective over the feasible points
    /// that satisfy the declared bounds (`−∞` if a needed bound is infinite).
    pub fn lower_bound(&self, z: &[f64]) -> f64 {
        if z.len() != self.rows.len() {
            return f64::NEG_INFINITY;
        }
        let z = self.project_dual(z);
        // ρ = c + Aᵀz with A = −(row coefficients); −bᵀz = −Σ constantᵢ zᵢ.
        let mut rho = vec![0.0; self.variables()];
        for &(j, c) in &self.objective.terms {
            rho[j] += c;
        }
        let mut bound = self.objective.constant;
        let mut magnitude = self.objective.constant.abs();
        for (row, &zi) in self.rows.iter().zip(&z) {
            for &(j, a) in &row.terms {
                rho[j] -= a * zi;
            }
            bound -= row.constant * zi;
            magnitude += (row.constant * zi).abs();
        }
        for (j, &r) in rho.iter().enumerate() {
            if r == 0.0 {
                continue;
            }
            let worst = (r * self.lower[j]).min(r * self.upper[j]);
            if !worst.is_finite() {
                return f64::NEG_INFINITY;
            }
            bound += worst;
            magnitude += worst.abs();
        }
        bound - 16.0 * f64::EPSILON * magnitude
    }

    /// `z` projected onto the dual cone `K*` block by block (every cone used here is self-dual; the
    /// zero cone's dual is the whole space).
    fn project_dual(&self, z: &[f64]) -> Vec<f64> {
        let mut out = z.to_vec();
        let mut start = 0;
        for &(cone, k) in &self.blocks {
            let block = &mut out[start..start + k];
            match cone {
                Cone::Zero => {}
                Cone::Nonnegative => block.iter_mut().for_each(|v| *v = v.max(0.0)),
                Cone::SecondOrder => project_second_order(block),
            }
            start += k;
        }
        out
    }
}

/// Euclidean projection onto the second-order cone `{(t, w): ‖w‖ ≤ t}`, in place.
fn project_second_order(v: &mut [f64]) {
    let t = v[0];
    let norm = v[1..].iter().map(|x| x * x).sum::<f64>().sqrt();
    if norm <= t {
        return;
    }
    if norm <= -t {
        v.iter_mut().for_each(|x| *x = 0.0);
        return;
    }
    let alpha = 0.5 * (t + norm);
    v[0] = alpha;
    for x in &mut v[1..] {
        *x *= alpha / norm;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_a_small_socp_with_a_valid_bound() {
        // min x + y  s.t. ‖(x − 1, y − 2)‖ ≤ 1: optimum 3 − √2 at (1, 2) − (1, 1)/√2.
        let mut p = Socp::new();
        let x = p.add_variable(-10.0, 10.0);
        let y = p.add_variable(-10.0, 10.0);
        p.minimize(Affine::var(x).plus(&Affine::var(y)));
        p.second_order(
            Affine::constant(1.0),
            &[Affine::var(x).shifted(-1.0), Affine::var(y).shifted(-2.0)],
        );
        let s = p.solve();
        let optimum = 3.0 - 2f64.sqrt();
        assert_eq!(s.status, SocpStatus::Solved);
        assert!((s.primal_objective - optimum).abs() < 1e-7, "{}", s.primal_objective);
        assert!(
            s.lower_bound <= optimum && s.lower_bound > optimum - 1e-6,
            "{}",
            s.lower_bound
        );
    }

    #[test]
    fn rotated_cone_and_infeasibility() {
        // min t s.t. x² ≤ t·1, x ≥ 2 (t ≥ 4).
        let mut p = Socp::new();
        let x = p.add_variable(0.0, 100.0);
        let t = p.add_variable(0.0, 1e4);
        p.minimize(Affine::var(t));
        p.rotated_second_order(&Affine::var(t), &Affine::constant(1.0), &[Affine::var(x)]);
        p.nonneg(Affine::var(x).shifted(-2.0));
        let s = p.solve();
        assert_eq!(s.status, SocpStatus::Solved);
        assert!((s.x[t] - 4.0).abs() < 1e-6 && s.lower_bound <= 4.0 && s.lower_bound > 4.0 - 1e-5);
        // Adding x ≤ 1 makes it infeasible.
        p.less_eq(&Affine::var(x), &Affine::constant(1.0));
        assert_eq!(p.solve().status, SocpStatus::Infeasible);
    }

    #[test]
    fn an_objective_unbounded_below_is_reported_as_such_with_no_bound() {
        // min x + 2y s.t. |y| ≤ x: along (x, y) = (s, −s) the objective is −s → −∞: unbounded
        // below, the dual infeasible.
        let mut p = Socp::new();
        let x = p.add_variable(f64::NEG_INFINITY, f64::INFINITY);
        let y = p.add_variable(f64::NEG_INFINITY, f64::INFINITY);
        p.minimize(Affine::var(x).plus(&Affine::term(y, 2.0)));
        p.second_order(Affine::var(x), &[Affine::var(y)]);
        let s = p.solve();
        assert_eq!(s.status, SocpStatus::Unbounded);
        assert_eq!(s.lower_bound, f64::NEG_INFINITY);
    }

    #[test]
    fn unknown_variable_bounds_give_no_bound_unless_the_residual_vanishes() {
        let mut p = Socp::new();
        let x = p.add_variable(f64::NEG_INFINITY, f64::INFINITY);
        p.minimize(Affine::var(x));
        p.nonneg(Affine::var(x).shifted(-1.5));
        let s = p.solve();
        assert!((s.primal_objective - 1.5).abs() < 1e-7);
        assert!(s.lower_bound <= 1.5);
    }

    #[test]
    fn projection_onto_the_cone() {
        let mut v = [0.0, 3.0, 4.0];
        project_second_order(&mut v);
        assert!((v[0] - 2.5).abs() < 1e-15 && (v[1] - 1.5).abs() < 1e-15 && (v[2] - 2.0).abs() < 1e-15);
        let mut inside = [5.0, 3.0, 4.0];
        project_second_order(&mut inside);
        assert_eq!(inside, [5.0, 3.0, 4.0]);
    }

    /// Three programs with optima known in closed form: `min x + y` over a disc, `min t` with
    /// `x² ≤ t`, `x ≥ 2`, and `min −x − 2y` over a triangle with an equality.
    fn known_programs() -> Vec<(Socp, f64)> {
        let mut disc = Socp::new();
        let (x, y) = (disc.add_variable(-10.0, 10.0), disc.add_variable(-10.0, 10.0));
        disc.minimize(Affine::var(x).plus(&Affine::var(y)));
        disc.second_order(
            Affine::constant(1.0),
            &[Affine::var(x).shifted(-1.0), Affine::var(y).shifted(-2.0)],
        );
        let mut rotated = Socp::new();
        let (x, t) = (rotated.add_variable(0.0, 100.0), rotated.add_variable(0.0, 1e4));
        rotated.minimize(Affine::var(t));
        rotated.rotated_second_order(&Affine::var(t), &Affine::constant(1.0), &[Affine::var(x)]);
        rotated.nonneg(Affine::var(x).shifted(-2.0));
        // x, y ≥ 0, x + y ≤ 1, z = x: the optimum −2 at (0, 1).
        let mut lp = Socp::new();
        let (x, y, z) = (
            lp.add_variable(0.0, 1.0),
            lp.add_variable(0.0, 1.0),
            lp.add_variable(-1.0, 1.0),
        );
        lp.minimize(Affine::term(x, -1.0).plus(&Affine::term(y, -2.0)));
        lp.nonneg(Affine::var(x));
        lp.nonneg(Affine::var(y));
        lp.less_eq(&Affine::var(x).plus(&Affine::var(y)), &Affine::constant(1.0));
        lp.equal(Affine::var(z).minus(&Affine::var(x)));
        vec![(disc, 3.0 - 2f64.sqrt()), (rotated, 4.0), (lp, -2.0)]
    }

    /// Weak duality holds for every dual vector, not only the solver's: perturbed, scaled, random
    /// and zero vectors all give bounds at or below the optimum, because the dual residual
    /// `c + Aᵀz` is paid for over the declared variable bounds. Without that correction the
    /// perturbed vectors give bounds above the optimum.
    #[test]
    fn perturbed_dual_vectors_keep_the_bound_below_the_optimum() {
        let mut rng = crate::rng::Rng::new(17);
        let mut above_without_residual = 0;
        for (p, optimum) in known_programs() {
            let s = p.solve();
            assert_eq!(s.status, SocpStatus::Solved);
            assert!(
                s.lower_bound <= optimum && s.lower_bound > optimum - 1e-5,
                "{}",
                s.lower_bound
            );
            for trial in 0..400 {
                let scale = 10f64.powf(rng.uniform_in(-6.0, 1.0));
                let z: Vec<f64> = match trial % 4 {
                    0 => s.z.iter().map(|v| v + scale * rng.normal()).collect(),
                    1 => s.z.iter().map(|v| v * (1.0 + scale * rng.normal())).collect(),
                    2 => s.z.iter().map(|_| scale * rng.normal()).collect(),
                    _ => vec![0.0; s.z.len()],
                };
                let bound = p.lower_bound(&z);
                // The bound's own rounding margin covers its arithmetic: no tolerance here.
                assert!(
                    bound <= optimum,
                    "trial {trial}: bound {bound} above the optimum {optimum}"
                );
                // −bᵀz alone (no residual term) over-reaches for many of these vectors: the test
                // exercises the correction.
                let projected = p.project_dual(&z);
                let naive = p.objective.constant
                    - p.rows
                        .iter()
                        .zip(&projected)
                        .map(|(r, zi)| r.constant * zi)
                        .sum::<f64>();
                if naive > optimum + 1e-9 {
                    above_without_residual += 1;
                }
            }
        }
        assert!(above_without_residual > 100, "{above_without_residual}");
    }

    /// A stop whose check counts its runs and asks for the stop at run `at` (never with `usize::MAX`).
    fn counting_stop(
        at: usize,
    ) -> (
        std::sync::Arc<crate::interrupt::Stop>,
        std::sync::Arc<std::sync::atomic::AtomicUsize>,
    ) {
        use std::sync::atomic::{AtomicUsize, Ordering};
        let polls = std::sync::Arc::new(AtomicUsize::new(0));
        let counted = std::sync::Arc::clone(&polls);
        let stop = crate::interrupt::Stop::new().with_check(move || counted.fetch_add(1, Ordering::Relaxed) + 1 == at);
        (std::sync::Arc::new(stop), polls)
    }

    /// Every solve polls the installed stop before it starts and at every interior-point iteration,
    /// so that Ctrl-C is seen within one iteration of a large program.
    #[test]
    fn a_solve_polls_the_stop_at_every_iteration() {
        use crate::interrupt::with_stop;
        use std::sync::atomic::Ordering;
        for (p, _) in known_programs() {
            let (stop, polls) = counting_stop(usize::MAX);
            let s = with_stop(stop, || p.solve());
            assert_eq!(s.status, SocpStatus::Solved);
            assert!(s.iterations >= 2, "{}", s.iterations);
            // One poll before the solve, one per iteration (the callback also runs at the
            // convergence check that ends the loop).
            assert!(
                polls.load(Ordering::Relaxed) > s.iterations + 1,
                "{} polls, {} iterations",
                polls.load(Ordering::Relaxed),
                s.iterations
            );
        }
    }

    /// A stop that fires during a solve ends it at that iteration with status `Stopped` and no bound;
    /// one that fired before does not start it; an expired time budget says so.
    #[test]
    fn a_stop_ends_a_solve_without_a_bound() {
        use crate::interrupt::{with_stop, Stop};
        use std::time::Duration;
        for (p, _) in known_programs() {
            let full = p.solve();
            // The first poll is before the solve; the third is in its second iteration.
            let (stop, _) = counting_stop(3);
            let s = with_stop(stop, || p.solve());
            assert_eq!(s.status, SocpStatus::Stopped(StopReason::Requested));
            assert_eq!(s.lower_bound, f64::NEG_INFINITY);
            assert!(
                s.iterations < full.iterations,
                "{} of {}",
                s.iterations,
                full.iterations
            );
            let requested = std::sync::Arc::new(Stop::new());
            requested.request();
            let s = with_stop(requested, || p.solve());
            assert_eq!(
                (s.status, s.iterations),
                (SocpStatus::Stopped(StopReason::Requested), 0)
            );
            let expired = std::sync::Arc::new(Stop::with_time_budget(Some(Duration::ZERO)));
            let s = with_stop(expired, || p.solve());
            assert_eq!(s.status, SocpStatus::Stopped(StopReason::TimeBudget));
            assert_eq!(s.lower_bound, f64::NEG_INFINITY);
        }
    }

    /// A solve stopped after a few iterations, or with loose tolerances, still yields a bound at or
    /// below the optimum from whatever dual vector it reached.
    #[test]
    fn an_early_or_loose_solve_gives_a_bound_below_the_optimum() {
        for (p, optimum) in known_programs() {
            for (max_iter, tol) in [(1, 1e-8), (2, 1e-8), (3, 1e-8), (50, 1e-1), (50, 1e-3)] {
                let settings = DefaultSettings::<f64> {
                    verbose: false,
                    presolve_enable: false,
                    max_iter,
                    tol_gap_abs: tol,
                    tol_gap_rel: tol,
                    tol_feas: tol,
                    tol_ktratio: tol.max(1e-6),
                    ..DefaultSettings::default()
                };
                let mut solver = p.clarabel_solver(settings).unwrap();
                solver.solve();
                let bound = p.lower_bound(&solver.solution.z);
                assert!(bound <= optimum, "max_iter {max_iter}, tol {tol}: {bound} > {optimum}");
                let s = p.solve_with(DefaultSettings::<f64> {
                    verbose: false,
                    max_iter,
                    ..DefaultSettings::default()
                });
                assert!(
                    s.lower_bound <= optimum,
                    "{:?}: {} > {optimum}",
                    s.status,
                    s.lower_bound
                );
            }
        }
    }
}
