//! Tests of [`super::solve`]: every mix, in every order of the features, goes to its solver and gives
//! the same set of poses.

use super::testing::*;
use super::*;
use crate::rng::Rng;

/// The six orders of three features.
const ORDERS: [[usize; 3]; 6] = [[0, 1, 2], [0, 2, 1], [1, 0, 2], [1, 2, 0], [2, 0, 1], [2, 1, 0]];

#[test]
fn solve_dispatches_every_mix_in_every_order() {
    let mut rng = Rng::new(6_001);
    for kinds in [[true; 3], [true, true, false], [true, false, false], [false; 3]] {
        for draw in 0..50 {
            let sample = Sample::random(&mut rng, kinds, 1.0);
            if sample.conditioning() > KAPPA_LIMIT {
                continue;
            }
            let reference = solve(&sample.features);
            let what = format!("{kinds:?}, draw {draw}");
            assert!(sample.error(&reference) <= POSE_TOLERANCE, "{what}");
            for order in ORDERS {
                let features = order.map(|i| sample.features[i]);
                let poses = solve(&features);
                assert_eq!(poses.len(), reference.len(), "{what}, order {order:?}");
                for Pose {
                    rotation: r,
                    translation: t,
                } in &poses
                {
                    let same = Sample {
                        rotation: *r,
                        translation: *t,
                        ..sample.clone()
                    };
                    assert!(same.error(&reference) <= POSE_TOLERANCE, "{what}, order {order:?}");
                }
            }
        }
    }
}
