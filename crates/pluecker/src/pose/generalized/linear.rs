//! The linear pose of a generalised camera (a [`crate::Rig`], whose rays need not meet in one
//! centre) from six or more rays and their object points: the non-minimal step of the rig's pose.
//!
//! A ray is a line of the rig's frame, a point `c` of it (its camera's centre) and its direction `d`
//! (the observed bearing turned into the rig's frame); in Plücker coordinates `(d, c × d)`. The object
//! point `X` lies on it at the pose `x_rig = R X + t` when `d × (R X + t − c) = 0`: three equations,
//! two of them independent, linear in the nine entries of `R`, the three of `t` and a homogeneous
//! scale `s` multiplying `d × c`. With `n ≥ 6` rays the 13 unknowns are the right singular vector of
//! the `3n x 13` system of least singular value, scaled to `s = 1`. When every ray passes through one
//! point (a central rig, or a single camera) `d × c` is the same linear function of `d` for every ray
//! and `s` is not fixed: the rays are then moved to pass through the origin and the 12 unknowns of
//! `(R, t)` are solved up to scale (the direct linear transform of a calibrated camera), the scale
//! following from `det R = 1`. Either way `R` is then the rotation nearest to the solved matrix (its
//! polar factor), and `t` the least-squares solution of the ray equations at that `R`.
//!
//! The equations are solved on conditioned data: the object points centred at their centroid and the
//! rays at their origins' centroid, both divided by the object's RMS radius (one scale for both frames,
//! so that `R` stays a rotation). Like every linear estimate it minimises an algebraic error, not the
//! reprojection error: it starts the refinement. Six points on a plane leave the 12 unknowns
//! undetermined (the plane's normal direction of `R` is free): coplanar object points are
//! [`Error::Degenerate`], as for the single camera's linear method.
//!
//! [`rays`] makes the rays of a rig's observed points: each pixel unprojected through its camera's
//! lens and turned into the rig's frame.

use super::ObservingCameras;
use crate::camera_pose::Pose;
use crate::error::{Error, Result};
use crate::geometry::quaternion::skew;
use crate::pose::correspondences::{principal_axes, DEGENERACY_TOLERANCE};
use crate::pose::Correspondences;
use crate::rig::Rig;
use nalgebra::{DMatrix, Matrix3, Vector3};

/// A ray of a generalised camera in the rig's frame: a point `origin` of it (its camera's optical
/// centre) and its `direction` (any length but zero: the bearing of an observation, turned into the
/// rig's frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ray {
    /// A point of the ray, rig frame (its camera's centre).
    pub origin: Vector3<f64>,
    /// Its direction, rig frame.
    pub direction: Vector3<f64>,
}

