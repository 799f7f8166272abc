//! Interval Taylor bounds of a sum of squared ratios of quadratic polynomials over a box.
//!
//! The cost is `f(w) = Σᵥ ‖rᵥ(w)‖²` with `rᵥ = nᵥ(w) / gᵥ(w)`, every entry of `nᵥ` and `gᵥ` a
//! quadratic polynomial on `ℝᴺ` ([`Quadratic`]). Over a box `Q` (centre `m`, half-widths `h`) the
//! polynomials, their gradients and (constant) Hessians have exact or nearly exact interval
//! enclosures (the centred form `s(m) + ∇s(m)·δ + ½ δᵀSδ`), and interval arithmetic
//! ([`super::interval`]) carries them through the quotient rule to enclosures of `rᵥ`, `∇rᵥ`, `∇²rᵥ`
//! and then of `∇f` and `∇²f` on `Q`. From these ([`bound_over_box`]):
//! - the **zeroth-order bound** `Σ mig([rᵥₖ])²`, with `mig([rᵥₖ]) ≥ mig([nᵥₖ]) / mag([gᵥ])` also where the
//!   denominator interval contains 0 (near a pole the residual is large, not unknown);
//! - the **second-order Taylor bound**: along the segment from `m` to any `m + δ ∈ Q`,
//!   `f(m + δ) = f(m) + ∇f(m)·δ + ½ δᵀ∇²f(ξ)δ` for some `ξ ∈ Q`, and `∇²f(ξ) ⪰ μ I` with `μ` the
//!   Gershgorin lower bound of the interval Hessian, so `f ≥ f(m) + Σᵢ min_{|δᵢ| ≤ hᵢ} (∂ᵢf(m) δᵢ +
//!   ½ μ δᵢ²)` on `Q` (valid for any sign of `μ`; tight, to second order, where `f` is convex);
//! - the **stationarity test**: when some `[∂ᵢf]` excludes 0, `Q` holds no stationary point.
//!
//! A denominator interval containing 0 makes the derivative enclosures of its view infinite (no
//! Taylor bound, no stationarity test for that box); the zeroth-order bound keeps `mig(n)/mag(g)`. The bounds are the pieces of the
//! interval branch and bound of [`crate::triangulation::line::taylor_search`].

use super::interval::Interval;
use nalgebra::{SMatrix, SVector};
use std::ops::{Add, Div, Mul, Sub};

/// Relative widening of every bound for rounding (module docs of [`super::interval`]).
pub const ROUNDING_MARGIN: f64 = 1e-9;

/// The quadratic polynomial `s(w) = c + gᵀw + ½ wᵀSw` on `ℝᴺ` (`S` symmetric).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Quadratic<const N: usize> {
    /// `c = s(0)`.
    pub constant: f64,
    /// `g = ∇s(0)`.
    pub gradient: SVector<f64, N>,
    /// `S = ∇²s`.
    pub hessian: SMatrix<f64, N, N>,
}

impl<const N: usize> Quadratic<N> {
    /// The zero polynomial.
    pub fn zero() -> Self {
        Quadratic {
            constant: 0.0,
            gradient: SVector::zeros(),
            hessian: SMatrix::zeros(),
        }
    }

    /// `s(w)`.
    pub fn value(&self, w: &SVector<f64, N>) -> f64 {
        self.constant + self.gradient.dot(w) + 0.5 * w.dot(&(self.hessian * w))
    }

    /// `∇s(w)`.
    pub fn gradient_at(&self, w: &SVector<f64, N>) -> SVector<f64, N> {
        self.gradient + self.hessian * w
    }

