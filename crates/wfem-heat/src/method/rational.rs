//! [`super::Method::Rational`], the paper's generalized Chebyshev method (Eq. (11)–(13)):
//! `K_t F ≈ c0 F + 2 Re Σ_j c_j (tL − z_j M)⁻¹ M F` with the poles of the best rational
//! approximation of e^{−x} on [0, ∞), solved by a [`shifted_solve::backend::Backend`].

use super::PreparedMethod;
use crate::{HeatError, Operators};
use faer::{Mat, MatRef};
use shifted_solve::backend::Backend;
use shifted_solve::poles::RationalApprox;
use shifted_solve::{RationalFactors, ShiftedSolver};
use std::sync::{Arc, Mutex};

/// The backend prepared on the context's pair, the approximant, and the factors of the last t.
#[derive(Debug)]
pub(crate) struct Rational {
    solver: ShiftedSolver,
    approx: &'static RationalApprox,
    cache: Mutex<Option<(f64, Arc<RationalFactors>)>>,
}

impl Rational {
    pub(crate) fn prepare(
        ops: &Operators,
        degree: usize,
        backend: Backend,
    ) -> Result<Box<dyn PreparedMethod>, HeatError> {
        let approx = RationalApprox::cram(degree)?;
        let solver = ShiftedSolver::with_pair(ops.pair().clone(), backend)?;
        Ok(Box::new(Self {
            solver,
            approx,
            cache: Mutex::new(None),
        }))
    }

    /// The factors of every pole at time t, reused when the previous call had the same t.
    fn factors(&self, t: f64) -> Result<Arc<RationalFactors>, HeatError> {
        let mut cache = self.cache.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
        if let Some((cached_t, factors)) = cache.as_ref() {
            if *cached_t == t {
                return Ok(factors.clone());
            }
        }
        let factors = Arc::new(self.solver.factor(self.approx, t)?);
        *cache = Some((t, factors.clone()));
        Ok(factors)
    }
}

impl PreparedMethod for Rational {
    fn apply(&self, _ops: &Operators, f: MatRef<'_, f64>, t: f64) -> Result<Mat<f64>, HeatError> {
        Ok(self.factors(t)?.apply(f)?.0)
    }

    /// `K̃_t G ≈ c0 M⁻¹G + 2 Re Σ_j c_j (tL − z_j M)⁻¹ G` (docs/NUMERICS.md §1): the resolvent sum needs
    /// no solve with M; the tiny `c0 M⁻¹G` term (|c0| = E_n) is kept, through the context's
    /// Cholesky of M, so the result matches `K_t M⁻¹ G` to the method's accuracy.
    fn apply_kernel_matrix(&self, ops: &Operators, g: MatRef<'_, f64>, t: f64) -> Result<Mat<f64>, HeatError> {
        let (mut y, _) = self.factors(t)?.apply_resolvent(g)?;
        if self.approx.c0 != 0.0 {
            let mut minv = g.to_owned();
            ops.mass_factor()?.solve_in_place(minv.as_mut());
            y += faer::Scale(self.approx.c0) * &minv;
        }
        Ok(y)
    }
}
