//! The reprojection error: the statistically optimal cost under Gaussian pixel noise.
//!
//! The dual-quaternion costs are algebraic; [`ReprojectionCost`] is what a maximum-likelihood estimate
//! minimises. Residuals are in pixels:
//! - a point: `π(R X + t) − u`, two residuals, with `π(x_cam) = K x_cam / z`;
//! - a line: the signed distances of the two observed segment endpoints to the projection of the
//!   3-D line (the line through the projections of its two 3-D endpoints), two residuals.
//!
//! With per-observation noise ([`super::ObservationNoise`]) the residuals are whitened: `W (π(R X + t) − u)` for a
//! point, the endpoint distance divided by the endpoint's standard deviation across the line.
//!
//! Through a lens ([`ReprojectionCost::exact`]) the residuals are in the image's own, distorted pixels,
//! through the exact projection `π(x_cam) = K D(x/z, y/z)` of the [`Camera`] (`D` its distortion):
//! - a point: `W (π(R X + t) − u)`, exactly as above with the lens's `π`;
//! - a segment endpoint `e`: its distance to the *curved* image `K D(ℓ)` of the projected line `ℓ` (the
//!   line through the normalised projections of the two 3-D endpoints, as for a pinhole camera), in
//!   standard deviations of `e` (the Mahalanobis distance `min_q √((u(q) − e)ᵀ C⁻¹ (u(q) − e))` over
//!   the points `q` of `ℓ`, the plain pixel distance without covariances). The minimum over `q` is a 1-D
//!   Gauss-Newton search along `ℓ` from the foot of the endpoint's unprojection, the nearest point of
//!   the curve's branch through the observation: [`crate::camera::curved_line`], shared with the
//!   triangulation of lines through lenses. With `D` the identity this
//!   is the pinhole residual up to its sign (only squares enter the cost).
//!
//! The pose is `(R, t)` with `x_cam = R X_world + t`; a tangent step `(ω, τ)` moves it to
//! `(exp(ω) R, t + τ)` (rotation perturbed on the left, in the camera frame).

use super::{Correspondences, CovarianceSource, ObservationNoise};
use crate::camera::curved_line::endpoint_residual;
use crate::camera::Camera;
use crate::camera::Intrinsics;
use crate::error::Result;
use crate::geometry::quaternion::{exp_so3, skew};
use crate::optim::{Linearization, Objective};
use nalgebra::{Matrix2, Matrix2x3, Matrix3, Matrix6, SMatrix, SVector, Vector2, Vector3};

pub(crate) use crate::camera_pose::Pose;

/// Points per batch of the point kernel. The kernel is written lane by lane over fixed-size arrays so
/// that the compiler turns each batch into vector instructions (the speed-up:
/// docs/benchmarks.md, "Figures behind code comments").
const LANES: usize = 4;

/// Reprojection-error objective over `SO(3) × ℝ³`.
#[derive(Debug, Clone)]
pub struct ReprojectionCost<'a> {
    camera: Intrinsics,
    k_inv: Matrix3<f64>,
    /// The point correspondences as five columns `[X…, Y…, Z…, u…, v…]` (structure of arrays).
    columns: Vec<f64>,
    n_points: usize,
    lines2d: &'a [[Vector2<f64>; 2]],
    lines3d: &'a [[Vector3<f64>; 2]],
    /// Per-observation weights ([`super::noise`]); `None` is the isotropic fast path.
    noise: Option<&'a ObservationNoise>,
    /// The lens the pixels were observed through ([`ReprojectionCost::exact`]); `None`: the pinhole
    /// `camera` itself.
    lens: Option<Lens<'a>>,
}

/// A lens of [`ReprojectionCost`], and where each segment endpoint's search along its line starts.
#[derive(Debug, Clone)]
struct Lens<'a> {
    camera: &'a Camera,
    /// The undistorted normalised coordinates of each segment endpoint ([`Camera::unproject`]),
    /// `None` outside the invertible region of the distortion (the search then starts from the
    /// projection of the 3-D endpoint of the same index).
    starts: Vec<[Option<Vector2<f64>>; 2]>,
}

/// One residual pair and its 2x6 Jacobian with respect to `(ω, τ)`.
pub(crate) type Block = (Vector2<f64>, SMatrix<f64, 2, 6>);

/// Residuals and Jacobian rows of `L` points, lane `l` being point `i₀ + l`.
struct PointLanes<const L: usize> {
    /// `u` residuals, pixels.
    ru: [f64; L],
    /// `v` residuals, pixels.
    rv: [f64; L],
    /// `∂u/∂(ω, τ)`, one array per column.
    ju: [[f64; L]; 6],
    /// `∂v/∂(ω, τ)`; column 3 (`τ_x`) is zero and left out of the sums.
    jv: [[f64; L]; 6],
}

/// Sums over points of the cost, gradient and upper triangle of `JᵀJ` (row-major, 21 entries), per lane.
struct Sums<const L: usize> {
    cost: [f64; L],
    gradient: [[f64; L]; 6],
    upper: [[f64; L]; 21],
}

