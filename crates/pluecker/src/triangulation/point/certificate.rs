//! A cheap sufficient test of global optimality for a triangulated point (in the spirit of
//! Hartley & Seo 2008, "Verifying global minima for L2 minimization problems").
//!
//! Work in a whitened chart ([`super::chart`]) around the local solution `X̂` (`y = 0`): per
//! view `aᵢ(y) = r̂ᵢ + Gᵢy`, `ζᵢ(y) = 1 + dᵢᵀy`, `‖rᵢ‖ = ‖aᵢ‖/ζᵢ`, and `Σ BᵢᵀBᵢ = I` with
//! `Bᵢ = Gᵢ − r̂ᵢdᵢᵀ`. Let `ε₀² = f(X̂) = Σ ρ̂ᵢ²` (`ρ̂ᵢ = ‖r̂ᵢ‖`) and `L = {y : f(y) ≤ ε₀², ζᵢ > 0}`,
//! the points at least as good as `X̂` (not known to be convex). The test builds a convex set
//! `K ⊇ L`, shows `f` strongly convex on `K`, and concludes.
//!
//! **1. Per-view cones.** `S = ∩ᵢ {‖aᵢ(y)‖ ≤ ε₀ ζᵢ(y)}` is convex and contains `L`. On `S`,
//! `aᵢ − r̂ᵢζᵢ = Bᵢy`, so `‖Bᵢy‖ ≤ (ε₀ + ρ̂ᵢ)ζᵢ`. If `|dᵢᵀy| ≤ κ` for all `i`, then `ζᵢ ≤ 1 + κ` and
//! `‖y‖² = Σ‖Bᵢy‖² ≤ (1 + κ)²E²`, `E² = Σ(ε₀ + ρ̂ᵢ)²`, hence `|dᵢᵀy| ≤ (1 + κ)E‖dᵢ‖`. With
//! `q = E maxᵢ‖dᵢ‖ < 1` and `κ₁ > q/(1 − q)` the assumption reproduces itself strictly; it holds at
//! `y = 0`, and on a segment from `0` inside the convex `S` it cannot fail first at a point where it
//! still holds. So `|dᵢᵀy| ≤ κ₁` on all of `S` (the lead's derivation, in whitened coordinates; the
//! code uses the metric of `ΣBᵢᵀBᵢ`, which is `I` here, so that any chart origin works). In the
//! mean-depth chart `Σᵢ ζᵢ = n` identically, so `ζᵢ < n` for points in front of every camera:
//! `κ = n − 1` is an a-priori bound whether or not `q < 1`.
//!
//! **2. The quadratic ellipsoid.** `F(y) = Σ‖aᵢ(y)‖² = ε₀² + 2bᵀy + yᵀNy` (`N = ΣGᵢᵀGᵢ`,
//! `b = ΣGᵢᵀr̂ᵢ`) is a convex quadratic, and `F = Σ‖rᵢ‖²ζᵢ² ≤ (1 + κ)² f` where `ζᵢ ≤ 1 + κ`. Given a
//! convex `K ⊇ L` with `|dᵢᵀy| ≤ κ` on `K`, every point of `L` lies in
//! `Q_κ = {F ≤ (1 + κ)²ε₀²}`, an ellipsoid of centre `−N⁻¹b` and radius
//! `ρ_Q² = (1 + κ)²ε₀² − ε₀² + bᵀN⁻¹b` in the `N` metric, on which
//! `|dᵢᵀy| ≤ |dᵢᵀN⁻¹b| + ρ_Q √(dᵢᵀN⁻¹dᵢ)`. Replacing `K` by `K ∩ Q_κ` and `κ` by this smaller bound,
//! from `K = S`, `κ = κ₁`, a few times, shrinks the depth bound by about `√n` (the sum `E` bounds
//! every view at once; `Q` only the total). At the end `K = S ∩ Q_{κ_Q}` with `|dᵢᵀy| ≤ κ_d < 1`
//! on `K`, and `f ≤ F/(1 − κ_d)² ≤ R² = (1 + κ_Q)²ε₀²/(1 − κ_d)²` on `K`.
//!
//! **3. Hessian.** For one view and `w ∈ ℝ³`, `α = Gᵢw`, `β = dᵢᵀw` (see
//! `cost::term_hessian`, the same algebra in any chart):
//! `wᵀ∇²‖rᵢ‖²w · ζᵢ²/2 = ‖α − 2βrᵢ‖² − ρᵢ²β² ≥ (1 − θ)‖α‖² − (4/θ − 3)ρᵢ²β²` for `θ ∈ (0, 1]`,
//! least ratio at `θ = 2/3` (factors ⅓ and 3; the lead's `θ = ½` gives ½ and 5). On `K`:
//! `wᵀ∇²f w ≥ wᵀPw − (6/(1 − κ_d)²) Σᵢ ρᵢ²(dᵢᵀw)²` with `P = 2N/(3(1 + κ_d)²)`; and since
//! `Σρᵢ² = f ≤ R²` and `(dᵢᵀw)² ≤ (dᵢᵀP⁻¹dᵢ)(wᵀPw)`,
//! `∇²f ⪰ (1 − μ)P`, `μ = 6R²/(1 − κ_d)² · maxᵢ dᵢᵀP⁻¹dᵢ`. Bounding the total `Σρᵢ²` rather than
//! each `ρᵢ ≤ ε₀` keeps the negative part from growing with the number of views.
//!
//! **4. Conclusion.** If `μ < 1`, `f` is strongly convex on the convex `K ∋ 0`; for `y ∈ K`, Taylor
//! along the segment gives `f(y) ≥ f(0) + gᵀy + ½yᵀHy ≥ ε₀² − ½gᵀH⁻¹g` with `H = (1 − μ)P` and `g`
//! the gradient at `y = 0` (zero at an exact stationary point). Points outside `K` are not in `L`:
//! they cost more than `ε₀²`. So `ε₀² − ½gᵀH⁻¹g` bounds `f` below over every point in front of all
//! cameras. The test runs in the mean-depth chart and, if that fails, in the Euclidean chart.
//!
//! It fails (branch and bound decides) when `q ≥ 1`, `κ_d ≥ 1` or `μ ≥ 1`: low parallax in the
//! Euclidean chart, large residuals, or a second minimum nearby.

