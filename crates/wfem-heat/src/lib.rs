//! # wfem-heat
//!
//! The wFEM heat kernel `K_t = exp(−t B⁻¹L) = X D_t Xᵀ B` (paper, Eq. (6)) applied to
//! functions on a triangle mesh, without computing the spectrum.

#![warn(missing_docs)]

mod error;
pub use error::HeatError;
