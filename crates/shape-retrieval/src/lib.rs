//! # shape-retrieval
//!
//! Heat kernel shape descriptors (HKS, scale-invariant HKS), feature points, bags of
//! features and retrieval metrics on top of [`wfem_heat`].
//!
//! Descriptors are computed from a truncated spectrum of the generalized eigenproblem
//! `L φ_k = λ_k B φ_k`, `ΦᵀBΦ = I` (paper, Eq. (4)), with L the cotangent stiffness
//! (symmetric positive semidefinite, positive diagonal) and B the mass matrix, given as plain
//! inputs ([`hks::Spectrum`]), so any eigensolver can feed them:
//!
//! * [`hks`]: heat kernel signature in the kernel-value and operator-diagonal conventions,
//!   scaled and scale-normalized variants;
//! * [`exact`]: the HKS without eigen truncation (the kernel's diagonal by selected inversion) and the
//!   per-time choice between it and the truncated sum ([`exact::HksMethod`], default auto);
//! * [`sihks`]: the scale-invariant HKS of Bronstein & Kokkinos;
//! * [`kmeans`](mod@kmeans), [`bof`]: vocabularies, soft-assigned (spatially sensitive) bags of features;
//! * [`retrieval`]: ranking, average precision, mAP, precision/recall;
//! * [`collection`]: a collection described or indexed in parallel, with progress, its
//!   unusable shapes left out and reported (or fatal);
//! * [`eval`](mod@eval): a labelled collection evaluated leave-one-out (mAP, NN, tiers,
//!   E-measure, DCG, per class, confused pairs);
//! * [`descriptor`]: from a mesh to DHK1–DHK3, SI-HKS and the SHK1/SHK2 feature points;
//! * [`model`]: the retrieval model — [`model::RetrievalSettings`], [`model::RetrievalIndex`],
//!   the vocabulary, the cleaning steps, the vertex weights and the global signature; [`store`]:
//!   where an index and a vocabulary are kept;
//! * [`features`]: feature points (local maxima), their repeatability, and robustness of
//!   dense descriptors.

#![warn(missing_docs)]
// Robustness (issue #8): no unwrap()/expect() on user-controlled data in library code; the few
// justified ones carry `#[allow]` and an `// invariant:` comment (checked by tests/no_unwrap.rs).
#![cfg_attr(not(test), warn(clippy::unwrap_used, clippy::expect_used))]

pub mod bof;
mod check;
pub mod collection;
pub mod descriptor;
pub mod distance;
mod error;
pub mod eval;
pub mod exact;
pub mod features;
pub mod global;
pub mod hks;
pub mod kmeans;
pub mod limits;
pub mod mesh_hks;
pub mod model;
mod output;
pub mod retrieval;
pub mod sihks;
pub mod spatial;
pub mod standardize;
pub mod store;
pub mod wks;

// The curated root (ARCHITECTURE.md, "Crate roots"): the error and the output check of an
// index. Every other item — the index and its settings included, in `model` with the rest of
// the retrieval model — is reached through its public module only.
pub use error::RetrievalError;
pub use output::check_index_output;
