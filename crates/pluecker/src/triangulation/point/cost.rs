//! The cost of a triangulated point (Josephson & Kahl 2008, eqs. 15-19) and its derivatives.
//!
//! With the depth-normalised camera `P = (p₁, p₂, p₃)ᵀ` ([`crate::triangulation::views::depth_normalized`]: `p₃ᵀX̃`
//! is the depth `z` of `X`, `X̃ = (X, 1)`), the observation `(u, v)` and the whitening factor `L`
//! (eq. 18), the residual of eqs. 16-17 is
//! `r(X) = L (p₁ᵀX̃/z − u, p₂ᵀX̃/z − v) = W X̃ / z`, `W = L [p₁ − u p₃; p₂ − v p₃]` (2x4),
//! and the cost is eq. 19, `f(X) = Σᵢ ‖rᵢ(X)‖²` in squared whitened pixels (pixels without a
//! covariance). Writing `A = W[:, :3]` and `c = p₃[:3]` (`∂z/∂X = c`, `‖c‖ = 1`):
//! - Jacobian: `∂r/∂X = (A − r cᵀ)/z`;
//! - Hessian of one term: `∇²‖r‖² = (2/z²) [(A − 2 r cᵀ)ᵀ(A − 2 r cᵀ) − ‖r‖² c cᵀ]`
//!   (expand `‖a + τα‖²/(z + τβ)²` to second order in `τ`; checked by finite differences below).

use crate::optim::{Linearization, Objective};
use nalgebra::{Matrix2, Matrix2x3, Matrix2x4, Matrix3, Matrix3x4, Vector2, Vector3, Vector4};

/// One view of a point: the whitened numerator rows `W` and the depth row `p₃` (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointView {
    /// `W = L [p₁ − u p₃; p₂ − v p₃]`, 2x4, whitened pixels per unit depth.
    pub w: Matrix2x4<f64>,
    /// `p₃ = (c, d)`: `p₃ᵀX̃` is the depth of `X` (world units), `‖c‖ = 1`.
    pub depth_row: Vector4<f64>,
}

impl PointView {
    /// The view of observation `x` (pixels) by the depth-normalised camera `p`, whitened by `l`.
    pub fn new(p: &Matrix3x4<f64>, x: &Vector2<f64>, l: &Matrix2<f64>) -> PointView {
        let p3 = p.row(2).transpose();
        let rows = Matrix2x4::from_rows(&[
            (p.row(0).transpose() - x.x * p3).transpose(),
            (p.row(1).transpose() - x.y * p3).transpose(),
        ]);
        PointView {
            w: l * rows,
            depth_row: p3,
        }
    }

    /// `A = W[:, :3]`.
    pub fn a(&self) -> Matrix2x3<f64> {
        self.w.fixed_view::<2, 3>(0, 0).into_owned()
    }

    /// `c = p₃[:3]`, the unit viewing direction of the camera's principal axis.
    pub fn c(&self) -> Vector3<f64> {
        self.depth_row.xyz()
    }

    /// The depth `z(X) = p₃ᵀX̃`, world units.
    pub fn depth(&self, x: &Vector3<f64>) -> f64 {
        self.depth_row.xyz().dot(x) + self.depth_row.w
    }

    /// The whitened numerator `W X̃` (eq. 16 times the depth).
    pub(crate) fn numerator(&self, x: &Vector3<f64>) -> Vector2<f64> {
        self.a() * x + self.w.column(3)
    }

    /// The whitened residual `r(X) = W X̃ / z` (eqs. 17-18), pixels.
    pub fn residual(&self, x: &Vector3<f64>) -> Vector2<f64> {
        self.numerator(x) / self.depth(x)
    }

    /// The whitened residual `r` and the information `JᵀJ = BᵀB/z²` of this view (`J = ∂r/∂X`,
    /// `B = A − r cᵀ`, module docs) at depth `z ≠ 0`: one division and the 6 distinct entries of the
    /// symmetric product, for the covariances of [`crate::triangulation::uncertainty`].
    #[inline]
    pub(crate) fn residual_and_information(&self, x: &Vector3<f64>) -> (Vector2<f64>, Matrix3<f64>) {
        let inv = 1.0 / self.depth(x);
        let r = self.numerator(x) * inv;
        let c = self.c();
        let (mut h00, mut h01, mut h02, mut h11, mut h12, mut h22) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        for k in 0..2 {
            let b = Vector3::new(
                self.w[(k, 0)] - r[k] * c.x,
                self.w[(k, 1)] - r[k] * c.y,
                self.w[(k, 2)] - r[k] * c.z,
            );
            h00 += b.x * b.x;
            h01 += b.x * b.y;
            h02 += b.x * b.z;
            h11 += b.y * b.y;
            h12 += b.y * b.z;
            h22 += b.z * b.z;
        }
        let s = inv * inv;
        (r, Matrix3::new(h00, h01, h02, h01, h11, h12, h02, h12, h22) * s)
    }

    /// The whitened residual and its Jacobian `∂r/∂X = (A − r cᵀ)/z` (module docs), at depth `z ≠ 0`.
    #[inline]
    pub(crate) fn residual_and_jacobian(&self, x: &Vector3<f64>) -> (Vector2<f64>, Matrix2x3<f64>) {
        let z = self.depth(x);
        let r = self.numerator(x) / z;
        (r, (self.a() - r * self.c().transpose()) / z)
    }
}

