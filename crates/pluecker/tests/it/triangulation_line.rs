//! Line triangulation (Josephson & Kahl 2008, sections 2.2, 3, 4): exact recovery, cost ordering,
//! covariance weighting, the soundness of the branch-and-bound bound, and bad input.

// `!(x > 0.0)` is true for NaN: the NaN guard used throughout (a NaN must take the failing branch).
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use crate::common;

use nalgebra::{Matrix2, Matrix3, Matrix3x4, Vector2, Vector3, Vector6};
use pluecker::geometry::plucker;
use pluecker::rng::Rng;
use pluecker::triangulation::line::{lines_from_segments, triangulate_line, LineObservations, LineTriangulation};
use pluecker::triangulation::scenes::{line_scene, LineScene};
use pluecker::triangulation::{CertificateKind, LineBound, Method, Status, TriangulationOptions};
use pluecker::Error;

fn opts(method: Method) -> TriangulationOptions {
    // A node cap keeps the tests fast; certificates below are asserted only where the gap closed.
    let mut options = TriangulationOptions::default();
    options.method = method;
    options.certify.max_nodes = Some(300);
    options
}

/// Sine of the angle between two lines' directions, and the distance between their closest points
/// to the origin.
fn line_error(result: &LineTriangulation, truth: &Vector6<f64>) -> (f64, f64) {
    let (p, d) = plucker::to_point_direction(truth).unwrap();
    (result.direction.cross(&d).norm(), (result.point - p).norm())
}

fn exact_lines(scene: &LineScene) -> Vec<Vector3<f64>> {
    scene
        .segments
        .iter()
        .map(|s| s[0].push(1.0).cross(&s[1].push(1.0)))
        .collect()
}

#[test]
fn noise_free_lines_are_recovered_by_every_method() {
    for (views, seed) in [(2, 1u64), (3, 2), (6, 3)] {
        let scene = line_scene(views, 0.8, seed);
        let lines = exact_lines(&scene);
        for method in Method::ALL.iter().copied() {
            let r = triangulate_line(&scene.cameras, LineObservations::Lines(&lines, None), &opts(method)).unwrap();
            let (angle, offset) = line_error(&r, &scene.plucker());
            assert!(
                angle < 1e-8 && offset < 1e-8,
                "views {views} seed {seed} {}: {angle} {offset}",
                method.as_str()
            );
            assert!(r.report.cost < 1e-12, "{}", r.report.cost);
            assert!(plucker::constraint(r.plucker.coordinates()).abs() < 1e-14);
            assert!((r.plucker.coordinates().norm() - 1.0).abs() < 1e-12);
            // point and direction describe the returned Plücker coordinates.
            assert!(
                (plucker::from_point_direction(&r.point, &r.direction).normalize() - r.plucker.coordinates()).norm()
                    < 1e-9
            );
            assert_eq!(r.report.status, Status::Success);
        }
    }
}

#[test]
fn noisy_costs_are_ordered_and_bounds_are_below_the_costs() {
    let mut certified = 0;
    for seed in 0..8u64 {
        let views = 3 + (seed as usize % 4);
        let scene = line_scene(views, 0.8, 100 + seed);
        let mut rng = Rng::new(200 + seed);
        let segments = scene.noisy_segments(1.0, &mut rng);
        let run = |m| triangulate_line(&scene.cameras, LineObservations::Segments(&segments, 1.0), &opts(m)).unwrap();
        let (linear, local, optimal) = (run(Method::Linear), run(Method::Local), run(Method::Optimal));
        let tol = 1e-9 * (1.0 + linear.report.cost);
        assert!(local.report.cost <= linear.report.cost + tol, "seed {seed}");
        assert!(optimal.report.cost <= local.report.cost + tol, "seed {seed}");
        let c = optimal.report.certificate.expect("a search ran");
        assert_eq!(c.kind, CertificateKind::TaylorBranchAndBound, "seed {seed}");
        assert_eq!(optimal.report.status == Status::Success, c.certified);
        certified += c.certified as usize;
        // The estimate fits the data at least as well as the true line does.
        let (lines, covariances) = lines_from_segments(&segments, 1.0).unwrap();
        // The raw bound against the independent cost of the answer; the gap recomputed from them
        // decides the certificate (the reported gap is not read back).
        let at_answer = independent_line_cost(
            &scene.cameras,
            &lines,
            &covariances,
            &optimal.point,
            &(optimal.point + optimal.direction),
        );
        assert!(
            (at_answer - optimal.report.cost).abs() <= 1e-8 * (1.0 + at_answer),
            "seed {seed}"
        );
        assert!(
            c.raw_lower_bound <= at_answer * (1.0 + 1e-9),
            "seed {seed}: {c:?} above {at_answer}"
        );
        let gap = (at_answer - c.raw_lower_bound.min(at_answer)) / at_answer;
        assert_eq!(c.certified, gap <= 1e-3 * (1.0 + 1e-6), "seed {seed}: gap {gap}, {c:?}");
        let truth = independent_line_cost(
            &scene.cameras,
            &lines,
            &covariances,
            &scene.endpoints[0],
            &scene.endpoints[1],
        );
        assert!(
            optimal.report.cost <= truth + tol,
            "seed {seed}: {} > {truth}",
            optimal.report.cost
        );
    }
    // Measured with the Taylor bound: 8 of 8 (7 at the root, where the whole search box is proved
    // convex; one after 73 nodes). At the real-data rate of 0.99 (bench/compare_line_triangulation.py),
    // fewer than 7 of 8 certify with probability 0.003 (binomial); a bound that stops closing gaps
    // certifies none.
    assert!(certified >= 7, "{certified} of 8 certified");
}

