//! The shifted-system engine: r_n(tM⁻¹L)F = c0·F + 2 Re Σ_j c_j (tL − z_j M)⁻¹ (M F)
//! (paper Eq. (12)–(13), written with upper-half-plane poles, see [`crate::poles`]), on a
//! validated [`OperatorPair`] with one of the [`Backend`]s.

use crate::backend::{Backend, BatchReport, Pole, PoleReport, PreparedBackend, ShiftedSolve};
use crate::poles::RationalApprox;
use crate::{OperatorPair, SolveError};
use faer::sparse::SparseColMatRef;
use faer::{Mat, MatRef};
use std::sync::Arc;

/// A backend prepared on one operator pair: the symbolic analyses shared by every pole and
/// every t. Cheap to clone (shared).
#[derive(Debug, Clone)]
pub struct ShiftedSolver {
    pair: Arc<OperatorPair>,
    backend: Backend,
    prepared: Arc<dyn PreparedBackend>,
}

pub(crate) fn check_time(t: f64) -> Result<(), SolveError> {
    if t.is_finite() && t > 0.0 {
        Ok(())
    } else {
        Err(SolveError::InvalidTime { t })
    }
}

fn check_rhs(rhs: MatRef<'_, f64>, n: usize) -> Result<(), SolveError> {
    if rhs.nrows() != n {
        return Err(SolveError::DimensionMismatch {
            what: "right-hand side rows vs matrix size",
            expected: n,
            got: rhs.nrows(),
        });
    }
    for j in 0..rhs.ncols() {
        for i in 0..n {
            let v = rhs[(i, j)];
            if !v.is_finite() {
                return Err(SolveError::NonFinite {
                    what: "right-hand side",
                    row: i,
                    col: j,
                    value: v,
                });
            }
        }
    }
    Ok(())
}

impl ShiftedSolver {
    /// Validates L (symmetric positive semidefinite stiffness, non-negative diagonal) and M
    /// (symmetric positive definite mass) into an [`OperatorPair`] and prepares `backend` on it.
    ///
    /// # Errors
    /// Those of [`OperatorPair::new`] and [`Self::with_pair`].
    pub fn new(
        stiffness: SparseColMatRef<'_, usize, f64>,
        mass: SparseColMatRef<'_, usize, f64>,
        backend: Backend,
    ) -> Result<Self, SolveError> {
        Self::with_pair(Arc::new(OperatorPair::new(stiffness, mass)?), backend)
    }

    /// Prepares `backend` on an already validated pair (shared with other solvers). The
    /// rational approximation is valid on the spectrum [0, ∞), so the pair's definiteness
    /// ([`OperatorPair::check_definite`]) is checked here (once per pair).
    ///
    /// # Errors
    /// [`SolveError::InvalidParameter`] for bad backend parameters,
    /// [`SolveError::MassNotPositiveDefinite`], [`SolveError::StiffnessIndefinite`],
    /// [`SolveError::Factorization`] for a failed symbolic analysis.
    pub fn with_pair(pair: Arc<OperatorPair>, backend: Backend) -> Result<Self, SolveError> {
        let prepared = backend.prepare(&pair)?;
        pair.check_definite()?;
        Ok(Self {
            pair,
            backend,
            prepared: Arc::from(prepared),
        })
    }

    /// Matrix size n.
    pub fn n(&self) -> usize {
        self.pair.n()
    }

    /// Number of stored entries of the shared pattern of L and M.
    pub fn nnz(&self) -> usize {
        self.pair.nnz()
    }

    /// The backend chosen at construction.
    pub fn backend(&self) -> &Backend {
        &self.backend
    }

    /// The validated operator pair.
    pub fn pair(&self) -> &Arc<OperatorPair> {
        &self.pair
    }

