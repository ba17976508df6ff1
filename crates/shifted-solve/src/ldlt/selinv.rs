//! Selected inversion of a complex-symmetric supernodal LDLᵀ factor (Erisman & Tinney, CACM
//! 18 (1975); supernodal form of Lin, Yang, Meza, Lu, Ying & E, ACM TOMS 37 (2011)
//! "SelInv"): the entries of `Z = A⁻¹` on the pattern of the factor, at about the cost of
//! the factorization, without forming a single column of A⁻¹.
//!
//! From `A = LDLᵀ`, `LᵀZ = D⁻¹L⁻¹` is upper triangular with diagonal D⁻¹. For a supernode J
//! (columns J, off-diagonal rows R) with `Û = L_RJ L_JJ⁻¹` this gives
//!
//! ```text
//! Z_RJ = −Z_RR Û,        Z_JJ = L_JJ⁻ᵀ D_J⁻¹ L_JJ⁻¹ − Ûᵀ Z_RJ,
//! ```
//!
//! and Z_RR lies inside the factor's pattern (the rows R of J belong to J's ancestors, whose
//! own patterns contain the rest of R), so sweeping the supernodes from the root down needs
//! only entries already computed.

use super::{LdltFactor, ONE, ZERO};
use faer::linalg::matmul::matmul;
use faer::linalg::triangular_solve::solve_unit_lower_triangular_in_place;
use faer::reborrow::ReborrowMut;
use faer::{c64, Accum, Mat, MatMut, MatRef, Par};

impl LdltFactor {
    /// `Z = (P A Pᵀ)⁻¹` on the pattern of the factor, in the factor's storage layout (every
    /// supernode's diagonal block in full, then its panel rows). In place: the sweep from the
    /// root down needs a supernode's L only until its own Z replaces it, so the factor's
    /// storage becomes Z's (no second copy of the factor in memory).
    pub(crate) fn selected_inverse(self) -> Vec<c64> {
        let sym = &*self.symbolic;
        let mut z = self.values;
        let n_sn = sym.n_supernodes();
        let mut col_sn = vec![0usize; sym.n];
        for s in 0..n_sn {
            col_sn[sym.begin[s]..sym.begin[s + 1]].fill(s);
        }
        let mut zrr: Vec<c64> = Vec::new();
        let mut pos: Vec<usize> = Vec::new();
        for s in (0..n_sn).rev() {
            let (s0, s1) = (sym.begin[s], sym.begin[s + 1]);
            let pat = sym.pattern(s);
            let nc = s1 - s0;
            let m = pat.len();
            let nr = nc + m;
            // This supernode's L (not yet overwritten): L_JJ⁻¹, D_J⁻¹ L_JJ⁻¹ and Û = L_RJ L_JJ⁻¹.
            let (linv, dlinv, u) = {
                let l = MatRef::from_column_major_slice(&z[sym.val_ptr[s]..sym.val_ptr[s] + nr * nc], nr, nc);
                let (top, bot) = l.split_at_row(nc);
                let mut linv = Mat::<c64>::identity(nc, nc);
                solve_unit_lower_triangular_in_place(top, linv.as_mut(), Par::Seq);
                let dlinv = Mat::<c64>::from_fn(nc, nc, |i, j| top[(i, i)].inv() * linv[(i, j)]);
                let mut u = Mat::<c64>::zeros(m, nc);
                if m > 0 {
                    matmul(u.as_mut(), Accum::Replace, bot, linv.as_ref(), ONE, Par::Seq);
                }
                (linv, dlinv, u)
            };
            let mut zjj = Mat::<c64>::zeros(nc, nc);
            matmul(
                zjj.as_mut(),
                Accum::Replace,
                linv.transpose(),
                dlinv.as_ref(),
                ONE,
                Par::Seq,
            );
            let mut zrj = Mat::<c64>::zeros(m, nc);
            if m > 0 {
                // Gather Z_RR (both triangles) from the ancestors, one run of rows of the same
                // supernode K at a time: rows inside K sit in its diagonal block, rows past K
                // in its panel (found by binary search in K's pattern).
                zrr.clear();
                zrr.resize(m * m, ZERO);
                let mut b0 = 0;
                while b0 < m {
                    let k = col_sn[pat[b0]];
                    let (k0, k1) = (sym.begin[k], sym.begin[k + 1]);
                    let kpat = sym.pattern(k);
                    let knr = (k1 - k0) + kpat.len();
                    let b1 = b0 + pat[b0..].partition_point(|&r| r < k1);
                    pos.clear();
                    for &r in &pat[b0..] {
                        pos.push(if r < k1 {
                            r - k0
                        } else {
                            // invariant: the rows of J past K are in K's pattern (elimination
                            // tree); a miss would be a bug in the symbolic analysis.
                            (k1 - k0) + kpat.binary_search(&r).unwrap_or_else(|p| p.min(kpat.len() - 1))
                        });
                    }
                    for b in b0..b1 {
                        let col = sym.val_ptr[k] + (pat[b] - k0) * knr;
                        for a in b..m {
                            let v = z[col + pos[a - b0]];
                            zrr[b * m + a] = v;
                            zrr[a * m + b] = v;
                        }
                    }
                    b0 = b1;
                }
                let zrr_m = MatRef::from_column_major_slice(&zrr, m, m);
                matmul(zrj.as_mut(), Accum::Replace, zrr_m, u.as_ref(), -ONE, Par::Seq);
                matmul(zjj.as_mut(), Accum::Add, u.transpose(), zrj.as_ref(), -ONE, Par::Seq);
            }
            let mut dst = MatMut::from_column_major_slice_mut(&mut z[sym.val_ptr[s]..sym.val_ptr[s] + nr * nc], nr, nc);
            dst.rb_mut().subrows_mut(0, nc).copy_from(&zjj);
            dst.subrows_mut(nc, m).copy_from(&zrj);
        }
        z
    }
}

