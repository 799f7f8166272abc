//! Many point tracks over the same cameras at once, in parallel (rayon).
//!
//! The data are plain row-major slices, the layout of numpy arrays, so that a binding can pass
//! `observations (n, v, 2)`, `visible (n, v)` and `covariances (n, v, 2, 2)` without reshaping:
//! [`PointTracks`]. Every track is triangulated from its visible views only, exactly as
//! [`super::point::triangulate_point`] would do it, and gets its own `Result`: a bad track (too
//! few visible views, NaN in a visible view, a covariance that is not positive definite, no
//! parallax between its views) is an error for that track alone. Errors of the whole call (bad
//! options, bad cameras, inconsistent array lengths) come first, as the outer `Result`.
//!
//! [`triangulate_points_linear`] is the fast path of [`Method::Linear`]: no allocation per track,
//! the results written straight into flat arrays.
//!
//! Every batch polls the stop of [`crate::interrupt`] before each track: tracks not started when it
//! fires are rejected with [`Error::Interrupted`] (the others keep their results), and a track being
//! solved by branch and bound ends with status `Interrupted` or `TimeBudget`.
//!
//! The line and quadric batches ([`super::line_batch`], [`super::quadric_batch`]) share this
//! module's helpers: the shape checks of flat per-observation arrays, the visible views of a track,
//! the cameras of a batch ([`TrackCameras`]), the parallel loop over tracks and the restating of a
//! single-track error for the batch.

use super::covariance::whitening;
use super::point::{solve_views, PointTriangulation};
use super::point_cost::PointView;
use super::point_linear::{accumulate_dlt, solve_dlt, LinearPoint, WorldFrame};
use super::uncertainty::covariance_of_information3;
use super::views::{centre, depth_normalized, validate_cameras};
use super::{Method, Status, TriangulationOptions};
use crate::chi_square::ResidualTest;
use crate::error::{Error, Result};
use crate::interrupt::{current, stop_reason, with_stop};
use nalgebra::{Matrix2, Matrix3, Matrix3x4, Matrix4, Vector2, Vector3};
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

/// Tracks of one batch, as flat row-major arrays (see the module docs). With `v` cameras and `n`
/// tracks: the pixel of track `t` in view `j` is `observations[2(t v + j) ..][..2]`, its flag
/// `visible[t v + j]`, its covariance (row-major 2x2, pixels²) `covariances[4(t v + j) ..][..4]`.
#[derive(Debug, Clone, Copy)]
pub struct PointTracks<'a> {
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
}

/// A shape error of a batch argument.
fn shape(what: &str, expected: String, actual: usize) -> Error {
    Error::Shape {
        what: what.into(),
        expected,
        actual: actual.to_string(),
    }
}

/// The number of tracks `n` of a flat array of `len = n · v · per_view` values (`unit` names the
/// `per_view` values of one observation, e.g. "2 coordinates"), or a shape error naming `what`.
pub(crate) fn track_count(what: &str, len: usize, v: usize, per_view: usize, unit: &str) -> Result<usize> {
    if v == 0 || len % (per_view * v) != 0 {
        return Err(shape(
            what,
            format!("n·{v}·{per_view} values (n tracks, {v} views, {unit})"),
            len,
        ));
    }
    Ok(len / (per_view * v))
}

/// Checks that a per-observation array holds `n · v · per_view` values (`unit`: the shape of one
/// observation's entry, e.g. "2 x 2").
pub(crate) fn check_values(
    what: &str,
    values: Option<&[f64]>,
    n: usize,
    v: usize,
    per_view: usize,
    unit: &str,
) -> Result<()> {
    match values {
        Some(values) if values.len() != per_view * n * v => Err(shape(
            what,
            format!("{} values ({n} tracks x {v} views x {unit})", per_view * n * v),
            values.len(),
        )),
        _ => Ok(()),
    }
}

/// Checks that a visibility mask holds `n · v` flags.
pub(crate) fn check_mask(mask: Option<&[bool]>, n: usize, v: usize) -> Result<()> {
    match mask {
        Some(mask) if mask.len() != n * v => Err(shape(
            "visible",
            format!("{} flags ({n} tracks x {v} views)", n * v),
            mask.len(),
        )),
        _ => Ok(()),
    }
}

/// The views of track `t` (in increasing order) that the mask flags visible: all `v` without a mask.
pub(crate) fn visible_views(mask: Option<&[bool]>, v: usize, t: usize) -> impl Iterator<Item = usize> + Clone + '_ {
    (0..v).filter(move |&j| mask.map_or(true, |m| m[t * v + j]))
}

