//! Thick-restart block Lanczos for the largest eigenpairs of an operator S that is
//! self-adjoint and positive semidefinite in the M-inner product ⟨u, v⟩_M = uᵀMv.
//!
//! The user is wfem-heat's spectral path (paper, Eq. (4)–(8)): with S = (L − σM)⁻¹M (σ < 0, one
//! real sparse Cholesky of the SPD matrix L − σM) the generalized pairs `L x = λ M x` become
//! `S x = θ x` with θ = 1/(λ − σ), so the k smallest λ are the k largest θ and converge first.
//! The method is what ARPACK does for `eigsh(..., sigma=σ)` (a restarted Krylov method with a
//! basis of about 2k vectors), in block form so that every operator application is a block
//! solve (n × b) and every orthogonalisation is a BLAS-3 product:
//!
//! 1. **Block Lanczos with full reorthogonalisation.** The basis V (M-orthonormal, n × m) and the
//!    projection H = VᵀM S V satisfy `S V = V H + Q B Eᵀ`, Q the next block (M-orthogonal to V)
//!    and E the last b columns of the identity. Each new block W = S V_j is M-orthogonalised
//!    against all of V by two passes of block classical Gram–Schmidt (`C = Vᵀ(MW)`,
//!    `W ← W − VC`; M W is recomputed by one sparse product per pass instead of storing M V), then
//!    M-orthonormalised within itself (Gram matrix eigendecomposition, "SVQB").
//! 2. **Rayleigh–Ritz.** H = YΘYᵀ; the residual of the Ritz pair (θᵢ, V yᵢ) is
//!    `‖S V yᵢ − θᵢ V yᵢ‖_M = ‖B Eᵀ yᵢ‖₂`, accepted when at most `tol·θᵢ`.
//! 3. **Thick restart** (Wu & Simon, SIAM J. Matrix Anal. Appl. 22 (2000) 602–616; Stewart's
//!    Krylov–Schur, SIAM J. Matrix Anal. Appl. 23 (2001) 601–614) when the basis is full: V is
//!    replaced by the Ritz vectors V Y_p of the p largest Ritz values (computed in place, row
//!    block by row block), H by diag(θ_p), and the relation `S V Y_p = V Y_p Θ_p + Q (B Eᵀ Y_p)`
//!    continues the iteration from the same Q: the coupling `B Eᵀ Y_p` becomes the first
//!    off-diagonal block of the new H.
//! 4. **Locking.** Converged pairs (from the largest θ down, contiguous) are locked at a restart:
//!    they stay in front of V, untouched by later restarts and outside the Rayleigh–Ritz
//!    problem, and new blocks are still orthogonalised against them. Their coupling to Q
//!    (at most `tol·θ` by the acceptance test) is dropped, a perturbation of H of that size.
//!
//! The basis never holds more than [`BlockLanczosParams::max_basis`] columns (the report's
//! `basis_peak` counts them), so the memory is `n·max_basis` doubles plus a few n × b blocks.
//! When `max_basis ≥ n` the basis can reach all of Rⁿ: the last block is then the M-orthogonal
//! complement of V (fewer than b columns if b does not divide n) and the Rayleigh–Ritz pairs are
//! exact for any k ≤ n. A block that loses rank (an invariant subspace) is completed with random
//! directions M-orthogonal to V.

use faer::linalg::matmul::matmul;
use faer::sparse::SparseColMatRef;
use faer::{Accum, Mat, MatMut, MatRef, Par};
use rayon::prelude::*;

use crate::blocks::{project_out, row_blocks, split_rows, ROTATION_ROWS};
use crate::lanczos::symmetric_eigen;
use crate::SolveError;
use wfem_base::rng::SplitMix64;

/// Options of [`largest_eigenpairs`].
#[derive(Clone, Debug, PartialEq)]
pub struct BlockLanczosParams {
    /// Block size b (columns per operator application). Must exceed the largest multiplicity
    /// among the wanted eigenvalues for all copies to be found before the basis is exhausted.
    pub block_size: usize,
    /// Relative residual tolerance: a pair is accepted when `‖Sx − θx‖_M ≤ tol·θ`.
    pub tol: f64,
    /// The most basis columns ever held: raised to k + 2b, and to n when within one block of n
    /// (then the basis may span Rⁿ and the pairs are exact, without restarts).
    pub max_basis: usize,
    /// Restarts allowed before giving up (returning the converged pairs only).
    pub max_restarts: usize,
    /// Seed of the random start block (and of replacement directions).
    pub seed: u64,
}

