//! The reproducing-kernel algebra of the wFEM heat kernel (paper, Sect. 3 and the start of
//! Sect. 4): the time-dependent scalar product `⟨·,·⟩_t` (Eq. (16); the mass product
//! `⟨·,·⟩_B` of Eq. (4) is [`Operators::mass_inner_product`]), the inverse `K_{−t} = K_t⁻¹`,
//! the reproducing kernel `H_t = X D_{−t} Xᵀ` (Prop. 3.1 B, Eq. (15)) and the two embeddings of
//! a vertex: the diffusion embedding `h_i = K_{t/2} e_i` (Eq. (18b)) and the reproducing
//! embedding `g_i = H_{t/2} e_i` (Eq. (18a), (20)).
//!
//! Notation: `K_t = X D_t Xᵀ B` (Eq. (6)) with `D_t = diag(e^{−λ_i t})` and B-orthonormal
//! eigenvectors `XᵀBX = I` (Eq. (4)); `S_t = B K_t = B X D_t Xᵀ B` induces `⟨·,·⟩_t`.
//! The paper's reproducing kernel is `H_t = X D_{−t} Xᵀ = K_{−t} B⁻¹ = S_t⁻¹` (it *grows*
//! with t); it is not the heat-kernel matrix `H̃_t = K_t B⁻¹ = X D_t Xᵀ` of the diffusion
//! distances (docs/NUMERICS.md §1), see [`crate::distance::DiffusionDistance`].
//!
//! **Two honest caveats** (the paper glosses over both):
//!
//! * Everything involving `D_{−t}` (`K_{−t}`, `H_t`, `g_i`) amplifies the eigencomponent of
//!   λ by e^{+tλ}, up to e^{tλ_max} ≈ e^{t·O(1/h²)} on a mesh of edge length h. Since e^{+x}
//!   has no uniform rational approximation on [0, ∞), the rational (Chebyshev) method cannot
//!   evaluate these operators. They are computed here either spectrally, truncated to the
//!   first k eigenpairs with a [`TruncationReport`] saying what was dropped, or (for
//!   `K_{−t} f`) by solving `K_t g = f` with conjugate gradients ([`inverse_cg`]), which
//!   refuses when the required amplification exceeds a cap.
//! * Eq. (17) as printed, `‖x_i − x_j‖_t² = exp(λ_i t) + exp(λ_j t)`, has a sign slip: from
//!   Eq. (16), `⟨x_i, x_j⟩_t = e^{−λ_i t} δ_ij`, so `‖x_i − x_j‖_t² = e^{−λ_i t} + e^{−λ_j t}`
//!   (the paper's own proof computes `e^{−λ_i t} δ_ij`). The tests check the corrected form.

use crate::check::{self, unit_columns};
use crate::operators::dot;
use crate::spectral::Eigenbasis;
use crate::{HeatError, HeatKernel, Operators};
use faer::Mat;

fn check_basis_size(basis: &Eigenbasis, ops: &Operators) -> Result<(), HeatError> {
    if basis.vectors.nrows() != ops.n() {
        return Err(HeatError::InconsistentOperators {
            reason: format!(
                "the eigenbasis has {} rows, the operators {} vertices",
                basis.vectors.nrows(),
                ops.n()
            ),
        });
    }
    Ok(())
}

/// The time-dependent scalar product `⟨f, g⟩_t = ⟨K_t f, g⟩_B = ⟨f, K_t g⟩_B = fᵀ S_t g`,
/// `S_t = B K_t = B X D_t Xᵀ B` (paper, Prop. 3.1 A, Eq. (16)), evaluated as the paper
/// suggests: `K_t g` by the kernel's method (the rational Chebyshev method by default), then
/// `fᵀ B (K_t g)`. S_t is symmetric positive definite with eigenvalues e^{−λ_i t} (in the
/// B-eigenbasis); with the rational method it is symmetric to rounding and accurate to
/// E_n‖f‖_B‖g‖_B.
///
/// # Errors
/// As [`HeatKernel::apply`].
pub fn heat_inner_product(kernel: &HeatKernel, f: &[f64], g: &[f64], t: f64) -> Result<f64, HeatError> {
    check::vector(f, kernel.n())?;
    let kg = kernel.apply(g, t)?;
    Ok(dot(f, &kernel.operators().mass_mul(&kg)))
}

