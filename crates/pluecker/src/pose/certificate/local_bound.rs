//! Step 4 of [`super`]'s module docs, the local bound along whitened rays: the local metric at the
//! pose ([`Whitening`]), the bound `K` on the second derivative of the residuals along every whitened
//! ray of a ball ([`RayCurvature`]), and the one-dimensional bound over the ball
//! ([`local_lower_bound`], [`LocalModel`]); through a lens, with the slack of the distortion's
//! variation ([`RaySlack`]).

use super::lens::Surrogate;
use super::minorant::largest_eigenvalue;
use super::problem::{norm2x2, CameraPart, Problem};
use crate::camera::linearisation::spectral_norm;
use crate::geometry::quaternion::skew;
use crate::pose::reprojection::Pose;
use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

/// Intervals of the one-dimensional minimisation of the local bound.
pub(super) const LOCAL_INTERVALS: usize = 256;

/// At most this many segment endpoints, those of the largest rates, are bounded apart in step 4's
/// curvature bound ([`RayCurvature::bound_with_parts`]; splits after 1, 2, 4, ... of them).
pub(super) const APART_ENDPOINTS: usize = 16;

/// The local metric `‖Δ‖_W = √(Δᵀ W Δ)`, `W = JᵀJ` at `R̂, t̂` in the chart `(ω, τ) ↦ (exp(ω) R̂, t̂ + τ)`:
/// a whitened step `δ` is the chart step `Δ = T δ`, `T = V Λ^(-1/2)` from `W = V Λ Vᵀ`, so that the
/// linearised residual moves by one pixel per unit of `‖δ‖` in every direction.
pub(super) struct Whitening {
    pub(super) w: SMatrix<f64, 6, 6>,
    pub(super) t: SMatrix<f64, 6, 6>,
    /// Largest rotation and translation per unit whitened step: `‖T_ω‖`, `‖T_τ‖` (row blocks).
    pub(super) alpha_omega: f64,
    pub(super) alpha_tau: f64,
}

impl Whitening {
    pub(super) fn new(w: &SMatrix<f64, 6, 6>) -> Option<Self> {
        let eigen = w.symmetric_eigen();
        if !eigen.eigenvalues.iter().all(|l| l.is_finite() && *l > 0.0) {
            return None;
        }
        let scale = SMatrix::<f64, 6, 6>::from_diagonal(&eigen.eigenvalues.map(|l| 1.0 / l.sqrt()));
        let t = eigen.eigenvectors * scale;
        let (alpha_omega, alpha_tau) = block_norms(&t);
        Some(Whitening {
            w: *w,
            alpha_omega,
            alpha_tau,
            t,
        })
    }

    /// The largest whitened length `√(sᵀ W_ωω s)` of a rotation step `s` in the box of half-widths
    /// `half` around 0: a convex function peaks at a vertex, and `±s` give the same length.
    pub(super) fn box_spread(&self, half: &Vector3<f64>) -> f64 {
        let w = self.w.fixed_view::<3, 3>(0, 0);
        [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)]
            .iter()
            .map(|&(b, c)| {
                let s = half.component_mul(&Vector3::new(1.0, b, c));
                (s.transpose() * w * s)[0]
            })
            .fold(0.0f64, f64::max)
            .sqrt()
    }

    /// `‖Δ‖_W` of the chart step `(ω, τ)`.
    pub(super) fn length(&self, omega: &Vector3<f64>, tau: &Vector3<f64>) -> f64 {
        let d = SVector::<f64, 6>::new(omega.x, omega.y, omega.z, tau.x, tau.y, tau.z);
        (d.transpose() * self.w * d)[0].max(0.0).sqrt()
    }

    /// The largest `‖(0, τ)‖_W` over the ellipsoid `τᵀ C τ ≤ slack` is `√(slack λ)`, with this
    /// `λ = λ_max(L⁻¹ W_ττ L⁻ᵀ)` and `C = L Lᵀ`.
    pub(super) fn ellipsoid_factor(&self, c: &Matrix3<f64>) -> Option<f64> {
        let l_inv = c.cholesky()?.l().try_inverse()?;
        let w_tt = self.w.fixed_view::<3, 3>(3, 3).into_owned();
        Some(largest_eigenvalue(&(l_inv * w_tt * l_inv.transpose())))
    }
}

/// `(‖T_ω‖, ‖T_τ‖)`: the spectral norms of the rotation and translation row blocks of `t`.
fn block_norms(t: &SMatrix<f64, 6, 6>) -> (f64, f64) {
    let block_norm = |rows: usize| t.fixed_view::<3, 6>(rows, 0).into_owned().singular_values().max();
    (block_norm(0), block_norm(3))
}

