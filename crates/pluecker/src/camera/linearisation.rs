//! An observation linearised through a lens at a point of its image, for the certificates through a
//! lens (the triangulated point's, [`crate::triangulation::point::lens`], and the pose's,
//! [`crate::pose::certificate`]).
//!
//! An observation is the observed pixel `u₀` of a camera `u = K D(n)` (`n` normalised coordinates),
//! whitened by `L` (`Lᵀ L = Σ⁻¹`): its residual at `n` is `e(n) = L (K D(n) − u₀) = M (D(n) − d₀)`
//! with `M = L K₂` (`K₂` the upper-left block of `K`) and `d₀` the observation's distorted normalised
//! coordinates. Linearised at `n*` (`e* = e(n*)`, `J* = ∂D/∂n(n*)`, `W = M J*`):
//! `e(n) = e* + (I + Δ) W (n − n*)` along the segment from `n*` (mean value theorem), with
//! `Δ = M (J̄ − J*) W⁻¹`, `J̄` the mean of `J` along the segment. Interval enclosures of
//! [`crate::camera::bounds`] hold `J` in a box of matrices on each of a few boxes covering the ball, so
//! `J̄` lies in the convex hull of their union, and `‖Δ‖₂ ≤ ε`, the largest `‖M (V − J*) W⁻¹‖₂` over the
//! vertices `V` of those boxes (a convex function's largest value on a hull; [`LinearisedObservation::epsilon`]).
//!
//! **Confinement** ([`LinearisedObservation::confinement`]). On the boundary of `B = {n : ‖W (n − n*)‖ ≤ ρ}`,
//! `‖e‖ ≥ (1 − ε) ρ − ‖e*‖ − s` (`s` the rounding of `e*`), which exceeds `√C` for `ρ` chosen so.
//! Let `n` lie in the disc where `D` is one-to-one ([`crate::camera::bounds::domain`]) with
//! `‖e(n)‖ ≤ √C`: `D(n)` lies in the ellipse `{d : ‖M (d − d₀)‖ ≤ √C}`, which the constructor requires
//! inside the disc of radius `ρ_D` that `D` maps onto. The segment from `D(n*)` to `D(n)` lies in that
//! ellipse, and its preimage under the homeomorphism `D` is a path from `n*` to `n` along which
//! `‖e‖ ≤ √C`: it never meets `∂B`, so `n ∈ B`.
//!
//! A fisheye projection off axis may use the **ray chart**: the normalised coordinates `n′` of the
//! camera rotated so that the ray of `n*` is its optical axis (`n′* = 0`, `n = h(n′)` a homography),
//! with the Jacobian of `D ∘ h`; a box of `n′` stays small in angle where one of `n` stretches with
//! `1/cos²θ`. The argument holds in either chart.

use crate::camera::bounds::{
    fisheye_ray_enclosure, jacobian_enclosure, radius_about, Coefficients, Distortion, Domain,
};
use crate::camera::Camera;
use nalgebra::{Matrix2, Matrix3, Rotation3, Vector2, Vector3};

/// Absolute rounding allowance of a computed pixel, relative to the pixel's magnitude (pixels up to
/// 1e5 computed through a few dozen operations).
pub(crate) const PIXEL_ROUNDING: f64 = 1e-13;
/// `εᵢ` above which the box of [`LinearisedObservation::epsilon`] is split.
pub(crate) const SPLIT_EPSILON: f64 = 0.01;
/// Sub-boxes per side of a split box of [`LinearisedObservation::epsilon`].
pub(crate) const SPLITS: usize = 8;
/// Fisheye projections farther off axis than this (`tan 10°`) use the ray chart.
const RAY_CHART_TAN: f64 = 0.176;
/// Growth of a view's confinement radius per retry of step 1.
const RADIUS_RETRIES: usize = 8;

/// Why a certificate through a lens found no bound.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LensBoundFailure {
    /// A lens that is not radially symmetric, or not covered by `camera::bounds`.
    Lens,
    /// A projection, or the box about it, reaches a lens's fold radius, or `εᵢ ≥ 1`.
    Fold,
    /// The convexity test failed (low parallax, large residuals, a second minimum nearby).
    Convexity,
}

