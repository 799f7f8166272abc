//! The practical trust-region algorithm of Phong & Horaud 1995, section 4.1.
//!
//! At iterate `xᵏ` the cost is modelled by `q(d) = ∇fᵀd + ½ dᵀHd` (eq. 26) inside `‖d‖ ≤ δₖ` (eq. 27).
//! The step is accepted when the ratio of actual to predicted decrease `rₖ` (eq. 28) is at least
//! `r`, and the radius doubles when `rₖ ≥ s`; otherwise the radius halves and the step is recomputed
//! (k.5-k.6). The subproblem solver is chosen by [`Subproblem`]:
//! - `Hebden`: `H = JᵀJ + αI` (k.3, α = 0.001) with Hebden's step (Appendix A) — the paper's method;
//! - `MoreSorensen`: `H` = the exact Hessian with the Moré-Sorensen safeguarded step, which section 4.2
//!   recommends for large-residual problems.

use super::problem::{invalid_option, nested_name, Objective, StoppingCriteria, Summary, Termination};
use super::subproblem::{hebden_step, more_sorensen_step, Step};
use nalgebra::SMatrix;

/// How the trust-region subproblem (eq. 27) is solved; named `hebden`, `more_sorensen`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, strum::IntoStaticStr, strum::EnumString, strum::VariantArray)]
#[strum(serialize_all = "snake_case")]
pub enum Subproblem {
    /// Gauss-Newton Hessian shifted by `hessian_shift`, Hebden's algorithm (section 4.1, Appendix A).
    Hebden,
    /// Exact Hessian, Moré-Sorensen's safeguarded algorithm (section 4.2).
    MoreSorensen,
}

impl Subproblem {
    /// The name used by Python and the command line.
    pub fn as_str(&self) -> &'static str {
        self.into()
    }

    /// Parses [`Subproblem::as_str`] names (errors name the option `subproblem`).
    pub fn parse(name: &str) -> crate::error::Result<Subproblem> {
        crate::names::parse("subproblem", "subproblem", name)
    }
}

/// Options of the trust-region solver. Defaults are the paper's values.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct TrustRegionOptions {
    /// Subproblem solver. Default [`Subproblem::Hebden`].
    pub subproblem: Subproblem,
    /// α in `H' = JᵀJ + αI` (step k.3). Default `0.001`.
    pub hessian_shift: f64,
    /// Initial trust radius δ₀. Default `1.0`.
    pub initial_radius: f64,
    /// Acceptance threshold r on the ratio of eq. 28 (paper: r ∈ [0.1, 0.3]). Default `0.25`.
    pub accept_ratio: f64,
    /// Expansion threshold s (paper: s ∈ [0.5, 0.8]). Default `0.75`.
    pub expand_ratio: f64,
    /// Stop when δ ≤ `radius_tolerance` (the ε_δ of k.2). Default `1e-12`.
    pub radius_tolerance: f64,
    /// The other stopping tests of k.2 and the iteration cap.
    pub stopping: StoppingCriteria,
}

impl Default for TrustRegionOptions {
    fn default() -> Self {
        TrustRegionOptions {
            subproblem: Subproblem::Hebden,
            hessian_shift: 1e-3,
            initial_radius: 1.0,
            accept_ratio: 0.25,
            expand_ratio: 0.75,
            radius_tolerance: 1e-12,
            stopping: StoppingCriteria::default(),
        }
    }
}

impl TrustRegionOptions {
    /// Checks the options (errors name `name.field`, or `field` when `name` is empty): a positive finite initial radius,
    /// `0 < accept_ratio < expand_ratio < 1`, `hessian_shift ≥ 0`, `radius_tolerance ≥ 0`, valid stopping
    /// tests.
    pub fn validate(&self, name: &str) -> crate::error::Result<()> {
        if !(self.initial_radius.is_finite() && self.initial_radius > 0.0) {
            return invalid_option(name, "initial_radius", "must be a positive finite number");
        }
        if !(0.0 < self.accept_ratio && self.accept_ratio < self.expand_ratio && self.expand_ratio < 1.0) {
            return invalid_option(name, "accept_ratio", "need 0 < accept_ratio < expand_ratio < 1");
        }
        if !(self.hessian_shift >= 0.0 && self.hessian_shift.is_finite()) {
            return invalid_option(name, "hessian_shift", "must be a finite number ≥ 0");
        }
        if !(self.radius_tolerance >= 0.0) {
            return invalid_option(name, "radius_tolerance", "must be a number ≥ 0");
        }
        self.stopping.validate(&nested_name(name, "stopping"))
    }
}

