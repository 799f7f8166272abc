//! A cheap sufficient test of global optimality for a sum of squared ratios of affine maps (in the
//! spirit of Hartley & Seo 2008, "Verifying global minima for L2 minimization problems"), for any
//! residual dimension `M` and number of unknowns `N`: points (`M = 2`, `N = 3`,
//! [`crate::triangulation::point::certificate`]) and quadrics (`M = 5`, `N = 9`,
//! [`crate::triangulation::quadric::certificate`]).
//!
//! The caller supplies a whitened affine chart around a local solution (`y = 0`): per view
//! `aᵢ(y) = r̂ᵢ + Gᵢy ∈ ℝᴹ`, `ζᵢ(y) = 1 + dᵢᵀy`, `‖rᵢ‖ = ‖aᵢ‖/ζᵢ`, and `Σ BᵢᵀBᵢ = I` with
//! `Bᵢ = Gᵢ − r̂ᵢdᵢᵀ` (the Gauss-Newton Hessian of `f = Σ‖rᵢ‖²` at `0` is `2I`). The domain is every
//! `y` with all `ζᵢ > 0`. Let `ε₀² = f(0) = Σ ρ̂ᵢ²` (`ρ̂ᵢ = ‖r̂ᵢ‖`) and `L = {y : f(y) ≤ ε₀², ζᵢ > 0}`,
//! the chart points at least as good as the origin (not known to be convex). The test builds a
//! convex set `K ⊇ L`, shows `f` strongly convex on `K`, and concludes.
//!
//! **1. Per-view cones.** `S = ∩ᵢ {‖aᵢ(y)‖ ≤ ε₀ ζᵢ(y)}` is convex and contains `L`. On `S`,
//! `aᵢ − r̂ᵢζᵢ = Bᵢy`, so `‖Bᵢy‖ ≤ (ε₀ + ρ̂ᵢ)ζᵢ`. If `|dᵢᵀy| ≤ κ` for all `i`, then `ζᵢ ≤ 1 + κ` and
//! `‖y‖² = Σ‖Bᵢy‖² ≤ (1 + κ)²E²`, `E² = Σ(ε₀ + ρ̂ᵢ)²`, hence `|dᵢᵀy| ≤ (1 + κ)E‖dᵢ‖`. With
//! `q = E maxᵢ‖dᵢ‖ < 1` and `κ₁ > q/(1 − q)` the assumption reproduces itself strictly; it holds at
//! `y = 0`, and on a segment from `0` inside the convex `S` it cannot fail first at a point where it
//! still holds. So `|dᵢᵀy| ≤ κ₁` on all of `S` (in the code, the metric of `ΣBᵢᵀBᵢ`, which is `I`
//! for a whitened chart, so that any chart origin works). A chart may also know an a-priori bound
//! (points: `ζᵢ < n` in the mean-depth chart, where `Σᵢ ζᵢ = n`), used whether or not `q < 1`.
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
//! **3. Hessian.** For one view and `w ∈ ℝᴺ`, `α = Gᵢw`, `β = dᵢᵀw`:
//! `wᵀ∇²‖rᵢ‖²w · ζᵢ²/2 = ‖α − 2βrᵢ‖² − ρᵢ²β² ≥ (1 − θ)‖α‖² − (4/θ − 3)ρᵢ²β²` for `θ ∈ (0, 1]`
//! (the second derivative of `‖(a + tα)/(ζ + tβ)‖²`, whatever `M`), least ratio at `θ = 2/3`
//! (factors ⅓ and 3). On `K`: `wᵀ∇²f w ≥ wᵀPw − (6/(1 − κ_d)²) Σᵢ ρᵢ²(dᵢᵀw)²` with
//! `P = 2N/(3(1 + κ_d)²)`; and since `Σρᵢ² = f ≤ R²` and `(dᵢᵀw)² ≤ (dᵢᵀP⁻¹dᵢ)(wᵀPw)`,
//! `∇²f ⪰ (1 − μ)P`, `μ = 6R²/(1 − κ_d)² · maxᵢ dᵢᵀP⁻¹dᵢ`. Bounding the total `Σρᵢ²` rather than
//! each `ρᵢ ≤ ε₀` keeps the negative part from growing with the number of views.
//!
//! **4. Conclusion.** If `μ < 1`, `f` is strongly convex on the convex `K ∋ 0`; for `y ∈ K`, Taylor
//! along the segment gives the `Minorant` `f(y) ≥ m(y) = f(0) + gᵀy + ½yᵀHy` with `H = (1 − μ)P`
//! and `g` the gradient at `0`. Points outside `K` cost more than `ε₀²`, so any lower bound of `m`
//! over a set containing the feasible part of `K` is, capped at `ε₀²`, a lower bound of `f` over
//! every feasible chart point: over all of them, `ε₀² − ½gᵀH⁻¹g`
//! (`Minorant::unconstrained_minimum`); under one extra quadratic constraint, the Lagrangian bound
//! of `Minorant::minimum_subject_to`.
//!
//! It fails (the caller's branch and bound decides) when `q ≥ 1` without an a-priori bound,
//! `κ_d ≥ 1` or `μ ≥ 1`: low parallax in an affine chart, large residuals, or a second minimum
//! nearby.

use nalgebra::allocator::Allocator;
use nalgebra::{Cholesky, Const, DefaultAllocator, DimDiff, DimSub, SMatrix, SVector, SymmetricEigen, U1};

/// `κ` bounds are taken this much above the computed ones (strict inequalities, rounding).
const KAPPA_MARGIN: f64 = 1e-6;
/// `μ` must stay below `1 − MU_MARGIN`.
const MU_MARGIN: f64 = 1e-6;
/// Stage 2 stops when `κ` shrinks by less than this factor, or after `MAX_REFINEMENTS` passes.
const REFINEMENT_RATIO: f64 = 0.99;
const MAX_REFINEMENTS: usize = 60;
/// Golden-section steps of the Lagrange multiplier in `Minorant::minimum_subject_to`.
const MULTIPLIER_STEPS: usize = 80;
/// The bound of `Minorant::minimum_subject_to` is lowered by this fraction of the cost.
const ROUNDING_MARGIN: f64 = 1e-9;

/// One view in chart coordinates: `a(y) = a0 + G y ∈ ℝᴹ`, `ζ(y) = 1 + dᵀy`, `y ∈ ℝᴺ`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct RatioView<const M: usize, const N: usize> {
    /// `r̂`, the whitened residual at the chart's origin.
    pub a0: SVector<f64, M>,
    /// `G`, the numerator's Jacobian in `y`.
    pub g: SMatrix<f64, M, N>,
    /// `d`, the denominator's gradient in `y`.
    pub d: SVector<f64, N>,
}

