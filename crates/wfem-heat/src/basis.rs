//! The canonical basis `{K_t eᵢ}` (paper, Sect. 4.1, Eq. (21)), shape-driven feature points
//! and the feature-driven approximation `f = f_glob + f_loc` (Sect. 4.2, Fig. 12–13), and the
//! scale behaviour of the kernel (Sect. 5): the largest eigenvalue λ_n and the normalised,
//! scale-invariant kernel.

use crate::eigen::{EigenParams, Eigenbasis, SplitMix};
use crate::kernel::{check_time, check_vector};
use crate::sparse::{spmv_sym, CholeskyPattern};
use crate::{HeatError, HeatKernel, HeatParams};
use faer::linalg::solvers::Solve;
use faer::sparse::SparseColMat;
use faer::{Mat, Side};
use mesh_fem::morse;
use mesh_fem::{FemOperators, TriMesh};

fn check_anchors(anchors: &[u32], n: usize) -> Result<(), HeatError> {
    if let Some(&a) = anchors.iter().find(|&&a| a as usize >= n) {
        return Err(HeatError::InvalidParameter {
            name: "anchors",
            reason: format!("vertex {a} does not exist (the mesh has {n} vertices)"),
        });
    }
    Ok(())
}

/// The canonical basis functions `K_t eᵢ` for every anchor i (paper, Sect. 4.1: the image of
/// the standard basis under the operator K_t of Eq. (21)), as the columns of an n × |A|
/// matrix, column j = `K_t e_{anchors[j]}`.
///
/// All anchors are computed together: one [`HeatKernel::apply_many`] on the n × |A| block
/// of unit vectors, so the t-dependent factorizations are done once for all anchors.
///
/// # Errors
/// [`HeatError::InvalidParameter`] for an anchor that is not a vertex; the errors of
/// [`HeatKernel::apply_many`] (e.g. [`HeatError::InvalidTime`]).
pub fn canonical_basis(kernel: &HeatKernel, anchors: &[u32], t: f64) -> Result<Mat<f64>, HeatError> {
    let n = kernel.n();
    check_anchors(anchors, n)?;
    check_time(t)?;
    let e = Mat::<f64>::from_fn(
        n,
        anchors.len(),
        |i, j| if anchors[j] as usize == i { 1.0 } else { 0.0 },
    );
    kernel.apply_many(e.as_ref(), t)
}

/// The constant limits `lim_{t→∞} K_t eᵢ = cᵢ·1` of the canonical basis functions of the
/// anchors, `cᵢ = 1ᵀM eᵢ / 1ᵀM1` (M the mass of the kernel: B, D or I).
///
/// **Correction of the paper.** Sect. 4.1 writes `K_t eᵢ → (eᵢᵀB1)·1`. On a connected mesh
/// the eigenvector of λ₁ = 0 is the B-normalised constant `x₁ = 1/√(1ᵀB1)` (not 1), so
/// `K_t eᵢ → ⟨eᵢ, x₁⟩_B x₁ = (eᵢᵀB1 / 1ᵀB1)·1`: the paper's limit misses the factor
/// 1/area(M) (1ᵀB1 is the surface area). The limit preserves the B-mean,
/// `1ᵀB K_t eᵢ = 1ᵀB eᵢ` for every t. (On a mesh with several connected components the
/// limit is piecewise constant instead.)
///
/// # Errors
/// [`HeatError::InvalidParameter`] for an anchor that is not a vertex.
pub fn canonical_limit(kernel: &HeatKernel, anchors: &[u32]) -> Result<Vec<f64>, HeatError> {
    let n = kernel.n();
    check_anchors(anchors, n)?;
    let row_sums = spmv_sym(kernel.mass(), &vec![1.0; n]);
    let total: f64 = row_sums.iter().sum();
    Ok(anchors.iter().map(|&a| row_sums[a as usize] / total).collect())
}

// ---------------------------------------------------------------------------------------
// Feature points (Sect. 4.2)
// ---------------------------------------------------------------------------------------

