//! Many line tracks at once, in parallel (rayon): the batch form of [`crate::triangulation::line`].
//!
//! A track is one 3-D line seen in some of `v` views. Its observations are plain row-major slices,
//! the layout of numpy arrays, so that a binding can pass `lines (n, v, 3)` or `segments (n, v, 2, 2)`,
//! `visible (n, v)` and `covariances (n, v, 2, 2)` without reshaping ([`DenseLineTracks`]), or one
//! observation per row grouped by track ([`SparseLineTracks`], and [`SparseSegmentTracks`] for segments
//! seen through views); all are [`LineTracks`]. The cameras are shared by every track or given per
//! track ([`TrackCameras`]).
//!
//! Every track is triangulated from its visible views exactly as a single call would do it
//! ([`triangulate_line`] on those views' cameras and lines or segments): the same minimisation of eq. 19 (Josephson & Kahl 2008, sections 2.2, 3, 4) on the same
//! numbers, so the results are identical to the single calls' but for `time_seconds`. Each track gets
//! its own `Result`: a bad track (fewer than 2 visible views, NaN in a visible view, a zero-length
//! segment, a covariance that is not positive definite, a line in an epipolar plane of its views) is
//! an error for that track alone, naming it (`lines[t][j]`: view `j` of track `t`). Errors of the whole
//! call (bad options, a bad `sigma`, bad shared cameras, inconsistent array lengths) come first, as the
//! outer `Result`.

#[cfg(doc)]
use super::triangulate_line;
use super::{line_of_projections, line_of_segment_views, lines_from_segments, LineTriangulation};
use crate::error::{Error, Result};
use crate::interrupt::StopReason;
use crate::triangulation::tracks::{
    check_mask, check_values, dense_observations, in_track, solve_tracks, solve_tracks_into, too_few, track_count,
    tracks_from, unsupported_cameras, Csr, Projections, TrackCameras,
};
use crate::triangulation::views::{validate_cameras, Cameras, View};
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

/// Line tracks over every view of a batch (see the module docs).
#[derive(Debug, Clone, Copy)]
pub struct DenseLineTracks<'a> {
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
fn check_batch(cameras: &Projections, tracks: &DenseLineTracks) -> Result<usize> {
    let v = cameras.views();
    if v == 0 {
        return Err(Error::Shape {
            what: "cameras".into(),
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
    cameras: &Projections,
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
            line_of_projections(&cams, &lines, covariances.as_deref(), opts)
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
                line_of_projections(&cams, &lines, Some(covariances.as_deref().unwrap_or(&from_noise)), opts)
            })
        }
    };
    let arrays: &[&str] = if cameras.per_track() {
        &["lines", "covariances", "cameras"]
    } else {
        &["lines", "covariances"]
    };
    result.map_err(|e| in_track(e, t, &views, arrays))
}

/// `sigma` of segments: positive and finite.
pub(super) fn check_sigma(lines: &ImageLines) -> Result<()> {
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

/// Triangulates every line track of `tracks` seen by `cameras` with `opts`, in parallel; each track
/// gets the result [`triangulate_line`] gives on its visible views (module docs). `progress`, when
/// given, counts the finished tracks, for another thread to poll.
///
/// The forms of tracks and the cameras that see them: [`DenseLineTracks`] with shared projections or
/// projections per track; [`SparseLineTracks`] with shared projections; [`SparseSegmentTracks`] with
/// views. In the rows forms a track naming an image beyond the cameras, or one image twice, is its own
/// error.
///
/// Whole-call errors: [`Error::InvalidOption`] (options, `sigma`, cameras that do not fit the form of
/// the tracks), [`Error::Shape`] (array lengths that do not fit `v` views and one another),
/// [`Error::NonFinite`] / [`Error::SingularCamera`] for shared cameras. Per track: the errors of
/// [`triangulate_line`] and [`lines_from_segments`], and [`Error::TooFewCorrespondences`] for fewer
/// than 2 visible views.
pub fn triangulate_lines<'a>(
    cameras: impl Into<TrackCameras<'a>>,
    tracks: impl Into<LineTracks<'a>>,
    opts: &TriangulationOptions,
    progress: Option<&AtomicUsize>,
) -> Result<Vec<Result<LineTriangulation>>> {
    let (n, one) = solver(cameras.into(), tracks.into(), opts)?;
    // A track takes from a millisecond to seconds: one track per rayon task balances the load.
    Ok(solve_tracks(n, 1, progress, one))
}

/// [`triangulate_lines`] handing each track's result to `write(t, row, result)` as it finishes, with
/// row `t` of `rows` (one per track), instead of collecting them: a stopped batch does not hand the
/// tracks it had not started to `write` and returns why (`Ok(None)`: every track was written), as
/// [`crate::triangulation::streaming::points_into`] does.
pub fn lines_into<'a, R: Send>(
    cameras: impl Into<TrackCameras<'a>>,
    tracks: impl Into<LineTracks<'a>>,
    opts: &TriangulationOptions,
    progress: Option<&AtomicUsize>,
    rows: impl IndexedParallelIterator<Item = R>,
    write: impl Fn(usize, R, Result<LineTriangulation>) + Sync + Send,
) -> Result<Option<StopReason>> {
    let (n, one) = solver(cameras.into(), tracks.into(), opts)?;
    solve_tracks_into(n, rows, 1, progress, one, write)
}

