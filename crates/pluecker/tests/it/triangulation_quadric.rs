//! Quadric triangulation (Josephson & Kahl 2008, sections 2.3, 3, 4): exact recovery (also of a flat
//! quadric, the paper's real-data case), cost ordering and certificates, the soundness of the bound,
//! cheirality and bad input.

use crate::common::{self, outlines};

use nalgebra::{Matrix3, Matrix3x4, Matrix4, Rotation3, Vector3};
use pluecker::geometry::{project_dual, Ellipse, Ellipsoid};
use pluecker::rng::Rng;
use pluecker::triangulation::fitting::fit_conic;
use pluecker::triangulation::quadric::{triangulate_quadric, Matrix5, QuadricObservations};
use pluecker::triangulation::scenes::quadric_scene;
use pluecker::triangulation::testing::quadric_convexity_bound;
use pluecker::triangulation::{CertificateKind, Method, QuadricBound, Status, TriangulationOptions};
use pluecker::Error;

fn opts(method: Method) -> TriangulationOptions {
    let mut options = TriangulationOptions::default();
    options.method = method;
    options.certify.max_nodes = Some(200);
    options
}

#[test]
fn noise_free_ellipsoids_are_recovered_by_every_method() {
    for (views, seed) in [(3, 1u64), (5, 2)] {
        let scene = quadric_scene(views, 0.8, seed);
        let conics = outlines(&scene.cameras, &scene.ellipsoid);
        for method in Method::ALL.iter().copied() {
            let r = triangulate_quadric(
                &scene.cameras,
                QuadricObservations::Conics(&conics, None),
                &opts(method),
            )
            .unwrap();
            let e = &scene.ellipsoid;
            assert!(
                (r.centre - e.centre).norm() < 1e-7,
                "{} {}",
                method.as_str(),
                (r.centre - e.centre).norm()
            );
            assert!(
                (r.semi_axes - e.semi_axes).norm() < 1e-7,
                "{} {:?}",
                method.as_str(),
                r.semi_axes
            );
            for k in 0..3 {
                assert!((r.axes.column(k).dot(&e.axes.column(k)).abs() - 1.0).abs() < 1e-6);
            }
            assert!(
                r.report.cost < 1e-12 && r.report.status == Status::Success,
                "{:?}",
                r.report
            );
            assert!((r.dual[(3, 3)] + 1.0).abs() < 1e-12);
            assert!((r.primal.unwrap() * r.dual - Matrix4::identity()).norm() < 1e-6);
        }
    }
}

#[test]
fn a_disc_is_recovered_as_a_flat_ellipsoid() {
    // The paper's real conics are planar (section 5.1): a disc of radii 0.4 and 0.25.
    let scene = quadric_scene(4, 0.8, 3);
    let disc = Ellipsoid {
        centre: Vector3::new(0.05, -0.1, 0.0),
        axes: Rotation3::new(Vector3::new(0.4, -0.3, 0.2)).into_inner(),
        semi_axes: Vector3::new(0.4, 0.25, 0.0),
    };
    let conics = outlines(&scene.cameras, &disc);
    for method in [Method::Linear, Method::Local] {
        let r = triangulate_quadric(
            &scene.cameras,
            QuadricObservations::Conics(&conics, None),
            &opts(method),
        )
        .unwrap();
        assert!((r.centre - disc.centre).norm() < 1e-6, "{}", method.as_str());
        assert!(
            (r.semi_axes.xy() - disc.semi_axes.xy()).norm() < 1e-6 && r.semi_axes.z < 1e-4,
            "{:?}",
            r.semi_axes
        );
        assert!(r.report.cost < 1e-9, "{:?}", r.report);
    }
}

