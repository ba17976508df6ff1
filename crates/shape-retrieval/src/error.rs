/// Failures of descriptor computation and retrieval.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RetrievalError {
    /// An error from the heat kernel.
    #[error(transparent)]
    Heat(#[from] wfem_heat::HeatError),
}