/// The line tracks of one batch: over every view ([`DenseLineTracks`]), or one observation per row
/// ([`SparseLineTracks`]; [`SparseSegmentTracks`] for segments through views). Every form (and a
/// reference to it) converts into it.
#[derive(Debug, Clone, Copy)]
pub enum LineTracks<'a> {
    /// `n` tracks over the `v` views, with a visibility mask.
    Dense(DenseLineTracks<'a>),
    /// Image lines or segments grouped by track, seen by projections.
    Sparse(SparseLineTracks<'a>),
    /// Segments with endpoint covariances grouped by track, seen through views.
    SparseSegments(SparseSegmentTracks<'a>),
}

tracks_from!(LineTracks: DenseLineTracks => Dense, SparseLineTracks => Sparse, SparseSegmentTracks => SparseSegments);

/// A batch's tracks with the cameras that fit their form.
enum Kernel<'a> {
    Dense(Projections<'a>, DenseLineTracks<'a>),
    Sparse(&'a [Matrix3x4<f64>], SparseLineTracks<'a>),
    Segments(&'a [View], SparseSegmentTracks<'a>),
}

/// The number of tracks of a batch, checked, and the solve of track `t`.
fn solver<'a>(
    cameras: TrackCameras<'a>,
    tracks: LineTracks<'a>,
    opts: &'a TriangulationOptions,
) -> Result<(usize, impl Fn(usize) -> Result<LineTriangulation> + Sync + Send + 'a)> {
    opts.validate()?;
    let kernel = match (cameras, tracks) {
        (TrackCameras::Shared(Cameras::Projections(p)), LineTracks::Dense(d)) => {
            Kernel::Dense(Projections::Shared(p.into()), d)
        }
        (TrackCameras::PerTrack { projections, views }, LineTracks::Dense(d)) => {
            Kernel::Dense(Projections::PerTrack { projections, views }, d)
        }
        (TrackCameras::Shared(Cameras::Projections(p)), LineTracks::Sparse(s)) => Kernel::Sparse(p, s),
        (TrackCameras::Shared(Cameras::Views(v)), LineTracks::SparseSegments(s)) => Kernel::Segments(v, s),
        (TrackCameras::Shared(Cameras::Views(_)), _) => {
            return Err(unsupported_cameras(
                "views see segments given one per row (SparseSegmentTracks); give projections for these tracks",
            ))
        }
        (_, LineTracks::SparseSegments(_)) => {
            return Err(unsupported_cameras(
                "segments with endpoint covariances (SparseSegmentTracks) are seen through views; give views",
            ))
        }
        (TrackCameras::PerTrack { .. }, LineTracks::Sparse(_)) => {
            return Err(unsupported_cameras(
                "projections per track apply to dense tracks (DenseLineTracks); rows index shared cameras",
            ))
        }
    };
    let n = match &kernel {
        Kernel::Dense(projections, tracks) => check_batch(projections, tracks)?,
        Kernel::Sparse(projections, tracks) => check_sparse(projections, tracks)?,
        Kernel::Segments(views, tracks) => check_segments(views, tracks)?,
    };
    let one = move |t| match &kernel {
        Kernel::Dense(projections, tracks) => {
            let seen = dense_observations(tracks.visible, projections.views(), t);
            line_track(projections, &tracks.lines, tracks.covariances, t, &seen, opts)
        }
        Kernel::Sparse(projections, tracks) => {
            let seen = tracks.csr.distinct_observations(t, projections.len())?;
            let shared = Projections::Shared((*projections).into());
            line_track(&shared, &tracks.lines, tracks.covariances, t, &seen, opts)
        }
        Kernel::Segments(views, tracks) => segment_track(views, tracks, t, opts),
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
    /// `m · 4` covariances of the line residuals (as in [`DenseLineTracks::covariances`]), or `None`.
    pub covariances: Option<&'a [f64]>,
}

/// The number of tracks of a sparse batch, checked.
fn check_sparse(projections: &[Matrix3x4<f64>], tracks: &SparseLineTracks) -> Result<usize> {
    check_sigma(&tracks.lines)?;
    Projections::Shared(projections.into()).check(0)?;
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
    Ok(n)
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

/// The number of tracks of a sparse batch through views, checked.
fn check_segments(views: &[View], tracks: &SparseSegmentTracks) -> Result<usize> {
    let cameras: Vec<Matrix3x4<f64>> = views.iter().map(View::projection).collect();
    validate_cameras(&cameras, "cameras")?;
    let n = tracks.csr.check()?;
    tracks
        .csr
        .check_values("lines", Some(tracks.lines), 4, "2 endpoints x 2 coordinates")?;
    tracks
        .csr
        .check_values("covariances", tracks.covariances, 8, "2 endpoints x 2 x 2")?;
    Ok(n)
}

/// Track `t` of segments through views, as [`triangulate_line`] solves it on its rows: a track naming
/// an image beyond the views, or one image twice, is its own error; its other errors name it
/// (`lines[t][j]`: image `j` of track `t`).
fn segment_track(
    views: &[View],
    tracks: &SparseSegmentTracks,
    t: usize,
    opts: &TriangulationOptions,
) -> Result<LineTriangulation> {
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
    line_of_segment_views(&track_views, &segments, covariances.as_deref(), opts)
        .map_err(|e| in_track(e, t, &images, &["lines", "covariances"]))
}
