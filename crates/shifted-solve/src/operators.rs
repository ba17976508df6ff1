//! The validated operator pair (L, M) on one shared sparsity pattern: the one context every
//! solver, backend and method of the workspace works on.
//!
//! L is the stiffness, symmetric positive **semi**definite with a non-negative diagonal
//! (wfem's sign convention; libigl's `cotmatrix` is −L); M is the mass, symmetric positive
//! definite (the consistent B, a lumped diagonal D, or I). Both are stored as values on the
//! sorted union of their patterns plus the diagonal, so every combination `a·L + b·M` (real or
//! complex) is assembled in O(nnz) as values on this pattern and one symbolic analysis serves
//! every pole, every t and every shift (docs/NUMERICS.md §1).
//!
//! Validation happens once, in [`OperatorPair::new`]: square, equal sizes, non-empty, finite,
//! symmetric (1e−10 relative), diag(M) > 0, diag(L) ≥ 0 — all O(nnz). The definiteness checks
//! (two sparse Cholesky factorizations) are needed only by the methods whose mathematics
//! assumes them (the rational approximation is valid on the spectrum [0, ∞)); they run on
//! first use of [`OperatorPair::check_definite`] and their verdict is kept.

use crate::factor::CholeskyPattern;
use crate::SolveError;
use faer::c64;
use faer::sparse::{SparseColMat, SparseColMatRef, SymbolicSparseColMat, SymbolicSparseColMatRef};
use faer::Par;
use std::sync::OnceLock;

/// Relative shift δ of the semidefiniteness test of L: `L + δ·diag(L)` must be positive definite.
const SEMIDEFINITE_DELTA: f64 = 1e-10;

/// L (stiffness, symmetric positive semidefinite) and M (mass, symmetric positive definite)
/// on one shared pattern, validated once, with the shared symbolic Cholesky analysis.
#[derive(Debug)]
pub struct OperatorPair {
    n: usize,
    symbolic: SymbolicSparseColMat<usize>,
    stiffness: Vec<f64>,
    mass: Vec<f64>,
    /// Position of the diagonal entry of every column.
    diag_pos: Vec<usize>,
    cholesky: OnceLock<Result<CholeskyPattern, SolveError>>,
    definite: OnceLock<Result<(), SolveError>>,
}

impl OperatorPair {
    /// Merges the patterns of L and M (plus the diagonal) and validates both matrices:
    /// square, same size, non-empty, finite, symmetric (1e−10 relative to the largest entry),
    /// diag(M) > 0, diag(L) ≥ 0. O(nnz).
    ///
    /// # Errors
    /// [`SolveError::NotSquare`], [`SolveError::DimensionMismatch`], [`SolveError::Empty`],
    /// [`SolveError::NonFinite`], [`SolveError::NotSymmetric`], [`SolveError::BadDiagonal`].
    pub fn new(
        stiffness: SparseColMatRef<'_, usize, f64>,
        mass: SparseColMatRef<'_, usize, f64>,
    ) -> Result<Self, SolveError> {
        for (which, m) in [("stiffness", &stiffness), ("mass", &mass)] {
            if m.nrows() != m.ncols() {
                return Err(SolveError::NotSquare {
                    which,
                    nrows: m.nrows(),
                    ncols: m.ncols(),
                });
            }
        }
        let n = stiffness.nrows();
        if mass.nrows() != n {
            return Err(SolveError::DimensionMismatch {
                what: "mass matrix size vs stiffness matrix size",
                expected: n,
                got: mass.nrows(),
            });
        }
        if n == 0 {
            return Err(SolveError::Empty);
        }
        let mut col_ptr = Vec::with_capacity(n + 1);
        col_ptr.push(0usize);
        let mut row_idx = Vec::with_capacity(stiffness.compute_nnz().max(mass.compute_nnz()) + n);
        let mut lv = Vec::with_capacity(row_idx.capacity());
        let mut bv = Vec::with_capacity(row_idx.capacity());
        let mut diag_pos = Vec::with_capacity(n);
        // (row, L value, M value) of one column; duplicates are summed.
        let mut col: Vec<(usize, f64, f64)> = Vec::new();
        for j in 0..n {
            col.clear();
            col.push((j, 0.0, 0.0));
            for (which, m, slot) in [("stiffness", &stiffness, 0usize), ("mass", &mass, 1)] {
                let rows = m.symbolic().row_idx_of_col_raw(j);
                let vals = m.val_of_col(j);
                for (&i, &v) in rows.iter().zip(vals) {
                    if !v.is_finite() {
                        return Err(SolveError::NonFinite {
                            what: which,
                            row: i,
                            col: j,
                            value: v,
                        });
                    }
                    col.push(if slot == 0 { (i, v, 0.0) } else { (i, 0.0, v) });
                }
            }
            col.sort_unstable_by_key(|e| e.0);
            let mut last = usize::MAX;
            for &(i, l, b) in &col {
                if i == last {
                    let k = lv.len() - 1;
                    lv[k] += l;
                    bv[k] += b;
                } else {
                    if i == j {
                        diag_pos.push(row_idx.len());
                    }
                    row_idx.push(i);
                    lv.push(l);
                    bv.push(b);
                    last = i;
                }
            }
            col_ptr.push(row_idx.len());
        }
        let symbolic = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
        let pair = Self {
            n,
            symbolic,
            stiffness: lv,
            mass: bv,
            diag_pos,
            cholesky: OnceLock::new(),
            definite: OnceLock::new(),
        };
        pair.check_symmetric("stiffness", &pair.stiffness)?;
        pair.check_symmetric("mass", &pair.mass)?;
        for j in 0..n {
            let d = pair.diag_pos[j];
            if pair.mass[d] <= 0.0 {
                return Err(SolveError::BadDiagonal {
                    which: "mass",
                    index: j,
                    value: pair.mass[d],
                    requirement: "> 0",
                });
            }
            if pair.stiffness[d] < 0.0 {
                return Err(SolveError::BadDiagonal {
                    which: "stiffness",
                    index: j,
                    value: pair.stiffness[d],
                    requirement: ">= 0",
                });
            }
        }
        Ok(pair)
    }

