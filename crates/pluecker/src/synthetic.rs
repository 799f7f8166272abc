//! Seeded synthetic scenes for tests, benchmarks and the paper's experiments.

use crate::camera::Camera;
use crate::geometry::quaternion::{from_axis_angle, to_rotation_matrix};
use crate::pose::Correspondences;
use crate::rng::Rng;
use nalgebra::{Matrix3, Vector2, Vector3};

/// A scene with its true pose and noise-free observations.
#[derive(Debug, Clone)]
pub struct Scene {
    pub camera: Camera,
    /// True `R` (world → camera).
    pub rotation: Matrix3<f64>,
    /// True `t`.
    pub translation: Vector3<f64>,
    /// Noise-free correspondences (pixels exact).
    pub correspondences: Correspondences,
}

impl Scene {
    /// Camera-frame coordinates of a world point under the true pose.
    pub fn to_camera(&self, x: &Vector3<f64>) -> Vector3<f64> {
        self.rotation * x + self.translation
    }

    /// The scene's correspondences with i.i.d. pixel noise added to every image point and segment
    /// endpoint: Gaussian with standard deviation `sigma` when `gaussian`, else uniform in `[−a, a]`
    /// per coordinate with `a = sigma` (the paper's "maximum amplitude").
    pub fn noisy(&self, sigma: f64, gaussian: bool, rng: &mut Rng) -> Correspondences {
        let mut noise = || {
            let mut draw = || if gaussian { sigma * rng.normal() } else { rng.uniform_in(-sigma, sigma) };
            Vector2::new(draw(), draw())
        };
        let c = &self.correspondences;
        Correspondences {
            points2d: c.points2d.iter().map(|p| p + noise()).collect(),
            points3d: c.points3d.clone(),
            lines2d: c.lines2d.iter().map(|s| [s[0] + noise(), s[1] + noise()]).collect(),
            lines3d: c.lines3d.clone(),
        }
    }
}

/// The ground truth of Phong & Horaud 1995, section 5: axis, angle (rad), translation (cm), intrinsics.
pub fn paper_pose() -> (Camera, Matrix3<f64>, Vector3<f64>) {
    let camera = Camera { fx: -1730.3, fy: 1220.7, cx: 243.8, cy: 241.2, skew: 0.0 };
    let axis = Vector3::new(-0.185148, -0.973420, -0.156567);
    let rotation = to_rotation_matrix(&from_axis_angle(&axis, 2.9512));
    (camera, rotation, Vector3::new(2.627650, -11.006138, 77.479236))
}

/// The paper's calibration object: 460 points on two faces of a dihedral "corner" (230 per face, a
/// 23 x 10 grid each, 0.8 cm pitch) seen at the paper's pose, every point inside a 512 x 512 image.
/// The paper does not describe its object beyond its size; this one fills the image the same way.
pub fn paper_calibration_object() -> Scene {
    let (camera, rotation, translation) = paper_pose();
    let depth = translation.z;
    let mut points3d = Vec::with_capacity(460);
    for face in [-1.0, 1.0] {
        for i in 0..10 {
            for j in 0..23 {
                // Camera-frame coordinates: the faces recede at 45° from the optical axis.
                let x = face * (0.6 + 0.9 * i as f64);
                let y = -8.8 + 0.8 * j as f64;
                let z = depth + 0.8 * x.abs();
                let x_cam = Vector3::new(x + 0.0, y, z);
                points3d.push(rotation.transpose() * (x_cam - translation));
            }
        }
    }
    let points2d = points3d.iter().map(|x| camera.project(&(rotation * x + translation))).collect();
    Scene {
        camera,
        rotation,
        translation,
        correspondences: Correspondences { points2d, points3d, lines2d: vec![], lines3d: vec![] },
    }
}

