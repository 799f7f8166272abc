//! Unit tests of the pose certificate's steps (module docs of [`super`]), each against an
//! independent oracle.

use super::*;
use crate::rng::Rng;
use crate::synthetic::visible_scene;

/// `RayCurvature` bounds the second derivative of the residual vector along random whitened
/// rays (central differences), on wide and narrow fields of view, with points and lines, at the
/// pose and at a perturbed one.
/// The bearing cone's claim, `bᵢ · (R Xᵢ + t) ≥ a · t − δ ‖t‖ − max ‖X‖`, at random rotations and
/// translations (and translations that make it nearly tight: along the bearing farthest from
/// the axis, and against it), on wide and narrow fields of view.
#[test]
fn the_bearing_cone_bounds_every_depth_from_below() {
    let mut rng = Rng::new(17);
    // How close each of the claim's two parts comes: `bᵢ · t ≥ a · t − δ ‖t‖` and
    // `bᵢ · R Xᵢ ≥ −max ‖X‖` (per unit of their scale).
    let (mut closest_t, mut closest_x) = (f64::INFINITY, f64::INFINITY);
    for (seed, f) in [(1, 250.0), (2, 800.0), (3, 15000.0)] {
        let scene = visible_scene(f, 12, 0, false, seed);
        let corr = scene.noisy(1.0, true, &mut rng);
        let k_inv = scene.camera.matrix().try_inverse().unwrap();
        let bearings: Vec<Vector3<f64>> = corr
            .points2d
            .iter()
            .map(|u| (k_inv * Vector3::new(u.x, u.y, 1.0)).normalize())
            .collect();
        let (axis, reach, largest) = bearing_cone(&bearings, &corr.points3d);
        let farthest = bearings
            .iter()
            .max_by(|a, b| (*a - axis).norm().total_cmp(&(*b - axis).norm()))
            .unwrap();
        let biggest = (0..corr.n_points())
            .max_by(|&i, &j| corr.points3d[i].norm().total_cmp(&corr.points3d[j].norm()))
            .unwrap();
        for trial in 0..400 {
            let mut r = exp_so3(&(rng.unit_vector3() * rng.uniform_in(0.0, 3.0)));
            let t = match trial % 4 {
                0 => rng.unit_vector3() * rng.uniform_in(0.0, 20.0),
                1 => farthest * rng.uniform_in(0.0, 20.0),
                // (b − a) · t = −δ ‖t‖ for the farthest bearing.
                2 => (axis - farthest) * rng.uniform_in(0.0, 20.0),
                // The largest point turned against its own bearing: b · R X = −max ‖X‖.
                _ => {
                    let (x, b) = (corr.points3d[biggest], bearings[biggest]);
                    r = nalgebra::Rotation3::rotation_between(&x, &-b).unwrap().into_inner();
                    rng.unit_vector3() * rng.uniform_in(0.0, 20.0)
                }
            };
            let claim = axis.dot(&t) - reach * t.norm() - largest;
            for (x, b) in corr.points3d.iter().zip(&bearings) {
                let depth = b.dot(&(r * x + t));
                assert!(
                    depth >= claim - 1e-12 * (1.0 + t.norm()),
                    "f = {f}: depth {depth} < {claim}"
                );
                closest_t = closest_t.min((b.dot(&t) - axis.dot(&t) + reach * t.norm()) / t.norm().max(1e-300));
                closest_x = closest_x.min((b.dot(&(r * x)) + largest) / largest);
            }
        }
    }
    // Each part is reached, up to rounding (a cone too narrow, or a smaller largest point, fails).
    assert!(
        closest_t < 1e-12 && closest_x < 1e-12,
        "the parts come within {closest_t}, {closest_x}"
    );
}

/// The closed-form largest eigenvalue agrees with nalgebra's and never falls below it.
#[test]
fn closed_form_largest_eigenvalue() {
    let mut rng = Rng::new(5);
    for i in 0..2000 {
        let a = Matrix3::from_fn(|_, _| rng.normal()) * 10f64.powi(i % 7 - 3);
        let m = a * a.transpose() + Matrix3::identity() * if i % 3 == 0 { 0.0 } else { 1e-3 };
        let exact = m.symmetric_eigenvalues().max();
        let mine = largest_eigenvalue(&m);
        assert!(
            mine >= exact && mine <= exact * (1.0 + 1e-7) + 1e-300,
            "{mine} vs {exact}"
        );
    }
    assert_eq!(largest_eigenvalue(&(Matrix3::identity() * 2.0)), 2.0 * (1.0 + 1e-9));
}

