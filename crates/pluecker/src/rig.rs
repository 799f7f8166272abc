//! A camera rig: several cameras fixed to one body, as COLMAP's rigs are. Each camera (a sensor)
//! has its pose in the body's frame, `x_sensor = R_k x_rig + t_k` (`sensor_from_rig[k]`); the pose of
//! the body, `rig_from_world` (`x_rig = R X_world + t`), then places every camera:
//! `sensor_from_world[k] = sensor_from_rig[k] ∘ rig_from_world`. A single camera is the rig of one
//! camera at the identity.
//!
//! Every observation of a rig is a ray that starts at its own camera's centre; the rays of several
//! cameras do not meet in one point. The lines of those rays, in Plücker coordinates, are what the
//! generalised pose works with.

use crate::camera::Camera;
use crate::camera_pose::Pose;
use crate::error::{Error, Result};
use nalgebra::{Matrix3, SMatrix, Vector3};

/// Cameras fixed to one body, each with its pose `x_sensor = R x_rig + t` in the body's frame
/// (module docs). Built by [`Rig::new`], which checks it; the fields are read through the methods.
///
/// ```
/// use pluecker::nalgebra::{Matrix3, Vector3};
/// use pluecker::{Camera, Pose, Rig};
///
/// let camera = Camera::pinhole(800.0, 800.0, 320.0, 240.0, 0.0).unwrap();
/// // A stereo pair: the second camera 0.2 units to the right of the first (the body's origin).
/// let right = Pose::new(Matrix3::identity(), Vector3::new(-0.2, 0.0, 0.0));
/// let rig = Rig::new(vec![camera.clone(), camera], vec![Pose::identity(), right]).unwrap();
/// assert_eq!(rig.len(), 2);
/// assert!((rig.centres()[1] - Vector3::new(0.2, 0.0, 0.0)).norm() < 1e-15);
/// // Where the rig stands in the world places each camera.
/// let rig_from_world = Pose::new(Matrix3::identity(), Vector3::new(0.0, 0.0, 5.0));
/// let second = rig.sensor_from_world(1, &rig_from_world);
/// assert!((second.translation - Vector3::new(-0.2, 0.0, 5.0)).norm() < 1e-15);
/// ```
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(try_from = "RigParts", into = "RigParts")
)]
pub struct Rig {
    cameras: Vec<Camera>,
    sensor_from_rig: Vec<Pose>,
}

impl Rig {
    /// The rig of `cameras`, camera `k` at `sensor_from_rig[k]`. Errors: no camera, or not one pose per
    /// camera ([`Error::Shape`] naming `sensor_from_rig`); a pose whose rotation is not a rotation
    /// matrix ([`Pose::rotation_defect`]) or whose translation is not finite ([`Error::InvalidOption`]
    /// naming `sensor_from_rig[k]`).
    pub fn new(cameras: Vec<Camera>, sensor_from_rig: Vec<Pose>) -> Result<Rig> {
        if cameras.is_empty() {
            return Err(Error::Shape {
                what: "cameras".into(),
                expected: "at least one camera".into(),
                actual: "none".into(),
            });
        }
        if sensor_from_rig.len() != cameras.len() {
            return Err(Error::Shape {
                what: "sensor_from_rig".into(),
                expected: format!("one pose per camera ({})", cameras.len()),
                actual: format!("{} poses", sensor_from_rig.len()),
            });
        }
        for (k, pose) in sensor_from_rig.iter().enumerate() {
            let defect = Pose::rotation_defect(&pose.rotation).or_else(|| {
                (!pose.translation.iter().all(|v| v.is_finite()))
                    .then(|| "the translation has a NaN or infinite entry".to_string())
            });
            if let Some(reason) = defect {
                return Err(Error::InvalidOption {
                    name: format!("sensor_from_rig[{k}]"),
                    reason,
                });
            }
        }
        Ok(Rig {
            cameras,
            sensor_from_rig,
        })
    }

