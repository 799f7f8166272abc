//! Tests of [`super::p1p2l`]: noise-free random instances, an independent multistart search, and the
//! degenerate cases (the point on a line, parallel lines, coincident planes, invalid input).

use super::super::testing::*;
use super::super::Feature;
use super::*;
use crate::rng::Rng;

const KINDS: [bool; 3] = [true, false, false];

fn solve(features: &[Feature; 3]) -> Vec<Pose> {
    let Feature::Point { bearing, point } = features[0] else {
        panic!("point first")
    };
    let mut normals = [Vector3::zeros(); 2];
    let mut endpoints = [[Vector3::zeros(); 2]; 2];
    for (i, f) in features[1..].iter().enumerate() {
        let Feature::Line { normal, endpoints: e } = f else {
            panic!("then two lines")
        };
        (normals[i], endpoints[i]) = (*normal, *e);
    }
    p1p2l(&bearing, &point, &normals, &endpoints)
}

#[test]
fn random_instances_recover_the_true_pose() {
    let summary = check_random_draws(
        "p1p2l",
        solve,
        KINDS,
        Draws {
            seed: 6_201,
            draws: 1000,
            half_width: 1.0,
        },
        1e-9,
        4,
    );
    assert_eq!(summary.counts[0], 0, "every instance has its true solution");
}

#[test]
fn narrow_field_of_view_is_as_accurate_as_its_conditioning() {
    check_random_draws(
        "p1p2l",
        solve,
        KINDS,
        Draws {
            seed: 6_202,
            draws: 300,
            half_width: 0.1,
        },
        1e-9,
        4,
    );
}

#[test]
fn every_solution_found_by_multistart_newton_is_returned() {
    check_multistart_completeness("p1p2l", solve, KINDS, 6_203);
}

/// A point and two lines in the camera frame as a sample under a random pose.
fn mixed_sample(rng: &mut Rng, point: Vector3<f64>, lines: [[Vector3<f64>; 2]; 2]) -> Sample {
    let (r, t) = random_pose(rng);
    Sample::from_camera_frame(rng, KINDS, &[point], &lines, r, t)
}

#[test]
fn point_on_a_line_gives_valid_poses_or_none() {
    // The point `offset` off the first line: at 0 the third rotation constraint vanishes (a continuum).
    let rows = sweep_degeneracy(
        "p1p2l, point on a line",
        solve,
        6_204,
        NEAR_DEGENERATE_RESIDUAL,
        4,
        0.0,
        |rng, offset| {
            let [a, b] = [camera_point(rng, 1.0), camera_point(rng, 1.0)];
            let point = a + (b - a) * rng.uniform_in(0.2, 0.8) + orthogonal_unit(rng, &(b - a)) * offset;
            let other = [camera_point(rng, 1.0), camera_point(rng, 1.0)];
            mixed_sample(rng, point, [[a, b], other])
        },
    );
    assert!(rows[0].0 == 0 && rows[0].2 == 0, "{rows:?}");
}

#[test]
fn parallel_lines_and_point_at_their_crossing_give_valid_poses_or_none() {
    // Parallel object lines: R d ∥ ±n₁ × n₂, then a rotation about it; well posed.
    let parallel = sweep_degeneracy(
        "p1p2l, parallel lines",
        solve,
        6_205,
        NEAR_DEGENERATE_RESIDUAL,
        4,
        0.0,
        |rng, offset| {
            let d = rng.unit_vector3();
            let tilted = (d + orthogonal_unit(rng, &d) * offset).normalize();
            let (a, c) = (camera_point(rng, 1.0), camera_point(rng, 1.0));
            let point = camera_point(rng, 1.0);
            mixed_sample(rng, point, [[a, a + d], [c, c + tilted * 1.3]])
        },
    );
    assert!(
        parallel.iter().all(|&(empty, _, lost)| empty == 0 && lost == 0),
        "{parallel:?}"
    );
    // Both lines through the point (each missing it by `offset`): the depth is then not fixed.
    let crossing = sweep_degeneracy(
        "p1p2l, point at the crossing",
        solve,
        6_206,
        NEAR_DEGENERATE_RESIDUAL,
        4,
        0.0,
        |rng, offset| {
            let point = camera_point(rng, 1.0);
            let [u, v] = [camera_point(rng, 1.0), camera_point(rng, 1.0)];
            let (miss1, miss2) = (rng.unit_vector3() * offset, rng.unit_vector3() * offset);
            mixed_sample(rng, point, [[point + miss1, u], [point + miss2, v]])
        },
    );
    assert_eq!(crossing[0].2, 0, "{crossing:?}");
    // Coincident interpretation planes: the second line in the plane of the camera centre and the first.
    let planes = sweep_degeneracy(
        "p1p2l, coincident planes",
        solve,
        6_207,
        NEAR_DEGENERATE_RESIDUAL,
        4,
        0.0,
        |rng, offset| {
            let [a, b] = [camera_point(rng, 1.0), camera_point(rng, 1.0)];
            let n = a.cross(&b).normalize();
            let second = [
                a * rng.uniform_in(0.5, 2.0) + n * offset,
                b * rng.uniform_in(0.5, 2.0) + (a - b) * 0.3,
            ];
            let point = camera_point(rng, 1.0);
            mixed_sample(rng, point, [[a, b], second])
        },
    );
    assert_eq!(planes[0].2, 0, "{planes:?}");
}

#[test]
fn invalid_input_gives_no_pose() {
    let mut rng = Rng::new(6_208);
    let sample = Sample::random(&mut rng, KINDS, 1.0);
    assert!(!solve(&sample.features).is_empty());
    assert_non_finite_gives_no_pose(solve, &sample);
    for i in 0..3 {
        let mut f = sample.features;
        match &mut f[i] {
            Feature::Point { bearing, .. } => *bearing = Vector3::zeros(),
            Feature::Line { normal, .. } => *normal = Vector3::zeros(),
        }
        assert!(solve(&f).is_empty(), "zero bearing or normal {i}");
    }
    for i in 1..3 {
        let mut f = sample.features;
        if let Feature::Line { endpoints, .. } = &mut f[i] {
            endpoints[1] = endpoints[0];
        }
        assert!(solve(&f).is_empty(), "coincident endpoints {i}");
    }
    assert_scale_invariant(solve, &sample, 4);
}
