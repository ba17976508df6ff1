//! The heat kernel object `K_t = exp(−t M⁻¹L)` (paper, Eq. (5)–(9)): an operator context
//! ([`Operators`]) with a prepared [`Method`], applied to any number of functions and times.

use crate::diagonal::{DiagonalMethod, DiagonalReport, Probes};
use crate::method::{spread_times, Method, PreparedMethod};
use crate::spectral::Eigenbasis;
use crate::{check, HeatError, Operators};
use faer::sparse::SparseColMatRef;
use faer::{Mat, MatRef};
use mesh_fem::{FemOperators, Mass};
use std::sync::Arc;
use wfem_base::Choice;

/// Kernels whose operators alone make K_t uncertain by more than this (relative) are refused
/// ([`crate::Conditioning`], [`HeatError::IllConditionedMesh`]).
pub const MAX_ROUNDING_ERROR: f64 = 1e-3;

/// Options of [`HeatKernel::new`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct HeatParams {
    /// Which discrete kernel: its mass matrix M (default the consistent B, the wFEM kernel).
    pub mass: Mass,
    /// How to evaluate it (default: the fast exact path, [`Method::Fast`]).
    pub method: Method,
}

/// The heat kernel of a mesh, `K_t = exp(−t M⁻¹L)` (paper, Eq. (6)), built once from the
/// operators and applied to any number of functions and times. Cheap to clone (shared).
///
/// L is the stiffness (symmetric positive semidefinite, positive diagonal; the paper prints
/// it with the opposite sign) and M the kernel's [`Mass`].
#[derive(Clone, Debug)]
pub struct HeatKernel {
    ops: Operators,
    method: Method,
    prepared: Arc<dyn PreparedMethod>,
}

impl HeatKernel {
    /// Builds the operator context of `params.mass` ([`Operators::new`]) and prepares
    /// `params.method` on it.
    ///
    /// # Errors
    /// Those of [`Operators::new`] and [`Self::with_operators`].
    pub fn new(fem: &FemOperators, params: HeatParams) -> Result<Self, HeatError> {
        Self::with_operators(&Operators::new(fem, params.mass)?, params.method)
    }

    /// Prepares `method` on a validated context (shared with other kernels, distances, …): the
    /// t-independent work of the method (the eigenpairs for `Dense`/`Spectral`, the factor of M
    /// for `Taylor`, the backend's analysis for `Rational`).
    ///
    /// # Errors
    /// [`HeatError::TooLargeForDense`]; [`HeatError::EigenNoConvergence`];
    /// [`HeatError::InvalidParameter`] for bad method parameters;
    /// [`HeatError::NotPositiveDefinite`]; [`HeatError::Solve`] (e.g. L not positive
    /// semidefinite for the rational method).
    pub fn with_operators(ops: &Operators, method: Method) -> Result<Self, HeatError> {
        let conditioning = ops.conditioning();
        let estimated_error = conditioning.rounding_error();
        if estimated_error > MAX_ROUNDING_ERROR {
            return Err(HeatError::IllConditionedMesh {
                vertex: conditioning.vertex,
                ratio: conditioning.ratio,
                estimated_error,
            });
        }
        let prepared = method.prepare(ops)?;
        Ok(Self {
            ops: ops.clone(),
            method,
            prepared: Arc::from(prepared),
        })
    }

    /// Number of vertices n.
    pub fn n(&self) -> usize {
        self.ops.n()
    }

    /// The operator context.
    pub fn operators(&self) -> &Operators {
        &self.ops
    }

    /// The method the kernel was built with.
    pub fn method(&self) -> &Method {
        &self.method
    }

