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
//! [`refine`] then minimises the rig's reprojection error, `½ Σ ‖π_k(R_k (R X + t) + t_k) − u‖²` over the
//! points `X` seen as pixels `u` by the cameras `k` (each through its own lens, in its own pixels), with
//! the trust region of section 4.1 ([`RigReprojectionCost`]).

use super::correspondences::{principal_axes, DEGENERACY_TOLERANCE};
use super::reprojection::{covariance_from_information, retract};
use crate::camera_pose::Pose;
use crate::error::{Error, Result};
use crate::geometry::quaternion::skew;
use crate::optim::{trust_region, Linearization, Objective, Summary, TrustRegionOptions};
use crate::rig::Rig;
use nalgebra::{DMatrix, Matrix2x3, Matrix3, SMatrix, SVector, Vector2, Vector3};

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

/// A point seen by one camera of a rig: the camera's index in the rig, the observed pixel (that
/// camera's own, through its lens) and the object point (world frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RigPoint {
    /// The index of the camera in the rig.
    pub camera: usize,
    /// The observed pixel.
    pub pixel: Vector2<f64>,
    /// The object point, world frame.
    pub point: Vector3<f64>,
}

/// Checks that every point names a camera of `rig`: [`Error::Shape`] naming `points[i].camera`.
fn check_cameras(rig: &Rig, points: &[RigPoint]) -> Result<()> {
    match points.iter().position(|p| p.camera >= rig.len()) {
        Some(i) => Err(Error::Shape {
            what: format!("points[{i}].camera"),
            expected: format!("a camera index below {}", rig.len()),
            actual: points[i].camera.to_string(),
        }),
        None => Ok(()),
    }
}

/// The ray of each observation in the rig's frame: its camera's centre and the bearing of its pixel
/// (unprojected through the camera's lens), turned into the rig's frame; the input of
/// [`linear_pose`]. Errors: a camera index out of range, a pixel the lens cannot unproject (naming it).
pub fn rays(rig: &Rig, points: &[RigPoint]) -> Result<Vec<Ray>> {
    check_cameras(rig, points)?;
    let centres = rig.centres();
    points
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let n = rig.cameras()[p.camera].unproject(&p.pixel, i)?;
            let turn = rig.sensor_from_rig()[p.camera].rotation.transpose();
            Ok(Ray {
                origin: centres[p.camera],
                direction: turn * Vector3::new(n.x, n.y, 1.0),
            })
        })
        .collect()
}

/// The reprojection cost of a rig's points at `rig_from_world` (module docs), in each camera's own
/// pixels, with its Jacobian in the tangent `(ω, t)` of `exp(ω) R`, `t` (as the single camera's
/// [`crate::pose::ReprojectionCost`]).
pub struct RigReprojectionCost<'a> {
    rig: &'a Rig,
    points: &'a [RigPoint],
}

impl<'a> RigReprojectionCost<'a> {
    /// The cost of `points` seen by `rig`; an error names a point whose camera index is out of range.
    pub fn new(rig: &'a Rig, points: &'a [RigPoint]) -> Result<Self> {
        check_cameras(rig, points)?;
        Ok(RigReprojectionCost { rig, points })
    }

    /// The covariance of `rig_from_world` at `pose`, 6x6 in the tangent `(ω, t)` (as the single
    /// camera's [`crate::pose::PoseResult::covariance`]): `σ² (JᵀJ)⁻¹` for pixel noise `sigma_px` in
    /// every camera; `None` when `JᵀJ` is singular (the points do not fix the pose).
    pub fn covariance(&self, pose: &Pose, sigma_px: f64) -> Option<SMatrix<f64, 6, 6>> {
        covariance_from_information(&self.linearize(pose).gauss_newton, sigma_px)
    }

    /// The point `p` in its camera's frame at `rig_from_world`, and in the rig's frame.
    fn in_camera(&self, pose: &Pose, p: &RigPoint) -> (Vector3<f64>, Vector3<f64>) {
        let x_rig = pose.transform(&p.point);
        (self.rig.sensor_from_rig()[p.camera].transform(&x_rig), x_rig)
    }
}

