//! The residual of an image conic (Josephson & Kahl 2008, sections 3.1-3.2, eqs. 17-18).
//!
//! The paper divides the dual conic `l` (eq. 11) by its last entry `l₃₃` and keeps the other five
//! entries. pluecker first translates the image to the centre `x₀` of the observed ellipse, `x' = x − x₀`
//! (the dual conic becomes `T l Tᵀ` with `T = [I −x₀; 0 1]`). An affine map leaves `l₃₃` unchanged, so
//! the denominators of eq. 20 are the paper's; the translation only makes the numerators small and
//! nearly linear. The residual of a candidate dual conic `l` against the observed one `l̂` is
//!
//! `r = v(T l Tᵀ) − v(T l̂ Tᵀ)`, with `v(e) = (e₁₁, e₁₂, e₂₂, e₁₃, e₂₃) / e₃₃`,
//!
//! in pixels² for the first three entries (the shape: `−R diag(s²) Rᵀ` of the ellipse) and pixels for
//! the last two (the centre offset). The covariance of `r` for a fitted conic is
//! [`crate::triangulation::fitting::fit_conic`]'s; without covariances the identity is used.

use crate::geometry::quadric::{conic_camera, sym3_to_vec, vec_to_sym3, Ellipse};
use crate::triangulation::fractional_residual::FractionalResidual;
use nalgebra::{Matrix2, Matrix3, Matrix3x4, SMatrix, SVector, Vector2, Vector6};

/// A 5-vector: the conic residual.
pub(crate) type Vector5 = SVector<f64, 5>;

/// Positions in the stacked dual conic (`geometry::quadric` order) of the five residual entries
/// `(l₁₁, l₁₂, l₂₂, l₁₃, l₂₃)`.
const RESIDUAL_ENTRIES: [usize; 5] = [0, 1, 3, 2, 4];
/// Position of `l₃₃` in the stacked dual conic.
const LAST: usize = 5;

/// The normalisation frame of one observed image ellipse (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ConicFrame {
    /// The centre `x₀` of the observed ellipse, pixels.
    pub centre: Vector2<f64>,
    /// `v(T l̂ Tᵀ)`: the observed dual conic in the frame, normalised (module docs).
    pub observed: Vector5,
}

impl ConicFrame {
    /// The frame of a primal image conic `c` (eq. 8, pixels, any scale); `None` unless it is a real
    /// ellipse.
    pub fn of_conic(c: &Matrix3<f64>) -> Option<ConicFrame> {
        let ellipse = Ellipse::from_primal(c)?;
        let mut frame = ConicFrame {
            centre: ellipse.centre,
            observed: Vector5::zeros(),
        };
        frame.observed = frame.normalized(&sym3_to_vec(&ellipse.dual()));
        Some(frame)
    }

    /// The linear map `l̃ ↦ (T l Tᵀ)~` on stacked dual conics.
    fn translation(&self) -> SMatrix<f64, 6, 6> {
        let t = Matrix3::new(1.0, 0.0, -self.centre.x, 0.0, 1.0, -self.centre.y, 0.0, 0.0, 1.0);
        let mut m = SMatrix::<f64, 6, 6>::zeros();
        for k in 0..6 {
            let e = vec_to_sym3(&Vector6::from_fn(|i, _| if i == k { 1.0 } else { 0.0 }));
            m.set_column(k, &sym3_to_vec(&(t * e * t.transpose())));
        }
        m
    }

    /// `v(T l Tᵀ)` for a stacked dual conic `l̃` (pixels).
    fn normalized(&self, l: &Vector6<f64>) -> Vector5 {
        let e = self.translation() * l;
        Vector5::from_fn(|k, _| e[RESIDUAL_ENTRIES[k]] / e[LAST])
    }

    /// The residual as a ratio of linear forms of a stacked candidate dual conic: `r = N l̃ / (dᵀ l̃)`.
    pub fn fraction(&self) -> (SMatrix<f64, 5, 6>, Vector6<f64>) {
        let m = self.translation();
        let d: Vector6<f64> = m.row(LAST).transpose();
        let num = SMatrix::<f64, 5, 6>::from_fn(|k, j| m[(RESIDUAL_ENTRIES[k], j)] - self.observed[k] * d[j]);
        (num, d)
    }

    /// The residual (module docs) of a candidate dual image conic (eq. 11, pixels, any scale).
    pub fn residual(&self, dual: &Matrix3<f64>) -> Vector5 {
        let (num, d) = self.fraction();
        let l = sym3_to_vec(dual);
        num * l / d.dot(&l)
    }

