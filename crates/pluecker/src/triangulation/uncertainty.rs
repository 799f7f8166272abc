//! First-order covariance of a triangulated point, line or quadric, propagated from the covariances of
//! the observations (Josephson & Kahl 2008, eqs. 17-19).
//!
//! **What is computed.** Observation `i` has the covariance `Σᵢ` of its residual `rᵢ` of eq. 17: 2x2
//! pixels² for a point, 2x2 for an image line and 5x5 for a conic (in the units of
//! `line::residual` / `quadric::residual`, e.g. from [`super::fitting`]). Its whitening
//! `Lᵢ` (eq. 18, `LᵢᵀLᵢ = Σᵢ⁻¹`) makes the stacked whitened residuals `ρ = (L₁r₁, …, Lₙrₙ)` of identity
//! covariance. At the returned estimate `θ̂`, with a minimal chart `δ ↦ θ(δ)`, `θ(0) = θ̂`, and
//! `J = ∂ρ/∂δ` at `δ = 0`, the covariance of the estimate in the chart is the first-order
//!
//! `Σ_δ = (JᵀJ)⁻¹`,
//!
//! the inverse of the Gauss-Newton Hessian of `½` eq. 19. The given covariances carry the scale: the
//! result is not rescaled by the cost reached (no a-posteriori variance factor). **Without
//! covariances** every `Σᵢ = I`: 1 px isotropic noise for points; for lines 1 px of offset and
//! `1/D` rad (`D` = `line::residual::LINE_FRAME_DISTANCE`) of angle; for conics unit variance
//! on each of the 5 residual entries (px² and px) — give covariances for lines and conics. It is
//! evaluated at whatever estimate the method returned: for `linear` that is the maximum-likelihood
//! covariance at the linear answer, not the covariance of the linear estimator itself. First-order
//! theory holds while the noise moves the estimate little compared with the curvature of the
//! problem: a point at low parallax gets a large, correct covariance, but its estimates are skewed
//! along the ray (an `O(σ²)` bias) once the depth error is a sizeable fraction of the depth.
//!
//! The covariances themselves are computed beside each primitive: `point_covariance` in
//! [`super::point`], `line_covariance` in [`super::line`], `quadric_covariance` in [`super::quadric`].
//!
//! **Charts** (the order of the rows and columns):
//! - point: `X` itself, 3x3, world units²;
//! - line: [`LineChart`](crate::geometry::plucker::LineChart) `(α₁, α₂, t₁, t₂)` pivoted at the point of the line closest to the world
//!   origin, 4x4 (`α` dimensionless, `t` world units); [`LineChart::plucker_covariance`](crate::geometry::plucker::LineChart::plucker_covariance) and
//!   [`LineChart::point_direction_covariance`](crate::geometry::plucker::LineChart::point_direction_covariance) map it to 6x6 forms;
//! - quadric: [`CentreShape`](crate::geometry::CentreShape) `(c₁, c₂, c₃, S₁₁, S₁₂, S₁₃, S₂₂, S₂₃, S₃₃)`, 9x9 (world units, units²):
//!   the ellipsoid is estimated as a real ellipsoid (9 dof); this chart of the normalised dual quadric
//!   stays regular for spheres and spheroids (where axes and semi-axes are not), and for flat ones.
//!   For a flat estimate (a semi-axis 0) the estimate lies on the boundary `S ⪰ 0` of the set searched,
//!   and the covariance is that of the unconstrained quadric: an upper bound in the flat direction.
//!
//! **`None`** when the estimate is not finite or when `JᵀJ` — in a chart scaled to the primitive
//! (lines: translations in units of the distance to the cameras; quadrics: units of the ellipsoid's
//! size) — is numerically singular: not positive definite, or `‖H‖_F ‖H⁻¹‖_F >` [`MAX_CONDITION`]
//! (the smallest eigenvalue would keep fewer than about 4 significant digits). The data then do not
//! determine some direction of the chart to first order: a point at infinity (parallel rays, or a
//! parallax below about 1e-6 rad, as `‖H‖‖H⁻¹‖` grows like 1/parallax²), a line in an epipolar plane of
//! every pair of views, a quadric seen by cameras that leave a family of quadrics tangent to every cone.

use nalgebra::{Matrix3, SMatrix};

/// Largest accepted `‖H‖_F ‖H⁻¹‖_F` of an information matrix `H = JᵀJ` (between the 2-norm condition
/// number and `N` times it).
pub const MAX_CONDITION: f64 = 1e12;