impl Objective<6> for RigReprojectionCost<'_> {
    type Point = Pose;

    fn cost(&self, pose: &Pose) -> f64 {
        let sum: f64 = self
            .points
            .iter()
            .map(|p| {
                let (x_cam, _) = self.in_camera(pose, p);
                (self.rig.cameras()[p.camera].project(&x_cam) - p.pixel).norm_squared()
            })
            .sum();
        0.5 * sum
    }

    fn linearize(&self, pose: &Pose) -> Linearization<6> {
        let mut lin = Linearization::zero();
        for p in self.points {
            let (x_cam, x_rig) = self.in_camera(pose, p);
            let (pixel, d_pixel) = self.rig.cameras()[p.camera].project_with_jacobian(&x_cam);
            // x_rig moves by ω × (R X) + δt under exp(ω) R, t + δt; the camera frame by R_k times that.
            let rotated = x_rig - pose.translation;
            let mut d_rig = SMatrix::<f64, 3, 6>::zeros();
            d_rig.fixed_view_mut::<3, 3>(0, 0).copy_from(&(-skew(&rotated)));
            d_rig.fixed_view_mut::<3, 3>(0, 3).copy_from(&Matrix3::identity());
            let jacobian: Matrix2x3<f64> = d_pixel * self.rig.sensor_from_rig()[p.camera].rotation;
            lin.add(&(pixel - p.pixel), &(jacobian * d_rig));
        }
        lin
    }

    fn retract(&self, pose: &Pose, d: &SVector<f64, 6>) -> Pose {
        retract(pose, d)
    }
}

