//! Certification of the pose: a proved lower bound on the reprojection cost `f = ½ Σ r²` (px²) over
//! every rotation and translation that keeps the object points in front of the camera.
//!
//! The *sublevel-set test*. Let `f̂` be the cost of the returned local minimum `(R̂, t̂)` and `S` the
//! set of poses, points in front, with `f ≤ f̂`. Every pose of `S` has every residual `‖rᵢ‖ ≤ ε₀ = √(2f̂)`.
//!
//! 1. **Depth bounds.** A pixel error `e` is a normalised-plane error of at least `e / s` (`s` the
//!    least singular value of the 2x2 block of `K`), and the gnomonic projection only stretches
//!    distances, so on `S` every object point is within the angle `α = ε₀ / s` of its observed ray
//!    `bᵢ`. Two points `i, j` seen `γᵢⱼ` apart are then at distances `‖xᵢ‖ ≤ dᵢⱼ / sin(γᵢⱼ ∓ 2α)` from
//!    the camera (law of sines); `Dᵢ` is the least such bound over a few partners `j`. The camera
//!    centre is within `Dᵢ` of every point, which bounds the distance `Mₗ` of every 3-D line from it
//!    and `‖t‖ ≤ T` (conditioned frame, centred on the object).
//! 2. **A quadratic minorant.** A point's squared pixel error is at least `wᵢ ‖(I − bᵢbᵢᵀ) xᵢ‖²` with
//!    `wᵢ = s² / Dᵢ²` (the sine of its angle to the ray, times `s`), a line endpoint's at least
//!    `w (ẽᵀ m)²` with `m = R m_w + t × R d_w` the line's moment in the camera frame and
//!    `w = s² / (‖ẽ‖² Mₗ²)`. Both are quadratic in `t` for a fixed rotation.
//! 3. **Rotation search.** Over a cube of rotation vectors `ω` (`R = exp(ω) R̂`) of half-width `h`,
//!    every rotation is within `θ = √3 h` of the centre's `R_c`, so each residual of the minorant moves
//!    by at most `θ ηᵢ` (`ηᵢ = ‖Xᵢ‖`, or `‖ẽ‖(‖m_w‖ + T)` for a line). With `Q(t)` the minorant at `R_c`
//!    and `E = θ² Σ w η²`, a pose of `S` in the cube has `Q(t) ≤ β² = (√(2f̂) + √E)²` (Minkowski). A cube
//!    where `min_t Q > β²`, or where some point is behind the camera for every `t` of that ellipsoid, holds
//!    no pose of `S` and is pruned; the others are split, down to cubes inside a small ball around `R̂`.
//!    What survives bounds `S` inside the ball `‖(ω, t − t̂)‖ ≤ ρ`.
//! 4. **Local bound.** On that ball the residual vector obeys `‖r(x̂ + Δ)‖ ≥ ‖r̂ + JΔ‖ − ½ K ‖Δ‖²` with `K`
//!    a bound on the second derivatives of the residuals (from bounds on depths, projections and
//!    `exp`), and `‖r̂ + JΔ‖² ≥ 2f̂ − 2‖g‖ d + λ_min(JᵀJ) d²` (`d = ‖Δ‖`). The least value of the square of
//!    the right-hand side over `d ≤ ρ`, halved, is the lower bound: when the curvature `λ_min` beats
//!    `K ε₀`, it is within rounding of `f̂`.
//!
//! So `lower_bound ≤ f` for every pose that keeps the points in front; the answer is certified when
//! `(f̂ − lower_bound) / f̂ ≤ gap`. What is needed: at least two points (lines alone give no depth
//! bound here) seen more than `2α` apart. The test fails honestly (`certified = false`, with the
//! reason) when the residuals are too large for the curvature (`K ε₀ ≥ λ_min`), when the search hits
//! `max_nodes` (another minimum nearly as good, or weak data), or without points.

use super::correspondences::Correspondences;
use super::reprojection::{Pose, ReprojectionCost};
use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::geometry::quaternion::exp_so3;
use crate::optim::Objective;
use nalgebra::{Matrix2, Matrix3, SMatrix, Vector3};

