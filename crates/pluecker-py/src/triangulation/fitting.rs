//! `fit_line`, `fit_conic` and `fitting_residual_samples`: image primitives fitted to edge points with
//! the covariance of their residual (Josephson & Kahl 2008, section 3.1), the weights `triangulate_line`
//! and `triangulate_quadric` take.

use crate::convert::{points as read_points, points_to_py, Integer, Real};
use crate::errors::{guarded, invalid_argument};
use crate::pickle::reduce;
use crate::properties::result_class;
use crate::threads::solve;
use pluecker::testing::number;
use pluecker::triangulation::fitting::{self, FittedConic, FittedLine, DEFAULT_SIGMA_PX, PAPER_IMAGE_SIZE};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

/// The `sigma` argument in pixels (`None`: the core's default), checked.
fn sigma_arg(sigma: Option<Real>) -> PyResult<f64> {
    super::positive_sigma(sigma.map_or(Ok(DEFAULT_SIGMA_PX), |s| s.get("sigma"))?)
}

/// An image line fitted to points, with the covariance of its 2-entry residual.
#[pyclass(frozen, name = "FittedLine", module = "pluecker")]
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
#[serde(transparent)]
pub struct PyFittedLine {
    inner: FittedLine,
}

result_class! {
    PyFittedLine {
        /// The image line `(a, b, c)`, `a u + b v + c = 0`, with `a² + b² = 1`.
        line = |f| f.inner.line;
        /// 2x2 covariance of the line's residual (section 3.1), px².
        covariance = |f| f.inner.covariance;
        /// RMS distance of the points to the line, pixels.
        rms_distance = |f| f.inner.rms_distance;
    }

    /// Pickle support (also `copy.deepcopy`): see `pickle.rs`.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        reduce(py, "FittedLine", self)
    }

    fn __repr__(&self) -> String {
        let l = self.inner.line;
        format!(
            "FittedLine(line=[{:.6}, {:.6}, {:.6}], rms_distance={:.3e})",
            l.x, l.y, l.z, self.inner.rms_distance
        )
    }
}

/// An ellipse fitted to points, with the covariance of its 5-entry residual.
#[pyclass(frozen, name = "FittedConic", module = "pluecker")]
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
#[serde(transparent)]
pub struct PyFittedConic {
    inner: FittedConic,
}

result_class! {
    PyFittedConic {
        /// The conic `C` (3x3, symmetric): `(u, v, 1) C (u, v, 1)ᵀ = 0` on the ellipse.
        conic = |f| f.inner.conic;
        /// Centre of the ellipse, pixels.
        centre = |f| f.inner.ellipse.centre;
        /// Principal axes of the ellipse, one per column.
        axes = |f| f.inner.ellipse.axes;
        /// Semi-axis lengths along `axes`, pixels.
        semi_axes = |f| f.inner.ellipse.semi_axes;
        /// 5x5 covariance of the conic's residual (section 3.1).
        covariance = |f| f.inner.covariance;
        /// Iterations of the geometric fit.
        iterations = |f| f.inner.iterations;
    }

    /// Pickle support (also `copy.deepcopy`): see `pickle.rs`.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        reduce(py, "FittedConic", self)
    }

    fn __repr__(&self) -> String {
        let e = &self.inner.ellipse;
        format!(
            "FittedConic(centre=[{:.3}, {:.3}], semi_axes=[{:.3}, {:.3}], iterations={})",
            e.centre.x, e.centre.y, e.semi_axes.x, e.semi_axes.y, self.inner.iterations
        )
    }
}

/// Fits an image line to points `(N, 2)` (total least squares) and returns it with its residual
/// covariance, for point noise `sigma` pixels (`None`: 1 px).
#[pyfunction]
#[pyo3(signature = (points, sigma = None))]
pub fn fit_line(points: &Bound<'_, PyAny>, sigma: Option<Real>) -> PyResult<PyFittedLine> {
    let pts = read_points::<2>("points", Some(points))?;
    let sigma = sigma_arg(sigma)?;
    guarded(|| fitting::fit_line(&pts, sigma)).map(|inner| PyFittedLine { inner })
}

