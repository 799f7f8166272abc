//! Faugeras-Toscani linear calibration (placeholder being written).
use crate::camera::Camera;
use crate::error::Result;
use nalgebra::{Matrix3, Vector2, Vector3};

/// Result of the linear calibration.
#[derive(Debug, Clone, PartialEq)]
pub struct LinearCalibration {
    pub camera: Camera,
    pub rotation: Matrix3<f64>,
    pub translation: Vector3<f64>,
}

/// Faugeras-Toscani.
pub fn faugeras_toscani(_points2d: &[Vector2<f64>], _points3d: &[Vector3<f64>]) -> Result<LinearCalibration> {
    todo!("being implemented")
}