/// The paper's relaxation (eqs. 22-27) proves a bound at every node, certified or not: stopped at the
/// root, after a few nodes and after many, its raw bound never exceeds the independent cost of the
/// answer or of the true line (both lie in the search box): the bound of a search that did not close
/// its gap is checked too, not only certified ones. The slack is the rounding of the costs (1e-9
/// relative): the bound itself is made valid against the solver's tolerance.
#[test]
fn the_relaxation_bound_is_below_the_costs_at_every_node_cap() {
    let mut compared = 0;
    for seed in 0..10u64 {
        let views = 3 + (seed as usize % 4);
        let spread = [0.8, 0.2, 0.05][seed as usize % 3];
        let scene = line_scene(views, spread, 700 + seed);
        let mut rng = Rng::new(800 + seed);
        let segments = scene.noisy_segments(2.0, &mut rng);
        let (lines, covariances) = lines_from_segments(&segments, 1.0).unwrap();
        let truth = independent_line_cost(
            &scene.cameras,
            &lines,
            &covariances,
            &scene.endpoints[0],
            &scene.endpoints[1],
        );
        for max_nodes in [1, 4, 40, 400] {
            let mut o = TriangulationOptions::default();
            o.method = Method::Optimal;
            o.line_bound = LineBound::Relaxation;
            o.certify.max_relative_gap = 1e-9;
            o.certify.max_nodes = Some(max_nodes);
            let r = triangulate_line(&scene.cameras, LineObservations::Lines(&lines, Some(&covariances)), &o).unwrap();
            let Some(bound) = r.report.certificate.map(|c| c.raw_lower_bound) else {
                continue; // nothing proved, nothing claimed
            };
            let at_answer =
                independent_line_cost(&scene.cameras, &lines, &covariances, &r.point, &(r.point + r.direction));
            assert_bound_below_costs(bound, at_answer, truth, &format!("seed {seed}, {max_nodes} nodes"));
            compared += 1;
        }
    }
    // Every run proves some bound (the root relaxation is always solvable for lines in front).
    assert!(compared >= 35, "only {compared} of 40 runs proved a bound");
}

/// A raw bound at or below the independent costs of the answer and of the true line, to the rounding
/// of the costs (1e-9 relative; the bound is made valid against the solver's tolerance).
fn assert_bound_below_costs(bound: f64, at_answer: f64, truth: f64, context: &str) {
    for (what, cost) in [("answer", at_answer), ("truth", truth)] {
        assert!(
            bound <= cost * (1.0 + 1e-9) + 1e-12,
            "{context}: raw bound {bound} above the {what}'s cost {cost}"
        );
    }
}

/// The relaxation's raw bound against the independent cost of the true line and of the answer when
/// one view's segment is moved off the line by 3 to 40 px, so that one view carries most of the
/// residual (its numerator term `tᵢ = ‖rᵢ‖²gᵢ` then nears the cap `min(γ², incumbent) · Gᵢᵁ` of
/// the relaxation's box): the bound is still below both, after one node and after sixty.
/// Every certified answer also costs no more than the true line (beyond the certified gap).
#[test]
fn the_relaxation_bound_is_below_the_costs_when_one_view_carries_the_residual() {
    let mut compared = 0;
    for seed in 0..8u64 {
        let views = 3 + (seed as usize % 3);
        let scene = line_scene(views, [0.8, 0.2][seed as usize % 2], 900 + seed);
        let mut rng = Rng::new(950 + seed);
        let mut segments = scene.noisy_segments(0.5, &mut rng);
        let shift = [3.0, 10.0, 40.0][seed as usize % 3];
        let along = (segments[0][1] - segments[0][0]).normalize();
        let normal = Vector2::new(-along.y, along.x) * shift;
        segments[0] = [segments[0][0] + normal, segments[0][1] + normal * 0.5];
        let (lines, covariances) = lines_from_segments(&segments, 1.0).unwrap();
        let truth = independent_line_cost(
            &scene.cameras,
            &lines,
            &covariances,
            &scene.endpoints[0],
            &scene.endpoints[1],
        );
        for max_nodes in [1, 60] {
            let mut o = TriangulationOptions::default();
            o.method = Method::Optimal;
            o.line_bound = LineBound::Relaxation;
            o.certify.max_nodes = Some(max_nodes);
            let r = triangulate_line(&scene.cameras, LineObservations::Lines(&lines, Some(&covariances)), &o).unwrap();
            let c = r.report.certificate.expect("a search ran");
            if c.raw_lower_bound.is_nan() {
                continue;
            }
            let at_answer =
                independent_line_cost(&scene.cameras, &lines, &covariances, &r.point, &(r.point + r.direction));
            let context = format!("seed {seed}, shift {shift}, {max_nodes} nodes");
            assert_bound_below_costs(c.raw_lower_bound, at_answer, truth, &context);
            if c.certified {
                assert!(
                    at_answer <= truth * (1.0 + 1e-3) + 1e-9,
                    "seed {seed}: certified answer costs {at_answer}, the true line {truth}"
                );
            }
            compared += 1;
        }
    }
    assert!(compared >= 12, "only {compared} of 16 runs proved a bound");
}

