//! `pluecker.PoseResult`, `pluecker.PoseStage` and `pluecker.RansacReport`: immutable reports owning
//! their data, each property declared once in a table ([`crate::fields`]). Every array property
//! returns a fresh array, so changing it cannot change the result.

use crate::camera::PyCamera;
use crate::fields::{result_class, Field};
use crate::pickle::{pack_struct, reduce, Pack, Reader};
use pluecker::chi_square::ResidualTest;
use pluecker::pose::{RansacReport, StageReport, Status};
use pluecker::PoseResult;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

/// One stage of the pose pipeline (algebraic estimator, linear solve, reprojection refinement).
#[pyclass(frozen, name = "PoseStage", module = "pluecker")]
#[derive(Debug, Clone)]
pub struct PyPoseStage {
    inner: StageReport,
}

impl PyPoseStage {
    pub(crate) fn wrap(inner: StageReport) -> Self {
        PyPoseStage { inner }
    }
}

result_class! {
    PyPoseStage {
        /// Name of the stage.
        name = |s| s.inner.name.clone();
        /// What `initial_cost` and `final_cost` measure: `algebraic` (eqs. 13-15, 22 as ½ΣΦ²), `reprojection`
        /// (½Σ squared pixel residuals) or `msac` (stage `ransac`: ½Σ min(e², τ²), px²).
        cost_kind = |s| s.inner.cost_kind;
        /// Rotation at the end of the stage, `x_cam = R X_world + t`.
        R = |s| s.inner.rotation;
        /// Translation at the end of the stage, world units.
        t = |s| s.inner.translation;
        /// Iterations of the stage.
        iterations = |s| s.inner.iterations;
        /// Cost at the stage's start.
        initial_cost = |s| s.inner.initial_cost;
        /// Cost at the stage's end.
        final_cost = |s| s.inner.final_cost;
        /// Why the stage stopped: `gradient_tolerance`, `radius_tolerance`, `cost_tolerance`, `step_tolerance`,
        /// `max_iterations`, `singular_hessian`, `non_finite_cost` or `closed_form`.
        termination = |s| s.inner.termination.as_str();
        /// Wall time of the stage, seconds.
        time_seconds = |s| s.inner.time_seconds;
    }

    /// Pickle support (also `copy.deepcopy`): see `pickle.rs`.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        reduce(py, "PoseStage", &[self])
    }

    fn __repr__(&self) -> String {
        let s = &self.inner;
        format!(
            "PoseStage(name='{}', cost_kind='{}', iterations={}, initial_cost={:e}, final_cost={:e}, termination='{}')",
            s.name, s.cost_kind, s.iterations, s.initial_cost, s.final_cost, s.termination.as_str()
        )
    }
}

impl Field for StageReport {
    fn get(self, py: Python<'_>) -> PyResult<PyObject> {
        Ok(Py::new(py, PyPoseStage::wrap(self))?.into_any())
    }
    fn plain(self, py: Python<'_>) -> PyResult<PyObject> {
        let d = PyDict::new(py);
        PyPoseStage::wrap(self).fill_dict(py, &d)?;
        Ok(d.into_any().unbind())
    }
    fn stub() -> String {
        "PoseStage".into()
    }
}

impl Field for Vec<StageReport> {
    fn get(self, py: Python<'_>) -> PyResult<PyObject> {
        let stages = self.into_iter().map(|s| s.get(py)).collect::<PyResult<Vec<_>>>()?;
        Ok(stages.into_pyobject(py)?.into_any().unbind())
    }
    fn plain(self, py: Python<'_>) -> PyResult<PyObject> {
        let stages = self.into_iter().map(|s| s.plain(py)).collect::<PyResult<Vec<_>>>()?;
        Ok(stages.into_pyobject(py)?.into_any().unbind())
    }
    fn stub() -> String {
        "List[PoseStage]".into()
    }
}

/// What the robust loop (LO-RANSAC) did: `PoseResult.ransac` of a robust estimate.
#[pyclass(frozen, name = "RansacReport", module = "pluecker")]
#[derive(Debug, Clone)]
pub struct PyRansacReport {
    inner: RansacReport,
}

