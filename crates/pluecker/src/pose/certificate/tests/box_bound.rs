//! The bounds of a box with the segments' terms, and without depth bounds
//! ([`super::super::box_bound`]).

use super::*;

/// The bounds of a box without depth bounds ([`Problem::ball_bound`]: the minorant's growth
/// against the drift, and the linearised minorant, both computed here at every box) against the
/// least reprojection cost over the box, rotations `exp(φ) r_c` (`‖φ‖ ≤ θ`) and translations in
/// the ellipsoid `{centre + L z : ‖z‖ ≤ 1}` with every point and segment endpoint in front, found by
/// sampling then a hill climb on the test's own cost (pixels projected here, an endpoint's residual
/// its pixel distance to the line through the two projected endpoints). Boxes from 1e-3 to 0.5 rad,
/// near the answer and far from it; round and elongated translation sets holding the true
/// translation or not. Neither bound may exceed the least cost found; each must be useful (above
/// half of it) on some boxes, or the test could not fail.
#[test]
fn the_bounds_without_depth_bounds_hold_over_the_box() {
    use nalgebra::Vector2;
    let mut rng = Rng::new(31);
    let (mut checked, mut useful, mut close_to_minorant) = (0usize, [0usize; 2], 0usize);
    for (f, np, nl, seed) in [
        (800.0, 0, 8, 31),
        (250.0, 0, 6, 32),
        (4000.0, 0, 10, 33),
        (800.0, 1, 5, 34),
    ] {
        let scene = visible_scene(f, np, nl, false, seed);
        let corr = scene.noisy(1.0, true, &mut rng);
        let truth = Pose::new(scene.rotation, scene.translation);
        let f_hat = 4.0 * ReprojectionCost::of(&scene.camera.intrinsics(), &corr).cost(&truth);
        let problem = Problem::new(&scene.camera.intrinsics(), &corr, f_hat).unwrap();
        assert!(problem.root().is_none(), "f = {f}: the search starts from depth bounds");
        let k = scene.camera.intrinsics().matrix();
        let pixel = |x: &Vector3<f64>| {
            let p = k * x;
            Vector2::new(p.x / p.z, p.y / p.z)
        };
        // ½ Σ r², +∞ with a point or endpoint behind the camera.
        let cost = |rotation: &Matrix3<f64>, t: &Vector3<f64>| -> f64 {
            let mut sum = 0.0;
            for (x, u) in corr.points3d.iter().zip(&corr.points2d) {
                let y = rotation * x + t;
                if y.z <= 0.0 {
                    return f64::INFINITY;
                }
                sum += (pixel(&y) - u).norm_squared();
            }
            for (segment, seen) in corr.lines3d.iter().zip(&corr.lines2d) {
                let [a, b] = segment.map(|x| rotation * x + t);
                if a.z <= 0.0 || b.z <= 0.0 {
                    return f64::INFINITY;
                }
                let (pa, pb) = (pixel(&a), pixel(&b));
                let dir = (pb - pa).normalize();
                let normal = Vector2::new(-dir.y, dir.x);
                sum += seen.iter().map(|e| normal.dot(&(e - pa)).powi(2)).sum::<f64>();
            }
            0.5 * sum
        };
        for case in 0..32 {
            // Half the boxes small and near the truth, where the bounds are tight.
            let near = case % 2 == 0;
            let away = if near { 0.02 } else { 0.6 } * rng.uniform_in(0.0, 1.0).powi(2);
            let r_c = exp_so3(&(rng.unit_vector3() * away)) * truth.rotation;
            let (least, span) = if near { (1e-4, 100.0f64) } else { (1e-3, 500.0) };
            let theta = least * span.powf(rng.uniform_in(0.0, 1.0));
            // The translation set: round or elongated along a random axis, its centre near the
            // truth (the truth inside it or not).
            let radius =
                scene.translation.norm() * 0.5f64.powf(rng.uniform_in(0.0, 6.0) + if near { 4.0 } else { 0.0 });
            let (ball, l) = translation_set(&scene.translation, radius, 1.5, &mut rng);
            let TranslationEllipsoid { centre, shape, .. } = ball;
            let Some(bounds) = problem.ball_bound(problem.lines.len(), &r_c, theta, &ball, f64::INFINITY) else {
                continue;
            };
            let at = |(phi, z): &(Vector3<f64>, Vector3<f64>)| cost(&(exp_so3(phi) * r_c), &(centre + l * z));
            let clamp = |v: Vector3<f64>, r: f64| v * (r / v.norm()).min(1.0);
            let mut best = (Vector3::zeros(), Vector3::zeros());
            let mut best_value = at(&best);
            for step in 0..400 {
                let candidate = if step < 150 {
                    (
                        rng.unit_vector3() * theta * rng.uniform().cbrt(),
                        rng.unit_vector3() * rng.uniform().cbrt(),
                    )
                } else {
                    let shrink = 0.98f64.powi(step - 150);
                    (
                        clamp(best.0 + rng.unit_vector3() * theta * 0.3 * shrink, theta),
                        clamp(best.1 + rng.unit_vector3() * 0.3 * shrink, 1.0),
                    )
                };
                let value = at(&candidate);
                if value < best_value {
                    (best, best_value) = (candidate, value);
                }
            }
            if !best_value.is_finite() {
                continue;
            }
            for (which, bound) in [bounds.by_growth, bounds.by_linear].into_iter().enumerate() {
                assert!(
                    bound <= best_value * (1.0 + 1e-9),
                    "f = {f}, θ = {theta}, {away:.3} rad from the truth: bound {which} = {bound} above the cost \
                     {best_value} of a pose of the box"
                );
                if bound > 0.5 * best_value {
                    useful[which] += 1;
                }
            }
            // The linearised bound against the minorant it bounds, closer to it than the cost
            // is: ½ Σ (weighted numerators and point terms)² at each rotation of the box, its
            // translation solved exactly (least squares), least over the rotations by sampling
            // then a hill climb. The weights are the box's (from its ellipsoid), the numerators
            // recomputed here: n = ēᵀ ((R a + t) × (R b + t)) = ēᵀ (R a × R b) + tᵀ ((R b − R a) × ē).
            let terms: Vec<LineTerm> = problem.line_terms(
                problem.lines.len(),
                (&r_c, theta),
                TranslationSet {
                    t_star: &centre,
                    spread: radius,
                    shape: Some(&shape),
                },
            );
            let depths = bounds.depths.clone();
            let minorant = |phi: &Vector3<f64>| -> f64 {
                let rotation = exp_so3(phi) * r_c;
                let (mut c, mut g, mut c0) = (Matrix3::zeros(), Vector3::zeros(), 0.0);
                for (index, term) in terms.iter().enumerate() {
                    let line = &problem.lines[index / 2];
                    let e = line.ends[index % 2].0;
                    let (ra, rb) = (rotation * line.a, rotation * line.b);
                    let (alpha, beta) = (e.dot(&ra.cross(&rb)), (rb - ra).cross(&e));
                    c += beta * beta.transpose() * term.weight;
                    g += beta * alpha * term.weight;
                    c0 += alpha * alpha * term.weight;
                }
                for ((x, form), depth) in corr.points3d.iter().zip(&problem.forms).zip(&depths) {
                    let (y, w) = (rotation * x, 1.0 / (depth * depth));
                    c += form.h * w;
                    g += form.h * y * w;
                    c0 += y.dot(&(form.h * y)) * w;
                }
                let t = -(c.lu().solve(&g).unwrap());
                0.5 * (c0 + g.dot(&t)).max(0.0)
            };
            let mut least = (Vector3::zeros(), minorant(&Vector3::zeros()));
            for step in 0..300 {
                let phi = if step < 100 {
                    rng.unit_vector3() * theta * rng.uniform().cbrt()
                } else {
                    clamp(
                        least.0 + rng.unit_vector3() * theta * 0.3 * 0.98f64.powi(step - 100),
                        theta,
                    )
                };
                let value = minorant(&phi);
                if value < least.1 {
                    least = (phi, value);
                }
            }
            // Rounding of c₀ − gᵀ C⁻¹ g: a relative ~1e-12 here.
            assert!(
                bounds.by_linear <= least.1 * (1.0 + 1e-9) + 1e-12,
                "f = {f}, θ = {theta}: the linearised bound {} above the minorant's least {}",
                bounds.by_linear,
                least.1
            );
            if bounds.by_linear > 0.7 * least.1 {
                close_to_minorant += 1;
            }
            checked += 1;
        }
    }
    assert!(checked >= 60, "only {checked} boxes checked");
    assert!(
        useful.iter().all(|&u| u >= 5) && close_to_minorant >= 10,
        "bounds above half the least cost on only {useful:?} of {checked} boxes, the linearised one above \
         0.7 of the minorant's least on {close_to_minorant}"
    );
}

