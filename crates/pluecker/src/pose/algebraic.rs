//! The dual-quaternion costs of Phong & Horaud 1995: eqs. 13 and 22 (rotation and translation
//! together), eq. 14 (rotation alone) and eq. 15 (translation given the rotation).
//!
//! Every constraint of the paper is linear in the 12 numbers
//! `y(x) = [vec R̃(r); t̃(r, s)]`, where `R̃(r)` is the lower block of `W(r)ᵀQ(r)` (eq. 6, `= |r|² R`)
//! and `t̃ = 2 W(r)ᵀ s` (eq. 7). Indeed, with `m = (1, 0, −x)` or `(0, 1, −y)`:
//! - point, eqs. 20-21: `rᵀAᵖr + 2rᵀBᵖs = mᵀ(R̃ M + t̃)`, coefficient vector `c = [m ⊗ M; m]`;
//! - line direction, eq. 10: `rᵀA r = nᵀ R̃ v`, `c = [n ⊗ v; 0]`;
//! - line point, eq. 12: `rᵀB r + rᵀC s = nᵀ(R̃ p + t̃)`, `c = [n ⊗ p; n]`.
//!
//! So `Σⱼ Φⱼ² = yᵀ G y` with the 12x12 Gram matrix `G = Σⱼ cⱼcⱼᵀ`, built once. The costs, their
//! gradients `JᵀΦ = Yᵀ G y` and Gauss-Newton Hessians `JᵀJ = Yᵀ G Y` (`Y = ∂y/∂x`) are then exactly the
//! paper's, at a cost per iteration independent of the number of correspondences. The penalty terms
//! `λ(rᵀr − 1)²` and `λ(rᵀs)²` are added as two more residuals `√λ(rᵀr − 1)`, `√λ rᵀs`.
//! All costs follow eq. 23's convention `f = ½ Σ Φ²`.

use crate::geometry::lines::ObjectLine;
use crate::geometry::quaternion::{scaled_rotation, w_matrix};
use crate::optim::{Linearization, Objective};
use nalgebra::{Matrix4, SMatrix, SVector, Vector2, Vector3, Vector4};

/// The 12-vector `y = [vec R̃ (row-major); t̃]`.
pub type Lifted = SVector<f64, 12>;
/// Gram matrix of the constraint coefficients.
pub type Gram = SMatrix<f64, 12, 12>;

/// A point correspondence in the frames the costs use: normalised image coordinates, object point.
#[derive(Debug, Clone, Copy)]
pub struct PointConstraint {
    pub image: Vector2<f64>,
    pub object: Vector3<f64>,
}

/// A line correspondence: interpretation-plane normal (camera frame), object line (object frame).
#[derive(Debug, Clone, Copy)]
pub struct LineConstraint {
    pub normal: Vector3<f64>,
    pub object: ObjectLine,
}

fn coefficients(m: &Vector3<f64>, object: &Vector3<f64>, translation_weight: f64) -> Lifted {
    let mut c = Lifted::zeros();
    for a in 0..3 {
        for b in 0..3 {
            c[3 * a + b] = m[a] * object[b];
        }
        c[9 + a] = translation_weight * m[a];
    }
    c
}

fn add_rank_one(g: &mut Gram, c: &Lifted) {
    for i in 0..12 {
        if c[i] != 0.0 {
            for j in i..12 {
                g[(i, j)] += c[i] * c[j];
            }
        }
    }
}

fn symmetrize(mut g: Gram) -> Gram {
    for i in 0..12 {
        for j in 0..i {
            g[(i, j)] = g[(j, i)];
        }
    }
    g
}