/// Options of the certificate. Every field has a documented default.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CertificateOptions {
    /// Relative gap `(cost − lower_bound) / cost` at or below which the answer is certified. Default
    /// `1e-3` (as triangulation).
    pub gap: f64,
    /// Cap on the rotation cells examined by the search. Default `20_000`.
    pub max_nodes: usize,
}

impl Default for CertificateOptions {
    fn default() -> Self {
        CertificateOptions { gap: 1e-3, max_nodes: 20_000 }
    }
}

impl CertificateOptions {
    /// Checks the ranges stated on each field.
    pub fn validate(&self) -> Result<()> {
        if !(self.gap.is_finite() && self.gap > 0.0 && self.gap < 1.0) {
            return Err(Error::InvalidOption {
                name: "certify_gap".into(),
                reason: format!("must be in (0, 1), got {}", self.gap),
            });
        }
        if self.max_nodes < 1 {
            return Err(Error::InvalidOption {
                name: "certify_max_nodes".into(),
                reason: "must be at least 1".into(),
            });
        }
        Ok(())
    }
}

/// How the answer was certified, or why it was not.
#[derive(Debug, Clone, PartialEq)]
pub enum Certificate {
    /// [`super::PoseOptions::certify`] was `None`.
    NotRequested,
    /// Proved by the sublevel-set test after examining `nodes` rotation cells.
    SublevelSet {
        /// Rotation cells examined.
        nodes: usize,
    },
    /// Not proved; the reason.
    NotProved(String),
}

impl Certificate {
    /// `"not_requested"`, `"sublevel_set"` or `"not_proved"`.
    pub fn as_str(&self) -> &'static str {
        match self {
            Certificate::NotRequested => "not_requested",
            Certificate::SublevelSet { .. } => "sublevel_set",
            Certificate::NotProved(_) => "not_proved",
        }
    }

    /// A sentence for reports.
    pub fn message(&self) -> String {
        match self {
            Certificate::NotRequested => "not requested (certify=False)".into(),
            Certificate::SublevelSet { nodes } => format!("proved by the sublevel-set test ({nodes} rotation cells)"),
            Certificate::NotProved(why) => why.clone(),
        }
    }
}

/// The certificate stage's outcome.
#[derive(Debug, Clone, PartialEq)]
pub struct Certification {
    pub certified: bool,
    pub lower_bound: f64,
    pub gap: f64,
    pub certificate: Certificate,
}

impl Certification {
    /// No certificate, for `reason`.
    pub fn none(certificate: Certificate) -> Self {
        Certification {
            certified: false,
            lower_bound: f64::NAN,
            gap: f64::NAN,
            certificate,
        }
    }
}


/// Partners per point for its depth bound (the widest-apart in the image of a small spread set).
const DEPTH_PARTNERS: usize = 8;
/// Rotation cells are split until they lie within this fraction of the local ball's radius.
const LOCAL_BALL: f64 = 0.2;
/// Intervals of the one-dimensional minimisation of the local bound.
const LOCAL_INTERVALS: usize = 256;

/// The data of the test, prepared once (conditioned frame, centred on the object).
struct Problem<'c> {
    corr: &'c Correspondences,
    /// Norm of the 2x2 block of `K`.
    k_norm: f64,
    /// `K⁻ᵀ` (pixel lines from camera-frame moments) and its norm.
    k_inv_t: Matrix3<f64>,
    k_inv_t_norm: f64,
    /// Unit bearings of the points.
    bearings: Vec<Vector3<f64>>,
    /// Per line endpoint: normalised homogeneous endpoint `ẽ`, weight, `η` (see [`Problem::lines`]).
    line_terms: Vec<LineTerm>,
    /// `Σ w η²` over points and line endpoints (the growth of the cell perturbation per θ²).
    eta2: f64,
    /// The 12x12 Gram matrix of the point minorant in `(vec R row-major, t)`.
    gram: SMatrix<f64, 12, 12>,
}

struct LineTerm {
    e: Vector3<f64>,
    weight: f64,
    moment: Vector3<f64>,
    direction: Vector3<f64>,
}

fn norm2x2(m: &Matrix2<f64>) -> (f64, f64) {
    let s = m.singular_values();
    (s.min(), s.max())
}

