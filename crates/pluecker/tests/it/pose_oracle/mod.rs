//! An independent oracle of the pose cost for the tests of the pose certificate: the reprojection
//! cost `½ Σ r²` written again from its definition (Phong & Horaud 1995; the library's
//! `pose::ReprojectionCost` documents the same residuals), and a plain Levenberg-Marquardt with numeric
//! Jacobians to find local minima from many starts. Nothing here calls the library's residuals,
//! refinement or certificate; only its data types (`Camera`, `Correspondences`) and its seeded `Rng`.
//!
//! Residuals, in pixels:
//! - a point `X` seen at `u`: `π(R X + t) − u`, `π(x) = (fx x/z + s y/z + cx, fy y/z + cy)`;
//! - a segment `(A, B)` seen with endpoints `e₁, e₂`: the signed distances of `e₁` and `e₂` to the image
//!   line through `π(R A + t)` and `π(R B + t)` (computed here from the two projected pixels; the sign
//!   does not enter the cost).
#![allow(dead_code)]

use nalgebra::{DMatrix, DVector, Matrix3, Matrix6, Rotation3, Vector2, Vector3, Vector6};
use pluecker::pose::Correspondences;
use pluecker::rng::Rng;
use pluecker::Camera;

/// A pose `x_cam = R X + t`.
#[derive(Debug, Clone, Copy)]
pub struct OraclePose {
    pub r: Matrix3<f64>,
    pub t: Vector3<f64>,
}

impl OraclePose {
    pub fn new(r: Matrix3<f64>, t: Vector3<f64>) -> Self {
        OraclePose { r, t }
    }

    /// The chart step `(ω, τ)`: `(exp(ω) R, t + τ)`.
    pub fn step(&self, d: &Vector6<f64>) -> Self {
        let w = Vector3::new(d[0], d[1], d[2]);
        OraclePose {
            r: exp(&w) * self.r,
            t: self.t + Vector3::new(d[3], d[4], d[5]),
        }
    }

    /// The chart coordinates of `other` around `self`: `(log(R' Rᵀ), t' − t)`.
    pub fn chart(&self, other: &OraclePose) -> Vector6<f64> {
        let w = log(&(other.r * self.r.transpose()));
        let d = other.t - self.t;
        Vector6::new(w.x, w.y, w.z, d.x, d.y, d.z)
    }

    pub fn to_library(self) -> pluecker::Pose {
        pluecker::Pose::new(self.r, self.t)
    }

    pub fn of(p: &pluecker::Pose) -> Self {
        OraclePose::new(p.rotation, p.translation)
    }
}

/// `exp` of a rotation vector (Rodrigues, through nalgebra).
pub fn exp(w: &Vector3<f64>) -> Matrix3<f64> {
    Rotation3::new(*w).into_inner()
}

/// The rotation vector of `r` (`‖ω‖ ≤ π`).
pub fn log(r: &Matrix3<f64>) -> Vector3<f64> {
    Rotation3::from_matrix(r).scaled_axis()
}

/// The pixel of the camera-frame point `x`.
pub fn pixel(k: &Camera, x: &Vector3<f64>) -> Vector2<f64> {
    Vector2::new(
        (k.intrinsics().fx * x.x + k.intrinsics().skew * x.y) / x.z + k.intrinsics().cx,
        k.intrinsics().fy * x.y / x.z + k.intrinsics().cy,
    )
}

/// The residuals, two per point, then two per segment. With per-observation noise
/// (`corr.noise`), a point's pixel error is multiplied by its whitening `W` and a segment endpoint's
/// distance to the projected line is divided by the standard deviation `√(nᵀ C n)` of its
/// covariance `C` across the line (`n` the line's unit normal).
pub fn residuals(k: &Camera, corr: &Correspondences, pose: &OraclePose) -> Vec<f64> {
    let mut out = Vec::with_capacity(2 * (corr.points2d.len() + corr.lines2d.len()));
    for (i, (u, x)) in corr.points2d.iter().zip(&corr.points3d).enumerate() {
        let mut e = pixel(k, &(pose.r * x + pose.t)) - u;
        if let Some(noise) = &corr.noise {
            e = noise.points[i] * e;
        }
        out.push(e.x);
        out.push(e.y);
    }
    for (i, (seen, ends)) in corr.lines2d.iter().zip(&corr.lines3d).enumerate() {
        let [a, b] = ends.map(|e| pixel(k, &(pose.r * e + pose.t)));
        // The line through a and b: n · (x − a) = 0 with n ⟂ (b − a).
        let d = b - a;
        let n = Vector2::new(-d.y, d.x) / d.norm();
        for (j, e) in seen.iter().enumerate() {
            let sigma = corr
                .noise
                .as_ref()
                .map_or(1.0, |noise| n.dot(&(noise.lines[i][j] * n)).sqrt());
            out.push(n.dot(&(e - a)) / sigma);
        }
    }
    out
}

/// `½ Σ r²`, px².
pub fn cost(k: &Camera, corr: &Correspondences, pose: &OraclePose) -> f64 {
    0.5 * residuals(k, corr, pose).iter().map(|r| r * r).sum::<f64>()
}

/// Whether every object point is in front of the camera (`z > 0`), the domain of the certificate.
pub fn points_in_front(corr: &Correspondences, pose: &OraclePose) -> bool {
    corr.points3d.iter().all(|x| (pose.r * x + pose.t).z > 0.0)
}