impl<const L: usize> Sums<L> {
    fn new() -> Self {
        Sums {
            cost: [0.0; L],
            gradient: [[0.0; L]; 6],
            upper: [[0.0; L]; 21],
        }
    }

    #[inline(always)]
    fn add(&mut self, p: &PointLanes<L>) {
        for l in 0..L {
            let (ru, rv) = (p.ru[l], p.rv[l]);
            self.cost[l] += 0.5 * (ru * ru + rv * rv);
            let ju: [f64; 6] = std::array::from_fn(|a| p.ju[a][l]);
            let jv: [f64; 6] = std::array::from_fn(|a| p.jv[a][l]);
            for a in 0..6 {
                self.gradient[a][l] += if a == 3 { ju[a] * ru } else { ju[a] * ru + jv[a] * rv };
            }
            let mut k = 0;
            for a in 0..6 {
                for b in a..6 {
                    self.upper[k][l] += if a == 3 || b == 3 {
                        ju[a] * ju[b]
                    } else {
                        ju[a] * ju[b] + jv[a] * jv[b]
                    };
                    k += 1;
                }
            }
        }
    }

    /// The lanes summed: `(cost, gradient, upper triangle)`.
    fn total(&self) -> (f64, [f64; 6], [f64; 21]) {
        let sum = |v: &[f64; L]| v.iter().sum::<f64>();
        (
            sum(&self.cost),
            std::array::from_fn(|a| sum(&self.gradient[a])),
            std::array::from_fn(|k| sum(&self.upper[k])),
        )
    }
}

impl<'a> ReprojectionCost<'a> {
    /// The cost of the given correspondences (pixels and world coordinates; segments as endpoints).
    /// The point data are copied into columns; the segments are borrowed.
    pub fn new(
        camera: Intrinsics,
        points2d: &'a [Vector2<f64>],
        points3d: &'a [Vector3<f64>],
        lines2d: &'a [[Vector2<f64>; 2]],
        lines3d: &'a [[Vector3<f64>; 2]],
    ) -> Self {
        let k_inv = camera.matrix().try_inverse().unwrap_or_else(Matrix3::identity);
        let n = points2d.len().min(points3d.len());
        let mut columns = vec![0.0; 5 * n];
        for (i, (u, x)) in points2d.iter().zip(points3d).enumerate() {
            for (c, v) in [x.x, x.y, x.z, u.x, u.y].into_iter().enumerate() {
                columns[c * n + i] = v;
            }
        }
        ReprojectionCost {
            camera,
            k_inv,
            columns,
            n_points: n,
            lines2d,
            lines3d,
            noise: None,
            lens: None,
        }
    }

    /// The exact cost of the correspondences of `c` seen by `camera`: their pixels are the observed
    /// ones (distorted, through a lens), weighted by their noise when they carry one (see the module
    /// documentation). The pinhole cost [`ReprojectionCost::of`] when the camera does not distort.
    pub fn exact(camera: &'a Camera, c: &'a Correspondences) -> Result<Self> {
        match camera.distortion() {
            Some(lens) => Self::through_lens(lens, c),
            None => Ok(Self::of(&camera.intrinsics(), c)),
        }
    }

    /// [`ReprojectionCost::exact`] for a [`Camera`].
    pub fn through_lens(lens: &'a Camera, c: &'a Correspondences) -> Result<Self> {
        let mut cost = Self::of(&lens.intrinsics(), c);
        if !lens.is_pinhole() {
            let start = |e: &Vector2<f64>| lens.unproject(e, 0).ok();
            cost.lens = Some(Lens {
                camera: lens,
                starts: c.lines2d.iter().map(|s| [start(&s[0]), start(&s[1])]).collect(),
            });
        }
        Ok(cost)
    }

    /// The cost of all the correspondences of `c`, weighted by their noise when they carry one.
    pub fn of(camera: &Intrinsics, c: &'a Correspondences) -> Self {
        let mut cost = ReprojectionCost::new(*camera, &c.points2d, &c.points3d, &c.lines2d, &c.lines3d);
        cost.noise = c.noise.as_ref();
        cost
    }

    /// Number of scalar residuals: two per point and two per line.
    pub fn residual_count(&self) -> usize {
        2 * (self.n_points + self.lines2d.len())
    }

    /// Column `c` (0-2: object X, Y, Z; 3-4: pixel u, v) of the point data.
    fn column(&self, c: usize) -> &[f64] {
        &self.columns[c * self.n_points..(c + 1) * self.n_points]
    }