/// What a spectrally truncated evaluation of an amplifying operator (`K_{−t}`, `H_t`) kept and
/// dropped.
#[derive(Clone, Debug, PartialEq)]
pub struct TruncationReport {
    /// Number k of eigenpairs used.
    pub k: usize,
    /// The largest eigenvalue used, λ_k.
    pub lambda_k: f64,
    /// The largest amplification applied, e^{tλ_k}.
    pub amplification: f64,
    /// `‖y − X_k X_kᵀ B y‖_B`: the B-norm of the part of the input function y outside
    /// span X_k, which was dropped (for `H_t v`, y = B⁻¹v).
    pub dropped_norm: f64,
    /// `‖y‖_B` of the input function, for scale.
    pub input_norm: f64,
}

impl TruncationReport {
    /// `dropped_norm / input_norm` (0 for a zero input).
    pub fn relative_dropped(&self) -> f64 {
        if self.input_norm > 0.0 {
            self.dropped_norm / self.input_norm
        } else {
            0.0
        }
    }
}

/// `X_k e^{+tΛ_k} X_kᵀ w` and the report, for w = B y given together with y.
fn amplify(basis: &Eigenbasis, ops: &Operators, y: &[f64], w: &[f64], t: f64) -> (Vec<f64>, TruncationReport) {
    let x = &basis.vectors;
    let k = x.ncols();
    let c = x.transpose() * faer::ColRef::from_slice(w);
    let proj = x * &c;
    let rest: Vec<f64> = (0..y.len()).map(|i| y[i] - proj[i]).collect();
    let dropped_norm = dot(&rest, &ops.mass_mul(&rest)).max(0.0).sqrt();
    let input_norm = dot(y, w).max(0.0).sqrt();
    let mut ca = c.to_owned();
    for (i, ci) in ca.iter_mut().enumerate() {
        *ci *= (t * basis.values[i]).exp();
    }
    let g = x * &ca;
    let lambda_k = basis.values.last().copied().unwrap_or(0.0);
    (
        g.iter().copied().collect(),
        TruncationReport {
            k,
            lambda_k,
            amplification: (t * lambda_k).exp(),
            dropped_norm,
            input_norm,
        },
    )
}

/// The inputs of the truncated inverse operators: t, the basis (its e^{tλ_k} finite) and the
/// vector `v` of length n.
fn check_input(basis: &Eigenbasis, ops: &Operators, v: &[f64], t: f64) -> Result<(), HeatError> {
    check::time(t)?;
    let n = basis.vectors.nrows();
    check_basis_size(basis, ops)?;
    if basis.values.len() != basis.vectors.ncols() || basis.values.is_empty() {
        return Err(HeatError::InvalidParameter {
            name: "basis",
            reason: format!(
                "{} eigenvalues for {} eigenvectors",
                basis.values.len(),
                basis.vectors.ncols()
            ),
        });
    }
    let lambda_k = basis.values[basis.values.len() - 1];
    let amplification = (t * lambda_k).exp();
    if !amplification.is_finite() {
        return Err(HeatError::IllConditionedInverse {
            t,
            reason: format!("e^(tλ_k) overflows for λ_k = {lambda_k:e}; use fewer eigenpairs or a smaller t"),
            amplification,
            cap: f64::MAX,
            iterations: 0,
            relative_residual: f64::NAN,
        });
    }
    check::vector(v, n)
}

