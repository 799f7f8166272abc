//! Step 2's minorant, its scale and the bounds it gives over a box of rotations
//! ([`super::super::minorant`]).

use super::*;

/// [`rotation_rest`] bounds what a rotation leaves beyond its first order, and is nearly reached:
/// for `y` across the axis the rest is `√((1 − cos θ)² + (θ − sin θ)²) ≈ θ²/2`.
#[test]
fn rotation_rest_bounds_the_second_order_of_a_rotation() {
    let mut rng = Rng::new(15);
    for theta in [1e-3, 0.01, 0.1, 0.3, 0.6] {
        let mut widest = 0.0f64;
        for _ in 0..200 {
            let axis = rng.unit_vector3();
            let y = rng.unit_vector3() * rng.uniform_in(0.5, 2.0);
            let phi = axis * theta * rng.uniform_in(0.5, 1.0);
            let rest = (exp_so3(&phi) * y - y - phi.cross(&y)).norm() / y.norm();
            assert!(rest <= rotation_rest(theta) * (1.0 + 1e-9), "θ = {theta}: {rest}");
            widest = widest.max(rest);
        }
        assert!(widest >= 0.75 * rotation_rest(theta), "θ = {theta}: at most {widest}");
    }
}

/// The linearised bound ([`ScaledMinorant::linear_bound`]) against the oracle: at rotations within the angle
/// `θ` of `r_c` (random ones inside the ball and on its sphere, then a descent from the least), half
/// the scaled minorant, summed point by point and minimised over `t` by its normal equations, is
/// never below it. Centres near the answer and away from it, `θ` from 1e-3 to 0.5, `κ` = 1 and
/// 2.5. The bound is not vacuous: it beats the Minkowski bound on most of these boxes.
#[test]
fn the_linearised_bound_holds_over_the_ball_of_rotations() {
    let mut rng = Rng::new(14);
    let (mut checked, mut better) = (0usize, 0usize);
    for (f, n, seed) in [(800.0, 10, 11), (15000.0, 10, 12), (250.0, 6, 13), (4000.0, 40, 14)] {
        let scene = visible_scene(f, n, 0, false, seed);
        let corr = scene.noisy(1.0, true, &mut rng);
        let truth = Pose::new(scene.rotation, scene.translation);
        let f_hat = 4.0 * ReprojectionCost::of(&scene.camera.intrinsics(), &corr).cost(&truth);
        let problem = Problem::new(&scene.camera.intrinsics(), &corr, f_hat).unwrap();
        let depths = problem.root().expect("depth bounds").depths.clone();
        for kappa in [1.0, 2.5] {
            let scaled = ScaledMinorant {
                minorant: Rc::clone(problem.root().expect("depth bounds")),
                scale: kappa,
            };
            for _ in 0..40 {
                let away = 0.3 * rng.uniform_in(0.0, 1.0).powi(2);
                let r_c = exp_so3(&(rng.unit_vector3() * away)) * truth.rotation;
                let theta = 1e-3 * 500f64.powf(rng.uniform_in(0.0, 1.0));
                let q_min = scaled.at(&r_c).unwrap().1;
                let bound = scaled.linear_bound(&r_c, theta, q_min, 0.0);
                let oracle =
                    |phi: &Vector3<f64>| bound_near_by_points(&problem, &depths, kappa, &(exp_so3(phi) * r_c), 0.0);
                let least = least_over_ball(&mut rng, theta, (60, 100), oracle);
                assert!(
                    bound <= least * (1.0 + 1e-9) + 1e-300,
                    "θ = {theta}: bound {bound} above {least}"
                );
                if bound > scaled.bound_near(&r_c, theta) {
                    better += 1;
                }
                checked += 1;
            }
        }
    }
    assert!(
        2 * better > checked,
        "better than the Minkowski bound on {better} of {checked}"
    );
}

