//! P3P: the absolute pose from three 2-D/3-D point correspondences, by the Lambda Twist method of
//! M. Persson and K. Nordberg, "Lambda Twist: An Accurate Fast Robust Perspective Three Point (P3P)
//! Solver", ECCV 2018.
//!
//! **Equations.** With unit bearings `yᵢ` (camera frame) and world points `xᵢ`, the unknowns are the
//! depths `λᵢ > 0` with `λᵢ yᵢ = R xᵢ + t`. A rigid motion keeps distances, so `R` and `t` drop out:
//! `‖λᵢ yᵢ − λⱼ yⱼ‖² = ‖xᵢ − xⱼ‖²`, i.e. with `aᵢⱼ = ‖xᵢ − xⱼ‖²` and `bᵢⱼ = yᵢ·yⱼ` (paper eq. 3)
//!
//! `λᵢ² − 2 bᵢⱼ λᵢ λⱼ + λⱼ² = aᵢⱼ`, written `Λᵀ Mᵢⱼ Λ = aᵢⱼ` for `ij ∈ {12, 13, 23}` (eq. 4).
//!
//! Lambda Twist (the paper's Algorithm 1) eliminates the scale: `D₁ = a₂₃ M₁₂ − a₁₂ M₂₃` and
//! `D₂ = a₂₃ M₁₃ − a₁₃ M₂₃` give two homogeneous conics `ΛᵀD₁Λ = ΛᵀD₂Λ = 0` in the projective plane of
//! `Λ`. Their pencil `D₀ = D₁ + γ D₂` is degenerate where `det(D₁ + γ D₂) = 0`, a cubic in `γ` with at
//! least one real root. A real degenerate member is a pair of lines through its vertex (the null vector
//! of `D₀`), and every solution lies on one of them. Each line meets a second conic of the pencil in at
//! most two points, and `Λᵀ(M₁₂ + M₁₃ + M₂₃)Λ = a₁₂ + a₁₃ + a₂₃` fixes the scale of each: hence **at
//! most four solutions** (two conics meet in four points, Bézout), the classical bound of Grunert (1841)
//! and Fischler & Bolles (CACM 1981). A few verified Gauss-Newton steps on eq. 4 polish the depths
//! (paper section 3.8), and the pose follows from the three camera-frame points `λᵢ yᵢ`.
//!
//! Where this implementation differs from the paper (same equations, different numerics):
//! - the correspondences are relabelled so that side 23 is the longest: a short side 23 makes `D₁` and
//!   `D₂` both nearly multiples of `M₂₃`, a nearly singular pencil (without the relabelling, rare
//!   instances lost up to 1e-4 in the pose where their conditioning allowed 1e-11, and nearly
//!   collinear ones up to 0.1);
//! - every real root of the cubic is tried and the member whose line pair is best conditioned is kept
//!   (largest `−σ₁σ₂ / (σ₁² + σ₂²)` of its two non-zero eigenvalues), and the cubic is solved in `γ` or
//!   `1/γ`, whichever keeps its leading coefficient the larger of `det D₁`, `det D₂`;
//! - each line is parametrised by its vertex and a unit direction (a binary quadratic in homogeneous
//!   form), never by a ratio of depths, so no coordinate that may vanish is divided by;
//! - the rotation maps an orthonormal triad of the world triangle onto that of the camera-frame
//!   triangle instead of inverting the matrix of the triangle's edges: it is a rotation to rounding
//!   error, and it is defined for every non-collinear triangle.
//!
//! **Degenerate cases.** Non-finite input, a zero bearing, or two coincident world points (`aᵢⱼ = 0`):
//! no solution. Collinear world points: the pose is fixed only up to a rotation about their line, so
//! exactly collinear points give no solution, and nearly collinear ones give finite poses whose
//! rotation about the line is ill-conditioned (error ∝ 1/relative height of the triangle), while the
//! points still reproject onto their bearings; the true solution then also nears its mirror image
//! across the plane of the camera centre and the line, a double root. Two equal bearings (two points on one ray) are
//! admissible; the residuals are evaluated in a form that keeps `1 − bᵢⱼ` accurate. The classical
//! near-degeneracy of P3P is the "danger cylinder" (Thompson 1966; Wolfe, Mathis, Sklair & Magee, IEEE
//! PAMI 13(1), 1991): with the camera centre on the right circular cylinder through the three points,
//! perpendicular to their plane, the Jacobian of eq. 4 is singular, two solutions merge, and accuracy
//! falls in proportion to the condition number of that Jacobian.

