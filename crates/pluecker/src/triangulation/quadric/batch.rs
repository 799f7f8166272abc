//! Many quadric tracks at once, in parallel (rayon): the batch form of [`crate::triangulation::quadric`].
//!
//! A track is one ellipsoid seen as an outline conic in some of `v` views. Its observations are plain
//! row-major slices, the layout of numpy arrays, so that a binding can pass `conics (n, v, 3, 3)`,
//! `visible (n, v)` and `covariances (n, v, 5, 5)` without reshaping ([`DenseQuadricTracks`]), or one
//! observation per row grouped by track ([`SparseQuadricTracks`]); both are [`QuadricTracks`]. The
//! cameras are shared by every track or given per track ([`TrackCameras`]; e.g. independent scenes
//! solved together).
//!
//! Every track is [`triangulate_quadric`] on its visible views' cameras, conics and covariances: the
//! same minimisation of eq. 19 (Josephson & Kahl 2008, sections 2.3, 3, 4) on the same numbers, so the
//! results are identical to the single calls' but for `time_seconds`. Each track gets its own
//! `Result`: a bad track (fewer than 3 visible views, NaN in a visible view, a conic that is not a real
//! ellipse, a covariance that is not positive definite) is an error for that track alone, naming it
//! (`conics[t][j]`: view `j` of track `t`). Errors of the whole call (bad options, bad shared cameras,
//! inconsistent array lengths) come first, as the outer `Result`.

#[cfg(doc)]
use super::triangulate_quadric;
use super::{quadric_of_projections, refuse_distortion, Matrix5, QuadricTriangulation};
use crate::error::{Error, Result};
use crate::interrupt::StopReason;
use crate::triangulation::tracks::{
    check_mask, check_values, dense_observations, in_track, solve_tracks, solve_tracks_into, too_few, track_count,
    tracks_from, unsupported_cameras, Csr, Projections, TrackCameras,
};
use crate::triangulation::views::{Cameras, View};
use crate::triangulation::TriangulationOptions;
use nalgebra::{Matrix3, Matrix3x4};
use rayon::prelude::*;
use std::sync::atomic::AtomicUsize;

/// The quadric tracks of one batch (see the module docs). With `v` views, the entry of track `t` in
/// view `j` is the `(t v + j)`-th of each array; entries of views where a track is not visible are
/// ignored (they may be NaN).
#[derive(Debug, Clone, Copy)]
pub struct DenseQuadricTracks<'a> {
    /// `n · v · 9` primal image conics (row-major 3x3, eq. 8, pixels, any scale and sign).
    pub conics: &'a [f64],
    /// `n · v` visibility flags, or `None` when every track is seen in every view.
    pub visible: Option<&'a [bool]>,
    /// `n · v · 25` covariances of the conic residuals (row-major 5x5, e.g. from
    /// [`crate::triangulation::fitting::fit_conic`]), or `None` (identity).
    pub covariances: Option<&'a [f64]>,
}

/// Checks the whole call and returns the number of tracks.
fn check_batch(cameras: &Projections, tracks: &DenseQuadricTracks) -> Result<usize> {
    let v = cameras.views();
    if v == 0 {
        return Err(Error::Shape {
            what: "cameras".into(),
            expected: "at least 3 views".into(),
            actual: "0".into(),
        });
    }
    let n = track_count("conics", tracks.conics.len(), v, 9, "3 x 3")?;
    cameras.check(n)?;
    check_mask(tracks.visible, n, v)?;
    check_values("covariances", tracks.covariances, n, v, 25, "5 x 5")?;
    Ok(n)
}

/// Track `t` by [`triangulate_quadric`] on its observations `seen`, `(view, row)` pairs: the camera of
/// the view, the conic and covariance of the row.
fn quadric_track(
    cameras: &Projections,
    conics: &[f64],
    covariances: Option<&[f64]>,
    t: usize,
    seen: &[(usize, usize)],
    opts: &TriangulationOptions,
) -> Result<QuadricTriangulation> {
    if seen.len() < 3 {
        return Err(too_few(opts.method, t, seen.len(), 3));
    }
    let views: Vec<usize> = seen.iter().map(|&(j, _)| j).collect();
    let cams = cameras.of_track(t, &views);
    let conics: Vec<Matrix3<f64>> = seen
        .iter()
        .map(|&(_, k)| Matrix3::from_row_slice(&conics[9 * k..][..9]))
        .collect();
    let covariances: Option<Vec<Matrix5>> = covariances.map(|c| {
        seen.iter()
            .map(|&(_, k)| Matrix5::from_row_slice(&c[25 * k..][..25]))
            .collect()
    });
    let arrays: &[&str] = if cameras.per_track() {
        &["conics", "covariances", "cameras"]
    } else {
        &["conics", "covariances"]
    };
    quadric_of_projections(&cams, &conics, covariances.as_deref(), opts).map_err(|e| in_track(e, t, &views, arrays))
}