/// The outcome of [`largest_eigenpairs`]: the converged pairs (θ descending) and what it cost.
#[derive(Clone, Debug)]
pub struct BlockLanczosReport {
    /// Converged eigenvalues θ of S, descending (all k requested ones on success).
    pub values: Vec<f64>,
    /// Their eigenvectors, n × `values.len()`, M-orthonormal.
    pub vectors: Mat<f64>,
    /// Number of pairs requested.
    pub requested: usize,
    /// Largest relative residual `‖Sx − θx‖_M / θ` among the requested pairs at the last
    /// Rayleigh–Ritz step (locked pairs count with their residual when locked).
    pub max_residual: f64,
    /// Restarts performed.
    pub restarts: usize,
    /// Columns the operator was applied to (= solves for a shift-and-invert S).
    pub applications: usize,
    /// The largest number of basis columns held at any time (≤ the effective `max_basis`).
    pub basis_peak: usize,
    /// The effective basis bound (`max_basis` after clamping).
    pub basis_bound: usize,
}

/// The old name of [`BlockLanczosReport`] (one word per meaning: results are reports).
#[deprecated(note = "renamed BlockLanczosReport")]
pub type BlockLanczosOutcome = BlockLanczosReport;

impl BlockLanczosReport {
    /// Whether all requested pairs converged.
    pub fn converged(&self) -> bool {
        self.values.len() >= self.requested
    }
}

/// Applies S to an n × b block X, given X and M X (for a shift-and-invert S = A⁻¹M the
/// right-hand side of the block solve: the eigensolver has M X at hand for every basis block).
pub type BlockOperator<'a> = dyn Fn(MatRef<'_, f64>, MatRef<'_, f64>) -> Result<Mat<f64>, SolveError> + Sync + 'a;
/// Applies M to an n × b block.
pub type BlockMass<'a> = dyn Fn(MatRef<'_, f64>) -> Mat<f64> + Sync + 'a;

/// The k largest eigenpairs of S (self-adjoint, positive semidefinite in ⟨·,·⟩_M), by thick-restart
/// block Lanczos with locking (see the module documentation). `apply(X, MX)` computes S X and
/// `mass` computes M X for n × b blocks; for the generalized problem `L x = λ M x`,
/// S = (L − σM)⁻¹M and `apply` is one block solve with MX.
///
/// Returns the converged pairs; fewer than k (with [`BlockLanczosReport::converged`] false) when
/// `max_restarts` restarts did not suffice.
///
/// # Errors
/// [`SolveError::InvalidParameter`] for k = 0, k > n, block size 0 or tol outside (0, 1);
/// whatever `apply` returns; [`SolveError::Factorization`] if a dense eigendecomposition fails.
pub fn largest_eigenpairs(
    n: usize,
    k: usize,
    apply: &BlockOperator<'_>,
    mass: &BlockMass<'_>,
    params: &BlockLanczosParams,
) -> Result<BlockLanczosReport, SolveError> {
    let bad = |name, value: f64, reason| Err(SolveError::InvalidParameter { name, value, reason });
    if k == 0 || k > n {
        return bad("k", k as f64, "must be in 1..=n");
    }
    if params.block_size == 0 {
        return bad("block_size", 0.0, "must be at least 1");
    }
    if !(params.tol > 0.0 && params.tol < 1.0) {
        return bad("tol", params.tol, "must lie in (0, 1)");
    }
    let b = params.block_size.min(n);
    // Within one block of n the basis may as well span Rⁿ (exact pairs, no restart); below,
    // every block keeps b columns, since n − dim > b.
    let cap = params.max_basis.max(k + 2 * b);
    let cap = if cap + b >= n { n } else { cap };
    Lanczos {
        n,
        k,
        b,
        cap,
        apply,
        mass,
        params,
        v: Mat::zeros(n, cap),
        h: Mat::zeros(cap, cap),
        locked: Vec::new(),
        locked_residual: 0.0,
        dim: 0,
        j0: 0,
        mq: Mat::zeros(0, 0),
        local: 0,
        rng: SplitMix64::new(params.seed),
        restarts: 0,
        applications: 0,
        basis_peak: 0,
    }
    .run()
}

