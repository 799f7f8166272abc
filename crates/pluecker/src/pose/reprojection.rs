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

use crate::camera::Camera;
use crate::geometry::quaternion::{exp_so3, skew};
use crate::optim::{Linearization, Objective};
use nalgebra::{Matrix3, SMatrix, SVector, Vector2, Vector3};

/// A pose `x_cam = R X + t`.
pub type Pose = (Matrix3<f64>, Vector3<f64>);

/// Reprojection-error objective over `SO(3) × ℝ³`.
#[derive(Debug, Clone)]
pub struct ReprojectionCost<'a> {
    camera: Camera,
    k_inv: Matrix3<f64>,
    points2d: &'a [Vector2<f64>],
    points3d: &'a [Vector3<f64>],
    lines2d: &'a [[Vector2<f64>; 2]],
    lines3d: &'a [[Vector3<f64>; 2]],
}

/// One residual pair and its 2x6 Jacobian with respect to `(ω, τ)`.
type Block = (Vector2<f64>, SMatrix<f64, 2, 6>);

impl<'a> ReprojectionCost<'a> {
    /// The cost of the given correspondences (pixels and world coordinates; segments as endpoints).
    pub fn new(
        camera: Camera,
        points2d: &'a [Vector2<f64>],
        points3d: &'a [Vector3<f64>],
        lines2d: &'a [[Vector2<f64>; 2]],
        lines3d: &'a [[Vector3<f64>; 2]],
    ) -> Self {
        let k_inv = camera.matrix().try_inverse().unwrap_or_else(Matrix3::identity);
        ReprojectionCost { camera, k_inv, points2d, points3d, lines2d, lines3d }
    }

    /// Number of scalar residuals: two per point and two per line.
    pub fn residual_count(&self) -> usize {
        2 * (self.points2d.len() + self.lines2d.len())
    }

    #[inline(always)]
    fn point_block(&self, pose: &Pose, i: usize, with_jacobian: bool) -> Block {
        let p = pose.0 * self.points3d[i];
        let c = p + pose.1;
        let iz = 1.0 / c.z;
        let (xn, yn) = (c.x * iz, c.y * iz);
        let cam = &self.camera;
        let residual = Vector2::new(cam.fx * xn + cam.skew * yn + cam.cx, cam.fy * yn + cam.cy) - self.points2d[i];
        let mut jac = SMatrix::<f64, 2, 6>::zeros();
        if with_jacobian {
            // Rows of ∂u/∂x_cam; the rotation part is a [p]ₓ ω·(−1) = (p × a)·ω for each row a.
            let du = Vector3::new(cam.fx * iz, cam.skew * iz, -(cam.fx * xn + cam.skew * yn) * iz);
            let dv = Vector3::new(0.0, cam.fy * iz, -cam.fy * yn * iz);
            for (row, a) in [du, dv].iter().enumerate() {
                let w = p.cross(a);
                jac[(row, 0)] = w.x;
                jac[(row, 1)] = w.y;
                jac[(row, 2)] = w.z;
                jac[(row, 3)] = a.x;
                jac[(row, 4)] = a.y;
                jac[(row, 5)] = a.z;
            }
        }
        (residual, jac)
    }

    fn line_block(&self, pose: &Pose, i: usize, with_jacobian: bool) -> Block {
        let [wa, wb] = self.lines3d[i];
        let (ra, rb) = (pose.0 * wa, pose.0 * wb);
        let (a, b) = (ra + pose.1, rb + pose.1);
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
                jac.fixed_view_mut::<1, 3>(k, 0).copy_from(&(dl.transpose() * dl_domega));
                jac.fixed_view_mut::<1, 3>(k, 3).copy_from(&(dl.transpose() * dl_dt));
            }
        }
        (residual, jac)
    }

    fn blocks<'s>(&'s self, pose: &'s Pose, with_jacobian: bool) -> impl Iterator<Item = Block> + 's {
        (0..self.points2d.len())
            .map(move |i| self.point_block(pose, i, with_jacobian))
            .chain((0..self.lines2d.len()).map(move |i| self.line_block(pose, i, with_jacobian)))
    }

    /// Per-correspondence reprojection errors in pixels: the point distance for points, the RMS of the
    /// two endpoint distances for lines (points first, then lines).
    pub fn errors(&self, pose: &Pose) -> Vec<f64> {
        self.blocks(pose, false)
            .enumerate()
            .map(|(i, (r, _))| if i < self.points2d.len() { r.norm() } else { (0.5 * r.norm_squared()).sqrt() })
            .collect()
    }

    /// The stacked Jacobian's normal matrix `JᵀJ` at `pose` (pixels per radian / per length unit).
    pub fn information(&self, pose: &Pose) -> SMatrix<f64, 6, 6> {
        self.blocks(pose, true).map(|(_, j)| j.transpose() * j).sum()
    }

    /// The number of 3-D points and line endpoints with `z ≤ 0` in the camera frame at `pose`.
    pub fn points_behind(&self, pose: &Pose) -> usize {
        let behind = |x: &Vector3<f64>| (pose.0 * x + pose.1).z <= 0.0;
        self.points3d.iter().filter(|x| behind(x)).count()
            + self.lines3d.iter().flat_map(|s| s.iter()).filter(|x| behind(x)).count()
    }
}