/// Triangulates every quadric track of `tracks` seen by `cameras` with `opts`, in parallel; each
/// track gets the result [`triangulate_quadric`] gives on its visible views (module docs).
/// `progress`, when given, counts the finished tracks, for another thread to poll.
///
/// [`DenseQuadricTracks`] take shared cameras (projections, or views refused when a camera distorts,
/// as [`triangulate_quadric`] refuses them) or projections per track; [`SparseQuadricTracks`] take
/// shared cameras, and a track naming an image beyond them, or one image twice, is its own error.
///
/// Whole-call errors: [`Error::InvalidOption`] (options, a distorting view, projections per track with
/// the rows form), [`Error::Shape`] (array lengths that do not fit `v` views and one another),
/// [`Error::NonFinite`] / [`Error::SingularCamera`] for shared cameras. Per track: the errors of
/// [`triangulate_quadric`], and [`Error::TooFewCorrespondences`] for fewer than 3 visible views.
pub fn triangulate_quadrics<'a>(
    cameras: impl Into<TrackCameras<'a>>,
    tracks: impl Into<QuadricTracks<'a>>,
    opts: &TriangulationOptions,
    progress: Option<&AtomicUsize>,
) -> Result<Vec<Result<QuadricTriangulation>>> {
    let (n, one) = solver(cameras.into(), tracks.into(), opts)?;
    // A track takes from a millisecond to seconds: one track per rayon task balances the load.
    Ok(solve_tracks(n, 1, progress, one))
}

/// [`triangulate_quadrics`] handing each track's result to `write(t, row, result)` as it finishes,
/// with row `t` of `rows` (one per track), instead of collecting them: a stopped batch does not hand
/// the tracks it had not started to `write` and returns why (`Ok(None)`: every track was written), as
/// [`crate::triangulation::streaming::points_into`] does.
pub fn quadrics_into<'a, R: Send>(
    cameras: impl Into<TrackCameras<'a>>,
    tracks: impl Into<QuadricTracks<'a>>,
    opts: &TriangulationOptions,
    progress: Option<&AtomicUsize>,
    rows: impl IndexedParallelIterator<Item = R>,
    write: impl Fn(usize, R, Result<QuadricTriangulation>) + Sync + Send,
) -> Result<Option<StopReason>> {
    let (n, one) = solver(cameras.into(), tracks.into(), opts)?;
    solve_tracks_into(n, rows, 1, progress, one, write)
}

/// The quadric tracks of one batch: over every view ([`DenseQuadricTracks`]) or one observation per
/// row ([`SparseQuadricTracks`]). Both forms (and references to them) convert into it.
#[derive(Debug, Clone, Copy)]
pub enum QuadricTracks<'a> {
    /// `n` tracks over the `v` views, with a visibility mask.
    Dense(DenseQuadricTracks<'a>),
    /// Conics grouped by track.
    Sparse(SparseQuadricTracks<'a>),
}

tracks_from!(QuadricTracks: DenseQuadricTracks => Dense, SparseQuadricTracks => Sparse);

/// The number of tracks of a batch, checked, and the solve of track `t`.
fn solver<'a>(
    cameras: TrackCameras<'a>,
    tracks: QuadricTracks<'a>,
    opts: &'a TriangulationOptions,
) -> Result<(usize, impl Fn(usize) -> Result<QuadricTriangulation> + Sync + Send + 'a)> {
    opts.validate()?;
    opts.reject_outlier_threshold("quadrics")?;
    let projections = match cameras {
        TrackCameras::Shared(Cameras::Projections(p)) => Projections::Shared(p.into()),
        TrackCameras::Shared(Cameras::Views(views)) => {
            refuse_distortion(views)?;
            let of_views: Vec<Matrix3x4<f64>> = views.iter().map(View::projection).collect();
            Projections::Shared(of_views.into())
        }
        TrackCameras::PerTrack { projections, views } => Projections::PerTrack { projections, views },
    };
    let n = match tracks {
        QuadricTracks::Dense(dense) => check_batch(&projections, &dense)?,
        QuadricTracks::Sparse(sparse) => {
            if projections.per_track() {
                return Err(unsupported_cameras(
                    "projections per track apply to dense tracks (DenseQuadricTracks); rows index shared cameras",
                ));
            }
            projections.check(0)?;
            let n = sparse.csr.check()?;
            sparse.csr.check_values("conics", Some(sparse.conics), 9, "3 x 3")?;
            sparse
                .csr
                .check_values("covariances", sparse.covariances, 25, "5 x 5")?;
            n
        }
    };
    let one = move |t| match tracks {
        QuadricTracks::Dense(dense) => {
            let seen = dense_observations(dense.visible, projections.views(), t);
            quadric_track(&projections, dense.conics, dense.covariances, t, &seen, opts)
        }
        QuadricTracks::Sparse(sparse) => {
            let seen = sparse.csr.distinct_observations(t, projections.views())?;
            quadric_track(&projections, sparse.conics, sparse.covariances, t, &seen, opts)
        }
    };
    Ok((n, one))
}

/// Quadric tracks given one observation per row ([`Csr`]): row `k` is the conic `conics[9k..]` (row-major
/// 3x3) in image `csr.image[k]`, with the covariance `covariances[25k..]` (5x5) when given.
#[derive(Debug, Clone, Copy)]
pub struct SparseQuadricTracks<'a> {
    /// Which rows belong to which track, and their images.
    pub csr: Csr<'a>,
    /// `m · 9` primal image conics.
    pub conics: &'a [f64],
    /// `m · 25` covariances of the conic residuals, or `None` (identity).
    pub covariances: Option<&'a [f64]>,
}
