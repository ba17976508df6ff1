//! The pivoted complex sparse LU backend ([`super::Backend::DirectLu`]): faer's LU with COLAMD
//! and partial pivoting, one symbolic analysis shared by every pole and every t.

use super::direct::{factor_all, ComplexFactor};
use super::{Pole, PreparedBackend, ShiftedSolve, SolveMethod};
use crate::factor::{lu_symbolic, LuSymbolic, SeqLu};
use crate::{OperatorPair, SolveError};
use faer::sparse::SparseColMatRef;
use faer::{c64, MatMut};
use std::sync::Arc;

/// The symbolic LU analysis of one pattern.
#[derive(Debug)]
pub(crate) struct LuBackend {
    symbolic: LuSymbolic,
}

impl LuBackend {
    pub(crate) fn prepare(pair: &Arc<OperatorPair>) -> Result<Box<dyn PreparedBackend>, SolveError> {
        let symbolic = lu_symbolic(pair.pattern()).map_err(|detail| SolveError::Factorization {
            what: "symbolic LU",
            detail,
        })?;
        Ok(Box::new(Self { symbolic }))
    }
}

impl ComplexFactor for SeqLu {
    fn solve_in_place(&self, rhs: MatMut<'_, c64>) {
        SeqLu::solve_in_place(self, rhs);
    }
}

impl PreparedBackend for LuBackend {
    fn factor(&self, pair: &Arc<OperatorPair>, poles: &[Pole], t: f64) -> Result<Box<dyn ShiftedSolve>, SolveError> {
        factor_all(pair, poles, t, SolveMethod::ComplexLu, |values| {
            SeqLu::new(&self.symbolic, SparseColMatRef::new(pair.pattern(), values))
                .map(|f| Box::new(f) as Box<dyn ComplexFactor>)
                .map_err(|_| ())
        })
    }
}