    /// The rig of one camera at the body's origin: `rig_from_world` is that camera's pose.
    pub fn single(camera: Camera) -> Rig {
        Rig {
            cameras: vec![camera],
            sensor_from_rig: vec![Pose::identity()],
        }
    }

    /// The same rig with every `sensor_from_rig` translation multiplied by `factor`: the rig in a
    /// length unit `1 / factor` times the given one (the pose's search runs on conditioned data).
    pub(crate) fn scaled(&self, factor: f64) -> Rig {
        Rig {
            cameras: self.cameras.clone(),
            sensor_from_rig: self
                .sensor_from_rig
                .iter()
                .map(|p| Pose::new(p.rotation, factor * p.translation))
                .collect(),
        }
    }

    /// The cameras, in order.
    pub fn cameras(&self) -> &[Camera] {
        &self.cameras
    }

    /// Camera `k`'s pose in the body's frame, `x_sensor = R x_rig + t`, in the cameras' order.
    pub fn sensor_from_rig(&self) -> &[Pose] {
        &self.sensor_from_rig
    }

    /// The number of cameras (at least one).
    pub fn len(&self) -> usize {
        self.cameras.len()
    }

    /// Always false: a rig has a camera ([`Rig::new`]).
    pub fn is_empty(&self) -> bool {
        false
    }

    /// Camera `k`'s pose in the world when the body is at `rig_from_world`:
    /// `sensor_from_rig[k] ∘ rig_from_world`. Panics when `k ≥ len()`.
    pub fn sensor_from_world(&self, k: usize, rig_from_world: &Pose) -> Pose {
        self.sensor_from_rig[k].compose(rig_from_world)
    }

    /// The cameras' optical centres in the body's frame, `−R_kᵀ t_k`.
    pub fn centres(&self) -> Vec<Vector3<f64>> {
        self.sensor_from_rig.iter().map(Pose::centre).collect()
    }

    /// Whether every camera has its optical centre at the same point (within `1e-12` of the rig's
    /// size, or exactly for a single camera): such a rig is one central camera seen through several
    /// images, and its pose problem is that of one camera.
    pub fn is_central(&self) -> bool {
        let centres = self.centres();
        let first = centres[0];
        let size = centres.iter().map(|c| c.norm()).fold(0.0, f64::max);
        centres.iter().all(|c| (c - first).norm() <= 1e-12 * size.max(1.0))
    }
}

/// What a [`Rig`] is written as with the `serde` feature: its cameras and their poses in the body.
#[cfg(feature = "serde")]
#[derive(serde::Serialize, serde::Deserialize)]
struct RigParts {
    cameras: Vec<Camera>,
    sensor_from_rig: Vec<Pose>,
}

#[cfg(feature = "serde")]
impl From<Rig> for RigParts {
    fn from(rig: Rig) -> RigParts {
        RigParts {
            cameras: rig.cameras,
            sensor_from_rig: rig.sensor_from_rig,
        }
    }
}

#[cfg(feature = "serde")]
impl TryFrom<RigParts> for Rig {
    type Error = Error;
    fn try_from(parts: RigParts) -> Result<Rig> {
        Rig::new(parts.cameras, parts.sensor_from_rig)
    }
}

