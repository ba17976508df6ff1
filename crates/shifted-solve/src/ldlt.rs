//! Complex-symmetric supernodal LDLᵀ of the shifted matrices A = tL − zB (docs/NUMERICS.md §3.1, §3.3d).
//!
//! A = tL − zB is complex *symmetric* (Aᵀ = A, not Hermitian). With z = p + iq, q > 0, the
//! Hermitian part of i·A is qB, which is positive definite, so every leading principal
//! submatrix of A (in any symmetric ordering) is nonsingular and the factorization
//!
//! ```text
//! P A Pᵀ = L D Lᵀ      (L unit lower triangular, D complex diagonal, no conjugation)
//! ```
//!
//! exists without pivoting. Compared with the pivoted complex LU it stores half the factor and
//! does half the arithmetic, and it reuses the real Cholesky's AMD ordering and supernodal
//! structure (faer's symbolic analysis of the pattern of L and B, computed once per pattern).
//! The numeric phase is our own: faer's supernodal LDLᴴ conjugates and keeps D real, which is
//! wrong for a complex-symmetric matrix.
//!
//! Left-looking supernodal algorithm: for each supernode s (columns s₀..s₁ and the off-diagonal
//! row pattern R_s), gather A's columns, subtract the updates `L_{·,d} D_d L_{mid,d}ᵀ` of every
//! descendant d whose pattern meets s₀..s₁ (one dense GEMM each), factor the diagonal block
//! densely (recursive blocked LDLᵀ) and compute the panel `L_{R_s} = A_{R_s} L_sᵀ⁻¹ D_s⁻¹`.
//! Stability is not guaranteed a priori (the skew/Hermitian ratio is about tλ_max/q); every
//! solve therefore reports its true residual, and the tests compare it with the pivoted LU.

use faer::linalg::matmul::matmul;
use faer::linalg::matmul::triangular::{self, BlockStructure};
use faer::linalg::triangular_solve::{solve_unit_lower_triangular_in_place, solve_unit_upper_triangular_in_place};
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::sparse::linalg::cholesky::{SymbolicCholesky, SymbolicCholeskyRaw};
use faer::sparse::SymbolicSparseColMatRef;
use faer::{c64, Accum, Mat, MatMut, MatRef, Par};

mod selinv;

const ZERO: c64 = c64 { re: 0.0, im: 0.0 };
const ONE: c64 = c64 { re: 1.0, im: 0.0 };

/// Below this size the dense diagonal-block factorization is unblocked.
const DENSE_BLOCK: usize = 32;

/// Supernodal structure of the factor, shared by every pole and every t of one pattern.
#[derive(Debug)]
pub(crate) struct LdltSymbolic {
    n: usize,
    /// New index → original index.
    perm: Vec<usize>,
    /// Supernode s holds the columns `begin[s]..begin[s + 1]` (permuted numbering).
    begin: Vec<usize>,
    /// Off-diagonal row pattern of supernode s: `rows[row_ptr[s]..row_ptr[s + 1]]` (sorted).
    row_ptr: Vec<usize>,
    rows: Vec<usize>,
    /// Values of supernode s: column-major (nc + |pattern|) × nc block at `val_ptr[s]`.
    val_ptr: Vec<usize>,
    /// Descendants of s: the supernodes d < s whose pattern meets s's columns, ascending.
    desc_ptr: Vec<usize>,
    desc: Vec<usize>,
    /// `values[dst[k]] += a[src[k]]` gathers A (on the shared pattern) into the factor storage.
    scatter_src: Vec<usize>,
    scatter_dst: Vec<usize>,
}

/// Numeric factor of one shifted matrix.
#[derive(Debug)]
pub(crate) struct LdltFactor {
    symbolic: std::sync::Arc<LdltSymbolic>,
    values: Vec<c64>,
}