/// The algebra of the bounds without depth bounds, on the parts [`Problem::ball_bound`] returns,
/// each against a minimum found here by sampling then a hill climb (boxes of 0.01-0.5 rad where the
/// second-order terms count, translation sets round or thin):
/// - a segment endpoint's linear part: `|n(exp(φ) r, t* + Δ) − (n* + βᵀ Δ + γᵀ φ)| ≤
///   θ ‖d‖ ‖ē × Δ‖ + ρ a` (`n` from the camera-frame endpoints);
/// - the linearised bound is at most `½ (min √L(φ, Δ) − θ √(Δᵀ N Δ) − ρ η₀)₊²` over `‖φ‖ ≤ θ` and
///   every `Δ`, `L` the weighted sum of squares of the linear parts;
/// - the growth bound is at most `½ (min √(q_min + Δᵀ C Δ) − spin − θ √(Δᵀ N Δ))₊²` over the
///   translations of the set (its algebra loses more than the linearised one's: above 0.4 of the
///   minimum counts as close);
/// - the ellipsoid holds every translation of the set where `√(q_min + Δᵀ C Δ) − θ √(Δᵀ N Δ)` is at
///   most `√(2f̂) + spin`.
#[test]
fn the_algebra_of_the_bounds_without_depth_bounds_holds() {
    let mut rng = Rng::new(35);
    let (mut boxes, mut tight) = (0usize, [0usize; 4]);
    for (f, np, nl, seed) in [(800.0, 0, 6, 51), (250.0, 1, 5, 52), (4000.0, 0, 8, 53)] {
        let scene = visible_scene(f, np, nl, false, seed);
        let corr = scene.noisy(1.0, true, &mut rng);
        let truth = Pose::new(scene.rotation, scene.translation);
        let f_hat = 4.0 * ReprojectionCost::of(&scene.camera.intrinsics(), &corr).cost(&truth);
        let problem = Problem::new(&scene.camera.intrinsics(), &corr, f_hat).unwrap();
        for _ in 0..24 {
            let theta = 0.005 * 40f64.powf(rng.uniform_in(0.0, 1.0));
            let r_c = exp_so3(&(rng.unit_vector3() * theta * rng.uniform_in(2.0, 8.0))) * truth.rotation;
            let radius = scene.translation.norm() * 0.5f64.powf(rng.uniform_in(2.0, 6.0));
            let (ball, l) = translation_set(&scene.translation, radius, 1.0, &mut rng);
            let TranslationEllipsoid { centre, shape, .. } = ball;
            let segments = problem.lines.len();
            let (Some(open), Some(level)) = (
                problem.ball_bound(segments, &r_c, theta, &ball, f64::INFINITY),
                problem.ball_bound(segments, &r_c, theta, &ball, f_hat),
            ) else {
                continue;
            };
            let g = &open.parts;
            let (t_star, rho) = (open.t_star, rotation_rest(theta));
            let terms: Vec<LineTerm> = problem.line_terms(
                segments,
                (&r_c, theta),
                TranslationSet {
                    t_star: &centre,
                    spread: radius,
                    shape: Some(&shape),
                },
            );
            let x_of = |d: &Vector3<f64>| d.dot(&(g.n * d)).max(0.0).sqrt();
            let q_of = |d: &Vector3<f64>| (g.q_min + d.dot(&(open.c * d))).sqrt();
            let clamp = |v: Vector3<f64>, r: f64| v * (r / v.norm()).min(1.0);
            // A hill climb over (φ, z), z the set's coordinate (Δ = centre + L z − t*), on `value`,
            // least first; `free` lets z leave the set (30 times its size).
            let mut climb = |value: &dyn Fn(&Vector3<f64>, &Vector3<f64>) -> f64, free: bool| {
                let reach = if free { 30.0 } else { 1.0 };
                let mut best = (Vector3::zeros(), l.solve_lower_triangular(&(t_star - centre)).unwrap());
                best.1 = clamp(best.1, reach);
                let mut best_value = value(&best.0, &best.1);
                for step in 0..600 {
                    let candidate = if step < 200 {
                        (
                            rng.unit_vector3() * theta * rng.uniform().cbrt(),
                            rng.unit_vector3() * reach * rng.uniform().cbrt(),
                        )
                    } else {
                        let shrink = 0.985f64.powi(step - 200);
                        (
                            clamp(best.0 + rng.unit_vector3() * theta * 0.3 * shrink, theta),
                            clamp(best.1 + rng.unit_vector3() * reach * 0.3 * shrink, reach),
                        )
                    };
                    let v = value(&candidate.0, &candidate.1);
                    if v < best_value {
                        (best, best_value) = (candidate, v);
                    }
                }
                best_value
            };
            let delta = |z: &Vector3<f64>| centre + l * z - t_star;
            // The linear parts and their rests.
            for (index, term) in terms.iter().enumerate() {
                let line = &problem.lines[index / 2];
                let e = line.ends[index % 2].0;
                let gamma = term.gamma(&t_star);
                let a = term.moment_part + term.d_norm * e.cross(&t_star).norm();
                let ratio = |phi: &Vector3<f64>, z: &Vector3<f64>| {
                    let d = delta(z);
                    let (rotation, t) = (exp_so3(phi) * r_c, t_star + d);
                    let n = e.dot(&(rotation * line.a + t).cross(&(rotation * line.b + t)));
                    let linear = term.alpha + term.beta.dot(&t) + gamma.dot(phi);
                    -((n - linear).abs() / (theta * term.d_norm * e.cross(&d).norm() + rho * a))
                };
                let worst = -climb(&ratio, true);
                assert!(
                    worst <= 1.0 + 1e-9,
                    "θ = {theta}: endpoint {index}'s linear part is off {worst}x its rest"
                );
                if worst > 0.5 {
                    tight[0] += 1;
                }
            }
            // The linearised bound's assembly.
            let linearised = |phi: &Vector3<f64>, z: &Vector3<f64>| {
                let d = delta(z);
                let mut sum = 0.0;
                for term in &terms {
                    let value = term.alpha + term.beta.dot(&(t_star + d)) + term.gamma(&t_star).dot(phi);
                    sum += term.weight * value * value;
                }
                for ((x, form), depth) in corr.points3d.iter().zip(&problem.forms).zip(&open.depths) {
                    let y = r_c * x;
                    let p = y + t_star + d - y.cross(phi);
                    sum += p.dot(&(form.h * p)) / (depth * depth);
                }
                sum.sqrt() - theta * x_of(&d) - rho * g.eta0
            };
            // A bound against ½ (least)₊² of its assembly over the set; how close it comes.
            let reaches = |bound: f64, least: f64| {
                let allowed = 0.5 * least.max(0.0).powi(2);
                assert!(
                    bound <= allowed * (1.0 + 1e-9) + 1e-12,
                    "θ = {theta}: {bound} > {allowed}"
                );
                if allowed > 0.0 {
                    bound / allowed
                } else {
                    0.0
                }
            };
            if reaches(open.by_linear, climb(&linearised, true)) > 0.8 {
                tight[1] += 1;
            }
            // The growth bound's assembly, over the set.
            let growth = |_: &Vector3<f64>, z: &Vector3<f64>| {
                let d = delta(z);
                q_of(&d) - g.spin - theta * x_of(&d)
            };
            if reaches(open.by_growth, climb(&growth, false)) > 0.4 {
                tight[2] += 1;
            }
            // The ellipsoid: the largest Δᵀ C Δ / slack where the growth allows a pose of S.
            let beta = (2.0 * f_hat).sqrt() + level.parts.spin;
            let inside = |_: &Vector3<f64>, z: &Vector3<f64>| {
                let d = delta(z);
                if q_of(&d) - theta * x_of(&d) <= beta {
                    -d.dot(&(level.c * d)) / level.slack
                } else {
                    0.0
                }
            };
            let widest = -climb(&inside, false);
            assert!(
                widest <= 1.0 + 1e-9,
                "θ = {theta}: the ellipsoid misses a translation ({widest}x its slack)"
            );
            if widest > 0.5 {
                tight[3] += 1;
            }
            boxes += 1;
        }
    }
    assert!(boxes >= 30, "only {boxes} boxes");
    assert!(
        tight.iter().all(|&t| t >= 3),
        "claims close to their bound: {tight:?} ({boxes} boxes)"
    );
}

