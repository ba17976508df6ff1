//! Tree-parallel supernodal triangular solves `L y = b`, `Lᵀ x = y` for the real Cholesky
//! factor `A = PᵀLLᵀP` (faer's supernodal layout).
//!
//! faer's supernodal solve visits the supernodes one after the other; with one right-hand side
//! each supernode is a small dense triangular solve and a GEMV, so the sweep is memory bound and
//! runs on one core while faer's numeric factorization uses all of them. The fast path of
//! wfem-heat makes ~30 solves per factorization, so the solve is what it waits for.
//!
//! Columns of disjoint subtrees of the supernodal elimination tree never touch each other: in
//! the forward sweep a supernode only updates rows of its ancestors, in the backward sweep it
//! only reads them. The plan splits the tree into a *top* part (the root supernodes and the
//! ancestors of the split points) and disjoint subtrees packed onto the workers (largest first,
//! each to the least loaded worker), choosing the split that minimises
//! `work(top) + max_w work(worker w)` with work = stored factor entries:
//!
//! - forward: the workers sweep their subtrees in parallel; the updates that leave a subtree go
//!   to top rows and are accumulated per worker, then added; the top supernodes follow in order;
//! - backward: the top supernodes first (in reverse), then the workers sweep their subtrees in
//!   reverse, reading top rows from a shared copy.
//!
//! Every row of x is written by exactly one task, so the result equals the sequential sweep up
//! to the order of the summation in the top rows (rounding level). Supernodes up to 32 columns
//! (almost all of a mesh factor: 10,115 supernodes for n = 40,962) take plain one-vector loops
//! instead of faer's dense kernels, whose per-call dispatch dominated at that size.
//!
//! Measured on the icosphere, AMD ordering, 2 cores (criterion, `cholesky_solve_1rhs_*` in
//! `benches/shifted.rs`): n = 10,242: 577 µs (faer) → 351 µs; n = 40,962: 6.08 → 3.70 ms. The
//! top part is about 20 % of the factor there and the plan predicts 61 % of the sequential work.

use std::ops::Range;

use faer::linalg::matmul::matmul;
use faer::linalg::triangular_solve::{solve_lower_triangular_in_place, solve_upper_triangular_in_place};
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::sparse::linalg::cholesky::supernodal::{SupernodalLltRef, SymbolicSupernodalCholesky};
use faer::{Accum, Mat, MatMut, MatRef, Par};
use rayon::prelude::*;

/// Below this predicted speed-up the plan is not used (the sequential sweep has no fork/join,
/// no per-worker buffers and no extra pass over the top rows).
const MIN_SPEEDUP: f64 = 1.15;

/// One subtree of the supernodal elimination tree: its supernodes and the (contiguous, by
/// postorder) rows of its columns.
#[derive(Clone, Debug)]
struct Subtree {
    supernodes: Range<usize>,
    rows: Range<usize>,
    worker: usize,
}

/// How one supernodal factor is split between workers (computed once per symbolic analysis).
#[derive(Clone, Debug)]
pub(crate) struct SolvePlan {
    /// Disjoint subtrees, sorted by rows.
    subtrees: Vec<Subtree>,
    /// Number of workers the subtrees are packed onto.
    workers: usize,
    /// Supernodes outside every subtree, ascending.
    top: Vec<usize>,
    /// Rows (columns of the factor) of the top supernodes, ascending.
    top_rows: Vec<usize>,
    /// `top_index[r]` = position of row r in `top_rows` (unused for other rows).
    top_index: Vec<u32>,
}