impl LdltSymbolic {
    /// Builds the factor layout from a pattern given with both triangles (sorted columns) and
    /// its supernodal analysis ([`crate::CholeskyPattern::supernodal`]).
    pub fn new(pattern: SymbolicSparseColMatRef<'_, usize>, sym: &SymbolicCholesky<usize>) -> Result<Self, String> {
        let n = pattern.nrows();
        let perm: Vec<usize> = match sym.perm() {
            Some(p) => p.arrays().0.to_vec(),
            None => (0..n).collect(),
        };
        let mut inv = vec![0usize; n];
        for (new, &old) in perm.iter().enumerate() {
            inv[old] = new;
        }
        let SymbolicCholeskyRaw::Supernodal(sn) = sym.raw() else {
            return Err("faer returned a simplicial analysis although supernodal was forced".into());
        };
        let n_sn = sn.n_supernodes();
        let mut begin = sn.supernode_begin().to_vec();
        begin.push(n);
        let mut row_ptr = Vec::with_capacity(n_sn + 1);
        let mut rows = Vec::new();
        let mut val_ptr = Vec::with_capacity(n_sn + 1);
        row_ptr.push(0);
        val_ptr.push(0);
        for s in 0..n_sn {
            rows.extend_from_slice(sn.supernode(s).pattern());
            row_ptr.push(rows.len());
            let nc = begin[s + 1] - begin[s];
            let nr = nc + (row_ptr[s + 1] - row_ptr[s]);
            val_ptr.push(val_ptr[s] + nr * nc);
        }
        // Column → supernode, then the descendant lists (the row structure of the supernodal
        // elimination tree).
        let mut col_sn = vec![0usize; n];
        for s in 0..n_sn {
            col_sn[begin[s]..begin[s + 1]].fill(s);
        }
        let mut counts = vec![0usize; n_sn + 1];
        let each_target = |d: usize, f: &mut dyn FnMut(usize)| {
            let mut last = usize::MAX;
            for &r in &rows[row_ptr[d]..row_ptr[d + 1]] {
                let s = col_sn[r];
                if s != last {
                    f(s);
                    last = s;
                }
            }
        };
        for d in 0..n_sn {
            each_target(d, &mut |s| counts[s + 1] += 1);
        }
        let mut desc_ptr = counts;
        for s in 0..n_sn {
            desc_ptr[s + 1] += desc_ptr[s];
        }
        let mut fill = desc_ptr.clone();
        let mut desc = vec![0usize; desc_ptr[n_sn]];
        for d in 0..n_sn {
            each_target(d, &mut |s| {
                desc[fill[s]] = d;
                fill[s] += 1;
            });
        }
        // Where each lower-triangle entry of P A Pᵀ lands in the factor storage.
        let mut scatter_src = Vec::new();
        let mut scatter_dst = Vec::new();
        let col_ptr = pattern.col_ptr();
        let row_idx = pattern.row_idx();
        for j in 0..n {
            let pj = inv[j];
            let s = col_sn[pj];
            let nc = begin[s + 1] - begin[s];
            let pat = &rows[row_ptr[s]..row_ptr[s + 1]];
            let nr = nc + pat.len();
            for (k, &i) in row_idx.iter().enumerate().take(col_ptr[j + 1]).skip(col_ptr[j]) {
                let pi = inv[i];
                if pi < pj {
                    continue;
                }
                let local_row = if pi < begin[s + 1] {
                    pi - begin[s]
                } else {
                    match pat.binary_search(&pi) {
                        Ok(p) => nc + p,
                        Err(_) => return Err(format!("entry ({pi}, {pj}) outside the symbolic factor")),
                    }
                };
                scatter_src.push(k);
                scatter_dst.push(val_ptr[s] + (pj - begin[s]) * nr + local_row);
            }
        }
        Ok(Self {
            n,
            perm,
            begin,
            row_ptr,
            rows,
            val_ptr,
            desc_ptr,
            desc,
            scatter_src,
            scatter_dst,
        })
    }

    fn n_supernodes(&self) -> usize {
        self.begin.len() - 1
    }

    fn pattern(&self, s: usize) -> &[usize] {
        &self.rows[self.row_ptr[s]..self.row_ptr[s + 1]]
    }

    /// Number of stored factor entries (diagonal blocks in full).
    pub fn len_val(&self) -> usize {
        self.val_ptr[self.n_supernodes()]
    }
}

