//! The certificate through a lens: the exact cost in the observed (distorted) pixels bounded from
//! below by a whitened pinhole problem, the *surrogate*, that the search of [`super`] localises.
//!
//! **The cost.** A point's residual is `eᵢ(n) = Lᵢ (K D(n) − uᵢ) = Mᵢ (D(n) − dᵢ)` (`n` its normalised
//! projection, `Mᵢ = Lᵢ K₂`); a segment endpoint's is `r = min_q ‖M (D(q) − d)‖` over the points `q` of the
//! projected line `ℓ` ([`crate::camera::curved_line`]; the reported residual is a local minimum of it, so at
//! least this). `C = Σ r²` is the cost at the answer `P̂`.
//!
//! **The domain.** Poses with the object points and the segments' object endpoints in front of the
//! camera whose point projections, and the points of the curves that the endpoint residuals are
//! measured to, lie in the disc where the lens is proved one-to-one
//! ([`crate::camera::bounds::domain`]).
//!
//! **The surrogate.** Each observation is linearised at the answer ([`crate::camera::linearisation`]): a
//! point at its projection `nᵢ*` (`Wᵢ = Mᵢ Jᵢ*`, `eᵢ* = eᵢ(nᵢ*)`), an endpoint at the point `q*` of
//! `ℓ̂` nearest to it through the lens (`W`, `ê`). The surrogate observes the point at
//! `n̄ᵢ = nᵢ* − Wᵢ⁻¹ eᵢ*` with whitening `Wᵢ`, and the endpoint at `ē = q* − W⁻¹ ê` with covariance
//! `(WᵀW)⁻¹` (normalised coordinates; in the pixels of `K` for [`super`]), so that its residuals are
//! `ℓᵢ = eᵢ* + Wᵢ (n − nᵢ*)` and `ρ = min_q ‖W (q − ē)‖`; at `P̂` they equal the lens residuals, and so
//! do their first derivatives.
//!
//! 1. **Confinement** (module docs of [`crate::camera::linearisation`]): a ball `Bᵢ = {‖Wᵢ (n − nᵢ*)‖ ≤ Rᵢ}`
//!    with `(1 − εᵢ) Rᵢ > √C + ‖eᵢ*‖ + sᵢ` holds every projection (every minimising `q` for an endpoint)
//!    of a pose of the domain with cost at most `C`. Inside it `eᵢ = eᵢ* + (I + Δ) vᵢ` (`vᵢ = Wᵢ (n − nᵢ*)`,
//!    `‖Δ‖ ≤ εᵢ`), so `‖vᵢ‖ ≤ (‖eᵢ‖ + ‖eᵢ*‖ + sᵢ) / (1 − εᵢ)` and
//!    `‖ℓᵢ‖ ≤ ‖eᵢ‖ + εᵢ ‖vᵢ‖ + sᵢ ≤ ‖eᵢ‖ / (1 − εᵢ) + δᵢ`, `δᵢ = εᵢ (‖eᵢ*‖ + sᵢ) / (1 − εᵢ) + sᵢ`; for an
//!    endpoint the same with `r ≥ ‖ê + u‖ − ε ‖u‖ − s` (`u = W (q − q*)`) and `ρ ≤ ‖ê + u‖`. Weighted,
//!    `(1 − εᵢ) ‖ℓᵢ‖ ≤ ‖eᵢ‖ + (1 − εᵢ) δᵢ`: the rotation search of [`super`] runs on the surrogate with
//!    each observation's whitening scaled by `1 − εᵢ` (its cost `Q̃`), where every pose with `F ≤ C`
//!    has `√Q̃ ≤ √F + δ̃`, `δ̃ = ‖((1 − εᵢ) δᵢ)‖` (Minkowski). The search localises `Q̃`'s sublevel set at
//!    the level `(√C + δ̃)²`, and a box bound `q̃` of `Q̃` is one of `(√q̃ − δ̃)₊²` on `F` ([`Slack`]).
//!    An observation far off the linear model pays only its own `εᵢ` (a common factor
//!    `1 / (1 − maxᵢ εᵢ)` would let the worst one loosen every other). A point that is not confined
//!    (its ball reaches the edge of the disc, or `εᵢ` stays too large) is left out of the search:
//!    `F ≥` the cost of the others, which the search bounds; step 4 takes every observation.
//! 2. **The ball.** Along a whitened ray of length `s` the surrogate's residuals move by at most
//!    `Δ(s) = μ s + ½ K s²` (stacked; `μ ≥ ‖J T v‖`, 1 up to rounding), and a point's
//!    `vᵢ = Wᵢ (n − nᵢ*)` by at most `μᵢ s + ½ K s²` (`μᵢ ≥ ‖gᵢ‖` the rate of its own rows `gᵢ` of
//!    `J T`; with many points far below 1), and `εᵢ` is taken over the ball of that radius. For an
//!    endpoint, write `ê + u = ρ ν + a τ` (`ν`, `τ` the unit normal and direction of the whitened line
//!    `W ℓ`); then `‖u‖ ≤ |a| + c` with `c = ‖ρ ν − ê‖` the motion of
//!    the residual's foot, `c ≤ |ρ − ρ̂| + ‖ê‖ φ + c₀` (`φ ≤ s ‖q′‖ / w` the turn of `ν`, from the
//!    curvature bound's parts; `c₀` the foot's offset at `P̂`, rounding), and
//!    `r ≥ √(ρ² + a²) − ε (|a| + c) ≥ √(1 − ε²) ρ − ε c`. The minimiser has
//!    `√(ρ² + a²) ≤ ρ + ε |a| + 2 ε c` (its residual is at most the foot's), which bounds `|a|`; `ε` is
//!    then taken over the ball of radius `|a| + c` (the foot must lie in a confinement ball: step 1's,
//!    or a larger one where `(1 − ε) R` still exceeds `√C + ‖ê‖ + s`). With `κ = minₑ √(1 − εₑ²)` and `ε`
//!    the largest, `√F ≥ κ √Q − ε (Δ(s) + s Φ + ‖c₀‖) − ‖s‖` (Minkowski),
//!    `Φ = ‖(‖êₑ‖ ‖q′ₑ‖ / wₑ)ₑ‖`, which step 4 of [`super`] bounds along each ray
//!    ([`super::local_bound::local_lower_bound`]), with `ε` and `κ` of the least of nested balls (radii `1/√2` apart)
//!    that holds the ray's step: near the answer, where the bound is least, only a small ball's
//!    variation is paid.
//!
//! The certificate fails, with the reason, for a lens that [`crate::camera::bounds`] does not cover, where
//! an observation or a confinement ball reaches the edge of the one-to-one disc, or where `ε` is too
//! large for the gap (strong distortion with large residuals).

