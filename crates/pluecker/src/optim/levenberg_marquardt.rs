//! Levenberg-Marquardt (Phong & Horaud 1995, section 4.2), the paper's first baseline:
//! `(JᵀJ + νI) d = −JᵀΦ`, with ν divided by 10 after a successful step and multiplied by 10 after a
//! failed one (Marquardt's original rule). Same cost and stopping tests as the trust region.

use super::problem::{invalid_option, nested_name, Objective, StoppingCriteria, Summary, Termination};
use nalgebra::SMatrix;

/// Options of the Levenberg-Marquardt solver.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct LevenbergMarquardtOptions {
    /// Initial damping, relative to the largest diagonal entry of `JᵀJ`. Default `1e-3`.
    pub initial_damping: f64,
    /// Failed steps in a row after which the method gives up (`RadiusTolerance`). Default 40.
    pub max_rejections: usize,
    /// Stopping tests and iteration cap.
    pub stopping: StoppingCriteria,
}

impl Default for LevenbergMarquardtOptions {
    fn default() -> Self {
        LevenbergMarquardtOptions {
            initial_damping: 1e-3,
            max_rejections: 40,
            stopping: StoppingCriteria::default(),
        }
    }
}

impl LevenbergMarquardtOptions {
    /// Checks the options (errors name `name.field`, or `field` when `name` is empty): a positive finite initial damping, at least one
    /// rejection, valid stopping tests.
    pub fn validate(&self, name: &str) -> crate::error::Result<()> {
        if !(self.initial_damping.is_finite() && self.initial_damping > 0.0) {
            return invalid_option(name, "initial_damping", "must be a positive finite number");
        }
        if self.max_rejections < 1 {
            return invalid_option(name, "max_rejections", "must be at least 1");
        }
        self.stopping.validate(&nested_name(name, "stopping"))
    }
}

/// Minimises `obj` from `x0` by Levenberg-Marquardt.
pub fn minimize<const N: usize, O: Objective<N>>(
    obj: &O,
    x0: O::Point,
    opts: &LevenbergMarquardtOptions,
) -> (O::Point, Summary) {
    let mut x = x0;
    let mut lin = obj.linearize(&x);
    let initial_cost = lin.cost;
    let mut nu = opts.initial_damping * lin.gauss_newton.diagonal().amax().max(1e-12);
    let (mut iterations, mut evaluations) = (0, 1);
    let termination = 'outer: loop {
        if let Some(t) = opts.stopping.check(&lin) {
            break t;
        }
        if iterations >= opts.stopping.max_iterations {
            break Termination::MaxIterations;
        }
        let mut rejections = 0;
        loop {
            let damped = lin.gauss_newton + SMatrix::<f64, N, N>::identity() * nu;
            let Some(chol) = damped.cholesky() else {
                nu *= 10.0;
                rejections += 1;
                if rejections > opts.max_rejections {
                    break 'outer Termination::SingularHessian;
                }
                continue;
            };
            let d = -chol.solve(&lin.gradient);
            let trial = obj.retract(&x, &d);
            let trial_cost = obj.cost(&trial);
            evaluations += 1;
            if trial_cost.is_finite() && trial_cost < lin.cost {
                nu = (nu / 10.0).max(1e-300);
                x = trial;
                iterations += 1;
                lin = obj.linearize(&x);
                evaluations += 1;
                if opts.stopping.step_is_negligible(&d, 1.0) {
                    break 'outer Termination::StepTolerance;
                }
                break;
            }
            nu *= 10.0;
            rejections += 1;
            if rejections > opts.max_rejections {
                break 'outer Termination::RadiusTolerance;
            }
        }
    };
    (
        x,
        Summary {
            iterations,
            evaluations,
            initial_cost,
            final_cost: lin.cost,
            termination,
        },
    )
}