/// The views of one track: depth-normalised cameras (see [`crate::triangulation::views::depth_normalized`]),
/// observations (pixels) and whitening factors (eq. 18).
pub fn point_views(
    cameras: &[Matrix3x4<f64>],
    observations: &[Vector2<f64>],
    whitenings: &[Matrix2<f64>],
) -> Vec<PointView> {
    cameras
        .iter()
        .zip(observations)
        .zip(whitenings)
        .map(|((p, x), l)| PointView::new(p, x, l))
        .collect()
}

/// The cost of eq. 19, `Σ ‖rᵢ(X)‖²`, squared whitened pixels.
pub fn point_cost(views: &[PointView], x: &Vector3<f64>) -> f64 {
    views.iter().map(|v| v.residual(x).norm_squared()).sum()
}

/// True when `X` is strictly in front of every camera (positive depth in every view).
pub fn in_front(views: &[PointView], x: &Vector3<f64>) -> bool {
    views.iter().all(|v| v.depth(x) > 0.0)
}

/// The Hessian of `‖r(X)‖²` for one view at `X` (module docs), whose depth there is `z`.
pub(crate) fn term_hessian(view: &PointView, x: &Vector3<f64>) -> Matrix3<f64> {
    let z = view.depth(x);
    let r = view.numerator(x) / z;
    let c = view.c();
    let b = view.a() - 2.0 * r * c.transpose();
    (b.transpose() * b - r.norm_squared() * c * c.transpose()) * (2.0 / (z * z))
}

/// Eq. 19 as a least-squares problem for [`crate::optim`]: `½ Σ ‖rᵢ(X)‖²` over `X ∈ ℝ³` (the
/// solvers' cost is half the triangulation cost).
#[derive(Debug, Clone, Copy)]
pub struct PointObjective<'a> {
    /// The views of the track.
    pub views: &'a [PointView],
}

impl Objective<3> for PointObjective<'_> {
    type Point = Vector3<f64>;

    fn cost(&self, x: &Vector3<f64>) -> f64 {
        0.5 * point_cost(self.views, x)
    }

    fn linearize(&self, x: &Vector3<f64>) -> Linearization<3> {
        let mut lin = Linearization::zero();
        for v in self.views {
            let (r, j) = v.residual_and_jacobian(x);
            lin.add(&r, &j);
        }
        lin
    }

    fn exact_hessian(&self, x: &Vector3<f64>) -> Option<Matrix3<f64>> {
        Some(self.views.iter().map(|v| 0.5 * term_hessian(v, x)).sum())
    }

    fn retract(&self, x: &Vector3<f64>, d: &Vector3<f64>) -> Vector3<f64> {
        x + d
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optim::problem::testing::{gradient_error, hessian_error};
    use crate::triangulation::views::depth_normalized;

    fn views() -> Vec<PointView> {
        let k = Matrix3::new(800.0, 2.0, 320.0, 0.0, 790.0, 240.0, 0.0, 0.0, 1.0);
        let cams = [
            Matrix3x4::new(1.0, 0.0, 0.0, 0.3, 0.0, 1.0, 0.0, -0.1, 0.0, 0.0, 1.0, 5.0),
            Matrix3x4::new(0.8, 0.0, -0.6, 0.2, 0.0, 1.0, 0.0, 0.4, 0.6, 0.0, 0.8, 4.0),
        ];
        let obs = [Vector2::new(300.0, 250.0), Vector2::new(410.0, 220.0)];
        let ls = [Matrix2::new(1.3, 0.0, 0.4, 0.7), Matrix2::identity()];
        let ps: Vec<Matrix3x4<f64>> = cams.iter().map(|c| depth_normalized(&(k * c * -2.0))).collect();
        point_views(&ps, &obs, &ls)
    }

    #[test]
    fn residual_is_the_whitened_pixel_error() {
        let k = Matrix3::new(800.0, 0.0, 320.0, 0.0, 800.0, 240.0, 0.0, 0.0, 1.0);
        let p = k * Matrix3x4::new(1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 2.0);
        let x = Vector3::new(0.1, -0.2, 2.0);
        let projected = Vector2::new(320.0 + 800.0 * 0.1 / 4.0, 240.0 - 800.0 * 0.2 / 4.0);
        let obs = projected + Vector2::new(1.5, -0.5);
        let l = Matrix2::new(2.0, 0.0, 1.0, 3.0);
        let v = PointView::new(&depth_normalized(&(p * 7.0)), &obs, &l);
        assert!((v.residual(&x) - l * (projected - obs)).norm() < 1e-12);
        assert!((v.depth(&x) - 4.0).abs() < 1e-12);
    }

    #[test]
    fn information_is_the_jacobian_product() {
        for v in views() {
            let x = Vector3::new(-0.4, 0.3, 1.5);
            let (r, j) = v.residual_and_jacobian(&x);
            let (r2, h) = v.residual_and_information(&x);
            assert!((r - r2).norm() < 1e-12 * r.norm() && (h - j.transpose() * j).norm() < 1e-12 * h.norm());
        }
    }

    #[test]
    fn gradient_and_hessians_match_finite_differences() {
        let vs = views();
        let obj = PointObjective { views: &vs };
        for x in [
            Vector3::new(0.0, 0.0, 0.5),
            Vector3::new(-0.4, 0.3, 1.5),
            Vector3::new(1.0, -1.0, 3.0),
        ] {
            assert!(
                gradient_error(&obj, &x, 1e-6) < 1e-6,
                "{}",
                gradient_error(&obj, &x, 1e-6)
            );
            assert!(
                hessian_error(&obj, &x, 1e-6) < 1e-5,
                "{}",
                hessian_error(&obj, &x, 1e-6)
            );
        }
    }
}
