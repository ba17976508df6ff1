//! The registries: one Rust type per user-visible choice with its names, aliases, help and
//! default ([`Choice`], declared with [`registry!`](crate::registry)).
//!
//! ```
//! use wfem_base::{registry, Choice};
//!
//! /// How to greet.
//! #[derive(Clone, Debug, Default, PartialEq)]
//! pub enum Greeting {
//!     /// Say hello.
//!     #[default]
//!     Hello,
//!     /// Wave a given number of times.
//!     Wave(u32),
//! }
//!
//! registry! {
//!     Greeting as "greeting" {
//!         Greeting::Hello = Greeting::Hello => "hello" ["hi"]: "Say hello.",
//!         Greeting::Wave(_) = Greeting::Wave(3) => "wave": "Wave three times.",
//!     }
//! }
//!
//! assert_eq!(Greeting::parse("HI"), Ok(Greeting::Hello));
//! assert_eq!(Greeting::Wave(7).name(), "wave");
//! assert_eq!(Greeting::default_name(), "hello");
//! let err = Greeting::parse("bow").unwrap_err();
//! assert_eq!(err.to_string(), "unknown greeting \"bow\": expected one of hello, wave");
//! ```
//!
//! **Names** are lowercase words joined by `-` (`backward-euler`, `si-hks`). Parsing is
//! case-insensitive and reads `_` as `-`, so Python's `backward_euler` and a shouted `SI-HKS`
//! name the same entry; aliases keep older spellings working.

use std::fmt;

/// One alternative of a choice, as users see it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Entry {
    /// The canonical name (lowercase, words joined by `-`).
    pub name: &'static str,
    /// Other accepted spellings (older names, the other convention's words).
    pub aliases: &'static [&'static str],
    /// One line of help: what the alternative is and when to choose it.
    pub help: &'static str,
}

/// A user-visible choice among named alternatives.
///
/// Implemented by [`registry!`]; [`Choice::name`] is an exhaustive `match`, so a variant
/// without a registry line does not compile. A choice with a default alternative implements
/// `Default` (every single-valued option does; a list of steps such as `--repair` need not).
pub trait Choice: Sized {
    /// What is being chosen, in a few words ("backend", "heat method"): used in messages.
    const WHAT: &'static str;

    /// Every alternative, in the order users see them.
    fn entries() -> &'static [Entry];

    /// The canonical name of this value's alternative.
    fn name(&self) -> &'static str;

    /// The value of an entry's canonical name, with the alternative's default parameters;
    /// `None` for a name that is not canonical.
    fn from_canonical(name: &str) -> Option<Self>;

    /// The entry of this value.
    fn entry(&self) -> &'static Entry {
        let name = self.name();
        // invariant: `name()` returns a name of `entries()` (checked by `check_registry`).
        Self::entries()
            .iter()
            .find(|e| e.name == name)
            .unwrap_or(&Self::entries()[0])
    }

    /// The value named `text` (a canonical name or an alias, case-insensitive, `_` read as
    /// `-`), with the alternative's default parameters.
    ///
    /// # Errors
    /// [`UnknownName`] listing the canonical names.
    fn parse(text: &str) -> Result<Self, UnknownName> {
        let wanted = normalize(text);
        Self::entries()
            .iter()
            .find(|e| e.name == wanted || e.aliases.iter().any(|a| normalize(a) == wanted))
            .and_then(|e| Self::from_canonical(e.name))
            .ok_or_else(|| UnknownName {
                what: Self::WHAT,
                given: text.to_string(),
                expected: Self::names().collect(),
            })
    }

    /// The canonical names, in order.
    fn names() -> impl Iterator<Item = &'static str> {
        Self::entries().iter().map(|e| e.name)
    }

    /// The canonical name of [`Default::default`].
    fn default_name() -> &'static str
    where
        Self: Default,
    {
        Self::default().name()
    }
}

/// A name that no alternative of a choice carries.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UnknownName {
    /// What was being chosen ([`Choice::WHAT`]).
    pub what: &'static str,
    /// The name given.
    pub given: String,
    /// The canonical names.
    pub expected: Vec<&'static str>,
}