/// Checks the whole call and returns the number of tracks.
fn check_batch(cameras: &[Matrix3x4<f64>], tracks: &PointTracks) -> Result<(usize, Prepared)> {
    validate_cameras(cameras, "cameras")?;
    let v = cameras.len();
    if v == 0 {
        return Err(Error::Shape {
            what: "cameras".into(),
            expected: "at least 2 cameras".into(),
            actual: "0".into(),
        });
    }
    let n = track_count("observations", tracks.observations.len(), v, 2, "2 coordinates")?;
    check_mask(tracks.visible, n, v)?;
    check_values("covariances", tracks.covariances, n, v, 4, "2 x 2")?;
    let centres: Vec<Vector3<f64>> = cameras.iter().map(centre).collect();
    let origin = centres.iter().sum::<Vector3<f64>>() / v as f64;
    let extent = centres.iter().map(|c| c.norm()).fold(1.0, f64::max);
    let prepared = Prepared {
        normalized: cameras.iter().map(depth_normalized).collect(),
        centres,
        origin,
        extent,
    };
    Ok((n, prepared))
}

/// View `j` of track `t` (a visible one): its pixel and whitening factor, checked.
fn track_view(tracks: &PointTracks, v: usize, t: usize, j: usize) -> Result<(Vector2<f64>, Matrix2<f64>)> {
    let k = t * v + j;
    let x = Vector2::new(tracks.observations[2 * k], tracks.observations[2 * k + 1]);
    if !(x.x.is_finite() && x.y.is_finite()) {
        return Err(Error::NonFinite {
            what: format!("observations[{t}]"),
            index: j,
        });
    }
    let l = match tracks.covariances {
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
/// [`super::point::triangulate_point`] up to the factor between RMS spread and baseline.
const SAME_CENTRE: f64 = 1e-10;

/// Track `t` has `visible` views where the method needs `required`.
pub(crate) fn too_few(method: Method, t: usize, visible: usize, required: usize) -> Error {
    Error::TooFewCorrespondences {
        method: method.as_str().into(),
        required: format!("{required} visible views per track"),
        actual: format!("track {t}: {visible} view(s)"),
    }
}

fn no_parallax(t: usize) -> Error {
    Error::Degenerate {
        what: format!("track {t}: the centres of the cameras that see it coincide (no parallax)"),
    }
}

/// `one(t)` for every track `t < n`, in parallel (rayon tasks of at least `min_len` tracks), in the
/// order of the tracks; `done`, when given, counts the finished tracks (another thread may poll it).
/// The stop installed on the calling thread ([`crate::interrupt`]) is carried into every task: a
/// track not started when it fires is `Err(Error::Interrupted)`, and the solvers of a started one
/// poll it themselves.
pub(crate) fn solve_tracks<X, F>(n: usize, min_len: usize, done: Option<&AtomicUsize>, one: F) -> Vec<Result<X>>
where
    X: Send,
    F: Fn(usize) -> Result<X> + Sync + Send,
{
    let stop = current();
    (0..n)
        .into_par_iter()
        .with_min_len(min_len.max(1))
        .map(|t| {
            let out = with_stop(stop.clone(), || match stop_reason() {
                Some(reason) => Err(Error::Interrupted { reason }),
                None => one(t),
            });
            if let Some(done) = done {
                done.fetch_add(1, Ordering::Relaxed);
            }
            out
        })
        .collect()
}

/// The cameras of a line or quadric batch (3x4, world → pixels, any positive scale; in front means
/// `(P X̃)₃ > 0`, [`super::views`]): one set seen
/// by every track, or one set per track (e.g. independent scenes solved together).
#[derive(Debug, Clone, Copy)]
pub enum TrackCameras<'a> {
    /// `v` cameras shared by every track; view `j` of every track is `cameras[j]`.
    Shared(&'a [Matrix3x4<f64>]),
    /// `n · views` cameras, track-major: view `j` of track `t` is `cameras[t · views + j]`.
    PerTrack {
        /// The cameras of all tracks.
        cameras: &'a [Matrix3x4<f64>],
        /// Views per track, `v`.
        views: usize,
    },
}

impl TrackCameras<'_> {
    /// Views per track, `v`.
    pub fn views(&self) -> usize {
        match self {
            TrackCameras::Shared(cameras) => cameras.len(),
            TrackCameras::PerTrack { views, .. } => *views,
        }
    }

    /// Checks the cameras for the whole call (`n` tracks): shared cameras must all be finite and
    /// non-singular; per-track cameras must number `n · views` (each track's are checked with it).
    pub(crate) fn check(&self, n: usize) -> Result<()> {
        match *self {
            TrackCameras::Shared(cameras) => validate_cameras(cameras, "cameras"),
            TrackCameras::PerTrack { cameras, views } if cameras.len() != n * views => Err(shape(
                "cameras",
                format!("{} cameras ({n} tracks x {views} views)", n * views),
                cameras.len(),
            )),
            TrackCameras::PerTrack { .. } => Ok(()),
        }
    }

    /// The cameras of views `seen` of track `t`.
    pub(crate) fn of_track(&self, t: usize, seen: &[usize]) -> Vec<Matrix3x4<f64>> {
        match *self {
            TrackCameras::Shared(cameras) => seen.iter().map(|&j| cameras[j]).collect(),
            TrackCameras::PerTrack { cameras, views } => seen.iter().map(|&j| cameras[t * views + j]).collect(),
        }
    }

    /// Whether the cameras are indexed by track (their errors then name the track).
    pub(crate) fn per_track(&self) -> bool {
        matches!(self, TrackCameras::PerTrack { .. })
    }
}

/// `text` of a single-track error restated for the batch (see [`in_track`]).
fn restate(text: &str, t: usize, seen: &[usize], arrays: &[&str]) -> String {
    let name_len = text
        .find(|c: char| !(c.is_ascii_lowercase() || c == '_'))
        .unwrap_or(text.len());
    let (name, rest) = text.split_at(name_len);
    let index = rest
        .strip_prefix('[')
        .and_then(|r| r.split_once(']'))
        .and_then(|(i, after)| Some((seen.get(i.parse::<usize>().ok()?)?, after)));
    let per_track = arrays.contains(&name);
    match (per_track, index) {
        (true, Some((j, after))) => format!("{name}[{t}][{j}]{after}"),
        (true, None) => format!("{name}[{t}]{rest}"),
        (false, Some((j, after))) => format!("track {t}: {name}[{j}]{after}"),
        (false, None) => format!("track {t}: {text}"),
    }
}

/// An error of a single-track call on views `seen` of track `t`, restated for the batch: an argument
/// of `arrays` (the ones indexed by track) gets the track, `lines[1]` → `lines[t][seen[1]]` and
/// `lines` → `lines[t]`, and an observation index becomes the batch's view `seen[i]`; any other
/// message is prefixed with `track t: `.
pub(crate) fn in_track(err: Error, t: usize, seen: &[usize], arrays: &[&str]) -> Error {
    let view = |i: usize| seen.get(i).copied().unwrap_or(i);
    match err {
        Error::NonFinite { what, index } if arrays.contains(&what.as_str()) => Error::NonFinite {
            what: format!("{what}[{t}]"),
            index: view(index),
        },
        Error::NonFinite { what, index } => Error::NonFinite {
            what: format!("track {t}: {what}"),
            index: view(index),
        },
        Error::Degenerate { what } => Error::Degenerate {
            what: restate(&what, t, seen, arrays),
        },
        Error::SingularCamera { what } => Error::SingularCamera {
            what: restate(&what, t, seen, arrays),
        },
        Error::Shape { what, expected, actual } => Error::Shape {
            what: restate(&what, t, seen, arrays),
            expected,
            actual,
        },
        Error::TooFewCorrespondences {
            method,
            required,
            actual,
        } => Error::TooFewCorrespondences {
            method,
            required,
            actual: format!("track {t}: {actual}"),
        },
        other @ (Error::InvalidOption { .. } | Error::Interrupted { .. }) => other,
    }
}

/// Triangulates every track of `tracks` seen by `cameras` (3x4, world → pixels) with `opts`, in
/// parallel. The outer error is about the whole call; each track has its own result (module docs).
/// `progress`, when given, counts the finished tracks, for another thread to poll.
pub fn triangulate_points(
    cameras: &[Matrix3x4<f64>],
    tracks: &PointTracks,
    opts: &TriangulationOptions,
    progress: Option<&AtomicUsize>,
) -> Result<Vec<Result<PointTriangulation>>> {
    opts.validate()?;
    let (n, prepared) = check_batch(cameras, tracks)?;
    let v = cameras.len();
    let one = |t: usize| -> Result<PointTriangulation> {
        let started = Instant::now();
        let mut views = Vec::with_capacity(v);
        let mut seen = Vec::with_capacity(v);
        for j in visible_views(tracks.visible, v, t) {
            let (x, l) = track_view(tracks, v, t, j)?;
            views.push(PointView::new(&prepared.normalized[j], &x, &l));
            seen.push(j);
        }
        if views.len() < 2 {
            return Err(too_few(opts.method, t, views.len(), 2));
        }
        let (frame, spread) = frame_of(seen.iter().map(|&j| prepared.centres[j]));
        if spread <= SAME_CENTRE {
            return Err(no_parallax(t));
        }
        Ok(solve_views(&views, &frame, opts, started))
    };
    Ok(solve_tracks(n, 16, progress, one))
}

/// The result of [`triangulate_points_linear`], as flat arrays of length `n` (points `n · 3`).
#[derive(Debug, Clone, PartialEq)]
pub struct LinearPoints {
    /// Row-major `(n, 3)` world points; NaN where the track failed or is at infinity.
    pub points: Vec<f64>,
    /// The cost of eq. 19 at each point (squared whitened pixels); NaN where there is no point.
    pub costs: Vec<f64>,
    /// Row-major `(n, 3, 3)` covariances of the points (world units², [`super::uncertainty`]); NaN
    /// where there is no point or its covariance is `None`.
    pub covariances: Vec<f64>,
    /// The p-value of each cost's χ² test ([`super::Report::residual_test`]); NaN where there is none.
    pub p_values: Vec<f64>,
    /// Per track: the status (`Success`, `BehindCamera` or `AtInfinity`) or why it was rejected.
    pub outcomes: Vec<Result<Status>>,
}

/// One track of the linear fast path: point, cost of eq. 19, covariance, status, and the p-value of
/// the cost's χ² test (NaN when there is none; see [`super::Report::residual_test`]).
type LinearTrack = (Vector3<f64>, f64, Option<Matrix3<f64>>, Status, f64);

/// The DLT of one track with no allocation: its point, cost and covariance, or its status / error.
/// Three passes over the views: checks and the spread of the centres, the Gram matrix, the cost and
/// the information matrix of [`super::uncertainty::point_covariance`].
fn linear_track(prepared: &Prepared, tracks: &PointTracks, v: usize, t: usize) -> Result<LinearTrack> {
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
    let nan = Vector3::repeat(f64::NAN);
    let LinearPoint::Finite(x) = solve_dlt(&g, &frame) else {
        return Ok((nan, f64::NAN, None, Status::AtInfinity, f64::NAN));
    };
    let (mut cost, mut front, mut information) = (0.0, true, Matrix3::zeros());
    for j in visible() {
        let pv = view(j)?;
        let (r, h) = pv.residual_and_information(&x);
        cost += r.norm_squared();
        information += h;
        front &= pv.depth(&x) > 0.0;
    }
    let covariance = covariance_of_information3(&information);
    let p_value = ResidualTest::new(cost, (2 * count).saturating_sub(3)).map_or(f64::NAN, |t| t.p_value);
    Ok((
        x,
        cost,
        covariance,
        if front { Status::Success } else { Status::BehindCamera },
        p_value,
    ))
}

/// The linear (DLT) point of every track, in parallel, without allocating per track (module docs).
pub fn triangulate_points_linear(cameras: &[Matrix3x4<f64>], tracks: &PointTracks) -> Result<LinearPoints> {
    let (n, prepared) = check_batch(cameras, tracks)?;
    let v = cameras.len();
    let mut out = LinearPoints {
        points: vec![f64::NAN; 3 * n],
        costs: vec![f64::NAN; n],
        covariances: vec![f64::NAN; 9 * n],
        p_values: vec![f64::NAN; n],
        outcomes: Vec::with_capacity(n),
    };
    let stop = current();
    (0..n)
        .into_par_iter()
        .with_min_len(256)
        .zip(out.points.par_chunks_mut(3))
        .zip(out.costs.par_iter_mut())
        .zip(out.covariances.par_chunks_mut(9))
        .zip(out.p_values.par_iter_mut())
        .map(
            |((((t, point), cost), covariance), p_value)| match stop.as_ref().and_then(|s| s.reason()) {
                Some(reason) => Err(Error::Interrupted { reason }),
                None => linear_track(&prepared, tracks, v, t),
            }
            .and_then(|track| {
                let (x, c, cov, status, p) = track;
                point.copy_from_slice(x.as_slice());
                *cost = c;
                *p_value = p;
                if let Some(cov) = cov {
                    // Symmetric: column-major storage is the row-major layout.
                    covariance.copy_from_slice(cov.as_slice());
                }
                Ok(status)
            }),
        )
        .collect_into_vec(&mut out.outcomes);
    Ok(out)
}