use super::{RaySlack, SublevelSetOutcome};
use crate::camera::curved_line::endpoint_residual;
use crate::camera::linearisation::{lens_domain, LensBoundFailure, LinearisedObservation, SPLITS, SPLIT_EPSILON};
use crate::camera::Camera;
use crate::camera::Intrinsics;
use crate::covariance::whitening;
use crate::pose::correspondences::Correspondences;
use crate::pose::noise::ObservationNoise;
use crate::pose::reprojection::Pose;
use nalgebra::{Matrix2, Vector2, Vector3};
use std::cell::RefCell;

/// Why a lens is not covered.
const NOT_COVERED: &str = "not attempted: the certificate through a lens covers the radial, OpenCV \
    (radial and tangential), fisheye (radial), division and EUCM models; not this one";

/// The slack between the search's surrogate and the cost through the lens (step 1): every pose of the
/// domain with `f ≤ f̂` (`f = ½ Σ r²`) has `√(2q) ≤ √(2f) + δ` (`q = ½ Σ (1 − εᵢ)² ℓᵢ²` the weighted
/// surrogate's cost), so a bound `q` of that surrogate on a box is one of `½ (√(2q) − δ)₊²` on the cost,
/// and the sublevel set `{f ≤ f̂}` lies in the surrogate's at the level `½ (√(2f̂) + δ)²`. `δ = 0` for a
/// pinhole camera (the identity).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Slack {
    pub delta: f64,
}

impl Slack {
    /// No slack: the pinhole certificate.
    pub const NONE: Slack = Slack { delta: 0.0 };

    /// The cost bound of a surrogate bound `q`.
    pub fn to_cost(self, q: f64) -> f64 {
        if self == Self::NONE {
            return q;
        }
        0.5 * ((2.0 * q.max(0.0)).sqrt() - self.delta).max(0.0).powi(2)
    }

    /// The least surrogate bound whose cost bound is `f` (the inverse of [`Self::to_cost`] above 0).
    pub fn to_surrogate(self, f: f64) -> f64 {
        if self == Self::NONE {
            return f;
        }
        0.5 * ((2.0 * f.max(0.0)).sqrt() + self.delta).powi(2)
    }
}