/// Step 2's minorant summed point by point, the oracle of [`Minorant`]: `Σ (y_z / Dᵢ)² ‖rᵢ(y)‖²`
/// at `y = R Xᵢ + t`, with the residual `rᵢ(y) = Wᵢ K₂ (π(y) − ūᵢ)` projected here.
fn minorant_by_points(problem: &Problem, depths: &[f64], r: &Matrix3<f64>, t: &Vector3<f64>) -> f64 {
    (problem
        .corr
        .points3d
        .iter()
        .zip(&problem.corr.points2d)
        .zip(depths)
        .zip(&problem.point_maps))
    .map(|(((x, u), d), map)| {
        let y = r * x + t;
        let seen = problem.k_inv * Vector3::new(u.x, u.y, 1.0);
        let residual = map * (y.xy() / y.z - seen.xy() / seen.z);
        (y.z / d).powi(2) * residual.norm_squared()
    })
    .sum()
}

/// Per point, `H = Aᵀ A` of the oracle's minorant `‖A y‖² = y_z² ‖rᵢ(y)‖²` (`A = Wᵢ K₂ E`,
/// `E = [1 0 −ū₁; 0 1 −ū₂]`), and `λ_max(H)`.
fn forms_by_points(problem: &Problem) -> Vec<(Matrix3<f64>, f64)> {
    (problem.corr.points2d.iter().zip(&problem.point_maps))
        .map(|(u, map)| {
            let seen = problem.k_inv * Vector3::new(u.x, u.y, 1.0);
            let e = SMatrix::<f64, 2, 3>::new(1.0, 0.0, -seen.x / seen.z, 0.0, 1.0, -seen.y / seen.z);
            let h = e.transpose() * map.transpose() * map * e;
            (h, h.symmetric_eigenvalues().max())
        })
        .collect()
}

/// The Minkowski bound `½ (√q_min − θ η)₊²` at the rotation `r` of the minorant of the depth
/// bounds `depths` scaled by `κ`, point by point (the oracle of [`Scaled::bound_near`]): `q_min` from
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

/// A translation set for the tests of the bound without depth bounds: largest semi-axis `radius`,
/// round or thin (a random axis and the others 0.05-0.5 of it), its centre within `off` radii of
/// `truth`; and its `L` (`shape = L Lᵀ`).
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

