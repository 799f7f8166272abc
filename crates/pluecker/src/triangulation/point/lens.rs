//! A point seen through lenses with distortion: the exact cost in the images' own pixels, its local
//! minimisation and its certificate.
//!
//! **Cost.** View `i` has a camera ([`Camera`]: `u = K D(n)`, `n = (x/z, y/z)`,
//! `x_cam = Rᵢ X + tᵢ`), the observed (distorted) pixel `uᵢ` and the whitening `Lᵢ` of its covariance.
//! The residual is `eᵢ(X) = Lᵢ (u(X) − uᵢ)` through the exact projection, and the cost is
//! `F(X) = Σ ‖eᵢ(X)‖²` (eq. 19 in the observed pixels). The first stages (DLT, the local and global
//! searches of [`super`]) run on the first-order problem in the undistorted pixels of each lens's
//! pinhole part (`first_order_view`); `refine` then minimises `F` itself from their answer.
//!
//! **Certificate** ([`lens_certificate`]), at a local minimiser `X*` of cost `C = F(X*)`, with
//! `eᵢ* = eᵢ(X*)`, `nᵢ*` its normalised projection, `Mᵢ = Lᵢ K₂` (`K₂` the upper-left block of `K`),
//! `Jᵢ* = ∂D/∂n(nᵢ*)` and `Wᵢ = Mᵢ Jᵢ*`. Its domain is every point in front of the cameras whose
//! projection in each image lies inside the disc `Dᵢ` where that lens is proved one-to-one
//! ([`crate::camera::bounds::domain`]: the fold radius for radially symmetric lenses; a scan of the
//! symmetric part of the Jacobian with OPENCV's tangential terms), which `D` maps onto a set holding
//! the disc of radius `ρ_Dᵢ` about the principal point.
//! 1. *Each view's projection is confined.* Let `Bᵢ = {n : ‖Wᵢ(n − nᵢ*)‖ ≤ ρᵢ}` and `εᵢ` a bound
//!    of `‖Mᵢ (J(n) − Jᵢ*) Wᵢ⁻¹‖₂` over `Bᵢ` (interval enclosures; [`crate::camera::linearisation`]).
//!    Along the segment from `nᵢ*` (mean value theorem),
//!    `eᵢ(n) = eᵢ* + (I + Δ) Wᵢ (n − nᵢ*)`, `‖Δ‖ ≤ εᵢ`, so on the boundary of `Bᵢ`
//!    `‖eᵢ‖ ≥ (1 − εᵢ)ρᵢ − ‖eᵢ*‖ > √C` for `ρᵢ` chosen so. Let `n ∈ Dᵢ` have `‖eᵢ(n)‖ ≤ √C`: `D(n)` lies
//!    in the ellipse `{d : ‖Mᵢ(d − dᵢ)‖ ≤ √C}` (`dᵢ` the observation's distorted coordinates), which the
//!    test requires inside the disc of radius `ρ_Dᵢ`. The segment from `D(nᵢ*)` to `D(n)` lies in that
//!    ellipse, and its preimage under the homeomorphism `D|Dᵢ` is a path from `nᵢ*` to `n` along which
//!    `‖eᵢ‖ ≤ √C`: it never meets `∂Bᵢ`, so `n ∈ Bᵢ`. Every point of the domain with `F ≤ C` has every
//!    projection in its `Bᵢ`.
//!
//!    Two devices keep `εᵢ` small. Interval arithmetic overestimates a box's variation by a multiple of
//!    its width, so a box whose `εᵢ` exceeds 1 % is split into 8x8 sub-boxes (only in a second pass,
//!    when the whole proof with one box per view has failed: the splits cost 64 enclosures). And a fisheye
//!    projection off axis may use the **ray chart**: the normalised coordinates `n′` of the camera
//!    rotated so that the ray of `nᵢ*` is its optical axis (`n′* = 0`, `n = h(n′)` a homography), with
//!    the Jacobian of `D ∘ h` ([`crate::camera::bounds::fisheye_ray_enclosure`]); a box of `n′` stays small
//!    in angle where one of `n` stretches with `1/cos²θ`. The argument above holds in either chart
//!    (`h(Bᵢ′)` is a closed set whose boundary is `h(∂Bᵢ′)`), and the chart of the smaller `εᵢ` is used.
//! 2. *A pinhole problem bounds `F` there.* With `vᵢ = Wᵢ(n − nᵢ*)` and `ℓᵢ = eᵢ* + vᵢ` (the
//!    linearisation at the estimate, a pinhole residual of the normalised camera `[Rᵢ | tᵢ]`, rotated
//!    into the ray chart when there is one, with whitening `Wᵢ`), `‖eᵢ‖ ≥ ‖ℓᵢ‖ − δᵢ`, `δᵢ = εᵢ‖vᵢ‖ + sᵢ` (`sᵢ` the rounding of `eᵢ*`), hence
//!    `‖eᵢ‖² ≥ ‖ℓᵢ‖² − 2‖ℓᵢ‖δᵢ` and `F ≥ Q − 2Σ(‖eᵢ*‖ + ‖vᵢ‖)(εᵢ‖vᵢ‖ + sᵢ)`, `Q = Σ‖ℓᵢ‖²`; and
//!    `F ≤ C` implies `Q ≤ C' = C + Σ 2√C(εᵢρᵢ + sᵢ) + (εᵢρᵢ + sᵢ)²`.
//! 3. *Convexity.* The test of [`crate::global::convexity`] at the level `C'`, in a whitened chart of
//!    the pinhole problem at `X*` (`Q(X*) = C`, `vᵢ = Bᵢy/ζᵢ`, `Σ BᵢᵀBᵢ = I`, `ζᵢ ≥ 1 − κ_d`): a convex
//!    `K ⊇ {Q ≤ C'}` on which `Q ≥ C + gᵀy + ½yᵀHy`. With `t = ‖y‖` and `k = 1/(1 − κ_d)`, on `K`
//!    `F ≥ C − 2Σ‖eᵢ*‖sᵢ − (‖g‖ + 2kα)t + (½λ_min(H) − 2k²ε)t²`, `α = (Σ(‖eᵢ*‖εᵢ + sᵢ)²)^½`,
//!    `ε = maxᵢ εᵢ`. Its minimum over `t ≥ 0` is a lower bound of `F` over the domain (points outside
//!    `K` cost more than `C`).
//! 4. *Tightening.* The loss is of order `ε²C`. Where the bound exceeds `C(1 − ½ gap)` for
//!    `t ≥ t₁`, the rest has `‖vᵢ‖ ≤ k‖Bᵢ‖t₁`: smaller boxes, smaller `εᵢ`, and step 3 again over
//!    `t ≤ t₁`, a few times.
//!
//! The certificate fails (the result is not certified, status `gap_not_closed`) for a lens it does not
//! cover (FOV, a rational FULL_OPENCV, the fisheyes' tangential and thin-prism terms), a projection or ellipse reaching the edge of its lens's domain, `εᵢ ≥ ½`, or a
//! failed convexity test (low parallax, large residuals); there is no branch and bound through a lens.
//! Exact data (a cost at the rounding level) is certified by the trivial bound 0 whatever the lens.

