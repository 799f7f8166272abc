//! `pluecker.PoseResult` and `pluecker.PoseStage`: immutable reports owning their data. Every array
//! getter returns a fresh array, so changing it cannot change the result.

use pluecker::chi_square::ResidualTest;
use crate::camera::PyCamera;
use crate::convert::{matrix3_rows, matrix3_to_py, vector_to_py};
use nalgebra::{Matrix6, Vector3, Vector4};
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2};
use pluecker::pose::StageReport;
use pluecker::{PoseResult, Status};
use crate::convert::strict_json_dict;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use crate::pickle::{pack_struct, reduce, Pack, Reader};
use pyo3::types::PyTuple;


/// One stage of the pose pipeline (algebraic estimator, linear solve, reprojection refinement).
#[pyclass(frozen, name = "PoseStage", module = "pluecker")]
#[derive(Debug, Clone)]
pub struct PyPoseStage {
    inner: StageReport,
}

#[pymethods]
impl PyPoseStage {
    #[getter]
    fn name(&self) -> &str {
        &self.inner.name
    }

    #[getter]
    fn cost_kind(&self) -> &str {
        self.inner.cost_kind
    }

    #[getter(R)]
    fn rotation<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        matrix3_to_py(py, &self.inner.rotation)
    }

    #[getter(t)]
    fn translation<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vector_to_py(py, &self.inner.translation)
    }

    #[getter]
    fn iterations(&self) -> usize {
        self.inner.iterations
    }

    #[getter]
    fn initial_cost(&self) -> f64 {
        self.inner.initial_cost
    }

    #[getter]
    fn final_cost(&self) -> f64 {
        self.inner.final_cost
    }

    #[getter]
    fn termination(&self) -> &'static str {
        self.inner.termination.as_str()
    }

    #[getter]
    fn time_seconds(&self) -> f64 {
        self.inner.time_seconds
    }

    /// Plain-Python (JSON-serialisable) form.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let s = &self.inner;
        let d = PyDict::new(py);
        d.set_item("name", &s.name)?;
        d.set_item("cost_kind", s.cost_kind)?;
        d.set_item("R", matrix3_rows(&s.rotation))?;
        d.set_item("t", s.translation.as_slice())?;
        d.set_item("iterations", s.iterations)?;
        d.set_item("initial_cost", s.initial_cost)?;
        d.set_item("final_cost", s.final_cost)?;
        d.set_item("termination", s.termination.as_str())?;
        d.set_item("time_seconds", s.time_seconds)?;
        strict_json_dict(d)
    }


    /// Pickle support (also `copy.deepcopy`): see `pickle.rs`.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        reduce(py, "PoseStage", &[self])
    }

    fn __repr__(&self) -> String {
        let s = &self.inner;
        format!(
            "PoseStage(name='{}', cost_kind='{}', iterations={}, initial_cost={:e}, final_cost={:e}, termination='{}')",
            s.name,
            s.cost_kind,
            s.iterations,
            s.initial_cost,
            s.final_cost,
            s.termination.as_str()
        )
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

    fn covariance_rows(&self) -> Option<Vec<[f64; 6]>> {
        let c: &Matrix6<f64> = self.inner.covariance.as_ref()?;
        Some((0..6).map(|i| std::array::from_fn(|j| c[(i, j)])).collect())
    }

    fn dual_quaternion_values(&self) -> [f64; 8] {
        let q = &self.inner.dual_quaternion;
        [q.r[0], q.r[1], q.r[2], q.r[3], q.s[0], q.s[1], q.s[2], q.s[3]]
    }
}

fn camera_dict<'py>(py: Python<'py>, c: &pluecker::Camera) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("fx", c.fx)?;
    d.set_item("fy", c.fy)?;
    d.set_item("cx", c.cx)?;
    d.set_item("cy", c.cy)?;
    d.set_item("skew", c.skew)?;
    Ok(d)
}