    /// Points `i₀ .. i₀ + L`: residuals `π(R X + t) − u` and, with `JACOBIAN`, their derivatives. The
    /// rotation part of a Jacobian row `a = ∂u/∂x_cam` is `(R X) × a` (left perturbation `exp(ω) R`).
    #[inline(always)]
    fn point_lanes<const L: usize, const JACOBIAN: bool>(&self, pose: &Pose, i0: usize) -> PointLanes<L> {
        let (r, t, cam) = (&pose.rotation, &pose.translation, &self.camera);
        let col = |c: usize| -> [f64; L] { std::array::from_fn(|l| self.column(c)[i0 + l]) };
        let (x, y, z, u, v) = (col(0), col(1), col(2), col(3), col(4));
        let mut out = PointLanes {
            ru: [0.0; L],
            rv: [0.0; L],
            ju: [[0.0; L]; 6],
            jv: [[0.0; L]; 6],
        };
        for l in 0..L {
            let px = r[(0, 0)] * x[l] + r[(0, 1)] * y[l] + r[(0, 2)] * z[l];
            let py = r[(1, 0)] * x[l] + r[(1, 1)] * y[l] + r[(1, 2)] * z[l];
            let pz = r[(2, 0)] * x[l] + r[(2, 1)] * y[l] + r[(2, 2)] * z[l];
            let iz = 1.0 / (pz + t.z);
            let (xn, yn) = ((px + t.x) * iz, (py + t.y) * iz);
            let fu = cam.fx * xn + cam.skew * yn;
            out.ru[l] = fu + cam.cx - u[l];
            out.rv[l] = cam.fy * yn + cam.cy - v[l];
            if JACOBIAN {
                // ∂u/∂x_cam = (fx, skew, −(fx xn + skew yn)) / z and ∂v/∂x_cam = (0, fy, −fy yn) / z.
                let (a0, a1, a2) = (cam.fx * iz, cam.skew * iz, -fu * iz);
                let (b1, b2) = (cam.fy * iz, -cam.fy * yn * iz);
                out.ju[0][l] = py * a2 - pz * a1;
                out.ju[1][l] = pz * a0 - px * a2;
                out.ju[2][l] = px * a1 - py * a0;
                out.ju[3][l] = a0;
                out.ju[4][l] = a1;
                out.ju[5][l] = a2;
                out.jv[0][l] = py * b2 - pz * b1;
                out.jv[1][l] = -px * b2;
                out.jv[2][l] = px * b1;
                out.jv[4][l] = b1;
                out.jv[5][l] = b2;
            }
        }
        out
    }

    /// The point terms of the cost and, with `JACOBIAN`, of the gradient and `JᵀJ`: full batches of
    /// [`LANES`] points, then the rest one by one.
    fn point_sums<const JACOBIAN: bool>(&self, pose: &Pose) -> (f64, [f64; 6], [f64; 21]) {
        if self.noise.is_some() || self.lens.is_some() {
            return self.weighted_point_sums::<JACOBIAN>(pose);
        }
        let full = self.n_points - self.n_points % LANES;
        let mut batches = Sums::<LANES>::new();
        let mut rest = Sums::<1>::new();
        for i0 in (0..full).step_by(LANES) {
            let p = self.point_lanes::<LANES, JACOBIAN>(pose, i0);
            if JACOBIAN {
                batches.add(&p);
            } else {
                for l in 0..LANES {
                    batches.cost[l] += 0.5 * (p.ru[l] * p.ru[l] + p.rv[l] * p.rv[l]);
                }
            }
        }
        for i in full..self.n_points {
            rest.add(&self.point_lanes::<1, JACOBIAN>(pose, i));
        }
        let (c0, g0, u0) = batches.total();
        let (c1, g1, u1) = rest.total();
        (
            c0 + c1,
            std::array::from_fn(|a| g0[a] + g1[a]),
            std::array::from_fn(|k| u0[k] + u1[k]),
        )
    }

    /// [`Self::point_sums`] with per-observation noise or a lens: point by point, whitened.
    #[cold]
    fn weighted_point_sums<const JACOBIAN: bool>(&self, pose: &Pose) -> (f64, [f64; 6], [f64; 21]) {
        let mut sums = (0.0, [0.0; 6], [0.0; 21]);
        for i in 0..self.n_points {
            add_block(&mut sums, &self.point_block(pose, i));
        }
        sums
    }

    /// Point `i`'s residual `W (π(R X + t) − u)` and its Jacobian, whitened by the noise (if any).
    fn point_block(&self, pose: &Pose, i: usize) -> Block {
        let (r, j) = match &self.lens {
            Some(lens) => self.lens_point_block(lens.camera, pose, i),
            None => {
                let p = self.point_lanes::<1, true>(pose, i);
                let r = Vector2::new(p.ru[0], p.rv[0]);
                let j = SMatrix::<f64, 2, 6>::from_fn(|row, col| if row == 0 { p.ju[col][0] } else { p.jv[col][0] });
                (r, j)
            }
        };
        let w = self.noise.map_or_else(Matrix2::identity, |n| n.points[i]);
        (w * r, w * j)
    }

    /// Point `i`'s residual `π(R X + t) − u` through `lens` and its Jacobian (unwhitened): with
    /// `a = ∂π/∂x_cam`, `∂/∂ω = −a [R X]×` and `∂/∂τ = a`.
    fn lens_point_block(&self, lens: &Camera, pose: &Pose, i: usize) -> Block {
        let (x, u) = self.point(i);
        let rx = pose.rotation * x;
        let (pixel, a) = lens.project_with_jacobian(&(rx + pose.translation));
        let mut j = SMatrix::<f64, 2, 6>::zeros();
        j.fixed_view_mut::<2, 3>(0, 0).copy_from(&(-a * skew(&rx)));
        j.fixed_view_mut::<2, 3>(0, 3).copy_from(&a);
        (pixel - u, j)
    }