use super::chart::{Chart, ChartKind};
use super::cost::PointView;
use super::robust::RobustTrack;
pub use crate::camera::linearisation::LensBoundFailure;
use crate::camera::linearisation::{LinearisedObservation, SPLITS};
use crate::camera::Camera;
use crate::certificate::Primitive;
use crate::error::Result;
use crate::global::convexity::{minorant_at_level, Minorant};
use crate::global::relative_gap;
use crate::optim::Termination;
use crate::optim::{trust_region, Linearization, Objective, Summary, TrustRegionOptions};
use crate::triangulation::point::linear::WorldFrame;
use crate::triangulation::point::PointTriangulation;
use crate::triangulation::uncertainty::covariance_of_information3;
use crate::triangulation::views::{depth_normalized, View};
use crate::triangulation::{Certificate, CertificateKind, Method, Status, TriangulationOptions};
use nalgebra::{Matrix2, Matrix2x3, Matrix3, Matrix3x4, Vector2, Vector3};
use std::time::Instant;

/// Rounds of the tightening of step 4.
const TIGHTENING_ROUNDS: usize = 6;

/// One observation through a camera: the camera, its pose, the observed pixel and the whitening `L`
/// of its covariance (`Lᵀ L = Σ⁻¹`).
#[derive(Debug, Clone, Copy)]
pub struct LensView<'a> {
    /// The camera.
    pub camera: &'a Camera,
    /// `R`, world to camera.
    pub rotation: Matrix3<f64>,
    /// `t`.
    pub translation: Vector3<f64>,
    /// The observed pixel.
    pub pixel: Vector2<f64>,
    /// `L`.
    pub whitening: Matrix2<f64>,
}

