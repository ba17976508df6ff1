//! The heat kernel object `K_t = exp(−t M⁻¹L)` (paper, Eq. (5)–(9)) and its methods.

use crate::eigen::{EigenParams, Eigenbasis};
use crate::krylov::{rational_krylov_exp, FastParams};
use crate::null_space::NullSpace;
use crate::sparse::{combine, same_pattern, spmm_sym, CholeskyPattern, SpdFactor};
use crate::HeatError;
use faer::sparse::SparseColMat;
use faer::{Mat, MatRef};
use mesh_fem::FemOperators;
use rayon::prelude::*;
use std::sync::{Arc, Mutex};

/// Which discrete heat kernel (paper, Table 1). All share the stiffness L (symmetric positive
/// semidefinite, positive diagonal) and differ in the mass matrix M of `K_t = exp(−t M⁻¹L)`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum KernelKind {
    /// The wFEM kernel `K_t = X D_t Xᵀ B` with the consistent mass B (paper, Eq. (6)).
    #[default]
    Wfem,
    /// The lumped-mass kernel `K_t = X D_t Xᵀ D` with the diagonal lumped mass D (Eq. (7)).
    Lumped,
    /// The linear FEM kernel with B := I, `K̃_t = X D_t Xᵀ` (text after Eq. (7)).
    Linear,
}

/// How to evaluate `K_t f`.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum Method {
    /// All n eigenpairs by a dense generalized eigendecomposition, `K_t f = X e^{−tΛ} XᵀMf`
    /// (Eq. (6)). Exact to rounding; O(n³) once, small meshes only
    /// (n ≤ [`crate::DENSE_MAX_VERTICES`]).
    Dense,
    /// The truncated spectral representation with the k smallest eigenpairs,
    /// `F_k = X_k e^{−tΛ_k} X_kᵀ M f` (Eq. (8)). Its error is the discarded tail, about
    /// e^{−tλ_{k+1}}‖f‖: large for small t (paper, Fig. 3).
    Spectral {
        /// Number of eigenpairs.
        k: usize,
        /// Eigensolver options.
        eigen: EigenParams,
    },
    /// First-order explicit Taylor step `M g = (M − tL) f`, i.e. `K_t ≈ I − tM⁻¹L`
    /// (Eq. (9)): one solve with M (factored once). It is a first-order method: the error of
    /// one step is `Σᵢ |e^{−tλᵢ} − 1 + tλᵢ| |cᵢ| ≈ t²λᵢ²/2` per eigencomponent cᵢ of f, so
    /// O(t²) for fixed smooth f, O(t) when a time T is covered in T/t steps, and unbounded
    /// (growing like tλ_max) for rough f: valid only for t → 0⁺. For comparison only.
    Taylor,
    /// One backward-Euler step `(M + tL) g = M f`, i.e. `K_t ≈ (I + tM⁻¹L)⁻¹`: one real
    /// sparse Cholesky per t. First order like [`Method::Taylor`] (one-step error
    /// `|1/(1 + tλ) − e^{−tλ}| ≈ t²λ²/2`, O(t) over a fixed horizon) but stable (it damps
    /// every mode). For comparison only.
    BackwardEuler,
    /// The fast exact path (beyond the paper): shift-and-invert rational Krylov on
    /// (M + γtL)⁻¹M, one real sparse Cholesky per t, reused for every iteration and every
    /// right-hand side; accurate to ≈1e−12 relative. See [`FastParams`].
    Fast(FastParams),
    /// The paper's generalized Chebyshev method (Eq. (11)–(13)): the best uniform rational
    /// approximation `e^{−x} ≈ c0 + 2 Re Σ_j c_j/(x − z_j)` of degree `degree` on [0, ∞)
    /// turns K_t f into `degree/2` complex shifted solves `(tL − z_j M) g_j = M f`,
    /// `K_t f ≈ c0 f + 2 Re Σ_j c_j g_j` (upper-half-plane poles; the paper's Eq. (13) is the
    /// same sum in the nuclear convention θ = −conj z, α = −conj c). The error is at most
    /// E_degree‖f‖_M (Eq. (14); E_16 = 2.1e−16, floored by rounding at ≈2e−14).
    /// The backend is the direct complex-symmetric LDLᵀ (default), the pivoted complex LU,
    /// MINRES (the paper's choice), or the multi-shift Lanczos that solves every pole in one
    /// Krylov space of (M + γtL)⁻¹M with a single real Cholesky; see [`shifted_solve::Backend`].
    Rational {
        /// Degree n of r_n (see [`shifted_solve::SHIPPED_DEGREES`]); E_n ≈ 9.289⁻ⁿ.
        degree: usize,
        /// How each shifted system is solved.
        backend: shifted_solve::Backend,
    },
}

