//! A cheap sufficient test of global optimality for a triangulated ellipsoid: the test of
//! [`crate::global::convexity`] in an affine chart of dual quadrics, with the ellipsoid constraint
//! (a flat ellipsoid, a disc, sits on its boundary) handled by a Lagrangian bound.
//!
//! **Chart.** In the conditioned frame of the local ellipsoid (origin at its centre, unit its largest
//! semi-axis) the dual quadric is normalised to `L₄₄ = +1`, `L = [ccᵀ − S, c; cᵀ, 1]` (centre `c`,
//! shape `S = R diag(s²) Rᵀ`), and its other 9 entries are `q = q̂ + u`. Every view's residual is
//! `Aᵢ L̃ / (cᵢᵀ L̃)` (eqs. 14, 17-18, [`super::residual`]), a ratio of affine maps of `u`; its
//! denominator `gᵢ = πᵢᵀ L πᵢ` (`πᵢ` the principal plane of camera `i`) is positive exactly when
//! the plane misses the ellipsoid. Dividing by `ĝᵢ` at the local ellipsoid and whitening
//! `u = T y` (`T = VΛ^{-1/2}` from the Gauss-Newton Hessian `ΣBᵢᵀBᵢ = VΛVᵀ` in `u`) gives the chart
//! of [`crate::global::convexity`]: `ζᵢ = gᵢ/ĝᵢ`, and the chart points with every `ζᵢ > 0` are the
//! quadrics with `L₄₄ ≠ 0` that no principal plane meets — among them every ellipsoid, flat or not,
//! that no camera's principal plane cuts, in front of the cameras or behind them.
//!
//! **Ellipsoids only.** Over all quadrics the best fit to the outlines of a disc is often a slightly
//! hyperbolic quadric (the smallest eigenvalue of `S` estimated below 0 from noisy data), cheaper than
//! every ellipsoid: no bound over all quadrics could certify the disc. An ellipsoid has `S ⪰ 0`, so
//! `vᵀSv ≥ 0` for any unit `v`; with `c(u)` and `Q(u)` affine in `u`,
//! `φ(u) = vᵀS(u)v = (vᵀc(u))² − vᵀQ(u)v` is the constraint `(c₀ + kᵀy)² − s₀ − pᵀy ≥ 0` of
//! `crate::global::convexity::Minorant::minimum_subject_to`, which bounds the cost over the
//! chart points that satisfy it (a superset of the ellipsoids). `v` runs over the eigenvectors of the
//! local `S`; the best of the three bounds (each valid) is kept. For a disc the eigenvector of its
//! zero semi-axis makes the constraint active and the bound tight (S-lemma); for a round ellipsoid
//! the constraints are inactive and the bound is the unconstrained one.
//!
//! The test fails (branch and bound, [`super::optimal`], decides) when the local ellipsoid is cut by a
//! principal plane, the data leave a direction of `q` unconstrained, or the enclosure or the Hessian
//! test of [`crate::global::convexity`] fails (large residuals, weak geometry, a second minimum).

use crate::geometry::quadric::vec_to_sym4;
use crate::global::convexity::{minorant, whitening, RatioView};
use crate::triangulation::fractional_residual::FractionalResidual;
use nalgebra::{Matrix3, SMatrix, SVector, SymmetricEigen, Vector3};

/// The whitened chart of the module docs around the stacked frame dual quadric `reference`
/// (`L₄₄ = +1`): its views, and `T`. `None` when a principal plane meets the reference or the
/// Hessian is singular.
fn chart(
    views: &[FractionalResidual<5, 10>],
    reference: &SVector<f64, 10>,
) -> Option<(Vec<RatioView<5, 9>>, SMatrix<f64, 9, 9>)> {
    let mut m = SMatrix::<f64, 9, 9>::zeros();
    let mut at = Vec::with_capacity(views.len());
    for v in views {
        let g = v.denominator_at(reference);
        if !(g > 0.0) {
            return None;
        }
        let r = v.numerator * reference / g;
        let a: SMatrix<f64, 5, 9> = v.numerator.fixed_columns::<9>(0) / g;
        let d: SVector<f64, 9> = v.denominator.fixed_rows::<9>(0) / g;
        let b = a - r * d.transpose();
        m += b.transpose() * b;
        at.push((r, a, d));
    }
    let t = whitening(&m)?;
    let chart_views = at
        .into_iter()
        .map(|(r, a, d)| RatioView {
            a0: r,
            g: a * t,
            d: t.transpose() * d,
        })
        .collect();
    Some((chart_views, t))
}

