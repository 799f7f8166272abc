//! Convex relaxations of the fractional cost of Josephson & Kahl 2008, section 4.1.1.
//!
//! The cost of eq. 19 is a sum of fractions `fᵢ(x)/gᵢ(x)` (eq. 20) with `fᵢ = ‖wᵢ(x)‖²/gᵢ(x)`
//! convex (`wᵢ` the `D` affine entries of a residual numerator: `D = 2` for points and lines, `5` for
//! conics) and `gᵢ` affine and positive (the denominator of eq. 17). Eq. 21 lifts each fraction to
//! `tᵢ/sᵢ` with `fᵢ(x) ≤ tᵢ` ([`add_quadratic_over_linear`]) and `sᵢ = gᵢ(x)`, and bounds `tᵢ/sᵢ`
//! below by its convex envelope over the box `[l, u] × [L, U]`, the SOCP of eq. 22
//! ([`add_fraction_envelope`]; Tawarmalani & Sahinidis 2001).
//!
//! ## Eq. 22, derived
//! With `λ = (u − t)/(u − l)`, `(t, s)` is the convex combination `λ (l, s'/λ) + (1 − λ) (u, (s − s')/(1 − λ))`
//! of two points on the edges `t = l` and `t = u`, on which `t/s` is convex in `s`; so
//! `convenv(t/s) = min_{s'} l λ²/s' + u (1 − λ)²/(s − s')` over `λL ≤ s' ≤ λU`,
//! `(1 − λ)L ≤ s − s' ≤ (1 − λ)U` (the paper's "λL ≤ s ≤ λU" is a misprint for `s'`). The two terms
//! are the rotated cones `(λ√l)² ≤ r' s'` and `((1 − λ)√u)² ≤ (r − r')(s − s')`, which is eq. 22.
//! [`fraction_envelope`] evaluates the same minimum in closed form (the minimiser
//! `s' = s λ√l / (λ√l + (1 − λ)√u)` clamped to its interval), for tests and cheap evaluations.

use super::socp::{Affine, Socp};

/// The box `[l, u] × [L, U]` of one fraction `t/s` (eq. 21): `0 ≤ l ≤ u`, `0 < L ≤ U`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FractionBox {
    /// `l`, lower bound of the numerator `t`.
    pub t_lower: f64,
    /// `u`, upper bound of the numerator `t`.
    pub t_upper: f64,
    /// `L > 0`, lower bound of the denominator `s`.
    pub s_lower: f64,
    /// `U`, upper bound of the denominator `s`.
    pub s_upper: f64,
}

/// Relative width below which the `t` interval is widened (λ of eq. 22 needs `u > l`).
const MIN_RELATIVE_WIDTH: f64 = 1e-12;

impl FractionBox {
    /// The box with `u > l` guaranteed (a degenerate `t` interval widened upwards by a relative
    /// 1e-12, which keeps it a superset) — what [`add_fraction_envelope`] uses.
    pub fn widened(&self) -> FractionBox {
        let floor = self.t_lower + MIN_RELATIVE_WIDTH * (1.0 + self.t_lower.abs());
        FractionBox {
            t_upper: self.t_upper.max(floor),
            ..*self
        }
    }
}

/// `convenv(t/s)` over the box at `(t, s)` inside it, in closed form (see the module docs).
#[cfg(test)]
pub fn fraction_envelope(t: f64, s: f64, b: &FractionBox) -> f64 {
    let b = b.widened();
    let (l, u, lo, hi) = (b.t_lower, b.t_upper, b.s_lower, b.s_upper);
    let lambda = ((u - t) / (u - l)).clamp(0.0, 1.0);
    let mu = 1.0 - lambda;
    if mu == 0.0 {
        return l / s;
    }
    if lambda == 0.0 {
        return u / s;
    }
    let (a, c) = (lambda * l.sqrt(), mu * u.sqrt());
    let first = (lambda * lo).max(s - mu * hi);
    let last = (lambda * hi).min(s - mu * lo);
    let sp = (s * a / (a + c)).clamp(first, last);
    let left = if a == 0.0 { 0.0 } else { a * a / sp };
    left + c * c / (s - sp)
}

