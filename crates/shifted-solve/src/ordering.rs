//! Fill-reducing orderings of a symmetric sparsity pattern for the real sparse Cholesky:
//! faer's approximate minimum degree (AMD) or our own graph nested dissection (ND), and the
//! choice between them.
//!
//! Nested dissection (George 1973) splits the adjacency graph of the pattern by a small vertex
//! separator S into two halves A and B with no edge between them, orders A, then B, then S,
//! and recurses into A and B; leaves of at most [`NdParams::leaf_size`] vertices are ordered
//! by AMD. Separators are multilevel (METIS's scheme, in `ordering/separator.rs`): the graph is coarsened
//! by heavy-edge matchings, split on the coarsest graph, and the separator refined by
//! Fiduccia–Mattheyses moves on the way back. On large meshes its factor is smaller than
//! AMD's and the gap grows with n (at 121K tetrahedral vertices: 0.81–0.84× the entries and
//! 0.55–0.65× the flops), but the dissection costs O(nnz log n) and is repaid only when the
//! factorization is expensive. So [`choose`] tries it only then ([`ND_MIN_WORK_RATIO`]) and
//! keeps the one of the two with fewer predicted flops — what CHOLMOD does by default — and
//! AMD whenever ND's factor is not smaller in both flops and entries, so no pattern gets a
//! bigger factor than before.
//!
//! Everything works from the sparsity graph alone (the crate has no mesh types), is
//! deterministic (matchings visit blocks of vertices in an order drawn from a fixed seed;
//! tries and the two halves of a split may run on two threads, their results combined in a
//! fixed order) and costs O(nnz log n) for the dissection plus O(nnz(factor)) for the column
//! counts that compare the two orderings.

mod coarsen;
mod separator;

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::amd;
use faer::sparse::linalg::cholesky::{simplicial, SymbolicCholesky, SymbolicCholeskyRaw};
use faer::sparse::SymbolicSparseColMatRef;

/// Patterns smaller than this keep AMD without trying nested dissection: below it the two
/// orderings' factors differ little in absolute terms and the dissection's cost is not repaid.
pub const ND_MIN_N: usize = 20_000;

/// Nested dissection is tried only when AMD's factorization costs at least this many flops
/// (Σ cⱼ² of its supernodes) per unit of the dissection's own work, nnz(A)·log₂ n: the
/// dissection is paid once per pattern, the saving on every factorization and solve, and a
/// caller with a single K_t f must not get slower. Measured on a 2-core box (docs/BENCHMARKS.md,
/// "Volumes", 2026-12-06): ratio 578 on the 121K armadillo (ND 0.7 s; one fast-path K_t f
/// 5–9 % faster with ND, one backward-Euler solve 45 % slower), 747 on the 655K icosphere (ND
/// 2.0 s; the fast path's K_t f 23–30 % faster once prepared, but one call slower by the
/// dissection), 5054 on the 1M monkey (ND 8.9 s against a 36 s AMD factorization: the fast
/// path 1.3× faster end to end). The threshold keeps both smaller cases on AMD.
pub const ND_MIN_WORK_RATIO: f64 = 2000.0;

/// Large three-dimensional patterns — at least this many rows and [`ND_EAGER_MIN_DEGREE`]
/// entries per column — compute faer's AMD ordering and the dissection **side by side** (one
/// core each) instead of one after the other, and run one symbolic analysis, of the ordering
/// kept ([`choose_eager`]). At this size a tetrahedral pencil's work ratio is far above
/// [`ND_MIN_WORK_RATIO`] (5054 at 1M vertices; it grows like n / log n), so the dissection is
/// almost never wasted; below it the sequential choice keeps a mid-size volume from paying for
/// a dissection AMD would win (121K: ratio 578). At 1M tetrahedral vertices the fast path's
/// preparation went from 16.4–17.1 s to 13.0 s (docs/BENCHMARKS.md, "Volumes").
pub const ND_EAGER_MIN_N: usize = 400_000;

/// Entries per column (of the lower triangle with the diagonal) of a pattern treated as
/// three-dimensional by [`ND_EAGER_MIN_N`]: a P1 tetrahedral pencil has about 8 (a vertex has
/// about 14 neighbours), a triangle mesh about 4.
pub const ND_EAGER_MIN_DEGREE: f64 = 6.0;