    /// Point `i`: its world coordinates and observed pixel.
    fn point(&self, i: usize) -> (Vector3<f64>, Vector2<f64>) {
        let c = |k: usize| self.column(k)[i];
        (Vector3::new(c(0), c(1), c(2)), Vector2::new(c(3), c(4)))
    }

    /// Line `i`'s two endpoint residuals and their Jacobian: `(l·ẽ) / √(l₁₂ᵀ C l₁₂)` with `C` the
    /// endpoint's covariance (the identity without noise: the pixel distance).
    #[inline(always)]
    fn line_block(&self, pose: &Pose, i: usize, with_jacobian: bool) -> Block {
        if let Some(lens) = &self.lens {
            return self.curved_line_block(lens, pose, i, with_jacobian);
        }
        match self.noise {
            None => self.line_block_with::<false>(pose, i, with_jacobian),
            Some(_) => self.line_block_with::<true>(pose, i, with_jacobian),
        }
    }

    /// [`Self::line_block`], with the endpoint covariances compiled in (`WEIGHTED`) or out.
    fn line_block_with<const WEIGHTED: bool>(&self, pose: &Pose, i: usize, with_jacobian: bool) -> Block {
        let [wa, wb] = self.lines3d[i];
        let (ra, rb) = (pose.rotation * wa, pose.rotation * wb);
        let (a, b) = (ra + pose.translation, rb + pose.translation);
        // The projected line in normalised coordinates, and its pixel form Kᵀ⁻¹ l.
        let l = a.cross(&b);
        let lp = self.k_inv.transpose() * l;
        let lp12 = lp.fixed_rows::<2>(0).into_owned();
        let plain_scale = if WEIGHTED { 0.0 } else { lp12.norm() };
        let mut residual = Vector2::zeros();
        let mut jac = SMatrix::<f64, 2, 6>::zeros();
        let dl_domega = skew(&b) * skew(&ra) - skew(&a) * skew(&rb);
        let dl_dt = skew(&a) - skew(&b);
        for (k, e) in self.lines2d[i].iter().enumerate() {
            let eh = Vector3::new(e.x, e.y, 1.0);
            let num = lp.dot(&eh);
            // C l₁₂ and √(l₁₂ᵀ C l₁₂), with C = I on the fast path.
            let (c_l, scale) = match self.noise {
                Some(n) if WEIGHTED => {
                    let c_l = n.lines[i][k] * lp12;
                    (c_l, lp12.dot(&c_l).sqrt())
                }
                _ => (lp12, plain_scale),
            };
            residual[k] = num / scale;
            if with_jacobian {
                // ∂/∂lp of (lp·e)/√(lp₁₂ᵀ C lp₁₂), then chain through lp = K⁻ᵀ l.
                let mut dlp = eh / scale;
                dlp.x -= num * c_l.x / scale.powi(3);
                dlp.y -= num * c_l.y / scale.powi(3);
                let dl = self.k_inv * dlp;
                jac.fixed_view_mut::<1, 3>(k, 0)
                    .copy_from(&(dl.transpose() * dl_domega));
                jac.fixed_view_mut::<1, 3>(k, 3).copy_from(&(dl.transpose() * dl_dt));
            }
        }
        (residual, jac)
    }

    /// Line `i`'s two endpoint residuals through a lens and their Jacobian: for each endpoint `e` with
    /// covariance `C` (the identity without noise), the point `q` of the projected line `ℓ` whose pixel
    /// `u(q)` is nearest to `e` ([`crate::camera::curved_line::endpoint_residual`]), then `ηᵀ (u(q) − e)` with `η = n / √(nᵀ C n)` and
    /// `n` the normal of the curve at `u(q)`: at the minimum `u(q) − e` is C-orthogonal to the curve,
    /// so this is `±` the Mahalanobis distance (the pixel distance for `C = I`). The Jacobian is
    /// `ηᵀ ∂u/∂(ω, τ)` at the fixed world point `X*` of the 3-D line that projects to `q`: the derivative
    /// of the minimum with respect to the pose is that at the minimiser (the envelope theorem), with the
    /// search's gradient `ηᵀ(…)`'s part along the curve zero. NaN when the 3-D line passes through the
    /// camera centre (no projected line), as for a pinhole.
    fn curved_line_block(&self, lens: &Lens, pose: &Pose, i: usize, with_jacobian: bool) -> Block {
        let [wa, wb] = self.lines3d[i];
        let (ra, rb) = (pose.rotation * wa, pose.rotation * wb);
        let (a, b) = (ra + pose.translation, rb + pose.translation);
        // ℓ: l₀ x + l₁ y + l₂ = 0 in normalised coordinates (NaN residuals where it does not exist).
        let l = a.cross(&b);
        let mut residual = Vector2::from_element(f64::NAN);
        let mut jac = SMatrix::<f64, 2, 6>::from_element(f64::NAN);
        for (k, e) in self.lines2d[i].iter().enumerate() {
            let cov = self.noise.map_or_else(Matrix2::identity, |n| n.lines[i][k]);
            let start = lens.starts[i][k].unwrap_or_else(|| {
                let p = if k == 0 { a } else { b };
                Vector2::new(p.x / p.z, p.y / p.z)
            });
            let Some(fit) = endpoint_residual(lens.camera, &l, &start, e, &cov) else {
                continue;
            };
            residual[k] = fit.residual;
            if with_jacobian {
                // X* = A + s (B − A), with x_cam(X*) = a + s (b − a) parallel to (q, 1).
                let q = fit.q;
                let qh = Vector3::new(q.x, q.y, 1.0);
                let (c0, c1) = (qh.cross(&a), qh.cross(&(b - a)));
                let s = -c0.dot(&c1) / c1.norm_squared();
                let (p, rx) = (a + (b - a) * s, ra + (rb - ra) * s);
                let z = p.z;
                let dq_dp = Matrix2x3::new(1.0 / z, 0.0, -q.x / z, 0.0, 1.0 / z, -q.y / z);
                let row = fit.gradient(lens.camera) * dq_dp;
                jac.fixed_view_mut::<1, 3>(k, 0).copy_from(&(-row * skew(&rx)));
                jac.fixed_view_mut::<1, 3>(k, 3).copy_from(&row);
            }
        }
        (residual, jac)
    }

