//! Certified triangulation of the real Model House and Corridor points (Oxford VGG data), every
//! point from all the views it is seen in, then from the first four views only (the paper's
//! Table 1 setting).
//!
//! `cargo run --release -p pluecker --example triangulate_vgg [-- DATA_DIR]` (default
//! the copy shipped in `python/pluecker/data/vgg`). Prints, per data set: points, fraction certified and by which
//! certificate, statuses, branch-and-bound nodes, median / 99th-percentile / max time per point
//! (single calls), the batch time per point, and the mean and standard deviation of the per-point
//! RMS reprojection error of the linear, local and optimal methods.
//!
//! Both sets use a mirrored world frame (data README): every camera is replaced by
//! `P diag(−1, −1, −1, 1)`, which keeps the projections and makes the depths positive.

use nalgebra::{Matrix3x4, Matrix4, Vector2};
use pluecker::triangulation::point::triangulate_point;
use pluecker::triangulation::point::{triangulate_points, PointTracks};
use pluecker::triangulation::{CertificateKind, Method, Status, TriangulationOptions};
use std::collections::BTreeMap;
use std::path::Path;

/// The VGG sequences shipped with the Python package.
const SHIPPED_DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../python/pluecker/data/vgg");

fn numbers(path: &Path) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    text.lines()
        .map(|l| l.split_whitespace().map(str::to_string).collect::<Vec<_>>())
        .filter(|r| !r.is_empty())
        .collect()
}

struct Dataset {
    cameras: Vec<Matrix3x4<f64>>,
    /// Per 3-D point: (view, pixel) of every view it is seen in.
    tracks: Vec<Vec<(usize, Vector2<f64>)>>,
}

fn load(dir: &Path, prefix: &str, views: usize) -> Dataset {
    let flip = Matrix4::from_diagonal(&nalgebra::Vector4::new(-1.0, -1.0, -1.0, 1.0));
    let mut cameras = Vec::new();
    let mut corners = Vec::new();
    for j in 0..views {
        let p = numbers(&dir.join(format!("{prefix}{j:03}.P")));
        let values: Vec<f64> = p.iter().flatten().map(|v| v.parse().unwrap()).collect();
        cameras.push(Matrix3x4::from_row_slice(&values) * flip);
        let c = numbers(&dir.join(format!("{prefix}{j:03}.corners")));
        corners.push(
            c.iter()
                .map(|r| Vector2::new(r[0].parse().unwrap(), r[1].parse().unwrap()))
                .collect::<Vec<_>>(),
        );
    }
    let tracks = numbers(&dir.join(format!("{prefix}nview-corners")))
        .iter()
        .map(|row| {
            row.iter()
                .enumerate()
                .filter(|(_, v)| v.as_str() != "*")
                .map(|(j, v)| (j, corners[j][v.parse::<usize>().unwrap()]))
                .collect()
        })
        .collect();
    Dataset { cameras, tracks }
}

fn percentile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    sorted[((sorted.len() - 1) as f64 * q).round() as usize]
}

fn mean_std(v: &[f64]) -> (f64, f64) {
    let n = v.len().max(1) as f64;
    let m = v.iter().sum::<f64>() / n;
    (m, (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / n).sqrt())
}