/// Adds eq. 22 for the fraction `t/s` (affine expressions of the program's variables) over `b`, and
/// returns the index of a new variable `r` with `r ≥ convenv(t/s)` (equality at a minimum of any
/// objective increasing in `r`). Also imposes `l ≤ t ≤ u`, `L ≤ s ≤ U` and `r ≤ u/L` (harmless:
/// the envelope never exceeds `t/s ≤ u/L`), so that every new variable has declared bounds.
pub fn add_fraction_envelope(p: &mut Socp, t: &Affine, s: &Affine, b: &FractionBox) -> usize {
    let b = b.widened();
    let (l, u, lo, hi) = (b.t_lower, b.t_upper, b.s_lower, b.s_upper);
    let r_max = u / lo;
    let r = p.add_variable(0.0, r_max);
    let rp = p.add_variable(0.0, r_max);
    let sp = p.add_variable(0.0, hi);
    // λ = (u − t)/(u − l) and 1 − λ = (t − l)/(u − l), affine in t.
    let width = u - l;
    let lambda = t.clone().scaled(-1.0 / width).shifted(u / width);
    let mu = t.clone().scaled(1.0 / width).shifted(-l / width);
    let (rv, rpv, spv) = (Affine::var(r), Affine::var(rp), Affine::var(sp));
    let rest_r = rv.clone().minus(&rpv);
    let rest_s = s.clone().minus(&spv);
    if l > 0.0 {
        p.rotated_second_order(&rpv, &spv, &[lambda.clone().scaled(l.sqrt())]);
    } else {
        p.nonneg(rpv.clone());
    }
    p.rotated_second_order(&rest_r, &rest_s, &[mu.clone().scaled(u.sqrt())]);
    p.less_eq(&lambda.clone().scaled(lo), &spv);
    p.less_eq(&spv, &lambda.scaled(hi));
    p.less_eq(&mu.clone().scaled(lo), &rest_s);
    p.less_eq(&rest_s, &mu.scaled(hi));
    p.less_eq(&Affine::constant(l), t);
    p.less_eq(t, &Affine::constant(u));
    p.less_eq(&Affine::constant(lo), s);
    p.less_eq(s, &Affine::constant(hi));
    p.less_eq(&rv, &Affine::constant(r_max));
    r
}

