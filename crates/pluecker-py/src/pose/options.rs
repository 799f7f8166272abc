//! `pluecker.PoseOptions` and `pluecker.RansacOptions`: the core's `PoseOptions` and `RansacOptions`
//! with the same names, the same nesting and the same defaults (their `Default`), settable from
//! Python and checked by the core's `validate` as they are set.
//!
//! `PoseOptions.ransac` (a `RansacOptions` or `None`), `PoseOptions.certify` (a `CertifyOptions` or
//! `None`) and the solvers' options (`trust_region`, `refinement`, `levenberg_marquardt`, `newton`) are
//! held by reference, pycolmap style: `options.certify.max_nodes = 10` or
//! `options.refinement.stopping.max_iterations = 20` changes the options that `options` uses. They are
//! read into the core's struct when `estimate_pose` is called.

use crate::certificate::PyCertifyOptions;
use crate::convert::{seconds_arg, Integer, Real};
use crate::errors::to_py_err;
use crate::nested::{NestedOptions, Shared};
use crate::optim::{PyLevenbergMarquardtOptions, PyStoppingCriteria, PyTrustRegionOptions};
use crate::pose::result::extract_pose;
use crate::properties::options_class;
use pluecker::pose::{Method, PoseOptions, RansacOptions};
use pyo3::prelude::*;

/// Options of `estimate_pose`, the core's `PoseOptions` (every default is the core's).
#[pyclass(name = "PoseOptions", module = "pluecker")]
#[derive(Debug, Clone, PartialEq)]
pub struct PyPoseOptions {
    /// The core's options but the nested ones (`ransac`, `certify` and the solvers': their values here
    /// stay the defaults, never read; see `core`).
    inner: PoseOptions,
    ransac: Option<Shared<PyRansacOptions>>,
    certify: Option<Shared<PyCertifyOptions>>,
    trust_region: Shared<PyTrustRegionOptions>,
    levenberg_marquardt: Shared<PyLevenbergMarquardtOptions>,
    newton: Shared<PyStoppingCriteria>,
    refinement: Shared<PyTrustRegionOptions>,
}

/// The core's defaults, the nested objects included (the refinement's differ from a plain
/// `TrustRegionOptions()`).
impl Default for PyPoseOptions {
    fn default() -> Self {
        let inner = PoseOptions::default();
        PyPoseOptions {
            ransac: None,
            certify: None,
            trust_region: Shared::new(PyTrustRegionOptions::from_core(inner.trust_region)),
            levenberg_marquardt: Shared::new(PyLevenbergMarquardtOptions::from_core(inner.levenberg_marquardt)),
            newton: Shared::new(PyStoppingCriteria { inner: inner.newton }),
            refinement: Shared::new(PyTrustRegionOptions::from_core(inner.refinement)),
            inner,
        }
    }
}

impl PyPoseOptions {
    fn validate(&self) -> PyResult<()> {
        self.core().validate().map_err(to_py_err)
    }

    /// The core's options, with the nested ones read from their objects now.
    pub(crate) fn core(&self) -> PoseOptions {
        let mut options = self.inner.clone();
        options.ransac = self.ransac.as_ref().map(|r| r.read().inner);
        options.certify = self.certify.as_ref().map(|c| c.read().inner);
        options.trust_region = self.trust_region.read().core();
        options.levenberg_marquardt = self.levenberg_marquardt.read().core();
        options.newton = self.newton.read().inner;
        options.refinement = self.refinement.read().core();
        options
    }
}