result_class! {
    PyRansacReport {
        /// Samples drawn.
        iterations = |r| r.inner.iterations;
        /// Samples without a pose in front of the camera (collinear points, parallel lines, ...).
        degenerate_samples = |r| r.inner.degenerate_samples;
        /// Poses scored (a sample may give several), fully or until an early exit.
        models_scored = |r| r.inner.models_scored;
        /// Poses rejected by the sequential probability ratio test.
        sprt_rejections = |r| r.inner.sprt_rejections;
        /// Reprojection errors evaluated while scoring: the work of the scoring.
        errors_evaluated = |r| r.inner.errors_evaluated;
        /// Local optimisations run (one per new best model).
        local_optimizations = |r| r.inner.local_optimizations;
        /// Inliers (points + lines) of the best model before the final refinement.
        inliers = |r| r.inner.inliers;
        /// Fewest inliers the best model needed, else status `too_few_inliers`: `max(min_inliers, min(c + 1,
        /// ⌈min_inlier_ratio · n⌉))`, `c` the most inliers a wrong pose plausibly gets by chance among `n`.
        required_inliers = |r| r.inner.required_inliers;
        /// MSAC score `½ Σ min(e², τ²)` of the best model, px².
        score = |r| r.inner.score;
        /// Why sampling stopped: `confidence`, `min_inlier_ratio` (enough samples to find a model with that
        /// inlier fraction, and none was), `iteration_cap`, `time_budget`, `interrupted` or `no_solvable_sample`.
        stop = |r| r.inner.stop.as_str();
        /// Wall time of the loop including local optimisation, seconds.
        time_seconds = |r| r.inner.time_seconds;
    }

    /// Pickle support (also `copy.deepcopy`): see `pickle.rs`.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        reduce(py, "RansacReport", &[self])
    }

    fn __repr__(&self) -> String {
        let r = &self.inner;
        format!(
            "RansacReport(iterations={}, inliers={}, required_inliers={}, stop='{}', time_seconds={:.3e})",
            r.iterations, r.inliers, r.required_inliers, r.stop.as_str(), r.time_seconds
        )
    }
}

impl Field for RansacReport {
    fn get(self, py: Python<'_>) -> PyResult<PyObject> {
        Ok(Py::new(py, PyRansacReport { inner: self })?.into_any())
    }
    fn plain(self, py: Python<'_>) -> PyResult<PyObject> {
        let d = PyDict::new(py);
        PyRansacReport { inner: self }.fill_dict(py, &d)?;
        Ok(d.into_any().unbind())
    }
    fn stub() -> String {
        "RansacReport".into()
    }
}

impl Field for ResidualTest {
    /// `{"chi2", "dof", "p_value", "consistent"}`.
    fn get(self, py: Python<'_>) -> PyResult<PyObject> {
        let d = PyDict::new(py);
        d.set_item("chi2", self.chi2)?;
        d.set_item("dof", self.dof)?;
        d.set_item("p_value", self.p_value)?;
        d.set_item("consistent", self.consistent)?;
        Ok(d.into_any().unbind())
    }
    fn stub() -> String {
        "_ResidualTest".into()
    }
}

impl Field for pluecker::Camera {
    fn get(self, py: Python<'_>) -> PyResult<PyObject> {
        Ok(Py::new(py, PyCamera::wrap(self))?.into_any())
    }
    fn plain(self, py: Python<'_>) -> PyResult<PyObject> {
        let d = PyDict::new(py);
        PyCamera::wrap(self).fill_dict(py, &d)?;
        Ok(d.into_any().unbind())
    }
    fn stub() -> String {
        "Camera".into()
    }
}

/// The answer of `estimate_pose`: the pose, how it was found, and whether it can be used.
#[pyclass(frozen, name = "PoseResult", module = "pluecker")]
#[derive(Debug, Clone)]
pub struct PyPoseResult {
    inner: PoseResult,
}

impl PyPoseResult {
    pub fn wrap(inner: PoseResult) -> Self {
        PyPoseResult { inner }
    }
}