/// Bisections tried at the first levels of the dissection (the best separator is kept): the top
/// separators matter most for the fill, and the rest is one try each.
const TOP_TRIES: [usize; 2] = [3, 2];

/// Below this size the two halves of a split are ordered on one thread.
const PARALLEL_MIN_N: usize = 20_000;

/// Parameters of [`nested_dissection`].
#[derive(Clone, Copy, Debug)]
pub struct NdParams {
    /// Parts of at most this many vertices are not split further but ordered by AMD.
    pub leaf_size: usize,
    /// Largest side of a split as a fraction of the part's vertices (balance bound of the
    /// separator refinement).
    pub max_side: f64,
}

impl Default for NdParams {
    fn default() -> Self {
        Self {
            leaf_size: 200,
            // Looser than an even split: smaller separators, measured less fill on tetrahedra.
            max_side: 0.7,
        }
    }
}

/// The fill-reducing ordering a Cholesky analysis uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FillOrdering {
    /// faer's approximate minimum degree.
    Amd,
    /// Our graph nested dissection ([`nested_dissection`]).
    NestedDissection,
}

/// Size of a Cholesky factor predicted from its column counts cⱼ (each including the
/// diagonal) — no numeric work.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FillStats {
    /// Σ cⱼ: stored entries of the factor L (simplicial; a supernodal factor stores a little
    /// more).
    pub entries: u64,
    /// Σ cⱼ²: the multiply-adds of the factorization, up to lower-order terms.
    pub flops: f64,
}

/// A permutation as faer takes it: `fwd[k]` is the original index eliminated k-th and
/// `inv[fwd[k]] = k`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Permutation {
    /// Original index of each new position.
    pub fwd: Vec<usize>,
    /// New position of each original index.
    pub inv: Vec<usize>,
}

impl Permutation {
    fn from_fwd(fwd: Vec<usize>) -> Self {
        let mut inv = vec![0; fwd.len()];
        for (k, &v) in fwd.iter().enumerate() {
            inv[v] = k;
        }
        Self { fwd, inv }
    }
}

/// The adjacency graph of a symmetric pattern: compressed rows without the diagonal, each
/// neighbour list sorted, every edge stored in both directions.
#[derive(Clone, Debug, Default)]
pub(crate) struct Graph {
    xadj: Vec<usize>,
    adj: Vec<u32>,
}

impl Graph {
    /// The graph of `pattern` + `patternᵀ` (either triangle or both may be stored).
    ///
    /// # Panics
    /// If the pattern is not square or has more than `u32::MAX` rows (callers check).
    pub(crate) fn from_pattern(pattern: SymbolicSparseColMatRef<'_, usize>) -> Self {
        let n = pattern.nrows();
        assert!(n == pattern.ncols() && u32::try_from(n).is_ok());
        let mut degree = vec![0usize; n + 1];
        for j in 0..n {
            for &i in pattern.row_idx_of_col_raw(j) {
                if i != j {
                    degree[i] += 1;
                    degree[j] += 1;
                }
            }
        }
        let mut xadj = vec![0usize; n + 1];
        for v in 0..n {
            xadj[v + 1] = xadj[v] + degree[v];
        }
        let mut fill = xadj[..n].to_vec();
        let mut adj = vec![0u32; xadj[n]];
        for j in 0..n {
            for &i in pattern.row_idx_of_col_raw(j) {
                if i != j {
                    adj[fill[i]] = j as u32;
                    fill[i] += 1;
                    adj[fill[j]] = i as u32;
                    fill[j] += 1;
                }
            }
        }
        // Sort and deduplicate every list in place, compacting as we go.
        let mut out = 0;
        let mut start = 0;
        for v in 0..n {
            let end = xadj[v + 1];
            let list = &mut adj[start..end];
            list.sort_unstable();
            let begin = out;
            let mut last = u32::MAX;
            for k in start..end {
                let u = adj[k];
                if u != last {
                    adj[out] = u;
                    out += 1;
                    last = u;
                }
            }
            xadj[v] = begin;
            start = end;
        }
        xadj[n] = out;
        adj.truncate(out);
        Self { xadj, adj }
    }

    pub(crate) fn n(&self) -> usize {
        self.xadj.len().saturating_sub(1)
    }

    fn n_edges(&self) -> usize {
        self.adj.len()
    }

