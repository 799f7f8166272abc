//! Quadrics in space and conics in the image (Josephson & Kahl 2008, section 2.3, eqs. 8-14).
//!
//! A quadric is the set `Xᵀ C X = 0` (eq. 9, `C` symmetric 4x4, `X` homogeneous world point); its dual
//! `L = C⁻¹` (eq. 10) is the set of planes `U` tangent to it, `Uᵀ L U = 0`. An image conic is
//! `xᵀ c x = 0` (eq. 8, `x` homogeneous pixels) with dual `l = c⁻¹` (eq. 11). A 3x4 camera `P` maps the
//! dual quadric to the dual of its outline conic, `λ l = P L Pᵀ` (eqs. 12-13), and on the stacked
//! symmetric entries this is the linear map of Lemma 2.1, `λ l̃ = P_C L̃` (eq. 14).
//!
//! Stacking order (upper triangles, row by row): `l̃ = (l₁₁, l₁₂, l₁₃, l₂₂, l₂₃, l₃₃)` and
//! `L̃ = (L₁₁, L₁₂, L₁₃, L₁₄, L₂₂, L₂₃, L₂₄, L₃₃, L₃₄, L₄₄)`.
//!
//! An ellipsoid with centre `c`, orthonormal axes `R` (columns) and semi-axes `s` has the dual
//! `L = H diag(s₁², s₂², s₃², −1) Hᵀ` with `H = [R c; 0 1]`, so `L₄₄ = −1` and `c = L[0..3, 3] / L₄₄`;
//! a flat ellipsoid (a disc, `s₃ = 0`) keeps a finite dual (of rank 3) but has no primal form.
//! Image ellipses are the same in 2-D: `l = H diag(s₁², s₂², −1) Hᵀ`.

use nalgebra::{Matrix2, Matrix3, Matrix3x4, Matrix4, SMatrix, SVector, Vector2, Vector3, Vector6};

/// The 6x10 conic camera of Lemma 2.1 (eq. 14).
pub type ConicCamera = SMatrix<f64, 6, 10>;

/// Index pairs of the stacked upper triangle of a symmetric 3x3 matrix.
pub const SYM3_INDEX: [(usize, usize); 6] = [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)];
/// Index pairs of the stacked upper triangle of a symmetric 4x4 matrix.
pub const SYM4_INDEX: [(usize, usize); 10] = [
    (0, 0),
    (0, 1),
    (0, 2),
    (0, 3),
    (1, 1),
    (1, 2),
    (1, 3),
    (2, 2),
    (2, 3),
    (3, 3),
];

/// Relative size of an eigenvalue below which it counts as zero (a flat ellipsoid or ellipse).
const EIGEN_TOLERANCE: f64 = 1e-12;

/// `l̃`: the upper triangle of a symmetric 3x3 matrix, stacked (module docs).
pub fn sym3_to_vec(c: &Matrix3<f64>) -> Vector6<f64> {
    Vector6::from_fn(|k, _| c[SYM3_INDEX[k]])
}

/// The symmetric 3x3 matrix of a stacked `l̃`.
pub fn vec_to_sym3(v: &Vector6<f64>) -> Matrix3<f64> {
    let mut c = Matrix3::zeros();
    for (k, &(i, j)) in SYM3_INDEX.iter().enumerate() {
        c[(i, j)] = v[k];
        c[(j, i)] = v[k];
    }
    c
}

/// `L̃`: the upper triangle of a symmetric 4x4 matrix, stacked (module docs).
pub fn sym4_to_vec(q: &Matrix4<f64>) -> SVector<f64, 10> {
    SVector::<f64, 10>::from_fn(|k, _| q[SYM4_INDEX[k]])
}

/// The symmetric 4x4 matrix of a stacked `L̃`.
pub fn vec_to_sym4(v: &SVector<f64, 10>) -> Matrix4<f64> {
    let mut q = Matrix4::zeros();
    for (k, &(i, j)) in SYM4_INDEX.iter().enumerate() {
        q[(i, j)] = v[k];
        q[(j, i)] = v[k];
    }
    q
}

/// Eqs. 12-13: the dual image conic `P L Pᵀ` of the dual quadric `L` (scale `λ = 1`).
pub fn project_dual(p: &Matrix3x4<f64>, dual: &Matrix4<f64>) -> Matrix3<f64> {
    p * dual * p.transpose()
}

