//! A nested options object (`CertifyOptions`, `RansacOptions`) held by reference inside another
//! options class, pycolmap style: `options.certify.max_nodes = 10` changes the options that hold it.
//! Its fields are read into the core's struct when a function is called.

use crate::properties::Field;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use pyo3::PyClass;

/// The nested options classes: their name in stubs and messages.
pub(crate) trait NestedOptions: PyClass + Clone + Default + PartialEq + Into<PyClassInitializer<Self>> {
    /// The class name in stubs and messages.
    const CLASS: &'static str;
}

/// One nested options object, held by reference (`Option<Shared<T>>` when it may be unset).
#[derive(Debug)]
pub(crate) struct Shared<T: PyClass>(Py<T>);

impl<T: NestedOptions> Shared<T> {
    /// A new object holding `value`.
    pub(crate) fn new(value: T) -> Self {
        Python::with_gil(|py| Shared(Py::new(py, value).expect("a Python object")))
    }

    /// The object's fields now (a copy).
    pub(crate) fn read(&self) -> T {
        Python::with_gil(|py| self.0.borrow(py).clone())
    }
}

/// Another reference to the same object (a copy of the options shares it, as `copy.copy` would).
impl<T: PyClass> Clone for Shared<T> {
    fn clone(&self) -> Self {
        Python::with_gil(|py| Shared(self.0.clone_ref(py)))
    }
}

/// A new object with every field at its default.
impl<T: NestedOptions> Default for Shared<T> {
    fn default() -> Self {
        Python::with_gil(|py| Shared(Py::new(py, T::default()).expect("a Python object")))
    }
}

/// Equal fields, not the same object.
impl<T: NestedOptions> PartialEq for Shared<T> {
    fn eq(&self, other: &Self) -> bool {
        self.read() == other.read()
    }
}

/// An object of the class (held by reference), or a dict of its fields (`to_dict()` and pickling
/// give one) for a new object.
impl<'py, T: NestedOptions> FromPyObject<'py> for Shared<T> {
    fn extract_bound(ob: &Bound<'py, PyAny>) -> PyResult<Self> {
        if let Ok(object) = ob.downcast::<T>() {
            return Ok(Shared(object.clone().unbind()));
        }
        if let Ok(fields) = ob.downcast::<PyDict>() {
            let object = ob.py().get_type::<T>().call((), Some(fields))?;
            return Ok(Shared(object.downcast_into::<T>()?.unbind()));
        }
        Err(pyo3::exceptions::PyTypeError::new_err(format!(
            "expected a {}, got {}",
            T::CLASS,
            ob.get_type().name()?
        )))
    }
}

impl<T: NestedOptions> Field for Shared<T> {
    /// The object itself (changing it changes the options that hold it).
    fn get(self, _py: Python<'_>) -> PyResult<PyObject> {
        Ok(self.0.into_any())
    }
    /// Its `to_dict()`.
    fn plain(self, py: Python<'_>) -> PyResult<PyObject> {
        Ok(self.0.bind(py).as_any().call_method0("to_dict")?.unbind())
    }
    fn stub() -> String {
        T::CLASS.into()
    }
}
