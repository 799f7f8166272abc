//! Pickling (and so `copy.deepcopy`) of every result class.
//!
//! A result's `__reduce__` packs the core data it owns into bytes with [`Pack`] — exactly: floats bit
//! for bit, NaN included — and names the function that rebuilds it, `pluecker._core._unpickle(kind,
//! data)`. The bytes start with the package version: they are a private format, read back only by the
//! same version (a pickle from another version is a `PlueckerError`, never a wrong object).
//!
//! `pack` destructures each struct completely and `unpack` builds it with a struct literal, so a field
//! added to a result does not compile until it is pickled too.

use crate::errors::PlueckerError;
use nalgebra::SMatrix;
use pluecker::camera::Intrinsics;
use pluecker::chi_square::ResidualTest;
use pluecker::geometry::dual_quaternion::DualQuaternion;
use pluecker::geometry::plucker::LineChart;
use pluecker::geometry::Ellipse;
use pluecker::optim::Termination;
use pluecker::pose::{CovarianceSource, Method as PoseMethod, PoseDetails, RansacReport, RansacStop, StageReport};
use pluecker::triangulation::fitting::{FittedConic, FittedLine};
use pluecker::triangulation::{Certificate, CertificateKind, CostKind, Method, Report, Status};
use pluecker::Primitive;
use pluecker::{Pose, PoseResult};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyTuple};
use pyo3::PyClass;
use std::collections::HashSet;
use std::sync::Mutex;

/// A value that packs into bytes and back.
pub trait Pack: Sized {
    fn pack(&self, out: &mut Vec<u8>);
    /// `None` when the bytes end early or hold an impossible value.
    fn unpack(input: &mut Reader<'_>) -> Option<Self>;
}

/// The unread rest of a pickle.
pub struct Reader<'a> {
    bytes: &'a [u8],
}

impl<'a> Reader<'a> {
    fn take<const N: usize>(&mut self) -> Option<[u8; N]> {
        let (head, rest) = self.bytes.split_at_checked(N)?;
        self.bytes = rest;
        head.try_into().ok()
    }

    fn take_slice(&mut self, n: usize) -> Option<&'a [u8]> {
        let (head, rest) = self.bytes.split_at_checked(n)?;
        self.bytes = rest;
        Some(head)
    }
}

impl Pack for f64 {
    fn pack(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.to_bits().to_le_bytes());
    }
    fn unpack(input: &mut Reader<'_>) -> Option<Self> {
        Some(f64::from_bits(u64::from_le_bytes(input.take()?)))
    }
}

impl Pack for u64 {
    fn pack(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.to_le_bytes());
    }
    fn unpack(input: &mut Reader<'_>) -> Option<Self> {
        Some(u64::from_le_bytes(input.take()?))
    }
}

impl Pack for usize {
    fn pack(&self, out: &mut Vec<u8>) {
        (*self as u64).pack(out)
    }
    fn unpack(input: &mut Reader<'_>) -> Option<Self> {
        usize::try_from(u64::unpack(input)?).ok()
    }
}

impl Pack for i64 {
    fn pack(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.to_le_bytes());
    }
    fn unpack(input: &mut Reader<'_>) -> Option<Self> {
        Some(i64::from_le_bytes(input.take()?))
    }
}

impl Pack for bool {
    fn pack(&self, out: &mut Vec<u8>) {
        out.push(u8::from(*self));
    }
    fn unpack(input: &mut Reader<'_>) -> Option<Self> {
        match input.take::<1>()? {
            [0] => Some(false),
            [1] => Some(true),
            _ => None,
        }
    }
}

impl Pack for String {
    fn pack(&self, out: &mut Vec<u8>) {
        self.len().pack(out);
        out.extend_from_slice(self.as_bytes());
    }
    fn unpack(input: &mut Reader<'_>) -> Option<Self> {
        let n = usize::unpack(input)?;
        String::from_utf8(input.take_slice(n)?.to_vec()).ok()
    }
}

/// The `&'static str` of a name read back: each distinct string is leaked once and reused, so that
/// unpickling many results does not grow memory (the names are a few enum names and stage kinds).
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