/// Lemma 2.1 (eq. 14): `P_C` with `P_C L̃ = (P L Pᵀ)~` for every symmetric `L`. Row `(i, j)`,
/// column `(k, l)` holds `P_ik P_jl + P_il P_jk` for `k ≠ l` and `P_ik P_jk` for `k = l`.
pub fn conic_camera(p: &Matrix3x4<f64>) -> ConicCamera {
    ConicCamera::from_fn(|row, col| {
        let (i, j) = SYM3_INDEX[row];
        let (k, l) = SYM4_INDEX[col];
        if k == l {
            p[(i, k)] * p[(j, k)]
        } else {
            p[(i, k)] * p[(j, l)] + p[(i, l)] * p[(j, k)]
        }
    })
}

/// The 9 coordinates of a dual quadric normalised so that `L₄₄ = −1` (the chart of the quadric
/// covariances of [`crate::triangulation::uncertainty`]): `θ = (c₁, c₂, c₃, S₁₁, S₁₂, S₁₃, S₂₂, S₂₃, S₃₃)`
/// with the centre `c` (world units) and the upper triangle of the symmetric **shape matrix**
/// `S = R diag(s²) Rᵀ` (world units²; the ellipsoid is `{c + S^{1/2} u : ‖u‖ ≤ 1}`), so that
/// `L = [S − c cᵀ, −c; −cᵀ, −1]` (module docs). A linear bijection of the 9 free entries of `L`; an
/// off-diagonal coordinate `S_ij` moves both `S_ij` and `S_ji`.
pub type CentreShape = SVector<f64, 9>;

/// The [`CentreShape`] coordinates of a dual quadric of any scale and sign; `None` when `L₄₄ = 0` or
/// an entry is not finite.
pub fn centre_shape(dual: &Matrix4<f64>) -> Option<CentreShape> {
    let q44 = dual[(3, 3)];
    if !(q44 != 0.0 && dual.iter().all(|v| v.is_finite())) {
        return None;
    }
    let q = dual / -q44;
    let c: Vector3<f64> = -q.fixed_view::<3, 1>(0, 3).into_owned();
    let shape: Matrix3<f64> = q.fixed_view::<3, 3>(0, 0).into_owned() + c * c.transpose();
    let v = sym3_to_vec(&(0.5 * (shape + shape.transpose())));
    Some(CentreShape::from_fn(|k, _| if k < 3 { c[k] } else { v[k - 3] }))
}

/// The dual quadric (`L₄₄ = −1`) of [`CentreShape`] coordinates.
pub fn dual_of_centre_shape(theta: &CentreShape) -> Matrix4<f64> {
    let c = Vector3::new(theta[0], theta[1], theta[2]);
    let shape = vec_to_sym3(&Vector6::from_fn(|k, _| theta[3 + k]));
    let mut q = Matrix4::zeros();
    q.fixed_view_mut::<3, 3>(0, 0).copy_from(&(shape - c * c.transpose()));
    q.fixed_view_mut::<3, 1>(0, 3).copy_from(&(-c));
    q.fixed_view_mut::<1, 3>(3, 0).copy_from(&(-c.transpose()));
    q[(3, 3)] = -1.0;
    q
}

/// `∂L̃/∂θ` (10x9) of [`dual_of_centre_shape`] at a quadric with centre `c` (it does not depend on
/// `S`): `∂L/∂c_k = −[e_k cᵀ + c e_kᵀ, e_k; e_kᵀ, 0]`, `∂L/∂S_ij` the symmetric unit matrix of `(i, j)`.
pub fn centre_shape_tangent(c: &Vector3<f64>) -> SMatrix<f64, 10, 9> {
    let mut t = SMatrix::<f64, 10, 9>::zeros();
    for k in 0..3 {
        let e = Vector3::ith(k, 1.0);
        let mut dl = Matrix4::zeros();
        dl.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&(-(e * c.transpose() + c * e.transpose())));
        dl.fixed_view_mut::<3, 1>(0, 3).copy_from(&(-e));
        dl.fixed_view_mut::<1, 3>(3, 0).copy_from(&(-e.transpose()));
        t.set_column(k, &sym4_to_vec(&dl));
    }
    for (k, &(i, j)) in SYM3_INDEX.iter().enumerate() {
        let mut dl = Matrix4::zeros();
        dl[(i, j)] = 1.0;
        dl[(j, i)] = 1.0;
        t.set_column(3 + k, &sym4_to_vec(&dl));
    }
    t
}