#[test]
fn noisy_ellipsoids_are_certified_and_costs_ordered() {
    for seed in 0..5u64 {
        let views = 3 + seed as usize;
        let scene = quadric_scene(views, 0.8, 10 + seed);
        let mut rng = Rng::new(20 + seed);
        let points = scene.noisy_outline_points(63, 1.0, &mut rng);
        let run =
            |m| triangulate_quadric(&scene.cameras, QuadricObservations::EdgePoints(&points, 1.0), &opts(m)).unwrap();
        let (linear, local, optimal) = (run(Method::Linear), run(Method::Local), run(Method::Optimal));
        let tol = 1e-9 * (1.0 + linear.report.cost);
        assert!(local.report.cost <= linear.report.cost + tol, "seed {seed}");
        assert!(optimal.report.cost <= local.report.cost + tol, "seed {seed}");
        let c = optimal.report.certificate.expect("a search ran");
        assert_eq!(c.kind, CertificateKind::ConvexityTest, "seed {seed}");
        assert!(c.certified, "seed {seed}: {:?}", optimal.report);
        assert_eq!(optimal.report.status, Status::Success);
        // The estimate fits at least as well as the truth.
        let fits: Vec<_> = points.iter().map(|p| fit_conic(p, 1.0).unwrap()).collect();
        let conics: Vec<Matrix3<f64>> = fits.iter().map(|f| f.conic).collect();
        let covariances: Vec<Matrix5> = fits.iter().map(|f| f.covariance).collect();
        let truth = independent_quadric_cost(&scene.cameras, &conics, &covariances, &scene.ellipsoid.dual());
        assert!(
            optimal.report.cost <= truth + tol,
            "seed {seed}: {} > {truth}",
            optimal.report.cost
        );
        let recomputed = independent_quadric_cost(&scene.cameras, &conics, &covariances, &optimal.dual);
        assert!((recomputed - optimal.report.cost).abs() < 1e-7 * (1.0 + recomputed));
        // The raw bound below the independent cost of the answer (to the 1e-7 of its recomputation)
        // and of the truth, and the gap recomputed from them closed.
        assert!(
            c.raw_lower_bound <= recomputed * (1.0 + 1e-7),
            "seed {seed}: {c:?} above {recomputed}"
        );
        assert!(
            c.raw_lower_bound <= truth * (1.0 + 1e-7),
            "seed {seed}: {c:?} above the truth's {truth}"
        );
        let gap = (recomputed - c.raw_lower_bound.min(recomputed)) / recomputed;
        assert!(gap <= 1e-3 * (1.0 + 1e-4), "seed {seed}: gap {gap}, {c:?}");
    }
}

/// A regime of the soundness test: the scene and the covariances of its fitted conics.
struct Regime {
    name: &'static str,
    spread: f64,
    /// `Some(tilt)`: the ellipsoid made a disc whose normal is `tilt` radians from the arc's axis.
    disc_tilt: Option<f64>,
    /// Per-entry standard-deviation factors applied to the fitted covariances.
    anisotropy: [f64; 5],
    bound: QuadricBound,
}

/// The scene of a regime: `None` when an outline is not an ellipse at least 8 px across.
fn regime_scene(regime: &Regime, seed: u64) -> Option<pluecker::triangulation::scenes::QuadricScene> {
    let mut scene = quadric_scene(4, regime.spread, seed);
    if let Some(tilt) = regime.disc_tilt {
        let mut rng = Rng::new(seed + 7);
        // The normal −z (towards the cameras) turned by `tilt` about a random axis in the xy plane.
        let about = Vector3::new(rng.normal(), rng.normal(), 0.0).normalize();
        let normal = Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(about), tilt) * -Vector3::z();
        let first = normal.cross(&rng.unit_vector3()).normalize();
        let axes = Matrix3::from_columns(&[first, normal.cross(&first), normal]);
        scene.ellipsoid = Ellipsoid {
            centre: scene.ellipsoid.centre,
            axes,
            semi_axes: Vector3::new(rng.uniform_in(0.3, 0.5), rng.uniform_in(0.15, 0.3), 0.0),
        };
        scene.outlines = scene
            .cameras
            .iter()
            .map(|p| Ellipse::from_primal(&project_dual(p, &scene.ellipsoid.dual()).try_inverse()?))
            .collect::<Option<Vec<_>>>()?;
    }
    scene.outlines.iter().all(|e| e.semi_axes.y > 8.0).then_some(scene)
}

