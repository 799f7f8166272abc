//! The certificate of a rig's pose ([`super::super::certify_rig`]): its minorant, its depth bounds and
//! the whole test, against oracles computed here camera by camera (each point projected through its
//! own camera at `sensor_from_rig ∘ rig_from_world`), on answers that are the global minimum and on
//! local minima that are not.

use super::*;
use crate::camera::Camera;
use crate::pose::generalized::{estimate_rig_pose, ObservingCameras, RigObservations, RigReprojectionCost};
use crate::pose::PoseOptions;
use crate::rig::Rig;
use nalgebra::{Rotation3, Vector2};

/// A rig scene: the rig, every camera's observations (noisy pixels), and the true `rig_from_world`.
struct RigScene {
    rig: Rig,
    shares: Vec<Correspondences>,
    truth: Pose,
}

impl RigScene {
    /// The observations as one input with the index of the camera of each.
    fn joined(&self) -> (Correspondences, ObservingCameras) {
        let (mut corr, mut cameras) = (Correspondences::default(), ObservingCameras::default());
        for (k, share) in self.shares.iter().enumerate() {
            corr.points2d.extend(&share.points2d);
            corr.points3d.extend(&share.points3d);
            corr.lines2d.extend(&share.lines2d);
            corr.lines3d.extend(&share.lines3d);
            cameras.point_cameras.extend(std::iter::repeat_n(k, share.n_points()));
            cameras.line_cameras.extend(std::iter::repeat_n(k, share.n_lines()));
        }
        (corr, cameras)
    }

    /// The cameras as the certificate reads them.
    fn cameras(&self) -> Vec<RigCamera<'_>> {
        (self.shares.iter().enumerate())
            .map(|(k, corr)| RigCamera {
                index: k,
                camera: &self.rig.cameras()[k],
                sensor_from_rig: self.rig.sensor_from_rig()[k],
                corr,
            })
            .collect()
    }

    /// The oracle's cost `½ Σ r²` at `rig_from_world`: every point projected here through its own
    /// pinhole camera (`u = K x / z`) at `sensor_from_rig ∘ rig_from_world`, and every segment endpoint's
    /// distance to the projected line; `None` when a point or an endpoint is not in front of its camera.
    fn cost(&self, pose: &Pose) -> Option<f64> {
        let mut sum = 0.0;
        for (k, share) in self.shares.iter().enumerate() {
            let s = self.rig.sensor_from_rig()[k];
            let (rotation, translation) = (s.rotation * pose.rotation, s.rotation * pose.translation + s.translation);
            let k_matrix = self.rig.cameras()[k].intrinsics().matrix();
            let camera = |x: &Vector3<f64>| rotation * x + translation;
            let pixel = |x: Vector3<f64>| {
                let u = k_matrix * x;
                Vector2::new(u.x / u.z, u.y / u.z)
            };
            for (u, x) in share.points2d.iter().zip(&share.points3d) {
                let x = camera(x);
                if !(x.z > 0.0) {
                    return None;
                }
                sum += (pixel(x) - u).norm_squared();
            }
            for (seen, [a, b]) in share.lines2d.iter().zip(&share.lines3d) {
                let (a, b) = (camera(a), camera(b));
                if !(a.z > 0.0 && b.z > 0.0) {
                    return None;
                }
                let (pa, pb) = (pixel(a), pixel(b));
                let normal = Vector2::new(pb.y - pa.y, pa.x - pb.x).normalize();
                for e in seen {
                    sum += (normal.dot(&(e - pa))).powi(2);
                }
            }
        }
        Some(0.5 * sum)
    }
}