impl LdltFactor {
    /// Factors the matrix whose values on the analysed pattern are `values`. A zero (or
    /// non-finite) pivot — the matrix is singular to working precision, or not of the form
    /// tL − zB with Im z ≠ 0 — is returned as its permuted index.
    pub fn new(symbolic: &std::sync::Arc<LdltSymbolic>, values: &[c64]) -> Result<Self, usize> {
        let sym = &**symbolic;
        let mut lv = vec![ZERO; sym.len_val()];
        for (&src, &dst) in sym.scatter_src.iter().zip(&sym.scatter_dst) {
            lv[dst] += values[src];
        }
        let mut local = vec![usize::MAX; sym.n];
        let mut update: Vec<c64> = Vec::new();
        let mut scaled: Vec<c64> = Vec::new();
        for s in 0..sym.n_supernodes() {
            let (s0, s1) = (sym.begin[s], sym.begin[s + 1]);
            let nc = s1 - s0;
            let pat = sym.pattern(s);
            let nr = nc + pat.len();
            for (i, &r) in pat.iter().enumerate() {
                local[r] = nc + i;
            }
            let (head, tail) = lv.split_at_mut(sym.val_ptr[s]);
            let ls = &mut tail[..nr * nc];
            for &d in &sym.desc[sym.desc_ptr[s]..sym.desc_ptr[s + 1]] {
                let dnc = sym.begin[d + 1] - sym.begin[d];
                let dpat = sym.pattern(d);
                let dnr = dnc + dpat.len();
                let ld = MatRef::from_column_major_slice(&head[sym.val_ptr[d]..sym.val_ptr[d] + dnr * dnc], dnr, dnc);
                let start = dpat.partition_point(|&r| r < s0);
                let mid = dpat[start..].partition_point(|&r| r < s1);
                let m = dpat.len() - start;
                let l_below = ld.subrows(dnc + start, m);
                // (L_mid D_d)ᵀ as a dnc × mid matrix, then W = L_below (L_mid D_d)ᵀ (m × mid).
                scaled.clear();
                scaled.resize(dnc * mid, ZERO);
                let mut sd = MatMut::from_column_major_slice_mut(&mut scaled, dnc, mid);
                for jj in 0..mid {
                    for k in 0..dnc {
                        sd[(k, jj)] = ld[(dnc + start + jj, k)] * ld[(k, k)];
                    }
                }
                update.clear();
                update.resize(m * mid, ZERO);
                let mut w = MatMut::from_column_major_slice_mut(&mut update, m, mid);
                matmul(w.rb_mut(), Accum::Replace, l_below, sd.rb(), ONE, Par::Seq);
                for jj in 0..mid {
                    let col = dpat[start + jj] - s0;
                    let dst = &mut ls[col * nr..(col + 1) * nr];
                    let wc = &update[jj * m..(jj + 1) * m];
                    for ii in jj..m {
                        let r = dpat[start + ii];
                        let row = if ii < mid { r - s0 } else { local[r] };
                        dst[row] -= wc[ii];
                    }
                }
            }
            let block = MatMut::from_column_major_slice_mut(ls, nr, nc);
            let (mut top, mut bot) = block.split_at_row_mut(nc);
            dense_ldlt(top.rb_mut()).map_err(|k| s0 + k)?;
            if !pat.is_empty() {
                solve_unit_lower_triangular_in_place(top.rb(), bot.rb_mut().transpose_mut(), Par::Seq);
                for j in 0..nc {
                    let dinv = top[(j, j)].inv();
                    for i in 0..pat.len() {
                        bot[(i, j)] *= dinv;
                    }
                }
            }
            for &r in pat {
                local[r] = usize::MAX;
            }
        }
        Ok(Self {
            symbolic: symbolic.clone(),
            values: lv,
        })
    }

    /// Supernode s: its column range s₀..s₁, off-diagonal row pattern, diagonal block (unit L
    /// below the diagonal, D on it) and the panel below.
    fn block(&self, s: usize) -> (usize, usize, &[usize], MatRef<'_, c64>, MatRef<'_, c64>) {
        let sym = &*self.symbolic;
        let (s0, s1) = (sym.begin[s], sym.begin[s + 1]);
        let nc = s1 - s0;
        let pat = sym.pattern(s);
        let nr = nc + pat.len();
        let l = MatRef::from_column_major_slice(&self.values[sym.val_ptr[s]..sym.val_ptr[s] + nr * nc], nr, nc);
        let (top, bot) = l.split_at_row(nc);
        (s0, s1, pat, top, bot)
    }

