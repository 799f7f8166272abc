//! Cameras: the pinhole [`Camera`] (with skew, any sign of focal length), the [`LensCamera`] of any of
//! COLMAP's [`CameraModel`]s, and [`AnyCamera`], either of them.
//!
//! One concept per module: [`model`] names the models and their parameters (COLMAP's ids and order),
//! `distortion` holds their distortion maps, `fold` the radius where a lens folds, `lens` the checked
//! camera with its projection and unprojection; `bounds` and `linearisation` are the enclosures of the
//! distortion that the certificates use, `curved_line` the image of a 3-D line through a lens.

mod any;
pub(crate) mod bounds;
pub(crate) mod curved_line;
mod distortion;
mod fold;
mod lens;
pub(crate) mod linearisation;
pub mod model;
mod pinhole;
#[cfg(test)]
mod tests;

pub use any::AnyCamera;
pub use fold::fold_radius;
pub use lens::LensCamera;
pub use model::{CameraModel, UNPROJECTION_TOLERANCE_PX};
pub use pinhole::Camera;