/// Adds the two constraints of every point (eqs. 20-21) to `g` (upper triangle).
///
/// With `h = (M, 1)` the coefficient vectors are `c_x = [h at (0,1,2,9); −x h at (6,7,8,11)]` and
/// `c_y = [h at (3,4,5,10); −y h at (6,7,8,11)]`, so `G` needs only the moments `Σ h hᵀ`,
/// `Σ x h hᵀ`, `Σ y h hᵀ` and `Σ (x² + y²) h hᵀ`: 40 products per point instead of two rank-one updates.
fn add_points(g: &mut Gram, points: &[PointConstraint]) {
    // Accumulated in LANES interleaved partial sums (lane l takes points l, l + LANES, …) so that the
    // compiler can process several points per vector instruction.
    const LANES: usize = 4;
    let mut lanes = [[[0.0f64; LANES]; 10]; 4];
    let mut add = |lane: usize, p: &PointConstraint| {
        let h = [p.object.x, p.object.y, p.object.z, 1.0];
        let (x, y) = (p.image.x, p.image.y);
        let weights = [1.0, x, y, x * x + y * y];
        let mut k = 0;
        for i in 0..4 {
            for j in i..4 {
                let hh = h[i] * h[j];
                for (m, w) in lanes.iter_mut().zip(weights) {
                    m[k][lane] += w * hh;
                }
                k += 1;
            }
        }
    };
    let mut batches = points.chunks_exact(LANES);
    for batch in &mut batches {
        for (lane, p) in batch.iter().enumerate() {
            add(lane, p);
        }
    }
    for p in batches.remainder() {
        add(0, p);
    }
    let moments: [[f64; 10]; 4] = std::array::from_fn(|w| std::array::from_fn(|k| lanes[w][k].iter().sum()));
    const A: [usize; 4] = [0, 1, 2, 9];
    const B: [usize; 4] = [3, 4, 5, 10];
    const C: [usize; 4] = [6, 7, 8, 11];
    let at = |m: &[f64; 10], i: usize, j: usize| {
        let (i, j) = if i <= j { (i, j) } else { (j, i) };
        m[i * 4 - i * (i + 1) / 2 + j]
    };
    let [s0, sx, sy, sq] = &moments;
    for i in 0..4 {
        for j in 0..4 {
            let mut add = |r: usize, c: usize, v: f64| {
                if r <= c {
                    g[(r, c)] += v;
                }
            };
            add(A[i], A[j], at(s0, i, j));
            add(B[i], B[j], at(s0, i, j));
            add(C[i], C[j], at(sq, i, j));
            add(A[i], C[j], -at(sx, i, j));
            add(C[j], A[i], -at(sx, i, j));
            add(B[i], C[j], -at(sy, i, j));
            add(C[j], B[i], -at(sy, i, j));
        }
    }
}

/// `G` for the constraints of points (eqs. 20-21) and lines (eqs. 10 and 12).
/// `line_directions = false` leaves out the direction constraints (eq. 15 uses only the others).
pub fn gram(points: &[PointConstraint], lines: &[LineConstraint], line_directions: bool) -> Gram {
    let mut g = Gram::zeros();
    add_points(&mut g, points);
    for l in lines {
        if line_directions {
            add_rank_one(&mut g, &coefficients(&l.normal, &l.object.direction, 0.0));
        }
        add_rank_one(&mut g, &coefficients(&l.normal, &l.object.point, 1.0));
    }
    symmetrize(g)
}

/// `y(x)` for `x = (r, s)`.
pub fn lift(x: &SVector<f64, 8>) -> Lifted {
    let r: Vector4<f64> = x.fixed_rows::<4>(0).into_owned();
    let s: Vector4<f64> = x.fixed_rows::<4>(4).into_owned();
    let rt = scaled_rotation(&r);
    let t = 2.0 * w_matrix(&r).transpose() * s;
    let mut y = Lifted::zeros();
    for a in 0..3 {
        for b in 0..3 {
            y[3 * a + b] = rt[(a, b)];
        }
        y[9 + a] = t[a + 1];
    }
    y
}

/// `∂ vec R̃ / ∂r` (9x4), row-major in `R̃`.
pub fn scaled_rotation_jacobian(r: &Vector4<f64>) -> SMatrix<f64, 9, 4> {
    let (w, x, y, z) = (2.0 * r[0], 2.0 * r[1], 2.0 * r[2], 2.0 * r[3]);
    SMatrix::<f64, 9, 4>::from_row_slice(&[
        w, x, -y, -z, //
        -z, y, x, -w, //
        y, z, w, x, //
        z, y, x, w, //
        w, -x, y, -z, //
        -x, -w, z, y, //
        -y, z, -w, x, //
        x, w, z, y, //
        w, -x, -y, z,
    ])
}

