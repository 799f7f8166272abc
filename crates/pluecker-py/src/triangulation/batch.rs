//! `pluecker.BatchReport`: the per-track report columns shared by every batch result
//! (`PointTriangulations`, `LineTriangulations`, `QuadricTriangulations` extend it), and the one way
//! these results are filled from the core's per-track results: every column is allocated for every
//! track before the solve ([`unstarted`], not started: `interrupted`, NaN), and the core's `_into`
//! batches write each track's row as it finishes ([`Sink`]), so that a stopped batch of millions of
//! tracks hands its results back without a pass over them.
//!
//! A track the core rejected gets a NaN cost, no certificate, a status naming the error kind
//! ([`Status::rejected`]) and a message; its estimate columns are NaN.
//!
//! Also the inputs every batch shares: cameras `(v, 3, 4)` for all tracks or `(n, v, 3, 4)` per
//! track ([`Cameras`]) and per-observation arrays ([`per_observation`]).

use crate::convert::{read, read_any, shape_string, Dim};
use crate::errors::{invalid_argument, shape_error, to_py_err};
use crate::pickle::{reduce, Name};
use crate::properties::{result_class, Mask};
use crate::setup_poll::in_chunks;
use nalgebra::Matrix3x4;
use pluecker::chi_square::ResidualTest;
use pluecker::interrupt::StopReason;
use pluecker::triangulation::TrackCameras;
use pluecker::triangulation::{CertificateKind, CostKind, Method, Report, Status};
use pluecker::Error;
use pyo3::exceptions::PyMemoryError;
use pyo3::prelude::*;
use pyo3::types::PyTuple;
use rayon::prelude::*;
use std::sync::Mutex;

/// Which form a batch's tracks take: dense arrays `(n, v, ...)` with an optional `visible` mask, or
/// one observation per row with `track=` and `image=` (both, and no `visible`): the rows, when given.
/// `n_tracks=` and `cameras=` (`has_cameras`) belong to the rows form; errors name the argument.
pub(crate) fn sparse_form<'a, 'py>(
    track: Option<&'a Bound<'py, PyAny>>,
    image: Option<&'a Bound<'py, PyAny>>,
    visible: Option<&Bound<'py, PyAny>>,
    n_tracks: Option<crate::convert::Integer>,
    has_views: bool,
) -> PyResult<Option<(&'a Bound<'py, PyAny>, &'a Bound<'py, PyAny>)>> {
    match (track, image) {
        (Some(track), Some(image)) if visible.is_none() => Ok(Some((track, image))),
        (Some(_), Some(_)) => Err(invalid_argument(
            "visible",
            "the rows form (track=, image=) lists only what is seen: leave visible out",
        )),
        (Some(_), None) => Err(invalid_argument("image", "track= needs image= (the image of each row)")),
        (None, Some(_)) => Err(invalid_argument("track", "image= needs track= (the track of each row)")),
        (None, None) if n_tracks.is_some() => Err(invalid_argument(
            "n_tracks",
            "n_tracks= counts the tracks of the rows form: pass track= and image=",
        )),
        (None, None) if has_views => Err(invalid_argument(
            "cameras",
            "views take the rows form: pass track= and image= (one observation per row)",
        )),
        (None, None) => Ok(None),
    }
}

/// Why track of `status` and `cost` was not started, if the batch was stopped before it (its cost is
/// NaN; a track stopped while being solved keeps the cost it reached).
fn not_started(status: &str, cost: f64) -> Option<StopReason> {
    if !cost.is_nan() {
        None
    } else if status == Status::Interrupted.as_str() {
        Some(StopReason::Requested)
    } else if status == Status::TimeBudget.as_str() {
        Some(StopReason::TimeBudget)
    } else {
        None
    }
}