/// The inverse heat operator `K_{−t} f = K_t⁻¹ f = X D_{−t} Xᵀ B f` (paper, Sect. 4,
/// "inversion property"), **truncated** to the eigenpairs of `basis`:
/// `g = X_k e^{+tΛ_k} X_kᵀ B f`. Exact (to rounding) for f in span X_k; the part of f outside
/// span X_k is dropped and its B-norm reported, together with k, λ_k and the amplification
/// e^{tλ_k} that was applied to the highest kept component. `basis` must be B-orthonormal for
/// the same mass (e.g. from [`Eigenbasis::dense`] or [`Eigenbasis::partial`]).
///
/// Why truncate: `‖K_{−t}‖_{B→B} = e^{tλ_max}`, astronomic on a fine mesh, and e^{+x} has no
/// uniform rational approximation on [0, ∞), so there is no "Chebyshev" evaluation of K_{−t}
/// on arbitrary data. See [`inverse_cg`] for a spectrum-free alternative.
///
/// # Errors
/// [`HeatError::InvalidTime`], [`HeatError::LengthMismatch`], [`HeatError::NonFiniteInput`],
/// [`HeatError::IllConditionedInverse`] if e^{tλ_k} overflows.
pub fn inverse_spectral(
    basis: &Eigenbasis,
    ops: &Operators,
    f: &[f64],
    t: f64,
) -> Result<(Vec<f64>, TruncationReport), HeatError> {
    check_input(basis, ops, f, t)?;
    let bf = ops.mass_mul(f);
    Ok(amplify(basis, ops, f, &bf, t))
}

/// The reproducing kernel of `(F(M), ⟨·,·⟩_t)` applied to a vector,
/// `H_t v = X D_{−t} Xᵀ v = K_{−t} B⁻¹ v = S_t⁻¹ v` (paper, Prop. 3.1 B; Eq. (20):
/// `B y = v`, `H_t v = K_{−t} y`), **truncated** to the eigenpairs of `basis`:
/// `X_k e^{+tΛ_k} X_kᵀ v`. The column `H_t e_i` is the representer `H_t(·, p_i)` of the
/// reproduction property `⟨H_t(·, p_i), f⟩_t = f(p_i)` (Eq. (15)), which then holds exactly
/// for every f in span X_k (band-limited f).
///
/// The report's dropped part is that of `y = B⁻¹ v` (one sparse Cholesky solve with B), the
/// function to which K_{−t} is applied in Eq. (20b). Same caveat as [`inverse_spectral`]: H_t
/// amplifies by up to e^{tλ_max}, so only the truncated operator is computable.
///
/// # Errors
/// As [`inverse_spectral`]; [`HeatError::NotPositiveDefinite`] if B cannot be factored.
pub fn reproducing_kernel_apply(
    basis: &Eigenbasis,
    ops: &Operators,
    v: &[f64],
    t: f64,
) -> Result<(Vec<f64>, TruncationReport), HeatError> {
    check_input(basis, ops, v, t)?;
    let y = ops.mass_factor()?.solve_vec(v);
    Ok(amplify(basis, ops, &y, v, t))
}

/// The wFEM diffusion-map embedding of vertex i, `h_i^t = K_{t/2} e_i` (paper, Eq. (18b)),
/// by the kernel's method, so that `⟨h_i, h_j⟩_B = S_t(i, j)` and
/// `‖h_i − h_j‖_B² = S_t(i,i) − 2S_t(i,j) + S_t(j,j)`. Several vertices at once:
/// [`diffusion_embeddings`].
///
/// # Errors
/// [`HeatError::VertexOutOfRange`]; as [`HeatKernel::apply`].
pub fn diffusion_embedding(kernel: &HeatKernel, i: usize, t: f64) -> Result<Vec<f64>, HeatError> {
    let m = diffusion_embeddings(kernel, &[i], t)?;
    Ok(m.col(0).iter().copied().collect())
}

/// The embeddings `[h_{i_1}, …, h_{i_m}] = K_{t/2} [e_{i_1}, …]` (paper, Eq. (18b)) as the
/// columns of an n × m matrix; one factorization serves all columns.
///
/// # Errors
/// As [`diffusion_embedding`].
pub fn diffusion_embeddings(kernel: &HeatKernel, vertices: &[usize], t: f64) -> Result<Mat<f64>, HeatError> {
    check::time(t)?;
    let e = unit_columns(kernel.n(), vertices)?;
    kernel.apply_many(e.as_ref(), 0.5 * t)
}

