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
    let summary = check_random_draws("p1p2l", solve, KINDS, 6_201, 1000, 1.0, 1e-9, 4);
    assert_eq!(summary.counts[0], 0, "every instance has its true solution");
}

#[test]
fn narrow_field_of_view_is_as_accurate_as_its_conditioning() {
    check_random_draws("p1p2l", solve, KINDS, 6_202, 300, 0.1, 1e-9, 4);
}

#[test]
fn every_solution_found_by_multistart_newton_is_returned() {
    let mut rng = Rng::new(6_203);
    let mut checked = 0;
    for draw in 0..100 {
        let sample = Sample::random(&mut rng, KINDS, 1.0);
        let poses = solve(&sample.features);
        checked += assert_multistart_finds_nothing_more(&sample, &poses, &mut rng, 40, &format!("draw {draw}"));
    }
    println!("p1p2l multistart: {checked} distinct solutions checked");
    assert!(checked >= 100, "{checked}");
}
