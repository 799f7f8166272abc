//! Minimal solvers for the absolute camera pose: the finitely many poses `(R, t)`, `x_cam = R X_world + t`,
//! that explain exactly the smallest number of correspondences that fixes the six degrees of freedom.
//!
//! They are the hypothesis generators of a robust (RANSAC) estimator: each returns every real solution
//! it finds, possibly none, and never fails loudly — a degenerate sample simply yields no pose, so the
//! caller draws another one. Inputs are camera-frame bearings (unit vectors along the rays, see
//! [`p3p()`] for how to get them from pixels with [`crate::camera::Camera`]), not pixels.
//!
//! | solver    | data     | max. solutions | reference                                     |
//! |-----------|----------|----------------|-----------------------------------------------|
//! | [`p3p()`] | 3 points | 4              | Persson & Nordberg, *Lambda Twist*, ECCV 2018 |

pub mod p3p;
mod polynomial;

pub use p3p::p3p;