/// Two claims of the bound without depth bounds, each against an oracle of its own. A segment
/// endpoint's drift ([`LineTerm::spin`]): `|n(exp(φ) r, t) − n(r, t)| ≤ spin + θ ‖d‖ ‖ē × Δ‖`
/// with `n = ēᵀ (A × B)` from the camera-frame endpoints, maximised over `‖φ‖ ≤ θ` and `Δ` by
/// sampling then a hill climb, θ up to 1 rad (where the second-order rest `ρ` matters); and
/// [`relative_floor`]'s `Δᵀ C Δ ≥ μ Δᵀ N Δ` at random and adversarial `Δ` for random forms.
#[test]
fn the_drift_and_the_relative_floor_hold() {
    let mut rng = Rng::new(33);
    let (mut checked, mut closest) = (0usize, 0.0f64);
    for (f, nl, seed) in [(800.0, 6, 41), (250.0, 5, 42), (4000.0, 6, 43)] {
        let scene = visible_scene(f, 0, nl, false, seed);
        let corr = scene.noisy(1.0, true, &mut rng);
        let truth = Pose::new(scene.rotation, scene.translation);
        let f_hat = 4.0 * ReprojectionCost::of(&scene.camera.intrinsics(), &corr).cost(&truth);
        let problem = Problem::new(&scene.camera.intrinsics(), &corr, f_hat).unwrap();
        for _ in 0..10 {
            let r_c = exp_so3(&(rng.unit_vector3() * rng.uniform_in(0.0, 0.5))) * truth.rotation;
            let theta = 1e-2 * 100f64.powf(rng.uniform_in(0.0, 1.0));
            let t_star = scene.translation + rng.unit_vector3() * rng.uniform_in(0.0, 1.0);
            let spread = rng.uniform_in(0.0, 1.0);
            let terms: Vec<LineTerm> = problem.line_terms(
                problem.lines.len(),
                (&r_c, theta),
                TranslationSet {
                    t_star: &t_star,
                    spread,
                    shape: None,
                },
            );
            for (index, term) in terms.iter().enumerate() {
                let line = &problem.lines[index / 2];
                let e = line.ends[index % 2].0;
                let n = |rotation: &Matrix3<f64>, t: &Vector3<f64>| {
                    e.dot(&(rotation * line.a + t).cross(&(rotation * line.b + t)))
                };
                let (_, spin, step) = term.spin(theta, &t_star);
                let ratio = |(phi, delta): &(Vector3<f64>, Vector3<f64>)| {
                    let t = t_star + delta;
                    let moved = (n(&(exp_so3(phi) * r_c), &t) - n(&r_c, &t)).abs();
                    let allowed = spin + step * term.d_norm * e.cross(delta).norm();
                    moved / allowed
                };
                let clamp = |v: Vector3<f64>, r: f64| v * (r / v.norm()).min(1.0);
                let mut best = (rng.unit_vector3() * theta, Vector3::zeros());
                let mut best_value = ratio(&best);
                for step in 0..300 {
                    let candidate = if step < 100 {
                        (rng.unit_vector3() * theta, rng.unit_vector3() * spread * rng.uniform())
                    } else {
                        let shrink = 0.98f64.powi(step - 100);
                        (
                            clamp(best.0 + rng.unit_vector3() * theta * 0.3 * shrink, theta),
                            clamp(best.1 + rng.unit_vector3() * spread * 0.3 * shrink, spread),
                        )
                    };
                    let value = ratio(&candidate);
                    if value > best_value {
                        (best, best_value) = (candidate, value);
                    }
                }
                // Rounding: n is a sum of products of the scene's size, exact to ~1e-15 of them.
                assert!(
                    best_value <= 1.0 + 1e-9,
                    "f = {f}, θ = {theta}: endpoint {index} drifts {best_value}x"
                );
                closest = closest.max(best_value);
                checked += 1;
            }
        }
    }
    assert!(
        checked >= 300 && closest > 0.9,
        "{checked} endpoints, closest {closest}"
    );
    // The relative floor: random forms, Δ at random and by a hill climb on the ratio.
    for _ in 0..200 {
        let random_form = |rng: &mut Rng| {
            let a = Matrix3::from_fn(|_, _| rng.normal());
            a * a.transpose() + Matrix3::identity() * 1e-3
        };
        let (c, n) = (random_form(&mut rng), random_form(&mut rng));
        let (mu, n_max) = relative_floor(&c.try_inverse().unwrap(), &n);
        let ratio = |d: &Vector3<f64>| d.dot(&(c * d)) / d.dot(&(n * d));
        let mut best = rng.unit_vector3();
        for step in 0..400 {
            let candidate = if step < 100 {
                rng.unit_vector3()
            } else {
                (best + rng.unit_vector3() * 0.3 * 0.98f64.powi(step - 100)).normalize()
            };
            if ratio(&candidate) < ratio(&best) {
                best = candidate;
            }
        }
        assert!(ratio(&best) >= mu * (1.0 - 1e-9), "{} < μ = {mu}", ratio(&best));
        assert!(
            ratio(&best) <= mu * 1.01,
            "μ = {mu} far below the least ratio {}",
            ratio(&best)
        );
        assert!(n_max >= best.dot(&(n * best)) * (1.0 - 1e-12));
    }
}

