//! The rational resolvent sum *on the sparsity pattern*, by selected inversion:
//!
//! ```text
//! R_t = 2 Re Σ_j c_j (tL − z_j M)⁻¹  (+ the real pole)  ≈  X e^{−tΛ} Xᵀ = K̃_t,
//! ```
//!
//! the heat-kernel matrix (paper Eq. (6) with `K_t = K̃_t M`; `XᵀMX = I`), evaluated only at
//! the stored entries (i, j) of the pattern of L and M — which include the diagonal
//! `K̃_t(i, i)`, the heat kernel signature, and every entry that `diag(K̃_t M)` (the diagonal of
//! K_t) needs. Each pole costs one complex-symmetric LDLᵀ and one selected inversion of it
//! (about the cost of the factorization); no column of `K̃_t` is formed, so the cost does not
//! depend on how far the kernel spreads (probing needs ever more columns as t grows; eigen
//! truncation misses the small-t diagonal).
//!
//! **Accuracy.** `|r_n(x) − e^{−x}| ≤ E_n` on [0, ∞) (Eq. (14)), so the full approximant is
//! within `E_n · (M⁻¹)_ii` of K̃_t(i, i) (since `Σ_k x_k(i)² = (M⁻¹)_ii`). The c0 term
//! `c0 M⁻¹` (|c0| ≤ E_n) is omitted, as in [`crate::RationalFactors::apply_resolvent`], which
//! adds at most another `E_n · (M⁻¹)_ii`: every entry is within `2 E_n · (M⁻¹)_ii`. With the
//! default degree 16 (E_16 ≈ 2e−16) that is rounding level relative to `K̃_t(i, i) ≥ 1/area`.

use crate::backend::direct::shift_scale;
use crate::backend::Pole;
use crate::ldlt::{LdltFactor, LdltSymbolic};
use crate::poles::RationalApprox;
use crate::solver::check_time;
use crate::{OperatorPair, SolveError};
use rayon::prelude::*;
use std::sync::Arc;

/// Selected inversion of the shifted matrices of one operator pair: the symbolic LDLᵀ layout
/// (shared by every pole and every t) and where each entry of the pair's pattern sits in it.
#[derive(Debug, Clone)]
pub struct SelectedInversion {
    pair: Arc<OperatorPair>,
    symbolic: Arc<LdltSymbolic>,
    positions: Arc<Vec<usize>>,
}

impl SelectedInversion {
    /// Prepares selected inversion on a validated pair (its supernodal analysis is shared).
    /// The rational approximation is valid on the spectrum [0, ∞), so the pair's
    /// definiteness ([`OperatorPair::check_definite`]) is checked here.
    ///
    /// # Errors
    /// [`SolveError::Factorization`] for a failed symbolic analysis;
    /// [`SolveError::MassNotPositiveDefinite`], [`SolveError::StiffnessIndefinite`].
    pub fn new(pair: Arc<OperatorPair>) -> Result<Self, SolveError> {
        let analysis = pair.cholesky()?.symbolic();
        let symbolic = LdltSymbolic::new(pair.pattern(), analysis).map_err(|detail| SolveError::Factorization {
            what: "symbolic LDLᵀ",
            detail,
        })?;
        pair.check_definite()?;
        let positions = symbolic.pattern_positions(pair.pattern());
        Ok(Self {
            pair,
            symbolic: Arc::new(symbolic),
            positions: Arc::new(positions),
        })
    }

    /// The operator pair.
    pub fn pair(&self) -> &Arc<OperatorPair> {
        &self.pair
    }

    /// `R_t = 2 Re Σ_j c_j (tL − z_j M)⁻¹` (+ the real pole) at every stored entry of the
    /// pair's pattern ([`OperatorPair::pattern`], both triangles, in its order): with the
    /// default approximation, the heat-kernel matrix K̃_t on the pattern (module docs). The
    /// poles run in parallel.
    ///
    /// # Errors
    /// [`SolveError::InvalidTime`]; [`SolveError::SingularShiftedMatrix`] for a zero pivot
    /// (the matrix is not of the form tL − zM with L ⪰ 0, M ≻ 0).
    pub fn resolvent_on_pattern(&self, approx: &RationalApprox, t: f64) -> Result<Vec<f64>, SolveError> {
        check_time(t)?;
        let pair = &*self.pair;
        let interrupt = wfem_base::interrupt::current();
        let parts = Pole::all(approx)
            .into_par_iter()
            .map(|pole| -> Result<Vec<f64>, SolveError> {
                wfem_base::interrupt::within(interrupt.as_ref(), wfem_base::interrupt::checkpoint)?;
                // Factor c·(tL − zM) (c a power of two, exact): its inverse is Z/c.
                let scale = shift_scale(pair, t, pole.z);
                let values: Vec<_> = pair.shifted_values(t, pole.z).into_iter().map(|v| v * scale).collect();
                let factor = LdltFactor::new(&self.symbolic, &values).map_err(|_| pole.singular(t))?;
                wfem_base::interrupt::within(interrupt.as_ref(), wfem_base::interrupt::checkpoint)?;
                let z = factor.selected_inverse();
                let w = pole.weight() * scale;
                let out: Vec<f64> = self.positions.iter().map(|&p| w * (pole.c * z[p]).re).collect();
                if out.iter().any(|v| !v.is_finite()) {
                    return Err(pole.singular(t));
                }
                Ok(out)
            })
            .collect::<Result<Vec<_>, SolveError>>()?;
        let mut sum = vec![0.0; self.positions.len()];
        for part in parts {
            sum.iter_mut().zip(part).for_each(|(s, v)| *s += v);
        }
        Ok(sum)
    }
}
