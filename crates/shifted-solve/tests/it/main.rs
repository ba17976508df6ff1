//! The integration tests of this package, in one test binary (one link instead of one per
//! file; see README, "Running the tests"). Each module is one former `tests/<name>.rs`.

mod common;

mod backends;
mod condition;
mod eigen;
mod errors;
mod singular;
mod tables;