impl SolvePlan {
    /// The plan for `workers` workers, or `None` when it would not pay (fewer than two workers,
    /// predicted speed-up below [`MIN_SPEEDUP`]) or the supernodes are not postordered.
    pub(crate) fn new(sn: &SymbolicSupernodalCholesky<usize>, workers: usize) -> Option<Self> {
        let ns = sn.n_supernodes();
        let n = sn.nrows();
        if workers < 2 || ns < 2 || n > u32::MAX as usize {
            return None;
        }
        let begin = sn.supernode_begin();
        let end = sn.supernode_end();
        let mut col_sn = vec![0usize; n];
        for s in 0..ns {
            col_sn[begin[s]..end[s]].fill(s);
        }
        let mut parent = vec![usize::MAX; ns];
        let mut work = vec![0.0f64; ns];
        for s in 0..ns {
            let pattern = sn.supernode(s).pattern();
            let nc = end[s] - begin[s];
            work[s] = ((nc + pattern.len()) * nc) as f64;
            if let Some(&r) = pattern.first() {
                parent[s] = col_sn[r];
                if parent[s] <= s {
                    return None;
                }
            }
        }
        // Subtree sizes, first descendants and work; a postordered tree has every subtree on
        // the contiguous range first[s]..=s.
        let mut first: Vec<usize> = (0..ns).collect();
        let mut size = vec![1usize; ns];
        let mut subtree_work = work.clone();
        let mut children = vec![Vec::new(); ns];
        for s in 0..ns {
            let p = parent[s];
            if p != usize::MAX {
                first[p] = first[p].min(first[s]);
                size[p] += size[s];
                subtree_work[p] += subtree_work[s];
                children[p].push(s);
            }
        }
        if (0..ns).any(|s| s + 1 - first[s] != size[s]) {
            return None;
        }
        let total: f64 = work.iter().sum();
        let roots: Vec<usize> = (0..ns).filter(|&s| parent[s] == usize::MAX).collect();

        // Greedy top-down split: repeatedly move the heaviest candidate subtree's root to the
        // top and its children to the candidates; keep the best packing seen.
        let pack = |cands: &[usize]| -> (f64, Vec<usize>) {
            let mut order: Vec<usize> = (0..cands.len()).collect();
            order.sort_by(|&a, &b| subtree_work[cands[b]].total_cmp(&subtree_work[cands[a]]));
            let mut bins = vec![0.0f64; workers];
            let mut assign = vec![0usize; cands.len()];
            for i in order {
                let w = (0..workers).min_by(|&a, &b| bins[a].total_cmp(&bins[b])).unwrap_or(0);
                bins[w] += subtree_work[cands[i]];
                assign[i] = w;
            }
            (bins.iter().copied().fold(0.0, f64::max), assign)
        };
        let mut cands = roots;
        let mut top = Vec::new();
        let mut top_work = 0.0;
        // (predicted time, candidate roots, their workers, top supernodes)
        type Split = (f64, Vec<usize>, Vec<usize>, Vec<usize>);
        let mut best: Option<Split> = None;
        for _ in 0..(64 + 8 * workers) {
            let (max_bin, assign) = pack(&cands);
            let time = top_work + max_bin;
            if best.as_ref().is_none_or(|b| time < b.0) {
                best = Some((time, cands.clone(), assign, top.clone()));
            }
            if top_work > 0.5 * total {
                break;
            }
            let Some(h) = (0..cands.len()).max_by(|&a, &b| subtree_work[cands[a]].total_cmp(&subtree_work[cands[b]]))
            else {
                break;
            };
            let root = cands.swap_remove(h);
            top.push(root);
            top_work += work[root];
            cands.extend(children[root].iter().copied());
        }
        let (time, cands, assign, mut top) = best?;
        let speedup = total / time.max(f64::MIN_POSITIVE);
        if speedup < MIN_SPEEDUP {
            return None;
        }
        let mut subtrees: Vec<Subtree> = cands
            .iter()
            .zip(&assign)
            .map(|(&s, &worker)| Subtree {
                supernodes: first[s]..s + 1,
                rows: begin[first[s]]..end[s],
                worker,
            })
            .collect();
        subtrees.sort_by_key(|t| t.rows.start);
        top.sort_unstable();
        let top_rows: Vec<usize> = top.iter().flat_map(|&s| begin[s]..end[s]).collect();
        let mut top_index = vec![u32::MAX; n];
        for (i, &r) in top_rows.iter().enumerate() {
            // invariant: n ≤ u32::MAX was checked above.
            top_index[r] = i as u32;
        }
        Some(Self {
            subtrees,
            workers,
            top,
            top_rows,
            top_index,
        })
    }

