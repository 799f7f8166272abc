//! The problem's claims: the bearing cone, the closed-form eigenvalue, an endpoint's sine
//! ([`super::super::problem`]).

use super::*;

/// The bearing cone's claim, `bᵢ · (R Xᵢ + t) ≥ a · t − δ ‖t‖ − max ‖X‖`, at random rotations and
/// translations (and translations that make it nearly tight: along the bearing farthest from
/// the axis, and against it), on wide and narrow fields of view.
#[test]
fn the_bearing_cone_bounds_every_depth_from_below() {
    let mut rng = Rng::new(17);
    // How close each of the claim's two parts comes: `bᵢ · t ≥ a · t − δ ‖t‖` and
    // `bᵢ · R Xᵢ ≥ −max ‖X‖` (per unit of their scale).
    let (mut closest_t, mut closest_x) = (f64::INFINITY, f64::INFINITY);
    for (seed, f) in [(1, 250.0), (2, 800.0), (3, 15000.0)] {
        let scene = visible_scene(f, 12, 0, false, seed);
        let corr = scene.noisy(1.0, true, &mut rng);
        let k_inv = scene.camera.intrinsics().matrix().try_inverse().unwrap();
        let bearings: Vec<Vector3<f64>> = corr
            .points2d
            .iter()
            .map(|u| (k_inv * Vector3::new(u.x, u.y, 1.0)).normalize())
            .collect();
        let (axis, reach, largest) = bearing_cone(&bearings, &corr.points3d, &vec![Vector3::zeros(); corr.n_points()]);
        let farthest = bearings
            .iter()
            .max_by(|a, b| (*a - axis).norm().total_cmp(&(*b - axis).norm()))
            .unwrap();
        let biggest = (0..corr.n_points())
            .max_by(|&i, &j| corr.points3d[i].norm().total_cmp(&corr.points3d[j].norm()))
            .unwrap();
        for trial in 0..400 {
            let mut r = exp_so3(&(rng.unit_vector3() * rng.uniform_in(0.0, 3.0)));
            let t = match trial % 4 {
                0 => rng.unit_vector3() * rng.uniform_in(0.0, 20.0),
                1 => farthest * rng.uniform_in(0.0, 20.0),
                // (b − a) · t = −δ ‖t‖ for the farthest bearing.
                2 => (axis - farthest) * rng.uniform_in(0.0, 20.0),
                // The largest point turned against its own bearing: b · R X = −max ‖X‖.
                _ => {
                    let (x, b) = (corr.points3d[biggest], bearings[biggest]);
                    r = nalgebra::Rotation3::rotation_between(&x, &-b).unwrap().into_inner();
                    rng.unit_vector3() * rng.uniform_in(0.0, 20.0)
                }
            };
            let claim = axis.dot(&t) - reach * t.norm() - largest;
            for (x, b) in corr.points3d.iter().zip(&bearings) {
                let depth = b.dot(&(r * x + t));
                assert!(
                    depth >= claim - 1e-12 * (1.0 + t.norm()),
                    "f = {f}: depth {depth} < {claim}"
                );
                closest_t = closest_t.min((b.dot(&t) - axis.dot(&t) + reach * t.norm()) / t.norm().max(1e-300));
                closest_x = closest_x.min((b.dot(&(r * x)) + largest) / largest);
            }
        }
    }
    // Each part is reached, up to rounding (a cone too narrow, or a smaller largest point, fails).
    assert!(
        closest_t < 1e-12 && closest_x < 1e-12,
        "the parts come within {closest_t}, {closest_x}"
    );
}