    /// The cost `½ Σ r²` at `pose` when it is below `bound`, else `None`: the points are summed in
    /// batches and the sum abandoned as soon as it reaches `bound` (for ranking many poses cheaply).
    pub fn cost_below(&self, pose: &Pose, bound: f64) -> Option<f64> {
        if self.noise.is_some() || self.lens.is_some() {
            return self.weighted_cost_below(pose, bound);
        }
        let full = self.n_points - self.n_points % LANES;
        let mut total = 0.0;
        for i0 in (0..full).step_by(LANES) {
            let p = self.point_lanes::<LANES, false>(pose, i0);
            total += (0..LANES)
                .map(|l| 0.5 * (p.ru[l] * p.ru[l] + p.rv[l] * p.rv[l]))
                .sum::<f64>();
            if !(total < bound) {
                return None;
            }
        }
        for i in full..self.n_points {
            let p = self.point_lanes::<1, false>(pose, i);
            total += 0.5 * (p.ru[0] * p.ru[0] + p.rv[0] * p.rv[0]);
        }
        self.lines_below(pose, total, bound)
    }

    /// [`Self::cost_below`] with per-observation noise or a lens: the bound checked after every point.
    #[cold]
    fn weighted_cost_below(&self, pose: &Pose, bound: f64) -> Option<f64> {
        let mut total = 0.0;
        for i in 0..self.n_points {
            total += 0.5 * self.point_residual(pose, i).norm_squared();
            if !(total < bound) {
                return None;
            }
        }
        self.lines_below(pose, total, bound)
    }

    /// `total` plus the line terms, while below `bound`.
    #[inline(always)]
    fn lines_below(&self, pose: &Pose, mut total: f64, bound: f64) -> Option<f64> {
        for i in 0..self.lines2d.len() {
            total += 0.5 * self.line_block(pose, i, false).0.norm_squared();
            if !(total < bound) {
                return None;
            }
        }
        (total < bound).then_some(total)
    }

    /// Point `i`'s residual, whitened by the noise (if any).
    fn point_residual(&self, pose: &Pose, i: usize) -> Vector2<f64> {
        let r = match &self.lens {
            Some(lens) => {
                let (x, u) = self.point(i);
                lens.camera.project(&pose.transform(&x)) - u
            }
            None => {
                let p = self.point_lanes::<1, false>(pose, i);
                Vector2::new(p.ru[0], p.rv[0])
            }
        };
        self.noise.map_or(r, |n| n.points[i] * r)
    }

    /// The stacked residual vector in pixels (whitened units with noise): `(u, v)` per point, then the two signed endpoint
    /// distances per line (the `r` of `½ Σ r²`).
    pub fn residuals(&self, pose: &Pose) -> Vec<f64> {
        let points = (0..self.n_points).flat_map(|i| {
            let r = self.point_residual(pose, i);
            [r.x, r.y]
        });
        let lines = (0..self.lines2d.len()).flat_map(|i| {
            let r = self.line_block(pose, i, false).0;
            [r.x, r.y]
        });
        points.chain(lines).collect()
    }

    /// Per-correspondence reprojection errors in pixels: the point distance for points, the RMS of the
    /// two endpoint distances for lines (points first, then lines).
    pub fn errors(&self, pose: &Pose) -> Vec<f64> {
        let points = (0..self.n_points).map(|i| self.point_residual(pose, i).norm());
        let lines = (0..self.lines2d.len()).map(|i| (0.5 * self.line_block(pose, i, false).0.norm_squared()).sqrt());
        points.chain(lines).collect()
    }

    /// The stacked Jacobian's normal matrix `JᵀJ` at `pose` (pixels per radian / per length unit).
    pub fn information(&self, pose: &Pose) -> SMatrix<f64, 6, 6> {
        self.linearize(pose).gauss_newton
    }

