//! Unit tests of the pose certificate's steps (module docs of [`super`]), each against an
//! independent oracle.

mod box_bound;
mod local_bound;
mod minorant;
mod problem;
mod rig;
mod search;

use super::box_bound::*;
use super::local_bound::*;
use super::minorant::*;
use super::problem::*;
use super::search::*;
use super::*;
use crate::geometry::quaternion::{exp_so3, skew};
use crate::global::branch_and_bound::{Bound, BoundingOracle, Region};
use crate::optim::Objective;
use crate::pose::reprojection::ReprojectionCost;
use crate::rng::Rng;
use crate::synthetic::visible_scene;
use nalgebra::{Matrix2, Matrix3, SMatrix, SVector, Vector3};
use std::rc::Rc;

/// Step 2's minorant summed point by point, the oracle of [`Minorant`]: `Σ (y_z / Dᵢ)² ‖rᵢ(y)‖²`
/// at `y = R Xᵢ + t`, with the residual `rᵢ(y) = Wᵢ K₂ (π(y) − ūᵢ)` projected here.
fn minorant_by_points(problem: &Problem, depths: &[f64], r: &Matrix3<f64>, t: &Vector3<f64>) -> f64 {
    (problem
        .corr
        .points3d
        .iter()
        .zip(&problem.corr.points2d)
        .zip(depths)
        .zip(&problem.cameras[0].point_maps))
    .map(|(((x, u), d), map)| {
        let y = r * x + t;
        let seen = problem.cameras[0].k_inv * Vector3::new(u.x, u.y, 1.0);
        let residual = map * (y.xy() / y.z - seen.xy() / seen.z);
        (y.z / d).powi(2) * residual.norm_squared()
    })
    .sum()
}

/// Per point, `H = Aᵀ A` of the oracle's minorant `‖A y‖² = y_z² ‖rᵢ(y)‖²` (`A = Wᵢ K₂ E`,
/// `E = [1 0 −ū₁; 0 1 −ū₂]`), and `λ_max(H)`.
fn forms_by_points(problem: &Problem) -> Vec<(Matrix3<f64>, f64)> {
    (problem.corr.points2d.iter().zip(&problem.cameras[0].point_maps))
        .map(|(u, map)| {
            let seen = problem.cameras[0].k_inv * Vector3::new(u.x, u.y, 1.0);
            let e = SMatrix::<f64, 2, 3>::new(1.0, 0.0, -seen.x / seen.z, 0.0, 1.0, -seen.y / seen.z);
            let h = e.transpose() * map.transpose() * map * e;
            (h, h.symmetric_eigenvalues().max())
        })
        .collect()
}

/// The Minkowski bound `½ (√q_min − θ η)₊²` at the rotation `r` of the minorant of the depth
/// bounds `depths` scaled by `κ`, point by point (the oracle of [`ScaledMinorant::bound_near`]): `q_min` from
/// the normal equations `Σ wᵢ Hᵢ (R Xᵢ + t) = 0`, `η² = Σ wᵢ λ_max(Hᵢ) ‖Xᵢ‖²`, `wᵢ = κ / Dᵢ²`.
fn bound_near_by_points(problem: &Problem, depths: &[f64], kappa: f64, r: &Matrix3<f64>, theta: f64) -> f64 {
    let (mut lhs, mut rhs, mut eta2) = (Matrix3::zeros(), Vector3::zeros(), 0.0);
    for ((x, d), (h, norm2)) in problem.corr.points3d.iter().zip(depths).zip(forms_by_points(problem)) {
        let w = kappa / (d * d);
        lhs += h * w;
        rhs -= h * (r * x) * w;
        eta2 += w * norm2 * x.norm_squared();
    }
    let t = lhs.lu().solve(&rhs).unwrap();
    let q_min = kappa * minorant_by_points(problem, depths, r, &t);
    0.5 * (q_min.sqrt() - theta * eta2.sqrt()).max(0.0).powi(2)
}

/// The least value of `f` found over the rotation ball `‖φ‖ ≤ θ`: `samples` random points (every other
/// one on the sphere), then `steps` of a random local search whose step shrinks where it fails. An
/// upper estimate of the minimum, which a lower bound must not exceed.
fn least_over_ball(
    rng: &mut Rng,
    theta: f64,
    (samples, steps): (usize, usize),
    f: impl Fn(&Vector3<f64>) -> f64,
) -> f64 {
    let mut best = (Vector3::zeros(), f(&Vector3::zeros()));
    for k in 0..samples {
        let radius = if k % 2 == 0 {
            theta
        } else {
            theta * rng.uniform_in(0.0, 1.0)
        };
        let phi = rng.unit_vector3() * radius;
        let value = f(&phi);
        if value < best.1 {
            best = (phi, value);
        }
    }
    let mut step = 0.25 * theta;
    for _ in 0..steps {
        let phi = best.0 + rng.unit_vector3() * step;
        let phi = phi * (theta / phi.norm()).min(1.0);
        let value = f(&phi);
        if value < best.1 {
            best = (phi, value);
        } else {
            step *= 0.95;
        }
    }
    best.1
}

