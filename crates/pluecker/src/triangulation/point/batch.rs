//! Many point tracks over the same cameras at once, in parallel (rayon).
//!
//! The data are plain row-major slices, the layout of numpy arrays, so that a binding can pass
//! `observations (n, v, 2)`, `visible (n, v)` and `covariances (n, v, 2, 2)` without reshaping
//! ([`DensePointTracks`]), or one observation per row grouped by track ([`SparsePointTracks`]); both
//! are [`PointTracks`]. Every track is triangulated from its visible views only, exactly as
//! [`super::triangulate_point`] would do it, and gets its own `Result`: a bad track (too
//! few visible views, NaN in a visible view, a covariance that is not positive definite, no
//! parallax between its views) is an error for that track alone. Errors of the whole call (bad
//! options, bad cameras, inconsistent array lengths) come first, as the outer `Result`.
//!
//! [`LinearPoints::from_tracks`] is the fast path of [`Method::Linear`]: no allocation per track,
//! the results written straight into flat arrays (`streaming::linear_points_into`: into the caller's
//! rows).
//!
//! Every batch polls the stop of [`crate::interrupt`] before each track: tracks not started when it
//! fires are rejected with [`Error::Interrupted`] (the others keep their results), and a track being
//! solved by branch and bound ends with status `Interrupted` or `TimeBudget`.
//!
//! The helpers it shares with the line and quadric batches (shape checks, visible views, the
//! parallel loop over tracks) are in [`crate::triangulation::tracks`].

use super::cost::PointView;
use super::lens::{first_order_view, solve_through_lenses, LensView};
use super::linear::{accumulate_dlt, solve_dlt, LinearPoint, WorldFrame};
use super::PointTriangulation;
use crate::covariance::whitening;
use crate::error::{Error, Result};
use crate::interrupt::{current, StopReason};
use crate::triangulation::tracks::{
    check_mask, check_values, solve_tracks, solve_tracks_into, too_few, track_count, visible_views, Csr,
};
use crate::triangulation::uncertainty::covariance_of_information3;
use crate::triangulation::views::{centre, depth_normalized, validate_cameras, Cameras, View};
use crate::triangulation::{Method, Status, TriangulationOptions};
use nalgebra::{Matrix2, Matrix3, Matrix3x4, Matrix4, Vector2, Vector3};
use rayon::prelude::*;
use std::sync::atomic::AtomicUsize;
use std::time::Instant;

/// Tracks of one batch, as flat row-major arrays (see the module docs). With `v` cameras and `n`
/// tracks: the pixel of track `t` in view `j` is `observations[2(t v + j) ..][..2]`, its flag
/// `visible[t v + j]`, its covariance (row-major 2x2, pixels²) `covariances[4(t v + j) ..][..4]`.
#[derive(Debug, Clone, Copy)]
pub struct DensePointTracks<'a> {
    /// `n · v · 2` pixels; entries of views where the track is not visible are ignored (may be NaN).
    pub observations: &'a [f64],
    /// `n · v` visibility flags, or `None` when every track is seen in every view.
    pub visible: Option<&'a [bool]>,
    /// `n · v · 4` covariances, or `None` (identity: costs in squared pixels).
    pub covariances: Option<&'a [f64]>,
}

/// The cameras of a batch, checked and prepared once.
struct Prepared {
    normalized: Vec<Matrix3x4<f64>>,
    centres: Vec<Vector3<f64>>,
    /// The centroid of all centres (spreads are computed relative to it, for accuracy).
    origin: Vector3<f64>,
    /// The largest distance of a centre from the world origin, at least 1 (the scale of the
    /// no-parallax test).
    extent: f64,
    /// The views, when a camera distorts: then the tracks go through [`super::lens`].
    views: Option<Vec<View>>,
}

/// Checks the whole call and returns the number of tracks.
fn check_batch(cameras: &[Matrix3x4<f64>], tracks: &DensePointTracks) -> Result<(usize, Prepared)> {
    let prepared = prepare(cameras)?;
    let n = PointTracks::Dense(*tracks).check(cameras.len())?;
    Ok((n, prepared))
}

/// The checked, depth-normalised cameras and their centres, shared by every track.
fn prepare(cameras: &[Matrix3x4<f64>]) -> Result<Prepared> {
    validate_cameras(cameras, "cameras")?;
    let v = cameras.len();
    if v == 0 {
        return Err(Error::Shape {
            what: "cameras".into(),
            expected: "at least 2 cameras".into(),
            actual: "0".into(),
        });
    }
    let centres: Vec<Vector3<f64>> = cameras.iter().map(centre).collect();
    let origin = centres.iter().sum::<Vector3<f64>>() / v as f64;
    let extent = centres.iter().map(|c| c.norm()).fold(1.0, f64::max);
    let prepared = Prepared {
        normalized: cameras.iter().map(depth_normalized).collect(),
        centres,
        origin,
        extent,
        views: None,
    };
    Ok(prepared)
}