#[test]
fn no_ellipsoid_anywhere_costs_less_than_the_certified_bound() {
    // The bound of every certified ellipsoid against ellipsoids from the whole domain of the
    // certificate (every ellipsoid, flat ones included, that no camera's principal plane cuts, in front
    // of the cameras or behind them), not only near the answer: 20000 random ones (centres in a box 16
    // units wide around the scene and the cameras, random axes, semi-axes 0.01-3, a third of them
    // flat), 1000 small ones near each camera centre, a random descent from the 30 cheapest (many
    // starts, flat ones reachable), and the answer moved by 1e-1 to 1e-5 (flattened too). The cost is
    // recomputed without the library's quadric code. Six regimes: ellipsoids at 46° and 3° of
    // parallax, discs at 46° and 3°, discs seen up to 83° from their normal (nearly edge-on), and
    // anisotropic covariances (entry standard deviations scaled by 3 to 0.3); and the paper's relaxation
    // on the first (every sample lies inside its a-priori box).
    let regimes = [
        Regime {
            name: "ellipsoid, 46°",
            spread: 0.8,
            disc_tilt: None,
            anisotropy: [1.0; 5],
            bound: QuadricBound::Convexity,
        },
        Regime {
            name: "ellipsoid, 3°",
            spread: 0.05,
            disc_tilt: None,
            anisotropy: [1.0; 5],
            bound: QuadricBound::Convexity,
        },
        Regime {
            name: "disc, 46°",
            spread: 0.8,
            disc_tilt: Some(0.4),
            anisotropy: [1.0; 5],
            bound: QuadricBound::Convexity,
        },
        Regime {
            name: "disc, 3°",
            spread: 0.05,
            disc_tilt: Some(0.4),
            anisotropy: [1.0; 5],
            bound: QuadricBound::Convexity,
        },
        Regime {
            name: "disc nearly edge-on",
            spread: 0.8,
            disc_tilt: Some(1.05),
            anisotropy: [1.0; 5],
            bound: QuadricBound::Convexity,
        },
        Regime {
            name: "anisotropic",
            spread: 0.8,
            disc_tilt: Some(0.4),
            anisotropy: [3.0, 1.0, 0.3, 2.0, 0.5],
            bound: QuadricBound::Convexity,
        },
        Regime {
            name: "ellipsoid, 46°, relaxation",
            spread: 0.8,
            disc_tilt: None,
            anisotropy: [1.0; 5],
            bound: QuadricBound::Relaxation,
        },
    ];
    let (mut checked, mut tried, mut violations) = (0, 0, 0);
    for regime in &regimes {
        let mut regime_opts = opts(Method::Optimal);
        regime_opts.quadric_bound = regime.bound;
        let mut certified_here = 0;
        for seed in 0..5u64 {
            let Some(scene) = regime_scene(regime, 30 + seed) else {
                continue;
            };
            tried += 1;
            let mut rng = Rng::new(seed + 1);
            let points = scene.noisy_outline_points(63, 1.0, &mut rng);
            let fits: Vec<_> = points.iter().map(|p| fit_conic(p, 1.0).unwrap()).collect();
            let conics: Vec<Matrix3<f64>> = fits.iter().map(|f| f.conic).collect();
            let scale = Matrix5::from_diagonal(&nalgebra::SVector::<f64, 5>::from(regime.anisotropy));
            let covariances: Vec<Matrix5> = fits.iter().map(|f| scale * f.covariance * scale).collect();
            let optimal = triangulate_quadric(
                &scene.cameras,
                QuadricObservations::Conics(&conics, Some(&covariances)),
                &regime_opts,
            )
            .unwrap();
            let c = optimal.report.certificate.expect("a search ran");
            if !c.certified {
                continue;
            }
            certified_here += 1;
            if regime.bound == QuadricBound::Relaxation {
                // The relaxation alone: never the convexity test's certificate.
                assert_eq!(c.kind, CertificateKind::BranchAndBound, "{} seed {seed}", regime.name);
            }
            let found = search_below(
                &scene.cameras,
                &conics,
                &covariances,
                &optimal,
                c.raw_lower_bound,
                &mut rng,
                &mut violations,
            );
            let slack = 1e-9 * (1.0 + optimal.report.cost);
            assert!(
                found >= optimal.report.cost * (1.0 - 1e-3) - slack,
                "{} seed {seed}: {found} < {}",
                regime.name,
                optimal.report.cost
            );
        }
        eprintln!("{}: {certified_here} certified and checked", regime.name);
        checked += certified_here;
    }
    eprintln!("{checked} of {tried} certified ellipsoids checked; {violations} violations");
    assert_eq!(violations, 0);
    // Measured: 34 of 34 (29 by the convexity test, 5 by the relaxation; a nearly edge-on seed has no
    // scene). At the target rate of 0.95, fewer than 29 of 34 happens with probability 0.006
    // (binomial); a bound that stops certifying leaves these to a node cap of 200.
    assert!(checked + 5 >= tried, "only {checked} of {tried} certified");
}

