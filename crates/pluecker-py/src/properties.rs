//! Each property of a result or options class is declared once, in a table ([`result_class!`],
//! [`options_class!`]), and that table makes the getter, the entry of `to_dict()` and the class
//! attribute `__fields__` from which `_core.pyi` is generated (`python -m pluecker._stubgen`) and
//! checked (tests/test_stubs.py). A value's three forms come from its type ([`Field`]): the getter's
//! (numpy arrays), the plain one of `to_dict` (lists, strict JSON) and its name in the stub.

use numpy::ndarray::{ArrayD, IxDyn};
use numpy::{IntoPyArray, PyArray1};
use pyo3::prelude::*;
use pyo3::types::PyList;

/// A value a property can hold.
pub(crate) trait Field: Sized {
    /// What the property returns.
    fn get(self, py: Python<'_>) -> PyResult<PyObject>;
    /// What `to_dict()` holds: plain Python (lists instead of arrays); NaN and inf become `None` later
    /// ([`crate::convert::strict_json`]).
    fn plain(self, py: Python<'_>) -> PyResult<PyObject> {
        self.get(py)
    }
    /// The type as `_core.pyi` writes it.
    fn stub() -> String;
}

/// The stub type of what `field` returns (the table's expressions are typed by inference).
pub(crate) fn stub_of<C, T: Field>(_field: impl Fn(&C) -> T) -> String {
    T::stub()
}

/// Values that convert the same way for the getter and `to_dict`.
macro_rules! scalar_field {
    ($($ty:ty => $stub:literal),+ $(,)?) => {$(
        impl Field for $ty {
            fn get(self, py: Python<'_>) -> PyResult<PyObject> {
                Ok(self.into_pyobject(py)?.to_owned().into_any().unbind())
            }
            fn stub() -> String {
                $stub.into()
            }
        }
    )+};
}
scalar_field!(f64 => "float", usize => "int", u64 => "int", i64 => "int", bool => "bool",
    &'static str => "str", String => "str", Vec<String> => "List[str]");

impl<T: Field> Field for Option<T> {
    fn get(self, py: Python<'_>) -> PyResult<PyObject> {
        self.map_or_else(|| Ok(py.None()), |v| v.get(py))
    }
    fn plain(self, py: Python<'_>) -> PyResult<PyObject> {
        self.map_or_else(|| Ok(py.None()), |v| v.plain(py))
    }
    fn stub() -> String {
        format!("Optional[{}]", T::stub())
    }
}

/// The element types of the arrays of properties, with their name in the stub.
pub(crate) trait Element: numpy::Element {
    const STUB: &'static str;
}

impl Element for f64 {
    const STUB: &'static str = "NDArray[np.float64]";
}

impl Element for bool {
    const STUB: &'static str = "NDArray[np.bool_]";
}

/// A numpy array of any shape, row-major: float64 by default, bool for the masks.
pub(crate) struct Array<T = f64> {
    pub values: Vec<T>,
    pub shape: Vec<usize>,
}

/// A boolean array (a batch's inlier masks).
pub(crate) type Mask = Array<bool>;

impl Array {
    /// `values` (row-major) as an array whose trailing axes are `tail`; the leading axis is what is left.
    pub fn rows(values: Vec<f64>, tail: &[usize]) -> Array {
        let per_row: usize = tail.iter().product();
        let mut shape = vec![values.len() / per_row.max(1)];
        shape.extend_from_slice(tail);
        Array { values, shape }
    }
}

impl<const R: usize, const C: usize> From<nalgebra::SMatrix<f64, R, C>> for Array {
    /// A `(R,)` array for a column vector, `(R, C)` otherwise.
    fn from(m: nalgebra::SMatrix<f64, R, C>) -> Array {
        let values = (0..R).flat_map(|i| (0..C).map(move |j| m[(i, j)])).collect();
        let shape = if C == 1 { vec![R] } else { vec![R, C] };
        Array { values, shape }
    }
}

impl<T: Element> Field for Array<T> {
    fn get(self, py: Python<'_>) -> PyResult<PyObject> {
        let array = ArrayD::from_shape_vec(IxDyn(&self.shape), self.values)
            .map_err(|e| pyo3::exceptions::PyRuntimeError::new_err(e.to_string()))?;
        Ok(array.into_pyarray(py).into_any().unbind())
    }
    fn plain(self, py: Python<'_>) -> PyResult<PyObject> {
        self.get(py)?.call_method0(py, "tolist")
    }
    fn stub() -> String {
        T::STUB.into()
    }
}

impl<const R: usize, const C: usize> Field for nalgebra::SMatrix<f64, R, C> {
    fn get(self, py: Python<'_>) -> PyResult<PyObject> {
        Array::from(self).get(py)
    }
    fn plain(self, py: Python<'_>) -> PyResult<PyObject> {
        Array::from(self).plain(py)
    }
    fn stub() -> String {
        Array::<f64>::stub()
    }
}

/// A one-dimensional numpy column (a batch's per-track values, an inlier mask).
macro_rules! column_field {
    ($($ty:ty => $stub:literal),+ $(,)?) => {$(
        impl Field for Vec<$ty> {
            fn get(self, py: Python<'_>) -> PyResult<PyObject> {
                Ok(PyArray1::from_vec(py, self).into_any().unbind())
            }
            fn plain(self, py: Python<'_>) -> PyResult<PyObject> {
                Ok(PyList::new(py, self)?.into_any().unbind())
            }
            fn stub() -> String {
                $stub.into()
            }
        }
    )+};
}
column_field!(f64 => "NDArray[np.float64]", i64 => "NDArray[np.int64]", bool => "NDArray[np.bool_]");

impl Field for Vec<&'static str> {
    /// A numpy array of strings (dtype `<U…`).
    fn get(self, py: Python<'_>) -> PyResult<PyObject> {
        let list = PyList::new(py, self)?;
        Ok(py.import("numpy")?.call_method1("array", (list, "str"))?.unbind())
    }
    fn plain(self, py: Python<'_>) -> PyResult<PyObject> {
        Ok(PyList::new(py, self)?.into_any().unbind())
    }
    fn stub() -> String {
        "NDArray[np.str_]".into()
    }
}

/// The `__fields__` entry of one property: `(name, stub type, doc)`.
pub(crate) type FieldDoc = (&'static str, String, String);

/// The doc comment lines of a table entry as one text (each `///` line starts with a space).
pub(crate) fn doc(lines: &[&str]) -> String {
    lines
        .iter()
        .map(|l| l.strip_prefix(' ').unwrap_or(l))
        .collect::<Vec<_>>()
        .join("\n")
}

/// The properties of a frozen result class from a table of `/// doc` + `name = |this| value;`
/// entries (`this` is `&Self`; the value is owned and implements [`Field`]), followed by the
/// class's other methods. Makes the getters, `to_dict()` (this class's properties after those of
/// `: Base`, if given, through `Base::fill_dict`), `fill_dict` and the class attribute `__fields__`.
macro_rules! result_class {
    (
        $class:ident $(: $base:ident)? {
            $( $(#[doc = $doc:literal])+ $name:ident = |$this:ident| $value:expr; )*
        }
        $($methods:tt)*
    ) => {
        impl $class {
            /// Puts this class's own properties into `d`, in their `to_dict` form.
            #[allow(unused_variables)]
            pub(crate) fn fill_dict(&self, py: Python<'_>, d: &Bound<'_, pyo3::types::PyDict>) -> PyResult<()> {
                $( { let $this = self; d.set_item(stringify!($name), $crate::properties::Field::plain($value, py)?)?; } )*
                Ok(())
            }
        }

        #[pymethods]
        impl $class {
            $(
                $(#[doc = $doc])+
                #[getter]
                #[allow(non_snake_case)]
                fn $name(&self, py: Python<'_>) -> PyResult<PyObject> {
                    let $this = self;
                    $crate::properties::Field::get($value, py)
                }
            )*

            /// Plain-Python form: every property, arrays as (nested) lists, NaN and inf as `None`, so that
            /// `json.dumps(result.to_dict(), allow_nan=False)` holds.
            fn to_dict<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, pyo3::types::PyDict>> {
                let d = pyo3::types::PyDict::new(slf.py());
                $( <$base>::fill_dict(slf.as_super().get(), slf.py(), &d)?; )?
                slf.get().fill_dict(slf.py(), &d)?;
                $crate::convert::strict_json_dict(d)
            }

            /// `(name, type, doc)` of this class's own properties (the stub is generated from them).
            #[classattr]
            fn __fields__() -> Vec<$crate::properties::FieldDoc> {
                vec![$((
                    stringify!($name),
                    $crate::properties::stub_of(|$this: &$class| $value),
                    $crate::properties::doc(&[$($doc),+]),
                )),*]
            }

            $($methods)*
        }
    };
}
pub(crate) use result_class;

/// An options class (mutable, with keyword construction, equality, `repr` and pickling) from a table
/// of `/// doc` + `name: Type = |o| getter, |o, v| setter;` entries over its core options `inner`
/// (`o` is `&Self` for the getter and `&mut Self` for the setter; `v` is the value extracted as
/// `Type`; the setter returns `PyResult<()>`). Every value set is checked by `Self::validate` on a
/// copy, so a rejected value leaves the options as they were. Defaults are `Self::default()`, which
/// is the core's `Default`: no default is written here.
macro_rules! options_class {
    (
        $class:ident {
            $( $(#[doc = $doc:literal])+ $name:ident : $ty:ty = |$o:ident| $get:expr, |$m:ident, $v:ident| $set:expr; )*
        }
        $($methods:tt)*
    ) => {
        paste::paste! {
        #[pymethods]
        impl $class {
            /// Options with every field at its default, then the given keywords set (unknown keywords
            /// are a `TypeError`).
            #[new]
            #[pyo3(signature = (**kwargs))]
            fn __new__(kwargs: Option<&Bound<'_, pyo3::types::PyDict>>) -> PyResult<Self> {
                let mut options = Self::default();
                if let Some(kwargs) = kwargs {
                    options.update(kwargs, stringify!($class))?;
                }
                Ok(options)
            }

            $(
                $(#[doc = $doc])+
                #[getter]
                fn $name(&self, py: Python<'_>) -> PyResult<PyObject> {
                    let $o = self;
                    $crate::properties::Field::get($get, py)
                }

                #[setter($name)]
                // `del options.x` is pyo3's AttributeError; `options.x = None` resets an optional field.
                fn [<set_ $name>](&mut self, value: &Bound<'_, PyAny>) -> PyResult<()> {
                    let $v: $ty = value.extract().map_err(|e: PyErr| {
                        let py = value.py();
                        let message = format!("{}: {}", stringify!($name), e.value(py));
                        // A nested options object given as a dict keeps its own error's kind
                        // (`InvalidOptionError` for a value out of range), named from the outside in.
                        if e.is_instance_of::<$crate::errors::PlueckerError>(py) {
                            PyErr::from_type(e.get_type(py), message)
                        } else {
                            pyo3::exceptions::PyTypeError::new_err(message)
                        }
                    })?;
                    let mut next = self.clone();
                    {
                        let $m = &mut next;
                        $set?;
                    }
                    next.validate()?;
                    *self = next;
                    Ok(())
                }
            )*

            /// Plain-Python form: every option by name (`type(self)(**options.to_dict())` is equal to it).
            fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, pyo3::types::PyDict>> {
                let d = pyo3::types::PyDict::new(py);
                $( { let $o = self; d.set_item(stringify!($name), $crate::properties::Field::plain($get, py)?)?; } )*
                Ok(d)
            }

            /// `(name, type, doc)` of the options (the stub is generated from them).
            #[classattr]
            fn __fields__() -> Vec<$crate::properties::FieldDoc> {
                vec![$((
                    stringify!($name),
                    $crate::properties::stub_of(|$o: &$class| $get),
                    $crate::properties::doc(&[$($doc),+]),
                )),*]
            }

            fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
                other.downcast::<Self>().is_ok_and(|o| *o.borrow() == *self)
            }

            fn __repr__(slf: &Bound<'_, Self>) -> PyResult<String> {
                let mut parts = Vec::new();
                $( parts.push(format!("{}={}", stringify!($name), slf.getattr(stringify!($name))?.repr()?)); )*
                Ok(format!("{}({})", stringify!($class).trim_start_matches("Py"), parts.join(", ")))
            }

            /// Pickling and `copy`: rebuilt from `to_dict()`.
            fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, pyo3::types::PyTuple>, Bound<'py, pyo3::types::PyDict>)> {
                let state = slf.borrow().to_dict(slf.py())?;
                Ok((slf.get_type().into_any(), pyo3::types::PyTuple::empty(slf.py()), state))
            }

            fn __setstate__(&mut self, state: &Bound<'_, pyo3::types::PyDict>) -> PyResult<()> {
                self.update(state, stringify!($class))
            }

            $($methods)*
        }

        impl $class {
            /// Sets every `name: value` of `values` by its setter; an unknown name is a `TypeError`.
            fn update(&mut self, values: &Bound<'_, pyo3::types::PyDict>, class: &str) -> PyResult<()> {
                use pyo3::types::PyDictMethods;
                let mut next = self.clone();
                for (key, value) in values.iter() {
                    let key: String = key.extract()?;
                    match key.as_str() {
                        $( stringify!($name) => next.[<set_ $name>](&value)?, )*
                        _ => {
                            let class = class.trim_start_matches("Py");
                            return Err(pyo3::exceptions::PyTypeError::new_err(format!(
                                "{class}() got an unexpected keyword argument '{key}' (the options: {})",
                                [$(stringify!($name)),*].join(", ")
                            )));
                        }
                    }
                }
                *self = next;
                Ok(())
            }
        }
        }
    };
}
pub(crate) use options_class;