/// `Y = ∂y/∂x` (12x8). Linear in `x`, so `Y(x) = Σₖ xₖ Y(eₖ)`.
pub fn lift_jacobian(x: &SVector<f64, 8>) -> SMatrix<f64, 12, 8> {
    let r: Vector4<f64> = x.fixed_rows::<4>(0).into_owned();
    let mut jac = SMatrix::<f64, 12, 8>::zeros();
    jac.fixed_view_mut::<9, 4>(0, 0)
        .copy_from(&scaled_rotation_jacobian(&r));
    // t̃ = 2 (s r̄) = 2 Q(s) C r with C = diag(1, −1, −1, −1), and = 2 W(r)ᵀ s: rows 1-3 of
    // 2 Q(s) C and of 2 W(r)ᵀ (eqs. 8-9), written out.
    let (s0, s1, s2, s3) = (2.0 * x[4], 2.0 * x[5], 2.0 * x[6], 2.0 * x[7]);
    let (r0, r1, r2, r3) = (2.0 * r[0], 2.0 * r[1], 2.0 * r[2], 2.0 * r[3]);
    let dt_dr = [[s1, -s0, s3, -s2], [s2, -s3, -s0, s1], [s3, s2, -s1, -s0]];
    let dt_ds = [[-r1, r0, -r3, r2], [-r2, r3, r0, -r1], [-r3, -r2, r1, r0]];
    for i in 0..3 {
        for j in 0..4 {
            jac[(9 + i, j)] = dt_dr[i][j];
            jac[(9 + i, 4 + j)] = dt_ds[i][j];
        }
    }
    jac
}

/// Eqs. 13 and 22 (and their sum for mixed data): rotation and translation together, `x = (r, s)`.
#[derive(Debug, Clone)]
pub struct JointCost {
    /// `G = Σ cⱼcⱼᵀ` over every point and line constraint.
    pub gram: Gram,
    /// Penalty weight λ of the rigidity constraints (paper: 50).
    pub lambda: f64,
}

impl JointCost {
    fn penalties(&self, x: &SVector<f64, 8>) -> [(f64, SVector<f64, 8>); 2] {
        let sl = self.lambda.sqrt();
        let r = x.fixed_rows::<4>(0);
        let s = x.fixed_rows::<4>(4);
        let mut g1 = SVector::<f64, 8>::zeros();
        g1.fixed_rows_mut::<4>(0).copy_from(&(2.0 * sl * r));
        let mut g2 = SVector::<f64, 8>::zeros();
        g2.fixed_rows_mut::<4>(0).copy_from(&(sl * s));
        g2.fixed_rows_mut::<4>(4).copy_from(&(sl * r));
        [(sl * (r.norm_squared() - 1.0), g1), (sl * r.dot(&s), g2)]
    }
}

impl Objective<8> for JointCost {
    type Point = SVector<f64, 8>;

    fn cost(&self, x: &Self::Point) -> f64 {
        let y = lift(x);
        let [(p1, _), (p2, _)] = self.penalties(x);
        0.5 * (y.dot(&(self.gram * y)) + p1 * p1 + p2 * p2)
    }

    fn linearize(&self, x: &Self::Point) -> Linearization<8> {
        // Y = ∂y/∂x = [[Yr, 0], [Tr, Ts]] (9 + 3 rows, 4 + 4 columns): the rotation entries of y do not
        // depend on s. So G Y = [G Y₀, G₉ Ts] with Y₀ its first four columns and G₉ the last three
        // columns of G, and JᵀJ = Yᵀ G Y is assembled from the blocks, about half the products of the
        // dense 12x8 form.
        let y = lift(x);
        let jy = lift_jacobian(x);
        let y0 = jy.fixed_view::<12, 4>(0, 0);
        let ts = jy.fixed_view::<3, 4>(9, 4);
        let gy = self.gram * y;
        let gy0 = self.gram * y0;
        let gts = self.gram.fixed_view::<12, 3>(0, 9) * ts;
        let mut gradient = SVector::<f64, 8>::zeros();
        gradient.fixed_rows_mut::<4>(0).copy_from(&(y0.transpose() * gy));
        gradient
            .fixed_rows_mut::<4>(4)
            .copy_from(&(ts.transpose() * gy.fixed_rows::<3>(9)));
        let rs = y0.transpose() * gts;
        let mut gauss_newton = SMatrix::<f64, 8, 8>::zeros();
        gauss_newton
            .fixed_view_mut::<4, 4>(0, 0)
            .copy_from(&(y0.transpose() * gy0));
        gauss_newton.fixed_view_mut::<4, 4>(0, 4).copy_from(&rs);
        gauss_newton.fixed_view_mut::<4, 4>(4, 0).copy_from(&rs.transpose());
        gauss_newton
            .fixed_view_mut::<4, 4>(4, 4)
            .copy_from(&(ts.transpose() * gts.fixed_rows::<3>(9)));
        let mut cost = y.dot(&gy);
        for (phi, grad) in self.penalties(x) {
            cost += phi * phi;
            gradient += phi * grad;
            gauss_newton += grad * grad.transpose();
        }
        Linearization {
            cost: 0.5 * cost,
            gradient,
            gauss_newton,
        }
    }