/// The reproducing (RKHS) embedding of vertex i, `g_i^t = H_{t/2} e_i = X D_{−t/2} Xᵀ e_i`
/// (paper, Eq. (18a), (20)), truncated to the eigenpairs of `basis` (see
/// [`reproducing_kernel_apply`] for why), so that
/// `⟨g_i, g_j⟩_B = H_t(i, j)` for the truncated H_t, hence
/// `‖g_i − g_j‖_B² = H_t(i,i) − 2H_t(i,j) + H_t(j,j)` (the display after Eq. (20) prints
/// `H_{t/2}` entries: with `g_i = H_{t/2} e_i` the Gram matrix is H_t, by Eq. (19)).
///
/// # Errors
/// [`HeatError::VertexOutOfRange`]; as [`reproducing_kernel_apply`].
pub fn reproducing_embedding(
    basis: &Eigenbasis,
    ops: &Operators,
    i: usize,
    t: f64,
) -> Result<(Vec<f64>, TruncationReport), HeatError> {
    let n = basis.vectors.nrows();
    let e = unit_columns(n, &[i])?;
    let e: Vec<f64> = e.col(0).iter().copied().collect();
    reproducing_kernel_apply(basis, ops, &e, 0.5 * t)
}

/// Options of [`inverse_cg`].
#[derive(Clone, Debug, PartialEq)]
pub struct InverseParams {
    /// Refuse when the amplification ‖g‖_B / ‖f‖_B exceeds this cap (default 1e6).
    pub max_amplification: f64,
    /// Stop when the normwise backward error `‖f − K_t g‖_B / (‖f‖_B + ‖g‖_B)` (note
    /// `‖K_t‖_{B→B} = 1`) is at most `tol` (default 1e−10). The forward error is then at most
    /// about `tol` times the amplification.
    pub tol: f64,
    /// Maximum number of CG iterations (each one application of K_t), default 300.
    pub max_iter: usize,
    /// Refuse as stalled when the residual has not halved within this many iterations
    /// (default 40).
    pub stall_window: usize,
}

impl Default for InverseParams {
    fn default() -> Self {
        Self {
            max_amplification: 1e6,
            tol: 1e-10,
            max_iter: 300,
            stall_window: 40,
        }
    }
}

/// What [`inverse_cg`] did.
#[derive(Clone, Debug, PartialEq)]
pub struct InverseReport {
    /// CG iterations (applications of K_t).
    pub iterations: usize,
    /// True relative residual `‖f − K_t g‖_B / ‖f‖_B` of the returned g (recomputed).
    pub relative_residual: f64,
    /// The amplification `‖g‖_B / ‖f‖_B` met.
    pub amplification: f64,
}

