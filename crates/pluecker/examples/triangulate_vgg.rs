//! Triangulate the real Model House points (Oxford VGG data, shipped with the Python package) from
//! files: cameras `house.00N.P`, corners `house.00N.corners`, tracks `house.nview-corners`.
//!
//! `cargo run --release -p pluecker --example triangulate_vgg [-- FOLDER]` (default: the shipped
//! `python/pluecker/data/vgg/model_house`) prints how many of the 672 points are seen in two or more of
//! the 10 views, how many are certified globally optimal (all of them), and the median reprojection
//! cost Σ r² per point (px²).

use pluecker::nalgebra::{Matrix3x4, Vector2};
use pluecker::triangulation::point::triangulate_point;
use pluecker::triangulation::TriangulationOptions;
use std::path::{Path, PathBuf};

/// The whitespace-separated words of each line of a text file.
fn rows(path: &Path) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let words = text
        .lines()
        .map(|l| l.split_whitespace().map(String::from).collect::<Vec<_>>());
    words.filter(|w| !w.is_empty()).collect()
}

/// Every number of a text file, in reading order.
fn numbers(path: &Path) -> Vec<f64> {
    rows(path)
        .iter()
        .flatten()
        .map(|w| w.parse().expect("a number"))
        .collect()
}

fn main() -> pluecker::Result<()> {
    let shipped = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../python/pluecker/data/vgg/model_house"
    );
    let folder = PathBuf::from(std::env::args().nth(1).unwrap_or(shipped.into()));

    // The views: each camera's P = K [R | t] (raw, as shipped: in front means (P X̃)₃ > 0) and corners.
    let file = |j: usize, ext: &str| folder.join(format!("house.{j:03}.{ext}"));
    let projections: Vec<_> = (0..10)
        .map(|j| Matrix3x4::from_row_slice(&numbers(&file(j, "P"))))
        .collect();
    let corners: Vec<Vec<_>> = (0..10)
        .map(|j| {
            numbers(&file(j, "corners"))
                .chunks(2)
                .map(Vector2::from_row_slice)
                .collect()
        })
        .collect();

    // Each track: a corner index per view, `*` where the point is not seen.
    let options = TriangulationOptions::default();
    let (mut solved, mut certified, mut costs) = (0, 0, Vec::new());
    let tracks = rows(&folder.join("house.nview-corners"));
    for track in &tracks {
        let seen: Vec<(usize, usize)> = track
            .iter()
            .enumerate()
            .filter_map(|(j, c)| c.parse().ok().map(|c| (j, c)))
            .collect();
        if seen.len() < 2 {
            continue;
        }
        let track_projections: Vec<_> = seen.iter().map(|&(j, _)| projections[j]).collect();
        let observations: Vec<_> = seen.iter().map(|&(j, c)| corners[j][c]).collect();
        let point = triangulate_point(&track_projections, &observations, None, &options)?;
        solved += 1;
        certified += usize::from(point.report.certified());
        costs.push(point.report.cost);
    }
    costs.sort_by(f64::total_cmp);
    println!(
        "{} points, {solved} seen in two or more views, {certified} certified",
        tracks.len()
    );
    println!("median cost: {:.3} px²", costs[costs.len() / 2]);
    Ok(())
}
