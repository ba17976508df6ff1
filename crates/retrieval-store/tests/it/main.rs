//! The integration tests of retrieval-store, in one test binary.

mod crash;
mod faults;
mod integrity;
mod readonly;
mod store;