    /// Overwrites the n × k `rhs` with `A⁻¹ rhs`.
    pub fn solve_in_place(&self, mut rhs: MatMut<'_, c64>) {
        let sym = &*self.symbolic;
        let (n, k) = (sym.n, rhs.ncols());
        let mut x = Mat::<c64>::from_fn(n, k, |i, j| rhs[(sym.perm[i], j)]);
        let mut tmp: Vec<c64> = Vec::new();
        // Forward: L y = P b.
        for s in 0..sym.n_supernodes() {
            let (s0, s1, pat, top, bot) = self.block(s);
            let nc = s1 - s0;
            let (upper, lower) = x.as_mut().split_at_row_mut(s1);
            let mut xs = upper.subrows_mut(s0, nc);
            solve_unit_lower_triangular_in_place(top, xs.rb_mut(), Par::Seq);
            if !pat.is_empty() {
                tmp.clear();
                tmp.resize(pat.len() * k, ZERO);
                let mut t = MatMut::from_column_major_slice_mut(&mut tmp, pat.len(), k);
                matmul(t.rb_mut(), Accum::Replace, bot, xs.rb(), ONE, Par::Seq);
                let mut lower = lower;
                for j in 0..k {
                    for (i, &r) in pat.iter().enumerate() {
                        lower[(r - s1, j)] -= t[(i, j)];
                    }
                }
            }
        }
        // Diagonal: D.
        for s in 0..sym.n_supernodes() {
            let (s0, s1, _, top, _) = self.block(s);
            for c in s0..s1 {
                let dinv = top[(c - s0, c - s0)].inv();
                for j in 0..k {
                    x[(c, j)] *= dinv;
                }
            }
        }
        // Backward: Lᵀ x = y.
        for s in (0..sym.n_supernodes()).rev() {
            let (s0, s1, pat, top, bot) = self.block(s);
            let nc = s1 - s0;
            let (upper, lower) = x.as_mut().split_at_row_mut(s1);
            let mut xs = upper.subrows_mut(s0, nc);
            if !pat.is_empty() {
                tmp.clear();
                tmp.resize(pat.len() * k, ZERO);
                let mut t = MatMut::from_column_major_slice_mut(&mut tmp, pat.len(), k);
                for j in 0..k {
                    for (i, &r) in pat.iter().enumerate() {
                        t[(i, j)] = lower[(r - s1, j)];
                    }
                }
                matmul(xs.rb_mut(), Accum::Add, bot.transpose(), t.rb(), -ONE, Par::Seq);
            }
            solve_unit_upper_triangular_in_place(top.transpose(), xs.rb_mut(), Par::Seq);
        }
        for j in 0..k {
            for i in 0..n {
                rhs[(sym.perm[i], j)] = x[(i, j)];
            }
        }
    }
}

