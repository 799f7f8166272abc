//! Small polynomial kernels shared by the minimal solvers: the real roots of a cubic and the real
//! directions of a binary quadratic form, both in forms that avoid cancellation, and the real roots of
//! a polynomial of any (small) degree in a bounded interval, isolated by the roots of its derivatives.

use nalgebra::Vector2;

/// The directions `(α, β)` (unit 2-vectors) with `a α² + 2b αβ + c β² = 0`: `(h, a)` and `(c, h)` with
/// `h = −(b + sign(b) √(b² − ac))`, a form without cancellation or division. When the discriminant
/// `b² − ac` is not positive (a double root, or a complex pair clamped to it, as Lambda Twist clamps),
/// the one direction `(−b, a)` or `(c, −b)`, whichever has the larger coefficient: the exact double root
/// when the discriminant is zero, the nearest real direction when it is slightly negative. A form that
/// vanishes identically has no isolated direction and gives none.
pub(crate) fn binary_quadratic_roots(a: f64, b: f64, c: f64) -> Vec<Vector2<f64>> {
    let discriminant = b * b - a * c;
    let candidates = if discriminant > 0.0 {
        let h = -(b + discriminant.sqrt().copysign(b));
        vec![Vector2::new(h, a), Vector2::new(c, h)]
    } else if a.abs() >= c.abs() {
        vec![Vector2::new(-b, a)]
    } else {
        vec![Vector2::new(c, -b)]
    };
    candidates
        .into_iter()
        .filter_map(|v| {
            let n = v.norm();
            (n > 0.0 && n.is_finite()).then(|| v / n)
        })
        .collect()
}

/// The real roots of `k₃x³ + k₂x² + k₁x + k₀` (`k₃ ≠ 0`): Cardano's formula when there is one, the
/// trigonometric form when there are three, each polished by up to three verified Newton steps.
pub(crate) fn cubic_real_roots(k: [f64; 4]) -> Vec<f64> {
    let [k3, k2, k1, k0] = k;
    let (b, c, d) = (k2 / k3, k1 / k3, k0 / k3);
    // x = s − b/3 gives the depressed cubic s³ + p s + q.
    let shift = -b / 3.0;
    let p = c - b * b / 3.0;
    let q = d + b * (2.0 * b * b - 9.0 * c) / 27.0;
    let (half_q, third_p) = (0.5 * q, p / 3.0);
    let discriminant = half_q * half_q + third_p * third_p * third_p;
    let mut roots = Vec::with_capacity(3);
    if discriminant > 0.0 {
        let u = (-half_q - discriminant.sqrt().copysign(half_q)).cbrt();
        let s = if u != 0.0 { u - third_p / u } else { 0.0 };
        roots.push(s + shift);
    } else {
        let r = (-third_p).sqrt();
        if r > 0.0 {
            let phi = (-half_q / (r * r * r)).clamp(-1.0, 1.0).acos();
            for i in 0..3 {
                roots.push(2.0 * r * ((phi - std::f64::consts::TAU * i as f64) / 3.0).cos() + shift);
            }
        } else {
            roots.push(shift);
        }
    }
    let f = |x: f64| ((k3 * x + k2) * x + k1) * x + k0;
    let df = |x: f64| (3.0 * k3 * x + 2.0 * k2) * x + k1;
    for x in roots.iter_mut() {
        for _ in 0..3 {
            let (fx, dfx) = (f(*x), df(*x));
            let next = *x - fx / dfx;
            if !(next.is_finite() && f(next).abs() < fx.abs()) {
                break;
            }
            *x = next;
        }
    }
    roots.retain(|x| x.is_finite());
    roots
}

/// `Σ c[k] xᵏ` by Horner's rule (coefficients lowest degree first).
pub(crate) fn evaluate(c: &[f64], x: f64) -> f64 {
    c.iter().rev().fold(0.0, |acc, &ck| acc * x + ck)
}

/// The product of two polynomials (coefficients lowest degree first).
pub(crate) fn multiply(p: &[f64], q: &[f64]) -> Vec<f64> {
    if p.is_empty() || q.is_empty() {
        return Vec::new();
    }
    let mut out = vec![0.0; p.len() + q.len() - 1];
    for (i, &pi) in p.iter().enumerate() {
        for (j, &qj) in q.iter().enumerate() {
            out[i + j] += pi * qj;
        }
    }
    out
}