#[test]
fn no_line_anywhere_costs_less_than_the_certified_bound() {
    // The bound of every certified line is checked against lines from the whole domain of its
    // certificate (every line at least 1 % of the local line's distance from each camera centre, in
    // front of the cameras or not), not only near the answer: 20000 lines through two uniform points
    // of a box ten times the scene, 2000 lines through points near each camera centre (between 1 % and
    // the full distance of the answer), the 50 cheapest of all improved by a random descent
    // (many-start local search), and lines 1e-1 to 1e-6 of the scene away from the optimum. The cost
    // is recomputed independently. Six regimes: 46° of parallax, 3°, 0.3°, anisotropic covariances
    // (endpoint noise 3 px along x, 0.3 px along y), a line 2° off the epipolar plane of the first two
    // views (nearly parallel image lines), and the paper's SOCP relaxation on the wide regime.
    let (mut checked, mut violations, mut tried) = (0, 0, 0);
    let regimes = [
        ("wide", 0.8, false, false, LineBound::Taylor),
        ("low parallax 3°", 0.05, false, false, LineBound::Taylor),
        ("low parallax 0.3°", 0.005, false, false, LineBound::Taylor),
        ("anisotropic", 0.8, true, false, LineBound::Taylor),
        ("near the epipolar plane", 0.8, false, true, LineBound::Taylor),
        ("wide, relaxation", 0.8, false, false, LineBound::Relaxation),
    ];
    for (regime, spread, anisotropic, epipolar, bound) in regimes {
        let mut certified_here = 0;
        for seed in 0..6u64 {
            let views = 3 + (seed as usize % 3);
            let mut scene = line_scene(views, spread, 300 + seed);
            if epipolar && !tilt_into_epipolar_plane(&mut scene, 2f64.to_radians()) {
                continue;
            }
            tried += 1;
            let mut rng = Rng::new(400 + seed);
            let segments = scene.noisy_segments(1.0, &mut rng);
            let (lines, covariances) = if anisotropic {
                let cov = Matrix2::new(9.0, 0.0, 0.0, 0.09);
                let fits: Vec<_> = segments
                    .iter()
                    .map(|s| pluecker::triangulation::fitting::line_from_endpoints(&s[0], &s[1], &cov, &cov).unwrap())
                    .collect();
                (
                    fits.iter().map(|f| f.line).collect::<Vec<_>>(),
                    fits.iter().map(|f| f.covariance).collect::<Vec<_>>(),
                )
            } else {
                lines_from_segments(&segments, 1.0).unwrap()
            };
            let mut o = opts(Method::Optimal);
            o.line_bound = bound;
            let optimal =
                triangulate_line(&scene.cameras, LineObservations::Lines(&lines, Some(&covariances)), &o).unwrap();
            let c = optimal.report.certificate.expect("a search ran");
            if !c.certified {
                continue;
            }
            certified_here += 1;
            let expected = match bound {
                LineBound::Taylor => CertificateKind::TaylorBranchAndBound,
                LineBound::Relaxation => CertificateKind::BranchAndBound,
            };
            assert_eq!(c.kind, expected, "{regime} seed {seed}");
            let found = search_below(
                &scene,
                &lines,
                &covariances,
                &optimal,
                c.raw_lower_bound,
                bound == LineBound::Taylor,
                &mut rng,
                &mut violations,
            );
            let slack = 1e-9 * (1.0 + optimal.report.cost);
            // The search finds nothing better than the certified answer either (beyond the gap).
            assert!(
                found >= optimal.report.cost * (1.0 - 1e-3) - slack,
                "{regime} seed {seed}: {found} < {}",
                optimal.report.cost
            );
        }
        eprintln!("{regime}: {certified_here} certified and checked");
        if bound == LineBound::Relaxation {
            // Measured 5 of 6. A relaxation that never closes (a wrong eq. 23 map from the branching
            // variables to the line makes every node's program fail, keeping its parent's bound) is
            // sound but useless, and the other regimes' counts would hide it.
            assert!(certified_here >= 4, "{regime}: only {certified_here} of 6 certified");
        }
        checked += certified_here;
    }
    eprintln!("{checked} of {tried} certified lines checked; {violations} violations");
    // Measured: 35 of 36. The Taylor bound closes the gap on every line of these regimes within
    // 300 nodes but the relaxation's (5 of 6 at this cap); fewer than 30 means certification broke.
    assert!(checked >= 30, "only {checked} of {tried} certified");
    assert_eq!(violations, 0);
}

/// Turns the scene's line so that it lies 2° (`angle`) off the plane through the first two camera
/// centres and its midpoint (an epipolar plane): its images are nearly the epipolar lines. False when
/// an endpoint leaves an image.
fn tilt_into_epipolar_plane(scene: &mut LineScene, angle: f64) -> bool {
    let centres: Vec<Vector3<f64>> = scene
        .cameras
        .iter()
        .map(pluecker::triangulation::testing::centre)
        .collect();
    let mid = 0.5 * (scene.endpoints[0] + scene.endpoints[1]);
    let baseline = (centres[1] - centres[0]).normalize();
    let normal = baseline.cross(&(mid - centres[0])).normalize();
    let half = 0.5 * (scene.endpoints[0] - scene.endpoints[1]).norm();
    let direction = baseline * angle.cos() + normal * angle.sin();
    scene.endpoints = [mid + direction * half, mid - direction * half];
    let mut segments = Vec::new();
    for p in &scene.cameras {
        let mut seg = [Vector2::zeros(); 2];
        for (k, x) in scene.endpoints.iter().enumerate() {
            let u = p * x.push(1.0);
            if !(u.z > 0.0) {
                return false;
            }
            seg[k] = u.xy() / u.z;
        }
        if (seg[0] - seg[1]).norm() < 30.0 {
            return false;
        }
        segments.push(seg);
    }
    scene.segments = segments;
    true
}