    /// Correspondence `k`'s residual pair and its 2x6 Jacobian at `pose` (points first, then lines, as
    /// in [`ReprojectionCost::residuals`]), whitened by the noise (if any).
    pub(crate) fn block(&self, pose: &Pose, k: usize) -> Block {
        if k < self.n_points {
            self.point_block(pose, k)
        } else {
            self.line_block(pose, k - self.n_points, true)
        }
    }

    /// Point `i`'s squared (whitened) residual `‖r‖²` at `pose` and a bound `b ≥ ‖J‖₂²` on its
    /// Jacobian (the block of [`ReprojectionCost::block`]), cheaper than the Jacobian itself: with
    /// `J = W a [−[R X]×, I]`, `a = ∂π/∂x_cam`, `‖J‖₂² ≤ ‖W‖_F² ‖a‖_F² (‖X‖² + 1)`. Behind the camera:
    /// `(∞, 0)`. Through a lens: `(0, ∞)` (no bound: the caller must take the block).
    pub(crate) fn point_jacobian_bound(&self, pose: &Pose, i: usize) -> (f64, f64) {
        if self.lens.is_some() {
            return (0.0, f64::INFINITY);
        }
        let (x, u) = self.point(i);
        let c = &self.camera;
        let p = pose.rotation * x;
        let cam = p + pose.translation;
        if !(cam.z > 0.0) {
            return (f64::INFINITY, 0.0);
        }
        let (xn, yn) = (cam.x / cam.z, cam.y / cam.z);
        let r = Vector2::new(c.fx * xn + c.skew * yn + c.cx - u.x, c.fy * yn + c.cy - u.y);
        let w = self.noise.map_or_else(Matrix2::identity, |n| n.points[i]);
        let du = c.fx * xn + c.skew * yn;
        let a2 = (c.fx * c.fx + c.skew * c.skew + du * du + c.fy * c.fy + c.fy * c.fy * yn * yn) / (cam.z * cam.z);
        ((w * r).norm_squared(), w.norm_squared() * a2 * (x.norm_squared() + 1.0))
    }

    /// The number of 3-D points and line endpoints with `z ≤ 0` in the camera frame at `pose`.
    pub fn points_behind(&self, pose: &Pose) -> usize {
        let (x, y, z) = (self.column(0), self.column(1), self.column(2));
        let points = (0..self.n_points).map(|i| Vector3::new(x[i], y[i], z[i]));
        count_behind(points.chain(self.lines3d.iter().flat_map(|s| s.iter().copied())), pose)
    }
}

/// Adds one residual pair's cost, gradient and upper triangle of `JᵀJ` to `sums`.
#[inline(always)]
fn add_block(sums: &mut (f64, [f64; 6], [f64; 21]), (r, j): &Block) {
    sums.0 += 0.5 * r.norm_squared();
    let mut k = 0;
    for a in 0..6 {
        sums.1[a] += j[(0, a)] * r.x + j[(1, a)] * r.y;
        for b in a..6 {
            sums.2[k] += j[(0, a)] * j[(0, b)] + j[(1, a)] * j[(1, b)];
            k += 1;
        }
    }
}

/// The number of `points` with `z ≤ 0` in the camera frame at `pose`.
pub(crate) fn count_behind(points: impl Iterator<Item = Vector3<f64>>, pose: &Pose) -> usize {
    let r = pose.rotation.row(2);
    points
        .filter(|p| r[0] * p.x + r[1] * p.y + r[2] * p.z + pose.translation.z <= 0.0)
        .count()
}

impl Objective<6> for ReprojectionCost<'_> {
    type Point = Pose;

    fn cost(&self, pose: &Pose) -> f64 {
        let lines: f64 = (0..self.lines2d.len())
            .map(|i| self.line_block(pose, i, false).0.norm_squared())
            .sum();
        self.point_sums::<false>(pose).0 + 0.5 * lines
    }

    fn linearize(&self, pose: &Pose) -> Linearization<6> {
        let mut sums = self.point_sums::<true>(pose);
        for i in 0..self.lines2d.len() {
            add_block(&mut sums, &self.line_block(pose, i, true));
        }
        let (cost, grad, upper) = sums;
        let mut gauss_newton = SMatrix::<f64, 6, 6>::zeros();
        let mut k = 0;
        for a in 0..6 {
            for b in a..6 {
                gauss_newton[(a, b)] = upper[k];
                gauss_newton[(b, a)] = upper[k];
                k += 1;
            }
        }
        Linearization {
            cost,
            gradient: SVector::from(grad),
            gauss_newton,
        }
    }

    fn retract(&self, pose: &Pose, d: &SVector<f64, 6>) -> Pose {
        retract(pose, d)
    }
}

/// The pose reached from `pose` by the tangent step `d = (ω, δt)`: `exp(ω) R`, `t + δt` (the tangent
/// of every pose cost and covariance of the crate, single camera or rig).
pub(crate) fn retract(pose: &Pose, d: &SVector<f64, 6>) -> Pose {
    Pose::new(
        exp_so3(&Vector3::new(d[0], d[1], d[2])) * pose.rotation,
        pose.translation + Vector3::new(d[3], d[4], d[5]),
    )
}

/// `JᵀJ` counts as singular when its smallest eigenvalue may be below this fraction of its largest
/// (see [`covariance_from_information`] for the test).
pub const RELATIVE_RANK_TOLERANCE: f64 = 1e-12;

