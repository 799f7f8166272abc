//! Many line tracks at once, in parallel (rayon): the batch form of [`crate::triangulation::line`].
//!
//! A track is one 3-D line seen in some of `v` views. Its observations are plain row-major slices,
//! the layout of numpy arrays, so that a binding can pass `lines (n, v, 3)` or `segments (n, v, 2, 2)`,
//! `visible (n, v)` and `covariances (n, v, 2, 2)` without reshaping: [`LineTracks`]. The cameras are
//! shared by every track or given per track ([`TrackCameras`]).
//!
//! Every track is triangulated from its visible views exactly as a single call would do it
//! ([`triangulate_line`] on those views' cameras and lines, or [`lines_from_segments`] first for
//! segments): the same minimisation of eq. 19 (Josephson & Kahl 2008, sections 2.2, 3, 4) on the same
//! numbers, so the results are identical to the single calls' but for `time_seconds`. Each track gets
//! its own `Result`: a bad track (fewer than 2 visible views, NaN in a visible view, a zero-length
//! segment, a covariance that is not positive definite, a line in an epipolar plane of its views) is
//! an error for that track alone, naming it (`lines[t][j]`: view `j` of track `t`). Errors of the whole
//! call (bad options, a bad `sigma`, bad shared cameras, inconsistent array lengths) come first, as the
//! outer `Result`.

use super::{lines_from_segments, triangulate_line, triangulate_line_segments_views, LineTriangulation};
use crate::error::{Error, Result};
use crate::interrupt::StopReason;
use crate::triangulation::tracks::{
    check_mask, check_values, dense_observations, in_track, solve_tracks, solve_tracks_into, too_few, track_count, Csr,
    TrackCameras,
};
use crate::triangulation::views::{validate_cameras, View};
use crate::triangulation::TriangulationOptions;
use nalgebra::{Matrix2, Matrix3x4, Vector2, Vector3};
use rayon::prelude::*;
use std::sync::atomic::AtomicUsize;

/// The image lines of a batch, one entry per track and view (row-major, track-major: the entry of
/// track `t` in view `j` is the `(t v + j)`-th). Entries of views where a track is not visible are
/// ignored (they may be NaN).
#[derive(Debug, Clone, Copy)]
pub enum ImageLines<'a> {
    /// `n · v · 3` homogeneous image lines `l` (pixels, any scale and sign: `l · (u, v, 1) = 0`).
    Homogeneous(&'a [f64]),
    /// `n · v · 4` image segments `(u₁, v₁, u₂, v₂)` (two pixel endpoints) whose endpoints have i.i.d.
    /// Gaussian noise of `sigma` px per coordinate: each gives its line and the covariance of the
    /// line's residual by [`lines_from_segments`].
    Segments {
        /// The segments' endpoints, pixels.
        endpoints: &'a [f64],
        /// Endpoint noise, pixels (positive, finite).
        sigma: f64,
    },
}

/// The line tracks of one batch (see the module docs).
#[derive(Debug, Clone, Copy)]
pub struct LineTracks<'a> {
    /// The observed image lines or segments.
    pub lines: ImageLines<'a>,
    /// `n · v` visibility flags, or `None` when every track is seen in every view.
    pub visible: Option<&'a [bool]>,
    /// `n · v · 4` covariances of the line residuals (row-major 2x2, the normalisation of section 3.1,
    /// e.g. from [`crate::triangulation::fitting::fit_line`]), or `None`: the identity for homogeneous lines, the
    /// endpoint noise `sigma` for segments. With segments, given covariances replace the endpoint
    /// noise's (the segments then only give the lines).
    pub covariances: Option<&'a [f64]>,
}

/// Checks the whole call and returns the number of tracks.
fn check_batch(cameras: &TrackCameras, tracks: &LineTracks) -> Result<usize> {
    let v = cameras.views();
    if v == 0 {
        return Err(Error::Shape {
            what: "projections".into(),
            expected: "at least 2 views".into(),
            actual: "0".into(),
        });
    }
    check_sigma(&tracks.lines)?;
    let n = match tracks.lines {
        ImageLines::Homogeneous(lines) => track_count("lines", lines.len(), v, 3, "3 line coordinates")?,
        ImageLines::Segments { endpoints, .. } => {
            track_count("lines", endpoints.len(), v, 4, "2 endpoints x 2 coordinates")?
        }
    };
    cameras.check(n)?;
    check_mask(tracks.visible, n, v)?;
    check_values("covariances", tracks.covariances, n, v, 4, "2 x 2")?;
    Ok(n)
}

