//! Measurements of line and quadric triangulation (Josephson & Kahl 2008): synthetic scenes at several
//! view counts with 1 px noise, and the real Model House and Corridor lines (Table 2).
//!
//! Run: `cargo bench -p pluecker-bench --bench lines_and_quadrics [-- DATA_DIR [GAP]]`, with
//! `DATA_DIR` the VGG folder (default: the copy shipped in `python/pluecker/data/vgg`) and `GAP` the relative gap (default the
//! library's 1e-3). Every number printed is computed here; nothing is copied from the paper.
//!
//! Real data: the first four frames of each sequence, every 3-D line seen in at least two of them.
//! The images are not available, so each segment's line covariance is the one of
//! [`lines_from_segments`] for endpoints with σ = 1 px. The reprojection error of a line in a view is
//! the mean distance of the two observed endpoints to the reprojected line (pixels); the table gives
//! its mean and standard deviation over all (line, view) pairs.

use nalgebra::{Matrix3x4, Matrix4, Vector2};
use pluecker::geometry::plucker;
use pluecker::rng::Rng;
use pluecker::triangulation::line::testing::endpoint_distances;
use pluecker::triangulation::line::{lines_from_segments, triangulate_line, LineObservations};
use pluecker::triangulation::quadric::{triangulate_quadric, QuadricObservations};
use pluecker::triangulation::scenes::{line_scene, quadric_scene};
use pluecker::triangulation::{Method, Report, TriangulationOptions};
use pluecker::CertifyOptions;
use std::fs;
use std::path::Path;

/// The VGG sequences shipped with the Python package.
const SHIPPED_DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../python/pluecker/data/vgg");

/// Summary statistics of one method over many runs.
#[derive(Default)]
struct Tally {
    cost: Vec<f64>,
    time: Vec<f64>,
    nodes: Vec<f64>,
    certified: usize,
    runs: usize,
}

impl Tally {
    fn add(&mut self, r: &Report) {
        self.cost.push(r.cost);
        self.time.push(r.time_seconds);
        self.nodes.push(r.certificate.map_or(0, |c| c.nodes) as f64);
        self.certified += r.certified() as usize;
        self.runs += 1;
    }

    fn row(&self, label: &str) -> String {
        format!(
            "{label:>8} | mean cost {:9.3} | median time {:9.3} ms | max time {:9.1} ms | median nodes {:6.0} | max nodes {:6.0} | certified {:3}/{:3}",
            mean(&self.cost),
            median(&self.time) * 1e3,
            self.time.iter().copied().fold(0.0, f64::max) * 1e3,
            median(&self.nodes),
            self.nodes.iter().copied().fold(0.0, f64::max),
            self.certified,
            self.runs
        )
    }
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len().max(1) as f64
}

fn std(v: &[f64]) -> f64 {
    let m = mean(v);
    (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len().max(2) - 1) as f64).sqrt()
}

fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(|a, b| a.total_cmp(b));
    if s.is_empty() {
        f64::NAN
    } else {
        s[s.len() / 2]
    }
}

fn options(method: Method, gap: f64) -> TriangulationOptions {
    let mut certify = CertifyOptions::default();
    certify.max_relative_gap = gap;
    let mut options = TriangulationOptions::default();
    options.method = method;
    options.certify = certify;
    options
}

/// One table of 20 scenes per number of views: `solve(views, seed)` gives every method's report, in the
/// order of `Method::ALL`, on scene `seed`; a row per method.
fn table(view_counts: &[usize], solve: impl Fn(usize, u64) -> Vec<Report>) {
    for &views in view_counts {
        let mut tallies: Vec<Tally> = Method::ALL.iter().map(|_| Tally::default()).collect();
        for seed in 0..20u64 {
            for (tally, report) in tallies.iter_mut().zip(solve(views, seed)) {
                tally.add(&report);
            }
        }
        println!("{views} views:");
        for (m, tally) in Method::ALL.iter().zip(&tallies) {
            println!("{}", tally.row(m.as_str()));
        }
    }
}

fn synthetic(gap: f64) {
    println!("## Synthetic lines: segments of 0.8-1.6 units at ~5 units, cameras on a 0.8 rad arc, 1 px endpoint noise, σ = 1 px covariances, 20 scenes per row");
    table(&[2, 3, 5, 10], |views, seed| {
        let scene = line_scene(views, 0.8, 1000 * views as u64 + seed);
        let segments = scene.noisy_segments(1.0, &mut Rng::new(7 + seed));
        let observations = LineObservations::Segments(&segments, 1.0);
        Method::ALL
            .iter()
            .map(|m| {
                triangulate_line(&scene.cameras, observations, &options(*m, gap))
                    .unwrap()
                    .report
            })
            .collect()
    });
    println!("\n## Synthetic ellipsoids: semi-axes 0.15-0.5 at ~5 units, 63 outline points per view with 1 px noise, fitted conics and covariances, 20 scenes per row");
    table(&[3, 5, 10], |views, seed| {
        let scene = quadric_scene(views, 0.8, 2000 * views as u64 + seed);
        let points = scene.noisy_outline_points(63, 1.0, &mut Rng::new(11 + seed));
        Method::ALL
            .iter()
            .map(|m| {
                let observations = QuadricObservations::EdgePoints(&points, 1.0);
                triangulate_quadric(&scene.cameras, observations, &options(*m, gap))
                    .unwrap()
                    .report
            })
            .collect()
    });
}

