//! Geometric primitives: quaternions, dual quaternions, lines, Plücker coordinates, quadrics and conics.

pub mod dual_quaternion;
pub(crate) mod lines;
pub mod plucker;
pub(crate) mod quadric;
pub(crate) mod quaternion;

pub use quadric::{project_dual, CentreShape, Ellipse, Ellipsoid};
pub use quaternion::rotation_distance;

/// Helpers the Python bindings and the integration tests call directly; not part of the user-facing
/// API.
#[doc(hidden)]
pub mod testing {
    pub use super::quadric::centre_shape;
    pub use super::quaternion::{exp_so3, log_so3, skew};
}