/// The convexity test's bound (its S-lemma step over the ellipsoids, `triangulation::quadric::certificate`)
/// at ellipsoids that are not the local minimum: the local answer moved by 1e-3 to 3e-2 of its size
/// (centre, axes and semi-axes; discs kept flat, some ellipsoids flattened), where the bound is below
/// the reference's cost by the decrease the minorant allows and the S-lemma constraint decides how
/// much. Against the least cost of eq. 19 recomputed without the library's quadric code over
/// ellipsoids (every one that no principal plane cuts, flat ones included): the local answer, the
/// reference, and random descents from both (signed semi-axes, so flat ones are reached).
#[test]
fn the_convexity_bound_away_from_the_local_minimum_is_below_every_ellipsoid() {
    let regimes = [
        Regime {
            name: "disc, 46°",
            spread: 0.8,
            disc_tilt: Some(0.4),
            anisotropy: [1.0; 5],
            bound: QuadricBound::Convexity,
        },
        Regime {
            name: "disc nearly edge-on",
            spread: 0.8,
            disc_tilt: Some(1.05),
            anisotropy: [1.0; 5],
            bound: QuadricBound::Convexity,
        },
        Regime {
            name: "ellipsoid, 46°",
            spread: 0.8,
            disc_tilt: None,
            anisotropy: [3.0, 1.0, 0.3, 2.0, 0.5],
            bound: QuadricBound::Convexity,
        },
    ];
    let (mut checked, mut closest) = (0, f64::INFINITY);
    for regime in &regimes {
        for seed in 0..5u64 {
            let Some(scene) = regime_scene(regime, 60 + seed) else {
                continue;
            };
            let mut rng = Rng::new(seed + 11);
            let points = scene.noisy_outline_points(63, 1.0, &mut rng);
            let fits: Vec<_> = points.iter().map(|p| fit_conic(p, 1.0).unwrap()).collect();
            let conics: Vec<Matrix3<f64>> = fits.iter().map(|f| f.conic).collect();
            let scale = Matrix5::from_diagonal(&nalgebra::SVector::<f64, 5>::from(regime.anisotropy));
            let covariances: Vec<Matrix5> = fits.iter().map(|f| scale * f.covariance * scale).collect();
            let local = triangulate_quadric(
                &scene.cameras,
                QuadricObservations::Conics(&conics, Some(&covariances)),
                &opts(Method::Local),
            )
            .unwrap();
            let cost = |x: &[f64; 9]| -> Option<f64> {
                let e = Ellipsoid {
                    centre: Vector3::new(x[0], x[1], x[2]),
                    axes: Rotation3::new(Vector3::new(x[3], x[4], x[5])).into_inner(),
                    semi_axes: Vector3::new(x[6].abs(), x[7].abs(), x[8].abs()),
                };
                let dual = e.dual();
                let missed = scene.cameras.iter().all(|p| {
                    let plane = p.row(2).transpose();
                    plane.dot(&(dual * plane)) < 0.0
                });
                missed.then(|| independent_quadric_cost(&scene.cameras, &conics, &covariances, &dual))
            };
            let rotation = Rotation3::from_matrix(&local.axes).scaled_axis();
            let (c, sa) = (local.centre, local.semi_axes);
            let at = [c.x, c.y, c.z, rotation.x, rotation.y, rotation.z, sa.x, sa.y, sa.z];
            let size = sa.max();
            for k in 0..6 {
                let move_by = [1e-3, 1e-2, 3e-2][k % 3];
                let mut x = at;
                for i in 0..3 {
                    x[i] += move_by * size * rng.normal();
                    x[3 + i] += move_by * rng.normal();
                    x[6 + i] *= 1.0 + move_by * rng.normal();
                }
                if k >= 3 {
                    x[8] = 0.0;
                }
                let reference = Ellipsoid {
                    centre: Vector3::new(x[0], x[1], x[2]),
                    axes: Rotation3::new(Vector3::new(x[3], x[4], x[5])).into_inner(),
                    semi_axes: Vector3::new(x[6].abs(), x[7].abs(), x[8].abs()),
                };
                let Some(bound) = quadric_convexity_bound(&scene.cameras, &conics, Some(&covariances), &reference)
                else {
                    continue;
                };
                let Some(at_reference) = cost(&x) else {
                    continue;
                };
                // The least cost found: the local answer, the reference, and descents from both.
                let mut least = cost(&at).expect("the local answer is in front").min(at_reference);
                for start in [at, x] {
                    let (mut best, mut y) = (cost(&start).unwrap_or(f64::INFINITY), start);
                    let mut step = move_by * size;
                    for _ in 0..1500 {
                        let trial: [f64; 9] = std::array::from_fn(|i| y[i] + step * rng.normal());
                        match cost(&trial) {
                            Some(v) if v < best => (best, y) = (v, trial),
                            _ => step *= 0.995,
                        }
                    }
                    least = least.min(best);
                }
                // Rounding of the two costs: ~1e-12 of their size.
                assert!(
                    bound <= least * (1.0 + 1e-9),
                    "{} seed {seed}, move {move_by}: bound {bound} above an ellipsoid's cost {least} \
                     (the reference's {at_reference})",
                    regime.name
                );
                closest = closest.min((least - bound) / (at_reference - least).max(1e-12 * least));
                checked += 1;
            }
        }
    }
    eprintln!("{checked} bounds checked; the least gap to the cheapest ellipsoid {closest:.3}x the reference's excess");
    assert!(checked >= 30, "only {checked} references had a bound");
}