/// `εᵢ` over whitened balls about the observation's linearisation point, memoised on the radii
/// `top 2^(−j/2)` (the least of them at least the one asked for): step 4 asks for many radii. Per
/// radius, the bound of one box and that of the box split ([`SPLITS`] x [`SPLITS`]).
struct Variation {
    lin: LinearisedObservation,
    top: f64,
    memo: RefCell<Vec<[Option<Option<f64>>; 2]>>,
}

/// Radii of [`Variation`]'s memo: `top` down to `top 2^(−20)`.
const MEMO_RADII: usize = 41;

impl Variation {
    fn new(lin: LinearisedObservation, top: f64) -> Self {
        Variation {
            lin,
            top,
            memo: RefCell::new(vec![[None; 2]; MEMO_RADII]),
        }
    }

    /// A bound of `ε` over the ball of `radius` from one box (`split` false) or from the box split
    /// (`None` where a box reaches the edge of the disc).
    fn epsilon_in(&self, radius: f64, split: bool) -> Option<f64> {
        let pieces = if split { SPLITS } else { 1 };
        if !(radius <= self.top) {
            return self.lin.epsilon_in(radius, pieces);
        }
        let steps = (2.0 * (self.top / radius.max(f64::MIN_POSITIVE)).log2()).floor();
        let j = (steps.max(0.0) as usize).min(MEMO_RADII - 1);
        let at = self.top * 0.5f64.powf(j as f64 / 2.0);
        // The memo's radius must hold the ball asked for.
        if at < radius {
            return self.lin.epsilon_in(radius, pieces);
        }
        *self.memo.borrow_mut()[j][split as usize].get_or_insert_with(|| self.lin.epsilon_in(at, pieces))
    }

    /// A bound of `ε` over the ball of `radius`: one box's, or the split box's where one box's exceeds
    /// [`SPLIT_EPSILON`] (`None` where a box reaches the edge of the disc).
    fn epsilon(&self, radius: f64) -> Option<f64> {
        let single = self.epsilon_in(radius, false)?;
        if !(single > SPLIT_EPSILON) {
            return Some(single);
        }
        Some(single.min(self.epsilon_in(radius, true)?))
    }
}

/// The largest [`Variation::epsilon`] of `all`, each over the ball of its radius, splitting boxes only where
/// that can change the largest: every one box's bound first, then, from the largest down, the split
/// bound until the next one box's bound is below the largest found (the split bound is at most the
/// one box's).
fn largest_epsilon<'v>(all: impl Iterator<Item = (&'v Variation, f64)>) -> Option<f64> {
    let mut singles = all
        .map(|(v, radius)| Some((v.epsilon_in(radius, false)?, v, radius)))
        .collect::<Option<Vec<_>>>()?;
    singles.sort_by(|a, b| b.0.total_cmp(&a.0));
    let mut largest: f64 = 0.0;
    for (single, v, radius) in singles {
        if single <= largest {
            break;
        }
        largest = largest.max(if single > SPLIT_EPSILON {
            v.epsilon(radius)?
        } else {
            single
        });
    }
    Some(largest)
}

/// One segment endpoint linearised at its nearest curve point `q*`, with its confinement.
struct Endpoint {
    variation: Variation,
    /// Step 1's ball `(R, ε)` about `q*`.
    confined: (f64, f64),
    /// `c₀ = ‖W (foot − q*)‖`: the foot of `ē` on `ℓ̂` (exactly `q*` up to rounding).
    c0: f64,
}

/// The surrogate of a problem through a lens (module docs) and what step 4 needs of it.
pub(super) struct Surrogate {
    /// The lens's pinhole part `K`.
    pub camera: Intrinsics,
    /// The surrogate's observations, in the pixels of `K`, with their whitenings (`absolute` noise).
    pub corr: Correspondences,
    /// The rotation search's observations (step 1): those of `corr`, each weighted by `1 − εᵢ` of its
    /// confinement ball, less the points that are not confined.
    search: Correspondences,
    /// Step 1's slack of the search's observations.
    pub slack: Slack,
    points: Vec<Variation>,
    endpoints: Vec<[Endpoint; 2]>,
    /// `C = Σ r²` at the answer: the level of step 1's confinement.
    level: f64,
    /// `‖(sᵢ)‖`: the rounding of every `eᵢ*`.
    rounding: f64,
}