/// Convention of the auto-diffusion map (heat kernel signature) of [`auto_diffusion`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum AutoDiffusion {
    /// The diagonal of the wFEM kernel matrix, `K_t(i,i) = (K_t eᵢ)(pᵢ) =
    /// Σ_k e^{−λ_k t} x_k(i) (M x_k)(i)` (Eq. (6)): the value at pᵢ of the canonical basis
    /// function centred at pᵢ. Dimensionless (→ Mᵢᵢ-weighted 1/area as t → ∞).
    #[default]
    MatrixDiagonal,
    /// The kernel function on the diagonal, `k_t(pᵢ,pᵢ) = Σ_k e^{−λ_k t} x_k(i)²` (the
    /// usual HKS of \[SOG09\], i.e. the diagonal of `X D_t Xᵀ = K_t M⁻¹`); units 1/area.
    KernelValue,
}

/// The auto-diffusion map (heat kernel signature) at one time t, computed spectrally from
/// the eigenpairs (paper, Sect. 4.2, \[GBAL09\]; Eq. (8) truncated to the pairs of `basis`):
/// `Σ_k e^{−λ_k t} x_k(i) (M x_k)(i)` ([`AutoDiffusion::MatrixDiagonal`]) or
/// `Σ_k e^{−λ_k t} x_k(i)²` ([`AutoDiffusion::KernelValue`]). With all n pairs
/// ([`Eigenbasis::dense`]) it is exact; with the k smallest it is accurate once
/// e^{−λ_{k+1} t} is negligible. `mass` is the mass matrix M the eigenpairs were computed with.
///
/// # Errors
/// [`HeatError::InvalidTime`]; [`HeatError::LengthMismatch`] if the mass and the
/// eigenvectors disagree in size.
pub fn auto_diffusion(
    basis: &Eigenbasis,
    mass: &SparseColMat<usize, f64>,
    t: f64,
    convention: AutoDiffusion,
) -> Result<Vec<f64>, HeatError> {
    check_time(t)?;
    let n = basis.vectors.nrows();
    if mass.nrows() != n {
        return Err(HeatError::LengthMismatch {
            expected: n,
            found: mass.nrows(),
        });
    }
    let mut out = vec![0.0; n];
    for (k, &lambda) in basis.values.iter().enumerate() {
        let w = (-t * lambda.max(0.0)).exp();
        let x: Vec<f64> = basis.vectors.col(k).iter().copied().collect();
        match convention {
            AutoDiffusion::KernelValue => {
                for (o, xi) in out.iter_mut().zip(&x) {
                    *o += w * xi * xi;
                }
            }
            AutoDiffusion::MatrixDiagonal => {
                let mx = spmv_sym(mass, &x);
                for ((o, xi), mxi) in out.iter_mut().zip(&x).zip(&mx) {
                    *o += w * xi * mxi;
                }
            }
        }
    }
    Ok(out)
}

/// Extrema of a field: all strict local maxima and minima (`persistence = None`), or only the
/// extrema whose persistence is at least `fraction · (max f − min f)` (`Some(fraction)`,
/// [`morse::persistent_extrema_relative`], saddles dropped). Sorted, without repetition.
///
/// # Errors
/// [`HeatError::Mesh`] for a field of the wrong length or with non-finite values.
pub fn extrema(mesh: &TriMesh, f: &[f64], persistence: Option<f64>) -> Result<Vec<u32>, HeatError> {
    let maxima = morse::local_maxima(mesh, f)?;
    let minima = morse::local_minima(mesh, f)?;
    let mut all: Vec<u32> = maxima.into_iter().chain(minima).collect();
    all.sort_unstable();
    all.dedup();
    if let Some(fraction) = persistence {
        let diagram = morse::persistence(mesh, f)?;
        let keep = morse::persistent_extrema_relative(&diagram, fraction);
        all.retain(|v| keep.binary_search(v).is_ok());
    }
    Ok(all)
}

/// Feature points from the first Laplacian eigenfunctions (paper, Sect. 4.2, \[RPSS10\]): the
/// union of the [`extrema`] of the eigenvectors x₂, …, x_{count+1} of `basis` (x₁, the
/// constant of λ₁ = 0, is skipped). Sorted, without repetition. Eigenvectors are defined up
/// to sign, and the union of maxima and minima does not depend on it.
///
/// # Errors
/// [`HeatError::InvalidParameter`] if `basis` has fewer than `count + 1` pairs;
/// [`HeatError::Mesh`] if the mesh and the basis disagree in size.
pub fn eigenfunction_features(
    mesh: &TriMesh,
    basis: &Eigenbasis,
    count: usize,
    persistence: Option<f64>,
) -> Result<Vec<u32>, HeatError> {
    if basis.values.len() < count + 1 {
        return Err(HeatError::InvalidParameter {
            name: "count",
            reason: format!(
                "{count} eigenfunctions after the constant need {} eigenpairs, the basis has {}",
                count + 1,
                basis.values.len()
            ),
        });
    }
    let mut all = Vec::new();
    for k in 1..=count {
        let x: Vec<f64> = basis.vectors.col(k).iter().copied().collect();
        all.extend(extrema(mesh, &x, persistence)?);
    }
    all.sort_unstable();
    all.dedup();
    Ok(all)
}