/// The state of one [`largest_eigenpairs`] run.
struct Lanczos<'a, 'p> {
    n: usize,
    k: usize,
    b: usize,
    cap: usize,
    apply: &'a BlockOperator<'a>,
    mass: &'a BlockMass<'a>,
    params: &'p BlockLanczosParams,
    /// Basis: locked vectors `0..locked.len()`, then the active ones up to `dim`.
    v: Mat<f64>,
    /// Projection H = VᵀMSV of the active part (indices as in `v`).
    h: Mat<f64>,
    /// θ of the locked pairs, in locking order (descending).
    locked: Vec<f64>,
    locked_residual: f64,
    /// Basis columns in use.
    dim: usize,
    /// Start of the newest block (`j0..dim`).
    j0: usize,
    /// M times the newest block.
    mq: Mat<f64>,
    /// Start of the part of the basis that S V_j couples to (`local..dim`): the previous and
    /// the newest block in the block-tridiagonal phase, everything after a restart.
    local: usize,
    rng: SplitMix64,
    restarts: usize,
    applications: usize,
    basis_peak: usize,
}

/// The Rayleigh–Ritz step of the active part: θ ascending, Y, residual norms.
struct Ritz {
    theta: Vec<f64>,
    y: Mat<f64>,
    residual: Vec<f64>,
}

impl Lanczos<'_, '_> {
    fn run(mut self) -> Result<BlockLanczosReport, SolveError> {
        let (n, b) = (self.n, self.b);
        let start = Mat::<f64>::from_fn(n, b, |_, _| self.rng.next_centered());
        let (q0, _, mq0) = m_orthonormalize(start, self.mass, self.v.as_ref().get(.., 0..0), &mut self.rng, 0.0);
        self.v.as_mut().get_mut(.., 0..b).copy_from(&q0);
        self.mq = mq0;
        self.dim = b;
        self.basis_peak = b;
        // Rayleigh–Ritz checks between restarts: a few per cycle (each is O(m³) dense work).
        let mut next_check = self.check_stride();
        loop {
            wfem_base::interrupt::checkpoint()?;
            let (j0, dim) = (self.j0, self.dim);
            let mut w = (self.apply)(self.v.as_ref().get(.., j0..dim), self.mq.as_ref())?;
            self.applications += dim - j0;
            let before = self.orthogonalize(w.as_mut());
            let nlock = self.locked.len();
            let exhausted = dim >= n;
            // Size of the next block: b, or the n − dim columns that complete Rⁿ.
            let bn = b.min(n - dim);
            let (q, bnext, mq) = if exhausted {
                (
                    Mat::<f64>::zeros(n, 0),
                    Mat::<f64>::zeros(0, dim - j0),
                    Mat::<f64>::zeros(n, 0),
                )
            } else if bn < dim - j0 {
                complement_block(
                    w.as_ref(),
                    bn,
                    self.mass,
                    self.v.as_ref().get(.., 0..dim),
                    &mut self.rng,
                )
            } else {
                orthonormal_block(w, &before, self.mass, self.v.as_ref().get(.., 0..dim), &mut self.rng)
            };
            let must_restart = !exhausted && dim + bn > self.cap;
            if exhausted || must_restart || dim >= next_check {
                let ritz = self.rayleigh_ritz(bnext.as_ref())?;
                let wanted = self.k - nlock;
                let converged = self.converged_count(&ritz, wanted);
                if converged >= wanted || exhausted {
                    let take = wanted.min(ritz.theta.len());
                    return Ok(self.finish(&ritz, take));
                }
                if must_restart {
                    if self.restarts >= self.params.max_restarts {
                        return Ok(self.finish(&ritz, converged));
                    }
                    self.restart(&ritz, converged, q.as_ref(), bnext.as_ref());
                    self.mq = mq;
                    next_check = self.dim + self.check_stride();
                    continue;
                }
                next_check = dim + self.check_stride();
            }
            // Extend the basis with the next block.
            self.v.as_mut().get_mut(.., dim..dim + bn).copy_from(&q);
            self.mq = mq;
            self.h.as_mut().get_mut(dim..dim + bn, j0..dim).copy_from(&bnext);
            self.local = j0;
            self.j0 = dim;
            self.dim = dim + bn;
            self.basis_peak = self.basis_peak.max(self.dim);
        }
    }