/// `M` with `aᵀ M a = (a × (a × y)) · c = (a·y)(a·c) − (a·a)(y·c)`.
pub(super) fn double_cross_form(y: &Vector3<f64>, c: &Vector3<f64>) -> Matrix3<f64> {
    0.5 * (y * c.transpose() + c * y.transpose()) - Matrix3::identity() * y.dot(c)
}

/// `P` with `P (a_ω, a_τ) = a_ω × y + a_τ`, the velocity of a point `R y + t` along a chart step.
pub(super) fn tangent_map(y: &Vector3<f64>) -> SMatrix<f64, 3, 6> {
    let mut p = SMatrix::<f64, 3, 6>::zeros();
    p.fixed_view_mut::<3, 3>(0, 0).copy_from(&(-skew(y)));
    p.fixed_view_mut::<3, 3>(0, 3).copy_from(&Matrix3::identity());
    p
}

/// A bound on `|n'''|` along whitened rays of length `s` from an endpoint's sight: with `X` one end
/// of the segment (`‖R̂ X‖ = y`), `u = ē × X` (`‖u(0)‖ = cross`, `max ‖u'(0)‖ = speed` per unit step)
/// and `D = B − A` (`‖D‖ = length`, `D⁽ᵏ⁾ = a_ω × D⁽ᵏ⁻¹⁾`), `n = ēᵀ (A × B) = Dᵀ u` and by Leibniz
/// `n''' = D'''ᵀ u + 3 D''ᵀ u' + 3 D'ᵀ u'' + Dᵀ u'''` (one piece each), with `‖u''‖ ≤ ‖ē‖ α_ω² y`, `‖u'''‖ ≤ ‖ē‖ α_ω³ y`.
/// `u` and `u'` see only the motion across the sight, so a step along it (the depth) costs nothing.
pub(super) fn sight_parts(a_w: f64, length: f64, e_norm: f64, y: f64, cross: f64, speed: f64, s: f64) -> SightParts {
    // ‖u'‖ grows by at most ‖ē‖ ‖X''‖ ≤ ‖ē‖ α_ω² y per unit of s.
    let speed = speed + s * e_norm * a_w * a_w * y;
    SightParts {
        speed,
        pieces: [
            a_w.powi(3) * length * (cross + s * speed),
            3.0 * a_w * a_w * length * speed,
            3.0 * a_w.powi(3) * length * e_norm * y,
            a_w.powi(3) * length * e_norm * y,
        ],
    }
}

/// `sup |x'|` on `[0, s]` for `|x''| ≤ d + c |x'|`, `|x'(0)| ≤ x0` (Grönwall).
pub(super) fn gronwall(x0: f64, d: f64, c: f64, s: f64) -> f64 {
    if c > 0.0 {
        (x0 + d / c) * (c * s).exp() - d / c
    } else {
        x0 + d * s
    }
}

/// A point's part of `RayCurvature`: what does not depend on the radius.
pub(super) struct PointRay {
    /// `‖y‖ = ‖R̂ X‖` and the camera-frame point `p = y + t̂`.
    pub(super) y_norm: f64,
    pub(super) p: Vector3<f64>,
    /// `‖e_zᵀ P T‖`: the largest depth rate at `s = 0` per unit whitened step.
    pub(super) depth_rate: f64,
    /// `gᵀ g` of the residual's whitened gradient `g = W K₂ Dπ P T` (2x6), and `‖W K₂‖`.
    pub(super) gram: SMatrix<f64, 6, 6>,
    pub(super) map_norm: f64,
    /// `‖g‖₂` (up to rounding, above): the residual's own rate at `s = 0` per unit whitened step.
    pub(super) rate: f64,
}

/// A line endpoint's part of `RayCurvature`: its residual is `n / w` with `n = ēᵀ m` and
/// `w = ‖G_e m_xy‖` ([`CameraPart::endpoint_maps`]).
pub(super) struct EndpointRay {
    /// `w₀ = ‖G_e m_xy‖`, `‖G_e‖`, `‖G_e N(0)_xy T‖` and `|w'(0)|` per unit whitened step.
    pub(super) w0: f64,
    pub(super) g_norm: f64,
    pub(super) q1_0: f64,
    pub(super) w1_0: f64,
    /// `ē = K⁻¹ ẽ`, its norm, `‖B × ē‖` and `‖ē × A‖`.
    pub(super) e_norm: f64,
    pub(super) cross_b: f64,
    pub(super) cross_a: f64,
    /// `‖[ē]× P_A T‖` and `‖[ē]× P_B T‖`: the largest `‖ē × A'(0)‖`, `‖ē × B'(0)‖` per unit whitened
    /// step. Far smaller than `‖ē‖ ‖A'‖` where the step moves the endpoint along its sight
    /// (the depth, poorly determined in a narrow field of view).
    pub(super) sight_speed: [f64; 2],
    /// Residual and whitened gradient norm at `s = 0`, and `gᵀ g`.
    pub(super) r0: f64,
    pub(super) slope0: f64,
    pub(super) gram: SMatrix<f64, 6, 6>,
    /// `max |vᵀ Tᵀ H T v|` over unit `v`: the exact `|n''(0)|`.
    pub(super) n2_exact: f64,
}