#[pymethods]
impl PyPoseResult {
    #[getter(R)]
    fn rotation<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        matrix3_to_py(py, &self.inner.rotation)
    }

    #[getter(t)]
    fn translation<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vector_to_py(py, &self.inner.translation)
    }

    #[getter]
    fn dual_quaternion<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.dual_quaternion_values())
    }

    #[getter]
    fn axis<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vector_to_py::<3>(py, &self.inner.axis)
    }

    #[getter]
    fn angle(&self) -> f64 {
        self.inner.angle
    }

    #[getter]
    fn method(&self) -> &'static str {
        self.inner.method.as_str()
    }

    #[getter]
    fn iterations(&self) -> usize {
        self.inner.iterations
    }

    #[getter]
    fn final_cost(&self) -> f64 {
        self.inner.final_cost
    }

    #[getter]
    fn termination(&self) -> &'static str {
        self.inner.termination.as_str()
    }

    #[getter]
    fn status(&self) -> &'static str {
        self.inner.status.as_str()
    }

    #[getter]
    fn success(&self) -> bool {
        self.inner.status == Status::Success
    }

    #[getter]
    fn rms_error_px(&self) -> f64 {
        self.inner.rms_error_px
    }

    #[getter]
    fn time_seconds(&self) -> f64 {
        self.inner.time_seconds
    }

    #[getter]
    fn stages(&self) -> Vec<PyPoseStage> {
        self.inner
            .stages
            .iter()
            .map(|s| PyPoseStage { inner: s.clone() })
            .collect()
    }

    #[getter]
    fn estimated_camera(&self) -> Option<PyCamera> {
        self.inner.estimated_camera.map(PyCamera::wrap)
    }

    #[getter]
    fn inliers_points<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<bool>> {
        PyArray1::from_slice(py, &self.inner.inliers_points)
    }

    #[getter]
    fn inliers_lines<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<bool>> {
        PyArray1::from_slice(py, &self.inner.inliers_lines)
    }

    #[getter]
    fn ransac_iterations(&self) -> usize {
        self.inner.ransac.as_ref().map_or(0, |r| r.iterations)
    }

    #[getter]
    fn ransac_models_scored(&self) -> usize {
        self.inner.ransac.as_ref().map_or(0, |r| r.models_scored)
    }

    #[getter]
    fn ransac_local_optimizations(&self) -> usize {
        self.inner.ransac.as_ref().map_or(0, |r| r.local_optimizations)
    }

    #[getter]
    fn ransac_sprt_rejections(&self) -> usize {
        self.inner.ransac.as_ref().map_or(0, |r| r.sprt_rejections)
    }

    #[getter]
    fn ransac_errors_evaluated(&self) -> usize {
        self.inner.ransac.as_ref().map_or(0, |r| r.errors_evaluated)
    }

    #[getter]
    fn ransac_required_inliers(&self) -> usize {
        self.inner.ransac.as_ref().map_or(0, |r| r.required_inliers)
    }

    #[getter]
    fn ransac_degenerate_samples(&self) -> usize {
        self.inner.ransac.as_ref().map_or(0, |r| r.degenerate_samples)
    }

    #[getter]
    fn ransac_time_seconds(&self) -> f64 {
        self.inner.ransac.as_ref().map_or(0.0, |r| r.time_seconds)
    }

    #[getter]
    fn ransac_stop(&self) -> Option<&'static str> {
        self.inner.ransac.as_ref().map(|r| r.stop.as_str())
    }

    #[getter]
    fn covariance<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray2<f64>>> {
        let c = self.inner.covariance.as_ref()?;
        Some(Array2::from_shape_fn((6, 6), |(i, j)| c[(i, j)]).into_pyarray(py))
    }

    #[getter]
    fn covariance_source(&self) -> Option<&'static str> {
        self.inner.covariance_source.map(|s| s.as_str())
    }

    #[getter]
    fn sigma_px(&self) -> Option<f64> {
        self.inner.sigma_px
    }

    #[getter]
    fn certified(&self) -> bool {
        self.inner.certified
    }

    #[getter]
    fn lower_bound(&self) -> f64 {
        self.inner.lower_bound
    }

    #[getter]
    fn gap(&self) -> f64 {
        self.inner.gap
    }

    #[getter]
    fn certificate(&self) -> &'static str {
        self.inner.certificate.as_str()
    }

    #[getter]
    fn certificate_message(&self) -> String {
        self.inner.certificate.message()
    }

    #[getter]
    fn ambiguous(&self) -> bool {
        self.inner.ambiguous
    }

    #[getter]
    #[allow(non_snake_case)]
    fn second_best_R<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray2<f64>>> {
        self.inner.second_best.as_ref().map(|((r, _), _)| matrix3_to_py(py, r))
    }

    #[getter]
    fn second_best_t<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<f64>>> {
        self.inner
            .second_best
            .as_ref()
            .map(|((_, t), _)| vector_to_py(py, t))
    }

    #[getter]
    fn second_best_cost(&self) -> Option<f64> {
        self.inner.second_best.as_ref().map(|(_, c)| *c)
    }

    #[getter]
    fn behind_camera_cost(&self) -> Option<f64> {
        self.inner.behind_camera_cost
    }

    #[getter]
    fn residual_test<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        self.inner.residual_test.as_ref().map(|t| residual_test_dict(py, t)).transpose()
    }

    /// Plain-Python (JSON-serialisable) form.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let r = &self.inner;
        let d = PyDict::new(py);
        d.set_item("R", matrix3_rows(&r.rotation))?;
        d.set_item("t", r.translation.as_slice())?;
        d.set_item("dual_quaternion", self.dual_quaternion_values())?;
        d.set_item("axis", r.axis.as_slice())?;
        d.set_item("angle", r.angle)?;
        d.set_item("method", r.method.as_str())?;
        d.set_item("iterations", r.iterations)?;
        d.set_item("final_cost", r.final_cost)?;
        d.set_item("termination", r.termination.as_str())?;
        d.set_item("status", r.status.as_str())?;
        d.set_item("success", r.status == Status::Success)?;
        d.set_item("rms_error_px", r.rms_error_px)?;
        d.set_item("time_seconds", r.time_seconds)?;
        let stages = self
            .stages()
            .iter()
            .map(|s| s.to_dict(py))
            .collect::<PyResult<Vec<_>>>()?;
        d.set_item("stages", stages)?;
        match &r.estimated_camera {
            Some(c) => d.set_item("estimated_camera", camera_dict(py, c)?)?,
            None => d.set_item("estimated_camera", py.None())?,
        }
        d.set_item("inliers_points", &r.inliers_points)?;
        d.set_item("inliers_lines", &r.inliers_lines)?;
        d.set_item("ransac_iterations", self.ransac_iterations())?;
        d.set_item("ransac_models_scored", self.ransac_models_scored())?;
        d.set_item("ransac_local_optimizations", self.ransac_local_optimizations())?;
        d.set_item("ransac_degenerate_samples", self.ransac_degenerate_samples())?;
        d.set_item("ransac_sprt_rejections", self.ransac_sprt_rejections())?;
        d.set_item("ransac_errors_evaluated", self.ransac_errors_evaluated())?;
        d.set_item("ransac_required_inliers", self.ransac_required_inliers())?;
        d.set_item("ransac_time_seconds", self.ransac_time_seconds())?;
        d.set_item("ransac_stop", self.ransac_stop())?;
        d.set_item("covariance", self.covariance_rows())?;
        d.set_item("covariance_source", self.covariance_source())?;
        d.set_item("sigma_px", r.sigma_px)?;
        d.set_item("certified", r.certified)?;
        d.set_item("lower_bound", r.lower_bound)?;
        d.set_item("gap", r.gap)?;
        d.set_item("certificate", self.certificate())?;
        d.set_item("certificate_message", self.certificate_message())?;
        d.set_item("ambiguous", r.ambiguous)?;
        match &r.second_best {
            Some(((rot, t), c)) => {
                d.set_item("second_best_R", matrix3_rows(rot))?;
                d.set_item("second_best_t", t.as_slice())?;
                d.set_item("second_best_cost", *c)?;
            }
            None => {
                d.set_item("second_best_R", py.None())?;
                d.set_item("second_best_t", py.None())?;
                d.set_item("second_best_cost", py.None())?;
            }
        }
        d.set_item("behind_camera_cost", r.behind_camera_cost)?;
        d.set_item("residual_test", self.residual_test(py)?)?;
        strict_json_dict(d)
    }

    /// Pickle support (also `copy.deepcopy`): see `pickle.rs`.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        reduce(py, "PoseResult", &[self])
    }

    fn __repr__(&self) -> String {
        let r = &self.inner;
        let t: &Vector3<f64> = &r.translation;
        let q: &Vector4<f64> = &r.dual_quaternion.r;
        format!(
            "PoseResult(method='{}', status='{}', iterations={}, rms_error_px={:.3e}, angle={:.6}, t=[{:.6}, {:.6}, {:.6}], r=[{:.6}, {:.6}, {:.6}, {:.6}])",
            r.method.as_str(),
            r.status.as_str(),
            r.iterations,
            r.rms_error_px,
            r.angle,
            t.x,
            t.y,
            t.z,
            q[0],
            q[1],
            q[2],
            q[3]
        )
    }
}

pack_struct!(PyPoseStage { inner });
pack_struct!(PyPoseResult { inner });

/// `{"chi2", "dof", "p_value", "consistent"}` of a χ² test of the residuals.
pub(crate) fn residual_test_dict<'py>(py: Python<'py>, t: &ResidualTest) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("chi2", t.chi2)?;
    d.set_item("dof", t.dof)?;
    d.set_item("p_value", t.p_value)?;
    d.set_item("consistent", t.consistent)?;
    Ok(d)
}