/// The least cost found over the domain of the certificate (see the test above; `every_line`: the
/// Taylor bound's, else lines through two points in front of every camera); every cost below
/// `bound` (less a rounding slack) counts as a violation.
#[allow(clippy::too_many_arguments)]
fn search_below(
    scene: &LineScene,
    lines: &[Vector3<f64>],
    covariances: &[Matrix2<f64>],
    optimal: &LineTriangulation,
    bound: f64,
    every_line: bool,
    rng: &mut Rng,
    violations: &mut usize,
) -> f64 {
    let cost = |a: &Vector3<f64>, b: &Vector3<f64>| independent_line_cost(&scene.cameras, lines, covariances, a, b);
    let centres: Vec<Vector3<f64>> = scene
        .cameras
        .iter()
        .map(pluecker::triangulation::testing::centre)
        .collect();
    let distance = |c: &Vector3<f64>, a: &Vector3<f64>, b: &Vector3<f64>| (c - a).cross(&(b - a).normalize()).norm();
    let (p, d) = (optimal.point, optimal.direction);
    let reference: Vec<f64> = centres.iter().map(|c| distance(c, &p, &(p + d))).collect();
    // 1.2 % rather than 1 %: the clearance is relative to the local line, the answer may differ.
    let admissible = |a: &Vector3<f64>, b: &Vector3<f64>| {
        if (a - b).norm() < 1e-6 {
            return false;
        }
        if every_line {
            centres
                .iter()
                .zip(&reference)
                .all(|(c, r)| distance(c, a, b) >= 0.012 * r)
        } else {
            [a, b]
                .iter()
                .all(|x| scene.cameras.iter().all(|p| (p * x.push(1.0)).z > 0.0))
        }
    };
    let sample = |scale: f64, rng: &mut Rng| {
        Vector3::new(
            rng.uniform_in(-1.0, 1.0),
            rng.uniform_in(-1.0, 1.0),
            rng.uniform_in(-1.0, 1.0),
        ) * scale
    };
    let mut candidates: Vec<(f64, Vector3<f64>, Vector3<f64>)> = Vec::new();
    while candidates.len() < 20_000 {
        let (a, b) = (sample(8.0, rng), sample(8.0, rng));
        if admissible(&a, &b) {
            candidates.push((cost(&a, &b), a, b));
        }
    }
    if every_line {
        for (c, r) in centres.iter().zip(&reference) {
            let mut added = 0;
            while added < 2000 {
                let a = c + rng.unit_vector3() * (*r * 10f64.powf(rng.uniform_in(-2.0, 0.0)));
                let b = a + rng.unit_vector3();
                if admissible(&a, &b) {
                    candidates.push((cost(&a, &b), a, b));
                    added += 1;
                }
            }
        }
    }
    candidates.sort_by(|x, y| x.0.total_cmp(&y.0));
    let mut costs: Vec<f64> = candidates.iter().map(|c| c.0).collect();
    for &(mut best, mut a, mut b) in candidates.iter().take(50) {
        let mut step = 1.0;
        for _ in 0..400 {
            let (na, nb) = (a + sample(step, rng), b + sample(step, rng));
            let c = cost(&na, &nb);
            if c < best && admissible(&na, &nb) {
                (best, a, b) = (c, na, nb);
            } else {
                step *= 0.98;
            }
        }
        costs.push(best);
    }
    for k in 0..600 {
        let scale = 10f64.powi(-(k % 6) - 1);
        costs.push(cost(&(p + sample(scale, rng)), &(p + d + sample(scale, rng))));
    }
    let slack = 1e-9 * (1.0 + optimal.report.cost);
    *violations += costs.iter().filter(|&&v| v < bound - slack).count();
    costs.iter().copied().fold(f64::INFINITY, f64::min)
}

/// Eq. 19 of the 3-D line through `a` and `b`, computed without the library's line code: the image line
/// through the projections of `a` and `b`, written in the frame of the observed line (section 3.1:
/// unit normal `n`, offset `c₀ ≤ 0`, origin `o = (D − c₀) n`), the residual `D (D (l₁, l₂)/l₃ − n)` of
/// eq. 17 there, and its Mahalanobis norm under the covariance (eq. 18).
fn independent_line_cost(
    cameras: &[Matrix3x4<f64>],
    lines: &[Vector3<f64>],
    covariances: &[Matrix2<f64>],
    a: &Vector3<f64>,
    b: &Vector3<f64>,
) -> f64 {
    const D: f64 = 1000.0;
    let mut total = 0.0;
    for ((p, obs), cov) in cameras.iter().zip(lines).zip(covariances) {
        let h = obs.xy().norm();
        let (mut n, mut c0) = (obs.xy() / h, obs.z / h);
        if c0 > 0.0 {
            (n, c0) = (-n, -c0);
        }
        let o = n * (D - c0);
        let l = (p * a.push(1.0)).cross(&(p * b.push(1.0)));
        // The candidate in the frame x' = x − o: (l₁, l₂, l₃ + l₁ o₁ + l₂ o₂).
        let last = l.z + l.x * o.x + l.y * o.y;
        let r = D * (D * Vector2::new(l.x, l.y) / last - n);
        total += r.dot(&(cov.try_inverse().unwrap() * r));
    }
    total
}

#[test]
fn reported_cost_is_eq_19() {
    let scene = line_scene(5, 0.8, 9);
    let mut rng = Rng::new(10);
    let segments = scene.noisy_segments(1.0, &mut rng);
    let (lines, covariances) = lines_from_segments(&segments, 1.0).unwrap();
    for method in Method::ALL.iter().copied() {
        let r = triangulate_line(
            &scene.cameras,
            LineObservations::Lines(&lines, Some(&covariances)),
            &opts(method),
        )
        .unwrap();
        let cost = independent_line_cost(&scene.cameras, &lines, &covariances, &r.point, &(r.point + r.direction));
        assert!(
            (cost - r.report.cost).abs() < 1e-8 * (1.0 + cost),
            "{}: {cost} vs {}",
            method.as_str(),
            r.report.cost
        );
    }
}

#[test]
fn a_view_with_huge_covariance_is_ignored() {
    // View 3's line is moved by 20 px; with a covariance 1e8 times larger it must not matter: the
    // answer equals the 3-view answer without it (to the 1e-4 relative weight it keeps).
    let scene = line_scene(4, 0.8, 11);
    let mut rng = Rng::new(12);
    let mut segments = scene.noisy_segments(1.0, &mut rng);
    segments[3] = [
        segments[3][0] + Vector2::new(0.0, 20.0),
        segments[3][1] + Vector2::new(0.0, 20.0),
    ];
    let (lines, mut covariances) = lines_from_segments(&segments, 1.0).unwrap();
    covariances[3] *= 1e8;
    let all = triangulate_line(
        &scene.cameras,
        LineObservations::Lines(&lines, Some(&covariances)),
        &opts(Method::Local),
    )
    .unwrap();
    let three = triangulate_line(
        &scene.cameras[..3],
        LineObservations::Lines(&lines[..3], Some(&covariances[..3])),
        &opts(Method::Local),
    )
    .unwrap();
    let (angle, offset) = line_error(&all, three.plucker.coordinates());
    assert!(angle < 1e-4 && offset < 1e-4, "{angle} {offset}");
    // With its nominal covariance the moved view pulls the answer away.
    let (_, nominal) = lines_from_segments(&segments, 1.0).unwrap();
    let pulled = triangulate_line(
        &scene.cameras,
        LineObservations::Lines(&lines, Some(&nominal)),
        &opts(Method::Local),
    )
    .unwrap();
    let (angle, offset) = line_error(&pulled, three.plucker.coordinates());
    assert!(angle > 1e-3 || offset > 1e-3, "{angle} {offset}");
}

