//! `pluecker.PoseResult`, `pluecker.Pose`, `pluecker.PoseDetails`, `pluecker.PoseStage` and
//! `pluecker.RansacReport`: immutable reports owning
//! their data, each property declared once in a table ([`crate::properties`]). Every array property
//! returns a fresh array, so changing it cannot change the result.

use crate::camera::PyCamera;
use crate::certificate::certificate_of;
use crate::pickle::reduce;
use crate::properties::{result_class, Field};
use pluecker::chi_square::ResidualTest;
use pluecker::pose::{PoseDetails, RansacReport, StageReport};
use pluecker::{Pose, PoseResult};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

/// One stage of the pose pipeline (algebraic estimator, linear solve, reprojection refinement).
#[pyclass(frozen, name = "PoseStage", module = "pluecker")]
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
#[serde(transparent)]
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
        /// What `initial_cost` and `final_cost` measure: `algebraic` (eqs. 13-15, 22 as ½ΣΦ²),
        /// `reprojection` (Σ squared pixel residuals, px²) or `msac` (stage `ransac`: Σ min(e², τ²), px²).
        cost_kind = |s| s.inner.cost_kind.as_str();
        /// Rotation `R` at the end of the stage, `x_cam = R X_world + t`.
        rotation = |s| s.inner.rotation;
        /// Translation `t` at the end of the stage, world units.
        translation = |s| s.inner.translation;
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
        reduce(py, "PoseStage", self)
    }

    fn __repr__(&self) -> String {
        let s = &self.inner;
        format!(
            "PoseStage(name='{}', cost_kind='{}', iterations={}, initial_cost={:e}, final_cost={:e}, termination='{}')",
            s.name, s.cost_kind.as_str(), s.iterations, s.initial_cost, s.final_cost, s.termination.as_str()
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
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
#[serde(transparent)]
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
        /// Local optimisations run (one per sample whose pose beat every sample's before it).
        local_optimizations = |r| r.inner.local_optimizations;
        /// Inliers (points + lines) of the best model before the final refinement.
        inliers = |r| r.inner.inliers;
        /// Fewest inliers the best model needed, else status `too_few_inliers`: `max(min_inliers, min(c + 1,
        /// ⌈min_inlier_ratio · n⌉))`, `c` the most inliers a wrong pose plausibly gets by chance among `n`.
        required_inliers = |r| r.inner.required_inliers;
        /// MSAC score `Σ min(e², τ²)` of the best model, px².
        score = |r| r.inner.score;
        /// Why sampling stopped: `confidence`, `min_inlier_ratio` (enough samples to find a model with that
        /// inlier fraction, and none was), `iteration_cap`, `time_budget`, `interrupted` or `no_solvable_sample`.
        stop = |r| r.inner.stop.as_str();
        /// Wall time of the loop including local optimisation, seconds.
        time_seconds = |r| r.inner.time_seconds;
    }

    /// Pickle support (also `copy.deepcopy`): see `pickle.rs`.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        reduce(py, "RansacReport", self)
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

/// An estimated `K` (the Faugeras-Toscani baseline's) as the pinhole `Camera` it is; in `to_dict()` its
/// five numbers.
fn pinhole_camera(k: pluecker::camera::Intrinsics) -> PyResult<PyCamera> {
    crate::errors::guarded(|| pluecker::Camera::pinhole(k.fx, k.fy, k.cx, k.cy, k.skew)).map(PyCamera::wrap)
}

impl Field for pluecker::camera::Intrinsics {
    fn get(self, py: Python<'_>) -> PyResult<PyObject> {
        Ok(Py::new(py, pinhole_camera(self)?)?.into_any())
    }
    /// `{fx, fy, cx, cy, skew}`, as the core writes it.
    fn plain(self, py: Python<'_>) -> PyResult<PyObject> {
        let d = PyDict::new(py);
        for (name, value) in [
            ("fx", self.fx),
            ("fy", self.fy),
            ("cx", self.cx),
            ("cy", self.cy),
            ("skew", self.skew),
        ] {
            d.set_item(name, value)?;
        }
        Ok(d.into_any().unbind())
    }
    fn stub() -> String {
        "Camera".into()
    }
}

/// A camera pose `x_cam = R X_world + t`, the core's `Pose`: `rotation` (`R`) and `translation` (`t`,
/// world units), and the rotation in its other forms as methods. Unpacks as `R, t = pose`.
#[pyclass(frozen, name = "Pose", module = "pluecker")]
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
#[serde(transparent)]
pub struct PyPose {
    pub(crate) inner: Pose,
}

result_class! {
    PyPose {
        /// `R`, world to camera (3x3 rotation matrix).
        rotation = |p| p.inner.rotation;
        /// `t`, world units: the world origin in the camera frame.
        translation = |p| p.inner.translation;
    }

    /// The same motion as a unit dual quaternion `(r0, rx, ry, rz, s0, sx, sy, sz)` (Phong & Horaud
    /// 1995, eqs. 6-7), `r0 ≥ 0`; NaN when the pose is not finite.
    fn dual_quaternion<'py>(&self, py: Python<'py>) -> PyResult<PyObject> {
        Field::get(self.inner.dual_quaternion().to_vector(), py)
    }

    /// The rotation as `(axis, angle)`: a unit axis and an angle in [0, π], radians.
    fn axis_angle(&self, py: Python<'_>) -> PyResult<(PyObject, f64)> {
        let (axis, angle) = self.inner.axis_angle();
        Ok((Field::get(axis, py)?, angle))
    }

    /// The rotation vector `angle · axis`, radians (`R = exp([ω]×)`).
    fn rotation_vector(&self, py: Python<'_>) -> PyResult<PyObject> {
        Field::get(self.inner.rotation_vector(), py)
    }

    /// The optical centre in the world frame, `−Rᵀ t`.
    fn centre(&self, py: Python<'_>) -> PyResult<PyObject> {
        Field::get(self.inner.centre(), py)
    }

    /// `R, t = pose`.
    fn __iter__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let parts = [Field::get(self.inner.rotation, py)?, Field::get(self.inner.translation, py)?];
        PyTuple::new(py, parts)?.into_any().try_iter().map(|i| i.into_any())
    }

    fn __len__(&self) -> usize {
        2
    }

    /// Pickle support (also `copy.deepcopy`): see `pickle.rs`.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        reduce(py, "Pose", self)
    }

    fn __repr__(&self) -> String {
        let t = &self.inner.translation;
        let w = self.inner.rotation_vector();
        format!(
            "Pose(rotation_vector=[{:.6}, {:.6}, {:.6}], translation=[{:.6}, {:.6}, {:.6}])",
            w.x, w.y, w.z, t.x, t.y, t.z
        )
    }
}