/// `n` pinhole cameras (focal length `f`, 640 x 480) on a ring of radius 0.3 about the rig's y axis,
/// looking outwards (camera `k` turned by `2π k / n`).
fn ring(n: usize, f: f64) -> Rig {
    let camera = Camera::pinhole(f, f, 320.0, 240.0, 0.0).unwrap();
    let sensors = (0..n)
        .map(|k| {
            let rig_from_camera = Rotation3::from_euler_angles(0.0, std::f64::consts::TAU * k as f64 / n as f64, 0.0);
            let centre = rig_from_camera * Vector3::new(0.0, 0.0, 0.3);
            let rotation = rig_from_camera.inverse().into_inner();
            Pose::new(rotation, -(rotation * centre))
        })
        .collect();
    Rig::new(vec![camera; n], sensors).unwrap()
}

/// `points[k]` points and `segments[k]` segments in view of camera `k` of `rig`, 3-9 units deep, at
/// a random pose; pixels with Gaussian noise of `sigma` px.
fn rig_scene(rig: Rig, points: &[usize], segments: &[usize], sigma: f64, seed: u64) -> RigScene {
    let mut rng = Rng::new(seed);
    let truth = Pose::new(rng.rotation(), Vector3::new(rng.normal(), rng.normal(), rng.normal()));
    let f = rig.cameras()[0].intrinsics().fx;
    // The field of view of 640 x 480 pixels, a little inside.
    let (half_x, half_y) = (300.0 / f, 220.0 / f);
    let mut in_view = |rng: &mut Rng| {
        Vector3::new(rng.uniform_in(-half_x, half_x), rng.uniform_in(-half_y, half_y), 1.0) * rng.uniform_in(3.0, 9.0)
    };
    let shares = (0..rig.len())
        .map(|k| {
            let camera = &rig.cameras()[k];
            let world_from_camera = rig.sensor_from_world(k, &truth).inverse();
            let mut corr = Correspondences::default();
            let mut noisy = |u: Vector2<f64>, rng: &mut Rng| u + sigma * Vector2::new(rng.normal(), rng.normal());
            for _ in 0..points[k] {
                let x = in_view(&mut rng);
                corr.points2d.push(noisy(camera.project(&x), &mut rng));
                corr.points3d.push(world_from_camera.transform(&x));
            }
            for _ in 0..segments[k] {
                let (a, b) = (in_view(&mut rng), in_view(&mut rng));
                let seen = [noisy(camera.project(&a), &mut rng), noisy(camera.project(&b), &mut rng)];
                corr.lines2d.push(seen);
                corr.lines3d
                    .push([world_from_camera.transform(&a), world_from_camera.transform(&b)]);
            }
            corr
        })
        .collect();
    RigScene { rig, shares, truth }
}

/// Spreads `total` over `n` cameras as evenly as can be.
fn spread(total: usize, n: usize) -> Vec<usize> {
    (0..n).map(|k| total / n + usize::from(k < total % n)).collect()
}

fn certify_options() -> PoseOptions {
    PoseOptions {
        certify: Some(CertifyOptions::default()),
        ..PoseOptions::default()
    }
}

#[test]
fn rig_certificates_statistics() {
    for (n, points, segments) in [(2, 10, 0), (2, 100, 0), (4, 10, 0), (4, 100, 0), (6, 10, 0), (6, 100, 0), (2, 10, 10)] {
        let mut certified = 0;
        let mut reasons = Vec::new();
        let trials = 40;
        let started = std::time::Instant::now();
        for seed in 0..trials {
            let scene = rig_scene(ring(n, 800.0), &spread(points, n), &spread(segments, n), 1.0, seed);
            let (corr, cameras) = scene.joined();
            let r = estimate_rig_pose(&scene.rig, &corr, &cameras, &certify_options()).unwrap();
            if r.report.certified() {
                certified += 1;
            } else {
                reasons.push(r.details.uncertified_reason.clone().unwrap_or_default());
            }
        }
        eprintln!(
            "n {n} points {points} segments {segments}: certified {certified}/{trials}, {:.2} ms per pose; {:?}",
            started.elapsed().as_secs_f64() * 1e3 / trials as f64,
            reasons.iter().take(3).collect::<Vec<_>>()
        );
    }
}