/// A line's part of `RayCurvature`.
pub(super) struct LineRay {
    /// `‖y_A‖`, `‖y_B‖`, `‖A‖`, `‖B‖`, the segment length.
    pub(super) ya: f64,
    pub(super) yb: f64,
    pub(super) a: f64,
    pub(super) b: f64,
    pub(super) length: f64,
    pub(super) endpoints: [EndpointRay; 2],
}

/// Step 4's curvature bound: `K` with `‖r''(s)‖ ≤ K` along every whitened ray `s ↦ x̂ + s T v`
/// (`‖v‖ = 1`, `s ≤ radius`), from data prepared once per pose ([`RayCurvature::new`]) and evaluated
/// per radius ([`RayCurvature::bound`]).
///
/// Along a ray the rotation is the one-parameter group `exp(s a_ω) R̂` (`a = T v`), so a camera-frame
/// point moves as `p' = a_ω × R_s y + a_τ`, `p'' = a_ω × (a_ω × R_s y)`. For a point residual
/// `r = W K₂ π(p)`, `D²π[p', p'] = −2 (p'_z / p_z) Dπ[p']`, hence `r'' = W K₂ Dπ[p''] − 2 (p'_z / p_z) r'`;
/// a line residual `n / w` (`n = ēᵀ m`, `w = ‖G m_xy‖`, `m = A × B`) obeys the same identity,
/// `r'' = (n'' − r w'') / w − 2 (w' / w) r'`. With `c₂` the norm of the first parts and `ρ` the rates
/// `|p'_z / p_z|` or `|w' / w|`, `‖r''‖ ≤ c₂ + 2 ‖diag(ρ) r'‖`, bounded two ways: by
/// `2 max ρ ‖r'‖` (Grönwall on `‖r'‖`, `‖r'(0)‖ ≤ μ`), or by `2 ρ_w + 2 max ρ · s K` with
/// `ρ_w² = λ_max(Σ ρ² gᵀ g)` (`g` the whitened gradients at `s = 0`, which spread `‖r'(0)‖ = 1`
/// over the residuals). In whitened steps every part is small: the large second derivatives lie
/// along the well-determined directions.
pub(super) struct RayCurvature {
    pub(super) alpha_omega: f64,
    pub(super) alpha_tau: f64,
    pub(super) mu: f64,
    pub(super) points: Vec<PointRay>,
    pub(super) lines: Vec<LineRay>,
}

impl RayCurvature {
    /// The bound's data at `pose` for the rays of `whitening`: every camera's observations at the
    /// camera's own pose, along its own rays ([`super::problem::CameraPart::own`]: for a rig's camera
    /// the rig's ray `(s a_ω, s a_τ)` is the camera's `(s R_k a_ω, s R_k a_τ)`, so its rays are
    /// those of the single camera with `diag(R_k, R_k) T`, of the same lengths per unit step).
    pub(super) fn new(problem: &Problem, whitening: &Whitening, pose: &Pose, mu: f64) -> Option<Self> {
        let (mut points, mut lines) = (Vec::new(), Vec::new());
        let (mut alpha_omega, mut alpha_tau) = (whitening.alpha_omega, whitening.alpha_tau);
        for part in &problem.cameras {
            let (pose, t) = part.own(pose, &whitening.t);
            if part.sensor.is_some() {
                // ‖R_k T_ω‖ = ‖T_ω‖ up to rounding: the larger of the two is kept.
                let (omega, tau) = block_norms(&t);
                (alpha_omega, alpha_tau) = (alpha_omega.max(omega), alpha_tau.max(tau));
            }
            let (own_points, own_lines) = Self::camera_parts(part, &t, &pose);
            points.extend(own_points);
            lines.extend(own_lines);
        }
        lines
            .iter()
            .flat_map(|l: &LineRay| &l.endpoints)
            .all(|end| end.w0 > 0.0 && end.w0.is_finite())
            .then_some(RayCurvature {
                alpha_omega,
                alpha_tau,
                mu,
                points,
                lines,
            })
    }

