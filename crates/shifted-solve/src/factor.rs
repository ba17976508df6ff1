//! Thin wrappers over faer's low-level sparse Cholesky and LU that run *sequentially* inside
//! one pole: the crate parallelises across poles and right-hand sides with rayon instead.
//! (Measured at n = 10,242 on a loaded 2-core box: a 2-RHS Cholesky solve takes 5.1 ms with
//! `Par::Seq` and 26.7 ms with faer's default rayon parallelism, which the high-level
//! `Llt`/`Lu` types always use.)

use std::sync::Arc;

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, LltRef, SymbolicCholesky, SymmetricOrdering,
};
use faer::sparse::linalg::lu::{factorize_symbolic_lu, LuRef, NumericLu, SymbolicLu};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{c64, Conj, MatMut, Par, Side};

/// Shared symbolic Cholesky analysis (AMD ordering) of the pattern of L and B.
pub(crate) type CholeskySymbolic = Arc<SymbolicCholesky<usize>>;
/// Shared symbolic LU analysis (COLAMD) of the pattern of L and B.
pub(crate) type LuSymbolic = Arc<SymbolicLu<usize>>;

pub(crate) fn cholesky_symbolic(pattern: SymbolicSparseColMatRef<'_, usize>) -> Result<CholeskySymbolic, String> {
    factorize_symbolic_cholesky(
        pattern,
        Side::Lower,
        SymmetricOrdering::Amd,
        CholeskySymbolicParams::default(),
    )
    .map(Arc::new)
    .map_err(|e| format!("{e:?}"))
}

pub(crate) fn lu_symbolic(pattern: SymbolicSparseColMatRef<'_, usize>) -> Result<LuSymbolic, String> {
    factorize_symbolic_lu(pattern, Default::default())
        .map(Arc::new)
        .map_err(|e| format!("{e:?}"))
}

/// Real sparse Cholesky factor L Lᵀ of an SPD matrix.
#[derive(Debug)]
pub(crate) struct SeqLlt {
    symbolic: CholeskySymbolic,
    values: Vec<f64>,
}

impl SeqLlt {
    /// Fails (with faer's message) when the matrix is not numerically positive definite.
    pub fn new(symbolic: &CholeskySymbolic, a: SparseColMatRef<'_, usize, f64>) -> Result<Self, String> {
        let mut values = vec![0.0; symbolic.len_val()];
        let par = Par::Seq;
        let mut buf = MemBuffer::try_new(symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default()))
            .map_err(|e| format!("{e:?}"))?;
        symbolic
            .factorize_numeric_llt(
                &mut values,
                a,
                Side::Lower,
                Default::default(),
                par,
                MemStack::new(&mut buf),
                Default::default(),
            )
            .map_err(|e| format!("{e:?}"))?;
        Ok(Self {
            symbolic: symbolic.clone(),
            values,
        })
    }

    pub fn solve_in_place(&self, rhs: MatMut<'_, f64>) {
        let par = Par::Seq;
        let mut buf = MemBuffer::new(self.symbolic.solve_in_place_scratch::<f64>(rhs.ncols(), par));
        LltRef::new(&self.symbolic, &self.values).solve_in_place_with_conj(Conj::No, rhs, par, MemStack::new(&mut buf));
    }
}

/// Complex sparse LU factor (partial pivoting) of one tL − zB.
#[derive(Debug)]
pub(crate) struct SeqLu {
    symbolic: LuSymbolic,
    numeric: NumericLu<usize, c64>,
}

impl SeqLu {
    pub fn new(symbolic: &LuSymbolic, a: SparseColMatRef<'_, usize, c64>) -> Result<Self, String> {
        let par = Par::Seq;
        let mut numeric = NumericLu::new();
        let mut buf = MemBuffer::try_new(symbolic.factorize_numeric_lu_scratch::<c64>(par, Default::default()))
            .map_err(|e| format!("{e:?}"))?;
        symbolic
            .factorize_numeric_lu(&mut numeric, a, par, MemStack::new(&mut buf), Default::default())
            .map_err(|e| format!("{e:?}"))?;
        Ok(Self {
            symbolic: symbolic.clone(),
            numeric,
        })
    }

    pub fn solve_in_place(&self, rhs: MatMut<'_, c64>) {
        let par = Par::Seq;
        let mut buf = MemBuffer::new(self.symbolic.solve_in_place_scratch::<c64>(rhs.ncols(), par));
        LuRef::new_unchecked(&self.symbolic, &self.numeric).solve_in_place_with_conj(
            Conj::No,
            rhs,
            par,
            MemStack::new(&mut buf),
        );
    }
}