/// A pose as a property: the `Pose` object, and `{"rotation", "translation"}` in `to_dict()`.
impl Field for PyPose {
    fn get(self, py: Python<'_>) -> PyResult<PyObject> {
        Ok(Py::new(py, self)?.into_any())
    }
    fn plain(self, py: Python<'_>) -> PyResult<PyObject> {
        let d = PyDict::new(py);
        self.fill_dict(py, &d)?;
        Ok(d.into_any().unbind())
    }
    fn stub() -> String {
        "Pose".into()
    }
}

/// The runner-up of `PoseDetails.second_best`: `(Pose, cost)`.
struct RunnerUp(Pose, f64);

impl Field for RunnerUp {
    fn get(self, py: Python<'_>) -> PyResult<PyObject> {
        let pose = PyPose { inner: self.0 }.get(py)?;
        Ok(PyTuple::new(py, [pose, self.1.into_pyobject(py)?.into_any().unbind()])?
            .into_any()
            .unbind())
    }
    fn plain(self, py: Python<'_>) -> PyResult<PyObject> {
        let pose = PyPose { inner: self.0 }.plain(py)?;
        Ok(PyTuple::new(py, [pose, self.1.into_pyobject(py)?.into_any().unbind()])?
            .into_any()
            .unbind())
    }
    fn stub() -> String {
        "Tuple[Pose, float]".into()
    }
}

