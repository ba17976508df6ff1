//! Diffusion distances (paper, Sect. 3, Eq. (18) and the display after Eq. (20); docs/NUMERICS.md §1)
//! on any [`HeatKernel`] — every kernel (wFEM, lumped, linear) and every method.
//!
//! Both distances are `d²(i, j) = (e_i − e_j)ᵀ A (e_i − e_j) = A_ii − 2A_ij + A_jj` for a
//! symmetric positive (semi)definite n × n matrix A:
//!
//! * [`DistanceKind::Diffusion`] (default): the standard diffusion distance (Coifman & Lafon;
//!   the paper's "linear FEM diffusion distance" with the eigenvectors of (L, M))
//!   `d_t²(i,j) = Σ_k e^{−2λ_k t} (x_k(i) − x_k(j))²` with `A = K̃_{2t} = K_{2t} M⁻¹ = X D_{2t} Xᵀ`,
//!   the heat-kernel matrix ([`HeatKernel::apply_kernel_matrix`]). It behaves like a distance:
//!   0 at the source and growing with the geodesic distance from it.
//! * [`DistanceKind::MassWeighted`]: the paper's wFEM distance `‖h_i − h_j‖_M²` with
//!   `h_i = K_{t/2} e_i` (Eq. (18b)), i.e. `A = S_t = M K_t = M X D_t Xᵀ M`,
//!   `d²(i,j) = Σ_k e^{−λ_k t} ((Mx_k)_i − (Mx_k)_j)²`. Its entries carry the vertex masses
//!   `(M·1)_i` twice, so on an irregular mesh it follows the vertex areas more than the
//!   geometry (measured on a real mesh: correlation 0.997 with `M·1`, 0.07 with the distance
//!   from the source). The paper's display after Eq. (20) writes it as
//!   `K_{t/2}(i,i) − 2K_{t/2}(i,j) + K_{t/2}(j,j)`; by Eq. (18b) the correct entries are those
//!   of `S_t = M K_t` (K_{t/2} is not even symmetric). (The paper's "linear diffusion distance"
//!   `‖g_i − g_j‖_B²` uses the RKHS kernel `H_t = X D_{−t} Xᵀ`, whose weights e^{+λt} grow with
//!   λ; it is an anti-diffusion quantity, available only truncated, see
//!   [`crate::rkhs::reproducing_embedding`].)
//!
//! Cost: [`DiffusionDistance::pairs`] needs one column `A(e_i − e_j)` per pair, in blocks of
//! columns with the kernel's factorizations of t reused. A whole row `d(i, ·)` needs the column
//! `A e_i` and the diagonal of A, computed once and cached, so every further row costs one
//! column. The diagonal of `K̃_{2t}` is `K̃_{2t}` on the sparsity pattern by selected inversion
//! (default, [`crate::diagonal::DiagonalMethod::SelectedInversion`]): eight complex LDLᵀ and
//! their selected inverses, whatever t — probing needed hundreds to thousands of columns
//! there, because `K̃_{2t} = K_{2t}M⁻¹` inherits the slow geometric decay of M⁻¹ (48K vertices:
//! 1.1 s for the whole `wfem distance` run, where probing took minutes). The mass-weighted
//! Gram matrix `M K_t` has no diagonal on the pattern and is probed ([`crate::diagonal`]).

use crate::check::{self, unit_columns};
use crate::diagonal::{diagonal, DiagonalMethod, DiagonalReport};
use crate::{DiagonalParams, HeatError, HeatKernel, KernelDiagonal};
use faer::{Mat, MatRef};
use std::sync::OnceLock;

/// Which diffusion distance (see the module documentation).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum DistanceKind {
    /// The standard diffusion distance `Σ_k e^{−2λ_k t}(x_k(i) − x_k(j))²`,
    /// `A = K̃_{2t} = K_{2t}M⁻¹`.
    #[default]
    Diffusion,
    /// The paper's wFEM distance `‖h_i − h_j‖_M²`, `h_i = K_{t/2} e_i`, `A = S_t = M K_t`
    /// (Eq. (18b)).
    MassWeighted,
}

wfem_base::registry! {
    DistanceKind as "distance" {
        DistanceKind::Diffusion = DistanceKind::Diffusion => "diffusion" ["linear"]:
            "the diffusion distance Σ e^{−2λt}(x(i) − x(j))², the paper's linear FEM distance (default)",
        DistanceKind::MassWeighted = DistanceKind::MassWeighted => "mass-weighted" ["wfem"]:
            "the paper's wFEM distance ‖K_{t/2}e_i − K_{t/2}e_j‖_M² (Eq. (18b))",
    }
}

/// Options of [`DiffusionDistance::new`].
#[derive(Clone, Debug, PartialEq)]
pub struct DistanceParams {
    /// Number of right-hand sides per block application (default 64).
    pub block: usize,
    /// How the diagonal of A is computed for whole rows (default: selected inversion, exact
    /// at every t for the diffusion distance; the mass-weighted one probes, tol 1e−10).
    pub diagonal: DiagonalMethod,
}