    /// Approximates the heat operator, `r_n(t M⁻¹L) F = c0·F + 2 Re Σ_j c_j (tL − z_j M)⁻¹ (M F)`
    /// (paper Eq. (13) in the sign convention of docs/NUMERICS.md §0.1). `rhs` is n × k.
    ///
    /// # Errors
    /// Invalid t, size/NaN problems in `rhs`, singular shifted matrices, non-convergence.
    pub fn apply(
        &self,
        approx: &RationalApprox,
        t: f64,
        rhs: MatRef<'_, f64>,
    ) -> Result<(Mat<f64>, BatchReport), SolveError> {
        self.factor_for(approx, t, rhs)?.apply(rhs)
    }

    /// `2 Re Σ_j c_j (tL − z_j M)⁻¹ G` (+ the real pole), without the c0 term and without the
    /// multiplication by M: with G = e_i this is the heat-kernel column H_t e_i (docs/NUMERICS.md §1).
    ///
    /// # Errors
    /// As [`Self::apply`].
    pub fn apply_resolvent(
        &self,
        approx: &RationalApprox,
        t: f64,
        rhs: MatRef<'_, f64>,
    ) -> Result<(Mat<f64>, BatchReport), SolveError> {
        self.factor_for(approx, t, rhs)?.apply_resolvent(rhs)
    }

    /// [`Self::factor`] for the right-hand sides `rhs`, checked first (before the cost of the
    /// factorization).
    fn factor_for(&self, approx: &RationalApprox, t: f64, rhs: MatRef<'_, f64>) -> Result<RationalFactors, SolveError> {
        check_rhs(rhs, self.n())?;
        self.factor(approx, t)
    }

    /// Prepares every pole of one t with the backend (complex factorizations, preconditioners,
    /// or the one real factor of the multi-shift backend). Reuse the result for any number of
    /// right-hand sides.
    ///
    /// # Errors
    /// [`SolveError::InvalidTime`], [`SolveError::SingularShiftedMatrix`],
    /// [`SolveError::Factorization`].
    pub fn factor(&self, approx: &RationalApprox, t: f64) -> Result<RationalFactors, SolveError> {
        check_time(t)?;
        let poles = Pole::all(approx);
        Ok(RationalFactors {
            pair: self.pair.clone(),
            t,
            c0: approx.c0,
            solve: self.prepared.factor(&self.pair, &poles, t)?,
        })
    }
}

/// All poles of one t, prepared once (paper Eq. (12)); apply to any number of right-hand sides.
#[derive(Debug)]
pub struct RationalFactors {
    pair: Arc<OperatorPair>,
    t: f64,
    c0: f64,
    solve: Box<dyn ShiftedSolve>,
}

impl RationalFactors {
    /// Diffusion time t of these factors.
    pub fn t(&self) -> f64 {
        self.t
    }

    /// `r_n(t M⁻¹L) F = c0·F + 2 Re Σ_j c_j (tL − z_j M)⁻¹ (M F)` for F of size n × k.
    ///
    /// # Errors
    /// Size/NaN problems in `rhs`, non-finite solutions, non-convergence.
    pub fn apply(&self, rhs: MatRef<'_, f64>) -> Result<(Mat<f64>, BatchReport), SolveError> {
        check_rhs(rhs, self.pair.n())?;
        let (mut out, poles) = self.solve.mass_resolvent(&self.pair, rhs)?;
        for j in 0..rhs.ncols() {
            for i in 0..rhs.nrows() {
                out[(i, j)] += self.c0 * rhs[(i, j)];
            }
        }
        Ok((out, self.report(rhs.ncols(), poles)))
    }

    /// `2 Re Σ_j c_j (tL − z_j M)⁻¹ G` (+ real pole), no c0 term, no multiplication by M.
    ///
    /// # Errors
    /// As [`Self::apply`].
    pub fn apply_resolvent(&self, rhs: MatRef<'_, f64>) -> Result<(Mat<f64>, BatchReport), SolveError> {
        check_rhs(rhs, self.pair.n())?;
        let (out, poles) = self.solve.resolvent(rhs)?;
        Ok((out, self.report(rhs.ncols(), poles)))
    }

    fn report(&self, n_rhs: usize, poles: Vec<PoleReport>) -> BatchReport {
        BatchReport {
            t: self.t,
            n_rhs,
            poles,
        }
    }
}