/// Whether every object point and segment endpoint is in front.
pub fn all_in_front(corr: &Correspondences, pose: &OraclePose) -> bool {
    points_in_front(corr, pose) && corr.lines3d.iter().flatten().all(|x| (pose.r * x + pose.t).z > 0.0)
}

/// The Jacobian of the residuals in the chart `(ω, τ)`, by central differences (step `h`).
pub fn jacobian(k: &Camera, corr: &Correspondences, pose: &OraclePose, h: f64) -> DMatrix<f64> {
    let m = 2 * (corr.points2d.len() + corr.lines2d.len());
    let mut j = DMatrix::zeros(m, 6);
    for c in 0..6 {
        let mut d = Vector6::zeros();
        d[c] = h;
        let plus = residuals(k, corr, &pose.step(&d));
        let minus = residuals(k, corr, &pose.step(&-d));
        for i in 0..m {
            j[(i, c)] = (plus[i] - minus[i]) / (2.0 * h);
        }
    }
    j
}

/// `JᵀJ` at `pose` (numeric Jacobian).
pub fn information(k: &Camera, corr: &Correspondences, pose: &OraclePose) -> Matrix6<f64> {
    let j = jacobian(k, corr, pose, 1e-6);
    let jtj = j.transpose() * &j;
    Matrix6::from_fn(|r, c| jtj[(r, c)])
}

/// A local minimum of the cost from `start`: Levenberg-Marquardt with numeric Jacobians, until the
/// step or the relative decrease is at the rounding level.
pub fn minimise(k: &Camera, corr: &Correspondences, start: &OraclePose) -> (OraclePose, f64) {
    let mut pose = *start;
    let mut f = cost(k, corr, &pose);
    let mut lambda = 1e-3;
    for _ in 0..300 {
        let r = DVector::from_vec(residuals(k, corr, &pose));
        let j = jacobian(k, corr, &pose, 1e-7);
        let jtj = j.transpose() * &j;
        let g = j.transpose() * &r;
        let mut improved = false;
        for _ in 0..30 {
            let mut a = jtj.clone();
            for i in 0..6 {
                a[(i, i)] += lambda * (1.0 + jtj[(i, i)]);
            }
            let Some(step) = a.cholesky().map(|c| c.solve(&-&g)) else {
                lambda *= 10.0;
                continue;
            };
            let d = Vector6::from_fn(|i, _| step[i]);
            let next = pose.step(&d);
            let fn_ = cost(k, corr, &next);
            if fn_.is_finite() && fn_ < f {
                let decrease = f - fn_;
                pose = next;
                f = fn_;
                lambda = (lambda * 0.3).max(1e-12);
                improved = true;
                if decrease <= 1e-15 * f.max(1e-300) || d.norm() < 1e-14 {
                    return (pose, f);
                }
                break;
            }
            lambda *= 10.0;
        }
        if !improved {
            break;
        }
    }
    (pose, f)
}

/// Every object point (the points and the segments' endpoints) and their centroid.
fn object_points(corr: &Correspondences) -> (Vec<Vector3<f64>>, Vector3<f64>) {
    let all: Vec<Vector3<f64>> = corr
        .points3d
        .iter()
        .chain(corr.lines3d.iter().flatten())
        .copied()
        .collect();
    let centroid = all.iter().sum::<Vector3<f64>>() / all.len() as f64;
    (all, centroid)
}

/// Distinct local minima with every object point in front, cheapest first, from the truth and from
/// `starts` random rotations placing the object's centroid at `depth` on the optical axis.
pub fn many_start(
    k: &Camera,
    corr: &Correspondences,
    truth: &OraclePose,
    starts: usize,
    rng: &mut Rng,
) -> Vec<(OraclePose, f64)> {
    let (all, centroid) = object_points(corr);
    let depth = (truth.r * centroid + truth.t).z;
    let mut candidates = vec![*truth];
    for _ in 0..starts {
        let r = rng.rotation();
        candidates.push(OraclePose::new(r, Vector3::new(0.0, 0.0, depth) - r * centroid));
    }
    let mut minima: Vec<(OraclePose, f64)> = Vec::new();
    for start in candidates {
        let (pose, f) = minimise(k, corr, &start);
        if !(f.is_finite() && points_in_front(corr, &pose)) {
            continue;
        }
        let scale = all.iter().map(|x| (x - centroid).norm()).fold(0.0, f64::max);
        let same = minima.iter().position(|(m, _)| {
            let d = m.chart(&pose);
            Vector3::new(d[0], d[1], d[2]).norm() < 1e-5 && Vector3::new(d[3], d[4], d[5]).norm() < 1e-5 * scale
        });
        match same {
            Some(i) if minima[i].1 <= f => {}
            Some(i) => minima[i] = (pose, f),
            None => minima.push((pose, f)),
        }
    }
    minima.sort_by(|a, b| a.1.total_cmp(&b.1));
    minima
}

/// The correspondences with the object moved to its centroid (`X → X − c`), and that centroid: a pose
/// `(R, t)` of the original is `(R, t + R c)` of the centred one, with the same residuals.
pub fn centred(corr: &Correspondences) -> (Correspondences, Vector3<f64>) {
    let (_, c) = object_points(corr);
    let mut out = corr.clone();
    out.points3d.iter_mut().for_each(|x| *x -= c);
    out.lines3d.iter_mut().flatten().for_each(|x| *x -= c);
    (out, c)
}