/// `α` for the angle bounds; the depth bound of every point (`None` when some point has no partner
/// seen far enough apart).
fn depth_bounds(corr: &Correspondences, bearings: &[Vector3<f64>], alpha: f64) -> Option<Vec<f64>> {
    let n = bearings.len();
    // Partners: an even spread of the points.
    let step = (n / DEPTH_PARTNERS).max(1);
    let partners: Vec<usize> = (0..n).step_by(step).take(DEPTH_PARTNERS).collect();
    let pair = |i: usize, j: usize| -> f64 {
        let gamma = bearings[i].angle(&bearings[j]);
        let (lo, hi) = (gamma - 2.0 * alpha, gamma + 2.0 * alpha);
        if i == j || lo <= 0.0 || hi >= std::f64::consts::PI {
            return f64::INFINITY;
        }
        (corr.points3d[i] - corr.points3d[j]).norm() / lo.sin().min(hi.sin())
    };
    (0..n)
        .map(|i| {
            let mut best = partners.iter().map(|&j| pair(i, j)).fold(f64::INFINITY, f64::min);
            // Every point as a partner when the spread set did not give a bound.
            if !best.is_finite() {
                best = (0..n).map(|j| pair(i, j)).fold(f64::INFINITY, f64::min);
            }
            best.is_finite().then_some(best)
        })
        .collect()
}

/// `A` (3x9) with `R X = A vec(R)` (row-major `vec`).
fn lift(x: &Vector3<f64>) -> SMatrix<f64, 3, 9> {
    let mut a = SMatrix::<f64, 3, 9>::zeros();
    for r in 0..3 {
        for c in 0..3 {
            a[(r, 3 * r + c)] = x[c];
        }
    }
    a
}

fn vec_row_major(r: &Matrix3<f64>) -> SMatrix<f64, 9, 1> {
    SMatrix::<f64, 9, 1>::from_fn(|i, _| r[(i / 3, i % 3)])
}

impl<'c> Problem<'c> {
    fn new(camera: &Camera, corr: &'c Correspondences, f_hat: f64) -> std::result::Result<Self, String> {
        if corr.n_points() < 2 {
            return Err("not attempted: the depth bounds need at least two points".into());
        }
        let k = camera.matrix();
        let (s_min, k_norm) = norm2x2(&Matrix2::new(camera.fx, camera.skew, 0.0, camera.fy));
        let k_inv = k.try_inverse().ok_or("singular camera")?;
        let k_inv_t = k_inv.transpose();
        let k_inv_t_norm = k_inv_t.norm();
        let eps0 = (2.0 * f_hat).sqrt();
        let alpha = eps0 / s_min;
        if !(alpha < 0.25) {
            return Err(format!("not proved: residuals too large ({eps0:.3e} px) for the angle bounds"));
        }
        let bearings: Vec<Vector3<f64>> = corr
            .points2d
            .iter()
            .map(|u| (k_inv * Vector3::new(u.x, u.y, 1.0)).normalize())
            .collect();
        let depths = depth_bounds(corr, &bearings, alpha)
            .ok_or("not proved: no two points are seen far enough apart to bound the depths")?;
        let point_weights: Vec<f64> = depths.iter().map(|d| s_min * s_min / (d * d)).collect();
        // Camera centre within Dᵢ of every point: ‖t‖ = ‖C‖ ≤ ‖Xᵢ‖ + Dᵢ (conditioned frame).
        let t_bound = corr
            .points3d
            .iter()
            .zip(&depths)
            .map(|(x, d)| x.norm() + d)
            .fold(f64::INFINITY, f64::min);
        let mut gram = SMatrix::<f64, 12, 12>::zeros();
        let mut eta2 = 0.0;
        for ((x, b), w) in corr.points3d.iter().zip(&bearings).zip(&point_weights) {
            let p = Matrix3::identity() - b * b.transpose();
            let mut m = SMatrix::<f64, 3, 12>::zeros();
            m.fixed_view_mut::<3, 9>(0, 0).copy_from(&lift(x));
            m.fixed_view_mut::<3, 3>(0, 9).copy_from(&Matrix3::identity());
            gram += (m.transpose() * p * m) * *w;
            eta2 += w * x.norm_squared();
        }
        let mut line_terms = Vec::with_capacity(2 * corr.n_lines());
        for (s2, s3) in corr.lines2d.iter().zip(&corr.lines3d) {
            let direction = (s3[1] - s3[0]).normalize();
            let moment = s3[0].cross(&direction);
            // Distance from the camera centre to the line: at most dist(Xᵢ, line) + Dᵢ.
            let m_bound = corr
                .points3d
                .iter()
                .zip(&depths)
                .map(|(x, d)| (x - s3[0]).cross(&direction).norm() + d)
                .fold(f64::INFINITY, f64::min);
            for e in s2 {
                let e = k_inv * Vector3::new(e.x, e.y, 1.0);
                let weight = s_min * s_min / (e.norm_squared() * m_bound * m_bound);
                eta2 += weight * (e.norm() * (moment.norm() + t_bound)).powi(2);
                line_terms.push(LineTerm {
                    e,
                    weight,
                    moment,
                    direction,
                });
            }
        }
        Ok(Problem {
            corr,
            k_norm,
            k_inv_t,
            k_inv_t_norm,
            bearings,
            line_terms,
            eta2,
            gram,
        })
    }

