//! # shifted-solve
//!
//! The linear-algebra engine behind the paper's Eq. (10)–(14): a best uniform rational
//! approximation `e^{-x} ≈ r_n(x) = c0 + 2 Re Σ_j c_j / (x − z_j)` of the exponential on
//! [0, ∞) (Eq. (10)–(11), [`poles::RationalApprox`]) turns the heat operator into shifted sparse
//! solves (Eq. (12)–(13)):
//!
//! ```text
//! K_t f = exp(−t B⁻¹L) f ≈ c0 f + 2 Re Σ_j c_j (tL − z_j B)⁻¹ (B f),
//! ```
//!
//! with error ‖r_n(tB⁻¹L) − K_t‖_{B→B} ≤ E_n (Eq. (14)). This crate knows nothing about meshes.
//! It takes any symmetric positive semidefinite L (the stiffness, positive diagonal — wfem's
//! sign convention; libigl's `cotmatrix` is −L) and symmetric positive definite B (the mass),
//! as faer `SparseColMat<usize, f64>`, possibly with different sparsity patterns.
//!
//! * [`OperatorPair`]: the validated pair (L, M) on one shared pattern with its one symbolic
//!   Cholesky analysis — the context every solver and method works on (validated once).
//! * [`ShiftedSolver`]: a [`backend::Backend`] prepared on a pair; applies r_n(tM⁻¹L) or the
//!   resolvent sum to n × k right-hand sides. Backends (one module each under [`backend`]):
//!   [`DirectLdlt`](backend::Backend::DirectLdlt) (complex-symmetric supernodal LDLᵀ without
//!   pivoting, the default), [`DirectLu`](backend::Backend::DirectLu) (pivoted complex sparse
//!   LU), [`Minres`](backend::Backend::Minres) (the paper's preconditioned MINRES on the real
//!   2n×2n form, [`iterative`]) and [`MultiShift`](backend::Backend::MultiShift) (every pole in
//!   one shift-and-invert Lanczos space, one real Cholesky per t).
//! * [`RationalFactors`]: all poles of one t factored once, reused for many right-hand sides.
//! * [`SelectedInversion`]: the resolvent sum (the heat-kernel matrix H_t) on the sparsity
//!   pattern — its diagonal is the exact heat kernel signature — by selected inversion of the
//!   LDLᵀ factors, at about the cost of the factorizations, for every t.
//! * [`function::lanczos_function`] with [`function::KrylovParams`]: h(S)u for
//!   S = (M + γtL)⁻¹M, the engine of wfem-heat's fast exact path and of the multi-shift backend.
//! * [`eigen::largest_eigenpairs`] with [`eigen::BlockLanczosParams`]: thick-restart block
//!   Lanczos with locking for the largest eigenpairs of an M-self-adjoint operator — with
//!   S = (L − σM)⁻¹M the smallest pairs of `L x = λ M x`, the engine of wfem-heat's spectral path.
//! * [`lanczos`]: the one Lanczos process; [`lanczos::symmetric_eigen`], the one scale-robust
//!   dense symmetric eigensolver of the Lanczos methods and of wfem-heat's dense reference.
//! * [`CholeskyPattern`], [`SpdFactor`]: the real sparse Cholesky (symbolic once, numeric per
//!   shift) with its tree-parallel solve; its fill-reducing ordering (AMD, or our nested
//!   dissection where it gives a smaller factor) is chosen in [`ordering`].
//! * [`ConditionReport`]: 2-norm condition numbers of tL − zB and of the preconditioned
//!   operator (paper Fig. 2c,d).

#![warn(missing_docs)]
// Robustness (issue #8): no unwrap()/expect() on user-controlled data in library code; the few
// justified ones carry `#[allow]` and an `// invariant:` comment (checked by tests/no_unwrap.rs).
#![cfg_attr(not(test), warn(clippy::unwrap_used, clippy::expect_used))]

pub mod backend;
mod blocks;
mod condition;
pub mod eigen;
mod error;
mod factor;
pub mod function;
pub mod iterative;
pub mod lanczos;
mod ldlt;
mod operators;
pub mod ordering;
pub mod poles;
mod selected;
mod solver;
mod trisolve;

#[cfg(test)]
mod cf;

// The curated root (ARCHITECTURE.md, "Crate roots"): the validated pair, the solver and what it
// factors, the error. Every other item is reached through its public module only.
pub use condition::ConditionReport;
pub use error::SolveError;
pub use factor::{CholeskyPattern, SpdFactor};
pub use operators::OperatorPair;
pub use selected::SelectedInversion;
pub use solver::{RationalFactors, ShiftedSolver};