/// Kinds of random scene used by the benchmarks.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SceneKind {
    /// Points in a box 4-8 units in front of the camera, filling a 640 x 480 image at f = 800.
    General,
    /// Points on one plane, tilted 30-60° to the image plane.
    Planar,
    /// Points in a box 10 units across at depth ~50 (weak perspective: ±80 px, depth range ±10%).
    Far,
}

impl SceneKind {
    /// Lower-case name.
    pub fn as_str(&self) -> &'static str {
        match self {
            SceneKind::General => "general",
            SceneKind::Planar => "planar",
            SceneKind::Far => "far",
        }
    }
}

/// A random scene of `n_points` points and `n_lines` segments with a random pose, noise-free.
/// Every point and endpoint is in front of the camera and inside the 640 x 480 image.
pub fn random_scene(kind: SceneKind, n_points: usize, n_lines: usize, seed: u64) -> Scene {
    let mut rng = Rng::new(seed);
    let camera = Camera { fx: 800.0, fy: 800.0, cx: 320.0, cy: 240.0, skew: 0.0 };
    let rotation = rng.rotation();
    let (depth, half_width) = match kind {
        SceneKind::Far => (50.0, 5.0),
        _ => (6.0, 1.5),
    };
    let tilt = to_rotation_matrix(&from_axis_angle(&rng.unit_vector3(), rng.uniform_in(0.5, 1.0)));
    let sample = |rng: &mut Rng| -> Vector3<f64> {
        loop {
            let local = match kind {
                SceneKind::Planar => Vector3::new(rng.uniform_in(-1.0, 1.0), rng.uniform_in(-1.0, 1.0), 0.0) * 2.0 * half_width,
                SceneKind::General => Vector3::new(rng.uniform_in(-1.0, 1.0), rng.uniform_in(-1.0, 1.0), rng.uniform_in(-1.0, 1.0)) * 2.0 * half_width,
                SceneKind::Far => Vector3::new(rng.uniform_in(-1.0, 1.0), rng.uniform_in(-1.0, 1.0), rng.uniform_in(-1.0, 1.0)) * half_width,
            };
            let x_cam = tilt * local + Vector3::new(0.0, 0.0, depth);
            let u = camera.project(&x_cam);
            if x_cam.z > 0.5 && (0.0..640.0).contains(&u.x) && (0.0..480.0).contains(&u.y) {
                return x_cam;
            }
        }
    };
    // World frame: a random rigid motion of the camera frame.
    let translation = Vector3::new(rng.normal(), rng.normal(), rng.normal());
    let to_world = |x_cam: Vector3<f64>| rotation.transpose() * (x_cam - translation);
    let points_cam: Vec<Vector3<f64>> = (0..n_points).map(|_| sample(&mut rng)).collect();
    let segs_cam: Vec<[Vector3<f64>; 2]> = (0..n_lines)
        .map(|_| loop {
            let (a, b) = (sample(&mut rng), sample(&mut rng));
            if (camera.project(&a) - camera.project(&b)).norm() > 40.0 {
                break [a, b];
            }
        })
        .collect();
    let correspondences = Correspondences {
        points2d: points_cam.iter().map(|x| camera.project(x)).collect(),
        points3d: points_cam.iter().map(|x| to_world(*x)).collect(),
        lines2d: segs_cam.iter().map(|s| [camera.project(&s[0]), camera.project(&s[1])]).collect(),
        lines3d: segs_cam.iter().map(|s| [to_world(s[0]), to_world(s[1])]).collect(),
    };
    Scene { camera, rotation, translation, correspondences }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paper_object_is_in_view_and_in_front() {
        let scene = paper_calibration_object();
        assert_eq!(scene.correspondences.points3d.len(), 460);
        for (x, u) in scene.correspondences.points3d.iter().zip(&scene.correspondences.points2d) {
            assert!(scene.to_camera(x).z > 0.0);
            assert!((0.0..512.0).contains(&u.x) && (0.0..512.0).contains(&u.y), "{u}");
        }
    }
}
