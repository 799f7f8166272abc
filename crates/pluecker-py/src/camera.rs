//! `pluecker.Camera`: the one camera class, any of the core's [`CameraModel`]s (COLMAP's, PINHOLE
//! among them, and SKEWED_PINHOLE) with its parameters (`pluecker::camera::Camera`): projection, and
//! unprojection exact to 1e-10 px.

use crate::convert::pose_from_parts;
use crate::convert::{matrix3_allow_non_finite, points, points_to_py, Real};
use crate::errors::{degenerate, guarded, invalid_argument, shape_error};
use crate::properties::{result_class, Field};
use nalgebra::{Matrix2, Vector2, Vector3};
use numpy::ndarray::Array3;
use numpy::{IntoPyArray, PyArray2, PyArray3};
use pluecker::camera::{Camera, CameraModel};
use pluecker::testing::number;
use pyo3::prelude::*;
use pyo3::types::PyTuple;
use std::collections::hash_map::DefaultHasher;
use std::hash::{Hash, Hasher};

/// A camera: one of the models in `Camera.MODELS` (COLMAP's, with PINHOLE one of them, and
/// SKEWED_PINHOLE) with its parameters in COLMAP's order. Its pixels are the observed ones: through a
/// lens with distortion `u = K D(x_cam / z)`, for the pinholes `u = K x_cam / z`. Immutable, `==`,
/// hashable, picklable.
#[pyclass(frozen, eq, name = "Camera", module = "pluecker")]
#[derive(Debug, Clone, PartialEq)]
pub struct PyCamera {
    pub inner: Camera,
}

impl PyCamera {
    pub fn wrap(inner: Camera) -> Self {
        PyCamera { inner }
    }
}

/// The camera of a pycolmap camera (`camera.model` is an enum with `.name` in pycolmap ≥ 0.5, a
/// string before; `camera.params`), or `None` for an object that is not one. The errors of the camera
/// of a model name its `camera_id`.
fn pycolmap_camera(camera: &Bound<'_, PyAny>) -> PyResult<Option<Camera>> {
    let made = pycolmap_parts(camera);
    match camera.getattr("camera_id").and_then(|id| id.extract::<u64>()) {
        Ok(id) => made.map_err(|e| prefixed(camera.py(), e, &format!("camera_id {id}"))),
        Err(_) => made,
    }
}

/// `error` of the same Python type with its message after `prefix: `.
fn prefixed(py: Python<'_>, error: PyErr, prefix: &str) -> PyErr {
    let message = format!("{prefix}: {}", error.value(py));
    match error.get_type(py).call1((message,)) {
        Ok(value) => PyErr::from_value(value),
        Err(other) => other,
    }
}

/// [`pycolmap_camera`] without the `camera_id` in its errors.
fn pycolmap_parts(camera: &Bound<'_, PyAny>) -> PyResult<Option<Camera>> {
    let (Ok(model), Ok(params)) = (camera.getattr("model"), camera.getattr("params")) else {
        return Ok(None);
    };
    let name = match model.getattr("name") {
        Ok(name) => name.extract::<String>()?,
        Err(_) => model.extract::<String>()?,
    };
    let params: Vec<Real> = params
        .extract()
        .map_err(|_| invalid_argument("camera.params", "expected a sequence of numbers"))?;
    model_camera(&name, &params).map(Some)
}

/// The camera of `model` (a name) with `params`, checked by the core.
fn model_camera(model: &str, params: &[Real]) -> PyResult<Camera> {
    let model = CameraModel::parse(model).map_err(crate::errors::to_py_err)?;
    let values = params
        .iter()
        .enumerate()
        .map(|(i, p)| p.get(&format!("params[{i}]")))
        .collect::<PyResult<Vec<_>>>()?;
    guarded(|| Camera::new(model, &values))
}

