//! The residual of an image line (Josephson & Kahl 2008, sections 3.1-3.2, eqs. 17-18) and the cost of
//! a 3-D line.
//!
//! **Normalisation of an observed line** (section 3.1). The paper scales the image line so that its
//! normal has unit norm, translates the image so that the line lies at distance 1 from the origin
//! (so its last coordinate is not 0) and divides by the last coordinate, leaving 2 numbers. The paper's
//! images are in units of the image size; pluecker works in pixels and puts the line at distance
//! [`LINE_FRAME_DISTANCE`] `= D` pixels from the new origin instead (at 1 px a line 1 px away would have
//! an infinite residual). For an observed line `l = (l₁, l₂, l₃)` (homogeneous, pixels):
//! `n = (l₁, l₂)/‖(l₁, l₂)‖`, `c₀ = l₃/‖(l₁, l₂)‖` with the sign chosen so that `c₀ ≤ 0` (the line is
//! `n·x + c₀ = 0` and `n` points from the pixel origin towards it); the frame origin is
//! `o = (D − c₀) n`, the foot of the perpendicular from the pixel origin moved `D` px along `n`. In
//! the frame `x' = x − o` the observed line is `n·x' + D = 0`.
//!
//! **Residual** (eq. 17). A candidate image line `(a, b, c)` in the frame (pixels, `c` its last
//! coordinate) has the residual `r = D (D (a, b)/c − n)`, which is eq. 17 in the frame scaled by
//! `1/D` (where the observed line is at distance 1), multiplied by `D` so that `r` is in pixels: to
//! first order `r ≈ D θ n⊥ + δ n`, with `θ` the rotation of the line about the foot point `o − D n` and
//! `δ` its displacement there along `n` (towards `o`). The covariance of `r` for a fitted line is [`crate::triangulation::fitting::fit_line`]'s.
//! Without covariances the identity is used, weighing an angle of 1/D rad like 1 px.

use crate::geometry::plucker;
use crate::triangulation::fractional_residual::FractionalResidual;
use nalgebra::{Matrix2, Matrix2x3, Matrix3x4, SMatrix, Vector2, Vector3, Vector6};

/// `D`: the distance in pixels between an observed line and the origin of its frame (module docs).
pub const LINE_FRAME_DISTANCE: f64 = 1000.0;

/// The normalisation frame of one observed image line (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LineFrame {
    /// The unit normal `n` of the observed line, oriented away from the pixel origin.
    pub normal: Vector2<f64>,
    /// The frame origin `o = (D − c₀) n`, pixels.
    pub origin: Vector2<f64>,
}

impl LineFrame {
    /// The frame of the homogeneous image line `l` (pixels); `None` when `(l₁, l₂) = 0` (the line at
    /// infinity) or an entry is not finite.
    pub fn of_line(l: &Vector3<f64>) -> Option<LineFrame> {
        let h = l.xy().norm();
        if !(h > 0.0) || !h.is_finite() || !l.z.is_finite() {
            return None;
        }
        let (mut n, mut c0) = (l.xy() / h, l.z / h);
        if c0 > 0.0 {
            n = -n;
            c0 = -c0;
        }
        Some(LineFrame {
            normal: n,
            origin: n * (LINE_FRAME_DISTANCE - c0),
        })
    }

    /// The observed line itself, `(n, c₀)` with a unit normal and `c₀ ≤ 0` (pixels).
    pub fn line(&self) -> Vector3<f64> {
        Vector3::new(
            self.normal.x,
            self.normal.y,
            LINE_FRAME_DISTANCE - self.normal.dot(&self.origin),
        )
    }

    /// The residual as a ratio of linear forms of a candidate pixel line `l`: `r = N l / (dᵀ l)`, with
    /// `d = (o₁, o₂, 1)` (the frame's last coordinate) and `N = D (D [I₂ 0] − n dᵀ)`.
    pub fn fraction(&self) -> (Matrix2x3<f64>, Vector3<f64>) {
        let d = Vector3::new(self.origin.x, self.origin.y, 1.0);
        let dd = LINE_FRAME_DISTANCE;
        let mut num = Matrix2x3::new(dd, 0.0, 0.0, 0.0, dd, 0.0) - self.normal * d.transpose();
        num *= dd;
        (num, d)
    }

    /// The residual `r` (pixels, module docs) of a candidate homogeneous image line `l` (pixels).
    pub fn residual(&self, l: &Vector3<f64>) -> Vector2<f64> {
        let (num, d) = self.fraction();
        num * l / d.dot(l)
    }

    /// `∂r/∂l` at `l` (2x3), for propagating the covariance of a fitted line.
    pub fn residual_jacobian(&self, l: &Vector3<f64>) -> Matrix2x3<f64> {
        let (num, d) = self.fraction();
        let g = d.dot(l);
        (num - (num * l / g) * d.transpose()) / g
    }
}