impl<'a> LensView<'a> {
    /// The observation `pixel`, whitened by `whitening`, in `view`.
    pub fn new(view: &'a View, pixel: Vector2<f64>, whitening: Matrix2<f64>) -> LensView<'a> {
        LensView {
            camera: &view.camera,
            rotation: view.pose.rotation,
            translation: view.pose.translation,
            pixel,
            whitening,
        }
    }

    fn x_cam(&self, x: &Vector3<f64>) -> Vector3<f64> {
        self.rotation * x + self.translation
    }

    /// The whitened residual `e = L (u(X) − uᵢ)` and `∂e/∂X`; `None` behind the camera.
    pub fn residual_and_jacobian(&self, x: &Vector3<f64>) -> Option<(Vector2<f64>, Matrix2x3<f64>)> {
        let xc = self.x_cam(x);
        if !(xc.z > 0.0) {
            return None;
        }
        let (u, j) = self.camera.project_with_jacobian(&xc);
        Some((self.whitening * (u - self.pixel), self.whitening * j * self.rotation))
    }

    /// `‖e(X)‖²`, `∞` behind the camera.
    pub fn squared_residual(&self, x: &Vector3<f64>) -> f64 {
        self.residual_and_jacobian(x)
            .map_or(f64::INFINITY, |(e, _)| e.norm_squared())
    }
}

/// The first-order view of `view` for the stages of [`super`]: the undistorted pixel of the lens's
/// pinhole part and the whitening `L J`, `J = ∂u/∂ū` at the observation, so that the whitened
/// residual is the observed one to first order. `Error::Degenerate` names observation `index` when
/// its pixel has no preimage inside the fold.
pub(crate) fn first_order_view(view: &LensView, index: usize) -> Result<PointView> {
    let k = view.camera.intrinsics();
    let mut rt = Matrix3x4::zeros();
    rt.fixed_view_mut::<3, 3>(0, 0).copy_from(&view.rotation);
    rt.set_column(3, &view.translation);
    let p = depth_normalized(&(k.matrix() * rt));
    match view.camera.distortion() {
        Some(lens) => {
            let (undistorted, j) = lens.undistort(&view.pixel, index)?;
            Ok(PointView::new(&p, &undistorted, &(view.whitening * j)))
        }
        None => Ok(PointView::new(&p, &view.pixel, &view.whitening)),
    }
}

/// `F(X) = Σ ‖eᵢ(X)‖²` (module docs), `∞` when `X` is behind a camera.
pub fn exact_cost(views: &[LensView], x: &Vector3<f64>) -> f64 {
    views.iter().map(|v| v.squared_residual(x)).sum()
}

/// `½ F` for [`crate::optim`]; points behind a camera cost `∞`, which the trust region rejects.
struct ExactObjective<'a, 'b> {
    views: &'a [LensView<'b>],
}

impl Objective<3> for ExactObjective<'_, '_> {
    type Point = Vector3<f64>;

    fn cost(&self, x: &Vector3<f64>) -> f64 {
        0.5 * exact_cost(self.views, x)
    }

    fn linearize(&self, x: &Vector3<f64>) -> Linearization<3> {
        let mut lin = Linearization::zero();
        for v in self.views {
            let Some((e, j)) = v.residual_and_jacobian(x) else {
                lin.cost = f64::INFINITY;
                return lin;
            };
            lin.add(&e, &j);
        }
        lin
    }

    fn retract(&self, x: &Vector3<f64>, d: &Vector3<f64>) -> Vector3<f64> {
        x + d
    }
}

/// The local minimum of `F` from `x0` (in front of every camera) by the trust region of
/// [`crate::optim`].
pub(crate) fn refine(views: &[LensView], x0: &Vector3<f64>, opts: &TrustRegionOptions) -> (Vector3<f64>, Summary) {
    trust_region::minimize(&ExactObjective { views }, *x0, opts)
}