/// `‖w(x)‖² ≤ t · z`: the numerator constraint `f(x) = ‖w‖²/z ≤ t` of eq. 21 for a residual
/// numerator `w` of any dimension (a rotated second-order cone; it also forces `t, z ≥ 0`).
pub fn add_quadratic_over_linear(p: &mut Socp, w: &[Affine], z: &Affine, t: &Affine) {
    p.rotated_second_order(t, z, w);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::global::socp::SocpStatus;
    use crate::rng::Rng;

    fn boxes() -> Vec<FractionBox> {
        vec![
            FractionBox {
                t_lower: 0.0,
                t_upper: 4.0,
                s_lower: 1.0,
                s_upper: 3.0,
            },
            FractionBox {
                t_lower: 0.5,
                t_upper: 2.0,
                s_lower: 0.2,
                s_upper: 0.25,
            },
            FractionBox {
                t_lower: 1.0,
                t_upper: 9.0,
                s_lower: 2.0,
                s_upper: 20.0,
            },
        ]
    }

    #[test]
    fn envelope_is_below_the_fraction_and_exact_on_the_t_edges() {
        let mut rng = Rng::new(22);
        for b in boxes() {
            for _ in 0..2000 {
                let t = rng.uniform_in(b.t_lower, b.t_upper);
                let s = rng.uniform_in(b.s_lower, b.s_upper);
                assert!(fraction_envelope(t, s, &b) <= t / s * (1.0 + 1e-14), "{b:?} {t} {s}");
                // On the edges t = l and t = u the fraction is convex in s, so the envelope is exact.
                for edge in [b.t_lower, b.t_upper] {
                    let e = fraction_envelope(edge, s, &b);
                    assert!((e - edge / s).abs() <= 1e-12 * (1.0 + edge / s), "{b:?} {edge} {s} {e}");
                }
            }
        }
    }

    #[test]
    fn envelope_is_convex_along_random_segments() {
        let mut rng = Rng::new(23);
        for b in boxes() {
            for _ in 0..2000 {
                let p = (
                    rng.uniform_in(b.t_lower, b.t_upper),
                    rng.uniform_in(b.s_lower, b.s_upper),
                );
                let q = (
                    rng.uniform_in(b.t_lower, b.t_upper),
                    rng.uniform_in(b.s_lower, b.s_upper),
                );
                let a = rng.uniform();
                let m = (a * p.0 + (1.0 - a) * q.0, a * p.1 + (1.0 - a) * q.1);
                let chord = a * fraction_envelope(p.0, p.1, &b) + (1.0 - a) * fraction_envelope(q.0, q.1, &b);
                assert!(fraction_envelope(m.0, m.1, &b) <= chord + 1e-12 * (1.0 + chord));
            }
        }
    }

    #[test]
    fn socp_of_eq_22_equals_the_closed_form_and_the_corners() {
        let mut rng = Rng::new(24);
        for b in boxes() {
            let corners = [
                (b.t_lower, b.s_lower),
                (b.t_lower, b.s_upper),
                (b.t_upper, b.s_lower),
                (b.t_upper, b.s_upper),
            ];
            let inside: Vec<(f64, f64)> = (0..6)
                .map(|_| {
                    (
                        rng.uniform_in(b.t_lower, b.t_upper),
                        rng.uniform_in(b.s_lower, b.s_upper),
                    )
                })
                .collect();
            for &(t0, s0) in corners.iter().chain(&inside) {
                let mut p = Socp::new();
                let t = p.add_variable(b.t_lower, b.t_upper);
                let s = p.add_variable(b.s_lower, b.s_upper);
                p.equal(Affine::var(t).shifted(-t0));
                p.equal(Affine::var(s).shifted(-s0));
                let r = add_fraction_envelope(&mut p, &Affine::var(t), &Affine::var(s), &b);
                p.minimize(Affine::var(r));
                let sol = p.solve();
                assert_eq!(sol.status, SocpStatus::Solved);
                let exact = fraction_envelope(t0, s0, &b);
                let tol = 1e-6 * (1.0 + exact);
                assert!(
                    (sol.primal_objective - exact).abs() < tol,
                    "{b:?} ({t0}, {s0}): {} vs {exact}",
                    sol.primal_objective
                );
                assert!(sol.lower_bound <= exact + 1e-12 && sol.lower_bound > exact - tol);
                if corners.contains(&(t0, s0)) {
                    assert!((exact - t0 / s0).abs() <= 1e-12 * (1.0 + t0 / s0));
                }
            }
        }
    }

    /// The convex envelope of `t/s` (linear in `t`) is the least mix `λ l/s₁ + (1 − λ) u/s₂` of two
    /// points `(l, s₁)`, `(u, s₂)` of the box's `t` edges averaging to `(t, s)`:
    /// `λ = (u − t)/(u − l)`, `s₂ = (s − λs₁)/(1 − λ)`, both `s₁, s₂ ∈ [L, U]`. Minimised here by
    /// golden section over `s₁` (the mix is convex in `s₁`), written from that definition and not from
    /// the closed form.
    fn envelope_by_edge_points(t: f64, s: f64, b: &FractionBox) -> f64 {
        let (l, u, lo, hi) = (b.t_lower, b.t_upper, b.s_lower, b.s_upper);
        let lambda = (u - t) / (u - l);
        let mix = |s1: f64| lambda * l / s1 + (1.0 - lambda) * u / ((s - lambda * s1) / (1.0 - lambda));
        // s₂ ∈ [L, U] ⇔ s₁ ∈ [(s − (1 − λ)U)/λ, (s − (1 − λ)L)/λ].
        let mut a = lo.max((s - (1.0 - lambda) * hi) / lambda);
        let mut c = hi.min((s - (1.0 - lambda) * lo) / lambda);
        let ratio = 0.5 * (5f64.sqrt() - 1.0);
        for _ in 0..200 {
            let (x1, x2) = (c - ratio * (c - a), a + ratio * (c - a));
            if mix(x1) <= mix(x2) {
                c = x2;
            } else {
                a = x1;
            }
        }
        mix(0.5 * (a + c))
    }

    /// The closed form equals the envelope built from its definition, over random boxes and points
    /// inside them (the `t` edges excluded, where λ is 0 or 1). The clamp of `s'` to `s − (1 − λ)L`
    /// never binds (the unclamped minimiser `sλ√l/(λ√l + (1 − λ)√u)` is below it since `s ≥ L` and
    /// `√u ≥ λ√l + (1 − λ)√u`), so no test can see a slip in it; the other clamps can be seen here.
    #[test]
    fn envelope_equals_the_least_mix_of_two_edge_points() {
        let mut rng = Rng::new(25);
        for _ in 0..200 {
            let l = if rng.uniform() < 0.3 {
                0.0
            } else {
                rng.uniform_in(0.0, 3.0)
            };
            let lo = rng.uniform_in(0.05, 2.0);
            let b = FractionBox {
                t_lower: l,
                t_upper: l + rng.uniform_in(0.1, 5.0),
                s_lower: lo,
                s_upper: lo * rng.uniform_in(1.05, 20.0),
            };
            for _ in 0..50 {
                let t = rng.uniform_in(b.t_lower, b.t_upper);
                let s = rng.uniform_in(b.s_lower, b.s_upper);
                let closed = fraction_envelope(t, s, &b);
                let defined = envelope_by_edge_points(t, s, &b);
                // Golden section to 1e-40 of the interval: the two agree to rounding, ~1e-12 relative.
                assert!(
                    (closed - defined).abs() <= 1e-9 * (1.0 + defined),
                    "{b:?} ({t}, {s}): closed form {closed}, envelope {defined}"
                );
            }
        }
    }

    #[test]
    fn quadratic_over_linear_is_the_fraction_numerator() {
        // min t s.t. ‖(x − 1, 2)‖² ≤ t z with z = 2 fixed and x free: t = 4/2 = 2 at x = 1.
        let mut p = Socp::new();
        let x = p.add_variable(-10.0, 10.0);
        let t = p.add_variable(0.0, 100.0);
        add_quadratic_over_linear(
            &mut p,
            &[Affine::var(x).shifted(-1.0), Affine::constant(2.0)],
            &Affine::constant(2.0),
            &Affine::var(t),
        );
        p.minimize(Affine::var(t));
        let sol = p.solve();
        assert!((sol.x[t] - 2.0).abs() < 1e-6 && (sol.x[x] - 1.0).abs() < 1e-4);
    }
}
