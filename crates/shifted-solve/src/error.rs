use faer::c64;

/// Failures of the shifted solvers.
///
/// Serialized (serde) as `{"Variant": {field: value}}`, which is how the Python package builds
/// its exceptions (a pole as its pair (re, im)).
#[derive(Debug, Clone, thiserror::Error, serde::Serialize)]
#[non_exhaustive]
pub enum SolveError {
    /// The computation was interrupted by its caller ([`wfem_base::interrupt`]).
    #[error(transparent)]
    Interrupted(#[from] wfem_base::interrupt::Interrupted),
    /// Matrix or vector dimensions do not agree.
    #[error("dimension mismatch: {what} (expected {expected}, got {got})")]
    DimensionMismatch {
        /// What was being compared.
        what: &'static str,
        /// Expected size.
        expected: usize,
        /// Size found.
        #[serde(rename = "found")]
        got: usize,
    },
    /// A matrix that must be square is not.
    #[error("{which} matrix is not square ({nrows} × {ncols})")]
    NotSquare {
        /// Which matrix (`"stiffness"` or `"mass"`).
        #[serde(rename = "matrix")]
        which: &'static str,
        /// Rows.
        nrows: usize,
        /// Columns.
        ncols: usize,
    },
    /// The matrices are empty (n = 0).
    #[error("the matrices are empty (n = 0)")]
    Empty,
    /// No rational approximation of this degree is shipped.
    #[error("no rational approximation of degree {degree} is shipped (available: {available:?})")]
    UnsupportedDegree {
        /// Requested degree.
        degree: usize,
        /// Degrees that exist.
        available: &'static [usize],
    },
    /// The diffusion time is not a finite positive number.
    #[error("diffusion time t = {t} must be finite and > 0")]
    InvalidTime {
        /// The offending t.
        t: f64,
    },
    /// NaN or ±∞ in an input.
    #[error("non-finite value {value} in {what} at row {row}, column {col}")]
    NonFinite {
        /// Which input (`"stiffness"`, `"mass"`, `"right-hand side"`).
        what: &'static str,
        /// Row.
        row: usize,
        /// Column.
        #[serde(rename = "column")]
        col: usize,
        /// The value.
        value: f64,
    },
    /// A matrix that must be symmetric is not.
    #[error("{which} matrix is not symmetric: entry ({row}, {col}) = {value} but ({col}, {row}) = {transposed}")]
    NotSymmetric {
        /// Which matrix.
        #[serde(rename = "matrix")]
        which: &'static str,
        /// Row.
        row: usize,
        /// Column.
        #[serde(rename = "column")]
        col: usize,
        /// A[row, col].
        value: f64,
        /// A[col, row].
        transposed: f64,
    },
    /// A diagonal entry that must be positive (mass) or non-negative (stiffness) is not.
    #[error("{which} matrix has diagonal entry {value} at index {index} (must be {requirement})")]
    BadDiagonal {
        /// Which matrix.
        #[serde(rename = "matrix")]
        which: &'static str,
        /// Index.
        index: usize,
        /// Value.
        value: f64,
        /// `"> 0"` or `">= 0"`.
        requirement: &'static str,
    },
    /// The Cholesky factorization of the mass matrix B failed: B is not positive definite.
    #[error("mass matrix B is not symmetric positive definite (Cholesky failed: {detail})")]
    MassNotPositiveDefinite {
        /// faer's message.
        #[serde(rename = "reason")]
        detail: String,
    },
    /// L + δ·diag(L) is not positive definite for a tiny relative δ > 0: L has a direction of
    /// negative curvature (wfem's L is positive semidefinite with a positive diagonal; libigl's
    /// `cotmatrix` has the opposite sign).
    #[error("stiffness matrix L is not positive semidefinite: Cholesky of L + {delta:e}·diag(L) failed (did you pass −L, e.g. libigl's cotmatrix?)")]
    StiffnessIndefinite {
        /// The regularising shift δ used in the test.
        delta: f64,
    },
    /// A shifted matrix tL − zB could not be factored or produced a non-finite solution.
    #[error("shifted matrix tL − zB is numerically singular for t = {t}, z = {pole}")]
    SingularShiftedMatrix {
        /// Diffusion time.
        t: f64,
        /// Pole z.
        #[serde(serialize_with = "complex")]
        pole: c64,
    },
    /// An iterative solver did not reach the requested tolerance.
    #[error(
        "iterative solve for pole z = {pole} stopped at relative residual {residual:e} after {iterations} iterations"
    )]
    NoConvergence {
        /// Relative (preconditioned) residual reached.
        residual: f64,
        /// Iterations performed.
        iterations: usize,
        /// The pole.
        #[serde(serialize_with = "complex")]
        pole: c64,
    },
    /// A shift-and-invert Lanczos iteration ([`crate::function::lanczos_function`],
    /// [`crate::backend::Backend::MultiShift`]) did not meet its tolerance.
    #[error("Lanczos iteration stopped after {iterations} steps with error estimate {estimate:e}")]
    KrylovNoConvergence {
        /// Steps performed.
        iterations: usize,
        /// Last successive-difference estimate (relative, B-norm).
        estimate: f64,
    },
    /// A parameter is out of range.
    #[error("invalid parameter {name} = {value}: {reason}")]
    InvalidParameter {
        /// Parameter name.
        name: &'static str,
        /// Value given.
        value: f64,
        /// What is required.
        reason: &'static str,
    },
    /// faer reported a structural or memory failure.
    #[error("sparse factorization failed ({what}): {detail}")]
    Factorization {
        /// Which factorization.
        what: &'static str,
        /// faer's message.
        #[serde(rename = "reason")]
        detail: String,
    },
}

/// A complex number as its pair (re, im) (serde has no complex type).
fn complex<S: serde::Serializer>(z: &c64, s: S) -> Result<S::Ok, S::Error> {
    serde::Serialize::serialize(&(z.re, z.im), s)
}