    pub(crate) fn neighbours(&self, v: usize) -> &[u32] {
        &self.adj[self.xadj[v]..self.xadj[v + 1]]
    }

    /// The induced subgraphs of the vertex classes `label[v] < n_parts` (`u32::MAX`: left
    /// out), each with the map from its vertices to ours, in one pass over the edges.
    fn split(&self, label: &[u32], n_parts: usize) -> Vec<(Graph, Vec<u32>)> {
        let mut local = vec![0u32; self.n()];
        let mut parts: Vec<(Graph, Vec<u32>)> = (0..n_parts)
            .map(|_| {
                (
                    Graph {
                        xadj: vec![0],
                        adj: Vec::new(),
                    },
                    Vec::new(),
                )
            })
            .collect();
        for (v, &p) in label.iter().enumerate() {
            if let Some(part) = parts.get_mut(p as usize) {
                local[v] = part.1.len() as u32;
                part.1.push(v as u32);
            }
        }
        for (g, ids) in &mut parts {
            g.xadj.reserve(ids.len());
            for &v in ids.iter() {
                let p = label[v as usize];
                g.adj.extend(
                    self.neighbours(v as usize)
                        .iter()
                        .filter(|&&u| label[u as usize] == p)
                        .map(|&u| local[u as usize]),
                );
                g.xadj.push(g.adj.len());
            }
        }
        parts
    }

    /// Connected components: (count, label of each vertex), numbered by their smallest vertex.
    fn components(&self) -> (usize, Vec<u32>) {
        let n = self.n();
        let mut label = vec![u32::MAX; n];
        let mut queue = Vec::new();
        let mut count = 0u32;
        for s in 0..n {
            if label[s] != u32::MAX {
                continue;
            }
            label[s] = count;
            queue.clear();
            queue.push(s as u32);
            let mut head = 0;
            while head < queue.len() {
                let v = queue[head] as usize;
                head += 1;
                for &u in self.neighbours(v) {
                    if label[u as usize] == u32::MAX {
                        label[u as usize] = count;
                        queue.push(u);
                    }
                }
            }
            count += 1;
        }
        (count as usize, label)
    }
}

/// Nested-dissection ordering of the symmetric pattern `pattern` (either triangle or both
/// stored; the diagonal is ignored), post-ordered along its elimination tree so that the
/// supernodes of the factor are contiguous.
///
/// Returns `None` when the pattern is not square or has more than `u32::MAX` rows.
pub fn nested_dissection(pattern: SymbolicSparseColMatRef<'_, usize>, params: NdParams) -> Option<Permutation> {
    if pattern.nrows() != pattern.ncols() || u32::try_from(pattern.nrows()).is_err() {
        return None;
    }
    let graph = Graph::from_pattern(pattern);
    Some(nested_dissection_of(&graph, params).0)
}

/// [`nested_dissection`] on a graph, with the predicted fill of the ordering.
pub(crate) fn nested_dissection_of(graph: &Graph, params: NdParams) -> (Permutation, FillStats) {
    let ids: Vec<u32> = (0..graph.n() as u32).collect();
    let order = dissect(graph, &ids, &params, 0);
    debug_assert_eq!(order.len(), graph.n());
    let perm = Permutation::from_fwd(order.into_iter().map(|v| v as usize).collect());
    let (etree, stats) = elimination_tree(graph, &perm);
    (postorder(perm, &etree), stats)
}