    /// M-orthogonalises W = S V_j (the newest block `j0..dim`) against the basis and adds the
    /// coefficients to H; returns the squared M-norms of its columns before.
    ///
    /// In the block-tridiagonal phase S V_j couples only to the previous and the newest block
    /// (`S V_j = V_{j−1}B_{j−1}ᵀ + V_j A_j + V_{j+1}B_j`), so two passes of Gram–Schmidt run
    /// against those (2b columns) and one pass against the rest of the basis, which only
    /// removes rounding: the components left after the local passes are O(ε‖W‖), and
    /// projecting them out once leaves O(ε‖W_after‖) (the second pass of "twice is enough" is
    /// needed only for the part where the norm dropped). Right after a restart S V_j couples
    /// to every kept Ritz vector, and both passes run against the whole basis. Coefficients on
    /// locked rows are dropped (deflation: they are at most tol·θ).
    fn orthogonalize(&mut self, mut w: MatMut<'_, f64>) -> Vec<f64> {
        let (nlock, dim, j0, local) = (self.locked.len(), self.dim, self.j0, self.local);
        let mut before = Vec::new();
        let pass = |h: &mut Mat<f64>, w: MatMut<'_, f64>, from: usize, before: &mut Vec<f64>| {
            let mw = (self.mass)(w.as_ref());
            if before.is_empty() {
                let wr = w.as_ref();
                *before = (0..wr.ncols())
                    .map(|c| wr.col(c).iter().zip(mw.col(c).iter()).map(|(a, b)| a * b).sum())
                    .collect();
            }
            let coef = project_out(self.v.as_ref().get(.., from..dim), w, mw.as_ref());
            let keep = nlock.max(from);
            let mut hb = h.as_mut().get_mut(keep..dim, j0..dim);
            hb += coef.as_ref().get(keep - from.., ..);
        };
        pass(&mut self.h, w.as_mut(), local, &mut before);
        pass(&mut self.h, w.as_mut(), local, &mut before);
        if local > 0 {
            let coef = {
                let mw = (self.mass)(w.as_ref());
                project_out(self.v.as_ref().get(.., 0..local), w.as_mut(), mw.as_ref())
            };
            if local > nlock {
                let mut hb = self.h.as_mut().get_mut(nlock..local, j0..dim);
                hb += coef.as_ref().get(nlock.., ..);
            }
        }
        before
    }

    /// Columns between two Rayleigh–Ritz checks: a quarter of the free part of the basis.
    fn check_stride(&self) -> usize {
        ((self.cap - self.dim.min(self.cap)) / 4).max(self.b)
    }

    /// Eigenpairs of the symmetrized active projection and the residual norms `‖B Eᵀ yᵢ‖`
    /// (`bnext` = B of the next block; empty when the basis spans Rⁿ, residuals 0).
    fn rayleigh_ritz(&self, bnext: MatRef<'_, f64>) -> Result<Ritz, SolveError> {
        let (a0, dim, j0) = (self.locked.len(), self.dim, self.j0);
        let (theta, y) = symmetric_eigen(self.h.as_ref().get(a0..dim, a0..dim))?;
        let last = y.as_ref().get(j0 - a0..dim - a0, ..);
        let residual = if bnext.nrows() == 0 {
            vec![0.0; theta.len()]
        } else {
            let r = bnext * last;
            (0..theta.len()).map(|i| r.col(i).norm_l2()).collect()
        };
        Ok(Ritz { theta, y, residual })
    }

    /// Number of leading (largest) Ritz pairs that meet the tolerance, contiguously, at most
    /// `wanted` (a pair below an unconverged one is not counted: locking keeps the order).
    fn converged_count(&self, ritz: &Ritz, wanted: usize) -> usize {
        let m = ritz.theta.len();
        let mut count = 0;
        let mut contiguous = true;
        for r in 0..wanted.min(m) {
            let i = m - 1 - r;
            let theta = ritz.theta[i];
            let ok = theta > 0.0 && ritz.residual[i] <= self.params.tol * theta;
            contiguous &= ok;
            if contiguous {
                count += 1;
            }
        }
        count
    }

    /// Largest relative residual among the wanted pairs of `ritz`.
    fn worst_residual(&self, ritz: &Ritz, wanted: usize) -> f64 {
        let m = ritz.theta.len();
        (0..wanted.min(m))
            .map(|r| {
                let i = m - 1 - r;
                ritz.residual[i] / ritz.theta[i].abs().max(f64::MIN_POSITIVE)
            })
            .fold(self.locked_residual, f64::max)
    }

    /// Locks the `converged` leading pairs, keeps the next p Ritz vectors and continues from
    /// the next block Q with the coupling `B Eᵀ Y_p`.
    fn restart(&mut self, ritz: &Ritz, converged: usize, q: MatRef<'_, f64>, bnext: MatRef<'_, f64>) {
        let (a0, dim, j0) = (self.locked.len(), self.dim, self.j0);
        let m = ritz.theta.len();
        let bn = q.ncols();
        self.locked_residual = self.locked_residual.max(
            (0..converged)
                .map(|r| ritz.residual[m - 1 - r] / ritz.theta[m - 1 - r])
                .fold(0.0, f64::max),
        );
        let nlock = a0 + converged;
        // Room for the kept Ritz vectors and the growth of the next cycle: keep the wanted
        // pairs still running plus a quarter of the remaining space (ARPACK keeps the wanted
        // ones, SLEPc's Krylov–Schur half of the space), at least one, leaving at least one
        // block. Measured on the 41K icosphere, k = 100, a basis of 208: keeping 0 / 25 / 50 /
        // 75 % of the extra space took 456 / 416 / 408 / 416 operator applications with 3 / 3 /
        // 4 / 7 restarts; a quarter has the fewest restarts for near-minimal applications.
        let free = self.cap - nlock - bn;
        let still = self.k - nlock;
        let keep = (still + free.saturating_sub(still) / 4).clamp(1, free.saturating_sub(bn).max(1));
        let keep = keep.min(m - converged);
        // Ritz vectors of the largest θ first: columns a0.. hold the newly locked, then the kept.
        let total = converged + keep;
        let sel = Mat::<f64>::from_fn(m, total, |i, c| ritz.y[(i, m - 1 - c)]);
        rotate_in_place(self.v.as_mut().get_mut(.., a0..dim), sel.as_ref());
        for c in 0..converged {
            self.locked.push(ritz.theta[m - 1 - c]);
        }
        // New projection: diag(θ) for the kept vectors, the coupling below, zero elsewhere.
        let new_dim = nlock + keep;
        self.h.as_mut().get_mut(a0.., a0..).fill(0.0);
        for c in 0..keep {
            self.h[(nlock + c, nlock + c)] = ritz.theta[m - 1 - converged - c];
        }
        let last = ritz.y.as_ref().get(j0 - a0..dim - a0, ..);
        let coupling = Mat::<f64>::from_fn(bn, keep, |r, c| {
            (0..bnext.ncols())
                .map(|s| bnext[(r, s)] * last[(s, m - 1 - converged - c)])
                .sum()
        });
        self.h
            .as_mut()
            .get_mut(new_dim..new_dim + bn, nlock..new_dim)
            .copy_from(&coupling);
        self.v.as_mut().get_mut(.., new_dim..new_dim + bn).copy_from(q);
        // S Q couples to every kept Ritz vector: the next block is orthogonalised in full.
        self.local = 0;
        self.j0 = new_dim;
        self.dim = new_dim + bn;
        self.basis_peak = self.basis_peak.max(self.dim);
        self.restarts += 1;
    }

    /// The locked pairs and the `take` largest Ritz pairs of the active part, θ descending.
    fn finish(mut self, ritz: &Ritz, take: usize) -> BlockLanczosReport {
        let (a0, dim) = (self.locked.len(), self.dim);
        let m = ritz.theta.len();
        let wanted = self.k - a0;
        let max_residual = self.worst_residual(ritz, wanted);
        let sel = Mat::<f64>::from_fn(m, take, |i, c| ritz.y[(i, m - 1 - c)]);
        rotate_in_place(self.v.as_mut().get_mut(.., a0..dim), sel.as_ref());
        let mut values = std::mem::take(&mut self.locked);
        values.extend((0..take).map(|c| ritz.theta[m - 1 - c]));
        let count = values.len();
        // Order by θ descending (locked pairs of a later restart can exceed earlier ones only
        // by rounding, but keep the contract exact).
        let mut order: Vec<usize> = (0..count).collect();
        order.sort_by(|&x, &y| values[y].total_cmp(&values[x]));
        let vectors = Mat::<f64>::from_fn(self.n, count, |i, c| self.v[(i, order[c])]);
        BlockLanczosReport {
            values: order.iter().map(|&i| values[i]).collect(),
            vectors,
            requested: self.k,
            max_residual,
            restarts: self.restarts,
            applications: self.applications,
            basis_peak: self.basis_peak,
            basis_bound: self.cap,
        }
    }
}