/// The whitened residual of a 3-D line (Plücker coordinates, eq. 3) seen by camera `p` as the
/// observed line of `frame`: `N P_𝓛 𝓛 / (dᵀ P_𝓛 𝓛)` (eqs. 6-7, 17-18), whitened by `w`.
pub(crate) fn line_view(p: &Matrix3x4<f64>, frame: &LineFrame, w: &Matrix2<f64>) -> FractionalResidual<2, 6> {
    let pl = plucker::camera(p);
    let (num, d) = frame.fraction();
    let a: SMatrix<f64, 2, 6> = num * pl;
    let c: Vector6<f64> = (d.transpose() * pl).transpose();
    FractionalResidual::new(&a, &c, w)
}

/// The distances (pixels) from the two endpoints of an image segment to the image line `l`: the
/// reprojection error of a line in Table 2.
pub fn endpoint_distances(l: &Vector3<f64>, a: &Vector2<f64>, b: &Vector2<f64>) -> [f64; 2] {
    let h = l.xy().norm();
    [(l.xy().dot(a) + l.z).abs() / h, (l.xy().dot(b) + l.z).abs() / h]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    #[test]
    fn frame_puts_the_line_at_distance_d_and_the_observation_has_zero_residual() {
        let mut rng = Rng::new(41);
        for _ in 0..50 {
            let l = Vector3::new(rng.normal(), rng.normal(), rng.normal() * 500.0) * rng.uniform_in(-3.0, 3.0);
            let f = LineFrame::of_line(&l).unwrap();
            // Distance from o to the line, pixels.
            let dist = (l.xy().dot(&f.origin) + l.z).abs() / l.xy().norm();
            assert!((dist - LINE_FRAME_DISTANCE).abs() < 1e-9 * LINE_FRAME_DISTANCE);
            assert!(f.residual(&l).norm() < 1e-9);
            assert!(f.residual(&(l * -2.0)).norm() < 1e-9, "sign and scale free");
            assert!(
                (f.line().normalize() - l.normalize()).norm() < 1e-12
                    || (f.line().normalize() + l.normalize()).norm() < 1e-12
            );
        }
    }

    #[test]
    fn residual_is_angle_and_offset_to_first_order() {
        let l = Vector3::new(0.6, 0.8, -400.0);
        let f = LineFrame::of_line(&l).unwrap();
        let n = f.normal;
        let n_perp = Vector2::new(-n.y, n.x);
        let foot = f.origin - LINE_FRAME_DISTANCE * n;
        // Shift by δ px along n.
        let delta = 1e-3;
        let shifted = Vector3::new(n.x, n.y, -n.dot(&(foot + delta * n)));
        let r = f.residual(&shifted);
        assert!((r - delta * n).norm() < 1e-8, "{r}");
        // Rotate by θ about the foot point.
        let theta = 1e-6;
        let nr = n + theta * n_perp;
        let rotated = Vector3::new(nr.x, nr.y, -nr.dot(&foot));
        let r = f.residual(&rotated);
        assert!((r - LINE_FRAME_DISTANCE * theta * n_perp).norm() < 1e-8, "{r}");
        // Analytic Jacobian against central differences.
        let j = f.residual_jacobian(&shifted);
        for k in 0..3 {
            let mut e = Vector3::zeros();
            e[k] = 1e-6 * (1.0 + shifted[k].abs());
            let fd = (f.residual(&(shifted + e)) - f.residual(&(shifted - e))) / (2.0 * e[k]);
            assert!((fd - j.column(k)).norm() < 1e-6 * (1.0 + j.column(k).norm()));
        }
    }

    #[test]
    fn line_view_residual_is_the_image_line_residual() {
        let mut rng = Rng::new(42);
        let k = nalgebra::Matrix3::new(800.0, 0.0, 320.0, 0.0, 800.0, 240.0, 0.0, 0.0, 1.0);
        let mut rt = Matrix3x4::zeros();
        rt.fixed_view_mut::<3, 3>(0, 0).copy_from(&rng.rotation());
        rt.set_column(3, &Vector3::new(0.1, 0.2, 6.0));
        let p = k * rt;
        let (a, b) = (Vector3::new(0.3, -0.2, 0.1), Vector3::new(-0.4, 0.5, 0.2));
        let image_line = (p * a.push(1.0)).cross(&(p * b.push(1.0)));
        let observed = image_line + Vector3::new(1e-4, -2e-4, 0.3) * image_line.norm() * 1e-3;
        let frame = LineFrame::of_line(&observed).unwrap();
        let w = Matrix2::new(0.5, 0.0, 0.2, 2.0);
        let view = line_view(&p, &frame, &w);
        let l = plucker::from_points(&a, &b);
        assert!((view.residual(&l) - w * frame.residual(&image_line)).norm() < 1e-9 * (1.0 + view.residual(&l).norm()));
    }
}