/// `φ(u) = (c₀ + c₁ᵀu)² − s₀ − q₁ᵀu` for `vᵀS(u)v` at `u = 0` (module docs): `(c₀, c₁, s₀, q₁)`.
fn flatness_constraint(reference: &SVector<f64, 10>, v: &Vector3<f64>) -> (f64, SVector<f64, 9>, f64, SVector<f64, 9>) {
    let parts = |stacked: &SVector<f64, 10>| {
        let l = vec_to_sym4(stacked);
        let c: Vector3<f64> = l.fixed_view::<3, 1>(0, 3).into_owned();
        let q: Matrix3<f64> = l.fixed_view::<3, 3>(0, 0).into_owned();
        (v.dot(&c), v.dot(&(q * v)))
    };
    let (c0, s0) = parts(reference);
    let (mut c1, mut q1) = (SVector::<f64, 9>::zeros(), SVector::<f64, 9>::zeros());
    for j in 0..9 {
        (c1[j], q1[j]) = parts(&SVector::<f64, 10>::ith(j, 1.0));
    }
    (c0, c1, s0, q1)
}

/// The lower bound of the module docs on eq. 19 over every ellipsoid that no principal plane cuts,
/// from the views in the frame (un-oriented, [`super::QuadricProblem::views`]) and the stacked frame
/// dual quadric `reference` of the local ellipsoid (`L₄₄ = +1`); `None` when the test fails.
pub(crate) fn convexity_bound(views: &[FractionalResidual<5, 10>], reference: &SVector<f64, 10>) -> Option<f64> {
    let (chart_views, t) = chart(views, reference)?;
    let m = minorant(&chart_views, None)?;
    let l = vec_to_sym4(reference);
    let c: Vector3<f64> = l.fixed_view::<3, 1>(0, 3).into_owned();
    let shape = c * c.transpose() - l.fixed_view::<3, 3>(0, 0);
    let axes = SymmetricEigen::new(0.5 * (shape + shape.transpose())).eigenvectors;
    let bound = axes
        .column_iter()
        .map(|v| {
            let (c0, c1, s0, q1) = flatness_constraint(reference, &v.into_owned());
            m.minimum_subject_to(c0, &(t.transpose() * c1), s0, &(t.transpose() * q1))
        })
        .fold(m.unconstrained_minimum(), f64::max);
    Some(bound)
}

/// The test hook `triangulation::testing::quadric_convexity_bound`: `convexity_bound` (this module)
/// at the world ellipsoid `at` (any, not only a local minimum), in the frame and with the reference
/// that the quadric's `optimal` search uses; `None` when the conics or covariances are not valid or
/// the test fails.
pub fn convexity_bound_at(
    projections: &[nalgebra::Matrix3x4<f64>],
    conics: &[Matrix3<f64>],
    covariances: Option<&[super::Matrix5]>,
    at: &crate::geometry::quadric::Ellipsoid,
) -> Option<f64> {
    let frames = conics
        .iter()
        .map(super::residual::ConicFrame::of_conic)
        .collect::<Option<Vec<_>>>()?;
    let problem = super::QuadricProblem {
        cameras: projections.to_vec(),
        frames,
        whitenings: crate::covariance::whitenings(covariances, projections.len(), "covariances").ok()?,
    };
    let sim = problem.frame_of(at);
    let frame_dual = super::transform_dual(&sim.matrix(), &at.dual());
    let reference = crate::geometry::quadric::sym4_to_vec(&(-frame_dual / frame_dual[(3, 3)].abs()));
    convexity_bound(&problem.views(&sim), &reference)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::quadric::{sym4_to_vec, Ellipsoid};
    use crate::rng::Rng;
    use nalgebra::{Matrix4, Rotation3};

    #[test]
    fn flatness_constraint_is_the_quadratic_form_of_the_shape() {
        let mut rng = Rng::new(4);
        let e = Ellipsoid {
            centre: Vector3::new(0.2, -0.1, 0.05),
            axes: Rotation3::new(Vector3::new(0.3, -0.2, 0.7)).into_inner(),
            semi_axes: Vector3::new(1.0, 0.6, 0.0),
        };
        let l: Matrix4<f64> = -e.dual();
        let reference = sym4_to_vec(&l);
        let v = rng.unit_vector3();
        let (c0, c1, s0, q1) = flatness_constraint(&reference, &v);
        for _ in 0..20 {
            let u = SVector::<f64, 9>::from_fn(|_, _| 0.1 * rng.normal());
            let mut z = reference;
            for j in 0..9 {
                z[j] += u[j];
            }
            let lu = vec_to_sym4(&z);
            let cu: Vector3<f64> = lu.fixed_view::<3, 1>(0, 3).into_owned();
            let s = cu * cu.transpose() - lu.fixed_view::<3, 3>(0, 0);
            let expected = v.dot(&(s * v));
            let phi = (c0 + c1.dot(&u)).powi(2) - s0 - q1.dot(&u);
            assert!((phi - expected).abs() < 1e-12, "{phi} vs {expected}");
        }
    }
}