/// One observation linearised at `n*` (module docs): `W`, `M`, `e*`, `n*`, `J*`, the distortion and
/// its one-to-one radius, `s`.
pub(crate) struct LinearisedObservation {
    pub(crate) w: Matrix2<f64>,
    pub(crate) w_inverse: Matrix2<f64>,
    pub(crate) m: Matrix2<f64>,
    pub(crate) e: Vector2<f64>,
    pub(crate) n: Vector2<f64>,
    pub(crate) j: Matrix2<f64>,
    pub(crate) distortion: Distortion,
    /// The one-to-one radius of [`crate::camera::bounds::domain`].
    pub(crate) radius: f64,
    /// The ray chart's rotation `R` (camera frame to a frame whose optical axis is the ray of `nᵢ*`),
    /// for fisheyes off axis; then `n` is `n′ = 0` and `J` is that of `D ∘ h`.
    pub(crate) ray: Option<Matrix3<f64>>,
    pub(crate) rounding: f64,
    /// Sub-boxes per side of the box of [`LinearisedObservation::epsilon`] when one box is not enough: 1 (never
    /// split) or [`SPLITS`].
    pub(crate) splits: usize,
    /// `εᵢ` at step 1's first radius ([`LinearisedObservation::first_radius`]) when choosing the chart already
    /// evaluated it (fisheyes off axis), so that [`LinearisedObservation::confinement`] does not repeat it.
    pub(crate) first_epsilon: Option<Option<f64>>,
}

impl LinearisedObservation {
    /// The observation `pixel` of `camera`, whitened by `whitening`, linearised at the camera-frame
    /// point `xc` (`n* = (x/z, y/z)`), for the level `cost` (`Σ ‖e‖²` over every observation; the
    /// path argument of the module docs needs the observation's ellipse of that level inside the
    /// lens's image disc). `splits`: sub-boxes per side where one box of [`Self::epsilon`]
    /// overestimates (1: never split). `ray_chart`: a fisheye off axis may use the ray chart.
    pub(crate) fn new(
        camera: &Camera,
        whitening: &Matrix2<f64>,
        pixel: &Vector2<f64>,
        xc: &Vector3<f64>,
        cost: f64,
        splits: usize,
        ray_chart: bool,
    ) -> std::result::Result<LinearisedObservation, LensBoundFailure> {
        let known = lens_domain(camera)?;
        Self::new_in(camera, &known, whitening, pixel, xc, cost, splits, ray_chart)
    }

