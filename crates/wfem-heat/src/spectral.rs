//! The spectral side of the kernel: generalized eigenpairs `L x = λ M x` (paper, Eq. (4)–(6)
//! and (8)) — the dense reference and a thick-restart shift-invert block Lanczos for the k
//! smallest pairs (the engine is shifted-solve's [`shifted_solve::eigen::largest_eigenpairs`]) —
//! and the (truncated) spectral kernel `X e^{−tΛ} Xᵀ`.
//!
//! L (stiffness) is symmetric positive **semi**definite with a positive diagonal (wfem sign
//! convention; the paper prints L with the opposite sign), M is the mass matrix of the
//! kernel (B, D or I), symmetric positive definite.

pub use crate::eigenbasis::Eigenbasis;
use crate::operators::AsSparse;
use crate::{HeatError, Operators};
use faer::linalg::triangular_solve::{solve_lower_triangular_in_place, solve_upper_triangular_in_place};
use faer::sparse::SparseColMatRef;
use faer::{Mat, MatRef, Par, Side};
use shifted_solve::eigen::{largest_eigenpairs, symmetric_block_mul, BlockLanczosParams};

/// The largest mesh (number of vertices) for which [`Eigenbasis::dense`] runs: O(n³) time
/// and 3 dense n × n matrices (≈ 600 MB at the limit).
pub const DENSE_MAX_VERTICES: usize = 5000;

/// Options of [`Eigenbasis::partial`] (thick-restart block Lanczos on the shift-inverted
/// operator, [`shifted_solve::eigen::largest_eigenpairs`]).
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
    /// The most basis vectors held at any time (the restart length, ARPACK's `ncv`): memory is
    /// n·max_dim doubles plus the factor. `None` = max(2k, k + 4b) + b, like ARPACK's
    /// ncv = 2k + 1 (scipy's `eigsh` default). Raised to k + 2b at least, and to n when within
    /// b of n (then the basis can span Rⁿ and the pairs are exact).
    pub max_dim: Option<usize>,
    /// Restarts allowed before [`HeatError::EigenNoConvergence`].
    pub max_restarts: usize,
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
            max_restarts: 100,
            seed: 0x5eed_2010,
        }
    }
}

impl EigenParams {
    /// The basis bound used for k pairs on n vertices (see [`Self::max_dim`]).
    pub fn basis_bound(&self, k: usize, n: usize) -> usize {
        let b = self.block_size.clamp(1, n.max(1));
        let bound = self
            .max_dim
            .unwrap_or_else(|| (2 * k).max(k + 4 * b) + b)
            .max(k + 2 * b);
        if bound + b >= n {
            n
        } else {
            bound
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
        // The symmetric part of C, power-of-two scaled for faer's eigensolver, which is not
        // scale invariant (mesh scaling by α multiplies C by α⁻²; see
        // `shifted_solve::lanczos::symmetric_eigen`, tested here by `eigen_scale.rs`).
        let (values, u) = shifted_solve::lanczos::symmetric_eigen(c.as_ref()).map_err(|_| HeatError::DenseEigen)?;
        drop(c);
        let mut x = u;
        solve_upper_triangular_in_place(r.transpose(), x.as_mut(), Par::rayon(0));
        Ok(Self { values, vectors: x })
    }

    /// The `k` smallest eigenpairs by thick-restart block Lanczos with locking, in the
    /// M-inner product, on the shift-inverted operator (docs/NUMERICS.md §5;
    /// [`shifted_solve::eigen::largest_eigenpairs`]).
    ///
    /// The operator S = (L − σM)⁻¹M (σ < 0, one sparse Cholesky of the SPD matrix L − σM) is
    /// self-adjoint in ⟨u, v⟩_M = uᵀMv and has eigenvalues θ = 1/(λ − σ), so the smallest λ
    /// are the largest θ and converge first. Ritz pairs are accepted when
    /// ‖Sx − θx‖_M ≤ tol·θ; then λ = σ + 1/θ and the Ritz vectors are M-orthonormal. The basis
    /// holds at most [`EigenParams::basis_bound`] vectors (about 2k, like ARPACK's `eigsh`):
    /// when it is full the iteration restarts from the best Ritz vectors, and converged pairs
    /// are locked.
    ///
    /// Small problems are handled exactly: when the bound reaches n the basis can span Rⁿ
    /// (the last block is the (n − dim)-dimensional M-orthogonal complement of the basis), so
    /// the Rayleigh–Ritz pairs are exact (any k ≤ n, any block size). An invariant block
    /// (rank-deficient remainder) is deflated by continuing with random directions
    /// M-orthogonal to the basis.
    ///
    /// # Errors
    /// [`HeatError::InvalidParameter`] for k = 0, k > n, a shift ≥ 0, block size 0 or a tol
    /// outside (0, 1); [`HeatError::InvalidOperatorEntry`] for a NaN/∞ entry or a non-positive
    /// diagonal of M; [`HeatError::NotPositiveDefinite`] if L − σM cannot be factored;
    /// [`HeatError::EigenNoConvergence`] (carrying the converged pairs) if `max_restarts`
    /// restarts do not suffice.
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
        crate::limits::eigenpairs("k", k, n)?;
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
        // S X = (L − σM)⁻¹ (M X): one block solve (n × b); the eigensolver supplies M X. M is
        // symmetric on the shared pattern, so its block products run over rows in parallel.
        let apply = |_: MatRef<'_, f64>, mx: MatRef<'_, f64>| -> Result<Mat<f64>, shifted_solve::SolveError> {
            let mut w = mx.to_owned();
            factor.solve_in_place(w.as_mut());
            Ok(w)
        };
        let mass = |x: MatRef<'_, f64>| symmetric_block_mul(ops.mass(), x);
        let lanczos = BlockLanczosParams {
            block_size: params.block_size,
            tol: params.tol,
            max_basis: params.basis_bound(k, n),
            max_restarts: params.max_restarts,
            seed: params.seed,
        };
        let outcome = largest_eigenpairs(n, k, &apply, &mass, &lanczos)?;
        let converged = outcome.values.len();
        // θ descending is λ = σ + 1/θ ascending.
        let basis = Self {
            values: outcome.values.iter().map(|&theta| sigma + 1.0 / theta).collect(),
            vectors: outcome.vectors,
        };
        if converged >= k {
            return Ok(basis);
        }
        Err(HeatError::EigenNoConvergence {
            requested: k,
            converged,
            dimension: outcome.basis_bound,
            max_residual: outcome.max_residual,
            found: Box::new(basis),
        })
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

    /// The spectral kernel matrix applied to a block, `X e^{−tΛ} Xᵀ G` (= `K̃_t G` with all
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
