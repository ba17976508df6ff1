/// Failures of heat-kernel evaluation.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum HeatError {
    /// The diffusion time is not a finite positive number.
    #[error("diffusion time t = {t} must be finite and positive")]
    InvalidTime {
        /// The time given.
        t: f64,
    },
    /// An error from the shifted solvers.
    #[error(transparent)]
    Solve(#[from] shifted_solve::SolveError),
    /// An error from mesh loading or assembly.
    #[error(transparent)]
    Mesh(#[from] mesh_fem::MeshError),
}
