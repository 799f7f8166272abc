//! `pluecker.LensCamera`: a camera of one of COLMAP's models, with lens distortion
//! (`pluecker::camera`): projection, and unprojection exact to 1e-10 px.

use crate::convert::{points, points_to_py, Real};
use crate::errors::{degenerate, guarded, shape_error};
use crate::properties::result_class;
use nalgebra::{Matrix2, Vector2, Vector3};
use numpy::ndarray::Array3;
use numpy::PyArray2;
use numpy::{IntoPyArray, PyArray3};
use pluecker::camera::{CameraModel, LensCamera};
use pluecker::testing::number;
use pyo3::prelude::*;
use pyo3::types::PyTuple;

/// A camera of one of COLMAP's models (`LensCamera.MODELS`), with COLMAP's parameter order. Immutable,
/// `==`, picklable.
#[pyclass(frozen, eq, name = "LensCamera", module = "pluecker")]
#[derive(Debug, Clone, PartialEq)]
pub struct PyLensCamera {
    pub inner: LensCamera,
}

result_class! {
    PyLensCamera {
        /// COLMAP's name of the model, e.g. `'OPENCV'`.
        model = |c| c.inner.model().as_str();
        /// The parameters in COLMAP's order (see `parameter_names`).
        params = |c| c.inner.params().to_vec();
        /// The names of `params`, e.g. `['fx', 'fy', 'cx', 'cy', 'k1', 'k2', 'p1', 'p2']`.
        parameter_names = |c| c.inner.model().parameter_names().iter().map(|s| s.to_string()).collect::<Vec<String>>();
    }

    #[new]
    fn new(model: &str, params: Vec<Real>) -> PyResult<Self> {
        let model = CameraModel::parse(model).map_err(crate::errors::to_py_err)?;
        let values = params.iter().enumerate().map(|(i, p)| p.get(&format!("params[{i}]"))).collect::<PyResult<Vec<_>>>()?;
        guarded(|| LensCamera::new(model, &values)).map(|inner| PyLensCamera { inner })
    }

    /// Every model name, in COLMAP's order of model ids.
    #[classattr]
    #[allow(non_snake_case)]
    fn MODELS() -> Vec<&'static str> {
        CameraModel::ALL.iter().map(|m| m.as_str()).collect()
    }

    /// Pixels (N, 2) of camera-frame points (N, 3) in front of the camera (`z > 0`).
    fn project<'py>(&self, py: Python<'py>, points_cam: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let xs = points::<3>("points_cam", Some(points_cam))?;
        let us: Vec<Vector2<f64>> = xs.iter().map(|x| self.inner.project(x).0).collect();
        Ok(points_to_py(py, &us))
    }

    /// Undistorted normalised coordinates (N, 2), `(x/z, y/z)` of the ray, of pixels (N, 2): the inverse
    /// of `project` to 1e-10 px. `DegenerateConfigurationError` naming the pixel outside the invertible
    /// region of the distortion.
    fn unproject<'py>(&self, py: Python<'py>, pixels: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let us = points::<2>("pixels", Some(pixels))?;
        let cam = &self.inner;
        let ns = guarded(|| us.iter().enumerate().map(|(i, u)| cam.unproject(u, i)).collect::<pluecker::Result<Vec<_>>>())?;
        Ok(points_to_py(py, &ns))
    }

    /// Unit rays (N, 3), camera frame, of pixels (N, 2): the bearings of the minimal solvers.
    fn bearings<'py>(&self, py: Python<'py>, pixels: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let us = points::<2>("pixels", Some(pixels))?;
        let cam = &self.inner;
        let rays = guarded(|| {
            us.iter()
                .enumerate()
                .map(|(i, u)| cam.unproject(u, i).map(|n| Vector3::new(n.x, n.y, 1.0).normalize()))
                .collect::<pluecker::Result<Vec<_>>>()
        })?;
        Ok(points_to_py(py, &rays))
    }

    /// The (N, 2, 2) covariances of the undistorted normalised coordinates of pixels (N, 2) whose pixel
    /// covariances are `covariances` (N, 2, 2) (`None`: 1 px² isotropic): first order, `J⁻¹ Σ J⁻ᵀ`
    /// with `J` the Jacobian of the projection at the unprojected point.
    /// A `covariances[k]` that is not symmetric positive semidefinite is a `DegenerateConfigurationError` naming it.
    #[pyo3(signature = (pixels, covariances = None))]
    fn normalized_covariances<'py>(
        &self,
        py: Python<'py>,
        pixels: &Bound<'py, PyAny>,
        covariances: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArray3<f64>>> {
        let us = points::<2>("pixels", Some(pixels))?;
        let covs = pixel_covariances(covariances, us.len())?;
        let cam = &self.inner;
        let out = guarded(|| {
            us.iter()
                .zip(&covs)
                .enumerate()
                .map(|(i, (u, c))| {
                    let n = cam.unproject(u, i)?;
                    cam.normalized_covariance(&n, c).ok_or_else(|| pluecker::Error::Degenerate {
                        what: format!("pixel {i}: the projection's Jacobian is singular there"),
                    })
                })
                .collect::<pluecker::Result<Vec<_>>>()
        })?;
        Ok(Array3::from_shape_fn((out.len(), 2, 2), |(i, j, k)| out[i][(j, k)]).into_pyarray(py))
    }

    /// The pinhole part `K = [fx 0 cx; 0 fy cy; 0 0 1]` as a `Camera`: the camera of undistorted pixels.
    #[getter]
    fn pinhole(&self) -> PyResult<crate::camera::PyCamera> {
        guarded(|| self.inner.pinhole()).map(|inner| crate::camera::PyCamera { inner })
    }

    /// Undistorted pixels (N, 2) of pixels (N, 2) (the image of the pinhole part, exact to 1e-10 px) and
    /// their covariances (N, 2, 2) for pixel covariances `covariances` (N, 2, 2) (`None`: 1 px²
    /// isotropic), to first order `J⁻¹ Σ J⁻ᵀ` with `J = ∂u/∂ū`: the input of `triangulate_*` with
    /// `projections = pinhole.P(R, t)`.
    /// A `covariances[k]` that is not symmetric positive semidefinite is a `DegenerateConfigurationError` naming it.
    #[pyo3(signature = (pixels, covariances = None))]
    fn undistort<'py>(
        &self,
        py: Python<'py>,
        pixels: &Bound<'py, PyAny>,
        covariances: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Undistorted<'py>> {
        let us = points::<2>("pixels", Some(pixels))?;
        let covs = pixel_covariances(covariances, us.len())?;
        let cam = &self.inner;
        let out = guarded(|| {
            us.iter()
                .zip(&covs)
                .enumerate()
                .map(|(i, (u, c))| {
                    let (ubar, j) = cam.undistort(u, i)?;
                    let j_inv = j.try_inverse().ok_or_else(|| pluecker::Error::Degenerate {
                        what: format!("pixel {i}: the distortion is singular there"),
                    })?;
                    Ok((ubar, j_inv * c * j_inv.transpose()))
                })
                .collect::<pluecker::Result<Vec<_>>>()
        })?;
        let ubar: Vec<Vector2<f64>> = out.iter().map(|o| o.0).collect();
        let c = Array3::from_shape_fn((out.len(), 2, 2), |(i, j, k)| out[i].1[(j, k)]);
        Ok((points_to_py(py, &ubar), c.into_pyarray(py)))
    }

    fn __repr__(&self) -> String {
        format!("LensCamera('{}', {:?})", self.inner.model().as_str(), self.inner.params())
    }

    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        let c = &slf.get().inner;
        let args = PyTuple::new(slf.py(), [c.model().as_str().into_pyobject(slf.py())?.into_any(), c.params().to_vec().into_pyobject(slf.py())?.into_any()])?;
        Ok((slf.get_type().into_any(), args))
    }
}