/// The inverse heat operator `g = K_{−t} f = K_t⁻¹ f` (paper, Sect. 4) without eigenpairs:
/// conjugate gradients on `K_t g = f` in the B-inner product. K_t is B-self-adjoint positive
/// definite (Prop. 3.1 A; the rational approximant keeps this exactly), so CG applies, each
/// iteration costing one application of K_t with the kernel's method (the rational factors of
/// t are factored once and reused).
///
/// **What "the computation of K_{−t} is stable" (paper, after Eq. (20)) does and does not
/// mean.** It is true that every step is a stable evaluation of K_t, so g is computed with a
/// small *backward* error: `K_t g = f + r` with `‖r‖_B ≤ tol·(‖f‖_B + ‖g‖_B)`. It is not true
/// that K_{−t} is a well-conditioned map: `‖K_{−t}‖_{B→B} = e^{tλ_max}`, so a perturbation
/// (rounding, the E_n ≈ 1e−14 error of the rational method, noise in f) in the eigencomponent
/// of λ is amplified by e^{tλ}. The result is meaningful only for band-limited f, whose
/// components above some λ_k are negligible, and its forward error is about tol·e^{tλ_k}.
/// Hence this routine measures the amplification ‖g‖_B/‖f‖_B it meets and refuses, rather
/// than return amplified noise, when it exceeds [`InverseParams::max_amplification`] or the
/// residual stalls (the rational K_t is accurate only to E_n, so residuals below about
/// E_n·‖g‖_B cannot be reached).
///
/// # Errors
/// [`HeatError::IllConditionedInverse`] (cap exceeded, stall, or `max_iter` reached);
/// [`HeatError::InvalidParameter`] for bad parameters; as [`HeatKernel::apply`].
pub fn inverse_cg(
    kernel: &HeatKernel,
    f: &[f64],
    t: f64,
    params: &InverseParams,
) -> Result<(Vec<f64>, InverseReport), HeatError> {
    check::time(t)?;
    let n = kernel.n();
    check::vector(f, n)?;
    if params.max_amplification.is_nan() || params.max_amplification < 1.0 {
        return Err(HeatError::InvalidParameter {
            name: "max_amplification",
            reason: format!("{} must be at least 1", params.max_amplification),
        });
    }
    if !(params.tol > 0.0 && params.tol < 1.0) {
        return Err(HeatError::InvalidParameter {
            name: "tol",
            reason: format!("{} is not in (0, 1)", params.tol),
        });
    }
    if params.max_iter == 0 || params.stall_window == 0 {
        return Err(HeatError::InvalidParameter {
            name: "max_iter",
            reason: "max_iter and stall_window must be positive".into(),
        });
    }
    let ops = kernel.operators();
    let bdot = |a: &[f64], b: &[f64]| dot(a, &ops.mass_mul(b));
    let f_norm = bdot(f, f).max(0.0).sqrt();
    if f_norm == 0.0 {
        return Ok((
            vec![0.0; n],
            InverseReport {
                iterations: 0,
                relative_residual: 0.0,
                amplification: 0.0,
            },
        ));
    }
    let refuse = |reason: String, amplification: f64, iterations: usize, relative_residual: f64| {
        HeatError::IllConditionedInverse {
            t,
            reason,
            amplification,
            cap: params.max_amplification,
            iterations,
            relative_residual,
        }
    };
    let mut g = vec![0.0; n];
    let mut r = f.to_vec();
    let mut p = r.clone();
    let mut rr = bdot(&r, &r);
    let mut best = rr.sqrt();
    let mut best_at = 0usize;
    for it in 1..=params.max_iter {
        let q = kernel.apply(&p, t)?;
        let pq = bdot(&p, &q);
        let rel_res = rr.sqrt() / f_norm;
        if !pq.is_finite() || pq <= 0.0 {
            let amp = bdot(&g, &g).sqrt() / f_norm;
            return Err(refuse(
                format!("⟨p, K_t p⟩_B = {pq:e} is not positive: K_t g = f is not solvable to rounding"),
                amp,
                it,
                rel_res,
            ));
        }
        let alpha = rr / pq;
        for i in 0..n {
            g[i] += alpha * p[i];
            r[i] -= alpha * q[i];
        }
        let rr_new = bdot(&r, &r);
        let g_norm = bdot(&g, &g).max(0.0).sqrt();
        let amp = g_norm / f_norm;
        let res = rr_new.max(0.0).sqrt();
        if amp > params.max_amplification || !amp.is_finite() {
            return Err(refuse(
                "the amplification exceeds the cap: f is not band-limited enough for this t".into(),
                amp,
                it,
                res / f_norm,
            ));
        }
        if res <= params.tol * (f_norm + g_norm) {
            // Recompute the true residual of the returned g.
            let kg = kernel.apply(&g, t)?;
            let rt: Vec<f64> = f.iter().zip(&kg).map(|(a, b)| a - b).collect();
            let relative_residual = bdot(&rt, &rt).max(0.0).sqrt() / f_norm;
            return Ok((
                g,
                InverseReport {
                    iterations: it,
                    relative_residual,
                    amplification: amp,
                },
            ));
        }
        if res < 0.5 * best {
            best = res;
            best_at = it;
        } else if it - best_at >= params.stall_window {
            return Err(refuse(
                format!(
                    "the residual stopped halving for {} iterations: f has components that K_t damps \
                     below its own accuracy, i.e. it is not band-limited at this t (smooth it, e.g. \
                     f = K_s h, or use a smaller t)",
                    params.stall_window
                ),
                amp,
                it,
                res / f_norm,
            ));
        }
        let beta = rr_new / rr;
        rr = rr_new;
        for i in 0..n {
            p[i] = r[i] + beta * p[i];
        }
    }
    let amp = bdot(&g, &g).max(0.0).sqrt() / f_norm;
    Err(refuse(
        format!("no convergence in {} iterations", params.max_iter),
        amp,
        params.max_iter,
        rr.sqrt() / f_norm,
    ))
}