result_class! {
    PyCamera {
        /// The model's name, e.g. `'PINHOLE'`, `'OPENCV'` (COLMAP's names; `'SKEWED_PINHOLE'` is pluecker's).
        model = |c| c.inner.model().as_str();
        /// The parameters in COLMAP's order (see `parameter_names`).
        params = |c| c.inner.params().to_vec();
        /// The names of `params`, e.g. `['fx', 'fy', 'cx', 'cy', 'k1', 'k2', 'p1', 'p2']`.
        parameter_names = |c| c.inner.model().parameter_names().iter().map(|s| s.to_string()).collect::<Vec<String>>();
        /// Focal length along u, pixels (negative for a mirrored axis).
        fx = |c| c.inner.intrinsics().fx;
        /// Focal length along v, pixels (negative for a mirrored axis).
        fy = |c| c.inner.intrinsics().fy;
        /// Principal point u, pixels.
        cx = |c| c.inner.intrinsics().cx;
        /// Principal point v, pixels.
        cy = |c| c.inner.intrinsics().cy;
        /// Skew, pixels (0 but for SKEWED_PINHOLE).
        skew = |c| c.inner.intrinsics().skew;
        /// The pinhole part `K = [[fx, skew, cx], [0, fy, cy], [0, 0, 1]]` (3, 3).
        K = |c| c.inner.intrinsics().matrix();
    }

    /// `Camera(model, params)`: a camera of `model` (a name of `Camera.MODELS`) with `params` in
    /// COLMAP's order; `Camera(pycolmap_camera)`: the same model and parameters as a `pycolmap.Camera`.
    /// `InvalidOptionError` for an unknown model, `ShapeError` for a wrong number of parameters,
    /// `SingularCameraError` for a zero focal length.
    #[new]
    #[pyo3(signature = (model, params = None))]
    fn new(model: &Bound<'_, PyAny>, params: Option<Vec<Real>>) -> PyResult<Self> {
        let camera = match params {
            Some(params) => {
                let name = model.extract::<String>().map_err(|_| {
                    invalid_argument("model", format!("expected a model name (str), got {}", model.get_type()))
                })?;
                model_camera(&name, &params)?
            }
            None => pycolmap_camera(model)?.ok_or_else(|| {
                invalid_argument("params", "missing: Camera(model, params), or Camera(pycolmap_camera)")
            })?,
        };
        Ok(PyCamera::wrap(camera))
    }

    /// The pinhole camera `K = [[fx, skew, cx], [0, fy, cy], [0, 0, 1]]`: PINHOLE, or SKEWED_PINHOLE
    /// with a skew.
    #[staticmethod]
    #[pyo3(signature = (fx, fy, cx, cy, skew = None))]
    fn pinhole(fx: Real, fy: Real, cx: Real, cy: Real, skew: Option<Real>) -> PyResult<Self> {
        let (fx, fy, cx, cy) = (fx.get("fx")?, fy.get("fy")?, cx.get("cx")?, cy.get("cy")?);
        // No skew unless given: the pixel axes of every camera made in the last decades are orthogonal.
        let skew = skew.map_or(Ok(0.0), |s| s.get("skew"))?;
        guarded(|| Camera::pinhole(fx, fy, cx, cy, skew)).map(PyCamera::wrap)
    }

    /// The pinhole camera of a (3, 3) calibration matrix `K` (upper triangular, last row (0, 0, 1) up to
    /// scale): PINHOLE, or SKEWED_PINHOLE with a skew.
    #[staticmethod]
    #[pyo3(name = "from_matrix", signature = (K))]
    #[allow(non_snake_case)]
    fn from_matrix(K: &Bound<'_, PyAny>) -> PyResult<Self> {
        // Non-finite entries are the core's to report, as a singular camera.
        let k = matrix3_allow_non_finite("K", K)?;
        guarded(|| Camera::from_matrix(&k)).map(PyCamera::wrap)
    }

    /// Every model name: COLMAP's, in the order of their model ids, then SKEWED_PINHOLE.
    #[classattr]
    #[allow(non_snake_case)]
    fn MODELS() -> Vec<&'static str> {
        CameraModel::ALL.iter().map(|m| m.as_str()).collect()
    }

    /// Whether the model distorts (`False` for the pinholes and for distortion parameters that are all
    /// zero).
    #[getter]
    fn distorts(&self) -> bool {
        self.inner.distorts()
    }

    /// The pinhole camera of this camera's `K`: the camera of its undistorted pixels (itself for a
    /// pinhole).
    #[getter]
    fn pinhole_part(&self) -> Self {
        PyCamera::wrap(self.inner.without_distortion())
    }

    /// The 3x4 matrix `P = K [R | t]` of the pinhole part at the pose `x_cam = R X_world + t`: a known
    /// camera of the triangulation functions (`λ (u, v, 1) = P (X, 1)` in undistorted pixels).
    #[pyo3(signature = (R, t))]
    #[allow(non_snake_case)]
    fn P<'py>(&self, py: Python<'py>, R: &Bound<'py, PyAny>, t: &Bound<'py, PyAny>) -> PyResult<PyObject> {
        self.inner.projection(&pose_from_parts("R", R, "t", t)?).get(py)
    }

    /// Pixels (N, 2) of camera-frame points (N, 3) in front of the camera (`z > 0`), through the lens.
    fn project<'py>(&self, py: Python<'py>, points_cam: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let xs = points::<3>("points_cam", Some(points_cam))?;
        let us: Vec<Vector2<f64>> = xs.iter().map(|x| self.inner.project(x)).collect();
        Ok(points_to_py(py, &us))
    }

    /// Undistorted normalised coordinates (N, 2), `(x/z, y/z)` of the ray, of pixels (N, 2): the inverse
    /// of `project` to 1e-10 px (`K⁻¹ (u, v, 1)` for the pinholes). `DegenerateConfigurationError`
    /// naming the pixel outside the invertible region of the distortion.
    fn unproject<'py>(&self, py: Python<'py>, pixels: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let us = points::<2>("pixels", Some(pixels))?;
        let cam = &self.inner;
        let ns = guarded(|| us.iter().enumerate().map(|(i, u)| cam.unproject(u, i)).collect::<pluecker::Result<Vec<_>>>())?;
        Ok(points_to_py(py, &ns))
    }

    /// Unit rays (N, 3), camera frame, of pixels (N, 2): the bearings of the minimal solvers (`p3p`, ...).
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

    /// Unit normals (M, 3), camera frame, of the interpretation planes (through the optical centre and
    /// the 3-D line) of segments (M, 2, 2) in pixels, from their unprojected endpoints: the line data
    /// of the minimal solvers. `DegenerateConfigurationError` naming the row for a zero-length segment.
    fn plane_normals<'py>(&self, py: Python<'py>, segments: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let segs = crate::convert::segments::<2>("segments", Some(segments))?;
        let cam = &self.inner;
        let k = cam.intrinsics();
        let normals = guarded(|| {
            segs.iter()
                .enumerate()
                .map(|(i, [a, b])| {
                    // Through a lens, the plane of the undistorted endpoints (they lie on the 3-D line's image).
                    let (a, b) = if cam.is_pinhole() { (*a, *b) } else { (cam.undistort(a, 2 * i)?.0, cam.undistort(b, 2 * i + 1)?.0) };
                    k.interpretation_plane_normal(&a, &b).map_err(|_| pluecker::Error::Degenerate {
                        what: format!("segments[{i}]: zero-length image segment"),
                    })
                })
                .collect::<pluecker::Result<Vec<_>>>()
        })?;
        Ok(points_to_py(py, &normals))
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
        let cam = &self.inner;
        let out = each_pixel(pixels, covariances, |i, u, c| {
            let n = cam.unproject(u, i)?;
            cam.normalized_covariance(&n, c).ok_or_else(|| pluecker::Error::Degenerate {
                what: format!("pixel {i}: the projection's Jacobian is singular there"),
            })
        })?;
        Ok(Array3::from_shape_fn((out.len(), 2, 2), |(i, j, k)| out[i][(j, k)]).into_pyarray(py))
    }

    /// Undistorted pixels (N, 2) of pixels (N, 2) (the image of the pinhole part, exact to 1e-10 px) and
    /// their covariances (N, 2, 2) for pixel covariances `covariances` (N, 2, 2) (`None`: 1 px²
    /// isotropic), to first order `J⁻¹ Σ J⁻ᵀ` with `J = ∂u/∂ū`: observations of `pinhole_part`.
    /// A `covariances[k]` that is not symmetric positive semidefinite is a `DegenerateConfigurationError` naming it.
    #[pyo3(signature = (pixels, covariances = None))]
    fn undistort<'py>(
        &self,
        py: Python<'py>,
        pixels: &Bound<'py, PyAny>,
        covariances: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Undistorted<'py>> {
        let cam = &self.inner;
        let out = each_pixel(pixels, covariances, |i, u, c| {
            let (ubar, j) = cam.undistort(u, i)?;
            let j_inv = j.try_inverse().ok_or_else(|| pluecker::Error::Degenerate {
                what: format!("pixel {i}: the distortion is singular there"),
            })?;
            Ok((ubar, j_inv * c * j_inv.transpose()))
        })?;
        let ubar: Vec<Vector2<f64>> = out.iter().map(|o| o.0).collect();
        let c = Array3::from_shape_fn((out.len(), 2, 2), |(i, j, k)| out[i].1[(j, k)]);
        Ok((points_to_py(py, &ubar), c.into_pyarray(py)))
    }

    fn __repr__(&self) -> String {
        format!("Camera('{}', {:?})", self.inner.model().as_str(), self.inner.params())
    }

    fn __hash__(&self) -> u64 {
        let mut h = DefaultHasher::new();
        self.inner.model().hash(&mut h);
        // `+ 0.0` maps -0.0 to 0.0, so that equal cameras hash equally.
        for v in self.inner.params() {
            (v + 0.0).to_bits().hash(&mut h);
        }
        h.finish()
    }

    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        let c = &slf.get().inner;
        let args = PyTuple::new(slf.py(), [c.model().as_str().into_pyobject(slf.py())?.into_any(), c.params().to_vec().into_pyobject(slf.py())?.into_any()])?;
        Ok((slf.get_type().into_any(), args))
    }
}