impl Surrogate {
    /// The surrogate of `corr` (observed pixels of `lens`, conditioned frame, with the caller's noise)
    /// at `pose`, of cost `cost` (`½ Σ r²`).
    pub fn new(lens: &Camera, corr: &Correspondences, pose: &Pose, cost: f64) -> Result<Self, String> {
        let level = 2.0 * cost;
        let camera = lens.intrinsics();
        let k = camera.matrix();
        let k2 = Matrix2::new(camera.fx, camera.skew, 0.0, camera.fy);
        let k2_inverse = k2.try_inverse().ok_or("singular camera")?;
        let known = match lens_domain(lens) {
            Ok(known) => known,
            Err(LensBoundFailure::Lens) => return Err(NOT_COVERED.into()),
            Err(_) => return Err("not proved: the lens has no disc where it is proved one-to-one".into()),
        };
        let noise = corr.noise.as_ref();
        let pixel_of = |n: &Vector2<f64>| (k * Vector3::new(n.x, n.y, 1.0)).xy();
        let edge = |what: &str, i: usize| {
            format!(
                "not proved: {what}[{i}] or the ball that confines it reaches the edge of the disc where \
                 the lens is proved one-to-one, or the distortion varies too much over it"
            )
        };
        let mut surrogate = Correspondences {
            points3d: corr.points3d.clone(),
            lines3d: corr.lines3d.clone(),
            ..Default::default()
        };
        let mut noise_out = ObservationNoise {
            points: Vec::with_capacity(corr.n_points()),
            lines: Vec::with_capacity(corr.n_lines()),
            absolute: true,
        };
        // The search's observations: the surrogate's, each weighted by 1 − εᵢ of its confinement
        // ball (step 1), less the points that are not confined.
        let mut search = Correspondences {
            points3d: Vec::with_capacity(corr.n_points()),
            lines3d: corr.lines3d.clone(),
            ..Default::default()
        };
        let mut search_noise = ObservationNoise {
            points: Vec::with_capacity(corr.n_points()),
            lines: Vec::with_capacity(corr.n_lines()),
            absolute: true,
        };
        // Step 1: ‖((1 − εᵢ) δᵢ)‖² over the search's observations; ‖(sᵢ)‖² over all.
        let (mut delta2, mut rounding2): (f64, f64) = (0.0, 0.0);
        let mut confine = |lin: &LinearisedObservation, eps: f64| {
            delta2 += (eps * (lin.e.norm() + lin.rounding) + (1.0 - eps) * lin.rounding).powi(2);
            1.0 - eps
        };
        let mut points = Vec::with_capacity(corr.n_points());
        for (i, (x, u)) in corr.points3d.iter().zip(&corr.points2d).enumerate() {
            let whitening = noise.map_or_else(Matrix2::identity, |n| n.points[i]);
            let xc = pose.transform(x);
            // A point that is not confined enters step 4 only (linearised without the level's path
            // argument, which step 4 does not need).
            let confined = LinearisedObservation::new_in(lens, &known, &whitening, u, &xc, level, SPLITS, false)
                .ok()
                .and_then(|lin| Some((lin.confinement(level)?, lin)));
            let (lin, radius, weight) = match confined {
                Some(((radius, eps), lin)) => {
                    let weight = confine(&lin, eps);
                    (lin, radius, Some(weight))
                }
                None => {
                    let lin = LinearisedObservation::new_in(lens, &known, &whitening, u, &xc, 0.0, SPLITS, false)
                        .map_err(|_| edge("points2d", i))?;
                    let radius = lin.first_radius(level);
                    (lin, radius, None)
                }
            };
            rounding2 += lin.rounding.powi(2);
            let (observed, map) = (pixel_of(&(lin.n - lin.w_inverse * lin.e)), lin.w * k2_inverse);
            surrogate.points2d.push(observed);
            noise_out.points.push(map);
            if let Some(weight) = weight {
                search.points3d.push(*x);
                search.points2d.push(observed);
                search_noise.points.push(map * weight);
            }
            points.push(Variation::new(lin, radius));
        }
        let mut endpoints = Vec::with_capacity(corr.n_lines());
        for (i, (s3, s2)) in corr.lines3d.iter().zip(&corr.lines2d).enumerate() {
            let (a, b) = (pose.transform(&s3[0]), pose.transform(&s3[1]));
            let l = a.cross(&b);
            let mut pair = Vec::with_capacity(2);
            let mut observed = [Vector2::zeros(); 2];
            let mut covariances = [Matrix2::identity(); 2];
            let mut weighted = [Matrix2::identity(); 2];
            for k in 0..2 {
                let e = s2[k];
                let cov = noise.map_or_else(Matrix2::identity, |n| n.lines[i][k]);
                let whitening = whitening(&cov, "line_covariances", i).map_err(|e| format!("not attempted: {e}"))?;
                let start = lens.unproject(&e, i).map_err(|_| edge("lines2d", i))?;
                let fit = endpoint_residual(lens, &l, &start, &e, &cov).ok_or_else(|| edge("lines2d", i))?;
                let xc = Vector3::new(fit.q.x, fit.q.y, 1.0);
                let lin = LinearisedObservation::new_in(lens, &known, &whitening, &e, &xc, level, SPLITS, false)
                    .map_err(|_| edge("lines2d", i))?;
                let confined = lin.confinement(level).ok_or_else(|| edge("lines2d", i))?;
                let e_bar = lin.n - lin.w_inverse * lin.e;
                // The foot of ē on ℓ̂ in the metric WᵀW: ē − C l₁₂ (l·ē) / (l₁₂ᵀ C l₁₂), C = (WᵀW)⁻¹.
                let c = lin.w_inverse * lin.w_inverse.transpose();
                let l12 = l.xy();
                let foot = e_bar - c * l12 * (l12.dot(&e_bar) + l.z) / l12.dot(&(c * l12));
                let c0 = (lin.w * (foot - lin.n)).norm();
                if !c0.is_finite() {
                    return Err(edge("lines2d", i));
                }
                let weight = confine(&lin, confined.1);
                rounding2 += lin.rounding.powi(2);
                observed[k] = pixel_of(&e_bar);
                covariances[k] = k2 * c * k2.transpose();
                weighted[k] = covariances[k] / (weight * weight);
                pair.push(Endpoint {
                    variation: Variation::new(lin, confined.0),
                    confined,
                    c0,
                });
            }
            surrogate.lines2d.push(observed);
            noise_out.lines.push(covariances);
            search.lines2d.push(observed);
            search_noise.lines.push(weighted);
            let [p0, p1]: [Endpoint; 2] = pair.try_into().map_err(|_| edge("lines2d", i))?;
            endpoints.push([p0, p1]);
        }
        surrogate.noise = Some(noise_out);
        search.noise = Some(search_noise);
        Ok(Surrogate {
            search,
            camera,
            corr: surrogate,
            slack: Slack { delta: delta2.sqrt() },
            points,
            endpoints,
            level,
            rounding: rounding2.sqrt(),
        })
    }