/// The estimate columns of a batch result class (its fields beside the [`PyBatchReport`] columns):
/// allocated for every track, NaN until a track's row is written ([`Sink`]).
pub(crate) trait EstimateColumns: Sized {
    /// The core's result of one track.
    type Track;
    /// What a track's cost measures unless its report says otherwise (lines from segments through a
    /// lens that distorts): the `cost_kind` of a track rejected or not started.
    const COST_KIND: CostKind;
    /// One track's entries of the columns.
    type Row<'a>: Send
    where
        Self: 'a;

    /// Columns for `n` tracks, NaN ([`column`]: Ctrl-C is seen while they are filled).
    fn unstarted(py: Python<'_>, n: usize) -> PyResult<Self>;
    /// The rows of every track, to write in parallel.
    fn rows_mut(&mut self) -> impl IndexedParallelIterator<Item = Self::Row<'_>>;
    /// Writes a solved track's estimate into its row; hands back its report and, with an outlier
    /// threshold, its inlier flags.
    fn write(row: Self::Row<'_>, track: Self::Track) -> (Report, Option<Vec<bool>>);
    /// The inlier masks of the tracks (a class without them ignores them).
    fn set_inliers(&mut self, _inliers: InlierColumns) {}
}

/// The message of rejected track `t`: `"track t: ..."`, the core's own `"track t: "` not repeated.
fn track_message(t: usize, err: &Error) -> String {
    let prefix = format!("track {t}: ");
    let text = err.to_string().replacen(&prefix, "", 1);
    format!("{prefix}{text}")
}

/// The report and estimate columns of `n` tracks solved with `method`, not started yet.
pub(crate) fn unstarted<C: EstimateColumns>(py: Python<'_>, method: Method, n: usize) -> PyResult<(PyBatchReport, C)> {
    Ok((
        PyBatchReport::unstarted(py, method, C::COST_KIND, n)?,
        C::unstarted(py, n)?,
    ))
}

/// The rows of every track of `report` and `columns`, for the core's `_into` batches.
pub(crate) fn rows<'a, C: EstimateColumns>(
    report: &'a mut PyBatchReport,
    columns: &'a mut C,
) -> impl IndexedParallelIterator<Item = (ReportRow<'a>, C::Row<'a>)> {
    report.rows_mut().zip(columns.rows_mut())
}

/// Where the core writes each finished track of a batch: its rows of the report and estimate columns
/// in place, the messages of rejected tracks and the inlier masks of a robust batch aside, until
/// [`Sink::finish`].
#[derive(Default)]
pub(crate) struct Sink {
    errors: Mutex<Vec<(usize, String)>>,
    masks: Mutex<Vec<(usize, Vec<bool>)>>,
}

impl Sink {
    /// Track `t`'s result into its rows.
    pub(crate) fn write<C: EstimateColumns>(
        &self,
        t: usize,
        (report, row): (ReportRow, C::Row<'_>),
        result: pluecker::Result<C::Track>,
    ) {
        match result {
            Ok(track) => {
                let (solved, mask) = C::write(row, track);
                if let Some(mask) = mask {
                    lock(&self.masks).push((t, mask));
                }
                report.solved(&solved);
            }
            Err(e) => self.reject(t, report, e),
        }
    }

    /// Track `t`, rejected by the core with `err` ([`ReportRow::rejected`]); its estimate stays NaN.
    pub(crate) fn reject(&self, t: usize, report: ReportRow, err: Error) {
        if let Some(message) = report.rejected(t, err) {
            lock(&self.errors).push(message);
        }
    }

    /// The columns of the `n` tracks, those not written not started because of `stopped`.
    pub(crate) fn finish<C: EstimateColumns>(
        self,
        mut report: PyBatchReport,
        mut columns: C,
        n: usize,
        stopped: Option<StopReason>,
    ) -> (PyBatchReport, C) {
        if let Some(reason) = stopped {
            report.not_started_because(reason);
        }
        report.set_errors(self.errors.into_inner().unwrap_or_else(|p| p.into_inner()));
        let masks = self.masks.into_inner().unwrap_or_else(|p| p.into_inner());
        columns.set_inliers(InlierColumns::from_masks(n, masks));
        (report, columns)
    }
}

/// The vector behind `mutex`, also if a panicking writer poisoned it (the panic is reported anyway).
fn lock<T>(mutex: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    mutex.lock().unwrap_or_else(|p| p.into_inner())
}

/// The inlier masks of a robust batch (`TriangulationOptions.outlier_threshold`): each solved track's
/// flags over its views, concatenated, and their count per track (0 for a rejected track) as the core
/// returns them, until [`InlierColumns::scatter`] lays them out as the observations were given.
#[derive(Debug, Default, serde::Serialize, serde::Deserialize)]
pub(crate) struct InlierColumns {
    flags: Vec<bool>,
    counts: Vec<usize>,
    laid_out: Option<(Vec<bool>, Vec<usize>)>,
}

impl InlierColumns {
    /// The columns of `n` tracks from the masks of the solved ones, `(track, mask)` in any order.
    pub fn from_masks(n: usize, mut masks: Vec<(usize, Vec<bool>)>) -> InlierColumns {
        masks.sort_unstable_by_key(|(t, _)| *t);
        let mut columns = InlierColumns {
            counts: vec![0; n],
            ..Default::default()
        };
        for (t, mask) in masks {
            columns.counts[t] = mask.len();
            columns.flags.extend(mask);
        }
        columns
    }

