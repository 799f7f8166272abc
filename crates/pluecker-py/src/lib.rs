//! Python bindings of [`pluecker`]: the extension module `pluecker._core`.
//!
//! This crate holds no geometry. Its layout mirrors the core's: `pose` and `triangulation`, one
//! module per primitive inside the latter. Around them: numpy arrays to nalgebra and back in one
//! reader (`convert`), the core's errors as Python exceptions (`errors`), every property of a
//! result or options class declared once (`fields`), pickling (`pickle`) and calls that Ctrl-C
//! can stop (`interrupt`). Every solve runs with the GIL released, and a Rust panic becomes a
//! Python exception. The Python package `pluecker` (python/pluecker/__init__.py) re-exports
//! everything defined here; `_core.pyi` types it.

// `!(x > 0.0)` is true for NaN: the NaN guard used throughout (a NaN input or bound must take the
// failing branch), which the comparison's partial_cmp spelling would hide.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

mod camera;
mod certificate;
mod convert;
mod errors;
#[cfg(unix)]
mod exit_deadline;
mod interrupt;
mod nested;
mod optim;
mod pickle;
mod pose;
mod properties;
mod rig;
mod setup_poll;
mod synthetic;
mod test_hook;
mod threads;
mod triangulation;
mod view;

use pickle::{payload, plain, subclass};
use pose::options::{PyPoseOptions, PyRansacOptions};
use pose::result::{PyPose, PyPoseDetails, PyPoseResult, PyPoseStage, PyRansacReport};
use pyo3::prelude::*;
use triangulation::batch::PyBatchReport;
use triangulation::fitting::{PyFittedConic, PyFittedLine};
use triangulation::line::{PyLineTriangulation, PyLineTriangulations};
use triangulation::point::{PyPointTriangulation, PyPointTriangulations};
use triangulation::quadric::{PyQuadricTriangulation, PyQuadricTriangulations};
use triangulation::report::PyTriangulationReport;
use triangulation::PyTriangulationOptions;

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    let methods: Vec<&str> = pluecker::pose::Method::ALL.iter().map(|m| m.as_str()).collect();
    m.add("METHODS", pyo3::types::PyTuple::new(m.py(), methods)?)?;
    let triangulation: Vec<&str> = pluecker::triangulation::Method::ALL
        .iter()
        .map(|m| m.as_str())
        .collect();
    m.add(
        "TRIANGULATION_METHODS",
        pyo3::types::PyTuple::new(m.py(), triangulation)?,
    )?;
    // Every status an estimate can have, in the core's order: `pluecker.Status` is built from it.
    let statuses: Vec<&str> = <pluecker::Status as strum::VariantArray>::VARIANTS
        .iter()
        .map(|s| s.as_str())
        .collect();
    m.add("STATUSES", pyo3::types::PyTuple::new(m.py(), statuses)?)?;
    errors::register(m)?;
    m.add_class::<camera::PyCamera>()?;
    m.add_class::<view::PyView>()?;
    m.add_class::<rig::PyRig>()?;
    m.add_class::<certificate::PyCertifyOptions>()?;
    m.add_class::<certificate::PyCertificate>()?;
    // Pose.
    m.add_class::<PyPoseOptions>()?;
    m.add_class::<PyRansacOptions>()?;
    m.add_class::<optim::PyTrustRegionOptions>()?;
    m.add_class::<optim::PyLevenbergMarquardtOptions>()?;
    m.add_class::<optim::PyStoppingCriteria>()?;
    m.add_class::<PyPose>()?;
    m.add_class::<PyPoseDetails>()?;
    m.add_class::<PyPoseResult>()?;
    m.add_class::<PyPoseStage>()?;
    m.add_class::<PyRansacReport>()?;
    m.add_function(wrap_pyfunction!(pose::estimate_pose, m)?)?;
    m.add_function(wrap_pyfunction!(pose::minimal::p3p, m)?)?;
    m.add_function(wrap_pyfunction!(pose::minimal::gp3p, m)?)?;
    m.add_function(wrap_pyfunction!(pose::minimal::p2p1l, m)?)?;
    m.add_function(wrap_pyfunction!(pose::minimal::p1p2l, m)?)?;
    m.add_function(wrap_pyfunction!(pose::minimal::p3l, m)?)?;
    m.add_function(wrap_pyfunction!(pose::minimal::refine_pose, m)?)?;
    m.add_function(wrap_pyfunction!(pose::reprojection::pose_covariance, m)?)?;
    m.add_function(wrap_pyfunction!(pose::reprojection::reprojection_errors, m)?)?;
    m.add_function(wrap_pyfunction!(pose::geometry::pose_to_dual_quaternion, m)?)?;
    m.add_function(wrap_pyfunction!(pose::geometry::dual_quaternion_to_pose, m)?)?;
    m.add_function(wrap_pyfunction!(pose::geometry::pose_to_screw, m)?)?;
    m.add_function(wrap_pyfunction!(synthetic::paper_scene, m)?)?;
    m.add_function(wrap_pyfunction!(threads::set_num_threads, m)?)?;
    m.add_function(wrap_pyfunction!(threads::get_num_threads, m)?)?;
    m.add_function(wrap_pyfunction!(synthetic::random_scene, m)?)?;
    // Triangulation.
    m.add_class::<PyTriangulationOptions>()?;
    m.add_class::<PyTriangulationReport>()?;
    m.add_class::<PyBatchReport>()?;
    m.add_class::<PyPointTriangulation>()?;
    m.add_class::<PyPointTriangulations>()?;
    m.add_function(wrap_pyfunction!(triangulation::point::triangulate_point, m)?)?;
    m.add_function(wrap_pyfunction!(triangulation::point::triangulate_points, m)?)?;
    m.add_class::<PyLineTriangulation>()?;
    m.add_class::<PyLineTriangulations>()?;
    m.add_function(wrap_pyfunction!(triangulation::line::triangulate_line, m)?)?;
    m.add_function(wrap_pyfunction!(triangulation::line::triangulate_lines, m)?)?;
    m.add_class::<PyQuadricTriangulation>()?;
    m.add_class::<PyQuadricTriangulations>()?;
    m.add_function(wrap_pyfunction!(triangulation::quadric::triangulate_quadric, m)?)?;
    m.add_function(wrap_pyfunction!(triangulation::quadric::triangulate_quadrics, m)?)?;
    m.add_class::<PyFittedLine>()?;
    m.add_class::<PyFittedConic>()?;
    m.add_function(wrap_pyfunction!(triangulation::fitting::fit_line, m)?)?;
    m.add_function(wrap_pyfunction!(triangulation::fitting::fit_conic, m)?)?;
    m.add_function(wrap_pyfunction!(triangulation::fitting::lines_from_endpoints, m)?)?;
    m.add_function(wrap_pyfunction!(triangulation::fitting::fitting_residual_samples, m)?)?;
    m.add_function(wrap_pyfunction!(_unpickle, m)?)?;
    // The test hooks: only in a build with the feature `test-hooks` (`make develop`), never in the wheel.
    #[cfg(feature = "test-hooks")]
    {
        m.add_function(wrap_pyfunction!(_panic_for_tests, m)?)?;
        m.add_function(wrap_pyfunction!(pose::certificate::_pose_rotation_search, m)?)?;
        m.add_function(wrap_pyfunction!(test_hook::_on_poll_for_tests, m)?)?;
        m.add_function(wrap_pyfunction!(test_hook::_setup_polls_for_tests, m)?)?;
        #[cfg(unix)]
        m.add_function(wrap_pyfunction!(exit_deadline::_hold_gil_for_tests, m)?)?;
    }
    #[cfg(unix)]
    m.add_class::<exit_deadline::ExitDeadline>()?;
    Ok(())
}