    fn exact_hessian(&self, x: &Self::Point) -> Option<SMatrix<f64, 8, 8>> {
        let mut h = self.linearize(x).gauss_newton;
        // Σᵢ (G y)ᵢ ∇²yᵢ: column k is Y(eₖ)ᵀ G y since Y is linear in x.
        let w = self.gram * lift(x);
        for k in 0..8 {
            let ek = SVector::<f64, 8>::from_fn(|i, _| if i == k { 1.0 } else { 0.0 });
            let col = lift_jacobian(&ek).transpose() * w;
            for i in 0..8 {
                h[(i, k)] += col[i];
            }
        }
        let sl = self.lambda.sqrt();
        let [(p1, _), (p2, _)] = self.penalties(x);
        for i in 0..4 {
            h[(i, i)] += p1 * 2.0 * sl;
            h[(i, i + 4)] += p2 * sl;
            h[(i + 4, i)] += p2 * sl;
        }
        Some(h)
    }

    fn retract(&self, x: &Self::Point, d: &SVector<f64, 8>) -> Self::Point {
        x + d
    }
}

/// Eq. 14: the rotation alone from line-direction constraints, `x = r`.
#[derive(Debug, Clone)]
pub struct RotationCost {
    /// The 9x9 upper-left block of `G` built from direction constraints only.
    pub gram: SMatrix<f64, 9, 9>,
    /// Penalty weight λ.
    pub lambda: f64,
}

impl RotationCost {
    /// The rotation cost of the given line constraints.
    pub fn new(lines: &[LineConstraint], lambda: f64) -> Self {
        let mut g = Gram::zeros();
        for l in lines {
            add_rank_one(&mut g, &coefficients(&l.normal, &l.object.direction, 0.0));
        }
        RotationCost {
            gram: symmetrize(g).fixed_view::<9, 9>(0, 0).into_owned(),
            lambda,
        }
    }
}

fn vec_rotation(r: &Vector4<f64>) -> SVector<f64, 9> {
    let rt = scaled_rotation(r);
    SVector::<f64, 9>::from_fn(|i, _| rt[(i / 3, i % 3)])
}

impl Objective<4> for RotationCost {
    type Point = Vector4<f64>;

    fn cost(&self, r: &Vector4<f64>) -> f64 {
        let y = vec_rotation(r);
        let p = self.lambda.sqrt() * (r.norm_squared() - 1.0);
        0.5 * (y.dot(&(self.gram * y)) + p * p)
    }

    fn linearize(&self, r: &Vector4<f64>) -> Linearization<4> {
        let y = vec_rotation(r);
        let jy = scaled_rotation_jacobian(r);
        let gy = self.gram * y;
        let sl = self.lambda.sqrt();
        let p = sl * (r.norm_squared() - 1.0);
        let gp = 2.0 * sl * r;
        Linearization {
            cost: 0.5 * (y.dot(&gy) + p * p),
            gradient: jy.transpose() * gy + p * gp,
            gauss_newton: jy.transpose() * self.gram * jy + gp * gp.transpose(),
        }
    }

    fn exact_hessian(&self, r: &Vector4<f64>) -> Option<Matrix4<f64>> {
        let mut h = self.linearize(r).gauss_newton;
        let w = self.gram * vec_rotation(r);
        for k in 0..4 {
            let ek = Vector4::from_fn(|i, _| if i == k { 1.0 } else { 0.0 });
            let col = scaled_rotation_jacobian(&ek).transpose() * w;
            for i in 0..4 {
                h[(i, k)] += col[i];
            }
        }
        let p = self.lambda.sqrt() * (r.norm_squared() - 1.0);
        h += Matrix4::identity() * (2.0 * self.lambda.sqrt() * p);
        Some(h)
    }

    fn retract(&self, r: &Vector4<f64>, d: &Vector4<f64>) -> Vector4<f64> {
        r + d
    }
}