/// Track `t` by the single-line functions on its observations `seen`, `(view, row)` pairs: the camera
/// of the view, the line (or segment) and covariance of the row (module docs).
fn line_track(
    cameras: &TrackCameras,
    lines: &ImageLines,
    covariances: Option<&[f64]>,
    t: usize,
    seen: &[(usize, usize)],
    opts: &TriangulationOptions,
) -> Result<LineTriangulation> {
    if seen.len() < 2 {
        return Err(too_few(opts.method, t, seen.len(), 2));
    }
    let views: Vec<usize> = seen.iter().map(|&(j, _)| j).collect();
    let cams = cameras.of_track(t, &views);
    let covariances: Option<Vec<Matrix2<f64>>> = covariances.map(|c| {
        seen.iter()
            .map(|&(_, k)| Matrix2::from_row_slice(&c[4 * k..][..4]))
            .collect()
    });
    let result = match *lines {
        ImageLines::Homogeneous(values) => {
            let lines: Vec<Vector3<f64>> = seen
                .iter()
                .map(|&(_, k)| Vector3::from_row_slice(&values[3 * k..][..3]))
                .collect();
            triangulate_line(&cams, &lines, covariances.as_deref(), opts)
        }
        ImageLines::Segments { endpoints, sigma } => {
            let segments: Vec<[Vector2<f64>; 2]> = seen
                .iter()
                .map(|&(_, k)| {
                    let s = &endpoints[4 * k..][..4];
                    [Vector2::new(s[0], s[1]), Vector2::new(s[2], s[3])]
                })
                .collect();
            lines_from_segments(&segments, sigma).and_then(|(lines, from_noise)| {
                triangulate_line(&cams, &lines, Some(covariances.as_deref().unwrap_or(&from_noise)), opts)
            })
        }
    };
    let arrays: &[&str] = if cameras.per_track() {
        &["lines", "covariances", "projections"]
    } else {
        &["lines", "covariances"]
    };
    result.map_err(|e| in_track(e, t, &views, arrays))
}

/// `sigma` of segments: positive and finite.
fn check_sigma(lines: &ImageLines) -> Result<()> {
    match *lines {
        ImageLines::Segments { sigma, .. } if !(sigma.is_finite() && sigma > 0.0) => Err(Error::InvalidOption {
            name: "sigma".into(),
            reason: format!(
                "must be a positive finite number of pixels, got {}",
                crate::error::number(sigma)
            ),
        }),
        _ => Ok(()),
    }
}

/// Triangulates every line track of `tracks` seen by `projections` with `opts`, in parallel; each track
/// gets the result [`triangulate_line`] gives on its visible views (module docs). `progress`, when
/// given, counts the finished tracks, for another thread to poll.
///
/// Whole-call errors: [`Error::InvalidOption`] (options, `sigma`), [`Error::Shape`] (array lengths
/// that do not fit `v` views and one another), [`Error::NonFinite`] / [`Error::SingularCamera`] for
/// shared cameras. Per track: the errors of [`triangulate_line`] and [`lines_from_segments`], and
/// [`Error::TooFewCorrespondences`] for fewer than 2 visible views.
pub fn triangulate_lines(
    projections: TrackCameras,
    tracks: &LineTracks,
    opts: &TriangulationOptions,
    progress: Option<&AtomicUsize>,
) -> Result<Vec<Result<LineTriangulation>>> {
    let (n, one) = dense_solver(projections, tracks, opts)?;
    // A track takes from a millisecond to seconds: one track per rayon task balances the load.
    Ok(solve_tracks(n, 1, progress, one))
}

/// [`triangulate_lines`] handing each track's result to `write(t, row, result)` as it finishes, with
/// row `t` of `rows` (one per track), instead of collecting them: a stopped batch does not hand the
/// tracks it had not started to `write` and returns why (`Ok(None)`: every track was written), as
/// [`crate::triangulation::point::testing::triangulate_points_into`] does.
pub fn triangulate_lines_into<R: Send>(
    projections: TrackCameras,
    tracks: &LineTracks,
    opts: &TriangulationOptions,
    progress: Option<&AtomicUsize>,
    rows: impl IndexedParallelIterator<Item = R>,
    write: impl Fn(usize, R, Result<LineTriangulation>) + Sync + Send,
) -> Result<Option<StopReason>> {
    let (n, one) = dense_solver(projections, tracks, opts)?;
    solve_tracks_into(n, rows, 1, progress, one, write)
}