/// Rebuilds a result pickled by its `__reduce__` (`pickle::reduce`).
#[pyfunction]
fn _unpickle(py: Python<'_>, kind: &str, data: &[u8]) -> PyResult<PyObject> {
    let input = payload(kind, data)?;
    match kind {
        "PoseResult" => plain::<PyPoseResult>(py, kind, input),
        "Pose" => plain::<PyPose>(py, kind, input),
        "PoseDetails" => plain::<PyPoseDetails>(py, kind, input),
        "PoseStage" => plain::<PyPoseStage>(py, kind, input),
        "RansacReport" => plain::<PyRansacReport>(py, kind, input),
        "FittedLine" => plain::<PyFittedLine>(py, kind, input),
        "FittedConic" => plain::<PyFittedConic>(py, kind, input),
        "TriangulationReport" => plain::<PyTriangulationReport>(py, kind, input),
        "Certificate" => plain::<certificate::PyCertificate>(py, kind, input),
        "Rig" => plain::<rig::PyRig>(py, kind, input),
        "PointTriangulation" => subclass!(py, kind, input, PyTriangulationReport, PyPointTriangulation),
        "LineTriangulation" => subclass!(py, kind, input, PyTriangulationReport, PyLineTriangulation),
        "QuadricTriangulation" => subclass!(py, kind, input, PyTriangulationReport, PyQuadricTriangulation),
        "BatchReport" => plain::<PyBatchReport>(py, kind, input),
        "PointTriangulations" => subclass!(py, kind, input, PyBatchReport, PyPointTriangulations),
        "LineTriangulations" => subclass!(py, kind, input, PyBatchReport, PyLineTriangulations),
        "QuadricTriangulations" => subclass!(py, kind, input, PyBatchReport, PyQuadricTriangulations),
        _ => Err(errors::PlueckerError::new_err(format!(
            "cannot unpickle a {kind}: not a pluecker result class"
        ))),
    }
}

/// Panics inside the guarded, GIL-released section every solve uses: the tests check that this
/// arrives as `PlueckerError("internal error: ...")` rather than aborting the interpreter.
#[cfg(feature = "test-hooks")]
#[pyfunction]
fn _panic_for_tests(py: Python<'_>, message: String) -> PyResult<()> {
    threads::solve(py, move || -> Result<(), pluecker::Error> { panic!("{message}") })
}