    /// Lays the flags out in a mask of `shape`: `positions(t)` lists, in track `t`'s order, where its
    /// observations go (false elsewhere, and for every observation of a rejected track).
    pub fn scatter(&mut self, shape: Vec<usize>, positions: impl Fn(usize) -> Vec<usize>) {
        let mut mask = vec![false; shape.iter().product()];
        let mut from = 0;
        for (t, &count) in self.counts.iter().enumerate() {
            if count > 0 {
                for (flag, k) in self.flags[from..from + count].iter().zip(positions(t)) {
                    mask[k] = *flag;
                }
            }
            from += count;
        }
        self.laid_out = Some((mask, shape));
    }

    /// The positions of track `t`'s observations in a dense `(n, v)` batch: its visible views.
    pub fn dense_positions(visible: Option<&[bool]>, v: usize, t: usize) -> Vec<usize> {
        (0..v)
            .filter(|&j| visible.map_or(true, |m| m[t * v + j]))
            .map(|j| t * v + j)
            .collect()
    }

    /// The laid-out mask, `None` when not robust.
    pub fn mask(&self) -> Option<Mask> {
        self.laid_out.clone().map(|(values, shape)| Mask { values, shape })
    }
}

/// The per-track report columns of a batch: the fields of `TriangulationReport`, one entry per track.
#[pyclass(frozen, subclass, name = "BatchReport", module = "pluecker")]
#[derive(Debug, serde::Serialize, serde::Deserialize)]
pub struct PyBatchReport {
    #[serde(deserialize_with = "crate::pickle::name")]
    method: Name,
    cost: Vec<f64>,
    /// What each track's cost measures.
    #[serde(deserialize_with = "crate::pickle::names")]
    cost_kind: Vec<Name>,
    lower_bound: Vec<f64>,
    raw_lower_bound: Vec<f64>,
    relative_gap: Vec<f64>,
    certified: Vec<bool>,
    #[serde(deserialize_with = "crate::pickle::names")]
    certificate: Vec<Name>,
    #[serde(deserialize_with = "crate::pickle::names")]
    status: Vec<Name>,
    nodes: Vec<i64>,
    iterations: Vec<i64>,
    time_seconds: Vec<f64>,
    /// Degrees of freedom of each cost (0: no χ² test); `p_value` derives from them and `cost`.
    residual_dof: Vec<usize>,
    /// `(track, message)` of every rejected track.
    errors: Vec<(usize, String)>,
}

/// One track's entries of the report columns, written in place (by a batch that writes its tracks
/// as they finish, [`PyBatchReport::rows_mut`]).
pub(crate) struct ReportRow<'a> {
    cost: &'a mut f64,
    cost_kind: &'a mut &'static str,
    lower_bound: &'a mut f64,
    raw_lower_bound: &'a mut f64,
    relative_gap: &'a mut f64,
    certified: &'a mut bool,
    certificate: &'a mut &'static str,
    status: &'a mut &'static str,
    nodes: &'a mut i64,
    iterations: &'a mut i64,
    time_seconds: &'a mut f64,
    residual_dof: &'a mut usize,
}

impl ReportRow<'_> {
    /// A solved track's report.
    pub(crate) fn solved(self, report: &Report) {
        *self.cost = report.cost;
        *self.cost_kind = report.cost_kind.as_str();
        // A track without a certificate: NaN bounds and gap, "none", no nodes (the columns' docs).
        let (lower, raw, gap, certified, kind, nodes) = report.certificate.map_or(
            (f64::NAN, f64::NAN, f64::NAN, false, CertificateKind::None.as_str(), 0),
            |c| {
                (
                    c.lower_bound,
                    c.raw_lower_bound,
                    c.relative_gap,
                    c.certified,
                    c.kind.as_str(),
                    c.nodes,
                )
            },
        );
        *self.lower_bound = lower;
        *self.raw_lower_bound = raw;
        *self.relative_gap = gap;
        *self.certified = certified;
        *self.certificate = kind;
        *self.status = report.status.as_str();
        *self.nodes = nodes as i64;
        *self.iterations = report.iterations as i64;
        *self.time_seconds = report.time_seconds;
        *self.residual_dof = report.residual_dof;
    }

