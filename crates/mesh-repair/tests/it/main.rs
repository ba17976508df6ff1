//! The integration tests of mesh-repair, in one test binary.

mod filter;
mod handles;