    /// Step 2's constants over the whitened ball of `radius` with the curvature bound `k`:
    /// `(κ, ε, Φ, ‖c₀‖ , ‖s‖)`, or `None` where a ball reaches the edge of the disc or leaves step 1's.
    /// `mu` bounds the rate of the stacked residuals, `rates[i]` that of point `i`'s alone;
    /// `turns[e]` bounds `‖q′ₑ‖ / wₑ` over the ball, endpoint by endpoint in the order of `corr`.
    pub fn ball(&self, radius: f64, k: f64, mu: f64, rates: &[f64], turns: &[f64]) -> Option<RaySlack> {
        let curve = 0.5 * k * radius * radius;
        let moved = mu * radius + curve;
        debug_assert_eq!(rates.len(), self.points.len());
        let each = rates.iter().map(|rate| rate.min(mu) * radius + curve);
        let mut eps = largest_epsilon(self.points.iter().zip(each))?;
        let (mut kappa, mut phi2, mut c0_2): (f64, f64, f64) = (1.0, 0.0, 0.0);
        for (end, &turn) in self.endpoints.iter().flatten().zip(turns) {
            let lin = &end.variation.lin;
            let e_hat = lin.e.norm() + lin.rounding;
            let c_max = moved + e_hat * radius * turn + end.c0;
            let rho_max = e_hat + moved;
            // The foot lies within c_max of q*: a confinement ball that holds it (step 1's, or a
            // larger one, which confines as well where (1 − ε) R still exceeds √C + ‖ê‖ + s).
            let (big, eps_big) = if c_max <= end.confined.0 {
                end.confined
            } else {
                let big = c_max * 1.001;
                let eps = end.variation.epsilon(big)?;
                if !((1.0 - eps) * big > lin.need(self.level)) {
                    return None;
                }
                (big, eps)
            };
            if !(eps_big < 1.0) {
                return None;
            }
            let a_max = along_line_reach(eps_big, rho_max, c_max);
            let small = end.variation.epsilon((a_max + c_max).min(big))?;
            if !(small < 1.0) {
                return None;
            }
            eps = eps.max(small);
            kappa = kappa.min(along_line_factor(small));
            phi2 += (e_hat * turn).powi(2);
            c0_2 += end.c0 * end.c0;
        }
        Some(RaySlack {
            kappa,
            rate: mu,
            eps,
            phi: phi2.sqrt(),
            offset: c0_2.sqrt(),
            rounding: self.rounding,
        })
    }

