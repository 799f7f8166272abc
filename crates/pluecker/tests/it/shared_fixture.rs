//! The fixture that `tests/test_api.py::test_shared_fixture_matches_rust` checks from Python: the same
//! seeded scene must come out of the generator bit-for-bit alike on both sides of the binding, and
//! every method must recover its pose. Change both files together.

use nalgebra::{Vector2, Vector3};
use pluecker::pose::{estimate_pose, Method, PoseOptions, Status};
use pluecker::synthetic::{random_scene, SceneKind};

const SEED: u64 = 2024;
const N_POINTS: usize = 12;
const N_LINES: usize = 4;
/// Noise-free data: every method must land within this of the truth (max abs entry of R and t).
const RECOVERY_TOLERANCE: f64 = 1e-8;

#[test]
fn shared_fixture_scene_is_pinned() {
    let scene = random_scene(SceneKind::General, N_POINTS, N_LINES, SEED);
    let c = &scene.correspondences;
    let close3 = |a: &Vector3<f64>, b: [f64; 3]| (a - Vector3::from(b)).amax() < 1e-12;
    let close2 = |a: &Vector2<f64>, b: [f64; 2]| (a - Vector2::from(b)).amax() < 1e-9;
    assert!(close3(
        &scene.translation,
        [-2.367385325682247, -0.8276321643515955, -0.5279960563202948]
    ));
    assert!(close3(
        &c.points3d[0],
        [2.8988763928469616, -7.2052549989512205, -2.916200958344869]
    ));
    assert!(close2(&c.points2d[0], [526.0136231263537, 181.72382603279056]));
    assert!(close3(
        &c.lines3d[3][1],
        [2.7386643955329504, -4.764093786434271, -2.609206889237841]
    ));
    let row0 = scene.rotation.row(0).transpose();
    assert!(close3(
        &row0,
        [0.45397091542994217, -0.6369359292289596, 0.6230754609202178]
    ));
}

#[test]
fn shared_fixture_every_method_recovers_the_pose() {
    let scene = random_scene(SceneKind::General, N_POINTS, N_LINES, SEED);
    for &method in Method::ALL {
        let mut opts = PoseOptions::default();
        opts.method = method;
        let result = estimate_pose(&scene.camera, &scene.correspondences, &opts).expect("valid input");
        let dr = (result.pose.rotation - scene.rotation).amax();
        let dt = (result.pose.translation - scene.translation).amax();
        assert_eq!(result.report.status, Status::Success, "{}", method.as_str());
        assert!(
            dr < RECOVERY_TOLERANCE && dt < RECOVERY_TOLERANCE,
            "{}: dR={dr:e} dt={dt:e}",
            method.as_str()
        );
    }
}
