//! The distance of an observed pixel to the curved image of a line through a lens.
//!
//! A lens ([`Camera`]: `u = K D(n)`, `n = (x/z, y/z)`) maps the straight image `ℓ` of a 3-D line
//! in normalised coordinates (the line `l₀ x + l₁ y + l₂ = 0`, `l = (l₀, l₁, l₂)` the camera-frame line
//! of the pinhole model: Josephson & Kahl 2008, eq. 6 with `K = I`) to the curve `K D(ℓ)` in the
//! image's own, distorted pixels. The residual of an observed segment endpoint `e` with covariance `C`
//! is its Mahalanobis distance to that curve, `min_q √((u(q) − e)ᵀ C⁻¹ (u(q) − e))` over the points
//! `q` of `ℓ`, with a sign ([`endpoint_residual`]); for `D` the identity it is
//! `−(l̄·ẽ) / √(l̄₁₂ᵀ C l̄₁₂)` with the pixel line `l̄ = K⁻ᵀ l` ([`pinhole_endpoint_residual`]). Both the pose
//! ([`crate::pose::reprojection`]) and the triangulation of lines through lenses
//! ([`crate::triangulation::line::lens`]) measure segment endpoints with it.

use crate::camera::Camera;
use nalgebra::{Matrix2, Matrix3, RowVector2, RowVector3, Vector2, Vector3};

/// The 1-D search of [`nearest_on_curve`] stops after a step that moves the point on the curve by at
/// most this many pixels (its cost is then exact to ~1e-20 px², its derivative to ~1e-10 px), or
/// after [`NEAREST_MAX_ITERATIONS`] steps (Gauss-Newton contracts by about the residual over the
/// curve's radius of curvature per step: a few steps for pixel residuals).
const NEAREST_TOLERANCE_PX: f64 = 1e-10;
/// See [`NEAREST_TOLERANCE_PX`].
const NEAREST_MAX_ITERATIONS: usize = 100;

/// The point nearest to the pixel `e`, in the metric `info = C⁻¹`, on the curve
/// `σ ↦ u(σ) = K D(foot + σ dir)` of `lens` (`dir` a unit vector): the local minimum of
/// `½ (u(σ) − e)ᵀ C⁻¹ (u(σ) − e)` that Gauss-Newton with step halving reaches from `σ = 0` (the foot on
/// the undistorted line of the undistorted observation: the branch of the curve through the
/// observation). Returns the point `foot + σ dir`, its pixel `u(σ)` and the tangent `du/dσ`.
pub fn nearest_on_curve(
    lens: &Camera,
    foot: &Vector2<f64>,
    dir: &Vector2<f64>,
    e: &Vector2<f64>,
    info: &Matrix2<f64>,
) -> (Vector2<f64>, Vector2<f64>, Vector2<f64>) {
    let ((fx, fy), (cx, cy)) = (lens.focal(), lens.principal_point());
    let at = |sigma: f64| {
        let q = foot + dir * sigma;
        let (d, jd) = lens.distort(&q);
        let tangent = jd * dir;
        (
            q,
            Vector2::new(fx * d.x + cx, fy * d.y + cy),
            Vector2::new(fx * tangent.x, fy * tangent.y),
        )
    };
    let half_square = |u: &Vector2<f64>| 0.5 * (u - e).dot(&(info * (u - e)));
    let (mut sigma, mut best) = (0.0, at(0.0));
    let mut cost = half_square(&best.1);
    for _ in 0..NEAREST_MAX_ITERATIONS {
        let (_, u, du) = best;
        let (g, h) = (du.dot(&(info * (u - e))), du.dot(&(info * du)));
        if !(h > 0.0 && g.is_finite()) {
            break;
        }
        let mut step = -g / h;
        let small = (du * step).norm() <= NEAREST_TOLERANCE_PX;
        let (before, mut accepted) = (cost, false);
        for _ in 0..60 {
            let next = at(sigma + step);
            let c = half_square(&next.1);
            if c <= cost {
                (sigma, best, cost, accepted) = (sigma + step, next, c, true);
                break;
            }
            step *= 0.5;
        }
        // A step that no longer lowers the cost is at its rounding: the search has converged (far off
        // axis through a fisheye, steps of rounding noise can stay above the tolerance).
        if small || !accepted || !(cost < before) {
            break;
        }
    }
    best
}

/// The residual of one observed endpoint against the curved image of a line (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EndpointResidual {
    /// The point `q*` of the normalised line `ℓ` whose pixel is nearest to the endpoint.
    pub q: Vector2<f64>,
    /// `η = n / √(nᵀ C n)`, `n` the normal of the curve at `u(q*)`.
    pub eta: Vector2<f64>,
    /// `r = ηᵀ (u(q*) − e)`: `±` the Mahalanobis distance (the pixel distance for `C = I`).
    pub residual: f64,
}

impl EndpointResidual {
    /// `∂r/∂q` at `q*` with the endpoint fixed, `ηᵀ diag(fx, fy) ∂D/∂n(q*)`. By the envelope theorem
    /// (the search's derivative along the curve is zero at its minimum) this is the derivative of the
    /// residual for any smooth motion of `q*` that keeps it on the moving line `ℓ`, and `r`'s
    /// derivative with respect to whatever moves `ℓ` is this row times that motion.
    pub fn gradient(&self, lens: &Camera) -> RowVector2<f64> {
        let (fx, fy) = lens.focal();
        let (_, jd) = lens.distort(&self.q);
        self.eta.transpose() * Matrix2::new(fx, 0.0, 0.0, fy) * jd
    }

