//! Dual number quaternions `q̂ = r + ε s` for rigid motions (Phong & Horaud 1995, section 2.1).
//!
//! The motion `x_cam = R X_world + t` is `r` = the unit quaternion of `R` and `s = ½ t r` (so that
//! `t = 2 W(r)ᵀ s`, eq. 7). A dual quaternion is a rigid motion exactly when `r·r = 1` and `r·s = 0`.
//! The screw `(d, φ, axis direction, axis point)` is Chasles' form of the same motion: a rotation by
//! `φ` about the line through `point` with unit `direction`, followed by a slide `d` along it.

use super::quaternion::{
    axis_angle, conjugate, from_rotation_matrix, multiply, pure, to_rotation_matrix, vector_part, w_matrix,
};
use nalgebra::{Matrix3, Vector3, Vector4};

/// A dual quaternion `r + ε s`; a rigid motion when [`DualQuaternion::constraint_residuals`] vanish.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct DualQuaternion {
    /// Real part: the rotation quaternion.
    pub r: Vector4<f64>,
    /// Dual part: `½ t r`.
    pub s: Vector4<f64>,
}

/// Chasles' screw form of a rigid motion.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Screw {
    /// Slide along the axis (length units of the translation).
    pub d: f64,
    /// Rotation angle about the axis, radians.
    pub angle: f64,
    /// Unit direction of the axis.
    pub direction: Vector3<f64>,
    /// The point of the axis closest to the origin (`point · direction = 0`).
    pub point: Vector3<f64>,
}

impl DualQuaternion {
    /// The identity motion.
    pub fn identity() -> Self {
        DualQuaternion {
            r: Vector4::new(1.0, 0.0, 0.0, 0.0),
            s: Vector4::zeros(),
        }
    }

    /// From a rotation matrix and translation (`x_cam = R X_world + t`), eqs. 6-7 inverted.
    pub fn from_rotation_translation(rot: &Matrix3<f64>, t: &Vector3<f64>) -> Self {
        let r = from_rotation_matrix(rot);
        let s = 0.5 * multiply(&pure(t), &r);
        DualQuaternion { r, s }
    }

    /// `(R, t)` by eqs. 6-7: `diag(1, R) = W(r)ᵀ Q(r)`, `(0, t) = 2 W(r)ᵀ s`. `r` is normalised first.
    pub fn to_rotation_translation(&self) -> (Matrix3<f64>, Vector3<f64>) {
        let n = self.r.norm();
        let (r, s) = (self.r / n, self.s / n);
        (
            to_rotation_matrix(&r),
            vector_part(&(2.0 * w_matrix(&r).transpose() * s)),
        )
    }

    /// The translation `t` (eq. 7).
    pub fn translation(&self) -> Vector3<f64> {
        self.to_rotation_translation().1
    }

    /// The residuals of the two rigidity constraints `(r·r − 1, r·s)`.
    pub fn constraint_residuals(&self) -> (f64, f64) {
        (self.r.norm_squared() - 1.0, self.r.dot(&self.s))
    }

    /// The nearest rigid motion: `r` normalised, the component of `s` along `r` removed.
    pub fn normalized(&self) -> Self {
        let n = self.r.norm();
        let r = self.r / n;
        let s = self.s / n;
        DualQuaternion {
            r,
            s: s - r * r.dot(&s),
        }
    }

    /// From Chasles' screw, section 2.1: `r = (cos φ/2, sin φ/2 ř)`,
    /// `s = (−d/2 sin φ/2, d/2 cos φ/2 ř + sin φ/2 l × ř)`.
    pub fn from_screw(screw: &Screw) -> Self {
        let dir = screw.direction.normalize();
        // Only the component of the point orthogonal to the axis matters.
        let l = screw.point - dir * dir.dot(&screw.point);
        let (sn, cs) = (0.5 * screw.angle).sin_cos();
        let r = Vector4::new(cs, sn * dir.x, sn * dir.y, sn * dir.z);
        let sv = 0.5 * screw.d * cs * dir + sn * l.cross(&dir);
        DualQuaternion {
            r,
            s: Vector4::new(-0.5 * screw.d * sn, sv.x, sv.y, sv.z),
        }
    }

    /// To Chasles' screw. For a pure translation (φ = 0) the axis is the translation direction through
    /// the origin; for the identity it is `(0, 0, 1)`.
    pub fn to_screw(&self) -> Screw {
        let (rot, t) = self.to_rotation_translation();
        let (direction, angle) = axis_angle(&from_rotation_matrix(&rot));
        if angle < 1e-12 {
            let d = t.norm();
            let direction = if d > 0.0 { t / d } else { Vector3::z() };
            return Screw {
                d,
                angle: 0.0,
                direction,
                point: Vector3::zeros(),
            };
        }
        let d = t.dot(&direction);
        let t_perp = t - d * direction;
        // t_perp = (I − R) l for l ⊥ axis, whose solution is l = ½ (t_perp + cot(φ/2) ř × t_perp).
        let point = 0.5 * (t_perp + direction.cross(&t_perp) / (0.5 * angle).tan());
        Screw {
            d,
            angle,
            direction,
            point,
        }
    }