/// A real ellipsoid (possibly flat: a semi-axis may be 0), world frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ellipsoid {
    /// Centre, world units.
    pub centre: Vector3<f64>,
    /// Orthonormal axes as columns, in the order of `semi_axes`.
    pub axes: Matrix3<f64>,
    /// Semi-axis lengths, world units, non-negative, in decreasing order.
    pub semi_axes: Vector3<f64>,
}

impl Ellipsoid {
    /// The dual quadric `H diag(s², −1) Hᵀ` (module docs), normalised so that `L₄₄ = −1`.
    pub fn dual(&self) -> Matrix4<f64> {
        let shape = self.axes * Matrix3::from_diagonal(&self.semi_axes.map(|s| s * s)) * self.axes.transpose();
        let c = self.centre;
        let mut q = Matrix4::zeros();
        q.fixed_view_mut::<3, 3>(0, 0).copy_from(&(shape - c * c.transpose()));
        q.fixed_view_mut::<3, 1>(0, 3).copy_from(&(-c));
        q.fixed_view_mut::<1, 3>(3, 0).copy_from(&(-c.transpose()));
        q[(3, 3)] = -1.0;
        q
    }

    /// The point quadric `C` of eq. 9 (`C = L⁻¹`), `None` when flat.
    pub fn primal(&self) -> Option<Matrix4<f64>> {
        if self.semi_axes.min() <= EIGEN_TOLERANCE * self.semi_axes.max() {
            return None;
        }
        self.dual().try_inverse()
    }

    /// The ellipsoid of a dual quadric of any scale and sign; `None` when `L₄₄ = 0` (a paraboloid or
    /// worse), when the shape matrix is not positive semi-definite (a hyperboloid, or no real points) or
    /// when entries are not finite.
    pub fn from_dual(dual: &Matrix4<f64>) -> Option<Ellipsoid> {
        let q44 = dual[(3, 3)];
        if !dual.iter().all(|v| v.is_finite()) || q44 == 0.0 {
            return None;
        }
        let q = dual / -q44;
        let centre: Vector3<f64> = -q.fixed_view::<3, 1>(0, 3).into_owned();
        let shape: Matrix3<f64> = q.fixed_view::<3, 3>(0, 0).into_owned() + centre * centre.transpose();
        let (values, axes) = sorted_eigen3(&(0.5 * (shape + shape.transpose())));
        if !(values[0] > 0.0) || values[2] < -EIGEN_TOLERANCE.sqrt() * values[0] {
            return None;
        }
        Some(Ellipsoid {
            centre,
            axes,
            semi_axes: values.map(|v| v.max(0.0).sqrt()),
        })
    }

    /// The ellipsoid of a point quadric `C` (eq. 9); `None` when `C` is singular or not an ellipsoid.
    pub fn from_primal(primal: &Matrix4<f64>) -> Option<Ellipsoid> {
        primal.try_inverse().and_then(|d| Ellipsoid::from_dual(&d))
    }

    /// `n` points of the contour generator seen from the camera centre `eye` (the points where the
    /// viewing rays touch the ellipsoid), evenly spaced in angle. Empty when `eye` is inside or the
    /// ellipsoid is flat.
    pub fn contour_generator(&self, eye: &Vector3<f64>, n: usize) -> Vec<Vector3<f64>> {
        if self.semi_axes.min() <= 0.0 {
            return vec![];
        }
        // In the frame where the ellipsoid is the unit sphere, the contour is the circle u·e = 1 of
        // the unit sphere, with e the eye in that frame.
        let e = (self.axes.transpose() * (eye - self.centre)).component_div(&self.semi_axes);
        let e2 = e.norm_squared();
        if e2 <= 1.0 {
            return vec![];
        }
        let (b1, b2) = orthonormal_complement(&(e / e2.sqrt()));
        let radius = (1.0 - 1.0 / e2).sqrt();
        (0..n)
            .map(|k| {
                let t = std::f64::consts::TAU * k as f64 / n as f64;
                let u = e / e2 + radius * (t.cos() * b1 + t.sin() * b2);
                self.centre + self.axes * u.component_mul(&self.semi_axes)
            })
            .collect()
    }
}