    /// `∂r/∂l` (the normalised line `l` of [`endpoint_residual`] moving, the endpoint fixed): [`Self::gradient`]
    /// times the motion of `q*` projected orthogonally onto the moving line,
    /// `q(l) = q* − l₁₂ (l·q̃*) / ‖l₁₂‖²`, whose derivative at `l` (where `l·q̃* = 0`) is
    /// `−l₁₂ q̃*ᵀ / ‖l₁₂‖²` (`q̃* = (q*, 1)`).
    pub fn line_gradient(&self, lens: &Camera, l: &Vector3<f64>) -> RowVector3<f64> {
        let l12 = Vector2::new(l.x, l.y);
        let qh = Vector3::new(self.q.x, self.q.y, 1.0);
        let dq_dl = -(l12 * qh.transpose()) / l12.norm_squared();
        self.gradient(lens) * dq_dl
    }
}

/// The residual of the observed pixel `e` (covariance `cov`) against the image of the normalised line
/// `l` through a camera without distortion, `u = K n` (`K` may have skew): the signed Mahalanobis
/// distance `r = −(l̄·ẽ) / s`, `s = √(l̄₁₂ᵀ C l̄₁₂)`, to the pixel line `l̄ = K⁻ᵀ l` (what
/// [`endpoint_residual`] gives for `D = I`, sign included, in closed form), and
/// `∂r/∂l = −K⁻¹ (ẽ + r (C l̄₁₂, 0) / s) / s`.
/// `None` when the pixel line does not exist or `cov` is not positive definite.
pub fn pinhole_endpoint_residual(
    k_inverse: &Matrix3<f64>,
    l: &Vector3<f64>,
    e: &Vector2<f64>,
    cov: &Matrix2<f64>,
) -> Option<(f64, RowVector3<f64>)> {
    let lp = k_inverse.transpose() * l;
    let lp12 = Vector2::new(lp.x, lp.y);
    let c_l = cov * lp12;
    let s = lp12.dot(&c_l).sqrt();
    if !(s > 0.0 && s.is_finite()) {
        return None;
    }
    let eh = Vector3::new(e.x, e.y, 1.0);
    let r = -lp.dot(&eh) / s;
    let d_lp = -(eh + Vector3::new(c_l.x, c_l.y, 0.0) * (r / s)) / s;
    Some((r, (k_inverse * d_lp).transpose()))
}

/// The residual of the observed pixel `e` (covariance `cov`, pixels²) against the curved image
/// `K D(ℓ)` of the normalised line `ℓ: l·(x, y, 1) = 0` (module docs), searched from the foot on `ℓ`
/// of `start` (the endpoint's unprojection, so that the search stays on the curve's branch through the
/// observation; [`nearest_on_curve`]). The sign is the side of the curve, `−(l̄·ẽ)/…` for `D = I`
/// ([`pinhole_endpoint_residual`]; only its square enters a cost).
/// `None` when `ℓ` does not exist (`(l₀, l₁) = 0` or not finite: the 3-D line passes through the
/// camera centre) or `cov` is singular.
pub fn endpoint_residual(
    lens: &Camera,
    l: &Vector3<f64>,
    start: &Vector2<f64>,
    e: &Vector2<f64>,
    cov: &Matrix2<f64>,
) -> Option<EndpointResidual> {
    let l12 = Vector2::new(l.x, l.y);
    let norm2 = l12.norm_squared();
    if !(norm2 > 0.0 && norm2.is_finite() && l.z.is_finite()) {
        return None;
    }
    let info = cov.try_inverse()?;
    let dir = Vector2::new(-l.y, l.x) / norm2.sqrt();
    let foot = start - l12 * ((l12.dot(start) + l.z) / norm2);
    let (q, u, du) = nearest_on_curve(lens, &foot, &dir, e, &info);
    // The normal of the curve (for D = I, along the pixel line's (l̄₁, l̄₂) when fx, fy > 0).
    let n = Vector2::new(du.y, -du.x);
    let eta = n / n.dot(&(cov * n)).sqrt();
    Some(EndpointResidual {
        q,
        eta,
        residual: eta.dot(&(u - e)),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::CameraModel;
    use crate::rng::Rng;

    #[test]
    fn without_distortion_the_curve_residual_is_the_closed_form_one() {
        // A PINHOLE lens through the search, and K through the closed form: the same signed residual
        // and the same ∂r/∂l, for anisotropic covariances (values of ~1e2 px: rounding ~1e-12).
        let lens = Camera::new(CameraModel::Pinhole, &[800.0, 780.0, 320.0, 240.0]).unwrap();
        let k_inverse = lens.intrinsics().matrix().try_inverse().unwrap();
        let mut rng = Rng::new(5);
        for _ in 0..200 {
            let l = Vector3::new(rng.normal(), rng.normal(), rng.normal() * 0.3);
            let e = Vector2::new(rng.uniform_in(0.0, 640.0), rng.uniform_in(0.0, 480.0));
            let a = Matrix2::new(
                rng.uniform_in(0.5, 2.0),
                rng.normal() * 0.3,
                0.0,
                rng.uniform_in(0.5, 2.0),
            );
            let cov = a * a.transpose();
            let n = (k_inverse * Vector3::new(e.x, e.y, 1.0)).xy();
            let fit = endpoint_residual(&lens, &l, &n, &e, &cov).unwrap();
            let (r, grad) = pinhole_endpoint_residual(&k_inverse, &l, &e, &cov).unwrap();
            assert!(
                (fit.residual - r).abs() <= 1e-9 * (1.0 + r.abs()),
                "{} vs {r}",
                fit.residual
            );
            let g = fit.line_gradient(&lens, &l);
            assert!((g - grad).norm() <= 1e-7 * (1.0 + grad.norm()), "{g} vs {grad}");
        }
    }
}
