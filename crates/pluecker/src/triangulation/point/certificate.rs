//! A cheap sufficient test of global optimality for a triangulated point: the test of
//! [`crate::global::convexity`] (an enclosure of the sublevel set on which the cost is strongly
//! convex, after Hartley & Seo 2008) in the whitened charts of [`super::chart`] around the local
//! solution `X̂`.
//!
//! A chart point is a point in front of every camera iff every `ζᵢ > 0` (and `w > 0`), so the bound
//! holds over every point in front of all cameras. In the mean-depth chart `Σᵢ ζᵢ = n` identically,
//! so `ζᵢ < n` for points in front of every camera: `κ = n − 1` is an a-priori depth bound whether or
//! not stage 1's `q < 1`. The test runs in the mean-depth chart and, if that fails, in the Euclidean
//! chart. It fails (branch and bound decides) at low parallax in the Euclidean chart, with large
//! residuals, or with a second minimum nearby.

use super::chart::{Chart, ChartKind};
use super::cost::PointView;
use crate::global::convexity::minorant;
use nalgebra::Vector3;

/// The outcome of [`convexity_test`].
#[derive(Debug, Clone, PartialEq)]
pub struct ConvexityCertificate {
    /// True when `μ < 1` in one of the charts: `lower_bound` is then valid for every point in front
    /// of all cameras.
    pub passed: bool,
    /// `ε₀² − ½gᵀH⁻¹g` when `passed`, else 0 (the trivial bound).
    pub lower_bound: f64,
}

/// The a-priori depth bound of a chart (module docs): `κ = n − 1` in the mean-depth chart.
pub(crate) fn a_priori_kappa(chart_kind: ChartKind, views: usize) -> Option<f64> {
    (chart_kind == ChartKind::MeanDepth).then_some(views as f64 - 1.0)
}

/// The sufficient test of the module docs at a local solution `x` (in front of every camera).
pub fn convexity_test(views: &[PointView], x: &Vector3<f64>) -> ConvexityCertificate {
    for kind in [ChartKind::MeanDepth, ChartKind::Euclidean] {
        let bound = Chart::new(views, x, kind)
            .and_then(|c| minorant(&c.views, a_priori_kappa(kind, views.len())))
            .map(|m| m.unconstrained_minimum());
        if let Some(lower_bound) = bound {
            return ConvexityCertificate {
                passed: true,
                lower_bound,
            };
        }
    }
    ConvexityCertificate {
        passed: false,
        lower_bound: 0.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::triangulation::point::cost::term_hessian;
    use nalgebra::{Matrix2x4, Vector4};

    #[test]
    fn per_view_hessian_bound_holds_for_random_directions() {
        // wᵀ∇²‖r‖²w ≥ (2/z²)(⅓‖Aw‖² − 3ρ²(cᵀw)²) at random points, views and directions.
        let mut rng = crate::rng::Rng::new(5);
        let mut checked = 0;
        for _ in 0..5000 {
            let c = rng.unit_vector3();
            let view = PointView {
                w: Matrix2x4::from_fn(|_, _| 300.0 * rng.normal()),
                depth_row: Vector4::new(c.x, c.y, c.z, rng.uniform_in(2.0, 9.0)),
            };
            let x = Vector3::new(rng.normal(), rng.normal(), rng.normal()) * 0.5;
            let z = view.depth(&x);
            if z <= 0.1 {
                continue;
            }
            let rho2 = view.residual(&x).norm_squared();
            let w = rng.unit_vector3();
            let exact = w.dot(&(term_hessian(&view, &x) * w));
            let bound = 2.0 / (z * z) * ((view.a() * w).norm_squared() / 3.0 - 3.0 * rho2 * view.c().dot(&w).powi(2));
            assert!(
                exact >= bound - 1e-9 * exact.abs().max(bound.abs()),
                "{exact} < {bound}"
            );
            checked += 1;
        }
        assert!(checked > 3000);
    }
}
