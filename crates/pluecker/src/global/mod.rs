//! Global optimisation: branch and bound over boxes, the convex envelopes of Josephson & Kahl 2008
//! (section 4.1) and the adapter to the `clarabel` conic solver.
//!
//! - [`socp`]: second-order cone programs built from affine expressions, solved by clarabel, with a
//!   lower bound that stays valid despite the solver's tolerance;
//! - [`envelopes`]: the convex envelope of a fraction `t/s` (eq. 22) and the quadratic-over-linear
//!   numerator constraint of eq. 21, for residuals of any dimension;
//! - [`monomial`]: the convex and concave envelopes of a bilinear monomial (eqs. 24-25), for the
//!   Plücker coordinates of lines;
//! - [`branch_and_bound`]: a generic best-first branch and bound over an axis-aligned box, driven by a
//!   problem-specific [`branch_and_bound::BoundingOracle`].

pub mod branch_and_bound;
pub mod envelopes;
pub mod monomial;
pub mod socp;
