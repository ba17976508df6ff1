//! Functions of a shift-and-invert operator applied to vectors, `h(S) u` with S = A⁻¹M,
//! A = M + σL symmetric positive definite (one real sparse Cholesky) and M the mass matrix.
//!
//! S is self-adjoint in ⟨u, v⟩_M = uᵀMv with eigenvalues s = 1/(1 + σλ) ∈ (0, 1] (λ the
//! eigenvalues of M⁻¹L). m steps of a [`LanczosProcess`] in that inner product give
//! S V_m = V_m T_m + β_m v_{m+1} e_mᵀ with V_mᵀMV_m = I, and
//!
//! `h(S) u ≈ ‖u‖_M V_m h(T_m) e₁`.
//!
//! Users: the fast path of wfem-heat (h(s) = exp(−(1/s − 1)/γ), the heat kernel itself;
//! van den Eshof & Hochbruck, SIAM J. Sci. Comput. 27 (2006) 1438–1457), the same for a whole
//! list of times from one space ([`lanczos_functions`]), and [`crate::backend::Backend::MultiShift`],
//! where h is the rational approximant written in s, so that every shifted system of paper
//! Eq. (13) is solved in the one Krylov space (shift invariance: with σ = γt,
//! `tL − zB = (1/γ) A (I − (1 + γz) S)`, a function of S). When h is smooth on (0, 1] with its
//! singularities at s ≤ 0, the convergence does not depend on ‖σL‖ (mesh size or t), only on
//! the accuracy wanted: a few tens of solves reach 1e−12.

use crate::lanczos::{LanczosProcess, Reorthogonalization};
use crate::SolveError;
use faer::{Mat, MatMut, MatRef};

/// Parameters of the shift-and-invert Krylov methods on S = (M + γtL)⁻¹M: the fast exact path
/// of wfem-heat (h(s) = exp(−(1/s − 1)/γ), i.e. K_t itself) and the multi-shift backend
/// ([`crate::backend::Backend::MultiShift`], h = the rational approximant written in s). One type for
/// both: they are the same iteration with a different h.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KrylovParams {
    /// Shift γ of the real factor A = M + γtL. Values 0.05–0.2 work well for exp(−x) at
    /// accuracy 1e−10…1e−12.
    pub gamma: f64,
    /// Relative tolerance on the difference of two successive iterates, in the M-norm,
    /// relative to ‖h(S)u‖_M (see [`LanczosParams::tol`]).
    pub tol: f64,
    /// Maximum number of Lanczos steps (= solves with the factor of A) per right-hand side.
    pub max_iter: usize,
}

impl Default for KrylovParams {
    fn default() -> Self {
        Self {
            gamma: 0.1,
            tol: 1e-11,
            max_iter: 200,
        }
    }
}

impl KrylovParams {
    /// Checks γ > 0 finite, tol ∈ (0, 1), max_iter ≥ 1.
    ///
    /// # Errors
    /// [`SolveError::InvalidParameter`] naming the parameter.
    pub fn validate(&self) -> Result<(), SolveError> {
        let bad = |name, value, reason| Err(SolveError::InvalidParameter { name, value, reason });
        if !(self.gamma.is_finite() && self.gamma > 0.0) {
            return bad("gamma", self.gamma, "must be finite and > 0");
        }
        if !(self.tol.is_finite() && self.tol > 0.0 && self.tol < 1.0) {
            return bad("tol", self.tol, "must lie in (0, 1)");
        }
        if self.max_iter == 0 {
            return bad("max_iter", 0.0, "must be at least 1");
        }
        Ok(())
    }

    /// The stopping rule of one [`lanczos_function`] run.
    pub fn lanczos(&self) -> LanczosParams {
        LanczosParams {
            tol: self.tol,
            max_iter: self.max_iter,
        }
    }
}

