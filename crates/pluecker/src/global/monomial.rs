//! Convex and concave envelopes of a bilinear monomial `x y` over a box (Josephson & Kahl 2008,
//! section 4.1.2, eqs. 24-25; McCormick 1976, Ryoo & Sahinidis 2001).
//!
//! Over `x ∈ [xᴸ, xᵁ]`, `y ∈ [yᴸ, yᵁ]`:
//! - `convenv(xy) = max(x yᵁ + xᵁ y − xᵁ yᵁ, x yᴸ + xᴸ y − xᴸ yᴸ)` (eq. 24),
//! - `concenv(xy) = min(x yᴸ + xᵁ y − xᵁ yᴸ, x yᵁ + xᴸ y − xᴸ yᵁ)` (eq. 25).
//!
//! Each inequality is `(x − a)(y − b) ≥ 0` or `≤ 0` for a corner `(a, b)`, true on the box; both
//! envelopes equal `xy` on the box's edges. A lifted variable `w` standing for `xy` is constrained by
//! the four linear inequalities `convenv ≤ w ≤ concenv` ([`add_mccormick`]), which keep it in the
//! interval [`product_bounds`].

pub use super::interval::Interval;
use super::socp::{Affine, Socp};
use std::ops::Mul;

/// The range of `xy` over the box: the least and greatest of the four corner products.
pub fn product_bounds(x: Interval, y: Interval) -> Interval {
    x.mul(y)
}

/// Eq. 24 at `(x, y)`.
#[cfg(test)]
pub fn convex_envelope(x: f64, y: f64, xb: Interval, yb: Interval) -> f64 {
    (x * yb.hi + xb.hi * y - xb.hi * yb.hi).max(x * yb.lo + xb.lo * y - xb.lo * yb.lo)
}

/// Eq. 25 at `(x, y)`.
#[cfg(test)]
pub fn concave_envelope(x: f64, y: f64, xb: Interval, yb: Interval) -> f64 {
    (x * yb.lo + xb.hi * y - xb.hi * yb.lo).min(x * yb.hi + xb.lo * y - xb.lo * yb.hi)
}

/// Adds a variable `w` standing for `xy`, with `x`, `y` affine expressions of the program's
/// variables known to lie in `xb`, `yb`, constrained by `convenv(xy) ≤ w ≤ concenv(xy)` (eqs. 24-25),
/// with declared bounds [`product_bounds`] (implied by the constraints when `x ∈ xb`, `y ∈ yb`), and
/// returns its index.
pub fn add_mccormick(p: &mut Socp, x: &Affine, xb: Interval, y: &Affine, yb: Interval) -> usize {
    let range = product_bounds(xb, yb);
    let w = p.add_variable(range.lo, range.hi);
    let wv = Affine::var(w);
    // a y + b x − a b, the plane through the corner (x, y) = (a, b).
    let plane = |a: f64, b: f64| x.clone().scaled(b).plus(&y.clone().scaled(a)).shifted(-a * b);
    p.less_eq(&plane(xb.hi, yb.hi), &wv);
    p.less_eq(&plane(xb.lo, yb.lo), &wv);
    p.less_eq(&wv, &plane(xb.hi, yb.lo));
    p.less_eq(&wv, &plane(xb.lo, yb.hi));
    w
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::global::socp::SocpStatus;
    use crate::rng::Rng;

    #[test]
    fn envelopes_sandwich_the_monomial_and_are_exact_on_the_edges() {
        let mut rng = Rng::new(71);
        for _ in 0..200 {
            let (a, b) = (rng.normal(), rng.normal());
            let xb = Interval::new(a.min(b), a.max(b));
            let (a, b) = (rng.normal(), rng.normal());
            let yb = Interval::new(a.min(b), a.max(b));
            for _ in 0..50 {
                let (x, y) = (rng.uniform_in(xb.lo, xb.hi), rng.uniform_in(yb.lo, yb.hi));
                let tol = 1e-12 * (1.0 + (x * y).abs());
                assert!(convex_envelope(x, y, xb, yb) <= x * y + tol);
                assert!(concave_envelope(x, y, xb, yb) >= x * y - tol);
                let range = product_bounds(xb, yb);
                assert!(range.lo <= x * y + tol && x * y <= range.hi + tol);
                for (ex, ey) in [(xb.lo, y), (xb.hi, y), (x, yb.lo), (x, yb.hi)] {
                    let exact = ex * ey;
                    assert!((convex_envelope(ex, ey, xb, yb) - exact).abs() < 1e-12 * (1.0 + exact.abs()));
                    assert!((concave_envelope(ex, ey, xb, yb) - exact).abs() < 1e-12 * (1.0 + exact.abs()));
                }
            }
        }
    }

    #[test]
    fn mccormick_constraints_give_the_envelopes_in_a_program() {
        let (xb, yb) = (Interval::new(-1.0, 2.0), Interval::new(0.5, 3.0));
        for (x0, y0) in [(0.3, 1.2), (-0.8, 2.9), (1.9, 0.6)] {
            for sign in [1.0, -1.0] {
                let mut p = Socp::new();
                let x = p.add_variable(xb.lo, xb.hi);
                let y = p.add_variable(yb.lo, yb.hi);
                p.equal(Affine::var(x).shifted(-x0));
                p.equal(Affine::var(y).shifted(-y0));
                let w = add_mccormick(&mut p, &Affine::var(x), xb, &Affine::var(y), yb);
                p.minimize(Affine::term(w, sign));
                let s = p.solve();
                assert_eq!(s.status, SocpStatus::Solved);
                let expected = if sign > 0.0 {
                    convex_envelope(x0, y0, xb, yb)
                } else {
                    concave_envelope(x0, y0, xb, yb)
                };
                assert!(
                    (s.x[w] - expected).abs() < 1e-6,
                    "{x0} {y0} {sign}: {} vs {expected}",
                    s.x[w]
                );
                assert!(s.lower_bound <= sign * expected + 1e-12);
            }
        }
    }
}