/// A proved lower bound of `F` over the certificate's domain (module docs), at most `cost`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LensBound {
    /// The bound, before any cap at the cost.
    pub raw_lower_bound: f64,
}

/// The certificate's lower bound of `F` at the local minimiser `x` of cost `cost` (module docs), or
/// why there is none. `gap` is the relative gap the caller will ask for (the tightening aims at half of it).
pub fn lens_certificate(
    views: &[LensView],
    x: &Vector3<f64>,
    cost: f64,
    gap: f64,
) -> std::result::Result<LensBound, LensBoundFailure> {
    // One box per view first; the split boxes, 64 times the enclosures, only where that bound does
    // not close the gap.
    match certificate_with_splits(views, x, cost, gap, 1) {
        Ok(bound) if relative_gap(cost, bound.raw_lower_bound.min(cost).max(0.0)) <= gap => Ok(bound),
        _ => certificate_with_splits(views, x, cost, gap, SPLITS),
    }
}

/// [`lens_certificate`] with the boxes of `εᵢ` split `splits` x `splits` where one box overestimates.
fn certificate_with_splits(
    views: &[LensView],
    x: &Vector3<f64>,
    cost: f64,
    gap: f64,
    splits: usize,
) -> std::result::Result<LensBound, LensBoundFailure> {
    let lin: Vec<LinearisedObservation> = views
        .iter()
        .map(|v| LinearisedObservation::new(v.camera, &v.whitening, &v.pixel, &v.x_cam(x), cost, splits, true))
        .collect::<std::result::Result<_, _>>()?;
    // Step 1.
    let confined: Vec<(f64, f64)> = lin
        .iter()
        .map(|l| l.confinement(cost))
        .collect::<Option<_>>()
        .ok_or(LensBoundFailure::Fold)?;
    // Step 2: the pinhole problem of the linearisation at X*, and the level C'.
    let root_cost = cost.sqrt();
    let level = cost
        + lin
            .iter()
            .zip(&confined)
            .map(|(l, &(rho, eps))| {
                let slack = eps * rho + l.rounding;
                2.0 * root_cost * slack + slack * slack
            })
            .sum::<f64>();
    let pinhole: Vec<PointView> = views
        .iter()
        .zip(&lin)
        .map(|(v, l)| {
            // The camera, rotated into the ray chart when the view has one; ℓ = W (n − c) with
            // c = n* − W⁻¹ e*: ℓ(X*) = e*.
            let turn = l.ray.unwrap_or_else(Matrix3::identity);
            let mut rt = Matrix3x4::zeros();
            rt.fixed_view_mut::<3, 3>(0, 0).copy_from(&(turn * v.rotation));
            rt.set_column(3, &(turn * v.translation));
            PointView::new(&depth_normalized(&rt), &(l.n - l.w_inverse * l.e), &l.w)
        })
        .collect();
    // Step 3, in the mean-depth chart, else the Euclidean one.
    let mut failure = LensBoundFailure::Convexity;
    for kind in [ChartKind::MeanDepth, ChartKind::Euclidean] {
        let Some(chart) = Chart::new(&pinhole, x, kind) else {
            continue;
        };
        let kappa = super::certificate::a_priori_kappa(kind, views.len());
        let Some((minorant, kappa_d)) = minorant_at_level(&chart.views, level, kappa) else {
            continue;
        };
        match tightened_bound(&chart, &lin, &confined, &minorant, kappa_d, gap) {
            Ok(bound) => return Ok(LensBound { raw_lower_bound: bound }),
            Err(why) => failure = why,
        }
    }
    Err(failure)
}

