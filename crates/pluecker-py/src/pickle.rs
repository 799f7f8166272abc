//! Pickling (and so `copy.deepcopy`) of every result class.
//!
//! A result's `__reduce__` writes the value it holds with serde (the core's `serde` feature) in CBOR
//! (`ciborium`: floats bit for bit, NaN included) — the core result it wraps, or for a subclass the
//! pair (base class's value, its own) — and names the function that rebuilds it,
//! `pluecker._core._unpickle(kind, data)`. The bytes start with the package version: they are a
//! private format, read back only by the same version (a pickle from another version is a
//! `PlueckerError`, never a wrong object).

use crate::errors::PlueckerError;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyTuple};
use pyo3::PyClass;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Deserializer, Serialize};
use std::collections::HashSet;
use std::sync::Mutex;

/// The version every pickle starts with.
const VERSION: &str = env!("CARGO_PKG_VERSION");

/// `(pluecker._core._unpickle, (kind, data))`: what `__reduce__` returns for a result of class `kind`
/// that holds `value` (read back by [`plain`] or [`subclass!`]).
pub fn reduce<'py, T: Serialize>(
    py: Python<'py>,
    kind: &str,
    value: &T,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
    let mut data = Vec::new();
    ciborium::into_writer(VERSION, &mut data)
        .and_then(|()| ciborium::into_writer(value, &mut data))
        .map_err(|e| PlueckerError::new_err(format!("cannot pickle a {kind}: {e}")))?;
    let restore = py.import("pluecker._core")?.getattr("_unpickle")?;
    let args = PyTuple::new(
        py,
        [kind.into_pyobject(py)?.into_any(), PyBytes::new(py, &data).into_any()],
    )?;
    Ok((restore, args))
}

/// The data of a pickle of class `kind` after its version; a `PlueckerError` when the pickle is from
/// another version.
pub fn payload<'a>(kind: &str, data: &'a [u8]) -> PyResult<&'a [u8]> {
    let mut input = data;
    let version: String = ciborium::from_reader(&mut input).map_err(|_| malformed(kind))?;
    if version != VERSION {
        return Err(PlueckerError::new_err(format!(
            "cannot unpickle a {kind} made by pluecker {version} with pluecker {VERSION} (results pickle within one version)"
        )));
    }
    Ok(input)
}

/// The value of a pickle of class `kind`: `payload` must hold it and nothing else.
pub fn value<T: DeserializeOwned>(kind: &str, payload: &[u8]) -> PyResult<T> {
    let mut input = payload;
    let value = ciborium::from_reader(&mut input).map_err(|_| malformed(kind))?;
    if !input.is_empty() {
        return Err(malformed(kind));
    }
    Ok(value)
}

fn malformed(kind: &str) -> PyErr {
    PlueckerError::new_err(format!("cannot unpickle a {kind}: the data are malformed"))
}

/// A result of class `T` read from the payload of a pickle of class `kind`.
pub fn plain<T>(py: Python<'_>, kind: &str, payload: &[u8]) -> PyResult<PyObject>
where
    T: PyClass + DeserializeOwned + Into<PyClassInitializer<T>>,
{
    Ok(Py::new(py, value::<T>(kind, payload)?)?.into_any())
}

/// A result of class `$sub`, a subclass of `$base`, read from the payload of a pickle of class `$kind`
/// (the pair of the base part and its own).
macro_rules! subclass {
    ($py:expr, $kind:expr, $payload:expr, $base:ty, $sub:ty) => {{
        let (base, sub) = $crate::pickle::value::<($base, $sub)>($kind, $payload)?;
        Ok(Py::new($py, PyClassInitializer::from(base).add_subclass(sub))?.into_any())
    }};
}
pub(crate) use subclass;

/// The `&'static str` of a name read back: each distinct string is leaked once and reused, so that
/// unpickling many results does not grow memory (the names are a few enum names).
fn intern(s: String) -> &'static str {
    static NAMES: Mutex<Option<HashSet<&'static str>>> = Mutex::new(None);
    let mut guard = NAMES.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
    let names = guard.get_or_insert_with(HashSet::new);
    if let Some(name) = names.get(s.as_str()) {
        return name;
    }
    let name: &'static str = Box::leak(s.into_boxed_str());
    names.insert(name);
    name
}

/// A name held by a result (a column of enum names), read back by [`name`] or [`names`]. An alias, so
/// that serde's derive does not take a `&'static str` field for a string borrowed from the pickle.
pub type Name = &'static str;

/// `#[serde(deserialize_with = "...")]` of a [`Name`] field: the name read, interned.
pub fn name<'de, D: Deserializer<'de>>(deserializer: D) -> Result<Name, D::Error> {
    Ok(intern(String::deserialize(deserializer)?))
}

/// `#[serde(deserialize_with = "...")]` of a `Vec<Name>` field: the names read, interned.
pub fn names<'de, D: Deserializer<'de>>(deserializer: D) -> Result<Vec<Name>, D::Error> {
    Ok(Vec::<String>::deserialize(deserializer)?
        .into_iter()
        .map(intern)
        .collect())
}
