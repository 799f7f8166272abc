//! Observations given one per row, as COLMAP lists them (`track`, `image` and the row's data): the
//! shared reading and the stable counting sort into the core's compressed rows ([`Csr`]), used by
//! the rows form (`track=`, `image=`) of `triangulate_points`, `triangulate_lines` and
//! `triangulate_quadrics`. The sort and the gathering of the rows run a chunk of rows at
//! a time, Python's signal handlers running between chunks ([`crate::setup_poll::setup_poll`]).

use crate::convert::{read, Dim, Integer};
use crate::errors::{invalid_argument, shape_error};
use crate::setup_poll::in_chunks;
use pluecker::testing::number;
use pluecker::triangulation::Csr;
use pluecker::Error;
use pyo3::prelude::*;
use pyo3::types::PyBool;

/// Non-negative integer indices `(m,)` (track or image ids), `InvalidOptionError` naming the first other
/// value (a negative, fractional or bool entry, or an integer too large for any array: numpy holds those
/// as Python objects).
pub fn indices(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<Vec<usize>> {
    refuse_object_entries(name, obj)?;
    let (_, values) = read(name, obj, &[Dim::Free("m")])?;
    values
        .iter()
        .enumerate()
        .map(|(k, &v)| {
            if v >= 0.0 && v.fract() == 0.0 && v < 2f64.powi(53) {
                Ok(v as usize)
            } else {
                Err(not_an_index(name, k, &number(v)))
            }
        })
        .collect()
}

fn not_an_index(name: &str, k: usize, shown: &str) -> PyErr {
    invalid_argument(name, format!("entry {k} is {shown}, not an index ≥ 0"))
}

/// An index argument that numpy can only hold as Python objects (`[0, 2**64]`, `[True, 1]` stays
/// numeric): `InvalidOptionError` naming the first entry that is not an index ≥ 0 below 2⁶⁴ (a huge
/// or negative int, a bool); any other object (a string) is left to [`read`]'s `TypeError`.
fn refuse_object_entries(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<()> {
    let np = obj.py().import("numpy")?;
    let Ok(array) = np.call_method1("asarray", (obj,)) else {
        return Ok(()); // `read` names the argument in its TypeError
    };
    if array.getattr("dtype")?.getattr("kind")?.extract::<String>()? != "O"
        || array.getattr("ndim")?.extract::<usize>()? != 1
    {
        return Ok(());
    }
    for (k, entry) in array.call_method0("tolist")?.try_iter()?.enumerate() {
        let entry = entry?;
        if entry.is_instance_of::<PyBool>() {
            return Err(not_an_index(name, k, &entry.str()?.to_string()));
        }
        if let Ok(i) = entry.extract::<Integer>() {
            if i.in_range(name, 0, u64::MAX as i128).is_err() {
                let shown = entry.str()?.to_string();
                let shown = if shown.len() > 24 {
                    format!("{}…", &shown[..24])
                } else {
                    shown
                };
                return Err(not_an_index(name, k, &shown));
            }
        }
    }
    Ok(())
}

/// `n_tracks`: `None`, or an integer from 0 to the number of rows `m` (every track beyond the rows
/// would have none, and the result holds one entry per track: memory follows the rows given).
fn track_count_arg(n_tracks: Option<Integer>, m: usize) -> PyResult<Option<usize>> {
    let Some(n) = n_tracks else { return Ok(None) };
    n.in_range("n_tracks", 0, i128::MAX).and_then(|n| {
        if n > m as i128 {
            Err(invalid_argument(
                "n_tracks",
                format!("{n} exceeds the {m} rows given: a track without rows has no answer; number the tracks 0..n densely (numpy.unique(track, return_inverse=True))"),
            ))
        } else {
            Ok(Some(n as usize))
        }
    })
}

/// A `ShapeError` unless the per-observation argument `name` has `m` rows, as `track` has.
pub fn same_count_as(name: &str, rows: usize, m: usize) -> PyResult<()> {
    if rows == m {
        Ok(())
    } else {
        Err(shape_error(
            name,
            &format!("{m} rows (one per entry of track)"),
            rows.to_string(),
        ))
    }
}

/// The rows sorted by track: `order[k']` is the row (as given) of the `k'`-th sorted one.
pub struct SortedRows {
    /// `n + 1` offsets into the sorted rows.
    pub offsets: Vec<usize>,
    /// The image of each sorted row.
    pub images: Vec<usize>,
    /// The row as given of each sorted row.
    pub order: Vec<usize>,
}

impl SortedRows {
    /// Reads `track` and `image` and sorts the rows by track (stable: a track's rows keep their order).
    /// Tracks are `0..n_tracks`, by default `max(track) + 1`; both are at most the number of rows.
    pub fn read(track: &Bound<'_, PyAny>, image: &Bound<'_, PyAny>, n_tracks: Option<Integer>) -> PyResult<SortedRows> {
        let (tracks, images) = (indices("track", track)?, indices("image", image)?);
        let m = tracks.len();
        same_count_as("image", images.len(), m)?;
        let n_tracks = track_count_arg(n_tracks, m)?;
        // Every track id is below the rows given (as `n_tracks` is), so that no allocation exceeds them.
        if let Some((k, &t)) = tracks.iter().enumerate().find(|(_, &t)| t >= m) {
            return Err(invalid_argument(
                "track",
                format!("entry {k} is {t}, not a track id below the {m} rows given (number the tracks 0..n densely: numpy.unique(track, return_inverse=True))"),
            ));
        }
        let used = tracks.iter().max().map_or(0, |t| t + 1);
        let n = match n_tracks {
            Some(n) if n < used => {
                return Err(invalid_argument(
                    "n_tracks",
                    format!("{n} is below max(track) + 1 = {used}"),
                ))
            }
            Some(n) => n,
            None => used,
        };
        let py = track.py();
        let mut offsets = vec![0usize; n + 1];
        in_chunks(py, m, |rows| {
            tracks[rows].iter().for_each(|&t| offsets[t + 1] += 1);
            Ok(())
        })?;
        (0..n).for_each(|t| offsets[t + 1] += offsets[t]);
        let mut next = offsets.clone();
        let mut order = vec![0usize; m];
        in_chunks(py, m, |rows| {
            for k in rows {
                order[next[tracks[k]]] = k;
                next[tracks[k]] += 1;
            }
            Ok(())
        })?;
        let mut sorted_images = Vec::with_capacity(m);
        in_chunks(py, m, |rows| {
            sorted_images.extend(order[rows].iter().map(|&k| images[k]));
            Ok(())
        })?;
        Ok(SortedRows {
            offsets,
            images: sorted_images,
            order,
        })
    }

    /// The number of rows, `m`.
    pub fn len(&self) -> usize {
        self.order.len()
    }

    /// The number of tracks, `n`.
    pub fn tracks(&self) -> usize {
        self.offsets.len() - 1
    }

    /// The core's view of the sorted rows.
    pub fn csr(&self) -> Csr<'_> {
        Csr {
            offsets: &self.offsets,
            image: &self.images,
        }
    }

    /// `values` (`per_row` per row as given) in sorted order.
    fn gather(&self, py: Python<'_>, values: &[f64], per_row: usize) -> PyResult<Vec<f64>> {
        let mut sorted = Vec::with_capacity(values.len());
        in_chunks(py, self.order.len(), |rows| {
            for &k in &self.order[rows] {
                sorted.extend_from_slice(&values[per_row * k..per_row * (k + 1)]);
            }
            Ok(())
        })?;
        Ok(sorted)
    }

    /// The rows as given of track `t`, in its order.
    pub fn rows_of(&self, t: usize) -> Vec<usize> {
        self.order[self.offsets[t]..self.offsets[t + 1]].to_vec()
    }

    /// A track's error as the caller knows the rows: the core's `image[k']` (row `k'` of the rows sorted by
    /// track) becomes `image[k]`, the row as given.
    pub fn restate(&self, e: Error) -> Error {
        match e {
            Error::Shape { what, expected, actual } => Error::Shape {
                what: what
                    .strip_prefix("image[")
                    .and_then(|k| k.strip_suffix(']'))
                    .and_then(|k| k.parse::<usize>().ok())
                    .map_or(what.clone(), |k| format!("image[{}]", self.order[k])),
                expected,
                actual,
            },
            e => e,
        }
    }

    /// Reads the per-row argument `name` of shape `(m, *tail)` and returns it in sorted order.
    pub fn per_row(&self, name: &str, obj: &Bound<'_, PyAny>, tail: &[usize]) -> PyResult<Vec<f64>> {
        let mut spec = vec![Dim::Free("m")];
        spec.extend(tail.iter().map(|&d| Dim::Fixed(d)));
        let (shape, values) = read(name, obj, &spec)?;
        same_count_as(name, shape[0], self.len())?;
        self.gather(obj.py(), &values, tail.iter().product())
    }
}
