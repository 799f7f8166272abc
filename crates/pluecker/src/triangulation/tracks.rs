//! Helpers shared by the batches of points ([`super::point::batch`]), lines ([`super::line::batch`]) and
//! quadrics ([`super::quadric::batch`]): the shape checks of flat per-observation arrays, the visible
//! views of a track, the cameras of a batch ([`TrackCameras`]), the parallel loop over tracks and the
//! restating of a single-track error for the batch.

use crate::error::{Error, Result};
use crate::interrupt::{current, stop_reason, Installed, StopReason};
use crate::triangulation::views::{validate_cameras, Cameras, View};
use crate::triangulation::Method;
use nalgebra::Matrix3x4;
use rayon::prelude::*;
use std::borrow::Cow;
use std::sync::atomic::{AtomicUsize, Ordering};

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

/// Tracks given one observation per row, grouped by track (compressed sparse rows), for models where a
/// track is seen in few of many images: track `t` owns rows `offsets[t]..offsets[t + 1]`, and row `k`
/// is an observation in image `image[k]` (an index into the projections; `image`, as the Python
/// argument of the same rows). The per-observation arrays of a
/// sparse batch hold one entry per row.
#[derive(Debug, Clone, Copy)]
pub struct Csr<'a> {
    /// `n + 1` non-decreasing offsets, from 0 to the number of rows `m`.
    pub offsets: &'a [usize],
    /// `m` image indices, one per row.
    pub image: &'a [usize],
}

impl Csr<'_> {
    /// The number of tracks, after checking the offsets against the `m` rows (an error of the call).
    pub(crate) fn check(&self) -> Result<usize> {
        let m = self.image.len();
        match (self.offsets.first(), self.offsets.last()) {
            (Some(0), Some(&last)) if last == m => {}
            _ => {
                return Err(shape(
                    "offsets",
                    format!("n + 1 offsets from 0 to {m} (the observations)"),
                    self.offsets.len(),
                ))
            }
        }
        if let Some(t) = self.offsets.windows(2).position(|w| w[1] < w[0]) {
            return Err(shape(
                "offsets",
                format!("non-decreasing offsets (offsets[{}] < offsets[{t}])", t + 1),
                t + 1,
            ));
        }
        Ok(self.offsets.len() - 1)
    }

    /// Checks that a per-observation array holds `m · per_row` values (`unit`: one entry's shape).
    pub(crate) fn check_values(&self, what: &str, values: Option<&[f64]>, per_row: usize, unit: &str) -> Result<()> {
        let m = self.image.len();
        match values {
            Some(values) if values.len() != per_row * m => Err(shape(
                what,
                format!("{} values ({m} observations x {unit})", per_row * m),
                values.len(),
            )),
            _ => Ok(()),
        }
    }

    /// `(image, row)` of every observation of track `t`, in row order; an image beyond the `v` cameras
    /// is the track's own error. An image may appear more than once (two keypoints of one image, as
    /// COLMAP's track merging leaves them): see [`Csr::distinct_observations`] for the kinds that refuse it.
    pub(crate) fn observations(&self, t: usize, v: usize) -> Result<Vec<(usize, usize)>> {
        let rows = self.offsets[t]..self.offsets[t + 1];
        let images = &self.image[rows.clone()];
        if let Some(i) = images.iter().position(|&j| j >= v) {
            return Err(Error::Shape {
                what: format!("image[{}]", rows.start + i),
                expected: format!("an image index below {v} (the cameras)"),
                actual: images[i].to_string(),
            });
        }
        Ok(images.iter().copied().zip(rows).collect())
    }

    /// [`Csr::observations`] of a track that must see each image at most once (lines and quadrics,
    /// whose two-view charts need two distinct cameras): an image seen twice is the track's own error.
    pub(crate) fn distinct_observations(&self, t: usize, v: usize) -> Result<Vec<(usize, usize)>> {
        let seen = self.observations(t, v)?;
        if let Some(i) = (1..seen.len()).find(|&i| seen[..i].iter().any(|o| o.0 == seen[i].0)) {
            return Err(Error::Degenerate {
                what: format!("track {t}: image {} observed twice", seen[i].0),
            });
        }
        Ok(seen)
    }
}

/// `(view, row)` of the visible views of track `t` of a dense batch of `v` views (row `t v + j`).
pub(crate) fn dense_observations(mask: Option<&[bool]>, v: usize, t: usize) -> Vec<(usize, usize)> {
    visible_views(mask, v, t).map(|j| (j, t * v + j)).collect()
}

