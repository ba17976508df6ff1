//! The one Lanczos process of the workspace ([`LanczosProcess`]) and what needs only its
//! tridiagonal matrix: the extreme eigenvalues ([`largest_ritz_value`]). Functions of a
//! shift-and-invert operator are in `crate::function`.

use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatMut, MatRef, Par, Side};

use crate::SolveError;

/// Eigendecomposition of the symmetric tridiagonal T (diagonal `a`, off-diagonal `b`,
/// `b.len() ≥ a.len() − 1`): eigenvalues ascending and eigenvectors (columns), by
/// [`symmetric_eigen`].
pub(crate) fn tridiagonal_eigen(a: &[f64], b: &[f64]) -> Result<(Vec<f64>, Mat<f64>), SolveError> {
    let m = a.len();
    let t = Mat::<f64>::from_fn(m, m, |i, j| {
        if i == j {
            a[i]
        } else if i == j + 1 {
            b[j]
        } else if j == i + 1 {
            b[i]
        } else {
            0.0
        }
    });
    symmetric_eigen(t.as_ref())
}

/// Eigendecomposition of the symmetric part ½(A + Aᵀ) of a dense square matrix: eigenvalues
/// ascending and orthonormal eigenvectors (columns). The one dense symmetric eigensolver of the
/// workspace's Lanczos methods and of wfem-heat's dense reference.
///
/// A is first multiplied by a power of two 2⁻ᵉ ≈ 1/max|aᵢⱼ| (exact, so the eigenvectors are
/// unchanged and λ = 2ᵉ·μ). faer 0.24's self-adjoint solver is not scale invariant: unlike
/// LAPACK's dstedc it does not normalise the tridiagonal matrix, and its secular-equation root
/// finder (svd/bidiag_svd.rs, `secular_eq_root_finder`) stops the secant iteration when
/// |f_cur − f_prev| ≤ ε, an *absolute* bound on a function of units 1/λ: for a matrix scaled by
/// 2⁻¹⁰ it stopped early (λ off by ≈ 2e−6 relative). With max|aᵢⱼ| ≈ 1 the bound is relative.
///
/// # Errors
/// [`SolveError::Factorization`] if faer's eigendecomposition fails.
pub fn symmetric_eigen(a: MatRef<'_, f64>) -> Result<(Vec<f64>, Mat<f64>), SolveError> {
    let m = a.nrows();
    let mut big = 0.0f64;
    for j in 0..a.ncols() {
        for i in 0..m {
            big = big.max(a[(i, j)].abs());
        }
    }
    let (down, up) = pow2_scale(big);
    let sym = Mat::<f64>::from_fn(m, m, |i, j| (0.5 * down) * (a[(i, j)] + a[(j, i)]));
    let evd = sym
        .self_adjoint_eigen(Side::Lower)
        .map_err(|e| SolveError::Factorization {
            what: "dense symmetric eigendecomposition",
            detail: format!("{e:?}"),
        })?;
    Ok((
        evd.S().column_vector().iter().map(|&s| up * s).collect(),
        evd.U().to_owned(),
    ))
}

/// (2⁻ᵉ, 2ᵉ) with 2ᵉ ≈ `big` ((1, 1) for zero or non-finite): scaling by a power of two is
/// exact, so the eigenvectors are unchanged and the eigenvalues scale exactly (and a linear
/// map of a field of 1e308 computed on the scaled field does not overflow).
pub fn pow2_scale(big: f64) -> (f64, f64) {
    if big > 0.0 && big.is_finite() {
        let e = big.log2().round().clamp(-1000.0, 1000.0) as i32;
        (2f64.powi(-e), 2f64.powi(e))
    } else {
        (1.0, 1.0)
    }
}

/// Lanczos basis V (columns v_i), grown by doubling its column capacity.
struct Basis {
    v: Mat<f64>,
    len: usize,
}

impl Basis {
    fn new(n: usize, cap: usize) -> Self {
        Self {
            v: Mat::zeros(n, cap),
            len: 0,
        }
    }
    fn push(&mut self, x: &[f64], scale: f64) {
        if self.len == self.v.ncols() {
            let (n, cap) = (self.v.nrows(), 2 * self.v.ncols().max(1));
            let mut v = Mat::zeros(n, cap);
            v.as_mut()
                .get_mut(.., 0..self.len)
                .copy_from(self.v.as_ref().get(.., 0..self.len));
            self.v = v;
        }
        let j = self.len;
        for (i, a) in x.iter().enumerate() {
            self.v[(i, j)] = a * scale;
        }
        self.len += 1;
    }
    fn col(&self, j: usize) -> &[f64] {
        self.v.col_as_slice(j)
    }
}

/// An operator S for a [`LanczosProcess`]: `w = S v` given `v` and `M v`.
pub type LanczosOperator<'a> = dyn Fn(&[f64], &[f64]) -> Result<Vec<f64>, SolveError> + Sync + 'a;

