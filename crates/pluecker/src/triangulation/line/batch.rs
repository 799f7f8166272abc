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

use super::{lines_from_segments, triangulate_line, LineTriangulation};
use crate::error::{Error, Result};
use crate::triangulation::tracks::{
    check_mask, check_values, in_track, solve_tracks, too_few, track_count, visible_views, TrackCameras,
};
use crate::triangulation::TriangulationOptions;
use nalgebra::{Matrix2, Vector2, Vector3};
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
            what: "cameras".into(),
            expected: "at least 2 views".into(),
            actual: "0".into(),
        });
    }
    let n = match tracks.lines {
        ImageLines::Homogeneous(lines) => track_count("lines", lines.len(), v, 3, "3 line coordinates")?,
        ImageLines::Segments { endpoints, sigma } => {
            if !(sigma.is_finite() && sigma > 0.0) {
                return Err(Error::InvalidOption {
                    name: "sigma".into(),
                    reason: format!("must be a positive finite number of pixels, got {sigma}"),
                });
            }
            track_count("segments", endpoints.len(), v, 4, "2 endpoints x 2 coordinates")?
        }
    };
    cameras.check(n)?;
    check_mask(tracks.visible, n, v)?;
    check_values("covariances", tracks.covariances, n, v, 4, "2 x 2")?;
    Ok(n)
}

/// Track `t` by the single-line functions on its visible views (module docs).
fn line_track(
    cameras: &TrackCameras,
    tracks: &LineTracks,
    t: usize,
    opts: &TriangulationOptions,
) -> Result<LineTriangulation> {
    let v = cameras.views();
    let seen: Vec<usize> = visible_views(tracks.visible, v, t).collect();
    if seen.len() < 2 {
        return Err(too_few(opts.method, t, seen.len(), 2));
    }
    let cams = cameras.of_track(t, &seen);
    let covariances: Option<Vec<Matrix2<f64>>> = tracks.covariances.map(|c| {
        seen.iter()
            .map(|&j| Matrix2::from_row_slice(&c[4 * (t * v + j)..][..4]))
            .collect()
    });
    let result = match tracks.lines {
        ImageLines::Homogeneous(values) => {
            let lines: Vec<Vector3<f64>> = seen
                .iter()
                .map(|&j| Vector3::from_row_slice(&values[3 * (t * v + j)..][..3]))
                .collect();
            triangulate_line(&cams, &lines, covariances.as_deref(), opts)
        }
        ImageLines::Segments { endpoints, sigma } => {
            let segments: Vec<[Vector2<f64>; 2]> = seen
                .iter()
                .map(|&j| {
                    let s = &endpoints[4 * (t * v + j)..][..4];
                    [Vector2::new(s[0], s[1]), Vector2::new(s[2], s[3])]
                })
                .collect();
            lines_from_segments(&segments, sigma).and_then(|(lines, from_noise)| {
                triangulate_line(&cams, &lines, Some(covariances.as_deref().unwrap_or(&from_noise)), opts)
            })
        }
    };
    let arrays: &[&str] = if cameras.per_track() {
        &["lines", "segments", "covariances", "cameras"]
    } else {
        &["lines", "segments", "covariances"]
    };
    result.map_err(|e| in_track(e, t, &seen, arrays))
}

/// Triangulates every line track of `tracks` seen by `cameras` with `opts`, in parallel; each track
/// gets the result [`triangulate_line`] gives on its visible views (module docs). `progress`, when
/// given, counts the finished tracks, for another thread to poll.
///
/// Whole-call errors: [`Error::InvalidOption`] (options, `sigma`), [`Error::Shape`] (array lengths
/// that do not fit `v` views and one another), [`Error::NonFinite`] / [`Error::SingularCamera`] for
/// shared cameras. Per track: the errors of [`triangulate_line`] and [`lines_from_segments`], and
/// [`Error::TooFewCorrespondences`] for fewer than 2 visible views.
pub fn triangulate_lines(
    cameras: TrackCameras,
    tracks: &LineTracks,
    opts: &TriangulationOptions,
    progress: Option<&AtomicUsize>,
) -> Result<Vec<Result<LineTriangulation>>> {
    opts.validate()?;
    opts.reject_outlier_threshold("lines")?;
    let n = check_batch(&cameras, tracks)?;
    // A track takes from a millisecond to seconds: one track per rayon task balances the load.
    Ok(solve_tracks(n, 1, progress, |t| line_track(&cameras, tracks, t, opts)))
}
