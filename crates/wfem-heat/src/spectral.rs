//! The spectral side of the kernel: generalized eigenpairs `L x = λ M x` (paper, Eq. (4)–(6)
//! and (8)) — the dense reference and a shift-invert block Lanczos for the k smallest pairs —
//! and the (truncated) spectral kernel `X e^{−tΛ} Xᵀ`.
//!
//! L (stiffness) is symmetric positive **semi**definite with a positive diagonal (wfem sign
//! convention; the paper prints L with the opposite sign), M is the mass matrix of the
//! kernel (B, D or I), symmetric positive definite.

use crate::operators::AsSparse;
use crate::{HeatError, Operators};
use faer::linalg::triangular_solve::{solve_lower_triangular_in_place, solve_upper_triangular_in_place};
use faer::sparse::SparseColMatRef;
use faer::{Mat, MatRef, Par, Side};
use shifted_solve::rng::SplitMix64;

/// The largest mesh (number of vertices) for which [`Eigenbasis::dense`] runs: O(n³) time
/// and 3 dense n × n matrices (≈ 600 MB at the limit).
pub const DENSE_MAX_VERTICES: usize = 5000;

/// Eigenpairs of the generalized problem `L xᵢ = λᵢ M xᵢ` (paper, Eq. (4)), sorted by
/// increasing λ, with M-orthonormal eigenvectors `XᵀMX = I`.
#[derive(Clone, Debug)]
pub struct Eigenbasis {
    /// Eigenvalues λ₁ ≤ λ₂ ≤ … (λ₁ ≈ 0 on a connected mesh, eigenvector the constant 1/√area).
    pub values: Vec<f64>,
    /// Eigenvectors as columns, n × k, M-orthonormal: `XᵀMX = I`.
    pub vectors: Mat<f64>,
}

/// Options of [`Eigenbasis::partial`] (shift-invert block Lanczos).
#[derive(Clone, Debug, PartialEq)]
pub struct EigenParams {
    /// Shift σ < 0 of the factored matrix `L − σM` (SPD because L is PSD). `None` picks
    /// σ = −0.01·4π/A with A = 1ᵀM1, i.e. 1% of the Weyl scale of the first eigenvalues.
    pub shift: Option<f64>,
    /// Block size b of the Lanczos iteration; must exceed the largest eigenvalue
    /// multiplicity among the wanted pairs (sphere: 2l+1; icosphere: at most 5).
    pub block_size: usize,
    /// Relative residual tolerance ‖Sx − θx‖_M / θ on the shift-inverted operator
    /// S = (L − σM)⁻¹M. The eigenvalue error is about the square of it.
    pub tol: f64,
    /// Maximum Krylov dimension (the basis is not restarted, so memory is 2·n·max_dim
    /// doubles); `None` = min(n, max(6k, k + 200)).
    pub max_dim: Option<usize>,
    /// Seed of the random start block.
    pub seed: u64,
}

impl Default for EigenParams {
    fn default() -> Self {
        Self {
            shift: None,
            block_size: 8,
            tol: 1e-10,
            max_dim: None,
            seed: 0x5eed_2010,
        }
    }
}

fn to_dense(a: SparseColMatRef<'_, usize, f64>) -> Mat<f64> {
    let n = a.nrows();
    let mut d = Mat::<f64>::zeros(n, a.ncols());
    let sym = a.symbolic();
    for j in 0..a.ncols() {
        for p in sym.col_range(j) {
            d[(sym.row_idx()[p], j)] += a.val()[p];
        }
    }
    d
}