/// `B = diag(R_k, R_k)` for a camera's `sensor_from_rig` rotation `R_k`: a step `(ω, δt)` of
/// `rig_from_world` in its tangent (`exp(ω) R`, `t + δt`) moves the camera's pose
/// `(R_k R, R_k t + t_k)` by the step `B (ω, δt)` of the camera's own tangent.
pub(crate) fn tangent_map(r_k: &Matrix3<f64>) -> SMatrix<f64, 6, 6> {
    let mut b = SMatrix::<f64, 6, 6>::zeros();
    b.fixed_view_mut::<3, 3>(0, 0).copy_from(r_k);
    b.fixed_view_mut::<3, 3>(3, 3).copy_from(r_k);
    b
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix3, Rotation3};

    fn camera() -> Camera {
        Camera::pinhole(800.0, 800.0, 320.0, 240.0, 0.0).unwrap()
    }

    #[test]
    fn each_camera_is_placed_by_the_rigs_pose() {
        let turn = Rotation3::from_euler_angles(0.1, -0.4, 0.2).into_inner();
        let poses = vec![Pose::identity(), Pose::new(turn, Vector3::new(0.3, -0.1, 0.05))];
        let rig = Rig::new(vec![camera(), camera()], poses.clone()).unwrap();
        let rig_from_world = Pose::new(
            Rotation3::from_euler_angles(-0.3, 0.2, 1.0).into_inner(),
            Vector3::new(0.5, 1.0, 6.0),
        );
        let x = Vector3::new(0.2, -0.7, 1.5);
        for (k, pose) in poses.iter().enumerate() {
            // The camera frame reached in two steps, world → body → camera, and in one.
            let two_steps = pose.transform(&rig_from_world.transform(&x));
            let one_step = rig.sensor_from_world(k, &rig_from_world).transform(&x);
            assert!((two_steps - one_step).norm() < 1e-14, "camera {k}");
            // The centre in the body's frame is where the camera frame's origin is.
            assert!(pose.transform(&rig.centres()[k]).norm() < 1e-14, "camera {k}");
        }
        assert!(!rig.is_central());
        assert!(Rig::single(camera()).is_central());
        let turned_in_place = Rig::new(
            vec![camera(), camera()],
            vec![Pose::identity(), Pose::new(turn, Vector3::zeros())],
        );
        assert!(turned_in_place.unwrap().is_central());
    }

    #[test]
    fn a_rig_that_is_not_one_is_refused_by_name() {
        let err = Rig::new(vec![], vec![]).unwrap_err().to_string();
        assert!(err.contains("cameras") && err.contains("at least one camera"), "{err}");
        let err = Rig::new(vec![camera(), camera()], vec![Pose::identity()])
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("sensor_from_rig") && err.contains("one pose per camera (2)"),
            "{err}"
        );
        let sheared = Matrix3::new(1.0, 0.01, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0);
        let mirrored = Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, -1.0));
        for (bad, says) in [(sheared, "R Rᵀ = I"), (mirrored, "det R = -1")] {
            let poses = vec![Pose::identity(), Pose::new(bad, Vector3::zeros())];
            let err = Rig::new(vec![camera(), camera()], poses).unwrap_err().to_string();
            assert!(err.contains("sensor_from_rig[1]") && err.contains(says), "{err}");
        }
        let poses = vec![Pose::new(Matrix3::identity(), Vector3::new(f64::NAN, 0.0, 0.0))];
        let err = Rig::new(vec![camera()], poses).unwrap_err().to_string();
        assert!(
            err.contains("sensor_from_rig[0]") && err.contains("translation"),
            "{err}"
        );
    }

    #[cfg(feature = "serde")]
    #[test]
    fn a_rig_is_written_as_its_cameras_and_poses_and_checked_when_read() {
        let rig = Rig::new(vec![camera()], vec![Pose::identity()]).unwrap();
        let json = serde_json::to_string(&rig).unwrap();
        assert!(json.starts_with(r#"{"cameras":[{"model":"PINHOLE""#), "{json}");
        assert_eq!(serde_json::from_str::<Rig>(&json).unwrap(), rig);
        let bad = json.replace(r#""rotation":[[1.0,0.0,0.0]"#, r#""rotation":[[2.0,0.0,0.0]"#);
        assert_ne!(bad, json);
        let err = serde_json::from_str::<Rig>(&bad).unwrap_err().to_string();
        assert!(err.contains("sensor_from_rig[0]"), "{err}");
    }
}