    /// The composition `self ∘ other`: first `other`, then `self`
    /// (`(r₁, s₁)(r₂, s₂) = (r₁ r₂, r₁ s₂ + s₁ r₂)`).
    pub fn compose(&self, other: &DualQuaternion) -> Self {
        DualQuaternion {
            r: multiply(&self.r, &other.r),
            s: multiply(&self.r, &other.s) + multiply(&self.s, &other.r),
        }
    }

    /// The inverse motion `(r̄, s̄)` of a rigid motion.
    pub fn inverse(&self) -> Self {
        DualQuaternion {
            r: conjugate(&self.r),
            s: conjugate(&self.s),
        }
    }

    /// Applies the motion to a point: `R X + t`.
    pub fn transform_point(&self, x: &Vector3<f64>) -> Vector3<f64> {
        let (rot, t) = self.to_rotation_translation();
        rot * x + t
    }

    /// The 8-vector `(r, s)` the solvers iterate on.
    pub fn to_vector(&self) -> nalgebra::SVector<f64, 8> {
        let mut x = nalgebra::SVector::<f64, 8>::zeros();
        x.fixed_rows_mut::<4>(0).copy_from(&self.r);
        x.fixed_rows_mut::<4>(4).copy_from(&self.s);
        x
    }

    /// From the 8-vector `(r, s)`.
    pub fn from_vector(x: &nalgebra::SVector<f64, 8>) -> Self {
        DualQuaternion {
            r: x.fixed_rows::<4>(0).into_owned(),
            s: x.fixed_rows::<4>(4).into_owned(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    fn random_motion(rng: &mut Rng) -> (Matrix3<f64>, Vector3<f64>) {
        let t = Vector3::new(rng.normal(), rng.normal(), rng.normal()) * 5.0;
        (rng.rotation(), t)
    }

    #[test]
    fn rotation_translation_round_trip_and_constraints() {
        let mut rng = Rng::new(1);
        for _ in 0..200 {
            let (rot, t) = random_motion(&mut rng);
            let q = DualQuaternion::from_rotation_translation(&rot, &t);
            let (c1, c2) = q.constraint_residuals();
            assert!(c1.abs() < 1e-12 && c2.abs() < 1e-12);
            let (r2, t2) = q.to_rotation_translation();
            assert!((r2 - rot).norm() < 1e-12 && (t2 - t).norm() < 1e-12);
            let x = Vector3::new(rng.normal(), rng.normal(), rng.normal());
            assert!((q.transform_point(&x) - (rot * x + t)).norm() < 1e-12);
        }
    }

    #[test]
    fn screw_round_trip_and_agreement_with_eq7() {
        let mut rng = Rng::new(2);
        for _ in 0..200 {
            let (rot, t) = random_motion(&mut rng);
            let q = DualQuaternion::from_rotation_translation(&rot, &t);
            let screw = q.to_screw();
            assert!(screw.point.dot(&screw.direction).abs() < 1e-9);
            // The screw moves a point on its axis by d along the axis.
            let on_axis = screw.point + 0.7 * screw.direction;
            assert!((q.transform_point(&on_axis) - (on_axis + screw.d * screw.direction)).norm() < 1e-9);
            // The paper's screw formula gives the same dual quaternion (up to the global sign ±q̂).
            let q2 = DualQuaternion::from_screw(&screw);
            let same = (q2.r - q.r).norm() + (q2.s - q.s).norm();
            let opposite = (q2.r + q.r).norm() + (q2.s + q.s).norm();
            assert!(same.min(opposite) < 1e-9, "{same} {opposite}");
        }
    }

    #[test]
    fn composition_and_inverse_are_the_group_operations() {
        let mut rng = Rng::new(3);
        for _ in 0..100 {
            let (r1, t1) = random_motion(&mut rng);
            let (r2, t2) = random_motion(&mut rng);
            let a = DualQuaternion::from_rotation_translation(&r1, &t1);
            let b = DualQuaternion::from_rotation_translation(&r2, &t2);
            let x = Vector3::new(rng.normal(), rng.normal(), rng.normal());
            let ab = a.compose(&b);
            assert!((ab.transform_point(&x) - a.transform_point(&b.transform_point(&x))).norm() < 1e-9);
            let id = a.compose(&a.inverse());
            let (ri, ti) = id.to_rotation_translation();
            assert!((ri - Matrix3::identity()).norm() < 1e-12 && ti.norm() < 1e-9);
            let (c1, c2) = ab.constraint_residuals();
            assert!(c1.abs() < 1e-12 && c2.abs() < 1e-12);
        }
    }

    #[test]
    fn normalization_projects_onto_the_constraints() {
        let q = DualQuaternion {
            r: Vector4::new(2.0, 0.1, -0.3, 0.2),
            s: Vector4::new(0.5, 1.0, 2.0, -1.0),
        };
        let (c1, c2) = q.normalized().constraint_residuals();
        assert!(c1.abs() < 1e-12 && c2.abs() < 1e-12);
    }
}