/// The points' second-order rest ([`ScaledMinorant::second_order_rest`], the rest of both linearised bounds)
/// against the points one by one: at rotations `exp(φ) r` with `‖φ‖ = θ`, the whitened residuals'
/// distance from their part linear in `φ`, `√(Σ κ/Dᵢ² eᵢᵀ Hᵢ eᵢ)` with `eᵢ = (exp(φ) − I − [φ]ₓ) r Xᵢ`
/// (`Hᵢ` and `Dᵢ` from the points, [`forms_by_points`]), never exceeds it, and comes near it on some
/// rotation (a rest too small for `κ > 1` or for large `η` would show).
#[test]
fn the_points_second_order_rest_holds_over_the_ball() {
    let mut rng = Rng::new(41);
    let mut closest = 0.0f64;
    for (f, n, seed) in [(250.0, 6, 1), (800.0, 10, 2), (15000.0, 10, 3), (4000.0, 40, 4)] {
        let scene = visible_scene(f, n, 0, false, seed);
        let corr = scene.noisy(1.0, true, &mut rng);
        let truth = Pose::new(scene.rotation, scene.translation);
        let f_hat = ReprojectionCost::of(&scene.camera.intrinsics(), &corr).cost(&truth);
        let problem = Problem::new(&scene.camera.intrinsics(), &corr, f_hat).unwrap();
        let root = problem.root().expect("depth bounds");
        let forms = forms_by_points(&problem);
        for kappa in [1.0, 2.5] {
            let scaled = ScaledMinorant {
                minorant: Rc::clone(root),
                scale: kappa,
            };
            for _ in 0..100 {
                let r = exp_so3(&(rng.unit_vector3() * rng.uniform_in(0.0, 0.5))) * truth.rotation;
                let theta = 1e-3 * 1000f64.powf(rng.uniform_in(0.0, 1.0));
                let phi = rng.unit_vector3() * theta;
                let second = exp_so3(&phi) - Matrix3::identity() - skew(&phi);
                let rest2: f64 = (corr.points3d.iter().zip(&root.depths).zip(&forms))
                    .map(|((x, d), (h, _))| {
                        let e = second * (r * x);
                        kappa / (d * d) * e.dot(&(h * e))
                    })
                    .sum();
                let ratio = rest2.sqrt() / scaled.second_order_rest(theta);
                assert!(
                    ratio <= 1.0 + 1e-9,
                    "f = {f}, κ = {kappa}, θ = {theta}: the points' rest reaches {ratio} of its bound"
                );
                closest = closest.max(ratio);
            }
        }
    }
    assert!(closest > 0.5, "the points' rest reaches at most {closest} of its bound");
}

