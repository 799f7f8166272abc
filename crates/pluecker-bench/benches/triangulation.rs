//! Time per triangulated point, by method, number of views and parallax, and of the batch.
//!
//! Scenes: [`triangulation_scene`] with 1 px Gaussian noise, a pool of 64 seeded scenes per case
//! (every run times the same inputs; each iteration takes the next scene of the pool, so a time is
//! the mean over the pool). Cases: 2, 5, 10, 20 views at 10° parallax (the largest angle between
//! two rays), and 5 and 20 views at 1° and 0.2°. Groups:
//! - `point/<case>/<method>`: one `triangulate_point` call;
//! - `batch/<case>/<method>`: `triangulate_points` (rayon) or the linear fast path on 4096 tracks
//!   of the same cameras, timed per batch (divide by 4096);
//! - `line/<views>-views/optimal-<bound>`: one certified line at 3 and 5 views, with the Taylor bound
//!   and the paper's relaxation ([`bench_lines`]);
//! - `quadric/<views>-views/<method>`: one ellipsoid at 3 and 5 views, `local` and `optimal`
//!   ([`bench_quadrics`]; fitting the conics included).
//!
//! At setup, one line per case goes to stderr: the fraction certified, by which certificate, the
//! branch-and-bound nodes, the median and 90th-percentile time per point measured sequentially
//! from the reports, and the median 3-D error of each method against the truth (so that a fast
//! wrong answer cannot pass unnoticed).
//!
//! Run: `cargo bench -p pluecker-bench --bench triangulation` (a few minutes on 2 cores), append
//! `-- --quick` for a rough pass or a filter such as `-- point/5-views`.

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use nalgebra::{Matrix3x4, Vector2, Vector3};
use pluecker::rng::Rng;
use pluecker::synthetic::triangulation_scene;
use pluecker::triangulation::line::LineObservations;
use pluecker::triangulation::point::triangulate_point;
use pluecker::triangulation::point::{triangulate_points, DensePointTracks, LinearPoints};
use pluecker::triangulation::quadric::QuadricObservations;
use pluecker::triangulation::{CertificateKind, LineBound, Method, TriangulationOptions};
use std::time::Duration;

const SIGMA_PX: f64 = 1.0;
const POOL: u64 = 64;
const BATCH: usize = 4096;

struct Case {
    name: String,
    views: usize,
    parallax_deg: f64,
}

fn cases() -> Vec<Case> {
    let mut out: Vec<Case> = [2, 5, 10, 20]
        .iter()
        .map(|&v| Case {
            name: format!("{v}-views-10deg"),
            views: v,
            parallax_deg: 10.0,
        })
        .collect();
    for parallax in [1.0, 0.2] {
        for v in [5, 20] {
            out.push(Case {
                name: format!("{v}-views-{parallax}deg"),
                views: v,
                parallax_deg: parallax,
            });
        }
    }
    out
}

type Track = (Vec<Matrix3x4<f64>>, Vec<Vector2<f64>>, Vector3<f64>);

fn pool(case: &Case) -> Vec<Track> {
    (0..POOL)
        .map(|seed| {
            let scene = triangulation_scene(case.views, case.parallax_deg.to_radians(), 7000 + seed);
            let obs = scene.noisy(SIGMA_PX, &mut Rng::new(seed));
            (scene.cameras, obs, scene.point)
        })
        .collect()
}

fn percentile(v: &mut [f64], q: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * q).round() as usize]
}

/// The setup line of a case (see the module docs).
fn summary(case: &Case, tracks: &[Track]) {
    let mut line = format!("{:>18}:", case.name);
    for &method in Method::ALL {
        let mut opts = TriangulationOptions::default();
        opts.method = method;
        let (mut times, mut errors, mut nodes) = (Vec::new(), Vec::new(), Vec::new());
        let (mut by_test, mut by_bnb, mut certified) = (0, 0, 0);
        for (cams, obs, truth) in tracks {
            let r = triangulate_point(cams, obs, None, &opts).unwrap();
            times.push(r.report.time_seconds * 1e6);
            errors.push((r.point - truth).norm());
            match r.report.certificate.map(|c| (c.kind, c.nodes)) {
                Some((CertificateKind::ConvexityTest | CertificateKind::LensConvexityTest, _)) => by_test += 1,
                Some((
                    CertificateKind::BranchAndBound
                    | CertificateKind::TaylorBranchAndBound
                    | CertificateKind::SublevelSet
                    | CertificateKind::LensSublevelSet,
                    n,
                )) => {
                    by_bnb += 1;
                    nodes.push(n as f64);
                }
                Some((CertificateKind::None, _)) | None => {}
            }
            certified += r.report.certified() as usize;
        }
        let errors_median = percentile(&mut errors, 0.5);
        line += &format!(
            " | {} median {:.1} us p90 {:.1} us err {:.2e}",
            method.as_str(),
            percentile(&mut times, 0.5),
            percentile(&mut times, 0.9),
            errors_median
        );
        if method == Method::Optimal {
            let n = tracks.len();
            line += &format!(
                " certified {certified}/{n} (test {by_test}, b&b {by_bnb}, nodes median {})",
                if nodes.is_empty() {
                    f64::NAN
                } else {
                    percentile(&mut nodes, 0.5)
                }
            );
        }
    }
    eprintln!("{line}");
}