    /// A track without a certificate (NaN lower bounds and gap, no nodes or iterations): a linear
    /// estimate of the point fast path, or a rejected track.
    pub(crate) fn uncertified(self, cost: f64, status: &'static str, seconds: f64, residual_dof: usize) {
        *self.cost = cost;
        *self.lower_bound = f64::NAN;
        *self.raw_lower_bound = f64::NAN;
        *self.relative_gap = f64::NAN;
        *self.certified = false;
        *self.certificate = CertificateKind::None.as_str();
        *self.status = status;
        *self.nodes = 0;
        *self.iterations = 0;
        *self.time_seconds = seconds;
        *self.residual_dof = residual_dof;
    }

    /// Track `t`, rejected by the core with `err` (which names the arguments as Python does): NaN
    /// cost, the error's status, time 0; the message to keep, except for a track the call was stopped
    /// before (`Error::Interrupted`): `messages` says it from the status, so that stopping a batch of
    /// millions of tracks stays cheap.
    pub(crate) fn rejected(self, t: usize, err: Error) -> Option<(usize, String)> {
        if let Error::Interrupted { reason } = err {
            self.uncertified(f64::NAN, Status::stopped(reason).as_str(), 0.0, 0);
            return None;
        }
        self.uncertified(f64::NAN, Status::rejected(&err).as_str(), 0.0, 0);
        Some((t, track_message(t, &err)))
    }
}

impl PyBatchReport {
    /// Columns for `n` tracks solved with `method`, costs of kind `cost_kind`, each not started
    /// (`interrupted`) until its row is written ([`PyBatchReport::rows_mut`]); allocated as [`column`] does.
    pub(crate) fn unstarted(py: Python<'_>, method: Method, cost_kind: CostKind, n: usize) -> PyResult<Self> {
        Ok(PyBatchReport {
            method: method.as_str(),
            cost: column(py, f64::NAN, n, 1)?,
            cost_kind: column(py, cost_kind.as_str(), n, 1)?,
            lower_bound: column(py, f64::NAN, n, 1)?,
            raw_lower_bound: column(py, f64::NAN, n, 1)?,
            relative_gap: column(py, f64::NAN, n, 1)?,
            certified: column(py, false, n, 1)?,
            certificate: column(py, CertificateKind::None.as_str(), n, 1)?,
            status: column(py, Status::Interrupted.as_str(), n, 1)?,
            nodes: column(py, 0, n, 1)?,
            iterations: column(py, 0, n, 1)?,
            time_seconds: column(py, 0.0, n, 1)?,
            residual_dof: column(py, 0, n, 1)?,
            errors: Vec::new(),
        })
    }

