//! Diffusion distances (paper, Sect. 3, Eq. (18) and the display after Eq. (20); NUMERICS §1)
//! through the rational Chebyshev method, with the factors of one t reused for every
//! right-hand side.
//!
//! Both distances are `d²(i, j) = (e_i − e_j)ᵀ A (e_i − e_j) = A_ii − 2A_ij + A_jj` for a
//! symmetric positive (semi)definite n × n matrix A:
//!
//! * [`DistanceKind::Wfem`]: `A = S_t = B K_t = B X D_t Xᵀ B`, the Gram matrix of the
//!   embeddings `h_i = K_{t/2} e_i` (Eq. (18b)): `d²(i,j) = ‖h_i − h_j‖_B²
//!   = Σ_k e^{−λ_k t} ((Bx_k)_i − (Bx_k)_j)²`. The paper's display after Eq. (20) writes this
//!   as `K_{t/2}(i,i) − 2K_{t/2}(i,j) + K_{t/2}(j,j)`; by Eq. (18b) the correct entries are those
//!   of `S_t = B K_t` (not of K_{t/2}, which is not even symmetric).
//! * [`DistanceKind::Linear`]: the standard (linear FEM) diffusion distance
//!   `d_t²(i,j) = Σ_k e^{−2λ_k t} (x_k(i) − x_k(j))²` with `A = H̃_{2t}`, where
//!   `H̃_s = K_s B⁻¹ = X D_s Xᵀ` is the heat-kernel matrix (the paper's linear kernel
//!   `K̃_s` with the eigenvectors of (L, B)). Its columns need no B-solve:
//!   `H̃_s ≈ c0 B⁻¹ + 2 Re Σ_j c_j (sL − z_j B)⁻¹` (NUMERICS §1); the tiny `c0 B⁻¹` term
//!   (|c0| = E_n) is included through one sparse Cholesky of B. (The paper's "linear
//!   diffusion distance" `‖g_i − g_j‖_B²` uses the RKHS kernel `H_t = X D_{−t} Xᵀ`, whose
//!   weights e^{+λt} grow with λ; it is an anti-diffusion quantity, available only truncated,
//!   see [`crate::embedding_g`]. By Eq. (18a) it equals `H_t(i,i) − 2H_t(i,j) + H_t(j,j)`; the
//!   display after Eq. (20) prints `H_{t/2}` entries, another index slip.)
//!
//! Cost: [`DiffusionDistance::pairs`] needs one column `A(e_i − e_j)` per pair, solved in blocks
//! of columns with the factors of t reused. A whole row `d(i, ·)` needs the column `A e_i` and
//! the diagonal of A; the diagonal is computed once (by probing with a distance-p colouring of
//! the mesh graph, or exactly from n unit-vector columns, see [`DiagonalMethod`]) and cached,
//! so every further row costs one column.

use crate::algebra::unit_columns;
use crate::kernel::check_time;
use crate::sparse::{spmm_sym, CholeskyPattern, SpdFactor};
use crate::HeatError;
use faer::sparse::SparseColMat;
use faer::Mat;
use mesh_fem::FemOperators;
use shifted_solve::{Backend, RationalApprox, RationalFactors, ShiftedSolver};
use std::sync::OnceLock;

/// Which diffusion distance (see the module documentation).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum DistanceKind {
    /// wFEM: `‖h_i − h_j‖_B²` with `h_i = K_{t/2} e_i`, i.e. `A = S_t = B K_t` (Eq. (18b)).
    #[default]
    Wfem,
    /// Linear FEM / standard: `Σ_k e^{−2λ_k t}(x_k(i) − x_k(j))²`, i.e. `A = H̃_{2t} = K_{2t}B⁻¹`.
    Linear,
}

/// Options of [`DiffusionDistance::new`].
#[derive(Clone, Debug, PartialEq)]
pub struct DistanceParams {
    /// Degree of the rational approximation (default [`shifted_solve::DEFAULT_DEGREE`]).
    pub degree: usize,
    /// How the shifted systems are solved (default: direct complex-symmetric LDLᵀ).
    pub backend: Backend,
    /// Number of right-hand sides per multi-RHS solve (default 64).
    pub block: usize,
    /// How the diagonal of A is computed for whole rows (default probing, tol 1e−10).
    pub diagonal: DiagonalMethod,
}