    /// One camera's points and segments at its pose `pose`, along the rays of the whitening `t`.
    fn camera_parts(part: &CameraPart, t: &SMatrix<f64, 6, 6>, pose: &Pose) -> (Vec<PointRay>, Vec<LineRay>) {
        let points = part
            .corr
            .points3d
            .iter()
            .zip(&part.point_maps)
            .map(|(x, map)| {
                let y = pose.rotation * x;
                let p = y + pose.translation;
                let d_pi =
                    SMatrix::<f64, 2, 3>::new(1.0 / p.z, 0.0, -p.x / (p.z * p.z), 0.0, 1.0 / p.z, -p.y / (p.z * p.z));
                let pt = tangent_map(&y) * t;
                let g = map * d_pi * pt;
                PointRay {
                    y_norm: y.norm(),
                    p,
                    depth_rate: pt.row(2).norm(),
                    gram: g.transpose() * g,
                    map_norm: norm2x2(map).1,
                    rate: spectral_norm(&(g * g.transpose())).sqrt() * (1.0 + 1e-12),
                }
            })
            .collect();
        let lines = part
            .corr
            .lines2d
            .iter()
            .zip(&part.corr.lines3d)
            .zip(&part.endpoint_maps)
            .map(|((s2, s3), maps)| {
                // Endpoints A = R_s y_A + t: A' = a_ω × R_s y_A + a_τ = P_A a.
                let (y_a, y_b) = (pose.rotation * s3[0], pose.rotation * s3[1]);
                let (a, b) = (y_a + pose.translation, y_b + pose.translation);
                let m0 = a.cross(&b);
                // m = A × B moves as m' = N a, N = [[B]×[y_A]× − [A]×[y_B]×, [A]× − [B]×].
                let mut n0 = SMatrix::<f64, 3, 6>::zeros();
                n0.fixed_view_mut::<3, 3>(0, 0)
                    .copy_from(&(skew(&b) * skew(&y_a) - skew(&a) * skew(&y_b)));
                n0.fixed_view_mut::<3, 3>(0, 3).copy_from(&(skew(&a) - skew(&b)));
                let nt = n0 * t;
                let (p_a, p_b) = (tangent_map(&y_a), tangent_map(&y_b));
                let endpoints = std::array::from_fn(|k| {
                    let (e, (g_e, g_norm)) = (s2[k], maps[k]);
                    let w0 = (g_e * m0.xy()).norm();
                    let q_t = g_e * nt.fixed_view::<2, 6>(0, 0);
                    // w' = q̂·q' with q̂ = G_e m_xy / w.
                    let q_hat = g_e * m0.xy() / w0;
                    let w1 = q_hat.transpose() * q_t;
                    let e_bar = part.k_inv * Vector3::new(e.x, e.y, 1.0);
                    let r0 = e_bar.dot(&m0) / w0;
                    // r' = (n' − r w') / w at s = 0.
                    let g = (e_bar.transpose() * nt - w1 * r0) / w0;
                    // n''(0) = ē·(A'' × B + A × B'' + 2 A' × B') = aᵀ H a.
                    let mut h = SMatrix::<f64, 6, 6>::zeros();
                    let rotation =
                        double_cross_form(&y_a, &b.cross(&e_bar)) + double_cross_form(&y_b, &e_bar.cross(&a));
                    h.fixed_view_mut::<3, 3>(0, 0).copy_from(&rotation);
                    let cross = p_a.transpose() * skew(&e_bar) * p_b;
                    h -= cross + cross.transpose();
                    EndpointRay {
                        w0,
                        g_norm,
                        q1_0: q_t.singular_values().max(),
                        w1_0: w1.norm(),
                        e_norm: e_bar.norm(),
                        cross_b: b.cross(&e_bar).norm(),
                        cross_a: e_bar.cross(&a).norm(),
                        sight_speed: [&p_a, &p_b].map(|p| (skew(&e_bar) * p * t).singular_values().max()),
                        r0,
                        slope0: g.norm(),
                        gram: g.transpose() * g,
                        n2_exact: (t.transpose() * h * t).symmetric_eigenvalues().abs().max(),
                    }
                });
                LineRay {
                    ya: y_a.norm(),
                    yb: y_b.norm(),
                    a: a.norm(),
                    b: b.norm(),
                    length: (b - a).norm(),
                    endpoints,
                }
            })
            .collect();
        (points, lines)
    }

    /// `K` on the whitened ball of radius `s`, or `None` when a depth or a projected line may vanish
    /// there (or a per-residual slope bound cannot be confirmed).
    pub(super) fn bound(&self, s: f64) -> Option<f64> {
        self.bound_with_parts(s, None)
    }