/// `f(i, pixel, covariance)` of every pixel (N, 2) of `pixels` with its `covariances` (N, 2, 2) (`None`:
/// 1 px² isotropic), the first error naming its pixel.
fn each_pixel<T>(
    pixels: &Bound<'_, PyAny>,
    covariances: Option<&Bound<'_, PyAny>>,
    f: impl Fn(usize, &Vector2<f64>, &Matrix2<f64>) -> pluecker::Result<T>,
) -> PyResult<Vec<T>> {
    let us = points::<2>("pixels", Some(pixels))?;
    let covs = pixel_covariances(covariances, us.len())?;
    guarded(|| us.iter().zip(&covs).enumerate().map(|(i, (u, c))| f(i, u, c)).collect())
}

/// `Camera.undistort`'s answer: undistorted pixels (N, 2) and their covariances (N, 2, 2).
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

/// The one coercion of a camera argument `name`: a `pluecker.Camera`, or a `pycolmap.Camera` (any
/// object with `model` and `params`) taken as it is; anything else is a `TypeError` naming `name`
/// (the Python convention for an argument of the wrong type, as for arrays that are not numeric).
pub(crate) fn coerce(name: &str, camera: &Bound<'_, PyAny>) -> PyResult<Camera> {
    if let Ok(c) = camera.downcast::<PyCamera>() {
        return Ok(c.get().inner.clone());
    }
    pycolmap_camera(camera)
        .map_err(|e| prefixed(camera.py(), e, name))?
        .ok_or_else(|| {
            let got = camera.get_type().name().map(|n| n.to_string()).unwrap_or_default();
            pyo3::exceptions::PyTypeError::new_err(format!(
                "{name}: expected a pluecker.Camera or a pycolmap.Camera, got {got}"
            ))
        })
}