/// The minorant's form (`at`, `C`, `C⁻¹`, `bᵢᵀ C⁻¹ bᵢ`, `λ_max(C⁻¹)`) agrees with the per-point sum
/// at random poses; and what a box hands down ([`ScaledMinorant::tightened`]: a scale, or a rebuild) is,
/// at every pose, at most the minorant of the tighter depth bounds it was given, and claims depth
/// bounds no tighter than those; a rebuilt minorant is handed down only where it bounds at least
/// as well as the scale (point by point). Cases: uneven shrinking, even shrinking (a scale
/// `κ > 1`), one bound that does not shrink (`κ = 1`), and shrinking by a hair.
#[test]
fn minorant_and_its_scale_against_the_per_point_sum() {
    let mut rng = Rng::new(11);
    let (mut rebuilt, mut scaled_up) = (0, 0);
    let mut choices = [0usize; 2];
    for (f, n, seed) in [(250.0, 6, 1), (800.0, 10, 2), (15000.0, 10, 3), (4000.0, 40, 4)] {
        let scene = visible_scene(f, n, 0, false, seed);
        let corr = scene.noisy(1.0, true, &mut rng);
        let truth = Pose::new(scene.rotation, scene.translation);
        let f_hat = ReprojectionCost::of(&scene.camera.intrinsics(), &corr).cost(&truth);
        let problem = Problem::new(&scene.camera.intrinsics(), &corr, f_hat).unwrap();
        let root = ScaledMinorant {
            minorant: Rc::clone(problem.root().expect("depth bounds")),
            scale: 1.0,
        };
        let depths = problem.root().expect("depth bounds").depths.clone();
        let random_pose = |rng: &mut Rng| {
            let r = exp_so3(&(rng.unit_vector3() * rng.uniform_in(0.0, 0.5))) * truth.rotation;
            (
                r,
                truth.translation + rng.unit_vector3() * rng.uniform_in(0.0, 2.0) * truth.translation.norm(),
            )
        };
        // The form against the sum.
        let m = problem.root().expect("depth bounds");
        let c_inv = m.c_inv.unwrap();
        assert!((m.c * c_inv - Matrix3::identity()).norm() < 1e-9);
        let c_inv_max = c_inv.symmetric_eigenvalues().max();
        assert!(m.c_inv_max >= c_inv_max && m.c_inv_max <= c_inv_max * (1.0 + 1e-7));
        for (b, spread) in problem.bearings.iter().zip(&m.bearing_spread) {
            assert!((b.dot(&(c_inv * b)) - spread).abs() <= 1e-12 * spread.abs().max(1e-300));
        }
        for _ in 0..50 {
            let (r, t) = random_pose(&mut rng);
            let (g, c0) = m.at(&r);
            let form = t.dot(&(m.c * t)) + 2.0 * g.dot(&t) + c0;
            let sum = minorant_by_points(&problem, &depths, &r, &t);
            assert!((form - sum).abs() <= 1e-9 * sum.max(1e-300), "{form} vs {sum}");
        }
        // What a box hands down, for four kinds of tighter depth bounds.
        // Uneven, even, all but one, by a hair, one by far.
        let shrink = |case: usize, i: usize, rng: &mut Rng| match case {
            0 => rng.uniform_in(0.3, 1.0),
            1 => 0.7,
            2 if i == 0 => 1.0,
            2 => 0.5,
            3 => 1.0 - 1e-9,
            _ if i == 0 => 0.05,
            _ => 1.0,
        };
        // Cases 2 and 4 ten times each, at ten boxes: the choice of the rebuilt minorant.
        let repeats = |case: usize| if case == 2 || case == 4 { 10 } else { 1 };
        for case in (0..5).flat_map(|case| std::iter::repeat_n(case, repeats(case))) {
            let reach: Vec<f64> = depths
                .iter()
                .enumerate()
                .map(|(i, d)| d * shrink(case, i, &mut rng))
                .collect();
            // A box of the search: its centre rotation some angle away from the truth, its
            // half-diagonal a fraction of that angle (where the bounds are not all 0).
            let angle = rng.uniform_in(0.01, 0.5);
            let r_c = exp_so3(&(rng.unit_vector3() * angle)) * truth.rotation;
            let theta = angle * rng.uniform_in(0.01, 0.3);
            let handed = root.tightened(|depths| problem.minorant(depths), reach.iter().copied(), &r_c, theta);
            let is_rebuilt = !Rc::ptr_eq(&handed.minorant, problem.root().expect("depth bounds"));
            match case {
                // Even shrinking is a scale, `1 / 0.7²`.
                1 => assert!(
                    !is_rebuilt && (handed.scale * 0.49 - 1.0).abs() < 1e-12,
                    "{}",
                    handed.scale
                ),
                // One bound that stays, with the others halved (or one cut to a twentieth),
                // raises the weights on average far more than the least: rebuilt, unless the
                // scale `κ = 1` bounds better.
                2 | 4 => {
                    let kept = bound_near_by_points(&problem, &depths, 1.0, &r_c, theta);
                    let rebuilt = bound_near_by_points(&problem, &reach, 1.0, &r_c, theta);
                    let tolerance = 1e-9 * kept.max(rebuilt);
                    if rebuilt > kept + tolerance {
                        assert!(is_rebuilt && handed.scale == 1.0, "{rebuilt} > {kept}, not rebuilt");
                        choices[0] += 1;
                    } else if kept > rebuilt + tolerance {
                        assert!(!is_rebuilt && handed.scale == 1.0, "{kept} > {rebuilt}, rebuilt");
                        choices[1] += 1;
                    }
                }
                _ => {}
            }
            if handed.scale == 1.0 && !Rc::ptr_eq(&handed.minorant, problem.root().expect("depth bounds")) {
                rebuilt += 1;
            } else if handed.scale > 1.0 {
                scaled_up += 1;
            }
            for (claimed, r) in handed.depths().zip(&reach) {
                assert!(
                    claimed >= r * (1.0 - 1e-12),
                    "claimed depth {claimed} below the reach {r}"
                );
            }
            for _ in 0..50 {
                let (r, t) = random_pose(&mut rng);
                let (g, c0) = handed.minorant.at(&r);
                let form = handed.scale * (t.dot(&(handed.minorant.c * t)) + 2.0 * g.dot(&t) + c0);
                let tighter = minorant_by_points(&problem, &reach, &r, &t);
                assert!(form <= tighter * (1.0 + 1e-9) + 1e-300, "{form} > {tighter}");
            }
        }
    }
    // Every branch of `tightened` was taken, and both choices of case 2 met.
    assert!(rebuilt > 0 && scaled_up > 0, "{rebuilt} rebuilt, {scaled_up} scaled");
    assert!(choices[0] > 0 && choices[1] > 0, "rebuilt / kept chosen {choices:?}");
}