#[test]
fn bad_input_is_rejected_with_the_argument_and_index() {
    let scene = line_scene(3, 0.8, 15);
    let lines = exact_lines(&scene);
    let o = opts(Method::Local);
    let err = |c: &[Matrix3x4<f64>], l: &[Vector3<f64>], cov: Option<&[Matrix2<f64>]>| {
        triangulate_line(c, LineObservations::Lines(l, cov), &o).unwrap_err()
    };
    assert!(matches!(
        err(&scene.cameras[..1], &lines[..1], None),
        Error::TooFewCorrespondences { .. }
    ));
    assert!(matches!(err(&scene.cameras, &lines[..2], None), Error::Shape { .. }));
    let mut nan = lines.clone();
    nan[2].y = f64::NAN;
    assert!(matches!(err(&scene.cameras, &nan, None), Error::NonFinite { ref what, index: 2 } if what == "lines"));
    let mut zero = lines.clone();
    zero[1] = Vector3::new(0.0, 0.0, 1.0);
    assert!(matches!(err(&scene.cameras, &zero, None), Error::Degenerate { ref what } if what.contains("lines[1]")));
    let mut cams = scene.cameras.clone();
    cams[1][(0, 0)] = f64::INFINITY;
    assert!(matches!(err(&cams, &lines, None), Error::NonFinite { index: 1, .. }));
    cams[1] = Matrix3x4::zeros();
    assert!(matches!(err(&cams, &lines, None), Error::SingularCamera { .. }));
    let bad_cov = [
        Matrix2::identity(),
        Matrix2::new(1.0, 2.0, 2.0, 1.0),
        Matrix2::identity(),
    ];
    assert!(
        matches!(err(&scene.cameras, &lines, Some(&bad_cov)), Error::Degenerate { ref what } if what.contains("covariances[1]"))
    );
    // Cameras sharing one centre: rotations about it.
    let k = Matrix3::new(800.0, 0.0, 320.0, 0.0, 800.0, 240.0, 0.0, 0.0, 1.0);
    let same: Vec<Matrix3x4<f64>> = (0..3)
        .map(|i| {
            let r = nalgebra::Rotation3::from_euler_angles(0.0, 0.05 * i as f64, 0.0).into_inner();
            let mut rt = Matrix3x4::zeros();
            rt.fixed_view_mut::<3, 3>(0, 0).copy_from(&r);
            rt.set_column(3, &(r * Vector3::new(0.0, 0.0, 5.0)));
            k * rt
        })
        .collect();
    assert!(matches!(err(&same, &lines, None), Error::Degenerate { ref what } if what.contains("centres")));
    // A line in the epipolar plane of the two views (parallel to the baseline): the back-projected
    // planes coincide.
    let cams = &scene.cameras[..2];
    let baseline =
        pluecker::triangulation::testing::centre(&cams[1]) - pluecker::triangulation::testing::centre(&cams[0]);
    let a = Vector3::new(0.1, 0.2, 0.3);
    let b = a + baseline * 0.2;
    let epipolar: Vec<Vector3<f64>> = cams
        .iter()
        .map(|p| (p * a.push(1.0)).cross(&(p * b.push(1.0))))
        .collect();
    assert!(matches!(err(cams, &epipolar, None), Error::Degenerate { ref what } if what.contains("epipolar")));
    // Options.
    let mut certify = pluecker::CertifyOptions::default();
    certify.max_relative_gap = -1.0;
    let mut bad = o.clone();
    bad.certify = certify;
    assert!(matches!(
        triangulate_line(&scene.cameras, LineObservations::Lines(&lines, None), &bad),
        Err(Error::InvalidOption { .. })
    ));
    // Segments: zero length, named by index.
    let mut segments = scene.segments.clone();
    segments[2][1] = segments[2][0];
    assert!(
        matches!(triangulate_line(&scene.cameras, LineObservations::Segments(&segments, 1.0), &o), Err(Error::Degenerate { ref what }) if what.contains("lines[2]"))
    );
}

/// Cameras 1e13 units from the world origin (baselines of 1e4): the line they see is "at infinity"
/// for the world-frame Plücker coordinates (its moment is 1e13 times its direction). `local`
/// reports that as a degenerate configuration; `optimal` used to panic in its frame (issue 10).
#[test]
fn a_line_far_from_the_origin_is_the_same_error_for_optimal_as_for_local() {
    let k = Matrix3::new(800.0, 0.0, 320.0, 0.0, 800.0, 240.0, 0.0, 0.0, 1.0);
    let offset = Vector3::new(1e13, 0.0, 0.0);
    let cameras: Vec<Matrix3x4<f64>> = [0.0, 1e4, 2e4]
        .iter()
        .map(|x| {
            let mut rt = Matrix3x4::identity();
            rt.set_column(3, &-(offset + Vector3::new(*x, 0.0, 0.0)));
            k * rt
        })
        .collect();
    let (a, b) = (
        offset + Vector3::new(0.0, 0.0, 5e4),
        offset + Vector3::new(1e4, 1e4, 6e4),
    );
    let project = |p: &Matrix3x4<f64>, x: &Vector3<f64>| p * x.push(1.0);
    let lines: Vec<Vector3<f64>> = cameras
        .iter()
        .zip([0.5, -0.3, 0.2])
        .map(|(p, shift)| {
            let l = project(p, &a).cross(&project(p, &b));
            let l = l / l.xy().norm();
            l + Vector3::new(0.0, 0.0, shift)
        })
        .collect();
    for method in [Method::Local, Method::Optimal] {
        let err = triangulate_line(&cameras, LineObservations::Lines(&lines, None), &opts(method)).unwrap_err();
        assert!(matches!(err, Error::Degenerate { .. }), "{method:?}: {err}");
    }
}