impl fmt::Display for UnknownName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "unknown {} {:?}: expected one of {}",
            self.what,
            self.given,
            self.expected.join(", ")
        )
    }
}

impl std::error::Error for UnknownName {}

/// The canonical form of a user's spelling: lowercase, `_` and spaces read as `-`.
pub fn normalize(text: &str) -> String {
    text.trim()
        .chars()
        .map(|c| match c {
            '_' | ' ' => '-',
            c => c.to_ascii_lowercase(),
        })
        .collect()
}

/// Checks a registry with a default: [`check_entries`], and the default is an entry. Every
/// registry's tests call it.
///
/// # Errors
/// A message naming the first inconsistency.
pub fn check_registry<T: Choice + Default>() -> Result<(), String> {
    check_entries::<T>()?;
    let default = T::default_name();
    if !T::entries().iter().any(|e| e.name == default) {
        return Err(format!("the default {} {default:?} is not registered", T::WHAT));
    }
    Ok(())
}

/// Checks a registry's entries: canonical names are normalized and unique, help is given, no
/// alias collides with another entry's name or alias, and every entry and alias parses back to
/// itself.
///
/// # Errors
/// A message naming the first inconsistency.
pub fn check_entries<T: Choice>() -> Result<(), String> {
    let entries = T::entries();
    if entries.is_empty() {
        return Err(format!("the {} registry is empty", T::WHAT));
    }
    let mut seen: Vec<String> = Vec::new();
    for e in entries {
        if normalize(e.name) != e.name || e.name.is_empty() {
            return Err(format!("{} name {:?} is not in canonical form", T::WHAT, e.name));
        }
        if e.help.trim().is_empty() {
            return Err(format!("{} {:?} has no help text", T::WHAT, e.name));
        }
        for spelling in std::iter::once(e.name).chain(e.aliases.iter().copied()) {
            let s = normalize(spelling);
            if seen.contains(&s) {
                return Err(format!("{} spelling {:?} is used twice", T::WHAT, spelling));
            }
            seen.push(s);
        }
        let value = T::from_canonical(e.name).ok_or_else(|| format!("{} {:?} does not construct", T::WHAT, e.name))?;
        if value.name() != e.name {
            return Err(format!(
                "{} {:?} constructs a value named {:?}",
                T::WHAT,
                e.name,
                value.name()
            ));
        }
        for alias in e.aliases {
            let parsed = T::parse(alias).map_err(|err| err.to_string())?;
            if parsed.name() != e.name {
                return Err(format!("{} alias {alias:?} does not name {:?}", T::WHAT, e.name));
            }
        }
    }
    Ok(())
}

/// (De)serializes a choice as its canonical name, for `#[serde(with = "wfem_base::serde_name")]`
/// (feature `serde`); reading accepts every alias.
pub mod serde_name {
    use super::Choice;
    use serde::{Deserialize, Deserializer, Serializer};

    /// Writes the canonical name.
    ///
    /// # Errors
    /// Those of the serializer.
    pub fn serialize<T: Choice, S: Serializer>(value: &T, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.serialize_str(value.name())
    }

    /// Reads a name or an alias.
    ///
    /// # Errors
    /// An unknown name, listing the canonical ones.
    pub fn deserialize<'de, T: Choice, D: Deserializer<'de>>(deserializer: D) -> Result<T, D::Error> {
        let text = String::deserialize(deserializer)?;
        T::parse(&text).map_err(serde::de::Error::custom)
    }
}