/// [`prepare`] of the views' matrices `K [R | t]`, keeping the views when a camera distorts.
fn prepare_views(views: &[View]) -> Result<Prepared> {
    let cameras: Vec<Matrix3x4<f64>> = views.iter().map(View::projection).collect();
    let mut prepared = prepare(&cameras)?;
    if views.iter().any(|v| v.camera.distortion().is_some()) {
        prepared.views = Some(views.to_vec());
    }
    Ok(prepared)
}

/// View `j` of track `t` (a visible one): its pixel and whitening factor, checked.
fn track_view(tracks: &DensePointTracks, v: usize, t: usize, j: usize) -> Result<(Vector2<f64>, Matrix2<f64>)> {
    observation(tracks.observations, tracks.covariances, t * v + j, t, j)
}

/// Observation `k` of the flat arrays (pixel `observations[2k..]`, covariance `covariances[4k..]`),
/// checked and named as entry `j` of track `t`: its pixel and whitening factor.
fn observation(
    observations: &[f64],
    covariances: Option<&[f64]>,
    k: usize,
    t: usize,
    j: usize,
) -> Result<(Vector2<f64>, Matrix2<f64>)> {
    let x = Vector2::new(observations[2 * k], observations[2 * k + 1]);
    if !(x.x.is_finite() && x.y.is_finite()) {
        return Err(Error::NonFinite {
            what: format!("observations[{t}]"),
            index: j,
        });
    }
    let l = match covariances {
        None => Matrix2::identity(),
        // The name is formatted only on failure: the fast path allocates nothing per track.
        Some(c) => {
            whitening(&Matrix2::from_row_slice(&c[4 * k..4 * k + 4]), "covariances", j).map_err(|e| match e {
                Error::Degenerate { what } => Error::Degenerate {
                    what: what.replacen("covariances", &format!("covariances[{t}]"), 1),
                },
                Error::NonFinite { index, .. } => Error::NonFinite {
                    what: format!("covariances[{t}]"),
                    index,
                },
                other => other,
            })?
        }
    };
    Ok((x, l))
}

/// The conditioning frame of the visible centres (see [`WorldFrame`]), without allocating.
fn frame_of(centres: impl Iterator<Item = Vector3<f64>> + Clone) -> (WorldFrame, f64) {
    let (sum, count) = centres
        .clone()
        .fold((Vector3::zeros(), 0usize), |(s, c), x| (s + x, c + 1));
    let mean = sum / count.max(1) as f64;
    let spread2 = centres.clone().map(|c| (c - mean).norm_squared()).sum::<f64>() / count.max(1) as f64;
    let widest = centres.map(|c| c.norm()).fold(1.0, f64::max);
    (
        WorldFrame {
            centre: mean,
            scale: if spread2 > 0.0 { spread2.sqrt() } else { 1.0 },
        },
        spread2.sqrt() / widest,
    )
}

/// Relative spread of the visible centres below which they coincide (no parallax); the same rule as
/// [`super::triangulate_point`] up to the factor between RMS spread and baseline.
const SAME_CENTRE: f64 = 1e-10;

fn no_parallax(t: usize) -> Error {
    Error::Degenerate {
        what: format!("track {t}: the centres of the cameras that see it coincide (no parallax)"),
    }
}

/// Triangulates every track of `tracks` (dense or one observation per row) seen by `cameras` with
/// `opts`, in parallel: each track as [`super::triangulate_point`] solves it on its observations. The
/// outer error is about the whole call; each track has its own result (module docs). In the rows form
/// a track naming an image beyond the cameras is its own error, and one image seen twice is used
/// twice. With [`Cameras::Views`] the observations are the images' own (distorted) pixels, and an
/// observation whose pixel has no preimage inside its lens's fold is an error of its track, naming it.
/// `progress`, when given, counts the finished tracks, for another thread to poll.
pub fn triangulate_points<'a>(
    cameras: impl Into<Cameras<'a>>,
    tracks: impl Into<PointTracks<'a>>,
    opts: &TriangulationOptions,
    progress: Option<&AtomicUsize>,
) -> Result<Vec<Result<PointTriangulation>>> {
    let (n, one) = solver(cameras.into(), tracks.into(), opts)?;
    Ok(solve_tracks(n, 16, progress, one))
}