/// The pose `x_rig = R X + t` under which every object point `points[i]` lies on `rays[i]` (module
/// docs), in the least-squares sense of the linear equations. Errors: fewer than 6 rays
/// ([`Error::TooFewCorrespondences`]), not one point per ray ([`Error::Shape`]), a non-finite entry
/// or a zero direction ([`Error::NonFinite`], [`Error::Degenerate`] naming the row), coplanar object
/// points or equations of rank below what the pose needs ([`Error::Degenerate`]).
pub fn linear_pose(rays: &[Ray], points: &[Vector3<f64>]) -> Result<Pose> {
    let n = rays.len();
    if points.len() != n {
        return Err(Error::Shape {
            what: "points".into(),
            expected: format!("one object point per ray ({n})"),
            actual: format!("{} points", points.len()),
        });
    }
    if n < 6 {
        return Err(Error::TooFewCorrespondences {
            method: "generalized linear".into(),
            required: "at least 6 rays with their object points".into(),
            actual: format!("{n}"),
        });
    }
    for (i, (ray, x)) in rays.iter().zip(points).enumerate() {
        let finite = ray
            .origin
            .iter()
            .chain(ray.direction.iter())
            .chain(x.iter())
            .all(|v| v.is_finite());
        if !finite {
            return Err(Error::NonFinite {
                what: "rays and points".into(),
                index: i,
            });
        }
        if ray.direction.norm() == 0.0 {
            return Err(Error::Degenerate {
                what: format!("rays[{i}] has a zero direction"),
            });
        }
    }
    let shape = principal_axes(points.iter());
    if shape.degenerate(points.iter(), 2, DEGENERACY_TOLERANCE) {
        return Err(Error::Degenerate {
            what: "the object points are coplanar; the generalized linear pose needs 6 non-coplanar points".into(),
        });
    }
    // Conditioning: one scale for both frames (module docs).
    let scale = shape.rms_radius;
    let object_centre = shape.centroid;
    let origin_centre = rays.iter().map(|r| r.origin).sum::<Vector3<f64>>() / n as f64;
    let xs: Vec<Vector3<f64>> = points.iter().map(|x| (x - object_centre) / scale).collect();
    let ds: Vec<Vector3<f64>> = rays.iter().map(|r| r.direction.normalize()).collect();
    let cs: Vec<Vector3<f64>> = rays.iter().map(|r| (r.origin - origin_centre) / scale).collect();
    let spread = cs.iter().map(|c| c.norm()).fold(0.0, f64::max);
    // A central rig: every ray through one point (to the rounding of the conditioned origins).
    let central = spread <= 1e-12;
    let columns = if central { 12 } else { 13 };
    let mut a = DMatrix::<f64>::zeros(3 * n, columns);
    for (i, ((x, d), c)) in xs.iter().zip(&ds).zip(&cs).enumerate() {
        let dx = skew(d);
        for col in 0..3 {
            // R X = Σ_col X[col] R[:, col]: the columns of vec(R) (column-major) times X[col].
            a.view_mut((3 * i, 3 * col), (3, 3)).copy_from(&(dx * x[col]));
        }
        a.view_mut((3 * i, 9), (3, 3)).copy_from(&dx);
        if !central {
            a.view_mut((3 * i, 12), (3, 1)).copy_from(&(-d.cross(c)));
        }
    }
    let svd = a.svd(false, true);
    let v_t = svd.v_t.ok_or_else(|| Error::Degenerate {
        what: "the generalized linear equations could not be decomposed".into(),
    })?;
    let mut order: Vec<usize> = (0..columns).collect();
    order.sort_by(|&i, &j| svd.singular_values[i].total_cmp(&svd.singular_values[j]));
    let (least, next) = (order[0], order[1]);
    // A second null direction: the equations do not fix the pose.
    if svd.singular_values[next] <= 1e-10 * svd.singular_values[order[columns - 1]] {
        return Err(Error::Degenerate {
            what: "the rays and points leave the generalized linear pose undetermined (rank below 12)".into(),
        });
    }
    let z: Vec<f64> = v_t.row(least).iter().copied().collect();
    let m = Matrix3::from_column_slice(&z[0..9]);
    // The scale: s = 1 (non-central), or det R = 1 (central).
    let factor = if central {
        let det = m.determinant();
        if det == 0.0 || !det.is_finite() {
            return Err(Error::Degenerate {
                what: "the generalized linear solution has a singular rotation part".into(),
            });
        }
        det.signum() / det.abs().cbrt()
    } else {
        if z[12].abs() <= 1e-12 {
            return Err(Error::Degenerate {
                what: "the rays' origins do not fix the generalized linear pose's scale".into(),
            });
        }
        1.0 / z[12]
    };
    let rotation = nearest_rotation(&(m * factor));
    // t̂ from the ray equations at R: Σ [d]×ᵀ[d]× t̂ = Σ [d]×ᵀ[d]× (ĉ − R X̂).
    let (mut normal, mut rhs) = (Matrix3::zeros(), Vector3::zeros());
    for ((x, d), c) in xs.iter().zip(&ds).zip(&cs) {
        let p = skew(d).transpose() * skew(d);
        normal += p;
        rhs += p * (c - rotation * x);
    }
    let t_hat = normal.try_inverse().ok_or_else(|| Error::Degenerate {
        what: "the rays are all parallel: the generalized linear pose's translation is undetermined".into(),
    })? * rhs;
    // Back to the frames as given: x_rig − μ_c = s (R (X − μ_X)/s + t̂).
    let translation = scale * t_hat + origin_centre - rotation * object_centre;
    Ok(Pose::new(rotation, translation))
}

/// The rotation nearest to `m` in the Frobenius norm (the polar factor `U Vᵀ`, with `det = +1`).
fn nearest_rotation(m: &Matrix3<f64>) -> Matrix3<f64> {
    let svd = m.svd(true, true);
    let (u, v_t) = (svd.u.expect("requested"), svd.v_t.expect("requested"));
    let mut d = Matrix3::identity();
    if (u * v_t).determinant() < 0.0 {
        d[(2, 2)] = -1.0;
    }
    u * d * v_t
}