use super::polynomial::{binary_quadratic_roots, cubic_real_roots};
use nalgebra::{Matrix3, Vector3};

pub(crate) use super::Pose;

/// Gauss-Newton steps on eq. 4 (the paper's implementation takes 5; each is kept only if it lowers the
/// sum of squared residuals).
const REFINEMENT_STEPS: usize = 5;

/// A refined candidate is a solution if every residual of eq. 4 is at most this fraction of the largest
/// squared side `max aᵢⱼ`. Genuine solutions reach rounding level (about 1e-15; 1e-11 next to a double
/// root, where Newton's method slows down) after the refinement, which converges quadratically; the
/// points that a clamped (complex) line pair produces satisfy eq. 4 only to first order and stay above
/// 1e-6 (the smallest seen over 3·10⁵ random instances). A relative error of 1e-8 in squared sides is
/// 5e-9 in side lengths, far below any pixel noise, so near-real solutions of noisy samples are kept.
const RESIDUAL_TOLERANCE: f64 = 1e-8;

/// Two solutions whose depths agree to this fraction of the largest depth are one (a double root).
const DUPLICATE_TOLERANCE: f64 = 1e-10;

/// A degenerate member `D₀` (scaled to unit Frobenius norm) counts as rank one, a double line, when the
/// largest column of its adjugate is below this: rounding of the entries of `D₀` alone perturbs the
/// adjugate by a few `ε` ≈ 1e-16, so its null vector would carry no correct digit.
const RANK_ONE_TOLERANCE: f64 = 1e-13;

/// The pairs `ij` in the order of `a` and `b`: 12, 13, 23.
const PAIRS: [(usize, usize); 3] = [(0, 1), (0, 2), (1, 2)];

/// Every real pose `(R, t)` with `x_cam = R X_world + t` that puts the three world `points` on the rays
/// of the three camera-frame `bearings`, at positive depth: zero to four of them (eq. 4 of Persson &
/// Nordberg 2018; see the [module documentation](super) for the method and the degenerate cases).
///
/// `bearings[i]` is the direction of the ray to `points[i]` in the camera frame; it is normalised here,
/// so any positive multiple works. From a pixel `u` of a [`crate::camera::Intrinsics`] `cam`:
/// `let n = cam.pixel_to_normalized(&u); let y = Vector3::new(n.x, n.y, 1.0).normalize();`
/// (the camera looks down `+z`). `points` are in world units; the returned `t` is too.
///
/// Degenerate or invalid input (non-finite values, a zero bearing, coincident or exactly collinear
/// points) returns an empty vector, never panics. The solutions are in no particular order; a robust
/// estimator scores each one on the other correspondences.
///
/// ```
/// use nalgebra::{Rotation3, Vector3};
/// use pluecker::pose::minimal::p3p;
/// use pluecker::Camera;
///
/// let cam = Camera::pinhole(800.0, 790.0, 320.0, 240.0, 0.0).unwrap();
/// let rotation = Rotation3::from_euler_angles(0.1, -0.2, 0.3).into_inner();
/// let translation = Vector3::new(0.2, -0.1, 4.0);
/// let points = [Vector3::new(0.0, 0.0, 0.0), Vector3::new(1.0, 0.0, 0.5), Vector3::new(0.0, 1.0, -0.5)];
/// let bearings = points.map(|x| {
///     let pixel = cam.project(&(rotation * x + translation)); // what the image gives
///     let n = cam.unproject(&pixel, 0).unwrap();
///     Vector3::new(n.x, n.y, 1.0).normalize()
/// });
/// let poses = p3p(&bearings, &points);
/// assert!(!poses.is_empty() && poses.len() <= 4);
/// assert!(poses.iter().any(|p| (p.rotation - rotation).norm() < 1e-9 && (p.translation - translation).norm() < 1e-9));
/// ```
pub fn p3p(bearings: &[Vector3<f64>; 3], points: &[Vector3<f64>; 3]) -> Vec<Pose> {
    let Some(problem) = Problem::new(bearings, points) else {
        return Vec::new();
    };
    let mut depths: Vec<Vector3<f64>> = Vec::with_capacity(4);
    for candidate in problem.candidate_depths() {
        let Some(lambda) = problem.refine(candidate) else {
            continue;
        };
        if !depths
            .iter()
            .any(|d| (d - lambda).amax() <= DUPLICATE_TOLERANCE * d.amax())
        {
            depths.push(lambda);
        }
    }
    depths.iter().filter_map(|lambda| problem.pose(lambda)).collect()
}