/// The line batch (`triangulation::line::batch`): every track's result equals the single call's on its
/// visible views, bit for bit; a bad track is an error naming it and never loses the others; whole-call errors.
mod batch {
    use super::common::{mask, noisy_segments, seen, segment, segment_tracks};
    use nalgebra::{Matrix2, Matrix3x4, Vector2, Vector3};
    use pluecker::rng::Rng;
    use pluecker::triangulation::line::{lines_from_segments, triangulate_line, LineObservations, LineTriangulation};
    use pluecker::triangulation::line::{triangulate_lines, DenseLineTracks, ImageLines};
    use pluecker::triangulation::scenes::arc_cameras;
    use pluecker::triangulation::TrackCameras;
    use pluecker::triangulation::{Method, Status, TriangulationOptions};
    use pluecker::Error;
    use std::sync::atomic::{AtomicUsize, Ordering};

    fn opts(method: Method) -> TriangulationOptions {
        // A node cap keeps branch and bound short; equality with the single call holds at any cap.
        let mut options = TriangulationOptions::default();
        options.method = method;
        options.certify.max_nodes = Some(40);
        options
    }

    /// A result with its wall time zeroed: the one field a batch and a single call may not share.
    fn untimed_line(mut r: LineTriangulation) -> LineTriangulation {
        r.report.time_seconds = 0.0;
        r
    }

    #[test]
    fn line_batch_equals_single_calls_for_every_input_form() {
        let mut rng = Rng::new(11);
        let (n, v) = (6, 5);
        let cameras = arc_cameras(v, 0.8, &mut rng);
        let endpoints = noisy_segments(&cameras, n, 1.0, &mut rng);
        let visible = mask(n, v, 2, &mut rng);
        let segments_of = |t: usize| -> Vec<[Vector2<f64>; 2]> {
            seen(&visible, v, t)
                .iter()
                .map(|&j| segment(&endpoints, v, t, j))
                .collect()
        };
        let cams_of = |t: usize| -> Vec<Matrix3x4<f64>> { seen(&visible, v, t).iter().map(|&j| cameras[j]).collect() };

        // Segments with endpoint noise, every method.
        for method in Method::ALL.iter().copied() {
            let tracks = DenseLineTracks {
                lines: ImageLines::Segments {
                    endpoints: &endpoints,
                    sigma: 1.5,
                },
                visible: Some(&visible),
                covariances: None,
            };
            let batch = triangulate_lines(&cameras, tracks, &opts(method), None).unwrap();
            assert_eq!(batch.len(), n);
            for (t, r) in batch.into_iter().enumerate() {
                let single = triangulate_line(
                    &cams_of(t),
                    LineObservations::Segments(&segments_of(t), 1.5),
                    &opts(method),
                )
                .unwrap();
                assert_eq!(
                    untimed_line(r.unwrap()),
                    untimed_line(single),
                    "{} track {t}",
                    method.as_str()
                );
            }
        }

        // Homogeneous lines with covariances (a skewed one per observation), and segments whose
        // covariances are given: both replace the endpoint noise.
        let mut lines = Vec::new();
        let mut covariances = Vec::new();
        for k in 0..n * v {
            let s = segment(&endpoints, v, k / v, k % v);
            lines.extend(s[0].push(1.0).cross(&s[1].push(1.0)).iter());
            let a = Matrix2::new(1.0 + rng.uniform(), rng.normal(), 0.0, 1.0 + rng.uniform());
            covariances.extend((a * a.transpose()).transpose().iter());
        }
        let covs_of = |t: usize| -> Vec<Matrix2<f64>> {
            seen(&visible, v, t)
                .iter()
                .map(|&j| Matrix2::from_row_slice(&covariances[4 * (t * v + j)..][..4]))
                .collect()
        };
        let homogeneous = DenseLineTracks {
            lines: ImageLines::Homogeneous(&lines),
            visible: Some(&visible),
            covariances: Some(&covariances),
        };
        let with_covariances = DenseLineTracks {
            lines: ImageLines::Segments {
                endpoints: &endpoints,
                sigma: 1.0,
            },
            ..homogeneous
        };
        for tracks in [homogeneous, with_covariances] {
            let batch = triangulate_lines(&cameras, tracks, &opts(Method::Local), None).unwrap();
            for (t, r) in batch.into_iter().enumerate() {
                let (image, _) = lines_from_segments(&segments_of(t), 1.0).unwrap();
                let single = triangulate_line(
                    &cams_of(t),
                    LineObservations::Lines(&image, Some(&covs_of(t))),
                    &opts(Method::Local),
                )
                .unwrap();
                let r = untimed_line(r.unwrap());
                // The homogeneous lines are the segments' lines up to scale and sign, which the residual
                // ignores (section 3.1 normalises each line): the same line to rounding (Plücker
                // coordinates are homogeneous: up to sign), and the same cost (about 1 per observation; 0
                // to rounding for a track in two views, which fit any line exactly).
                let distance = (r.plucker.coordinates() - single.plucker.coordinates())
                    .norm()
                    .min((r.plucker.coordinates() + single.plucker.coordinates()).norm());
                assert!(distance < 1e-9, "track {t}: {distance}");
                let tolerance = 1e-9 * single.report.cost + 1e-12;
                assert!((r.report.cost - single.report.cost).abs() <= tolerance, "track {t}");
            }
        }
    }

