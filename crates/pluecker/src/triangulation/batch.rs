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

use super::covariance::whitening;
use super::point::{solve_views, PointTriangulation};
use super::point_cost::PointView;
use super::point_linear::{accumulate_dlt, solve_dlt, LinearPoint, WorldFrame};
use super::views::{centre, depth_normalized, validate_cameras};
use super::{Method, Status, TriangulationOptions};
use crate::error::{Error, Result};
use nalgebra::{Matrix2, Matrix3x4, Matrix4, Vector2, Vector3};
use rayon::prelude::*;
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
    let shape = |what: &str, expected: String, actual: usize| Error::Shape {
        what: what.into(),
        expected,
        actual: actual.to_string(),
    };
    if tracks.observations.len() % (2 * v) != 0 {
        return Err(shape(
            "observations",
            format!("n·{v}·2 values (n tracks, {v} views, 2 coordinates)"),
            tracks.observations.len(),
        ));
    }
    let n = tracks.observations.len() / (2 * v);
    if let Some(mask) = tracks.visible {
        if mask.len() != n * v {
            return Err(shape(
                "visible",
                format!("{} flags ({n} tracks x {v} views)", n * v),
                mask.len(),
            ));
        }
    }
    if let Some(covs) = tracks.covariances {
        if covs.len() != 4 * n * v {
            return Err(shape(
                "covariances",
                format!("{} values ({n} tracks x {v} views x 2 x 2)", 4 * n * v),
                covs.len(),
            ));
        }
    }
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

/// One visible view of track `t`: its index, pixel and whitening factor, checked.
fn track_view(tracks: &PointTracks, v: usize, t: usize, j: usize) -> Result<Option<(Vector2<f64>, Matrix2<f64>)>> {
    let k = t * v + j;
    if tracks.visible.is_some_and(|m| !m[k]) {
        return Ok(None);
    }
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
    Ok(Some((x, l)))
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

fn too_few(method: Method, t: usize, visible: usize) -> Error {
    Error::TooFewCorrespondences {
        method: method.as_str().into(),
        required: "2 visible views per track".into(),
        actual: format!("track {t}: {visible} view(s)"),
    }
}

fn no_parallax(t: usize) -> Error {
    Error::Degenerate {
        what: format!("track {t}: the centres of the cameras that see it coincide (no parallax)"),
    }
}

/// Triangulates every track of `tracks` seen by `cameras` (3x4, world → pixels) with `opts`, in
/// parallel. The outer error is about the whole call; each track has its own result (module docs).
pub fn triangulate_points(
    cameras: &[Matrix3x4<f64>],
    tracks: &PointTracks,
    opts: &TriangulationOptions,
) -> Result<Vec<Result<PointTriangulation>>> {
    opts.validate()?;
    let (n, prepared) = check_batch(cameras, tracks)?;
    let v = cameras.len();
    let one = |t: usize| -> Result<PointTriangulation> {
        let started = Instant::now();
        let mut views = Vec::with_capacity(v);
        let mut seen = Vec::with_capacity(v);
        for j in 0..v {
            if let Some((x, l)) = track_view(tracks, v, t, j)? {
                views.push(PointView::new(&prepared.normalized[j], &x, &l));
                seen.push(j);
            }
        }
        if views.len() < 2 {
            return Err(too_few(opts.method, t, views.len()));
        }
        let (frame, spread) = frame_of(seen.iter().map(|&j| prepared.centres[j]));
        if spread <= SAME_CENTRE {
            return Err(no_parallax(t));
        }
        Ok(solve_views(&views, &frame, opts, started))
    };
    Ok((0..n).into_par_iter().with_min_len(16).map(one).collect())
}

/// The result of [`triangulate_points_linear`], as flat arrays of length `n` (points `n · 3`).
#[derive(Debug, Clone, PartialEq)]
pub struct LinearPoints {
    /// Row-major `(n, 3)` world points; NaN where the track failed or is at infinity.
    pub points: Vec<f64>,
    /// The cost of eq. 19 at each point (squared whitened pixels); NaN where there is no point.
    pub costs: Vec<f64>,
    /// Per track: the status (`Success`, `BehindCamera` or `AtInfinity`) or why it was rejected.
    pub outcomes: Vec<Result<Status>>,
}

/// The DLT of one track with no allocation: its point and cost, or its status / error. Three
/// passes over the views: checks and the spread of the centres, the Gram matrix, the cost.
fn linear_track(prepared: &Prepared, tracks: &PointTracks, v: usize, t: usize) -> Result<(Vector3<f64>, f64, Status)> {
    let visible = |j: usize| tracks.visible.map_or(true, |m| m[t * v + j]);
    let (mut count, mut sum, mut sum2) = (0usize, Vector3::zeros(), 0.0);
    for j in (0..v).filter(|&j| visible(j)) {
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
        return Err(too_few(Method::Linear, t, count));
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
            Some(_) => track_view(tracks, v, t, j).map(|o| {
                let (x, l) = o.expect("visible");
                PointView::new(&prepared.normalized[j], &x, &l)
            }),
        }
    };
    let mut g = Matrix4::zeros();
    for j in (0..v).filter(|&j| visible(j)) {
        accumulate_dlt(&mut g, &view(j)?, &frame);
    }
    let nan = Vector3::repeat(f64::NAN);
    let LinearPoint::Finite(x) = solve_dlt(&g, &frame) else {
        return Ok((nan, f64::NAN, Status::AtInfinity));
    };
    let (mut cost, mut front) = (0.0, true);
    for j in (0..v).filter(|&j| visible(j)) {
        let pv = view(j)?;
        let z = pv.depth(&x);
        cost += (pv.numerator(&x) / z).norm_squared();
        front &= z > 0.0;
    }
    Ok((x, cost, if front { Status::Success } else { Status::BehindCamera }))
}

/// The linear (DLT) point of every track, in parallel, without allocating per track (module docs).
pub fn triangulate_points_linear(cameras: &[Matrix3x4<f64>], tracks: &PointTracks) -> Result<LinearPoints> {
    let (n, prepared) = check_batch(cameras, tracks)?;
    let v = cameras.len();
    let mut out = LinearPoints {
        points: vec![f64::NAN; 3 * n],
        costs: vec![f64::NAN; n],
        outcomes: Vec::with_capacity(n),
    };
    (0..n)
        .into_par_iter()
        .with_min_len(256)
        .zip(out.points.par_chunks_mut(3))
        .zip(out.costs.par_iter_mut())
        .map(|((t, point), cost)| match linear_track(&prepared, tracks, v, t) {
            Ok((x, c, status)) => {
                point.copy_from_slice(x.as_slice());
                *cost = c;
                Ok(status)
            }
            Err(e) => Err(e),
        })
        .collect_into_vec(&mut out.outcomes);
    Ok(out)
}