/// The number of tracks of a dense batch, checked, and the solve of track `t`.
fn dense_solver<'a>(
    projections: TrackCameras<'a>,
    tracks: &'a LineTracks<'a>,
    opts: &'a TriangulationOptions,
) -> Result<(usize, impl Fn(usize) -> Result<LineTriangulation> + Sync + Send + 'a)> {
    opts.validate()?;
    let n = check_batch(&projections, tracks)?;
    let v = projections.views();
    let one = move |t| {
        let seen = dense_observations(tracks.visible, v, t);
        line_track(&projections, &tracks.lines, tracks.covariances, t, &seen, opts)
    };
    Ok((n, one))
}

/// Line tracks given one observation per row ([`Csr`]): row `k` is the line or segment `k` of `lines`
/// (`m · 3` or `m · 4` values) in image `csr.image[k]`, with the covariance `covariances[4k..]` when
/// given. Memory grows with the observations, not with tracks × images.
#[derive(Debug, Clone, Copy)]
pub struct SparseLineTracks<'a> {
    /// Which rows belong to which track, and their images.
    pub csr: Csr<'a>,
    /// The observed image lines or segments, one per row.
    pub lines: ImageLines<'a>,
    /// `m · 4` covariances of the line residuals (as in [`LineTracks::covariances`]), or `None`.
    pub covariances: Option<&'a [f64]>,
}

/// Triangulates every track of the sparse `tracks` seen by `projections` (3x4, world → pixels), in
/// parallel: the same per-track solve and results as [`triangulate_lines`] on the dense form. A track
/// naming an image beyond the cameras, or one image twice, is its own error.
pub fn triangulate_line_observations(
    projections: &[Matrix3x4<f64>],
    tracks: &SparseLineTracks,
    opts: &TriangulationOptions,
    progress: Option<&AtomicUsize>,
) -> Result<Vec<Result<LineTriangulation>>> {
    let (n, one) = sparse_solver(projections, tracks, opts)?;
    Ok(solve_tracks(n, 1, progress, one))
}

/// [`triangulate_line_observations`] handing each track's result to `write(t, row, result)` as
/// [`triangulate_lines_into`] does.
pub fn triangulate_line_observations_into<R: Send>(
    projections: &[Matrix3x4<f64>],
    tracks: &SparseLineTracks,
    opts: &TriangulationOptions,
    progress: Option<&AtomicUsize>,
    rows: impl IndexedParallelIterator<Item = R>,
    write: impl Fn(usize, R, Result<LineTriangulation>) + Sync + Send,
) -> Result<Option<StopReason>> {
    let (n, one) = sparse_solver(projections, tracks, opts)?;
    solve_tracks_into(n, rows, 1, progress, one, write)
}

/// The number of tracks of a sparse batch, checked, and the solve of track `t`.
fn sparse_solver<'a>(
    projections: &'a [Matrix3x4<f64>],
    tracks: &'a SparseLineTracks<'a>,
    opts: &'a TriangulationOptions,
) -> Result<(usize, impl Fn(usize) -> Result<LineTriangulation> + Sync + Send + 'a)> {
    opts.validate()?;
    check_sigma(&tracks.lines)?;
    let shared = TrackCameras::Shared(projections);
    shared.check(0)?;
    let n = tracks.csr.check()?;
    match tracks.lines {
        ImageLines::Homogeneous(lines) => tracks.csr.check_values("lines", Some(lines), 3, "3 line coordinates")?,
        ImageLines::Segments { endpoints, .. } => {
            tracks
                .csr
                .check_values("lines", Some(endpoints), 4, "2 endpoints x 2 coordinates")?
        }
    }
    tracks.csr.check_values("covariances", tracks.covariances, 4, "2 x 2")?;
    let one = move |t| {
        let seen = tracks.csr.distinct_observations(t, projections.len())?;
        line_track(&shared, &tracks.lines, tracks.covariances, t, &seen, opts)
    };
    Ok((n, one))
}