/// How a `PoseResult` was found: the core's `PoseDetails`. Costs are `Σ r²`, px².
#[pyclass(frozen, name = "PoseDetails", module = "pluecker")]
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
#[serde(transparent)]
pub struct PyPoseDetails {
    inner: PoseDetails,
}

result_class! {
    PyPoseDetails {
        /// Every stage in order; the last one gave the returned pose.
        stages = |d| d.inner.stages.clone();
        /// Root-mean-square reprojection error over the used correspondences, pixels: `√(cost / m)`.
        rms_error_px = |d| d.inner.rms_error_px;
        /// Intrinsics estimated by method `'linear'` (`None` for the others).
        estimated_camera = |d| d.inner.estimated_camera;
        /// What the robust loop did; `None` unless `options.ransac` is set.
        ransac = |d| d.inner.ransac.clone();
        /// Where the σ of the covariance came from: `given` or `estimated`.
        covariance_source = |d| d.inner.covariance_source.map(|s| s.as_str());
        /// The σ of `covariance`: `options.sigma_px`, or `σ̂ = √(Σ r² / (m − 6))` over the m used residuals.
        sigma_px = |d| d.inner.sigma_px;
        /// The cheapest other local minimum with every point in front and its cost `Σ r²` (px²); `None` if none was
        /// found. Within `ambiguity_threshold · σ²` of `cost`, the status is `ambiguous`.
        second_best = |d| d.inner.second_best.map(|(p, c)| RunnerUp(p, c));
        /// Cost `Σ r²` of a pose with every point behind the camera that fits far better (status `behind_camera`).
        behind_camera_cost = |d| d.inner.behind_camera_cost;
        /// χ² test of the residuals against `sigma_px`; `None` without `options.sigma_px`.
        residual_test = |d| d.inner.residual_test;
        /// Why the pose is not certified, in words; `None` when it is.
        uncertified_reason = |d| d.inner.uncertified_reason.clone();
    }

    /// Pickle support (also `copy.deepcopy`): see `pickle.rs`.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        reduce(py, "PoseDetails", self)
    }

    fn __repr__(&self) -> String {
        let d = &self.inner;
        format!(
            "PoseDetails(stages={}, rms_error_px={:.3e})",
            d.stages.len(), d.rms_error_px
        )
    }
}

impl Field for PoseDetails {
    fn get(self, py: Python<'_>) -> PyResult<PyObject> {
        Ok(Py::new(py, PyPoseDetails { inner: self })?.into_any())
    }
    fn plain(self, py: Python<'_>) -> PyResult<PyObject> {
        let d = PyDict::new(py);
        PyPoseDetails { inner: self }.fill_dict(py, &d)?;
        Ok(d.into_any().unbind())
    }
    fn stub() -> String {
        "PoseDetails".into()
    }
}