impl<const M: usize, const N: usize> RatioView<M, N> {
    /// `a(y)`.
    pub(crate) fn numerator(&self, y: &SVector<f64, N>) -> SVector<f64, M> {
        self.a0 + self.g * y
    }

    /// `ζ(y)`.
    pub(crate) fn denominator(&self, y: &SVector<f64, N>) -> f64 {
        1.0 + self.d.dot(y)
    }

    /// `Bᵢ = Gᵢ − r̂ᵢdᵢᵀ`, the residual's Jacobian at `y = 0`.
    fn jacobian(&self) -> SMatrix<f64, M, N> {
        self.g - self.a0 * self.d.transpose()
    }
}

/// Smallest accepted ratio of the least to the largest eigenvalue of a chart's Gauss-Newton Hessian
/// (a direction the data do not constrain at all makes the chart singular).
const MIN_CONDITION: f64 = 1e-14;

/// The whitening `T = VΛ^{-1/2}` of a chart's Gauss-Newton Hessian `M = ΣBᵢᵀBᵢ = VΛVᵀ` (then
/// `TᵀMT = I`, as the module docs assume); `None` when `M` is numerically singular.
pub(crate) fn whitening<const N: usize>(m: &SMatrix<f64, N, N>) -> Option<SMatrix<f64, N, N>>
where
    Const<N>: DimSub<U1>,
    DefaultAllocator: Allocator<DimDiff<Const<N>, U1>>,
{
    let eig = SymmetricEigen::<f64, Const<N>>::new(*m);
    if !(eig.eigenvalues.min() > MIN_CONDITION * eig.eigenvalues.max()) {
        return None;
    }
    Some(eig.eigenvectors * SMatrix::<f64, N, N>::from_diagonal(&eig.eigenvalues.map(|l| 1.0 / l.sqrt())))
}

/// `f(y) = Σ ‖aᵢ(y)‖²/ζᵢ(y)²` (no ½): the tests' check of a chart against eq. 19.
#[cfg(test)]
pub(crate) fn cost<const M: usize, const N: usize>(views: &[RatioView<M, N>], y: &SVector<f64, N>) -> f64 {
    views
        .iter()
        .map(|v| v.numerator(y).norm_squared() / v.denominator(y).powi(2))
        .sum()
}

/// A convex set `K ⊇ {f ≤ ℓ}` in chart coordinates with its depth bound (module docs, stages 1-2).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Enclosure<const N: usize> {
    /// The per-view radius of `S` (`ε₀` for the test).
    pub gamma: f64,
    /// `S` lies in the cube `|y_k| ≤ ball_radius` (`∞` when stage 1 did not apply).
    pub ball_radius: f64,
    /// `N = ΣGᵢᵀGᵢ`.
    pub n: SMatrix<f64, N, N>,
    /// `b = ΣGᵢᵀr̂ᵢ`.
    pub b: SVector<f64, N>,
    /// The level `ℓ` of the enclosed sublevel set `{f ≤ ℓ}` (`ε₀²` for the test).
    pub level: f64,
    /// `F(0) = f` at the chart's origin (`ε₀²` for the test).
    pub origin_cost: f64,
    /// `κ_Q`: `K = S ∩ {F ≤ (1 + κ_Q)² ℓ}`.
    pub kappa_q: f64,
    /// `κ_d`: `|dᵢᵀy| ≤ κ_d` on `K`.
    pub kappa_d: f64,
}

impl<const N: usize> Enclosure<N> {
    /// The box `[lo, hi]` containing the ellipsoid `Q_{κ_Q}` and the ball of `S`.
    pub(crate) fn bounding_box(&self) -> Option<(SVector<f64, N>, SVector<f64, N>)> {
        let inverse = self.n.cholesky()?.inverse();
        let centre = -(inverse * self.b);
        let radius = self.q_radius(&inverse)?;
        let half = inverse.diagonal().map(|v| radius * v.max(0.0).sqrt());
        let ball = SVector::<f64, N>::repeat(self.ball_radius);
        let lo = (centre - half).sup(&-ball);
        let hi = (centre + half).inf(&ball);
        (lo < hi).then_some((lo, hi))
    }