    /// The minorant at rotation `r` as a quadratic in `t`: `tᵀ C t + 2 gᵀ t + c₀`.
    fn quadratic(&self, r: &Matrix3<f64>) -> (Matrix3<f64>, Vector3<f64>, f64) {
        let v = vec_row_major(r);
        let a = self.gram.fixed_view::<9, 9>(0, 0);
        let b = self.gram.fixed_view::<9, 3>(0, 9);
        let mut c = self.gram.fixed_view::<3, 3>(9, 9).into_owned();
        let mut g: Vector3<f64> = b.transpose() * v;
        let mut c0 = (v.transpose() * a * v)[0];
        for term in &self.line_terms {
            // ẽᵀ(R m_w + t × R d_w) = ẽᵀ R m_w + tᵀ (R d_w × ẽ)
            let lin = (r * term.direction).cross(&term.e);
            let off = term.e.dot(&(r * term.moment));
            c += lin * lin.transpose() * term.weight;
            g += lin * (off * term.weight);
            c0 += term.weight * off * off;
        }
        (c, g, c0)
    }
}

/// One cube of rotation vectors `ω` (`R = exp(ω) R̂`): centre and half-width.
#[derive(Clone, Copy)]
struct Cell {
    centre: Vector3<f64>,
    half: f64,
}

/// What the rotation search proved: every pose of `S` has `‖ω‖ ≤ rho_rotation` and
/// `‖t − t̂‖ ≤ rho_translation`.
struct Localised {
    rho_rotation: f64,
    rho_translation: f64,
    nodes: usize,
}

