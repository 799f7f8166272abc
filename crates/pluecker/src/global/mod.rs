//! Global optimisation: branch and bound over boxes, the convex envelopes of Josephson & Kahl 2008
//! (section 4.1) and the adapter to the `clarabel` conic solver.
//!
//! - [`socp`]: second-order cone programs built from affine expressions, solved by clarabel, with a
//!   lower bound that stays valid despite the solver's tolerance;
//! - [`envelopes`]: the convex envelope of a fraction `t/s` (eq. 22) and the quadratic-over-linear
//!   numerator constraint of eq. 21, for residuals of any dimension;
//! - [`monomial`]: the convex and concave envelopes of a bilinear monomial (eqs. 24-25), for the
//!   Plücker coordinates of lines;
//! - [`interval`], [`taylor_bound`]: interval arithmetic and the interval Taylor bounds of a sum of
//!   squared ratios of quadratics over a box (the line certificate's default bound);
//! - [`convexity`]: the sufficient global-optimality test of a sum of squared ratios of affine maps
//!   (strong convexity on an enclosure of the sublevel set), shared by points and quadrics;
//! - [`branch_and_bound`]: a generic best-first branch and bound over an axis-aligned box, driven by a
//!   problem-specific [`branch_and_bound::BoundingOracle`].

pub mod branch_and_bound;
pub mod convexity;
pub mod envelopes;
pub mod interval;
pub mod monomial;
pub mod socp;
pub mod taylor_bound;

/// Costs below this (squared pixels: 1e-6 px of error) count as exact: certificate gaps are measured
/// relative to `max(cost, CERTIFICATE_COST_FLOOR)` ([`relative_gap`]), since a relative gap cannot close at the rounding level.
pub const CERTIFICATE_COST_FLOOR: f64 = 1e-12;

/// The relative gap `(cost − lower) / max(cost, CERTIFICATE_COST_FLOOR)`, at least 0.
pub fn relative_gap(cost: f64, lower: f64) -> f64 {
    ((cost - lower) / cost.max(CERTIFICATE_COST_FLOOR)).max(0.0)
}