fn numbers(path: &Path) -> Vec<Vec<String>> {
    let text = fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    text.lines()
        .map(|l| l.split_whitespace().map(str::to_string).collect::<Vec<_>>())
        .filter(|r| !r.is_empty())
        .collect()
}

/// A line's track: the views that see it and its segment in each.
type Track = (Vec<usize>, Vec<[Vector2<f64>; 2]>);

/// The first four views of a VGG sequence (cameras fixed for the mirrored frame, see the data
/// README) and every line seen in at least two of them: (view indices, segments).
fn vgg_lines(dir: &Path, prefix: &str) -> (Vec<Matrix3x4<f64>>, Vec<Track>) {
    let mirror = Matrix4::from_diagonal(&nalgebra::Vector4::new(-1.0, -1.0, -1.0, 1.0));
    let mut cameras = Vec::new();
    let mut segments = Vec::new();
    for v in 0..4 {
        let p = numbers(&dir.join(format!("{prefix}{v:03}.P")));
        let p = Matrix3x4::from_fn(|r, c| p[r][c].parse::<f64>().unwrap());
        cameras.push(p * mirror);
        let rows = numbers(&dir.join(format!("{prefix}{v:03}.lines")));
        let segs: Vec<[Vector2<f64>; 2]> = rows
            .iter()
            .map(|r| {
                let x: Vec<f64> = r.iter().take(4).map(|s| s.parse().unwrap()).collect();
                [Vector2::new(x[0], x[1]), Vector2::new(x[2], x[3])]
            })
            .collect();
        segments.push(segs);
    }
    let tracks = numbers(&dir.join(format!("{prefix}nview-lines")));
    let lines = tracks
        .iter()
        .filter_map(|row| {
            let seen: Vec<(usize, usize)> = (0..4)
                .filter_map(|v| row.get(v)?.parse::<usize>().ok().map(|i| (v, i)))
                .collect();
            (seen.len() >= 2).then(|| {
                (
                    seen.iter().map(|s| s.0).collect(),
                    seen.iter().map(|&(v, i)| segments[v][i]).collect(),
                )
            })
        })
        .collect();
    (cameras, lines)
}

fn real(data: &Path, gap: f64) {
    println!("\n## Table 2: lines of the first four frames, covariance from the segment endpoints with σ = 1 px");
    for (name, folder, prefix) in [("House", "model_house", "house."), ("Corridor", "corridor", "bt.")] {
        let (cameras, lines) = vgg_lines(&data.join(folder), prefix);
        let mut errors: Vec<Vec<f64>> = vec![Vec::new(); 3];
        let mut tallies: Vec<Tally> = Method::ALL.iter().map(|_| Tally::default()).collect();
        let mut same_as_local = 0;
        for (views, segments) in &lines {
            let cams: Vec<Matrix3x4<f64>> = views.iter().map(|&v| cameras[v]).collect();
            let (homogeneous, covariances) = lines_from_segments(segments, 1.0).unwrap();
            let mut estimates = Vec::new();
            for (k, m) in Method::ALL.iter().enumerate() {
                let r = triangulate_line(
                    &cams,
                    LineObservations::Lines(&homogeneous, Some(&covariances)),
                    &options(*m, gap),
                )
                .unwrap();
                for (p, s) in cams.iter().zip(segments) {
                    let d = endpoint_distances(&plucker::project(p, r.plucker.coordinates()), &s[0], &s[1]);
                    errors[k].push(0.5 * (d[0] + d[1]));
                }
                tallies[k].add(&r.report);
                estimates.push(r.report.cost);
            }
            same_as_local += ((estimates[2] - estimates[1]).abs() <= 1e-9 * (1.0 + estimates[1])) as usize;
        }
        println!("{name}: {} lines ({} line observations)", lines.len(), errors[0].len());
        println!("| method | mean (px) | std (px) |");
        for (k, m) in Method::ALL.iter().enumerate() {
            println!("| {} | {:.2} | {:.2} |", m.as_str(), mean(&errors[k]), std(&errors[k]));
        }
        for (m, tally) in Method::ALL.iter().zip(&tallies) {
            println!("{}", tally.row(m.as_str()));
        }
        println!(
            "optimal cost equal to the local cost (1e-9) for {same_as_local} of {} lines",
            lines.len()
        );
    }
}

fn main() {
    // `cargo bench` appends `--bench` to the arguments.
    let args: Vec<String> = std::env::args().filter(|a| a != "--bench").collect();
    let data = args.get(1).map_or(SHIPPED_DATA, |s| s.as_str()).to_string();
    let gap = args
        .get(2)
        .map_or(TriangulationOptions::default().certify.max_relative_gap, |s| {
            s.parse().expect("GAP must be a number")
        });
    println!(
        "relative gap {gap:e}, max nodes {} (relaxation), {} (Taylor)",
        pluecker::triangulation::CONIC_MAX_NODES,
        pluecker::triangulation::line::TAYLOR_MAX_NODES
    );
    synthetic(gap);
    real(Path::new(&data), gap);
}