impl Method {
    /// The rational Chebyshev method of `degree` with the direct complex-symmetric LDLᵀ backend
    /// (NUMERICS §3.3d; about half the work of the pivoted LU, residual reported per pole).
    pub fn rational(degree: usize) -> Self {
        Method::Rational {
            degree,
            backend: shifted_solve::Backend::DirectLdlt,
        }
    }

    /// The spectral method with the `k` smallest eigenpairs and default eigensolver options.
    pub fn spectral(k: usize) -> Self {
        Method::Spectral {
            k,
            eigen: EigenParams::default(),
        }
    }
}

/// The default is the paper's rational Chebyshev method with
/// [`shifted_solve::DEFAULT_DEGREE`] (error ≈ 1e−14) and the direct complex-symmetric LDLᵀ backend.
impl Default for Method {
    fn default() -> Self {
        Method::rational(shifted_solve::DEFAULT_DEGREE)
    }
}

/// Options of [`HeatKernel::new`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct HeatParams {
    /// Which discrete kernel (mass matrix).
    pub kernel: KernelKind,
    /// How to evaluate it.
    pub method: Method,
}

#[derive(Debug)]
enum Prepared {
    Eigen(Eigenbasis),
    /// Cholesky factor of M (Taylor).
    MassFactor(SpdFactor),
    /// Only the symbolic analysis; the numeric factor depends on t.
    Shifted,
    /// The shifted solver (symbolic analyses) and the rational approximation.
    Rational(shifted_solve::ShiftedSolver, &'static shifted_solve::RationalApprox),
}

/// The heat kernel of a mesh, `K_t = exp(−t M⁻¹L)` (paper, Eq. (6)), built once from the FEM
/// operators and applied to any number of functions and times.
///
/// L is the stiffness (symmetric positive semidefinite, positive diagonal; the paper prints
/// it with the opposite sign) and M the mass of the [`KernelKind`].
#[derive(Debug)]
pub struct HeatKernel {
    stiffness: SparseColMat<usize, f64>,
    mass: SparseColMat<usize, f64>,
    /// Symbolic Cholesky of the shared pattern, built on first use (the rational method has its
    /// own analysis inside the shifted solver; a second AMD cost 0.24 s at n = 163,842).
    pattern: std::sync::OnceLock<CholeskyPattern>,
    params: HeatParams,
    prepared: Prepared,
    /// The constants on the connected components, deflated exactly (see `null_space.rs`).
    null_space: NullSpace,
    /// The last t-dependent factor `M + sL` and its s.
    cache: Mutex<Option<(f64, Arc<SpdFactor>)>>,
    /// The rational factors of the last t (`Rational` method).
    rational_cache: Mutex<Option<(f64, Arc<shifted_solve::RationalFactors>)>>,
}

pub(crate) fn check_time(t: f64) -> Result<(), HeatError> {
    if t.is_finite() && t > 0.0 {
        Ok(())
    } else {
        Err(HeatError::InvalidTime { t })
    }
}

pub(crate) fn check_vector(f: &[f64], n: usize) -> Result<(), HeatError> {
    if f.len() != n {
        return Err(HeatError::LengthMismatch {
            expected: n,
            found: f.len(),
        });
    }
    if let Some((row, &value)) = f.iter().enumerate().find(|(_, x)| !x.is_finite()) {
        return Err(HeatError::NonFiniteInput { row, column: 0, value });
    }
    Ok(())
}

/// Validates the operators of every method (O(nnz)): all entries of L and M finite, every
/// diagonal entry of M positive. Without it a NaN in L passed through the Taylor step as NaN
/// output, and a zero row of M (singular M, K_t undefined) went through the fast path as a
/// finite answer.
pub(crate) fn check_operators(
    stiffness: &SparseColMat<usize, f64>,
    mass: &SparseColMat<usize, f64>,
) -> Result<(), HeatError> {
    for (matrix, a) in [("stiffness L", stiffness), ("mass M", mass)] {
        let s = a.symbolic();
        for col in 0..a.ncols() {
            for p in s.col_range(col) {
                let value = a.val()[p];
                if !value.is_finite() {
                    return Err(HeatError::InvalidOperatorEntry {
                        matrix,
                        row: s.row_idx()[p],
                        col,
                        value,
                        requirement: "finite",
                    });
                }
            }
        }
    }
    let s = mass.symbolic();
    for col in 0..mass.ncols() {
        let value: f64 = s
            .col_range(col)
            .filter(|&p| s.row_idx()[p] == col)
            .map(|p| mass.val()[p])
            .sum();
        if value <= 0.0 {
            return Err(HeatError::InvalidOperatorEntry {
                matrix: "mass M",
                row: col,
                col,
                value,
                requirement: "> 0 on the diagonal",
            });
        }
    }
    Ok(())
}

impl HeatKernel {
    /// Prepares the kernel: picks the mass matrix of `params.kernel`, runs the symbolic
    /// Cholesky analysis of the shared pattern and the t-independent work of the method
    /// (the eigenpairs for `Dense`/`Spectral`, the factor of M for `Taylor`).
    ///
    /// # Errors
    /// [`HeatError::InconsistentOperators`] if L and M differ in size or pattern;
    /// [`HeatError::InvalidOperatorEntry`] for a NaN/∞ entry or a non-positive diagonal
    /// entry of M; [`HeatError::TooLargeForDense`]; [`HeatError::EigenNoConvergence`];
    /// [`HeatError::InvalidParameter`] for bad method parameters;
    /// [`HeatError::NotPositiveDefinite`].
    pub fn new(ops: &FemOperators, params: HeatParams) -> Result<Self, HeatError> {
        let stiffness = ops.stiffness.clone();
        let mass = match params.kernel {
            KernelKind::Wfem => ops.mass.clone(),
            KernelKind::Lumped => ops.lumped_mass.clone(),
            KernelKind::Linear => ops.identity_mass(),
        };
        if !same_pattern(&stiffness, &mass) || stiffness.nrows() != stiffness.ncols() {
            return Err(HeatError::InconsistentOperators {
                reason: format!("stiffness and {:?} mass do not share one square pattern", params.kernel),
            });
        }
        check_operators(&stiffness, &mass)?;
        let pattern = std::sync::OnceLock::new();
        let analysed = || analysed_pattern(&pattern, &stiffness);
        let prepared = match &params.method {
            Method::Dense => Prepared::Eigen(Eigenbasis::dense(&stiffness, &mass)?),
            Method::Spectral { k, eigen } => Prepared::Eigen(Eigenbasis::partial(&stiffness, &mass, *k, eigen)?),
            Method::Taylor => Prepared::MassFactor(analysed()?.factor(&mass, || "mass matrix M".into())?),
            Method::BackwardEuler => {
                analysed()?;
                Prepared::Shifted
            }
            Method::Fast(fp) => {
                if !(fp.gamma > 0.0 && fp.gamma.is_finite()) {
                    return Err(HeatError::InvalidParameter {
                        name: "gamma",
                        reason: format!("γ = {} must be positive", fp.gamma),
                    });
                }
                if !(fp.tol > 0.0 && fp.tol < 1.0) {
                    return Err(HeatError::InvalidParameter {
                        name: "tol",
                        reason: format!("{} is not in (0, 1)", fp.tol),
                    });
                }
                if fp.max_iter == 0 {
                    return Err(HeatError::InvalidParameter {
                        name: "max_iter",
                        reason: "must be positive".into(),
                    });
                }
                analysed()?;
                Prepared::Shifted
            }
            Method::Rational { degree, backend } => {
                let approx = shifted_solve::RationalApprox::cram(*degree)?;
                let solver = shifted_solve::ShiftedSolver::new(stiffness.as_ref(), mass.as_ref(), *backend)?;
                Prepared::Rational(solver, approx)
            }
        };
        let null_space = NullSpace::new(&stiffness, &mass);
        Ok(Self {
            stiffness,
            mass,
            pattern,
            params,
            prepared,
            null_space,
            cache: Mutex::new(None),
            rational_cache: Mutex::new(None),
        })
    }

