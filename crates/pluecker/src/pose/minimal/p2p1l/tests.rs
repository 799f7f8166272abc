//! Tests of [`super::p2p1l`]: noise-free random instances, an independent multistart search, and the
//! degenerate cases (the line through both points, both points on one ray, invalid input).

use super::super::testing::*;
use super::super::Feature;
use super::*;
use crate::rng::Rng;

const KINDS: [bool; 3] = [true, true, false];

fn solve(features: &[Feature; 3]) -> Vec<Pose> {
    let mut bearings = [Vector3::zeros(); 2];
    let mut points = [Vector3::zeros(); 2];
    for (i, f) in features[..2].iter().enumerate() {
        let Feature::Point { bearing, point } = f else {
            panic!("two points first")
        };
        (bearings[i], points[i]) = (*bearing, *point);
    }
    let Feature::Line { normal, endpoints } = features[2] else {
        panic!("then a line")
    };
    p2p1l(&bearings, &points, &normal, &endpoints)
}

#[test]
fn random_instances_recover_the_true_pose() {
    let summary = check_random_draws("p2p1l", solve, KINDS, 6_101, 1000, 1.0, 1e-9, 4);
    assert_eq!(summary.counts[0], 0, "every instance has its true solution");
}

#[test]
fn narrow_field_of_view_is_as_accurate_as_its_conditioning() {
    check_random_draws("p2p1l", solve, KINDS, 6_102, 300, 0.1, 1e-9, 4);
}

#[test]
fn every_solution_found_by_multistart_newton_is_returned() {
    let mut rng = Rng::new(6_103);
    let mut checked = 0;
    for draw in 0..100 {
        let sample = Sample::random(&mut rng, KINDS, 1.0);
        let poses = solve(&sample.features);
        checked += assert_multistart_finds_nothing_more(&sample, &poses, &mut rng, 40, &format!("draw {draw}"));
    }
    println!("p2p1l multistart: {checked} distinct solutions checked");
    assert!(checked >= 100, "{checked}");
}