/// Relative size of `|p(x)|` (against `Σ|cₖ|`, the bound of `|p|` on `[−1, 1]`) under which a local
/// extremum counts as a root: a double root, or two simple roots so close that rounding of the
/// coefficients (a few ε relative to `Σ|cₖ|` in the callers) hides their sign change. Candidates
/// it admits that are not roots of the underlying system are rejected by the callers' verification.
const TANGENT_TOLERANCE: f64 = 1e-11;

/// The real roots in `[lo, hi]` (with `−1 ≤ lo < hi ≤ 1`) of `Σ c[k] xᵏ`, in increasing order.
///
/// Method: the real roots of the derivative split `[lo, hi]` into intervals on which `p` is monotone
/// (found recursively, down to degree one), and each interval with a sign change holds exactly one
/// root, found by bisection accelerated with Newton steps that stay inside the bracket, to full
/// precision. This finds every simple root (unlike a companion matrix, no root is lost to a complex
/// perturbation, and each is bracketed, so none is found twice). A local extremum whose value is
/// within rounding of zero ([`TANGENT_TOLERANCE`]) is returned too, as a double root. The zero
/// polynomial and non-finite coefficients give no roots.
pub(crate) fn real_roots_in(c: &[f64], lo: f64, hi: f64) -> Vec<f64> {
    if c.iter().any(|v| !v.is_finite()) {
        return Vec::new();
    }
    let degree = match c.iter().rposition(|&v| v != 0.0) {
        Some(d) => d,
        None => return Vec::new(),
    };
    let c = &c[..=degree];
    if degree == 0 {
        return Vec::new();
    }
    if degree == 1 {
        let x = -c[0] / c[1];
        return if (lo..=hi).contains(&x) { vec![x] } else { Vec::new() };
    }
    let derivative: Vec<f64> = c.iter().enumerate().skip(1).map(|(k, &ck)| k as f64 * ck).collect();
    let critical = real_roots_in(&derivative, lo, hi);
    let scale: f64 = c.iter().map(|v| v.abs()).sum();
    let mut knots = Vec::with_capacity(critical.len() + 2);
    knots.push(lo);
    knots.extend(critical.iter().copied());
    knots.push(hi);
    let mut roots: Vec<f64> = Vec::with_capacity(degree);
    let push = |x: f64, roots: &mut Vec<f64>| {
        if roots.last().map_or(true, |&last| x > last) {
            roots.push(x);
        }
    };
    for pair in knots.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        let (fa, fb) = (evaluate(c, a), evaluate(c, b));
        if fa == 0.0 {
            push(a, &mut roots);
        }
        if (fa < 0.0 && fb > 0.0) || (fa > 0.0 && fb < 0.0) {
            push(bracketed_root(c, &derivative, a, b, fa), &mut roots);
        } else if fa != 0.0 && fb != 0.0 && critical.contains(&b) && fb.abs() <= TANGENT_TOLERANCE * scale {
            // A tangency (no sign change on either side of this extremum is needed: a sign change on
            // the next interval adds its own root beside it, and the callers merge duplicates).
            push(b, &mut roots);
        }
    }
    if evaluate(c, hi) == 0.0 {
        push(hi, &mut roots);
    }
    roots
}