impl Eigenbasis {
    /// All n eigenpairs by a dense generalized symmetric eigendecomposition: M = RRᵀ
    /// (Cholesky), C = R⁻¹LR⁻ᵀ, C = YΛYᵀ, X = R⁻ᵀY, so that `XᵀMX = I` (paper, Eq. (4)–(6)).
    /// This is the exact oracle of the test suite.
    ///
    /// # Errors
    /// [`HeatError::TooLargeForDense`] above [`DENSE_MAX_VERTICES`];
    /// [`HeatError::InvalidOperatorEntry`] for a NaN/∞ entry or a non-positive diagonal of M;
    /// [`HeatError::NotPositiveDefinite`] if M is not SPD; [`HeatError::DenseEigen`].
    pub fn dense(stiffness: impl AsSparse, mass: impl AsSparse) -> Result<Self, HeatError> {
        Self::dense_of(&Operators::from_matrices(stiffness.as_sparse(), mass.as_sparse())?)
    }

    /// [`Self::dense`] on a validated context.
    ///
    /// # Errors
    /// As [`Self::dense`].
    pub fn dense_of(ops: &Operators) -> Result<Self, HeatError> {
        per_component(ops, ops.n(), &|sub, _| Self::dense_connected(sub))
    }

    /// [`Self::dense`] of one connected context.
    fn dense_connected(ops: &Operators) -> Result<Self, HeatError> {
        let n = ops.n();
        if n > DENSE_MAX_VERTICES {
            return Err(HeatError::TooLargeForDense {
                n_vertices: n,
                limit: DENSE_MAX_VERTICES,
            });
        }
        let l = to_dense(ops.stiffness());
        let m = to_dense(ops.mass());
        let llt = m.llt(Side::Lower).map_err(|_| HeatError::NotPositiveDefinite {
            matrix: "mass matrix M (dense)".into(),
        })?;
        let r = llt.L();
        // Y = R⁻¹ L, then C = R⁻¹ Yᵀ = R⁻¹ L R⁻ᵀ (L symmetric).
        let mut y = l;
        solve_lower_triangular_in_place(r, y.as_mut(), Par::rayon(0));
        let mut c = y.transpose().to_owned();
        solve_lower_triangular_in_place(r, c.as_mut(), Par::rayon(0));
        // Symmetrize to remove rounding asymmetry before the symmetric solver, and scale C
        // by a power of two 2⁻ᵉ ≈ 1/max|cᵢⱼ| (exact, so the eigenvectors are unchanged and
        // λ = 2ᵉ·μ). faer 0.24's self-adjoint solver is not scale invariant: unlike LAPACK's
        // dstedc it does not normalise the tridiagonal matrix, and its secular-equation root
        // finder (svd/bidiag_svd.rs, `secular_eq_root_finder`) stops the secant iteration
        // when |f_cur − f_prev| ≤ ε, an ABSOLUTE bound on a function of units 1/λ. Mesh
        // scaling by α multiplies C by α⁻², so for α ≲ 1/32 the roots stopped early
        // (α = 2⁻¹⁰: λ₁ = 0 came out ≈ 5e−3, λ off by ≈ 2e−6 relative). With max|cᵢⱼ| ≈ 1
        // the solver always works at the scale where that bound is relative.
        let (down, up) = pow2_scale(c.as_ref());
        let c = Mat::<f64>::from_fn(n, n, |i, j| (0.5 * down) * (c[(i, j)] + c[(j, i)]));
        let evd = c.self_adjoint_eigen(Side::Lower).map_err(|_| HeatError::DenseEigen)?;
        let values: Vec<f64> = (0..n).map(|i| up * evd.S()[i]).collect();
        let mut x = evd.U().to_owned();
        solve_upper_triangular_in_place(r.transpose(), x.as_mut(), Par::rayon(0));
        Ok(Self { values, vectors: x })
    }