    /// Number of vertices n.
    pub fn n(&self) -> usize {
        self.stiffness.nrows()
    }

    /// The parameters the kernel was built with.
    pub fn params(&self) -> &HeatParams {
        &self.params
    }

    /// The mass matrix M of the kernel (B, D or I).
    pub fn mass(&self) -> &SparseColMat<usize, f64> {
        &self.mass
    }

    /// The eigenpairs, for the `Dense` and `Spectral` methods.
    pub fn eigenbasis(&self) -> Option<&Eigenbasis> {
        match &self.prepared {
            Prepared::Eigen(e) => Some(e),
            _ => None,
        }
    }

    /// Applies the heat kernel, `g = K_t f = exp(−t M⁻¹L) f = X e^{−tΛ} XᵀM f`
    /// (paper, Eq. (6)), with the method of the kernel. `f` has length n.
    ///
    /// The null space of L (the constants on every connected component) is deflated exactly,
    /// `K_t f = Pf + (I − P) K_t (I − P) f` with P the M-orthogonal projector onto it, so every
    /// method conserves each component's mass `1_cᵀM K_t f = 1_cᵀM f` to rounding for any t
    /// (without it the drift grew like ε·t·λ_max: 1.6e−5 at t = 1e8·h̄²).
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
        check_time(t)?;
        let n = self.n();
        if f.nrows() != n {
            return Err(HeatError::LengthMismatch {
                expected: n,
                found: f.nrows(),
            });
        }
        for c in 0..f.ncols() {
            for r in 0..n {
                let value = f[(r, c)];
                if !value.is_finite() {
                    return Err(HeatError::NonFiniteInput {
                        row: r,
                        column: c,
                        value,
                    });
                }
            }
        }
        // K_t f = P f + (I − P) K_t (I − P) f with P the M-orthogonal projector onto the
        // constants of each component (exact: K_t P = P); see `null_space.rs`.
        let (deflated, coefs) = self.null_space.split(f);
        let mut g = self.apply_method(deflated.as_ref(), t)?;
        self.null_space.restore(&mut g, &coefs);
        Ok(g)
    }