    /// [`Self::new`] with the camera's [`lens_domain`] computed once for all its observations.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn new_in(
        camera: &Camera,
        (distortion, domain): &(&Distortion, Domain),
        whitening: &Matrix2<f64>,
        pixel: &Vector2<f64>,
        xc: &Vector3<f64>,
        cost: f64,
        splits: usize,
        ray_chart: bool,
    ) -> std::result::Result<LinearisedObservation, LensBoundFailure> {
        let xc = *xc;
        let (distortion, domain) = ((*distortion).clone(), *domain);
        let lens = camera.distortion();
        if !(xc.z > 0.0) {
            return Err(LensBoundFailure::Fold);
        }
        let n = Vector2::new(xc.x / xc.z, xc.y / xc.z);
        if !(n.norm() < domain.radius) {
            return Err(LensBoundFailure::Fold);
        }
        // Step 1's path argument needs the ellipse {‖e‖ ≤ √C} of distorted normalised coordinates
        // inside the disc that the one-to-one disc maps onto.
        let pinhole = camera.intrinsics();
        let m = whitening * pinhole.pixel_jacobian();
        let m_inverse_norm = m.try_inverse().ok_or(LensBoundFailure::Lens)?.norm();
        let observed = pinhole.pixel_to_normalized(pixel);
        if !(observed.norm() + cost.sqrt() * m_inverse_norm < domain.image_radius) {
            return Err(LensBoundFailure::Fold);
        }
        let jd = lens.map_or(Matrix2::identity(), |lens: &Camera| lens.distort(&n).1);
        let u = camera.project(&xc);
        let e = whitening * (u - pixel);
        // The rounding of e: of u and of the pixel, through L.
        let rounding = whitening.norm() * PIXEL_ROUNDING * (u.norm() + pixel.norm() + 1.0);
        let w = m * jd;
        let plain = LinearisedObservation {
            w,
            w_inverse: w.try_inverse().ok_or(LensBoundFailure::Fold)?,
            m,
            e,
            n,
            j: jd,
            distortion,
            radius: domain.radius,
            ray: None,
            rounding,
            splits,
            first_epsilon: None,
        };
        // A fisheye off axis may do better in the ray chart (module docs): the chart of smaller εᵢ.
        if let (Distortion::Fisheye(_), true) = (&plain.distortion, ray_chart && n.norm() > RAY_CHART_TAN) {
            let turned =
                Rotation3::rotation_between(&xc, &Vector3::z()).and_then(|r| plain.in_ray_chart(r.into_inner()));
            if let Some(turned) = turned {
                // Both charts share eᵢ* and sᵢ, hence the first radius.
                let rho = plain.first_radius(cost);
                // The plain chart is chosen only where its εᵢ is at most the ray chart's: its
                // enclosures stop as soon as they show that it is not.
                let a = turned.epsilon(rho);
                let b = plain.epsilon_unless_above(rho, a.unwrap_or(f64::INFINITY));
                let better = match (a, b) {
                    (Some(a), Some(b)) => a < b,
                    (Some(_), None) => true,
                    _ => false,
                };
                let (chosen, eps) = if better { (turned, a) } else { (plain, b) };
                return Ok(LinearisedObservation {
                    first_epsilon: Some(eps),
                    ..chosen
                });
            }
        }
        Ok(plain)
    }

    /// The same view in the ray chart of `ray` (`n′ = 0` at the estimate, `J` that of `D ∘ h`).
    fn in_ray_chart(&self, ray: Matrix3<f64>) -> Option<LinearisedObservation> {
        let j = self.j * homography_jacobian(&ray);
        let w = self.m * j;
        Some(LinearisedObservation {
            w,
            w_inverse: w.try_inverse()?,
            n: Vector2::zeros(),
            j,
            ray: Some(ray),
            distortion: self.distortion.clone(),
            first_epsilon: None,
            ..*self
        })
    }

    /// `εᵢ` over the box holding `{n : ‖W(n − n*)‖ ≤ ρ}`; `None` where the box reaches the edge of the
    /// domain or the camera's principal plane. Interval arithmetic overestimates the Jacobian's
    /// variation by a multiple of the box's width (the dependency effect); where that shows (`εᵢ` above
    /// [`SPLIT_EPSILON`]) the box is split into `splits` x `splits` sub-boxes, and `E` is the largest of
    /// their radii about `J*` (each sub-box's enclosure holds the Jacobian on it).
    pub(crate) fn epsilon(&self, rho: f64) -> Option<f64> {
        self.epsilon_unless_above(rho, f64::INFINITY)
    }

    /// [`Self::epsilon`], or, once the sub-boxes show that it exceeds `cap`, some value above `cap`
    /// (the enclosures of the other sub-boxes are then not computed): enough to compare two charts.
    fn epsilon_unless_above(&self, rho: f64, cap: f64) -> Option<f64> {
        let single = self.epsilon_in_unless_above(rho, 1, cap)?;
        if !(single > SPLIT_EPSILON) || self.splits == 1 {
            return Some(single);
        }
        // min(single, split) is exact whenever it is at most `cap`.
        Some(single.min(self.epsilon_in_unless_above(rho, self.splits, cap)?))
    }

    /// `εᵢ` over the box of [`Self::epsilon`] cut into `pieces` x `pieces` sub-boxes. Each sub-box that
    /// meets the ball (the ellipse `{‖W(n − n*)‖ ≤ ρ}`; the others are skipped) has an enclosure, a box
    /// of matrices holding `J` on it, so the mean `J̄` of `J` along a segment of the ball lies in the
    /// convex hull of their union; `‖M (J̄ − J*) W⁻¹‖₂` is convex in `J̄`, so its largest value there is
    /// at a vertex of one of the enclosures (16 each).
    pub(crate) fn epsilon_in(&self, rho: f64, pieces: usize) -> Option<f64> {
        self.epsilon_in_unless_above(rho, pieces, f64::INFINITY)
    }

    /// [`Self::epsilon_in`], returned as soon as it exceeds `cap` (then a value above `cap`, at most
    /// that of every sub-box).
    fn epsilon_in_unless_above(&self, rho: f64, pieces: usize, cap: f64) -> Option<f64> {
        let wtw_inverse = self.w_inverse * self.w_inverse.transpose();
        let half = Vector2::new(wtw_inverse[(0, 0)].sqrt(), wtw_inverse[(1, 1)].sqrt()) * rho;
        let step = half * (2.0 / pieces as f64);
        let (m_abs, w_inverse_abs) = (self.m.abs(), self.w_inverse.abs());
        // M (V − J*) W⁻¹ = Σ (V_rc − J*_rc) M e_r e_cᵀ W⁻¹ is linear in V: its four directions.
        let basis = |r: usize, c: usize| self.m.column(r) * self.w_inverse.row(c);
        let basis = [[basis(0, 0), basis(0, 1)], [basis(1, 0), basis(1, 1)]];
        let mut eps: f64 = 0.0;
        // Outer sub-boxes first (their variation is the largest), so that the skip below skips most.
        let outer_first = |k: usize| if k % 2 == 0 { k / 2 } else { pieces - 1 - k / 2 };
        for a in (0..pieces).map(outer_first) {
            for b in (0..pieces).map(outer_first) {
                let lo = self.n - half + Vector2::new(step.x * a as f64, step.y * b as f64);
                let hi = lo + step;
                if pieces > 1 && !(self.least_whitened_distance(&lo, &hi) <= rho * (1.0 + 1e-9)) {
                    continue;
                }
                let enclosure = match (&self.ray, &self.distortion) {
                    (Some(r), Distortion::Fisheye(c)) => {
                        fisheye_ray_enclosure(c, self.radius, &r.transpose(), &lo, &hi)?
                    }
                    _ => jacobian_enclosure(&self.distortion, self.radius, &lo, &hi)?,
                };
                // ‖|M| E |W⁻¹|‖_F (E the enclosure's entrywise radius about J*) bounds every vertex's
                // value: a sub-box below the largest so far cannot raise it.
                if (m_abs * radius_about(&enclosure, &self.j) * w_inverse_abs).norm() <= eps {
                    continue;
                }
                // The vertices are the 16 sums of one end's term per entry, pairs of entries summed first.
                let term = |r: usize, c: usize, end: f64| basis[r][c] * (end - self.j[(r, c)]);
                let ends = |r: usize, c: usize| [term(r, c, enclosure[r][c].lo), term(r, c, enclosure[r][c].hi)];
                let (e00, e01, e10, e11) = (ends(0, 0), ends(0, 1), ends(1, 0), ends(1, 1));
                let first = [e00[0] + e01[0], e00[0] + e01[1], e00[1] + e01[0], e00[1] + e01[1]];
                let second = [e10[0] + e11[0], e10[0] + e11[1], e10[1] + e11[0], e10[1] + e11[1]];
                for x in &first {
                    for y in &second {
                        eps = eps.max(spectral_norm(&(x + y)));
                    }
                }
                if eps > cap {
                    return Some(eps);
                }
            }
        }
        // The rounding of the products above (relative, far below the enclosures' own widening).
        let eps = eps * (1.0 + 1e-12);
        eps.is_finite().then_some(eps)
    }

    /// The least `‖W (n − n*)‖` over the box `[lo, hi]` (0 when it holds `n*`; else on an edge, where the
    /// quadratic's least value has a closed form).
    fn least_whitened_distance(&self, lo: &Vector2<f64>, hi: &Vector2<f64>) -> f64 {
        if (lo.x..=hi.x).contains(&self.n.x) && (lo.y..=hi.y).contains(&self.n.y) {
            return 0.0;
        }
        let corners = [*lo, Vector2::new(hi.x, lo.y), *hi, Vector2::new(lo.x, hi.y)];
        (0..4)
            .map(|k| {
                let (p, q) = (corners[k], corners[(k + 1) % 4]);
                let (a, d) = (self.w * (p - self.n), self.w * (q - p));
                let t = if d.norm_squared() > 0.0 {
                    (-a.dot(&d) / d.norm_squared()).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                (a + d * t).norm()
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// `√C + ‖eᵢ*‖ + sᵢ`: what step 1's radius `ρ` must leave, `(1 − εᵢ) ρ` above it.
    pub(crate) fn need(&self, cost: f64) -> f64 {
        cost.sqrt() + self.e.norm() + self.rounding
    }

    /// Step 1's first radius `ρ = 1.001 (√C + ‖eᵢ*‖ + sᵢ)`.
    pub(crate) fn first_radius(&self, cost: f64) -> f64 {
        self.need(cost) * 1.001
    }

    /// Step 1: `(ρᵢ, εᵢ)` with `(1 − εᵢ)ρᵢ − ‖eᵢ*‖ − sᵢ > √C`.
    pub(crate) fn confinement(&self, cost: f64) -> Option<(f64, f64)> {
        let need = self.need(cost);
        let mut rho = self.first_radius(cost);
        for retry in 0..RADIUS_RETRIES {
            let eps = match (retry, self.first_epsilon) {
                (0, Some(known)) => known?,
                _ => self.epsilon(rho)?,
            };
            if eps < 1.0 && (1.0 - eps) * rho > need {
                return Some((rho, eps));
            }
            if !(eps < 0.5) {
                return None;
            }
            rho = need / (1.0 - eps) * 1.01;
        }
        None
    }
}

/// The distortion of `camera` that [`crate::camera::bounds`] covers and the disc where it is proved
/// one-to-one (the identity and the whole plane for a pinhole camera), as the camera computed them once.
pub(crate) fn lens_domain(camera: &Camera) -> std::result::Result<(&Distortion, Domain), LensBoundFailure> {
    static IDENTITY: Distortion = Distortion::Polynomial(Coefficients::new_const());
    match camera.distortion() {
        None => Ok((
            &IDENTITY,
            Domain {
                radius: f64::INFINITY,
                image_radius: f64::INFINITY,
            },
        )),
        Some(lens) => {
            let distortion = lens.covered_distortion().ok_or(LensBoundFailure::Lens)?;
            Ok((distortion, lens.one_to_one_domain().ok_or(LensBoundFailure::Fold)?))
        }
    }
}

/// The largest singular value of a 2 x 2 matrix: `(√((a + d)² + (b − c)²) + √((a − d)² + (b + c)²)) / 2`.
pub(crate) fn spectral_norm(m: &Matrix2<f64>) -> f64 {
    let (a, b, c, d) = (m[(0, 0)], m[(0, 1)], m[(1, 0)], m[(1, 1)]);
    // sqrt of the sum of squares rather than hypot (several times slower): the entries are far from
    // overflow, and the relative rounding is covered by the callers' allowance.
    let (p, q) = ((a + d).powi(2) + (b - c).powi(2), (a - d).powi(2) + (b + c).powi(2));
    0.5 * (p.sqrt() + q.sqrt())
}

/// `∂h/∂n′` at `n′ = 0` of `h(n′) = (w₁/w₃, w₂/w₃)`, `w = Rᵀ (n′, 1)`: the ray chart's map to `n`.
fn homography_jacobian(ray: &Matrix3<f64>) -> Matrix2<f64> {
    let back = ray.transpose();
    let w = back.column(2);
    let h = Vector2::new(w.x / w.z, w.y / w.z);
    Matrix2::from_fn(|r, c| (back[(r, c)] - h[r] * back[(2, c)]) / w.z)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::CameraModel;
    use crate::rng::Rng;

    #[test]
    fn the_spectral_norm_is_the_largest_singular_value() {
        let mut rng = Rng::new(5);
        for _ in 0..200 {
            let m = Matrix2::from_fn(|_, _| rng.normal() * 10f64.powf(rng.uniform_in(-3.0, 3.0)));
            let svd = m.singular_values();
            let largest = svd[0].max(svd[1]);
            assert!((spectral_norm(&m) - largest).abs() <= 1e-13 * largest, "{m}");
        }
    }

    /// Two radial lenses (barrel and pincushion), a strong OPENCV one and an OPENCV_FISHEYE one. The
    /// fisheye's points lie off axis, in the ray chart: there J (of D ∘ h) is not symmetric, so an
    /// enclosure whose off-diagonal entries were swapped would show.
    fn test_lenses() -> [Camera; 4] {
        [
            Camera::new(CameraModel::Radial, &[300.0, 320.0, 240.0, 0.3, 0.05]).unwrap(),
            Camera::new(CameraModel::Radial, &[300.0, 320.0, 240.0, -0.2, 0.02]).unwrap(),
            Camera::new(
                CameraModel::OpenCv,
                &[250.0, 260.0, 320.0, 240.0, -0.3, 0.1, 1e-3, -5e-4],
            )
            .unwrap(),
            Camera::new(
                CameraModel::OpenCvFisheye,
                &[300.0, 300.0, 320.0, 240.0, 0.05, -0.01, 0.002, -0.0005],
            )
            .unwrap(),
        ]
    }

    #[test]
    fn epsilon_bounds_the_sampled_variation_of_the_jacobian_on_the_ball() {
        // ‖M (J(n) − J*) W⁻¹‖₂ at points of the ball {‖W (n − n*)‖ ≤ ρ}, J by central differences of the
        // distortion map, never exceeds ε (one box and split). Points on the axes too, where one entry of
        // J varies most (a bound that left out an entry's extreme would show there).
        let lenses = test_lenses();
        let mut rng = Rng::new(13);
        let (mut tightest, mut charted) = (f64::INFINITY, 0);
        for lens in &lenses {
            let camera = lens.clone();
            for k in 0..24 {
                let xc = match k % 3 {
                    0 => Vector3::new(0.0, rng.uniform_in(-1.0, 1.0), 1.0),
                    1 => Vector3::new(rng.uniform_in(-1.0, 1.0), 0.0, 1.0),
                    _ => Vector3::new(rng.uniform_in(-1.0, 1.0), rng.uniform_in(-1.0, 1.0), 1.0),
                };
                let l = if k % 2 == 0 {
                    Matrix2::identity()
                } else {
                    Matrix2::new(rng.uniform_in(0.3, 2.0), rng.normal(), 0.0, rng.uniform_in(0.3, 2.0))
                };
                let pixel = camera.project(&xc) + Vector2::new(rng.normal(), rng.normal());
                let xc = if lens.model() == CameraModel::OpenCvFisheye {
                    xc * 2.0 - Vector3::z()
                } else {
                    xc
                };
                let Ok(lin) = LinearisedObservation::new(&camera, &l, &pixel, &xc, 1.0, SPLITS, true) else {
                    continue;
                };
                // The chart's map to normalised coordinates: n′ ↦ (w₁/w₃, w₂/w₃), w = Rᵀ (n′, 1).
                let chart = |n: Vector2<f64>| match lin.ray {
                    Some(r) => {
                        let w = r.transpose() * Vector3::new(n.x, n.y, 1.0);
                        Vector2::new(w.x / w.z, w.y / w.z)
                    }
                    None => n,
                };
                let jacobian = |n: Vector2<f64>| {
                    let h = 1e-6;
                    let column =
                        |d: Vector2<f64>| (lens.distort(&chart(n + d)).0 - lens.distort(&chart(n - d)).0) / (2.0 * h);
                    Matrix2::from_columns(&[column(Vector2::new(h, 0.0)), column(Vector2::new(0.0, h))])
                };
                let j_star = jacobian(lin.n);
                for rho in [2.0, 8.0, 20.0] {
                    for pieces in [1, SPLITS] {
                        let Some(eps) = lin.epsilon_in(rho, pieces) else {
                            continue;
                        };
                        let mut sampled: f64 = 0.0;
                        for a in 0..64 {
                            let angle = a as f64 * std::f64::consts::TAU / 64.0;
                            for t in [0.25, 0.5, 0.75, 1.0] {
                                let v = Vector2::new(angle.cos(), angle.sin()) * rho * t;
                                let n = lin.n + lin.w_inverse * v;
                                sampled = sampled.max(spectral_norm(&(lin.m * (jacobian(n) - j_star) * lin.w_inverse)));
                            }
                        }
                        // Central differences: error O(h²) relative, far below the 1e-6 allowed here.
                        assert!(
                            eps >= sampled * (1.0 - 1e-6),
                            "ρ {rho}, {pieces} pieces: ε {eps} < sampled {sampled}"
                        );
                        if sampled > 1e-3 {
                            tightest = tightest.min(eps / sampled);
                        }
                        charted += lin.ray.is_some() as usize;
                    }
                }
            }
        }
        assert!(tightest.is_finite(), "no ball was checked");
        assert!(charted > 0, "no ball in the ray chart was checked");
        eprintln!("least ε / sampled variation {tightest:.3}");
    }

    #[test]
    fn the_least_whitened_distance_of_a_box_is_its_sampled_least() {
        // Against a dense grid of the box: never above its least value, and within the grid's spacing.
        let lens = Camera::new(
            CameraModel::OpenCv,
            &[250.0, 260.0, 320.0, 240.0, -0.3, 0.1, 1e-3, -5e-4],
        )
        .unwrap();
        let camera = lens.clone();
        let mut rng = Rng::new(8);
        for _ in 0..100 {
            let l = Matrix2::new(rng.uniform_in(0.3, 2.0), rng.normal(), 0.0, rng.uniform_in(0.3, 2.0));
            let xc = Vector3::new(rng.uniform_in(-1.0, 1.0), rng.uniform_in(-1.0, 1.0), 1.0);
            let pixel = camera.project(&xc) + Vector2::new(rng.normal(), rng.normal());
            let Ok(lin) = LinearisedObservation::new(&camera, &l, &pixel, &xc, 1.0, SPLITS, false) else {
                continue;
            };
            let lo = lin.n + Vector2::new(rng.uniform_in(-0.2, 0.2), rng.uniform_in(-0.2, 0.2));
            let hi = lo + Vector2::new(rng.uniform_in(0.0, 0.1), rng.uniform_in(0.0, 0.1));
            let least = lin.least_whitened_distance(&lo, &hi);
            let steps = 200;
            let mut sampled = f64::INFINITY;
            for a in 0..=steps {
                for b in 0..=steps {
                    let t = Vector2::new(a as f64, b as f64) / steps as f64;
                    let n = lo + (hi - lo).component_mul(&t);
                    sampled = sampled.min((lin.w * (n - lin.n)).norm());
                }
            }
            let spacing = (lin.w * (hi - lo)).norm() / steps as f64;
            assert!(least <= sampled * (1.0 + 1e-12) + 1e-15, "{least} > {sampled}");
            assert!(least >= sampled - spacing, "{least} < {sampled} − {spacing}");
        }
    }

    /// `ε` against its own claim, vertex by vertex: the box of the ball `{‖W (n − n*)‖ ≤ ρ}` (half-widths
    /// `ρ ‖row k of W⁻¹‖`, written out here) cut into `p` x `p` sub-boxes; every sub-box that holds a
    /// point of the ball (a 9 x 9 grid of it, strictly inside) has its enclosure of `J` (the enclosures
    /// themselves are [`crate::camera::bounds`]'s, tested there), and `ε` is at least
    /// `‖M (V − J*) W⁻¹‖₂` (nalgebra's singular values) at each of its 16 vertices `V`. So is the
    /// certificate's `ε` ([`LinearisedObservation::epsilon`], one box or the split one) the smaller of the two
    /// oracles at most; and `ε` is no more than the largest vertex over all the sub-boxes (the documented
    /// value, not a looser one). The sampled test above never gets near a vertex (the enclosures are wider than
    /// the Jacobian's variation), so a vertex left out, a sub-box skipped that meets the ball, or a box
    /// narrower than the ball passes it; here each fails. Rounding: sums of four 2x2 products and the
    /// closed-form norm, ~1e-15 relative to the terms, which at the largest vertex are at most its size.
    #[test]
    fn epsilon_is_at_least_every_vertex_of_every_enclosure_of_the_ball() {
        let lenses = test_lenses();
        let mut rng = Rng::new(17);
        let (mut vertices, mut charted, mut split_won) = (0, 0, 0);
        for lens in &lenses {
            let camera = lens.clone();
            for k in 0..12 {
                let xc = match k % 3 {
                    0 => Vector3::new(0.0, rng.uniform_in(-1.0, 1.0), 1.0),
                    1 => Vector3::new(rng.uniform_in(-1.0, 1.0), 0.0, 1.0),
                    _ => Vector3::new(rng.uniform_in(-1.0, 1.0), rng.uniform_in(-1.0, 1.0), 1.0),
                };
                let xc = if lens.model() == CameraModel::OpenCvFisheye {
                    xc * 2.0 - Vector3::z()
                } else {
                    xc
                };
                let l = if k % 2 == 0 {
                    Matrix2::identity()
                } else {
                    Matrix2::new(rng.uniform_in(0.3, 2.0), rng.normal(), 0.0, rng.uniform_in(0.3, 2.0))
                };
                let pixel = camera.project(&xc) + Vector2::new(rng.normal(), rng.normal());
                let Ok(lin) = LinearisedObservation::new(&camera, &l, &pixel, &xc, 1.0, SPLITS, true) else {
                    continue;
                };
                let w_inverse = lin.w.try_inverse().expect("W is invertible");
                let half = Vector2::new(w_inverse.row(0).norm(), w_inverse.row(1).norm());
                let inside = |n: Vector2<f64>, rho: f64| (lin.w * (n - lin.n)).norm() < rho * (1.0 - 1e-9);
                // The largest vertex over the enclosures of the p x p sub-boxes that meet the ball.
                let oracle = |rho: f64, p: usize, all: bool, vertices: &mut usize| -> Option<f64> {
                    let mut largest: f64 = 0.0;
                    for a in 0..p {
                        for b in 0..p {
                            let corner = |i: usize, j: usize| {
                                lin.n
                                    + Vector2::new(
                                        half.x * rho * (2.0 * i as f64 / p as f64 - 1.0),
                                        half.y * rho * (2.0 * j as f64 / p as f64 - 1.0),
                                    )
                            };
                            let (lo, hi) = (corner(a, b), corner(a + 1, b + 1));
                            let meets = (0..81).any(|g| {
                                let t = Vector2::new((g % 9) as f64 / 8.0, (g / 9) as f64 / 8.0);
                                inside(lo + (hi - lo).component_mul(&t), rho)
                            });
                            if !meets && !all {
                                continue;
                            }
                            let enclosure = match (&lin.ray, &lin.distortion) {
                                (Some(r), Distortion::Fisheye(c)) => {
                                    fisheye_ray_enclosure(c, lin.radius, &r.transpose(), &lo, &hi)?
                                }
                                _ => jacobian_enclosure(&lin.distortion, lin.radius, &lo, &hi)?,
                            };
                            for v in 0..16 {
                                let vertex = Matrix2::from_fn(|r, c| {
                                    let entry = enclosure[r][c];
                                    if v >> (2 * r + c) & 1 == 1 {
                                        entry.hi
                                    } else {
                                        entry.lo
                                    }
                                });
                                let value = (lin.m * (vertex - lin.j) * w_inverse).singular_values().max();
                                largest = largest.max(value);
                                *vertices += 1;
                            }
                        }
                    }
                    Some(largest)
                };
                for rho in [0.5, 2.0, 8.0, 20.0] {
                    let mut least: Option<f64> = None;
                    for pieces in [1, 2, 3, SPLITS] {
                        let (Some(eps), Some(largest)) =
                            (lin.epsilon_in(rho, pieces), oracle(rho, pieces, false, &mut vertices))
                        else {
                            continue;
                        };
                        // No larger than the largest vertex of every sub-box, met or not (the code skips
                        // some that miss the ball): the documented ε, not a looser one.
                        if let Some(every) = oracle(rho, pieces, true, &mut 0) {
                            assert!(
                                eps <= every * (1.0 + 1e-11),
                                "{:?}, ρ {rho}, {pieces} x {pieces} pieces: ε {eps} above every vertex's {every}",
                                lens.model()
                            );
                        }
                        assert!(
                            eps >= largest * (1.0 - 1e-12),
                            "{:?}, ρ {rho}, {pieces} x {pieces} pieces: ε {eps} below a vertex's {largest}",
                            lens.model()
                        );
                        if pieces == 1 || pieces == SPLITS {
                            least = Some(least.map_or(largest, |l: f64| l.min(largest)));
                            split_won += usize::from(pieces == SPLITS && least == Some(largest));
                        }
                        charted += usize::from(lin.ray.is_some());
                    }
                    if let (Some(eps), Some(least)) = (lin.epsilon(rho), least) {
                        assert!(
                            eps >= least * (1.0 - 1e-12),
                            "{:?}, ρ {rho}: the certificate's ε {eps} below both oracles' {least}",
                            lens.model()
                        );
                    }
                }
            }
        }
        assert!(vertices > 100_000, "only {vertices} vertices checked");
        assert!(charted > 0, "no ball in the ray chart was checked");
        assert!(split_won > 0, "the split box never gave the smaller ε");
    }
}