/// The order of the vertices of `g` (named by `ids`): the two halves of a separator each
/// dissected in turn, then the separator; components one after the other.
fn dissect(g: &Graph, ids: &[u32], params: &NdParams, depth: usize) -> Vec<u32> {
    let n = g.n();
    if n <= params.leaf_size.max(3) {
        return leaf_order(g, ids);
    }
    let (n_components, label) = g.components();
    if n_components > 1 {
        let mut order = Vec::with_capacity(n);
        for (sub, map) in g.split(&label, n_components) {
            let sub_ids: Vec<u32> = map.iter().map(|&v| ids[v as usize]).collect();
            order.extend(dissect(&sub, &sub_ids, params, depth));
        }
        return order;
    }
    let tries = TOP_TRIES.get(depth).copied().unwrap_or(1);
    let Some(side) = separator::bisect(g, params.max_side, tries) else {
        return leaf_order(g, ids);
    };
    let label: Vec<u32> = side
        .iter()
        .map(|&s| if s < 2 { u32::from(s) } else { u32::MAX })
        .collect();
    let mut halves = g.split(&label, 2);
    let (gb, mb) = halves.pop().unwrap_or_default();
    let (ga, ma) = halves.pop().unwrap_or_default();
    let ids_a: Vec<u32> = ma.iter().map(|&v| ids[v as usize]).collect();
    let ids_b: Vec<u32> = mb.iter().map(|&v| ids[v as usize]).collect();
    let (mut order, order_b) = if n >= PARALLEL_MIN_N {
        rayon::join(
            || dissect(&ga, &ids_a, params, depth + 1),
            || dissect(&gb, &ids_b, params, depth + 1),
        )
    } else {
        (
            dissect(&ga, &ids_a, params, depth + 1),
            dissect(&gb, &ids_b, params, depth + 1),
        )
    };
    order.reserve(n - order.len());
    order.extend(order_b);
    order.extend(side.iter().zip(ids).filter(|(&s, _)| s == 2).map(|(_, &id)| id));
    order
}

/// AMD order of a small part (faer's `amd` on its own pattern).
fn leaf_order(g: &Graph, ids: &[u32]) -> Vec<u32> {
    let n = g.n();
    if n <= 2 || g.n_edges() == 0 {
        return ids.to_vec();
    }
    let col_ptr: Vec<usize> = g.xadj.clone();
    let row_idx: Vec<usize> = g.adj.iter().map(|&u| u as usize).collect();
    let pattern = SymbolicSparseColMatRef::new_checked(n, n, &col_ptr, None, &row_idx);
    let mut fwd = vec![0usize; n];
    let mut inv = vec![0usize; n];
    let mut buf = MemBuffer::new(amd::order_scratch::<usize>(n, row_idx.len()));
    match amd::order(
        &mut fwd,
        &mut inv,
        pattern,
        amd::Control::default(),
        MemStack::new(&mut buf),
    ) {
        Ok(_) => fwd.iter().map(|&v| ids[v]).collect(),
        // AMD fails only on index overflow, impossible for a leaf; the given order is valid.
        Err(_) => ids.to_vec(),
    }
}

/// Elimination tree (parent of each column of the permuted matrix, `None` for a root) and the
/// predicted fill of `graph` in the order `perm`.
fn elimination_tree(graph: &Graph, perm: &Permutation) -> (Vec<Option<usize>>, FillStats) {
    let n = graph.n();
    // The upper triangle of P A Pᵀ: column j holds the rows inv[u] < j of its vertex's
    // neighbours (faer's column counts read the upper triangle only).
    let mut col_ptr = Vec::with_capacity(n + 1);
    col_ptr.push(0usize);
    let mut row_idx = Vec::with_capacity(graph.n_edges() / 2);
    for (j, &v) in perm.fwd.iter().enumerate() {
        row_idx.extend(
            graph
                .neighbours(v)
                .iter()
                .map(|&u| perm.inv[u as usize])
                .filter(|&i| i < j),
        );
        col_ptr.push(row_idx.len());
    }
    let upper = SymbolicSparseColMatRef::new_unsorted_checked(n, n, &col_ptr, None, &row_idx);
    let mut etree = vec![0isize; n];
    let mut counts = vec![0usize; n];
    let mut buf = MemBuffer::new(simplicial::prefactorize_symbolic_cholesky_scratch::<usize>(
        n,
        row_idx.len(),
    ));
    simplicial::prefactorize_symbolic_cholesky(&mut etree, &mut counts, upper, MemStack::new(&mut buf));
    let stats = FillStats {
        entries: counts.iter().map(|&c| c as u64).sum(),
        flops: counts.iter().map(|&c| (c as f64) * (c as f64)).sum(),
    };
    let parents = etree.iter().map(|&p| usize::try_from(p).ok()).collect();
    (parents, stats)
}