/// In-place LDLᵀ (no conjugation, no pivoting) of the lower triangle of a square block: on
/// return the strict lower triangle holds L (unit diagonal implied) and the diagonal holds D.
/// Returns the local index of a zero or non-finite pivot.
fn dense_ldlt(mut a: MatMut<'_, c64>) -> Result<(), usize> {
    let n = a.nrows();
    if n <= DENSE_BLOCK {
        for k in 0..n {
            let d = a[(k, k)];
            let mag = d.norm();
            if mag == 0.0 || !mag.is_finite() {
                return Err(k);
            }
            let dinv = d.inv();
            for j in k + 1..n {
                let f = a[(j, k)] * dinv;
                for i in j..n {
                    let aik = a[(i, k)];
                    a[(i, j)] -= aik * f;
                }
            }
            for i in k + 1..n {
                a[(i, k)] *= dinv;
            }
        }
        return Ok(());
    }
    let n1 = n / 2;
    let (mut a11, _, mut a21, mut a22) = a.rb_mut().split_at_mut(n1, n1);
    dense_ldlt(a11.rb_mut())?;
    // a21 ← A21 L11⁻ᵀ = L21 D1.
    solve_unit_lower_triangular_in_place(a11.rb(), a21.rb_mut().transpose_mut(), Par::Seq);
    let l21 = Mat::<c64>::from_fn(a21.nrows(), n1, |i, j| a21[(i, j)] * a11[(j, j)].inv());
    // A22 ← A22 − L21 (L21 D1)ᵀ (lower triangle only).
    triangular::matmul(
        a22.rb_mut(),
        BlockStructure::TriangularLower,
        Accum::Add,
        l21.as_ref(),
        BlockStructure::Rectangular,
        a21.rb().transpose(),
        BlockStructure::Rectangular,
        -ONE,
        Par::Seq,
    );
    a21.copy_from(&l21);
    dense_ldlt(a22).map_err(|k| k + n1)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lcg(state: &mut u64) -> f64 {
        *state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((*state >> 11) as f64) / ((1u64 << 53) as f64) - 0.5
    }

    /// A random complex-symmetric matrix K − zM with K, M real symmetric, M diagonally
    /// dominant (so the Hermitian part of i·A is definite, as for the shifted systems).
    fn random_shifted(n: usize, z: c64, seed: u64) -> Mat<c64> {
        let mut s = seed;
        let mut k = Mat::<f64>::zeros(n, n);
        let mut m = Mat::<f64>::zeros(n, n);
        for j in 0..n {
            for i in j..n {
                let (a, b) = (lcg(&mut s), 0.1 * lcg(&mut s));
                k[(i, j)] = a;
                k[(j, i)] = a;
                m[(i, j)] = b;
                m[(j, i)] = b;
            }
            m[(j, j)] = n as f64;
        }
        Mat::from_fn(n, n, |i, j| c64::new(k[(i, j)], 0.0) - z * m[(i, j)])
    }

    /// L D Lᵀ rebuilt from the packed factor equals A (relative 1e-13), for sizes that use the
    /// unblocked kernel, one level and several levels of recursion.
    #[test]
    fn dense_ldlt_reconstructs_the_matrix() {
        for n in [1, 5, DENSE_BLOCK, DENSE_BLOCK + 1, 77, 200] {
            let a = random_shifted(n, c64::new(1.4, 13.5), n as u64);
            let mut f = a.clone();
            dense_ldlt(f.as_mut()).unwrap();
            let l = Mat::<c64>::from_fn(n, n, |i, j| match i.cmp(&j) {
                std::cmp::Ordering::Greater => f[(i, j)],
                std::cmp::Ordering::Equal => ONE,
                std::cmp::Ordering::Less => ZERO,
            });
            let d = Mat::<c64>::from_fn(n, n, |i, j| if i == j { f[(i, i)] } else { ZERO });
            let back = &l * &d * l.transpose();
            let err = (&back - &a).norm_l2() / a.norm_l2();
            assert!(err < 1e-13, "n = {n}: {err:e}");
        }
    }

    /// On a mesh pattern (icosphere, n = 2,562) the analysis has supernodes wider than the
    /// unblocked kernel, so the recursive path and the descendant updates are exercised; the
    /// sparse factor solves a random complex-symmetric shifted system to 1e-13.
    #[test]
    fn sparse_factor_solves_a_mesh_system() {
        let mesh = mesh_fem::generate::icosphere(4);
        let ops = mesh_fem::assemble(&mesh, &mesh_fem::AssemblyParams::default()).unwrap();
        let (l, b) = (ops.stiffness, ops.mass);
        let pair = crate::OperatorPair::new(l.as_ref(), b.as_ref()).unwrap();
        let analysis = pair.cholesky().unwrap().symbolic();
        let sym = std::sync::Arc::new(LdltSymbolic::new(pair.pattern(), analysis).unwrap());
        let widest = (0..sym.n_supernodes())
            .map(|s| sym.begin[s + 1] - sym.begin[s])
            .max()
            .unwrap();
        assert!(widest > 2 * DENSE_BLOCK, "widest supernode {widest}");
        let (t, z) = (0.3, c64::new(10.844, 19.277));
        let a = pair.shifted(t, z);
        let f = LdltFactor::new(&sym, a.val()).unwrap();
        let n = pair.n();
        let mut s = 5u64;
        let rhs = Mat::<c64>::from_fn(n, 2, |_, _| c64::new(lcg(&mut s), lcg(&mut s)));
        let mut x = rhs.clone();
        f.solve_in_place(x.as_mut());
        for j in 0..2 {
            let mut ax = vec![ZERO; n];
            pair.complex_mul(c64::new(t, 0.0), -z, x.col_as_slice(j), &mut ax);
            let num: f64 = (0..n).map(|i| (ax[i] - rhs[(i, j)]).norm_sqr()).sum();
            let den: f64 = (0..n).map(|i| rhs[(i, j)].norm_sqr()).sum();
            assert!((num / den).sqrt() < 1e-13, "residual {:e}", (num / den).sqrt());
        }
    }

    /// A zero pivot is reported with its index instead of producing NaN.
    #[test]
    fn zero_pivot_is_reported() {
        let mut a = Mat::<c64>::identity(40, 40);
        a[(17, 17)] = ZERO;
        assert_eq!(dense_ldlt(a.as_mut()), Err(17));
        let mut b = Mat::<c64>::identity(3, 3);
        b[(1, 1)] = c64::new(f64::NAN, 0.0);
        assert_eq!(dense_ldlt(b.as_mut()), Err(1));
    }
}