/// Minimises the rig's reprojection cost of `points` from `initial` (`rig_from_world`) with the trust
/// region of section 4.1 and `options`; the pose reached and the solver's summary (costs `½ Σ r²`).
pub fn refine(rig: &Rig, points: &[RigPoint], initial: &Pose, options: &TrustRegionOptions) -> Result<(Pose, Summary)> {
    let cost = RigReprojectionCost::new(rig, points)?;
    Ok(trust_region::minimize(&cost, *initial, options))
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::quaternion::exp_so3;
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

    /// A rig of a pinhole, an OPENCV and a SIMPLE_RADIAL camera looking three ways, `per_camera` points
    /// in front of each (pixels exact), and the rig's true pose.
    fn lens_rig_scene(per_camera: usize, rng: &mut Rng) -> (Rig, Vec<RigPoint>, Pose) {
        use crate::camera::{Camera, CameraModel};
        let cameras = vec![
            Camera::pinhole(800.0, 800.0, 320.0, 240.0, 0.0).unwrap(),
            Camera::new(
                CameraModel::OpenCv,
                &[600.0, 610.0, 320.0, 240.0, -0.1, 0.01, 1e-3, -1e-3],
            )
            .unwrap(),
            Camera::new(CameraModel::SimpleRadial, &[500.0, 320.0, 240.0, 0.05]).unwrap(),
        ];
        let poses = vec![
            Pose::identity(),
            Pose::new(
                Rotation3::from_euler_angles(0.0, 1.2, 0.0).into_inner(),
                Vector3::new(0.2, 0.0, -0.1),
            ),
            Pose::new(
                Rotation3::from_euler_angles(0.1, -1.4, 0.2).into_inner(),
                Vector3::new(-0.3, 0.05, 0.0),
            ),
        ];
        let rig = Rig::new(cameras, poses).unwrap();
        let truth = Pose::new(
            random_rotation(rng),
            Vector3::new(rng.normal(), rng.normal(), rng.normal()),
        );
        let mut points = Vec::new();
        for k in 0..rig.len() {
            let world_from_camera = rig.sensor_from_world(k, &truth).inverse();
            for _ in 0..per_camera {
                let x_cam = Vector3::new(rng.uniform_in(-0.3, 0.3), rng.uniform_in(-0.25, 0.25), 1.0)
                    * rng.uniform_in(3.0, 9.0);
                let pixel = rig.cameras()[k].project(&x_cam);
                points.push(RigPoint {
                    camera: k,
                    pixel,
                    point: world_from_camera.transform(&x_cam),
                });
            }
        }
        (rig, points, truth)
    }

    #[test]
    fn through_lenses_the_linear_pose_and_its_refinement_find_the_rigs_pose() {
        let mut rng = Rng::new(17);
        let (rig, points, truth) = lens_rig_scene(8, &mut rng);
        let rays = rays(&rig, &points).unwrap();
        let objects: Vec<Vector3<f64>> = points.iter().map(|p| p.point).collect();
        let linear = linear_pose(&rays, &objects).unwrap();
        assert!((linear.rotation - truth.rotation).amax() < 1e-8, "{:?}", linear);
        // From a start 0.05 rad and 0.1 units off, the refinement returns to the truth.
        let start = Pose::new(
            exp_so3(&Vector3::new(0.03, -0.02, 0.03)) * truth.rotation,
            truth.translation + Vector3::new(0.1, -0.05, 0.05),
        );
        let (pose, summary) = refine(&rig, &points, &start, &TrustRegionOptions::default()).unwrap();
        // Converged on exact pixels: residuals below 1e-5 px RMS (½ Σ r² over 2n residuals), so a pose
        // within about 1e-5 px / 500 px of rotation and that times the 3-9 unit depths of translation.
        assert!(summary.final_cost < 1e-10 * points.len() as f64, "{summary:?}");
        assert!((pose.rotation - truth.rotation).amax() < 1e-7, "{pose:?}");
        assert!((pose.translation - truth.translation).amax() < 1e-6, "{pose:?}");
    }

    #[test]
    fn the_gradient_is_the_costs_derivative_along_the_tangent() {
        let mut rng = Rng::new(23);
        let (rig, mut points, truth) = lens_rig_scene(4, &mut rng);
        for p in points.iter_mut() {
            p.pixel += Vector2::new(rng.normal(), rng.normal()); // residuals that are not zero
        }
        let cost = RigReprojectionCost::new(&rig, &points).unwrap();
        let lin = cost.linearize(&truth);
        assert!((lin.cost - cost.cost(&truth)).abs() <= 1e-12 * lin.cost);
        for j in 0..6 {
            let mut step = SVector::<f64, 6>::zeros();
            step[j] = 1e-6;
            let ahead = cost.cost(&cost.retract(&truth, &step));
            let behind = cost.cost(&cost.retract(&truth, &(-step)));
            let numeric = (ahead - behind) / 2e-6;
            assert!(
                (numeric - lin.gradient[j]).abs() <= 1e-5 * (1.0 + lin.gradient[j].abs()),
                "{j}: {numeric} vs {}",
                lin.gradient[j]
            );
        }
    }

    #[test]
    fn the_covariance_predicts_the_spread_of_refined_poses() {
        // Monte Carlo: N noisy copies of one scene, each refined from the truth; the Mahalanobis
        // distances d² of the errors under the predicted covariance average 6 (the pose's dimension)
        // within 4 standard errors, √(2·6/N) · 4, and so does each whitened coordinate's variance
        // (1 within 4 √(2/N)).
        let mut rng = Rng::new(31);
        let (rig, exact, truth) = lens_rig_scene(6, &mut rng);
        let sigma = 0.7;
        let cost = RigReprojectionCost::new(&rig, &exact).unwrap();
        let covariance = cost.covariance(&truth, sigma).unwrap();
        let whiten = covariance.cholesky().unwrap().l().try_inverse().unwrap(); // L⁻¹ of Σ = L Lᵀ
        let trials = 400;
        let (mut d2, mut diagonal) = (0.0, SVector::<f64, 6>::zeros());
        for _ in 0..trials {
            let noisy: Vec<RigPoint> = exact
                .iter()
                .map(|p| RigPoint {
                    pixel: p.pixel + sigma * Vector2::new(rng.normal(), rng.normal()),
                    ..*p
                })
                .collect();
            let (pose, _) = refine(&rig, &noisy, &truth, &TrustRegionOptions::default()).unwrap();
            let omega = crate::geometry::quaternion::log_so3(&(pose.rotation * truth.rotation.transpose()));
            let error = SVector::<f64, 6>::from_iterator(
                omega
                    .iter()
                    .chain((pose.translation - truth.translation).iter())
                    .copied(),
            );
            let z = whiten * error;
            d2 += z.norm_squared() / trials as f64;
            diagonal += z.component_mul(&z) / trials as f64;
        }
        let n = trials as f64;
        assert!((d2 - 6.0).abs() < 4.0 * (12.0 / n).sqrt(), "mean d² {d2}");
        for (j, v) in diagonal.iter().enumerate() {
            assert!(
                (v - 1.0).abs() < 4.0 * (2.0 / n).sqrt(),
                "coordinate {j}: whitened variance {v}"
            );
        }
    }

    #[test]
    fn a_point_of_a_camera_the_rig_does_not_have_is_named() {
        let mut rng = Rng::new(2);
        let (rig, mut points, truth) = lens_rig_scene(2, &mut rng);
        points[4].camera = 3;
        let err = RigReprojectionCost::new(&rig, &points).err().unwrap().to_string();
        assert!(err.contains("points[4].camera") && err.contains("below 3"), "{err}");
        assert!(rays(&rig, &points).is_err() && refine(&rig, &points, &truth, &TrustRegionOptions::default()).is_err());
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