/// `perm` followed by a depth-first post-order of its elimination tree (children in
/// increasing order): the same factor, with every subtree's columns contiguous.
fn postorder(perm: Permutation, parent: &[Option<usize>]) -> Permutation {
    let n = parent.len();
    let mut first_child = vec![usize::MAX; n];
    let mut next_sibling = vec![usize::MAX; n];
    // Children are linked in decreasing order so that each list reads increasing.
    for j in (0..n).rev() {
        if let Some(p) = parent[j] {
            next_sibling[j] = first_child[p];
            first_child[p] = j;
        }
    }
    let mut fwd = Vec::with_capacity(n);
    let mut stack = Vec::new();
    for root in (0..n).filter(|&j| parent[j].is_none()) {
        stack.push((root, false));
        while let Some((j, expanded)) = stack.pop() {
            if expanded {
                fwd.push(perm.fwd[j]);
                continue;
            }
            stack.push((j, true));
            // Push children in reverse so that the smallest is visited first.
            let mut children = Vec::new();
            let mut c = first_child[j];
            while c != usize::MAX {
                children.push(c);
                c = next_sibling[c];
            }
            stack.extend(children.into_iter().rev().map(|c| (c, false)));
        }
    }
    Permutation::from_fwd(fwd)
}

/// Predicted fill of the Cholesky factor of `pattern` in the order `perm`.
///
/// # Panics
/// If the pattern is not square, has more than `u32::MAX` rows, or `perm` has another size.
pub fn fill_stats(pattern: SymbolicSparseColMatRef<'_, usize>, perm: &Permutation) -> FillStats {
    let graph = Graph::from_pattern(pattern);
    assert_eq!(perm.fwd.len(), graph.n());
    elimination_tree(&graph, perm).1
}

/// The dissection's work unit nnz(A)·log₂ n of [`ND_MIN_WORK_RATIO`].
pub fn work_unit(pattern: SymbolicSparseColMatRef<'_, usize>) -> f64 {
    pattern.compute_nnz() as f64 * (pattern.nrows().max(2) as f64).log2()
}

/// The outcome of [`choose`]: the chosen ordering, its permutation when it is not faer's own
/// AMD, and the predicted fill of the candidates.
#[derive(Clone, Debug)]
pub struct OrderingChoice {
    /// The ordering kept.
    pub chosen: FillOrdering,
    /// The nested-dissection permutation when it was chosen.
    pub permutation: Option<Permutation>,
    /// The fill with AMD: from the column counts when ND was tried, else from the supernodes
    /// of faer's analysis (an upper bound if faer relaxed them).
    pub amd: FillStats,
    /// The fill with ND (`None` when it was not tried).
    pub nd: Option<FillStats>,
}

/// The fill of a symbolic factor read from its structure in O(n): the column counts of a
/// simplicial factor, or of the supernodes (each column of a supernode of width w with r
/// rows below it has w − k + r entries).
pub fn symbolic_stats(symbolic: &SymbolicCholesky<usize>) -> FillStats {
    let mut stats = FillStats { entries: 0, flops: 0.0 };
    let mut add = |c: usize| {
        stats.entries += c as u64;
        stats.flops += (c as f64) * (c as f64);
    };
    match symbolic.raw() {
        SymbolicCholeskyRaw::Simplicial(s) => s.col_ptr().windows(2).for_each(|w| add(w[1] - w[0])),
        SymbolicCholeskyRaw::Supernodal(s) => {
            let (begin, end, rows) = (s.supernode_begin(), s.supernode_end(), s.col_ptr_for_row_idx());
            for k in 0..s.n_supernodes() {
                let (width, below) = (end[k] - begin[k], rows[k + 1] - rows[k]);
                (0..width).for_each(|j| add(width - j + below));
            }
        }
    }
    stats
}

/// Chooses between faer's AMD analysis `amd` of `pattern` and nested dissection. ND is tried
/// only from [`ND_MIN_N`] rows and when AMD's factorization is expensive against the cost of
/// the dissection ([`ND_MIN_WORK_RATIO`]; CHOLMOD tries METIS on a test of the same kind), so
/// that other patterns pay O(n) for the choice; it is kept only when its factor needs fewer
/// flops and no more entries than AMD's, from the column counts of both.
pub fn choose(pattern: SymbolicSparseColMatRef<'_, usize>, amd: &SymbolicCholesky<usize>) -> OrderingChoice {
    choose_with(pattern, amd, ND_MIN_WORK_RATIO)
}

