//! The rotation search: what a box hands down to its octants ([`super::super::search`]).

use super::*;

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
                let scaled = ScaledMinorant {
                    minorant: Rc::clone(problem.root().expect("depth bounds")),
                    scale: kappa,
                };
                let depths: Vec<f64> = scaled.depths().collect();
                let rebuilt = ScaledMinorant {
                    minorant: Rc::new(Minorant::build(
                        &corr.points3d,
                        &problem.bearings,
                        &problem.forms,
                        &problem.offsets,
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
                    let mut run = |given: &ScaledMinorant| {
                        search.radius = 0.0;
                        let (bound, handed) = search.bound_with(&region, &Some(HandedDown::Minorant(given.clone())));
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
