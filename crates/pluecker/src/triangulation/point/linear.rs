//! The linear (DLT) triangulation of a point (Hartley & Zisserman, section 12.2), with conditioning.
//!
//! Each view contributes the two rows `W = L [p₁ − u p₃; p₂ − v p₃]` of [`PointView`] (the
//! numerators of eq. 16, whitened by eq. 18): `W X̃ = 0` for the true point. The point is the least
//! right singular vector of the stacked rows, i.e. the eigenvector of the least eigenvalue of the 4x4
//! Gram matrix `Σ BᵢᵀBᵢ` of the conditioned rows `Bᵢ`.
//!
//! Conditioning (the role of Hartley's normalisation): the world is translated to the centroid `C̄` of
//! the camera centres and scaled by their RMS distance `s` to it (`WorldFrame`), `X = C̄ + s X'`;
//! each view's row pair is divided by the Frobenius norm of its 3x3 part, so that every view counts
//! alike whatever its focal length, covariance scale or the arbitrary scale of its `P`. A solution
//! with a (relatively) zero fourth coordinate is a point at infinity: parallel rays.

use super::cost::PointView;
use nalgebra::{Matrix2x4, Matrix3x4, Matrix4, Vector3, Vector4};

/// `|X̃₄| ≤ AT_INFINITY · ‖X̃‖` (conditioned coordinates) is a point at infinity: a point
/// `10¹²` camera spreads away, beyond what double precision can place.
const AT_INFINITY: f64 = 1e-12;

/// A similarity `X = centre + scale · X'` that conditions the DLT (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct WorldFrame {
    /// `C̄`, the centroid of the camera centres (world units).
    pub centre: Vector3<f64>,
    /// `s`, the RMS distance of the centres to `C̄` (world units, > 0 when the centres differ).
    pub scale: f64,
}

impl WorldFrame {
    /// The frame of a set of camera centres.
    pub(crate) fn from_centres(centres: &[Vector3<f64>]) -> WorldFrame {
        let n = centres.len().max(1) as f64;
        let centre = centres.iter().sum::<Vector3<f64>>() / n;
        let scale = (centres.iter().map(|c| (c - centre).norm_squared()).sum::<f64>() / n).sqrt();
        WorldFrame {
            centre,
            scale: if scale > 0.0 { scale } else { 1.0 },
        }
    }
}

/// The result of the DLT.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum LinearPoint {
    /// A finite point (world coordinates).
    Finite(Vector3<f64>),
    /// A point at infinity in this (unit) world direction.
    AtInfinity(Vector3<f64>),
}

/// Adds the conditioned rows of one view to the Gram matrix `g`.
pub(crate) fn accumulate_dlt(g: &mut Matrix4<f64>, view: &PointView, frame: &WorldFrame) {
    let a = view.a();
    let norm = a.norm();
    if !(norm > 0.0) {
        return;
    }
    // B = W H / (s ‖A‖) with H = [[s I, C̄], [0, 1]]: B = [A / ‖A‖, W (C̄, 1) / (s ‖A‖)].
    let offset = view.numerator(&frame.centre) / (frame.scale * norm);
    let b = Matrix2x4::from_columns(&[a.column(0) / norm, a.column(1) / norm, a.column(2) / norm, offset]);
    *g += b.transpose() * b;
}

/// The unit eigenvector of the least eigenvalue of a symmetric positive semi-definite 4x4 matrix:
/// inverse iteration (four solves with one Cholesky factorisation of `G + δI`, `δ` a few ulps of
/// the trace, started from the column of `G⁻¹` with the largest diagonal), checked by its residual,
/// else cyclic Jacobi rotations. Both are accurate to rounding in the eigenvector when the least
/// eigenvalue is separated (an implicit QR iteration was measured to lose half the digits).
pub(crate) fn least_eigenvector(g: &Matrix4<f64>) -> Vector4<f64> {
    let shift = 16.0 * f64::EPSILON * g.trace().abs();
    if let Some(chol) = (g + Matrix4::identity() * shift).cholesky() {
        let inverse = chol.inverse();
        let k = (0..4)
            .max_by(|&i, &j| inverse[(i, i)].total_cmp(&inverse[(j, j)]))
            .unwrap_or(3);
        let mut v: Vector4<f64> = inverse.column(k).into_owned();
        for _ in 0..3 {
            v = inverse * (v / v.norm());
        }
        let v = v / v.norm();
        let gv = g * v;
        if v.iter().all(|x| x.is_finite()) && (gv - v * v.dot(&gv)).norm() <= INVERSE_ITERATION_RESIDUAL * g.norm() {
            return v;
        }
    }
    jacobi_least_eigenvector(g)
}

/// Inverse iteration is accepted when `‖Gv − (vᵀGv)v‖ ≤ this · ‖G‖`.
const INVERSE_ITERATION_RESIDUAL: f64 = 1e-14;