/// The root of the monotone `p` on `[a, b]` where it changes sign (`fa = p(a)`): bisection with a
/// Newton step whenever that step stays strictly inside the current bracket.
fn bracketed_root(c: &[f64], derivative: &[f64], mut a: f64, mut b: f64, fa: f64) -> f64 {
    let rising = fa < 0.0;
    let mut x = 0.5 * (a + b);
    for _ in 0..100 {
        let fx = evaluate(c, x);
        if fx == 0.0 {
            return x;
        }
        if (fx < 0.0) == rising {
            a = x;
        } else {
            b = x;
        }
        let newton = x - fx / evaluate(derivative, x);
        let next = if newton > a && newton < b {
            newton
        } else {
            0.5 * (a + b)
        };
        if next == x || b - a <= 0.0 || !(a < next && next < b) {
            return x;
        }
        x = next;
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The cubic `k₃ (x − r₀)(x − r₁)(x − r₂)`, coefficients highest degree first.
    fn from_roots(k3: f64, r: [f64; 3]) -> [f64; 4] {
        let e1 = r[0] + r[1] + r[2];
        let e2 = r[0] * r[1] + r[0] * r[2] + r[1] * r[2];
        let e3 = r[0] * r[1] * r[2];
        [k3, -k3 * e1, k3 * e2, -k3 * e3]
    }

    #[test]
    fn cubic_roots_are_found_to_rounding() {
        // Three well separated real roots (trigonometric branch), any leading coefficient and sign.
        for &k3 in &[1.0, -3.5, 1e-6, 2e5] {
            let mut roots = cubic_real_roots(from_roots(k3, [-3.0, 1.0, 2.0]));
            roots.sort_by(f64::total_cmp);
            assert_eq!(roots.len(), 3, "{k3}: {roots:?}");
            for (x, want) in roots.iter().zip([-3.0, 1.0, 2.0]) {
                // Simple roots of a polynomial with O(1) coefficients: condition ≈ 10, so ~1e-15.
                assert!((x - want).abs() < 1e-13, "{k3}: {roots:?}");
            }
        }
        // One real root (Cardano branch): (x − 0.5)(x² + x + 1).
        let roots = cubic_real_roots([2.0, 1.0, 1.0, -1.0]);
        assert_eq!(roots.len(), 1);
        assert!((roots[0] - 0.5).abs() < 1e-15, "{roots:?}");
        // A triple root: x³ (p = q = 0) and (x − 1)³, whose roots are only determined to ε^(1/3).
        assert_eq!(cubic_real_roots([1.0, 0.0, 0.0, 0.0]), vec![0.0]);
        for x in cubic_real_roots(from_roots(1.0, [1.0, 1.0, 1.0])) {
            assert!((x - 1.0).abs() < 1e-4, "{x}");
        }
    }

    #[test]
    fn binary_quadratic_directions_solve_the_form() {
        let form = |a: f64, b: f64, c: f64, v: &Vector2<f64>| a * v.x * v.x + 2.0 * b * v.x * v.y + c * v.y * v.y;
        // Two real lines, including the cases a = 0, c = 0 and b = 0.
        for &(a, b, c) in &[
            (1.0, 0.3, -2.0),
            (0.0, 1.0, 4.0),
            (3.0, -1.0, 0.0),
            (1.0, 0.0, -1.0),
            (-1e-9, 5.0, 2.0),
        ] {
            let dirs = binary_quadratic_roots(a, b, c);
            assert_eq!(dirs.len(), 2, "{a} {b} {c}");
            for v in &dirs {
                assert!((v.norm() - 1.0).abs() < 1e-15);
                assert!(
                    form(a, b, c, v).abs() < 1e-14 * (a.abs() + b.abs() + c.abs()),
                    "{a} {b} {c}: {v}"
                );
            }
            assert!((dirs[0].perp(&dirs[1])).abs() > 1e-3, "the two directions are distinct");
        }
        // A double root, (x + y)², and a slightly definite form clamped to it: one direction, (1, −1)/√2
        // (the perturbation δ = 1e-12 of c tilts the clamped direction by about δ/√8).
        for &(c, tol) in &[(1.0, 1e-15), (1.0 + 1e-12, 1e-12)] {
            let dirs = binary_quadratic_roots(1.0, 1.0, c);
            assert_eq!(dirs.len(), 1, "{dirs:?}");
            assert!(
                (dirs[0].x + dirs[0].y).abs() < tol && (dirs[0].x.abs() - 0.5f64.sqrt()).abs() < tol,
                "{dirs:?}"
            );
        }
        // A definite form far from tangency still gives its nearest direction (here the axis of the
        // smaller coefficient); the solver's residual test rejects what such a direction leads to.
        let dirs = binary_quadratic_roots(4.0, 0.0, 1.0);
        assert!(dirs.len() == 1 && dirs[0].x.abs() < 1e-15 && (dirs[0].y.abs() - 1.0).abs() < 1e-15);
        // A form that vanishes identically has no isolated direction.
        assert!(binary_quadratic_roots(0.0, 0.0, 0.0).is_empty());
    }
}
