//! Geometric primitives: quaternions, dual quaternions, lines.

pub mod dual_quaternion;
pub mod lines;
pub mod quaternion;