/// How far from orthonormal a returned rotation may be (it is orthonormal to rounding by construction).
const ROTATION_TOLERANCE: f64 = 1e-9;

/// The data of eq. 4, conditioned: squared sides divided by the largest one.
struct Problem {
    /// Unit bearings, relabelled so that side 23 is the longest.
    y: [Vector3<f64>; 3],
    /// World points, in the same order.
    x: [Vector3<f64>; 3],
    /// `√a₂₃ = √max aᵢⱼ` (world units); depths are computed in this unit.
    scale: f64,
    /// `aᵢⱼ / scale²` in the order of [`PAIRS`]; `a₂₃ = 1`.
    a: [f64; 3],
    /// `bᵢⱼ = yᵢ·yⱼ`.
    b: [f64; 3],
    /// `1 − bᵢⱼ = ‖yᵢ − yⱼ‖²/2`, accurate when the bearings nearly coincide.
    one_minus_b: [f64; 3],
    /// Orthonormal triad of the world triangle (columns).
    world_triad: Matrix3<f64>,
}

impl Problem {
    fn new(bearings: &[Vector3<f64>; 3], points: &[Vector3<f64>; 3]) -> Option<Problem> {
        if bearings.iter().chain(points).any(|v| v.iter().any(|c| !c.is_finite())) {
            return None;
        }
        // Relabel so that the longest side is 23: with a₂₃ the largest, D₁ and D₂ are far from
        // proportional (a short side 23 makes both nearly multiples of M₂₃, an ill-conditioned pencil).
        let opposite = (0..3)
            .max_by(|&p, &q| {
                let side = |v: usize| (points[(v + 1) % 3] - points[(v + 2) % 3]).norm_squared();
                side(p).total_cmp(&side(q))
            })
            .unwrap_or(0);
        let order = [opposite, (opposite + 1) % 3, (opposite + 2) % 3];
        let x = order.map(|i| points[i]);
        let mut y = [Vector3::zeros(); 3];
        for (yi, &i) in y.iter_mut().zip(&order) {
            let n = bearings[i].norm();
            if !(n > 0.0 && n.is_finite()) {
                return None;
            }
            *yi = bearings[i] / n;
        }
        let squared = PAIRS.map(|(i, j)| (x[i] - x[j]).norm_squared());
        let max = squared[2];
        if !max.is_finite() || squared.iter().any(|&s| !(s > 0.0)) {
            return None;
        }
        let world_triad = triad(&x, PAIRS[2])?;
        Some(Problem {
            y,
            x,
            scale: max.sqrt(),
            a: squared.map(|s| s / max),
            b: PAIRS.map(|(i, j)| y[i].dot(&y[j])),
            one_minus_b: PAIRS.map(|(i, j)| 0.5 * (y[i] - y[j]).norm_squared()),
            world_triad,
        })
    }