/// How [`DiffusionDistance::diagonal`] computes `diag(A)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DiagonalMethod {
    /// Exactly (to the rational error) from n unit-vector columns: cost grows like n × (one
    /// multi-RHS solve), for small meshes or as a reference.
    Exact,
    /// Probing (Tang & Saad, NLAA 19 (2012) 485–501; NUMERICS §4): a greedy distance-p colouring
    /// of the mesh graph (vertices within p edges get different colours), one column per colour,
    /// `diag_j ≈ (A v_{c(j)})_j` with `v_c` the indicator of colour c. The error at j is the sum
    /// of `A_jk` over same-coloured k, all more than p edges away. p is the smallest number of
    /// hops such that the column `A e_i` of the queried vertex i has
    /// `Σ_{dist(i,k) > p} |A_ik| ≤ tol · A_ii` (the heat kernel decays like e^{−d²/4t}, so p
    /// and the number of colours depend on t/h², not on n). Falls back to [`Self::Exact`] when
    /// the colouring would need more than n/4 colours (large t).
    Probing {
        /// Relative tail tolerance (default 1e−10).
        tol: f64,
    },
}

/// How the cached diagonal was computed.
#[derive(Clone, Debug, PartialEq)]
pub struct DiagonalInfo {
    /// Number of probe columns used (n for the exact method).
    pub columns: usize,
    /// Graph distance p of the colouring (`None` for the exact method).
    pub hops: Option<usize>,
    /// The relative tail `Σ_{dist(i,k) > p} |A_ik| / A_ii` of the column used to choose p.
    pub relative_tail: f64,
}

impl Default for DistanceParams {
    fn default() -> Self {
        Self {
            degree: shifted_solve::DEFAULT_DEGREE,
            backend: Backend::DirectLdlt,
            block: 64,
            diagonal: DiagonalMethod::Probing { tol: 1e-10 },
        }
    }
}

/// Diffusion distances of one kind at one time t, with the rational factors of t (or 2t)
/// built once and reused for every query.
#[derive(Debug)]
pub struct DiffusionDistance {
    kind: DistanceKind,
    t: f64,
    block: usize,
    mass: SparseColMat<usize, f64>,
    factors: RationalFactors,
    c0: f64,
    mass_factor: Option<SpdFactor>,
    diagonal_method: DiagonalMethod,
    diagonal: OnceLock<(Vec<f64>, DiagonalInfo)>,
}

impl DiffusionDistance {
    /// Factors the shifted systems `sL − z_j B` of every pole at s = t (wFEM) or s = 2t
    /// (linear), with the stiffness L and consistent mass B of `ops`.
    ///
    /// # Errors
    /// [`HeatError::InvalidTime`], [`HeatError::InvalidParameter`] (degree, block),
    /// [`HeatError::Solve`] (operator validation, factorization),
    /// [`HeatError::NotPositiveDefinite`] (B, linear kind).
    pub fn new(ops: &FemOperators, kind: DistanceKind, t: f64, params: &DistanceParams) -> Result<Self, HeatError> {
        check_time(t)?;
        if let DiagonalMethod::Probing { tol } = params.diagonal {
            if !(tol > 0.0 && tol < 1.0) {
                return Err(HeatError::InvalidParameter {
                    name: "diagonal.tol",
                    reason: format!("{tol} is not in (0, 1)"),
                });
            }
        }
        if params.block == 0 {
            return Err(HeatError::InvalidParameter {
                name: "block",
                reason: "must be positive".into(),
            });
        }
        let approx = RationalApprox::cram(params.degree)?;
        let solver = ShiftedSolver::new(ops.stiffness.as_ref(), ops.mass.as_ref(), params.backend)?;
        let s = match kind {
            DistanceKind::Wfem => t,
            DistanceKind::Linear => 2.0 * t,
        };
        check_time(s)?;
        let factors = solver.factor(approx, s)?;
        let mass_factor = match kind {
            DistanceKind::Wfem => None,
            DistanceKind::Linear => {
                let pattern = CholeskyPattern::new(&ops.mass)?;
                Some(pattern.factor(&ops.mass, || "mass matrix B".into())?)
            }
        };
        Ok(Self {
            kind,
            t,
            block: params.block,
            mass: ops.mass.clone(),
            factors,
            c0: approx.c0,
            mass_factor,
            diagonal_method: params.diagonal,
            diagonal: OnceLock::new(),
        })
    }

    /// The kind of distance.
    pub fn kind(&self) -> DistanceKind {
        self.kind
    }