/// A real image ellipse, pixels.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Ellipse {
    /// Centre, pixels.
    pub centre: Vector2<f64>,
    /// Orthonormal axes as columns, in the order of `semi_axes`.
    #[cfg_attr(feature = "serde", serde(with = "crate::matrix_rows"))]
    pub axes: Matrix2<f64>,
    /// Semi-axis lengths, pixels, positive, in decreasing order.
    pub semi_axes: Vector2<f64>,
}

impl Ellipse {
    /// The point conic `c` of eq. 8: `(x − x₀)ᵀ R diag(s⁻²) Rᵀ (x − x₀) − 1 = 0` in homogeneous form.
    pub fn primal(&self) -> Matrix3<f64> {
        let m = self.axes * Matrix2::from_diagonal(&self.semi_axes.map(|s| 1.0 / (s * s))) * self.axes.transpose();
        let b = -(m * self.centre);
        let f = self.centre.dot(&(m * self.centre)) - 1.0;
        Matrix3::new(m[(0, 0)], m[(0, 1)], b.x, m[(1, 0)], m[(1, 1)], b.y, b.x, b.y, f)
    }

    /// The dual conic `l = H diag(s², −1) Hᵀ` of eq. 11 (so `l₃₃ = −1`).
    pub fn dual(&self) -> Matrix3<f64> {
        let shape = self.axes * Matrix2::from_diagonal(&self.semi_axes.map(|s| s * s)) * self.axes.transpose();
        let c = self.centre;
        let top = shape - c * c.transpose();
        Matrix3::new(
            top[(0, 0)],
            top[(0, 1)],
            -c.x,
            top[(1, 0)],
            top[(1, 1)],
            -c.y,
            -c.x,
            -c.y,
            -1.0,
        )
    }

    /// The ellipse of a point conic of any scale and sign; `None` unless it is a real, non-degenerate
    /// ellipse (not a hyperbola, parabola, line pair, point, or imaginary ellipse).
    pub fn from_primal(c: &Matrix3<f64>) -> Option<Ellipse> {
        if !c.iter().all(|v| v.is_finite()) {
            return None;
        }
        let a = Matrix2::new(
            c[(0, 0)],
            0.5 * (c[(0, 1)] + c[(1, 0)]),
            0.5 * (c[(0, 1)] + c[(1, 0)]),
            c[(1, 1)],
        );
        let b = Vector2::new(0.5 * (c[(0, 2)] + c[(2, 0)]), 0.5 * (c[(1, 2)] + c[(2, 1)]));
        // Definite 2x2 part (relative to its own size), and a value at the centre that does not
        // vanish by cancellation (a point or a line pair).
        if !(a.determinant() > EIGEN_TOLERANCE * a.norm_squared()) {
            return None;
        }
        let centre = -(a.try_inverse()? * b);
        let k = c[(2, 2)] + b.dot(&centre);
        if !(k.abs() > EIGEN_TOLERANCE * (c[(2, 2)].abs() + b.dot(&centre).abs())) {
            return None;
        }
        let m = a / -k;
        let eig = m.symmetric_eigen();
        if eig.eigenvalues.min() <= 0.0 {
            return None;
        }
        // Decreasing semi-axes = increasing eigenvalues of m.
        let order = if eig.eigenvalues[0] <= eig.eigenvalues[1] {
            [0, 1]
        } else {
            [1, 0]
        };
        let axes = Matrix2::from_columns(&[eig.eigenvectors.column(order[0]), eig.eigenvectors.column(order[1])]);
        let semi_axes = Vector2::new(
            1.0 / eig.eigenvalues[order[0]].sqrt(),
            1.0 / eig.eigenvalues[order[1]].sqrt(),
        );
        Some(Ellipse {
            centre,
            axes,
            semi_axes,
        })
    }

    /// `n` points of the ellipse, evenly spaced in the angle of the parametrisation
    /// `x₀ + R (s₁ cos t, s₂ sin t)`, starting at `t = phase`.
    pub fn sample(&self, n: usize, phase: f64) -> Vec<Vector2<f64>> {
        (0..n)
            .map(|k| {
                let t = phase + std::f64::consts::TAU * k as f64 / n as f64;
                self.centre + self.axes * Vector2::new(self.semi_axes.x * t.cos(), self.semi_axes.y * t.sin())
            })
            .collect()
    }
}

