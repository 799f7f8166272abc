//! Affine charts of the projective point around a local solution, in which the cost of eq. 19 keeps
//! the form "sum of ‖affine‖² / affine²" needed by the certificate and by branch and bound.
//!
//! Around `X̂` (depths `ẑᵢ > 0`, whitened residuals `r̂ᵢ`) write the homogeneous point as
//! `X̃ = (X̂ w + u, w)`. Then `Wᵢ X̃/ẑᵢ = Aᵢu/ẑᵢ + r̂ᵢ w` and `p₃ᵢᵀX̃/ẑᵢ = cᵢᵀu/ẑᵢ + w`. A chart fixes
//! `w = 1 − eᵀu` for a 3-vector `e`:
//! - `e = 0`: the Euclidean chart, `X = X̂ + u`;
//! - `e = ē = mean(cᵢ/ẑᵢ)`: the mean-depth chart, where `Σᵢ zᵢ/ẑᵢ` is constant and the point at
//!   infinity in front of the cameras is a finite `u` (`w = 0`); the cost is close to quadratic in
//!   it when the parallax is small (image motion is nearly linear in inverse depth).
//!
//! In a chart, per view, the numerator `aᵢ(u) = r̂ᵢ + (Aᵢ/ẑᵢ − r̂ᵢ eᵀ) u` and the denominator
//! `ζᵢ(u) = 1 + (cᵢ/ẑᵢ − e)ᵀu` are affine, `ζᵢ = zᵢ w/ẑᵢ`, and `‖aᵢ/ζᵢ‖ = ‖rᵢ‖`. The coordinates are
//! finally whitened, `u = T y` with `T = QΛ^{-1/2}` from `M = Σ BᵢᵀBᵢ/ẑᵢ² = QΛQᵀ`
//! (`Bᵢ = Aᵢ − r̂ᵢcᵢᵀ`, the Gauss-Newton Hessian at `X̂`, the same in every chart), so that `y` is in
//! whitened pixels and the Gauss-Newton Hessian of `f` in `y` at `0` is `2I`. A chart point is a
//! point in front of every camera iff `w > 0` and every `ζᵢ > 0`; it is `X = X̂ + T y / w`.

use super::cost::PointView;
use crate::global::convexity::{whitening, RatioView};
use nalgebra::{Matrix3, Vector3};

/// One view in chart coordinates: `a(y) = a0 + G y`, `ζ(y) = 1 + dᵀy`.
pub(crate) type ChartView = RatioView<2, 3>;

/// Which chart (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum ChartKind {
    /// `e = 0`.
    Euclidean,
    /// `e = mean(cᵢ/ẑᵢ)`.
    MeanDepth,
}

/// A whitened affine chart around a local solution (module docs).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Chart {
    /// `X̂`, the chart's origin.
    pub origin: Vector3<f64>,
    /// `T`, world units per whitened pixel.
    pub t: Matrix3<f64>,
    /// `Tᵀe`: `w(y) = 1 − w_gradientᵀ y`.
    pub w_gradient: Vector3<f64>,
    /// The views.
    pub views: Vec<ChartView>,
}

impl Chart {
    /// The chart of `kind` around `x` (in front of every camera), or `None` when `x` is not in front
    /// of every camera or `M` is singular.
    pub fn new(views: &[PointView], x: &Vector3<f64>, kind: ChartKind) -> Option<Chart> {
        let mut m = Matrix3::zeros();
        let mut mean = Vector3::zeros();
        let mut at = Vec::with_capacity(views.len());
        for v in views {
            let z = v.depth(x);
            if !(z > 0.0) {
                return None;
            }
            let r = v.numerator(x) / z;
            let b = (v.a() - r * v.c().transpose()) / z;
            m += b.transpose() * b;
            mean += v.c() / z;
            at.push((z, r));
        }
        let e = match kind {
            ChartKind::Euclidean => Vector3::zeros(),
            ChartKind::MeanDepth => mean / views.len() as f64,
        };
        let t = whitening(&m)?;
        let chart_views = views
            .iter()
            .zip(&at)
            .map(|(v, &(z, r))| ChartView {
                a0: r,
                g: (v.a() / z - r * e.transpose()) * t,
                d: t.transpose() * (v.c() / z - e),
            })
            .collect();
        Some(Chart {
            origin: *x,
            t,
            w_gradient: t.transpose() * e,
            views: chart_views,
        })
    }

    /// `w(y) = 1 − eᵀT y`: positive for finite points in front, 0 at infinity.
    pub fn w(&self, y: &Vector3<f64>) -> f64 {
        1.0 - self.w_gradient.dot(y)
    }

    /// The world point of `y`, when it is finite (`w > 0`).
    pub fn point(&self, y: &Vector3<f64>) -> Option<Vector3<f64>> {
        let w = self.w(y);
        (w > 0.0).then(|| self.origin + self.t * y / w)
    }

    /// The cost of eq. 19 at `y`, `Σ ‖aᵢ‖²/ζᵢ²` (the tests' check of the chart against eq. 19).
    #[cfg(test)]
    pub fn cost(&self, y: &Vector3<f64>) -> f64 {
        crate::global::convexity::cost(&self.views, y)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;
    use crate::synthetic::triangulation_scene;
    use crate::triangulation::point::cost::{point_cost, point_views};
    use crate::triangulation::views::depth_normalized;
    use nalgebra::{Matrix2, Matrix3x4};

    #[test]
    fn chart_cost_is_the_cost_of_the_mapped_point() {
        let scene = triangulation_scene(4, 0.3, 9);
        let mut rng = Rng::new(9);
        let obs = scene.noisy(1.0, &mut rng);
        let ps: Vec<Matrix3x4<f64>> = scene.cameras.iter().map(depth_normalized).collect();
        let views = point_views(&ps, &obs, &[Matrix2::new(1.0, 0.0, 0.3, 2.0); 4]);
        for kind in [ChartKind::Euclidean, ChartKind::MeanDepth] {
            let chart = Chart::new(&views, &scene.point, kind).unwrap();
            assert!((chart.cost(&Vector3::zeros()) - point_cost(&views, &scene.point)).abs() < 1e-9);
            for _ in 0..20 {
                let y = Vector3::new(rng.normal(), rng.normal(), rng.normal()) * 3.0;
                let x = chart.point(&y).unwrap();
                let (fc, fx) = (chart.cost(&y), point_cost(&views, &x));
                assert!((fc - fx).abs() < 1e-9 * (1.0 + fx), "{kind:?}: {fc} vs {fx}");
                for (cv, v) in chart.views.iter().zip(&views) {
                    // ζ = z w / ẑ.
                    let expected = v.depth(&x) * chart.w(&y) / v.depth(&scene.point);
                    assert!((cv.denominator(&y) - expected).abs() < 1e-9);
                }
            }
        }
    }
}