    /// `Mᵢⱼ` of eq. 4 for the `k`-th pair.
    fn m(&self, k: usize) -> Matrix3<f64> {
        let (i, j) = PAIRS[k];
        let mut m = Matrix3::zeros();
        m[(i, i)] = 1.0;
        m[(j, j)] = 1.0;
        m[(i, j)] = -self.b[k];
        m[(j, i)] = -self.b[k];
        m
    }

    /// Unrefined depths (conditioned units) from the line pair of the best degenerate member.
    fn candidate_depths(&self) -> Vec<Vector3<f64>> {
        let [a12, a13, a23] = self.a;
        let [m12, m13, m23] = [self.m(0), self.m(1), self.m(2)];
        let d1 = m12 * a23 - m23 * a12;
        let d2 = m13 * a23 - m23 * a13;
        let Some(d0) = best_degenerate_member(&d1, &d2) else {
            return Vec::new();
        };
        let other = orthogonal_member(&d0, &d1, &d2);
        let sum_m = m12 + m13 + m23;
        let sum_a = a12 + a13 + a23;
        let mut out = Vec::with_capacity(4);
        for (p, w) in line_pair(&d0) {
            let form = |u: &Vector3<f64>, v: &Vector3<f64>| u.dot(&(other * v));
            for ab in binary_quadratic_roots(form(&p, &p), form(&p, &w), form(&w, &w)) {
                let mut d = p * ab.x + w * ab.y;
                if d.sum() < 0.0 {
                    d = -d;
                }
                let k = d.dot(&(sum_m * d));
                if k > 0.0 {
                    out.push(d * (sum_a / k).sqrt());
                }
            }
        }
        out
    }

    /// Residuals `ΛᵀMᵢⱼΛ − aᵢⱼ` of eq. 4, as `(λᵢ − λⱼ)² + 2(1 − bᵢⱼ)λᵢλⱼ − aᵢⱼ`.
    fn residuals(&self, l: &Vector3<f64>) -> Vector3<f64> {
        Vector3::from_fn(|k, _| {
            let (i, j) = PAIRS[k];
            let diff = l[i] - l[j];
            diff * diff + 2.0 * self.one_minus_b[k] * l[i] * l[j] - self.a[k]
        })
    }

    /// The Jacobian of [`Problem::residuals`].
    fn jacobian(&self, l: &Vector3<f64>) -> Matrix3<f64> {
        let mut jac = Matrix3::zeros();
        for (k, &(i, j)) in PAIRS.iter().enumerate() {
            jac[(k, i)] = 2.0 * (l[i] - self.b[k] * l[j]);
            jac[(k, j)] = 2.0 * (l[j] - self.b[k] * l[i]);
        }
        jac
    }

    /// Verified Gauss-Newton steps on eq. 4 (a square system: the step is `−J⁻¹ r`); the depths if they
    /// are positive and satisfy eq. 4 to [`RESIDUAL_TOLERANCE`].
    fn refine(&self, mut lambda: Vector3<f64>) -> Option<Vector3<f64>> {
        let mut r = self.residuals(&lambda);
        let mut cost = r.norm_squared();
        for _ in 0..REFINEMENT_STEPS {
            if !(cost > 0.0) {
                break;
            }
            let Some(inverse) = self.jacobian(&lambda).try_inverse() else {
                break;
            };
            let next = lambda - inverse * r;
            let r_next = self.residuals(&next);
            let cost_next = r_next.norm_squared();
            if !(cost_next < cost) {
                break;
            }
            (lambda, r, cost) = (next, r_next, cost_next);
        }
        let valid = lambda.iter().all(|&v| v > 0.0 && v.is_finite()) && r.amax() <= RESIDUAL_TOLERANCE;
        valid.then_some(lambda)
    }