    /// `Σ cⱼ sⱼ`.
    pub fn combination<'a>(terms: impl IntoIterator<Item = (f64, &'a Quadratic<N>)>) -> Self {
        terms.into_iter().fold(Quadratic::zero(), |acc, (c, s)| Quadratic {
            constant: acc.constant + c * s.constant,
            gradient: acc.gradient + s.gradient * c,
            hessian: acc.hessian + s.hessian * c,
        })
    }

    /// The polynomial in new variables `u` with `w = M u`: `c`, `Mᵀg`, `MᵀSM`.
    pub fn substitute(&self, m: &SMatrix<f64, N, N>) -> Self {
        Quadratic {
            constant: self.constant,
            gradient: m.transpose() * self.gradient,
            hessian: m.transpose() * self.hessian * m,
        }
    }

    /// An enclosure of `s` over the box `m ± h` (centred form).
    pub fn range(&self, m: &SVector<f64, N>, h: &SVector<f64, N>) -> Interval {
        self.enclose(m, h).0
    }

    /// Value and gradient enclosures over the box `m ± h` (centred form, exact for the gradient).
    fn enclose(&self, m: &SVector<f64, N>, h: &SVector<f64, N>) -> (Interval, [Interval; N], f64, SVector<f64, N>) {
        let value = self.value(m);
        let grad = self.gradient_at(m);
        let abs_s = self.hessian.abs();
        let spread = abs_s * h;
        let radius = grad.abs().dot(h) + 0.5 * h.dot(&spread);
        let grads = std::array::from_fn(|i| Interval::centred(grad[i], spread[i]));
        (Interval::centred(value, radius), grads, value, grad)
    }
}

/// One view's residual `r(w) = n(w) / g(w)` with `D` entries (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QuadraticRatio<const D: usize, const N: usize> {
    /// The numerators `nₖ`.
    pub numerator: [Quadratic<N>; D],
    /// The denominator `g`.
    pub denominator: Quadratic<N>,
}

#[cfg(test)]
impl<const D: usize, const N: usize> QuadraticRatio<D, N> {
    /// `r(w)`.
    pub fn residual(&self, w: &SVector<f64, N>) -> SVector<f64, D> {
        let g = self.denominator.value(w);
        SVector::from_fn(|k, _| self.numerator[k].value(w) / g)
    }
}

/// `f(w)` and `∇f(w)`.
pub fn cost_and_gradient<const D: usize, const N: usize>(
    views: &[QuadraticRatio<D, N>],
    w: &SVector<f64, N>,
) -> (f64, SVector<f64, N>) {
    let mut f = 0.0;
    let mut grad = SVector::zeros();
    for v in views {
        let g = v.denominator.value(w);
        let dg = v.denominator.gradient_at(w);
        for n in &v.numerator {
            let r = n.value(w) / g;
            f += r * r;
            grad += (n.gradient_at(w) - dg * r) * (2.0 * r / g);
        }
    }
    (f, grad)
}

/// What [`bound_over_box`] proved about a box.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoxBound {
    /// A lower bound of `f` over the box (at least 0), widened for rounding.
    pub lower: f64,
    /// `f` at the centre of the box.
    pub centre_cost: f64,
    /// False when some `[∂ᵢf]` excludes 0: the box holds no stationary point of `f`.
    pub may_be_stationary: bool,
    /// The largest lower bound of a single view's `‖rᵥ‖²` over the box.
    pub worst_view: f64,
    /// The Gershgorin lower bound `μ` of the Hessian's eigenvalues over the box (`−∞` when a
    /// denominator may vanish).
    pub curvature: f64,
}

