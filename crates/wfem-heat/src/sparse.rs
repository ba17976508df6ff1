//! Small sparse helpers on the shared FEM pattern: products, linear combinations and a real
//! sparse Cholesky factorization whose symbolic analysis is reused across shifts.

use crate::HeatError;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, LltRef, SymbolicCholesky, SymmetricOrdering,
};
use faer::sparse::SparseColMat;
use faer::{get_global_parallelism, Conj, Mat, MatMut, MatRef, Par, Side};
use rayon::prelude::*;
use std::sync::Arc;

/// `A x` for a symmetric CSC matrix, computed row-wise (column j of A is row j) in parallel.
pub(crate) fn spmv_sym(a: &SparseColMat<usize, f64>, x: &[f64]) -> Vec<f64> {
    let sym = a.symbolic();
    let rows = sym.row_idx();
    let val = a.val();
    (0..sym.ncols())
        .into_par_iter()
        .with_min_len(4096)
        .map(|j| sym.col_range(j).map(|p| val[p] * x[rows[p]]).sum())
        .collect()
}

/// `A x` for a symmetric CSC matrix, sequentially (for use inside parallel loops).
pub(crate) fn spmv_seq(a: &SparseColMat<usize, f64>, x: &[f64]) -> Vec<f64> {
    let sym = a.symbolic();
    let rows = sym.row_idx();
    let val = a.val();
    (0..sym.ncols())
        .map(|j| sym.col_range(j).map(|p| val[p] * x[rows[p]]).sum())
        .collect()
}

/// `A X` column by column for a symmetric CSC matrix.
pub(crate) fn spmm_sym(a: &SparseColMat<usize, f64>, x: MatRef<'_, f64>) -> Mat<f64> {
    let n = x.nrows();
    let mut out = Mat::<f64>::zeros(n, x.ncols());
    let sym = a.symbolic();
    let rows = sym.row_idx();
    let val = a.val();
    for c in 0..x.ncols() {
        let xc = x.col(c);
        let mut oc = out.as_mut().col_mut(c);
        for j in 0..n {
            let mut s = 0.0;
            for p in sym.col_range(j) {
                s += val[p] * xc[rows[p]];
            }
            oc[j] = s;
        }
    }
    out
}

/// `a·A + b·C` for two matrices on the same pattern (checked by the caller).
pub(crate) fn combine(
    a: f64,
    m1: &SparseColMat<usize, f64>,
    b: f64,
    m2: &SparseColMat<usize, f64>,
) -> SparseColMat<usize, f64> {
    let val: Vec<f64> = m1.val().iter().zip(m2.val()).map(|(x, y)| a * x + b * y).collect();
    SparseColMat::new(m1.symbolic().to_owned().expect("clone of a valid pattern"), val)
}

/// True if both matrices have the same dimensions and the same stored pattern.
pub(crate) fn same_pattern(a: &SparseColMat<usize, f64>, b: &SparseColMat<usize, f64>) -> bool {
    a.nrows() == b.nrows()
        && a.ncols() == b.ncols()
        && a.symbolic().col_ptr() == b.symbolic().col_ptr()
        && a.symbolic().row_idx() == b.symbolic().row_idx()
}

/// The symbolic Cholesky analysis (AMD ordering, elimination tree, supernodes) of the
/// shared pattern, computed once and reused for every shift.
#[derive(Clone, Debug)]
pub(crate) struct CholeskyPattern {
    symbolic: Arc<SymbolicCholesky<usize>>,
}

impl CholeskyPattern {
    pub(crate) fn new(pattern: &SparseColMat<usize, f64>) -> Result<Self, HeatError> {
        let symbolic = factorize_symbolic_cholesky(
            pattern.symbolic(),
            Side::Lower,
            SymmetricOrdering::Amd,
            CholeskySymbolicParams::default(),
        )
        .map_err(|e| HeatError::InconsistentOperators {
            reason: format!("symbolic Cholesky analysis failed: {e:?}"),
        })?;
        Ok(Self {
            symbolic: Arc::new(symbolic),
        })
    }

    /// Numeric factorization of an SPD matrix on the analysed pattern (parallel).
    pub(crate) fn factor(
        &self,
        a: &SparseColMat<usize, f64>,
        what: impl FnOnce() -> String,
    ) -> Result<SpdFactor, HeatError> {
        let sym = &self.symbolic;
        let mut values = vec![0.0f64; sym.len_val()];
        let par = get_global_parallelism();
        let mut buf = MemBuffer::new(sym.factorize_numeric_llt_scratch::<f64>(par, Default::default()));
        sym.factorize_numeric_llt::<f64>(
            &mut values,
            a.as_ref(),
            Side::Lower,
            LltRegularization::default(),
            par,
            MemStack::new(&mut buf),
            Default::default(),
        )
        .map_err(|_| HeatError::NotPositiveDefinite { matrix: what() })?;
        Ok(SpdFactor {
            symbolic: self.symbolic.clone(),
            values,
        })
    }
}

/// A numeric sparse Cholesky factor `A = PᵀRRᵀP`.
#[derive(Debug)]
pub(crate) struct SpdFactor {
    symbolic: Arc<SymbolicCholesky<usize>>,
    values: Vec<f64>,
}

impl SpdFactor {
    /// Overwrites `rhs` with `A⁻¹ rhs`. Triangular solves are memory bound, so they run
    /// sequentially: callers parallelise over right-hand sides instead.
    pub(crate) fn solve_in_place(&self, rhs: MatMut<'_, f64>) {
        let par = Par::Seq;
        let mut buf = MemBuffer::new(self.symbolic.solve_in_place_scratch::<f64>(rhs.ncols(), par));
        LltRef::new(&self.symbolic, &self.values).solve_in_place_with_conj(Conj::No, rhs, par, MemStack::new(&mut buf));
    }

    /// `A⁻¹ b` for a vector.
    pub(crate) fn solve_vec(&self, b: &[f64]) -> Vec<f64> {
        let mut m = Mat::<f64>::from_fn(b.len(), 1, |i, _| b[i]);
        self.solve_in_place(m.as_mut());
        (0..b.len()).map(|i| m[(i, 0)]).collect()
    }
}