// ---------------------------------------------------------------------------------------
// Feature-driven approximation (Sect. 4.2)
// ---------------------------------------------------------------------------------------

/// How the coefficients of the global component are chosen.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Coefficients {
    /// The paper's definition, `f_glob = Σ_{i∈A} f(pᵢ) K_t eᵢ` (Sect. 4.2): the feature
    /// values themselves. Since `Σᵢ f(pᵢ) K_t eᵢ = K_t(f·χ_A)` it costs one application of
    /// K_t. With A = all vertices it is K_t f (→ f as t → 0); with a sparse A it is small
    /// (each K_t eᵢ has B-mass 1ᵀBeᵢ, see [`canonical_limit`]), so the L∞ error is ≈ ‖f‖∞.
    #[default]
    FeatureValues,
    /// Interpolation on the anchors (beyond the paper's formula, matching its wording "the
    /// approximation of specific f-values"): `f_glob = Σ_{i∈A} cᵢ K_t eᵢ` with
    /// `f_glob(pⱼ) = f(pⱼ)` for j ∈ A, i.e. `K_t[A,A] c = f_A` (an |A| × |A| LU solve; the
    /// basis costs |A| right-hand sides, one set of factorizations).
    Interpolate,
}

/// Persistence threshold selecting the anchor set A among the critical points of f.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Persistence {
    /// Persistence ≥ fraction · (max f − min f) ([`morse::persistent_extrema_relative`]).
    Relative(f64),
    /// Persistence ≥ the value, in units of f ([`morse::persistent_extrema`]).
    Absolute(f64),
}

/// Options of [`feature_approximation`].
#[derive(Clone, Debug, PartialEq)]
pub struct ApproxParams {
    /// Index k of the eigenvalue λ_k that sets the time scale (paper: k = 20).
    pub k: usize,
    /// Number N of scales `tᵢ = (i/10) λ_k⁻¹`, i = 1..N (paper: "from five to ten").
    pub scales: usize,
    /// Threshold of the anchor set A (default: 10 % of the range, as in Fig. 13).
    pub persistence: Persistence,
    /// Coefficients of the global component.
    pub coefficients: Coefficients,
    /// Eigensolver options for λ_k.
    pub eigen: EigenParams,
}

impl Default for ApproxParams {
    fn default() -> Self {
        Self {
            k: 20,
            scales: 10,
            persistence: Persistence::Relative(0.1),
            coefficients: Coefficients::default(),
            eigen: EigenParams::default(),
        }
    }
}

/// The decomposition `f = f_glob + f_loc` at one scale t.
#[derive(Clone, Debug)]
pub struct ScaleApproximation {
    /// The diffusion time t.
    pub t: f64,
    /// The global component `f_glob = Σ_{i∈A} cᵢ K_t eᵢ`.
    pub global: Vec<f64>,
    /// The local component `f_loc = f − f_glob`.
    pub local: Vec<f64>,
    /// `‖f − f_glob‖∞`.
    pub linf_error: f64,
    /// `‖f − f_glob‖∞ / (max f − min f)` (the paper's "L∞ error below 2 %"); equal to
    /// `linf_error` for a constant f.
    pub relative_linf_error: f64,
    /// Number of critical points (maxima, minima, saddles) of f_glob
    /// ([`morse::critical_points`]; Fig. 13(d)). Where f_glob is numerically flat (far from
    /// every anchor at small t, values ≈ 1e−300) rounding creates spurious critical points;
    /// see [`ScaleApproximation::significant_critical_points`].
    pub critical_points: usize,
    /// Critical points of f_glob that are not rounding artefacts: the extrema of f_glob with
    /// persistence ≥ [`SIGNIFICANT_PERSISTENCE`] · (max f − min f) and their paired saddles
    /// ([`morse::persistent_extrema`]; the 2g unpaired saddles of a genus-g surface are not
    /// counted).
    pub significant_critical_points: usize,
}

