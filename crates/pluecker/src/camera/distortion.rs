//! The distortion functions `D(n)` of the camera models (see [`super::model`]'s table), each with
//! its Jacobian.

use super::model::FOV_SERIES_BOUND;
use nalgebra::{Matrix2, Vector2};

/// `v g` and its Jacobian `g I + 2 g' v vᵀ`, for a radial factor `g(|v|²)` with derivative `g' = dg/d|v|²`.
pub(super) fn scaled(v: &Vector2<f64>, g: f64, dg: f64) -> (Vector2<f64>, Matrix2<f64>) {
    (v * g, Matrix2::identity() * g + v * v.transpose() * (2.0 * dg))
}

/// `g(s) = 1 + c₁ s + c₂ s² + …` for `coefficients = [c₁, c₂, …]`, and `g'(s)` (Horner's scheme).
pub(super) fn polynomial(coefficients: &[f64], s: f64) -> (f64, f64) {
    let (mut p, mut dp) = (0.0, 0.0);
    for c in coefficients.iter().rev() {
        dp = p + s * dp;
        p = c + s * p;
    }
    (1.0 + s * p, p + s * dp)
}

/// The radial polynomial distortion `v g(|v|²)`, `g` = [`polynomial`]`(coefficients)`, and its Jacobian.
pub(super) fn radial(v: &Vector2<f64>, coefficients: &[f64]) -> (Vector2<f64>, Matrix2<f64>) {
    let (g, dg) = polynomial(coefficients, v.norm_squared());
    scaled(v, g, dg)
}

/// The tangential term `t(v)` of the module docs and its Jacobian.
pub(super) fn tangential(v: &Vector2<f64>, p1: f64, p2: f64) -> (Vector2<f64>, Matrix2<f64>) {
    let (x, y) = (v.x, v.y);
    let r2 = x * x + y * y;
    let t = Vector2::new(
        2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x),
        p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y,
    );
    let j = Matrix2::new(
        2.0 * p1 * y + 6.0 * p2 * x,
        2.0 * p1 * x + 2.0 * p2 * y,
        2.0 * p1 * x + 2.0 * p2 * y,
        6.0 * p1 * y + 2.0 * p2 * x,
    );
    (t, j)
}

/// The thin-prism term `(s0 ρ² + s1 ρ⁴, s2 ρ² + s3 ρ⁴)`, `ρ = |v|`, and its Jacobian (rows
/// `(2 s0 + 4 s1 ρ²) vᵀ` and `(2 s2 + 4 s3 ρ²) vᵀ`).
pub(super) fn thin_prism(v: &Vector2<f64>, s: [f64; 4]) -> (Vector2<f64>, Matrix2<f64>) {
    let q = v.norm_squared();
    let (a, b) = (2.0 * s[0] + 4.0 * s[1] * q, 2.0 * s[2] + 4.0 * s[3] * q);
    (
        Vector2::new(q * (s[0] + s[1] * q), q * (s[2] + s[3] * q)),
        Matrix2::new(a * v.x, a * v.y, b * v.x, b * v.y),
    )
}

/// The equidistant fisheye coordinates `m = n θ / r`, `θ = atan r`, and `∂m/∂n`.
pub(super) fn equidistant(n: &Vector2<f64>) -> (Vector2<f64>, Matrix2<f64>) {
    let r2 = n.norm_squared();
    let r = r2.sqrt();
    if r < 1e-8 {
        // θ / r = 1 − r²/3 + …, which is 1 in double precision; the Jacobian is the identity to O(r²).
        return (*n, Matrix2::identity());
    }
    let theta = r.atan();
    // m = n s(r), s = θ / r: ∂m/∂n = s I + (s'(r) / r) n nᵀ with s' = (r θ'(r) − θ) / r², θ' = 1 / (1 + r²).
    // The cancellation in s' costs an absolute error ε / r² in s' / r, multiplied by |n nᵀ| = r².
    let s = theta / r;
    let ds = (r / (1.0 + r2) - theta) / r2;
    (n * s, Matrix2::identity() * s + n * n.transpose() * (ds / r))
}

/// COLMAP's FOV distortion (module docs, with its two series) and its Jacobian.
pub(super) fn fov(n: &Vector2<f64>, omega: f64) -> (Vector2<f64>, Matrix2<f64>) {
    let s = n.norm_squared();
    let w2 = omega * omega;
    if w2 < FOV_SERIES_BOUND {
        return scaled(n, w2 * s / 3.0 - w2 / 12.0 + 1.0, w2 / 3.0);
    }
    let t = (omega / 2.0).tan();
    if s < FOV_SERIES_BOUND {
        let g = -2.0 * t * (4.0 * s * t * t - 3.0) / (3.0 * omega);
        return scaled(n, g, -8.0 * t * t * t / (3.0 * omega));
    }
    let r = s.sqrt();
    let a = (2.0 * r * t).atan();
    let g = a / (r * omega);
    // dg/dr = (2 t r / (1 + 4 t² r²) − a) / (ω r²), and dg/ds = (dg/dr) / (2r).
    let dg_dr = (2.0 * t * r / (1.0 + 4.0 * t * t * s) - a) / (omega * s);
    scaled(n, g, dg_dr / (2.0 * r))
}

/// The division model's projection `2 n / (1 + √(1 − 4 k r²))` and its Jacobian (NaN where `4 k r² > 1`:
/// no point there projects).
pub(super) fn division(n: &Vector2<f64>, k: f64) -> (Vector2<f64>, Matrix2<f64>) {
    let q = (1.0 - 4.0 * k * n.norm_squared()).sqrt();
    // g = 2 / (1 + q), q' = dq/ds = −2k / q: g' = 4k / (q (1 + q)²).
    scaled(n, 2.0 / (1.0 + q), 4.0 * k / (q * (1.0 + q) * (1.0 + q)))
}

/// EUCM's projection `n / (α √(1 + β r²) + 1 − α)` and its Jacobian.
pub(super) fn eucm(n: &Vector2<f64>, alpha: f64, beta: f64) -> (Vector2<f64>, Matrix2<f64>) {
    let q = (1.0 + beta * n.norm_squared()).sqrt();
    let g = 1.0 / (alpha * q + 1.0 - alpha);
    // g' = −α q' g², q' = β / (2q).
    scaled(n, g, -alpha * beta / (2.0 * q) * g * g)
}