/// The 9x9 covariance of a quadric in the [`CentreShape`](crate::geometry::CentreShape) chart.
pub type QuadricCovariance = SMatrix<f64, 9, 9>;

/// `H⁻¹` for a symmetric information matrix `H = JᵀJ`, or `None` when it is not finite, not positive
/// definite, or `‖H‖_F ‖H⁻¹‖_F > MAX_CONDITION` (module docs). The result is symmetrised.
pub(crate) fn covariance_of_information<const N: usize>(info: &SMatrix<f64, N, N>) -> Option<SMatrix<f64, N, N>> {
    if !info.iter().all(|v| v.is_finite()) {
        return None;
    }
    // Cholesky only decides positive definiteness; the closed-form inverse of nalgebra (N ≤ 4, LU
    // beyond) is several times cheaper than solving with the factor.
    info.cholesky()?;
    let inverse = info.try_inverse()?;
    let condition = info.norm() * inverse.norm();
    (condition.is_finite() && condition <= MAX_CONDITION).then(|| 0.5 * (inverse + inverse.transpose()))
}

/// [`covariance_of_information`] for 3x3, in closed form (the batches call it once per point):
/// positive definite by Sylvester's criterion (leading minors `h₁₁`, `h₁₁h₂₂ − h₁₂²`, `det H` all
/// positive), `H⁻¹ = adj(H)/det H`, the same condition test.
pub(crate) fn covariance_of_information3(h: &Matrix3<f64>) -> Option<Matrix3<f64>> {
    let minor2 = h[(0, 0)] * h[(1, 1)] - h[(0, 1)] * h[(1, 0)];
    let (c00, c01, c02) = (
        h[(1, 1)] * h[(2, 2)] - h[(1, 2)] * h[(2, 1)],
        h[(1, 2)] * h[(2, 0)] - h[(1, 0)] * h[(2, 2)],
        h[(1, 0)] * h[(2, 1)] - h[(1, 1)] * h[(2, 0)],
    );
    let det = h[(0, 0)] * c00 + h[(0, 1)] * c01 + h[(0, 2)] * c02;
    // Written so that NaN fails every test.
    if !(h[(0, 0)] > 0.0 && minor2 > 0.0 && det > 0.0 && det.is_finite()) {
        return None;
    }
    let c11 = h[(0, 0)] * h[(2, 2)] - h[(0, 2)] * h[(2, 0)];
    let c12 = h[(0, 1)] * h[(2, 0)] - h[(0, 0)] * h[(2, 1)];
    let inverse = Matrix3::new(c00, c01, c02, c01, c11, c12, c02, c12, minor2) / det;
    let condition = h.norm() * inverse.norm();
    (condition.is_finite() && condition <= MAX_CONDITION).then_some(inverse)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix2, Vector3};

    #[test]
    fn closed_form_3x3_agrees_with_the_general_inverse() {
        let mut rng = crate::rng::Rng::new(5);
        for scale in [1.0, 1e-3, 1e5] {
            let a = Matrix3::from_fn(|_, _| rng.normal());
            let h = (a * a.transpose() + Matrix3::identity() * 0.1) * scale;
            let general = covariance_of_information(&h).unwrap();
            let closed = covariance_of_information3(&h).unwrap();
            assert!((general - closed).norm() <= 1e-10 * general.norm());
        }
        let singular = Matrix3::new(1.0, 1.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0, 1.0);
        assert!(covariance_of_information3(&singular).is_none());
        assert!(covariance_of_information3(&Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, 1e-13))).is_none());
        assert!(covariance_of_information3(&Matrix3::from_diagonal(&Vector3::new(1.0, -1.0, -1.0))).is_none());
        assert!(covariance_of_information3(&Matrix3::repeat(f64::NAN)).is_none());
    }

    #[test]
    fn information_inverse_is_checked() {
        let h = Matrix2::new(4.0, 1.0, 1.0, 3.0);
        let c = covariance_of_information(&h).unwrap();
        assert!((c * h - Matrix2::identity()).norm() < 1e-14);
        assert!(covariance_of_information(&Matrix2::new(1.0, 1.0, 1.0, 1.0)).is_none());
        assert!(covariance_of_information(&Matrix2::new(1.0, 0.0, 0.0, 1e-13)).is_none());
        assert!(covariance_of_information(&Matrix2::new(1.0, 0.0, 0.0, 1e-11)).is_some());
        assert!(covariance_of_information(&Matrix2::new(f64::NAN, 0.0, 0.0, 1.0)).is_none());
        assert!(covariance_of_information(&Matrix2::new(-1.0, 0.0, 0.0, 1.0)).is_none());
    }
}