/// [`triangulate_points`] handing each track's result to `write(t, row, result)` as it finishes,
/// with row `t` of `rows` (e.g. track `t`'s entries of preallocated output columns), instead of
/// collecting them: nothing is kept per track beyond what `write` keeps. `rows` must have one row
/// per track.
///
/// A stopped batch ([`crate::interrupt`]) does not hand the tracks it had not started to `write`
/// (their rows stay as they were, and it ends without a pass over them): `Ok(Some(reason))` then
/// says why; `Ok(None)`: every track was written. `progress` counts the tracks written.
pub fn points_into<'a, R: Send>(
    cameras: impl Into<Cameras<'a>>,
    tracks: impl Into<PointTracks<'a>>,
    opts: &TriangulationOptions,
    progress: Option<&AtomicUsize>,
    rows: impl IndexedParallelIterator<Item = R>,
    write: impl Fn(usize, R, Result<PointTriangulation>) + Sync + Send,
) -> Result<Option<StopReason>> {
    let (n, one) = solver(cameras.into(), tracks.into(), opts)?;
    solve_tracks_into(n, rows, 16, progress, one, write)
}

/// The number of tracks of a batch, checked, and the solve of track `t`.
fn solver<'a>(
    cameras: Cameras<'_>,
    tracks: PointTracks<'a>,
    opts: &'a TriangulationOptions,
) -> Result<(usize, impl Fn(usize) -> Result<PointTriangulation> + Sync + Send + 'a)> {
    opts.validate()?;
    let prepared = match cameras {
        Cameras::Projections(projections) => prepare(projections)?,
        Cameras::Views(views) => prepare_views(views)?,
    };
    let v = prepared.normalized.len();
    let n = tracks.check(v)?;
    let one = move |t: usize| match tracks {
        PointTracks::Dense(dense) => {
            let views = visible_views(dense.visible, v, t).map(|j| Ok((j, track_view(&dense, v, t, j)?)));
            solve_track(&prepared, opts, t, views)
        }
        PointTracks::Sparse(sparse) => {
            let rows = sparse.csr.observations(t, v)?;
            let views = rows
                .iter()
                .enumerate()
                .map(|(i, &(j, k))| Ok((j, observation(sparse.observations, sparse.covariances, k, t, i)?)));
            solve_track(&prepared, opts, t, views)
        }
    };
    Ok((n, one))
}

/// Track `t` from its observations `(image, (pixel, whitening))`: at least two, with parallax.
fn solve_track(
    prepared: &Prepared,
    opts: &TriangulationOptions,
    t: usize,
    observations: impl Iterator<Item = Result<(usize, (Vector2<f64>, Matrix2<f64>))>>,
) -> Result<PointTriangulation> {
    let started = Instant::now();
    let count = observations.size_hint().0;
    let mut views = Vec::with_capacity(count);
    let mut seen = Vec::with_capacity(count);
    let mut lens_views = Vec::with_capacity(if prepared.views.is_some() { count } else { 0 });
    for o in observations {
        let (j, (x, l)) = o?;
        match &prepared.views {
            Some(all) => {
                let view = LensView::new(&all[j], x, l);
                views.push(first_order_view(&view, seen.len()).map_err(|e| match e {
                    Error::Degenerate { what } => Error::Degenerate {
                        what: format!("track {t}, image {j}: {what}"),
                    },
                    other => other,
                })?);
                lens_views.push(view);
            }
            None => views.push(PointView::new(&prepared.normalized[j], &x, &l)),
        }
        seen.push(j);
    }
    if views.len() < 2 {
        return Err(too_few(opts.method, t, views.len(), 2));
    }
    // Several observations may share an image (two keypoints of one image): all are used, but the
    // point needs two distinct images.
    let mut images = seen.clone();
    images.sort_unstable();
    images.dedup();
    if images.len() < 2 {
        return Err(Error::TooFewCorrespondences {
            method: opts.method.as_str().into(),
            required: "2 distinct images per track".into(),
            actual: format!("track {t}: {} observations, all in image {}", views.len(), images[0]),
        });
    }
    let (frame, spread) = frame_of(images.iter().map(|&j| prepared.centres[j]));
    if spread <= SAME_CENTRE {
        return Err(no_parallax(t));
    }
    Ok(solve_through_lenses(&views, &lens_views, &frame, opts, started))
}

