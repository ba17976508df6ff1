//! # wfem-base
//!
//! What every wfem crate shares and nothing else: the **registries** of user-visible choices
//! (a rational backend, a heat method, a mass, a descriptor, a bag distance, an output format …,
//! each one Rust type carrying its names, aliases, help and default), the workspace's **one
//! seeded generator** and the **interrupt** flag that long computations check, and the one
//! description of a **file kind** that is not a regular file.
//!
//! * [`Choice`] and [`registry!`]: declare a choice once, next to its type; the command-line
//!   tool builds its `clap` values from [`Choice::entries`] and the Python bindings parse strings
//!   with [`Choice::parse`], so neither keeps a copy of a name.
//! * [`rng`]: SplitMix64, the one seeded generator (Lanczos starts, k-means++, samples,
//!   synthetic benchmark data).
//! * [`interrupt`]: cooperative interruption (a Python Ctrl-C, a cancelled request) checked
//!   between the steps of every long loop.
//! * [`fs`]: what a path that is not a regular file is, in one phrase for every error message.
//! * [`tempfiles`]: the temporary files of every writer, removed on a signal and, after a
//!   kill, by the next writer of the same target.
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
//! ```

#![warn(missing_docs)]
#![deny(unsafe_code)]

mod choice;

pub mod fs;
pub mod interrupt;
pub mod rng;
pub mod simd;
pub mod tempfiles;

pub use choice::serde_name;
pub use choice::{check_entries, check_registry, normalize, Choice, Entry, UnknownName};