    /// Overwrites the n × k `x` (already permuted, `x ← P b`) with `(LLᵀ)⁻¹ x`, the workers'
    /// shares run as rayon tasks.
    pub(crate) fn solve_in_place(&self, llt: SupernodalLltRef<'_, usize, f64>, mut x: MatMut<'_, f64>) {
        let deltas: Vec<Mat<f64>> = self
            .pieces(x.rb_mut())
            .into_par_iter()
            .with_max_len(1)
            .map(|pieces| self.forward_share(llt, pieces))
            .collect();
        let top_values = self.top_sweeps(llt, x.rb_mut(), &deltas);
        self.pieces(x.rb_mut())
            .into_par_iter()
            .with_max_len(1)
            .for_each(|pieces| self.backward_share(llt, pieces, top_values.as_ref()));
    }

    /// Forward sweep over one worker's subtrees; returns its updates of the top rows.
    fn forward_share(
        &self,
        llt: SupernodalLltRef<'_, usize, f64>,
        pieces: Vec<(&Subtree, MatMut<'_, f64>)>,
    ) -> Mat<f64> {
        let k = pieces.first().map_or(1, |(_, xs)| xs.ncols());
        let mut delta = Mat::<f64>::zeros(self.top_rows.len(), k);
        let mut tmp = Vec::new();
        for (tree, mut xs) in pieces {
            for s in tree.supernodes.clone() {
                let spill = |r: usize, j: usize, v: f64| delta[(self.top_index[r] as usize, j)] += v;
                forward(llt, s, xs.rb_mut(), tree.rows.clone(), &mut tmp, spill);
            }
        }
        delta
    }

    /// Backward sweep over one worker's subtrees, reading the top rows from `top_values`.
    fn backward_share(
        &self,
        llt: SupernodalLltRef<'_, usize, f64>,
        pieces: Vec<(&Subtree, MatMut<'_, f64>)>,
        top_values: MatRef<'_, f64>,
    ) {
        let mut tmp = Vec::new();
        for (tree, mut xs) in pieces {
            for s in tree.supernodes.clone().rev() {
                let outside = |r: usize, j: usize| top_values[(self.top_index[r] as usize, j)];
                backward(llt, s, xs.rb_mut(), tree.rows.clone(), &mut tmp, outside);
            }
        }
    }

    /// Between the two parallel phases: adds the workers' top-row updates, runs the top
    /// supernodes forward then backward, and returns a copy of the top rows.
    fn top_sweeps(
        &self,
        llt: SupernodalLltRef<'_, usize, f64>,
        mut x: MatMut<'_, f64>,
        deltas: &[Mat<f64>],
    ) -> Mat<f64> {
        let (n, k) = (x.nrows(), x.ncols());
        for delta in deltas {
            for j in 0..k {
                for (i, &r) in self.top_rows.iter().enumerate() {
                    x[(r, j)] -= delta[(i, j)];
                }
            }
        }
        let mut tmp = Vec::new();
        for &s in &self.top {
            forward(llt, s, x.rb_mut(), 0..n, &mut tmp, |_, _, _| {});
        }
        for &s in self.top.iter().rev() {
            backward(llt, s, x.rb_mut(), 0..n, &mut tmp, |_, _| 0.0);
        }
        Mat::<f64>::from_fn(self.top_rows.len(), k, |i, j| x[(self.top_rows[i], j)])
    }

    /// Splits x into the disjoint row blocks of the subtrees, grouped by worker.
    fn pieces<'a>(&'a self, x: MatMut<'a, f64>) -> Vec<Vec<(&'a Subtree, MatMut<'a, f64>)>> {
        let mut groups: Vec<Vec<(&Subtree, MatMut<'a, f64>)>> = (0..self.workers).map(|_| Vec::new()).collect();
        let mut rest = x;
        let mut offset = 0;
        for tree in &self.subtrees {
            let (_, tail) = rest.split_at_row_mut(tree.rows.start - offset);
            let (piece, tail) = tail.split_at_row_mut(tree.rows.len());
            groups[tree.worker].push((tree, piece));
            rest = tail;
            offset = tree.rows.end;
        }
        groups
    }
}

/// Forward step of supernode s on the rows `rows` of x held in `xs`: `x_s ← L_ss⁻¹ x_s`, then
/// `x_r −= (L_bs x_s)_r` for the pattern rows inside `rows` and `spill(r, j, (L_bs x_s)_r)` for
/// the others.
fn forward(
    llt: SupernodalLltRef<'_, usize, f64>,
    s: usize,
    mut xs: MatMut<'_, f64>,
    rows: Range<usize>,
    tmp: &mut Vec<f64>,
    mut spill: impl FnMut(usize, usize, f64),
) {
    let node = llt.supernode(s);
    let (start, pattern, l) = (node.start(), node.pattern(), node.val());
    let nc = l.ncols();
    let k = xs.ncols();
    if let Some((block, x)) = one_vector(llt, s, &mut xs) {
        forward_vec(block, x, rows, tmp, |r, v| spill(r, 0, v));
        return;
    }
    let (l_top, l_bot) = l.split_at_row(nc);
    let (upper, mut lower) = xs.split_at_row_mut(start + nc - rows.start);
    let mut x_s = upper.subrows_mut(start - rows.start, nc);
    solve_lower_triangular_in_place(l_top, x_s.rb_mut(), Par::Seq);
    if pattern.is_empty() {
        return;
    }
    let t = product(l_bot, x_s.rb(), tmp);
    let below = start + nc;
    for j in 0..k {
        for (i, &r) in pattern.iter().enumerate() {
            if r < rows.end {
                lower[(r - below, j)] -= t[(i, j)];
            } else {
                spill(r, j, t[(i, j)]);
            }
        }
    }
}

/// Backward step of supernode s: `x_s ← L_ssᵀ⁻¹ (x_s − L_bsᵀ x_b)` with `x_b` read from xs for
/// rows inside `rows` and from `outside(r, j)` for the others.
fn backward(
    llt: SupernodalLltRef<'_, usize, f64>,
    s: usize,
    mut xs: MatMut<'_, f64>,
    rows: Range<usize>,
    tmp: &mut Vec<f64>,
    outside: impl Fn(usize, usize) -> f64,
) {
    let node = llt.supernode(s);
    let (start, pattern, l) = (node.start(), node.pattern(), node.val());
    let nc = l.ncols();
    let k = xs.ncols();
    if let Some((block, x)) = one_vector(llt, s, &mut xs) {
        backward_vec(block, x, rows, tmp, |r| outside(r, 0));
        return;
    }
    let (l_top, l_bot) = l.split_at_row(nc);
    let (upper, lower) = xs.split_at_row_mut(start + nc - rows.start);
    let mut x_s = upper.subrows_mut(start - rows.start, nc);
    if !pattern.is_empty() {
        let below = start + nc;
        tmp.clear();
        tmp.reserve(pattern.len() * k);
        for j in 0..k {
            for &r in pattern {
                tmp.push(if r < rows.end {
                    lower[(r - below, j)]
                } else {
                    outside(r, j)
                });
            }
        }
        let t = MatRef::from_column_major_slice(tmp, pattern.len(), k);
        matmul(x_s.rb_mut(), Accum::Add, l_bot.transpose(), t, -1.0, Par::Seq);
    }
    solve_upper_triangular_in_place(l_top.transpose(), x_s, Par::Seq);
}

/// Supernodes up to this width take the one-vector loops below (faer's dense kernels pay a
/// dispatch cost per call that dominates for the typical 2–8 columns of a mesh factor).
const SMALL: usize = 32;

/// One supernode as the one-vector kernels see it.
struct Block<'a> {
    /// Column-major values, (nc + |pattern|) × nc.
    vals: &'a [f64],
    /// Number of columns.
    nc: usize,
    /// Off-diagonal row pattern.
    pattern: &'a [usize],
    /// First column.
    start: usize,
}

impl<'a> Block<'a> {
    /// Column `c` of the supernode: its nc + |pattern| values.
    fn column(&self, c: usize) -> &'a [f64] {
        let nr = self.nc + self.pattern.len();
        &self.vals[c * nr..(c + 1) * nr]
    }
}

