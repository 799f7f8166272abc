//! What the solvers minimise, and what they report.
//!
//! Every solver in [`crate::optim`] minimises a non-linear least-squares cost (Phong & Horaud 1995,
//! eq. 23) `f(x) = ½ Σⱼ Φⱼ(x)²` over a point `x` of an `N`-dimensional space. The space may be curved
//! (a rotation and a translation): the solver computes a step `d ∈ ℝᴺ` in the tangent space and the
//! problem maps it back with [`Objective::retract`]. For a vector space `retract(x, d) = x + d`.

use nalgebra::{SMatrix, SVector};

/// The local model of a least-squares cost at one point: `f`, `∇f = JᵀΦ` and `JᵀJ` (eq. 24-25).
#[derive(Debug, Clone)]
pub struct Linearization<const N: usize> {
    /// `f(x) = ½ Σ Φⱼ²`.
    pub cost: f64,
    /// `∇f(x) = J(x)ᵀ Φ(x)`.
    pub gradient: SVector<f64, N>,
    /// The Gauss-Newton Hessian `J(x)ᵀ J(x)`.
    pub gauss_newton: SMatrix<f64, N, N>,
}

impl<const N: usize> Linearization<N> {
    /// The model of an empty sum: zero cost, gradient and Hessian.
    pub fn zero() -> Self {
        Linearization {
            cost: 0.0,
            gradient: SVector::zeros(),
            gauss_newton: SMatrix::zeros(),
        }
    }

    /// Adds the model `other` of a sum whose variable is `B x` (its Jacobian times `B`): its cost,
    /// `Bᵀ ∇f` and `Bᵀ JᵀJ B` (a rig's camera: `B = diag(R_k, R_k)`).
    pub fn add_mapped(&mut self, other: &Linearization<N>, b: &SMatrix<f64, N, N>) {
        self.cost += other.cost;
        self.gradient += b.transpose() * other.gradient;
        self.gauss_newton += b.transpose() * other.gauss_newton * b;
    }

    /// Adds the residuals `Φ` (length `M`) with Jacobian `J` (`M x N`): `½‖Φ‖²`, `JᵀΦ` and `JᵀJ`.
    pub fn add<const M: usize>(&mut self, residual: &SVector<f64, M>, jacobian: &SMatrix<f64, M, N>) {
        self.cost += 0.5 * residual.norm_squared();
        self.gradient += jacobian.transpose() * residual;
        self.gauss_newton += jacobian.transpose() * jacobian;
    }
}

/// A least-squares cost the solvers can minimise.
pub trait Objective<const N: usize> {
    /// A point of the search space.
    type Point: Clone;
    /// `f(x) = ½ Σ Φⱼ(x)²`.
    fn cost(&self, x: &Self::Point) -> f64;
    /// Cost, gradient and Gauss-Newton Hessian at `x`.
    fn linearize(&self, x: &Self::Point) -> Linearization<N>;
    /// The exact Hessian `JᵀJ + Σ Φⱼ ∇²Φⱼ` (eq. 25), for the solvers that need it; `None` if the
    /// problem does not provide second derivatives.
    fn exact_hessian(&self, _x: &Self::Point) -> Option<SMatrix<f64, N, N>> {
        None
    }
    /// The point reached from `x` by the tangent step `d`.
    fn retract(&self, x: &Self::Point, d: &SVector<f64, N>) -> Self::Point;
}

/// Why a solver stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, strum::IntoStaticStr, strum::EnumString, strum::VariantArray)]
#[strum(serialize_all = "snake_case")]
pub enum Termination {
    /// `‖∇f‖∞ ≤ gradient_tolerance` (step k.2 of section 4.1).
    GradientTolerance,
    /// The trust radius fell to `radius_tolerance`: no step of the model reduces the cost (k.2).
    RadiusTolerance,
    /// `f ≤ cost_tolerance` (k.2).
    CostTolerance,
    /// The step was shorter than `step_tolerance · (‖x‖ + step_tolerance)`.
    StepTolerance,
    /// The iteration limit was reached before any other test passed.
    MaxIterations,
    /// The Hessian was singular or not positive definite where the method needs it to be (Newton).
    SingularHessian,
    /// The cost became NaN or infinite (a diverging plain Newton iteration, or bad data).
    NonFiniteCost,
    /// Not iterative: a direct (closed-form or linear least-squares) solution.
    ClosedForm,
}

impl Termination {
    /// True when the stop is a convergence test rather than a limit or a failure.
    pub fn converged(&self) -> bool {
        matches!(
            self,
            Termination::GradientTolerance
                | Termination::RadiusTolerance
                | Termination::CostTolerance
                | Termination::StepTolerance
                | Termination::ClosedForm
        )
    }

    /// A short snake_case name, used in reports, JSON and Python.
    pub fn as_str(&self) -> &'static str {
        self.into()
    }
}

