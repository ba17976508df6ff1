//! Shape-driven feature points and the feature-driven approximation `f = f_glob + f_loc`
//! (paper, Sect. 4.2, Fig. 12–13): the global component is spanned by the canonical basis
//! functions `K_t eᵢ` of the persistent critical points of f.

use crate::basis::{canonical_basis, check_anchors};
use crate::check;
use crate::spectral::{EigenParams, Eigenbasis};
use crate::{HeatError, HeatKernel};
use faer::linalg::solvers::Solve;
use faer::Mat;
use mesh_fem::morse;
use mesh_fem::TriMesh;

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

/// How the coefficients of the global component are chosen.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Coefficients {
    /// The paper's definition, `f_glob = Σ_{i∈A} f(pᵢ) K_t eᵢ` (Sect. 4.2): the feature
    /// values themselves. Since `Σᵢ f(pᵢ) K_t eᵢ = K_t(f·χ_A)` it costs one application of
    /// K_t. With A = all vertices it is K_t f (→ f as t → 0); with a sparse A it is small
    /// (each K_t eᵢ has B-mass 1ᵀBeᵢ, see [`crate::basis::canonical_limit`]), so the L∞ error is ≈ ‖f‖∞
    /// (measured on the TOSCA cat with a noisy field: f_glob spans ±0.04 where f spans ±2.4).
    FeatureValues,
    /// Interpolation on the anchors (beyond the paper's formula, matching its wording "the
    /// approximation of specific f-values"): `f_glob = Σ_{i∈A} cᵢ K_t eᵢ` with
    /// `f_glob(pⱼ) = f(pⱼ)` for j ∈ A, i.e. `K_t[A,A] c = f_A` (an |A| × |A| LU solve; the
    /// basis costs |A| right-hand sides, one set of factorizations). At larger t the basis
    /// functions overlap and the interpolant oscillates between the anchors.
    Interpolate,
    /// The best approximation of f in the span of the feature-driven basis:
    /// `f_glob = Σ_{i∈A} cᵢ K_t eᵢ` minimising `‖f − f_glob‖_M` (the M-orthogonal projection
    /// onto span{K_t eᵢ : i ∈ A}; nearly dependent directions of the Gram matrix dropped).
    /// f_glob is then the part of f the persistent features and the scale t explain, and
    /// f_loc = f − f_glob is orthogonal to it. The default: it is never farther from f than the
    /// literal feature values (or 0) in the M-norm, and on a noisy smooth field it was the
    /// closest to the smooth part at every scale and anchor density tried
    /// (tests/it/basis.rs, `approx_default_is_a_meaningful_global_component`).
    #[default]
    LeastSquares,
    /// The paper's feature values with the basis normalised to a partition of unity:
    /// `f_glob = Σ_{i∈A} f(pᵢ) K_t eᵢ / Σ_{i∈A} K_t eᵢ` — a heat-kernel weighted average of the
    /// persistent feature values (Nadaraya–Watson regression with the heat kernel). It lies
    /// between the smallest and the largest feature value and it is smooth; with A = all
    /// vertices and non-negative weights it would be the paper's formula itself, `K_t f` (since
    /// `K_t 1 = 1`). The weights are the basis functions with their small negative lobes (the
    /// consistent mass does not preserve positivity) set to 0, so that f_glob is a convex
    /// combination (|A| columns, one block application). The default:
    /// on the TOSCA cat with a noisy linear field, its relative L∞ error stays at 0.29–0.43
    /// over the ten scales (the noise alone is ≈ 0.15), where the literal feature values give
    /// 0.5; but with very few anchors (2 on a smooth field) it is a crude two-valued field.
    Normalized,
}

wfem_choice::registry! {
    Coefficients as "coefficients" {
        Coefficients::LeastSquares = Coefficients::LeastSquares => "least-squares":
            "the best approximation of f in span{K_t e_i : i ∈ A} (M-orthogonal projection; default)",
        Coefficients::Normalized = Coefficients::Normalized => "normalized":
            "the feature values averaged with heat-kernel weights: Σ f(p_i) K_t e_i / Σ K_t e_i",
        Coefficients::FeatureValues = Coefficients::FeatureValues => "feature-values" ["paper"]:
            "the paper's literal f_glob = Σ_{i∈A} f(p_i) K_t e_i (small with sparse anchors)",
        Coefficients::Interpolate = Coefficients::Interpolate => "interpolate":
            "interpolate f on the anchors: Σ_{i∈A} c_i K_t e_i with f_glob(p_j) = f(p_j), j ∈ A",
    }
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
    check::vector(f, n)?;
    check_anchors(anchors, n)?;
    check::time(t)?;
    // Every rule is homogeneous of degree 1 in f: work on f/2ᵉ with 2ᵉ ≈ max|f| (exact), so
    // that the M-products of a field of 1e308 do not overflow, and scale back.
    let (down, up) = shifted_solve::pow2_scale(linf(f));
    if down != 1.0 {
        let scaled: Vec<f64> = f.iter().map(|x| x * down).collect();
        let g = global_component_unit(kernel, anchors, &scaled, t, coefficients)?;
        return Ok(g.into_iter().map(|x| x * up).collect());
    }
    global_component_unit(kernel, anchors, f, t, coefficients)
}

