//! Seeded synthetic scenes for tests, benchmarks and the paper's experiments.

use crate::camera::{Camera, Intrinsics};
use crate::error::{Error, Result};
use crate::geometry::quaternion::{from_axis_angle, to_rotation_matrix};
use crate::pose::{Correspondences, ObservationNoise};
use crate::rng::Rng;
use nalgebra::{Matrix2, Matrix3, Matrix3x4, Vector2, Vector3};

/// A scene with its true pose and noise-free observations.
#[derive(Debug, Clone)]
pub struct Scene {
    /// The intrinsics the observations were made with.
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
            let mut draw = || {
                if gaussian {
                    sigma * rng.normal()
                } else {
                    rng.uniform_in(-sigma, sigma)
                }
            };
            Vector2::new(draw(), draw())
        };
        let c = &self.correspondences;
        Correspondences {
            points2d: c.points2d.iter().map(|p| p + noise()).collect(),
            points3d: c.points3d.clone(),
            lines2d: c.lines2d.iter().map(|s| [s[0] + noise(), s[1] + noise()]).collect(),
            lines3d: c.lines3d.clone(),
            noise: None,
        }
    }
}

/// The ground truth of Phong & Horaud 1995, section 5: axis, angle (rad), translation (cm), intrinsics.
pub fn paper_pose() -> (Camera, Matrix3<f64>, Vector3<f64>) {
    let k = Intrinsics {
        fx: -1730.3,
        fy: 1220.7,
        cx: 243.8,
        cy: 241.2,
        skew: 0.0,
    };
    let camera = Camera::pinhole(k.fx, k.fy, k.cx, k.cy, k.skew).expect("the paper's camera");
    let axis = Vector3::new(-0.185148, -0.973420, -0.156567);
    let rotation = to_rotation_matrix(&from_axis_angle(&axis, 2.9512));
    (camera, rotation, Vector3::new(2.627650, -11.006138, 77.479236))
}

/// The paper's calibration object: 460 points on two faces of a dihedral "corner" (230 per face, a
/// 23 x 10 grid each, 0.8 cm pitch) seen at the paper's pose, every point inside a 512 x 512 image.
/// The paper does not describe its object beyond its size; this one fills the image the same way.
pub fn paper_calibration_object() -> Scene {
    let (camera, rotation, translation) = paper_pose();
    let k = camera.intrinsics();
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
    let points2d = points3d
        .iter()
        .map(|x| k.project(&(rotation * x + translation)))
        .collect();
    Scene {
        camera,
        rotation,
        translation,
        correspondences: Correspondences {
            points2d,
            points3d,
            lines2d: vec![],
            lines3d: vec![],
            noise: None,
        },
    }
}

/// Kinds of random scene used by the benchmarks.
#[derive(Debug, Clone, Copy, PartialEq, Eq, strum::IntoStaticStr, strum::EnumString, strum::VariantArray)]
#[strum(serialize_all = "snake_case")]
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
        self.into()
    }
}

/// The most points plus segments a generated scene may hold through [`check_scene_size`]: ten
/// million (about 0.5 GB of correspondences, as much again once copied to numpy).
pub const MAX_SCENE_FEATURES: usize = 10_000_000;

/// [`Error::InvalidOption`] naming the count when a scene of `n_points` points and `n_lines`
/// segments would hold more than [`MAX_SCENE_FEATURES`] features. The scene generators allocate
/// their vectors in one go and an allocation that fails aborts the process, so callers with
/// untrusted sizes (the Python bindings) check first.
pub fn check_scene_size(n_points: usize, n_lines: usize) -> Result<()> {
    let too_many = |name: &str, value: usize| Error::InvalidOption {
        name: name.into(),
        reason: format!("a scene holds at most {MAX_SCENE_FEATURES} points and segments together, got {value}"),
    };
    if n_points > MAX_SCENE_FEATURES {
        return Err(too_many("n_points", n_points));
    }
    if n_lines > MAX_SCENE_FEATURES - n_points {
        return Err(too_many("n_lines", n_lines));
    }
    Ok(())
}

