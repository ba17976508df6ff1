//! The integration tests of wfem-render, in one test binary.

mod render;
mod splats;
