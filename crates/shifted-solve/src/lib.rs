//! # shifted-solve
//!
//! The linear-algebra engine behind the paper's Eq. (10)–(14): a rational approximation
//! `e^{-x} ≈ c0 + 2 Re Σ_j c_j / (x − z_j)` of the exponential on [0, ∞) turns
//! `exp(−t B⁻¹L) f` into shifted sparse solves `(tL − z_j B) g_j = B f`.
//!
//! This crate knows nothing about meshes. It takes any symmetric positive semidefinite L
//! (the stiffness, positive diagonal) and symmetric positive definite B (the mass).

#![warn(missing_docs)]

mod error;
pub use error::SolveError;
