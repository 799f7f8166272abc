//! Covariance weighting of residuals (Josephson & Kahl 2008, section 3.2, eq. 18), shared by pose and
//! triangulation.
//!
//! An observation with covariance `Σ` (2x2 for points and lines, 5x5 for conics) contributes
//! `‖L r‖² = rᵀ Σ⁻¹ r` to the cost of eq. 19. With the Cholesky factorisation `Σ = C Cᵀ` (`C` lower
//! triangular), `L = C⁻¹` is lower triangular and `Lᵀ L = Σ⁻¹`: the paper's "Cholesky factor of the
//! inverse covariance". No covariance means `Σ = I` and `L = I`.

use crate::error::{Error, Result};
use nalgebra::SMatrix;

/// Relative asymmetry `max|Σ − Σᵀ| / max|Σ|` above which a covariance is rejected.
const SYMMETRY_TOLERANCE: f64 = 1e-9;
/// Smallest accepted ratio of the least to the largest Cholesky pivot (squared: a condition number
/// of 1e24 is numerically singular in double precision).
const PIVOT_RATIO: f64 = 1e-12;
/// Smallest accepted Cholesky pivot, `1/√f64::MAX`: below it `Σ⁻¹` (entries up to `1/pivot²`)
/// overflows, and the whitened cost with it (`5e-324 I` gave NaN estimates).
const MIN_PIVOT: f64 = 7.458_340_731_200_208e-155;

/// The whitening factor `L = C⁻¹` of one covariance `Σ = C Cᵀ` (see the module docs).
///
/// Errors with [`Error::NonFinite`] on NaN/inf and [`Error::Degenerate`] when `Σ` is not symmetric
/// positive definite; `what` names the argument and `index` the observation in the message.
pub fn whitening<const D: usize>(cov: &SMatrix<f64, D, D>, what: &str, index: usize) -> Result<SMatrix<f64, D, D>> {
    if cov.iter().any(|v| !v.is_finite()) {
        return Err(Error::NonFinite {
            what: what.into(),
            index,
        });
    }
    let scale = cov.amax();
    if (cov - cov.transpose()).amax() > SYMMETRY_TOLERANCE * scale {
        return Err(Error::Degenerate {
            what: format!("{what}[{index}] is not symmetric"),
        });
    }
    let not_pd = || Error::Degenerate {
        what: format!("{what}[{index}] is not positive definite"),
    };
    let chol = cov.cholesky().ok_or_else(not_pd)?;
    let c = chol.l();
    let pivots = c.diagonal();
    let (lo, hi) = (pivots.min(), pivots.max());
    if !(lo > PIVOT_RATIO * hi) {
        return Err(not_pd());
    }
    if !(lo >= MIN_PIVOT) {
        return Err(Error::Degenerate {
            what: format!(
                "{what}[{index}] is too small to invert in double precision (Cholesky pivot {lo:e} < {MIN_PIVOT:e}: Σ⁻¹ overflows)"
            ),
        });
    }
    c.solve_lower_triangular(&SMatrix::<f64, D, D>::identity())
        .ok_or_else(not_pd)
}

/// Whitening factors of every observation: identities when `covariances` is `None`, else one per
/// row (the caller has checked the count).
pub(crate) fn whitenings<const D: usize>(
    covariances: Option<&[SMatrix<f64, D, D>]>,
    count: usize,
    what: &str,
) -> Result<Vec<SMatrix<f64, D, D>>> {
    match covariances {
        None => Ok(vec![SMatrix::<f64, D, D>::identity(); count]),
        Some(covs) => {
            if covs.len() != count {
                return Err(Error::Shape {
                    what: what.into(),
                    expected: format!("{count} covariances (one per view)"),
                    actual: format!("{}", covs.len()),
                });
            }
            covs.iter().enumerate().map(|(i, c)| whitening(c, what, i)).collect()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix2, Vector2};

    #[test]
    fn whitened_norm_is_the_mahalanobis_norm() {
        let cov = Matrix2::new(4.0, 1.2, 1.2, 0.9);
        let l = whitening(&cov, "cov", 0).unwrap();
        let r = Vector2::new(0.7, -1.9);
        let mahalanobis = r.dot(&(cov.try_inverse().unwrap() * r));
        assert!(((l * r).norm_squared() - mahalanobis).abs() < 1e-12 * mahalanobis);
        assert_eq!(l[(0, 1)], 0.0, "L is lower triangular");
    }

    #[test]
    fn rejects_indefinite_asymmetric_and_non_finite() {
        let indefinite = Matrix2::new(1.0, 2.0, 2.0, 1.0);
        assert!(matches!(whitening(&indefinite, "cov", 3), Err(Error::Degenerate { what }) if what.contains("cov[3]")));
        assert!(whitening(&Matrix2::new(1.0, 0.5, 0.0, 1.0), "cov", 0).is_err());
        assert!(matches!(
            whitening(&Matrix2::new(f64::NAN, 0.0, 0.0, 1.0), "cov", 1),
            Err(Error::NonFinite { index: 1, .. })
        ));
        assert!(whitening(&Matrix2::new(1.0, 0.0, 0.0, 0.0), "cov", 0).is_err());
    }

    #[test]
    fn rejects_a_covariance_whose_inverse_overflows() {
        assert_eq!(MIN_PIVOT, 1.0 / f64::MAX.sqrt());
        let tiny = Matrix2::identity() * 5e-324;
        assert!(
            matches!(whitening(&tiny, "cov", 2), Err(Error::Degenerate { what }) if what.contains("cov[2] is too small"))
        );
        let smallest = Matrix2::identity() * (MIN_PIVOT * MIN_PIVOT * 1.01);
        let l = whitening(&smallest, "cov", 0).unwrap();
        assert!(l.iter().all(|v| v.is_finite()) && (l.transpose() * l).iter().all(|v| v.is_finite()));
    }
}