    /// `K_t f` by the method of the kernel, without the null-space deflation (`f` validated).
    fn apply_method(&self, f: MatRef<'_, f64>, t: f64) -> Result<Mat<f64>, HeatError> {
        let n = self.n();
        match (&self.params.method, &self.prepared) {
            (_, Prepared::Eigen(e)) => Ok(e.apply_heat_many(&self.mass, f, t)),
            (Method::Taylor, Prepared::MassFactor(mf)) => {
                // M g = (M − tL) f, i.e. g = f − t M⁻¹L f.
                let lf = spmm_sym(&self.stiffness, f);
                let mut step = lf;
                mf.solve_in_place(step.as_mut());
                Ok(Mat::from_fn(n, f.ncols(), |i, j| f[(i, j)] - t * step[(i, j)]))
            }
            (Method::BackwardEuler, _) => {
                let factor = self.shifted_factor(t, "M + tL")?;
                let mut g = spmm_sym(&self.mass, f);
                factor.solve_in_place(g.as_mut());
                Ok(g)
            }
            (Method::Fast(fp), _) => {
                let factor = self.shifted_factor(fp.gamma * t, "M + γtL")?;
                let column = |c: usize| f.col(c).iter().copied().collect::<Vec<f64>>();
                let cols: Vec<Vec<f64>> = if f.ncols() == 1 {
                    // One vector: its solves and products with M use every core.
                    let solve = |b: &[f64]| factor.solve_vec(b);
                    let (g, _) = rational_krylov_exp(&solve, &self.mass, &column(0), fp, 0, true)?;
                    vec![g]
                } else {
                    (0..f.ncols())
                        .into_par_iter()
                        .map(|c| {
                            let solve = |b: &[f64]| factor.solve_vec(b);
                            rational_krylov_exp(&solve, &self.mass, &column(c), fp, c, false).map(|(g, _)| g)
                        })
                        .collect::<Result<_, _>>()?
                };
                Ok(Mat::from_fn(n, cols.len(), |i, j| cols[j][i]))
            }
            (_, Prepared::Rational(solver, approx)) => {
                let factors = self.rational_factors(solver, approx, t)?;
                Ok(factors.apply(f)?.0)
            }
            _ => unreachable!("every method has its prepared data"),
        }
    }