    /// `(R, t)` mapping the world triangle onto the camera-frame points `λᵢ yᵢ` (world units).
    fn pose(&self, lambda: &Vector3<f64>) -> Option<Pose> {
        let cam: [Vector3<f64>; 3] = std::array::from_fn(|i| self.y[i] * (lambda[i] * self.scale));
        let rotation = triad(&cam, PAIRS[2])? * self.world_triad.transpose();
        let centroid = |p: &[Vector3<f64>; 3]| (p[0] + p[1] + p[2]) / 3.0;
        let translation = centroid(&cam) - rotation * centroid(&self.x);
        let finite = rotation.iter().chain(translation.iter()).all(|v| v.is_finite());
        // The two triads are orthonormal, so is their product; a flat camera-side triangle (points on one
        // ray) is the one way to lose that, and such a pose explains nothing.
        let orthonormal = (rotation * rotation.transpose() - Matrix3::identity()).amax() <= ROTATION_TOLERANCE
            && rotation.determinant() > 0.0;
        (finite && orthonormal).then_some(Pose::new(rotation, translation))
    }
}

/// Orthonormal frame (columns) of a triangle: first axis along side `pair`, second towards the third
/// vertex (Gram-Schmidt, so the frame is orthonormal to rounding however thin the triangle), third
/// along the normal. `None` when the triangle is flat (exactly collinear or coincident vertices).
pub(super) fn triad(p: &[Vector3<f64>; 3], pair: (usize, usize)) -> Option<Matrix3<f64>> {
    let (i, j) = pair;
    let k = 3 - i - j;
    let side = p[j] - p[i];
    let side_norm = side.norm();
    if !(side_norm > 0.0 && side_norm.is_finite()) {
        return None;
    }
    let f1 = side / side_norm;
    // Two Gram-Schmidt passes: after one, a nearly parallel side leaves a remainder that is itself
    // mostly rounding error and not orthogonal to `f1`; the second pass makes it so ("twice is enough").
    let mut height = p[k] - p[i];
    for _ in 0..2 {
        height -= f1 * f1.dot(&height);
    }
    let height_norm = height.norm();
    if !(height_norm > 0.0 && height_norm.is_finite()) {
        return None;
    }
    let f2 = height / height_norm;
    Some(Matrix3::from_columns(&[f1, f2, f1.cross(&f2)]))
}

/// The adjugate of a symmetric 3x3 matrix (symmetric too): `adj(M) M = det(M) I`.
fn adjugate(m: &Matrix3<f64>) -> Matrix3<f64> {
    let c = |r0: usize, r1: usize, c0: usize, c1: usize| m[(r0, c0)] * m[(r1, c1)] - m[(r0, c1)] * m[(r1, c0)];
    let (a00, a11, a22) = (c(1, 2, 1, 2), c(0, 2, 0, 2), c(0, 1, 0, 1));
    let (a01, a02, a12) = (-c(0, 2, 1, 2), c(0, 1, 1, 2), -c(0, 1, 0, 2));
    Matrix3::new(a00, a01, a02, a01, a11, a12, a02, a12, a22)
}

/// The degenerate member `D₁ + γ D₂` (or `D₂ + γ D₁`) of the pencil whose line pair is best conditioned,
/// scaled to unit Frobenius norm. `det(P + γQ) = det Q γ³ + tr(adj(Q) P) γ² + tr(adj(P) Q) γ + det P`.
fn best_degenerate_member(d1: &Matrix3<f64>, d2: &Matrix3<f64>) -> Option<Matrix3<f64>> {
    let (det1, det2) = (d1.determinant(), d2.determinant());
    let (p, q) = if det2.abs() >= det1.abs() { (d1, d2) } else { (d2, d1) };
    let (det_p, det_q) = (p.determinant(), q.determinant());
    let coefficients = [det_q, (adjugate(q) * p).trace(), (adjugate(p) * q).trace(), det_p];
    let roots = if det_q == 0.0 {
        vec![0.0]
    } else {
        cubic_real_roots(coefficients)
    };
    roots
        .into_iter()
        .filter_map(|gamma| {
            let member = p + q * gamma;
            let norm = member.norm();
            (norm > 0.0 && norm.is_finite()).then(|| member / norm)
        })
        .map(|member| (line_pair_conditioning(&member), member))
        .max_by(|x, y| x.0.total_cmp(&y.0))
        .map(|(_, member)| member)
}

