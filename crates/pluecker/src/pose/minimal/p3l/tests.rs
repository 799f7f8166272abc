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
    let summary = check_random_draws("p3l", solve, LINES, 6_301, 1000, 1.0, 1e-9, 8);
    assert_eq!(summary.counts[0], 0, "every instance has its true solution");
}

#[test]
fn narrow_field_of_view_is_as_accurate_as_its_conditioning() {
    check_random_draws("p3l", solve, LINES, 6_302, 300, 0.1, 1e-9, 8);
}

#[test]
fn every_solution_found_by_multistart_newton_is_returned() {
    let mut rng = Rng::new(6_303);
    let mut checked = 0;
    for draw in 0..100 {
        let sample = Sample::random(&mut rng, LINES, 1.0);
        let poses = solve(&sample.features);
        checked += assert_multistart_finds_nothing_more(&sample, &poses, &mut rng, 40, &format!("draw {draw}"));
    }
    println!("p3l multistart: {checked} distinct solutions checked");
    assert!(checked > 100, "{checked}");
}