    /// The `k` smallest eigenpairs by shift-invert block Lanczos with full
    /// reorthogonalisation in the M-inner product (NUMERICS §5).
    ///
    /// The operator S = (L − σM)⁻¹M (σ < 0, one sparse Cholesky of the SPD matrix L − σM)
    /// is self-adjoint in ⟨u, v⟩_M = uᵀMv and has eigenvalues θ = 1/(λ − σ), so the
    /// smallest λ are the largest θ and converge first. Ritz pairs are accepted when
    /// ‖Sx − θx‖_M ≤ tol·θ; then λ = σ + 1/θ and the Ritz vectors are M-orthonormal.
    ///
    /// Small problems are handled exactly: when fewer than b directions remain, the last
    /// block is the (n − dim)-dimensional M-orthogonal complement of the basis, so the Krylov
    /// basis reaches Rⁿ and the Rayleigh–Ritz pairs are exact (any k ≤ n, any block size).
    /// An invariant block (rank-deficient remainder) is deflated by continuing with random
    /// directions M-orthogonal to the basis.
    ///
    /// # Errors
    /// [`HeatError::InvalidParameter`] for k = 0, k > n, a shift ≥ 0 or block size 0;
    /// [`HeatError::InvalidOperatorEntry`] for a NaN/∞ entry or a non-positive diagonal of M;
    /// [`HeatError::EigenNoConvergence`] (carrying the converged pairs) if the Krylov
    /// dimension limit is hit first.
    pub fn partial(
        stiffness: impl AsSparse,
        mass: impl AsSparse,
        k: usize,
        params: &EigenParams,
    ) -> Result<Self, HeatError> {
        Self::partial_of(
            &Operators::from_matrices(stiffness.as_sparse(), mass.as_sparse())?,
            k,
            params,
        )
    }

    /// [`Self::partial`] on a validated context.
    ///
    /// # Errors
    /// As [`Self::partial`].
    pub fn partial_of(ops: &Operators, k: usize, params: &EigenParams) -> Result<Self, HeatError> {
        let n = ops.n();
        if k == 0 || k > n {
            return Err(HeatError::InvalidParameter {
                name: "k",
                reason: format!("k = {k} must be in 1..={n}"),
            });
        }
        per_component(ops, k, &|sub, kc| {
            // A component with fewer vertices than a Lanczos block or than the pairs asked of
            // it is solved densely (exact and cheap).
            if kc == sub.n() || sub.n() <= params.block_size.max(16) {
                let mut basis = Self::dense_connected(sub)?;
                basis.values.truncate(kc);
                basis.vectors = basis.vectors.subcols(0, kc).to_owned();
                Ok(basis)
            } else {
                Self::partial_connected(sub, kc, params)
            }
        })
    }