/// `LensCamera.undistort`'s answer: undistorted pixels (N, 2) and their covariances (N, 2, 2).
type Undistorted<'py> = (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray3<f64>>);

/// The `covariances=` argument of the pixel methods: (N, 2, 2), or the identity (1 px²) for each of
/// `n` pixels.
fn pixel_covariances(covariances: Option<&Bound<'_, PyAny>>, n: usize) -> PyResult<Vec<Matrix2<f64>>> {
    use crate::convert::{check_finite, matrices, read, shape_string, Dim};
    let Some(c) = covariances else {
        return Ok(vec![Matrix2::identity(); n]);
    };
    let (shape, values) = read("covariances", c, &[Dim::Free("N"), Dim::Fixed(2), Dim::Fixed(2)])?;
    check_finite("covariances", &values, 4)?;
    if shape[0] != n {
        return Err(shape_error(
            "covariances",
            &format!("shape ({n}, 2, 2) (one per pixel)"),
            shape_string(&shape),
        ));
    }
    let covs = matrices::<2, 2>(&values);
    if let Some(k) = covs.iter().position(|c| !symmetric_psd(c)) {
        return Err(degenerate(format!(
            "covariances[{k}] is not a covariance (symmetric positive semidefinite): [[{}, {}], [{}, {}]]",
            number(values[4 * k]),
            number(values[4 * k + 1]),
            number(values[4 * k + 2]),
            number(values[4 * k + 3])
        )));
    }
    Ok(covs)
}

/// Whether `c` is symmetric and positive semidefinite, to the rounding of its entries (relative
/// 1e-12 of its largest entry): the only matrices a covariance can be.
fn symmetric_psd(c: &Matrix2<f64>) -> bool {
    let tolerance = 1e-12 * c.amax();
    let (a, b, d) = (c[(0, 0)], 0.5 * (c[(0, 1)] + c[(1, 0)]), c[(1, 1)]);
    (c[(0, 1)] - c[(1, 0)]).abs() <= tolerance
        && a >= -tolerance
        && d >= -tolerance
        && a * d - b * b >= -tolerance * c.amax()
}