    /// `∂r/∂l̃` at a stacked dual conic (5x6), for propagating the covariance of a fitted conic.
    pub fn residual_jacobian(&self, dual: &Vector6<f64>) -> SMatrix<f64, 5, 6> {
        let (num, d) = self.fraction();
        let g = d.dot(dual);
        (num - (num * dual / g) * d.transpose()) / g
    }
}

/// The whitened residual of a dual quadric `L̃` (stacked, eq. 14) seen by camera `p` as the observed
/// ellipse of `frame`: `N P_C L̃ / (dᵀ P_C L̃)` (Lemma 2.1, eqs. 17-18), whitened by `w`.
pub(crate) fn quadric_view(
    p: &Matrix3x4<f64>,
    frame: &ConicFrame,
    w: &SMatrix<f64, 5, 5>,
) -> FractionalResidual<5, 10> {
    let pc = conic_camera(p);
    let (num, d) = frame.fraction();
    let a: SMatrix<f64, 5, 10> = num * pc;
    let c: SVector<f64, 10> = (d.transpose() * pc).transpose();
    FractionalResidual::new(&a, &c, w)
}

/// The observed ellipse of a frame, back in pixels (its shape entries are `−R diag(s²) Rᵀ`).
pub(crate) fn observed_shape(frame: &ConicFrame) -> Matrix2<f64> {
    let v = frame.observed;
    -Matrix2::new(v[0], v[1], v[1], v[2])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::quadric::{project_dual, sym4_to_vec, Ellipsoid};
    use nalgebra::{Rotation2, Vector3};

    #[test]
    fn observed_ellipse_has_zero_residual_and_the_shape_in_the_frame() {
        let e = Ellipse {
            centre: Vector2::new(420.0, 260.0),
            axes: Rotation2::new(0.7).into_inner(),
            semi_axes: Vector2::new(90.0, 40.0),
        };
        let frame = ConicFrame::of_conic(&(e.primal() * -3.0)).unwrap();
        assert!((frame.centre - e.centre).norm() < 1e-9);
        assert!(frame.residual(&(e.dual() * 7.0)).norm() < 1e-7);
        let shape = e.axes * Matrix2::from_diagonal(&e.semi_axes.map(|s| s * s)) * e.axes.transpose();
        assert!((observed_shape(&frame) - shape).norm() < 1e-7 * shape.norm());
        // Moving the centre by δ gives a residual of δ in the last two entries (and δδᵀ in the shape).
        let moved = Ellipse {
            centre: e.centre + Vector2::new(0.5, -0.25),
            ..e
        };
        let r = frame.residual(&moved.dual());
        assert!(
            (Vector2::new(r[3], r[4]) - Vector2::new(0.5, -0.25)).norm() < 1e-9,
            "{r}"
        );
        let j = frame.residual_jacobian(&sym3_to_vec(&moved.dual()));
        let l = sym3_to_vec(&moved.dual());
        for k in 0..6 {
            let mut dl = Vector6::zeros();
            dl[k] = 1e-6 * (1.0 + l[k].abs());
            let fd =
                (frame.residual(&vec_to_sym3(&(l + dl))) - frame.residual(&vec_to_sym3(&(l - dl)))) / (2.0 * dl[k]);
            assert!(
                (fd - j.column(k)).norm() < 1e-5 * (1.0 + j.column(k).norm()),
                "column {k}"
            );
        }
    }

    #[test]
    fn quadric_view_residual_is_the_image_conic_residual() {
        let q = Ellipsoid {
            centre: Vector3::new(0.1, -0.2, 0.3),
            axes: nalgebra::Matrix3::identity(),
            semi_axes: Vector3::new(0.5, 0.4, 0.2),
        };
        let k = Matrix3::new(800.0, 0.0, 320.0, 0.0, 800.0, 240.0, 0.0, 0.0, 1.0);
        let mut rt = Matrix3x4::zeros();
        rt.fixed_view_mut::<3, 3>(0, 0).copy_from(&Matrix3::identity());
        rt.set_column(3, &Vector3::new(0.0, 0.0, 5.0));
        let p = k * rt;
        let image = project_dual(&p, &q.dual());
        let observed = Ellipse::from_primal(&(image.try_inverse().unwrap())).unwrap();
        let shifted = Ellipse {
            centre: observed.centre + Vector2::new(1.0, 2.0),
            ..observed
        };
        let frame = ConicFrame::of_conic(&shifted.primal()).unwrap();
        let w = SMatrix::<f64, 5, 5>::identity() * 0.3;
        let view = quadric_view(&p, &frame, &w);
        let expected = w * frame.residual(&image);
        assert!((view.residual(&sym4_to_vec(&q.dual())) - expected).norm() < 1e-8 * expected.norm());
    }
}