/// The least cost found over the certificate's domain (see the test above); every cost below `bound`
/// (less a rounding slack) counts as a violation.
fn search_below(
    cameras: &[Matrix3x4<f64>],
    conics: &[Matrix3<f64>],
    covariances: &[Matrix5],
    optimal: &pluecker::triangulation::quadric::QuadricTriangulation,
    bound: f64,
    rng: &mut Rng,
    violations: &mut usize,
) -> f64 {
    // (centre, rotation vector, signed semi-axes) → cost, when no principal plane cuts the ellipsoid
    // (πᵀ Q* π < 0 for the dual Q* normalised to Q*₄₄ = −1).
    let cost = |x: &[f64; 9]| -> Option<f64> {
        let e = Ellipsoid {
            centre: Vector3::new(x[0], x[1], x[2]),
            axes: Rotation3::new(Vector3::new(x[3], x[4], x[5])).into_inner(),
            semi_axes: Vector3::new(x[6].abs(), x[7].abs(), x[8].abs()),
        };
        let dual = e.dual();
        let missed = cameras.iter().all(|p| {
            let plane = p.row(2).transpose();
            plane.dot(&(dual * plane)) < 0.0
        });
        missed.then(|| independent_quadric_cost(cameras, conics, covariances, &dual))
    };
    let random = |centre: Vector3<f64>, reach: f64, largest: f64, rng: &mut Rng| -> [f64; 9] {
        let flat = rng.uniform_in(0.0, 1.0) < 1.0 / 3.0;
        std::array::from_fn(|k| match k {
            0..=2 => centre[k] + rng.uniform_in(-reach, reach),
            3..=5 => rng.uniform_in(-3.2, 3.2),
            8 if flat => 0.0,
            _ => largest * 10f64.powf(rng.uniform_in(-2.0, 0.0)),
        })
    };
    let mut candidates: Vec<(f64, [f64; 9])> = Vec::new();
    while candidates.len() < 20_000 {
        let x = random(Vector3::zeros(), 8.0, 3.0, rng);
        candidates.extend(cost(&x).map(|v| (v, x)));
    }
    for p in cameras {
        let centre = pluecker::triangulation::testing::centre(p);
        let mut added = 0;
        while added < 1000 {
            let x = random(centre, 2.0, 0.5, rng);
            if let Some(v) = cost(&x) {
                candidates.push((v, x));
                added += 1;
            }
        }
    }
    candidates.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut costs: Vec<f64> = candidates.iter().map(|c| c.0).collect();
    for &(mut best, mut x) in candidates.iter().take(30) {
        let mut step = 0.3;
        for _ in 0..500 {
            let y: [f64; 9] = std::array::from_fn(|k| x[k] + step * rng.normal());
            match cost(&y) {
                Some(v) if v < best => (best, x) = (v, y),
                _ => step *= 0.99,
            }
        }
        costs.push(best);
    }
    // The independent cost agrees with the reported one at the answer.
    let at_answer = independent_quadric_cost(cameras, conics, covariances, &optimal.dual);
    assert!(
        (at_answer - optimal.report.cost).abs() <= 1e-8 * (1.0 + at_answer),
        "{at_answer} vs {}",
        optimal.report.cost
    );
    let rotation = Rotation3::from_matrix(&optimal.axes).scaled_axis();
    let (c, s) = (optimal.centre, optimal.semi_axes);
    let at = [c.x, c.y, c.z, rotation.x, rotation.y, rotation.z, s.x, s.y, s.z];
    for k in 0..1000 {
        let scale = 10f64.powi(-(k % 5) - 1);
        let mut y: [f64; 9] = std::array::from_fn(|i| at[i] + scale * rng.normal());
        if k % 2 == 0 {
            y[8] = 0.0;
        }
        costs.extend(cost(&y));
    }
    let slack = 1e-9 * (1.0 + optimal.report.cost);
    *violations += costs.iter().filter(|&&v| v < bound - slack).count();
    costs.iter().copied().fold(f64::INFINITY, f64::min)
}

/// Eq. 19 at a world dual quadric without the library's quadric code: the image dual conic `P Q* Pᵀ`
/// and the observed one `c⁻¹`, both moved to the observed ellipse's centre `x₀ = (l̂₁₃, l̂₂₃)/l̂₃₃`
/// (`T l Tᵀ` with `T = [I −x₀; 0 1]`), the residual `v(T l Tᵀ) − v(T l̂ Tᵀ)` with
/// `v(e) = (e₁₁, e₁₂, e₂₂, e₁₃, e₂₃)/e₃₃` (section 3.1), and its Mahalanobis norm (eq. 18).
fn independent_quadric_cost(
    cameras: &[Matrix3x4<f64>],
    conics: &[Matrix3<f64>],
    covariances: &[Matrix5],
    dual: &Matrix4<f64>,
) -> f64 {
    let v = |e: &Matrix3<f64>| {
        nalgebra::SVector::<f64, 5>::from_column_slice(&[e[(0, 0)], e[(0, 1)], e[(1, 1)], e[(0, 2)], e[(1, 2)]])
            / e[(2, 2)]
    };
    let mut total = 0.0;
    for ((p, c), cov) in cameras.iter().zip(conics).zip(covariances) {
        let observed = c.try_inverse().unwrap();
        let (x0, y0) = (observed[(0, 2)] / observed[(2, 2)], observed[(1, 2)] / observed[(2, 2)]);
        let t = Matrix3::new(1.0, 0.0, -x0, 0.0, 1.0, -y0, 0.0, 0.0, 1.0);
        let projected = p * dual * p.transpose();
        let r = v(&(t * projected * t.transpose())) - v(&(t * observed * t.transpose()));
        total += r.dot(&(cov.try_inverse().unwrap() * r));
    }
    total
}