result_class! {
    PyPoseResult {
        /// Rotation, `x_cam = R X_world + t`.
        R = |r| r.inner.rotation;
        /// Translation, world units.
        t = |r| r.inner.translation;
        /// The same motion as a unit dual quaternion `(r0, rx, ry, rz, s0, sx, sy, sz)` (eqs. 6-7), `r0 ≥ 0`.
        dual_quaternion = |r| r.inner.dual_quaternion.to_vector();
        /// Unit rotation axis.
        axis = |r| r.inner.axis;
        /// Rotation angle about `axis`, radians in [0, π].
        angle = |r| r.inner.angle;
        /// The estimator that ran.
        method = |r| r.inner.method.as_str();
        /// Iterations summed over the stages.
        iterations = |r| r.inner.iterations;
        /// Cost of the last stage at the returned pose.
        final_cost = |r| r.inner.final_cost;
        /// Why the last iterative stage stopped.
        termination = |r| r.inner.termination.as_str();
        /// `success`, or why not: `not_converged` (a stage hit its cap), `numerical_failure`, `behind_camera`
        /// (points behind at the pose, or the data fit far better behind: `behind_camera_cost`), `ambiguous`
        /// (another minimum nearly as good: `second_best_*`); robust: `too_few_inliers`, `no_hypothesis`.
        status = |r| r.inner.status.as_str();
        /// `status == 'success'`.
        success = |r| r.inner.status == Status::Success;
        /// Root-mean-square reprojection error over all correspondences, pixels.
        rms_error_px = |r| r.inner.rms_error_px;
        /// Total wall time, seconds.
        time_seconds = |r| r.inner.time_seconds;
        /// Every stage in order; the last one gave the returned pose.
        stages = |r| r.inner.stages.clone();
        /// Intrinsics estimated by method `'linear'` (`None` for the others).
        estimated_camera = |r| r.inner.estimated_camera;
        /// (N,) points used for the pose: when robust the final inliers (error ≤ `point_threshold` px), else all true.
        inliers_points = |r| r.inner.inliers_points.clone();
        /// (M,) lines used: when robust those within RMS `line_threshold` px of the projected line, else all true.
        inliers_lines = |r| r.inner.inliers_lines.clone();
        /// What the robust loop did; `None` unless estimated with `ransac=`.
        ransac = |r| r.inner.ransac.clone();
        /// 6x6 covariance `σ² (JᵀJ)⁻¹` of `(ω, t)` at the pose (`ω` the tangent of `exp(ω) R`, radians, camera
        /// frame; then `t`, world units), from the used correspondences; `None` when `JᵀJ` is singular or σ unknown.
        covariance = |r| r.inner.covariance;
        /// Where the σ of the covariance came from: `given` or `estimated`.
        covariance_source = |r| r.inner.covariance_source.map(|s| s.as_str());
        /// The σ of `covariance`: `options.sigma_px`, or `σ̂ = √(Σ r² / (m − 6))` over the m used residuals.
        sigma_px = |r| r.inner.sigma_px;
        /// Proved global minimum of `½ Σ r²` within `certify_gap`, over every pose keeping the points in front
        /// (`options.certify` only).
        certified = |r| r.inner.certified;
        /// The proved lower bound on `½ Σ r²` (px²); NaN when there is none.
        lower_bound = |r| r.inner.lower_bound;
        /// The bound as proved, before the clamp to the cost that gives `lower_bound`; NaN when there is none.
        raw_lower_bound = |r| r.inner.raw_lower_bound;
        /// `(cost − lower_bound) / cost`; NaN when there is no bound.
        gap = |r| r.inner.gap;
        /// `sublevel_set` (proved), `not_requested` or `not_proved`.
        certificate = |r| r.inner.certificate.as_str();
        /// The certificate's explanation in words.
        certificate_message = |r| r.inner.certificate.message();
        /// `status == 'ambiguous'`: another local minimum explains the data nearly as well.
        ambiguous = |r| r.inner.ambiguous;
        /// Rotation of the cheapest other local minimum with every point in front; `None` if none was found.
        second_best_R = |r| r.inner.second_best.map(|(p, _)| p.rotation);
        /// Translation of that minimum.
        second_best_t = |r| r.inner.second_best.map(|(p, _)| p.translation);
        /// Its cost `½ Σ r²`, px².
        second_best_cost = |r| r.inner.second_best.map(|(_, c)| c);
        /// Cost of a pose with every point behind the camera that fits far better (status `behind_camera`).
        behind_camera_cost = |r| r.inner.behind_camera_cost;
        /// χ² test of the residuals against `sigma_px`; `None` without `options.sigma_px`.
        residual_test = |r| r.inner.residual_test;
    }

    /// Pickle support (also `copy.deepcopy`): see `pickle.rs`.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        reduce(py, "PoseResult", &[self])
    }

    fn __repr__(&self) -> String {
        let r = &self.inner;
        let (t, q) = (&r.translation, &r.dual_quaternion.r);
        format!(
            "PoseResult(method='{}', status='{}', iterations={}, rms_error_px={:.3e}, angle={:.6}, t=[{:.6}, {:.6}, {:.6}], r=[{:.6}, {:.6}, {:.6}, {:.6}])",
            r.method.as_str(), r.status.as_str(), r.iterations, r.rms_error_px, r.angle,
            t.x, t.y, t.z, q[0], q[1], q[2], q[3]
        )
    }
}

pack_struct!(PyPoseStage { inner });
pack_struct!(PyRansacReport { inner });
pack_struct!(PyPoseResult { inner });