/// For one right-hand side and a supernode of at most [`SMALL`] columns: the supernode and x as
/// a slice.
fn one_vector<'a>(
    llt: SupernodalLltRef<'a, usize, f64>,
    s: usize,
    xs: &'a mut MatMut<'_, f64>,
) -> Option<(Block<'a>, &'a mut [f64])> {
    let node = llt.supernode(s);
    let nc = node.val().ncols();
    if xs.ncols() != 1 || nc > SMALL {
        return None;
    }
    let x = xs.rb_mut().col_mut(0).try_as_col_major_mut()?;
    let ptr = llt.symbolic().col_ptr_for_val();
    let block = Block {
        vals: &llt.values()[ptr[s]..ptr[s + 1]],
        nc,
        pattern: node.pattern(),
        start: node.start(),
    };
    Some((block, x.as_slice_mut()))
}

/// [`forward`] for one right-hand side held in the slice `x` (rows `rows`).
fn forward_vec(b: Block<'_>, x: &mut [f64], rows: Range<usize>, tmp: &mut Vec<f64>, mut spill: impl FnMut(usize, f64)) {
    let (nc, pattern, base) = (b.nc, b.pattern, b.start - rows.start);
    tmp.clear();
    tmp.resize(pattern.len(), 0.0);
    for c in 0..nc {
        let col = b.column(c);
        let xc = x[base + c] / col[c];
        x[base + c] = xc;
        for (xi, li) in x[base + c + 1..base + nc].iter_mut().zip(&col[c + 1..nc]) {
            *xi -= li * xc;
        }
        for (ti, li) in tmp.iter_mut().zip(&col[nc..]) {
            *ti += li * xc;
        }
    }
    for (&r, &v) in pattern.iter().zip(tmp.iter()) {
        if r < rows.end {
            x[r - rows.start] -= v;
        } else {
            spill(r, v);
        }
    }
}