/// How a [`LanczosProcess`] keeps its basis orthogonal.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reorthogonalization {
    /// The three-term recurrence with the α projection done twice. Enough for functions of
    /// the operator: finite-precision Lanczos then converges like exact Lanczos on a slightly
    /// enlarged spectral interval (Druskin & Knizhnerman 1991, Greenbaum 1989); lost
    /// orthogonality only duplicates converged Ritz values.
    Local,
    /// Two passes of classical Gram–Schmidt against the whole basis: needed when the Ritz
    /// values themselves are the answer (extreme eigenvalues, condition numbers).
    Full,
}

/// The one Lanczos process of the workspace: for an operator S self-adjoint in the inner
/// product ⟨u, v⟩_M = uᵀMv, m steps from a start vector u give
/// `S V_m = V_m T_m + β_m v_{m+1} e_mᵀ` with `V_mᵀ M V_m = I` and T_m tridiagonal.
///
/// Users: [`crate::function::lanczos_function`] (h(S)u, the fast path and the multi-shift backend), the
/// extreme eigenvalues of the condition estimates and of λ_max (wfem-heat's scale
/// normalisation).
pub struct LanczosProcess<'a> {
    /// `w = S v` given `v` and `M v`.
    apply: &'a LanczosOperator<'a>,
    mass: &'a (dyn Fn(&[f64]) -> Vec<f64> + Sync),
    reorth: Reorthogonalization,
    basis: Basis,
    /// `M v_j` of the newest basis vector (the next right-hand side of a shift-and-invert S).
    mv_last: Vec<f64>,
    norm: f64,
    alpha: Vec<f64>,
    beta: Vec<f64>,
}

impl<'a> LanczosProcess<'a> {
    /// Starts from `u` (normalised in the M-norm; a zero `u` gives an empty process).
    /// `capacity` is a hint for the number of steps.
    pub fn new(
        u: &[f64],
        apply: &'a LanczosOperator<'a>,
        mass: &'a (dyn Fn(&[f64]) -> Vec<f64> + Sync),
        reorth: Reorthogonalization,
        capacity: usize,
    ) -> Self {
        let n = u.len();
        let mu = mass(u);
        let norm = dot(u, &mu).max(0.0).sqrt();
        let mut basis = Basis::new(n, capacity.min(n).max(1) + 1);
        let mut mv_last = Vec::new();
        if norm > 0.0 && norm.is_finite() {
            basis.push(u, 1.0 / norm);
            mv_last = mu.iter().map(|x| x / norm).collect();
        }
        Self {
            apply,
            mass,
            reorth,
            basis,
            mv_last,
            norm,
            alpha: Vec::new(),
            beta: Vec::new(),
        }
    }

    /// ‖u‖_M of the start vector.
    pub fn norm(&self) -> f64 {
        self.norm
    }

    /// The vector length n.
    pub fn dimension(&self) -> usize {
        self.basis.v.nrows()
    }

    /// Steps done (the size m of T_m).
    pub fn steps(&self) -> usize {
        self.alpha.len()
    }

    /// Whether there is nothing to do: a zero start vector, or the basis reached an invariant
    /// subspace or the dimension.
    pub fn exhausted(&self) -> bool {
        self.basis.len == self.alpha.len()
    }

    /// Diagonal α of T_m.
    pub fn alpha(&self) -> &[f64] {
        &self.alpha
    }

    /// Off-diagonal of T_m followed by β_m (so `beta().len() == alpha().len()`).
    pub fn beta(&self) -> &[f64] {
        &self.beta
    }

    /// One step: `w = S v_j`, orthogonalised; appends α_j and β_j = ‖w‖_M and, unless w
    /// vanished (an invariant subspace: β_j ≤ 1e−14·|α_j|) or the basis spans the whole space,
    /// the next basis vector. Returns β_j.
    ///
    /// # Errors
    /// Whatever `apply` returns.
    pub fn step(&mut self) -> Result<f64, SolveError> {
        let j = self.alpha.len();
        let w = (self.apply)(self.basis.col(j), &self.mv_last)?;
        Ok(self.step_with(w))
    }

    /// `M v_j` of the newest basis vector: the input of the operator's next application
    /// (for a shift-and-invert S = A⁻¹M, the right-hand side of the next solve).
    pub fn next_mass_vector(&self) -> &[f64] {
        &self.mv_last
    }

