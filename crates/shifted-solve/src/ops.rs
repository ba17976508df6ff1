//! The validated pair (L, B) on one shared (union) sparsity pattern.
//!
//! Every shifted matrix `a·L + b·B` (real or complex) is assembled in O(nnz) as values on this
//! pattern, so one symbolic analysis serves every pole and every t (NUMERICS §1).

use crate::SolveError;
use faer::c64;
use faer::sparse::{SparseColMat, SparseColMatRef, SymbolicSparseColMat};

/// L (symmetric positive semidefinite stiffness) and B (SPD mass) on one sorted union pattern
/// that always contains the diagonal.
#[derive(Debug, Clone)]
pub(crate) struct PairOperators {
    pub n: usize,
    pub symbolic: SymbolicSparseColMat<usize>,
    pub stiffness: Vec<f64>,
    pub mass: Vec<f64>,
    pub col_ptr: Vec<usize>,
    pub row_idx: Vec<usize>,
}

impl PairOperators {
    /// Merges the patterns of L and B (plus the diagonal) and validates both matrices:
    /// square, same size, finite, symmetric, diag(L) ≥ 0, diag(B) > 0.
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
        let mut row_idx = Vec::new();
        let mut lv = Vec::new();
        let mut bv = Vec::new();
        // (row, L value, B value) of one column; duplicates are summed.
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
                    row_idx.push(i);
                    lv.push(l);
                    bv.push(b);
                    last = i;
                }
            }
            col_ptr.push(row_idx.len());
        }
        let symbolic = SymbolicSparseColMat::new_checked(n, n, col_ptr.clone(), None, row_idx.clone());
        let ops = Self {
            n,
            symbolic,
            stiffness: lv,
            mass: bv,
            col_ptr,
            row_idx,
        };
        ops.check_symmetric("stiffness", &ops.stiffness)?;
        ops.check_symmetric("mass", &ops.mass)?;
        for j in 0..n {
            let d = ops.diag_position(j);
            if ops.mass[d] <= 0.0 {
                return Err(SolveError::BadDiagonal {
                    which: "mass",
                    index: j,
                    value: ops.mass[d],
                    requirement: "> 0",
                });
            }
            if ops.stiffness[d] < 0.0 {
                return Err(SolveError::BadDiagonal {
                    which: "stiffness",
                    index: j,
                    value: ops.stiffness[d],
                    requirement: ">= 0",
                });
            }
        }
        Ok(ops)
    }

    fn position(&self, i: usize, j: usize) -> Option<usize> {
        let (a, b) = (self.col_ptr[j], self.col_ptr[j + 1]);
        self.row_idx[a..b].binary_search(&i).ok().map(|k| a + k)
    }

    fn diag_position(&self, j: usize) -> usize {
        // The diagonal is always part of the union pattern (inserted in `new`).
        self.position(j, j).unwrap_or(self.col_ptr[j])
    }

    /// Diagonal entries of `a·L + b·B`.
    pub fn diagonal(&self, a: f64, b: f64) -> Vec<f64> {
        (0..self.n)
            .map(|j| {
                let d = self.diag_position(j);
                a * self.stiffness[d] + b * self.mass[d]
            })
            .collect()
    }

    fn check_symmetric(&self, which: &'static str, vals: &[f64]) -> Result<(), SolveError> {
        let scale = vals.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let tol = 1e-10 * scale;
        for j in 0..self.n {
            for k in self.col_ptr[j]..self.col_ptr[j + 1] {
                let i = self.row_idx[k];
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

    /// The real matrix `a·L + b·B` on the shared pattern.
    pub fn real_combination(&self, a: f64, b: f64) -> SparseColMat<usize, f64> {
        let vals = self
            .stiffness
            .iter()
            .zip(&self.mass)
            .map(|(l, m)| a * l + b * m)
            .collect();
        SparseColMat::new(self.symbolic.clone(), vals)
    }

    /// The complex shifted matrix `tL − zB` on the shared pattern (paper Eq. (12)–(13)).
    pub fn shifted(&self, t: f64, z: c64) -> SparseColMat<usize, c64> {
        SparseColMat::new(self.symbolic.clone(), self.shifted_values(t, z))
    }

    /// The values of `tL − zB` on the shared pattern (no copy of the pattern).
    pub fn shifted_values(&self, t: f64, z: c64) -> Vec<c64> {
        self.stiffness
            .iter()
            .zip(&self.mass)
            .map(|(&l, &m)| c64::new(t * l - z.re * m, -z.im * m))
            .collect()
    }

    /// (L x, B x) in one pass over the pattern.
    pub fn stiffness_mass_mul(&self, x: &[f64], lx: &mut [f64], bx: &mut [f64]) {
        lx.iter_mut().for_each(|v| *v = 0.0);
        bx.iter_mut().for_each(|v| *v = 0.0);
        for (j, &xj) in x.iter().enumerate().take(self.n) {
            if xj == 0.0 {
                continue;
            }
            for k in self.col_ptr[j]..self.col_ptr[j + 1] {
                let i = self.row_idx[k];
                lx[i] += self.stiffness[k] * xj;
                bx[i] += self.mass[k] * xj;
            }
        }
    }

    /// B x.
    pub fn mass_mul(&self, x: &[f64], bx: &mut [f64]) {
        bx.iter_mut().for_each(|v| *v = 0.0);
        for (j, &xj) in x.iter().enumerate().take(self.n) {
            for k in self.col_ptr[j]..self.col_ptr[j + 1] {
                bx[self.row_idx[k]] += self.mass[k] * xj;
            }
        }
    }

    /// (a·L + b·B) x for complex a, b and complex x.
    pub fn complex_mul(&self, a: c64, b: c64, x: &[c64], y: &mut [c64]) {
        y.iter_mut().for_each(|v| *v = c64::new(0.0, 0.0));
        for (j, &xj) in x.iter().enumerate().take(self.n) {
            for k in self.col_ptr[j]..self.col_ptr[j + 1] {
                y[self.row_idx[k]] += (a * self.stiffness[k] + b * self.mass[k]) * xj;
            }
        }
    }
}