use super::chart::{Chart, ChartKind};
use super::cost::PointView;
use nalgebra::{Matrix3, Vector3};

/// `κ` bounds are taken this much above the computed ones (strict inequalities, rounding).
const KAPPA_MARGIN: f64 = 1e-6;
/// `μ` must stay below `1 − MU_MARGIN`.
const MU_MARGIN: f64 = 1e-6;
/// Stage 2 stops when `κ` shrinks by less than this factor, or after `MAX_REFINEMENTS` passes.
const REFINEMENT_RATIO: f64 = 0.99;
const MAX_REFINEMENTS: usize = 60;

/// A convex set `K ⊇ {f ≤ ε₀²}` in chart coordinates with its depth bound (module docs, stages 1-2).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Enclosure {
    /// The per-view radius of `S` (`ε₀` for the test).
    pub gamma: f64,
    /// `S` lies in the cube `|y_k| ≤ ball_radius` (`∞` when stage 1 did not apply).
    pub ball_radius: f64,
    /// `N = ΣGᵢᵀGᵢ`.
    pub n: Matrix3<f64>,
    /// `b = ΣGᵢᵀr̂ᵢ`.
    pub b: Vector3<f64>,
    /// The level `ℓ` of the enclosed sublevel set `{f ≤ ℓ}` (`ε₀²` for the test).
    pub level: f64,
    /// `F(0) = f` at the chart's origin (`ε₀²` for the test).
    pub origin_cost: f64,
    /// `κ_Q`: `K = S ∩ {F ≤ (1 + κ_Q)² ε₀²}`.
    pub kappa_q: f64,
    /// `κ_d`: `|dᵢᵀy| ≤ κ_d` on `K`.
    pub kappa_d: f64,
}

impl Enclosure {
    /// The box `[lo, hi]` containing the ellipsoid `Q_{κ_Q}` and the ball of `S`.
    pub(crate) fn bounding_box(&self) -> Option<(Vector3<f64>, Vector3<f64>)> {
        let inverse = self.n.cholesky()?.inverse();
        let centre = -(inverse * self.b);
        let radius = self.q_radius(&inverse)?;
        let half = inverse.diagonal().map(|v| radius * v.max(0.0).sqrt());
        let ball = Vector3::repeat(self.ball_radius);
        let lo = (centre - half).sup(&-ball);
        let hi = (centre + half).inf(&ball);
        (lo < hi).then_some((lo, hi))
    }

    /// `ρ_Q` for `κ_Q`: `F ≤ (1 + κ_Q)² ℓ` is `(y − c)ᵀN(y − c) ≤ ρ_Q²`, `c = −N⁻¹b`.
    fn q_radius(&self, inverse: &Matrix3<f64>) -> Option<f64> {
        let r2 = (1.0 + self.kappa_q).powi(2) * self.level - self.origin_cost + self.b.dot(&(inverse * self.b));
        (r2 >= 0.0).then(|| r2.sqrt())
    }

    /// `(1 + κ_Q) √ℓ`: `K` lies in `‖(a₁(y), …, a_n(y))‖ ≤ q_bound`.
    pub(crate) fn q_bound(&self) -> f64 {
        (1.0 + self.kappa_q) * self.level.sqrt()
    }
}

