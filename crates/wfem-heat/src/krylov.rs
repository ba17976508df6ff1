//! The fast exact path: shift-and-invert (restricted-denominator) rational Krylov for
//! `exp(−t M⁻¹L) f` (van den Eshof & Hochbruck, SIAM J. Sci. Comput. 27 (2006) 1438–1457).
//!
//! With A = M + γtL (SPD, one real sparse Cholesky per t) the operator
//! S = A⁻¹M = (I + γt M⁻¹L)⁻¹ is self-adjoint in ⟨u, v⟩_M = uᵀMv with eigenvalues
//! s = 1/(1 + γtλ) ∈ (0, 1]. Since tλ = (1/s − 1)/γ,
//!
//! `K_t f = g(S) f`, with `g(s) = exp(−(1/s − 1)/γ)`.
//!
//! m steps of Lanczos in the M-inner product give S V_m = V_m T_m + β v_{m+1} e_mᵀ with
//! V_mᵀMV_m = I, and `K_t f ≈ ‖f‖_M V_m g(T_m) e₁`. Because g is smooth on (0, 1] and its
//! poles are all at s = 0, the convergence does not depend on ‖tL‖ (mesh size or t), only
//! on the accuracy wanted: a few tens of solves reach 1e−12.

use crate::sparse::{spmv_seq, spmv_sym};
use crate::HeatError;
use shifted_solve::{lanczos_function, LanczosParams, SolveError};

/// Options of the fast path ([`crate::Method::Fast`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FastParams {
    /// Shift parameter γ of `A = M + γtL`. Values 0.05–0.2 work well for exp(−x) at
    /// accuracy 1e−10…1e−12.
    pub gamma: f64,
    /// Relative tolerance on the difference of two successive iterates, in the M-norm,
    /// relative to ‖K_t f‖_M (or to ‖f‖_M·1e−3 when the result is that small).
    pub tol: f64,
    /// Maximum number of Lanczos steps (= solves with the factor of A).
    pub max_iter: usize,
}

impl Default for FastParams {
    fn default() -> Self {
        Self {
            gamma: 0.1,
            tol: 1e-11,
            max_iter: 200,
        }
    }
}

/// g(s) = exp(−(1/s − 1)/γ), continued by 0 for s ≤ 0 (rounding can push a Ritz value
/// of S, whose spectrum lies in (0, 1], marginally below zero).
fn g(s: f64, gamma: f64) -> f64 {
    if s <= 0.0 {
        0.0
    } else {
        (-(1.0 / s - 1.0) / gamma).exp()
    }
}

/// Outcome of one fast-path evaluation (per right-hand side).
#[derive(Clone, Copy, Debug)]
pub(crate) struct KrylovOutcome {
    pub iterations: usize,
    pub estimate: f64,
}

/// `K_t f ≈ ‖f‖_M V_m g(T_m) e₁` with `solve` applying (M + γtL)⁻¹ (the Lanczos run itself
/// is [`shifted_solve::lanczos_function`]). `alone`: this is the only right-hand side, so the
/// products with M may use every core (inside a parallel loop over columns they must not).
pub(crate) fn rational_krylov_exp(
    solve: &dyn Fn(&[f64]) -> Vec<f64>,
    mass: &faer::sparse::SparseColMat<usize, f64>,
    f: &[f64],
    params: &FastParams,
    column: usize,
    alone: bool,
) -> Result<(Vec<f64>, KrylovOutcome), HeatError> {
    let gamma = params.gamma;
    let lanczos = LanczosParams {
        tol: params.tol,
        max_iter: params.max_iter,
    };
    let mass_mul = |x: &[f64]| if alone { spmv_sym(mass, x) } else { spmv_seq(mass, x) };
    match lanczos_function(solve, &mass_mul, f, &|s| g(s, gamma), &lanczos) {
        Ok((out, o)) => Ok((
            out,
            KrylovOutcome {
                iterations: o.iterations,
                estimate: o.estimate,
            },
        )),
        Err(SolveError::KrylovNoConvergence { iterations, estimate }) => Err(HeatError::KrylovNoConvergence {
            column,
            iterations,
            estimate,
        }),
        Err(SolveError::Factorization { .. }) => Err(HeatError::DenseEigen),
        Err(e) => Err(e.into()),
    }
}