    /// Matrix size n.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Number of stored entries of the shared pattern.
    pub fn nnz(&self) -> usize {
        self.stiffness.len()
    }

    /// The shared pattern (both triangles, sorted columns, diagonal included).
    pub fn pattern(&self) -> SymbolicSparseColMatRef<'_, usize> {
        self.symbolic.as_ref()
    }

    /// L on the shared pattern.
    pub fn stiffness(&self) -> SparseColMatRef<'_, usize, f64> {
        SparseColMatRef::new(self.symbolic.as_ref(), &self.stiffness)
    }

    /// M on the shared pattern.
    pub fn mass(&self) -> SparseColMatRef<'_, usize, f64> {
        SparseColMatRef::new(self.symbolic.as_ref(), &self.mass)
    }

    /// The values of L on the shared pattern.
    pub fn stiffness_values(&self) -> &[f64] {
        &self.stiffness
    }

    /// The values of M on the shared pattern.
    pub fn mass_values(&self) -> &[f64] {
        &self.mass
    }

    fn position(&self, i: usize, j: usize) -> Option<usize> {
        let (a, b) = (self.symbolic.col_ptr()[j], self.symbolic.col_ptr()[j + 1]);
        self.symbolic.row_idx()[a..b].binary_search(&i).ok().map(|k| a + k)
    }

    /// Diagonal entries of `a·L + b·M`.
    pub fn diagonal(&self, a: f64, b: f64) -> Vec<f64> {
        self.diag_pos
            .iter()
            .map(|&d| a * self.stiffness[d] + b * self.mass[d])
            .collect()
    }

    /// Row sums `M·1` (the vertex areas when M is a FEM mass matrix).
    pub fn mass_row_sums(&self) -> Vec<f64> {
        // M is symmetric: column sums are row sums, and columns are contiguous.
        let ptr = self.symbolic.col_ptr();
        (0..self.n)
            .map(|j| self.mass[ptr[j]..ptr[j + 1]].iter().sum())
            .collect()
    }

    fn check_symmetric(&self, which: &'static str, vals: &[f64]) -> Result<(), SolveError> {
        let scale = vals.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let tol = 1e-10 * scale;
        let (ptr, rows) = (self.symbolic.col_ptr(), self.symbolic.row_idx());
        for j in 0..self.n {
            for k in ptr[j]..ptr[j + 1] {
                let i = rows[k];
                if i <= j {
                    continue;
                }
                let transposed = self.position(j, i).map_or(0.0, |p| vals[p]);
                if (vals[k] - transposed).abs() > tol {
                    return Err(SolveError::NotSymmetric {
                        which,
                        row: i,
                        col: j,
                        value: vals[k],
                        transposed,
                    });
                }
            }
        }
        Ok(())
    }

    /// The values of `a·L + b·M` on the shared pattern.
    pub fn combination_values(&self, a: f64, b: f64) -> Vec<f64> {
        self.stiffness
            .iter()
            .zip(&self.mass)
            .map(|(l, m)| a * l + b * m)
            .collect()
    }

    /// The real matrix `a·L + b·M` on the shared pattern.
    pub fn combination(&self, a: f64, b: f64) -> SparseColMat<usize, f64> {
        SparseColMat::new(self.symbolic.clone(), self.combination_values(a, b))
    }

    /// The complex shifted matrix `tL − zM` on the shared pattern (paper Eq. (12)–(13)).
    pub fn shifted(&self, t: f64, z: c64) -> SparseColMat<usize, c64> {
        SparseColMat::new(self.symbolic.clone(), self.shifted_values(t, z))
    }

    /// The values of `tL − zM` on the shared pattern (no copy of the pattern).
    pub fn shifted_values(&self, t: f64, z: c64) -> Vec<c64> {
        self.stiffness
            .iter()
            .zip(&self.mass)
            .map(|(&l, &m)| c64::new(t * l - z.re * m, -z.im * m))
            .collect()
    }

    /// (L x, M x) in one sequential pass over the pattern.
    pub fn stiffness_mass_mul(&self, x: &[f64], lx: &mut [f64], mx: &mut [f64]) {
        lx.iter_mut().for_each(|v| *v = 0.0);
        mx.iter_mut().for_each(|v| *v = 0.0);
        let (ptr, rows) = (self.symbolic.col_ptr(), self.symbolic.row_idx());
        for (j, &xj) in x.iter().enumerate().take(self.n) {
            if xj == 0.0 {
                continue;
            }
            let range = ptr[j]..ptr[j + 1];
            for ((&i, &l), &m) in rows[range.clone()]
                .iter()
                .zip(&self.stiffness[range.clone()])
                .zip(&self.mass[range])
            {
                lx[i] += l * xj;
                mx[i] += m * xj;
            }
        }
    }

    /// `y = A x` for a symmetric matrix given by its values on the shared pattern
    /// (`(Ax)_j = Σ_k A_kj x_k` over the contiguous column j).
    fn symmetric_mul(&self, values: &[f64], x: &[f64], y: &mut [f64]) {
        let ptr = self.symbolic.col_ptr();
        let rows = self.symbolic.row_idx();
        for (j, yj) in y.iter_mut().enumerate().take(self.n) {
            let (a, b) = (ptr[j], ptr[j + 1]);
            *yj = rows[a..b].iter().zip(&values[a..b]).map(|(&i, v)| v * x[i]).sum();
        }
    }

    /// [`Self::symmetric_mul`] with the rows split over the rayon pool.
    fn symmetric_mul_par(&self, values: &[f64], x: &[f64]) -> Vec<f64> {
        use rayon::prelude::*;
        let ptr = self.symbolic.col_ptr();
        let rows = self.symbolic.row_idx();
        (0..self.n)
            .into_par_iter()
            .with_min_len(4096)
            .map(|j| {
                let (a, b) = (ptr[j], ptr[j + 1]);
                rows[a..b].iter().zip(&values[a..b]).map(|(&i, v)| v * x[i]).sum()
            })
            .collect()
    }

    /// `y = (a·L + b·M) x`, sequentially; for use inside parallel loops.
    pub fn combination_mul(&self, a: f64, b: f64, x: &[f64], y: &mut [f64]) {
        match (a, b) {
            (0.0, _) => {
                self.symmetric_mul(&self.mass, x, y);
                y.iter_mut().for_each(|v| *v *= b);
            }
            (_, 0.0) => {
                self.symmetric_mul(&self.stiffness, x, y);
                y.iter_mut().for_each(|v| *v *= a);
            }
            _ => self.symmetric_mul(&self.combination_values(a, b), x, y),
        }
    }

    /// `M x`, sequentially; for use inside parallel loops.
    pub fn mass_mul(&self, x: &[f64], mx: &mut [f64]) {
        self.symmetric_mul(&self.mass, x, mx);
    }

    /// `M x` with the rows split over the rayon pool (one large product at a time).
    pub fn mass_mul_par(&self, x: &[f64]) -> Vec<f64> {
        self.symmetric_mul_par(&self.mass, x)
    }

    /// `L x` with the rows split over the rayon pool.
    pub fn stiffness_mul_par(&self, x: &[f64]) -> Vec<f64> {
        self.symmetric_mul_par(&self.stiffness, x)
    }

    /// `(a·L + b·M) x` with the rows split over the rayon pool.
    pub fn combination_mul_par(&self, a: f64, b: f64, x: &[f64]) -> Vec<f64> {
        match (a, b) {
            (0.0, _) => self.mass_mul_par(x).into_iter().map(|v| b * v).collect(),
            (_, 0.0) => self.stiffness_mul_par(x).into_iter().map(|v| a * v).collect(),
            _ => self.symmetric_mul_par(&self.combination_values(a, b), x),
        }
    }

    /// `(a·L + b·M) x` for complex a, b and complex x.
    pub fn complex_mul(&self, a: c64, b: c64, x: &[c64], y: &mut [c64]) {
        y.iter_mut().for_each(|v| *v = c64::new(0.0, 0.0));
        let (ptr, rows) = (self.symbolic.col_ptr(), self.symbolic.row_idx());
        for (j, &xj) in x.iter().enumerate().take(self.n) {
            let range = ptr[j]..ptr[j + 1];
            for ((&i, &l), &m) in rows[range.clone()]
                .iter()
                .zip(&self.stiffness[range.clone()])
                .zip(&self.mass[range])
            {
                y[i] += (a * l + b * m) * xj;
            }
        }
    }

    /// The symbolic Cholesky analysis of the shared pattern (AMD ordering, forced supernodal,
    /// with its tree-parallel solve plan), computed on first use and shared by every real and
    /// complex-symmetric factorization of every shift.
    ///
    /// # Errors
    /// [`SolveError::Factorization`] if faer's symbolic analysis fails.
    pub fn cholesky(&self) -> Result<&CholeskyPattern, SolveError> {
        self.cholesky
            .get_or_init(|| CholeskyPattern::supernodal(self.symbolic.as_ref()))
            .as_ref()
            .map_err(Clone::clone)
    }

    /// Factors the SPD matrix `a·L + b·M` with faer's global parallelism (one large
    /// factorization at a time).
    ///
    /// # Errors
    /// [`SolveError::Factorization`] for the analysis, or `not_definite()` when the matrix is
    /// not numerically positive definite.
    pub fn factor_spd(
        &self,
        a: f64,
        b: f64,
        not_definite: impl FnOnce() -> SolveError,
    ) -> Result<crate::SpdFactor, SolveError> {
        self.factor_spd_with(a, b, faer::get_global_parallelism(), not_definite)
    }

    /// [`Self::factor_spd`] with the given faer parallelism (`Par::Seq` inside parallel loops).
    ///
    /// # Errors
    /// As [`Self::factor_spd`].
    pub fn factor_spd_with(
        &self,
        a: f64,
        b: f64,
        par: Par,
        not_definite: impl FnOnce() -> SolveError,
    ) -> Result<crate::SpdFactor, SolveError> {
        let pattern = self.cholesky()?;
        let matrix = self.combination(a, b);
        pattern.factor(matrix.as_ref(), par).map_err(|_| not_definite())
    }

    /// Checks, once, what the rational approximation of e^{−x} on [0, ∞) assumes of the pair:
    /// M positive definite (Cholesky of M) and L positive semidefinite (Cholesky of
    /// `L + δ·diag(L)` with δ = 1e−10, which fails when L has a direction of negative
    /// curvature below −δ·diag(L), e.g. when −L was passed). The shift is relative to L's own
    /// diagonal, so the test does not depend on the scale of M nor on the size of a connected
    /// component (a tiny component has a tiny M and an O(1) L). The verdict is kept.
    ///
    /// # Errors
    /// [`SolveError::MassNotPositiveDefinite`], [`SolveError::StiffnessIndefinite`],
    /// [`SolveError::Factorization`].
    pub fn check_definite(&self) -> Result<(), SolveError> {
        self.definite
            .get_or_init(|| {
                let pattern = self.cholesky()?;
                // A row with a zero L-diagonal (an isolated vertex) gets the shift of an average
                // row, scaled by its mass, so that it does not read as a failed test.
                let (tr_l, tr_m) = self
                    .diag_pos
                    .iter()
                    .fold((0.0, 0.0), |(l, m), &d| (l + self.stiffness[d], m + self.mass[d]));
                let ratio = if tr_m > 0.0 { tr_l / tr_m } else { 0.0 };
                let mut reg = self.stiffness.clone();
                for &d in &self.diag_pos {
                    let base = if reg[d] > 0.0 { reg[d] } else { ratio * self.mass[d] };
                    reg[d] += SEMIDEFINITE_DELTA * base;
                }
                // The two checks are independent factorizations: run them side by side.
                let (mass_check, stiffness_check) = rayon::join(
                    || {
                        pattern
                            .factor(self.mass(), Par::Seq)
                            .map(|_| ())
                            .map_err(|e| SolveError::MassNotPositiveDefinite { detail: e.to_string() })
                    },
                    || {
                        pattern
                            .factor(SparseColMatRef::new(self.symbolic.as_ref(), &reg), Par::Seq)
                            .map(|_| ())
                            .map_err(|_| SolveError::StiffnessIndefinite {
                                delta: SEMIDEFINITE_DELTA,
                            })
                    },
                );
                mass_check?;
                stiffness_check
            })
            .clone()
    }
}