/// The closed-form largest eigenvalue agrees with nalgebra's and never falls below it.
#[test]
fn closed_form_largest_eigenvalue() {
    let mut rng = Rng::new(5);
    for i in 0..2000 {
        let a = Matrix3::from_fn(|_, _| rng.normal()) * 10f64.powi(i % 7 - 3);
        let m = a * a.transpose() + Matrix3::identity() * if i % 3 == 0 { 0.0 } else { 1e-3 };
        let exact = m.symmetric_eigenvalues().max();
        let mine = largest_eigenvalue(&m);
        assert!(
            mine >= exact && mine <= exact * (1.0 + 1e-7) + 1e-300,
            "{mine} vs {exact}"
        );
    }
    assert_eq!(largest_eigenvalue(&(Matrix3::identity() * 2.0)), 2.0 * (1.0 + 1e-9));
}

/// [`endpoint_sine`] against its claim at random poses near and far from the truth, with and
/// without covariances: the sine of the angle between each observed endpoint's ray and the
/// camera-frame interpretation plane, computed here from the projected endpoints, is at most
/// `endpoint_sine` of the endpoint's own residual (the test's pixel distance to the projected line,
/// over its standard deviation across it), and close to it somewhere.
#[test]
fn the_sine_of_an_endpoint_is_bounded_by_its_residual() {
    use crate::synthetic::random_observation_noise;
    use nalgebra::Vector2;
    let mut rng = Rng::new(36);
    let (mut checked, mut closest) = (0usize, 0.0f64);
    for (f, nl, seed, with_covariances) in [(800.0, 6, 61, false), (250.0, 5, 62, true), (4000.0, 6, 63, true)] {
        let scene = visible_scene(f, 0, nl, false, seed);
        let mut corr = scene.noisy(1.0, true, &mut rng);
        if with_covariances {
            corr.noise = Some(random_observation_noise(&mut rng, 0, nl, (0.3, 3.0)));
        }
        let truth = Pose::new(scene.rotation, scene.translation);
        let f_hat = 4.0 * ReprojectionCost::of(&scene.camera.intrinsics(), &corr).cost(&truth);
        let problem = Problem::new(&scene.camera.intrinsics(), &corr, f_hat).unwrap();
        let k = scene.camera.intrinsics().matrix();
        let k_inv = k.try_inverse().unwrap();
        let pixel = |x: &Vector3<f64>| {
            let p = k * x;
            Vector2::new(p.x / p.z, p.y / p.z)
        };
        for _ in 0..200 {
            let rotation = exp_so3(&(rng.unit_vector3() * rng.uniform_in(0.0, 0.3))) * scene.rotation;
            let t = scene.translation + rng.unit_vector3() * rng.uniform_in(0.0, 1.0);
            for (line, (segment, seen)) in corr.lines3d.iter().zip(&corr.lines2d).enumerate() {
                let [a, b] = segment.map(|x| rotation * x + t);
                if a.z <= 0.0 || b.z <= 0.0 {
                    continue;
                }
                let normal_plane = a.cross(&b).normalize();
                let (pa, pb) = (pixel(&a), pixel(&b));
                let dir = (pb - pa).normalize();
                let normal = Vector2::new(-dir.y, dir.x);
                for (end, observed) in seen.iter().enumerate() {
                    let sigma = corr
                        .noise
                        .as_ref()
                        .map_or(1.0, |n| normal.dot(&(n.lines[line][end] * normal)).sqrt());
                    let residual = normal.dot(&(observed - pa)).abs() / sigma;
                    let e = k_inv * Vector3::new(observed.x, observed.y, 1.0);
                    let sine = e.normalize().dot(&normal_plane).abs();
                    let bound = endpoint_sine(residual, problem.cameras[0].endpoint_maps[line][end].1, &e);
                    // Rounding: the pixels and the normal at ~1e-15 of their sizes.
                    assert!(sine <= bound * (1.0 + 1e-9) + 1e-15, "sine {sine} > its bound {bound}");
                    closest = closest.max(sine / bound);
                    checked += 1;
                }
            }
        }
    }
    assert!(
        checked > 3000 && closest > 0.9,
        "{checked} endpoints, closest {closest}"
    );
}