impl super::LdltSymbolic {
    /// Where each stored entry (i, j) of the pattern the symbolic analysis was built from
    /// (both triangles, in its order) sits in the factor storage: the position of
    /// `(max(p_i, p_j), min(p_i, p_j))` in the permuted numbering (Z is symmetric).
    pub(crate) fn pattern_positions(&self, pattern: faer::sparse::SymbolicSparseColMatRef<'_, usize>) -> Vec<usize> {
        let n = self.n;
        let mut inv = vec![0usize; n];
        for (new, &old) in self.perm.iter().enumerate() {
            inv[old] = new;
        }
        let mut col_sn = vec![0usize; n];
        for s in 0..self.n_supernodes() {
            col_sn[self.begin[s]..self.begin[s + 1]].fill(s);
        }
        let (ptr, idx) = (pattern.col_ptr(), pattern.row_idx());
        let mut out = Vec::with_capacity(idx.len());
        for j in 0..n {
            for &i in &idx[ptr[j]..ptr[j + 1]] {
                let (pi, pj) = (inv[i], inv[j]);
                let (r, c) = (pi.max(pj), pi.min(pj));
                let s = col_sn[c];
                let nc = self.begin[s + 1] - self.begin[s];
                let pat = self.pattern(s);
                let local = if r < self.begin[s + 1] {
                    r - self.begin[s]
                } else {
                    // invariant: every entry of the analysed pattern is in the factor
                    // (checked by `LdltSymbolic::new`'s scatter map).
                    nc + pat.binary_search(&r).unwrap_or_else(|p| p.min(pat.len() - 1))
                };
                out.push(self.val_ptr[s] + (c - self.begin[s]) * (nc + pat.len()) + local);
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::super::LdltSymbolic;
    use super::*;
    use faer::linalg::solvers::DenseSolveCore;

    /// On a mesh pattern with supernodes wide enough for the blocked paths, the selected
    /// inverse of a shifted matrix tL − zM equals the dense inverse (pivoted LU of the
    /// assembled dense matrix, an independent route) on every entry of the pattern.
    #[test]
    fn selected_inverse_matches_the_dense_inverse_on_the_pattern() {
        let mesh = mesh_fem::generate::icosphere(3);
        let ops = mesh_fem::assemble(&mesh, &mesh_fem::AssemblyParams::default()).unwrap();
        let pair = crate::OperatorPair::new(ops.stiffness.as_ref(), ops.mass.as_ref()).unwrap();
        let analysis = pair.cholesky().unwrap().symbolic();
        let sym = std::sync::Arc::new(LdltSymbolic::new(pair.pattern(), analysis).unwrap());
        let positions = sym.pattern_positions(pair.pattern());
        let n = pair.n();
        for (t, z) in [
            (0.3, c64::new(10.844, 19.277)),
            (0.01, c64::new(-2.5, 0.75)),
            (2.0, c64::new(-8.0, 0.0)),
        ] {
            let a = pair.shifted(t, z);
            let f = LdltFactor::new(&sym, a.val()).unwrap();
            let zsel = f.selected_inverse();
            let dense = a.to_dense();
            let inv = dense.partial_piv_lu().inverse();
            let (ptr, idx) = (pair.pattern().col_ptr(), pair.pattern().row_idx());
            let scale = (0..n).map(|i| inv[(i, i)].norm()).fold(0.0, f64::max);
            let mut worst = 0.0f64;
            for j in 0..n {
                for (k, &i) in idx.iter().enumerate().take(ptr[j + 1]).skip(ptr[j]) {
                    worst = worst.max((zsel[positions[k]] - inv[(i, j)]).norm() / scale);
                }
            }
            assert!(worst < 1e-12, "t = {t}, z = {z:?}: {worst:e}");
        }
    }
}
