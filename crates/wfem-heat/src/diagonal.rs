//! The diagonal of a symmetric operator A that decays with graph distance on the mesh (the
//! heat-kernel matrix `K̃_t`, the Gram matrix `S_t = M K_t`), known only through products
//! `A E` with blocks of vectors: probing (Tang & Saad, NLAA 19 (2012) 485–501; docs/NUMERICS.md §4) or,
//! as a reference, n unit vectors.
//!
//! **Probing.** A greedy distance-p colouring of the mesh graph (vertices within p edges get
//! different colours) and one column per colour: `diag_j ≈ (A v_{c(j)})_j` with `v_c` the
//! indicator of colour c. The error at j is the sum of `A_jk` over the same-coloured k, all
//! more than p edges away. p is the smallest number of hops such that a sample column
//! `A e_i` has `Σ_{dist(i,k) > p} |A_ik| ≤ tol · A_ii`; the heat kernel decays like
//! e^{−d²/4t}, so p and the number of colours depend on t/h², not on n.

use crate::HeatError;
use faer::sparse::SymbolicSparseColMatRef;
use faer::Mat;

/// A block product `E ↦ A E`.
pub(crate) type BlockOperator<'a> = dyn Fn(&Mat<f64>) -> Result<Mat<f64>, HeatError> + 'a;

/// A block product for several operators at once: `P ↦ [A_0 P, A_1 P, …]`.
pub(crate) type BlockOperators<'a> = dyn FnMut(&Mat<f64>) -> Result<Vec<Mat<f64>>, HeatError> + 'a;

/// How a diagonal is computed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DiagonalMethod {
    /// Exactly (rational degree 16, rounding level), from the heat-kernel matrix on the
    /// sparsity pattern by selected inversion of one complex LDLᵀ per pole
    /// ([`shifted_solve::SelectedInversion`]): the cost of 8 factorizations per t whatever t
    /// is — no probe columns, no eigen truncation. For the diagonal of `K̃_t` and `K_t`
    /// ([`crate::HeatKernel::diagonal`], the diffusion distance); an operator whose diagonal
    /// is not on the pattern (the Gram matrix `M K_t` of the mass-weighted distance) is
    /// probed instead, with the default tolerance.
    SelectedInversion,
    /// From n unit-vector columns, exact to the kernel method's accuracy: cost grows like
    /// n × (one block application), for small meshes or as a reference.
    UnitColumns,
    /// Probing with a distance-p colouring chosen for a relative tail `tol` (see the module
    /// docs). Falls back to [`Self::UnitColumns`] when the colouring would need more than n/4
    /// colours (large t).
    Probing {
        /// Relative tail tolerance (default 1e−10).
        tol: f64,
    },
}

/// The relative tail of [`DiagonalMethod::Probing`] by default.
pub const DEFAULT_PROBING_TOL: f64 = 1e-10;

impl Default for DiagonalMethod {
    /// Selected inversion: exact at every t, and 30–300× faster than probing at 1e−6 on the
    /// TOSCA meshes (5K/28K vertices: 0.03/0.3 s per t against 1–90 s), where probing's
    /// tail estimate also let errors up to 7e−4 through.
    fn default() -> Self {
        DiagonalMethod::SelectedInversion
    }
}

wfem_base::registry! {
    DiagonalMethod as "diagonal method" {
        DiagonalMethod::SelectedInversion = DiagonalMethod::SelectedInversion => "selected-inversion" ["selinv"]:
            "selected inversion of the rational method's factors: exact at every t, no eigenpairs (default)",
        DiagonalMethod::Probing { .. } = DiagonalMethod::Probing { tol: DEFAULT_PROBING_TOL } => "probing":
            "probing with a distance-p colouring of the mesh (Tang & Saad), relative tail tol",
        DiagonalMethod::UnitColumns = DiagonalMethod::UnitColumns => "unit-columns" ["columns"]:
            "n unit columns (small meshes; a reference)",
    }
}

impl DiagonalMethod {
    /// For the column-based computation: the probing tolerance, or `None` for the n unit
    /// columns ([`Self::UnitColumns`]); [`Self::SelectedInversion`] falls back to the default
    /// probing where it does not apply.
    pub(crate) fn probe_tol(self) -> Option<f64> {
        match self {
            DiagonalMethod::Probing { tol } => Some(tol),
            DiagonalMethod::SelectedInversion => Some(DEFAULT_PROBING_TOL),
            DiagonalMethod::UnitColumns => None,
        }
    }

