//! `pluecker.StoppingCriteria`, `pluecker.TrustRegionOptions` and `pluecker.LevenbergMarquardtOptions`:
//! the core's `optim` options with the same names, nesting and defaults. They are nested in
//! `PoseOptions` (`trust_region`, `refinement`, `levenberg_marquardt`, `newton`) and hold their own
//! `stopping` the same way: by reference, pycolmap style (`options.refinement.stopping.max_iterations
//! = 50` changes the options that hold it), read into the core's structs when a function is called.

use crate::convert::{Integer, Real};
use crate::errors::to_py_err;
use crate::nested::{NestedOptions, Shared};
use crate::properties::options_class;
use pluecker::optim::{LevenbergMarquardtOptions, StoppingCriteria, Subproblem, TrustRegionOptions};
use pyo3::prelude::*;

/// Stopping tests and iteration cap of a solver, the core's `StoppingCriteria`.
#[pyclass(name = "StoppingCriteria", module = "pluecker")]
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PyStoppingCriteria {
    pub(crate) inner: StoppingCriteria,
}

impl NestedOptions for PyStoppingCriteria {
    const CLASS: &'static str = "StoppingCriteria";
}

impl PyStoppingCriteria {
    fn validate(&self) -> PyResult<()> {
        self.inner.validate("").map_err(to_py_err)
    }
}

options_class! {
    PyStoppingCriteria {
        /// Stop when the gradient's largest entry is at most this.
        gradient_tolerance: Real = |o| o.inner.gradient_tolerance,
            |o, v| v.get("gradient_tolerance").map(|x| o.inner.gradient_tolerance = x);
        /// Stop when the cost is at most this.
        cost_tolerance: Real = |o| o.inner.cost_tolerance, |o, v| v.get("cost_tolerance").map(|x| o.inner.cost_tolerance = x);
        /// Stop when an accepted step is this small relative to the tangent step size.
        step_tolerance: Real = |o| o.inner.step_tolerance, |o, v| v.get("step_tolerance").map(|x| o.inner.step_tolerance = x);
        /// Iteration cap.
        max_iterations: Integer = |o| o.inner.max_iterations,
            |o, v| v.count("max_iterations", 1).map(|n| o.inner.max_iterations = n);
    }
}

/// Options of the trust-region solver (Phong & Horaud 1995, section 4.1), the core's
/// `TrustRegionOptions`; defaults are the paper's values.
#[pyclass(name = "TrustRegionOptions", module = "pluecker")]
#[derive(Debug, Clone, Default)]
pub struct PyTrustRegionOptions {
    /// The core's options but `stopping` (held by `stopping`, read by [`PyTrustRegionOptions::core`]).
    inner: TrustRegionOptions,
    stopping: Shared<PyStoppingCriteria>,
}

/// Equal options: the same fields and stopping tests (`inner.stopping` is never read).
impl PartialEq for PyTrustRegionOptions {
    fn eq(&self, other: &Self) -> bool {
        self.core() == other.core()
    }
}

impl NestedOptions for PyTrustRegionOptions {
    const CLASS: &'static str = "TrustRegionOptions";
}

impl PyTrustRegionOptions {
    fn validate(&self) -> PyResult<()> {
        self.core().validate("").map_err(to_py_err)
    }

    /// The core's options, with `stopping` read from its object now.
    pub(crate) fn core(&self) -> TrustRegionOptions {
        let mut options = self.inner;
        options.stopping = self.stopping.read().inner;
        options
    }

    /// Options whose fields and stopping tests are `options`'.
    pub(crate) fn from_core(options: TrustRegionOptions) -> Self {
        let stopping = Shared::new(PyStoppingCriteria {
            inner: options.stopping,
        });
        PyTrustRegionOptions {
            inner: options,
            stopping,
        }
    }
}