    /// The observations of the rotation search (step 1).
    pub fn search_corr(&self) -> &Correspondences {
        &self.search
    }

    /// Endpoints, for [`Self::ball`]'s `turns`.
    pub fn n_endpoints(&self) -> usize {
        2 * self.endpoints.len()
    }

    /// Per point, what a test needs to check its `ε` over the ball of `radius` independently:
    /// `(ε, W, M, n*)`, `ε` through the memo (after the radii `radius · 2^(±k/3)` were asked for), and
    /// the largest `ε` as step 4 takes it.
    pub fn point_variations(&self, radius: f64) -> (Vec<PointVariation>, Option<f64>) {
        for k in [-3, 2, -1, 1, 3] {
            let _ = largest_epsilon(self.points.iter().map(|v| (v, radius * 2f64.powf(k as f64 / 3.0))));
        }
        let each = self
            .points
            .iter()
            .map(|v| PointVariation {
                epsilon: v.epsilon(radius),
                w: v.lin.w,
                m: v.lin.m,
                n: v.lin.n,
            })
            .collect();
        (each, largest_epsilon(self.points.iter().map(|v| (v, radius))))
    }
}

/// A point's `ε` over a whitened ball and what defines the ball (the test hook
/// [`super::testing::lens_point_variations`]).
#[derive(Debug, Clone, Copy)]
pub struct PointVariation {
    /// The bound of `‖M (J(n) − J*) W⁻¹‖` over the ball (`None` where it reaches the edge of the disc).
    pub epsilon: Option<f64>,
    /// `W = M J*`: the ball is `{n : ‖W (n − n*)‖ ≤ radius}`.
    pub w: Matrix2<f64>,
    /// `M = L K₂`.
    pub m: Matrix2<f64>,
    /// The ball's centre `n*`.
    pub n: Vector2<f64>,
}

/// Step 2's lemma for an endpoint (module docs): where `r(u) ≥ ‖ê + u‖ − ε ‖u‖` on the whitened line
/// `{νᵀ (ê + u) = ρ}` and `c = ‖ρ ν − ê‖`, every `u` of the line has `r ≥ κ |ρ| − ε c` with this `κ`,
/// `√(1 − ε²)` (the least of `√(ρ² + a²) − ε |a|` over the line's coordinate `a`).
fn along_line_factor(eps: f64) -> f64 {
    (1.0 - eps * eps).sqrt()
}

/// The reach `|a| ≤ a_max` along the line of a minimiser of `r` (module docs): its residual is at most
/// the foot's, `r ≤ |ρ| + ε c`, so `√(ρ² + a²) − ε (|a| + c) ≤ |ρ| + ε c`; solved for `|a|` at the largest
/// `|ρ|` and `c` (the bound increases in both).
fn along_line_reach(eps: f64, rho_max: f64, c_max: f64) -> f64 {
    let b = rho_max + 2.0 * eps * c_max;
    let (e2, rest) = (eps * eps, b * b - rho_max * rho_max);
    (b * eps + (b * b * e2 + (1.0 - e2) * rest).sqrt()) / (1.0 - e2)
}