impl Pack for &'static str {
    fn pack(&self, out: &mut Vec<u8>) {
        self.to_string().pack(out)
    }
    fn unpack(input: &mut Reader<'_>) -> Option<Self> {
        Some(intern(String::unpack(input)?))
    }
}

impl<T: Pack> Pack for Option<T> {
    fn pack(&self, out: &mut Vec<u8>) {
        self.is_some().pack(out);
        if let Some(v) = self {
            v.pack(out);
        }
    }
    fn unpack(input: &mut Reader<'_>) -> Option<Self> {
        Some(if bool::unpack(input)? {
            Some(T::unpack(input)?)
        } else {
            None
        })
    }
}

impl<T: Pack> Pack for Vec<T> {
    fn pack(&self, out: &mut Vec<u8>) {
        self.len().pack(out);
        self.iter().for_each(|v| v.pack(out));
    }
    fn unpack(input: &mut Reader<'_>) -> Option<Self> {
        let n = usize::unpack(input)?;
        // Every element takes at least one byte: a corrupt length cannot reserve more than the data.
        let mut v = Vec::with_capacity(n.min(input.bytes.len()));
        for _ in 0..n {
            v.push(T::unpack(input)?);
        }
        Some(v)
    }
}

impl<A: Pack, B: Pack> Pack for (A, B) {
    fn pack(&self, out: &mut Vec<u8>) {
        self.0.pack(out);
        self.1.pack(out);
    }
    fn unpack(input: &mut Reader<'_>) -> Option<Self> {
        Some((A::unpack(input)?, B::unpack(input)?))
    }
}

impl<T: Pack, const N: usize> Pack for [T; N] {
    fn pack(&self, out: &mut Vec<u8>) {
        self.iter().for_each(|v| v.pack(out));
    }
    fn unpack(input: &mut Reader<'_>) -> Option<Self> {
        let v: Vec<T> = (0..N).map(|_| T::unpack(input)).collect::<Option<_>>()?;
        v.try_into().ok()
    }
}

impl<const R: usize, const C: usize> Pack for SMatrix<f64, R, C> {
    fn pack(&self, out: &mut Vec<u8>) {
        self.iter().for_each(|v| v.pack(out));
    }
    fn unpack(input: &mut Reader<'_>) -> Option<Self> {
        let v: Vec<f64> = (0..R * C).map(|_| f64::unpack(input)).collect::<Option<_>>()?;
        Some(SMatrix::from_column_slice(&v))
    }
}

/// [`Pack`] for field-less enums by their derived names (`strum`): every variant is covered.
macro_rules! pack_by_name {
    ($($ty:ty),+ $(,)?) => {$(
        impl Pack for $ty {
            fn pack(&self, out: &mut Vec<u8>) {
                self.as_str().pack(out)
            }
            fn unpack(input: &mut Reader<'_>) -> Option<Self> {
                let name = String::unpack(input)?;
                <$ty as strum::VariantArray>::VARIANTS.iter().copied().find(|v| v.as_str() == name)
            }
        }
    )+};
}

pack_by_name!(
    Termination,
    Method,
    Status,
    CertificateKind,
    CostKind,
    Primitive,
    PoseMethod,
    CovarianceSource,
    RansacStop
);

/// [`Pack`] for a struct of packable fields: `pack` destructures it completely (a new field does
/// not compile until listed) and `unpack` reads the fields back in the same order.
macro_rules! pack_struct {
    ($ty:ident { $($field:ident),+ $(,)? }) => {
        impl Pack for $ty {
            fn pack(&self, out: &mut Vec<u8>) {
                let $ty { $($field),+ } = self;
                $($field.pack(out);)+
            }
            fn unpack(input: &mut Reader<'_>) -> Option<Self> {
                $(let $field = Pack::unpack(input)?;)+
                Some($ty { $($field),+ })
            }
        }
    };
}
pub(crate) use pack_struct;