/// The segments' terms of the box bound ([`Problem::line_terms`]), each claim against an oracle
/// of its own at poses of the box (rotations `exp(φ) r_c`, `‖φ‖ ≤ θ`; translations within
/// `spread` of `t*`), found by random sampling then a hill climb towards where each claim is
/// closest to failing: `w ≤ W` (`w = ‖G_e m_xy‖`, `G_e = C^½ G` from the covariance's own
/// eigen-decomposition, `m = A × B` of the camera-frame endpoints), `|n − n_c| ≤ θ drift`
/// (`n = ēᵀ m`, `n_c = α + βᵀ t` its linear form at `r_c`, which must equal `n` there), and
/// `|n| / w` equal to the residual the oracle projects (the pixel distance of the endpoint to the
/// image of the segment's line, in standard deviations). Then the assembly: `lines_bound` at
/// `θ = 0` is half the minimum over `t` of `κ Q + Σ weight (α + βᵀ t)²`, solved here from the
/// per-point forms ([`forms_by_points`]), and at `θ > 0` the Minkowski bound with
/// `η_total² = κ η² + Σ weight drift²`. Scenes with few points and several segments, with and
/// without covariances, f from 250 to 15000 px.
#[test]
fn the_segments_terms_of_the_box_bound_hold_over_the_box() {
    use crate::synthetic::random_observation_noise;
    use nalgebra::Vector2;
    let mut rng = Rng::new(16);
    let (mut checked, mut closest, mut ellipsoids) = (0usize, [0.0f64; 2], 0usize);
    for (f, np, nl, seed, with_covariances) in [
        (800.0, 3, 3, 21, false),
        (250.0, 3, 4, 22, true),
        (4000.0, 4, 4, 23, false),
        (15000.0, 3, 5, 24, true),
    ] {
        let scene = visible_scene(f, np, nl, false, seed);
        let mut corr = scene.noisy(1.0, true, &mut rng);
        if with_covariances {
            corr.noise = Some(random_observation_noise(&mut rng, np, nl, (0.3, 3.0)));
        }
        let truth = Pose::new(scene.rotation, scene.translation);
        let f_hat = 4.0 * ReprojectionCost::of(&scene.camera.intrinsics(), &corr).cost(&truth);
        let problem = Problem::new(&scene.camera.intrinsics(), &corr, f_hat).unwrap();
        let k = scene.camera.intrinsics().matrix();
        let k_inv = k.try_inverse().unwrap();
        let g = k_inv.transpose().fixed_view::<2, 2>(0, 0).into_owned();
        let map = |line: usize, end: usize| match &corr.noise {
            None => g,
            Some(noise) => {
                let eigen = noise.lines[line][end].symmetric_eigen();
                eigen.eigenvectors
                    * Matrix2::from_diagonal(&eigen.eigenvalues.map(f64::sqrt))
                    * eigen.eigenvectors.transpose()
                    * g
            }
        };
        // The oracle's residual: the pixel distance of the endpoint to the line through the two
        // projected endpoints, over its standard deviation across the line.
        let pixel = |x: &Vector3<f64>| {
            let p = k * x;
            Vector2::new(p.x / p.z, p.y / p.z)
        };
        let residual = |line: usize, end: usize, a: &Vector3<f64>, b: &Vector3<f64>| {
            let (pa, pb) = (pixel(a), pixel(b));
            let dir = (pb - pa).normalize();
            let normal = Vector2::new(-dir.y, dir.x);
            let e = corr.lines2d[line][end];
            let sigma = corr
                .noise
                .as_ref()
                .map_or(1.0, |n| normal.dot(&(n.lines[line][end] * normal)).sqrt());
            normal.dot(&(e - pa)).abs() / sigma
        };
        let forms = forms_by_points(&problem);
        let segments = longest_segments(&corr, BOX_BOUND_SEGMENTS);
        for kappa in [1.0, 2.0] {
            let scaled = ScaledMinorant {
                minorant: Rc::clone(problem.root().expect("depth bounds")),
                scale: kappa,
            };
            for _ in 0..12 {
                let r_c = exp_so3(&(rng.unit_vector3() * 0.2 * rng.uniform_in(0.0, 1.0).powi(2))) * truth.rotation;
                let theta = 1e-3 * 300f64.powf(rng.uniform_in(0.0, 1.0));
                let (t_star, q_min, eta) = scaled.at(&r_c).unwrap();
                let slack = (((2.0 * f_hat).sqrt() + theta * eta).powi(2) - q_min).max(0.0);
                let spread = (slack / kappa * problem.root().expect("depth bounds").c_inv_max).sqrt();
                let terms: Vec<LineTerm> = problem.line_terms(
                    problem.box_segments,
                    (&r_c, theta),
                    TranslationSet {
                        t_star: &t_star,
                        spread,
                        shape: None,
                    },
                );
                // Per endpoint: w √weight and |n − n_c| / (θ drift), each at most 1.
                let ratios = |phi: &Vector3<f64>, u: &Vector3<f64>, index: usize| -> [f64; 2] {
                    let (line, end) = (segments[index / 2], index % 2);
                    let (rotation, t) = (exp_so3(phi) * r_c, t_star + u);
                    let [a, b] = corr.lines3d[line].map(|x| rotation * x + t);
                    let m = a.cross(&b);
                    let e = k_inv * Vector3::new(corr.lines2d[line][end].x, corr.lines2d[line][end].y, 1.0);
                    let (n, w) = (e.dot(&m), (map(line, end) * m.xy()).norm());
                    let term = &terms[index];
                    let linear = term.alpha + term.beta.dot(&t);
                    if phi.norm() == 0.0 {
                        let scale = term.alpha.abs() + term.beta.norm() * t.norm();
                        assert!(
                            (n - linear).abs() <= 1e-9 * scale,
                            "n {n} against its linear form {linear}"
                        );
                    }
                    let projected = residual(line, end, &a, &b);
                    // Both round to ~1e-16 of the sizes they cancel: ‖ē‖ ‖m‖ / w and the pixels.
                    let sizes = e.norm() * m.norm() / w + corr.lines2d[line][end].norm();
                    assert!(
                        (n.abs() / w - projected).abs() <= 1e-9 * projected + 1e-12 * sizes,
                        "|n| / w = {} against the projected residual {projected}",
                        n.abs() / w
                    );
                    [w * term.weight.sqrt(), (n - linear).abs() / (theta * term.drift)]
                };
                for index in 0..terms.len() {
                    ratios(&Vector3::zeros(), &Vector3::zeros(), index);
                    for (claim, closest) in closest.iter_mut().enumerate() {
                        let value = |x: &(Vector3<f64>, Vector3<f64>)| ratios(&x.0, &x.1, index)[claim];
                        let mut best = (Vector3::zeros(), Vector3::zeros());
                        let mut best_value = value(&best);
                        for step in 0..200 {
                            let candidate = if step < 40 {
                                (rng.unit_vector3() * theta, rng.unit_vector3() * spread)
                            } else {
                                let shrink = 0.97f64.powi(step - 40);
                                let phi = best.0 + rng.unit_vector3() * theta * 0.3 * shrink;
                                let u = best.1 + rng.unit_vector3() * spread * 0.3 * shrink;
                                (phi * (theta / phi.norm()).min(1.0), u * (spread / u.norm()).min(1.0))
                            };
                            let v = value(&candidate);
                            if v > best_value {
                                (best, best_value) = (candidate, v);
                            }
                        }
                        assert!(
                            best_value <= 1.0 + 1e-9,
                            "f = {f}, θ = {theta}: claim {claim} of endpoint {index} reaches {best_value}"
                        );
                        *closest = closest.max(best_value);
                        checked += 1;
                    }
                }
                // The assembly, from the per-point forms and the terms.
                // The Minkowski bound of `κ Q + Σ weight (α + βᵀ t)²` over a rotation spread `th`,
                // t from the normal equations, and the rounding of `c₀ − gᵀ C⁻¹ g` (~1e-16 of the
                // form at t = 0 times the condition of C, up to ~1e6 here).
                let depths: Vec<f64> = scaled.depths().collect();
                let assembled = |terms: &[LineTerm], th: f64| {
                    let (mut c, mut gv, mut eta2) = (Matrix3::zeros(), Vector3::zeros(), 0.0);
                    for ((x, d), (h, norm2)) in corr.points3d.iter().zip(&depths).zip(&forms) {
                        c += h / (d * d);
                        gv += h * (r_c * x) / (d * d);
                        eta2 += norm2 * x.norm_squared() / (d * d);
                    }
                    for term in terms {
                        c += term.beta * term.beta.transpose() * term.weight;
                        gv += term.beta * term.alpha * term.weight;
                        eta2 += term.weight * term.drift * term.drift;
                    }
                    let lines_at = |t: &Vector3<f64>| {
                        (terms.iter())
                            .map(|term| term.weight * (term.alpha + term.beta.dot(t)).powi(2))
                            .sum::<f64>()
                    };
                    let t_min = -(c.lu().solve(&gv).unwrap());
                    let q = minorant_by_points(&problem, &depths, &r_c, &t_min) + lines_at(&t_min);
                    let origin = Vector3::zeros();
                    let at_origin = minorant_by_points(&problem, &depths, &r_c, &origin) + lines_at(&origin);
                    let bound = 0.5 * (q.sqrt() - th * eta2.sqrt()).max(0.0).powi(2);
                    (bound, 1e-9 * (q + at_origin))
                };
                // A line's distance bound grows with θ: at θ = 0 its terms are those for θ = 0.
                let at_zero: Vec<LineTerm> = problem.line_terms(
                    problem.box_segments,
                    (&r_c, 0.0),
                    TranslationSet {
                        t_star: &t_star,
                        spread,
                        shape: None,
                    },
                );
                for (th, terms) in [(0.0, &at_zero), (theta, &terms)] {
                    let (expected, rounding) = assembled(terms, th);
                    // (`wanted` 0: the linearised bound is not computed; it has its own test.)
                    let found = problem
                        .lines_bound(&scaled, &r_c, th, (&t_star, q_min), spread, problem.box_segments, None)
                        .map_or(0.0, |l| l.lower);
                    assert!(
                        (found - expected).abs() <= rounding,
                        "θ = {th}: {found} against {expected}"
                    );
                }
                // The ellipsoid of the translations: on its boundary Q_total(t) = (√(2f̂) + θ η_total)²
                // exactly (Q_total and η_total recomputed from the per-point forms and the terms,
                // rounding as above), and its reach is attained along C's least axis and never
                // exceeded: a slack or a reach too small (or too large) fails.
                let q_total = |t: &Vector3<f64>| {
                    minorant_by_points(&problem, &depths, &r_c, t)
                        + (terms.iter())
                            .map(|term| term.weight * (term.alpha + term.beta.dot(t)).powi(2))
                            .sum::<f64>()
                };
                let eta_total = ((corr.points3d.iter().zip(&depths).zip(&forms))
                    .map(|((x, d), (_, norm2))| norm2 * x.norm_squared() / (d * d))
                    .sum::<f64>()
                    + terms
                        .iter()
                        .map(|term| term.weight * term.drift * term.drift)
                        .sum::<f64>())
                .sqrt();
                let l = problem
                    .lines_bound(
                        &scaled,
                        &r_c,
                        theta,
                        (&t_star, q_min),
                        spread,
                        problem.box_segments,
                        None,
                    )
                    .expect("the terms fix the translation");
                let (slack_l, reach) = l.ellipsoid(f_hat, theta);
                let level = ((2.0 * f_hat).sqrt() + theta * eta_total).powi(2);
                if slack_l <= 0.0 {
                    // No translation: the box is pruned (checked above through the bound).
                    continue;
                }
                let eigen = l.c.symmetric_eigen();
                let least = eigen.eigenvalues.imin();
                // The points' minorant enters the library's quadratic through its own minimum and
                // minimiser at r_c, each rounded to ~1e-9 of the form's size (as in the bound
                // above): 1e-8 of it leaves room, and a slack or reach 1 % off is far outside.
                let rounding = 1e-8 * (level + q_total(&Vector3::zeros()));
                let axis: Vector3<f64> = eigen.eigenvectors.column(least).into();
                let mut boundary = vec![l.t_star + axis * reach];
                for _ in 0..8 {
                    let u = rng.unit_vector3();
                    boundary.push(l.t_star + u * (slack_l / u.dot(&(l.c * u))).sqrt());
                }
                for t in &boundary {
                    let q = q_total(t);
                    assert!(
                        (q - level).abs() <= rounding,
                        "f = {f}, θ = {theta}: Q_total = {q} on the ellipsoid's boundary, not {level}"
                    );
                    assert!(
                        (t - l.t_star).norm() <= reach * (1.0 + 1e-9),
                        "f = {f}: beyond the reach"
                    );
                }
                ellipsoids += 1;
            }
        }
    }
    eprintln!("segment terms: {checked} claims, the closest reach {closest:?} of their bounds");
    assert!(checked >= 500, "only {checked} claims");
    assert!(ellipsoids >= 50, "only {ellipsoids} ellipsoids");
    // The claims are nearly reached (else a bound twice too strong would pass).
    assert!(
        closest[0] > 0.5 && closest[1] > 0.5,
        "the claims reach only {closest:?}"
    );
}