/// Point tracks as a flat list of observations grouped by track ([`Csr`]), for models where each track
/// is seen in few of many images: memory grows with the observations, not with tracks × images. Row `k`
/// is the pixel `observations[2k..2k + 2]` in image `csr.image[k]` (an index into the cameras), with the
/// covariance `covariances[4k..4k + 4]` (row-major 2x2) when given.
#[derive(Debug, Clone, Copy)]
pub struct SparsePointTracks<'a> {
    /// Which rows belong to which track, and their images.
    pub csr: Csr<'a>,
    /// `m · 2` pixels.
    pub observations: &'a [f64],
    /// `m · 4` covariances, or `None` (identity: costs in squared pixels).
    pub covariances: Option<&'a [f64]>,
}

impl SparsePointTracks<'_> {
    /// The number of tracks, after checking the shapes of the arrays (errors about the whole call).
    fn check(&self) -> Result<usize> {
        let n = self.csr.check()?;
        self.csr
            .check_values("observations", Some(self.observations), 2, "2 coordinates")?;
        self.csr.check_values("covariances", self.covariances, 4, "2 x 2")?;
        Ok(n)
    }
}

/// The point tracks of one batch: every track over every camera ([`DensePointTracks`]), or one
/// observation per row ([`SparsePointTracks`]). Both forms (and references to them) convert into it.
#[derive(Debug, Clone, Copy)]
pub enum PointTracks<'a> {
    /// `n` tracks over the `v` cameras, with a visibility mask.
    Dense(DensePointTracks<'a>),
    /// Observations grouped by track.
    Sparse(SparsePointTracks<'a>),
}

impl PointTracks<'_> {
    /// The number of tracks over `v` cameras, after checking the shapes of the arrays (errors about
    /// the whole call).
    fn check(&self, v: usize) -> Result<usize> {
        match self {
            PointTracks::Dense(tracks) => {
                let n = track_count("observations", tracks.observations.len(), v, 2, "2 coordinates")?;
                check_mask(tracks.visible, n, v)?;
                check_values("covariances", tracks.covariances, n, v, 4, "2 x 2")?;
                Ok(n)
            }
            PointTracks::Sparse(tracks) => tracks.check(),
        }
    }
}

crate::triangulation::tracks::tracks_from!(PointTracks: DensePointTracks => Dense, SparsePointTracks => Sparse);

/// The result of [`LinearPoints::from_tracks`], as flat arrays of length `n` (points `n · 3`).
#[derive(Debug, Clone, PartialEq)]
pub struct LinearPoints {
    /// Row-major `(n, 3)` world points; NaN where the track failed or is at infinity.
    pub points: Vec<f64>,
    /// The cost of eq. 19 at each point (squared whitened pixels); NaN where there is no point.
    pub costs: Vec<f64>,
    /// Row-major `(n, 3, 3)` covariances of the points (world units², [`crate::triangulation::uncertainty`]); NaN
    /// where there is no point or its covariance is `None`.
    pub covariances: Vec<f64>,
    /// The degrees of freedom of each cost (`2 v − 3` over its `v` visible views, 0 where there is
    /// no cost): the χ² test of [`crate::triangulation::Report::residual_test`].
    pub residual_dofs: Vec<usize>,
    /// Per track: the status (`Success`, `BehindCamera` or `AtInfinity`) or why it was rejected.
    pub outcomes: Vec<Result<Status>>,
}

/// One track of the linear fast path ([`linear_points_into`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinearTrack {
    /// The world point; NaN at infinity.
    pub point: Vector3<f64>,
    /// The cost of eq. 19 at the point (squared whitened pixels); NaN at infinity.
    pub cost: f64,
    /// The point's covariance ([`crate::triangulation::uncertainty`]), `None` when singular.
    pub covariance: Option<Matrix3<f64>>,
    /// `Success`, `BehindCamera` or `AtInfinity`.
    pub status: Status,
    /// The degrees of freedom of the cost (see [`crate::triangulation::Report::residual_dof`]).
    pub residual_dof: usize,
}