options_class! {
    PyTrustRegionOptions {
        /// Subproblem solver: `hebden` (Gauss-Newton Hessian shifted by `hessian_shift`, the paper's
        /// step, Appendix A) or `more_sorensen` (exact Hessian, section 4.2).
        subproblem: String = |o| o.inner.subproblem.as_str(),
            |o, v| Subproblem::parse(&v).map(|s| o.inner.subproblem = s).map_err(to_py_err);
        /// α in `H' = JᵀJ + αI` (step k.3).
        hessian_shift: Real = |o| o.inner.hessian_shift, |o, v| v.get("hessian_shift").map(|x| o.inner.hessian_shift = x);
        /// Initial trust radius δ₀.
        initial_radius: Real = |o| o.inner.initial_radius, |o, v| v.get("initial_radius").map(|x| o.inner.initial_radius = x);
        /// Acceptance threshold r on the ratio of eq. 28 (paper: r ∈ [0.1, 0.3]).
        accept_ratio: Real = |o| o.inner.accept_ratio, |o, v| v.get("accept_ratio").map(|x| o.inner.accept_ratio = x);
        /// Expansion threshold s (paper: s ∈ [0.5, 0.8]).
        expand_ratio: Real = |o| o.inner.expand_ratio, |o, v| v.get("expand_ratio").map(|x| o.inner.expand_ratio = x);
        /// Stop when the trust radius δ is at most this (the ε_δ of step k.2).
        radius_tolerance: Real = |o| o.inner.radius_tolerance,
            |o, v| v.get("radius_tolerance").map(|x| o.inner.radius_tolerance = x);
        /// The other stopping tests of step k.2 and the iteration cap. Held by reference.
        stopping: Shared<PyStoppingCriteria> = |o| o.stopping.clone(), |o, v| Ok::<(), PyErr>(o.stopping = v);
    }
}

/// Options of the Levenberg-Marquardt solver (Phong & Horaud 1995, section 4.2), the core's
/// `LevenbergMarquardtOptions`.
#[pyclass(name = "LevenbergMarquardtOptions", module = "pluecker")]
#[derive(Debug, Clone, Default)]
pub struct PyLevenbergMarquardtOptions {
    /// The core's options but `stopping` (held by `stopping`).
    inner: LevenbergMarquardtOptions,
    stopping: Shared<PyStoppingCriteria>,
}

/// Equal options: the same fields and stopping tests (`inner.stopping` is never read).
impl PartialEq for PyLevenbergMarquardtOptions {
    fn eq(&self, other: &Self) -> bool {
        self.core() == other.core()
    }
}

impl NestedOptions for PyLevenbergMarquardtOptions {
    const CLASS: &'static str = "LevenbergMarquardtOptions";
}

impl PyLevenbergMarquardtOptions {
    fn validate(&self) -> PyResult<()> {
        self.core().validate("").map_err(to_py_err)
    }

    /// Options whose fields and stopping tests are `options`'.
    pub(crate) fn from_core(options: LevenbergMarquardtOptions) -> Self {
        let stopping = Shared::new(PyStoppingCriteria {
            inner: options.stopping,
        });
        PyLevenbergMarquardtOptions {
            inner: options,
            stopping,
        }
    }

    /// The core's options, with `stopping` read from its object now.
    pub(crate) fn core(&self) -> LevenbergMarquardtOptions {
        let mut options = self.inner;
        options.stopping = self.stopping.read().inner;
        options
    }
}

options_class! {
    PyLevenbergMarquardtOptions {
        /// Initial damping, relative to the largest diagonal entry of `JᵀJ`.
        initial_damping: Real = |o| o.inner.initial_damping, |o, v| v.get("initial_damping").map(|x| o.inner.initial_damping = x);
        /// Failed steps in a row after which the method gives up.
        max_rejections: Integer = |o| o.inner.max_rejections,
            |o, v| v.count("max_rejections", 1).map(|n| o.inner.max_rejections = n);
        /// Stopping tests and iteration cap. Held by reference.
        stopping: Shared<PyStoppingCriteria> = |o| o.stopping.clone(), |o, v| Ok::<(), PyErr>(o.stopping = v);
    }
}
