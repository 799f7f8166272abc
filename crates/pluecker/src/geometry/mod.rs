//! Geometric primitives: quaternions, dual quaternions, lines, Plücker coordinates, quadrics and conics.

pub mod dual_quaternion;
pub mod lines;
pub mod plucker;
pub mod quadric;
pub mod quaternion;