    /// The Cholesky factor of `M + s·L`, reused when the previous call had the same s
    /// (repeated `apply` at one t then costs only the solves).
    fn shifted_factor(&self, s: f64, what: &str) -> Result<Arc<SpdFactor>, HeatError> {
        let mut cache = self.cache.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
        if let Some((cached_s, factor)) = cache.as_ref() {
            if *cached_s == s {
                return Ok(factor.clone());
            }
        }
        let a = combine(1.0, &self.mass, s, &self.stiffness);
        let pattern = analysed_pattern(&self.pattern, &self.stiffness)?;
        let factor = Arc::new(pattern.factor(&a, || format!("{what} with shift {s:e}"))?);
        *cache = Some((s, factor.clone()));
        Ok(factor)
    }

    /// The factors of every pole at time t, reused when the previous call had the same t.
    fn rational_factors(
        &self,
        solver: &shifted_solve::ShiftedSolver,
        approx: &shifted_solve::RationalApprox,
        t: f64,
    ) -> Result<Arc<shifted_solve::RationalFactors>, HeatError> {
        let mut cache = self
            .rational_cache
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner());
        if let Some((cached_t, factors)) = cache.as_ref() {
            if *cached_t == t {
                return Ok(factors.clone());
            }
        }
        let factors = Arc::new(solver.factor(approx, t)?);
        *cache = Some((t, factors.clone()));
        Ok(factors)
    }

    /// Fast path with its per-column iteration counts (for benchmarks and diagnostics).
    #[doc(hidden)]
    pub fn apply_fast_report(&self, f: &[f64], t: f64) -> Result<(Vec<f64>, usize, f64), HeatError> {
        check_time(t)?;
        check_vector(f, self.n())?;
        let fp = match &self.params.method {
            Method::Fast(fp) => *fp,
            _ => FastParams::default(),
        };
        let factor = self.shifted_factor(fp.gamma * t, "M + γtL")?;
        let solve = |b: &[f64]| factor.solve_vec(b);
        let (g, out) = rational_krylov_exp(&solve, &self.mass, f, &fp, 0, true)?;
        Ok((g, out.iterations, out.estimate))
    }
}

/// The symbolic Cholesky analysis of `stiffness`'s pattern held in `cell`, computed on first use.
fn analysed_pattern<'a>(
    cell: &'a std::sync::OnceLock<CholeskyPattern>,
    stiffness: &SparseColMat<usize, f64>,
) -> Result<&'a CholeskyPattern, HeatError> {
    if let Some(p) = cell.get() {
        return Ok(p);
    }
    let p = CholeskyPattern::new(stiffness)?;
    Ok(cell.get_or_init(|| p))
}

/// One-shot `K_t f` with the default parameters (wFEM kernel, fast exact path).
///
/// # Errors
/// As [`HeatKernel::new`] and [`HeatKernel::apply`].
pub fn heat(ops: &FemOperators, f: &[f64], t: f64) -> Result<Vec<f64>, HeatError> {
    HeatKernel::new(ops, HeatParams::default())?.apply(f, t)
}