    /// The rows of every track, to write in parallel.
    pub(crate) fn rows_mut(&mut self) -> impl IndexedParallelIterator<Item = ReportRow<'_>> {
        let numbers = (
            self.cost.par_iter_mut(),
            self.lower_bound.par_iter_mut(),
            self.relative_gap.par_iter_mut(),
            self.time_seconds.par_iter_mut(),
            self.nodes.par_iter_mut(),
            self.iterations.par_iter_mut(),
            self.residual_dof.par_iter_mut(),
        );
        let labels = (
            self.raw_lower_bound.par_iter_mut(),
            self.certified.par_iter_mut(),
            self.certificate.par_iter_mut(),
            self.status.par_iter_mut(),
            self.cost_kind.par_iter_mut(),
        );
        numbers.into_par_iter().zip(labels.into_par_iter()).map(
            |(
                (cost, lower_bound, relative_gap, time_seconds, nodes, iterations, residual_dof),
                (raw_lower_bound, certified, certificate, status, cost_kind),
            )| {
                ReportRow {
                    cost,
                    cost_kind,
                    lower_bound,
                    raw_lower_bound,
                    relative_gap,
                    certified,
                    certificate,
                    status,
                    nodes,
                    iterations,
                    time_seconds,
                    residual_dof,
                }
            },
        )
    }

    /// The tracks whose rows were never written ([`PyBatchReport::unstarted`]) were not started
    /// because of `reason`.
    pub(crate) fn not_started_because(&mut self, reason: StopReason) {
        let status = Status::stopped(reason).as_str();
        if status == Status::Interrupted.as_str() {
            return; // as they were filled
        }
        (self.status.par_iter_mut())
            .zip(self.cost.par_iter())
            .filter(|(s, cost)| not_started(s, **cost).is_some())
            .for_each(|(s, _)| *s = status);
    }

    /// Every track the linear fast path solved (status `success`, `behind_camera` or `at_infinity`),
    /// which it does not time one by one, takes `seconds`, the batch's mean.
    pub(crate) fn time_solved(&mut self, seconds: f64) {
        let solved = [Status::Success, Status::BehindCamera, Status::AtInfinity].map(|s| s.as_str());
        (self.time_seconds.par_iter_mut())
            .zip(self.status.par_iter())
            .filter(|(_, status)| solved.contains(status))
            .for_each(|(time, _)| *time = seconds);
    }

    /// The messages of the rejected tracks, `(track, message)` in any order.
    pub(crate) fn set_errors(&mut self, mut errors: Vec<(usize, String)>) {
        errors.sort_unstable_by_key(|(t, _)| *t);
        self.errors = errors;
    }

    pub(crate) fn len(&self) -> usize {
        self.status.len()
    }

    /// `class(method=..., tracks=..., success=..., certified=..., rejected=...)`.
    pub(crate) fn repr(&self, class: &str) -> String {
        let success = self.status.iter().filter(|s| **s == Status::Success.as_str()).count();
        let certified = self.certified.iter().filter(|c| **c).count();
        format!(
            "{class}(method='{}', tracks={}, success={success}, certified={certified}, rejected={})",
            self.method,
            self.len(),
            self.errors.len()
        )
    }
}

impl PyBatchReport {
    /// `p_value` of every track: the χ² test of its cost with its degrees of freedom (NaN without).
    fn p_values(&self) -> Vec<f64> {
        self.cost
            .iter()
            .zip(&self.residual_dof)
            .map(|(&cost, &dof)| ResidualTest::new(cost, dof).map_or(f64::NAN, |t| t.p_value))
            .collect()
    }