#[test]
fn branch_and_bound_reports_its_work() {
    // The first 3-view scene with 15 px of outline noise whose local ellipsoid the convexity test
    // cannot certify:
    let fitted = |scene: &pluecker::triangulation::scenes::QuadricScene, seed: u64| {
        let points = scene.noisy_outline_points(63, 15.0, &mut Rng::new(seed));
        let fits: Option<Vec<_>> = points.iter().map(|p| fit_conic(p, 15.0).ok()).collect();
        fits.map(|f| {
            (
                f.iter().map(|f| f.conic).collect::<Vec<_>>(),
                f.iter().map(|f| f.covariance).collect::<Vec<_>>(),
            )
        })
    };
    let hard = (0..60u64).find_map(|seed| {
        let scene = quadric_scene(3, 0.8, 40 + seed);
        let (conics, covariances) = fitted(&scene, seed)?;
        let r = triangulate_quadric(
            &scene.cameras,
            QuadricObservations::Conics(&conics, Some(&covariances)),
            &opts(Method::Optimal),
        )
        .ok()?;
        (r.report.certificate.map(|c| c.kind) == Some(CertificateKind::BranchAndBound)).then_some((
            scene,
            conics,
            covariances,
        ))
    });
    let (scene, conics, covariances) = hard.expect("some 3-view scene at 15 px needs branch and bound");
    // The search's work as reported: each node solves at least one conic program (≥ 1 interior-point
    // iteration), and no program takes more than clarabel's 200 iterations; the root's bound
    // tightening adds at most 2 passes of 2 solves per each of the 9 entries of the dual's upper block.
    let searched = triangulate_quadric(
        &scene.cameras,
        QuadricObservations::Conics(&conics, Some(&covariances)),
        &opts(Method::Optimal),
    )
    .unwrap();
    let c = searched.report.certificate.expect("a search ran");
    assert!(c.nodes >= 1 && c.solver_iterations >= c.nodes, "{c:?}");
    assert!(c.solver_iterations <= 200 * (4 * c.nodes + 36), "{c:?}");
}

#[test]
fn an_ellipsoid_behind_a_camera_is_reported() {
    // Camera 0 turned to look away from the ellipsoid (same centre, rotated by π about its y axis):
    // the outline equations (eq. 12) still hold, but the estimate lies behind that camera.
    let scene = quadric_scene(4, 0.8, 50);
    let mut cameras = scene.cameras.clone();
    let turn = Rotation3::from_axis_angle(&Vector3::y_axis(), std::f64::consts::PI).into_inner();
    let k = Matrix3::new(800.0, 0.0, 320.0, 0.0, 800.0, 240.0, 0.0, 0.0, 1.0);
    let rt = k.try_inverse().unwrap() * cameras[0];
    let r = turn * rt.fixed_view::<3, 3>(0, 0);
    let mut turned = Matrix3x4::zeros();
    turned.fixed_view_mut::<3, 3>(0, 0).copy_from(&r);
    turned.set_column(3, &(turn * rt.column(3)));
    cameras[0] = k * turned;
    let conics = outlines(&cameras, &scene.ellipsoid);
    assert!(
        Ellipse::from_primal(&conics[0]).is_some(),
        "the mirrored outline is still an ellipse"
    );
    for method in Method::ALL.iter().copied() {
        let r = triangulate_quadric(&cameras, QuadricObservations::Conics(&conics, None), &opts(method)).unwrap();
        assert_eq!(r.report.status, Status::BehindCamera, "{}", method.as_str());
        // Status and certificate agree (issue 10: optimal said behind_camera and certified).
        assert!(!r.report.certified(), "{}", method.as_str());
    }
}