/// Eigenvalues in decreasing order and the matching unit eigenvectors (columns) of a symmetric 3x3.
fn sorted_eigen3(m: &Matrix3<f64>) -> (Vector3<f64>, Matrix3<f64>) {
    let eig = m.symmetric_eigen();
    let mut order = [0usize, 1, 2];
    order.sort_by(|&i, &j| eig.eigenvalues[j].total_cmp(&eig.eigenvalues[i]));
    let values = Vector3::from_fn(|k, _| eig.eigenvalues[order[k]]);
    let mut vectors = Matrix3::from_fn(|r, k| eig.eigenvectors[(r, order[k])]);
    if vectors.determinant() < 0.0 {
        vectors.column_mut(2).neg_mut();
    }
    (values, vectors)
}

/// Two unit vectors completing the unit vector `v` to an orthonormal basis.
fn orthonormal_complement(v: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let axis = if v.x.abs() < 0.9 { Vector3::x() } else { Vector3::y() };
    let b1 = v.cross(&axis).normalize();
    (b1, v.cross(&b1))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    fn random_ellipsoid(rng: &mut Rng) -> Ellipsoid {
        let mut s = [
            rng.uniform_in(0.3, 1.5),
            rng.uniform_in(0.3, 1.5),
            rng.uniform_in(0.3, 1.5),
        ];
        s.sort_by(|a, b| b.total_cmp(a));
        let mut axes = rng.rotation();
        if axes.determinant() < 0.0 {
            axes.column_mut(2).neg_mut();
        }
        Ellipsoid {
            centre: Vector3::new(rng.normal(), rng.normal(), rng.normal()) * 0.5,
            axes,
            semi_axes: Vector3::from(s),
        }
    }

    fn random_camera(rng: &mut Rng) -> Matrix3x4<f64> {
        let k = Matrix3::new(800.0, 2.0, 320.0, 0.0, 790.0, 240.0, 0.0, 0.0, 1.0);
        let mut rt = Matrix3x4::zeros();
        rt.fixed_view_mut::<3, 3>(0, 0).copy_from(&rng.rotation());
        rt.set_column(3, &Vector3::new(rng.normal() * 0.3, rng.normal() * 0.3, 8.0));
        k * rt * rng.uniform_in(0.5, 2.0)
    }

    #[test]
    fn stacking_round_trips_and_the_conic_camera_is_lemma_2_1() {
        let mut rng = Rng::new(21);
        let q = Matrix4::from_fn(|_, _| rng.normal());
        let q = q + q.transpose();
        assert_eq!(vec_to_sym4(&sym4_to_vec(&q)), q);
        let c = Matrix3::from_fn(|_, _| rng.normal());
        let c = c + c.transpose();
        assert_eq!(vec_to_sym3(&sym3_to_vec(&c)), c);
        let p = random_camera(&mut rng);
        let direct = sym3_to_vec(&project_dual(&p, &q));
        assert!((conic_camera(&p) * sym4_to_vec(&q) - direct).norm() < 1e-12 * direct.norm());
    }

    #[test]
    fn contour_generator_projects_onto_the_image_conic() {
        let mut rng = Rng::new(22);
        for _ in 0..30 {
            let e = random_ellipsoid(&mut rng);
            let p = random_camera(&mut rng);
            // The image conic from eqs. 12-13: c = (P L Pᵀ)⁻¹.
            let c = project_dual(&p, &e.dual()).try_inverse().unwrap();
            let ellipse = Ellipse::from_primal(&c).expect("an ellipsoid in front of a camera images as an ellipse");
            // The camera centre: P (eye, 1) = 0.
            let eye = -(p.fixed_view::<3, 3>(0, 0).try_inverse().unwrap() * p.column(3));
            let points = e.contour_generator(&eye, 24);
            assert_eq!(points.len(), 24);
            for x in &points {
                // On the ellipsoid ...
                let xh = x.push(1.0);
                assert!(xh.dot(&(e.primal().unwrap() * xh)).abs() < 1e-9);
                // ... and its image on the conic: algebraic distance relative to the gradient = pixels.
                let u = p * xh;
                let u = u / u.z;
                let grad = (c * u).xy().norm();
                let pixel_distance = u.dot(&(c * u)).abs() / (2.0 * grad);
                assert!(pixel_distance < 1e-7, "{pixel_distance} px");
                // The viewing ray touches: it is orthogonal to the surface normal there.
                let normal = (e.primal().unwrap() * xh).xyz();
                assert!(normal.normalize().dot(&(x - eye).normalize()).abs() < 1e-9);
            }
            assert!(ellipse.semi_axes.x >= ellipse.semi_axes.y && ellipse.semi_axes.y > 0.0);
        }
    }

    #[test]
    fn ellipsoid_centre_axes_and_forms_round_trip() {
        let mut rng = Rng::new(23);
        for _ in 0..30 {
            let e = random_ellipsoid(&mut rng);
            let back = Ellipsoid::from_dual(&(e.dual() * rng.uniform_in(-3.0, 3.0))).unwrap();
            assert!((back.centre - e.centre).norm() < 1e-12);
            assert!((back.semi_axes - e.semi_axes).norm() < 1e-10);
            for k in 0..3 {
                assert!((back.axes.column(k).dot(&e.axes.column(k)).abs() - 1.0).abs() < 1e-9);
            }
            let from_primal = Ellipsoid::from_primal(&e.primal().unwrap()).unwrap();
            assert!((from_primal.semi_axes - e.semi_axes).norm() < 1e-9);
            // Points on the surface satisfy eq. 9.
            let x = e.centre + e.axes * Vector3::new(e.semi_axes.x, 0.0, 0.0);
            assert!(x.push(1.0).dot(&(e.primal().unwrap() * x.push(1.0))).abs() < 1e-12);
        }
        // A disc: finite dual, no primal; a hyperboloid: rejected.
        let disc = Ellipsoid {
            centre: Vector3::zeros(),
            axes: Matrix3::identity(),
            semi_axes: Vector3::new(2.0, 1.0, 0.0),
        };
        assert!(disc.primal().is_none());
        assert!((Ellipsoid::from_dual(&disc.dual()).unwrap().semi_axes - disc.semi_axes).norm() < 1e-12);
        let hyperboloid = Matrix4::from_diagonal(&nalgebra::Vector4::new(1.0, 1.0, -1.0, -1.0));
        assert!(Ellipsoid::from_dual(&hyperboloid).is_none());
    }

    #[test]
    fn ellipse_forms_and_rejections() {
        let ellipse = Ellipse {
            centre: Vector2::new(300.0, 200.0),
            axes: nalgebra::Rotation2::new(0.4).into_inner(),
            semi_axes: Vector2::new(80.0, 30.0),
        };
        let c = ellipse.primal();
        let inverse = c.try_inverse().unwrap();
        assert!((inverse / -inverse[(2, 2)] - ellipse.dual()).norm() < 1e-9 * ellipse.dual().norm());
        for x in ellipse.sample(10, 0.3) {
            assert!(x.push(1.0).dot(&(c * x.push(1.0))).abs() < 1e-12);
        }
        let back = Ellipse::from_primal(&(c * -4.0)).unwrap();
        assert!((back.centre - ellipse.centre).norm() < 1e-9 && (back.semi_axes - ellipse.semi_axes).norm() < 1e-9);
        let hyperbola = Matrix3::from_diagonal(&Vector3::new(1.0, -1.0, -1.0));
        let imaginary = Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, 1.0));
        let parabola = Matrix3::new(1.0, 0.0, 0.0, 0.0, 0.0, -0.5, 0.0, -0.5, 0.0);
        for bad in [hyperbola, imaginary, parabola] {
            assert!(Ellipse::from_primal(&bad).is_none(), "{bad}");
        }
    }

    #[test]
    fn centre_shape_chart_round_trips_and_its_tangent_matches_central_differences() {
        let mut rng = Rng::new(23);
        let e = random_ellipsoid(&mut rng);
        let theta = centre_shape(&(e.dual() * -3.0)).unwrap();
        assert!((dual_of_centre_shape(&theta) - e.dual()).norm() < 1e-12 * e.dual().norm());
        let c = Vector3::new(theta[0], theta[1], theta[2]);
        assert!((c - e.centre).norm() < 1e-12);
        let t = centre_shape_tangent(&c);
        for k in 0..9 {
            let mut d = CentreShape::zeros();
            d[k] = 1e-6;
            let fd = (sym4_to_vec(&dual_of_centre_shape(&(theta + d)))
                - sym4_to_vec(&dual_of_centre_shape(&(theta - d))))
                / 2e-6;
            assert!((fd - t.column(k)).norm() < 1e-8, "column {k}");
        }
        assert!(centre_shape(&Matrix4::zeros()).is_none());
    }
}