impl Default for DistanceParams {
    fn default() -> Self {
        Self {
            block: 64,
            diagonal: DiagonalMethod::SelectedInversion,
        }
    }
}

/// Diffusion distances of one kind at one time t, on a heat kernel (its method and its
/// factorizations of t are reused for every query).
#[derive(Debug)]
pub struct DiffusionDistance {
    kernel: HeatKernel,
    kind: DistanceKind,
    t: f64,
    params: DistanceParams,
    diagonal: OnceLock<(Vec<f64>, DiagonalReport)>,
}

impl DiffusionDistance {
    /// Distances of `kind` at time t through `kernel` (cloned; shared).
    ///
    /// # Errors
    /// [`HeatError::InvalidTime`], [`HeatError::InvalidParameter`] (block, diagonal tol, a t
    /// whose 2t overflows).
    pub fn new(kernel: &HeatKernel, kind: DistanceKind, t: f64, params: &DistanceParams) -> Result<Self, HeatError> {
        check::time(t)?;
        if kind == DistanceKind::Diffusion && !(2.0 * t).is_finite() {
            // The error names the time given, not the overflowed 2t.
            return Err(HeatError::InvalidParameter {
                name: "t",
                reason: format!(
                    "t = {t:e} is too large: the diffusion distance applies K_2t, and 2t overflows (t ≤ {:e})",
                    f64::MAX / 2.0
                ),
            });
        }
        params.diagonal.validate()?;
        if params.block == 0 {
            return Err(HeatError::InvalidParameter {
                name: "block",
                reason: "must be positive".into(),
            });
        }
        Ok(Self {
            kernel: kernel.clone(),
            kind,
            t,
            params: params.clone(),
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
        self.kernel.n()
    }

    /// The kernel the distances use.
    pub fn kernel(&self) -> &HeatKernel {
        &self.kernel
    }

    /// `A E` for an n × m block E: `K̃_{2t} E` ([`DistanceKind::Diffusion`]) or `M K_t E`
    /// ([`DistanceKind::MassWeighted`]), in blocks of columns.
    ///
    /// # Errors
    /// [`HeatError::LengthMismatch`], [`HeatError::NonFiniteInput`], and those of the kernel.
    pub fn gram_apply(&self, e: MatRef<'_, f64>) -> Result<Mat<f64>, HeatError> {
        let n = self.n();
        check::block(e, n)?;
        let m = e.ncols();
        let mut out = Mat::<f64>::zeros(n, m);
        let mut start = 0;
        while start < m {
            let end = (start + self.params.block).min(m);
            let blk = e.get(.., start..end);
            let y = match self.kind {
                DistanceKind::Diffusion => self.kernel.apply_kernel_matrix(blk, 2.0 * self.t)?,
                DistanceKind::MassWeighted => {
                    let k = self.kernel.apply_many(blk, self.t)?;
                    self.kernel.operators().mass_mul_block(k.as_ref())
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
            check::vertices(&[i, j], n)?;
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

    /// The diagonal of A (`K̃_{2t}(j,j)`, the heat kernel signature HKS_{2t}, or `S_t(j,j)`), by
    /// the [`DiagonalMethod`] of the parameters (probing chooses its colouring from the column
    /// of vertex 0). Computed on the first call (of this or of [`Self::row_squared`]) and
    /// cached; [`Self::diagonal_info`] says how.
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
    pub fn diagonal_info(&self) -> Option<&DiagonalReport> {
        self.diagonal.get().map(|(_, info)| info)
    }

    fn diagonal_from(&self, i: usize, col: &[f64]) -> Result<&[f64], HeatError> {
        if let Some((d, _)) = self.diagonal.get() {
            return Ok(d);
        }
        let computed =
            if self.kind == DistanceKind::Diffusion && self.params.diagonal == DiagonalMethod::SelectedInversion {
                let params = DiagonalParams {
                    method: DiagonalMethod::SelectedInversion,
                    ..DiagonalParams::default()
                };
                let series = self
                    .kernel
                    .diagonal(&[2.0 * self.t], KernelDiagonal::KernelValue, &params)?;
                (series.values.col(0).iter().copied().collect(), series.info)
            } else {
                let pattern = self.kernel.operators().pair().pattern();
                let apply = |p: &Mat<f64>| self.gram_apply(p.as_ref());
                diagonal(pattern, self.params.diagonal, self.params.block, i, col, &apply)?
            };
        Ok(&self.diagonal.get_or_init(|| computed).0)
    }

    /// Squared distances from vertex i to every vertex,
    /// `d²(i, j) = A_ii − 2A_ij + A_jj` (clamped at 0), from the column `A e_i` and the cached
    /// [`Self::diagonal`]. The first call pays for the diagonal; each further row costs one
    /// column.
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

    /// Distances from each of `sources` to every vertex: row r is `d(sources[r], ·)`, from one
    /// block of columns `A E` (the diagonal computed once).
    ///
    /// # Errors
    /// [`HeatError::VertexOutOfRange`]; [`HeatError::InvalidParameter`] for an empty list; as
    /// [`Self::gram_apply`].
    pub fn rows(&self, sources: &[usize]) -> Result<Vec<Vec<f64>>, HeatError> {
        let n = self.n();
        let mut out = vec![0.0; sources.len() * n];
        self.rows_into(sources, &mut out)?;
        Ok(out.chunks(n).map(<[f64]>::to_vec).collect())
    }

    /// [`Self::rows`] written into `out` (`|sources| × n`, row-major) instead of new vectors:
    /// what [`write_rows`] streams an all-pairs matrix with.
    ///
    /// # Errors
    /// As [`Self::rows`]; [`HeatError::LengthMismatch`] if `out` is not `|sources| × n`.
    pub fn rows_into(&self, sources: &[usize], out: &mut [f64]) -> Result<(), HeatError> {
        let n = self.n();
        if sources.is_empty() {
            return Err(HeatError::InvalidParameter {
                name: "sources",
                reason: "no source given; give at least one vertex".into(),
            });
        }
        check::vertices(sources, n)?;
        if out.len() != sources.len() * n {
            return Err(HeatError::LengthMismatch {
                expected: sources.len() * n,
                found: out.len(),
            });
        }
        let e = unit_columns(n, sources)?;
        let y = self.gram_apply(e.as_ref())?;
        let first: Vec<f64> = y.col(0).iter().copied().collect();
        let d = self.diagonal_from(sources[0], &first)?;
        for ((c, &i), row) in sources.iter().enumerate().zip(out.chunks_mut(n)) {
            let col = y.col(c);
            let aii = col[i];
            for (j, r) in row.iter_mut().enumerate() {
                *r = (aii - 2.0 * col[j] + d[j]).max(0.0).sqrt();
            }
            row[i] = 0.0;
        }
        Ok(())
    }

    /// Distances from vertex i to every vertex (square roots of [`Self::row_squared`]).
    ///
    /// # Errors
    /// As [`Self::row_squared`].
    pub fn row(&self, i: usize) -> Result<Vec<f64>, HeatError> {
        Ok(self.row_squared(i)?.into_iter().map(f64::sqrt).collect())
    }
}

/// Bytes of rows held in memory at once by [`write_rows`] (the rest of a matrix is on disk).
pub const ROW_BLOCK_BYTES: usize = 64 << 20;

/// How a matrix written by [`write_rows`] went.
#[derive(Clone, Debug, PartialEq)]
pub struct RowsReport {
    /// The file written.
    pub path: std::path::PathBuf,
    /// Rows written in all (n).
    pub rows: usize,
    /// Rows found written by an earlier, interrupted run and kept.
    pub resumed_from: usize,
    /// Rows computed and held in memory at a time.
    pub block: usize,
}

/// Writes an `n_rows × n_cols` matrix to an `.npy` file a block of rows at a time
/// (`compute(range, block)` fills `block` with the rows of `range`, concatenated; `block_rows`
/// of them, by default as many as fit in [`ROW_BLOCK_BYTES`]), so memory holds one block — one
/// buffer, reused — whatever the size of the matrix: an all-pairs distance matrix
/// of 50K vertices (20 GB) in 64 MB. Atomic and resumable ([`mesh_fem::io::rows`]): an
/// interrupted run (Ctrl-C, [`wfem_base::interrupt`], a crash) leaves the rows it finished in
/// a partial file beside the target, which a run with the same `key` continues.
/// `progress(done, total)` is called after each block.
///
/// # Errors
/// [`HeatError::Mesh`] for the file ([`mesh_fem::MeshError::RowFile`], I/O);
/// [`HeatError::Solve`] with `Interrupted` when interrupted; those of `compute`.
pub fn write_rows(
    path: &std::path::Path,
    n_rows: usize,
    n_cols: usize,
    key: &str,
    block_rows: Option<usize>,
    compute: impl Fn(std::ops::Range<usize>, &mut [f64]) -> Result<(), HeatError>,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<RowsReport, HeatError> {
    let mut file = mesh_fem::io::rows::RowFile::open(path, n_rows, n_cols, key)?;
    let block = block_rows
        .unwrap_or(ROW_BLOCK_BYTES / (8 * n_cols.max(1)))
        .clamp(1, n_rows.max(1));
    let resumed_from = file.rows_done();
    progress(resumed_from, n_rows);
    let mut start = resumed_from;
    // rows_done() never exceeds n_rows.
    let mut buffer = vec![0.0; block.min(n_rows - resumed_from) * n_cols];
    while start < n_rows {
        wfem_base::interrupt::checkpoint().map_err(shifted_solve::SolveError::from)?;
        let end = (start + block).min(n_rows);
        let rows = &mut buffer[..(end - start) * n_cols];
        rows.fill(f64::NAN);
        compute(start..end, rows)?;
        if let Some(i) = rows.iter().position(|x| x.is_nan()) {
            return Err(HeatError::NonFiniteResult {
                method: "distance rows",
                row: start + i / n_cols,
                column: i % n_cols,
            });
        }
        file.append(rows)?;
        start = end;
        progress(start, n_rows);
    }
    let path = file.finish()?;
    Ok(RowsReport {
        path,
        rows: n_rows,
        resumed_from,
        block,
    })
}