    #[test]
    fn line_batch_with_cameras_per_track_and_progress() {
        let mut rng = Rng::new(12);
        let (n, v) = (4, 3);
        let mut cameras = Vec::new();
        let mut endpoints = Vec::new();
        for _ in 0..n {
            let own = arc_cameras(v, 0.6, &mut rng);
            endpoints.extend(noisy_segments(&own, 1, 1.0, &mut rng));
            cameras.extend(own);
        }
        let tracks = segment_tracks(&endpoints, 1.0);
        let done = AtomicUsize::new(0);
        let per_track = TrackCameras::PerTrack {
            projections: &cameras,
            views: v,
        };
        let batch = triangulate_lines(per_track, tracks, &opts(Method::Local), Some(&done)).unwrap();
        assert_eq!(done.load(Ordering::Relaxed), n);
        for (t, r) in batch.into_iter().enumerate() {
            let segments: Vec<[Vector2<f64>; 2]> = (0..v).map(|j| segment(&endpoints, v, t, j)).collect();
            let single = triangulate_line(
                &cameras[t * v..(t + 1) * v],
                LineObservations::Segments(&segments, 1.0),
                &opts(Method::Local),
            )
            .unwrap();
            assert_eq!(untimed_line(r.unwrap()), untimed_line(single), "track {t}");
        }
        // A singular camera of one track is that track's error, named by track and view.
        let mut bad = cameras.clone();
        bad[2 * v + 1] = Matrix3x4::zeros();
        let per_track = TrackCameras::PerTrack {
            projections: &bad,
            views: v,
        };
        let batch = triangulate_lines(per_track, tracks, &opts(Method::Linear), None).unwrap();
        assert!(matches!(&batch[2], Err(Error::SingularCamera { what }) if what.starts_with("cameras[2][1]")));
        assert!(batch.iter().enumerate().all(|(t, r)| r.is_ok() == (t != 2)));
    }

    #[test]
    fn a_bad_line_track_is_its_own_error_and_never_loses_the_others() {
        let mut rng = Rng::new(13);
        let (n, v) = (8, 4);
        let cameras = arc_cameras(v, 0.8, &mut rng);
        let endpoints = noisy_segments(&cameras, n, 1.0, &mut rng);
        let mut lines: Vec<f64> = (0..n * v)
            .flat_map(|k| {
                let s = segment(&endpoints, v, k / v, k % v);
                s[0].push(1.0)
                    .cross(&s[1].push(1.0))
                    .iter()
                    .copied()
                    .collect::<Vec<_>>()
            })
            .collect();
        let mut visible = vec![true; n * v];
        let mut covariances: Vec<f64> = (0..n * v).flat_map(|_| [1.0, 0.0, 0.0, 1.0]).collect();
        // Track 1: NaN in visible view 2. Track 2: NaN in a view it is not seen in (fine).
        lines[3 * (v + 2)] = f64::NAN;
        lines[3 * (2 * v + 3) + 1] = f64::NAN;
        visible[2 * v + 3] = false;
        // Track 3: one visible view.
        for j in 1..v {
            visible[3 * v + j] = false;
        }
        // Track 4: the line at infinity (zero normal) in view 1.
        lines[3 * (4 * v + 1)..3 * (4 * v + 1) + 3].copy_from_slice(&[0.0, 0.0, 1.0]);
        // Track 5: a covariance that is not positive definite in view 3.
        covariances[4 * (5 * v + 3)..4 * (5 * v + 3) + 4].copy_from_slice(&[1.0, 2.0, 2.0, 1.0]);
        // Track 6: seen by views 0 and 1 only, the 3-D line parallel to their baseline: it lies in an
        // epipolar plane of the pair, both back-projected planes are that plane.
        let (c0, c1) = (centre(&cameras[0]), centre(&cameras[1]));
        let a = (c0 + c1) / 2.0 + (c1 - c0).cross(&Vector3::y()).normalize() * 4.0;
        let b = a + (c1 - c0);
        for j in 0..v {
            visible[6 * v + j] = j < 2;
            let l = (cameras[j] * a.push(1.0)).cross(&(cameras[j] * b.push(1.0)));
            lines[3 * (6 * v + j)..3 * (6 * v + j) + 3].copy_from_slice(l.as_slice());
        }
        let tracks = DenseLineTracks {
            lines: ImageLines::Homogeneous(&lines),
            visible: Some(&visible),
            covariances: Some(&covariances),
        };
        let batch = triangulate_lines(&cameras, tracks, &opts(Method::Local), None).unwrap();
        assert!(matches!(&batch[1], Err(Error::NonFinite { what, index: 2 }) if what == "lines[1]"));
        assert!(
            matches!(&batch[3], Err(Error::TooFewCorrespondences { actual, .. }) if actual == "track 3: 1 view(s)")
        );
        assert!(
            matches!(&batch[4], Err(Error::Degenerate { what }) if what.starts_with("lines[4][1] has a zero normal"))
        );
        assert!(
            matches!(&batch[5], Err(Error::Degenerate { what }) if what == "covariances[5][3] is not positive definite")
        );
        assert!(
            matches!(&batch[6], Err(Error::Degenerate { what }) if what.starts_with("lines[6]: the back-projected planes coincide")),
            "{:?}",
            batch[6]
        );
        for t in [0, 2, 7] {
            let r = batch[t].as_ref().unwrap();
            assert_eq!(r.report.status, Status::Success, "track {t}");
            let views = seen(&visible, v, t);
            let cams: Vec<Matrix3x4<f64>> = views.iter().map(|&j| cameras[j]).collect();
            let image: Vec<Vector3<f64>> = views
                .iter()
                .map(|&j| Vector3::from_row_slice(&lines[3 * (t * v + j)..][..3]))
                .collect();
            let covs = vec![Matrix2::identity(); views.len()];
            let single = triangulate_line(
                &cams,
                LineObservations::Lines(&image, Some(&covs)),
                &opts(Method::Local),
            )
            .unwrap();
            assert_eq!(untimed_line(r.clone()), untimed_line(single), "track {t}");
        }

        // Segments: NaN and a zero-length segment name the segment.
        let mut endpoints = endpoints.clone();
        endpoints[4 * (2 * v + 1) + 3] = f64::INFINITY;
        let p = &endpoints[4 * 5 * v..][..2].to_vec();
        endpoints[4 * 5 * v + 2..4 * 5 * v + 4].copy_from_slice(p);
        let tracks = segment_tracks(&endpoints, 1.0);
        let batch = triangulate_lines(&cameras, tracks, &opts(Method::Linear), None).unwrap();
        assert!(matches!(&batch[2], Err(Error::NonFinite { what, index: 1 }) if what == "lines[2]"));
        assert!(matches!(&batch[5], Err(Error::Degenerate { what }) if what == "lines[5][0] has zero length"));
        assert_eq!(batch.iter().filter(|r| r.is_ok()).count(), n - 2);
    }