/// `−σ₁σ₂ / (σ₁² + σ₂²)` of a rank-two symmetric matrix of unit Frobenius norm with non-zero eigenvalues
/// `σ₁, σ₂`: `σ₁σ₂` is the sum of the principal 2x2 minors. In `(0, ½]` for a real line pair, ½ for two
/// perpendicular lines, 0 for a double line, negative for a complex pair (a single real point).
fn line_pair_conditioning(m: &Matrix3<f64>) -> f64 {
    let minor = |i: usize, j: usize| m[(i, i)] * m[(j, j)] - m[(i, j)] * m[(i, j)];
    -(minor(0, 1) + minor(0, 2) + minor(1, 2))
}

/// The member of the pencil orthogonal (Frobenius inner product) to `d0`, of `d1`'s or `d2`'s scale:
/// the second conic that each line of `d0` is intersected with.
fn orthogonal_member(d0: &Matrix3<f64>, d1: &Matrix3<f64>, d2: &Matrix3<f64>) -> Matrix3<f64> {
    let reject = |d: &Matrix3<f64>| {
        let r = d - d0 * d.dot(d0);
        let relative = r.norm() / d.norm();
        (relative, r)
    };
    let (r1, r2) = (reject(d1), reject(d2));
    if r1.0 >= r2.0 || r2.0.is_nan() {
        r1.1
    } else {
        r2.1
    }
}

/// The lines of the degenerate conic `d0` (unit Frobenius norm), each as `(p, w)`: two orthonormal
/// vectors spanning it. For a rank-two `d0`, `p` is its vertex, and the lines through it solve the
/// binary quadratic of `d0` restricted to the plane orthogonal to `p` (a complex pair is clamped to its
/// double line, as in the paper; the residual test rejects what it produces). For a rank-one `d0`, the
/// double line is its null space.
fn line_pair(d0: &Matrix3<f64>) -> Vec<(Vector3<f64>, Vector3<f64>)> {
    let adj = adjugate(d0);
    let column = (0..3)
        .map(|c| adj.column(c).into_owned())
        .max_by(|u, v| u.norm().total_cmp(&v.norm()));
    let column = column.unwrap_or_else(Vector3::zeros);
    let norm = column.norm();
    if norm > RANK_ONE_TOLERANCE {
        let vertex = column / norm;
        let (u, v) = orthonormal_complement(&vertex);
        let form = |s: &Vector3<f64>, t: &Vector3<f64>| s.dot(&(d0 * t));
        binary_quadratic_roots(form(&u, &u), form(&u, &v), form(&v, &v))
            .into_iter()
            .map(|dir| (vertex, u * dir.x + v * dir.y))
            .collect()
    } else {
        let row = (0..3)
            .map(|r| d0.row(r).transpose())
            .max_by(|u, v| u.norm().total_cmp(&v.norm()));
        match row {
            Some(normal) if normal.norm() > 0.0 => vec![orthonormal_complement(&normal.normalize())],
            _ => Vec::new(),
        }
    }
}

/// Two unit vectors completing the unit vector `n` to an orthonormal basis.
fn orthonormal_complement(n: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let axis = (0..3).min_by(|&i, &j| n[i].abs().total_cmp(&n[j].abs())).unwrap_or(0);
    let u = n.cross(&Vector3::ith(axis, 1.0)).normalize();
    (u, n.cross(&u))
}

#[cfg(test)]
mod tests;