/// Declares the registry of a choice: one line per alternative,
/// `pattern = constructor => "name" ["alias", …]: "help",`.
///
/// The pattern matches every value of the alternative (`Backend::Minres(_)`), the constructor
/// builds it with default parameters (`Backend::Minres(MinresParams::default())`). The
/// generated `name()` is an exhaustive match over the patterns, so a variant without a line
/// is a compile error.
#[macro_export]
macro_rules! registry {
    (
        $ty:ty as $what:literal {
            $( $pat:pat = $make:expr => $name:literal $( [ $($alias:literal),* $(,)? ] )? : $help:literal ),+ $(,)?
        }
    ) => {
        impl $crate::Choice for $ty {
            const WHAT: &'static str = $what;

            fn entries() -> &'static [$crate::Entry] {
                const ENTRIES: &[$crate::Entry] = &[
                    $( $crate::Entry { name: $name, aliases: &[$($($alias),*)?], help: $help } ),+
                ];
                ENTRIES
            }

            #[allow(unreachable_patterns)]
            fn name(&self) -> &'static str {
                match self {
                    $( $pat => $name, )+
                }
            }

            fn from_canonical(name: &str) -> Option<Self> {
                match name {
                    $( $name => Some($make), )+
                    _ => None,
                }
            }
        }
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Clone, Debug, Default, PartialEq)]
    enum Shape {
        #[default]
        Round,
        Square {
            side: f64,
        },
        Many(Vec<u8>),
    }

    registry! {
        Shape as "shape" {
            Shape::Round = Shape::Round => "round" ["circle", "Disc_Shape"]: "A disc.",
            Shape::Square { .. } = Shape::Square { side: 1.0 } => "square": "A unit square.",
            Shape::Many(_) = Shape::Many(vec![1, 2]) => "many-shapes": "Several.",
        }
    }

    #[test]
    fn parses_names_and_aliases_in_any_case() {
        assert_eq!(Shape::parse("round"), Ok(Shape::Round));
        assert_eq!(Shape::parse("CIRCLE"), Ok(Shape::Round));
        assert_eq!(Shape::parse("disc-shape"), Ok(Shape::Round));
        assert_eq!(Shape::parse(" many_shapes "), Ok(Shape::Many(vec![1, 2])));
        assert_eq!(Shape::parse("Square"), Ok(Shape::Square { side: 1.0 }));
    }

    #[test]
    fn unknown_names_list_the_canonical_ones() {
        let err = Shape::parse("triangle").unwrap_err();
        assert_eq!(err.what, "shape");
        assert_eq!(err.expected, vec!["round", "square", "many-shapes"]);
        assert_eq!(
            err.to_string(),
            "unknown shape \"triangle\": expected one of round, square, many-shapes"
        );
        assert!(Shape::parse("").is_err());
    }

    #[test]
    fn names_ignore_parameters() {
        assert_eq!(Shape::Square { side: 7.0 }.name(), "square");
        assert_eq!(Shape::Many(vec![]).entry().help, "Several.");
        assert_eq!(Shape::default_name(), "round");
        assert_eq!(Shape::names().collect::<Vec<_>>(), ["round", "square", "many-shapes"]);
    }

    #[test]
    fn the_test_registry_is_consistent() {
        check_registry::<Shape>().unwrap();
    }

    #[derive(Clone, Debug, Default, PartialEq)]
    #[allow(dead_code)]
    enum Broken {
        #[default]
        A,
        B,
    }

    registry! {
        Broken as "broken" {
            Broken::A = Broken::A => "a" ["b"]: "First.",
            Broken::B = Broken::A => "b": "Second, built wrongly.",
        }
    }

    #[test]
    fn check_registry_finds_collisions_and_wrong_constructors() {
        let err = check_registry::<Broken>().unwrap_err();
        assert!(err.contains("used twice"), "{err}");
    }

    #[derive(Clone, Debug, Default, PartialEq)]
    #[allow(dead_code)]
    enum Miswired {
        #[default]
        A,
        B,
    }

    registry! {
        Miswired as "miswired" {
            Miswired::A = Miswired::A => "a": "First.",
            Miswired::B = Miswired::A => "b": "Second, built as the first.",
        }
    }

    #[test]
    fn check_registry_finds_a_constructor_of_the_wrong_alternative() {
        let err = check_registry::<Miswired>().unwrap_err();
        assert!(err.contains("constructs a value named \"a\""), "{err}");
    }

    #[test]
    fn normalize_reads_underscores_and_case() {
        assert_eq!(normalize("Backward_Euler"), "backward-euler");
        assert_eq!(normalize("  SI HKS "), "si-hks");
    }
}
