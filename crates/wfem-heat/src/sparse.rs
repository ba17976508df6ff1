//! Small sparse helpers on the shared FEM pattern: products, linear combinations and a real
//! sparse Cholesky factorization whose symbolic analysis is reused across shifts.

use crate::HeatError;
use faer::sparse::SparseColMat;
use faer::{get_global_parallelism, Mat, MatRef};
use rayon::prelude::*;

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
#[allow(clippy::expect_used)]
pub(crate) fn combine(
    a: f64,
    m1: &SparseColMat<usize, f64>,
    b: f64,
    m2: &SparseColMat<usize, f64>,
) -> SparseColMat<usize, f64> {
    let val: Vec<f64> = m1.val().iter().zip(m2.val()).map(|(x, y)| a * x + b * y).collect();
    // invariant: cloning an existing valid pattern can only fail to allocate.
    SparseColMat::new(m1.symbolic().to_owned().expect("clone of a valid pattern"), val)
}

/// True if both matrices have the same dimensions and the same stored pattern.
pub(crate) fn same_pattern(a: &SparseColMat<usize, f64>, b: &SparseColMat<usize, f64>) -> bool {
    a.nrows() == b.nrows()
        && a.ncols() == b.ncols()
        && a.symbolic().col_ptr() == b.symbolic().col_ptr()
        && a.symbolic().row_idx() == b.symbolic().row_idx()
}

/// The symbolic Cholesky analysis of the shared pattern, computed once and reused for every
/// shift; a thin wrapper over [`shifted_solve::CholeskyPattern`] that names the failing matrix
/// in a [`HeatError`].
#[derive(Clone, Debug)]
pub(crate) struct CholeskyPattern {
    inner: shifted_solve::CholeskyPattern,
}

/// A numeric sparse Cholesky factor `A = PᵀRRᵀP` (from shifted-solve).
pub(crate) use shifted_solve::SpdFactor;

impl CholeskyPattern {
    pub(crate) fn new(pattern: &SparseColMat<usize, f64>) -> Result<Self, HeatError> {
        let inner =
            shifted_solve::CholeskyPattern::new(pattern.symbolic()).map_err(|e| HeatError::InconsistentOperators {
                reason: format!("symbolic Cholesky analysis failed: {e}"),
            })?;
        Ok(Self { inner })
    }

    /// Numeric factorization of an SPD matrix on the analysed pattern (faer's global
    /// parallelism: one large factorization at a time is where it pays).
    pub(crate) fn factor(
        &self,
        a: &SparseColMat<usize, f64>,
        what: impl FnOnce() -> String,
    ) -> Result<SpdFactor, HeatError> {
        self.inner
            .factor(a.as_ref(), get_global_parallelism())
            .map_err(|_| HeatError::NotPositiveDefinite { matrix: what() })
    }
}