impl Objective<6> for ReprojectionCost<'_> {
    type Point = Pose;

    fn cost(&self, pose: &Pose) -> f64 {
        0.5 * self.blocks(pose, false).map(|(r, _)| r.norm_squared()).sum::<f64>()
    }

    fn linearize(&self, pose: &Pose) -> Linearization<6> {
        // Accumulated in plain arrays (upper triangle of JᵀJ, 21 entries): this loop is the hot path
        // of the refinement, and fixed-size arrays let the compiler unroll it without bounds checks.
        let mut cost = 0.0;
        let mut grad = [0.0; 6];
        let mut upper = [0.0; 21];
        let points = (0..self.points2d.len()).map(|i| self.point_block(pose, i, true));
        let lines = (0..self.lines2d.len()).map(|i| self.line_block(pose, i, true));
        let mut add = |(r, j): Block| {
            cost += 0.5 * (r.x * r.x + r.y * r.y);
            let (j0, j1) = (j.row(0), j.row(1));
            let (j0, j1): ([f64; 6], [f64; 6]) = (std::array::from_fn(|a| j0[a]), std::array::from_fn(|a| j1[a]));
            let mut k = 0;
            for a in 0..6 {
                grad[a] += j0[a] * r.x + j1[a] * r.y;
                for b in a..6 {
                    upper[k] += j0[a] * j0[b] + j1[a] * j1[b];
                    k += 1;
                }
            }
        };
        points.for_each(&mut add);
        lines.for_each(&mut add);
        let mut gauss_newton = SMatrix::<f64, 6, 6>::zeros();
        let mut k = 0;
        for a in 0..6 {
            for b in a..6 {
                gauss_newton[(a, b)] = upper[k];
                gauss_newton[(b, a)] = upper[k];
                k += 1;
            }
        }
        Linearization { cost, gradient: SVector::from(grad), gauss_newton }
    }

    fn retract(&self, pose: &Pose, d: &SVector<f64, 6>) -> Pose {
        let omega = Vector3::new(d[0], d[1], d[2]);
        (exp_so3(&omega) * pose.0, pose.1 + Vector3::new(d[3], d[4], d[5]))
    }
}

/// `JᵀJ` counts as singular when its smallest eigenvalue is below this fraction of its largest.
pub const RELATIVE_RANK_TOLERANCE: f64 = 1e-12;

/// The 6x6 covariance of `(ω, t)` (rotation as a tangent vector in radians, translation in world
/// units) at `pose` for isotropic pixel noise of standard deviation `sigma_px`: `σ² (JᵀJ)⁻¹`,
/// symmetrised. At the true pose this is the Cramér-Rao bound for unbiased estimators. `None` if `JᵀJ`
/// is not finite or is singular (smallest eigenvalue ≤ [`RELATIVE_RANK_TOLERANCE`] × largest).
pub fn pose_covariance(cost: &ReprojectionCost<'_>, pose: &Pose, sigma_px: f64) -> Option<SMatrix<f64, 6, 6>> {
    let information = cost.information(pose);
    if information.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let eig = information.symmetric_eigenvalues();
    if !(eig.max() > 0.0 && eig.min() > RELATIVE_RANK_TOLERANCE * eig.max()) {
        return None;
    }
    let cov = information.try_inverse()? * (sigma_px * sigma_px);
    cov.iter().all(|v| v.is_finite()).then(|| 0.5 * (cov + cov.transpose()))
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
            let p3: Vec<Vector3<f64>> = (0..6).map(|_| Vector3::new(rng.normal(), rng.normal(), rng.normal())).collect();
            let p2: Vec<Vector2<f64>> =
                p3.iter().map(|x| cam.project(&(rot * x + t)) + Vector2::new(rng.normal(), rng.normal())).collect();
            let l3: Vec<[Vector3<f64>; 2]> = (0..4)
                .map(|_| [Vector3::new(rng.normal(), rng.normal(), rng.normal()), Vector3::new(rng.normal(), rng.normal(), rng.normal())])
                .collect();
            let l2: Vec<[Vector2<f64>; 2]> = l3
                .iter()
                .map(|s| [cam.project(&(rot * s[0] + t)) + Vector2::new(3.0, -2.0), cam.project(&(rot * s[1] + t))])
                .collect();
            let cost = ReprojectionCost::new(cam, &p2, &p3, &l2, &l3);
            // Perturb away from the data so the gradient is not ~0.
            let pose = (exp_so3(&Vector3::new(0.01, -0.02, 0.03)) * rot, t + Vector3::new(0.1, 0.0, -0.2));
            assert!(gradient_error(&cost, &pose, 1e-6) < 1e-6);
            // Line residuals vanish at the true pose for exact endpoints.
            let l2_exact: Vec<[Vector2<f64>; 2]> =
                l3.iter().map(|s| [cam.project(&(rot * s[0] + t)), cam.project(&(rot * s[1] + t))]).collect();
            let exact = ReprojectionCost::new(cam, &[], &[], &l2_exact, &l3);
            assert!(exact.cost(&(rot, t)) < 1e-18);
        }
    }
}