/// The DLT of one track with no allocation: its point, cost and covariance, or its status / error.
/// Three passes over the views: checks and the spread of the centres, the Gram matrix, the cost and
/// the information matrix of [`crate::triangulation::uncertainty::point_covariance`].
fn linear_track(prepared: &Prepared, tracks: &DensePointTracks, v: usize, t: usize) -> Result<LinearTrack> {
    let visible = || visible_views(tracks.visible, v, t);
    let (mut count, mut sum, mut sum2) = (0usize, Vector3::zeros(), 0.0);
    for j in visible() {
        let k = t * v + j;
        if !(tracks.observations[2 * k].is_finite() && tracks.observations[2 * k + 1].is_finite()) {
            return Err(Error::NonFinite {
                what: format!("observations[{t}]"),
                index: j,
            });
        }
        let c = prepared.centres[j] - prepared.origin;
        count += 1;
        sum += c;
        sum2 += c.norm_squared();
    }
    if count < 2 {
        return Err(too_few(Method::Linear, t, count, 2));
    }
    let mean = sum / count as f64;
    let spread = (sum2 / count as f64 - mean.norm_squared()).max(0.0).sqrt();
    if spread <= SAME_CENTRE * prepared.extent {
        return Err(no_parallax(t));
    }
    let frame = WorldFrame {
        centre: prepared.origin + mean,
        scale: spread,
    };
    let view = |j: usize| -> Result<PointView> {
        let k = t * v + j;
        let x = Vector2::new(tracks.observations[2 * k], tracks.observations[2 * k + 1]);
        match tracks.covariances {
            None => Ok(PointView::new(&prepared.normalized[j], &x, &Matrix2::identity())),
            Some(_) => track_view(tracks, v, t, j).map(|(x, l)| PointView::new(&prepared.normalized[j], &x, &l)),
        }
    };
    let mut g = Matrix4::zeros();
    for j in visible() {
        accumulate_dlt(&mut g, &view(j)?, &frame);
    }
    let LinearPoint::Finite(x) = solve_dlt(&g, &frame) else {
        return Ok(LinearTrack {
            point: Vector3::repeat(f64::NAN),
            cost: f64::NAN,
            covariance: None,
            status: Status::AtInfinity,
            residual_dof: 0,
        });
    };
    let (mut cost, mut front, mut information) = (0.0, true, Matrix3::zeros());
    for j in visible() {
        let pv = view(j)?;
        let (r, h) = pv.residual_and_information(&x);
        cost += r.norm_squared();
        information += h;
        front &= pv.depth(&x) > 0.0;
    }
    Ok(LinearTrack {
        point: x,
        cost,
        covariance: covariance_of_information3(&information),
        status: if front { Status::Success } else { Status::BehindCamera },
        residual_dof: (2 * count).saturating_sub(3),
    })
}

impl LinearPoints {
    /// The linear (DLT) point of every track of `tracks` seen by `projections`, in parallel, without
    /// allocating per track (module docs): the fast path of [`Method::Linear`], with flat results and
    /// no report per track.
    pub fn from_tracks(projections: &[Matrix3x4<f64>], tracks: &DensePointTracks) -> Result<LinearPoints> {
        let (n, prepared) = check_batch(projections, tracks)?;
        let v = projections.len();
        let mut out = LinearPoints {
            points: vec![f64::NAN; 3 * n],
            costs: vec![f64::NAN; n],
            covariances: vec![f64::NAN; 9 * n],
            residual_dofs: vec![0; n],
            outcomes: Vec::with_capacity(n),
        };
        let stop = current();
        (0..n)
            .into_par_iter()
            .with_min_len(256)
            .zip(out.points.par_chunks_mut(3))
            .zip(out.costs.par_iter_mut())
            .zip(out.covariances.par_chunks_mut(9))
            .zip(out.residual_dofs.par_iter_mut())
            .map(|((((t, point), cost), covariance), residual_dof)| {
                match stop.as_ref().and_then(|s| s.reason()) {
                    Some(reason) => Err(Error::Interrupted { reason }),
                    None => linear_track(&prepared, tracks, v, t),
                }
                .map(|track| {
                    point.copy_from_slice(track.point.as_slice());
                    *cost = track.cost;
                    *residual_dof = track.residual_dof;
                    if let Some(cov) = track.covariance {
                        // Symmetric: column-major storage is the row-major layout.
                        covariance.copy_from_slice(cov.as_slice());
                    }
                    track.status
                })
            })
            .collect_into_vec(&mut out.outcomes);
        Ok(out)
    }
}

/// [`LinearPoints::from_tracks`] handing each track's estimate to `write(t, row, result)` as it
/// finishes, with row `t` of `rows` (one per track), as [`points_into`] does: a stopped
/// batch does not hand the tracks it had not started to `write` and returns why (`Ok(None)`: every
/// track was written). `progress` counts the tracks written. No allocation per track.
pub fn linear_points_into<R: Send>(
    projections: &[Matrix3x4<f64>],
    tracks: &DensePointTracks,
    progress: Option<&AtomicUsize>,
    rows: impl IndexedParallelIterator<Item = R>,
    write: impl Fn(usize, R, Result<LinearTrack>) + Sync + Send,
) -> Result<Option<StopReason>> {
    let (n, prepared) = check_batch(projections, tracks)?;
    let v = projections.len();
    let one = |t| linear_track(&prepared, tracks, v, t);
    solve_tracks_into(n, rows, 256, progress, one, write)
}