/// [`global_component`] of a validated field of moderate size.
fn global_component_unit(
    kernel: &HeatKernel,
    anchors: &[u32],
    f: &[f64],
    t: f64,
    coefficients: Coefficients,
) -> Result<Vec<f64>, HeatError> {
    let n = kernel.n();
    match coefficients {
        Coefficients::FeatureValues => {
            // Σ f(pᵢ) K_t eᵢ = K_t (Σ f(pᵢ) eᵢ): one application (linearity of Eq. (21)).
            let mut masked = vec![0.0; n];
            for &a in anchors {
                masked[a as usize] = f[a as usize];
            }
            kernel.apply(&masked, t)
        }
        Coefficients::Interpolate => interpolate(kernel, anchors, f, t),
        Coefficients::Normalized => normalized(kernel, anchors, f, t),
        Coefficients::LeastSquares => {
            let m = anchors.len();
            if m == 0 {
                return Ok(vec![0.0; n]);
            }
            // Φ = [K_t e_i]_{i∈A}; minimise ‖f − Φc‖_M: (ΦᵀMΦ) c = ΦᵀM f, solved through the
            // eigendecomposition of the Gram matrix with the directions below 1e−12 of its
            // largest eigenvalue dropped (nearly dependent basis functions at large t).
            let basis = canonical_basis(kernel, anchors, t)?;
            let ops = kernel.operators();
            let m_basis = ops.mass_mul_block(basis.as_ref());
            let gram = basis.transpose() * &m_basis;
            let gram = Mat::<f64>::from_fn(m, m, |r, c| 0.5 * (gram[(r, c)] + gram[(c, r)]));
            let mf = ops.mass_mul(f);
            let rhs = basis.transpose() * faer::ColRef::from_slice(&mf);
            let evd = gram
                .self_adjoint_eigen(faer::Side::Lower)
                .map_err(|_| HeatError::DenseEigen)?;
            let top = evd.S().column_vector().iter().fold(0.0f64, |a, &b| a.max(b));
            let mut y = evd.U().transpose() * &rhs;
            for (k, yk) in y.iter_mut().enumerate() {
                let s = evd.S()[k];
                *yk = if s > 1e-12 * top { *yk / s } else { 0.0 };
            }
            let c = evd.U() * &y;
            let out = &basis * &c;
            Ok(out.iter().copied().collect())
        }
    }
}

/// `Σ_{i∈A} f(pᵢ) wᵢ / Σ_{i∈A} wᵢ` with the weights `wᵢ = max(K_t eᵢ, 0)` (the exact weights are
/// positive; the computed ones carry rounding of ≈1e−12 of their maximum). Where every weight
/// is below the accuracy of the kernel (1e−9 of the largest total weight: far from all anchors
/// at a small t) the ratio would be noise over noise, and the value of the nearest anchor in
/// edge hops is used instead — the limit of the weighted average as t → 0.
fn normalized(kernel: &HeatKernel, anchors: &[u32], f: &[f64], t: f64) -> Result<Vec<f64>, HeatError> {
    let n = kernel.n();
    if anchors.is_empty() {
        return Ok(vec![0.0; n]);
    }
    let basis = canonical_basis(kernel, anchors, t)?;
    let mut num = vec![0.0; n];
    let mut den = vec![0.0; n];
    for (c, &a) in anchors.iter().enumerate() {
        let fa = f[a as usize];
        for i in 0..n {
            let w = basis[(i, c)].max(0.0);
            num[i] += fa * w;
            den[i] += w;
        }
    }
    let top = den.iter().fold(0.0f64, |a, &b| a.max(b));
    let floor = 1e-9 * top;
    let mut out: Vec<f64> = (0..n)
        .map(|i| if den[i] > floor { num[i] / den[i] } else { f64::NAN })
        .collect();
    if out.iter().any(|v| v.is_nan()) {
        // Multi-source breadth-first search from the anchors over the mesh graph.
        let pattern = kernel.operators().pair().pattern();
        let mut nearest = vec![usize::MAX; n];
        let mut queue = std::collections::VecDeque::new();
        for &a in anchors {
            let a = a as usize;
            if nearest[a] == usize::MAX {
                nearest[a] = a;
                queue.push_back(a);
            }
        }
        while let Some(v) = queue.pop_front() {
            for &w in &pattern.row_idx()[pattern.col_range(v)] {
                if nearest[w] == usize::MAX {
                    nearest[w] = nearest[v];
                    queue.push_back(w);
                }
            }
        }
        for (i, o) in out.iter_mut().enumerate() {
            if o.is_nan() {
                // A vertex in a component without anchors keeps f's own value (no feature there).
                *o = if nearest[i] == usize::MAX { f[i] } else { f[nearest[i]] };
            }
        }
    }
    Ok(out)
}

/// `Σ_{i∈A} cᵢ K_t eᵢ` with `K_t[A,A] c = f_A` (its value at every anchor is f there).
fn interpolate(kernel: &HeatKernel, anchors: &[u32], f: &[f64], t: f64) -> Result<Vec<f64>, HeatError> {
    let n = kernel.n();
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
    let out: Vec<f64> = (&basis * &c).col(0).iter().copied().collect();
    // Overlapping basis functions make K_t[A,A] nearly singular: the interpolant then swings
    // far beyond the data (measured up to 5e4 × the range of f) instead of approximating it.
    let data = f.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let swing = out.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    if swing > 1e3 * data.max(f64::MIN_POSITIVE) {
        return Err(HeatError::InvalidParameter {
            name: "anchors",
            reason: format!(
                "interpolating {m} anchors at t = {t:e} is unstable (values up to {swing:.1e} for data up to \
                 {data:.1e}: the basis functions overlap); use least squares or fewer anchors"
            ),
        });
    }
    Ok(out)
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
/// (critical points); the eigensolver and kernel errors.
pub fn feature_approximation(
    mesh: &TriMesh,
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
    check::vector(f, n)?;
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
    let eig = Eigenbasis::partial_of(kernel.operators(), params.k, &params.eigen)?;
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