    /// The diffusion time t.
    pub fn t(&self) -> f64 {
        self.t
    }

    /// Number of vertices n.
    pub fn n(&self) -> usize {
        self.mass.nrows()
    }

    /// `A E` for an n × m block E: `B r(tB⁻¹L) E` (wFEM, A = S_t) or
    /// `c0 B⁻¹E + 2 Re Σ_j c_j (2tL − z_j B)⁻¹ E` (linear, A = H̃_{2t}), in blocks of columns.
    ///
    /// # Errors
    /// [`HeatError::LengthMismatch`], [`HeatError::Solve`].
    pub fn gram_apply(&self, e: faer::MatRef<'_, f64>) -> Result<Mat<f64>, HeatError> {
        let n = self.n();
        if e.nrows() != n {
            return Err(HeatError::LengthMismatch {
                expected: n,
                found: e.nrows(),
            });
        }
        let m = e.ncols();
        let mut out = Mat::<f64>::zeros(n, m);
        let mut start = 0;
        while start < m {
            let end = (start + self.block).min(m);
            let blk = e.get(.., start..end);
            let y = match self.kind {
                DistanceKind::Wfem => {
                    let (k, _) = self.factors.apply(blk)?;
                    spmm_sym(&self.mass, k.as_ref())
                }
                DistanceKind::Linear => {
                    let (mut y, _) = self.factors.apply_resolvent(blk)?;
                    if let Some(mf) = &self.mass_factor {
                        let mut binv = blk.to_owned();
                        mf.solve_in_place(binv.as_mut());
                        y += faer::Scale(self.c0) * &binv;
                    }
                    y
                }
            };
            out.as_mut().get_mut(.., start..end).copy_from(&y);
            start = end;
        }
        Ok(out)
    }

    /// Squared distances `d²(i, j) = (e_i − e_j)ᵀ A (e_i − e_j)` for the given pairs, one
    /// column `A(e_i − e_j)` per pair (no diagonal needed; free of the cancellation of
    /// `A_ii − 2A_ij + A_jj`). Tiny negative values from rounding are clamped to 0.
    ///
    /// # Errors
    /// [`HeatError::VertexOutOfRange`]; as [`Self::gram_apply`].
    pub fn pairs_squared(&self, pairs: &[(usize, usize)]) -> Result<Vec<f64>, HeatError> {
        let n = self.n();
        for &(i, j) in pairs {
            for index in [i, j] {
                if index >= n {
                    return Err(HeatError::VertexOutOfRange { index, n_vertices: n });
                }
            }
        }
        let mut e = Mat::<f64>::zeros(n, pairs.len());
        for (c, &(i, j)) in pairs.iter().enumerate() {
            e[(i, c)] += 1.0;
            e[(j, c)] -= 1.0;
        }
        let y = self.gram_apply(e.as_ref())?;
        Ok(pairs
            .iter()
            .enumerate()
            .map(|(c, &(i, j))| (y[(i, c)] - y[(j, c)]).max(0.0))
            .collect())
    }

    /// Distances `d(i, j)` for the given pairs (square roots of [`Self::pairs_squared`]).
    ///
    /// # Errors
    /// As [`Self::pairs_squared`].
    pub fn pairs(&self, pairs: &[(usize, usize)]) -> Result<Vec<f64>, HeatError> {
        Ok(self.pairs_squared(pairs)?.into_iter().map(f64::sqrt).collect())
    }

    /// The diagonal of A (`S_t(j,j)` or `H̃_{2t}(j,j)`, the latter being the heat kernel
    /// signature HKS_{2t}), by the [`DiagonalMethod`] of the parameters (probing chooses its
    /// colouring from the column of vertex 0). Computed on the first call (of this or of
    /// [`Self::row_squared`]) and cached; [`Self::diagonal_info`] says how.
    ///
    /// # Errors
    /// As [`Self::gram_apply`].
    pub fn diagonal(&self) -> Result<&[f64], HeatError> {
        if let Some((d, _)) = self.diagonal.get() {
            return Ok(d);
        }
        let e = unit_columns(self.n(), &[0])?;
        let y = self.gram_apply(e.as_ref())?;
        let col: Vec<f64> = y.col(0).iter().copied().collect();
        self.diagonal_from(0, &col)
    }

    /// How the cached diagonal was computed (`None` before the first row or diagonal).
    pub fn diagonal_info(&self) -> Option<&DiagonalInfo> {
        self.diagonal.get().map(|(_, info)| info)
    }