/// Minimises `obj` from `x0` by the trust-region method of section 4.1.
///
/// Each accepted step decreases the cost (Figure 4). Returns the last accepted point and a summary.
pub fn minimize<const N: usize, O: Objective<N>>(
    obj: &O,
    x0: O::Point,
    opts: &TrustRegionOptions,
) -> (O::Point, Summary) {
    let mut x = x0;
    let mut delta = opts.initial_radius;
    let mut lin = obj.linearize(&x);
    let initial_cost = lin.cost;
    let mut evaluations = 1;
    let mut iterations = 0;
    let finish = |x, cost, iterations, evaluations, termination| {
        (
            x,
            Summary {
                iterations,
                evaluations,
                initial_cost,
                final_cost: cost,
                termination,
            },
        )
    };
    loop {
        // k.2
        if let Some(t) = opts.stopping.check(&lin) {
            return finish(x, lin.cost, iterations, evaluations, t);
        }
        if iterations >= opts.stopping.max_iterations {
            return finish(x, lin.cost, iterations, evaluations, Termination::MaxIterations);
        }
        let hessian: SMatrix<f64, N, N> = match opts.subproblem {
            Subproblem::Hebden => lin.gauss_newton + SMatrix::<f64, N, N>::identity() * opts.hessian_shift,
            Subproblem::MoreSorensen => match obj.exact_hessian(&x) {
                Some(h) => h,
                None => lin.gauss_newton,
            },
        };
        // k.3-k.6: shrink the radius until a step is accepted.
        loop {
            if delta <= opts.radius_tolerance {
                return finish(x, lin.cost, iterations, evaluations, Termination::RadiusTolerance);
            }
            let step: Option<Step<N>> = match opts.subproblem {
                Subproblem::Hebden => hebden_step(&hessian, &lin.gradient, delta),
                Subproblem::MoreSorensen => Some(more_sorensen_step(&hessian, &lin.gradient, delta)),
            };
            let Some(step) = step else {
                return finish(x, lin.cost, iterations, evaluations, Termination::SingularHessian);
            };
            // A negligible interior step is the last one: take it after checking only its cost (the
            // model is exact to second order at that scale), sparing a full linearisation.
            if step.mu == 0.0 && opts.stopping.step_is_negligible(&step.d, 1.0) {
                let trial = obj.retract(&x, &step.d);
                let trial_cost = obj.cost(&trial);
                evaluations += 1;
                if trial_cost <= lin.cost {
                    return finish(
                        trial,
                        trial_cost,
                        iterations + 1,
                        evaluations,
                        Termination::StepTolerance,
                    );
                }
                return finish(x, lin.cost, iterations, evaluations, Termination::StepTolerance);
            }
            // The trial point is linearised at once: near a solution almost every step is accepted,
            // so this saves a separate cost evaluation per iteration.
            let trial = obj.retract(&x, &step.d);
            let trial_lin = obj.linearize(&trial);
            evaluations += 1;
            let actual = lin.cost - trial_lin.cost;
            // eq. 28; a zero predicted decrease means the model is flat: treat as a failed step.
            let ratio = if step.predicted_decrease > 0.0 {
                actual / step.predicted_decrease
            } else {
                -1.0
            };
            if trial_lin.cost.is_finite() && ratio >= opts.accept_ratio {
                // k.5
                if ratio >= opts.expand_ratio {
                    delta *= 2.0;
                }
                x = trial;
                lin = trial_lin;
                iterations += 1;
                if opts.stopping.step_is_negligible(&step.d, 1.0) {
                    return finish(x, lin.cost, iterations, evaluations, Termination::StepTolerance);
                }
                break;
            }
            // k.6: δ ← δ/2. When the rejected step was an interior one much shorter than δ, halving δ
            // alone would recompute the same step; halve its length instead (same iterate, fewer solves).
            delta = delta.min(step.d.norm()) / 2.0;
        }
    }
}
