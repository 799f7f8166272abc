//! Tests of [`super::p3l`]: noise-free random instances, an independent multistart search, and the
//! degenerate cases (parallel lines, concurrent image lines, coincident planes, invalid input).

use super::super::testing::*;
use super::super::Feature;
use super::*;
use crate::rng::Rng;

const LINES: [bool; 3] = [false; 3];

fn solve(features: &[Feature; 3]) -> Vec<Pose> {
    let mut normals = [Vector3::zeros(); 3];
    let mut endpoints = [[Vector3::zeros(); 2]; 3];
    for (i, f) in features.iter().enumerate() {
        let Feature::Line { normal, endpoints: e } = f else {
            panic!("a line sample")
        };
        (normals[i], endpoints[i]) = (*normal, *e);
    }
    p3l(&normals, &endpoints)
}

#[test]
fn random_instances_recover_the_true_pose() {
    let summary = check_random_draws(
        "p3l",
        solve,
        LINES,
        Draws {
            seed: 6_301,
            draws: 1000,
            half_width: 1.0,
        },
        1e-9,
        8,
    );
    assert_eq!(summary.counts[0], 0, "every instance has its true solution");
}

#[test]
fn narrow_field_of_view_is_as_accurate_as_its_conditioning() {
    check_random_draws(
        "p3l",
        solve,
        LINES,
        Draws {
            seed: 6_302,
            draws: 300,
            half_width: 0.1,
        },
        1e-9,
        8,
    );
}

#[test]
fn every_solution_found_by_multistart_newton_is_returned() {
    check_multistart_completeness("p3l", solve, LINES, 6_303);
}

/// Three camera-frame lines `[a, b]` as a sample under a random pose.
fn lines_sample(rng: &mut Rng, lines: [[Vector3<f64>; 2]; 3]) -> Sample {
    let (r, t) = random_pose(rng);
    Sample::from_camera_frame(rng, LINES, &[], &lines, r, t)
}

#[test]
fn parallel_lines_give_valid_poses_or_none() {
    // All three parallel (the direction of the third tilted by `offset`): at offset 0 the rotation
    // constraints have no solution (independent normals), so no pose.
    let all = sweep_degeneracy(
        "p3l, three parallel",
        solve,
        6_304,
        NEAR_DEGENERATE_RESIDUAL,
        8,
        0.0,
        |rng, offset| {
            let d = rng.unit_vector3();
            let line = |rng: &mut Rng, d: Vector3<f64>| {
                let a = camera_point(rng, 1.0);
                [a, a + d * rng.uniform_in(0.5, 2.0)]
            };
            let tilted = (d + orthogonal_unit(rng, &d) * offset).normalize();
            let lines = [line(rng, d), line(rng, d), line(rng, tilted)];
            lines_sample(rng, lines)
        },
    );
    assert_eq!(all.last().map(|r| r.0), Some(SWEEP_DRAWS), "exactly parallel: no pose");
    // Two parallel: R d ∥ n₁ × n₂ and a rotation about it, a well-posed problem (up to 4 poses).
    let two = sweep_degeneracy(
        "p3l, two parallel",
        solve,
        6_305,
        NEAR_DEGENERATE_RESIDUAL,
        8,
        0.0,
        |rng, offset| {
            let d = rng.unit_vector3();
            let a = [camera_point(rng, 1.0), camera_point(rng, 1.0), camera_point(rng, 1.0)];
            let tilted = (d + orthogonal_unit(rng, &d) * offset).normalize();
            let far = camera_point(rng, 1.0);
            lines_sample(rng, [[a[0], a[0] + d], [a[1], a[1] + tilted * 1.5], [a[2], far]])
        },
    );
    assert!(two.iter().all(|&(empty, _, lost)| empty == 0 && lost == 0), "{two:?}");
}

#[test]
fn concurrent_lines_and_coincident_planes_give_valid_poses_or_none() {
    // Three object lines through one point (the third missing it by `offset`): concurrent image lines,
    // det N = 0, the translation along the common ray is free.
    let concurrent = sweep_degeneracy(
        "p3l, concurrent",
        solve,
        6_306,
        NEAR_DEGENERATE_RESIDUAL,
        8,
        0.0,
        |rng, offset| {
            let c = camera_point(rng, 1.0);
            let miss = rng.unit_vector3() * offset;
            let far = [camera_point(rng, 1.0), camera_point(rng, 1.0), camera_point(rng, 1.0)];
            lines_sample(rng, [[c, far[0]], [c, far[1]], [c + miss, far[2]]])
        },
    );
    assert_eq!(concurrent.last().map(|r| r.2), Some(0), "{concurrent:?}");
    // The second line in the interpretation plane of the first (off it by `offset`): equal normals.
    let planes = sweep_degeneracy(
        "p3l, coincident planes",
        solve,
        6_307,
        NEAR_DEGENERATE_RESIDUAL,
        8,
        0.0,
        |rng, offset| {
            let [a, b] = [camera_point(rng, 1.0), camera_point(rng, 1.0)];
            let n = a.cross(&b).normalize();
            let (s, u) = (rng.uniform_in(0.5, 2.0), rng.uniform_in(0.5, 2.0));
            let second = [a * s + n * offset, b * u + (a - b) * 0.3];
            let third = [camera_point(rng, 1.0), camera_point(rng, 1.0)];
            lines_sample(rng, [[a, b], second, third])
        },
    );
    assert_eq!(planes.last().map(|r| r.2), Some(0), "{planes:?}");
}

#[test]
fn invalid_input_gives_no_pose() {
    let mut rng = Rng::new(6_308);
    let sample = Sample::random(&mut rng, LINES, 1.0);
    assert!(!solve(&sample.features).is_empty());
    for i in 0..3 {
        for bad in [f64::NAN, f64::INFINITY] {
            let mut f = sample.features;
            if let Feature::Line { normal, .. } = &mut f[i] {
                normal.y = bad;
            }
            assert!(solve(&f).is_empty(), "normal {i} {bad}");
            let mut f = sample.features;
            if let Feature::Line { endpoints, .. } = &mut f[i] {
                endpoints[1].z = bad;
            }
            assert!(solve(&f).is_empty(), "endpoint {i} {bad}");
        }
        let mut f = sample.features;
        if let Feature::Line { normal, endpoints } = &mut f[i] {
            *normal = Vector3::zeros();
            endpoints[1] = endpoints[0];
        }
        assert!(solve(&f).is_empty(), "zero normal {i}");
        let mut f = sample.features;
        if let Feature::Line { endpoints, .. } = &mut f[i] {
            endpoints[1] = endpoints[0];
        }
        assert!(solve(&f).is_empty(), "coincident endpoints {i}");
    }
    // Huge and tiny scenes: same number of poses (the kernel works on unit vectors, N on unit normals).
    assert_scale_invariant(solve, &sample, 8);
}
