//! The complex-symmetric supernodal LDLᵀ backend ([`super::Backend::DirectLdlt`], the default):
//! `P(tL − zM)Pᵀ = LDLᵀ` without pivoting and without conjugation, on the AMD ordering and
//! supernodes of the pair's shared Cholesky analysis (numeric kernel: `crate::ldlt`; why it
//! exists without pivoting: the Hermitian part of i(tL − zM) is qM ≻ 0, docs/NUMERICS.md §3.3d).

use super::direct::{factor_all, ComplexFactor};
use super::{Pole, PreparedBackend, ShiftedSolve, SolveMethod};
use crate::ldlt::{LdltFactor, LdltSymbolic};
use crate::{OperatorPair, SolveError};
use faer::{c64, MatMut};
use std::sync::Arc;

/// The LDLᵀ layout (supernodes, descendant lists, scatter map) of one pattern.
#[derive(Debug)]
pub(crate) struct LdltBackend {
    symbolic: Arc<LdltSymbolic>,
}

impl LdltBackend {
    pub(crate) fn prepare(pair: &Arc<OperatorPair>) -> Result<Box<dyn PreparedBackend>, SolveError> {
        let analysis = pair.cholesky()?.symbolic();
        let symbolic = LdltSymbolic::new(pair.pattern(), analysis).map_err(|detail| SolveError::Factorization {
            what: "symbolic LDLᵀ",
            detail,
        })?;
        Ok(Box::new(Self {
            symbolic: Arc::new(symbolic),
        }))
    }
}

impl ComplexFactor for LdltFactor {
    fn solve_in_place(&self, rhs: MatMut<'_, c64>) {
        LdltFactor::solve_in_place(self, rhs);
    }
}

impl PreparedBackend for LdltBackend {
    fn factor(&self, pair: &Arc<OperatorPair>, poles: &[Pole], t: f64) -> Result<Box<dyn ShiftedSolve>, SolveError> {
        factor_all(pair, poles, t, SolveMethod::ComplexLdlt, |values| {
            LdltFactor::new(&self.symbolic, values)
                .map(|f| Box::new(f) as Box<dyn ComplexFactor>)
                .map_err(|_| ())
        })
    }
}