/// [`backward`] for one right-hand side held in the slice `x`.
fn backward_vec(b: Block<'_>, x: &mut [f64], rows: Range<usize>, tmp: &mut Vec<f64>, outside: impl Fn(usize) -> f64) {
    let (nc, pattern, base) = (b.nc, b.pattern, b.start - rows.start);
    tmp.clear();
    tmp.extend(
        pattern
            .iter()
            .map(|&r| if r < rows.end { x[r - rows.start] } else { outside(r) }),
    );
    for c in (0..nc).rev() {
        let col = b.column(c);
        let mut v = x[base + c] - dot(&col[nc..], tmp);
        for (xi, li) in x[base + c + 1..base + nc].iter().zip(&col[c + 1..nc]) {
            v -= li * xi;
        }
        x[base + c] = v / col[c];
    }
}

/// Dot product with four independent accumulators (the compiler may not reassociate one).
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let mut acc = [0.0f64; 4];
    let (a4, a_rest) = a.split_at(a.len() - a.len() % 4);
    let (b4, b_rest) = b.split_at(a4.len());
    for (x, y) in a4.chunks_exact(4).zip(b4.chunks_exact(4)) {
        for i in 0..4 {
            acc[i] += x[i] * y[i];
        }
    }
    let rest: f64 = a_rest.iter().zip(b_rest).map(|(x, y)| x * y).sum();
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + rest
}