/// A translation set for the tests of the bound without depth bounds: largest semi-axis `radius`,
/// round or thin (a random axis and the others 0.05-0.5 of it), its centre within `off` radii of
/// `truth`; and its `L` (`shape = L Lᵀ`).
fn translation_set(truth: &Vector3<f64>, radius: f64, off: f64, rng: &mut Rng) -> (TranslationEllipsoid, Matrix3<f64>) {
    let centre = truth + rng.unit_vector3() * radius * rng.uniform_in(0.0, off);
    let axis = rng.unit_vector3();
    let thin = if rng.uniform() < 0.5 {
        1.0
    } else {
        rng.uniform_in(0.05, 0.5)
    };
    let shape =
        (axis * axis.transpose() * (1.0 - thin * thin) + Matrix3::identity() * (thin * thin)) * (radius * radius);
    let l = shape.cholesky().unwrap().l();
    (TranslationEllipsoid { centre, shape, radius }, l)
}

/// `½ min (tᵀ C t + 2 gᵀ t + c₀)` over the ball `‖t − t*‖ ≤ spread`, by projected gradient steps
/// (the oracle of the linearised bounds with segments, whose quadratics the tests assemble).
fn least_in_ball(c: &Matrix3<f64>, g: &Vector3<f64>, c0: f64, t_star: &Vector3<f64>, spread: f64) -> f64 {
    let value = |t: &Vector3<f64>| t.dot(&(c * t)) + 2.0 * g.dot(t) + c0;
    let lipschitz = c.symmetric_eigenvalues().max();
    let mut t = *t_star;
    for _ in 0..400 {
        let step = t - (c * t + g) / lipschitz;
        let off = step - t_star;
        t = t_star + off * (spread / off.norm()).min(1.0);
    }
    0.5 * value(&t)
}

/// Runs `body` on a rotation search (recording, not bounding, inside the whitened ball of
/// `target`) around the true pose of a seeded scene with 1 px noise, at a level raised to 4× the
/// true pose's cost so that more boxes stay open.
fn with_rotation_search(
    f: f64,
    n: usize,
    seed: u64,
    rng: &mut Rng,
    target: f64,
    body: impl FnOnce(&mut RotationSearch, &mut Rng),
) {
    let scene = visible_scene(f, n, 0, false, seed);
    let corr = scene.noisy(1.0, true, rng);
    let truth = Pose::new(scene.rotation, scene.translation);
    let cost = ReprojectionCost::of(&scene.camera.intrinsics(), &corr);
    let f_hat = 4.0 * cost.cost(&truth);
    let problem = Problem::new(&scene.camera.intrinsics(), &corr, f_hat).unwrap();
    let whitening = Whitening::new(&cost.linearize(&truth).gauss_newton).unwrap();
    let mut record = RecordedCells::new(0.0);
    let mut search = RotationSearch {
        problem: &problem,
        whitening: &whitening,
        pose: &truth,
        f_hat,
        target,
        max_relative_gap: 0.0,
        slack: Slack::NONE,
        inside_ball: InsideBall::Record(&mut record),
        linearise_lines: true,
        radius: 0.0,
    };
    body(&mut search, rng);
}

/// The test's gap on `f = ½ Σ r²` is the documented gap on `Σ r² = 2f`, `(cost − lower) / max(cost,
/// 1e-12)` (written out here, not taken from the crate), and the level a bound must reach to close the
/// gap (`f − gap · max(f, HALF_COST_FLOOR)`, the local bound's target) closes it exactly: a floor of
/// `1e-12` on `f` (twice the documented one) would report gaps up to 2x smaller for costs below
/// `2e-12` and certify where the documented gap does not close.
#[test]
fn the_gap_of_half_costs_is_the_documented_gap_of_the_sums_of_squares() {
    let documented = |cost: f64, lower: f64| ((cost - lower) / cost.max(1e-12)).max(0.0);
    for f in [1e-14, 3e-13, 0.5e-12, 0.7e-12, 1e-12, 1.5e-12, 1e-3, 10.0] {
        for fraction in [0.0, 1e-4, 0.5, 1.0] {
            let lower = f * (1.0 - fraction);
            let (proved, want) = (super::half_cost_gap(f, lower), documented(2.0 * f, 2.0 * lower));
            assert!(
                (proved - want).abs() <= 1e-15 * want.max(1.0),
                "f {f:e}, lower {lower:e}: {proved:e} against {want:e}"
            );
        }
        let gap = 1e-3;
        let target = f - gap * f.max(super::HALF_COST_FLOOR);
        let closes = documented(2.0 * f, 2.0 * target);
        assert!(
            (closes - gap).abs() <= 1e-9 * gap,
            "f {f:e}: the target closes a gap of {closes:e}"
        );
    }
}