    /// The mass matrix M of the kernel (B, D, I or a custom one).
    pub fn mass(&self) -> SparseColMatRef<'_, usize, f64> {
        self.ops.mass()
    }

    /// The relative error that rounding in the operators alone can cause in K_t
    /// ([`crate::Conditioning::rounding_error`]): about 1e−15 on a well-shaped mesh; a CLI
    /// should warn above 1e−8. Kernels above [`MAX_ROUNDING_ERROR`] are refused.
    pub fn rounding_error(&self) -> f64 {
        self.ops.conditioning().rounding_error()
    }

    /// The eigenpairs, for the `Dense` and `Spectral` methods.
    pub fn eigenbasis(&self) -> Option<&Eigenbasis> {
        self.prepared.eigenbasis()
    }

    /// Applies the heat kernel, `g = K_t f = exp(−t M⁻¹L) f = X e^{−tΛ} XᵀM f`
    /// (paper, Eq. (6)), with the method of the kernel. `f` has length n.
    ///
    /// The null space of L (the constants on every connected component) is deflated exactly,
    /// `K_t f = Pf + (I − P) K_t (I − P) f` with P the M-orthogonal projector onto it, so every
    /// method conserves each component's mass `1_cᵀM K_t f = 1_cᵀM f` to rounding for any t
    /// (without it the drift grew like ε·t·λ_max: 1.6e−5 at t = 1e8·h̄²). From
    /// [`Operators::time_at_infinity`] on, `K_t f = P f` exactly (every other mode has
    /// decayed below the smallest double), whatever the method.
    ///
    /// # Errors
    /// [`HeatError::InvalidTime`] unless t is finite and positive;
    /// [`HeatError::LengthMismatch`]; [`HeatError::NonFiniteInput`];
    /// [`HeatError::KrylovNoConvergence`] (fast path).
    pub fn apply(&self, f: &[f64], t: f64) -> Result<Vec<f64>, HeatError> {
        let m = self.apply_many(MatRef::from_column_major_slice(f, f.len(), 1), t)?;
        Ok(m.col(0).iter().copied().collect())
    }

    /// Applies the heat kernel to every column of the n × k matrix `f`; one factorization
    /// (per t) serves all columns.
    ///
    /// # Errors
    /// As [`HeatKernel::apply`]; [`HeatError::NonFiniteInput`] names row and column.
    pub fn apply_many(&self, f: MatRef<'_, f64>, t: f64) -> Result<Mat<f64>, HeatError> {
        self.deflated(f, t, false)
    }

    /// `K_t F` (`kernel_matrix` false) or `K̃_t F` (true) with the null space deflated exactly:
    /// `K_t f = P f + (I − P) K_t (I − P) f` with P the M-orthogonal projector onto the
    /// constants of each component (exact: K_t P = P), and the dual split for `K̃_t`
    /// (`null_space.rs`); only the null space survives from [`Operators::time_at_infinity`] on.
    fn deflated(&self, f: MatRef<'_, f64>, t: f64, kernel_matrix: bool) -> Result<Mat<f64>, HeatError> {
        check::time(t)?;
        check::block(f, self.n())?;
        let null_space = self.ops.null_space();
        let (deflated, coefs) = null_space.split_for(f, kernel_matrix);
        let mut g = if t >= self.ops.time_at_infinity() {
            Mat::zeros(f.nrows(), f.ncols())
        } else if kernel_matrix {
            self.prepared.apply_kernel_matrix(&self.ops, deflated.as_ref(), t)?
        } else {
            self.prepared.apply(&self.ops, deflated.as_ref(), t)?
        };
        null_space.restore(&mut g, &coefs);
        self.finite(g)
    }

    /// Refuses a result with NaN or ∞ (never returned).
    fn finite(&self, m: Mat<f64>) -> Result<Mat<f64>, HeatError> {
        for j in 0..m.ncols() {
            if let Some(row) = m.col(j).iter().position(|v| !v.is_finite()) {
                return Err(HeatError::NonFiniteResult {
                    method: self.method.name(),
                    row,
                    column: j,
                });
            }
        }
        Ok(m)
    }

    /// The heat-kernel matrix applied to a block, `K̃_t G = K_t M⁻¹ G = X D_t Xᵀ G`
    /// (docs/NUMERICS.md §1): column i of `K̃_t` is the heat kernel `K̃_t(·, p_i)`, whose value at p_i is
    /// the heat kernel signature HKS_t(i), and `K̃_{2t}` is the Gram matrix of the diffusion
    /// distances. Symmetric positive definite. The null space is deflated exactly, so the
    /// constant part `Σ_c 1_c 1_cᵀ/1_cᵀM1_c` (the t → ∞ limit) is exact for every t.
    ///
    /// # Errors
    /// As [`Self::apply_many`]; [`HeatError::NotPositiveDefinite`] if M must be factored and
    /// cannot be.
    pub fn apply_kernel_matrix(&self, g: MatRef<'_, f64>, t: f64) -> Result<Mat<f64>, HeatError> {
        self.deflated(g, t, true)
    }
}

/// The heat kernel at a list of times ([`HeatKernel::apply_times`]).
#[derive(Clone, Debug)]
pub struct TimeSeries {
    /// The times t, as given.
    pub times: Vec<f64>,
    /// `K_t F` (or `K̃_t F`) for each t, n × k each.
    pub values: Vec<Mat<f64>>,
    /// Per t, the largest relative error estimate over the columns (the fast path's
    /// successive-iterate estimate in the M-norm); `None` for methods exact to their own
    /// stated accuracy (dense, rational) or without an estimate (spectral, first order).
    pub error_estimates: Vec<Option<f64>>,
}

