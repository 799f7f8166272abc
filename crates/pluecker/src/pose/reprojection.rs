//! The reprojection error: the statistically optimal cost under Gaussian pixel noise.
//!
//! The dual-quaternion costs are algebraic; [`ReprojectionCost`] is what a maximum-likelihood estimate
//! minimises. Residuals are in pixels:
//! - a point: `π(R X + t) − u`, two residuals, with `π(x_cam) = K x_cam / z`;
//! - a line: the signed distances of the two observed segment endpoints to the projection of the
//!   3-D line (the line through the projections of its two 3-D endpoints), two residuals.
//!
//! The pose is `(R, t)` with `x_cam = R X_world + t`; a tangent step `(ω, τ)` moves it to
//! `(exp(ω) R, t + τ)` (rotation perturbed on the left, in the camera frame).

use super::{Correspondences, CovarianceSource};
use crate::camera::Camera;
use crate::geometry::quaternion::{exp_so3, skew};
use crate::optim::{Linearization, Objective};
use nalgebra::{Matrix3, Matrix6, SMatrix, SVector, Vector2, Vector3};

pub use crate::rigid::Pose;

/// Points per batch of the point kernel. The kernel is written lane by lane over fixed-size arrays so
/// that the compiler turns each batch into vector instructions (the speed-up: `bench/README.md`).
const LANES: usize = 4;

/// Reprojection-error objective over `SO(3) × ℝ³`.
#[derive(Debug, Clone)]
pub struct ReprojectionCost<'a> {
    camera: Camera,
    k_inv: Matrix3<f64>,
    /// The point correspondences as five columns `[X…, Y…, Z…, u…, v…]` (structure of arrays).
    columns: Vec<f64>,
    n_points: usize,
    lines2d: &'a [[Vector2<f64>; 2]],
    lines3d: &'a [[Vector3<f64>; 2]],
}

/// One residual pair and its 2x6 Jacobian with respect to `(ω, τ)`.
type Block = (Vector2<f64>, SMatrix<f64, 2, 6>);

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
        camera: Camera,
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
        }
    }

    /// The cost of all the correspondences of `c`.
    pub fn of(camera: &Camera, c: &'a Correspondences) -> Self {
        ReprojectionCost::new(*camera, &c.points2d, &c.points3d, &c.lines2d, &c.lines3d)
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

    fn line_block(&self, pose: &Pose, i: usize, with_jacobian: bool) -> Block {
        let [wa, wb] = self.lines3d[i];
        let (ra, rb) = (pose.rotation * wa, pose.rotation * wb);
        let (a, b) = (ra + pose.translation, rb + pose.translation);
        // The projected line in normalised coordinates, and its pixel form Kᵀ⁻¹ l.
        let l = a.cross(&b);
        let lp = self.k_inv.transpose() * l;
        let scale = lp.fixed_rows::<2>(0).norm();
        let mut residual = Vector2::zeros();
        let mut jac = SMatrix::<f64, 2, 6>::zeros();
        let dl_domega = skew(&b) * skew(&ra) - skew(&a) * skew(&rb);
        let dl_dt = skew(&a) - skew(&b);
        for (k, e) in self.lines2d[i].iter().enumerate() {
            let eh = Vector3::new(e.x, e.y, 1.0);
            let num = lp.dot(&eh);
            residual[k] = num / scale;
            if with_jacobian {
                // ∂/∂lp of (lp·e)/‖lp₀₁‖, then chain through lp = K⁻ᵀ l.
                let mut dlp = eh / scale;
                dlp.x -= num * lp.x / scale.powi(3);
                dlp.y -= num * lp.y / scale.powi(3);
                let dl = self.k_inv * dlp;
                jac.fixed_view_mut::<1, 3>(k, 0)
                    .copy_from(&(dl.transpose() * dl_domega));
                jac.fixed_view_mut::<1, 3>(k, 3).copy_from(&(dl.transpose() * dl_dt));
            }
        }
        (residual, jac)
    }

    /// The cost `½ Σ r²` at `pose` when it is below `bound`, else `None`: the points are summed in
    /// batches and the sum abandoned as soon as it reaches `bound` (for ranking many poses cheaply).
    pub fn cost_below(&self, pose: &Pose, bound: f64) -> Option<f64> {
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
        for i in 0..self.lines2d.len() {
            total += 0.5 * self.line_block(pose, i, false).0.norm_squared();
            if !(total < bound) {
                return None;
            }
        }
        (total < bound).then_some(total)
    }

    /// The stacked residual vector in pixels: `(u, v)` per point, then the two signed endpoint
    /// distances per line (the `r` of `½ Σ r²`).
    pub fn residuals(&self, pose: &Pose) -> Vec<f64> {
        let points = (0..self.n_points).flat_map(|i| {
            let p = self.point_lanes::<1, false>(pose, i);
            [p.ru[0], p.rv[0]]
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
        let points = (0..self.n_points).map(|i| {
            let p = self.point_lanes::<1, false>(pose, i);
            (p.ru[0] * p.ru[0] + p.rv[0] * p.rv[0]).sqrt()
        });
        let lines = (0..self.lines2d.len()).map(|i| (0.5 * self.line_block(pose, i, false).0.norm_squared()).sqrt());
        points.chain(lines).collect()
    }

    /// The stacked Jacobian's normal matrix `JᵀJ` at `pose` (pixels per radian / per length unit).
    pub fn information(&self, pose: &Pose) -> SMatrix<f64, 6, 6> {
        self.linearize(pose).gauss_newton
    }

    /// The number of 3-D points and line endpoints with `z ≤ 0` in the camera frame at `pose`.
    pub fn points_behind(&self, pose: &Pose) -> usize {
        let (x, y, z) = (self.column(0), self.column(1), self.column(2));
        let points = (0..self.n_points).map(|i| Vector3::new(x[i], y[i], z[i]));
        count_behind(points.chain(self.lines3d.iter().flat_map(|s| s.iter().copied())), pose)
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
        let (mut cost, mut grad, mut upper) = self.point_sums::<true>(pose);
        for i in 0..self.lines2d.len() {
            let (r, j) = self.line_block(pose, i, true);
            cost += 0.5 * r.norm_squared();
            let mut k = 0;
            for a in 0..6 {
                grad[a] += j[(0, a)] * r.x + j[(1, a)] * r.y;
                for b in a..6 {
                    upper[k] += j[(0, a)] * j[(0, b)] + j[(1, a)] * j[(1, b)];
                    k += 1;
                }
            }
        }
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
        let omega = Vector3::new(d[0], d[1], d[2]);
        Pose::new(
            exp_so3(&omega) * pose.rotation,
            pose.translation + Vector3::new(d[3], d[4], d[5]),
        )
    }
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

/// `σ² (JᵀJ)⁻¹`, symmetrised, from the normal matrix `A = JᵀJ`. `None` when `A` is not finite, not
/// positive definite (its Cholesky factorisation fails), or too close to singular:
/// `1 / tr(A⁻¹) ≤ ` [`RELATIVE_RANK_TOLERANCE`] `· tr(A)`. Since `λ_min ≥ 1 / tr(A⁻¹)` and
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
    cov.iter().all(|v| v.is_finite()).then(|| 0.5 * (cov + cov.transpose()))
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
        let cam = Camera::new(-1730.3, 1220.7, 243.8, 241.2, 2.0).unwrap();
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
}