/// Steps 1-3 of the module documentation.
fn localise(problem: &Problem, pose: &Pose, f_hat: f64, ball: f64, max_nodes: usize) -> std::result::Result<Localised, String> {
    let root = (2.0 * f_hat).sqrt();
    let pi = std::f64::consts::PI;
    let mut stack: Vec<Cell> = vec![];
    let h0 = pi / 2.0;
    for i in 0..8 {
        let s = |k: usize| if i >> k & 1 == 1 { h0 } else { -h0 };
        stack.push(Cell {
            centre: Vector3::new(s(0), s(1), s(2)),
            half: h0,
        });
    }
    let sqrt3 = 3f64.sqrt();
    let mut out = Localised {
        rho_rotation: 0.0,
        rho_translation: 0.0,
        nodes: 0,
    };
    while let Some(cell) = stack.pop() {
        out.nodes += 1;
        if out.nodes > max_nodes {
            return Err(format!("not proved: the rotation search reached max_nodes = {max_nodes}"));
        }
        // The cube's nearest point to the origin: cubes wholly outside the ball ‖ω‖ ≤ π repeat rotations.
        let nearest = cell.centre.map(|c| (c.abs() - cell.half).max(0.0)).norm();
        if nearest > pi {
            continue;
        }
        let theta = sqrt3 * cell.half;
        let r_c = exp_so3(&cell.centre) * pose.0;
        let (c, g, c0) = problem.quadratic(&r_c);
        let Some(c_inv) = c.try_inverse() else {
            return Err("not proved: the minorant does not fix the translation".into());
        };
        let t_star = -(c_inv * g);
        let q_min = (c0 - g.dot(&(c_inv * g))).max(0.0);
        let beta = root + theta * problem.eta2.sqrt();
        let slack = beta * beta - q_min;
        if slack < 0.0 {
            continue;
        }
        // Cheirality: a point behind the camera for every t of the ellipsoid.
        let behind = problem.corr.points3d.iter().zip(&problem.bearings).any(|(x, b)| {
            let reach = b.dot(&(r_c * x + t_star)) + (slack * b.dot(&(c_inv * b))).max(0.0).sqrt();
            reach <= -theta * x.norm()
        });
        if behind {
            continue;
        }
        let outer = cell.centre.norm() + theta;
        if outer <= ball {
            // Translation extent over the ellipsoid (t − t*)ᵀ C (t − t*) ≤ slack.
            let lambda_min = c.symmetric_eigenvalues().min();
            if !(lambda_min > 0.0) {
                return Err("not proved: the minorant does not fix the translation".into());
            }
            let extent = (t_star - pose.1).norm() + (slack / lambda_min).sqrt();
            out.rho_rotation = out.rho_rotation.max(outer);
            out.rho_translation = out.rho_translation.max(extent);
            continue;
        }
        let h = 0.5 * cell.half;
        for i in 0..8 {
            let s = |k: usize| if i >> k & 1 == 1 { h } else { -h };
            stack.push(Cell {
                centre: cell.centre + Vector3::new(s(0), s(1), s(2)),
                half: h,
            });
        }
    }
    Ok(out)
}

/// A bound `K` on the second derivatives of the residual vector over the ball `‖Δ‖ ≤ rho` around
/// `pose` (the chart `(ω, τ) ↦ (exp(ω) R̂, t̂ + τ)`), or `None` when a depth or a projected line may
/// vanish there.
fn curvature_bound(problem: &Problem, pose: &Pose, rho: f64) -> Option<f64> {
    let grow = rho.exp();
    let mut total = 0.0;
    for x in &problem.corr.points3d {
        let y = pose.0 * x;
        let p = y + pose.1;
        let g1 = (grow * grow * y.norm_squared() + 1.0).sqrt();
        let z_lo = p.z - g1 * rho;
        if !(z_lo > 0.0) {
            return None;
        }
        let pi_max = ((p.x * p.x + p.y * p.y).sqrt() + g1 * rho) / z_lo;
        let factor = (1.0 + pi_max * pi_max).sqrt() / z_lo;
        let kappa = problem.k_norm * factor * (grow * y.norm() + 2.0 * g1 * g1 / z_lo);
        total += kappa * kappa;
    }
    for (s2, s3) in problem.corr.lines2d.iter().zip(&problem.corr.lines3d) {
        let (ya, yb) = (pose.0 * s3[0], pose.0 * s3[1]);
        let (a, b) = (ya + pose.1, yb + pose.1);
        let (g1a, g1b) = (
            (grow * grow * ya.norm_squared() + 1.0).sqrt(),
            (grow * grow * yb.norm_squared() + 1.0).sqrt(),
        );
        let (a_max, b_max) = (a.norm() + g1a * rho, b.norm() + g1b * rho);
        let m1 = g1a * b_max + a_max * g1b;
        let m2 = grow * ya.norm() * b_max + 2.0 * g1a * g1b + a_max * grow * yb.norm();
        let lp = problem.k_inv_t * a.cross(&b);
        let s_hat = (lp.x * lp.x + lp.y * lp.y).sqrt();
        let kn = problem.k_inv_t_norm;
        let s_lo = s_hat - kn * m1 * rho;
        if !(s_lo > 0.0) {
            return None;
        }
        for e in s2 {
            let eh = Vector3::new(e.x, e.y, 1.0);
            let en = eh.norm();
            let r_hat = (lp.dot(&eh) / s_hat).abs();
            let c = kn * m1 * rho / s_lo;
            if !(c < 1.0) {
                return None;
            }
            let r_max = (r_hat + en * c) / (1.0 - c);
            let kappa = (en + r_max) / s_lo * kn * m2 + (2.0 * en + 4.0 * r_max) / (s_lo * s_lo) * kn * kn * m1 * m1;
            total += kappa * kappa;
        }
    }
    Some(total.sqrt())
}