/// Track `t` has `visible` views where the method needs `required`.
pub(crate) fn too_few(method: Method, t: usize, visible: usize, required: usize) -> Error {
    Error::TooFewCorrespondences {
        method: method.as_str().into(),
        required: format!("{required} visible views per track"),
        actual: format!("track {t}: {visible} view(s)"),
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
        // Installed once per rayon task, not per track (an `Arc` clone per track contends).
        .map_init(
            || Installed::new(stop.clone()),
            |_, t| {
                let out = unless_stopped(t, &one);
                count(done);
                out
            },
        )
        .collect()
}

/// [`solve_tracks`] handing each track's result to `write(t, row, result)` as it finishes, with
/// row `t` of `rows` (one per track), instead of collecting them: a binding writes them straight into
/// its output columns. `rows` must number the `n` tracks (else [`Error::Shape`], the caller's error,
/// not the data's); `done` counts the tracks written.
///
/// Once the installed stop fires, the tracks not started are not handed to `write` at all (their rows
/// stay as they were, and the loop ends without a pass over them): the reason is returned, `None`
/// when every track was written.
pub(crate) fn solve_tracks_into<X, R, F, W>(
    n: usize,
    rows: impl IndexedParallelIterator<Item = R>,
    min_len: usize,
    done: Option<&AtomicUsize>,
    one: F,
    write: W,
) -> Result<Option<StopReason>>
where
    R: Send,
    F: Fn(usize) -> Result<X> + Sync + Send,
    W: Fn(usize, R, Result<X>) + Sync + Send,
{
    check_rows(rows.len(), n)?;
    let stop = current();
    Ok(rows
        .enumerate()
        .with_min_len(min_len.max(1))
        .try_for_each_init(
            || Installed::new(stop.clone()),
            |_, (t, row)| {
                if let Some(reason) = stop_reason() {
                    return Err(reason);
                }
                write(t, row, one(t));
                count(done);
                Ok(())
            },
        )
        .err())
}

/// The output rows of a batch of `n` tracks number `rows`: an error of the caller's, not the data's.
fn check_rows(rows: usize, n: usize) -> Result<()> {
    if rows == n {
        return Ok(());
    }
    Err(Error::Shape {
        what: "rows".into(),
        expected: format!("one output row per track ({n})"),
        actual: rows.to_string(),
    })
}

/// `one(t)`, or `Err(Error::Interrupted)` when the installed stop has fired.
fn unless_stopped<X>(t: usize, one: impl Fn(usize) -> Result<X>) -> Result<X> {
    match stop_reason() {
        Some(reason) => Err(Error::Interrupted { reason }),
        None => one(t),
    }
}

fn count(done: Option<&AtomicUsize>) {
    if let Some(done) = done {
        done.fetch_add(1, Ordering::Relaxed);
    }
}

/// The cameras of a line or quadric batch: one set seen by every track ([`Cameras`]: 3x4 projections
/// or views), or 3x4 projections given per track (e.g. independent scenes solved together). Every
/// form of [`Cameras`] converts into it.
#[derive(Debug, Clone, Copy)]
pub enum TrackCameras<'a> {
    /// `v` cameras shared by every track; view `j` of every track is camera `j` (errors name them
    /// `projections`).
    Shared(Cameras<'a>),
    /// `n · views` projections (3x4, world → pixels, any positive scale; in front means
    /// `(P X̃)₃ > 0`), track-major: view `j` of track `t` is `projections[t · views + j]`.
    PerTrack {
        /// The projections of all tracks.
        projections: &'a [Matrix3x4<f64>],
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
}

impl<'a> From<Cameras<'a>> for TrackCameras<'a> {
    fn from(cameras: Cameras<'a>) -> Self {
        TrackCameras::Shared(cameras)
    }
}

macro_rules! track_cameras_from {
    ($($t:ty),+) => {
        $(impl<'a> From<$t> for TrackCameras<'a> {
            fn from(cameras: $t) -> Self {
                TrackCameras::Shared(cameras.into())
            }
        })+
    };
}
track_cameras_from!(&'a [Matrix3x4<f64>], &'a Vec<Matrix3x4<f64>>, &'a [View], &'a Vec<View>);

impl<'a, const N: usize> From<&'a [Matrix3x4<f64>; N]> for TrackCameras<'a> {
    fn from(cameras: &'a [Matrix3x4<f64>; N]) -> Self {
        TrackCameras::Shared(cameras.into())
    }
}