/// Steps 3-4 in one chart: the bound, or why there is none.
fn tightened_bound(
    chart: &Chart,
    lin: &[LinearisedObservation],
    confined: &[(f64, f64)],
    minorant: &Minorant<3>,
    kappa_d: f64,
    gap: f64,
) -> std::result::Result<f64, LensBoundFailure> {
    let k = 1.0 / (1.0 - kappa_d);
    // Σ‖Bᵢy‖² ≤ λ_S ‖y‖² (λ_S = 1 up to the rounding of the whitening), and ‖Bᵢ‖ per view.
    let jacobians: Vec<_> = chart.views.iter().map(|v| v.g - v.a0 * v.d.transpose()).collect();
    let s: Matrix3<f64> = jacobians.iter().map(|b| b.transpose() * b).sum();
    let lambda_s = s.symmetric_eigenvalues().max();
    let b_norms: Vec<f64> = jacobians.iter().map(|b| b.norm()).collect();
    // H = LLᵀ from its Cholesky factor.
    let factor = minorant.hessian.unpack();
    let lambda_h = (factor * factor.transpose()).symmetric_eigenvalues().min();
    let g_norm = minorant.gradient.norm();
    let a0 = minorant.cost - 2.0 * lin.iter().map(|l| l.e.norm() * l.rounding).sum::<f64>();
    // The bound a0 − a1 t + a2 t² over a ball of y where view i has the constant eps[i].
    let coefficients = |eps: &[f64]| {
        let alpha = lin
            .iter()
            .zip(eps)
            .map(|(l, e)| (l.e.norm() * e + l.rounding).powi(2))
            .sum::<f64>()
            .sqrt();
        let eps_max = eps.iter().copied().fold(0.0, f64::max);
        (
            g_norm + 2.0 * k * alpha * lambda_s.sqrt(),
            0.5 * lambda_h - 2.0 * k * k * eps_max * lambda_s,
        )
    };
    let target = minorant.cost * (1.0 - 0.5 * gap);
    let mut eps: Vec<f64> = confined.iter().map(|c| c.1).collect();
    // Outside the ball of `radius` every point is known to cost at least `target`.
    let mut radius = f64::INFINITY;
    let mut bound = f64::NEG_INFINITY;
    for _ in 0..TIGHTENING_ROUNDS {
        let (a1, a2) = coefficients(&eps);
        if !(a2 > 0.0) {
            break;
        }
        let t_min = (a1 / (2.0 * a2)).min(radius);
        bound = a0 - a1 * t_min + a2 * t_min * t_min;
        if bound >= target {
            break;
        }
        let t1 = beyond(a0, a1, a2, target);
        if !(t1 < radius) {
            break;
        }
        radius = t1;
        eps = lin
            .iter()
            .zip(confined)
            .zip(&b_norms)
            .map(|((l, &(rho, _)), b)| l.epsilon((k * b * radius).min(rho)))
            .collect::<Option<_>>()
            .ok_or(LensBoundFailure::Fold)?;
    }
    if !bound.is_finite() {
        return Err(LensBoundFailure::Convexity);
    }
    Ok(if radius.is_finite() { bound.min(target) } else { bound })
}