    /// [`Self::partial`] of one connected context.
    fn partial_connected(ops: &Operators, k: usize, params: &EigenParams) -> Result<Self, HeatError> {
        let n = ops.n();
        if k == 0 || k > n {
            return Err(HeatError::InvalidParameter {
                name: "k",
                reason: format!("k = {k} must be in 1..={n}"),
            });
        }
        if params.block_size == 0 {
            return Err(HeatError::InvalidParameter {
                name: "block_size",
                reason: "must be positive".into(),
            });
        }
        if !(params.tol > 0.0 && params.tol < 1.0) {
            return Err(HeatError::InvalidParameter {
                name: "tol",
                reason: format!("{} is not in (0, 1)", params.tol),
            });
        }
        let sigma = match params.shift {
            Some(s) if s < 0.0 && s.is_finite() => s,
            Some(s) => {
                return Err(HeatError::InvalidParameter {
                    name: "shift",
                    reason: format!("σ = {s} must be finite and negative (L − σM must be SPD)"),
                })
            }
            None => {
                // Weyl's law λ_k ≈ 4πk/A (A = 1ᵀM1): a shift 1% of the first nonzero
                // eigenvalue's scale below zero keeps the wanted θ = 1/(λ − σ) well separated.
                -1e-2 * 4.0 * std::f64::consts::PI / ops.total_mass()
            }
        };
        let factor = ops.factor_combination(1.0, -sigma, || format!("L − σM with σ = {sigma:e}"))?;
        let mass = ops;

        let b = params.block_size.min(n);
        let max_dim = params
            .max_dim
            .unwrap_or_else(|| (6 * k).max(k + 200))
            .clamp(k.max(b), n);
        let max_blocks = max_dim.div_ceil(b);
        let cap = max_blocks * b;

        // Basis V (n × cap), MV = M V, projected matrix H = VᵀMSV.
        let mut v = Mat::<f64>::zeros(n, cap + b);
        let mut mv = Mat::<f64>::zeros(n, cap + b);
        let mut h = Mat::<f64>::zeros(cap + b, cap + b);
        let mut rng = SplitMix64::new(params.seed);
        let start = Mat::<f64>::from_fn(n, b, |_, _| rng.next_centered());
        let mut dim = 0usize; // number of basis columns so far
        let (q0, _) = m_orthonormalize(start, mass, &v, &mv, 0, &mut rng);
        let mq0 = mass.mass_mul_block(q0.as_ref());
        v.as_mut().get_mut(.., 0..b).copy_from(&q0);
        mv.as_mut().get_mut(.., 0..b).copy_from(&mq0);
        dim += b;
        // Size of the newest block: b, except a last partial block that completes Rⁿ.
        let mut bc = b;

        loop {
            let j0 = dim - bc;
            // W = S V_j = (L − σM)⁻¹ M V_j.
            let mut w = mv.as_ref().get(.., j0..dim).to_owned();
            factor.solve_in_place(w.as_mut());
            // Two passes of block classical Gram–Schmidt in the M-inner product.
            for _ in 0..2 {
                let coef = mv.as_ref().get(.., 0..dim).transpose() * &w;
                w -= v.as_ref().get(.., 0..dim) * &coef;
                let mut hb = h.as_mut().get_mut(0..dim, j0..dim);
                hb += &coef;
            }
            // The basis spans Rⁿ: the Rayleigh–Ritz pairs are the exact eigenpairs.
            let exhausted = dim >= n;
            let at_full = exhausted || dim >= cap;
            // Size of the next block: b, or the n − dim columns that complete the basis.
            let bn = b.min(n.saturating_sub(dim));
            // Ritz step: eigenpairs of the symmetrized projection.
            // θ = up·(eigenvalue of the power-of-two-normalised projection), see `pow2_scale`.
            let (down, up) = pow2_scale(h.as_ref().get(0..dim, 0..dim));
            let hm = Mat::<f64>::from_fn(dim, dim, |i, jj| (0.5 * down) * (h[(i, jj)] + h[(jj, i)]));
            let evd = hm.self_adjoint_eigen(Side::Lower).map_err(|_| HeatError::DenseEigen)?;
            // Residual of Ritz pair i: ‖W_rest · Q[last block, i]‖_M where W = V_{j+1} B_j.
            let (qn, bj) = if at_full {
                (Mat::<f64>::zeros(n, 0), Mat::<f64>::zeros(0, bc))
            } else if bn < bc {
                // Fewer than b directions remain: W (already M-orthogonal to V) lies in the
                // (n − dim)-dimensional M-orthogonal complement of V; take an M-orthonormal
                // basis Q of that complement (random block, projected) and B = QᵀMW.
                complement_block(w.as_ref(), bn, mass, &v, &mv, dim, &mut rng)
            } else {
                m_orthonormalize(w.clone(), mass, &v, &mv, dim, &mut rng)
            };
            let nk = k.min(dim);
            let mut converged = 0usize;
            let mut worst = 0.0f64;
            let mut order = Vec::with_capacity(nk);
            for r in 0..nk {
                let i = dim - 1 - r; // largest θ first
                let theta = up * evd.S()[i];
                let res = if exhausted {
                    0.0
                } else if at_full {
                    // Residual from the unnormalized remainder W.
                    let qi = evd.U().col(i).subrows(j0, bc);
                    let x = &w * qi;
                    let xs: Vec<f64> = x.iter().copied().collect();
                    let mx = mass.mass_mul(&xs);
                    xs.iter().zip(&mx).map(|(a, c)| a * c).sum::<f64>().max(0.0).sqrt()
                } else {
                    let qi = evd.U().col(i).subrows(j0, bc);
                    (&bj * qi).norm_l2()
                };
                let rel = res / theta.abs().max(f64::MIN_POSITIVE);
                worst = worst.max(rel);
                if rel <= params.tol && theta > 0.0 && converged == r {
                    converged += 1;
                }
                order.push(i);
            }
            if converged >= k || at_full {
                let take = if converged >= k { k } else { converged };
                let basis = ritz(&evd, up, &v, dim, &order[..take], sigma);
                if converged >= k {
                    return Ok(basis);
                }
                return Err(HeatError::EigenNoConvergence {
                    requested: k,
                    converged,
                    dimension: dim,
                    max_residual: worst,
                    found: Box::new(basis),
                });
            }
            // Extend the basis with the next block.
            let mq = mass.mass_mul_block(qn.as_ref());
            v.as_mut().get_mut(.., dim..dim + bn).copy_from(&qn);
            mv.as_mut().get_mut(.., dim..dim + bn).copy_from(&mq);
            h.as_mut().get_mut(dim..dim + bn, j0..dim).copy_from(&bj);
            dim += bn;
            bc = bn;
        }
    }