/// What a solver did.
#[derive(Debug, Clone, PartialEq)]
pub struct Summary {
    /// Accepted steps (outer iterations k of section 4.1).
    pub iterations: usize,
    /// Cost evaluations, including rejected trial steps.
    pub evaluations: usize,
    /// `f(x⁰)`.
    pub initial_cost: f64,
    /// `f` at the returned point.
    pub final_cost: f64,
    /// Why it stopped.
    pub termination: Termination,
}

/// The name of option `field` of the solver options named `name`: `name.field`, or `field` alone when
/// `name` is empty (options checked on their own).
pub(crate) fn nested_name(name: &str, field: &str) -> String {
    if name.is_empty() {
        field.into()
    } else {
        format!("{name}.{field}")
    }
}

/// The error of option `field` of the solver options named `name` ([`nested_name`]), out of its range.
pub(crate) fn invalid_option<T>(name: &str, field: &str, reason: &str) -> crate::error::Result<T> {
    Err(crate::error::Error::InvalidOption {
        name: nested_name(name, field),
        reason: reason.into(),
    })
}

/// Stopping tests shared by every solver (the k.2 tests of section 4.1, plus a step-size test).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct StoppingCriteria {
    /// Stop when `‖∇f‖∞ ≤ gradient_tolerance`. Default `1e-12`.
    pub gradient_tolerance: f64,
    /// Stop when `f ≤ cost_tolerance`. Default `1e-24`.
    pub cost_tolerance: f64,
    /// Stop when an accepted step has `‖d‖ ≤ step_tolerance · (‖d‖ + step_tolerance)` relative to the
    /// tangent step size. Default `1e-12`.
    pub step_tolerance: f64,
    /// Iteration cap. Default 200.
    pub max_iterations: usize,
}

impl Default for StoppingCriteria {
    fn default() -> Self {
        StoppingCriteria {
            gradient_tolerance: 1e-12,
            cost_tolerance: 1e-24,
            step_tolerance: 1e-12,
            max_iterations: 200,
        }
    }
}

impl StoppingCriteria {
    /// Checks the options of a solver named `name` (errors name `name.field`, or `field` when `name` is
    /// empty): tolerances are numbers ≥ 0, the iteration cap at least 1.
    pub fn validate(&self, name: &str) -> crate::error::Result<()> {
        for (field, value) in [
            ("gradient_tolerance", self.gradient_tolerance),
            ("cost_tolerance", self.cost_tolerance),
            ("step_tolerance", self.step_tolerance),
        ] {
            if !(value >= 0.0) {
                return invalid_option(name, field, "must be a number ≥ 0");
            }
        }
        if self.max_iterations < 1 {
            return invalid_option(name, "max_iterations", "must be at least 1");
        }
        Ok(())
    }

    /// The k.2 tests that depend only on the current point.
    pub fn check<const N: usize>(&self, lin: &Linearization<N>) -> Option<Termination> {
        if !lin.cost.is_finite() || lin.gradient.iter().any(|g| !g.is_finite()) {
            Some(Termination::NonFiniteCost)
        } else if lin.cost <= self.cost_tolerance {
            Some(Termination::CostTolerance)
        } else if lin.gradient.amax() <= self.gradient_tolerance {
            Some(Termination::GradientTolerance)
        } else {
            None
        }
    }

    /// True when an accepted step is too short to matter.
    pub fn step_is_negligible<const N: usize>(&self, step: &SVector<f64, N>, scale: f64) -> bool {
        step.norm() <= self.step_tolerance * (scale + self.step_tolerance)
    }
}

#[cfg(test)]
pub(crate) mod testing {
    //! Shared test helpers: finite-difference checks of gradients and Hessians.
    use super::*;

    /// Central differences of the cost along each tangent direction, compared with the analytic
    /// gradient and Gauss-Newton Hessian. Returns the largest relative discrepancies.
    pub fn gradient_error<const N: usize, O: Objective<N>>(obj: &O, x: &O::Point, h: f64) -> f64 {
        let lin = obj.linearize(x);
        let mut worst: f64 = 0.0;
        for k in 0..N {
            let mut d = SVector::<f64, N>::zeros();
            d[k] = h;
            let fd = (obj.cost(&obj.retract(x, &d)) - obj.cost(&obj.retract(x, &-d))) / (2.0 * h);
            let scale = lin.gradient.amax().max(1e-8);
            worst = worst.max((fd - lin.gradient[k]).abs() / scale);
        }
        worst
    }

    /// Central differences of the gradient, compared with the exact Hessian.
    pub fn hessian_error<const N: usize, O: Objective<N>>(obj: &O, x: &O::Point, h: f64) -> f64 {
        let hess = obj.exact_hessian(x).expect("objective has an exact Hessian");
        let mut worst: f64 = 0.0;
        for k in 0..N {
            let mut d = SVector::<f64, N>::zeros();
            d[k] = h;
            let gp = obj.linearize(&obj.retract(x, &d)).gradient;
            let gm = obj.linearize(&obj.retract(x, &-d)).gradient;
            let col = (gp - gm) / (2.0 * h);
            let scale = hess.amax().max(1e-8);
            worst = worst.max((col - hess.column(k)).amax() / scale);
        }
        worst
    }
}