/// The image lines `(M, 3)` (unit normal, pixels) through segments `(M, 2, 2)` whose two endpoints have
/// the covariances `covariances` `(M, 2, 2, 2)` (pixels²; e.g. from `Camera.undistort`), and the
/// covariances `(M, 2, 2)` of their residuals: the `lines` and `covariances` of `triangulate_line(s)`
/// (core `fitting::line_from_endpoints`).
#[pyfunction]
pub fn lines_from_endpoints<'py>(
    py: Python<'py>,
    segments: &Bound<'py, PyAny>,
    covariances: &Bound<'py, PyAny>,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
    use crate::convert::{check_finite, read, Dim};
    let (shape, ends) = read("segments", segments, &[Dim::Free("M"), Dim::Fixed(2), Dim::Fixed(2)])?;
    let (cshape, covs) = read(
        "covariances",
        covariances,
        &[Dim::Free("M"), Dim::Fixed(2), Dim::Fixed(2), Dim::Fixed(2)],
    )?;
    check_finite("segments", &ends, 4)?;
    check_finite("covariances", &covs, 8)?;
    if cshape[0] != shape[0] {
        return Err(crate::errors::shape_error(
            "covariances",
            &format!("shape ({}, 2, 2, 2) (two endpoints per segment)", shape[0]),
            crate::convert::shape_string(&cshape),
        ));
    }
    let m = |v: &[f64]| nalgebra::Matrix2::new(v[0], v[1], v[2], v[3]);
    let fits = guarded(|| {
        ends.chunks_exact(4)
            .zip(covs.chunks_exact(8))
            .enumerate()
            .map(|(i, (e, c))| {
                let (a, b) = (nalgebra::Vector2::new(e[0], e[1]), nalgebra::Vector2::new(e[2], e[3]));
                fitting::line_from_endpoints(&a, &b, &m(&c[..4]), &m(&c[4..])).map_err(|err| match err {
                    pluecker::Error::Degenerate { what } => pluecker::Error::Degenerate {
                        what: format!("segments[{i}]: {what}"),
                    },
                    other => other,
                })
            })
            .collect::<pluecker::Result<Vec<_>>>()
    })?;
    let lines: Vec<f64> = fits
        .iter()
        .flat_map(|f| f.line.iter().copied().collect::<Vec<_>>())
        .collect();
    let covariances: Vec<f64> = fits
        .iter()
        .flat_map(|f| {
            [
                f.covariance[(0, 0)],
                f.covariance[(0, 1)],
                f.covariance[(1, 0)],
                f.covariance[(1, 1)],
            ]
        })
        .collect();
    use crate::properties::Field;
    let lines = crate::properties::Array::rows(lines, &[3]).get(py)?.into_bound(py);
    let covariances = crate::properties::Array::rows(covariances, &[2, 2])
        .get(py)?
        .into_bound(py);
    Ok((lines, covariances))
}

/// Fits an ellipse to points `(N, 2)` and returns it with its residual covariance, for point noise
/// `sigma` pixels (`None`: 1 px).
#[pyfunction]
#[pyo3(signature = (points, sigma = None))]
pub fn fit_conic(py: Python<'_>, points: &Bound<'_, PyAny>, sigma: Option<Real>) -> PyResult<PyFittedConic> {
    let pts = read_points::<2>("points", Some(points))?;
    let sigma = sigma_arg(sigma)?;
    solve(py, move || fitting::fit_conic(&pts, sigma)).map(|inner| PyFittedConic { inner })
}

/// The residual samples of the paper's Figures 1-2 (section 3.1): `draws` fits to points spread
/// over `size` pixels (`None`: the paper's 1000) with noise `sigma` pixels (`None`: 1 px), seeded by `seed` (`None`: 0).
#[pyfunction]
#[pyo3(signature = (draws, size = None, sigma = None, seed = None))]
pub fn fitting_residual_samples<'py>(
    py: Python<'py>,
    draws: Integer,
    size: Option<Real>,
    sigma: Option<Real>,
    seed: Option<Integer>,
) -> PyResult<Bound<'py, PyDict>> {
    let draws = draws.count("draws", 1)?;
    let seed = seed.map_or(Ok(0), |s| s.seed("seed"))?;
    let size = size.map_or(Ok(PAPER_IMAGE_SIZE), |s| s.get("size"))?;
    if !(size.is_finite() && size > 0.0) {
        return Err(invalid_argument(
            "size",
            format!("must be a positive number of pixels, got {}", number(size)),
        ));
    }
    let sigma = sigma_arg(sigma)?;
    let samples = solve(py, move || fitting::residual_samples(draws, size, sigma, seed))?;
    let d = PyDict::new(py);
    d.set_item("line", points_to_py(py, &samples.line))?;
    d.set_item("line_whitened", points_to_py(py, &samples.line_whitened))?;
    d.set_item("conic", points_to_py(py, &samples.conic))?;
    d.set_item("conic_whitened", points_to_py(py, &samples.conic_whitened))?;
    Ok(d)
}