fn translation_set(truth: &Vector3<f64>, radius: f64, off: f64, rng: &mut Rng) -> (Translations, Matrix3<f64>) {
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
    (Translations { centre, shape, radius }, l)
}

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
        let f_hat = 4.0 * ReprojectionCost::of(&scene.camera, &corr).cost(&truth);
        let problem = Problem::new(&scene.camera, &corr, f_hat).unwrap();
        assert!(problem.root().is_none(), "f = {f}: the search starts from depth bounds");
        let k = scene.camera.matrix();
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
            let Translations { centre, shape, .. } = ball;
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
        let f_hat = 4.0 * ReprojectionCost::of(&scene.camera, &corr).cost(&truth);
        let problem = Problem::new(&scene.camera, &corr, f_hat).unwrap();
        for _ in 0..24 {
            let theta = 0.005 * 40f64.powf(rng.uniform_in(0.0, 1.0));
            let r_c = exp_so3(&(rng.unit_vector3() * theta * rng.uniform_in(2.0, 8.0))) * truth.rotation;
            let radius = scene.translation.norm() * 0.5f64.powf(rng.uniform_in(2.0, 6.0));
            let (ball, l) = translation_set(&scene.translation, radius, 1.0, &mut rng);
            let Translations { centre, shape, .. } = ball;
            let segments = problem.lines.len();
            let (Some(open), Some(level)) = (
                problem.ball_bound(segments, &r_c, theta, &ball, f64::INFINITY),
                problem.ball_bound(segments, &r_c, theta, &ball, f_hat),
            ) else {
                continue;
            };
            let g = &open.growth;
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
            let beta = (2.0 * f_hat).sqrt() + level.growth.spin;
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

/// [`endpoint_sine`] against its claim at random poses near and far from the truth, with and
/// without covariances: the sine of the angle between each observed endpoint's ray and the
/// camera-frame interpretation plane, computed here from the projected endpoints, is at most
/// `endpoint_sine` of the endpoint's own residual (the test's pixel distance to the projected line,
/// over its standard deviation across it), and close to it somewhere.
#[test]
fn the_sine_of_an_endpoint_is_bounded_by_its_residual() {
    use crate::synthetic::random_observation_noise;
    use nalgebra::Vector2;
    let mut rng = Rng::new(36);
    let (mut checked, mut closest) = (0usize, 0.0f64);
    for (f, nl, seed, with_covariances) in [(800.0, 6, 61, false), (250.0, 5, 62, true), (4000.0, 6, 63, true)] {
        let scene = visible_scene(f, 0, nl, false, seed);
        let mut corr = scene.noisy(1.0, true, &mut rng);
        if with_covariances {
            corr.noise = Some(random_observation_noise(&mut rng, 0, nl, (0.3, 3.0)));
        }
        let truth = Pose::new(scene.rotation, scene.translation);
        let f_hat = 4.0 * ReprojectionCost::of(&scene.camera, &corr).cost(&truth);
        let problem = Problem::new(&scene.camera, &corr, f_hat).unwrap();
        let k = scene.camera.matrix();
        let k_inv = k.try_inverse().unwrap();
        let pixel = |x: &Vector3<f64>| {
            let p = k * x;
            Vector2::new(p.x / p.z, p.y / p.z)
        };
        for _ in 0..200 {
            let rotation = exp_so3(&(rng.unit_vector3() * rng.uniform_in(0.0, 0.3))) * scene.rotation;
            let t = scene.translation + rng.unit_vector3() * rng.uniform_in(0.0, 1.0);
            for (line, (segment, seen)) in corr.lines3d.iter().zip(&corr.lines2d).enumerate() {
                let [a, b] = segment.map(|x| rotation * x + t);
                if a.z <= 0.0 || b.z <= 0.0 {
                    continue;
                }
                let normal_plane = a.cross(&b).normalize();
                let (pa, pb) = (pixel(&a), pixel(&b));
                let dir = (pb - pa).normalize();
                let normal = Vector2::new(-dir.y, dir.x);
                for (end, observed) in seen.iter().enumerate() {
                    let sigma = corr
                        .noise
                        .as_ref()
                        .map_or(1.0, |n| normal.dot(&(n.lines[line][end] * normal)).sqrt());
                    let residual = normal.dot(&(observed - pa)).abs() / sigma;
                    let e = k_inv * Vector3::new(observed.x, observed.y, 1.0);
                    let sine = e.normalize().dot(&normal_plane).abs();
                    let bound = endpoint_sine(residual, problem.endpoint_maps[line][end].1, &e);
                    // Rounding: the pixels and the normal at ~1e-15 of their sizes.
                    assert!(sine <= bound * (1.0 + 1e-9) + 1e-15, "sine {sine} > its bound {bound}");
                    closest = closest.max(sine / bound);
                    checked += 1;
                }
            }
        }
    }
    assert!(
        checked > 3000 && closest > 0.9,
        "{checked} endpoints, closest {closest}"
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
        let f_hat = 4.0 * ReprojectionCost::of(&scene.camera, &corr).cost(&truth);
        let problem = Problem::new(&scene.camera, &corr, f_hat).unwrap();
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
        let f_hat = 4.0 * ReprojectionCost::of(&scene.camera, &corr).cost(&truth);
        let problem = Problem::new(&scene.camera, &corr, f_hat).unwrap();
        let k = scene.camera.matrix();
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
            let scaled = Scaled {
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

/// The linearised bound ([`Scaled::linear_bound`]) against the oracle: at rotations within the angle
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
        let f_hat = 4.0 * ReprojectionCost::of(&scene.camera, &corr).cost(&truth);
        let problem = Problem::new(&scene.camera, &corr, f_hat).unwrap();
        let depths = problem.root().expect("depth bounds").depths.clone();
        for kappa in [1.0, 2.5] {
            let scaled = Scaled {
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
        let f_hat = 4.0 * ReprojectionCost::of(&scene.camera, &corr).cost(&truth);
        let problem = Problem::new(&scene.camera, &corr, f_hat).unwrap();
        let k_inv = scene.camera.matrix().try_inverse().unwrap();
        let forms = forms_by_points(&problem);
        let segments = longest_segments(&corr, problem.box_segments);
        for kappa in [1.0, 2.0] {
            let scaled = Scaled {
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
                    let value = |t: &Vector3<f64>| t.dot(&(c * t)) + 2.0 * g.dot(t) + c0;
                    let lipschitz = c.symmetric_eigenvalues().max();
                    let mut t = t_star;
                    for _ in 0..400 {
                        let step = t - (c * t + g) / lipschitz;
                        let off = step - t_star;
                        t = t_star + off * (spread / off.norm()).min(1.0);
                    }
                    0.5 * value(&t)
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

/// The points' second-order rest ([`Scaled::second_order_rest`], the rest of both linearised bounds)
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
        let f_hat = ReprojectionCost::of(&scene.camera, &corr).cost(&truth);
        let problem = Problem::new(&scene.camera, &corr, f_hat).unwrap();
        let root = problem.root().expect("depth bounds");
        let forms = forms_by_points(&problem);
        for kappa in [1.0, 2.5] {
            let scaled = Scaled {
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
/// at random poses; and what a box hands down ([`Scaled::tightened`]: a scale, or a rebuild) is,
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
        let f_hat = ReprojectionCost::of(&scene.camera, &corr).cost(&truth);
        let problem = Problem::new(&scene.camera, &corr, f_hat).unwrap();
        let root = Scaled {
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
            let handed = root.tightened(&problem, reach.iter().copied(), &r_c, theta);
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
    let cost = ReprojectionCost::of(&scene.camera, &corr);
    let f_hat = 4.0 * cost.cost(&truth);
    let problem = Problem::new(&scene.camera, &corr, f_hat).unwrap();
    let whitening = Whitening::new(&cost.linearize(&truth).gauss_newton).unwrap();
    let mut record = Record::new(0.0);
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

/// `κ Q` for the depth bounds `D` is `Q` for `D / √κ`: a box bounded with a scaled minorant gets the
/// bound, the emptiness verdict, the whitened radius and the hand-down of the minorant rebuilt for
/// `D / √κ`, to rounding (random boxes near and far from the answer, inside and outside the unit
/// ball of rotation vectors, some with a point behind the camera; `κ` = 1, 1.7 and 4).
#[test]
fn a_scaled_minorant_bounds_a_box_as_the_minorant_rebuilt_for_its_depths() {
    let mut rng = Rng::new(12);
    let mut kinds = [0usize; 4]; // split, pruned, inside the ball, behind the camera
    for (f, n, seed) in [(800.0, 10, 5), (4000.0, 30, 6), (250.0, 6, 7)] {
        with_rotation_search(f, n, seed, &mut rng, f64::INFINITY, |search, rng| {
            let (problem, f_hat) = (search.problem, search.f_hat);
            let corr = problem.corr;
            for kappa in [1.0, 1.7, 4.0] {
                let scaled = Scaled {
                    minorant: Rc::clone(problem.root().expect("depth bounds")),
                    scale: kappa,
                };
                let depths: Vec<f64> = scaled.depths().collect();
                let rebuilt = Scaled {
                    minorant: Rc::new(Minorant::build(
                        &corr.points3d,
                        &problem.bearings,
                        &problem.forms,
                        depths,
                    )),
                    scale: 1.0,
                };
                for box_index in 0..300 {
                    // Small boxes, most near the answer (split or pruned, some inside the ball),
                    // and large ones anywhere (some behind the camera).
                    let (centre, half) = if box_index % 2 == 0 {
                        let centre = rng.unit_vector3() * 3.0 * rng.uniform_in(0.0, 1.0).powi(3);
                        (
                            centre,
                            Vector3::from_fn(|_, _| 0.001 * 100f64.powf(rng.uniform_in(0.0, 1.0))),
                        )
                    } else {
                        let centre = rng.unit_vector3() * rng.uniform_in(0.0, 3.0);
                        (centre, Vector3::from_fn(|_, _| rng.uniform_in(0.2, 0.6)))
                    };
                    let region = Region::new(
                        (centre - half).iter().copied().collect::<Vec<f64>>(),
                        (centre + half).iter().copied().collect::<Vec<f64>>(),
                    );
                    let mut run = |given: &Scaled| {
                        search.radius = 0.0;
                        let (bound, handed) = search.bound_with(&region, &Some(Handed::Minorant(given.clone())));
                        let lower = match bound {
                            Bound::Bounded { lower, .. } => lower,
                            Bound::Empty { .. } => f64::NAN,
                            Bound::Failed { .. } => panic!("the minorant fixes t"),
                        };
                        let depths: Option<Vec<f64>> = handed.map(|h| h.minorant().depths().collect());
                        (lower, search.radius, depths)
                    };
                    let (lower_s, radius_s, handed_s) = run(&scaled);
                    let (lower_r, radius_r, handed_r) = run(&rebuilt);
                    let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * a.abs().max(b.abs()).max(1e-300);
                    assert!(lower_s.is_nan() == lower_r.is_nan(), "κ = {kappa}: emptiness differs");
                    if lower_s.is_nan() {
                        kinds[3] += 1;
                    }
                    if !lower_s.is_nan() {
                        assert!(close(lower_s, lower_r), "κ = {kappa}: bound {lower_s} vs {lower_r}");
                    }
                    assert!(
                        close(radius_s, radius_r),
                        "κ = {kappa}: radius {radius_s} vs {radius_r}"
                    );
                    match (handed_s, handed_r) {
                        (Some(a), Some(b)) => {
                            assert!(
                                a.iter().zip(&b).all(|(x, y)| close(*x, *y)),
                                "κ = {kappa}: {a:?} vs {b:?}"
                            );
                            kinds[0] += 1;
                        }
                        (None, None) if radius_s > 0.0 => kinds[2] += 1,
                        (None, None) if lower_s >= f_hat => kinds[1] += 1,
                        (None, None) => {}
                        _ => panic!("κ = {kappa}: one hands down, the other does not"),
                    }
                }
            }
        });
    }
    assert!(
        kinds.iter().all(|&k| k > 0),
        "split / pruned / inside the ball / behind: {kinds:?}"
    );
}

/// The depth bounds a box hands down hold, point by point, at the farthest pose of the box the
/// proof covers: the rotation at each corner of the box and at its centre, with the translation
/// on the ellipsoid `Q(t) ≤ β²` farthest along the point's direction. The ellipsoid comes from an
/// oracle of its own (the minorant summed point by point, minimised over `t` in closed form), not
/// from the search's quadratic form.
#[test]
fn handed_down_depths_hold_at_the_corners_of_the_box_and_the_ellipsoid() {
    let mut rng = Rng::new(13);
    let mut checked = 0;
    for (f, n, seed) in [(800.0, 10, 8), (4000.0, 30, 9), (250.0, 6, 10)] {
        with_rotation_search(f, n, seed, &mut rng, 0.0, |search, rng| {
            let (problem, f_hat) = (search.problem, search.f_hat);
            let (corr, truth) = (problem.corr, *search.pose);
            let depths = problem.root().expect("depth bounds").depths.clone();
            let weights: Vec<f64> = depths.iter().map(|d| 1.0 / (d * d)).collect();
            let forms = forms_by_points(problem);
            for _ in 0..1000 {
                // Most near the answer, where boxes are split rather than pruned.
                let centre = rng.unit_vector3() * rng.uniform_in(0.0, 1.0).powi(3);
                let half = Vector3::from_fn(|_, _| 0.001 * 100f64.powf(rng.uniform_in(0.0, 1.0)));
                let region = Region::new(
                    (centre - half).iter().copied().collect::<Vec<f64>>(),
                    (centre + half).iter().copied().collect::<Vec<f64>>(),
                );
                let (_, Some(handed)) = search.bound_with(&region, &None) else {
                    continue;
                };
                // The oracle's ellipsoid at the centre rotation: Q(t) = Σ wᵢ (R_c Xᵢ + t)ᵀ Hᵢ (R_c Xᵢ + t).
                let r_c = exp_so3(&centre) * truth.rotation;
                let mut c = Matrix3::zeros();
                let mut g = Vector3::zeros();
                for ((x, (h, _)), w) in corr.points3d.iter().zip(&forms).zip(&weights) {
                    c += h * *w;
                    g += h * (r_c * x) * *w;
                }
                let c_inv = c.try_inverse().unwrap();
                let t_star = -(c_inv * g);
                let q_min = minorant_by_points(problem, &depths, &r_c, &t_star);
                let eta = (corr.points3d.iter().zip(&weights).zip(&forms))
                    .map(|((x, w), (_, norm2))| w * norm2 * x.norm_squared())
                    .sum::<f64>()
                    .sqrt();
                let beta = (2.0 * f_hat).sqrt() + half.norm() * eta;
                let slack = beta * beta - q_min;
                for ((i, x), claimed) in corr.points3d.iter().enumerate().zip(handed.minorant().depths()) {
                    if claimed >= depths[i] * (1.0 - 1e-12) {
                        continue; // capped by the inherited bound, which the ellipsoid may exceed
                    }
                    for corner in 0..9 {
                        let sign = |k: usize| if corner >> k & 1 == 1 { 1.0 } else { -1.0 };
                        let omega = if corner == 8 {
                            centre
                        } else {
                            centre + Vector3::new(sign(0) * half.x, sign(1) * half.y, sign(2) * half.z)
                        };
                        let y = exp_so3(&omega) * truth.rotation * x;
                        let d = (y + t_star).normalize();
                        let t = t_star + c_inv * d * (slack / d.dot(&(c_inv * d))).sqrt();
                        let distance = (y + t).norm();
                        assert!(distance <= claimed * (1.0 + 1e-9), "point {i}: {distance} > {claimed}");
                        checked += 1;
                    }
                }
            }
        });
    }
    assert!(checked > 1000, "{checked} checks");
}

#[test]
fn ray_curvature_bounds_the_second_derivative() {
    let mut checked = 0;
    let mut worst: f64 = 0.0;
    for (f, np, nl, planar) in [
        (250.0, 10, 0, false),
        (800.0, 20, 20, false),
        (4000.0, 30, 10, true),
        (15000.0, 10, 5, false),
    ] {
        for seed in 0..4 {
            let scene = visible_scene(f, np, nl, planar, seed);
            let mut rng = Rng::new(70 + seed);
            let corr = scene.noisy(1.0, true, &mut rng);
            let cost = ReprojectionCost::of(&scene.camera, &corr);
            let truth = Pose::new(scene.rotation, scene.translation);
            let nudged = Pose::new(
                exp_so3(&Vector3::new(2e-3, -1e-3, 1e-3)) * truth.rotation,
                truth.translation + Vector3::new(1e-3, 2e-3, -3e-3),
            );
            for pose in [truth, nudged] {
                let f_hat = cost.cost(&pose);
                let problem = Problem::new(&scene.camera, &corr, f_hat).unwrap();
                let lin = cost.linearize(&pose);
                let whitening = Whitening::new(&lin.gauss_newton).unwrap();
                let mu = (whitening.t.transpose() * lin.gauss_newton * whitening.t)
                    .symmetric_eigenvalues()
                    .max()
                    .sqrt();
                let radius = 3.0 * ((2.0 * f_hat).sqrt() + 0.1);
                let Some(k) = RayCurvature::new(&problem, &whitening, &pose, mu).and_then(|c| c.bound(radius)) else {
                    continue;
                };
                for _ in 0..20 {
                    let v = SVector::<f64, 6>::from_fn(|_, _| rng.normal()).normalize();
                    let a = whitening.t * v;
                    let at = |s: f64| -> Vec<f64> {
                        let omega = Vector3::new(a[0], a[1], a[2]) * s;
                        let tau = Vector3::new(a[3], a[4], a[5]) * s;
                        cost.residuals(&Pose::new(exp_so3(&omega) * pose.rotation, pose.translation + tau))
                    };
                    let h = 1e-2 * radius;
                    for i in 1..10 {
                        let s = radius * i as f64 / 10.0;
                        let (lo, mid, hi) = (at(s - h), at(s), at(s + h));
                        let second: f64 = lo
                            .iter()
                            .zip(&mid)
                            .zip(&hi)
                            .map(|((l, m), u)| ((l - 2.0 * m + u) / (h * h)).powi(2))
                            .sum::<f64>()
                            .sqrt();
                        // Central differences: error O(h² r'''), far below K here.
                        assert!(
                            second <= k * 1.01 + 1e-9,
                            "f={f} {np}p {nl}l seed {seed}: ‖r''‖ = {second} > K = {k}"
                        );
                        checked += 1;
                        worst = worst.max(second / k);
                    }
                }
            }
        }
    }
    assert!(checked > 1000, "only {checked} samples");
    // Not vacuous: the bound is within two orders of magnitude of what the rays reach.
    assert!(
        worst > 1e-2,
        "K is {:.0}x the largest sampled second derivative",
        1.0 / worst
    );
}

/// `Whitening::box_spread` claims the largest whitened length `√(sᵀ W_ωω s)` of a rotation step `s` in
/// the box `|s_k| ≤ half_k`, which step 4 adds to a box centre's length to get its whitened radius.
/// Checked against an oracle written out here: the quadratic form summed entry by entry at all eight
/// vertices (the length is convex, so its largest value on the box is at one) and at uniform points of
/// the box and of its faces, none above the spread, and the spread the largest vertex (up to the
/// rounding of nine products, ~1e-15 relative: the largest vertex's form is at least a third of
/// `Σ|sᵢ W_ij s_j|`, since the vertices' mean is `Σ hᵢ² W_ii`). The metrics: random ones whose rotation
/// block couples the axes strongly (each of the four vertex pairs `±s` is the largest on some of them,
/// so a spread that left one out fails), and `JᵀJ` of real scenes at the truth.
#[test]
fn the_whitened_spread_of_a_rotation_box_is_its_largest_vertex() {
    let mut rng = Rng::new(61);
    let mut metrics: Vec<SMatrix<f64, 6, 6>> = (0..3000)
        .map(|_| {
            let scales = SVector::<f64, 6>::from_fn(|_, _| 10f64.powf(rng.uniform_in(-1.5, 1.5)));
            let a = SMatrix::<f64, 6, 6>::from_fn(|_, _| rng.normal()) * SMatrix::from_diagonal(&scales);
            a.transpose() * a
        })
        .collect();
    for (f, np, nl, seed) in [(250.0, 10, 0, 1), (800.0, 20, 20, 2), (4000.0, 30, 10, 3)] {
        let scene = visible_scene(f, np, nl, false, seed);
        let corr = scene.noisy(1.0, true, &mut Rng::new(seed));
        let truth = Pose::new(scene.rotation, scene.translation);
        metrics.push(
            ReprojectionCost::of(&scene.camera, &corr)
                .linearize(&truth)
                .gauss_newton,
        );
    }
    let mut winners = [0usize; 4];
    let mut checked = 0;
    for w in &metrics {
        let whitening = Whitening::new(w).expect("a positive definite metric");
        for _ in 0..4 {
            let half = Vector3::from_fn(|_, _| 10f64.powf(rng.uniform_in(-4.0, 0.0)));
            let spread = whitening.box_spread(&half);
            let length = |s: &[f64; 3]| {
                let mut q = 0.0;
                for i in 0..3 {
                    for j in 0..3 {
                        q += s[i] * w[(i, j)] * s[j];
                    }
                }
                q.max(0.0).sqrt()
            };
            let (mut largest, mut arg) = (0.0f64, 0);
            for vertex in 0..8 {
                let s: [f64; 3] = std::array::from_fn(|k| if vertex >> k & 1 == 1 { half[k] } else { -half[k] });
                let l = length(&s);
                if l > largest {
                    (largest, arg) = (l, vertex);
                }
            }
            // The pair ±s of the largest vertex: the signs of s₂ and s₃ relative to s₁.
            let relative = |k: usize| usize::from((arg >> k & 1) != (arg & 1));
            winners[relative(1) + 2 * relative(2)] += 1;
            assert!(
                (spread - largest).abs() <= 1e-12 * largest,
                "spread {spread} is not the largest vertex's length {largest} (half {half:?})"
            );
            for k in 0..40 {
                let mut s: [f64; 3] = std::array::from_fn(|i| rng.uniform_in(-half[i], half[i]));
                if k % 2 == 0 {
                    // On a face.
                    let i = k / 2 % 3;
                    s[i] = if k % 4 == 0 { half[i] } else { -half[i] };
                }
                assert!(
                    length(&s) <= spread * (1.0 + 1e-12),
                    "a step {s:?} of the box is longer, {}, than the spread {spread}",
                    length(&s)
                );
                checked += 1;
            }
        }
    }
    assert!(checked > 100_000, "{checked} points");
    assert!(
        winners.iter().all(|&n| n >= 500),
        "each vertex pair must be the largest on some boxes: {winners:?}"
    );
}
