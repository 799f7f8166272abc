//! The bounds inside the pose certificate (`pose::certificate`), each checked against an independent
//! oracle (`pose_oracle`: the cost written again, numeric derivatives, brute force), on poses that are
//! not minima and where the bounds are nearly tight:
//! - step 1's depth bounds against a pose of the sublevel set built to reach as far as it can;
//! - step 4's one-dimensional bound against a fine grid;
//! - step 4's curvature bound `K` against second differences of the oracle's residuals along
//!   whitened rays;
//! - step 4's bound over a whitened ball against the least cost found in the ball.

use crate::pose_oracle;

use nalgebra::{Matrix2, Rotation3, Unit, Vector2, Vector3, Vector6};
use pluecker::pose::Correspondences;
use pluecker::rng::Rng;
use pluecker::synthetic::{random_observation_noise, visible_scene};
use pluecker::testing::pose_certificate::{depth_bounds, local_bound, local_lower_bound, LocalBound};
use pluecker::Camera;
use pose_oracle::{centred, cost, many_start, pixel, residuals, OraclePose};

/// `M` with `‖M m_xy‖` the standard deviation scale of line `line`'s endpoint `end`: with `G` the
/// upper-left 2x2 block of `K⁻ᵀ` (`G m_xy` is the normal of the pixel line of the moment `m`) and `C`
/// the endpoint's covariance, `M = C^½ G` (`‖M v‖² = vᵀ Gᵀ C G v`; the symmetric square root, from the
/// eigen-decomposition), `G` without covariances.
fn endpoint_map(k: &Camera, corr: &Correspondences, line: usize, end: usize) -> Matrix2<f64> {
    let g = k
        .intrinsics()
        .matrix()
        .try_inverse()
        .unwrap()
        .transpose()
        .fixed_view::<2, 2>(0, 0)
        .into_owned();
    match &corr.noise {
        None => g,
        Some(noise) => {
            let eigen = noise.lines[line][end].symmetric_eigen();
            let root = eigen.eigenvectors
                * Matrix2::from_diagonal(&eigen.eigenvalues.map(f64::sqrt))
                * eigen.eigenvectors.transpose();
            root * g
        }
    }
}

/// The unit ray of pixel `u` (camera frame).
fn bearing(k: &Camera, u: &Vector2<f64>) -> Vector3<f64> {
    let y = (u.y - k.intrinsics().cy) / k.intrinsics().fy;
    let x = (u.x - k.intrinsics().cx - k.intrinsics().skew * y) / k.intrinsics().fx;
    Vector3::new(x, y, 1.0).normalize()
}

/// `b` turned by `angle` towards `towards`, in their plane.
fn turned(b: &Vector3<f64>, towards: &Vector3<f64>, angle: f64) -> Vector3<f64> {
    let axis = Unit::new_normalize(b.cross(towards));
    Rotation3::from_axis_angle(&axis, angle) * b
}