impl<'a, const N: usize> From<&'a [View; N]> for TrackCameras<'a> {
    fn from(cameras: &'a [View; N]) -> Self {
        TrackCameras::Shared(cameras.into())
    }
}

/// The 3x4 projections of a line or quadric batch ([`TrackCameras`] once its views, if any, are
/// resolved into their matrices).
#[derive(Debug, Clone)]
pub(crate) enum Projections<'a> {
    /// Shared by every track.
    Shared(Cow<'a, [Matrix3x4<f64>]>),
    /// Per track, track-major.
    PerTrack {
        projections: &'a [Matrix3x4<f64>],
        views: usize,
    },
}

impl Projections<'_> {
    /// Views per track, `v`.
    pub(crate) fn views(&self) -> usize {
        match self {
            Projections::Shared(cameras) => cameras.len(),
            Projections::PerTrack { views, .. } => *views,
        }
    }

    /// Checks the cameras for the whole call (`n` tracks): shared cameras must all be finite and
    /// non-singular; per-track cameras must number `n · views` (each track's are checked with it).
    pub(crate) fn check(&self, n: usize) -> Result<()> {
        match *self {
            Projections::Shared(ref cameras) => validate_cameras(cameras, "cameras"),
            Projections::PerTrack { projections, views } if projections.len() != n * views => Err(shape(
                "cameras",
                format!("{} projections ({n} tracks x {views} views)", n * views),
                projections.len(),
            )),
            Projections::PerTrack { .. } => Ok(()),
        }
    }

    /// The cameras of views `seen` of track `t`.
    pub(crate) fn of_track(&self, t: usize, seen: &[usize]) -> Vec<Matrix3x4<f64>> {
        match *self {
            Projections::Shared(ref cameras) => seen.iter().map(|&j| cameras[j]).collect(),
            Projections::PerTrack { projections, views } => seen.iter().map(|&j| projections[t * views + j]).collect(),
        }
    }

    /// Whether the cameras are indexed by track (their errors then name the track).
    pub(crate) fn per_track(&self) -> bool {
        matches!(self, Projections::PerTrack { .. })
    }
}

/// The `From` impls of a batch's tracks enum `$tracks`: each form `$form` (and a reference to it)
/// becomes variant `$variant`.
macro_rules! tracks_from {
    ($tracks:ident: $($form:ident => $variant:ident),+) => {
        $(
            impl<'a> From<$form<'a>> for $tracks<'a> {
                fn from(tracks: $form<'a>) -> Self {
                    $tracks::$variant(tracks)
                }
            }
            impl<'a> From<&$form<'a>> for $tracks<'a> {
                fn from(tracks: &$form<'a>) -> Self {
                    $tracks::$variant(*tracks)
                }
            }
        )+
        impl<'a> From<&$tracks<'a>> for $tracks<'a> {
            fn from(tracks: &$tracks<'a>) -> Self {
                *tracks
            }
        }
    };
}
pub(crate) use tracks_from;

/// [`Error::InvalidOption`] naming `cameras` for a form of tracks that the cameras given cannot
/// solve (`why` says which ones can).
pub(crate) fn unsupported_cameras(why: &str) -> Error {
    Error::InvalidOption {
        name: "cameras".into(),
        reason: why.into(),
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_that_do_not_number_the_tracks_are_refused_before_any_is_solved() {
        let solved = AtomicUsize::new(0);
        let one = |t: usize| -> Result<usize> {
            solved.fetch_add(1, Ordering::Relaxed);
            Ok(t)
        };
        let refused = solve_tracks_into(3, (0..2usize).into_par_iter(), 1, None, one, |_, _, _| {});
        assert!(matches!(refused, Err(Error::Shape { .. })), "{refused:?}");
        assert_eq!(solved.load(Ordering::Relaxed), 0);
        let written = std::sync::Mutex::new(Vec::new());
        let done = solve_tracks_into(3, (0..3usize).into_par_iter(), 1, None, one, |t, row, r| {
            written.lock().unwrap().push((t, row, r.unwrap()))
        });
        assert!(matches!(done, Ok(None)), "{done:?}");
        let mut written = written.into_inner().unwrap();
        written.sort();
        assert_eq!(written, vec![(0, 0, 0), (1, 1, 1), (2, 2, 2)]);
    }
}