/// Step 4: the least of `½ (√q(d) − ½ K d²)₊²` over `d ≤ rho`, `q(d) = 2f̂ − 2‖g‖d + λ d²`, by
/// [`LOCAL_INTERVALS`] intervals on each of which `q` takes its exact minimum and `d²` its maximum.
fn local_lower_bound(f_hat: f64, gradient: f64, lambda: f64, k: f64, rho: f64) -> f64 {
    let q = |d: f64| 2.0 * f_hat - 2.0 * gradient * d + lambda * d * d;
    let vertex = if lambda > 0.0 { gradient / lambda } else { f64::INFINITY };
    let mut least = f64::INFINITY;
    for i in 0..LOCAL_INTERVALS {
        let (a, b) = (
            rho * i as f64 / LOCAL_INTERVALS as f64,
            rho * (i + 1) as f64 / LOCAL_INTERVALS as f64,
        );
        let q_min = if (a..=b).contains(&vertex) { q(vertex) } else { q(a).min(q(b)) };
        let h = q_min.max(0.0).sqrt() - 0.5 * k * b * b;
        least = least.min(0.5 * h.max(0.0).powi(2));
    }
    least
}

/// Certifies `pose` (conditioned frame of `corr`), a local minimum of cost `cost` = `½ Σ r²` (see the
/// module documentation). Never fails: a certificate that cannot be computed is `certified = false`
/// with the reason.
pub fn certify(camera: &Camera, corr: &Correspondences, pose: &Pose, cost: f64, options: &CertificateOptions) -> Certification {
    if !(cost.is_finite() && cost >= 0.0) {
        return Certification::none(Certificate::NotProved("not attempted: the cost is not finite".into()));
    }
    let problem = match Problem::new(camera, corr, cost) {
        Ok(p) => p,
        Err(why) => return Certification::none(Certificate::NotProved(why)),
    };
    let lin = ReprojectionCost::of(camera, corr).linearize(pose);
    let lambda = lin.gauss_newton.symmetric_eigenvalues().min();
    let gradient = lin.gradient.norm();
    // The ball the rotation search localises into: where the local bound can still hold, estimated
    // from the curvature bound at a small radius (K grows slowly with the radius).
    let Some(k_small) = curvature_bound(&problem, pose, 1e-6) else {
        return Certification::none(Certificate::NotProved("not proved: a depth vanishes at the pose".into()));
    };
    if !(lambda > k_small * (2.0 * cost).sqrt()) {
        return Certification::none(Certificate::NotProved(format!(
            "not proved: the residuals ({:.3e} px) are too large for the curvature of the cost",
            (2.0 * cost).sqrt()
        )));
    }
    let ball = (LOCAL_BALL * (lambda.sqrt() / k_small)).min(0.5);
    let localised = match localise(&problem, pose, cost, ball, options.max_nodes) {
        Ok(l) => l,
        Err(why) => return Certification::none(Certificate::NotProved(why)),
    };
    let rho = localised.rho_rotation.hypot(localised.rho_translation);
    let Some(k) = curvature_bound(&problem, pose, rho) else {
        return Certification::none(Certificate::NotProved("not proved: a depth may vanish within the localised ball".into()));
    };
    let lower_bound = local_lower_bound(lin.cost, gradient, lambda, k, rho).min(lin.cost);
    let gap = if lin.cost > 0.0 { (lin.cost - lower_bound) / lin.cost } else { 0.0 };
    let certified = gap <= options.gap;
    Certification {
        certified,
        lower_bound,
        gap,
        certificate: if certified {
            Certificate::SublevelSet { nodes: localised.nodes }
        } else {
            Certificate::NotProved(format!(
                "not proved: the local bound leaves a gap of {gap:.3e} (ball radius {rho:.3e}, {} rotation cells)",
                localised.nodes
            ))
        },
    }
}