/// Step 1: two points seen `γ` apart at the level `f̂`. The pose built here has each point turned
/// towards the other by the angle `δ` at which its pixel error is `√f̂` (so the cost is `f̂`), and the
/// triangle camera-Xᵢ-Xⱼ right-angled at Xⱼ, which puts Xᵢ at the largest distance `d / sin(γ − 2δ)`
/// that those angles allow. The depth bound must hold there; it is `d / sin(γ − 2α)` with
/// `α = √(2f̂) / s` (`s` the least singular value of `K`'s 2x2 block), and `δ ≈ α / √2`, so a
/// bound that drops a factor of the angle, takes the wrong sine, or uses `K`'s largest singular value
/// falls below it.
#[test]
fn depth_bounds_hold_at_the_farthest_pose_of_the_sublevel_set() {
    let mut rng = Rng::new(41);
    let mut checked = 0;
    let mut tightest: f64 = 0.0;
    // (fx, fy, skew, separation direction in the image): square pixels; fy < fx with the points
    // apart vertically (the least singular value is fy's); skew.
    let cameras = [
        (800.0, 800.0, 0.0, Vector2::new(1.0, 0.0)),
        (250.0, 250.0, 0.0, Vector2::new(0.6, 0.8)),
        (900.0, 450.0, 0.0, Vector2::new(0.0, 1.0)),
        (600.0, 600.0, 40.0, Vector2::new(0.0, 1.0)),
    ];
    for &(fx, fy, skew, dir) in &cameras {
        let k = Camera::pinhole(fx, fy, 320.0, 240.0, skew).unwrap();
        for _ in 0..25 {
            let centre = Vector2::new(rng.uniform_in(200.0, 440.0), rng.uniform_in(150.0, 330.0));
            let sep = rng.uniform_in(10.0, 80.0);
            let (ui, uj) = (centre - dir * sep * 0.5, centre + dir * sep * 0.5);
            let (bi, bj) = (bearing(&k, &ui), bearing(&k, &uj));
            let gamma = bi.angle(&bj);
            // The level at which α is a third of γ (γ − 2α = γ/3 > 0).
            let s_min = nalgebra::Matrix2::new(fx, skew, 0.0, fy).singular_values().min();
            let level = 0.5 * (gamma * s_min / 3.0).powi(2);
            // δ at which the pixel error of a point turned towards its partner is √level (bisection
            // on the oracle's pixel; the error grows with δ).
            let error = |b: &Vector3<f64>, other: &Vector3<f64>, u: &Vector2<f64>, delta: f64| {
                (pixel(&k, &turned(b, other, delta)) - u).norm()
            };
            let solve = |b: &Vector3<f64>, other: &Vector3<f64>, u: &Vector2<f64>| {
                let (mut lo, mut hi) = (0.0, gamma / 2.0);
                for _ in 0..80 {
                    let mid = 0.5 * (lo + hi);
                    if error(b, other, u, mid) <= level.sqrt() {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                lo
            };
            let (di, dj) = (solve(&bi, &bj, &ui), solve(&bj, &bi, &uj));
            let (ai, aj) = (turned(&bi, &bj, di), turned(&bj, &bi, dj));
            let g = ai.angle(&aj);
            let d = rng.uniform_in(0.5, 3.0);
            let (xi, xj) = (ai * d / g.sin(), aj * d / g.tan());
            // World points: the pair moved by a random rigid motion.
            let r = rng.rotation();
            let offset = Vector3::new(rng.normal(), rng.normal(), rng.normal());
            let (wi, wj) = (r.transpose() * (xi - offset), r.transpose() * (xj - offset));
            let corr = Correspondences {
                points2d: vec![ui, uj],
                points3d: vec![wi, wj],
                ..Default::default()
            };
            let pose = OraclePose::new(r, offset);
            let f = cost(&k, &corr, &pose);
            // The construction: cost at the level (bisection to ~1e-16 relative), points in front.
            assert!(f <= level * (1.0 + 1e-9), "cost {f} above the level {level}");
            assert!(xi.z > 0.0 && xj.z > 0.0);
            let bounds = depth_bounds(&k.intrinsics(), &corr, level).expect("two points seen apart");
            let reached = xi.norm();
            assert!(
                reached <= bounds[0] * (1.0 + 1e-9),
                "fx={fx} fy={fy} skew={skew}: ‖xᵢ‖ = {reached} at cost {f} ≤ {level}, above the depth bound {}",
                bounds[0]
            );
            tightest = tightest.max(reached / bounds[0]);
            checked += 1;
        }
    }
    assert_eq!(checked, 100);
    // The construction nearly reaches the bound (δ ≈ α/√2: sin(γ/3) / sin((1 − √2/3)γ) ≈ 0.63).
    eprintln!("depth bounds: the farthest pose reaches {tightest:.3} of the bound");
    assert!(tightest > 0.5, "the construction reaches only {tightest} of the bound");
}

/// Step 4's one-dimensional bound is at most the least of `½ (√q(d) − ½ k d²)₊²` on a fine grid of
/// `[0, ρ]`, for random models (vertex inside and outside the interval, small and large `k`).
#[test]
fn the_local_bound_is_below_its_function_on_a_fine_grid() {
    let mut rng = Rng::new(42);
    for i in 0..400 {
        let f_hat = 10f64.powf(rng.uniform_in(-3.0, 3.0));
        let root = (2.0 * f_hat).sqrt();
        let gradient = if i % 4 == 0 {
            0.0
        } else {
            root * rng.uniform_in(0.0, 1.5)
        };
        let lambda = rng.uniform_in(0.5, 1.5);
        let k = 10f64.powf(rng.uniform_in(-4.0, 0.0)) / root;
        let rho = root * rng.uniform_in(0.5, 20.0);
        let bound = local_lower_bound(f_hat, gradient, lambda, k, rho);
        let function = |d: f64| {
            let q = 2.0 * f_hat - 2.0 * gradient * d + lambda * d * d;
            0.5 * (q.max(0.0).sqrt() - 0.5 * k * d * d).max(0.0).powi(2)
        };
        let n = 20_000;
        let least = (0..=n)
            .map(|j| function(rho * j as f64 / n as f64))
            .fold(f64::INFINITY, f64::min);
        // Rounding of q near its vertex: ~1e-15 of 2f̂.
        assert!(
            bound <= least + 1e-12 * f_hat,
            "case {i}: bound {bound} above the least sampled value {least} (f̂ {f_hat}, g {gradient}, λ {lambda}, k {k}, ρ {rho})"
        );
        assert!(bound >= 0.0);
    }
    // Exact for a flat model: q(d) = 2f̂ + d², k = 0: the least value is f̂ at d = 0.
    assert_eq!(local_lower_bound(2.0, 0.0, 1.0, 0.0, 5.0), 2.0);
}

/// Scenes for step 4: wide and narrow fields of view, with and without lines, at a pose that is not
/// a minimum (the oracle's minimum moved by a whitened step).
fn step4_scenes() -> Vec<(Camera, Correspondences, OraclePose, String)> {
    let plain = [
        (250.0, 10, 0, false),
        (800.0, 20, 6, false),
        (800.0, 6, 0, true),
        (800.0, 5, 0, true),
        (250.0, 6, 0, true),
        (4000.0, 12, 4, true),
        (15000.0, 10, 3, false),
    ];
    // Per-observation covariances: anisotropic, standard deviations 0.3-3 px, random orientations.
    let with_covariances = [(800.0, 20, 6, false), (4000.0, 12, 4, true), (250.0, 10, 3, false)];
    let cases = (plain
        .into_iter()
        .flat_map(|case| (0..3u64).map(move |seed| (case, seed, false))))
    .chain(
        with_covariances
            .into_iter()
            .flat_map(|case| (50..52u64).map(move |seed| (case, seed, true))),
    );
    cases
        .map(|((f, np, nl, planar), seed, covariances)| {
            let scene = visible_scene(f, np, nl, planar, seed);
            let mut rng = Rng::new(800 + seed);
            let (mut corr, c) = centred(&scene.noisy(1.0, true, &mut rng));
            if covariances {
                corr.noise = Some(random_observation_noise(&mut rng, np, nl, (0.3, 3.0)));
            }
            let truth = OraclePose::new(scene.rotation, scene.translation + scene.rotation * c);
            let minimum = many_start(&scene.camera, &corr, &truth, 0, &mut rng)[0].0;
            let label = if covariances { " covariances" } else { "" };
            (
                scene.camera,
                corr,
                minimum,
                format!("f={f} {np}p+{nl}l planar={planar}{label} seed {seed}"),
            )
        })
        .collect()
}

/// The length unit of the step-4 tests: `√(2f̂) + 0.1`, the residual norm at the minimum (plus a
/// margin for exact data).
fn residual_unit(k: &Camera, corr: &Correspondences, minimum: &OraclePose) -> f64 {
    (2.0 * cost(k, corr, minimum)).sqrt() + 0.1
}

/// A ball of step 4 centred away from `minimum`: the pose `shift` units ([`residual_unit`]) of
/// whitened step from it in a random direction, the ball's radius of `scale` units, and step 4's bound
/// there (`None` where it cannot be formed).
fn ball_off_the_minimum(
    k: &Camera,
    corr: &Correspondences,
    minimum: &OraclePose,
    shift: f64,
    scale: f64,
    rng: &mut Rng,
) -> Option<(OraclePose, f64, LocalBound)> {
    let unit = residual_unit(k, corr, minimum);
    let start = local_bound(
        &k.intrinsics(),
        corr,
        &minimum.to_library(),
        cost(k, corr, minimum),
        1.0,
    )
    .unwrap();
    let v0 = Vector6::from_fn(|_, _| rng.normal()).normalize();
    let pose = minimum.step(&(start.whitening * v0 * shift * unit));
    let radius = scale * unit;
    let b = local_bound(&k.intrinsics(), corr, &pose.to_library(), cost(k, corr, &pose), radius).ok()?;
    Some((pose, radius, b))
}

/// The correspondences with every object coordinate multiplied by `lambda`, and `pose` with its
/// translation multiplied by `lambda`: the same pixels, the same residuals at corresponding poses.
fn scaled_world(corr: &Correspondences, pose: &OraclePose, lambda: f64) -> (Correspondences, OraclePose) {
    let mut out = corr.clone();
    out.points3d.iter_mut().for_each(|x| *x *= lambda);
    out.lines3d.iter_mut().flatten().for_each(|x| *x *= lambda);
    (out, OraclePose::new(pose.r, pose.t * lambda))
}

/// `K` bounds `‖r''(s)‖` along whitened rays `s ↦ (exp(s a_ω) R̂, t̂ + s a_τ)`, `a = T v`, `s ≤ ρ`: the
/// second differences of the oracle's residuals, along random directions and then along the
/// direction that maximised them refined by random search, never exceed it.
#[test]
fn the_curvature_bound_holds_along_whitened_rays() {
    let mut rng = Rng::new(43);
    let mut worst: f64 = 0.0;
    let (mut checked, mut with_covariances) = (0, 0);
    for (k, corr, minimum, name) in step4_scenes() {
        for (shift, scale) in [(0.0, 3.0), (2.0, 6.0), (0.0, 16.0)] {
            let Some((pose, radius, b)) = ball_off_the_minimum(&k, &corr, &minimum, shift, scale, &mut rng) else {
                continue;
            };
            let second = |v: &Vector6<f64>, s: f64| -> f64 {
                let a = b.whitening * v;
                let h = 1e-2 * radius;
                let at = |x: f64| residuals(&k, &corr, &pose.step(&(a * x)));
                let (lo, mid, hi) = (at(s - h), at(s), at(s + h));
                lo.iter()
                    .zip(&mid)
                    .zip(&hi)
                    .map(|((l, m), u)| ((l - 2.0 * m + u) / (h * h)).powi(2))
                    .sum::<f64>()
                    .sqrt()
            };
            // Random directions at the ball's edge and half-way, then a hill climb from the three
            // largest on the sphere of directions and the radius.
            let mut found: Vec<(f64, Vector6<f64>, f64)> = Vec::new();
            for _ in 0..60 {
                let v = Vector6::from_fn(|_, _| rng.normal()).normalize();
                for s in [radius, 0.5 * radius] {
                    found.push((second(&v, s), v, s));
                }
            }
            found.sort_by(|a, b| b.0.total_cmp(&a.0));
            let mut best = found[0];
            for start in found.into_iter().take(3) {
                let mut here = start;
                let mut step = 0.3;
                for _ in 0..80 {
                    let v = (here.1 + Vector6::from_fn(|_, _| rng.normal()) * step).normalize();
                    let s = (here.2 + radius * step * rng.normal()).clamp(0.0, radius);
                    let value = second(&v, s);
                    if value > here.0 {
                        here = (value, v, s);
                    } else {
                        step = (step * 0.93).max(1e-3);
                    }
                }
                if here.0 > best.0 {
                    best = here;
                }
            }
            // Central differences: error O(h² r''''), far below K (h = ρ/100).
            assert!(
                best.0 <= b.curvature * 1.01 + 1e-9,
                "{name}, shift {shift}: ‖r''‖ = {} > K = {} at s = {} of {radius}",
                best.0,
                b.curvature,
                best.2
            );
            // The same ball in units λ times larger (object and translation scaled by λ; pixels and
            // rotations unchanged) is the same problem: the whitened rays map one to one and
            // `‖r''(s)‖` along them is unchanged, so the largest value found above bounds it there too
            // and `K` must cover it at every λ. Depths far below one unit and segments whose moment is
            // far above or below one exercise every term of the bound (a term whose units are wrong,
            // say `‖y‖ + ‖y‖²` or a `%` for a `/`, falls below the truth at one of the scales).
            let level = cost(&k, &corr, &pose);
            for lambda in [1e-3, 1e-2, 0.1, 10.0, 1e3] {
                let (scaled, scaled_pose) = scaled_world(&corr, &pose, lambda);
                let Ok(b_scaled) = local_bound(&k.intrinsics(), &scaled, &scaled_pose.to_library(), level, radius)
                else {
                    panic!("{name}, shift {shift}: no bound at scale {lambda} where there is one at scale 1");
                };
                assert!(
                    best.0 <= b_scaled.curvature * 1.01 + 1e-9,
                    "{name}, shift {shift}, world scaled by {lambda}: ‖r''‖ = {} > K = {} (K = {} at scale 1)",
                    best.0,
                    b_scaled.curvature,
                    b.curvature
                );
            }
            worst = worst.max(best.0 / b.curvature);
            checked += 1;
            with_covariances += usize::from(corr.noise.is_some());
        }
    }
    eprintln!(
        "curvature: {checked} balls ({with_covariances} with covariances), the largest ‖r''‖ reaches {worst:.3} of K"
    );
    assert!(with_covariances >= 8, "only {with_covariances} balls with covariances");
    assert!(checked >= 20, "only {checked} balls");
}

/// Step 4's bound over a whitened ball is at most the least cost in the ball, found by the oracle
/// (projected gradient descent in whitened coordinates from the centre and from random points), at
/// poses that are not minima (nonzero gradient), where the bound is far below the centre's cost.
#[test]
fn the_local_bound_is_below_the_least_cost_in_the_ball() {
    let mut rng = Rng::new(44);
    let (mut checked, mut with_covariances) = (0, 0);
    let mut closest: f64 = f64::INFINITY;
    for (k, corr, minimum, name) in step4_scenes() {
        let unit = residual_unit(&k, &corr, &minimum);
        for (shift, scale) in [(0.0, 2.0), (1.0, 2.0), (3.0, 4.0)] {
            let Some((pose, radius, b)) = ball_off_the_minimum(&k, &corr, &minimum, shift, scale, &mut rng) else {
                continue;
            };
            let t = b.whitening;
            let f = |v: &Vector6<f64>| cost(&k, &corr, &pose.step(&(t * v)));
            let project = |v: Vector6<f64>| if v.norm() > radius { v * (radius / v.norm()) } else { v };
            let mut least = f(&Vector6::zeros());
            for trial in 0..6 {
                let mut v = if trial == 0 {
                    Vector6::zeros()
                } else {
                    project(Vector6::from_fn(|_, _| rng.normal()) * radius)
                };
                let mut fv = f(&v);
                let mut step = 0.5;
                for _ in 0..200 {
                    // Whitened gradient by central differences.
                    let g = Vector6::from_fn(|i, _| {
                        let mut e = Vector6::zeros();
                        e[i] = 1e-6 * unit;
                        (f(&(v + e)) - f(&(v - e))) / (2e-6 * unit)
                    });
                    let next = project(v - g * step);
                    let fn_ = f(&next);
                    if fn_ < fv {
                        v = next;
                        fv = fn_;
                        step *= 1.2;
                    } else {
                        step *= 0.5;
                        if step < 1e-12 {
                            break;
                        }
                    }
                }
                least = least.min(fv);
            }
            assert!(
                b.raw_bound <= least * (1.0 + 1e-9) + 1e-12,
                "{name}, shift {shift}: bound {} above the least cost {least} found in the ball of radius {radius}",
                b.raw_bound
            );
            closest = closest.min((least - b.raw_bound) / least.max(1e-12));
            checked += 1;
            with_covariances += usize::from(corr.noise.is_some());
        }
    }
    eprintln!(
        "local bound: {checked} balls ({with_covariances} with covariances), the closest bound is within \
         {closest:.3e} (relative) of the least cost"
    );
    assert!(
        checked >= 30 && with_covariances >= 12,
        "only {checked} balls, {with_covariances} with covariances"
    );
}

/// The largest value of `f(v, s)` found over unit directions `v` and `s ≤ radius`: random directions
/// at the edge of the ball and half-way, then a hill climb from the best three.
fn climb(f: &dyn Fn(&Vector6<f64>, f64) -> f64, radius: f64, rng: &mut Rng) -> f64 {
    let mut found: Vec<(f64, Vector6<f64>, f64)> = Vec::new();
    for _ in 0..30 {
        let v = Vector6::from_fn(|_, _| rng.normal()).normalize();
        for s in [radius, 0.5 * radius] {
            found.push((f(&v, s), v, s));
        }
    }
    found.sort_by(|a, b| b.0.total_cmp(&a.0));
    let mut best = found[0].0;
    for start in found.into_iter().take(3) {
        let mut here = start;
        let mut step = 0.3;
        for _ in 0..60 {
            let v = (here.1 + Vector6::from_fn(|_, _| rng.normal()) * step).normalize();
            let s = (here.2 + radius * step * rng.normal()).clamp(0.0, radius);
            let value = f(&v, s);
            if value > here.0 {
                here = (value, v, s);
            } else {
                step = (step * 0.93).max(1e-3);
            }
        }
        best = best.max(here.0);
    }
    best
}

/// The parts of `K`, each against the quantity it bounds, recomputed here from its definition along
/// whitened rays `s ↦ (exp(s a_ω) R̂, t̂ + s a_τ)` (`a = T v`) and differentiated numerically: a point's
/// depth `p_z` and `|p_z' / p_z|`; a segment's `w = ‖G (A × B)_xy‖` (`G` the upper-left 2x2 block of
/// `K⁻ᵀ`), `|w''|`, `|w' / w|` and each endpoint's `|(ēᵀ (A × B))''|`. On scenes with points and
/// lines, narrow and wide fields of view, in balls up to 32 residual units, and with the world scaled
/// by λ = 0.01 and 30 (the same problem; depths and moments far from one unit, where a term with
/// the wrong units, or a `%` for a `/`, falls below the truth).
#[test]
fn each_part_of_the_curvature_bound_holds_along_whitened_rays() {
    use pluecker::testing::pose_certificate::curvature_parts;
    let mut rng = Rng::new(45);
    let (mut checked, mut worst) = (0usize, 0.0f64);
    for (k, corr, minimum, name) in step4_scenes() {
        let k_inv = k.intrinsics().matrix().try_inverse().unwrap();
        for (shift, scale) in [(0.0, 6.0), (2.0, 16.0), (0.0, 32.0)] {
            let Some((pose0, radius, _)) = ball_off_the_minimum(&k, &corr, &minimum, shift, scale, &mut rng) else {
                continue;
            };
            let level = cost(&k, &corr, &pose0);
            for lambda in [1.0, 0.01, 30.0] {
                let (c, pose) = scaled_world(&corr, &pose0, lambda);
                let Ok(parts) = curvature_parts(&k.intrinsics(), &c, &pose.to_library(), level, radius) else {
                    continue;
                };
                let t = parts.whitening;
                let at = |v: &Vector6<f64>, s: f64| pose.step(&(t * v * s));
                // Central differences in s: step 1e-3 of the radius (relative error ~1e-6 of the
                // derivative, far below the slack the checks allow).
                let h = 1e-3 * radius;
                let diff = |q: &dyn Fn(f64) -> f64, s: f64| {
                    let (lo, mid, hi) = (q(s - h), q(s), q(s + h));
                    ((hi - lo) / (2.0 * h), (hi - 2.0 * mid + lo) / (h * h), mid)
                };
                let mut check = |what: String, found: f64, bound: f64| {
                    assert!(
                        found <= bound * (1.0 + 1e-3) + 1e-12 * bound.abs().max(1e-300),
                        "{name}, shift {shift}, scale {lambda}: {what}: found {found} above the bound {bound}"
                    );
                    worst = worst.max(found / bound);
                    checked += 1;
                };
                // The least value of a positive quantity q over the ball, and the largest |q' / q|.
                let least_and_rate = |q: &dyn Fn(&Vector6<f64>, f64) -> f64, rng: &mut Rng| {
                    let least = -climb(&|v, s| -q(v, s), radius, rng);
                    let rate = climb(
                        &|v, s| {
                            let (d1, _, value) = diff(&|u| q(v, u), s);
                            (d1 / value).abs()
                        },
                        radius,
                        rng,
                    );
                    (least, rate)
                };
                for (x, pp) in c.points3d.iter().zip(&parts.points) {
                    let depth = |v: &Vector6<f64>, s: f64| {
                        let p = at(v, s);
                        (p.r * x + p.t).z
                    };
                    let (least, rate) = least_and_rate(&depth, &mut rng);
                    check(format!("depth lower bound (least depth {least})"), pp.z_lo, least);
                    check("|p_z'/p_z|".into(), rate, pp.rate);
                }
                // Each point's whitened residual moves at the pose at most at its own rate, along any
                // unit whitened direction (the largest over random directions, here by differences).
                for (i, (x, pp)) in c.points3d.iter().zip(&parts.points).enumerate() {
                    let map = c.noise.as_ref().map_or_else(Matrix2::identity, |n| n.points[i])
                        * Matrix2::new(k.intrinsics().fx, k.intrinsics().skew, 0.0, k.intrinsics().fy);
                    let residual = |v: &Vector6<f64>, s: f64| {
                        let p = at(v, s);
                        let y = p.r * x + p.t;
                        map * Vector2::new(y.x / y.z, y.y / y.z)
                    };
                    let mut fastest: f64 = 0.0;
                    for _ in 0..200 {
                        let v = Vector6::from_fn(|_, _| rng.normal()).normalize();
                        fastest = fastest.max(((residual(&v, h) - residual(&v, -h)) / (2.0 * h)).norm());
                    }
                    check("‖r_i'(0)‖".into(), fastest, pp.residual_rate);
                }
                for (line, ((seen, ends), lp)) in c.lines2d.iter().zip(&c.lines3d).zip(&parts.lines).enumerate() {
                    let moment = |v: &Vector6<f64>, s: f64| {
                        let p = at(v, s);
                        (p.r * ends[0] + p.t).cross(&(p.r * ends[1] + p.t))
                    };
                    for (end, (e, ep)) in seen.iter().zip(&lp.endpoints).enumerate() {
                        let g = endpoint_map(&k, &c, line, end);
                        let w = |v: &Vector6<f64>, s: f64| (g * moment(v, s).xy()).norm();
                        let (least, rate) = least_and_rate(&w, &mut rng);
                        check(format!("w lower bound (least w {least})"), ep.w_lo, least);
                        let w2 = climb(&|v, s| diff(&|u| w(v, u), s).1.abs(), radius, &mut rng);
                        check("|w''|".into(), w2, ep.w2);
                        check("|w'/w|".into(), rate, ep.rate);
                        let e_bar = k_inv * Vector3::new(e.x, e.y, 1.0);
                        let n = climb(&|v, s| diff(&|u| e_bar.dot(&moment(v, u)), s).1.abs(), radius, &mut rng);
                        check("|n''|".into(), n, ep.n2);
                    }
                }
            }
        }
    }
    eprintln!("curvature parts: {checked} checks, the closest reaches {worst:.3} of its bound");
    assert!(checked > 500, "only {checked} checks");
}

/// `n2_exact`, the largest `|n''(0)|` over unit whitened directions (`n = ēᵀ (A × B)`), is exact: it
/// equals the largest `|eigenvalue|` of the Hessian of `x ↦ n(exp(ω(Tx)) R̂, t̂ + τ(Tx))` at `x = 0`
/// (`d²n(s v)/ds² = vᵀ H v`), the Hessian taken here by central differences of the oracle's pose
/// step with Richardson extrapolation. Equality both ways: a form that is too small or too large fails.
#[test]
fn the_exact_moment_curvature_at_the_pose_matches_a_numeric_hessian() {
    use nalgebra::Matrix6;
    use pluecker::testing::pose_certificate::curvature_parts;
    let mut rng = Rng::new(46);
    let (mut checked, mut worst) = (0usize, 0.0f64);
    for (k, corr, minimum, name) in step4_scenes() {
        if corr.lines3d.is_empty() {
            continue;
        }
        let k_inv = k.intrinsics().matrix().try_inverse().unwrap();
        for shift in [0.0, 2.0] {
            let Some((pose0, radius, _)) = ball_off_the_minimum(&k, &corr, &minimum, shift, 1.0, &mut rng) else {
                continue;
            };
            let level = cost(&k, &corr, &pose0);
            for lambda in [1.0, 0.01, 30.0] {
                let (c, pose) = scaled_world(&corr, &pose0, lambda);
                let parts = curvature_parts(&k.intrinsics(), &c, &pose.to_library(), level, radius).unwrap();
                let t = parts.whitening;
                // The step h of the differences: 1e-3 rad of rotation and 1e-3 of the least depth of
                // translation (the whitened chart is far from isotropic, so h is set per scene).
                let alpha_w = t.fixed_rows::<3>(0).into_owned().singular_values().max();
                let alpha_t = t.fixed_rows::<3>(3).into_owned().singular_values().max();
                let depth = c
                    .lines3d
                    .iter()
                    .flatten()
                    .map(|x| (pose.r * x + pose.t).z)
                    .fold(f64::INFINITY, f64::min);
                let h = 1e-3 / alpha_w.max(alpha_t / depth);
                for ((seen, ends), lp) in c.lines2d.iter().zip(&c.lines3d).zip(&parts.lines) {
                    for (e, n2_exact) in seen.iter().zip(lp.endpoints.map(|ep| ep.n2_exact)) {
                        let e_bar = k_inv * Vector3::new(e.x, e.y, 1.0);
                        let n = |x: &Vector6<f64>| {
                            let p = pose.step(&(t * x));
                            e_bar.dot(&(p.r * ends[0] + p.t).cross(&(p.r * ends[1] + p.t)))
                        };
                        let hessian = |h: f64| {
                            Matrix6::from_fn(|i, j| {
                                let (ei, ej) = (Vector6::ith(i, h), Vector6::ith(j, h));
                                (n(&(ei + ej)) - n(&(ei - ej)) - n(&(ej - ei)) + n(&(-ei - ej))) / (4.0 * h * h)
                            })
                        };
                        // Central differences err by O(h²); Richardson's (4 H(h/2) − H(h)) / 3 by O(h⁴).
                        let hm = (hessian(0.5 * h) * 4.0 - hessian(h)) / 3.0;
                        let hm = (hm + hm.transpose()) * 0.5;
                        let numeric = hm.symmetric_eigenvalues().abs().max();
                        let gap = (n2_exact - numeric).abs() / numeric;
                        // h is 1e-3 of the scales over which n bends, so the O(h⁴) truncation is ~1e-12
                        // and the rounding (ε |n| / h² with |n''| ~ 1e-6 |n| / h²) is ~1e-10: 1e-5
                        // leaves room and still catches any wrong term of the form.
                        assert!(
                            gap <= 1e-5,
                            "{name}, shift {shift}, scale {lambda}: n2_exact = {n2_exact}, numeric Hessian gives {numeric}"
                        );
                        worst = worst.max(gap);
                        checked += 1;
                    }
                }
            }
        }
    }
    eprintln!("n2_exact: {checked} endpoints, the largest relative gap is {worst:.2e}");
    assert!(checked >= 50, "only {checked} endpoints");
}

/// Derivatives along a whitened ray `s ↦ (exp(s ω) R̂, t̂ + s τ)` of an object point `X`, in closed
/// form from the group motion (independent of the certificate's code): the camera-frame point
/// `p = R_s X + t̂ + s τ` and `p', p'', p'''` (`p' = ω × R_s X + τ`, `p⁽ᵏ⁺¹⁾ = ω × p⁽ᵏ⁾` for k ≥ 1).
fn point_jet(pose: &OraclePose, a: &Vector6<f64>, s: f64, x: &Vector3<f64>) -> [Vector3<f64>; 4] {
    let omega = a.fixed_rows::<3>(0).into_owned();
    let tau = a.fixed_rows::<3>(3).into_owned();
    let p = pose.step(&(a * s));
    let y = p.r * x;
    let d2 = omega.cross(&omega.cross(&y));
    [y + p.t, omega.cross(&y) + tau, d2, omega.cross(&d2)]
}

/// `m = A × B` and its first three derivatives along the ray (Leibniz).
fn moment_jet(jet_a: &[Vector3<f64>; 4], jet_b: &[Vector3<f64>; 4]) -> [Vector3<f64>; 4] {
    let binom = [
        [1.0, 0.0, 0.0, 0.0],
        [1.0, 1.0, 0.0, 0.0],
        [1.0, 2.0, 1.0, 0.0],
        [1.0, 3.0, 3.0, 1.0],
    ];
    std::array::from_fn(|k| (0..=k).map(|i| jet_a[i].cross(&jet_b[k - i]) * binom[k][i]).sum())
}

/// Each term of a line's part of `K`, against the quantity it bounds, its largest value along whitened
/// rays found by a hill climb over directions and `s ≤ ρ` ([`climb`]): the endpoint speeds `‖A'‖`,
/// `‖B'‖` (`speed`), the drift `‖m'(s) − m'(0)‖ / s` (`drift`), `‖q'‖` with `q = G m_xy` (`q1`),
/// `|w''|` (`w2`), and per endpoint `|n'''|` (`n3`) and `|n''|` (`n2`), `n = ēᵀ m`. The balls go out
/// to the largest radius at which the bound exists (where `w_lo` nears 0 and the `s`-terms carry the
/// bound), on wide and narrow fields of view, with the world scaled by λ from 1e-3 to 1e3 (segments
/// whose lengths, depths and moments are far from one unit). The sums are also checked piece by piece,
/// each piece against the quantity it bounds (the totals reach only ~0.1-0.4 of their bounds, the
/// pieces 0.6-0.95): the three parts of the drift, `‖m''‖ ≤ m2` and `‖q'‖² / w ≤ w2 − ‖G‖ m2` in
/// `w2`, and the mixed and end terms of `n'''` in `n3`. The derivatives come in closed form from the
/// group motion ([`point_jet`], [`moment_jet`]), themselves checked against central differences here.
#[test]
fn each_term_of_a_lines_curvature_bound_holds_out_to_the_largest_ball() {
    use pluecker::testing::pose_certificate::curvature_parts;
    let mut rng = Rng::new(47);
    let (mut checked, mut worst) = (0usize, std::collections::BTreeMap::<&str, f64>::new());
    for (k, corr, minimum, name) in step4_scenes() {
        if corr.lines3d.is_empty() {
            continue;
        }
        let k_inv = k.intrinsics().matrix().try_inverse().unwrap();
        let unit = residual_unit(&k, &corr, &minimum);
        for shift in [0.0, 2.0] {
            let Some((pose0, _, _)) = ball_off_the_minimum(&k, &corr, &minimum, shift, 1.0, &mut rng) else {
                continue;
            };
            let level = cost(&k, &corr, &pose0);
            for lambda in [1.0, 0.01, 30.0, 1e-3, 1e3] {
                let (c, pose) = scaled_world(&corr, &pose0, lambda);
                let parts_at = |r: f64| curvature_parts(&k.intrinsics(), &c, &pose.to_library(), level, r).ok();
                // The largest radius with a bound, by doubling then bisection (in residual units).
                let (mut lo, mut hi) = (1.0, 2.0);
                while parts_at(hi * unit).is_some() && hi < 1e9 {
                    (lo, hi) = (hi, 2.0 * hi);
                }
                for _ in 0..30 {
                    let mid = 0.5 * (lo + hi);
                    if parts_at(mid * unit).is_some() {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                for radius in [0.999 * lo * unit, 0.5 * lo * unit, 16.0f64.min(0.1 * lo) * unit] {
                    let Some(parts) = parts_at(radius) else {
                        continue;
                    };
                    let t = parts.whitening;
                    for (line, ((seen, ends), lp)) in c.lines2d.iter().zip(&c.lines3d).zip(&parts.lines).enumerate() {
                        let jets = |v: &Vector6<f64>, s: f64| {
                            let a = t * v;
                            let (ja, jb) = (point_jet(&pose, &a, s, &ends[0]), point_jet(&pose, &a, s, &ends[1]));
                            (ja, jb, moment_jet(&ja, &jb))
                        };
                        // |w''| = |(‖q'‖² + q·q'' − w'²) / w| with w' = q·q' / w, for endpoint `end`.
                        let maps = [0, 1].map(|end| endpoint_map(&k, &c, line, end));
                        let w2_of = |g: &Matrix2<f64>, v: &Vector6<f64>, s: f64| {
                            let m = jets(v, s).2;
                            let (q, q1, q2) = (g * m[0].xy(), g * m[1].xy(), g * m[2].xy());
                            let w = q.norm();
                            let w1 = q.dot(&q1) / w;
                            ((q1.norm_squared() + q.dot(&q2) - w1 * w1) / w).abs()
                        };
                        // The closed forms against central differences of the oracle's pose step.
                        for (g, ep) in maps.iter().zip(&lp.endpoints) {
                            let v = Vector6::from_fn(|_, _| rng.normal()).normalize();
                            let s = rng.uniform_in(0.1, 0.9) * radius;
                            let h = 1e-2 * radius;
                            let w = |u: f64| {
                                let p = pose.step(&(t * v * u));
                                (g * (p.r * ends[0] + p.t).cross(&(p.r * ends[1] + p.t)).xy()).norm()
                            };
                            let numeric = ((w(s + h) - 2.0 * w(s) + w(s - h)) / (h * h)).abs();
                            let exact = w2_of(g, &v, s);
                            // Second differences err by O(h² w'''') + O(ε w / h²); 1% still catches a
                            // wrong term or factor in the closed forms.
                            assert!(
                                (numeric - exact).abs() <= 1e-2 * exact.max(ep.w2 * 1e-3),
                                "{name}: closed-form |w''| {exact} vs differences {numeric}"
                            );
                        }
                        let mut check = |what: &'static str, found: f64, bound: f64| {
                            assert!(
                                found <= bound * (1.0 + 1e-9),
                                "{name}, shift {shift}, scale {lambda}, radius {radius:.4e} (largest {:.4e}): \
                                 {what}: found {found} above the bound {bound}",
                                lo * unit
                            );
                            let r = worst.entry(what).or_insert(0.0);
                            *r = r.max(found / bound);
                            checked += 1;
                        };
                        let speed_a = climb(&|v, s| jets(v, s).0[1].norm(), radius, &mut rng);
                        check("‖A'‖", speed_a, lp.speed[0]);
                        let speed_b = climb(&|v, s| jets(v, s).1[1].norm(), radius, &mut rng);
                        check("‖B'‖", speed_b, lp.speed[1]);
                        let drift = climb(
                            &|v, s| {
                                if s <= 0.0 {
                                    return 0.0;
                                }
                                (jets(v, s).2[1] - jets(v, 0.0).2[1]).norm() / s
                            },
                            radius,
                            &mut rng,
                        );
                        check("‖m'(s) − m'(0)‖ / s", drift, lp.drift);
                        // drift is the sum of bounds on the drifts of the three parts of
                        // m' = (ω × y_A) × B + A × (ω × y_B) + (A − B) × τ (y = R_s X, so ω × y_A = A' − τ):
                        // α_ω ‖y_A‖ (‖B'‖ + α_ω ‖B‖), α_ω ‖y_B‖ (‖A'‖ + α_ω ‖A‖) and α_τ α_ω ‖B − A‖, with
                        // ‖A‖, ‖B‖ their largest over the ball (‖B(0)‖ + radius ‖B'‖).
                        // Each part's drift stays below drift less the other two.
                        let alpha_w = t.fixed_rows::<3>(0).into_owned().singular_values().max();
                        let alpha_t = t.fixed_rows::<3>(3).into_owned().singular_values().max();
                        let (a0, b0) = (pose.r * ends[0] + pose.t, pose.r * ends[1] + pose.t);
                        let pieces = [
                            alpha_w * ends[0].norm() * (lp.speed[1] + alpha_w * (b0.norm() + radius * lp.speed[1])),
                            alpha_w * ends[1].norm() * (lp.speed[0] + alpha_w * (a0.norm() + radius * lp.speed[0])),
                            alpha_t * alpha_w * (ends[1] - ends[0]).norm(),
                        ];
                        for (i, what) in [
                            "drift of (ω × y_A) × B",
                            "drift of A × (ω × y_B)",
                            "drift of (A − B) × τ",
                        ]
                        .into_iter()
                        .enumerate()
                        {
                            let part = |v: &Vector6<f64>, s: f64| {
                                let tau = (t * v).fixed_rows::<3>(3).into_owned();
                                let (ja, jb, _) = jets(v, s);
                                [
                                    (ja[1] - tau).cross(&jb[0]),
                                    ja[0].cross(&(jb[1] - tau)),
                                    (ja[0] - jb[0]).cross(&tau),
                                ][i]
                            };
                            let found = climb(
                                &|v, s| {
                                    if s > 0.0 {
                                        (part(v, s) - part(v, 0.0)).norm() / s
                                    } else {
                                        0.0
                                    }
                                },
                                radius,
                                &mut rng,
                            );
                            let others: f64 = (0..3).filter(|&j| j != i).map(|j| pieces[j]).sum();
                            // The subtraction rounds to ~1e-16 drift: 1e-12 drift of room.
                            check(what, found, lp.drift - others + 1e-12 * lp.drift);
                        }
                        check("‖m''‖", climb(&|v, s| jets(v, s).2[2].norm(), radius, &mut rng), lp.m2);
                        for (g, ep) in maps.iter().zip(&lp.endpoints) {
                            let q1 = climb(&|v, s| (g * jets(v, s).2[1].xy()).norm(), radius, &mut rng);
                            check("‖q'‖", q1, ep.q1);
                            check("|w''|", climb(&|v, s| w2_of(g, v, s), radius, &mut rng), ep.w2);
                            // Within w2 = q1² / w_lo + ‖G_e‖ m2: ‖q'‖² / w ≤ w2 − ‖G_e‖ m2 (the
                            // difference rounds to ~1e-16 w2, hence the absolute 1e-12 w2).
                            let q1_over_w = climb(
                                &|v, s| {
                                    let m = jets(v, s).2;
                                    (g * m[1].xy()).norm_squared() / (g * m[0].xy()).norm()
                                },
                                radius,
                                &mut rng,
                            );
                            let g_norm = g.singular_values().max();
                            check("‖q'‖² / w", q1_over_w, ep.w2 - g_norm * lp.m2 + 1e-12 * ep.w2);
                        }
                        // m''' less its two ends' third derivatives: 3 (A'' × B' + A' × B'').
                        let mixed = climb(
                            &|v, s| {
                                let (ja, jb, _) = jets(v, s);
                                (ja[2].cross(&jb[1]) + ja[1].cross(&jb[2])).norm() * 3.0
                            },
                            radius,
                            &mut rng,
                        );
                        check("‖3 (A'' × B' + A' × B'')‖", mixed, lp.mixed3);
                        for (e, ep) in seen.iter().zip(&lp.endpoints) {
                            let e_bar = k_inv * Vector3::new(e.x, e.y, 1.0);
                            let n3 = climb(&|v, s| e_bar.dot(&jets(v, s).2[3]).abs(), radius, &mut rng);
                            check("|n'''|", n3, ep.n3);
                            let ends3 = climb(
                                &|v, s| {
                                    let (ja, jb, _) = jets(v, s);
                                    e_bar.dot(&(ja[3].cross(&jb[0]) + ja[0].cross(&jb[3]))).abs()
                                },
                                radius,
                                &mut rng,
                            );
                            let rest = ep.leibniz - e_bar.norm() * lp.mixed3;
                            check("|ēᵀ (A''' × B + A × B''')|", ends3, rest + 1e-12 * ep.leibniz);
                            // About either end X: n = Dᵀ u, D = B − A, u = ē × X; each Leibniz term
                            // of n''' against its piece, u' against `speed`, n''' against the sum.
                            for (x, sight) in ep.sights.iter().enumerate() {
                                let terms = |v: &Vector6<f64>, s: f64| {
                                    let (ja, jb, _) = jets(v, s);
                                    let jx = [ja, jb][x];
                                    let d: [Vector3<f64>; 4] = std::array::from_fn(|k| jb[k] - ja[k]);
                                    let u: [Vector3<f64>; 4] = std::array::from_fn(|k| e_bar.cross(&jx[k]));
                                    [
                                        u[1].norm(),
                                        d[3].dot(&u[0]).abs(),
                                        3.0 * d[2].dot(&u[1]).abs(),
                                        3.0 * d[1].dot(&u[2]).abs(),
                                        d[0].dot(&u[3]).abs(),
                                    ]
                                };
                                let bounds = [
                                    sight.speed,
                                    sight.pieces[0],
                                    sight.pieces[1],
                                    sight.pieces[2],
                                    sight.pieces[3],
                                ];
                                for (i, what) in ["‖(ē × X)'‖", "|D'''ᵀ u|", "|3 D''ᵀ u'|", "|3 D'ᵀ u''|", "|Dᵀ u'''|"]
                                    .into_iter()
                                    .enumerate()
                                {
                                    check(what, climb(&|v, s| terms(v, s)[i], radius, &mut rng), bounds[i]);
                                }
                                check("|n'''| about an end", n3, sight.pieces.iter().sum());
                            }
                            assert!(ep.n3 <= ep.leibniz && ep.sights.iter().all(|p| ep.n3 <= p.pieces.iter().sum()));
                            let n2 = climb(&|v, s| e_bar.dot(&jets(v, s).2[2]).abs(), radius, &mut rng);
                            check("|n''|", n2, ep.n2);
                        }
                    }
                }
            }
        }
    }
    eprintln!("line terms: {checked} checks, the closest per term (found / bound): {worst:?}");
    assert!(checked > 300, "only {checked} checks");
}