options_class! {
    PyPoseOptions {
        /// Estimator, one of `METHODS`.
        method: String = |o| o.inner.method.as_str(), |o, v| Method::parse(&v).map(|m| o.inner.method = m).map_err(to_py_err);
        /// Penalty λ on the dual-quaternion constraints `r·r = 1`, `r·s = 0` (Phong & Horaud 1995, eqs. 13-15, 22).
        penalty: Real = |o| o.inner.penalty, |o, v| v.get("penalty").map(|x| o.inner.penalty = x);
        /// Solve the algebraic stage in a centred, unit-scale object frame.
        normalize: bool = |o| o.inner.normalize, |o, v| Ok::<(), PyErr>(o.inner.normalize = v);
        /// Follow the estimator with a minimisation of the reprojection error in pixels.
        refine: bool = |o| o.inner.refine, |o, v| Ok::<(), PyErr>(o.inner.refine = v);
        /// An extra starting pose `(R, t)`, tried first besides the default starts; `None`: no guess needed.
        initial_pose: Option<Bound<'_, PyAny>> = |o| o.inner.initial_pose,
            |o, v| v.map(|p| extract_pose("initial_pose", &p)).transpose().map(|p| o.inner.initial_pose = p);
        /// The trust-region solver of the algebraic stage (methods `trust-region`, `trust-region-exact`). Held by reference.
        trust_region: Shared<PyTrustRegionOptions> = |o| o.trust_region.clone(), |o, v| Ok::<(), PyErr>(o.trust_region = v);
        /// The solver of method `'levenberg-marquardt'`. Held by reference.
        levenberg_marquardt: Shared<PyLevenbergMarquardtOptions> = |o| o.levenberg_marquardt.clone(),
            |o, v| Ok::<(), PyErr>(o.levenberg_marquardt = v);
        /// The stopping tests of method `'newton'`. Held by reference.
        newton: Shared<PyStoppingCriteria> = |o| o.newton.clone(), |o, v| Ok::<(), PyErr>(o.newton = v);
        /// The trust-region minimisation of the reprojection error (`refine`). Held by reference.
        refinement: Shared<PyTrustRegionOptions> = |o| o.refinement.clone(), |o, v| Ok::<(), PyErr>(o.refinement = v);
        /// Pixel noise σ of every image point and endpoint, for the covariance; `None`: estimated from the residuals.
        sigma_px: Option<Real> = |o| o.inner.sigma_px, |o, v| v.map(|r| r.get("sigma_px")).transpose().map(|s| o.inner.sigma_px = s);
        /// Status `ambiguous` when another minimum is within `ambiguity_threshold · σ²` of the answer's cost.
        ambiguity_threshold: Real = |o| o.inner.ambiguity_threshold, |o, v| v.get("ambiguity_threshold").map(|x| o.inner.ambiguity_threshold = x);
        /// Robust estimation (LO-RANSAC over points and lines) with these options instead of `method`'s estimator;
        /// `None`: every correspondence is an inlier. Held by reference.
        ransac: Option<Shared<PyRansacOptions>> = |o| o.ransac.clone(), |o, v| Ok::<(), PyErr>(o.ransac = v);
        /// The global-optimality certificate (the sublevel-set test) with these options; `None`: not requested.
        /// Held by reference. A requested certificate that does not hold gives status `gap_not_closed`.
        certify: Option<Shared<PyCertifyOptions>> = |o| o.certify.clone(), |o, v| Ok::<(), PyErr>(o.certify = v);
    }
}

/// Options of the robust estimator (LO-RANSAC over points and lines), the core's `RansacOptions`.
/// Thresholds are in pixels.
#[pyclass(name = "RansacOptions", module = "pluecker")]
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PyRansacOptions {
    pub(crate) inner: RansacOptions,
}

impl NestedOptions for PyRansacOptions {
    const CLASS: &'static str = "RansacOptions";
}

impl PyRansacOptions {
    fn validate(&self) -> PyResult<()> {
        self.inner.validate().map_err(to_py_err)
    }
}

options_class! {
    PyRansacOptions {
        /// Inlier threshold of a point: reprojection distance, pixels.
        point_threshold: Real = |o| o.inner.point_threshold, |o, v| v.get("point_threshold").map(|x| o.inner.point_threshold = x);
        /// Inlier threshold of a segment: RMS distance of its endpoints to the projected line, pixels.
        line_threshold: Real = |o| o.inner.line_threshold, |o, v| v.get("line_threshold").map(|x| o.inner.line_threshold = x);
        /// Probability of having drawn an all-inlier sample when sampling stops, in (0, 1).
        confidence: Real = |o| o.inner.confidence, |o, v| v.get("confidence").map(|x| o.inner.confidence = x);
        /// Cap on the samples drawn.
        max_iterations: Integer = |o| o.inner.max_iterations, |o, v| v.count("max_iterations", 1).map(|n| o.inner.max_iterations = n);
        /// Samples drawn at least, whatever the confidence.
        min_iterations: Integer = |o| o.inner.min_iterations, |o, v| v.count("min_iterations", 0).map(|n| o.inner.min_iterations = n);
        /// Lowest inlier ratio sampling plans for (caps the samples drawn), in [0, 1).
        min_inlier_ratio: Real = |o| o.inner.min_inlier_ratio, |o, v| v.get("min_inlier_ratio").map(|x| o.inner.min_inlier_ratio = x);
        /// Sequential probability ratio test: stop scoring a hypothesis once it cannot beat the best.
        sprt: bool = |o| o.inner.sprt, |o, v| Ok::<(), PyErr>(o.inner.sprt = v);
        /// Wall-time budget of the sampling loop, seconds; `None`: no budget.
        time_budget: Option<Real> = |o| o.inner.time_budget.map(|d| d.as_secs_f64()),
            |o, v| v.map(|r| r.get("time_budget").and_then(|s| seconds_arg("time_budget", s))).transpose().map(|d| o.inner.time_budget = d);
        /// Seed of the sampler: the same seed and data give the same result.
        seed: Integer = |o| o.inner.seed, |o, v| v.seed("seed").map(|s| o.inner.seed = s);
        /// Iteration cap of each local optimisation run; 0 disables local optimisation.
        local_iterations: Integer = |o| o.inner.local_iterations, |o, v| v.count("local_iterations", 0).map(|n| o.inner.local_iterations = n);
        /// Fewest inliers of a usable model (at least 3); fewer correspondences in all is an error.
        min_inliers: Integer = |o| o.inner.min_inliers, |o, v| v.count("min_inliers", 3).map(|n| o.inner.min_inliers = n);
    }
}