    /// The message of every track: why it was rejected or not started, else empty.
    fn track_messages(&self) -> Vec<String> {
        let mut out: Vec<String> = self
            .status
            .iter()
            .zip(&self.cost)
            .enumerate()
            .map(|(t, (&status, cost))| match not_started(status, *cost) {
                Some(reason) => format!("track {t}: {}", Error::Interrupted { reason }),
                None => String::new(),
            })
            .collect();
        for (track, message) in &self.errors {
            out[*track] = message.clone();
        }
        out
    }
}

result_class! {
    PyBatchReport {
        /// The method that ran: `linear`, `local` or `optimal`.
        method = |b| b.method;
        /// Per track: `success`, or why not (the statuses of `TriangulationReport`, and `too_few_views`, `non_finite`, `degenerate`, ... for a rejected track).
        status = |b| b.status.clone();
        /// Per track: the cost at the estimate, of kind `cost_kind` (NaN for a rejected track).
        cost = |b| b.cost.clone();
        /// Per track: what `cost` measures, as `TriangulationReport.cost_kind`: `reprojection` (points; lines from
        /// segments through a lens that distorts), `line_residual` (other lines) or `conic_residual` (quadrics); for a
        /// rejected track the primitive's own (`line_residual` for lines).
        cost_kind = |b| b.cost_kind.clone();
        /// Per track: the proved lower bound on the cost (the single result's `certificate.lower_bound`; NaN: no bound was computed, as for `linear`, `local` or a rejected track).
        lower_bound = |b| b.lower_bound.clone();
        /// Per track: the proved bound before the cap at the cost (NaN without a bound).
        raw_lower_bound = |b| b.raw_lower_bound.clone();
        /// Per track: `(cost − lower_bound) / max(cost, 1e-12)` (NaN without a bound).
        relative_gap = |b| b.relative_gap.clone();
        /// Per track: whether the estimate is certified globally optimal.
        certified = |b| b.certified.clone();
        /// Per track: the certificate's `kind` (`convexity_test`, `branch_and_bound`, `taylor_branch_and_bound`, `lens_convexity_test`), `none` without one.
        certificate = |b| b.certificate.clone();
        /// Per track: nodes of the certificate's search (0 without one).
        nodes = |b| b.nodes.clone();
        /// Per track: iterations of the local minimisation.
        iterations = |b| b.iterations.clone();
        /// Per track: wall time, seconds.
        time_seconds = |b| b.time_seconds.clone();
        /// Per track: p-value of the χ² test of the cost (NaN without spare degrees of freedom).
        p_value = |b| b.p_values();
        /// Per track: why it was rejected or not started; empty otherwise.
        messages = |b| b.track_messages();
    }

    fn __len__(&self) -> usize {
        self.len()
    }

    /// Pickle support (also `copy.deepcopy`): see `pickle.rs`.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        reduce(py, "BatchReport", self)
    }

    fn __repr__(&self) -> String {
        self.repr("BatchReport")
    }
}

/// An output column of `tracks` rows of `per_track` copies of `value` each; a `MemoryError` rather
/// than an abort when it cannot be allocated. Filled (its pages touched) a chunk at a time with the GIL
/// released, Python's signal handlers running between chunks ([`crate::setup_poll::in_chunks`]).
pub(crate) fn column<T: Clone + Send + Sync>(
    py: Python<'_>,
    value: T,
    tracks: usize,
    per_track: usize,
) -> PyResult<Vec<T>> {
    let too_many = || PyMemoryError::new_err(format!("cannot allocate the results of {tracks} tracks"));
    let n = tracks.checked_mul(per_track).ok_or_else(too_many)?;
    let mut entries = Vec::new();
    entries.try_reserve_exact(n).map_err(|_| too_many())?;
    in_chunks(py, n, |chunk| {
        py.allow_threads(|| entries.resize(chunk.end, value.clone()));
        Ok(())
    })?;
    Ok(entries)
}