/// `V ← V Y` in place for the first `y.ncols()` columns (V n × m, Y m × p, p ≤ m), row block
/// by row block in parallel, so no n × p temporary is needed.
fn rotate_in_place(v: MatMut<'_, f64>, y: MatRef<'_, f64>) {
    let p = y.ncols();
    if p == 0 {
        return;
    }
    let mut chunks = Vec::new();
    let mut rest = v;
    while rest.nrows() > ROTATION_ROWS {
        let (head, tail) = rest.split_at_row_mut(ROTATION_ROWS);
        chunks.push(head);
        rest = tail;
    }
    chunks.push(rest);
    chunks.into_par_iter().for_each(|mut chunk| {
        let mut tmp = Mat::<f64>::zeros(chunk.nrows(), p);
        matmul(tmp.as_mut(), Accum::Replace, chunk.as_ref(), y, 1.0, Par::Seq);
        chunk.as_mut().get_mut(.., 0..p).copy_from(&tmp);
    });
}

/// `A X` for a symmetric sparse A (both triangles stored, CSC) and an n × b block, in
/// parallel over rows: row j of AX is column j of A (symmetry) times X. X is copied to row-major
/// order first, so each stored entry a_ij costs one contiguous b-wide multiply-add
/// (`(AX)_j += a_ij X_i`) instead of b scattered reads.
pub fn symmetric_block_mul(a: SparseColMatRef<'_, usize, f64>, x: MatRef<'_, f64>) -> Mat<f64> {
    let (n, b) = (x.nrows(), x.ncols());
    if b == 0 {
        return Mat::zeros(n, 0);
    }
    let sym = a.symbolic();
    let (ptr, idx, val) = (sym.col_ptr(), sym.row_idx(), a.val());
    let rows = row_blocks(n);
    // Row-major copy of X: x_rows[i·b + c] = X[i, c].
    let x_rows: Vec<f64> = (0..n * b).into_par_iter().map(|k| x[(k / b, k % b)]).collect();
    let mut out = Mat::<f64>::zeros(n, b);
    let chunks = split_rows(out.as_mut(), &rows);
    chunks.into_par_iter().for_each(|(r0, mut chunk)| {
        let mut acc = vec![0.0f64; b];
        for jj in 0..chunk.nrows() {
            let j = r0 + jj;
            acc.iter_mut().for_each(|a| *a = 0.0);
            for p in ptr[j]..ptr[j + 1] {
                let (i, v) = (idx[p], val[p]);
                for (a, xv) in acc.iter_mut().zip(&x_rows[i * b..(i + 1) * b]) {
                    *a += v * xv;
                }
            }
            for (c, a) in acc.iter().enumerate() {
                chunk[(jj, c)] = *a;
            }
        }
    });
    out
}