    pub(crate) fn validate(&self) -> Result<(), HeatError> {
        if let DiagonalMethod::Probing { tol } = *self {
            if !(tol > 0.0 && tol < 1.0) {
                return Err(HeatError::InvalidParameter {
                    name: "diagonal.tol",
                    reason: format!("{tol} is not in (0, 1)"),
                });
            }
        }
        Ok(())
    }
}

/// How a diagonal was computed.
#[derive(Clone, Debug, PartialEq)]
pub struct DiagonalReport {
    /// The method that computed the diagonal: the one asked for, or the one it gave way to
    /// where it does not apply (probing at a t where the colouring needs more than n/4 colours
    /// takes the n unit columns; selected inversion of an operator whose diagonal is not on
    /// the pattern is probed). Never silent: reports and sidecars name it.
    pub method: DiagonalMethod,
    /// Number of probe columns used (n for unit columns, 0 for selected inversion).
    pub columns: usize,
    /// Graph distance p of the colouring (`None` for unit columns and selected
    /// inversion).
    pub hops: Option<usize>,
    /// The relative tail `Σ_{dist(i,k) > p} |A_ik| / A_ii` of the sample column used to choose
    /// p: the stated error bound of every entry, relative to its own size, when the kernel's
    /// decay is uniform over the mesh (0 for unit columns and selected inversion).
    pub relative_tail: f64,
}

/// The old name of [`DiagonalReport`] (one word per meaning: results are reports).
#[deprecated(note = "renamed DiagonalReport")]
pub type DiagonalInfo = DiagonalReport;

/// The probe vectors of a diagonal: the colour of every vertex (one probe column per colour).
#[derive(Clone, Debug)]
pub(crate) struct Probes {
    colour: Vec<usize>,
    n_colours: usize,
    pub(crate) info: DiagonalReport,
}

impl Probes {
    /// The probes of `method` for an operator whose column at vertex i is `col = A e_i` (the
    /// sample that sets the colouring distance), on the mesh graph `pattern`. A colouring that
    /// would need more than `max_columns` (or n/4) colours gives up early and falls back to
    /// the n unit columns.
    pub(crate) fn new(
        pattern: SymbolicSparseColMatRef<'_, usize>,
        method: DiagonalMethod,
        i: usize,
        col: &[f64],
        max_columns: usize,
    ) -> Self {
        let n = pattern.nrows();
        let probed = method
            .probe_tol()
            .and_then(|tol| Some((tol, colouring(pattern, i, col, tol, (n / 4).min(max_columns))?)));
        match probed {
            Some((tol, (colour, n_colours, hops, relative_tail))) => Self {
                colour,
                n_colours,
                info: DiagonalReport {
                    method: DiagonalMethod::Probing { tol },
                    columns: n_colours,
                    hops: Some(hops),
                    relative_tail,
                },
            },
            None => Self {
                colour: (0..n).collect(),
                n_colours: n,
                info: DiagonalReport {
                    method: DiagonalMethod::UnitColumns,
                    columns: n,
                    hops: None,
                    relative_tail: 0.0,
                },
            },
        }
    }

    /// The diagonals of several operators sharing the probes: `apply(P)` returns one block
    /// `A_l P` per operator for a block P of probe columns (at most `block` columns).
    pub(crate) fn diagonals(
        &self,
        block: usize,
        outputs: usize,
        apply: &mut BlockOperators<'_>,
    ) -> Result<Vec<Vec<f64>>, HeatError> {
        let n = self.colour.len();
        let mut d = vec![vec![0.0; n]; outputs];
        let mut start = 0;
        while start < self.n_colours {
            let end = (start + block.max(1)).min(self.n_colours);
            let mut p = Mat::<f64>::zeros(n, end - start);
            for (v, &c) in self.colour.iter().enumerate() {
                if (start..end).contains(&c) {
                    p[(v, c - start)] = 1.0;
                }
            }
            let ys = apply(&p)?;
            for (dl, y) in d.iter_mut().zip(&ys) {
                for (v, &c) in self.colour.iter().enumerate() {
                    if (start..end).contains(&c) {
                        dl[v] = y[(v, c - start)];
                    }
                }
            }
            start = end;
        }
        Ok(d)
    }
}