/// Stopping rule of [`lanczos_function`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LanczosParams {
    /// Relative tolerance on the difference of two successive iterates, in the M-norm,
    /// relative to ‖h(S)u‖_M (or to ‖u‖_M·1e−3 when the result is that small). Two consecutive
    /// hits are required.
    pub tol: f64,
    /// Maximum number of Lanczos steps (= solves with A).
    pub max_iter: usize,
}

/// What one [`lanczos_function`] call did.
#[derive(Clone, Debug, PartialEq)]
pub struct LanczosReport {
    /// Lanczos steps (solves with A).
    pub iterations: usize,
    /// Last successive-difference estimate (relative, M-norm).
    pub estimate: f64,
    /// ‖u‖_M.
    pub norm: f64,
    /// Diagonal of T_m.
    pub alpha: Vec<f64>,
    /// Off-diagonal of T_m followed by β_m (so `beta.len() == alpha.len()`).
    pub beta: Vec<f64>,
}

/// The old name of [`LanczosReport`] (one word per meaning: results are reports).
#[deprecated(note = "renamed LanczosReport")]
pub type LanczosOutcome = LanczosReport;

/// y = h(T) e₁ from the eigendecomposition (θ, U) of T.
fn h_e1(theta: &[f64], u: &Mat<f64>, h: &dyn Fn(f64) -> f64) -> Vec<f64> {
    let m = theta.len();
    let mut y = vec![0.0; m];
    for k in 0..m {
        let w = h(theta[k]) * u[(0, k)];
        if w == 0.0 {
            continue;
        }
        for (i, yi) in y.iter_mut().enumerate() {
            *yi += w * u[(i, k)];
        }
    }
    y
}

/// Per function: the n × k results and the k outcomes.
pub type FunctionsResult = Result<(Vec<Mat<f64>>, Vec<Vec<LanczosReport>>), SolveError>;

/// Per column: its n × count results and its outcomes.
type ColumnsResult = Result<Vec<(Mat<f64>, Vec<LanczosReport>)>, SolveError>;

