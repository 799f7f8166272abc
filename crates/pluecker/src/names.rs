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