/// Triangulates every track (restricted to `views`) and prints the statistics.
fn run(name: &str, data: &Dataset, views: &[usize]) {
    let opts = TriangulationOptions::default();
    let mut kinds: BTreeMap<&str, usize> = BTreeMap::new();
    let mut statuses: BTreeMap<&str, usize> = BTreeMap::new();
    let (mut times, mut nodes, mut rms) = (Vec::new(), Vec::new(), BTreeMap::<&str, Vec<f64>>::new());
    let mut certified = 0;
    let mut subset = Vec::new();
    for track in &data.tracks {
        let seen: Vec<&(usize, Vector2<f64>)> = track.iter().filter(|(j, _)| views.contains(j)).collect();
        if seen.len() < 2 {
            continue;
        }
        let cams: Vec<Matrix3x4<f64>> = seen.iter().map(|(j, _)| data.cameras[*j]).collect();
        let obs: Vec<Vector2<f64>> = seen.iter().map(|(_, x)| *x).collect();
        subset.push((cams.clone(), obs.clone()));
        let r = triangulate_point(&cams, &obs, None, &opts).expect("valid VGG track");
        times.push(r.report.time_seconds);
        *kinds
            .entry(r.report.certificate.map_or("none", |c| c.kind.as_str()))
            .or_default() += 1;
        *statuses.entry(r.report.status.as_str()).or_default() += 1;
        if r.report.certified() {
            certified += 1;
        }
        if let Some(c) = r
            .report
            .certificate
            .filter(|c| c.kind == CertificateKind::BranchAndBound)
        {
            nodes.push(c.nodes as f64);
        }
        // The three methods on the same points: skip a point whose linear or local answer is not
        // a finite point in front of the cameras (counted).
        let mut costs = vec![(Method::Optimal, r.report.cost)];
        for method in [Method::Linear, Method::Local] {
            let mut other = opts.clone();
            other.method = method;
            let m = triangulate_point(&cams, &obs, None, &other).unwrap();
            if matches!(m.report.status, Status::AtInfinity | Status::BehindCamera) {
                *statuses
                    .entry("(linear/local not in front: left out of the RMS table)")
                    .or_default() += 1;
                costs.clear();
                break;
            }
            costs.push((method, m.report.cost));
        }
        for (method, cost) in costs {
            rms.entry(method.as_str())
                .or_default()
                .push((cost / obs.len() as f64).sqrt());
        }
    }
    times.sort_by(f64::total_cmp);
    nodes.sort_by(f64::total_cmp);
    let n = times.len();
    println!("{name}: {n} points (seen in >= 2 of views {views:?})");
    println!(
        "  certified {certified}/{n} = {:.2} %  by {kinds:?}  statuses {statuses:?}",
        100.0 * certified as f64 / n as f64
    );
    println!(
        "  time per point (single calls): median {:.1} us, p99 {:.1} us, max {:.1} us; branch and bound on {} points, nodes median {} max {}",
        1e6 * percentile(&times, 0.5),
        1e6 * percentile(&times, 0.99),
        1e6 * times.last().copied().unwrap_or(f64::NAN),
        nodes.len(),
        percentile(&nodes, 0.5),
        nodes.last().copied().unwrap_or(f64::NAN)
    );
    for (method, values) in &rms {
        let (m, s) = mean_std(values);
        println!("  RMS reprojection error per point, {method:>7}: mean {m:.3} px, std {s:.3} px");
    }
    // The same tracks through the batch (rayon over the cores), as flat arrays.
    let v = data.cameras.len();
    let mut observations = vec![f64::NAN; subset.len() * v * 2];
    let mut visible = vec![false; subset.len() * v];
    let mut t = 0;
    for track in &data.tracks {
        let seen: Vec<&(usize, Vector2<f64>)> = track.iter().filter(|(j, _)| views.contains(j)).collect();
        if seen.len() < 2 {
            continue;
        }
        for (j, x) in seen {
            visible[t * v + j] = true;
            observations[2 * (t * v + j)] = x.x;
            observations[2 * (t * v + j) + 1] = x.y;
        }
        t += 1;
    }
    let tracks = PointTracks {
        observations: &observations,
        visible: Some(&visible),
        covariances: None,
    };
    let started = std::time::Instant::now();
    let results = triangulate_points(&data.cameras, &tracks, &opts, None).unwrap();
    let elapsed = started.elapsed().as_secs_f64();
    let batch_certified = results
        .iter()
        .filter(|r| r.as_ref().is_ok_and(|r| r.report.certified()))
        .count();
    println!(
        "  batch ({} threads): {:.1} us per point, certified {batch_certified}/{}",
        rayon::current_num_threads(),
        1e6 * elapsed / results.len() as f64,
        results.len()
    );
}

fn main() {
    let root = std::env::args().nth(1).unwrap_or_else(|| SHIPPED_DATA.into());
    let root = Path::new(&root);
    for (name, folder, prefix, views) in [
        ("Model House", "model_house", "house.", 10),
        ("Corridor", "corridor", "bt.", 11),
    ] {
        let data = load(&root.join(folder), prefix, views);
        run(&format!("{name}, all views"), &data, &(0..views).collect::<Vec<_>>());
        run(&format!("{name}, first four views"), &data, &[0, 1, 2, 3]);
    }
}
