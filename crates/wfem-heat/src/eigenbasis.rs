//! The eigenpairs type, data only: its constructors ([`Eigenbasis::dense`],
//! [`Eigenbasis::partial`], …) and the spectral kernel live in [`crate::spectral`]. It sits
//! below the error type, which carries the converged pairs of an eigensolve that stopped short
//! ([`crate::HeatError::EigenNoConvergence`]), so that neither module depends on the other.

use faer::Mat;

/// Eigenpairs of the generalized problem `L xᵢ = λᵢ M xᵢ` (paper, Eq. (4)), sorted by
/// increasing λ, with M-orthonormal eigenvectors `XᵀMX = I`.
#[derive(Clone, Debug)]
pub struct Eigenbasis {
    /// Eigenvalues λ₁ ≤ λ₂ ≤ … (λ₁ ≈ 0 on a connected mesh, eigenvector the constant 1/√area).
    pub values: Vec<f64>,
    /// Eigenvectors as columns, n × k, M-orthonormal: `XᵀMX = I`.
    pub vectors: Mat<f64>,
}