/// The 6x6 covariance of `(ω, t)` (rotation as a tangent vector in radians, translation in world
/// units) at `pose` for isotropic pixel noise of standard deviation `sigma_px`: `σ² (JᵀJ)⁻¹`,
/// symmetrised. At the true pose this is the Cramér-Rao bound for unbiased estimators. `None` if `JᵀJ`
/// is not finite or is singular (see [`covariance_from_information`]).
pub fn pose_covariance(cost: &ReprojectionCost<'_>, pose: &Pose, sigma_px: f64) -> Option<SMatrix<f64, 6, 6>> {
    covariance_from_information(&cost.information(pose), sigma_px)
}

/// `σ² (JᵀJ)⁻¹`, symmetrised, from the normal matrix `A = JᵀJ`. `None` when `σ² A⁻¹` overflows or
/// (for `σ > 0`) underflows a variance below the smallest normal double, or `A` is not finite, not
/// positive definite (its Cholesky factorisation fails), or too close to singular:
/// `1 / tr(A⁻¹) ≤ ` `RELATIVE_RANK_TOLERANCE` `· tr(A)`. Since `λ_min ≥ 1 / tr(A⁻¹)` and
/// `λ_max ≤ tr(A)`, an accepted `A` has `λ_min > 1e-12 λ_max`, and a rejected one has
/// `λ_min ≤ 36e-12 λ_max` (each bound is within a factor 6 of the eigenvalue it bounds): the
/// eigenvalue test to within a factor 36, at the price of one Cholesky factorisation.
pub fn covariance_from_information(information: &SMatrix<f64, 6, 6>, sigma_px: f64) -> Option<SMatrix<f64, 6, 6>> {
    if information.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let inverse = information.cholesky()?.inverse();
    if !(1.0 / inverse.trace() > RELATIVE_RANK_TOLERANCE * information.trace()) {
        return None;
    }
    let cov = inverse * (sigma_px * sigma_px);
    // σ² (JᵀJ)⁻¹ must be representable: no overflow, and no variance lost to underflow for a σ > 0
    // (σ = 1e-200 px would give zeros, a pose known exactly).
    let underflow = sigma_px > 0.0 && cov.diagonal().iter().any(|&v| v < f64::MIN_POSITIVE);
    (cov.iter().all(|v| v.is_finite()) && !underflow).then(|| 0.5 * (cov + cov.transpose()))
}