/// A column of the lockstep iteration: its index, its process and its functions.
type ColumnSlot<'p, 'a> = (usize, &'p mut LanczosProcess<'a>, &'p mut Functions);

/// Relative successive differences below this are rounding noise of the recurrence (not a
/// convergence rate to extrapolate).
const NOISE_FLOOR: f64 = 1e-13;

/// The stopping rule of [`lanczos_function`] for one process: successive iterates of
/// `y_m = h(T_m) e₁`, two consecutive small differences once the top Ritz pair converged.
struct FunctionTracker {
    y_prev: Vec<f64>,
    /// The previous successive difference ‖y_m − y_{m−1}‖ (relative), for the rate.
    diff_prev: f64,
    hits: usize,
    outcome: LanczosReport,
}

impl FunctionTracker {
    fn new(norm: f64) -> Self {
        Self {
            y_prev: Vec::new(),
            diff_prev: f64::INFINITY,
            hits: 0,
            outcome: LanczosReport {
                iterations: 0,
                estimate: f64::INFINITY,
                norm,
                alpha: Vec::new(),
                beta: Vec::new(),
            },
        }
    }

    /// The stopping rule given the Ritz decomposition (θ, U) of T_m: the coefficients
    /// `y = h(T_m) e₁` if converged.
    fn judge(
        &mut self,
        process: &LanczosProcess<'_>,
        theta: &[f64],
        evecs: &Mat<f64>,
        b_j: f64,
        h: &dyn Fn(f64) -> f64,
        tol: f64,
    ) -> Option<Vec<f64>> {
        let j = process.steps() - 1;
        let a_j = process.alpha()[j];
        let y = h_e1(theta, evecs, h);
        let m = theta.len();
        // The successive-iterate estimate cannot see a contribution that has not appeared yet:
        // for a u without low modes (e.g. zero mean) and a large t, h(θ) underflows on the
        // first Ritz values, y stays ≈ 0 for a few steps and two "small differences" would
        // stop the iteration with h(S)u ≈ 0 (measured: 1e−18 instead of 6e−4·‖u‖ on a sheared
        // grid at t = 10 h̄²). Since h is increasing, the dominant term comes from the top of
        // the spectrum of S, so a hit counts only once the largest Ritz pair has converged
        // (Ritz residual β_m|e_mᵀu_max| ≤ 1e−2·θ_max; the eigenvalues are ascending).
        let top_converged = b_j * evecs[(m - 1, m - 1)].abs() <= 1e-2 * theta[m - 1].abs();
        // Successive-iterate error estimate (V M-orthonormal: ‖V δ‖_M = ‖δ‖₂).
        let ynorm = norm(&y);
        let diff = (0..m)
            .map(|i| {
                let d = y[i] - self.y_prev.get(i).copied().unwrap_or(0.0);
                d * d
            })
            .sum::<f64>()
            .sqrt();
        let diff = diff / ynorm.max(1e-3).max(f64::MIN_POSITIVE);
        // The difference of two successive iterates underestimates the error when the
        // convergence is slow: with a rate ρ = diff_m/diff_{m−1} the remaining error is about
        // diff·ρ/(1 − ρ) (geometric tail), so the estimate is diff/(1 − ρ). Measured with many
        // times from one factor (t/σ = 0.03 at the small end of a three-decade window): the
        // plain difference said 5e−12 where the error was 1.5e−10.
        let rate = if diff > NOISE_FLOOR && self.diff_prev.is_finite() && self.diff_prev > 0.0 {
            (diff / self.diff_prev).min(0.9)
        } else {
            0.0
        };
        self.diff_prev = diff;
        self.outcome.estimate = diff / (1.0 - rate);
        self.outcome.iterations = j + 1;
        // An invariant subspace (b_j ≈ 0) makes the result exact.
        let invariant = b_j <= 1e-14 * a_j.abs().max(f64::MIN_POSITIVE) || process.exhausted();
        // Require two consecutive small differences: one alone can be a plateau.
        self.hits = if self.outcome.estimate <= tol && top_converged {
            self.hits + 1
        } else {
            0
        };
        if self.hits >= 2 || invariant {
            self.outcome.alpha = process.alpha().to_vec();
            self.outcome.beta = process.beta().to_vec();
            return Some(y);
        }
        self.y_prev = y;
        None
    }

    fn failure(&self) -> SolveError {
        SolveError::KrylovNoConvergence {
            iterations: self.outcome.iterations,
            estimate: self.outcome.estimate,
        }
    }
}

/// The stopping rules of several functions h_0 … h_{count−1} of one process: each stops on its
/// own; function l keeps the coefficients y_l of the step at which it converged (the bases are
/// nested, so `V_m [y_l; 0]` is its result at any later m).
struct Functions {
    trackers: Vec<FunctionTracker>,
    coefficients: Vec<Option<Vec<f64>>>,
    running: Vec<usize>,
}

impl Functions {
    fn new(count: usize, norm: f64) -> Self {
        Self {
            trackers: (0..count).map(|_| FunctionTracker::new(norm)).collect(),
            coefficients: vec![None; count],
            running: (0..count).collect(),
        }
    }

    /// Nothing to do (a zero start vector): every result is 0, exactly.
    fn trivial(&mut self) {
        self.trackers.iter_mut().for_each(|t| t.outcome.estimate = 0.0);
        self.coefficients.iter_mut().for_each(|c| *c = Some(Vec::new()));
        self.running.clear();
    }

    /// Judges every running function after one step (one Ritz decomposition for all);
    /// returns true when all have converged.
    fn advance(
        &mut self,
        process: &LanczosProcess<'_>,
        b_j: f64,
        h: &(dyn Fn(usize, f64) -> f64 + Sync),
        tol: f64,
    ) -> Result<bool, SolveError> {
        let (theta, evecs) = process.ritz()?;
        let mut still = Vec::with_capacity(self.running.len());
        for &l in &self.running {
            let hl = |s: f64| h(l, s);
            match self.trackers[l].judge(process, &theta, &evecs, b_j, &hl, tol) {
                Some(y) => self.coefficients[l] = Some(y),
                None => still.push(l),
            }
        }
        self.running = still;
        Ok(self.running.is_empty())
    }

    /// Marks the steps done for every running function (checks skipped during a warm-up).
    fn skip(&mut self, steps: usize) {
        for &l in &self.running {
            self.trackers[l].outcome.iterations = steps;
        }
    }

    fn failure(&self) -> SolveError {
        self.running.first().map_or(
            SolveError::KrylovNoConvergence {
                iterations: 0,
                estimate: f64::NAN,
            },
            |&l| self.trackers[l].failure(),
        )
    }

    /// The n × count results `‖u‖_M V Y` (one matrix product).
    fn results(&self, process: &LanczosProcess<'_>) -> Mat<f64> {
        let m = process.steps();
        let y = Mat::<f64>::from_fn(m, self.coefficients.len(), |i, l| {
            self.coefficients[l]
                .as_ref()
                .and_then(|c| c.get(i).copied())
                .unwrap_or(0.0)
        });
        if m == 0 {
            return Mat::zeros(process.dimension(), self.coefficients.len());
        }
        process.combine_block(y.as_ref(), process.norm())
    }

    fn outcomes(self) -> Vec<LanczosReport> {
        self.trackers.into_iter().map(|t| t.outcome).collect()
    }
}

/// `h(S) u ≈ ‖u‖_M V_m h(T_m) e₁` with `solve` applying A⁻¹ and `mass` applying M
/// (S = A⁻¹M; a [`LanczosProcess`] with local reorthogonalisation).
///
/// `h` must be finite on the Ritz values, which lie in (0, 1] up to rounding (continue it
/// sensibly for s ≤ 0), and should be increasing there (the stopping rule waits for the
/// largest Ritz value to converge, since that is where such an h is largest).
///
/// # Errors
/// [`SolveError::KrylovNoConvergence`] after `max_iter` steps;
/// [`SolveError::Factorization`] if the tridiagonal eigendecomposition fails.
pub fn lanczos_function(
    solve: &(dyn Fn(&[f64]) -> Vec<f64> + Sync),
    mass: &(dyn Fn(&[f64]) -> Vec<f64> + Sync),
    u: &[f64],
    h: &(dyn Fn(f64) -> f64 + Sync),
    params: &LanczosParams,
) -> Result<(Vec<f64>, LanczosReport), SolveError> {
    let (x, mut outcomes) = lanczos_functions(solve, mass, u, &|_, s| h(s), 1, params)?;
    let outcome = outcomes.pop().ok_or(SolveError::KrylovNoConvergence {
        iterations: 0,
        estimate: f64::NAN,
    })?;
    Ok((x.col(0).iter().copied().collect(), outcome))
}

/// Several functions of S applied to one vector from one Krylov space:
/// `h_l(S) u ≈ ‖u‖_M V_m h_l(T_m) e₁` for l = 0 … count−1, where `h(l, s)` is h_l(s) — e.g.
/// the heat kernel at a whole list of times with one factor of A. Each function has its own
/// successive-iterate estimate and stopping rule (that of [`lanczos_function`]); the space is
/// grown until every function has converged, and function l uses the basis of the step at
/// which it converged (its coefficients padded with zeros: the bases are nested), so each
/// result is the one [`lanczos_function`] would return for it alone. The final combination is
/// one matrix product `V Y`. The solves and products with M of the one vector may use every
/// core.
///
/// Returns the n × count results and one outcome per function (its steps and estimate).
///
/// # Errors
/// [`SolveError::KrylovNoConvergence`] (for the first function still running after
/// `max_iter` steps); [`SolveError::Factorization`] if a tridiagonal eigendecomposition fails.
pub fn lanczos_functions(
    solve: &(dyn Fn(&[f64]) -> Vec<f64> + Sync),
    mass: &(dyn Fn(&[f64]) -> Vec<f64> + Sync),
    u: &[f64],
    h: &(dyn Fn(usize, f64) -> f64 + Sync),
    count: usize,
    params: &LanczosParams,
) -> Result<(Mat<f64>, Vec<LanczosReport>), SolveError> {
    let n = u.len();
    // Measured on the icosphere at n = 40,962 (f = e_i, t = 0.01): local reorthogonalisation
    // gives the same iteration counts and errors against the rational reference for
    // tol = 1e−9…1e−12 as full Gram–Schmidt, which cost 40 ms of the 250 ms.
    let apply = |_: &[f64], mv: &[f64]| Ok(solve(mv));
    let mut process = LanczosProcess::new(u, &apply, mass, Reorthogonalization::Local, params.max_iter.min(24));
    let mut functions = Functions::new(count, process.norm());
    if process.exhausted() {
        functions.trivial();
    }
    let mut steps = 0;
    while !functions.running.is_empty() {
        if steps >= params.max_iter.min(n) {
            return Err(functions.failure());
        }
        wfem_base::interrupt::checkpoint()?;
        steps += 1;
        let b_j = process.step()?;
        functions.advance(&process, b_j, h, params.tol)?;
    }
    Ok((functions.results(&process), functions.outcomes()))
}

/// [`lanczos_function`] for every column of `u` (n × k): a shorthand for
/// [`lanczos_functions_many`] with one function.
///
/// # Errors
/// As [`lanczos_functions_many`].
pub fn lanczos_function_many(
    solve_block: &(dyn Fn(MatMut<'_, f64>) + Sync),
    mass: &(dyn Fn(&[f64]) -> Vec<f64> + Sync),
    u: MatRef<'_, f64>,
    h: &(dyn Fn(f64) -> f64 + Sync),
    params: &LanczosParams,
    block: usize,
) -> Result<(Mat<f64>, Vec<LanczosReport>), SolveError> {
    let (mut values, mut outcomes) = lanczos_functions_many(solve_block, mass, u, &|_, s| h(s), 1, params, block)?;
    Ok((values.remove(0), outcomes.remove(0)))
}

/// [`lanczos_functions`] for every column of `u` (n × k): up to `block` columns at a time step
/// in lockstep and share one block solve per step (`solve_block` overwrites an n × k' block
/// with `A⁻¹` of it), so a sparse factor is swept once per step for all columns still running —
/// what makes the shift-and-invert Krylov methods competitive with blocked direct solves when
/// there are many right-hand sides. Columns stop on their own; a column that fails stops the
/// call with its error. `mass` applies M to one vector (called in parallel over columns).
///
/// The stopping rule needs the Ritz decomposition of T_m at every step (O(m³), which dominates
/// once the block solve is shared). The number of steps depends little on the column (it is
/// set by σ, the functions and the tolerance), so after the first block the checks start two
/// steps before the fewest steps any column has needed: a column can only run longer (more
/// accurately), never stop earlier.
///
/// Returns, per function, the n × k results and the k outcomes.
///
/// # Errors
/// As [`lanczos_function`] (the first failing column).
pub fn lanczos_functions_many(
    solve_block: &(dyn Fn(MatMut<'_, f64>) + Sync),
    mass: &(dyn Fn(&[f64]) -> Vec<f64> + Sync),
    u: MatRef<'_, f64>,
    h: &(dyn Fn(usize, f64) -> f64 + Sync),
    count: usize,
    params: &LanczosParams,
    block: usize,
) -> FunctionsResult {
    let (n, k) = (u.nrows(), u.ncols());
    let mut values = vec![Mat::<f64>::zeros(n, k); count];
    let mut outcomes: Vec<Vec<LanczosReport>> = vec![Vec::with_capacity(k); count];
    let mut warmup = 0usize;
    let lockstep = Lockstep {
        solve_block,
        mass,
        h,
        count,
        params,
    };
    for start in (0..k).step_by(block.max(1)) {
        let end = (start + block.max(1)).min(k);
        let columns = lockstep.run(u.get(.., start..end), warmup)?;
        let mut fewest = usize::MAX;
        for (c, (x, o)) in columns.into_iter().enumerate() {
            for (l, outcome) in o.into_iter().enumerate() {
                values[l].col_as_slice_mut(start + c).copy_from_slice(x.col_as_slice(l));
                if outcome.iterations > 0 {
                    fewest = fewest.min(outcome.iterations);
                }
                outcomes[l].push(outcome);
            }
        }
        if fewest < usize::MAX {
            warmup = warmup.max(fewest.saturating_sub(2));
        }
    }
    Ok((values, outcomes))
}

/// The inputs of [`lanczos_functions_many`] that every block of columns shares.
struct Lockstep<'a> {
    solve_block: &'a (dyn Fn(MatMut<'_, f64>) + Sync),
    mass: &'a (dyn Fn(&[f64]) -> Vec<f64> + Sync),
    h: &'a (dyn Fn(usize, f64) -> f64 + Sync),
    count: usize,
    params: &'a LanczosParams,
}

impl Lockstep<'_> {
    /// One block `u` of [`lanczos_functions_many`]: per column, its n × count results and
    /// outcomes; no convergence checks before step `warmup`.
    fn run(&self, u: MatRef<'_, f64>, warmup: usize) -> ColumnsResult {
        use rayon::prelude::*;
        let Lockstep {
            solve_block,
            mass,
            h,
            count,
            params,
        } = *self;
        let (n, k) = (u.nrows(), u.ncols());
        // The operator is applied outside the processes (block solve), never through `apply`.
        let unused = |_: &[f64], mv: &[f64]| Ok(mv.to_vec());
        let cols: Vec<Vec<f64>> = (0..k).map(|j| u.col(j).iter().copied().collect()).collect();
        let mut processes: Vec<LanczosProcess<'_>> = cols
            .par_iter()
            .map(|c| LanczosProcess::new(c, &unused, mass, Reorthogonalization::Local, params.max_iter.min(24)))
            .collect();
        let mut functions: Vec<Functions> = processes.iter().map(|p| Functions::new(count, p.norm())).collect();
        let mut active: Vec<usize> = Vec::with_capacity(k);
        for (j, (p, f)) in processes.iter().zip(functions.iter_mut()).enumerate() {
            if p.exhausted() {
                f.trivial();
            } else {
                active.push(j);
            }
        }
        let mut step = 0;
        while !active.is_empty() {
            if step >= params.max_iter.min(n) {
                return Err(functions[active[0]].failure());
            }
            wfem_base::interrupt::checkpoint()?;
            step += 1;
            let mut rhs = Mat::<f64>::from_fn(n, active.len(), |i, c| processes[active[c]].next_mass_vector()[i]);
            solve_block(rhs.as_mut());
            // Finish the step of every active process in parallel.
            let mut slots: Vec<ColumnSlot<'_, '_>> = processes
                .iter_mut()
                .zip(functions.iter_mut())
                .enumerate()
                .filter(|(j, _)| active.binary_search(j).is_ok())
                .map(|(j, (p, f))| (j, p, f))
                .collect();
            let results: Vec<(usize, Result<bool, SolveError>)> = slots
                .par_iter_mut()
                .enumerate()
                .map(|(c, (j, p, f))| {
                    let w: Vec<f64> = rhs.col(c).iter().copied().collect();
                    let b_j = p.step_with(w);
                    if step < warmup && !p.exhausted() {
                        f.skip(step);
                        return (*j, Ok(false));
                    }
                    (*j, f.advance(p, b_j, h, params.tol))
                })
                .collect();
            drop(slots);
            let mut still = Vec::with_capacity(active.len());
            for (j, done) in results {
                if !done? {
                    still.push(j);
                }
            }
            active = still;
        }
        Ok(processes
            .iter()
            .zip(functions)
            .map(|(p, f)| (f.results(p), f.outcomes()))
            .collect())
    }
}

fn norm(a: &[f64]) -> f64 {
    a.iter().map(|x| x * x).sum::<f64>().sqrt()
}