    /// Applies the (truncated) spectral heat kernel
    /// `F_k = X_k e^{−tΛ_k} X_kᵀ M f` (paper, Eq. (8); Eq. (6) when k = n), M the mass the
    /// eigenpairs were computed with.
    ///
    /// # Errors
    /// [`HeatError::InvalidTime`], [`HeatError::LengthMismatch`], [`HeatError::NonFiniteInput`].
    pub fn apply_heat(&self, mass: impl AsSparse, f: &[f64], t: f64) -> Result<Vec<f64>, HeatError> {
        crate::check::time(t)?;
        crate::check::vector(f, self.vectors.nrows())?;
        let mass = mass.as_sparse();
        if mass.nrows() != f.len() {
            return Err(HeatError::LengthMismatch {
                expected: mass.nrows(),
                found: f.len(),
            });
        }
        let mf: Vec<f64> = (0..f.len())
            .map(|j| {
                let rows = mass.symbolic().row_idx_of_col_raw(j);
                rows.iter().zip(mass.val_of_col(j)).map(|(&i, v)| v * f[i]).sum()
            })
            .collect();
        let g = self.heat_scaled(MatRef::from_column_major_slice(&mf, mf.len(), 1), t);
        Ok(g.col(0).iter().copied().collect())
    }

    /// The spectral kernel matrix applied to a block, `X e^{−tΛ} Xᵀ G` (= `H_t G` with all
    /// pairs; truncated to the pairs held otherwise).
    pub(crate) fn heat_scaled(&self, g: MatRef<'_, f64>, t: f64) -> Mat<f64> {
        let mut c = self.vectors.transpose() * g;
        for i in 0..c.nrows() {
            let d = (-t * self.values[i]).exp();
            for j in 0..c.ncols() {
                c[(i, j)] *= d;
            }
        }
        &self.vectors * &c
    }
}