/// Which diagonal of the heat kernel ([`HeatKernel::diagonal`]); the two conventions of the heat
/// kernel signature (HKS).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum KernelDiagonal {
    /// `K̃_t(i, i) = (K_t M⁻¹)_ii = Σ_k e^{−λ_k t} x_k(i)²`: the diagonal of the symmetric kernel
    /// matrix `K̃_t = X D_t Xᵀ`, the heat kernel's value `k_t(x_i, x_i)` (units 1/area) — the
    /// heat kernel signature of Sun, Ovsjanikov & Guibas, pyFM and most libraries.
    #[default]
    KernelValue,
    /// `K_t(i, i) = Σ_k e^{−λ_k t} x_k(i)(M x_k)(i)`: the diagonal of the heat operator
    /// `K_t = X D_t Xᵀ M` of the paper's Eq. (6) (dimensionless; its sum is the heat trace).
    OperatorDiagonal,
}

wfem_base::registry! {
    KernelDiagonal as "HKS convention" {
        KernelDiagonal::KernelValue = KernelDiagonal::KernelValue => "kernel-value":
            "the kernel's value k_t(x, x) = Σ e^{−λt} φ(x)², the diagonal of X D_t Xᵀ (Sun et al., pyFM; default)",
        KernelDiagonal::OperatorDiagonal = KernelDiagonal::OperatorDiagonal => "operator-diagonal" ["matrix-diagonal"]:
            "the diagonal of the heat operator K_t = X D_t Xᵀ M of Eq. (6) (dimensionless; sums to the heat trace)",
    }
}

/// Options of [`HeatKernel::diagonal`].
#[derive(Clone, Debug, PartialEq)]
pub struct DiagonalParams {
    /// How (default: selected inversion, exact at every t).
    pub method: DiagonalMethod,
    /// Probing only: refuse (rather than run for hours) when more probe columns than this
    /// would be needed (default 4096): at large t the kernel is not local.
    pub max_columns: usize,
    /// Probe columns per block (default 64).
    pub block: usize,
}

impl Default for DiagonalParams {
    fn default() -> Self {
        Self {
            method: DiagonalMethod::default(),
            max_columns: 4096,
            block: 64,
        }
    }
}

/// The diagonal of the heat kernel at a list of times ([`HeatKernel::diagonal`]).
#[derive(Clone, Debug)]
pub struct DiagonalSeries {
    /// The times t, as given.
    pub times: Vec<f64>,
    /// n × T: column l is the diagonal at `times[l]`.
    pub values: Mat<f64>,
    /// How the probes were chosen (none for selected inversion: columns 0, tail 0);
    /// `relative_tail` bounds the probing error of each entry
    /// relative to the entry (at the largest t; smaller t decay faster).
    pub info: DiagonalReport,
    /// The kernel evaluations' own error estimates per t (see [`TimeSeries`]).
    pub error_estimates: Vec<Option<f64>>,
}

impl HeatKernel {
    /// `K_t F` for every t of `times` (paper Eq. (6)); with the fast path (the default), one
    /// real sparse Cholesky of `M + σL` (σ chosen for the whole window; a list wider than three
    /// decades is split into windows of three decades, one factor each) and one Krylov space
    /// per column serve every t, instead of one factorization per t — the way to evaluate a
    /// scale space, a multi-scale descriptor or a time window.
    ///
    /// # Errors
    /// As [`Self::apply_many`]; [`HeatError::InvalidParameter`] for an empty list of times.
    pub fn apply_times(&self, f: MatRef<'_, f64>, times: &[f64]) -> Result<TimeSeries, HeatError> {
        self.times(f, times, false)
    }

    /// The heat-kernel matrix `K̃_t G = K_t M⁻¹ G` for every t of `times` (see
    /// [`Self::apply_kernel_matrix`] and [`Self::apply_times`]).
    ///
    /// # Errors
    /// As [`Self::apply_times`].
    pub fn apply_kernel_matrix_times(&self, g: MatRef<'_, f64>, times: &[f64]) -> Result<TimeSeries, HeatError> {
        self.times(g, times, true)
    }