    /// `ρ_Q` for `κ_Q`: `F ≤ (1 + κ_Q)² ℓ` is `(y − c)ᵀN(y − c) ≤ ρ_Q²`, `c = −N⁻¹b`.
    fn q_radius(&self, inverse: &SMatrix<f64, N, N>) -> Option<f64> {
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
/// a convex set containing every chart point with all `ζᵢ > 0` and `f ≤ level`, or `None` when no
/// depth bound below 1 results or `N` is singular. `a_priori_kappa`, when the chart knows one, bounds
/// `|dᵢᵀy|` for every chart point with all `ζᵢ > 0`.
pub(crate) fn enclosure<const M: usize, const N: usize>(
    views: &[RatioView<M, N>],
    level: f64,
    gamma: f64,
    a_priori_kappa: Option<f64>,
) -> Option<Enclosure<N>> {
    let origin_cost: f64 = views.iter().map(|v| v.a0.norm_squared()).sum();
    let (mut n, mut b, mut m) = (
        SMatrix::<f64, N, N>::zeros(),
        SVector::<f64, N>::zeros(),
        SMatrix::<f64, N, N>::zeros(),
    );
    for v in views {
        let bi = v.jacobian();
        m += bi.transpose() * bi;
        n += v.g.transpose() * v.g;
        b += v.g.transpose() * v.a0;
    }
    // Stage 1 in the metric of M = Σ BᵢᵀBᵢ (the identity at a whitened local solution).
    let m_inverse = m.cholesky()?.inverse();
    let e = views.iter().map(|v| (gamma + v.a0.norm()).powi(2)).sum::<f64>().sqrt();
    let q = e * views
        .iter()
        .map(|v| v.d.dot(&(m_inverse * v.d)).max(0.0).sqrt())
        .fold(0.0, f64::max);
    let mut kappa = a_priori_kappa.unwrap_or(f64::INFINITY);
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
        let depth = views
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

/// `m(y) = f(0) + gᵀy + ½yᵀHy ≤ f(y)` on the enclosure `K` of the sublevel set `{f ≤ f(0)}` (module
/// docs, stage 4): every feasible chart point outside `K` costs more than `f(0)`.
#[derive(Debug, Clone)]
pub(crate) struct Minorant<const N: usize> {
    /// `f(0) = ε₀²`.
    pub cost: f64,
    /// `g = ∇f(0)`.
    pub gradient: SVector<f64, N>,
    /// The Cholesky factor of `H = (1 − μ)P`.
    pub hessian: Cholesky<f64, Const<N>>,
}

impl<const N: usize> Minorant<N> {
    /// `ε₀² − ½gᵀH⁻¹g`, at least 0: a lower bound of `f` over every chart point with all `ζᵢ > 0`.
    pub(crate) fn unconstrained_minimum(&self) -> f64 {
        (self.cost - 0.5 * self.gradient.dot(&self.hessian.solve(&self.gradient))).max(0.0)
    }

    /// A lower bound of `f` over the chart points with all `ζᵢ > 0` that satisfy
    /// `φ(y) = (c₀ + kᵀy)² − s₀ − pᵀy ≥ 0`: for every `λ ≥ 0` with `H − 2λkkᵀ ≻ 0`,
    /// `min_y m(y) − λφ(y) = ε₀² − λ(c₀² − s₀) − ½bᵀ(H − 2λkkᵀ)⁻¹b` with `b = g − 2λc₀k + λp` is below
    /// `m` wherever `φ ≥ 0` (weak duality: any such `λ` gives a valid bound; for one quadratic
    /// constraint the best `λ` closes the gap, by the S-lemma). The best `λ` of a golden-section
    /// search over `[0, 1/(2kᵀH⁻¹k))`, less a rounding margin of 1e-9 `ε₀²`, capped at `ε₀²` (part of
    /// the proof, not a cosmetic cap: points outside `K` are only known to cost more than `ε₀²`).
    pub(crate) fn minimum_subject_to(&self, c0: f64, k: &SVector<f64, N>, s0: f64, p: &SVector<f64, N>) -> f64 {
        // (H − αkkᵀ)⁻¹ = H⁻¹ + αH⁻¹kkᵀH⁻¹/(1 − αkᵀH⁻¹k) (Sherman-Morrison), α = 2λ.
        let (hg, hk, hp) = (
            self.hessian.solve(&self.gradient),
            self.hessian.solve(k),
            self.hessian.solve(p),
        );
        let kk = k.dot(&hk);
        let dual = |lambda: f64| -> f64 {
            let alpha = 2.0 * lambda;
            let denominator = 1.0 - alpha * kk;
            if !(denominator > 0.0) {
                return f64::NEG_INFINITY;
            }
            // b = g + λ(p − 2c₀k); H⁻¹b and kᵀH⁻¹b from the solves above.
            let hb = hg + (hp - hk * (2.0 * c0)) * lambda;
            let b = self.gradient + (p - k * (2.0 * c0)) * lambda;
            let kb = k.dot(&hb);
            let quadratic = b.dot(&hb) + alpha * kb * kb / denominator;
            self.cost - lambda * (c0 * c0 - s0) - 0.5 * quadratic
        };
        let upper = if kk > 0.0 { 0.5 / kk } else { 1e12 };
        let (mut lo, mut hi) = (0.0, upper * (1.0 - 1e-6));
        let ratio = 0.5 * (5f64.sqrt() - 1.0);
        let mut best = dual(0.0);
        for _ in 0..MULTIPLIER_STEPS {
            let (a, b) = (hi - ratio * (hi - lo), lo + ratio * (hi - lo));
            let (fa, fb) = (dual(a), dual(b));
            best = best.max(fa).max(fb);
            if fa < fb {
                lo = a;
            } else {
                hi = b;
            }
        }
        // The terms of the dual cancel partly: a relative margin for their rounding.
        (best - ROUNDING_MARGIN * self.cost).clamp(0.0, self.cost)
    }
}

/// Stages 1-4 of the module docs at the chart's origin: the minorant when `μ < 1`. `a_priori_kappa`
/// as for [`enclosure`].
pub(crate) fn minorant<const M: usize, const N: usize>(
    views: &[RatioView<M, N>],
    a_priori_kappa: Option<f64>,
) -> Option<Minorant<N>> {
    let cost: f64 = views.iter().map(|v| v.a0.norm_squared()).sum();
    minorant_at_level(views, cost, a_priori_kappa).map(|(m, _)| m)
}

/// Stages 1-4 for the sublevel set `{f ≤ level}`, `level ≥ f(0)`: the minorant `m ≤ f` on a convex
/// `K ⊇ {f ≤ level}` (every feasible chart point outside `K` costs more than `level`), with the
/// depth bound `κ_d` of `K` (`|dᵢᵀy| ≤ κ_d` there). With `level = f(0)` it is [`minorant`].
pub(crate) fn minorant_at_level<const M: usize, const N: usize>(
    views: &[RatioView<M, N>],
    level: f64,
    a_priori_kappa: Option<f64>,
) -> Option<(Minorant<N>, f64)> {
    let cost: f64 = views.iter().map(|v| v.a0.norm_squared()).sum();
    if !(level >= cost) {
        return None;
    }
    let k = enclosure(views, level, level.sqrt(), a_priori_kappa)?;
    let r2 = (1.0 + k.kappa_q).powi(2) * level / (1.0 - k.kappa_d).powi(2);
    let p = k.n * (2.0 / (3.0 * (1.0 + k.kappa_d).powi(2)));
    let p_chol = p.cholesky()?;
    let worst = views.iter().map(|v| v.d.dot(&p_chol.solve(&v.d))).fold(0.0, f64::max);
    let mu = 6.0 * r2 / (1.0 - k.kappa_d).powi(2) * worst;
    if !(mu < 1.0 - MU_MARGIN) {
        return None;
    }
    // g = ∇f(0) = 2 Σ Bᵢᵀ r̂ᵢ.
    let gradient: SVector<f64, N> = views.iter().map(|v| 2.0 * v.jacobian().transpose() * v.a0).sum();
    let hessian = (p * (1.0 - mu)).cholesky()?;
    Some((
        Minorant {
            cost,
            gradient,
            hessian,
        },
        k.kappa_d,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;
    use nalgebra::{Matrix2, Vector2};

    #[test]
    fn per_view_hessian_identity_holds_in_any_dimension() {
        // wᵀ∇²‖a/ζ‖²w · ζ²/2 = ‖α − 2βr‖² − ρ²β² (stage 3), by central differences, M = 5, N = 9.
        let mut rng = Rng::new(8);
        for _ in 0..200 {
            let v = RatioView::<5, 9> {
                a0: SVector::from_fn(|_, _| rng.normal()),
                g: SMatrix::from_fn(|_, _| rng.normal()),
                d: SVector::from_fn(|_, _| 0.2 * rng.normal()),
            };
            let y = SVector::<f64, 9>::from_fn(|_, _| 0.3 * rng.normal());
            let w = SVector::<f64, 9>::from_fn(|_, _| rng.normal());
            let f = |t: f64| cost(std::slice::from_ref(&v), &(y + w * t));
            let h = 1e-4;
            let second = (f(h) - 2.0 * f(0.0) + f(-h)) / (h * h);
            let (zeta, r) = (v.denominator(&y), v.numerator(&y) / v.denominator(&y));
            let (alpha, beta) = (v.g * w, v.d.dot(&w));
            let identity =
                2.0 / (zeta * zeta) * ((alpha - r * (2.0 * beta)).norm_squared() - r.norm_squared() * beta * beta);
            assert!(
                (second - identity).abs() < 1e-4 * (1.0 + identity.abs()),
                "{second} vs {identity}"
            );
        }
    }

    #[test]
    fn constrained_minimum_is_below_the_minorant_on_the_feasible_set_and_tight_for_a_linear_constraint() {
        // m(y) = 4 + gᵀy + ½yᵀHy on ℝ², φ(y) = (c₀ + kᵀy)² − s₀ − pᵀy ≥ 0.
        let h = Matrix2::new(2.0, 0.3, 0.3, 1.0);
        let m = Minorant {
            cost: 4.0,
            gradient: Vector2::new(0.8, -0.5),
            hessian: h.cholesky().unwrap(),
        };
        let model = |y: &Vector2<f64>| 4.0 + m.gradient.dot(y) + 0.5 * y.dot(&(h * y));
        let mut rng = Rng::new(3);
        for _ in 0..50 {
            let (c0, s0) = (0.3 * rng.normal(), 0.3 * rng.normal());
            let (k, p) = (
                Vector2::new(rng.normal(), rng.normal()) * 0.5,
                Vector2::new(rng.normal(), rng.normal()),
            );
            let bound = m.minimum_subject_to(c0, &k, s0, &p);
            // Dense sampling of the feasible set: the model is never below the bound.
            let mut least = f64::INFINITY;
            for i in 0..200 {
                for j in 0..200 {
                    let y = Vector2::new(-4.0 + 0.04 * i as f64, -4.0 + 0.04 * j as f64);
                    if (c0 + k.dot(&y)).powi(2) - s0 - p.dot(&y) >= 0.0 {
                        least = least.min(model(&y));
                    }
                }
            }
            assert!(bound <= least.min(4.0) + 1e-9, "{bound} > {least}");
        }
        // A linear constraint (k = 0), here y₁ ≤ −0.8, is a half-plane: the bound is its exact minimum.
        let p = Vector2::new(1.0, 0.0);
        let bound = m.minimum_subject_to(0.0, &Vector2::zeros(), 0.8, &p);
        let unconstrained = -h.cholesky().unwrap().solve(&m.gradient);
        assert!(unconstrained.x > -0.8, "the test needs an active constraint");
        let y2 = -(m.gradient.y - h[(1, 0)] * 0.8) / h[(1, 1)];
        let exact = model(&Vector2::new(-0.8, y2));
        assert!((bound - exact).abs() < 1e-6, "{bound} vs {exact}");
    }

    /// `f(y) = Σ ‖a₀ + Gy‖²/(1 + dᵀy)²` written out entry by entry (not [`RatioView`]'s methods), and
    /// whether every denominator is positive (the chart's domain).
    fn plain_cost<const M: usize, const N: usize>(views: &[RatioView<M, N>], y: &[f64; N]) -> Option<f64> {
        let mut f = 0.0;
        for v in views {
            let zeta = 1.0 + (0..N).map(|j| v.d[j] * y[j]).sum::<f64>();
            if zeta <= 0.0 || zeta.is_nan() {
                return None;
            }
            for i in 0..M {
                let a = v.a0[i] + (0..N).map(|j| v.g[(i, j)] * y[j]).sum::<f64>();
                f += (a / zeta).powi(2);
            }
        }
        Some(f)
    }

    /// Random charts of `n` views whose origin is not a minimiser (`a₀` random), residuals of every
    /// size relative to the data's curvature, and strong perspective (`d`) on some views.
    fn random_chart<const M: usize, const N: usize>(rng: &mut Rng, n: usize) -> Vec<RatioView<M, N>> {
        let residual = 10f64.powf(rng.uniform_in(-2.0, 0.0));
        let perspective = 10f64.powf(rng.uniform_in(-1.5, 0.0));
        (0..n)
            .map(|_| RatioView {
                a0: SVector::from_fn(|_, _| residual * rng.normal()),
                g: SMatrix::from_fn(|_, _| rng.normal()),
                d: SVector::from_fn(|_, _| perspective * rng.normal()),
            })
            .collect()
    }

    /// A grid of `per_axis^N` points over the box `[lo, hi]`.
    fn grid<const N: usize>(lo: &SVector<f64, N>, hi: &SVector<f64, N>, per_axis: usize) -> Vec<[f64; N]> {
        let total = per_axis.pow(N as u32);
        (0..total)
            .map(|mut k| {
                std::array::from_fn(|j| {
                    let i = k % per_axis;
                    k /= per_axis;
                    lo[j] + (hi[j] - lo[j]) * i as f64 / (per_axis - 1) as f64
                })
            })
            .collect()
    }

    /// The minorant and the enclosure of random charts centred away from the minimiser, checked
    /// against the cost on a dense grid over a box three times the enclosure's bounding box: every
    /// grid point in the chart's domain with `f ≤ f(0)` lies in the box, satisfies the depth bound
    /// `|dᵢᵀy| ≤ κ_d` and the ellipsoid `F ≤ (1 + κ_Q)² f(0)`, and has `m(y) ≤ f(y)`; the bound
    /// `min m` is below the least cost on the grid and below the minimum a golden-section or
    /// coordinate search reaches from the best grid point. A minorant whose curvature is too large,
    /// or an enclosure too small, fails here.
    fn check_minorants<const M: usize, const N: usize>(seed: u64, instances: usize, per_axis: usize) -> usize {
        let mut rng = Rng::new(seed);
        let mut passed = 0;
        for instance in 0..instances {
            let count = 2 + rng.below(3);
            let views = random_chart::<M, N>(&mut rng, count);
            let f0: f64 = views.iter().map(|v| v.a0.norm_squared()).sum();
            let Some(m) = minorant(&views, None) else {
                continue;
            };
            let k = enclosure(&views, f0, f0.sqrt(), None).expect("the minorant's enclosure exists");
            let (lo, hi) = k.bounding_box().expect("a bounding box");
            let (centre, half) = ((lo + hi) * 0.5, (hi - lo) * 0.5);
            let (big_lo, big_hi) = (centre - half * 3.0, centre + half * 3.0);
            let h = m.hessian.l() * m.hessian.l().transpose();
            let model = |y: &SVector<f64, N>| m.cost + m.gradient.dot(y) + 0.5 * y.dot(&(h * y));
            let bound = m.unconstrained_minimum();
            let mut least = (f64::INFINITY, [0.0; N]);
            for y in grid(&big_lo, &big_hi, per_axis) {
                let Some(f) = plain_cost(&views, &y) else {
                    continue;
                };
                if f < least.0 {
                    least = (f, y);
                }
                let yv = SVector::<f64, N>::from_column_slice(&y);
                // The minorant is claimed on all of K = S ∩ Q, not only on the sublevel set.
                let in_s = views
                    .iter()
                    .all(|v| (v.a0 + v.g * yv).norm() <= k.gamma * (1.0 + v.d.dot(&yv)));
                let big_f: f64 = views.iter().map(|v| (v.a0 + v.g * yv).norm_squared()).sum();
                if in_s && big_f <= (1.0 + k.kappa_q).powi(2) * f0 {
                    assert!(
                        model(&yv) <= f + 1e-12 * f0,
                        "instance {instance}: minorant {} above the cost {f} at {y:?} in K",
                        model(&yv)
                    );
                }
                if f > f0 {
                    continue;
                }
                // Rounding of the grid cost and of the model: a few ulps of f(0).
                let tol = 1e-12 * f0;
                assert!(
                    (0..N).all(|j| yv[j] >= lo[j] - tol && yv[j] <= hi[j] + tol),
                    "instance {instance}: {y:?} with f {f} ≤ f(0) {f0} outside the box [{lo:?}, {hi:?}]"
                );
                for v in &views {
                    assert!(
                        v.d.dot(&yv).abs() <= k.kappa_d * (1.0 + 1e-9),
                        "instance {instance}: depth {} beyond κ_d {}",
                        v.d.dot(&yv),
                        k.kappa_d
                    );
                }
                let big_f: f64 = views.iter().map(|v| (v.a0 + v.g * yv).norm_squared()).sum();
                assert!(
                    big_f <= (1.0 + k.kappa_q).powi(2) * f0 * (1.0 + 1e-9) + tol,
                    "instance {instance}: F"
                );
                assert!(
                    model(&yv) <= f + tol,
                    "instance {instance}: minorant {} above the cost {f} at {y:?}",
                    model(&yv)
                );
            }
            // Polish the best grid point by coordinate golden-section searches (any point's cost is
            // an upper bound of the minimum, so the polish cannot make the check fail wrongly).
            let (mut best, mut y) = least;
            let step: [f64; N] = std::array::from_fn(|j| (big_hi[j] - big_lo[j]) / per_axis as f64);
            for _ in 0..30 {
                for j in 0..N {
                    let (mut a, mut b) = (y[j] - step[j], y[j] + step[j]);
                    let at = |t: f64, y: &[f64; N]| {
                        let mut z = *y;
                        z[j] = t;
                        plain_cost(&views, &z).unwrap_or(f64::INFINITY)
                    };
                    for _ in 0..60 {
                        let (c, d) = (b - 0.618 * (b - a), a + 0.618 * (b - a));
                        if at(c, &y) < at(d, &y) {
                            b = d;
                        } else {
                            a = c;
                        }
                    }
                    let t = 0.5 * (a + b);
                    if at(t, &y) < best {
                        best = at(t, &y);
                        y[j] = t;
                    }
                }
            }
            assert!(
                bound <= best + 1e-12 * f0,
                "instance {instance}: bound {bound} above the cost {best} at {y:?} (f(0) = {f0})"
            );
            passed += 1;
        }
        passed
    }

    #[test]
    fn minorants_of_random_charts_centred_away_from_the_minimiser_stay_below_the_cost_in_one_dimension() {
        // How many instances pass the test is not the point; a handful must, or nothing was checked.
        let passed = check_minorants::<1, 1>(11, 3000, 4001) + check_minorants::<2, 1>(12, 2000, 4001);
        assert!(passed >= 200, "only {passed} instances passed the test");
    }

    #[test]
    fn minorants_of_random_charts_centred_away_from_the_minimiser_stay_below_the_cost_in_two_dimensions() {
        let passed = check_minorants::<1, 2>(21, 600, 161) + check_minorants::<2, 2>(22, 600, 161);
        assert!(passed >= 100, "only {passed} instances passed the test");
    }
    /// Mean-depth-like charts (`Σᵢ dᵢ = 0`, so `Σᵢ ζᵢ = n` and every chart point with all `ζᵢ > 0`
    /// has `|dᵢᵀy| < n − 1`, the a-priori bound of points) of 4 to 12 views in one unknown, with
    /// residuals and perspective large enough that stage 2 starts from the a-priori `κ = n − 1` with
    /// radii above 1. Every point of the chart's domain with `f ≤ f(0)` on a 20001-point grid lies in
    /// the enclosure: `|dᵢᵀy| ≤ κ_d` and `F(y) ≤ (1 + κ_Q)² f(0)`.
    #[test]
    fn enclosures_from_the_a_priori_depth_bound_hold_every_point_of_the_sublevel_set() {
        let mut rng = Rng::new(39);
        let (mut enclosed, mut points) = (0, 0);
        for instance in 0..3000 {
            let n = 4 + rng.below(9);
            let residual = 10f64.powf(rng.uniform_in(-1.0, 0.7));
            let perspective = 10f64.powf(rng.uniform_in(-1.0, 0.5));
            let mut views: Vec<RatioView<1, 1>> = (0..n)
                .map(|_| RatioView {
                    a0: SVector::from([residual * rng.normal()]),
                    g: SMatrix::from([[rng.normal()]]),
                    d: SVector::from([perspective * rng.normal()]),
                })
                .collect();
            let mean = views.iter().map(|v| v.d[0]).sum::<f64>() / n as f64;
            for v in &mut views {
                v.d[0] -= mean;
            }
            let f0: f64 = views.iter().map(|v| v.a0.norm_squared()).sum();
            let Some(k) = enclosure(&views, f0, f0.sqrt(), Some(n as f64 - 1.0)) else {
                continue;
            };
            enclosed += 1;
            // Tight as well as sound: unless stage 2 never refined (`κ_d = κ_Q`), `κ_d` is the largest
            // depth over the ellipsoid `F ≤ (1 + κ_Q)² f(0)` (the roots of the quadratic `F`, written
            // out), widened by the margin `KAPPA_MARGIN`.
            let (qa, qb, qc) = views
                .iter()
                .fold((0.0, 0.0, -(1.0 + k.kappa_q).powi(2) * f0), |(a, b, c), v| {
                    let (g, a0) = (v.g[(0, 0)], v.a0[0]);
                    (a + g * g, b + 2.0 * g * a0, c + a0 * a0)
                });
            let disc = (qb * qb - 4.0 * qa * qc).max(0.0).sqrt();
            let ends = [(-qb - disc) / (2.0 * qa), (-qb + disc) / (2.0 * qa)];
            let deepest = views
                .iter()
                .flat_map(|v| ends.map(|y| (v.d[0] * y).abs()))
                .fold(0.0, f64::max);
            // Rounding of the roots and of κ_d's own formula: ~1e-12 relative to the terms, well
            // inside the margin's 1e-6.
            assert!(
                k.kappa_d == k.kappa_q || k.kappa_d <= deepest * (1.0 + KAPPA_MARGIN) * (1.0 + 1e-9) + 1e-12,
                "instance {instance} ({n} views): κ_d {} above the ellipsoid's largest depth {deepest}",
                k.kappa_d
            );
            // The chart's domain {all ζᵢ > 0} is the interval (lo, hi) between the nearest poles.
            let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
            for v in &views {
                let pole = -1.0 / v.d[0];
                if v.d[0] > 0.0 {
                    lo = lo.max(pole);
                } else if v.d[0] < 0.0 {
                    hi = hi.min(pole);
                }
            }
            let (lo, hi) = (lo.max(-1e3), hi.min(1e3));
            for i in 1..20_000 {
                let y = lo + (hi - lo) * i as f64 / 20_000.0;
                let Some(f) = plain_cost(&views, &[y]) else {
                    continue;
                };
                if f > f0 {
                    continue;
                }
                points += 1;
                for v in &views {
                    assert!(
                        (v.d[0] * y).abs() <= k.kappa_d * (1.0 + 1e-9),
                        "instance {instance} ({n} views): depth {} at y = {y} (f {f} ≤ f(0) {f0}) beyond κ_d {}",
                        v.d[0] * y,
                        k.kappa_d
                    );
                }
                let big_f: f64 = views.iter().map(|v| (v.a0[0] + v.g[(0, 0)] * y).powi(2)).sum();
                // Rounding of F at a point where it is ~f(0): a few ulps.
                assert!(
                    big_f <= (1.0 + k.kappa_q).powi(2) * f0 * (1.0 + 1e-9),
                    "instance {instance} ({n} views): F {big_f} at y = {y} beyond (1 + κ_Q)² f(0), κ_Q {}",
                    k.kappa_q
                );
            }
        }
        eprintln!("{enclosed} enclosures, {points} sublevel points checked");
        assert!(enclosed >= 300, "{enclosed}");
    }

    /// Charts of two or three views whose residuals are large against the perspective: each view's
    /// `t = dᵢ r̂ᵢ / gᵢ` (the ratio that decides the sign of its curvature, module docs stage 3)
    /// between −0.4 and 0.4, the region where the test is close to failing and the cost's curvature
    /// on the enclosure comes closest to the minorant's.
    fn adversarial_chart(rng: &mut Rng) -> Vec<RatioView<1, 1>> {
        let views = 2 + rng.below(2);
        (0..views)
            .map(|_| {
                let g = rng.normal();
                let a0 = 10f64.powf(rng.uniform_in(-1.5, 0.0)) * rng.normal();
                let t = rng.uniform_in(-0.4, 0.4);
                RatioView {
                    a0: SVector::from([a0]),
                    g: SMatrix::from([[g]]),
                    d: SVector::from([t * g / a0]),
                }
            })
            .collect()
    }

    /// Stage 3's claim, checked pointwise: the minorant's Hessian `H = (1 − μ)P` is at most the cost's
    /// curvature at every point of the enclosure `K = S ∩ Q` (central differences of the cost written out
    /// in [`plain_cost`], on a 4001-point grid of `K`'s bounding box). The inequality chain has slack
    /// (the cost's curvature on `K` comes down to about twice `H` on the worst of these charts, none
    /// lower), so a minorant twice as curved (`P` doubled) is caught only on those worst charts; halving
    /// the `6` of `μ` is not caught here (the documented-formula test below catches it).
    #[test]
    fn the_minorants_curvature_is_below_the_costs_on_the_enclosure() {
        let mut rng = Rng::new(31);
        let (mut passed, mut points) = (0, 0);
        for instance in 0..40_000 {
            let views = adversarial_chart(&mut rng);
            let Some(m) = minorant(&views, None) else {
                continue;
            };
            let f0: f64 = views.iter().map(|v| v.a0.norm_squared()).sum();
            let k = enclosure(&views, f0, f0.sqrt(), None).expect("the minorant's enclosure");
            let (lo, hi) = k.bounding_box().expect("a bounding box");
            let h = (m.hessian.l() * m.hessian.l().transpose())[(0, 0)];
            let step = (hi[0] - lo[0]) / 4000.0;
            let in_k = |y: f64| {
                let in_s = views.iter().all(|v| {
                    let zeta = 1.0 + v.d[0] * y;
                    zeta > 0.0 && (v.a0[0] + v.g[(0, 0)] * y).abs() <= f0.sqrt() * zeta
                });
                let big_f: f64 = views.iter().map(|v| (v.a0[0] + v.g[(0, 0)] * y).powi(2)).sum();
                in_s && big_f <= (1.0 + k.kappa_q).powi(2) * f0
            };
            passed += 1;
            for i in 1..4000 {
                let y = lo[0] + step * i as f64;
                if !(in_k(y - step) && in_k(y) && in_k(y + step)) {
                    continue;
                }
                let f = |y: f64| plain_cost(&views, &[y]).expect("inside the domain");
                let curvature = (f(y + step) - 2.0 * f(y) + f(y - step)) / (step * step);
                // Rounding of the three costs (a few ulps of f(0), divided by step²) and the
                // truncation of central differences (step ~1e-4 of K: ~1e-8 relative).
                let tol = 1e-6 * h + 1e-14 * f0 / (step * step);
                assert!(
                    curvature >= h - tol,
                    "instance {instance}: the cost's curvature {curvature} at {y} is below the minorant's {h}"
                );
                points += 1;
            }
        }
        assert!(passed >= 1000 && points >= 100_000, "{passed} charts, {points} points");
    }

    /// The minorant of stage 4 is the documented one, recomputed here from the module docs' formulas
    /// and the enclosure: `g` is the cost's gradient at the origin (central differences of
    /// [`plain_cost`]), `H = (1 − μ)P` with `P = 2N/(3(1 + κ_d)²)`, `R² = (1 + κ_Q)² ε₀²/(1 − κ_d)²`,
    /// `μ = 6R²/(1 − κ_d)² maxᵢ dᵢᵀP⁻¹dᵢ`, and the test passes exactly when `μ < 1 − 10⁻⁶`. The
    /// constants are the proof's (θ = 2/3 gives the factors ⅓ and 3); a minorant more curved than the
    /// proof allows, which the pointwise check above meets only where the proof's slack runs out, is
    /// caught here on every chart.
    #[test]
    fn the_minorant_is_the_documented_one() {
        let mut rng = Rng::new(37);
        let mut compared = 0;
        for _ in 0..3000 {
            let views = adversarial_chart(&mut rng);
            let f0: f64 = views.iter().map(|v| v.a0.norm_squared()).sum();
            let Some(k) = enclosure(&views, f0, f0.sqrt(), None) else {
                assert!(minorant(&views, None).is_none());
                continue;
            };
            let n: f64 = views.iter().map(|v| v.g[(0, 0)].powi(2)).sum();
            let r2 = (1.0 + k.kappa_q).powi(2) * f0 / (1.0 - k.kappa_d).powi(2);
            let p = 2.0 * n / (3.0 * (1.0 + k.kappa_d).powi(2));
            let worst = views.iter().map(|v| v.d[0] * v.d[0] / p).fold(0.0, f64::max);
            let mu = 6.0 * r2 / (1.0 - k.kappa_d).powi(2) * worst;
            let m = minorant(&views, None);
            assert_eq!(m.is_some(), mu < 1.0 - 1e-6, "μ = {mu}");
            let Some(m) = m else {
                continue;
            };
            let h = (m.hessian.l() * m.hessian.l().transpose())[(0, 0)];
            assert!((h - (1.0 - mu) * p).abs() <= 1e-9 * p, "{h} vs {}", (1.0 - mu) * p);
            let e = 1e-6 * (f0.sqrt() / n.sqrt()).max(1e-12);
            let f = |y: f64| plain_cost(&views, &[y]).unwrap();
            let gradient = (f(e) - f(-e)) / (2.0 * e);
            assert!(
                (m.gradient[0] - gradient).abs() <= 1e-5 * (gradient.abs() + f0.sqrt() * n.sqrt()),
                "{} vs {gradient}",
                m.gradient[0]
            );
            compared += 1;
        }
        assert!(compared >= 200, "{compared}");
    }

    /// A random minorant `m(y) = f₀ + gᵀy + ½yᵀHy` in `N` unknowns (`H` of condition up to ~1e3) and a
    /// random constraint `φ(y) = (c₀ + kᵀy)² − s₀ − pᵀy ≥ 0`, in the regimes that matter: the
    /// unconstrained minimiser infeasible (the constraint active) or feasible, `k = 0` (a half-space),
    /// `p = 0`, and `s₀` of either sign.
    fn random_constrained<const N: usize>(
        rng: &mut Rng,
        case: usize,
    ) -> (Minorant<N>, f64, SVector<f64, N>, f64, SVector<f64, N>) {
        let a = SMatrix::<f64, N, N>::from_fn(|_, _| rng.normal());
        let h = a.transpose() * a + SMatrix::<f64, N, N>::identity() * 10f64.powf(rng.uniform_in(-1.5, 0.5));
        let cost = 10f64.powf(rng.uniform_in(-1.0, 1.0));
        let hessian = h.cholesky().expect("positive definite");
        // The unconstrained decrease ½gᵀH⁻¹g from 0.05 f₀ to 1.2 f₀ (the cap at 0 rarely decides).
        let direction = SVector::<f64, N>::from_fn(|_, _| rng.normal());
        let decrease = 0.5 * direction.dot(&hessian.solve(&direction));
        let gradient = direction * (cost * rng.uniform_in(0.05, 1.2) / decrease).sqrt();
        let m = Minorant {
            cost,
            gradient,
            hessian,
        };
        let scale = 10f64.powf(rng.uniform_in(-1.0, 1.0));
        let k = if case % 7 == 0 {
            SVector::<f64, N>::zeros()
        } else {
            SVector::<f64, N>::from_fn(|_, _| rng.normal()) * scale
        };
        let p = if case % 5 == 0 {
            SVector::<f64, N>::zeros()
        } else {
            SVector::<f64, N>::from_fn(|_, _| rng.normal()) * scale
        };
        // s₀ puts the unconstrained minimiser y* on either side of the boundary (φ(y*) = −δ), about as
        // often inside as outside, or anywhere.
        let c0 = rng.normal() * 0.5;
        let free = -m.hessian.solve(&m.gradient);
        let s0 = if case % 3 == 0 {
            rng.normal()
        } else {
            (c0 + k.dot(&free)).powi(2) - p.dot(&free) + rng.normal() * (1.0 + scale * scale)
        };
        (m, c0, k, s0, p)
    }

    /// `m(y)` written out.
    fn minorant_value<const N: usize>(m: &Minorant<N>, y: &SVector<f64, N>) -> f64 {
        let h = m.hessian.l() * m.hessian.l().transpose();
        m.cost + m.gradient.dot(y) + 0.5 * y.dot(&(h * y))
    }

    /// The S-lemma step against the exact constrained minimum in one unknown: `φ` is a convex
    /// quadratic in `y`, so the feasible set is the line less an open interval (the roots of `φ`,
    /// closed form), and the least `m` there is at the unconstrained minimiser when it is feasible and
    /// at a root otherwise. The bound (which the code caps at `f₀`, part of the proof) must not exceed
    /// that minimum; with its rounding margin of 1e-9 `f₀` it sits below it, so a margin added instead
    /// of subtracted fails here, while the rounding of this oracle is ~1e-15 `f₀`. And it is the
    /// S-lemma's exact value (the gap closes for one constraint) within 1e-6 on most of them.
    #[test]
    fn the_constrained_minimum_is_below_the_exact_minimum_in_one_unknown() {
        let mut rng = Rng::new(41);
        let (mut active, mut tight, mut checked) = (0, 0, 0);
        for case in 0..20_000 {
            let (m, c0, k, s0, p) = random_constrained::<1>(&mut rng, case);
            let bound = m.minimum_subject_to(c0, &k, s0, &p);
            let h = (m.hessian.l() * m.hessian.l().transpose())[(0, 0)];
            let phi = |y: f64| (c0 + k[0] * y).powi(2) - s0 - p[0] * y;
            let model = |y: f64| m.cost + m.gradient[0] * y + 0.5 * h * y * y;
            let free = -m.gradient[0] / h;
            // φ(y) = A y² + B y + C.
            let (qa, qb, qc) = (k[0] * k[0], 2.0 * c0 * k[0] - p[0], c0 * c0 - s0);
            let exact = if phi(free) >= 0.0 {
                model(free)
            } else if qa == 0.0 && qb == 0.0 {
                // φ a negative constant: nothing is feasible.
                f64::INFINITY
            } else if qa == 0.0 {
                // A half-line: its end.
                model(-qc / qb)
            } else {
                let disc = (qb * qb - 4.0 * qa * qc).max(0.0).sqrt();
                let roots = [(-qb - disc) / (2.0 * qa), (-qb + disc) / (2.0 * qa)];
                active += 1;
                roots.map(model).into_iter().fold(f64::INFINITY, f64::min)
            };
            // The cost is never negative: the bound is capped at 0 below as well as at f₀ above.
            let target = exact.min(m.cost).max(0.0);
            assert!(
                bound <= target + 1e-12 * m.cost,
                "case {case}: bound {bound} above the least feasible value {target} (f₀ {})",
                m.cost
            );
            tight += usize::from(bound >= target - 1e-6 * m.cost);
            checked += 1;
        }
        eprintln!("{active} active constraints; the bound exact on {tight} of {checked}");
        assert!(active >= 5000, "only {active} active constraints");
        assert!(
            tight * 10 >= checked * 9,
            "the bound is the exact minimum on only {tight} of {checked}"
        );
    }

    /// The same in two unknowns against the exact minimum on the feasible set's boundary: with `e`
    /// along `k` and `e⊥` across it, `φ` is linear in the `e⊥` coordinate, so the boundary `φ = 0` is
    /// the graph of a quadratic over the `e` coordinate, minimised by a scan and golden sections (an
    /// upper estimate of the minimum, so it cannot fail wrongly); and at random feasible points.
    #[test]
    fn the_constrained_minimum_is_below_the_minimum_on_the_boundary_in_two_unknowns() {
        let mut rng = Rng::new(43);
        let (mut active, mut tight) = (0, 0);
        let cases = 3000;
        for case in 0..cases {
            let (m, c0, k, s0, p) = random_constrained::<2>(&mut rng, case + 1);
            let bound = m.minimum_subject_to(c0, &k, s0, &p);
            let phi = |y: &Vector2<f64>| (c0 + k.dot(y)).powi(2) - s0 - p.dot(y);
            let free = -m.hessian.solve(&m.gradient);
            let mut least = m.cost;
            if phi(&free) >= 0.0 {
                least = least.min(minorant_value(&m, &free));
            } else if k.norm() > 0.0 && p.norm() > 0.0 {
                active += 1;
                let e = k.normalize();
                let across = Vector2::new(-e.y, e.x);
                let (kn, pe, pa) = (k.norm(), p.dot(&e), p.dot(&across));
                if pa.abs() < 1e-3 * p.norm() {
                    continue;
                }
                // φ(α e + β e⊥) = (c₀ + ‖k‖α)² − s₀ − p_e α − p_⊥ β = 0.
                let point = |alpha: f64| {
                    let beta = ((c0 + kn * alpha).powi(2) - s0 - pe * alpha) / pa;
                    e * alpha + across * beta
                };
                let along = |alpha: f64| minorant_value(&m, &point(alpha));
                let reach = 10.0 * (1.0 + free.norm() + (s0.abs() + c0 * c0).sqrt() / kn);
                let steps = 4000;
                let h = 2.0 * reach / steps as f64;
                let (mut best_alpha, mut best) = (0.0, f64::INFINITY);
                for i in 0..=steps {
                    let alpha = -reach + h * i as f64;
                    if along(alpha) < best {
                        (best_alpha, best) = (alpha, along(alpha));
                    }
                }
                let (mut lo, mut hi) = (best_alpha - h, best_alpha + h);
                let g = (5f64.sqrt() - 1.0) / 2.0;
                for _ in 0..120 {
                    let (x, y) = (hi - g * (hi - lo), lo + g * (hi - lo));
                    if along(x) < along(y) {
                        hi = y;
                    } else {
                        lo = x;
                    }
                }
                least = least.min(best).min(along(0.5 * (lo + hi)));
            } else {
                continue;
            }
            // Random feasible points near the minimiser: none below the bound either.
            for _ in 0..50 {
                let y = free + Vector2::new(rng.normal(), rng.normal()) * (1.0 + free.norm());
                if phi(&y) >= 0.0 {
                    least = least.min(minorant_value(&m, &y));
                }
            }
            let least = least.max(0.0);
            assert!(
                bound <= least + 1e-12 * m.cost,
                "case {case}: bound {bound} above the feasible value {least} (f₀ {})",
                m.cost
            );
            tight += usize::from(bound >= least - 1e-6 * m.cost);
        }
        eprintln!("{active} active constraints; the bound exact on {tight} of {cases}");
        assert!(active >= 600, "only {active} active constraints");
        assert!(
            tight * 10 >= cases * 8,
            "the bound is the exact minimum on only {tight} of {cases}"
        );
    }

    /// In the quadric's nine unknowns, against the constrained minimiser found from the primal side:
    /// `y(λ)` minimises `m − λφ` (a linear solve of the full `H − 2λkkᵀ` by LU, not the code's
    /// Sherman-Morrison), `φ(y(λ))` increases with `λ` (the dual is concave), and bisection on its sign
    /// gives a feasible point with `φ ≥ 0` at which `m` is the constrained minimum up to the
    /// bisection's width. `m` there, and at random feasible points, is at least the bound.
    #[test]
    fn the_constrained_minimum_is_below_the_feasible_minimiser_in_nine_unknowns() {
        let mut rng = Rng::new(47);
        let (mut active, mut tight) = (0, 0);
        let cases = 3000;
        for case in 0..cases {
            let (m, c0, k, s0, p) = random_constrained::<9>(&mut rng, case);
            let bound = m.minimum_subject_to(c0, &k, s0, &p);
            let h = m.hessian.l() * m.hessian.l().transpose();
            let phi = |y: &SVector<f64, 9>| (c0 + k.dot(y)).powi(2) - s0 - p.dot(y);
            let stationary = |lambda: f64| {
                let a = h - k * k.transpose() * (2.0 * lambda);
                let rhs = -(m.gradient - k * (2.0 * lambda * c0) + p * lambda);
                a.lu().solve(&rhs)
            };
            let free = stationary(0.0).expect("H is invertible");
            let mut least = m.cost;
            if phi(&free) >= 0.0 {
                least = least.min(minorant_value(&m, &free));
            } else {
                // λ below 1/(2 kᵀH⁻¹k), where H − 2λkkᵀ stays positive definite.
                let kk = k.dot(&m.hessian.solve(&k));
                let top = if kk > 0.0 { 0.5 / kk } else { 1e12 };
                let (mut lo, mut hi) = (0.0, top);
                let mut feasible = None;
                for _ in 0..200 {
                    let mid = 0.5 * (lo + hi);
                    match stationary(mid) {
                        Some(y) if phi(&y) >= 0.0 => {
                            feasible = Some(y);
                            hi = mid;
                        }
                        _ => lo = mid,
                    }
                }
                if let Some(y) = feasible {
                    active += 1;
                    least = least.min(minorant_value(&m, &y));
                }
            }
            for _ in 0..50 {
                let y = free + SVector::<f64, 9>::from_fn(|_, _| rng.normal()) * (1.0 + free.norm());
                if phi(&y) >= 0.0 {
                    least = least.min(minorant_value(&m, &y));
                }
            }
            let least = least.max(0.0);
            assert!(
                bound <= least + 1e-12 * m.cost,
                "case {case}: bound {bound} above the feasible value {least} (f₀ {})",
                m.cost
            );
            tight += usize::from(bound >= least - 1e-6 * m.cost);
        }
        eprintln!("{active} active constraints; the bound exact on {tight} of {cases}");
        assert!(
            active >= 1000,
            "only {active} active constraints with a feasible minimiser"
        );
        assert!(
            tight * 10 >= cases * 8,
            "the bound is the exact minimum on only {tight} of {cases}"
        );
    }
}
