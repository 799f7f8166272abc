//! The names of the enums in reports, JSON, Python and the command line. Each enum derives them
//! (strum: `IntoStaticStr` for the name, `VariantArray` for the list, `EnumString` for the parse),
//! so a new variant cannot be forgotten in a table; [`parse`] gives the one error for an unknown name.

use crate::error::{Error, Result};
use std::str::FromStr;
use strum::VariantArray;

/// An enum whose variants have names.
pub trait Named: Copy + Into<&'static str> + FromStr + VariantArray + 'static {}

impl<T: Copy + Into<&'static str> + FromStr + VariantArray + 'static> Named for T {}

/// Every name of `T`, in declaration order, joined by ", ".
pub fn names<T: Named>() -> String {
    T::VARIANTS
        .iter()
        .map(|v| -> &'static str { (*v).into() })
        .collect::<Vec<_>>()
        .join(", ")
}

/// The variant of `T` named `name`; otherwise `Error::InvalidOption` for the option `option`, saying
/// "unknown {what} '{name}'" and listing every name.
pub fn parse<T: Named>(option: &str, what: &str, name: &str) -> Result<T> {
    T::from_str(name).map_err(|_| Error::InvalidOption {
        name: option.into(),
        reason: format!("unknown {what} '{name}'; expected one of {}", names::<T>()),
    })
}

/// `serde` of a named enum: written as its name, read back by [`parse`]'s rule (an unknown name is an
/// error listing every name). [`serde_by_name!`] implements both traits with these two functions.
#[cfg(feature = "serde")]
pub(crate) mod by_name {
    use super::{names, Named};
    use serde::de::Error as _;
    use serde::{Deserialize, Deserializer, Serializer};

    /// Writes `value` as its name.
    pub(crate) fn serialize<T: Named, S: Serializer>(value: &T, serializer: S) -> std::result::Result<S::Ok, S::Error> {
        serializer.serialize_str((*value).into())
    }

    /// Reads a name of `T`.
    pub(crate) fn deserialize<'de, T: Named, D: Deserializer<'de>>(deserializer: D) -> Result<T, D::Error> {
        let name = String::deserialize(deserializer)?;
        T::from_str(&name)
            .map_err(|_| D::Error::custom(format!("unknown name '{name}'; expected one of {}", names::<T>())))
    }
}

/// `serde::Serialize` and `serde::Deserialize` of named enums by their names ([`by_name`]), with the
/// `serde` feature.
macro_rules! serde_by_name {
    ($($ty:ty),+ $(,)?) => {$(
        #[cfg(feature = "serde")]
        impl serde::Serialize for $ty {
            fn serialize<S: serde::Serializer>(&self, serializer: S) -> std::result::Result<S::Ok, S::Error> {
                crate::names::by_name::serialize(self, serializer)
            }
        }

        #[cfg(feature = "serde")]
        impl<'de> serde::Deserialize<'de> for $ty {
            fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> std::result::Result<Self, D::Error> {
                crate::names::by_name::deserialize(deserializer)
            }
        }
    )+};
}

pub(crate) use serde_by_name;