/// Stages 1-2 of the module docs for the sublevel set `{f ≤ level}` (`level = ε₀²` for the test;
/// the chart's origin need not be a minimiser) and the per-view radius `gamma ≥ √level` of `S_γ`:
/// a convex set containing every point in front of the cameras with `f ≤ level`, or `None` when no
/// depth bound below 1 results or `N` is singular. `mean_depth` says the chart is the mean-depth
/// one, where `Σᵢ ζᵢ = n` gives the a-priori bound `ζᵢ < n` for points in front of every camera.
pub(crate) fn enclosure(chart: &Chart, level: f64, gamma: f64, mean_depth: bool) -> Option<Enclosure> {
    let origin_cost: f64 = chart.views.iter().map(|v| v.a0.norm_squared()).sum();
    let (mut n, mut b, mut m) = (Matrix3::zeros(), Vector3::zeros(), Matrix3::zeros());
    for v in &chart.views {
        let bi = v.g - v.a0 * v.d.transpose();
        m += bi.transpose() * bi;
        n += v.g.transpose() * v.g;
        b += v.g.transpose() * v.a0;
    }
    // Stage 1 in the metric of M = Σ BᵢᵀBᵢ (the identity at a whitened local solution).
    let m_inverse = m.cholesky()?.inverse();
    let e = chart
        .views
        .iter()
        .map(|v| (gamma + v.a0.norm()).powi(2))
        .sum::<f64>()
        .sqrt();
    let q = e * chart
        .views
        .iter()
        .map(|v| v.d.dot(&(m_inverse * v.d)).max(0.0).sqrt())
        .fold(0.0, f64::max);
    let mut kappa = if mean_depth {
        chart.views.len() as f64 - 1.0
    } else {
        f64::INFINITY
    };
    let mut ball_radius = f64::INFINITY;
    if q < 1.0 {
        let kappa_1 = q / (1.0 - q) * (1.0 + KAPPA_MARGIN);
        // yᵀMy ≤ ((1 + κ₁)E)² implies |y_k| ≤ (1 + κ₁)E √(M⁻¹)_kk; keep the widest for the ball.
        ball_radius = (1.0 + kappa_1) * e * m_inverse.diagonal().max().max(0.0).sqrt();
        kappa = kappa.min(kappa_1);
    }
    if !kappa.is_finite() {
        return None;
    }
    let inverse = n.cholesky()?.inverse();
    let centre = -(inverse * b);
    let mut out = Enclosure {
        gamma,
        ball_radius,
        n,
        b,
        level,
        origin_cost,
        kappa_q: kappa,
        kappa_d: kappa,
    };
    for _ in 0..MAX_REFINEMENTS {
        let candidate = Enclosure {
            kappa_q: out.kappa_d,
            ..out.clone()
        };
        let radius = candidate.q_radius(&inverse)?;
        let depth = chart
            .views
            .iter()
            .map(|v| v.d.dot(&centre).abs() + radius * v.d.dot(&(inverse * v.d)).max(0.0).sqrt())
            .fold(0.0, f64::max)
            * (1.0 + KAPPA_MARGIN);
        if !(depth < REFINEMENT_RATIO * candidate.kappa_q) {
            break;
        }
        out = Enclosure {
            kappa_d: depth,
            ..candidate
        };
    }
    (out.kappa_d < 1.0).then_some(out)
}

/// The outcome of [`convexity_test`].
#[derive(Debug, Clone, PartialEq)]
pub struct ConvexityCertificate {
    /// True when `μ < 1` in one of the charts: `lower_bound` is then valid for every point in front
    /// of all cameras.
    pub passed: bool,
    /// `ε₀² − ½gᵀH⁻¹g` when `passed`, else 0 (the trivial bound).
    pub lower_bound: f64,
}

/// Stage 3-4 in one chart: the lower bound when `μ < 1`.
fn test_in_chart(chart: &Chart, mean_depth: bool) -> Option<f64> {
    let cost: f64 = chart.views.iter().map(|v| v.a0.norm_squared()).sum();
    let k = enclosure(chart, cost, cost.sqrt(), mean_depth)?;
    let r2 = (1.0 + k.kappa_q).powi(2) * cost / (1.0 - k.kappa_d).powi(2);
    let p = k.n * (2.0 / (3.0 * (1.0 + k.kappa_d).powi(2)));
    let p_chol = p.cholesky()?;
    let worst = chart
        .views
        .iter()
        .map(|v| v.d.dot(&p_chol.solve(&v.d)))
        .fold(0.0, f64::max);
    let mu = 6.0 * r2 / (1.0 - k.kappa_d).powi(2) * worst;
    if !(mu < 1.0 - MU_MARGIN) {
        return None;
    }
    // g = ∇f(0) = 2 Σ Bᵢᵀ r̂ᵢ, Bᵢ = Gᵢ − r̂ᵢdᵢᵀ.
    let g: Vector3<f64> = chart
        .views
        .iter()
        .map(|v| 2.0 * (v.g - v.a0 * v.d.transpose()).transpose() * v.a0)
        .sum();
    let newton = p_chol.solve(&g) / (1.0 - mu);
    Some((cost - 0.5 * g.dot(&newton)).max(0.0))
}

/// The sufficient test of the module docs at a local solution `x` (in front of every camera).
pub fn convexity_test(views: &[PointView], x: &Vector3<f64>) -> ConvexityCertificate {
    for kind in [ChartKind::MeanDepth, ChartKind::Euclidean] {
        let mean_depth = kind == ChartKind::MeanDepth;
        if let Some(lower_bound) = Chart::new(views, x, kind).and_then(|c| test_in_chart(&c, mean_depth)) {
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
