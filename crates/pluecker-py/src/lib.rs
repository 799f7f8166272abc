//! Python bindings of [`pluecker`]: the extension module `pluecker._core`.
//!
//! This crate holds no geometry. It converts numpy arrays to nalgebra and back ([`convert`]), maps
//! the core's errors to Python exceptions in one place ([`errors`]), releases the GIL around every
//! solve, and turns any Rust panic into a Python exception. The Python package `pluecker`
//! (python/pluecker/__init__.py) re-exports everything defined here; `_core.pyi` documents it.

mod camera;
mod convert;
mod errors;
mod geometry;
mod interrupt;
mod pickle;
mod pose;
mod reprojection;
mod result;
mod synthetic;
mod triangulation;
mod triangulation_arrays;
mod triangulation_batch;
mod triangulation_batch_lines;
mod triangulation_batch_report;
mod triangulation_fitting;
mod triangulation_line;
mod triangulation_point;
mod triangulation_quadric;

use pyo3::prelude::*;

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    let methods: Vec<&str> = pluecker::Method::ALL.iter().map(|m| m.as_str()).collect();
    m.add("METHODS", pyo3::types::PyTuple::new(m.py(), methods)?)?;
    let triangulation: Vec<&str> = pluecker::triangulation::Method::ALL.iter().map(|m| m.as_str()).collect();
    m.add("TRIANGULATION_METHODS", pyo3::types::PyTuple::new(m.py(), triangulation)?)?;
    errors::register(m)?;
    m.add_class::<camera::PyCamera>()?;
    m.add_class::<result::PyPoseResult>()?;
    m.add_class::<result::PyPoseStage>()?;
    m.add_function(wrap_pyfunction!(pose::estimate_pose, m)?)?;
    m.add_function(wrap_pyfunction!(reprojection::pose_covariance, m)?)?;
    m.add_function(wrap_pyfunction!(reprojection::reprojection_errors, m)?)?;
    m.add_function(wrap_pyfunction!(geometry::pose_to_dual_quaternion, m)?)?;
    m.add_function(wrap_pyfunction!(geometry::dual_quaternion_to_pose, m)?)?;
    m.add_function(wrap_pyfunction!(geometry::pose_to_screw, m)?)?;
    m.add_function(wrap_pyfunction!(synthetic::paper_scene, m)?)?;
    m.add_function(wrap_pyfunction!(synthetic::random_scene, m)?)?;
    m.add_class::<triangulation::PyTriangulationReport>()?;
    m.add_class::<triangulation_point::PyPointTriangulation>()?;
    m.add_function(wrap_pyfunction!(triangulation_point::triangulate_point, m)?)?;
    m.add_class::<triangulation_batch_report::PyBatchReport>()?;
    m.add_class::<triangulation_batch::PyPointTriangulations>()?;
    m.add_function(wrap_pyfunction!(triangulation_batch::triangulate_points, m)?)?;
    m.add_class::<triangulation_line::PyLineTriangulation>()?;
    m.add_function(wrap_pyfunction!(triangulation_line::triangulate_line, m)?)?;
    m.add_class::<triangulation_quadric::PyQuadricTriangulation>()?;
    m.add_function(wrap_pyfunction!(triangulation_quadric::triangulate_quadric, m)?)?;
    m.add_class::<triangulation_batch_lines::PyLineTriangulations>()?;
    m.add_class::<triangulation_batch_lines::PyQuadricTriangulations>()?;
    m.add_function(wrap_pyfunction!(triangulation_batch_lines::triangulate_lines, m)?)?;
    m.add_function(wrap_pyfunction!(triangulation_batch_lines::triangulate_quadrics, m)?)?;
    m.add_class::<triangulation_fitting::PyFittedLine>()?;
    m.add_class::<triangulation_fitting::PyFittedConic>()?;
    m.add_function(wrap_pyfunction!(triangulation_fitting::fit_line, m)?)?;
    m.add_function(wrap_pyfunction!(triangulation_fitting::fit_conic, m)?)?;
    m.add_function(wrap_pyfunction!(triangulation_fitting::fitting_residual_samples, m)?)?;
    m.add_function(wrap_pyfunction!(pickle::_unpickle, m)?)?;
    m.add_function(wrap_pyfunction!(_panic_for_tests, m)?)?;
    Ok(())
}

/// Panics inside the guarded, GIL-released section every solve uses: the tests check that this
/// arrives as `PlueckerError("internal error: ...")` rather than aborting the interpreter.
#[pyfunction]
fn _panic_for_tests(py: Python<'_>, message: String) -> PyResult<()> {
    errors::solve(py, move || -> Result<(), pluecker::Error> { panic!("{message}") })
}