/// Eigenpairs of a context with several connected components, component by component (L and
/// M do not couple them, so the spectrum is the union of theirs): `solve(sub, k_c)` gives the
/// k_c = min(k, n_c) smallest pairs of component c; the union is sorted and truncated to the k
/// smallest, the vectors scattered back to all n vertices. Each component's matrices are then
/// scaled for it alone: a stray tetrahedron of size 1e−12 next to a unit shape (eigenvalues
/// 1e24 times larger) left the joint dense decomposition 27 % off on the large part.
///
/// The smallest eigenvalue of a component whose constants are in the null space of L is set to
/// 0 exactly (it comes out as rounding noise ±ε‖M⁻¹L‖, and e^{−λt} of a noise λ = 1e−15 is
/// visibly off at t = 1e16 and 0 at t = 1e300 where it must be 1).
fn per_component(
    ops: &Operators,
    k: usize,
    solve: &dyn Fn(&Operators, usize) -> Result<Eigenbasis, HeatError>,
) -> Result<Eigenbasis, HeatError> {
    let components = ops.components();
    let single = components.len() == 1;
    let mut pairs: Vec<(f64, usize, usize)> = Vec::new(); // (λ, part, column)
    let mut parts: Vec<(Vec<usize>, Eigenbasis)> = Vec::with_capacity(components.len());
    for vertices in components {
        let (sub, basis) = if single {
            (ops.clone(), solve(ops, k)?)
        } else {
            let sub = ops.restrict(vertices)?;
            let kc = k.min(vertices.len());
            let basis = solve(&sub, kc)?;
            (sub, basis)
        };
        let mut basis = basis;
        if let Some(first) = basis.values.first_mut() {
            let null = sub.null_space_is_deflated();
            let scale = sub.mean_rayleigh_quotient();
            if null && first.abs() <= 1e-8 * scale {
                *first = 0.0;
            }
        }
        for (c, &lambda) in basis.values.iter().enumerate() {
            pairs.push((lambda, parts.len(), c));
        }
        parts.push((vertices.clone(), basis));
    }
    if single {
        if let Some((_, basis)) = parts.pop() {
            return Ok(basis);
        }
    }
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    pairs.truncate(k);
    let n = ops.n();
    let mut vectors = Mat::<f64>::zeros(n, pairs.len());
    for (col, &(_, part, c)) in pairs.iter().enumerate() {
        let (vertices, basis) = &parts[part];
        for (i, &v) in vertices.iter().enumerate() {
            vectors[(v, col)] = basis.vectors[(i, c)];
        }
    }
    Ok(Eigenbasis {
        values: pairs.iter().map(|p| p.0).collect(),
        vectors,
    })
}

/// (2⁻ᵉ, 2ᵉ) with 2ᵉ ≈ max|aᵢⱼ| (1 for a zero or non-finite matrix): multiplying by a power
/// of two is exact, so a matrix scaled by 2⁻ᵉ has the same eigenvectors and eigenvalues
/// exactly 2⁻ᵉ times the original. faer's self-adjoint eigensolver needs this (see
/// [`Eigenbasis::dense`]).
fn pow2_scale(a: faer::MatRef<'_, f64>) -> (f64, f64) {
    let mut amax = 0.0f64;
    for j in 0..a.ncols() {
        for i in 0..a.nrows() {
            amax = amax.max(a[(i, j)].abs());
        }
    }
    if amax > 0.0 && amax.is_finite() {
        let e = amax.log2().round().clamp(-1000.0, 1000.0) as i32;
        (2f64.powi(-e), 2f64.powi(e))
    } else {
        (1.0, 1.0)
    }
}

/// Ritz vectors of the chosen (largest-θ first) indices, converted to λ = σ + 1/θ and
/// sorted by increasing λ.
fn ritz(
    evd: &faer::linalg::solvers::SelfAdjointEigen<f64>,
    up: f64,
    v: &Mat<f64>,
    dim: usize,
    idx: &[usize],
    sigma: f64,
) -> Eigenbasis {
    let n = v.nrows();
    let mut q = Mat::<f64>::zeros(dim, idx.len());
    for (c, &i) in idx.iter().enumerate() {
        q.as_mut().col_mut(c).copy_from(evd.U().col(i));
    }
    let x = v.as_ref().get(.., 0..dim) * &q;
    let values: Vec<f64> = idx.iter().map(|&i| sigma + 1.0 / (up * evd.S()[i])).collect();
    // θ descending means λ ascending already; keep an explicit sort for safety.
    let mut perm: Vec<usize> = (0..idx.len()).collect();
    perm.sort_by(|&a, &b| values[a].total_cmp(&values[b]));
    let vectors = Mat::<f64>::from_fn(n, idx.len(), |i, c| x[(i, perm[c])]);
    Eigenbasis {
        values: perm.iter().map(|&p| values[p]).collect(),
        vectors,
    }
}

