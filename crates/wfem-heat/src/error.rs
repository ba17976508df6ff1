/// Failures of heat-kernel evaluation.
///
/// Serialized (serde) as `{"Variant": {field: value}}`, which is how the Python package builds
/// its exceptions (the eigenpairs an eigensolve did find are not serialized).
#[derive(Debug, thiserror::Error, serde::Serialize)]
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

    // ---- wfem-heat core (HeatKernel, Eigenbasis, fast path) ----
    /// An input vector (or matrix) has the wrong number of rows.
    #[error("input has {found} rows, but the mesh has {expected} vertices")]
    LengthMismatch {
        /// The number of vertices n.
        expected: usize,
        /// The length given.
        found: usize,
    },
    /// An input entry is NaN or infinite.
    #[error("input entry (row {row}, column {column}) is not finite: {value}")]
    NonFiniteInput {
        /// Row (vertex) of the culprit.
        row: usize,
        /// Column (right-hand side) of the culprit; 0 for a vector.
        column: usize,
        /// The value found.
        value: f64,
    },
    /// The dense reference was asked for a mesh too large for O(n³) work and O(n²) memory.
    #[error("dense eigendecomposition refused for n = {n_vertices} vertices (limit {limit})")]
    TooLargeForDense {
        /// Number of vertices of the mesh.
        n_vertices: usize,
        /// The limit, [`crate::spectral::DENSE_MAX_VERTICES`].
        limit: usize,
    },
    /// A parameter is outside its valid range.
    #[error("invalid parameter `{name}`: {reason}")]
    InvalidParameter {
        /// Name of the parameter.
        name: &'static str,
        /// Why it was rejected.
        reason: String,
    },
    /// An option given beside a method's name that belongs to another method (it is refused,
    /// not ignored; [`crate::method::Method::with_options`]).
    #[error("option `{option}` applies to the {owner} method only, not to {method}")]
    MisplacedOption {
        /// The option (`degree`, `backend`, `eigenpairs`).
        option: &'static str,
        /// The method it was given to.
        method: &'static str,
        /// The method it belongs to.
        owner: &'static str,
    },
    /// The operators are inconsistent (size or sparsity pattern).
    #[error("inconsistent operators: {reason}")]
    InconsistentOperators {
        /// What is wrong.
        reason: String,
    },
    /// A sparse or dense Cholesky factorization failed: the matrix is not numerically
    /// positive definite (e.g. a mass matrix of a mesh with degenerate faces).
    #[error("Cholesky factorization of {matrix} failed (not positive definite)")]
    NotPositiveDefinite {
        /// Which matrix, e.g. "B + γtL".
        matrix: String,
    },
    /// A dense eigendecomposition did not converge.
    #[error("dense self-adjoint eigendecomposition did not converge")]
    DenseEigen,
    /// The shift-invert Lanczos eigensolver stopped before `requested` eigenpairs converged.
    /// The pairs that did converge (the smallest ones) are returned in `found`.
    #[error(
        "eigensolver found {converged} of {requested} eigenpairs (Krylov dimension {dimension}, \
         worst relative residual {max_residual:.2e})"
    )]
    EigenNoConvergence {
        /// Number of eigenpairs asked for.
        requested: usize,
        /// Number of eigenpairs that met the tolerance.
        converged: usize,
        /// Krylov dimension reached.
        dimension: usize,
        /// Largest relative residual among the requested pairs.
        max_residual: f64,
        /// The converged pairs (smallest eigenvalues first).
        #[serde(skip)]
        found: Box<crate::eigenbasis::Eigenbasis>,
    },
    /// The rational Krylov iteration of the fast path did not reach its tolerance.
    #[error(
        "fast path did not converge for column {column}: {iterations} iterations, \
         error estimate {estimate:.2e}"
    )]
    KrylovNoConvergence {
        /// Right-hand side that failed.
        column: usize,
        /// Iterations performed.
        iterations: usize,
        /// Last a-posteriori error estimate (relative, in the B-norm).
        estimate: f64,
    },

    // ---- operator algebra, RKHS and diffusion distances (algebra.rs, distance.rs) ----
    /// The inverse heat operator `K_{−t} = K_t⁻¹` (paper, Sect. 4) was refused: the data are
    /// not band-limited enough for the requested t, so the answer would be amplified noise.
    #[error(
        "inverse heat operator K_(-t) refused at t = {t}: {reason} (amplification {amplification:.3e}, \
         cap {cap:.1e}, {iterations} iterations, relative residual {relative_residual:.2e})"
    )]
    IllConditionedInverse {
        /// The diffusion time t of K_{−t}.
        t: f64,
        /// Why: the amplification cap was exceeded, or the residual stalled.
        reason: String,
        /// The amplification ‖g‖_B / ‖f‖_B reached (or e^{tλ_k} for the spectral inverse).
        amplification: f64,
        /// The user's cap on the amplification.
        cap: f64,
        /// Iterations performed (0 for the spectral inverse).
        iterations: usize,
        /// Last relative residual ‖f − K_t g‖_B / ‖f‖_B.
        #[serde(rename = "residual")]
        relative_residual: f64,
    },
    /// A vertex index is out of range.
    #[error("vertex {index} does not exist (the mesh has {n_vertices} vertices)")]
    VertexOutOfRange {
        /// The index given.
        #[serde(rename = "vertex")]
        index: usize,
        /// Number of vertices n.
        n_vertices: usize,
    },

    // ---- robustness (issue #8): operator validation ----
    /// An entry of the stiffness or mass matrix is invalid: NaN or infinite, or a diagonal
    /// entry of the mass matrix that is not positive (M would be singular and
    /// K_t = exp(−tM⁻¹L) undefined).
    #[error("{matrix} entry ({row}, {col}) = {value} is invalid (must be {requirement})")]
    InvalidOperatorEntry {
        /// Which matrix, e.g. "stiffness L" or "mass M".
        matrix: &'static str,
        /// Row of the culprit.
        row: usize,
        /// Column of the culprit.
        #[serde(rename = "column")]
        col: usize,
        /// The value found.
        value: f64,
        /// What is required, e.g. "finite" or "> 0 on the diagonal".
        requirement: &'static str,
    },
    /// The mesh has needle or cap triangles so thin that rounding in the assembled L alone
    /// (cotangent weights of order ±1/angle) spoils K_t beyond the stated error: the result
    /// would be noise ([`crate::Conditioning`]).
    #[error(
        "nearly degenerate triangles at vertex {vertex}: its stiffness L_ii is {ratio:.1e} times that of a \
         well-shaped mesh, so rounding alone makes K_t uncertain by about {estimated_error:.0e} (relative); \
         collapse or drop the needle/cap faces (mesh validation lists them) and try again"
    )]
    IllConditionedMesh {
        /// A vertex of the worst row of L.
        vertex: usize,
        /// The conditioning ratio ([`crate::Conditioning::ratio`]).
        ratio: f64,
        /// The relative error rounding alone can cause.
        estimated_error: f64,
    },
    /// A computation produced NaN or ∞ (it is refused instead of returned).
    #[error("the {method} method produced a non-finite value at row {row}, column {column}")]
    NonFiniteResult {
        /// The method.
        method: &'static str,
        /// Row of the first non-finite entry.
        row: usize,
        /// Its column.
        column: usize,
    },
}