    fn times(&self, f: MatRef<'_, f64>, times: &[f64], kernel_matrix: bool) -> Result<TimeSeries, HeatError> {
        check::times(times)?;
        check::block(f, self.n())?;
        let null_space = self.ops.null_space();
        let (deflated, coefs) = null_space.split_for(f, kernel_matrix);
        // Times at which only the null space survives are exact without the method.
        let t_inf = self.ops.time_at_infinity();
        let finite: Vec<f64> = times.iter().copied().filter(|&t| t < t_inf).collect();
        let (computed, computed_estimates) = if finite.is_empty() {
            (Vec::new(), Vec::new())
        } else {
            self.prepared
                .apply_times(&self.ops, deflated.as_ref(), &finite, kernel_matrix)?
        };
        let (mut values, error_estimates) =
            spread_times(times, t_inf, (computed, computed_estimates), (f.nrows(), f.ncols()));
        for v in &mut values {
            null_space.restore(v, &coefs);
        }
        let values = values
            .into_iter()
            .map(|v| self.finite(v))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(TimeSeries {
            times: times.to_vec(),
            values,
            error_estimates,
        })
    }

    /// The diagonal of the heat kernel at every t of `times`, without eigenpairs (issue #17).
    /// By default ([`DiagonalMethod::SelectedInversion`]) the heat-kernel matrix on the
    /// sparsity pattern by selected inversion, exact at every t for the cost of eight complex
    /// factorizations per t. Selectable: probing (Tang & Saad; [`crate::diagonal`]) with a
    /// distance-p colouring of the mesh
    /// chosen so that a sample column at the largest t has a relative tail below
    /// `params.method`'s tolerance beyond p edges (the sample is the vertex of smallest area,
    /// where the kernel spans the most edges), and one block evaluation of all times per block
    /// of probe columns ([`Self::apply_kernel_matrix_times`]: one factorization for all t with
    /// the fast path). Exact where spectral truncation fails — at small t, where even 300
    /// eigenpairs miss most of the diagonal — and cheap there, since the kernel is local.
    ///
    /// # Errors
    /// [`HeatError::InvalidParameter`] for an empty list of times or when probing needs
    /// more than `params.max_columns` probes (large t); as [`Self::apply_times`]; with
    /// selected inversion, [`HeatError::Solve`] for a singular shifted matrix.
    pub fn diagonal(
        &self,
        times: &[f64],
        which: KernelDiagonal,
        params: &DiagonalParams,
    ) -> Result<DiagonalSeries, HeatError> {
        check::times(times)?;
        params.method.validate()?;
        if params.block == 0 {
            return Err(HeatError::InvalidParameter {
                name: "block",
                reason: "must be positive".into(),
            });
        }
        if params.method == DiagonalMethod::SelectedInversion {
            return self.selected_diagonal(times, which);
        }
        let t_max = times.iter().copied().fold(0.0f64, f64::max);
        let n = self.n();
        let probes = self.probes(t_max, which, params)?;
        let mut estimates: Vec<Option<f64>> = vec![None; times.len()];
        let diagonals = probes.diagonals(params.block, times.len(), &mut |p| {
            let series = self.apply_diagonal_kind(which, p.as_ref(), times)?;
            for (e, s) in estimates.iter_mut().zip(&series.error_estimates) {
                *e = match (*e, *s) {
                    (Some(a), Some(b)) => Some(a.max(b)),
                    (a, b) => a.or(b),
                };
            }
            Ok(series.values)
        })?;
        Ok(DiagonalSeries {
            times: times.to_vec(),
            values: Mat::from_fn(n, times.len(), |r, l| diagonals[l][r]),
            info: probes.info,
            error_estimates: estimates,
        })
    }

    /// [`Self::diagonal`] by selected inversion ([`DiagonalMethod::SelectedInversion`]): per
    /// t, the heat-kernel matrix on the pattern, `R_t ≈ K̃_t` (rational degree 16), whose
    /// diagonal is `K̃_t(i, i)` and whose entries in column i give `K_t(i, i) = Σ_j K̃_t(i, j)
    /// M(j, i)`. From [`Operators::time_at_infinity`] on, the exact limit.
    fn selected_diagonal(&self, times: &[f64], which: KernelDiagonal) -> Result<DiagonalSeries, HeatError> {
        let n = self.n();
        let pair = self.ops.pair();
        let selected = shifted_solve::SelectedInversion::new(pair.clone())?;
        let approx = shifted_solve::poles::RationalApprox::cram(shifted_solve::poles::DEFAULT_DEGREE)?;
        let matrix = which == KernelDiagonal::OperatorDiagonal;
        let (ptr, idx) = (pair.pattern().col_ptr(), pair.pattern().row_idx());
        let mass = pair.mass_values();
        let mut values = Mat::<f64>::zeros(n, times.len());
        for (l, &t) in times.iter().enumerate() {
            let d = if t >= self.ops.time_at_infinity() {
                self.ops.null_space().limit_diagonal(matrix)
            } else {
                let r = selected.resolvent_on_pattern(approx, t)?;
                (0..n)
                    .map(|j| {
                        (ptr[j]..ptr[j + 1])
                            .filter(|&k| matrix || idx[k] == j)
                            .map(|k| if matrix { r[k] * mass[k] } else { r[k] })
                            .sum()
                    })
                    .collect()
            };
            for (j, v) in d.into_iter().enumerate() {
                values[(j, l)] = v;
            }
        }
        Ok(DiagonalSeries {
            times: times.to_vec(),
            values: self.finite(values)?,
            info: DiagonalReport {
                method: DiagonalMethod::SelectedInversion,
                columns: 0,
                hops: None,
                relative_tail: 0.0,
            },
            error_estimates: vec![None; times.len()],
        })
    }

