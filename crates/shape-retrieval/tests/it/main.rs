//! The integration tests of this package, in one test binary (one link instead of one per
//! file; see README, "Running the tests"). Each module is one former `tests/<name>.rs`.

mod common;

mod bof;
mod clouds;
mod collection;
mod descriptor;
mod distance;
mod eval;
mod exact;
mod features;
mod hks;
mod kmeans;
mod model;
mod retrieval;
mod sihks;
mod solids;
mod spatial;
mod standardize;
mod store;