    /// [`Self::bound`], recording its per-residual parts in `parts` (the test hook
    /// [`super::testing::curvature_parts`] only).
    pub(super) fn bound_with_parts(&self, s: f64, mut parts: Option<&mut CurvatureParts>) -> Option<f64> {
        let (a_w, a_t) = (self.alpha_omega, self.alpha_tau);
        let mut direct2 = 0.0;
        let mut rate: f64 = 0.0;
        let mut weighted = SMatrix::<f64, 6, 6>::zeros();
        // Per segment endpoint: its rate ρ, |r''| ≤ direct + 2ρ σ (σ its own bound on |r'|), and
        // the terms it adds to `direct2` and `weighted`.
        let mut endpoints: Vec<(f64, f64, f64, SMatrix<f64, 6, 6>)> = Vec::new();
        for pt in &self.points {
            // |p'_z| ≤ ‖e_zᵀ P T‖ + s α_ω² ‖y‖ (the drift of a_ω × R_s y).
            let depth_rate = pt.depth_rate + s * a_w * a_w * pt.y_norm;
            let z_lo = pt.p.z - s * depth_rate;
            if !(z_lo > 0.0) {
                return None;
            }
            let pi_max = (pt.p.xy().norm() + s * (a_w * pt.y_norm + a_t)) / z_lo;
            // ‖W K₂ Dπ p''‖ ≤ ‖W K₂‖ √(1 + ‖π‖²) / z · α_ω² ‖y‖.
            let direct = pt.map_norm * (1.0 + pi_max * pi_max).sqrt() / z_lo * a_w * a_w * pt.y_norm;
            direct2 += direct * direct;
            let rho = depth_rate / z_lo;
            if let Some(p) = parts.as_deref_mut() {
                p.points.push(PointParts {
                    z_lo,
                    rate: rho,
                    residual_rate: pt.rate,
                });
            }
            rate = rate.max(rho);
            weighted += pt.gram * (rho * rho);
        }
        for line in &self.lines {
            let (v_a, v_b) = (a_w * line.ya + a_t, a_w * line.yb + a_t);
            // ‖A‖, ‖B‖ anywhere on the ball: they move at most v_a, v_b per unit of s.
            let (a_max, b_max) = (line.a + s * v_a, line.b + s * v_b);
            // ‖(N(s) − N(0)) a‖ ≤ s · drift, drift ≥ sup ‖N'(σ) a‖ over σ ≤ s: the rotation block moves as
            // (a_ω × y_A)' × B + (a_ω × y_A) × B' (and A's twin), with ‖B(σ)‖ ≤ b_max, not ‖B(0)‖.
            let drift = a_w * (v_b * line.ya + b_max * a_w * line.ya + v_a * line.yb + a_max * a_w * line.yb)
                + a_t * a_w * line.length;
            // ‖m''‖: m'' = A'' × B + A × B'' + 2 A' × (a_ω × D), D = B − A = R_s (y_B − y_A).
            let m2 = a_w * a_w * (line.ya * b_max + a_max * line.yb) + 2.0 * v_a.min(v_b) * a_w * line.length;
            // m''' = A''' × B + A × B''' + 3 (A'' × (a_ω × D) + A' × (a_ω × (a_ω × D))).
            let mixed3 = 3.0 * a_w * a_w * line.length * (v_a + a_w * line.ya).min(v_b + a_w * line.yb);
            let mut ends = [EndpointParts::default(); 2];
            for (end, found) in line.endpoints.iter().zip(&mut ends) {
                let q1 = end.q1_0 + s * end.g_norm * drift;
                let w_lo = end.w0 - s * q1;
                if !(w_lo > 0.0) {
                    return None;
                }
                // |w''| ≤ ‖q'‖² / w + ‖q''‖; |w'| ≤ |w'(0)| + s |w''|.
                let w2 = q1 * q1 / w_lo + end.g_norm * m2;
                let rho = (end.w1_0 + s * w2) / w_lo;
                rate = rate.max(rho);
                let n3 = a_w.powi(3)
                    * (line.ya * (end.cross_b + s * v_b * end.e_norm) + line.yb * (end.cross_a + s * v_a * end.e_norm))
                    + end.e_norm * mixed3;
                // The same n''' about either end X: n = ēᵀ (A × B) = Dᵀ u with D = B − A, u = ē × X.
                let ends = [(line.ya, end.cross_a), (line.yb, end.cross_b)];
                let sights = std::array::from_fn(|x| {
                    let (y, cross) = ends[x];
                    sight_parts(a_w, line.length, end.e_norm, y, cross, end.sight_speed[x], s)
                });
                let leibniz = n3;
                let n3 = sights
                    .iter()
                    .map(|p: &SightParts| p.pieces.iter().sum())
                    .fold(leibniz, f64::min);
                let n2 = end.n2_exact + s * n3;
                *found = EndpointParts {
                    w_lo,
                    w2,
                    rate: rho,
                    q1,
                    n2,
                    n2_exact: end.n2_exact,
                    n3,
                    leibniz,
                    sights,
                };
                // |r(s)| ≤ |r(0)| + s σ with σ a bound on |r'| along the ray, confirmed by Grönwall
                // on |r''| ≤ d + 2ρ |r'|, d = (|n''| + |r| |w''|) / w.
                let mut sigma = 1.2 * end.slope0 + 1e-12;
                let mut confirmed = None;
                for _ in 0..6 {
                    let direct = (n2 + (end.r0.abs() + s * sigma) * w2) / w_lo;
                    let reached = gronwall(end.slope0, direct, 2.0 * rho, s);
                    if reached <= sigma {
                        confirmed = Some((direct, reached));
                        break;
                    }
                    sigma = 1.5 * reached;
                }
                let (direct, speed) = confirmed?;
                direct2 += direct * direct;
                weighted += end.gram * (rho * rho);
                endpoints.push((rho, direct, direct + 2.0 * rho * speed, end.gram * (rho * rho)));
            }
            if let Some(p) = parts.as_deref_mut() {
                p.lines.push(LineParts {
                    speed: [v_a, v_b],
                    drift,
                    m2,
                    mixed3,
                    endpoints: ends,
                });
            }
        }
        let by_rates = |rate: f64, direct2: f64, weighted: &SMatrix<f64, 6, 6>, apart: f64| {
            let (c1, c2) = (2.0 * rate, direct2.max(0.0).sqrt());
            let by_max_rate = c2 + apart + c1 * gronwall(self.mu, c2 + apart, c1, s);
            let rho_w = weighted.symmetric_eigenvalues().max().max(0.0).sqrt();
            let by_weights = if c1 * s < 1.0 {
                (c2 + apart + 2.0 * rho_w) / (1.0 - c1 * s) + apart
            } else {
                f64::INFINITY
            };
            by_max_rate.min(by_weights)
        };
        let mut k = by_rates(rate, direct2, &weighted, 0.0);
        // A few endpoints of fast-turning lines (short in the image, or seen nearly end-on) set the
        // largest rate. Bounded apart, each by its own |r''| ≤ direct + 2ρσ, they leave the others
        // a smaller rate: ‖r''‖ ≤ ‖r''_rest‖ + ‖r''_apart‖ (Minkowski), the rest bounded as above
        // with ‖r''_apart‖ in its constant part. The least over a few splits.
        if !endpoints.is_empty() {
            endpoints.sort_by(|a, b| b.0.total_cmp(&a.0));
            let point_rate = self.points_rate(s, a_w);
            let mut apart2 = 0.0;
            let (mut rest2, mut rest_weighted) = (direct2, weighted);
            for (count, &(_, direct, bound, gram)) in endpoints.iter().enumerate().take(APART_ENDPOINTS) {
                apart2 += bound * bound;
                rest2 -= direct * direct;
                rest_weighted -= gram;
                let rest_rate = endpoints.get(count + 1).map_or(0.0, |e| e.0).max(point_rate);
                if (count + 1).is_power_of_two() {
                    k = k.min(by_rates(rest_rate, rest2, &rest_weighted, apart2.sqrt()));
                }
            }
        }
        Some(k)
    }