/// [`choose`] with the threshold `min_work_ratio` in place of [`ND_MIN_WORK_RATIO`].
pub(crate) fn choose_with(
    pattern: SymbolicSparseColMatRef<'_, usize>,
    amd: &SymbolicCholesky<usize>,
    min_work_ratio: f64,
) -> OrderingChoice {
    let n = pattern.nrows();
    let amd_stats = symbolic_stats(amd);
    let mut choice = OrderingChoice {
        chosen: FillOrdering::Amd,
        permutation: None,
        amd: amd_stats,
        nd: None,
    };
    let dense_enough = amd_stats.flops >= min_work_ratio * work_unit(pattern);
    let Some(amd_perm) = amd.perm() else { return choice };
    if n < ND_MIN_N || !dense_enough || n != pattern.ncols() || u32::try_from(n).is_err() {
        return choice;
    }
    let (fwd, inv) = amd_perm.arrays();
    let amd_perm = Permutation {
        fwd: fwd.to_vec(),
        inv: inv.to_vec(),
    };
    let graph = Graph::from_pattern(pattern);
    let (amd_stats, (perm, nd)) = rayon::join(
        || elimination_tree(&graph, &amd_perm).1,
        || nested_dissection_of(&graph, NdParams::default()),
    );
    let better = nd.flops < amd_stats.flops && nd.entries <= amd_stats.entries;
    choice.amd = amd_stats;
    choice.nd = Some(nd);
    if better {
        choice.chosen = FillOrdering::NestedDissection;
        choice.permutation = Some(perm);
    }
    choice
}

/// Whether `pattern` takes the side-by-side choice of [`choose_eager`] (see [`ND_EAGER_MIN_N`]).
pub fn eager(pattern: SymbolicSparseColMatRef<'_, usize>) -> bool {
    let n = pattern.nrows();
    if n < ND_EAGER_MIN_N || n != pattern.ncols() || u32::try_from(n).is_err() {
        return false;
    }
    // Lower triangle with the diagonal, whichever triangles the pattern stores.
    let lower: usize = (0..n)
        .map(|j| pattern.row_idx_of_col_raw(j).iter().filter(|&&i| i >= j).count())
        .sum();
    lower as f64 >= ND_EAGER_MIN_DEGREE * n as f64
}

/// faer's AMD permutation of the pattern of A + Aᵀ (`None` if faer refuses it).
fn amd_permutation(pattern: SymbolicSparseColMatRef<'_, usize>) -> Option<Permutation> {
    let n = pattern.nrows();
    let (mut fwd, mut inv) = (vec![0usize; n], vec![0usize; n]);
    let mut buf = MemBuffer::new(amd::order_maybe_unsorted_scratch::<usize>(n, pattern.compute_nnz()));
    amd::order_maybe_unsorted(
        &mut fwd,
        &mut inv,
        pattern,
        amd::Control::default(),
        MemStack::new(&mut buf),
    )
    .ok()?;
    Some(Permutation { fwd, inv })
}

/// The choice of [`choose_with`] for a large three-dimensional pattern ([`eager`]): AMD's
/// ordering (with its column counts) and the dissection computed side by side, the dissection
/// kept when AMD's factorization is dense enough (`min_work_ratio`) and the dissection's factor
/// needs fewer flops and no more entries. The permutation of the ordering kept is always
/// returned (the caller runs one symbolic analysis, on it); `None` if AMD itself failed.
pub(crate) fn choose_eager(pattern: SymbolicSparseColMatRef<'_, usize>, min_work_ratio: f64) -> Option<OrderingChoice> {
    let graph = Graph::from_pattern(pattern);
    let (amd, (nd_perm, nd)) = rayon::join(
        || {
            amd_permutation(pattern).map(|perm| {
                let stats = elimination_tree(&graph, &perm).1;
                (perm, stats)
            })
        },
        || nested_dissection_of(&graph, NdParams::default()),
    );
    let (amd_perm, amd_stats) = amd?;
    let dense_enough = amd_stats.flops >= min_work_ratio * work_unit(pattern);
    let better = dense_enough && nd.flops < amd_stats.flops && nd.entries <= amd_stats.entries;
    Some(OrderingChoice {
        chosen: if better {
            FillOrdering::NestedDissection
        } else {
            FillOrdering::Amd
        },
        permutation: Some(if better { nd_perm } else { amd_perm }),
        amd: amd_stats,
        nd: Some(nd),
    })
}

#[cfg(test)]
mod tests;
