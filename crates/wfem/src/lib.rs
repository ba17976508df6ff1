//! # wfem
//!
//! The wFEM heat kernel on triangle meshes, as one dependency. This facade re-exports the
//! workspace's library crates, in the order of the pipeline:
//!
//! * [`wfem_base`]: the registries of choices, the seeded generator, interrupts;
//! * [`mesh_fem`]: meshes, point clouds and their FEM operators L, B, D;
//! * [`mesh_repair`]: hole filling, thin handles, spikes;
//! * [`shifted_solve`]: rational approximations of e^{−x} and shifted sparse solvers;
//! * [`wfem_heat`]: K_t f, the kernel diagonal, RKHS, diffusion distances, the canonical basis;
//! * [`shape_retrieval`]: heat kernel signatures, bags of features, the retrieval model;
//! * with the feature `store`, `retrieval_store` (the SQLite index file); with `render`,
//!   `wfem_render` (headless PNG figures).
//!
//! It has no default features and no command-line dependency: the `wfem` command-line tool is
//! the package `wfem-cli`.

// Robustness (issue #8): no unwrap()/expect() on user-controlled data in library code
// (checked by tests/it/no_unwrap.rs).
#![cfg_attr(not(test), warn(clippy::unwrap_used, clippy::expect_used))]

pub use mesh_fem;
pub use mesh_repair;
#[cfg(feature = "store")]
pub use retrieval_store;
pub use shape_retrieval;
pub use shifted_solve;
pub use wfem_base;
pub use wfem_heat;
#[cfg(feature = "render")]
pub use wfem_render;

/// The README's example, compiled as a doc test.
#[doc = include_str!("../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;
