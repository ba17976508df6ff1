//! The integration tests of this package, in one test binary (one link instead of one per
//! file; see README, "Running the tests"). Each module is one former `tests/<name>.rs`.

mod approx_eval;
mod cleaning;
mod eval;
mod handles;
mod synth;
mod transform;