/// [`Problem::lines_bound`]'s linearised bound (`by_linear`) against the minorant it bounds, summed
/// term by term here: the points' `κ ‖Aᵢ (R Xᵢ + t)‖² / Dᵢ²` and the segment endpoints'
/// `weight (ēᵀ ((R a + t) × (R b + t)))²` (the weights are the library's, checked by
/// `the_segments_terms_of_the_box_bound_hold_over_the_box`), minimised over the rotations of the box
/// (random and hill-climbing `φ`, `‖φ‖ ≤ θ`) and, at each, over the translations within `spread` of
/// `t*` (projected gradient on the quadratic in `t`, assembled here). The bound must never exceed
/// that minimum, and must beat the Minkowski bound on most of the smallest boxes.
#[test]
fn the_linearised_bound_with_segments_holds_over_the_box() {
    let mut rng = Rng::new(17);
    let (mut checked, mut small, mut better, mut closest) = (0usize, 0usize, 0usize, 0.0f64);
    for (f, np, nl, seed) in [
        (800.0, 6, 4, 31),
        (250.0, 5, 5, 32),
        (4000.0, 8, 6, 33),
        (15000.0, 10, 8, 34),
    ] {
        let scene = visible_scene(f, np, nl, false, seed);
        let corr = scene.noisy(1.0, true, &mut rng);
        let truth = Pose::new(scene.rotation, scene.translation);
        let f_hat = 4.0 * ReprojectionCost::of(&scene.camera.intrinsics(), &corr).cost(&truth);
        let problem = Problem::new(&scene.camera.intrinsics(), &corr, f_hat).unwrap();
        let k_inv = scene.camera.intrinsics().matrix().try_inverse().unwrap();
        let forms = forms_by_points(&problem);
        let segments = longest_segments(&corr, problem.box_segments);
        for kappa in [1.0, 2.0] {
            let scaled = ScaledMinorant {
                minorant: Rc::clone(problem.root().expect("depth bounds")),
                scale: kappa,
            };
            let depths: Vec<f64> = scaled.depths().collect();
            for _ in 0..10 {
                let away = 0.05 * rng.uniform_in(0.0, 1.0).powi(2);
                let r_c = exp_so3(&(rng.unit_vector3() * away)) * truth.rotation;
                let theta = 1e-4 * 1000f64.powf(rng.uniform_in(0.0, 1.0));
                let (t_star, q_min, eta) = scaled.at(&r_c).unwrap();
                let slack = (((2.0 * f_hat).sqrt() + theta * eta).powi(2) - q_min).max(0.0);
                let spread = (slack / kappa * problem.root().expect("depth bounds").c_inv_max).sqrt();
                // The linearised bound is computed where the Minkowski bound falls short of
                // `wanted` and its ceiling does not: `wanted` just above the Minkowski bound.
                let bounds_for = |wanted: f64| {
                    let (segments, set) = (problem.box_segments, (&t_star, q_min));
                    problem.lines_bound(&scaled, &r_c, theta, set, spread, segments, Some(wanted))
                };
                let Some(growth) = bounds_for(0.0).map(|b| b.by_growth) else {
                    continue;
                };
                let bounds = bounds_for(growth * (1.0 + 1e-12) + 1e-300).expect("as without `wanted`");
                let weights: Vec<f64> = problem
                    .line_terms(
                        problem.box_segments,
                        (&r_c, theta),
                        TranslationSet {
                            t_star: &t_star,
                            spread,
                            shape: None,
                        },
                    )
                    .iter()
                    .map(|term| term.weight)
                    .collect();
                // Per endpoint, the rest of its numerator beyond the linear part,
                // |n − (α + βᵀ t + φᵀ γ(t*))| ≤ θ ‖d‖ ‖ē × Δ‖ + ρ (‖ē‖ ‖a × d‖ + ‖d‖ ‖ē × t*‖), at rotations
                // and translations on the boundaries of the box's ball and of the set.
                let terms = problem.line_terms(
                    problem.box_segments,
                    (&r_c, theta),
                    TranslationSet {
                        t_star: &t_star,
                        spread,
                        shape: None,
                    },
                );
                let rho = rotation_rest(theta);
                for (index, term) in terms.iter().enumerate() {
                    let (line, end) = (segments[index / 2], index % 2);
                    let e = k_inv * Vector3::new(corr.lines2d[line][end].x, corr.lines2d[line][end].y, 1.0);
                    let (a, b) = (corr.lines3d[line][0], corr.lines3d[line][1]);
                    let (d, moment) = (b - a, a.cross(&(b - a)));
                    for _ in 0..30 {
                        let phi = rng.unit_vector3() * theta;
                        let delta = rng.unit_vector3() * spread;
                        let rotation = exp_so3(&phi) * r_c;
                        let t = t_star + delta;
                        let n = e.dot(&(rotation * a + t).cross(&(rotation * b + t)));
                        let linear = term.alpha + term.beta.dot(&t) + phi.dot(&term.gamma(&t_star));
                        let rest = theta * d.norm() * e.cross(&delta).norm()
                            + rho * (e.norm() * moment.norm() + d.norm() * e.cross(&t_star).norm());
                        let claimed = term.linear_rest(theta, &t_star, e.cross(&delta).norm());
                        assert!(
                            (claimed - rest).abs() <= 1e-9 * rest,
                            "endpoint {index}: the library's rest {claimed} against {rest}"
                        );
                        let ratio = (n - linear).abs() / rest;
                        assert!(
                            ratio <= 1.0 + 1e-6,
                            "f = {f}, θ = {theta}: endpoint {index}'s rest reaches {ratio} of its bound"
                        );
                        closest = closest.max(ratio);
                    }
                }
                // ½ min over ‖t − t*‖ ≤ spread of the minorant at the rotation exp(φ) r_c.
                let at_rotation = |phi: &Vector3<f64>| -> f64 {
                    let rotation = exp_so3(phi) * r_c;
                    let (mut c, mut g, mut c0) = (Matrix3::zeros(), Vector3::zeros(), 0.0);
                    for ((x, d), (h, _)) in corr.points3d.iter().zip(&depths).zip(&forms) {
                        let (y, w) = (rotation * x, 1.0 / (d * d));
                        c += h * w;
                        g += h * y * w;
                        c0 += y.dot(&(h * y)) * w;
                    }
                    for (index, weight) in weights.iter().enumerate() {
                        let (line, end) = (segments[index / 2], index % 2);
                        let [a, b] = corr.lines3d[line].map(|x| rotation * x);
                        let e = k_inv * Vector3::new(corr.lines2d[line][end].x, corr.lines2d[line][end].y, 1.0);
                        let (alpha, beta) = (e.dot(&a.cross(&b)), (b - a).cross(&e));
                        c += beta * beta.transpose() * *weight;
                        g += beta * alpha * *weight;
                        c0 += alpha * alpha * weight;
                    }
                    least_in_ball(&c, &g, c0, &t_star, spread)
                };
                let least = least_over_ball(&mut rng, theta, (40, 60), at_rotation);
                assert!(
                    bounds.by_linear <= least * (1.0 + 1e-9) + 1e-12,
                    "f = {f}, θ = {theta}: linearised bound {} above the minorant's least {least}",
                    bounds.by_linear,
                );
                checked += 1;
                if theta < 1e-3 {
                    small += 1;
                    if bounds.by_linear > bounds.by_growth {
                        better += 1;
                    }
                }
            }
        }
    }
    assert!(checked >= 60, "only {checked} boxes checked");
    // The endpoints' rests are nearly attained: a bound on them much too loose would show here.
    assert!(
        closest > 0.5,
        "the endpoints' rests reach at most {closest} of their bounds"
    );
    assert!(
        2 * better > small,
        "better than the Minkowski bound on {better} of {small} small boxes"
    );
}