/// Relative persistence (in units of the range of f) below which a critical point of f_glob
/// is counted as a rounding artefact in [`ScaleApproximation::significant_critical_points`].
pub const SIGNIFICANT_PERSISTENCE: f64 = 1e-6;

/// The result of [`feature_approximation`]: the anchor set and one decomposition per scale.
#[derive(Clone, Debug)]
pub struct FeatureApproximation {
    /// The anchors A: the persistent critical points of f (extrema and their paired saddles).
    pub anchors: Vec<u32>,
    /// The eigenvalue λ_k of the time scale.
    pub lambda_k: f64,
    /// Number of critical points of f itself.
    pub input_critical_points: usize,
    /// One entry per scale, increasing t.
    pub scales: Vec<ScaleApproximation>,
}

/// The global component `f_glob = Σ_{i∈A} cᵢ K_t eᵢ` of f on the anchors at time t (paper,
/// Sect. 4.2), with the coefficients of `coefficients`.
///
/// # Errors
/// [`HeatError::LengthMismatch`], [`HeatError::NonFiniteInput`], [`HeatError::InvalidTime`],
/// [`HeatError::InvalidParameter`] for a bad or repeated anchor or a singular anchor matrix.
pub fn global_component(
    kernel: &HeatKernel,
    anchors: &[u32],
    f: &[f64],
    t: f64,
    coefficients: Coefficients,
) -> Result<Vec<f64>, HeatError> {
    let n = kernel.n();
    check_vector(f, n)?;
    check_anchors(anchors, n)?;
    check_time(t)?;
    match coefficients {
        Coefficients::FeatureValues => {
            // Σ f(pᵢ) K_t eᵢ = K_t (Σ f(pᵢ) eᵢ): one application (linearity of Eq. (21)).
            let mut masked = vec![0.0; n];
            for &a in anchors {
                masked[a as usize] = f[a as usize];
            }
            kernel.apply(&masked, t)
        }
        Coefficients::Interpolate => {
            let mut sorted = anchors.to_vec();
            sorted.sort_unstable();
            if let Some(w) = sorted.windows(2).find(|w| w[0] == w[1]) {
                return Err(HeatError::InvalidParameter {
                    name: "anchors",
                    reason: format!("vertex {} is repeated", w[0]),
                });
            }
            let m = anchors.len();
            if m == 0 {
                return Ok(vec![0.0; n]);
            }
            let basis = canonical_basis(kernel, anchors, t)?;
            let g = Mat::<f64>::from_fn(m, m, |r, c| basis[(anchors[r] as usize, c)]);
            let rhs = Mat::<f64>::from_fn(m, 1, |r, _| f[anchors[r] as usize]);
            let c = g.partial_piv_lu().solve(&rhs);
            if c.col(0).iter().any(|x| !x.is_finite()) {
                return Err(HeatError::InvalidParameter {
                    name: "anchors",
                    reason: format!("the anchor matrix K_t[A,A] is singular at t = {t:e}"),
                });
            }
            let out = &basis * &c;
            Ok(out.col(0).iter().copied().collect())
        }
    }
}

/// The multiscale times `tᵢ = (i/10) λ_k⁻¹`, i = 1..=scales (paper, Sect. 4.2).
pub fn multiscale_times(lambda_k: f64, scales: usize) -> Vec<f64> {
    (1..=scales).map(|i| i as f64 / 10.0 / lambda_k).collect()
}

fn linf(a: &[f64]) -> f64 {
    a.iter().fold(0.0f64, |m, &x| m.max(x.abs()))
}