/// The ray of each observed point of `corr` in the rig's frame: its camera's centre and the bearing of
/// its pixel (unprojected through the camera's lens), turned into the rig's frame; the input of
/// [`linear_pose`]. `cameras` must have been checked against `rig` and `corr`
/// ([`ObservingCameras::check`]). A pixel its lens cannot unproject is [`Error::Degenerate`] naming
/// `points2d[i]` and the camera.
pub fn rays(rig: &Rig, corr: &Correspondences, cameras: &ObservingCameras) -> Result<Vec<Ray>> {
    let centres = rig.centres();
    corr.points2d
        .iter()
        .enumerate()
        .map(|(i, pixel)| {
            let k = cameras.point(i);
            let n = rig.cameras()[k].unproject(pixel, i).map_err(|e| Error::Degenerate {
                what: format!("points2d[{i}] (camera {k}): {e}"),
            })?;
            let turn = rig.sensor_from_rig()[k].rotation.transpose();
            Ok(Ray {
                origin: centres[k],
                direction: turn * Vector3::new(n.x, n.y, 1.0),
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;
    use nalgebra::Rotation3;

    fn random_rotation(rng: &mut Rng) -> Matrix3<f64> {
        let axis = rng.unit_vector3();
        Rotation3::from_scaled_axis(axis * rng.uniform_in(0.0, 3.0)).into_inner()
    }

    /// `n` object points in a cube about `(0, 0, 6)` of the rig (so in front of every camera looking
    /// down `+z`), their rays from `cameras` rig-frame centres chosen in turn, and the true pose.
    fn scene(cameras: &[Vector3<f64>], n: usize, noise: f64, rng: &mut Rng) -> (Vec<Ray>, Vec<Vector3<f64>>, Pose) {
        let truth = Pose::new(
            random_rotation(rng),
            Vector3::new(rng.normal(), rng.normal(), rng.normal()),
        );
        let inverse = truth.inverse();
        let (mut rays, mut points) = (Vec::new(), Vec::new());
        for i in 0..n {
            let y = Vector3::new(
                rng.uniform_in(-2.0, 2.0),
                rng.uniform_in(-2.0, 2.0),
                rng.uniform_in(4.0, 8.0),
            );
            let c = cameras[i % cameras.len()];
            let d = (y - c).normalize() + noise * Vector3::new(rng.normal(), rng.normal(), rng.normal());
            rays.push(Ray {
                origin: c,
                direction: d,
            });
            points.push(inverse.transform(&y));
        }
        (rays, points, truth)
    }

    fn rig_centres(k: usize, baseline: f64, rng: &mut Rng) -> Vec<Vector3<f64>> {
        (0..k)
            .map(|_| baseline * Vector3::new(rng.normal(), rng.normal(), rng.normal()))
            .collect()
    }

    #[test]
    fn noise_free_rays_give_the_pose_exactly_for_rigs_and_single_cameras() {
        let mut rng = Rng::new(41);
        for (cameras, baseline) in [(1, 0.0), (2, 0.3), (4, 1.0), (6, 0.05), (3, 3.0)] {
            for n in [6, 7, 20, 200] {
                let centres = rig_centres(cameras, baseline, &mut rng);
                let (rays, points, truth) = scene(&centres, n, 0.0, &mut rng);
                let pose = linear_pose(&rays, &points).unwrap();
                let (dr, dt) = (
                    (pose.rotation - truth.rotation).amax(),
                    (pose.translation - truth.translation).amax(),
                );
                assert!(
                    dr < 1e-9 && dt < 1e-8,
                    "{cameras} cameras, {n} rays: |ΔR| {dr:e}, |Δt| {dt:e}"
                );
                assert!((pose.rotation.determinant() - 1.0).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn the_rays_of_a_central_rig_away_from_the_origin_give_the_pose() {
        let mut rng = Rng::new(5);
        let centre = Vector3::new(0.4, -1.0, 0.2);
        let (rays, points, truth) = scene(&[centre, centre, centre], 30, 0.0, &mut rng);
        let pose = linear_pose(&rays, &points).unwrap();
        assert!((pose.rotation - truth.rotation).amax() < 1e-9);
        assert!((pose.translation - truth.translation).amax() < 1e-8);
    }

    #[test]
    fn noisy_rays_give_a_pose_near_the_truth() {
        let mut rng = Rng::new(9);
        let centres = rig_centres(4, 0.5, &mut rng);
        // 1e-3 rad of direction noise: about 1 px at f = 1000 px.
        let (rays, points, truth) = scene(&centres, 100, 1e-3, &mut rng);
        let pose = linear_pose(&rays, &points).unwrap();
        let angle = crate::geometry::quaternion::rotation_distance(&pose.rotation, &truth.rotation);
        assert!(angle < 0.01, "rotation off by {angle} rad");
        assert!((pose.translation - truth.translation).norm() < 0.1);
    }

    #[test]
    fn too_few_coplanar_or_bad_rays_are_errors_naming_why() {
        let mut rng = Rng::new(3);
        let centres = rig_centres(2, 0.3, &mut rng);
        let (rays, mut points, _) = scene(&centres, 8, 0.0, &mut rng);
        assert!(matches!(
            linear_pose(&rays[..5], &points[..5]),
            Err(Error::TooFewCorrespondences { .. })
        ));
        assert!(matches!(linear_pose(&rays, &points[..7]), Err(Error::Shape { .. })));
        let mut bad = rays.clone();
        bad[3].direction = Vector3::zeros();
        let err = linear_pose(&bad, &points).unwrap_err().to_string();
        assert!(err.contains("rays[3]"), "{err}");
        bad[3].direction = Vector3::new(f64::NAN, 0.0, 1.0);
        assert!(matches!(
            linear_pose(&bad, &points),
            Err(Error::NonFinite { index: 3, .. })
        ));
        for p in points.iter_mut() {
            p.z = 2.0; // every object point on the plane z = 2
        }
        let err = linear_pose(&rays, &points).unwrap_err().to_string();
        assert!(err.contains("coplanar"), "{err}");
    }
}