/// Eq. 15: the dual part `s` minimising `Σ (rᵀBᵢr + rᵀCᵢs)² + λ(rᵀs)²` for a fixed `r` — a linear
/// least-squares problem in `s`. `gram` is built without line-direction constraints (those do not
/// involve `s`); point constraints (eqs. 20-21) are linear in `s` too and may be included.
/// Returns `None` if the normal equations are singular (too few independent constraints).
pub fn solve_translation(gram: &Gram, r: &Vector4<f64>, lambda: f64) -> Option<Vector4<f64>> {
    // y = [vec R̃; A s] with A = rows 1..3 of 2W(r)ᵀ: minimise [v; A s]ᵀ G [v; A s] + λ (rᵀs)².
    let v = vec_rotation(r);
    let a: SMatrix<f64, 3, 4> = (2.0 * w_matrix(r).transpose()).fixed_view::<3, 4>(1, 0).into_owned();
    let g_tt = gram.fixed_view::<3, 3>(9, 9);
    let g_tr = gram.fixed_view::<3, 9>(9, 0);
    let normal = a.transpose() * g_tt * a + lambda * r * r.transpose();
    let rhs = -(a.transpose() * (g_tr * v));
    normal.cholesky().map(|c| c.solve(&rhs))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::dual_quaternion::DualQuaternion;
    use crate::geometry::quaternion::{pure, q_matrix, vector_part};
    use crate::optim::problem::testing::{gradient_error, hessian_error};
    use crate::rng::Rng;

    fn random_problem(rng: &mut Rng) -> (Vec<PointConstraint>, Vec<LineConstraint>) {
        let rot = rng.rotation();
        let t = Vector3::new(rng.normal(), rng.normal(), 6.0);
        let points = (0..8)
            .map(|_| {
                let x = Vector3::new(rng.normal(), rng.normal(), rng.normal());
                let c = rot * x + t;
                PointConstraint {
                    image: Vector2::new(c.x / c.z + 0.01 * rng.normal(), c.y / c.z),
                    object: x,
                }
            })
            .collect();
        let lines = (0..5)
            .map(|_| {
                let a = Vector3::new(rng.normal(), rng.normal(), rng.normal());
                let b = Vector3::new(rng.normal(), rng.normal(), rng.normal());
                let n = (rot * a + t).cross(&(rot * b + t)).normalize() + Vector3::new(0.01, 0.0, 0.0) * rng.normal();
                LineConstraint {
                    normal: n,
                    object: ObjectLine::from_endpoints(&a, &b).unwrap(),
                }
            })
            .collect();
        (points, lines)
    }

    #[test]
    fn lifted_constraints_equal_the_papers_quaternion_forms() {
        // Eq. 20: rᵀ Q(m)ᵀ W(M) r + 2 rᵀ Q(m)ᵀ s, and eq. 12: rᵀQ(n)ᵀW(p)r + rᵀ(2Q(n)ᵀ)s, at any (r, s).
        let mut rng = Rng::new(20);
        for _ in 0..50 {
            let x = SVector::<f64, 8>::from_fn(|_, _| rng.normal());
            let r = x.fixed_rows::<4>(0).into_owned();
            let s = x.fixed_rows::<4>(4).into_owned();
            let m = Vector3::new(1.0, 0.0, -rng.normal());
            let big_m = Vector3::new(rng.normal(), rng.normal(), rng.normal());
            let paper = r.dot(&(q_matrix(&pure(&m)).transpose() * w_matrix(&pure(&big_m)) * r))
                + 2.0 * r.dot(&(q_matrix(&pure(&m)).transpose() * s));
            let ours = coefficients(&m, &big_m, 1.0).dot(&lift(&x));
            assert!((paper - ours).abs() < 1e-10 * (1.0 + paper.abs()));
            // Eq. 10 for a direction.
            let paper_dir = r.dot(&(q_matrix(&pure(&m)).transpose() * w_matrix(&pure(&big_m)) * r));
            assert!((paper_dir - coefficients(&m, &big_m, 0.0).dot(&lift(&x))).abs() < 1e-10 * (1.0 + paper_dir.abs()));
        }
    }

    #[test]
    fn lift_jacobian_matches_central_differences() {
        // y(x) is quadratic, so central differences are exact up to round-off.
        let mut rng = Rng::new(12);
        for _ in 0..20 {
            let x = SVector::<f64, 8>::from_fn(|_, _| rng.normal());
            let jac = lift_jacobian(&x);
            for k in 0..8 {
                let mut e = SVector::<f64, 8>::zeros();
                e[k] = 1e-3;
                let column = (lift(&(x + e)) - lift(&(x - e))) / 2e-3;
                assert!((column - jac.column(k)).amax() < 1e-10, "column {k}");
            }
        }
    }

    #[test]
    fn lifted_vector_at_a_rigid_motion_is_rotation_and_translation() {
        let mut rng = Rng::new(7);
        let rot = rng.rotation();
        let t = Vector3::new(1.0, -2.0, 3.0);
        let q = DualQuaternion::from_rotation_translation(&rot, &t);
        let y = lift(&q.to_vector());
        for i in 0..9 {
            assert!((y[i] - rot[(i / 3, i % 3)]).abs() < 1e-12);
        }
        assert!((Vector3::new(y[9], y[10], y[11]) - t).norm() < 1e-12);
        assert!((vector_part(&(2.0 * w_matrix(&q.r).transpose() * q.s)) - t).norm() < 1e-12);
    }

    #[test]
    fn gradients_and_hessians_match_finite_differences() {
        let mut rng = Rng::new(99);
        for _ in 0..20 {
            let (points, lines) = random_problem(&mut rng);
            let joint = JointCost {
                gram: gram(&points, &lines, true),
                lambda: 50.0,
            };
            let x = SVector::<f64, 8>::from_fn(|_, _| rng.normal());
            assert!(gradient_error(&joint, &x, 1e-6) < 1e-6);
            assert!(hessian_error(&joint, &x, 1e-6) < 1e-6);
            let rotation = RotationCost::new(&lines, 50.0);
            let r = Vector4::from_fn(|_, _| rng.normal());
            assert!(gradient_error(&rotation, &r, 1e-6) < 1e-6);
            assert!(hessian_error(&rotation, &r, 1e-6) < 1e-6);
            // The Gauss-Newton Hessian equals JᵀJ of the explicit residuals (central differences of Φ).
            let lin = joint.linearize(&x);
            let mut coeffs: Vec<Lifted> = Vec::new();
            for p in &points {
                coeffs.push(coefficients(&Vector3::new(1.0, 0.0, -p.image.x), &p.object, 1.0));
                coeffs.push(coefficients(&Vector3::new(0.0, 1.0, -p.image.y), &p.object, 1.0));
            }
            for l in &lines {
                coeffs.push(coefficients(&l.normal, &l.object.direction, 0.0));
                coeffs.push(coefficients(&l.normal, &l.object.point, 1.0));
            }
            let mut jtj = SMatrix::<f64, 8, 8>::zeros();
            for c in &coeffs {
                let row = lift_jacobian(&x).transpose() * c;
                jtj += row * row.transpose();
            }
            for (_, g) in joint.penalties(&x) {
                jtj += g * g.transpose();
            }
            assert!((jtj - lin.gauss_newton).amax() < 1e-9 * lin.gauss_newton.amax());
        }
    }

    #[test]
    fn point_moments_give_the_same_gram_as_rank_one_updates() {
        let mut rng = Rng::new(21);
        let (points, _) = random_problem(&mut rng);
        let mut direct = Gram::zeros();
        for p in &points {
            add_rank_one(
                &mut direct,
                &coefficients(&Vector3::new(1.0, 0.0, -p.image.x), &p.object, 1.0),
            );
            add_rank_one(
                &mut direct,
                &coefficients(&Vector3::new(0.0, 1.0, -p.image.y), &p.object, 1.0),
            );
        }
        let direct = symmetrize(direct);
        assert!((gram(&points, &[], true) - direct).amax() < 1e-12 * direct.amax());
    }

    #[test]
    fn eq15_recovers_the_translation_from_the_true_rotation() {
        let mut rng = Rng::new(15);
        let rot = rng.rotation();
        let t = Vector3::new(0.3, -0.2, 5.0);
        let lines: Vec<LineConstraint> = (0..6)
            .map(|_| {
                let a = Vector3::new(rng.normal(), rng.normal(), rng.normal());
                let b = Vector3::new(rng.normal(), rng.normal(), rng.normal());
                LineConstraint {
                    normal: (rot * a + t).cross(&(rot * b + t)).normalize(),
                    object: ObjectLine::from_endpoints(&a, &b).unwrap(),
                }
            })
            .collect();
        let q = DualQuaternion::from_rotation_translation(&rot, &t);
        let s = solve_translation(&gram(&[], &lines, false), &q.r, 50.0).unwrap();
        assert!((s - q.s).norm() < 1e-9);
    }
}