/// The bounds of the module docs over the box `[lower, upper]`.
///
/// `target` (`∞`: none) is the bound the caller needs to discard the box: a view whose denominator
/// may vanish on the box gets the projective test [`ratio_exceeds`] at the share of `target` the other
/// views leave it.
pub fn bound_over_box<const D: usize, const N: usize>(
    views: &[QuadraticRatio<D, N>],
    lower: &[f64],
    upper: &[f64],
    target: f64,
) -> BoxBound {
    let m = SVector::<f64, N>::from_fn(|i, _| 0.5 * (lower[i] + upper[i]));
    let h = SVector::<f64, N>::from_fn(|i, _| 0.5 * (upper[i] - lower[i]));
    let mut zeroth = 0.0;
    let mut worst_view: f64 = 0.0;
    let mut centre_cost = 0.0;
    let mut centre_grad = SVector::<f64, N>::zeros();
    let mut grad = [Interval::point(0.0); N];
    let mut hess = [[Interval::point(0.0); N]; N];
    let mut poles: Vec<(usize, f64)> = Vec::new();
    for (index, v) in views.iter().enumerate() {
        let (g, dg, g_m, dg_m) = v.denominator.enclose(&m, &h);
        let mut view_lower = 0.0;
        for n in &v.numerator {
            let (num, dnum, n_m, dn_m) = n.enclose(&m, &h);
            // Point values at the centre.
            let r_m = n_m / g_m;
            let dr_m = (dn_m - dg_m * r_m) / g_m;
            centre_cost += r_m * r_m;
            centre_grad += dr_m * (2.0 * r_m);
            // ∇r = (∇n − r ∇g) / g, first with the natural enclosure of r, then with the centred one.
            let natural = num.div(g);
            let d_r = |r: Interval| -> [Interval; N] { std::array::from_fn(|i| dnum[i].sub(r.mul(dg[i])).div(g)) };
            let dr_natural = d_r(natural);
            let centred = (0..N).fold(Interval::point(r_m), |acc, i| {
                acc.add(dr_natural[i].mul(Interval::centred(0.0, h[i])))
            });
            let r = if natural.lo.is_finite() && natural.hi.is_finite() {
                natural.meet(centred)
            } else {
                centred
            };
            let dr = d_r(r);
            // |r| = |n|/|g| ≥ mig(n)/mag(g) holds where g may vanish too (near a pole of r).
            let term = r.mig().max(num.mig() / g.mag()).powi(2);
            view_lower += term;
            for i in 0..N {
                grad[i] = grad[i].add(r.mul(dr[i]).scale(2.0));
                for j in i..N {
                    // ∂ᵢⱼr = (∂ᵢⱼn − ∂ᵢr ∂ⱼg − ∂ᵢg ∂ⱼr − r ∂ᵢⱼg) / g.
                    let d2r = Interval::point(n.hessian[(i, j)])
                        .sub(dr[i].mul(dg[j]))
                        .sub(dg[i].mul(dr[j]))
                        .sub(r.mul(Interval::point(v.denominator.hessian[(i, j)])))
                        .div(g);
                    let outer = if i == j { dr[i].sqr() } else { dr[i].mul(dr[j]) };
                    hess[i][j] = hess[i][j].add(outer.add(r.mul(d2r)).scale(2.0));
                }
            }
        }
        if g.contains_zero() {
            poles.push((index, view_lower));
        }
        zeroth += view_lower;
        worst_view = worst_view.max(view_lower);
    }
    for (index, view_lower) in poles {
        let share = target - (zeroth - view_lower);
        if share.is_finite() && share > view_lower && ratio_exceeds(&views[index], &m, &h, share) {
            zeroth += share - view_lower;
            worst_view = worst_view.max(share);
        }
    }
    // Gershgorin: λ_min(H) ≥ minᵢ (min Hᵢᵢ − Σ_{j≠i} max |Hᵢⱼ|) for every H in the interval matrix.
    let curvature = (0..N)
        .map(|i| {
            let off: f64 = (0..N)
                .filter(|&j| j != i)
                .map(|j| if j > i { hess[i][j].mag() } else { hess[j][i].mag() })
                .sum();
            hess[i][i].lo - off
        })
        .fold(f64::INFINITY, f64::min);
    let curvature = if curvature.is_nan() {
        f64::NEG_INFINITY
    } else {
        curvature
    };
    let second = if curvature == f64::NEG_INFINITY {
        f64::NEG_INFINITY
    } else {
        centre_cost
            + (0..N)
                .map(|i| {
                    let (g, hi) = (centre_grad[i], h[i]);
                    if curvature > 0.0 {
                        let d = (-g / curvature).clamp(-hi, hi);
                        g * d + 0.5 * curvature * d * d
                    } else {
                        -g.abs() * hi + 0.5 * curvature * hi * hi
                    }
                })
                .sum::<f64>()
    };
    let best = zeroth.max(second);
    let lower = (best - ROUNDING_MARGIN * best.abs().max(centre_cost)).max(0.0);
    // The mean-value form of the gradient, ∇f(m) + [∇²f]·[−h, h], intersected with the natural one.
    let sym = |i: usize, j: usize| if i <= j { hess[i][j] } else { hess[j][i] };
    let grad: [Interval; N] = std::array::from_fn(|i| {
        let mean_value = (0..N).fold(Interval::point(centre_grad[i]), |acc, j| {
            acc.add(sym(i, j).mul(Interval::centred(0.0, h[j])))
        });
        if mean_value.lo.is_finite() && mean_value.hi.is_finite() {
            grad[i].meet(mean_value)
        } else {
            grad[i]
        }
    });
    let may_be_stationary = grad.iter().all(|gi| {
        let slack = ROUNDING_MARGIN * gi.mag().min(1e300) + 1e-300;
        !(gi.lo > slack || gi.hi < -slack)
    });
    BoxBound {
        lower: if lower.is_nan() { 0.0 } else { lower },
        centre_cost,
        may_be_stationary,
        worst_view,
        curvature,
    }
}