#[test]
fn bad_input_is_rejected_with_the_argument_and_index() {
    let scene = quadric_scene(3, 0.8, 60);
    let conics = outlines(&scene.cameras, &scene.ellipsoid);
    let o = opts(Method::Local);
    let err = |c: &[Matrix3x4<f64>], q: &[Matrix3<f64>], cov: Option<&[Matrix5]>| {
        triangulate_quadric(c, QuadricObservations::Conics(q, cov), &o).unwrap_err()
    };
    assert!(matches!(
        err(&scene.cameras[..2], &conics[..2], None),
        Error::TooFewCorrespondences { .. }
    ));
    assert!(matches!(err(&scene.cameras, &conics[..2], None), Error::Shape { .. }));
    let mut nan = conics.clone();
    nan[1][(0, 2)] = f64::NAN;
    assert!(matches!(err(&scene.cameras, &nan, None), Error::NonFinite { ref what, index: 1 } if what == "conics"));
    let mut hyperbola = conics.clone();
    hyperbola[2] = Matrix3::from_diagonal(&Vector3::new(1.0, -1.0, -100.0));
    assert!(
        matches!(err(&scene.cameras, &hyperbola, None), Error::Degenerate { ref what } if what.contains("conics[2]"))
    );
    let mut bad_cov = vec![Matrix5::identity(); 3];
    bad_cov[0][(4, 4)] = -1.0;
    assert!(
        matches!(err(&scene.cameras, &conics, Some(&bad_cov)), Error::Degenerate { ref what } if what.contains("covariances[0]"))
    );
    let same = vec![scene.cameras[0], scene.cameras[0] * 2.0, scene.cameras[0] * -1.0];
    assert!(matches!(err(&same, &conics, None), Error::Degenerate { ref what } if what.contains("centres")));
    let mut cams = scene.cameras.clone();
    cams[2] = Matrix3x4::zeros();
    assert!(matches!(err(&cams, &conics, None), Error::SingularCamera { .. }));
    let mut certify = pluecker::CertifyOptions::default();
    certify.max_nodes = Some(0);
    let mut bad = o.clone();
    bad.certify = certify;
    assert!(matches!(
        triangulate_quadric(&scene.cameras, QuadricObservations::Conics(&conics, None), &bad),
        Err(Error::InvalidOption { .. })
    ));
}

/// The quadric batch (`triangulation::quadric::batch`): every track equals the single call, with shared
/// and per-track cameras; a bad track never loses the others.
mod batch {
    use super::common::{mask, seen};
    use nalgebra::{Matrix3, Matrix3x4, Vector2};
    use pluecker::geometry::{project_dual, Ellipse};
    use pluecker::rng::Rng;
    use pluecker::triangulation::fitting::fit_conic;
    use pluecker::triangulation::quadric::{triangulate_quadric, Matrix5, QuadricObservations, QuadricTriangulation};
    use pluecker::triangulation::quadric::{triangulate_quadrics, DenseQuadricTracks};
    use pluecker::triangulation::scenes::quadric_scene;
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

    fn untimed_quadric(mut r: QuadricTriangulation) -> QuadricTriangulation {
        r.report.time_seconds = 0.0;
        r
    }

    /// Conics fitted to 63 outline points with 1 px noise, and their covariances, of an ellipsoid seen by
    /// `cameras`: the flat `(v, 3, 3)` and `(v, 5, 5)` entries of one track.
    fn fitted_outlines(
        cameras: &[Matrix3x4<f64>],
        dual: &nalgebra::Matrix4<f64>,
        rng: &mut Rng,
    ) -> (Vec<f64>, Vec<f64>) {
        let (mut conics, mut covariances) = (Vec::new(), Vec::new());
        for p in cameras {
            let outline = Ellipse::from_primal(&project_dual(p, dual).try_inverse().unwrap()).unwrap();
            let points: Vec<Vector2<f64>> = outline
                .sample(63, rng.uniform_in(0.0, 6.3))
                .into_iter()
                .map(|x| x + Vector2::new(rng.normal(), rng.normal()))
                .collect();
            let fit = fit_conic(&points, 1.0).unwrap();
            conics.extend(fit.conic.transpose().iter());
            covariances.extend(fit.covariance.transpose().iter());
        }
        (conics, covariances)
    }