/// The exact stage after the first-order stages of [`super`] (module docs): `result` was solved
/// from the first-order views of `views` (all of them, or its inliers). Its point is refined on `F`
/// over the views it used; its cost, covariance and status become those of `F`; with method
/// `optimal` the certificate is [`lens_certificate`]'s, and never the first-order one, which bounds
/// another cost.
pub(crate) fn through_lenses(result: &mut PointTriangulation, views: &[LensView], opts: &TriangulationOptions) {
    let used: Vec<LensView> = match &result.inliers {
        Some(flags) => views.iter().zip(flags).filter(|(_, &f)| f).map(|(v, _)| *v).collect(),
        None => views.to_vec(),
    };
    let report = &mut result.report;
    let x0 = result.point;
    // ∞ behind a camera and for a NaN point (no projection in front).
    let start_cost = exact_cost(&used, &x0);
    let refinable = matches!(
        report.status,
        Status::Success | Status::GapNotClosed | Status::NotConverged
    ) && opts.method != Method::Linear
        && start_cost.is_finite();
    if !refinable {
        if start_cost.is_finite() {
            report.cost = start_cost;
            result.covariance = exact_covariance(&used, &x0);
        }
        report.certificate = None;
        report.test_residuals(2 * used.len(), 3);
        return;
    }
    let (mut x, mut summary) = refine(&used, &x0, &opts.local);
    let mut used = used;
    if let (Some(tau), Some(flags)) = (opts.outlier_threshold, result.inliers.as_mut()) {
        // The inliers are those within τ at the exact optimum, re-solved while they change (as
        // `robust` does, by the same exact residuals, at the first-order optimum).
        x = super::robust::reselect_at_optimum(
            flags,
            x,
            tau,
            &mut summary,
            |j, x| views[j].squared_residual(x),
            |flags, x| {
                used = views.iter().zip(flags).filter(|(_, &f)| f).map(|(v, _)| *v).collect();
                Some(refine(&used, x, &opts.local))
            },
        );
    }
    let cost = exact_cost(&used, &x);
    result.point = x;
    result.covariance = exact_covariance(&used, &x);
    report.cost = cost;
    report.iterations += summary.iterations;
    report.termination = summary.termination;
    report.status = match summary.termination {
        Termination::NonFiniteCost | Termination::SingularHessian => Status::NumericalFailure,
        Termination::MaxIterations => Status::NotConverged,
        _ => Status::Success,
    };
    report.certificate = None;
    if opts.method == Method::Optimal && report.status == Status::Success {
        // Without a proof, the trivial bound 0 still certifies exact data (a cost at the rounding level).
        let raw = match lens_certificate(&used, &x, cost, opts.certify.max_relative_gap) {
            Ok(bound) => Some(bound.raw_lower_bound),
            Err(_) => (relative_gap(cost, 0.0) <= opts.certify.max_relative_gap).then_some(0.0),
        };
        if let Some(raw) = raw {
            let lower_bound = raw.min(cost).max(0.0);
            let relative_gap = relative_gap(cost, lower_bound);
            report.certificate = Some(Certificate::new(
                CertificateKind::LensConvexityTest,
                Primitive::Point,
                lower_bound,
                raw,
                relative_gap,
                relative_gap <= opts.certify.max_relative_gap,
            ));
        }
        if !report.certified() {
            report.status = Status::GapNotClosed;
        }
    }
    report.test_residuals(2 * used.len(), 3);
}

/// The radius `t₁ ≥ 0` beyond which `a0 − a1 t + a2 t² ≥ target` (`a2 > 0`): the larger root, or 0
/// when the quadratic never falls below the target.
fn beyond(a0: f64, a1: f64, a2: f64, target: f64) -> f64 {
    let discriminant = a1 * a1 - 4.0 * a2 * (a0 - target);
    if discriminant < 0.0 {
        return 0.0;
    }
    ((a1 + discriminant.sqrt()) / (2.0 * a2)).max(0.0)
}

/// `(Σ JᵢᵀJᵢ)⁻¹` of the exact residuals at `x` ([`crate::triangulation::uncertainty`]).
fn exact_covariance(views: &[LensView], x: &Vector3<f64>) -> Option<Matrix3<f64>> {
    let mut information = Matrix3::zeros();
    for v in views {
        let (_, j) = v.residual_and_jacobian(x)?;
        information += j.transpose() * j;
    }
    covariance_of_information3(&information)
}

/// A track through lenses as the consensus of [`super::robust`] sees it: the first-order views
/// `first` of `views` for the linear and local stages, the exact residuals of `views` for every
/// decision, and `refine` for a pair's minimum.
pub(crate) struct LensTrack<'a, 'b> {
    pub first: &'a [PointView],
    pub views: &'a [LensView<'b>],
}

impl RobustTrack for LensTrack<'_, '_> {
    fn first_order(&self) -> &[PointView] {
        self.first
    }

    fn squared_error(&self, j: usize, x: &Vector3<f64>) -> f64 {
        self.views[j].squared_residual(x)
    }

    fn refine_pair(
        &self,
        (a, b): (usize, usize),
        x0: &Vector3<f64>,
        opts: &TriangulationOptions,
    ) -> Option<Vector3<f64>> {
        Some(refine(&[self.views[a], self.views[b]], x0, &opts.local).0)
    }
}

/// One track seen through `views`: the first-order stages of [`super`] on `first_order_view`s,
/// then, when a camera distorts, [`through_lenses`]. `started` times the whole call.
pub(crate) fn solve_lens_track(
    views: &[LensView],
    frame: &WorldFrame,
    opts: &TriangulationOptions,
    started: Instant,
) -> Result<PointTriangulation> {
    let first: Vec<PointView> = views
        .iter()
        .enumerate()
        .map(|(i, v)| first_order_view(v, i))
        .collect::<Result<_>>()?;
    Ok(solve_through_lenses(&first, views, frame, opts, started))
}