    /// Per point, its residual's rate `‖g‖₂` at the pose: along a whitened ray of length `s` the
    /// residual moves by at most `‖g‖₂ s + ½ K s²` (`K` of [`Self::bound`]).
    pub(super) fn point_rates(&self) -> Vec<f64> {
        self.points.iter().map(|pt| pt.rate).collect()
    }

    /// The largest rate `|p_z' / p_z|` of the points over the ball of radius `s` (0 without points).
    pub(super) fn points_rate(&self, s: f64, a_w: f64) -> f64 {
        self.points
            .iter()
            .map(|pt| {
                let depth_rate = pt.depth_rate + s * a_w * a_w * pt.y_norm;
                depth_rate / (pt.p.z - s * depth_rate)
            })
            .fold(0.0, f64::max)
    }
}

/// Step 4: the least of `½ (√q(d) − ½ K d²)₊²` over `d ≤ rho`, `q(d) = 2f̂ − 2‖g‖d + λ d²`, by
/// [`LOCAL_INTERVALS`] intervals on each of which `q` takes its exact minimum and `d²` its maximum.
pub(super) fn local_lower_bound(
    f_hat: f64,
    gradient: f64,
    lambda: f64,
    k: f64,
    rho: f64,
    slacks: &[(f64, RaySlack)],
) -> f64 {
    let q = |d: f64| 2.0 * f_hat - 2.0 * gradient * d + lambda * d * d;
    let vertex = if lambda > 0.0 { gradient / lambda } else { f64::INFINITY };
    let mut least = f64::INFINITY;
    let mut slack = slacks.iter().peekable();
    for i in 0..LOCAL_INTERVALS {
        let (a, b) = (
            rho * i as f64 / LOCAL_INTERVALS as f64,
            rho * (i + 1) as f64 / LOCAL_INTERVALS as f64,
        );
        let q_min = if (a..=b).contains(&vertex) {
            q(vertex)
        } else {
            q(a).min(q(b))
        };
        // The slack of the least ball that holds this interval's steps.
        while slack.next_if(|(radius, _)| *radius < b).is_some() {}
        let Some((_, slack)) = slack.peek() else {
            return 0.0;
        };
        let h = slack.kappa * (q_min.max(0.0).sqrt() - 0.5 * k * b * b)
            - slack.eps * (slack.rate * b + 0.5 * k * b * b + b * slack.phi + slack.offset)
            - slack.rounding;
        least = least.min(0.5 * h.max(0.0).powi(2));
    }
    least
}