/// The feature-driven approximation of f (paper, Sect. 4.2, Fig. 12–13): the anchors A are
/// the critical points of f with persistence above `params.persistence`
/// ([`morse::persistence`], [`morse::persistent_extrema`]), and for every scale
/// `tᵢ = (i/10) λ_k⁻¹` (λ_k the k-th smallest eigenvalue of `L x = λ M x`, by a partial
/// eigensolve) f splits into `f_glob = Σ_{i∈A} cᵢ K_t eᵢ` ([`global_component`]) and
/// `f_loc = f − f_glob`, with the L∞ error and the number of critical points of f_glob
/// (Fig. 13(d)).
///
/// # Errors
/// [`HeatError::LengthMismatch`]/[`HeatError::NonFiniteInput`] for a bad f;
/// [`HeatError::InvalidParameter`] for k = 0, k > n, scales = 0 or a negative/NaN threshold;
/// [`HeatError::Mesh`] when the mesh and the kernel disagree or the mesh is not manifold
/// (critical points); the eigensolver and kernel errors. `ops` are the operators `kernel`
/// was built from (its stiffness L enters the eigensolve with the kernel's mass).
pub fn feature_approximation(
    mesh: &TriMesh,
    ops: &FemOperators,
    kernel: &HeatKernel,
    f: &[f64],
    params: &ApproxParams,
) -> Result<FeatureApproximation, HeatError> {
    let n = kernel.n();
    if mesh.n_vertices() != n {
        return Err(HeatError::LengthMismatch {
            expected: n,
            found: mesh.n_vertices(),
        });
    }
    check_vector(f, n)?;
    if params.scales == 0 {
        return Err(HeatError::InvalidParameter {
            name: "scales",
            reason: "must be positive".into(),
        });
    }
    let threshold_ok = match params.persistence {
        Persistence::Relative(x) | Persistence::Absolute(x) => x.is_finite() && x >= 0.0,
    };
    if !threshold_ok {
        return Err(HeatError::InvalidParameter {
            name: "persistence",
            reason: format!("{:?} must be finite and non-negative", params.persistence),
        });
    }
    let diagram = morse::persistence(mesh, f)?;
    let anchors = match params.persistence {
        Persistence::Relative(x) => morse::persistent_extrema_relative(&diagram, x),
        Persistence::Absolute(x) => morse::persistent_extrema(&diagram, x),
    };
    let input_critical_points = morse::critical_points(mesh, f)?.len();
    if ops.stiffness.nrows() != n {
        return Err(HeatError::InconsistentOperators {
            reason: format!("operators of {} vertices, kernel of {n}", ops.stiffness.nrows()),
        });
    }
    let eig = Eigenbasis::partial(&ops.stiffness, kernel.mass(), params.k, &params.eigen)?;
    let lambda_k = eig.values[params.k - 1];
    if lambda_k.is_nan() || lambda_k <= 0.0 {
        return Err(HeatError::InvalidParameter {
            name: "k",
            reason: format!(
                "λ_{} = {lambda_k:e} is not positive (too few vertices or components)",
                params.k
            ),
        });
    }
    let (lo, hi) = f
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| (a.min(x), b.max(x)));
    let range = hi - lo;
    let mut scales = Vec::with_capacity(params.scales);
    for t in multiscale_times(lambda_k, params.scales) {
        let global = global_component(kernel, &anchors, f, t, params.coefficients)?;
        let local: Vec<f64> = f.iter().zip(&global).map(|(a, b)| a - b).collect();
        let linf_error = linf(&local);
        let critical_points = morse::critical_points(mesh, &global)?.len();
        let significant_critical_points = if range > 0.0 {
            morse::persistent_extrema(&morse::persistence(mesh, &global)?, SIGNIFICANT_PERSISTENCE * range).len()
        } else {
            critical_points
        };
        scales.push(ScaleApproximation {
            t,
            linf_error,
            relative_linf_error: if range > 0.0 { linf_error / range } else { linf_error },
            critical_points,
            significant_critical_points,
            global,
            local,
        });
    }
    Ok(FeatureApproximation {
        anchors,
        lambda_k,
        input_critical_points,
        scales,
    })
}

// ---------------------------------------------------------------------------------------
// Scale (Sect. 5)
// ---------------------------------------------------------------------------------------

/// Options of [`largest_eigenvalue`] (Lanczos on M⁻¹L).
#[derive(Clone, Debug, PartialEq)]
pub struct LargestEigenParams {
    /// Relative residual tolerance `‖M⁻¹Lx − θx‖_M ≤ tol·θ` of the largest Ritz pair.
    pub tol: f64,
    /// Maximum number of Lanczos steps (capped at n).
    pub max_iter: usize,
    /// Seed of the random start vector.
    pub seed: u64,
}

impl Default for LargestEigenParams {
    fn default() -> Self {
        Self {
            tol: 1e-10,
            max_iter: 300,
            seed: 0x1a2b_3c4d,
        }
    }
}