/// The solve of a track whose first-order views `first` (of `views`) are built. With `optimal`
/// through a lens, the first stages run `local` (a first-order certificate bounds another cost), and
/// the first-order branch and bound, whose global search may find a better basin, only when the lens
/// certificate then fails; the certified result, else the cheaper one, is kept.
pub(crate) fn solve_through_lenses(
    first: &[PointView],
    views: &[LensView],
    frame: &WorldFrame,
    opts: &TriangulationOptions,
    started: Instant,
) -> PointTriangulation {
    if !views.iter().any(|v| v.camera.distortion().is_some()) {
        return super::solve_track_views(first, frame, opts, started);
    }
    let track = LensTrack { first, views };
    let through = |first_opts: &TriangulationOptions| {
        let mut result = super::solve_track_views(&track, frame, first_opts, started);
        result.report.method = opts.method;
        through_lenses(&mut result, views, opts);
        result
    };
    let mut result = if opts.method == Method::Optimal {
        let local = through(&TriangulationOptions {
            method: Method::Local,
            ..opts.clone()
        });
        if local.report.certified() {
            local
        } else {
            let searched = through(opts);
            let cheaper = searched.report.cost < local.report.cost || !local.report.cost.is_finite();
            if searched.report.certified() || cheaper {
                searched
            } else {
                local
            }
        }
    } else {
        through(opts)
    };
    result.report.time_seconds = started.elapsed().as_secs_f64();
    result
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::{Camera, CameraModel};
    use crate::rng::Rng;

    /// A view of `x` through `lens` from a camera at distance 5 whose axis is `angle` off the point,
    /// the pixel displaced by `noise` px.
    fn view_of(
        lens: &Camera,
        x: &Vector3<f64>,
        angle: f64,
        noise: Vector2<f64>,
        rng: &mut Rng,
    ) -> (Matrix3<f64>, Vector3<f64>, Vector2<f64>) {
        let centre = x + rng.unit_vector3() * 5.0;
        let to_point = (x - centre).normalize();
        let side = to_point.cross(&rng.unit_vector3()).normalize();
        let axis = to_point * angle.cos() + side * angle.sin();
        let zx = axis.cross(&rng.unit_vector3()).normalize();
        let rotation = Matrix3::from_rows(&[zx.transpose(), axis.cross(&zx).transpose(), axis.transpose()]);
        let translation = -(rotation * centre);
        let u = lens.project(&(rotation * x + translation)) + noise;
        (rotation, translation, u)
    }

    /// The chart coordinates of the normalised point `n` (identity, or the ray chart's `n′`).
    fn chart_of(l: &LinearisedObservation, n: &Vector2<f64>) -> Option<Vector2<f64>> {
        match &l.ray {
            None => Some(*n),
            Some(r) => {
                let w = r * Vector3::new(n.x, n.y, 1.0);
                (w.z > 0.0).then(|| Vector2::new(w.x / w.z, w.y / w.z))
            }
        }
    }

    #[test]
    fn beyond_the_returned_radius_the_quadratic_is_above_the_target() {
        let mut rng = Rng::new(8);
        for _ in 0..2000 {
            let (a0, a1, a2) = (
                rng.uniform_in(0.0, 10.0),
                rng.uniform_in(0.0, 5.0),
                rng.uniform_in(0.01, 3.0),
            );
            let target = a0 * rng.uniform_in(0.5, 1.2);
            let t1 = beyond(a0, a1, a2, target);
            for k in 0..50 {
                let t = t1 * (1.0 + 1e-9) + k as f64 * rng.uniform_in(0.0, 1.0);
                assert!(
                    a0 - a1 * t + a2 * t * t >= target - 1e-9 * target.abs(),
                    "{a0} {a1} {a2} {target}: t = {t}"
                );
            }
            // The least such radius: just inside it (when positive) the quadratic is below the target.
            if t1 > 1e-6 {
                let t = t1 * (1.0 - 1e-6);
                assert!(
                    a0 - a1 * t + a2 * t * t < target,
                    "{a0} {a1} {a2} {target}: not the least, t1 = {t1}"
                );
            }
        }
    }

    #[test]
    fn step_one_confines_every_projection_within_the_level_and_bounds_the_remainder() {
        // The claims of steps 1-2 for one view, checked at sampled normalised points with the
        // library's projection: a point with ‖e‖ ≤ √C lies in B = {‖W n′‖ ≤ ρ}, and inside B
        // ‖e‖ ≥ ‖ℓ‖ − ε‖v‖ − s and ‖e‖ ≥ (1 − ε)‖v‖ − ‖e*‖ (the mean-value bound).
        let mut rng = Rng::new(3);
        let lenses = [
            Camera::new(CameraModel::SimpleRadial, &[5000.0, 600.0, 500.0, -14.0]).unwrap(),
            Camera::new(
                CameraModel::OpenCvFisheye,
                &[300.0, 300.0, 512.0, 384.0, 0.05, -0.01, 0.002, -3e-4],
            )
            .unwrap(),
            Camera::new(
                CameraModel::OpenCv,
                &[600.0, 610.0, 320.0, 240.0, -0.3, 0.0, 2e-3, -1e-3],
            )
            .unwrap(),
        ];
        let (mut inside, mut checked) = (0, 0);
        for (k, camera) in lenses.iter().enumerate() {
            let widest = [0.09, 1.35, 0.6][k];
            for _ in 0..40 {
                let x = Vector3::new(rng.normal(), rng.normal(), rng.normal()) * 0.2;
                let noise = Vector2::new(rng.normal(), rng.normal()) * 2.0;
                let (rotation, translation, pixel) = view_of(camera, &x, rng.uniform_in(0.0, widest), noise, &mut rng);
                let view = LensView {
                    camera,
                    rotation,
                    translation,
                    pixel,
                    whitening: Matrix2::identity(),
                };
                // A level above the view's own cost, as with other views in the track.
                let cost = view.squared_residual(&x) + rng.uniform_in(0.5, 20.0);
                let Ok(l) = LinearisedObservation::new(
                    view.camera,
                    &view.whitening,
                    &view.pixel,
                    &view.x_cam(&x),
                    cost,
                    SPLITS,
                    true,
                ) else {
                    continue;
                };
                let Some((rho, eps)) = l.confinement(cost) else {
                    continue;
                };
                // Step 1's contract: ε is the bound over B's box, and B's boundary is above the level.
                assert_eq!(l.epsilon(rho), Some(eps));
                assert!(
                    (1.0 - eps) * rho > cost.sqrt() + l.e.norm() + l.rounding,
                    "{k}: ρ = {rho}, ε = {eps}"
                );
                let xc = rotation * x + translation;
                let n_star = Vector2::new(xc.x / xc.z, xc.y / xc.z);
                // Sample normalised points around the estimate out to twice B in the chart's metric.
                let reach = 2.0 * rho * l.w_inverse.norm();
                for _ in 0..400 {
                    let offset = Vector2::new(rng.uniform_in(-1.0, 1.0), rng.uniform_in(-1.0, 1.0)) * reach;
                    let n = match &l.ray {
                        None => n_star + offset,
                        Some(r) => {
                            let w = r.transpose() * Vector3::new(offset.x, offset.y, 1.0);
                            if w.z <= 0.0 {
                                continue;
                            }
                            Vector2::new(w.x / w.z, w.y / w.z)
                        }
                    };
                    let Some(c) = chart_of(&l, &n) else { continue };
                    // e(n) through the library's projection of the ray (n, 1) in the camera frame.
                    let u = camera.project(&Vector3::new(n.x, n.y, 1.0));
                    let e = (u - pixel).norm();
                    let v = (l.w * (c - l.n)).norm();
                    checked += 1;
                    if e <= cost.sqrt() {
                        assert!(
                            v <= rho * (1.0 + 1e-9),
                            "{k}: ‖e‖ = {e} ≤ √C = {} but ‖W n′‖ = {v} > ρ = {rho}",
                            cost.sqrt()
                        );
                    }
                    if v <= rho {
                        inside += 1;
                        let ell = (l.e + l.w * (c - l.n)).norm();
                        assert!(
                            e >= ell - eps * v - l.rounding - 1e-9 * ell,
                            "{k}: ‖e‖ = {e} < ‖ℓ‖ − εv = {}",
                            ell - eps * v
                        );
                    }
                }
            }
        }
        assert!(checked > 20_000 && inside > 2_000, "{checked} {inside}");
    }
}
