//! # wfem
//!
//! The wFEM heat kernel on triangle meshes. This facade re-exports the workspace crates:
//! [`mesh_fem`] (meshes and FEM operators), [`shifted_solve`] (rational approximation and
//! shifted sparse solvers), [`wfem_heat`] (K_t f, distances) and [`shape_retrieval`]
//! (descriptors and retrieval).
//!
//! The `wfem` command-line tool lives in the binary of this package (feature `cli`, on by
//! default); a library user who sets `default-features = false` compiles none of its
//! dependencies (clap, indicatif, the PNG renderer `wfem-render`).

// Robustness (issue #8): no unwrap()/expect() on user-controlled data in library code
// (checked by tests/it/no_unwrap.rs).
#![cfg_attr(not(test), warn(clippy::unwrap_used, clippy::expect_used))]

pub use mesh_fem;
pub use shape_retrieval;
pub use shifted_solve;
pub use wfem_heat;