/// The largest eigenvalue λ_n of `L x = λ M x` (paper, Sect. 5: the normalisation of the
/// scale-invariant kernel, "computed using the inverse method").
///
/// Lanczos on S = M⁻¹L, which is self-adjoint in ⟨u, v⟩_M = uᵀMv, with full
/// reorthogonalisation in that inner product: each step is one product with L and one solve
/// with M (sparse Cholesky, factored once). The largest Ritz value θ of the tridiagonal
/// projection converges first (an extreme eigenvalue); it stops when the residual
/// `β_m |y_m| ≤ tol·θ` (then |θ − λ_n| ≲ tol²·λ_n·(gap factor) and θ ≤ λ_n always).
///
/// # Errors
/// [`HeatError::InconsistentOperators`] for mismatched sizes; [`HeatError::NotPositiveDefinite`]
/// if M is not SPD; [`HeatError::InvalidParameter`] for bad options or if the iteration does
/// not reach the tolerance in `max_iter` steps.
pub fn largest_eigenvalue(
    stiffness: &SparseColMat<usize, f64>,
    mass: &SparseColMat<usize, f64>,
    params: &LargestEigenParams,
) -> Result<f64, HeatError> {
    let n = stiffness.nrows();
    if stiffness.ncols() != n || mass.nrows() != n || mass.ncols() != n || !crate::sparse::same_pattern(stiffness, mass)
    {
        return Err(HeatError::InconsistentOperators {
            reason: "stiffness and mass must be square on one pattern".into(),
        });
    }
    if !(params.tol > 0.0 && params.tol < 1.0) {
        return Err(HeatError::InvalidParameter {
            name: "tol",
            reason: format!("{} is not in (0, 1)", params.tol),
        });
    }
    if params.max_iter == 0 || n == 0 {
        return Err(HeatError::InvalidParameter {
            name: "max_iter",
            reason: "must be positive (and the mesh non-empty)".into(),
        });
    }
    let pattern = CholeskyPattern::new(mass)?;
    let factor = pattern.factor(mass, || "mass matrix M".into())?;
    let m_norm = |x: &[f64]| -> f64 {
        let mx = spmv_sym(mass, x);
        x.iter().zip(&mx).map(|(a, b)| a * b).sum::<f64>().max(0.0).sqrt()
    };
    let steps = params.max_iter.min(n);
    let mut rng = SplitMix(params.seed);
    let mut v: Vec<f64> = (0..n).map(|_| rng.next_f64()).collect();
    let nv = m_norm(&v);
    v.iter_mut().for_each(|x| *x /= nv);
    let mut basis: Vec<Vec<f64>> = Vec::with_capacity(steps);
    let mut mbasis: Vec<Vec<f64>> = Vec::with_capacity(steps);
    let mut alpha: Vec<f64> = Vec::new();
    let mut beta: Vec<f64> = Vec::new();
    let mut last = f64::NAN;
    for j in 0..steps {
        let mv = spmv_sym(mass, &v);
        basis.push(v.clone());
        mbasis.push(mv);
        // w = M⁻¹ L v; α = ⟨w, v⟩_M = vᵀLv.
        let lv = spmv_sym(stiffness, &v);
        let a: f64 = lv.iter().zip(&v).map(|(x, y)| x * y).sum();
        alpha.push(a);
        let mut w = factor.solve_vec(&lv);
        // Full reorthogonalisation (twice) in the M-inner product.
        for _ in 0..2 {
            for (q, mq) in basis.iter().zip(&mbasis) {
                let c: f64 = w.iter().zip(mq).map(|(x, y)| x * y).sum();
                w.iter_mut().zip(q).for_each(|(x, y)| *x -= c * y);
            }
        }
        let b = m_norm(&w);
        // Ritz values of the (j+1)×(j+1) tridiagonal matrix.
        let m = j + 1;
        let tri = Mat::<f64>::from_fn(m, m, |r, c| {
            if r == c {
                alpha[r]
            } else if r + 1 == c {
                beta[r]
            } else if c + 1 == r {
                beta[c]
            } else {
                0.0
            }
        });
        let evd = tri.self_adjoint_eigen(Side::Lower).map_err(|_| HeatError::DenseEigen)?;
        let theta = evd.S()[m - 1];
        let residual = b * evd.U()[(m - 1, m - 1)].abs();
        last = residual / theta.abs().max(f64::MIN_POSITIVE);
        if residual <= params.tol * theta.abs() || m == n || b <= f64::EPSILON * theta.abs() {
            return Ok(theta);
        }
        beta.push(b);
        v = w.iter().map(|x| x / b).collect();
    }
    Err(HeatError::InvalidParameter {
        name: "max_iter",
        reason: format!("Lanczos for λ_n did not converge in {steps} steps (relative residual {last:.2e})"),
    })
}