/// The last, partial Lanczos block when only `r` < b directions remain outside span(V)
/// (V = first `dim` columns of `v`, r = n − dim): an M-orthonormal basis Q (n × r) of the
/// M-orthogonal complement of V, from a random block projected twice against V and then
/// M-orthonormalized, and B = QᵀM·W (r × b), so that W = QB for W ⟂_M V.
fn complement_block(
    w: faer::MatRef<'_, f64>,
    r: usize,
    mass: &Operators,
    v: &Mat<f64>,
    mv: &Mat<f64>,
    dim: usize,
    rng: &mut SplitMix64,
) -> (Mat<f64>, Mat<f64>) {
    let n = w.nrows();
    let mut z = Mat::<f64>::from_fn(n, r, |_, _| rng.next_centered());
    for _ in 0..2 {
        let coef = mv.as_ref().get(.., 0..dim).transpose() * &z;
        z -= v.as_ref().get(.., 0..dim) * &coef;
    }
    let (q, _) = m_orthonormalize(z, mass, v, mv, dim, rng);
    let mq = mass.mass_mul_block(q.as_ref());
    let bj = mq.transpose() * w;
    (q, bj)
}

/// M-orthonormalizes the columns of `w` against the first `dim` columns of `v` (already
/// done by the caller, repeated here once for safety) and among themselves: returns (Q, R)
/// with W = Q R, QᵀMQ = I. Directions lost to rank deficiency (an invariant subspace) are
/// replaced by random vectors orthogonal to everything, with a zero row in R.
fn m_orthonormalize(
    mut w: Mat<f64>,
    mass: &Operators,
    v: &Mat<f64>,
    mv: &Mat<f64>,
    dim: usize,
    rng: &mut SplitMix64,
) -> (Mat<f64>, Mat<f64>) {
    let n = w.nrows();
    let b = w.ncols();
    let mut r_total = Mat::<f64>::identity(b, b);
    let mut first = true;
    for pass in 0..3 {
        if dim > 0 && pass > 0 {
            let coef = mv.as_ref().get(.., 0..dim).transpose() * &w;
            w -= v.as_ref().get(.., 0..dim) * &coef;
        }
        let mw = mass.mass_mul_block(w.as_ref());
        let g = w.transpose() * &mw;
        let (down, up) = pow2_scale(g.as_ref());
        let g = Mat::<f64>::from_fn(b, b, |i, j| (0.5 * down) * (g[(i, j)] + g[(j, i)]));
        let evd = match g.self_adjoint_eigen(Side::Lower) {
            Ok(e) => e,
            Err(_) => break,
        };
        let smax = (up * evd.S()[b - 1]).max(0.0);
        // W = (W U S^{-1/2}) (S^{1/2} Uᵀ).
        let mut q = Mat::<f64>::zeros(n, b);
        let mut r = Mat::<f64>::zeros(b, b);
        let wu = &w * evd.U();
        let mut replaced = false;
        for c in 0..b {
            let s = up * evd.S()[c];
            if s > 1e-24 * smax.max(f64::MIN_POSITIVE) && s > 0.0 {
                let sq = s.sqrt();
                for i in 0..n {
                    q[(i, c)] = wu[(i, c)] / sq;
                }
                for j in 0..b {
                    r[(c, j)] = sq * evd.U()[(j, c)];
                }
            } else {
                for i in 0..n {
                    q[(i, c)] = rng.next_centered();
                }
                replaced = true;
            }
        }
        w = q;
        r_total = if first { r } else { &r * &r_total };
        first = false;
        if !replaced && pass >= 1 {
            break;
        }
    }
    (w, r_total)
}