fn bench_points(c: &mut Criterion) {
    let mut group = c.benchmark_group("point");
    group
        .sample_size(20)
        .measurement_time(Duration::from_secs(2))
        .warm_up_time(Duration::from_millis(300));
    for case in cases() {
        let tracks = pool(&case);
        summary(&case, &tracks);
        for &method in Method::ALL {
            let mut opts = TriangulationOptions::default();
            opts.method = method;
            let mut k = 0;
            group.bench_function(format!("{}/{}", case.name, method.as_str()), |b| {
                b.iter(|| {
                    let (cams, obs, _) = &tracks[k % tracks.len()];
                    k += 1;
                    black_box(triangulate_point(cams, obs, None, &opts).unwrap())
                })
            });
        }
    }
    group.finish();
}

fn bench_batch(c: &mut Criterion) {
    let mut group = c.benchmark_group("batch");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(3))
        .warm_up_time(Duration::from_millis(300));
    let scene = triangulation_scene(5, 10f64.to_radians(), 99);
    let mut rng = Rng::new(99);
    let mut observations = Vec::with_capacity(BATCH * 10);
    for _ in 0..BATCH {
        let x = scene.point + Vector3::new(rng.normal(), rng.normal(), rng.normal()) * 0.05;
        for p in &scene.cameras {
            let h = p * x.push(1.0);
            observations.extend([h.x / h.z + SIGMA_PX * rng.normal(), h.y / h.z + SIGMA_PX * rng.normal()]);
        }
    }
    let tracks = DensePointTracks {
        observations: &observations,
        visible: None,
        covariances: None,
    };
    group.bench_function("5-views-10deg/linear-fast-path", |b| {
        b.iter(|| black_box(LinearPoints::from_tracks(&scene.cameras, &tracks).unwrap()))
    });
    for &method in Method::ALL {
        let mut opts = TriangulationOptions::default();
        opts.method = method;
        group.bench_function(format!("5-views-10deg/{}", method.as_str()), |b| {
            b.iter(|| black_box(triangulate_points(&scene.cameras, tracks, &opts, None).unwrap()))
        });
    }
    group.finish();
}

/// `line/<views>-views/optimal-<bound>`: one certified line (latest numbers: docs/benchmarks.md), on a pool of 16
/// seeded scenes of [`line_scene`] (46° of parallax) with 1 px endpoint noise; the fraction certified
/// and the nodes go to stderr at setup.
fn bench_lines(c: &mut Criterion) {
    use pluecker::triangulation::line::triangulate_line;
    use pluecker::triangulation::scenes::line_scene;
    let mut group = c.benchmark_group("line");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(5));
    for views in [3usize, 5] {
        let problems: Vec<_> = (0..16u64)
            .map(|seed| {
                let scene = line_scene(views, 0.8, 500 + seed);
                let segments = scene.noisy_segments(SIGMA_PX, &mut Rng::new(600 + seed));
                (scene.cameras, segments)
            })
            .collect();
        for &bound in LineBound::ALL {
            let mut opts = TriangulationOptions::default();
            opts.line_bound = bound;
            let results: Vec<_> = problems
                .iter()
                .map(|(p, s)| triangulate_line(p, LineObservations::Segments(s, SIGMA_PX), &opts).expect("valid"))
                .collect();
            let certified = results.iter().filter(|r| r.report.certified()).count();
            let nodes: usize = results
                .iter()
                .map(|r| r.report.certificate.map_or(0, |c| c.nodes))
                .sum();
            let name = format!("{views}-views/optimal-{}", bound.as_str());
            eprintln!("setup line/{name}: {certified}/16 certified, mean nodes {}", nodes / 16);
            let mut k = 0;
            group.bench_function(name, |b| {
                b.iter(|| {
                    let (p, s) = &problems[k % problems.len()];
                    k += 1;
                    triangulate_line(black_box(p), LineObservations::Segments(black_box(s), SIGMA_PX), &opts)
                })
            });
        }
    }
    group.finish();
}

/// `quadric/<views>-views/<method>`: one ellipsoid by `local` and by `optimal` (the convexity test), on
/// a pool of 16 seeded scenes of [`quadric_scene`] (46° of parallax) with conics fitted to 63 outline
/// points of 1 px noise; the fraction certified goes to stderr at setup.
fn bench_quadrics(c: &mut Criterion) {
    use pluecker::triangulation::quadric::triangulate_quadric;
    use pluecker::triangulation::scenes::quadric_scene;
    let mut group = c.benchmark_group("quadric");
    group
        .sample_size(20)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3));
    for views in [3usize, 5] {
        let problems: Vec<_> = (0..16u64)
            .map(|seed| {
                let scene = quadric_scene(views, 0.8, 700 + seed);
                let points = scene.noisy_outline_points(63, SIGMA_PX, &mut Rng::new(800 + seed));
                (scene.cameras, points)
            })
            .collect();
        for method in [Method::Local, Method::Optimal] {
            let mut opts = TriangulationOptions::default();
            opts.method = method;
            let certified = problems
                .iter()
                .map(|(p, x)| {
                    triangulate_quadric(p, QuadricObservations::EdgePoints(x, SIGMA_PX), &opts).expect("valid")
                })
                .filter(|r| {
                    r.report
                        .certificate
                        .is_some_and(|c| c.kind == CertificateKind::ConvexityTest && c.certified)
                })
                .count();
            let name = format!("{views}-views/{}", method.as_str());
            eprintln!("setup quadric/{name}: {certified}/16 certified by the convexity test");
            let mut k = 0;
            group.bench_function(name, |b| {
                b.iter(|| {
                    let (p, x) = &problems[k % problems.len()];
                    k += 1;
                    triangulate_quadric(
                        black_box(p),
                        QuadricObservations::EdgePoints(black_box(x), SIGMA_PX),
                        &opts,
                    )
                })
            });
        }
    }
    group.finish();
}

criterion_group!(benches, bench_points, bench_batch, bench_lines, bench_quadrics);
criterion_main!(benches);
