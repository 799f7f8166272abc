//! The whitened residual of one view as a ratio of linear forms (Josephson & Kahl 2008, eqs. 16-18).
//!
//! For every primitive the residual of eq. 17 in one view is `r(z) = (x_k g(z) − p_kᵀz)_k / g(z)` with
//! `z` the stacked homogeneous coordinates of the primitive (4 for a point, the 6 Plücker coordinates
//! for a line, the 10 entries of a dual quadric), `p_k` the rows of the camera acting on `z`, `x_k` the
//! normalised observation and `g(z) = p_nᵀz` the last coordinate. Whitened by eq. 18 it reads
//! `L r(z) = A z / (cᵀz)` with `A = L (x cᵀ − P)` (`D x K`) and `c = p_n`. The ratio is invariant to the
//! scale of `z` and to a common sign change of `(A, c)`; `FractionalResidual::oriented` uses the
//! latter to make `cᵀz > 0` at a reference primitive, as the fractional program of eq. 20 requires.

use crate::optim::Linearization;
use nalgebra::{SMatrix, SVector};

/// One view's whitened residual `A z / (cᵀz)` (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FractionalResidual<const D: usize, const K: usize> {
    /// `A = L (x cᵀ − P)`, already whitened.
    pub numerator: SMatrix<f64, D, K>,
    /// `c`, the row whose product with `z` is the denominator `g(z)` of eq. 20.
    pub denominator: SVector<f64, K>,
}

impl<const D: usize, const K: usize> FractionalResidual<D, K> {
    /// The residual `W a z / (cᵀ z)` from the unwhitened numerator `a`, the denominator `c` and the
    /// whitening `w` of eq. 18, scaled so that `‖c‖ = 1` (the ratio does not change).
    pub fn new(a: &SMatrix<f64, D, K>, c: &SVector<f64, K>, w: &SMatrix<f64, D, D>) -> Self {
        let scale = c.norm();
        let scale = if scale > 0.0 { 1.0 / scale } else { 1.0 };
        FractionalResidual {
            numerator: w * a * scale,
            denominator: c * scale,
        }
    }

    /// `g(z) = cᵀz`.
    pub fn denominator_at(&self, z: &SVector<f64, K>) -> f64 {
        self.denominator.dot(z)
    }

    /// The whitened residual `L r(z)`.
    pub fn residual(&self, z: &SVector<f64, K>) -> SVector<f64, D> {
        self.numerator * z / self.denominator.dot(z)
    }

    /// The residual and its Jacobian `∂r/∂z = (A − r cᵀ) / (cᵀz)`.
    pub(crate) fn residual_and_jacobian(&self, z: &SVector<f64, K>) -> (SVector<f64, D>, SMatrix<f64, D, K>) {
        let g = self.denominator.dot(z);
        let r = self.numerator * z / g;
        (r, (self.numerator - r * self.denominator.transpose()) / g)
    }

    /// The same residual with `(A, c)` negated if needed so that `cᵀ z_ref ≥ 0`.
    pub(crate) fn oriented(&self, z_ref: &SVector<f64, K>) -> Self {
        if self.denominator.dot(z_ref) < 0.0 {
            FractionalResidual {
                numerator: -self.numerator,
                denominator: -self.denominator,
            }
        } else {
            *self
        }
    }
}

/// The cost of eq. 19, `Σᵢ ‖Lᵢ rᵢ(z)‖²` (no ½).
pub fn cost<const D: usize, const K: usize>(views: &[FractionalResidual<D, K>], z: &SVector<f64, K>) -> f64 {
    views.iter().map(|v| v.residual(z).norm_squared()).sum()
}

/// The Gauss-Newton model of `½ Σ ‖Lᵢ rᵢ(z(x))‖²` at `z` for a parametrisation with tangent
/// Jacobian `dz = ∂z/∂δ` (`K x N`), as the solvers of [`crate::optim`] expect.
pub(crate) fn linearize<const D: usize, const K: usize, const N: usize>(
    views: &[FractionalResidual<D, K>],
    z: &SVector<f64, K>,
    dz: &SMatrix<f64, K, N>,
) -> Linearization<N> {
    let mut lin = Linearization::zero();
    for v in views {
        let (r, j) = v.residual_and_jacobian(z);
        lin.add(&r, &(j * dz));
    }
    lin
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;
    use nalgebra::{Matrix2, Matrix2x4, Vector4};

    #[test]
    fn jacobian_matches_central_differences_and_orientation_keeps_the_residual() {
        let mut rng = Rng::new(31);
        let a = Matrix2x4::from_fn(|_, _| rng.normal());
        let c = Vector4::from_fn(|_, _| rng.normal());
        let w = Matrix2::new(2.0, 0.0, 0.5, 1.0);
        let view = FractionalResidual::new(&a, &c, &w);
        let z = Vector4::from_fn(|_, _| rng.normal());
        let (r, j) = view.residual_and_jacobian(&z);
        assert!((r - w * a * z / c.dot(&z)).norm() < 1e-12 * r.norm());
        let h = 1e-6;
        for k in 0..4 {
            let mut dz = Vector4::zeros();
            dz[k] = h;
            let fd = (view.residual(&(z + dz)) - view.residual(&(z - dz))) / (2.0 * h);
            assert!((fd - j.column(k)).norm() < 1e-6 * (1.0 + j.norm()), "column {k}");
        }
        let flipped = view.oriented(&(-z * (c.dot(&z)).signum()));
        assert!(flipped.denominator_at(&(-z * (c.dot(&z)).signum())) >= 0.0);
        assert!((flipped.residual(&z) - r).norm() < 1e-12 * r.norm());
        // Scale invariance of the ratio.
        assert!((view.residual(&(z * -3.7)) - r).norm() < 1e-12 * r.norm());
    }
}