/// [`super::certify`] through `lens`: `corr` holds the observed (distorted) pixels and the caller's
/// noise, conditioned frame; `pose` is the local minimum of cost `cost` (`½ Σ r²`).
pub(super) fn certify(
    lens: &Camera,
    corr: &Correspondences,
    pose: &Pose,
    cost: f64,
    options: &crate::certificate::CertifyOptions,
) -> SublevelSetOutcome {
    match Surrogate::new(lens, corr, pose, cost) {
        Ok(surrogate) => super::certify_pinhole(
            &surrogate.camera,
            &surrogate.corr,
            pose,
            cost,
            options,
            Some(&surrogate),
        ),
        Err(why) => SublevelSetOutcome::none(why),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    #[test]
    fn the_along_line_lemma_holds_for_the_worst_perturbation() {
        // The worst r the lemma allows, r(u) = ‖ê + u‖ − ε ‖u‖, minimised along the line
        // {νᵀ (ê + u) = ρ} by a fine scan and golden sections: the minimum is at least κ |ρ| − ε c, and
        // the minimiser's |a| is within the reach. Where c = 0 (the line through the foot at the
        // answer) the minimum is κ |ρ| itself: a κ any larger would fail.
        let mut rng = Rng::new(21);
        let mut tightest = f64::INFINITY;
        for _ in 0..400 {
            let eps = rng.uniform_in(0.0, 0.6);
            let e_hat = Vector2::new(rng.normal(), rng.normal()) * rng.uniform_in(0.1, 5.0);
            let nu = Vector2::new(rng.normal(), rng.normal()).normalize();
            let tau = Vector2::new(-nu.y, nu.x);
            let rho = if rng.uniform_in(0.0, 1.0) < 0.3 {
                nu.dot(&e_hat)
            } else {
                rng.uniform_in(-6.0, 6.0)
            };
            let foot = nu * rho;
            let c = (foot - e_hat).norm();
            let r = |a: f64| {
                let y = foot + tau * a;
                y.norm() - eps * (y - e_hat).norm()
            };
            let scan = 200.0 * (1.0 + rho.abs() + c);
            let steps = 20_000;
            let (mut best_a, mut best) = (0.0, r(0.0));
            for i in 0..=steps {
                let a = -scan + 2.0 * scan * i as f64 / steps as f64;
                if r(a) < best {
                    (best_a, best) = (a, r(a));
                }
            }
            let h = 2.0 * scan / steps as f64;
            let (mut lo, mut hi) = (best_a - h, best_a + h);
            let g = (5f64.sqrt() - 1.0) / 2.0;
            while hi - lo > 1e-12 * (1.0 + scan) {
                let (x, y) = (hi - g * (hi - lo), lo + g * (hi - lo));
                if r(x) < r(y) {
                    hi = y;
                } else {
                    lo = x;
                }
            }
            let (a_min, least) = (0.5 * (lo + hi), r(0.5 * (lo + hi)).min(best));
            let bound = along_line_factor(eps) * rho.abs() - eps * c;
            tightest = tightest.min(least - bound);
            assert!(
                least >= bound - 1e-9 * (1.0 + rho.abs()),
                "ε {eps}, ρ {rho}, c {c}: {least} < {bound}"
            );
            let reach = along_line_reach(eps, rho.abs(), c);
            assert!(
                a_min.abs() <= reach * (1.0 + 1e-9) + 1e-9,
                "ε {eps}, ρ {rho}, c {c}: |a| {a_min} > {reach}"
            );
        }
        // The lemma is tight: some line with c = 0 reaches its bound.
        assert!(
            tightest.abs() < 1e-6,
            "the least margin {tightest} (the lemma should be tight at c = 0)"
        );
    }

    /// The reach of the endpoint lemma (`along_line_reach`) against the residuals the lemma allows,
    /// both ways: inside a confinement ball `r = ‖ê + u + Δ u‖` with `‖Δ‖ ≤ ε`, so `r(a)` can be anything
    /// between `√(ρ² + a²) ∓ ε ‖u(a)‖` along the line (`u(a) = ρ ν + a τ − ê`, `‖u(a)‖` here the exact
    /// distance, not the lemma's `|a| + c`). A minimiser can then sit at any `a` whose least possible
    /// residual is at most the least of the largest possible ones, `U = min (√(ρ² + a′²) + ε ‖u(a′)‖)`
    /// (take `r` at the lower envelope there and at the upper one elsewhere); the farthest such `a`
    /// (a scan of `|a| ≤ (U + ε c)/(1 − ε)`, beyond which the lower envelope exceeds `U`, then
    /// bisection) must lie within the reach, for `|ρ|` and `c` at or below the bounds passed. The
    /// worst cases push the foot's residual up by `ε c` (the term a one-sided perturbation,
    /// `r = ‖ê + u‖ − ε ‖u‖`, never exercises) and have `ê` off the line's normal so that `‖u(a)‖`
    /// nears `|a| + c` on one side. The reach is also the root of the lemma's own inequality, so a
    /// looser one fails as well.
    #[test]
    fn the_reach_holds_every_minimiser_of_a_residual_within_the_lemma() {
        let mut rng = Rng::new(23);
        let mut tightest = f64::INFINITY;
        for case in 0..3000 {
            let eps = match case % 3 {
                0 => rng.uniform_in(0.0, 0.2),
                1 => rng.uniform_in(0.2, 0.6),
                _ => rng.uniform_in(0.6, 0.95),
            };
            let e_hat = Vector2::new(rng.normal(), rng.normal()) * 10f64.powf(rng.uniform_in(-1.0, 1.0));
            let nu = Vector2::new(rng.normal(), rng.normal()).normalize();
            let tau = Vector2::new(-nu.y, nu.x);
            // The foot ρ ν: at the answer (ρ = νᵀê, c along τ), near it, or anywhere.
            let rho = match case % 4 {
                0 => nu.dot(&e_hat),
                1 => nu.dot(&e_hat) + rng.normal() * 1e-2 * e_hat.norm(),
                _ => rng.uniform_in(-2.0, 2.0) * e_hat.norm(),
            };
            let foot = nu * rho;
            let c = (foot - e_hat).norm();
            let distance = |a: f64| (foot + tau * a - e_hat).norm();
            let upper = |a: f64| (rho * rho + a * a).sqrt() + eps * distance(a);
            let lower = |a: f64| (rho * rho + a * a).sqrt() - eps * distance(a);
            // U: the upper envelope is convex in a, and at least |a|, so its minimum lies in |a| ≤ upper(0).
            let (mut lo, mut hi) = (-upper(0.0), upper(0.0));
            let g = (5f64.sqrt() - 1.0) / 2.0;
            for _ in 0..200 {
                let (x, y) = (hi - g * (hi - lo), lo + g * (hi - lo));
                if upper(x) < upper(y) {
                    hi = y;
                } else {
                    lo = x;
                }
            }
            let least_upper = upper(0.5 * (lo + hi)).min(upper(0.0));
            // The farthest a with lower(a) ≤ U, on each side.
            let limit = (least_upper + eps * c) / (1.0 - eps) * (1.0 + 1e-9) + 1e-12;
            let steps = 4000;
            let mut farthest: f64 = 0.0;
            for side in [-1.0, 1.0] {
                let at = |i: usize| side * limit * i as f64 / steps as f64;
                let Some(i) = (0..=steps).rev().find(|&i| lower(at(i)) <= least_upper) else {
                    continue;
                };
                let (mut inside, mut outside) = (at(i), at((i + 1).min(steps)));
                for _ in 0..100 {
                    let mid = 0.5 * (inside + outside);
                    if lower(mid) <= least_upper {
                        inside = mid;
                    } else {
                        outside = mid;
                    }
                }
                farthest = farthest.max(inside.abs());
            }
            // The reach at bounds of |ρ| and c: the values themselves, or above them.
            let (rho_max, c_max) = if case % 5 == 0 {
                (rho.abs() * rng.uniform_in(1.0, 2.0), c * rng.uniform_in(1.0, 2.0))
            } else {
                (rho.abs(), c)
            };
            let reach = along_line_reach(eps, rho_max, c_max);
            // Rounding: the envelopes are sums of a few square roots, ~1e-15 relative to their size.
            assert!(
                farthest <= reach * (1.0 + 1e-9) + 1e-12 * (1.0 + e_hat.norm()),
                "ε {eps}, ρ {rho}, c {c}: a minimiser may sit at |a| = {farthest}, beyond the reach {reach}"
            );
            if farthest > 0.0 {
                tightest = tightest.min(reach / farthest);
            }
            // And no looser than the lemma: the reach is the root of its inequality
            // √(ρ² + a²) − ε (a + c) = |ρ| + ε c (at the bounds passed), which only grows past it.
            let lemma = |a: f64| (rho_max * rho_max + a * a).sqrt() - eps * (a + c_max) - rho_max - eps * c_max;
            assert!(
                lemma(reach).abs() <= 1e-9 * (rho_max + reach + c_max) && lemma(reach * (1.0 + 1e-6) + 1e-12) > 0.0,
                "ε {eps}, ρ {rho_max}, c {c_max}: the reach {reach} is not the root of the lemma's inequality"
            );
        }
        // Not vacuous: some case comes within 10 % of the reach.
        assert!(
            tightest < 1.1,
            "the reach is at least {tightest}x the farthest minimiser"
        );
        eprintln!("least reach / farthest minimiser {tightest:.4}");
    }
}