/// Step 4 through a lens (`lens`, step 2): along a whitened ray of length `s` the cost through the
/// lens has `√(2f) ≥ κ √(2q) − ε (μ s + ½ K s² + s Φ + offset) − rounding` (`q` the surrogate's cost);
/// [`RaySlack::NONE`] for a pinhole camera.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct RaySlack {
    pub(super) kappa: f64,
    /// `μ ≥ ‖J T v‖`, the rate of the residuals along a unit whitened ray (1 up to rounding).
    pub(super) rate: f64,
    pub(super) eps: f64,
    pub(super) phi: f64,
    pub(super) offset: f64,
    pub(super) rounding: f64,
}

impl RaySlack {
    /// The pinhole certificate: no slack.
    pub(super) const NONE: RaySlack = RaySlack {
        kappa: 1.0,
        rate: 1.0,
        eps: 0.0,
        phi: 0.0,
        offset: 0.0,
        rounding: 0.0,
    };
}

/// The local model at the pose, in whitened steps: cost, gradient norm `‖Tᵀ g‖`, the least
/// eigenvalue of `Tᵀ JᵀJ T` (1 up to rounding) and the curvature bound; through a lens, the
/// surrogate whose cost they describe (`lens`).
pub(super) struct LocalModel<'s> {
    pub(super) cost: f64,
    pub(super) gradient: f64,
    pub(super) lambda_min: f64,
    pub(super) curvature: RayCurvature,
    pub(super) lens: Option<&'s Surrogate>,
}

impl<'s> LocalModel<'s> {
    /// The local model at `pose` (frame of `problem`) and the whitening it is expressed in.
    pub(super) fn at(
        problem: &Problem,
        pose: &Pose,
        lens: Option<&'s Surrogate>,
    ) -> std::result::Result<(Whitening, Self), String> {
        let lin = problem.linearize(pose);
        let whitening = Whitening::new(&lin.gauss_newton).ok_or("not proved: JᵀJ is singular at the pose")?;
        let whitened = whitening.t.transpose() * lin.gauss_newton * whitening.t;
        let eigen = whitened.symmetric_eigenvalues();
        let curvature = RayCurvature::new(problem, &whitening, pose, eigen.max().max(0.0).sqrt())
            .ok_or("not proved: a projected line vanishes at the pose")?;
        let model = LocalModel {
            cost: lin.cost,
            gradient: (whitening.t.transpose() * lin.gradient).norm(),
            lambda_min: eigen.min(),
            curvature,
            lens,
        };
        Ok((whitening, model))
    }

    /// The lower bound of step 4 over the whitened ball of `radius` (unclamped: at most the cost when
    /// sound, since the ball holds the pose), or `None` where a depth or a projected line may vanish.
    /// Through a lens, the bound with the distortion's variation over the whole ball comes first, and
    /// the nested balls only where it falls short of `wanted`.
    pub(super) fn raw_bound(&self, radius: f64, wanted: Option<f64>) -> Option<f64> {
        let (k, slacks) = match self.lens {
            None => (self.curvature.bound(radius)?, vec![(radius, RaySlack::NONE)]),
            Some(lens) => {
                let mut parts = CurvatureParts::default();
                let k = self.curvature.bound_with_parts(radius, Some(&mut parts))?;
                // The turn rate ‖q′‖ / w of each endpoint's whitened line normal over the ball.
                let turns: Vec<f64> = parts
                    .lines
                    .iter()
                    .flat_map(|line| line.endpoints.iter().map(|end| end.q1 / end.w_lo))
                    .collect();
                debug_assert_eq!(turns.len(), lens.n_endpoints());
                let mu = self.curvature.mu;
                let rates = self.curvature.point_rates();
                let whole = (radius, lens.ball(radius, k, mu, &rates, &turns)?);
                let coarse = local_lower_bound(self.cost, self.gradient, self.lambda_min, k, radius, &[whole]);
                if wanted.is_some_and(|w| coarse >= w) {
                    return Some(coarse);
                }
                // The distortion's variation over nested balls: the steps near the answer, where
                // the bound is least, pay only that of a small ball.
                let mut slacks = vec![whole];
                for j in 1..=NESTED_BALLS {
                    let r = radius * 0.5f64.powf(j as f64 / 2.0);
                    match lens.ball(r, k, mu, &rates, &turns) {
                        Some(slack) => slacks.push((r, slack)),
                        None => break,
                    }
                }
                slacks.reverse();
                (k, slacks)
            }
        };
        Some(local_lower_bound(
            self.cost,
            self.gradient,
            self.lambda_min,
            k,
            radius,
            &slacks,
        ))
    }
}

