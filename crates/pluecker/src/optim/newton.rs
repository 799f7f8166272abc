//! Plain Newton's method (Phong & Horaud 1995, section 4 and Figure 3), the paper's other baseline:
//! `xᵏ⁺¹ = xᵏ − (∇²f)⁻¹ ∇f` with the exact Hessian, no line search and no trust region. It may
//! increase the cost or diverge; that is the behaviour the paper compares against.

use super::problem::{Objective, StoppingCriteria, Summary, Termination};

/// Minimises `obj` from `x0` by undamped Newton steps. Needs [`Objective::exact_hessian`]; without it
/// the Gauss-Newton Hessian is used (Gauss-Newton's method).
pub fn minimize<const N: usize, O: Objective<N>>(
    obj: &O,
    x0: O::Point,
    stopping: &StoppingCriteria,
) -> (O::Point, Summary) {
    let mut x = x0;
    let mut lin = obj.linearize(&x);
    let initial_cost = lin.cost;
    let (mut iterations, mut evaluations) = (0, 1);
    let termination = loop {
        if let Some(t) = stopping.check(&lin) {
            break t;
        }
        if iterations >= stopping.max_iterations {
            break Termination::MaxIterations;
        }
        let h = obj.exact_hessian(&x).unwrap_or(lin.gauss_newton);
        let dense = nalgebra::DMatrix::from_column_slice(N, N, h.as_slice());
        let Some(d) = dense
            .lu()
            .solve(&nalgebra::DVector::from_column_slice((-lin.gradient).as_slice()))
        else {
            break Termination::SingularHessian;
        };
        let d = nalgebra::SVector::<f64, N>::from_column_slice(d.as_slice());
        if d.iter().any(|v| !v.is_finite()) {
            break Termination::SingularHessian;
        }
        x = obj.retract(&x, &d);
        iterations += 1;
        lin = obj.linearize(&x);
        evaluations += 1;
        if stopping.step_is_negligible(&d, 1.0) {
            break if lin.cost.is_finite() {
                Termination::StepTolerance
            } else {
                Termination::NonFiniteCost
            };
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