    fn centre(p: &Matrix3x4<f64>) -> Vector3<f64> {
        let m = p.fixed_view::<3, 3>(0, 0).into_owned();
        -(m.try_inverse().unwrap() * p.column(3))
    }

    #[test]
    fn line_batch_whole_call_errors() {
        let mut rng = Rng::new(14);
        let cameras = arc_cameras(3, 0.8, &mut rng);
        let endpoints = noisy_segments(&cameras, 2, 1.0, &mut rng);
        let shared = &cameras;
        let o = opts(Method::Linear);
        let run = |tracks: &DenseLineTracks, o: &TriangulationOptions| {
            triangulate_lines(shared, tracks, o, None).unwrap_err()
        };
        let tracks = |sigma| DenseLineTracks {
            lines: ImageLines::Segments {
                endpoints: &endpoints,
                sigma,
            },
            visible: None,
            covariances: None,
        };
        assert!(matches!(run(&tracks(0.0), &o), Error::InvalidOption { name, .. } if name == "sigma"));
        assert!(matches!(run(&tracks(f64::NAN), &o), Error::InvalidOption { name, .. } if name == "sigma"));
        let mut certify = pluecker::CertifyOptions::default();
        certify.max_nodes = Some(0);
        let mut bad = o.clone();
        bad.certify = certify;
        assert!(matches!(run(&tracks(1.0), &bad), Error::InvalidOption { name, .. } if name == "certify.max_nodes"));
        let short = DenseLineTracks {
            lines: ImageLines::Homogeneous(&endpoints[..8]),
            ..tracks(1.0)
        };
        assert!(matches!(run(&short, &o), Error::Shape { what, .. } if what == "lines"));
        let flags = [true; 5];
        let masked = DenseLineTracks {
            visible: Some(&flags),
            ..tracks(1.0)
        };
        assert!(matches!(run(&masked, &o), Error::Shape { what, .. } if what == "visible"));
        let covs = [1.0; 8];
        let covariances = DenseLineTracks {
            covariances: Some(&covs),
            ..tracks(1.0)
        };
        assert!(matches!(run(&covariances, &o), Error::Shape { what, .. } if what == "covariances"));
        let mut singular = cameras.clone();
        singular[1][(0, 0)] = f64::NAN;
        assert!(matches!(
            triangulate_lines(&singular, tracks(1.0), &o, None),
            Err(Error::NonFinite { what, index: 1 }) if what == "cameras"
        ));
        let per_track = TrackCameras::PerTrack {
            projections: &cameras,
            views: 3,
        };
        assert!(matches!(
            triangulate_lines(per_track, tracks(1.0), &o, None),
            Err(Error::Shape { what, .. }) if what == "cameras"
        ));
        let empty = DenseLineTracks {
            lines: ImageLines::Homogeneous(&[]),
            ..tracks(1.0)
        };
        assert!(triangulate_lines(shared, empty, &o, None).unwrap().is_empty());
    }
}

#[test]
fn sparse_line_tracks_equal_the_dense_batch() {
    use pluecker::triangulation::line::{triangulate_lines, SparseLineTracks};
    use pluecker::triangulation::Csr;
    // Three views, four tracks seen in all of them; the sparse form lists the same rows track by track.
    let mut rng = pluecker::rng::Rng::new(21);
    let scene = pluecker::synthetic::triangulation_scene(3, 0.6, 21);
    let cameras = scene.cameras.clone();
    let mut endpoints = Vec::new();
    for _ in 0..4 {
        let a = scene.point + nalgebra::Vector3::new(rng.normal(), rng.normal(), rng.normal()) * 0.3;
        let b = scene.point + nalgebra::Vector3::new(rng.normal(), rng.normal(), rng.normal()) * 0.3;
        for p in &cameras {
            for x in [a, b] {
                let h = p * x.push(1.0);
                endpoints.extend([h.x / h.z + 0.5 * rng.normal(), h.y / h.z + 0.5 * rng.normal()]);
            }
        }
    }
    let opts = pluecker::triangulation::TriangulationOptions::default();
    let dense = pluecker::triangulation::line::triangulate_lines(
        &cameras,
        pluecker::triangulation::line::DenseLineTracks {
            lines: pluecker::triangulation::line::ImageLines::Segments {
                endpoints: &endpoints,
                sigma: 1.0,
            },
            visible: None,
            covariances: None,
        },
        &opts,
        None,
    )
    .unwrap();
    let offsets = [0, 3, 6, 9, 12];
    let images: Vec<usize> = (0..4).flat_map(|_| 0..3).collect();
    let sparse = triangulate_lines(
        &cameras,
        SparseLineTracks {
            csr: Csr {
                offsets: &offsets,
                image: &images,
            },
            lines: pluecker::triangulation::line::ImageLines::Segments {
                endpoints: &endpoints,
                sigma: 1.0,
            },
            covariances: None,
        },
        &opts,
        None,
    )
    .unwrap();
    for (t, (d, s)) in dense.into_iter().zip(sparse).enumerate() {
        let (mut d, mut s) = (d.unwrap(), s.unwrap());
        (d.report.time_seconds, s.report.time_seconds) = (0.0, 0.0);
        assert_eq!(d, s, "track {t}");
    }
}