/// Through a lens, step 4 takes the distortion's variation over balls of the radius and of this many
/// smaller ones, each `1/√2` of the last (halving instead lost 8 of 28 certificates on the
/// bench's strong lens at f = 250 px with 10 correspondences).
pub(super) const NESTED_BALLS: usize = 24;

/// A point's part of `K` on the ball: along every whitened ray `s ↦ (exp(s a_ω) R̂, t̂ + s a_τ)`
/// (`a = T v`, `‖v‖ = 1`, `s ≤ radius`) its camera-frame depth `p_z ≥ z_lo` and `|p_z' / p_z| ≤ rate`.
#[doc(hidden)]
#[derive(Debug, Clone, Copy)]
pub struct PointParts {
    pub z_lo: f64,
    pub rate: f64,
    /// `‖g‖₂` at the pose: the rate of the point's whitened residual per unit whitened step.
    pub residual_rate: f64,
}

/// One observed endpoint's part of `K` on the ball, along the same rays: with `m = A × B`
/// (camera-frame endpoints of the object segment) and `w = ‖G_e m_xy‖` (`G_e = Lᵀ G`, `G` the
/// upper-left 2x2 block of `K⁻ᵀ`, `L Lᵀ` the endpoint's covariance, the identity without one),
/// `w ≥ w_lo`, `|w''| ≤ w2`, `|w' / w| ≤ rate`, `‖q'‖ ≤ q1` (`q = G_e m_xy`), and with
/// `ē = K⁻¹ ẽ`, `|(ēᵀ m)''| ≤ n2` and `|(ēᵀ m)'''| ≤ n3`; `n2_exact` is `max |(ēᵀ m)''(0)|` over
/// the unit whitened directions, exactly. Within them, `w2 − ‖G_e‖ m2` bounds `‖q'‖² / w` and
/// `n3 − ‖ē‖ mixed3` bounds `|ēᵀ (A''' × B + A × B''')|`.
#[doc(hidden)]
#[derive(Debug, Clone, Copy, Default)]
pub struct EndpointParts {
    pub w_lo: f64,
    pub w2: f64,
    pub rate: f64,
    pub q1: f64,
    pub n2: f64,
    pub n2_exact: f64,
    pub n3: f64,
    /// The bound on `|n'''|` from `m''' = A''' × B + A × B''' + mixed`.
    pub leibniz: f64,
    /// The bounds on `|n'''|` about the ends `A` and `B` (see [`SightParts`]); `n3` is the least
    /// of theirs and `leibniz`.
    pub sights: [SightParts; 2],
}

/// `|n'''|` about one end `X` of the segment: `n = Dᵀ u` with `D = B − A` and `u = ē × X`, so
/// `n''' = D'''ᵀ u + 3 D''ᵀ u' + 3 D'ᵀ u'' + Dᵀ u'''`. Along the rays, `speed` bounds `‖u'‖`
/// and `pieces` bound the four terms in that order.
#[doc(hidden)]
#[derive(Debug, Clone, Copy, Default)]
pub struct SightParts {
    pub speed: f64,
    pub pieces: [f64; 4],
}

/// A line's part of `K` on the ball, along the same rays, each a claim of its own: `speed`
/// bounds `‖A'‖` and `‖B'‖`, `drift` bounds `‖m'(s) − m'(0)‖ / s`, `m2` bounds `‖m''‖` and
/// `mixed3` bounds `‖3 (A'' × B' + A' × B'')‖` (all over the ball); `endpoints` are the parts of
/// the two observed endpoints.
#[doc(hidden)]
#[derive(Debug, Clone, Copy)]
pub struct LineParts {
    pub speed: [f64; 2],
    pub drift: f64,
    pub m2: f64,
    pub mixed3: f64,
    pub endpoints: [EndpointParts; 2],
}

/// The parts of `K` (see [`PointParts`], [`LineParts`]; a record of the test hook
/// `testing::curvature_parts`, hidden from the docs) and the whitening `T` of the rays.
#[doc(hidden)]
#[derive(Debug, Clone, Default)]
pub struct CurvatureParts {
    pub whitening: SMatrix<f64, 6, 6>,
    pub points: Vec<PointParts>,
    pub lines: Vec<LineParts>,
}