/// True when `‖n(w)‖² > t g(w)²` on the box `m ± h`, so that `‖r‖² > t` wherever `r` is defined:
/// the centred second-order form of `φ = ‖n‖² − t g²` (a quartic) with interval Hessian. Unlike the
/// quotient of intervals it keeps the correlation of `n` and `g`, which near a pole (where both are
/// small) is what decides.
pub fn ratio_exceeds<const D: usize, const N: usize>(
    view: &QuadraticRatio<D, N>,
    m: &SVector<f64, N>,
    h: &SVector<f64, N>,
    t: f64,
) -> bool {
    let mut value = 0.0;
    let mut grad = SVector::<f64, N>::zeros();
    let mut hess = [[Interval::point(0.0); N]; N];
    let terms = view
        .numerator
        .iter()
        .map(|n| (1.0, n))
        .chain(std::iter::once((-t, &view.denominator)));
    for (weight, s) in terms {
        let (range, d_range, at_m, d_at_m) = s.enclose(m, h);
        value += weight * at_m * at_m;
        grad += d_at_m * (2.0 * weight * at_m);
        for i in 0..N {
            for j in i..N {
                // ∂ᵢⱼ(s²) = 2 (∂ᵢs ∂ⱼs + s ∂ᵢⱼs).
                let outer = if i == j {
                    d_range[i].sqr()
                } else {
                    d_range[i].mul(d_range[j])
                };
                let term = outer.add(range.scale(s.hessian[(i, j)]));
                hess[i][j] = hess[i][j].add(term.scale(2.0 * weight));
            }
        }
    }
    let mut least = value - grad.abs().dot(h);
    for i in 0..N {
        least += 0.5 * hess[i][i].lo.min(0.0) * h[i] * h[i];
        for j in i + 1..N {
            least -= hess[i][j].mag() * h[i] * h[j];
        }
    }
    least > ROUNDING_MARGIN * value.abs()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;
    use nalgebra::{Matrix4, Vector4};

    /// Three views of random ratios of quadratics in 4 unknowns and a random box of width 1e-3 to 1.
    fn random_ratios_and_box(rng: &mut Rng) -> (Vec<QuadraticRatio<2, 4>>, Vec<f64>, Vec<f64>) {
        let views = (0..3)
            .map(|_| QuadraticRatio {
                numerator: [random_quadratic(rng, 0.2), random_quadratic(rng, 0.2)],
                denominator: random_quadratic(rng, 0.05),
            })
            .collect();
        let centre: Vec<f64> = (0..4).map(|_| rng.normal()).collect();
        let width = 10f64.powf(rng.uniform_in(-3.0, 0.0));
        let lower = centre.iter().map(|c| c - width * rng.uniform()).collect();
        let upper = centre.iter().map(|c| c + width * rng.uniform()).collect();
        (views, lower, upper)
    }

    fn random_quadratic(rng: &mut Rng, scale: f64) -> Quadratic<4> {
        let a = Matrix4::from_fn(|_, _| rng.normal() * scale);
        Quadratic {
            constant: rng.normal() + 3.0,
            gradient: Vector4::from_fn(|_, _| rng.normal()),
            hessian: a + a.transpose(),
        }
    }

    #[test]
    fn quadratic_value_and_gradient_match_the_definition() {
        let mut rng = Rng::new(3);
        let s = random_quadratic(&mut rng, 0.3);
        let w = Vector4::from_fn(|_, _| rng.normal());
        let e = 1e-6;
        for i in 0..4 {
            let mut d = Vector4::zeros();
            d[i] = e;
            let fd = (s.value(&(w + d)) - s.value(&(w - d))) / (2.0 * e);
            assert!((fd - s.gradient_at(&w)[i]).abs() < 1e-6);
        }
    }

    /// Random ratios, random boxes: the bound is below `f` at every sampled point of the box, and
    /// a box whose sampled gradients change sign in every coordinate is never declared free of
    /// stationary points.
    #[test]
    fn bounds_hold_at_every_sampled_point() {
        let mut rng = Rng::new(4);
        let mut checked = 0;
        for _ in 0..300 {
            let (views, lower, upper) = random_ratios_and_box(&mut rng);
            let b = bound_over_box(&views, &lower, &upper, f64::INFINITY);
            let mut signs = [[false; 2]; 4];
            for _ in 0..200 {
                let w = Vector4::from_fn(|i, _| rng.uniform_in(lower[i], upper[i]));
                let (f, g) = cost_and_gradient(&views, &w);
                if !f.is_finite() {
                    continue;
                }
                checked += 1;
                assert!(b.lower <= f * (1.0 + 1e-12), "bound {} above f {f}", b.lower);
                for i in 0..4 {
                    signs[i][usize::from(g[i] > 0.0)] = true;
                }
            }
            if signs.iter().all(|s| s[0] && s[1]) {
                assert!(b.may_be_stationary);
            }
        }
        assert!(checked > 50_000);
    }

    #[test]
    fn second_order_bound_is_tight_at_a_convex_minimum() {
        // f = ‖w‖² + ‖(w₁ + 0.1 w₂², w₃)/(1 + 0.01 w₄)‖²: minimum 0 at w = 0.
        let mut id = [Quadratic::<4>::zero(); 4];
        for (i, q) in id.iter_mut().enumerate() {
            q.gradient[i] = 1.0;
        }
        let one = Quadratic {
            constant: 1.0,
            ..Quadratic::zero()
        };
        let mut bent = id[0];
        bent.hessian[(1, 1)] = 0.2;
        let mut den = one;
        den.gradient[3] = 0.01;
        let views = vec![
            QuadraticRatio {
                numerator: [id[0], id[1]],
                denominator: one,
            },
            QuadraticRatio {
                numerator: [id[2], id[3]],
                denominator: one,
            },
            QuadraticRatio {
                numerator: [bent, id[2]],
                denominator: den,
            },
        ];
        let b = bound_over_box(
            &views,
            &[-0.01, -0.02, -0.01, -0.03],
            &[0.02, 0.01, 0.01, 0.01],
            f64::INFINITY,
        );
        assert!(b.curvature > 1.5, "{}", b.curvature);
        assert!(b.lower <= 0.0 + 1e-15 && b.lower >= 0.0);
        let b = bound_over_box(&views, &[0.1, 0.1, 0.1, 0.1], &[0.11, 0.12, 0.11, 0.11], f64::INFINITY);
        let (f_corner, _) = cost_and_gradient(&views, &Vector4::new(0.1, 0.1, 0.1, 0.1));
        assert!(b.lower > 0.95 * f_corner, "{} vs {f_corner}", b.lower);
        assert!(!b.may_be_stationary);
    }

    /// `f(w) = Σᵥ Σₖ (nᵥₖ(w)/gᵥ(w))²` with every quadratic written out (`c + gᵀw + ½wᵀSw`), not
    /// through [`Quadratic::value`] or [`cost_and_gradient`]; `None` where a denominator vanishes.
    fn plain_cost<const D: usize>(views: &[QuadraticRatio<D, 4>], w: &[f64; 4]) -> Option<f64> {
        let q = |s: &Quadratic<4>| {
            let mut v = s.constant;
            for i in 0..4 {
                v += s.gradient[i] * w[i];
                for j in 0..4 {
                    v += 0.5 * s.hessian[(i, j)] * w[i] * w[j];
                }
            }
            v
        };
        let mut f = 0.0;
        for v in views {
            let g = q(&v.denominator);
            if g == 0.0 {
                return None;
            }
            for n in &v.numerator {
                f += (q(n) / g).powi(2);
            }
        }
        f.is_finite().then_some(f)
    }

    /// The least eigenvalue of the Hessian of [`plain_cost`] at `w` by central differences.
    fn least_curvature<const D: usize>(views: &[QuadraticRatio<D, 4>], w: &[f64; 4], e: f64) -> Option<f64> {
        let at = |di: usize, si: f64, dj: usize, sj: f64| {
            let mut z = *w;
            z[di] += si * e;
            z[dj] += sj * e;
            plain_cost(views, &z)
        };
        let mut h = Matrix4::zeros();
        for i in 0..4 {
            for j in 0..4 {
                h[(i, j)] = (at(i, 1.0, j, 1.0)? - at(i, 1.0, j, -1.0)? - at(i, -1.0, j, 1.0)? + at(i, -1.0, j, -1.0)?)
                    / (4.0 * e * e);
            }
        }
        Some(
            nalgebra::SymmetricEigen::new(0.5 * (h + h.transpose()))
                .eigenvalues
                .min(),
        )
    }

    /// The least value of [`plain_cost`] over the box that projected gradient descent (numerical
    /// gradient, backtracking) reaches from the centre and from random points: an upper bound of the
    /// box's minimum, so a bound above it is wrong.
    fn box_minimum<const D: usize>(views: &[QuadraticRatio<D, 4>], lo: &[f64], hi: &[f64], rng: &mut Rng) -> f64 {
        let project = |w: [f64; 4]| -> [f64; 4] { std::array::from_fn(|i| w[i].clamp(lo[i], hi[i])) };
        let mut best = f64::INFINITY;
        for start in 0..4 {
            let mut w: [f64; 4] = std::array::from_fn(|i| {
                if start == 0 {
                    0.5 * (lo[i] + hi[i])
                } else {
                    rng.uniform_in(lo[i], hi[i])
                }
            });
            let Some(mut f) = plain_cost(views, &w) else {
                continue;
            };
            let mut step = (0..4).map(|i| hi[i] - lo[i]).fold(0.0, f64::max);
            for _ in 0..400 {
                let e = 1e-7 * (1.0 + w.iter().map(|v| v.abs()).fold(0.0, f64::max));
                let grad: [f64; 4] = std::array::from_fn(|i| {
                    let (mut a, mut b) = (w, w);
                    a[i] += e;
                    b[i] -= e;
                    match (plain_cost(views, &a), plain_cost(views, &b)) {
                        (Some(fa), Some(fb)) => (fa - fb) / (2.0 * e),
                        _ => 0.0,
                    }
                });
                let norm = grad.iter().map(|g| g * g).sum::<f64>().sqrt();
                if norm <= 0.0 || norm.is_nan() {
                    break;
                }
                let mut moved = false;
                while step > 1e-14 {
                    let trial = project(std::array::from_fn(|i| w[i] - step * grad[i] / norm));
                    if let Some(ft) = plain_cost(views, &trial).filter(|&ft| ft < f) {
                        (w, f) = (trial, ft);
                        step *= 2.0;
                        moved = true;
                        break;
                    }
                    step *= 0.5;
                }
                if !moved {
                    break;
                }
            }
            best = best.min(f);
        }
        best
    }

    /// Views whose cost is a rotated, badly conditioned quadratic bowl (strong off-diagonal
    /// curvature) bent by small quadratic terms and a mild perspective denominator.
    fn coupled_views(rng: &mut Rng) -> Vec<QuadraticRatio<2, 4>> {
        let rotation = nalgebra::SymmetricEigen::new({
            let a = Matrix4::from_fn(|_, _| rng.normal());
            a + a.transpose()
        })
        .eigenvectors;
        let bend = 10f64.powf(rng.uniform_in(-3.0, -1.0));
        let row = |k: usize, scale: f64, rng: &mut Rng| {
            let a = Matrix4::from_fn(|_, _| rng.normal() * bend);
            Quadratic {
                constant: 0.3 * rng.normal(),
                gradient: rotation.column(k).into_owned() * scale,
                hessian: a + a.transpose(),
            }
        };
        let weak = 10f64.powf(rng.uniform_in(-2.0, -0.5));
        (0..2)
            .map(|v| {
                let mut denominator = Quadratic {
                    constant: 1.0,
                    ..Quadratic::zero()
                };
                denominator.gradient = Vector4::from_fn(|_, _| 0.05 * rng.normal());
                QuadraticRatio {
                    numerator: [
                        row(2 * v, if v == 0 { weak } else { 1.0 }, rng),
                        row(2 * v + 1, 1.0, rng),
                    ],
                    denominator,
                }
            })
            .collect()
    }

    /// Over random boxes of functions whose curvature is mostly off the diagonal: the Gershgorin
    /// curvature is at most the least Hessian eigenvalue at every sampled point, and the bound is
    /// below the box's minimum reached by projected gradient descent. Halving the off-diagonal
    /// term of the Gershgorin bound fails both.
    #[test]
    fn bounds_hold_against_local_minimisation_in_the_box_when_off_diagonal_curvature_matters() {
        let mut rng = Rng::new(41);
        let mut curvature_checks = 0;
        for instance in 0..300 {
            let views = coupled_views(&mut rng);
            let centre: Vec<f64> = (0..4).map(|_| rng.normal()).collect();
            let width = 10f64.powf(rng.uniform_in(-1.5, 0.3));
            let lower: Vec<f64> = centre.iter().map(|c| c - width * rng.uniform_in(0.2, 1.0)).collect();
            let upper: Vec<f64> = centre.iter().map(|c| c + width * rng.uniform_in(0.2, 1.0)).collect();
            let b = bound_over_box(&views, &lower, &upper, f64::INFINITY);
            let least = box_minimum(&views, &lower, &upper, &mut rng);
            // The bound is widened by 1e-9 relative for rounding; the descent's value is exact to ~1e-15.
            assert!(
                b.lower <= least * (1.0 + 1e-12) + 1e-300,
                "instance {instance}: bound {} above the box minimum {least}",
                b.lower
            );
            if b.curvature.is_finite() {
                for _ in 0..20 {
                    let w: [f64; 4] = std::array::from_fn(|i| rng.uniform_in(lower[i], upper[i]));
                    let scale = 1.0 + w.iter().map(|v| v.abs()).fold(0.0, f64::max);
                    if let Some(lambda) = least_curvature(&views, &w, 1e-4 * scale) {
                        // Central differences of a function of size ~1: errors ~1e-8/1e-8 = 1e-5 relative.
                        assert!(
                            b.curvature <= lambda + 1e-5 * (1.0 + lambda.abs()),
                            "instance {instance}: Gershgorin curvature {} above the Hessian's least eigenvalue {lambda}",
                            b.curvature
                        );
                        curvature_checks += 1;
                    }
                }
            }
        }
        assert!(curvature_checks > 1000, "{curvature_checks}");
    }

    /// One view whose ratio `‖n‖²/g²` has a minimum near `w = 0` of size about 1 and whose
    /// denominator bends strongly (gradient and curvature of order 1): the denominator's negative
    /// weight `−t` in `φ = ‖n‖² − t g²` then decides [`ratio_exceeds`].
    fn bent_ratio(rng: &mut Rng) -> QuadraticRatio<2, 4> {
        let mut numerator = [random_quadratic(rng, 0.5), random_quadratic(rng, 0.5)];
        for n in &mut numerator {
            n.constant = rng.normal();
        }
        let mut denominator = random_quadratic(rng, 0.3);
        denominator.constant = 1.0;
        denominator.gradient *= 0.6;
        QuadraticRatio { numerator, denominator }
    }

    /// [`ratio_exceeds`] never claims `‖r‖² > t` over a box that holds a point with `‖r‖² < t`: `t`
    /// is set just above the least ratio over the box found independently ([`plain_cost`] of the one
    /// view, 3000 uniform samples and projected gradient descent), for boxes of half-width 1e-3 to 1.
    /// The claims it does make at `t` 0.1 % below that minimum are counted, so that the test sees the
    /// bound decide (it is tight there); a 2 + weight for 2 · weight in its Hessian fails here.
    #[test]
    fn ratio_exceeds_never_claims_a_box_holding_a_point_below_the_level() {
        let mut rng = Rng::new(47);
        let (mut checked, mut claimed_below) = (0, 0);
        for instance in 0..400 {
            let view = bent_ratio(&mut rng);
            let half = 10f64.powf(rng.uniform_in(-3.0, 0.0));
            let m = Vector4::from_fn(|_, _| rng.normal() * 0.3);
            let h = Vector4::from_fn(|_, _| half * rng.uniform_in(0.3, 1.0));
            let (lo, hi): (Vec<f64>, Vec<f64>) = (0..4).map(|i| (m[i] - h[i], m[i] + h[i])).unzip();
            let views = [view];
            // Boxes the denominator crosses or nears are left out: no minimum to compare there.
            let mut least = f64::INFINITY;
            let mut poles = false;
            for _ in 0..3000 {
                let w: [f64; 4] = std::array::from_fn(|i| rng.uniform_in(lo[i], hi[i]));
                match plain_cost(&views, &w) {
                    Some(f) if view.denominator.value(&Vector4::from(w)).abs() > 1e-3 => least = least.min(f),
                    _ => poles = true,
                }
            }
            if poles || !least.is_finite() {
                continue;
            }
            least = least.min(box_minimum(&views, &lo, &hi, &mut rng));
            // `least` is a value of the ratio at a point of the box (exact to ~1e-15 relative), so
            // every t above it has a point of the box with ratio < t.
            let t = least * (1.0 + 1e-6) + 1e-300;
            assert!(
                !ratio_exceeds(&view, &m, &h, t),
                "instance {instance}: ratio > {t} claimed over a box (half-width {half}) holding ratio {least}"
            );
            checked += 1;
            if ratio_exceeds(&view, &m, &h, least * 0.999) {
                claimed_below += 1;
            }
        }
        eprintln!("{checked} boxes checked; exceeds proved at 0.999 × the minimum on {claimed_below}");
        assert!(checked > 200, "{checked}");
    }

    /// The same against the random ratios of [`bounds_hold_at_every_sampled_point`], now checked
    /// against projected gradient descent inside each box (samples alone miss a narrow valley).
    #[test]
    fn bound_over_box_is_below_a_local_minimisation_inside_random_boxes() {
        let mut rng = Rng::new(43);
        for instance in 0..300 {
            let (views, lower, upper) = random_ratios_and_box(&mut rng);
            let b = bound_over_box(&views, &lower, &upper, f64::INFINITY);
            let least = box_minimum(&views, &lower, &upper, &mut rng);
            if least.is_finite() {
                assert!(
                    b.lower <= least * (1.0 + 1e-12),
                    "instance {instance}: bound {} above the box minimum {least}",
                    b.lower
                );
            }
        }
    }
}