/// [`crate::pose::PoseResult::covariance`], its source and `σ` from the linearisation at the returned
/// pose (`None` for a non-finite pose): `σ² (JᵀJ)⁻¹` with `σ` given or estimated as
/// `σ̂² = Σ r² / (m − 6)` over `m` residuals (`Σ r² = 2 × cost`).
pub(crate) fn covariance(
    linearization: Option<&Linearization<6>>,
    residual_count: usize,
    given: Option<f64>,
) -> (Option<Matrix6<f64>>, Option<CovarianceSource>, Option<f64>) {
    let Some(lin) = linearization else {
        return (None, None, given);
    };
    let (sigma, source) = match given {
        Some(sigma) => (Some(sigma), CovarianceSource::Given),
        None if residual_count > 6 => (
            Some((2.0 * lin.cost / (residual_count - 6) as f64).sqrt()),
            CovarianceSource::Estimated,
        ),
        None => (None, CovarianceSource::Estimated),
    };
    let cov = sigma
        .filter(|s| s.is_finite())
        .and_then(|s| covariance_from_information(&lin.gauss_newton, s));
    let source = cov.is_some().then_some(source);
    (cov, source, sigma)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optim::problem::testing::gradient_error;
    use crate::rng::Rng;

    #[test]
    fn jacobian_matches_finite_differences() {
        let mut rng = Rng::new(5);
        let cam = Intrinsics::new(-1730.3, 1220.7, 243.8, 241.2, 2.0).unwrap();
        for _ in 0..20 {
            let rot = rng.rotation();
            let t = Vector3::new(rng.normal(), rng.normal(), 20.0);
            let p3: Vec<Vector3<f64>> = (0..6)
                .map(|_| Vector3::new(rng.normal(), rng.normal(), rng.normal()))
                .collect();
            let p2: Vec<Vector2<f64>> = p3
                .iter()
                .map(|x| cam.project(&(rot * x + t)) + Vector2::new(rng.normal(), rng.normal()))
                .collect();
            let l3: Vec<[Vector3<f64>; 2]> = (0..4)
                .map(|_| {
                    [
                        Vector3::new(rng.normal(), rng.normal(), rng.normal()),
                        Vector3::new(rng.normal(), rng.normal(), rng.normal()),
                    ]
                })
                .collect();
            let l2: Vec<[Vector2<f64>; 2]> = l3
                .iter()
                .map(|s| {
                    [
                        cam.project(&(rot * s[0] + t)) + Vector2::new(3.0, -2.0),
                        cam.project(&(rot * s[1] + t)),
                    ]
                })
                .collect();
            let cost = ReprojectionCost::new(cam, &p2, &p3, &l2, &l3);
            // Perturb away from the data so the gradient is not ~0.
            let pose = Pose::new(
                exp_so3(&Vector3::new(0.01, -0.02, 0.03)) * rot,
                t + Vector3::new(0.1, 0.0, -0.2),
            );
            assert!(gradient_error(&cost, &pose, 1e-6) < 1e-6);
            // Line residuals vanish at the true pose for exact endpoints.
            let l2_exact: Vec<[Vector2<f64>; 2]> = l3
                .iter()
                .map(|s| [cam.project(&(rot * s[0] + t)), cam.project(&(rot * s[1] + t))])
                .collect();
            let exact = ReprojectionCost::new(cam, &[], &[], &l2_exact, &l3);
            assert!(exact.cost(&Pose::new(rot, t)) < 1e-18);
        }
    }

    #[test]
    fn weighted_residuals_match_finite_differences_and_reduce_to_pixels() {
        let mut rng = Rng::new(8);
        let cam = Intrinsics::new(900.0, 880.0, 320.0, 240.0, 0.0).unwrap();
        let rot = rng.rotation();
        let t = Vector3::new(0.2, -0.1, 8.0);
        let p3: Vec<Vector3<f64>> = (0..5)
            .map(|_| Vector3::new(rng.normal(), rng.normal(), rng.normal()))
            .collect();
        let p2: Vec<Vector2<f64>> = p3
            .iter()
            .map(|x| cam.project(&(rot * x + t)) + Vector2::new(1.0, -2.0))
            .collect();
        let l3: Vec<[Vector3<f64>; 2]> = (0..3)
            .map(|_| {
                [
                    Vector3::new(rng.normal(), rng.normal(), 1.0),
                    Vector3::new(rng.normal(), 0.5, rng.normal()),
                ]
            })
            .collect();
        let l2: Vec<[Vector2<f64>; 2]> = l3
            .iter()
            .map(|s| {
                [
                    cam.project(&(rot * s[0] + t)) + Vector2::new(2.0, 1.0),
                    cam.project(&(rot * s[1] + t)),
                ]
            })
            .collect();
        let plain = Correspondences {
            points2d: p2,
            points3d: p3,
            lines2d: l2,
            lines3d: l3,
            noise: None,
        };
        let pose = Pose::new(rot, t);
        // Identity noise: the same cost as the fast path.
        let identity = Correspondences {
            noise: Some(ObservationNoise {
                points: vec![Matrix2::identity(); 5],
                lines: vec![[Matrix2::identity(); 2]; 3],
                absolute: false,
            }),
            ..plain.clone()
        };
        let (a, b) = (
            ReprojectionCost::of(&cam, &plain),
            ReprojectionCost::of(&cam, &identity),
        );
        assert!((a.cost(&pose) - b.cost(&pose)).abs() < 1e-12 * a.cost(&pose));
        assert!(
            (a.linearize(&pose).gauss_newton - b.linearize(&pose).gauss_newton).amax()
                < 1e-9 * a.information(&pose).amax()
        );
        // Anisotropic covariances: point i's cost is ½ rᵀ Σ⁻¹ r, and the gradient is consistent.
        let covs: Vec<Matrix2<f64>> = (0..5).map(|i| Matrix2::new(1.0 + i as f64, 0.3, 0.3, 0.5)).collect();
        let line_covs: Vec<[Matrix2<f64>; 2]> = (0..3)
            .map(|_| [Matrix2::new(2.0, -0.4, -0.4, 0.7), Matrix2::new(0.3, 0.0, 0.0, 3.0)])
            .collect();
        let weighted = Correspondences {
            noise: Some(ObservationNoise::from_covariances(&covs, &line_covs).unwrap()),
            ..plain.clone()
        };
        let cost = ReprojectionCost::of(&cam, &weighted);
        let expected_points: f64 = (0..5)
            .map(|i| {
                let r = cam.project(&(rot * plain.points3d[i] + t)) - plain.points2d[i];
                0.5 * (r.transpose() * covs[i].try_inverse().unwrap() * r)[0]
            })
            .sum();
        let expected_lines: f64 = (0..3)
            .map(|i| {
                // The projected line in pixels from two projected points; the distance's variance is nᵀ C n.
                let (a, b) = (
                    cam.project(&(rot * plain.lines3d[i][0] + t)),
                    cam.project(&(rot * plain.lines3d[i][1] + t)),
                );
                let d = (b - a).normalize();
                let n = Vector2::new(-d.y, d.x);
                (0..2)
                    .map(|k| {
                        let dist = n.dot(&(plain.lines2d[i][k] - a));
                        0.5 * dist * dist / (n.transpose() * line_covs[i][k] * n)[0]
                    })
                    .sum::<f64>()
            })
            .sum();
        let total = expected_points + expected_lines;
        assert!(
            (cost.cost(&pose) - total).abs() < 1e-9 * total,
            "{} vs {total}",
            cost.cost(&pose)
        );
        let moved = Pose::new(
            exp_so3(&Vector3::new(0.01, 0.02, -0.01)) * rot,
            t + Vector3::new(0.05, 0.0, 0.1),
        );
        assert!(gradient_error(&cost, &moved, 1e-6) < 1e-6);
    }
}
