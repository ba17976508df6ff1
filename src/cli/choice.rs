//! Command-line values of the library's registries ([`wfem_base::Choice`]): the names,
//! aliases, help and default of every choice (backend, heat method, mass, descriptor, …) come
//! from the library type, so the CLI keeps no copy of a name.
//!
//! ```ignore
//! #[arg(long, value_parser = choice::<Method>(), default_value = Method::default_name())]
//! method: Method,
//! ```

use clap::builder::{PossibleValue, TypedValueParser};
use clap::error::{ContextKind, ContextValue, ErrorKind};
use std::ffi::OsStr;
use std::marker::PhantomData;
use wfem_base::Choice;

/// A `clap` value parser for the registry `T`: accepts its names and aliases (any case, `_`
/// for `-`), lists its names with their help in `--help`, and names the valid ones when a
/// value is unknown.
pub struct ChoiceParser<T>(PhantomData<fn() -> T>);

impl<T> Clone for ChoiceParser<T> {
    fn clone(&self) -> Self {
        ChoiceParser(PhantomData)
    }
}

/// The value parser of the registry `T`.
pub fn choice<T: Choice + Clone + Send + Sync + 'static>() -> ChoiceParser<T> {
    ChoiceParser(PhantomData)
}

impl<T: Choice + Clone + Send + Sync + 'static> TypedValueParser for ChoiceParser<T> {
    type Value = T;

    fn parse_ref(&self, cmd: &clap::Command, arg: Option<&clap::Arg>, value: &OsStr) -> Result<T, clap::Error> {
        let invalid = |shown: String| {
            let mut err = clap::Error::new(ErrorKind::InvalidValue).with_cmd(cmd);
            if let Some(arg) = arg {
                err.insert(ContextKind::InvalidArg, ContextValue::String(arg.to_string()));
            }
            err.insert(ContextKind::InvalidValue, ContextValue::String(shown));
            err.insert(
                ContextKind::ValidValue,
                ContextValue::Strings(T::names().map(str::to_string).collect()),
            );
            err
        };
        let text = value
            .to_str()
            .ok_or_else(|| invalid(value.to_string_lossy().into_owned()))?;
        T::parse(text).map_err(|_| invalid(text.to_string()))
    }

    fn possible_values(&self) -> Option<Box<dyn Iterator<Item = PossibleValue> + '_>> {
        Some(Box::new(T::entries().iter().map(|e| {
            PossibleValue::new(e.name)
                .help(e.help)
                .aliases(e.aliases.iter().copied())
        })))
    }
}