    /// One step given `w = S v_j` computed outside (e.g. many processes sharing one block
    /// solve); otherwise as [`Self::step`].
    pub fn step_with(&mut self, mut w: Vec<f64>) -> f64 {
        let j = self.alpha.len();
        let n = self.basis.v.nrows();
        let mv_j = &self.mv_last;
        let mut a_j = 0.0;
        match self.reorth {
            Reorthogonalization::Local => {
                if j > 0 {
                    let b_prev = self.beta[j - 1];
                    for (wi, vi) in w.iter_mut().zip(self.basis.col(j - 1)) {
                        *wi -= b_prev * vi;
                    }
                }
                for _ in 0..2 {
                    let c = dot(&w, mv_j);
                    for (wi, vi) in w.iter_mut().zip(self.basis.col(j)) {
                        *wi -= c * vi;
                    }
                    a_j += c;
                }
            }
            Reorthogonalization::Full => {
                // The block Gram–Schmidt of the eigensolver with one column: M w is recomputed
                // per pass instead of keeping M v_i for every basis vector (n·m doubles).
                for _ in 0..2 {
                    let mw = (self.mass)(&w);
                    let coef = crate::blocks::project_out(
                        self.basis.v.as_ref().get(.., 0..j + 1),
                        MatMut::from_column_major_slice_mut(&mut w, n, 1),
                        MatRef::from_column_major_slice(&mw, n, 1),
                    );
                    a_j += coef[(j, 0)];
                }
            }
        }
        let mw = (self.mass)(&w);
        let b_j = dot(&w, &mw).max(0.0).sqrt();
        self.alpha.push(a_j);
        self.beta.push(b_j);
        // (a NaN β counts as vanished: the process cannot continue)
        let invariant = b_j.is_nan() || b_j <= 1e-14 * a_j.abs().max(f64::MIN_POSITIVE) || j + 1 >= n;
        if !invariant {
            self.basis.push(&w, 1.0 / b_j);
            self.mv_last = mw.iter().map(|x| x / b_j).collect();
        }
        b_j
    }

    /// Eigenvalues (ascending) and eigenvectors of T_m.
    ///
    /// # Errors
    /// [`SolveError::Factorization`] if the tridiagonal eigendecomposition fails.
    pub fn ritz(&self) -> Result<(Vec<f64>, Mat<f64>), SolveError> {
        tridiagonal_eigen(&self.alpha, &self.beta)
    }

    /// `scale · V_m Y` for Y of size m × k (m ≤ the steps done; one matrix product).
    pub fn combine_block(&self, y: faer::MatRef<'_, f64>, scale: f64) -> Mat<f64> {
        let (n, m) = (self.basis.v.nrows(), y.nrows());
        let mut out = Mat::<f64>::zeros(n, y.ncols());
        matmul(
            out.as_mut(),
            Accum::Replace,
            self.basis.v.as_ref().get(.., 0..m),
            y,
            scale,
            faer::get_global_parallelism(),
        );
        out
    }

    /// `scale · V_m y` for y of length m (the steps done).
    pub fn combine(&self, y: &[f64], scale: f64) -> Vec<f64> {
        let (n, m) = (self.basis.v.nrows(), y.len());
        let yc = Mat::<f64>::from_fn(m, 1, |i, _| y[i]);
        let mut out = Mat::<f64>::zeros(n, 1);
        matmul(
            out.as_mut(),
            Accum::Replace,
            self.basis.v.as_ref().get(.., 0..m),
            yc.as_ref(),
            scale,
            Par::Seq,
        );
        out.col(0).iter().copied().collect()
    }
}

/// The largest eigenvalue of an operator S self-adjoint and positive semidefinite in the
/// M-inner product (`apply(v, Mv) = S v`), by a [`LanczosProcess`] with full
/// reorthogonalisation from `start`: stops when the Ritz residual of the largest Ritz value θ,
/// `β_m |e_mᵀ u_max|`, is at most `tol·θ`, when the basis is exhausted (exact), or after
/// `max_steps` steps (then `converged` is false). Returns (θ, relative residual, converged).
///
/// # Errors
/// Whatever `apply` returns; [`SolveError::Factorization`] if the tridiagonal
/// eigendecomposition fails.
pub fn largest_ritz_value(
    start: &[f64],
    apply: &LanczosOperator<'_>,
    mass: &(dyn Fn(&[f64]) -> Vec<f64> + Sync),
    tol: f64,
    max_steps: usize,
) -> Result<(f64, f64, bool), SolveError> {
    let mut process = LanczosProcess::new(start, apply, mass, Reorthogonalization::Full, max_steps);
    if process.exhausted() {
        return Ok((0.0, 0.0, true));
    }
    let mut last = (0.0, f64::INFINITY);
    for _ in 0..max_steps.max(1) {
        let b = process.step()?;
        let (theta, u) = process.ritz()?;
        let m = theta.len();
        let top = theta[m - 1];
        let residual = b * u[(m - 1, m - 1)].abs();
        let rel = residual / top.abs().max(f64::MIN_POSITIVE);
        last = (top, rel);
        if residual <= tol * top.abs() || process.exhausted() {
            return Ok((top, if process.exhausted() { 0.0 } else { rel }, true));
        }
    }
    Ok((last.0, last.1, false))
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}