/// Segment tracks seen through [`View`]s, one observation per row ([`Csr`]): row `k` is the segment
/// `segments[4k..4k + 4]` (`(u₁, v₁, u₂, v₂)`, the image's own, distorted pixels) in image
/// `csr.image[k]`, with its endpoints' covariances `covariances[8k..8k + 8]` (two row-major 2x2
/// matrices, pixels²) when given.
#[derive(Debug, Clone, Copy)]
pub struct SparseSegmentTracks<'a> {
    /// Which rows belong to which track, and their images.
    pub csr: Csr<'a>,
    /// `m · 4` segment endpoints `(u₁, v₁, u₂, v₂)`, pixels: the image lines as segments.
    pub lines: &'a [f64],
    /// `m · 8` endpoint covariances, or `None` (the identity: costs in squared pixels).
    pub covariances: Option<&'a [f64]>,
}

/// Triangulates every track of the sparse `tracks` seen in `views` (a pinhole or any of COLMAP's
/// models, and a pose, per image), in parallel: each track as
/// [`super::triangulate_line_segments_views`] solves it on its rows. A track naming an image beyond
/// the views, or one image twice, is its own error; its other errors name it
/// (`segments[t][j]`: image `j` of track `t`).
///
/// Whole-call errors: [`Error::InvalidOption`] (options), [`Error::Shape`] (array lengths),
/// [`Error::NonFinite`] / [`Error::SingularCamera`] for the views' cameras.
pub fn triangulate_line_observations_views(
    views: &[View],
    tracks: &SparseSegmentTracks,
    opts: &TriangulationOptions,
    progress: Option<&AtomicUsize>,
) -> Result<Vec<Result<LineTriangulation>>> {
    let (n, one) = views_solver(views, tracks, opts)?;
    Ok(solve_tracks(n, 1, progress, one))
}

/// [`triangulate_line_observations_views`] handing each track's result to `write(t, row, result)` as
/// [`triangulate_lines_into`] does.
pub fn triangulate_line_observations_views_into<R: Send>(
    views: &[View],
    tracks: &SparseSegmentTracks,
    opts: &TriangulationOptions,
    progress: Option<&AtomicUsize>,
    rows: impl IndexedParallelIterator<Item = R>,
    write: impl Fn(usize, R, Result<LineTriangulation>) + Sync + Send,
) -> Result<Option<StopReason>> {
    let (n, one) = views_solver(views, tracks, opts)?;
    solve_tracks_into(n, rows, 1, progress, one, write)
}

/// The number of tracks of a sparse batch through views, checked, and the solve of track `t`.
fn views_solver<'a>(
    views: &'a [View],
    tracks: &'a SparseSegmentTracks<'a>,
    opts: &'a TriangulationOptions,
) -> Result<(usize, impl Fn(usize) -> Result<LineTriangulation> + Sync + Send + 'a)> {
    opts.validate()?;
    let cameras: Vec<Matrix3x4<f64>> = views.iter().map(View::projection).collect::<Result<_>>()?;
    validate_cameras(&cameras, "views")?;
    let n = tracks.csr.check()?;
    tracks
        .csr
        .check_values("lines", Some(tracks.lines), 4, "2 endpoints x 2 coordinates")?;
    tracks
        .csr
        .check_values("covariances", tracks.covariances, 8, "2 endpoints x 2 x 2")?;
    let one = move |t| {
        let seen = tracks.csr.distinct_observations(t, views.len())?;
        if seen.len() < 2 {
            return Err(too_few(opts.method, t, seen.len(), 2));
        }
        let images: Vec<usize> = seen.iter().map(|&(j, _)| j).collect();
        let track_views: Vec<View> = images.iter().map(|&j| views[j].clone()).collect();
        let segments: Vec<[Vector2<f64>; 2]> = seen
            .iter()
            .map(|&(_, k)| {
                let s = &tracks.lines[4 * k..][..4];
                [Vector2::new(s[0], s[1]), Vector2::new(s[2], s[3])]
            })
            .collect();
        let covariances: Option<Vec<[Matrix2<f64>; 2]>> = tracks.covariances.map(|c| {
            seen.iter()
                .map(|&(_, k)| {
                    let c = &c[8 * k..][..8];
                    [Matrix2::from_row_slice(&c[..4]), Matrix2::from_row_slice(&c[4..])]
                })
                .collect()
        });
        triangulate_line_segments_views(&track_views, &segments, covariances.as_deref(), opts)
            .map_err(|e| in_track(e, t, &images, &["lines", "covariances"]))
    };
    Ok((n, one))
}
