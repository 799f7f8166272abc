//! Cameras: the one [`Camera`] of pose and triangulation, a [`CameraModel`] (COLMAP's models, PINHOLE
//! among them, and `SKEWED_PINHOLE`) with its parameters; [`Intrinsics`] is its pinhole part `K`.
//!
//! One concept per module: [`model`] names the models and their parameters (COLMAP's ids and order),
//! `intrinsics` holds `K` (pixels ↔ normalised coordinates), `distortion` the models' distortion maps,
//! `fold` the radius where a lens folds, `lens` the checked camera with its projection and
//! unprojection; `bounds` and `linearisation` are the enclosures of the distortion that the
//! certificates use, `curved_line` the image of a 3-D line through a lens.

pub(crate) mod bounds;
pub(crate) mod curved_line;
mod distortion;
mod fold;
mod intrinsics;
mod lens;
pub(crate) mod linearisation;
pub mod model;
#[cfg(test)]
mod tests;

pub use fold::fold_radius;
pub use intrinsics::Intrinsics;
pub use lens::Camera;
pub use model::{CameraModel, UNPROJECTION_TOLERANCE_PX};