pack_struct!(Intrinsics { fx, fy, cx, cy, skew });
pack_struct!(Pose { rotation, translation });
pack_struct!(DualQuaternion { r, s });
pack_struct!(StageReport {
    name,
    cost_kind,
    rotation,
    translation,
    iterations,
    initial_cost,
    final_cost,
    termination,
    time_seconds
});
pack_struct!(RansacReport {
    iterations,
    degenerate_samples,
    models_scored,
    sprt_rejections,
    errors_evaluated,
    local_optimizations,
    inliers,
    required_inliers,
    score,
    stop,
    time_seconds
});
pack_struct!(PoseResult {
    pose,
    status,
    cost,
    inliers_points,
    inliers_lines,
    covariance,
    certificate,
    details
});
pack_struct!(PoseDetails {
    method,
    iterations,
    termination,
    stages,
    rms_error_px,
    time_seconds,
    estimated_camera,
    ransac,
    covariance_source,
    sigma_px,
    second_best,
    behind_camera_cost,
    residual_test,
    uncertified_reason
});
pack_struct!(ResidualTest {
    chi2,
    dof,
    p_value,
    consistent
});
pack_struct!(Certificate {
    lower_bound,
    raw_lower_bound,
    relative_gap,
    certified,
    kind,
    nodes,
    solver_iterations
});
pack_struct!(Report {
    method,
    status,
    cost,
    cost_kind,
    certificate,
    iterations,
    termination,
    time_seconds,
    residual_dof
});
pack_struct!(LineChart { pivot, direction, axes });
pack_struct!(Ellipse {
    centre,
    axes,
    semi_axes
});
pack_struct!(FittedLine {
    line,
    covariance,
    rms_distance
});
pack_struct!(FittedConic {
    conic,
    ellipse,
    covariance,
    iterations
});

/// `(pluecker._core._unpickle, (kind, data))`: what `__reduce__` returns for a result of class `kind`
/// whose parts pack into `parts` (in the order [`unpickle`] reads them).
pub fn reduce<'py>(
    py: Python<'py>,
    kind: &str,
    parts: &[&dyn PackDyn],
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
    let mut data = Vec::new();
    env!("CARGO_PKG_VERSION").pack(&mut data);
    parts.iter().for_each(|p| p.pack_dyn(&mut data));
    let restore = py.import("pluecker._core")?.getattr("_unpickle")?;
    let args = PyTuple::new(
        py,
        [kind.into_pyobject(py)?.into_any(), PyBytes::new(py, &data).into_any()],
    )?;
    Ok((restore, args))
}

/// [`Pack::pack`] behind a reference to a trait object (the parts of a result of several structs).
pub trait PackDyn {
    fn pack_dyn(&self, out: &mut Vec<u8>);
}

impl<T: Pack> PackDyn for T {
    fn pack_dyn(&self, out: &mut Vec<u8>) {
        self.pack(out)
    }
}

/// The packed parts of a pickle of class `kind`, after its version header; a `PlueckerError` when
/// the pickle is from another version.
pub fn parts<'a>(kind: &str, data: &'a [u8]) -> PyResult<Reader<'a>> {
    let mut input = Reader { bytes: data };
    let version = String::unpack(&mut input).ok_or_else(|| malformed(kind))?;
    if version != env!("CARGO_PKG_VERSION") {
        return Err(PlueckerError::new_err(format!(
            "cannot unpickle a {kind} made by pluecker {version} with pluecker {} (results pickle within one version)",
            env!("CARGO_PKG_VERSION")
        )));
    }
    Ok(input)
}

/// The next part of a pickle of class `kind`.
pub fn part<T: Pack>(kind: &str, input: &mut Reader<'_>) -> PyResult<T> {
    T::unpack(input).ok_or_else(|| malformed(kind))
}

/// A `PlueckerError` unless the whole pickle has been read.
pub fn finished(kind: &str, input: &Reader<'_>) -> PyResult<()> {
    if input.bytes.is_empty() {
        Ok(())
    } else {
        Err(malformed(kind))
    }
}

fn malformed(kind: &str) -> PyErr {
    PlueckerError::new_err(format!("cannot unpickle a {kind}: the data are malformed"))
}

/// A result of class `T` read from `input` (a pickle of class `kind`).
pub fn plain<T>(py: Python<'_>, kind: &str, input: &mut Reader<'_>) -> PyResult<PyObject>
where
    T: PyClass + Pack + Into<PyClassInitializer<T>>,
{
    Ok(Py::new(py, part::<T>(kind, input)?)?.into_any())
}