    fn diagonal_from(&self, i: usize, col: &[f64]) -> Result<&[f64], HeatError> {
        if let Some((d, _)) = self.diagonal.get() {
            return Ok(d);
        }
        let n = self.n();
        let probed = match self.diagonal_method {
            DiagonalMethod::Exact => None,
            DiagonalMethod::Probing { tol } => self.probe_colouring(i, col, tol),
        };
        let (d, info) = match probed {
            Some((colour, n_colours, hops, relative_tail)) => {
                let mut d = vec![0.0; n];
                let mut start = 0;
                while start < n_colours {
                    let end = (start + self.block).min(n_colours);
                    let mut p = Mat::<f64>::zeros(n, end - start);
                    for (v, &c) in colour.iter().enumerate() {
                        if (start..end).contains(&c) {
                            p[(v, c - start)] = 1.0;
                        }
                    }
                    let y = self.gram_apply(p.as_ref())?;
                    for (v, &c) in colour.iter().enumerate() {
                        if (start..end).contains(&c) {
                            d[v] = y[(v, c - start)];
                        }
                    }
                    start = end;
                }
                (
                    d,
                    DiagonalInfo {
                        columns: n_colours,
                        hops: Some(hops),
                        relative_tail,
                    },
                )
            }
            None => {
                let mut d = vec![0.0; n];
                let mut start = 0;
                while start < n {
                    let end = (start + self.block).min(n);
                    let idx: Vec<usize> = (start..end).collect();
                    let e = unit_columns(n, &idx)?;
                    let y = self.gram_apply(e.as_ref())?;
                    for (c, &v) in idx.iter().enumerate() {
                        d[v] = y[(v, c)];
                    }
                    start = end;
                }
                (
                    d,
                    DiagonalInfo {
                        columns: n,
                        hops: None,
                        relative_tail: 0.0,
                    },
                )
            }
        };
        Ok(&self.diagonal.get_or_init(|| (d, info)).0)
    }

    /// Chooses p from the tail of `col = A e_i` and colours the graph at distance p.
    /// Returns (colour of each vertex, number of colours, p, relative tail), or `None` when
    /// more than n/4 colours would be needed.
    fn probe_colouring(&self, i: usize, col: &[f64], tol: f64) -> Option<(Vec<usize>, usize, usize, f64)> {
        let n = self.n();
        let sym = self.mass.symbolic();
        let (ptr, idx) = (sym.col_ptr(), sym.row_idx());
        // BFS distances from i.
        let mut dist = vec![usize::MAX; n];
        dist[i] = 0;
        let mut queue = std::collections::VecDeque::from([i]);
        let mut per_depth: Vec<f64> = Vec::new();
        while let Some(v) = queue.pop_front() {
            let d = dist[v];
            if per_depth.len() <= d {
                per_depth.resize(d + 1, 0.0);
            }
            per_depth[d] += col[v].abs();
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
        // Greedy distance-p colouring.
        let max_colours = n / 4;
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

    /// Squared distances from vertex i to every vertex,
    /// `d²(i, j) = A_ii − 2A_ij + A_jj` (clamped at 0), from the column `A e_i` and the cached
    /// [`Self::diagonal`]. The first call pays for the diagonal (a number of probe columns that
    /// depends on t/h², not on n, with [`DiagonalMethod::Probing`]; n columns with
    /// [`DiagonalMethod::Exact`]); each further row costs one column.
    ///
    /// # Errors
    /// [`HeatError::VertexOutOfRange`]; as [`Self::gram_apply`].
    pub fn row_squared(&self, i: usize) -> Result<Vec<f64>, HeatError> {
        let n = self.n();
        let e = unit_columns(n, &[i])?;
        let y = self.gram_apply(e.as_ref())?;
        let col: Vec<f64> = y.col(0).iter().copied().collect();
        let d = self.diagonal_from(i, &col)?;
        let aii = col[i];
        let mut row: Vec<f64> = (0..n).map(|j| (aii - 2.0 * col[j] + d[j]).max(0.0)).collect();
        row[i] = 0.0;
        Ok(row)
    }

    /// Distances from vertex i to every vertex (square roots of [`Self::row_squared`]).
    ///
    /// # Errors
    /// As [`Self::row_squared`].
    pub fn row(&self, i: usize) -> Result<Vec<f64>, HeatError> {
        Ok(self.row_squared(i)?.into_iter().map(f64::sqrt).collect())
    }
}
