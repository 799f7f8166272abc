//! `pluecker.Camera`: pinhole intrinsics, projection and normalisation.

use crate::convert::pose_from_parts;
use crate::convert::{matrix3_allow_non_finite, points, points_to_py, Real};
use crate::errors::guarded;
use crate::properties::{result_class, Field};
use nalgebra::{Vector2, Vector3};
use numpy::PyArray2;
use pyo3::prelude::*;
use pyo3::types::PyTuple;
use std::collections::hash_map::DefaultHasher;
use std::hash::{Hash, Hasher};

/// Pinhole intrinsics in pixels, `K = [[fx, skew, cx], [0, fy, cy], [0, 0, 1]]`. Immutable.
#[pyclass(frozen, eq, name = "Camera", module = "pluecker")]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PyCamera {
    pub inner: pluecker::Camera,
}

impl PyCamera {
    pub fn wrap(inner: pluecker::Camera) -> Self {
        PyCamera { inner }
    }
}

result_class! {
    PyCamera {
        /// Focal length along u, pixels (negative for a mirrored axis).
        fx = |c| c.inner.fx;
        /// Focal length along v, pixels (negative for a mirrored axis).
        fy = |c| c.inner.fy;
        /// Principal point u, pixels.
        cx = |c| c.inner.cx;
        /// Principal point v, pixels.
        cy = |c| c.inner.cy;
        /// Skew, pixels.
        skew = |c| c.inner.skew;
        /// The calibration matrix `K = [[fx, skew, cx], [0, fy, cy], [0, 0, 1]]`.
        K = |c| c.inner.matrix();
    }

    #[new]
    #[pyo3(signature = (fx, fy, cx, cy, skew = None))]
    fn new(fx: Real, fy: Real, cx: Real, cy: Real, skew: Option<Real>) -> PyResult<Self> {
        let (fx, fy, cx, cy) = (fx.get("fx")?, fy.get("fy")?, cx.get("cx")?, cy.get("cy")?);
        // No skew unless given: the pixel axes of every camera made in the last decades are orthogonal.
        let skew = skew.map_or(Ok(0.0), |s| s.get("skew"))?;
        guarded(|| pluecker::Camera::new(fx, fy, cx, cy, skew)).map(PyCamera::wrap)
    }

    /// From a (3, 3) calibration matrix.
    #[staticmethod]
    #[pyo3(name = "from_matrix", signature = (K))]
    #[allow(non_snake_case)]
    fn from_matrix(K: &Bound<'_, PyAny>) -> PyResult<Self> {
        // Non-finite entries are the core's to report, as a singular camera.
        let k = matrix3_allow_non_finite("K", K)?;
        guarded(|| pluecker::Camera::from_matrix(&k)).map(PyCamera::wrap)
    }

    /// The 3x4 camera matrix `P = K [R | t]` of this camera at the pose `x_cam = R X_world + t`:
    /// what the triangulation functions take as known cameras (`λ (u, v, 1) = P (X, 1)`).
    #[pyo3(signature = (R, t))]
    #[allow(non_snake_case)]
    fn P<'py>(&self, py: Python<'py>, R: &Bound<'py, PyAny>, t: &Bound<'py, PyAny>) -> PyResult<PyObject> {
        self.inner.projection(&pose_from_parts("R", R, "t", t)?).get(py)
    }

    /// Unit rays (N, 3), camera frame, of pixels (N, 2): `K⁻¹ (u, v, 1)` normalised; the bearings of the
    /// minimal solvers (`p3p`, ...).
    fn bearings<'py>(&self, py: Python<'py>, pixels: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let us = points::<2>("pixels", Some(pixels))?;
        let cam = self.inner;
        let rays: Vec<Vector3<f64>> = guarded(|| {
            Ok(us.iter().map(|u| { let x = cam.pixel_to_normalized(u); Vector3::new(x.x, x.y, 1.0).normalize() }).collect())
        })?;
        Ok(points_to_py(py, &rays))
    }

    /// Unit normals (M, 3), camera frame, of the interpretation planes (through the optical centre and
    /// the image segment) of segments (M, 2, 2) in pixels: the line data of the minimal solvers.
    /// `DegenerateConfigurationError` naming the row for a zero-length segment.
    fn plane_normals<'py>(&self, py: Python<'py>, segments: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let segs = crate::convert::segments::<2>("segments", Some(segments))?;
        let cam = self.inner;
        let normals = guarded(|| {
            segs.iter()
                .enumerate()
                .map(|(i, [a, b])| {
                    cam.interpretation_plane_normal(a, b).map_err(|_| pluecker::Error::Degenerate {
                        what: format!("segments[{i}]: zero-length image segment"),
                    })
                })
                .collect::<pluecker::Result<Vec<_>>>()
        })?;
        Ok(points_to_py(py, &normals))
    }

    /// Pixels `u = K x_cam / z` of camera-frame points (N, 3).
    fn project<'py>(&self, py: Python<'py>, points_cam: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let xs = points::<3>("points_cam", Some(points_cam))?;
        let cam = self.inner;
        let us: Vec<Vector2<f64>> = guarded(|| Ok(xs.iter().map(|x: &Vector3<f64>| cam.project(x)).collect()))?;
        Ok(points_to_py(py, &us))
    }

    /// Normalised coordinates `(x, y)` with `(x, y, 1) ∝ K⁻¹ (u, v, 1)` of pixels (N, 2).
    fn pixel_to_normalized<'py>(
        &self,
        py: Python<'py>,
        pixels: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let us = points::<2>("pixels", Some(pixels))?;
        let cam = self.inner;
        let xs: Vec<Vector2<f64>> = guarded(|| Ok(us.iter().map(|u| cam.pixel_to_normalized(u)).collect()))?;
        Ok(points_to_py(py, &xs))
    }

    /// Pixels of normalised coordinates (N, 2).
    fn normalized_to_pixel<'py>(
        &self,
        py: Python<'py>,
        normalized: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let xs = points::<2>("normalized", Some(normalized))?;
        let cam = self.inner;
        let us: Vec<Vector2<f64>> = guarded(|| Ok(xs.iter().map(|x| cam.normalized_to_pixel(x)).collect()))?;
        Ok(points_to_py(py, &us))
    }

    fn __repr__(&self) -> String {
        let c = &self.inner;
        format!(
            "Camera(fx={:?}, fy={:?}, cx={:?}, cy={:?}, skew={:?})",
            c.fx, c.fy, c.cx, c.cy, c.skew
        )
    }

    fn __hash__(&self) -> u64 {
        let c = &self.inner;
        let mut h = DefaultHasher::new();
        // `+ 0.0` maps -0.0 to 0.0, so that equal cameras hash equally.
        for v in [c.fx, c.fy, c.cx, c.cy, c.skew] {
            (v + 0.0).to_bits().hash(&mut h);
        }
        h.finish()
    }

    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        let c = slf.get().inner;
        let args = PyTuple::new(slf.py(), [c.fx, c.fy, c.cx, c.cy, c.skew])?;
        Ok((slf.get_type().into_any(), args))
    }
}