/// `diag(A)` from block products `apply(E) = A E` (blocks of at most `block` columns), given
/// the sample column `col = A e_i` of vertex i and the mesh graph `pattern`.
pub(crate) fn diagonal(
    pattern: SymbolicSparseColMatRef<'_, usize>,
    method: DiagonalMethod,
    block: usize,
    i: usize,
    col: &[f64],
    apply: &BlockOperator<'_>,
) -> Result<(Vec<f64>, DiagonalReport), HeatError> {
    let probes = Probes::new(pattern, method, i, col, usize::MAX);
    let mut d = probes.diagonals(block, 1, &mut |p| Ok(vec![apply(p)?]))?;
    Ok((d.remove(0), probes.info))
}

/// Chooses p from the tail of `col = A e_i` and colours the graph at distance p.
/// Returns (colour of each vertex, number of colours, p, relative tail), or `None` when more
/// than `max_colours` colours would be needed.
fn colouring(
    pattern: SymbolicSparseColMatRef<'_, usize>,
    i: usize,
    col: &[f64],
    tol: f64,
    max_colours: usize,
) -> Option<(Vec<usize>, usize, usize, f64)> {
    let n = pattern.nrows();
    let (ptr, idx) = (pattern.col_ptr(), pattern.row_idx());
    // BFS distances from i.
    let mut dist = vec![usize::MAX; n];
    dist[i] = 0;
    let mut queue = std::collections::VecDeque::from([i]);
    let mut per_depth: Vec<f64> = Vec::new();
    let mut count_per_depth: Vec<usize> = Vec::new();
    while let Some(v) = queue.pop_front() {
        let d = dist[v];
        if per_depth.len() <= d {
            per_depth.resize(d + 1, 0.0);
            count_per_depth.resize(d + 1, 0);
        }
        per_depth[d] += col[v].abs();
        count_per_depth[d] += 1;
        for &w in &idx[ptr[v]..ptr[v + 1]] {
            if dist[w] == usize::MAX {
                dist[w] = d + 1;
                queue.push_back(w);
            }
        }
    }
    let aii = col[i].abs();
    let mut tail: f64 = per_depth.iter().skip(1).sum();
    let mut hops = 0;
    while tail > tol * aii && hops + 1 < per_depth.len() {
        hops += 1;
        tail -= per_depth[hops];
    }
    let tail = tail.max(0.0);
    if tail > tol * aii {
        return None;
    }
    // Any two vertices of the ball of radius ⌊p/2⌋ around i are within p edges of each other,
    // so they all need different colours: when that ball alone exceeds the limit, give up
    // before the colouring (which costs n × |ball(p)| and dominated a refused probe).
    let half_ball: usize = count_per_depth.iter().take(hops / 2 + 1).sum();
    if half_ball > max_colours {
        return None;
    }
    // Greedy distance-p colouring.
    let mut colour = vec![usize::MAX; n];
    let mut stamp = vec![usize::MAX; n];
    let mut used: Vec<usize> = Vec::new();
    let mut n_colours = 0;
    let mut frontier = Vec::new();
    let mut next = Vec::new();
    for v in 0..n {
        used.clear();
        stamp[v] = v;
        frontier.clear();
        frontier.push(v);
        for _ in 0..hops {
            next.clear();
            for &u in &frontier {
                for &w in &idx[ptr[u]..ptr[u + 1]] {
                    if stamp[w] != v {
                        stamp[w] = v;
                        next.push(w);
                        if colour[w] != usize::MAX {
                            used.push(colour[w]);
                        }
                    }
                }
            }
            std::mem::swap(&mut frontier, &mut next);
        }
        used.sort_unstable();
        used.dedup();
        let c = used
            .iter()
            .enumerate()
            .find(|(k, &u)| *k != u)
            .map_or(used.len(), |(k, _)| k);
        colour[v] = c;
        n_colours = n_colours.max(c + 1);
        if n_colours > max_colours {
            return None;
        }
    }
    Some((colour, n_colours, hops, if aii > 0.0 { tail / aii } else { 0.0 }))
}
