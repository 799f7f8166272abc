//! An oracle of the point triangulation tests written without the library's point code (no
//! `point_cost`, `PointView`, `trust_region` or chart): eq. 19 from the camera matrices, the pixels
//! and the covariances, cheirality from the sign of the depth, and a Levenberg-Marquardt search of
//! its own from many starts. Certificates are checked against these numbers, never against the
//! library's residuals. Used as `use crate::common::oracle_triangulation as oracle;`.
#![allow(dead_code)]

use nalgebra::{Matrix2, Matrix3, Matrix3x4, Vector2, Vector3};
use pluecker::rng::Rng;

/// A point observed by cameras: `P`, the pixel and the inverse covariance of each view.
pub struct PointData {
    pub cameras: Vec<Matrix3x4<f64>>,
    pub pixels: Vec<Vector2<f64>>,
    /// `Σᵢ⁻¹` (the identity without covariances).
    pub information: Vec<Matrix2<f64>>,
}

impl PointData {
    /// The data with per-view covariances (`None`: 1 px isotropic).
    pub fn new(cameras: &[Matrix3x4<f64>], pixels: &[Vector2<f64>], covariances: Option<&[Matrix2<f64>]>) -> PointData {
        let information = match covariances {
            None => vec![Matrix2::identity(); cameras.len()],
            Some(c) => c
                .iter()
                .map(|c| c.try_inverse().expect("invertible covariance"))
                .collect(),
        };
        PointData {
            cameras: cameras.to_vec(),
            pixels: pixels.to_vec(),
            information,
        }
    }

    /// The depth of `x` in camera `i`, signed so that it is positive in front: `(P X̃)₃ · sign det M`.
    pub fn depth(&self, i: usize, x: &Vector3<f64>) -> f64 {
        let p = &self.cameras[i];
        let m: Matrix3<f64> = p.fixed_view::<3, 3>(0, 0).into_owned();
        (p * x.push(1.0)).z * m.determinant().signum()
    }

    /// True when `x` is in front of every camera.
    pub fn in_front(&self, x: &Vector3<f64>) -> bool {
        (0..self.cameras.len()).all(|i| self.depth(i, x) > 0.0)
    }

    /// Eq. 19: `Σᵢ (π(Pᵢ X̃) − uᵢ)ᵀ Σᵢ⁻¹ (π(Pᵢ X̃) − uᵢ)`, squared pixels.
    pub fn cost(&self, x: &Vector3<f64>) -> f64 {
        (0..self.cameras.len())
            .map(|i| {
                let h = self.cameras[i] * x.push(1.0);
                let e = h.xy() / h.z - self.pixels[i];
                e.dot(&(self.information[i] * e))
            })
            .sum()
    }

    /// The Gauss-Newton normal equations `(JᵀWJ, JᵀWe)` at `x`.
    fn normal_equations(&self, x: &Vector3<f64>) -> (Matrix3<f64>, Vector3<f64>) {
        let (mut h, mut g) = (Matrix3::zeros(), Vector3::zeros());
        for i in 0..self.cameras.len() {
            let p = &self.cameras[i];
            let u = p * x.push(1.0);
            let proj = u.xy() / u.z;
            let e = proj - self.pixels[i];
            // ∂π/∂X = (rows 1-2 of M − π · row 3 of M) / z.
            let m = p.fixed_view::<3, 3>(0, 0);
            let mut j = nalgebra::Matrix2x3::zeros();
            for r in 0..2 {
                for c in 0..3 {
                    j[(r, c)] = (m[(r, c)] - proj[r] * m[(2, c)]) / u.z;
                }
            }
            let wj = self.information[i] * j;
            h += j.transpose() * wj;
            g += wj.transpose() * e;
        }
        (h, g)
    }

    /// Levenberg-Marquardt from `x0` (kept in front of every camera): the point and its cost.
    pub fn minimize(&self, x0: &Vector3<f64>) -> (Vector3<f64>, f64) {
        let mut x = *x0;
        let mut f = self.cost(&x);
        let mut lambda = 1e-3;
        for _ in 0..300 {
            let (h, g) = self.normal_equations(&x);
            let mut improved = false;
            while lambda < 1e12 {
                let damped = h + Matrix3::from_diagonal(&h.diagonal()) * lambda + Matrix3::identity() * 1e-300;
                let Some(step) = damped.lu().solve(&(-g)) else {
                    lambda *= 10.0;
                    continue;
                };
                let trial = x + step;
                let ft = self.cost(&trial);
                if self.in_front(&trial) && ft < f {
                    let done = f - ft <= 1e-15 * f;
                    (x, f) = (trial, ft);
                    lambda = (lambda * 0.3).max(1e-12);
                    improved = !done;
                    break;
                }
                lambda *= 10.0;
            }
            if !improved {
                break;
            }
        }
        (x, f)
    }

    /// The least cost over `starts` random starts in front of every camera, spread along the first
    /// camera's ray through `x_ref` from 0.1 to 1000 times its depth and laterally, and from `x_ref`
    /// itself: an upper bound of the global minimum that many-start search makes tight.
    pub fn many_start_minimum(&self, x_ref: &Vector3<f64>, starts: usize, rng: &mut Rng) -> (Vector3<f64>, f64) {
        let p = &self.cameras[0];
        let m: Matrix3<f64> = p.fixed_view::<3, 3>(0, 0).into_owned();
        let centre = -(m.try_inverse().expect("a finite camera") * p.column(3));
        let ray = x_ref - centre;
        let mut best = self.minimize(x_ref);
        for _ in 0..starts {
            let depth = 10f64.powf(rng.uniform_in(-1.0, 3.0));
            let jitter = Vector3::new(rng.normal(), rng.normal(), rng.normal()) * 0.02 * depth * ray.norm();
            let x0 = centre + ray * depth + jitter;
            if !self.in_front(&x0) {
                continue;
            }
            let found = self.minimize(&x0);
            if found.1 < best.1 {
                best = found;
            }
        }
        best
    }
}

/// The relative gap `(cost − min(raw, cost)) / max(cost, 1e-12)` recomputed from a cost and a raw
/// bound (never read back from a certificate).
pub fn gap(cost: f64, raw_lower_bound: f64) -> f64 {
    ((cost - raw_lower_bound.min(cost)) / cost.max(1e-12)).max(0.0)
}