/// The next block from W (already M-orthogonal to V by two passes): (Q, B, MQ) with W = QB
/// and QᵀMQ = I, by [`m_orthonormalize`] with the squared M-norms of the columns before the
/// projection as the reference for lost norm.
fn orthonormal_block(
    w: Mat<f64>,
    before: &[f64],
    mass: &BlockMass<'_>,
    v: MatRef<'_, f64>,
    rng: &mut SplitMix64,
) -> (Mat<f64>, Mat<f64>, Mat<f64>) {
    let reference = before.iter().copied().fold(0.0, f64::max);
    m_orthonormalize(w, mass, v, rng, reference)
}

/// The last, partial block when only `r` < b directions remain outside span(V) (r = n − dim):
/// an M-orthonormal basis Q (n × r) of the M-orthogonal complement of V, from a random block
/// projected twice against V and M-orthonormalised, and B = QᵀM·W (r × b), so that W = QB for
/// W ⟂_M V (and MQ).
fn complement_block(
    w: MatRef<'_, f64>,
    r: usize,
    mass: &BlockMass<'_>,
    v: MatRef<'_, f64>,
    rng: &mut SplitMix64,
) -> (Mat<f64>, Mat<f64>, Mat<f64>) {
    let n = w.nrows();
    let mut z = Mat::<f64>::from_fn(n, r, |_, _| rng.next_centered());
    for _ in 0..2 {
        let mz = mass(z.as_ref());
        project_out(v, z.as_mut(), mz.as_ref());
    }
    let (q, _, mq) = m_orthonormalize(z, mass, v, rng, 0.0);
    let bj = mq.transpose() * w;
    (q, bj, mq)
}

