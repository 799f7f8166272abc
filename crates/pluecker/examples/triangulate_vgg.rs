//! Triangulate the real Model House points (Oxford VGG data, shipped with the Python package) from
//! files: cameras `house.00N.P`, corners `house.00N.corners`, tracks `house.nview-corners`.
//!
//! `cargo run --release -p pluecker --example triangulate_vgg [-- FOLDER]` (default: the shipped
//! `python/pluecker/data/vgg/model_house`) prints how many of the 672 points are seen in two or more of
//! the 10 views, how many are certified globally optimal (all of them), and the median reprojection
//! cost Σ r² per point (px²).

use nalgebra::{Matrix3x4, Vector2};
use pluecker::triangulation::point::triangulate_point;
use pluecker::triangulation::TriangulationOptions;
use std::path::{Path, PathBuf};

/// The whitespace-separated rows of a text file.
fn rows(path: &Path) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    text.lines()
        .map(|l| l.split_whitespace().map(String::from).collect())
        .filter(|r: &Vec<String>| !r.is_empty())
        .collect()
}

fn main() -> pluecker::Result<()> {
    let shipped = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../python/pluecker/data/vgg/model_house"
    );
    let folder = std::env::args()
        .nth(1)
        .map_or_else(|| PathBuf::from(shipped), PathBuf::from);
    let number = |s: &String| -> f64 { s.parse().expect("a number") };

    // The views: each camera's P = K [R | t] (raw, as shipped: in front means (P X̃)₃ > 0) and corners.
    let views = 10;
    let mut projections = Vec::new();
    let mut corners = Vec::new();
    for j in 0..views {
        let p: Vec<f64> = rows(&folder.join(format!("house.{j:03}.P")))
            .iter()
            .flatten()
            .map(number)
            .collect();
        projections.push(Matrix3x4::from_row_slice(&p));
        let c = rows(&folder.join(format!("house.{j:03}.corners")));
        corners.push(
            c.iter()
                .map(|r| Vector2::new(number(&r[0]), number(&r[1])))
                .collect::<Vec<_>>(),
        );
    }

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