/// Row-major entries of a matrix.
pub(crate) fn row_major<const R: usize, const C: usize>(
    m: &nalgebra::SMatrix<f64, R, C>,
) -> impl Iterator<Item = f64> + '_ {
    (0..R).flat_map(move |i| (0..C).map(move |j| m[(i, j)]))
}

/// A matrix's entries in row-major order into `entries` (a track's part of a column); left as they are
/// (NaN) when there is none.
pub(crate) fn write_row_major<const R: usize, const C: usize>(
    entries: &mut [f64],
    matrix: Option<&nalgebra::SMatrix<f64, R, C>>,
) {
    if let Some(m) = matrix {
        entries.iter_mut().zip(row_major(m)).for_each(|(e, v)| *e = v);
    }
}

/// The cameras of a batch: `(v, 3, 4)` shared or `(n, v, 3, 4)` per track; `n` is `None` when shared.
pub(crate) struct Cameras {
    matrices: Vec<Matrix3x4<f64>>,
    tracks: Option<usize>,
    views: usize,
}

impl Cameras {
    pub(crate) fn read(obj: &Bound<'_, PyAny>, min_views: usize, method: Method) -> PyResult<Cameras> {
        let (shape, values) = read_any("cameras", obj)?;
        let (tracks, views) = match shape.as_slice() {
            [v, 3, 4] => (None, *v),
            [n, v, 3, 4] => (Some(*n), *v),
            _ => {
                return Err(shape_error(
                    "cameras",
                    "shape (v, 3, 4) (shared cameras) or (n, v, 3, 4) (cameras per track)",
                    shape_string(&shape),
                ))
            }
        };
        if views < min_views {
            return Err(to_py_err(Error::TooFewCorrespondences {
                method: method.as_str().into(),
                required: format!("{min_views} cameras"),
                actual: format!("{views} camera(s) in cameras"),
            }));
        }
        let matrices = values.chunks_exact(12).map(Matrix3x4::from_row_slice).collect();
        Ok(Cameras {
            matrices,
            tracks,
            views,
        })
    }

    /// A shape error unless an observation array of shape `shape` has `v` views (and `n` tracks for
    /// cameras per track).
    pub(crate) fn check_observations(&self, name: &str, shape: &[usize], tail: &str) -> PyResult<()> {
        let tracks_fit = self.tracks.map_or(true, |n| n == shape[0]);
        if shape[1] != self.views || !tracks_fit {
            let n = self.tracks.map_or("n".to_string(), |n| n.to_string());
            let expected = format!(
                "shape ({n}, {}, {tail}) (one column per camera in projections)",
                self.views
            );
            return Err(shape_error(name, &expected, shape_string(shape)));
        }
        Ok(())
    }

    pub(crate) fn core(&self) -> TrackCameras<'_> {
        match self.tracks {
            None => TrackCameras::Shared((&self.matrices).into()),
            Some(_) => TrackCameras::PerTrack {
                projections: &self.matrices,
                views: self.views,
            },
        }
    }
}

/// `(n, v, ...)` per-observation values of `obj` (`covariances`), checked against `n` tracks and `v` views.
pub(crate) fn per_observation(
    name: &str,
    obj: &Bound<'_, PyAny>,
    n: usize,
    v: usize,
    entry: [usize; 2],
) -> PyResult<Vec<f64>> {
    let spec = [
        Dim::Free("n"),
        Dim::Free("v"),
        Dim::Fixed(entry[0]),
        Dim::Fixed(entry[1]),
    ];
    let (shape, values) = read(name, obj, &spec)?;
    if shape[0] != n || shape[1] != v {
        let expected = format!("shape ({n}, {v}, {}, {}) (one per observation)", entry[0], entry[1]);
        return Err(shape_error(name, &expected, shape_string(&shape)));
    }
    Ok(values)
}