/// How [`NormalizedHeatKernel`] makes the time dimensionless (paper, Sect. 5).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Normalization {
    /// Eigenvalues divided by the largest one, λ/λ_n ∈ [0, 1] (the paper's choice):
    /// `K̂_τ = exp(−τ M⁻¹L/λ_n) = K_{τ/λ_n}`.
    #[default]
    LargestEigenvalue,
    /// By the surface area A = 1ᵀM1: `K̂_τ = K_{τ·A}`, i.e. eigenvalues λ·A. (The paper
    /// writes λ/area, which is not invariant: under M ↦ αM the eigenvalues scale by α⁻²
    /// and the area by α², so λ·A is the invariant combination.)
    Area,
}

/// A scale-invariant heat kernel (paper, Sect. 5): `K̂_τ = K_{τ/s}` with s = λ_n or s = 1/A
/// ([`Normalization`]). Because the wFEM kernel is scale-covariant,
/// `K_t(αM) = K_{α⁻²t}(M)` (λ ↦ α⁻²λ, B ↦ α²B), and s scales like α⁻², so
/// `K̂_τ(αM) = K̂_τ(M)` for every global scaling α.
#[derive(Debug)]
pub struct NormalizedHeatKernel {
    kernel: HeatKernel,
    normalization: Normalization,
    scale: f64,
}

impl NormalizedHeatKernel {
    /// Builds the kernel of `ops` with `params` ([`HeatKernel::new`]) and computes λ_n of
    /// `L x = λ M x` (M the kernel's mass) by [`largest_eigenvalue`], or the area 1ᵀM1.
    ///
    /// # Errors
    /// As [`HeatKernel::new`] and [`largest_eigenvalue`]; [`HeatError::InvalidParameter`] if
    /// the scale is not positive.
    pub fn new(ops: &FemOperators, params: HeatParams, normalization: Normalization) -> Result<Self, HeatError> {
        let kernel = HeatKernel::new(ops, params)?;
        let scale = match normalization {
            Normalization::LargestEigenvalue => {
                largest_eigenvalue(&ops.stiffness, kernel.mass(), &LargestEigenParams::default())?
            }
            Normalization::Area => {
                let n = kernel.n();
                1.0 / spmv_sym(kernel.mass(), &vec![1.0; n]).iter().sum::<f64>()
            }
        };
        if !(scale > 0.0 && scale.is_finite()) {
            return Err(HeatError::InvalidParameter {
                name: "normalization",
                reason: format!("{normalization:?} scale {scale:e} is not positive"),
            });
        }
        Ok(Self {
            kernel,
            normalization,
            scale,
        })
    }

    /// The normalising eigenvalue scale s: λ_n, or 1/A for [`Normalization::Area`].
    pub fn scale(&self) -> f64 {
        self.scale
    }

    /// The normalization used.
    pub fn normalization(&self) -> Normalization {
        self.normalization
    }

    /// The wrapped kernel.
    pub fn kernel(&self) -> &HeatKernel {
        &self.kernel
    }

    /// The physical time t = τ/s of the dimensionless time τ.
    pub fn time(&self, tau: f64) -> f64 {
        tau / self.scale
    }

    /// `K̂_τ f = K_{τ/s} f`.
    ///
    /// # Errors
    /// As [`HeatKernel::apply`].
    pub fn apply(&self, f: &[f64], tau: f64) -> Result<Vec<f64>, HeatError> {
        check_time(tau)?;
        self.kernel.apply(f, self.time(tau))
    }

    /// `K̂_τ` applied to every column of `f`.
    ///
    /// # Errors
    /// As [`HeatKernel::apply_many`].
    pub fn apply_many(&self, f: faer::MatRef<'_, f64>, tau: f64) -> Result<Mat<f64>, HeatError> {
        check_time(tau)?;
        self.kernel.apply_many(f, self.time(tau))
    }
}