/// [`least_eigenvector`] by cyclic Jacobi rotations.
fn jacobi_least_eigenvector(g: &Matrix4<f64>) -> Vector4<f64> {
    let mut a = *g;
    let mut v = Matrix4::<f64>::identity();
    // Off-diagonal entries below ε² ‖G‖ move an eigenvector by ε² ‖G‖ / gap: negligible. The
    // convergence is quadratic, so about six sweeps get there.
    let negligible = f64::EPSILON * f64::EPSILON * g.norm();
    for _ in 0..JACOBI_SWEEPS {
        let mut rotated = false;
        for p in 0..4 {
            for q in p + 1..4 {
                let apq = a[(p, q)];
                if apq.abs() <= negligible {
                    continue;
                }
                rotated = true;
                let theta = (a[(q, q)] - a[(p, p)]) / (2.0 * apq);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                // A ← Jᵀ A J with the rotation J in the (p, q) plane that zeroes a_pq exactly
                // (Numerical Recipes' update), and V ← V J.
                a[(p, p)] -= t * apq;
                a[(q, q)] += t * apq;
                a[(p, q)] = 0.0;
                a[(q, p)] = 0.0;
                for r in (0..4).filter(|&r| r != p && r != q) {
                    let (arp, arq) = (a[(r, p)], a[(r, q)]);
                    a[(r, p)] = c * arp - s * arq;
                    a[(r, q)] = s * arp + c * arq;
                    a[(p, r)] = a[(r, p)];
                    a[(q, r)] = a[(r, q)];
                }
                for k in 0..4 {
                    let (vkp, vkq) = (v[(k, p)], v[(k, q)]);
                    v[(k, p)] = c * vkp - s * vkq;
                    v[(k, q)] = s * vkp + c * vkq;
                }
            }
        }
        if !rotated {
            break;
        }
    }
    let k = (0..4).min_by(|&i, &j| a[(i, i)].total_cmp(&a[(j, j)])).unwrap_or(3);
    v.column(k).into_owned()
}

/// Sweeps of [`least_eigenvector`] (convergence is quadratic; 4x4 needs about 5).
const JACOBI_SWEEPS: usize = 30;

/// The DLT solution from the Gram matrix of [`accumulate_dlt`].
pub(crate) fn solve_dlt(g: &Matrix4<f64>, frame: &WorldFrame) -> LinearPoint {
    let v = least_eigenvector(g);
    if v.w.abs() <= AT_INFINITY * v.norm() {
        let d = v.xyz();
        return LinearPoint::AtInfinity(d / d.norm());
    }
    LinearPoint::Finite(frame.centre + v.xyz() * (frame.scale / v.w))
}

/// The DLT point of the views (see the module docs).
pub(crate) fn linear_point(views: &[PointView], frame: &WorldFrame) -> LinearPoint {
    let mut g = Matrix4::zeros();
    for v in views {
        accumulate_dlt(&mut g, v, frame);
    }
    solve_dlt(&g, frame)
}

/// The conditioning frame of a set of (finite) cameras.
pub(crate) fn frame_of_cameras(cameras: &[Matrix3x4<f64>]) -> WorldFrame {
    let centres: Vec<Vector3<f64>> = cameras.iter().map(crate::triangulation::views::centre).collect();
    WorldFrame::from_centres(&centres)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::triangulation::point::cost::point_views;
    use crate::triangulation::views::depth_normalized;
    use nalgebra::{Matrix2, Matrix3, Vector2};

    fn camera(centre: Vector3<f64>, scale: f64) -> Matrix3x4<f64> {
        let k = Matrix3::new(700.0, 0.0, 300.0, 0.0, 700.0, 200.0, 0.0, 0.0, 1.0);
        let mut rt = Matrix3x4::identity();
        rt.set_column(3, &-centre);
        k * rt * scale
    }

    #[test]
    fn recovers_a_far_point_exactly_and_detects_parallel_rays() {
        let cams = [
            camera(Vector3::new(0.0, 0.0, 0.0), 1.0),
            camera(Vector3::new(1e-3, 0.0, 0.0), -5.0),
        ];
        let truth = Vector3::new(0.3, -0.2, 50.0);
        let project = |p: &Matrix3x4<f64>, x: &Vector3<f64>| {
            let h = p * Vector4::new(x.x, x.y, x.z, 1.0);
            Vector2::new(h.x / h.z, h.y / h.z)
        };
        let ps: Vec<Matrix3x4<f64>> = cams.iter().map(depth_normalized).collect();
        let obs: Vec<Vector2<f64>> = cams.iter().map(|p| project(p, &truth)).collect();
        let views = point_views(&ps, &obs, &[Matrix2::identity(); 2]);
        let frame = frame_of_cameras(&cams);
        let LinearPoint::Finite(x) = linear_point(&views, &frame) else {
            panic!("finite expected")
        };
        // Depth 5e4 baselines: the triangulation angle is 2e-5 rad, so relative accuracy ~ ε / 2e-5.
        assert!((x - truth).norm() < 1e-7 * truth.norm(), "{x} vs {truth}");
        // The same pixel in two translated cameras: parallel rays.
        let same = vec![obs[0], obs[0]];
        let views = point_views(&ps, &same, &[Matrix2::identity(); 2]);
        assert!(matches!(linear_point(&views, &frame), LinearPoint::AtInfinity(_)));
    }

    #[test]
    fn jacobi_finds_the_least_eigenvector_of_random_symmetric_matrices() {
        let mut rng = crate::rng::Rng::new(3);
        for _ in 0..200 {
            let b = nalgebra::Matrix4::from_fn(|_, _| rng.normal());
            let g = b.transpose() * b;
            let v = least_eigenvector(&g);
            let lambda = v.dot(&(g * v));
            let eig = nalgebra::SymmetricEigen::new(g);
            assert!((v.norm() - 1.0).abs() < 1e-14);
            assert!((g * v - v * lambda).norm() < 1e-13 * g.norm());
            assert!((lambda - eig.eigenvalues.min()).abs() < 1e-10 * g.norm());
        }
    }
}