    #[test]
    fn quadric_batch_equals_single_calls_with_shared_and_per_track_cameras() {
        let mut rng = Rng::new(15);
        let (n, v) = (4, 5);
        let cameras = quadric_scene(v, 0.8, 1).cameras;
        let (mut conics, mut covariances) = (Vec::new(), Vec::new());
        for k in 0..n {
            let e = quadric_scene(v, 0.8, 20 + k as u64).ellipsoid;
            let (c, s) = fitted_outlines(&cameras, &e.dual(), &mut rng);
            conics.extend(c);
            covariances.extend(s);
        }
        let visible = mask(n, v, 3, &mut rng);
        let single = |cams: &[Matrix3x4<f64>], t: usize, views: &[usize], method| {
            let c: Vec<Matrix3<f64>> = views
                .iter()
                .map(|&j| Matrix3::from_row_slice(&conics[9 * (t * v + j)..][..9]))
                .collect();
            let s: Vec<Matrix5> = views
                .iter()
                .map(|&j| Matrix5::from_row_slice(&covariances[25 * (t * v + j)..][..25]))
                .collect();
            triangulate_quadric(cams, QuadricObservations::Conics(&c, Some(&s)), &opts(method)).unwrap()
        };
        for method in Method::ALL.iter().copied() {
            let tracks = DenseQuadricTracks {
                conics: &conics,
                visible: Some(&visible),
                covariances: Some(&covariances),
            };
            let batch = triangulate_quadrics(&cameras, tracks, &opts(method), None).unwrap();
            for (t, r) in batch.into_iter().enumerate() {
                let views = seen(&visible, v, t);
                let cams: Vec<Matrix3x4<f64>> = views.iter().map(|&j| cameras[j]).collect();
                let expected = untimed_quadric(single(&cams, t, &views, method));
                assert_eq!(untimed_quadric(r.unwrap()), expected, "{} track {t}", method.as_str());
            }
        }
        // The same conics with every track's cameras given per track (here the shared ones, repeated,
        // with track 1's scaled: a camera's scale does not matter).
        let mut per_track: Vec<Matrix3x4<f64>> = (0..n).flat_map(|_| cameras.iter().copied()).collect();
        for p in &mut per_track[v..2 * v] {
            *p *= -3.0;
        }
        let tracks = DenseQuadricTracks {
            conics: &conics,
            visible: None,
            covariances: Some(&covariances),
        };
        let done = AtomicUsize::new(0);
        let cams = TrackCameras::PerTrack {
            projections: &per_track,
            views: v,
        };
        let batch = triangulate_quadrics(cams, tracks, &opts(Method::Local), Some(&done)).unwrap();
        assert_eq!(done.load(Ordering::Relaxed), n);
        let all: Vec<usize> = (0..v).collect();
        for (t, r) in batch.into_iter().enumerate() {
            let expected = untimed_quadric(single(&per_track[t * v..(t + 1) * v], t, &all, Method::Local));
            assert_eq!(untimed_quadric(r.unwrap()), expected, "track {t}");
        }
    }

    #[test]
    fn a_bad_quadric_track_is_its_own_error_and_never_loses_the_others() {
        let mut rng = Rng::new(16);
        let (n, v) = (6, 4);
        let cameras = quadric_scene(v, 0.8, 2).cameras;
        let (mut conics, mut covariances) = (Vec::new(), Vec::new());
        for k in 0..n {
            let e = quadric_scene(v, 0.8, 40 + k as u64).ellipsoid;
            let (c, s) = fitted_outlines(&cameras, &e.dual(), &mut rng);
            conics.extend(c);
            covariances.extend(s);
        }
        let mut visible = vec![true; n * v];
        // Track 1: NaN in visible view 3. Track 2: two visible views. Track 3: a hyperbola in view 0.
        // Track 4: a covariance that is not positive definite in view 2.
        conics[9 * (v + 3) + 4] = f64::NAN;
        visible[2 * v] = false;
        visible[2 * v + 1] = false;
        conics[9 * 3 * v..9 * 3 * v + 9].copy_from_slice(&[1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, -100.0]);
        covariances[25 * (4 * v + 2) + 24] = -1.0;
        let tracks = DenseQuadricTracks {
            conics: &conics,
            visible: Some(&visible),
            covariances: Some(&covariances),
        };
        let batch = triangulate_quadrics(&cameras, tracks, &opts(Method::Local), None).unwrap();
        assert!(matches!(&batch[1], Err(Error::NonFinite { what, index: 3 }) if what == "conics[1]"));
        assert!(
            matches!(&batch[2], Err(Error::TooFewCorrespondences { required, actual, .. }) if required.starts_with('3') && actual == "track 2: 2 view(s)")
        );
        assert!(matches!(&batch[3], Err(Error::Degenerate { what }) if what == "conics[3][0] is not a real ellipse"));
        assert!(matches!(&batch[4], Err(Error::Degenerate { what }) if what.starts_with("covariances[4][2]")));
        for t in [0, 5] {
            let r = batch[t].as_ref().unwrap();
            assert_eq!(r.report.status, Status::Success, "track {t}");
        }
        // Whole-call errors: lengths that do not fit.
        let short = DenseQuadricTracks {
            conics: &conics[..10],
            visible: None,
            covariances: None,
        };
        let o = opts(Method::Linear);
        assert!(matches!(
            triangulate_quadrics(&cameras, short, &o, None),
            Err(Error::Shape { what, .. }) if what == "conics"
        ));
        let covs = DenseQuadricTracks {
            covariances: Some(&covariances[..25]),
            ..tracks
        };
        assert!(matches!(
            triangulate_quadrics(&cameras, covs, &o, None),
            Err(Error::Shape { what, .. }) if what == "covariances"
        ));
        assert!(matches!(
            triangulate_quadrics(&[] as &[Matrix3x4<f64>], tracks, &o, None),
            Err(Error::Shape { what, .. }) if what == "cameras"
        ));
    }
}