/// A random scene of `n_points` points and `n_lines` segments with a random pose, noise-free.
/// Every point and endpoint is in front of the camera and inside the 640 x 480 image.
pub fn random_scene(kind: SceneKind, n_points: usize, n_lines: usize, seed: u64) -> Scene {
    let mut rng = Rng::new(seed);
    let camera = Intrinsics {
        fx: 800.0,
        fy: 800.0,
        cx: 320.0,
        cy: 240.0,
        skew: 0.0,
    };
    let rotation = rng.rotation();
    let (depth, half_width) = match kind {
        SceneKind::Far => (50.0, 5.0),
        _ => (6.0, 1.5),
    };
    let tilt = to_rotation_matrix(&from_axis_angle(&rng.unit_vector3(), rng.uniform_in(0.5, 1.0)));
    let sample = |rng: &mut Rng| -> Vector3<f64> {
        loop {
            let local = match kind {
                SceneKind::Planar => {
                    Vector3::new(rng.uniform_in(-1.0, 1.0), rng.uniform_in(-1.0, 1.0), 0.0) * 2.0 * half_width
                }
                SceneKind::General => {
                    Vector3::new(
                        rng.uniform_in(-1.0, 1.0),
                        rng.uniform_in(-1.0, 1.0),
                        rng.uniform_in(-1.0, 1.0),
                    ) * 2.0
                        * half_width
                }
                SceneKind::Far => {
                    Vector3::new(
                        rng.uniform_in(-1.0, 1.0),
                        rng.uniform_in(-1.0, 1.0),
                        rng.uniform_in(-1.0, 1.0),
                    ) * half_width
                }
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
    let structure = Structure::draw(&mut rng, sample, n_points, n_lines, |a, b| {
        (camera.project(a) - camera.project(b)).norm() > 40.0
    });
    structure.seen(camera, rotation, translation)
}

/// Points and segments drawn in the camera frame.
struct Structure {
    points: Vec<Vector3<f64>>,
    segments: Vec<[Vector3<f64>; 2]>,
}

impl Structure {
    /// `n_points` points and `n_lines` segments from `sample`, each segment drawn again until `long`
    /// accepts its endpoints.
    fn draw(
        rng: &mut Rng,
        sample: impl Fn(&mut Rng) -> Vector3<f64>,
        n_points: usize,
        n_lines: usize,
        long: impl Fn(&Vector3<f64>, &Vector3<f64>) -> bool,
    ) -> Structure {
        let points = (0..n_points).map(|_| sample(rng)).collect();
        let segments = (0..n_lines)
            .map(|_| loop {
                let (a, b) = (sample(rng), sample(rng));
                if long(&a, &b) {
                    break [a, b];
                }
            })
            .collect();
        Structure { points, segments }
    }

    /// The scene of this structure seen by `camera` at the pose `(rotation, translation)` (world
    /// points `Rᵀ (x_cam − t)`), with exact pixels.
    fn seen(&self, camera: Intrinsics, rotation: Matrix3<f64>, translation: Vector3<f64>) -> Scene {
        let to_world = |x_cam: &Vector3<f64>| rotation.transpose() * (x_cam - translation);
        let correspondences = Correspondences {
            points2d: self.points.iter().map(|x| camera.project(x)).collect(),
            points3d: self.points.iter().map(to_world).collect(),
            lines2d: self
                .segments
                .iter()
                .map(|s| [camera.project(&s[0]), camera.project(&s[1])])
                .collect(),
            lines3d: self
                .segments
                .iter()
                .map(|s| [to_world(&s[0]), to_world(&s[1])])
                .collect(),
            noise: None,
        };
        Scene {
            camera: Camera::pinhole(camera.fx, camera.fy, camera.cx, camera.cy, camera.skew)
                .expect("a scene's focal length is non-zero"),
            rotation,
            translation,
            correspondences,
        }
    }
}

/// Per-observation noise for `n_points` points and `n_lines` segments (one covariance per endpoint):
/// anisotropic covariances `R(φ) diag(σ₁², σ₂²) R(φ)ᵀ`, `σ₁, σ₂` uniform in `sigma` (px), `φ` uniform,
/// drawn from `rng` (points first). Only the weights: the pixels keep the noise they were drawn with.
pub fn random_observation_noise(rng: &mut Rng, n_points: usize, n_lines: usize, sigma: (f64, f64)) -> ObservationNoise {
    let mut covariance = || {
        let (s1, s2, phi) = (
            rng.uniform_in(sigma.0, sigma.1),
            rng.uniform_in(sigma.0, sigma.1),
            rng.uniform_in(0.0, std::f64::consts::PI),
        );
        let r = Matrix2::new(phi.cos(), -phi.sin(), phi.sin(), phi.cos());
        r * Matrix2::new(s1 * s1, 0.0, 0.0, s2 * s2) * r.transpose()
    };
    let points: Vec<Matrix2<f64>> = (0..n_points).map(|_| covariance()).collect();
    let lines: Vec<[Matrix2<f64>; 2]> = (0..n_lines).map(|_| [covariance(), covariance()]).collect();
    ObservationNoise::from_covariances(&points, &lines).expect("positive definite by construction")
}

/// The scenes of the global-minimum tests and benchmark: a 640 x 480 image with
/// `fx = fy = focal` (px), principal point at the centre, a uniformly random pose, and structure drawn
/// where the camera sees it: each point (segment endpoint) is a uniform pixel back-projected to a depth
/// uniform in 6 ± 30 % (4.2-7.8 units) or, for `planar`, to a plane through `(0, 0, 6)` (camera frame)
/// tilted 30-60° from the image plane (depths kept in 2-20). Segments are at least 20 px long.
/// Noise-free; add noise with [`Scene::noisy`].
pub fn visible_scene(focal: f64, n_points: usize, n_lines: usize, planar: bool, seed: u64) -> Scene {
    let mut rng = Rng::new(seed);
    let camera = Intrinsics {
        fx: focal,
        fy: focal,
        cx: 320.0,
        cy: 240.0,
        skew: 0.0,
    };
    let rotation = rng.rotation();
    let normal = {
        let tilt = rng.uniform_in(30f64.to_radians(), 60f64.to_radians());
        let azimuth = rng.uniform_in(0.0, std::f64::consts::TAU);
        Vector3::new(tilt.sin() * azimuth.cos(), tilt.sin() * azimuth.sin(), -tilt.cos())
    };
    let sample = |rng: &mut Rng| -> Vector3<f64> {
        loop {
            let u = Vector2::new(rng.uniform_in(0.0, 640.0), rng.uniform_in(0.0, 480.0));
            let n = camera.pixel_to_normalized(&u);
            let ray = Vector3::new(n.x, n.y, 1.0);
            let depth = if planar {
                // normal · (depth ray − (0, 0, 6)) = 0
                6.0 * normal.z / normal.dot(&ray)
            } else {
                rng.uniform_in(4.2, 7.8)
            };
            if (2.0..=20.0).contains(&depth) {
                return ray * depth;
            }
        }
    };
    let translation = Vector3::new(rng.normal(), rng.normal(), rng.normal());
    let structure = Structure::draw(&mut rng, sample, n_points, n_lines, |a, b| {
        (camera.project(a) - camera.project(b)).norm() >= 20.0
    });
    structure.seen(camera, rotation, translation)
}

/// One 3-D point seen by several cameras: the input of point triangulation, with its truth.
#[derive(Debug, Clone)]
pub struct TriangulationScene {
    /// 3x4 cameras `K [R | t]` mapping world points to pixels (`K`: f = 800, 640 x 480).
    pub cameras: Vec<Matrix3x4<f64>>,
    /// The true point (world units).
    pub point: Vector3<f64>,
    /// Its noise-free projections, one per camera (pixels, inside the image).
    pub observations: Vec<Vector2<f64>>,
}

impl TriangulationScene {
    /// The observations with i.i.d. Gaussian pixel noise of standard deviation `sigma` per coordinate.
    pub fn noisy(&self, sigma: f64, rng: &mut Rng) -> Vec<Vector2<f64>> {
        self.observations
            .iter()
            .map(|x| x + Vector2::new(sigma * rng.normal(), sigma * rng.normal()))
            .collect()
    }
}

/// A seeded scene of `views ≥ 2` cameras looking at one point with a given parallax: the largest
/// angle between two rays from the point to the camera centres is exactly `parallax` (radians; two
/// centres sit on opposite sides of a cone of half-angle `parallax/2` around a random mean direction,
/// the others inside it). The point is near the world origin, the cameras 4-6 units away, each with
/// a random roll and the point at a random pixel at least 40 px inside the 640 x 480 image.
pub fn triangulation_scene(views: usize, parallax: f64, seed: u64) -> TriangulationScene {
    let mut rng = Rng::new(seed);
    let camera = Intrinsics {
        fx: 800.0,
        fy: 800.0,
        cx: 320.0,
        cy: 240.0,
        skew: 0.0,
    };
    let k = camera.matrix();
    let point = Vector3::new(rng.normal(), rng.normal(), rng.normal()) * 0.5;
    let mean = rng.unit_vector3();
    let helper = if mean.x.abs() < 0.9 { Vector3::x() } else { Vector3::y() };
    let e1 = mean.cross(&helper).normalize();
    let e2 = mean.cross(&e1);
    let half = 0.5 * parallax;
    let mut cameras = Vec::with_capacity(views);
    let mut observations = Vec::with_capacity(views);
    for j in 0..views.max(2) {
        let (theta, phi) = match j {
            0 => (half, 0.0),
            1 => (half, std::f64::consts::PI),
            _ => (half * rng.uniform().sqrt(), rng.uniform_in(0.0, std::f64::consts::TAU)),
        };
        let direction = mean * theta.cos() + (e1 * phi.cos() + e2 * phi.sin()) * theta.sin();
        let centre = point + direction * rng.uniform_in(4.0, 6.0);
        // The ray to the point, in the camera frame, through a random pixel.
        let pixel = Vector2::new(rng.uniform_in(40.0, 600.0), rng.uniform_in(40.0, 440.0));
        let ray_cam = Vector3::new(
            (pixel.x - camera.cx) / camera.fx,
            (pixel.y - camera.cy) / camera.fy,
            1.0,
        )
        .normalize();
        let ray_world = (point - centre).normalize();
        // R maps ray_world to ray_cam, after a random roll about ray_world.
        let roll = to_rotation_matrix(&from_axis_angle(&ray_world, rng.uniform_in(0.0, std::f64::consts::TAU)));
        let align = nalgebra::Rotation3::rotation_between(&ray_world, &ray_cam)
            .unwrap_or_else(|| nalgebra::Rotation3::from_axis_angle(&nalgebra::Vector3::x_axis(), std::f64::consts::PI))
            .into_inner();
        let rotation = align * roll;
        let translation = -(rotation * centre);
        let mut rt = Matrix3x4::zeros();
        rt.fixed_view_mut::<3, 3>(0, 0).copy_from(&rotation);
        rt.set_column(3, &translation);
        cameras.push(k * rt);
        observations.push(camera.project(&(rotation * point + translation)));
    }
    TriangulationScene {
        cameras,
        point,
        observations,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scene_sizes_are_checked_against_the_cap_without_overflow() {
        assert!(check_scene_size(MAX_SCENE_FEATURES, 0).is_ok());
        assert!(check_scene_size(MAX_SCENE_FEATURES - 5, 5).is_ok());
        for (n, m, name) in [
            (MAX_SCENE_FEATURES + 1, 0, "n_points"),
            (1 << 40, 0, "n_points"),
            (MAX_SCENE_FEATURES, 1, "n_lines"),
            (0, usize::MAX, "n_lines"),
        ] {
            let err = check_scene_size(n, m).unwrap_err();
            assert!(
                matches!(&err, Error::InvalidOption { name: got, .. } if got == name),
                "{err}"
            );
        }
    }

    #[test]
    fn paper_object_is_in_view_and_in_front() {
        let scene = paper_calibration_object();
        assert_eq!(scene.correspondences.points3d.len(), 460);
        for (x, u) in scene
            .correspondences
            .points3d
            .iter()
            .zip(&scene.correspondences.points2d)
        {
            assert!(scene.to_camera(x).z > 0.0);
            assert!((0.0..512.0).contains(&u.x) && (0.0..512.0).contains(&u.y), "{u}");
        }
    }

    #[test]
    fn triangulation_scene_has_the_requested_parallax_and_projections() {
        for (views, parallax, seed) in [(2, 0.2f64.to_radians(), 1), (7, 0.3, 2), (20, 1.0f64.to_radians(), 3)] {
            let scene = triangulation_scene(views, parallax, seed);
            assert_eq!(scene.cameras.len(), views);
            let centres: Vec<Vector3<f64>> = scene.cameras.iter().map(crate::triangulation::views::centre).collect();
            let mut widest: f64 = 0.0;
            for a in &centres {
                for b in &centres {
                    widest = widest.max((a - scene.point).angle(&(b - scene.point)));
                }
            }
            assert!((widest - parallax).abs() < 1e-9, "{widest} vs {parallax}");
            for (p, u) in scene.cameras.iter().zip(&scene.observations) {
                let h = p * scene.point.push(1.0);
                assert!(h.z > 0.0 && (Vector2::new(h.x / h.z, h.y / h.z) - u).norm() < 1e-9);
                assert!((40.0..600.0).contains(&u.x) && (40.0..440.0).contains(&u.y));
            }
        }
    }
}