/// M-orthonormalizes the columns of `w` (already M-orthogonal to V): returns (Q, R) with
/// W = QR, QᵀMQ = I, by "SVQB" (Stathopoulos & Wu, SIAM J. Sci. Comput. 23 (2002) 2165–2182):
/// the Gram matrix G = WᵀMW = UΣUᵀ gives Q = WUΣ^{−1/2}, R = Σ^{1/2}Uᵀ.
///
/// Normalising a direction of tiny σ amplifies whatever rounding it carries, its components
/// along V included. So when the smallest σ is below 1e−8 of `reference` (the largest squared
/// M-norm the columns had before their projection against V: the direction lost more than
/// 10⁴ of its norm) Q is projected against V once more and orthonormalised again
/// (Daniel–Gragg–Kaufman–Stewart: "twice is enough" unless the norm drops that much).
/// Directions with σ ≤ 1e−24·σ_max (rank deficiency: an invariant subspace) are replaced by
/// random vectors, with a zero row in R, and handled the same way.
pub(crate) fn m_orthonormalize(
    mut w: Mat<f64>,
    mass: &BlockMass<'_>,
    v: MatRef<'_, f64>,
    rng: &mut SplitMix64,
    reference: f64,
) -> (Mat<f64>, Mat<f64>, Mat<f64>) {
    let (n, b) = (w.nrows(), w.ncols());
    let mut r_total = Mat::<f64>::identity(b, b);
    let mut project = false;
    let mut mq = None;
    for pass in 0..3 {
        if project && v.ncols() > 0 {
            let mw = mass(w.as_ref());
            project_out(v, w.as_mut(), mw.as_ref());
        }
        let mw = mass(w.as_ref());
        let g = w.transpose() * &mw;
        let Ok((s, u)) = symmetric_eigen(g.as_ref()) else {
            break;
        };
        // MQ = MW·UΣ^{−1/2} for the kept directions (replaced ones are recomputed).
        let mut scale = Mat::<f64>::zeros(b, b);
        let smax = s[b - 1].max(0.0);
        let wu = &w * &u;
        let mut q = Mat::<f64>::zeros(n, b);
        let mut r = Mat::<f64>::zeros(b, b);
        let mut replaced = false;
        for c in 0..b {
            if s[c] > 1e-24 * smax.max(f64::MIN_POSITIVE) && s[c] > 0.0 {
                let sq = s[c].sqrt();
                for i in 0..n {
                    q[(i, c)] = wu[(i, c)] / sq;
                }
                for j in 0..b {
                    scale[(j, c)] = u[(j, c)] / sq;
                }
                for j in 0..b {
                    r[(c, j)] = sq * u[(j, c)];
                }
            } else {
                for i in 0..n {
                    q[(i, c)] = rng.next_centered();
                }
                replaced = true;
            }
        }
        mq = (!replaced).then(|| &mw * &scale);
        w = q;
        r_total = &r * &r_total;
        // SVQB leaves QᵀMQ − I of order ε·κ(G): one more pass (cheap, b × b) when κ(G) > 10⁴;
        // the projection against V again when a direction was replaced or lost its norm.
        project = replaced || (pass == 0 && s[0] <= 1e-8 * reference.max(smax));
        let ill_conditioned = s[0] < 1e-4 * smax;
        if !project && !ill_conditioned {
            break;
        }
    }
    let mq = mq.unwrap_or_else(|| mass(w.as_ref()));
    (w, r_total, mq)
}