    /// How [`Self::diagonal`] would probe at times up to `t` — the number of probe columns and
    /// the colouring distance — at the cost of one kernel column and the colouring, without
    /// computing the diagonal: the cheap test of whether the exact diagonal is within reach.
    ///
    /// # Errors
    /// As [`Self::diagonal`]: [`HeatError::InvalidParameter`] (`max_columns`) when probing
    /// would need more than `params.max_columns` columns.
    pub fn diagonal_probes(
        &self,
        t: f64,
        which: KernelDiagonal,
        params: &DiagonalParams,
    ) -> Result<DiagonalReport, HeatError> {
        check::time(t)?;
        params.method.validate()?;
        if params.method == DiagonalMethod::SelectedInversion {
            return Ok(DiagonalReport {
                method: DiagonalMethod::SelectedInversion,
                columns: 0,
                hops: None,
                relative_tail: 0.0,
            });
        }
        Ok(self.probes(t, which, params)?.info)
    }

    /// The operator whose diagonal `which` names, applied to a block at several times:
    /// `K̃_t P` for the kernel value, `K_t P` for the operator diagonal.
    fn apply_diagonal_kind(
        &self,
        which: KernelDiagonal,
        p: MatRef<'_, f64>,
        ts: &[f64],
    ) -> Result<TimeSeries, HeatError> {
        match which {
            KernelDiagonal::KernelValue => self.apply_kernel_matrix_times(p, ts),
            KernelDiagonal::OperatorDiagonal => self.apply_times(p, ts),
        }
    }

    /// The probes for times up to `t_max`: a sample column at the vertex of smallest area
    /// (where the kernel spans the most edges) at `t_max`, and its colouring.
    fn probes(&self, t_max: f64, which: KernelDiagonal, params: &DiagonalParams) -> Result<Probes, HeatError> {
        let n = self.n();
        let areas = self.ops.vertex_areas();
        let i = (0..n).min_by(|&a, &b| areas[a].total_cmp(&areas[b])).unwrap_or(0);
        let unit = check::unit_columns(n, &[i])?;
        let sample = self.apply_diagonal_kind(which, unit.as_ref(), &[t_max])?;
        let col: Vec<f64> = sample.values[0].col(0).iter().copied().collect();
        let probes = Probes::new(self.ops.pair().pattern(), params.method, i, &col, params.max_columns);
        if probes.info.columns > params.max_columns {
            return Err(HeatError::InvalidParameter {
                name: "max_columns",
                reason: format!(
                    "probing the diagonal at t = {t_max:e} needs {} columns (limit {}): the kernel is not \
                     local at this time; use the spectral diagonal (a few hundred eigenpairs are accurate there)",
                    probes.info.columns, params.max_columns
                ),
            });
        }
        Ok(probes)
    }

    /// Fast path with its iteration count and final estimate (for benchmarks and
    /// diagnostics): the kernel's own fast method, or the default one.
    #[doc(hidden)]
    pub fn apply_fast_report(&self, f: &[f64], t: f64) -> Result<(Vec<f64>, usize, f64), HeatError> {
        check::time(t)?;
        check::vector(f, self.n())?;
        let (g, outcome) = crate::method::fast_report(&*self.prepared, &self.ops, f, t)?;
        Ok((g, outcome.iterations, outcome.estimate))
    }
}

/// One-shot `K_t f` with the default parameters (wFEM kernel, fast exact path).
///
/// # Errors
/// As [`HeatKernel::new`] and [`HeatKernel::apply`].
pub fn heat(ops: &FemOperators, f: &[f64], t: f64) -> Result<Vec<f64>, HeatError> {
    HeatKernel::new(ops, HeatParams::default())?.apply(f, t)
}