/// The answer of `estimate_pose`, the core's `PoseResult`: the pose, its report's fields (as on every
/// result: method, status, cost, certificate, iterations, time), the correspondences used and its
/// covariance; how it was found is in `details`.
#[pyclass(frozen, name = "PoseResult", module = "pluecker")]
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
#[serde(transparent)]
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
        /// The pose `x_cam = R X_world + t` (NaN if the solver failed); `R, t = result.pose`.
        pose = |r| PyPose { inner: r.inner.pose };
        /// The estimator that ran.
        method = |r| r.inner.report.method.as_str();
        /// `success`, or why not: `gap_not_closed` (a requested certificate does not hold), `not_converged` (a
        /// stage hit its cap), `numerical_failure`, `behind_camera` (points behind at the pose, or the data fit far
        /// better behind: `details.behind_camera_cost`), `ambiguous` (another minimum nearly as good:
        /// `details.second_best`); robust: `too_few_inliers`, `no_hypothesis`; `interrupted`, `time_budget`.
        status = |r| r.inner.report.status.as_str();
        /// `status == 'success'`.
        success = |r| r.inner.report.success();
        /// Reprojection cost `Σ r²` (px²) of the used correspondences at the pose, in the observed pixels.
        cost = |r| r.inner.report.cost;
        /// What `cost` measures: `reprojection`.
        cost_kind = |r| r.inner.report.cost_kind.as_str();
        /// Proved lower bound on `cost` over every pose keeping the points and segment endpoints in front
        /// (`options.certify`); `None` when no bound was computed (`details.uncertified_reason` says why).
        certificate = |r| certificate_of(r.inner.report.certificate);
        /// `certificate is not None and certificate.certified`.
        certified = |r| r.inner.report.certified();
        /// Iterations summed over the stages.
        iterations = |r| r.inner.report.iterations;
        /// Why the last iterative stage stopped.
        termination = |r| r.inner.report.termination.as_str();
        /// Wall time, seconds.
        time_seconds = |r| r.inner.report.time_seconds;
        /// Degrees of freedom of `cost`: the residuals used minus the 6 of the pose (0 when not known).
        residual_dof = |r| r.inner.report.residual_dof;
        /// (N,) points used for the pose: when robust the final inliers (error ≤ `point_threshold` px), else all true.
        inliers_points = |r| r.inner.inliers_points.clone();
        /// (M,) lines used: when robust those within RMS `line_threshold` px of the projected line, else all true.
        inliers_lines = |r| r.inner.inliers_lines.clone();
        /// 6x6 covariance `σ² (JᵀJ)⁻¹` of `(ω, t)` at the pose (`ω` the tangent of `exp(ω) R`, radians, camera
        /// frame; then `t`, world units), from the used correspondences; `None` when `JᵀJ` is singular or σ unknown.
        covariance = |r| r.inner.covariance;
        /// How the pose was found: stages, noise, runner-up.
        details = |r| r.inner.details.clone();
    }

    /// The result as JSON, written by the core (`serde`): the same keys and values as `to_dict()`, NaN
    /// and inf as `null`; what `pluecker pose` prints.
    fn to_json(&self) -> PyResult<String> {
        serde_json::to_string(&self.inner).map_err(|e| pyo3::exceptions::PyValueError::new_err(e.to_string()))
    }

    /// Pickle support (also `copy.deepcopy`): see `pickle.rs`.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        reduce(py, "PoseResult", self)
    }

    fn __repr__(&self) -> String {
        let r = &self.inner;
        let t = &r.pose.translation;
        let w = r.pose.rotation_vector();
        format!(
            "PoseResult(status='{}', cost={:.6e}, rotation_vector=[{:.6}, {:.6}, {:.6}], translation=[{:.6}, {:.6}, {:.6}], certified={})",
            r.report.status.as_str(), r.report.cost, w.x, w.y, w.z, t.x, t.y, t.z,
            if r.report.certified() { "True" } else { "False" }
        )
    }
}

/// A pose `x_cam = R X_world + t` as Python passes it: a `Pose`, or the pair `(R, t)` of a `(3, 3)` rotation and a
/// `(3,)` translation, its parts checked and named `"{name} R"` and `"{name} t"`.
pub fn extract_pose(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<Pose> {
    if let Ok(pose) = obj.downcast::<PyPose>() {
        return Ok(pose.get().inner);
    }
    let pair = obj.downcast::<PyTuple>().map_err(|_| {
        let kind = obj.get_type().name().map_or("?".into(), |n| n.to_string());
        pyo3::exceptions::PyTypeError::new_err(format!("{name}: expected a tuple (R, t), got a {kind}"))
    })?;
    if pair.len() != 2 {
        return Err(crate::errors::shape_error(
            name,
            "a tuple (R, t)",
            format!("a tuple of length {}", pair.len()),
        ));
    }
    crate::convert::pose_from_parts(
        &format!("{name} R"),
        &pair.get_item(0)?,
        &format!("{name} t"),
        &pair.get_item(1)?,
    )
}