/// `l · x` into the scratch `tmp` (resized), as a column-major view.
fn product<'a>(l: MatRef<'_, f64>, x: MatRef<'_, f64>, tmp: &'a mut Vec<f64>) -> MatRef<'a, f64> {
    let (m, k) = (l.nrows(), x.ncols());
    tmp.clear();
    tmp.resize(m * k, 0.0);
    let mut t = MatMut::from_column_major_slice_mut(tmp, m, k);
    matmul(t.rb_mut(), Accum::Replace, l, x, 1.0, Par::Seq);
    MatRef::from_column_major_slice(tmp, m, k)
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::sparse::linalg::cholesky::{factorize_symbolic_cholesky, LltRef, SymbolicCholeskyRaw, SymmetricOrdering};
    use faer::sparse::{SparseColMat, Triplet};
    use faer::Side;

    /// SPD 5-point Laplacian plus identity on a w × h grid; with `cut`, the edges between
    /// columns w/2 − 1 and w/2 are left out (two components: the elimination tree is a forest).
    fn grid(w: usize, h: usize, cut: bool) -> SparseColMat<usize, f64> {
        let id = |i: usize, j: usize| i * h + j;
        let mut t = Vec::new();
        for i in 0..w {
            for j in 0..h {
                t.push(Triplet::new(id(i, j), id(i, j), 4.5));
                if i + 1 < w && !(cut && i + 1 == w / 2) {
                    t.push(Triplet::new(id(i + 1, j), id(i, j), -1.0));
                    t.push(Triplet::new(id(i, j), id(i + 1, j), -1.0));
                }
                if j + 1 < h {
                    t.push(Triplet::new(id(i, j + 1), id(i, j), -1.0));
                    t.push(Triplet::new(id(i, j), id(i, j + 1), -1.0));
                }
            }
        }
        SparseColMat::try_new_from_triplets(w * h, w * h, &t).expect("grid")
    }

    /// The plan's solve equals faer's sequential supernodal solve, for 1 and 3 right-hand sides
    /// and 2, 3 and 5 workers, on a connected grid and on one cut in two (a forest), and every
    /// supernode is in exactly one place.
    #[test]
    fn tree_parallel_solve_matches_faer() {
        for cut in [false, true] {
            let roots = check_against_faer(&grid(60, 45, cut));
            assert_eq!(roots, if cut { 2 } else { 1 });
        }
    }

    /// Returns the number of roots of the supernodal elimination forest.
    fn check_against_faer(a: &SparseColMat<usize, f64>) -> usize {
        let n = a.nrows();
        let params = faer::sparse::linalg::cholesky::CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: faer::sparse::linalg::SupernodalThreshold::FORCE_SUPERNODAL,
            ..Default::default()
        };
        let sym =
            factorize_symbolic_cholesky(a.symbolic(), Side::Lower, SymmetricOrdering::Amd, params).expect("symbolic");
        let mut values = vec![0.0; sym.len_val()];
        let mut buf =
            faer::dyn_stack::MemBuffer::new(sym.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()));
        sym.factorize_numeric_llt(
            &mut values,
            a.as_ref(),
            Side::Lower,
            Default::default(),
            Par::Seq,
            faer::dyn_stack::MemStack::new(&mut buf),
            Default::default(),
        )
        .expect("llt");
        let SymbolicCholeskyRaw::Supernodal(sn) = sym.raw() else {
            panic!("supernodal forced")
        };
        let perm = sym.perm().expect("AMD permutes").arrays().0.to_vec();
        for workers in [2, 3, 5] {
            // `Some` means a predicted speed-up of at least MIN_SPEEDUP.
            let plan = SolvePlan::new(sn, workers).expect("a grid tree splits");
            let mut seen = vec![0u8; sn.n_supernodes()];
            for &s in &plan.top {
                seen[s] += 1;
            }
            for tree in &plan.subtrees {
                assert!(tree.worker < workers);
                for s in tree.supernodes.clone() {
                    seen[s] += 1;
                }
            }
            assert!(seen.iter().all(|&c| c == 1), "every supernode exactly once");
            for k in [1, 3] {
                let b = Mat::<f64>::from_fn(n, k, |i, j| ((i * 7 + j * 13) % 17) as f64 - 8.0);
                let mut reference = b.clone();
                let mut buf = faer::dyn_stack::MemBuffer::new(sym.solve_in_place_scratch::<f64>(k, Par::Seq));
                LltRef::new(&sym, &values).solve_in_place_with_conj(
                    faer::Conj::No,
                    reference.as_mut(),
                    Par::Seq,
                    faer::dyn_stack::MemStack::new(&mut buf),
                );
                let mut x = Mat::<f64>::from_fn(n, k, |i, j| b[(perm[i], j)]);
                plan.solve_in_place(SupernodalLltRef::new(sn, &values), x.as_mut());
                let mut err = 0.0f64;
                for j in 0..k {
                    for i in 0..n {
                        err = err.max((x[(i, j)] - reference[(perm[i], j)]).abs());
                    }
                }
                let scale = reference.norm_max();
                assert!(err <= 1e-13 * scale, "workers {workers}, k {k}: {err:e}");
            }
        }
        // One worker never gets a plan.
        assert!(SolvePlan::new(sn, 1).is_none());
        (0..sn.n_supernodes())
            .filter(|&s| sn.supernode(s).pattern().is_empty())
            .count()
    }
}
