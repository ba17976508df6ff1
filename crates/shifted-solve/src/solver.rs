//! The shifted-system engine: r_n(tB⁻¹L)F = c0·F + 2 Re Σ_j c_j (tL − z_j B)⁻¹ (B F)
//! (paper Eq. (12)–(13), written with upper-half-plane poles, see [`crate::poles`]).

use std::sync::Arc;

use crate::factor::{
    cholesky_symbolic, lu_symbolic, CholeskyPattern, CholeskySymbolic, LuSymbolic, SeqLlt, SeqLu, SpdFactor,
};
use crate::iterative::{minres, pcg, MinresParams, PrecondFactor, Preconditioner, PreconditionerShift};
use crate::lanczos::{lanczos_function, tridiagonal_eigen, LanczosOutcome, LanczosParams};
use crate::ldlt::{LdltFactor, LdltSymbolic};
use crate::ops::PairOperators;
use crate::{RationalApprox, SolveError};
use faer::c64;
use faer::sparse::SparseColMatRef;
use faer::{Mat, MatRef};
use rayon::prelude::*;

/// How each shifted system (tL − z_j B) x = b is solved.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Backend {
    /// Sparse complex LU (faer, COLAMD + partial pivoting) with one symbolic analysis shared by
    /// every pole and every t; the real pole of odd degrees uses a real sparse Cholesky.
    /// Factors are reused for any number of right-hand sides.
    DirectLu,
    /// Complex-symmetric supernodal LDLᵀ without pivoting (NUMERICS §3.3d; module `ldlt`
    /// docs): it exists because the Hermitian part of i(tL − zB) is qB ≻ 0, reuses the real
    /// Cholesky's AMD ordering and supernodes, and does about half the work of the LU. Every
    /// solve reports its true residual; the real pole uses a real sparse Cholesky.
    DirectLdlt,
    /// Preconditioned MINRES on the real 2n×2n symmetric form (the paper's choice); the real
    /// pole uses preconditioned CG on the SPD system tL + |z|B.
    Minres(MinresParams),
    /// All poles in one Krylov space, with one *real* sparse Cholesky per t. With
    /// A = B + γtL and S = A⁻¹B,
    ///
    /// `tL − zB = (1/γ) A (I − (1 + γz) S)`, so `(tL − zB)⁻¹ = γ (I − (1 + γz) S)⁻¹ A⁻¹`:
    ///
    /// every shifted system of Eq. (13) is a function of the one operator S (shift
    /// invariance), and so is their weighted sum,
    /// `r_n(tB⁻¹L) F = R(S) F` with `R(s) = r_n((1/s − 1)/γ)`. One shift-and-invert Lanczos run
    /// per right-hand side ([`crate::lanczos_function`]) evaluates the sum in the Galerkin sense
    /// of multi-shift FOM. Its tolerance controls the *sum* (what K_t f needs); the per-pole
    /// Galerkin residuals are reported, and the poles nearest the spectrum of S converge more
    /// slowly than the sum. Cost: one real Cholesky and a few tens of solves with it, instead
    /// of one complex factorization per pole.
    MultiShift(MultiShiftParams),
}

/// Parameters of [`Backend::MultiShift`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MultiShiftParams {
    /// Shift γ of the real factor A = B + γtL (0.05–0.2 work well).
    pub gamma: f64,
    /// Relative tolerance of the Lanczos iteration on the sum (see
    /// [`crate::LanczosParams::tol`]).
    pub tol: f64,
    /// Maximum Lanczos steps per right-hand side.
    pub max_iter: usize,
}

impl Default for MultiShiftParams {
    fn default() -> Self {
        Self {
            gamma: 0.1,
            tol: 1e-11,
            max_iter: 200,
        }
    }
}

impl MultiShiftParams {
    fn validate(&self) -> Result<(), SolveError> {
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
}

/// Which method solved one pole.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SolveMethod {
    /// Sparse complex LU.
    ComplexLu,
    /// Sparse complex-symmetric LDLᵀ.
    ComplexLdlt,
    /// Sparse real Cholesky (real pole).
    RealCholesky,
    /// Preconditioned MINRES on the real 2n form.
    Minres,
    /// Preconditioned conjugate gradients (real pole).
    ConjugateGradient,
    /// One shift-and-invert Lanczos space for all poles ([`Backend::MultiShift`]).
    MultiShiftLanczos,
}

/// What happened for one pole of a batch.
#[derive(Debug, Clone, PartialEq)]
pub struct PoleReport {
    /// The pole z_j (upper half plane, or real negative).
    pub pole: c64,
    /// Its residue c_j.
    pub residue: c64,
    /// The method used.
    pub method: SolveMethod,
    /// Largest iteration count over the right-hand sides (0 for direct methods).
    pub iterations: usize,
    /// Largest true relative residual ‖b − (tL − zB)x‖₂ / ‖b‖₂ over the right-hand sides.
    pub relative_residual: f64,
    /// Convergence history of the first right-hand side (iterative methods only): the relative
    /// preconditioned residual norm after each iteration.
    pub residual_history: Vec<f64>,
}

/// Per-pole information of one [`RationalFactors::apply`] call.
#[derive(Debug, Clone, PartialEq)]
pub struct BatchReport {
    /// Diffusion time t.
    pub t: f64,
    /// Number of right-hand sides.
    pub n_rhs: usize,
    /// One entry per solve (complex pairs first, then the real pole).
    pub poles: Vec<PoleReport>,
}

impl BatchReport {
    /// Total iterations over all poles (largest per pole), 0 for direct methods.
    pub fn total_iterations(&self) -> usize {
        self.poles.iter().map(|p| p.iterations).sum()
    }

    /// Largest relative residual over all poles.
    pub fn max_relative_residual(&self) -> f64 {
        self.poles.iter().map(|p| p.relative_residual).fold(0.0, f64::max)
    }
}

/// Owns copies of L and B on one shared sparsity pattern plus the symbolic analyses shared by
/// every pole and every t.
#[derive(Debug, Clone)]
pub struct ShiftedSolver {
    ops: Arc<PairOperators>,
    backend: Backend,
    llt_symbolic: CholeskySymbolic,
    lu_symbolic: Option<LuSymbolic>,
    ldlt_symbolic: Option<Arc<LdltSymbolic>>,
    /// The real Cholesky pattern with its tree-parallel solve plan ([`Backend::MultiShift`]).
    spd_pattern: Option<CholeskyPattern>,
}

pub(crate) fn check_time(t: f64) -> Result<(), SolveError> {
    if t.is_finite() && t > 0.0 {
        Ok(())
    } else {
        Err(SolveError::InvalidTime { t })
    }
}

fn check_rhs(rhs: MatRef<'_, f64>, n: usize) -> Result<(), SolveError> {
    if rhs.nrows() != n {
        return Err(SolveError::DimensionMismatch {
            what: "right-hand side rows vs matrix size",
            expected: n,
            got: rhs.nrows(),
        });
    }
    for j in 0..rhs.ncols() {
        for i in 0..n {
            let v = rhs[(i, j)];
            if !v.is_finite() {
                return Err(SolveError::NonFinite {
                    what: "right-hand side",
                    row: i,
                    col: j,
                    value: v,
                });
            }
        }
    }
    Ok(())
}

impl ShiftedSolver {
    /// Validates L (symmetric positive semidefinite stiffness, positive diagonal) and B
    /// (symmetric positive definite mass), merges their patterns and runs the symbolic analyses.
    ///
    /// Checks: square, equal sizes, finite, symmetric (1e−10 relative), diag(B) > 0,
    /// diag(L) ≥ 0, B positive definite (Cholesky), and L + δB positive definite with
    /// δ = 1e−10·tr(L)/tr(B), which detects a negative generalized eigenvalue of (L, B) below −δ
    /// (e.g. when −L is passed).
    ///
    /// # Errors
    /// The [`SolveError`] variant naming the failed check.
    pub fn new(
        stiffness: SparseColMatRef<'_, usize, f64>,
        mass: SparseColMatRef<'_, usize, f64>,
        backend: Backend,
    ) -> Result<Self, SolveError> {
        match &backend {
            Backend::Minres(p) => p.validate()?,
            Backend::MultiShift(p) => p.validate()?,
            Backend::DirectLu | Backend::DirectLdlt => {}
        }
        let ops = PairOperators::new(stiffness, mass)?;
        let symbolic_error = |detail| SolveError::Factorization {
            what: "symbolic Cholesky",
            detail,
        };
        // The LDLᵀ needs a supernodal analysis; the real Cholesky factors then share it (one AMD).
        let (llt_symbolic, ldlt_symbolic) = if backend == Backend::DirectLdlt {
            let analysis = LdltSymbolic::cholesky_analysis(ops.symbolic.as_ref()).map_err(symbolic_error)?;
            let ldlt =
                LdltSymbolic::new(ops.symbolic.as_ref(), &analysis).map_err(|detail| SolveError::Factorization {
                    what: "symbolic LDLᵀ",
                    detail,
                })?;
            (Arc::new(analysis), Some(Arc::new(ldlt)))
        } else {
            (cholesky_symbolic(ops.symbolic.as_ref()).map_err(symbolic_error)?, None)
        };
        let tr_l: f64 = ops.diagonal(1.0, 0.0).iter().sum();
        let tr_b: f64 = ops.diagonal(0.0, 1.0).iter().sum();
        let delta = 1e-10 * (tr_l / tr_b).max(f64::MIN_POSITIVE);
        // The two definiteness checks are independent factorizations: run them side by side.
        let (mass_check, stiffness_check) = rayon::join(
            || {
                let b = ops.real_combination(0.0, 1.0);
                SeqLlt::new(&llt_symbolic, b.as_ref()).map_err(|detail| SolveError::MassNotPositiveDefinite { detail })
            },
            || {
                let reg = ops.real_combination(1.0, delta);
                SeqLlt::new(&llt_symbolic, reg.as_ref()).map_err(|_| SolveError::StiffnessIndefinite { delta })
            },
        );
        mass_check?;
        stiffness_check?;
        let lu_symbolic = match backend {
            Backend::DirectLu => {
                Some(
                    lu_symbolic(ops.symbolic.as_ref()).map_err(|detail| SolveError::Factorization {
                        what: "symbolic LU",
                        detail,
                    })?,
                )
            }
            Backend::Minres(_) | Backend::DirectLdlt | Backend::MultiShift(_) => None,
        };
        let spd_pattern = match backend {
            Backend::MultiShift(_) => Some(CholeskyPattern::from_symbolic(llt_symbolic.clone())),
            _ => None,
        };
        Ok(Self {
            ops: Arc::new(ops),
            backend,
            llt_symbolic,
            lu_symbolic,
            ldlt_symbolic,
            spd_pattern,
        })
    }

    /// Matrix size n.
    pub fn n(&self) -> usize {
        self.ops.n
    }

    /// Number of stored entries of the shared pattern of L and B.
    pub fn nnz(&self) -> usize {
        self.ops.row_idx.len()
    }

    /// The backend chosen at construction.
    pub fn backend(&self) -> &Backend {
        &self.backend
    }

    pub(crate) fn ops(&self) -> &PairOperators {
        &self.ops
    }

    pub(crate) fn llt_symbolic(&self) -> &CholeskySymbolic {
        &self.llt_symbolic
    }

    pub(crate) fn lu_symbolic(&self) -> Result<LuSymbolic, SolveError> {
        match &self.lu_symbolic {
            Some(s) => Ok(s.clone()),
            None => lu_symbolic(self.ops.symbolic.as_ref()).map_err(|detail| SolveError::Factorization {
                what: "symbolic LU",
                detail,
            }),
        }
    }

    /// Approximates the heat operator, `r_n(t B⁻¹L) F = c0·F + 2 Re Σ_j c_j (tL − z_j B)⁻¹ (B F)`
    /// (paper Eq. (13) in the sign convention of NUMERICS §0.1). `rhs` is n × k.
    ///
    /// # Errors
    /// Invalid t, size/NaN problems in `rhs`, singular shifted matrices, non-convergence.
    pub fn apply(
        &self,
        approx: &RationalApprox,
        t: f64,
        rhs: MatRef<'_, f64>,
    ) -> Result<(Mat<f64>, BatchReport), SolveError> {
        check_rhs(rhs, self.n())?;
        self.factor(approx, t)?.apply(rhs)
    }

    /// `2 Re Σ_j c_j (tL − z_j B)⁻¹ G` (+ the real pole), without the c0 term and without the
    /// multiplication by B: with G = e_i this is the heat-kernel column H_t e_i (NUMERICS §1).
    ///
    /// # Errors
    /// As [`Self::apply`].
    pub fn apply_resolvent(
        &self,
        approx: &RationalApprox,
        t: f64,
        rhs: MatRef<'_, f64>,
    ) -> Result<(Mat<f64>, BatchReport), SolveError> {
        check_rhs(rhs, self.n())?;
        self.factor(approx, t)?.apply_resolvent(rhs)
    }

    /// Factors every pole of one t (in parallel): complex LUs for [`Backend::DirectLu`], the
    /// SPD preconditioners for [`Backend::Minres`]. Reuse the result for any number of
    /// right-hand sides.
    ///
    /// # Errors
    /// [`SolveError::InvalidTime`], [`SolveError::SingularShiftedMatrix`],
    /// [`SolveError::Factorization`].
    pub fn factor(&self, approx: &RationalApprox, t: f64) -> Result<RationalFactors, SolveError> {
        check_time(t)?;
        let mut jobs: Vec<(c64, c64, bool)> = approx
            .poles
            .iter()
            .zip(approx.residues)
            .map(|(&z, &c)| (z, c, false))
            .collect();
        if let Some((z, c)) = approx.real_pole {
            jobs.push((c64::new(z, 0.0), c64::new(c, 0.0), true));
        }
        let ops = &*self.ops;
        let terms: Vec<PoleTerm> = match self.backend {
            Backend::DirectLu | Backend::DirectLdlt => {
                let direct = match &self.ldlt_symbolic {
                    Some(ldlt) => DirectSymbolic::Ldlt(ldlt.clone()),
                    None => DirectSymbolic::Lu(self.lu_symbolic()?),
                };
                jobs.par_iter()
                    .map(|&(z, c, real)| {
                        let solver = if real {
                            let a = ops.real_combination(t, -z.re);
                            let llt = SeqLlt::new(&self.llt_symbolic, a.as_ref())
                                .map_err(|_| SolveError::SingularShiftedMatrix { t, pole: z })?;
                            PoleSolver::Cholesky(llt)
                        } else {
                            let singular = SolveError::SingularShiftedMatrix { t, pole: z };
                            match &direct {
                                DirectSymbolic::Ldlt(sym) => PoleSolver::Ldlt(Box::new(
                                    LdltFactor::new(sym, &ops.shifted_values(t, z)).map_err(|_| singular)?,
                                )),
                                DirectSymbolic::Lu(sym) => PoleSolver::Lu(Box::new(
                                    SeqLu::new(sym, ops.shifted(t, z).as_ref()).map_err(|_| singular)?,
                                )),
                            }
                        };
                        Ok(PoleTerm {
                            pole: z,
                            residue: c,
                            solver,
                        })
                    })
                    .collect::<Result<_, SolveError>>()?
            }
            Backend::MultiShift(params) => return self.factor_multi_shift(approx, t, params, &jobs),
            Backend::Minres(params) => {
                let shared = match params.preconditioner {
                    Preconditioner::ShiftedCholesky(PreconditionerShift::Shared(s)) => Some(Arc::new(
                        PrecondFactor::build(ops, &self.llt_symbolic, params.preconditioner, t, s)?,
                    )),
                    Preconditioner::None => Some(Arc::new(PrecondFactor::Identity)),
                    _ => None,
                };
                jobs.par_iter()
                    .map(|&(z, c, _)| {
                        let precond = match &shared {
                            Some(p) => p.clone(),
                            None => Arc::new(PrecondFactor::build(
                                ops,
                                &self.llt_symbolic,
                                params.preconditioner,
                                t,
                                z.norm(),
                            )?),
                        };
                        Ok(PoleTerm {
                            pole: z,
                            residue: c,
                            solver: PoleSolver::Krylov { precond, params },
                        })
                    })
                    .collect::<Result<_, SolveError>>()?
            }
        };
        Ok(RationalFactors {
            ops: self.ops.clone(),
            t,
            c0: approx.c0,
            terms,
            shared: None,
        })
    }
}

impl ShiftedSolver {
    /// [`Backend::MultiShift`]: the one real factor of B + γtL; the poles are kept for the
    /// Lanczos evaluation.
    fn factor_multi_shift(
        &self,
        approx: &RationalApprox,
        t: f64,
        params: MultiShiftParams,
        jobs: &[(c64, c64, bool)],
    ) -> Result<RationalFactors, SolveError> {
        let pattern = match &self.spd_pattern {
            Some(p) => p.clone(),
            None => CholeskyPattern::from_symbolic(self.llt_symbolic.clone()),
        };
        let a = self.ops.real_combination(params.gamma * t, 1.0);
        let factor = pattern
            .factor(a.as_ref(), faer::get_global_parallelism())
            .map_err(|_| SolveError::SingularShiftedMatrix {
                t,
                pole: SharedKrylov::real_pole(params.gamma),
            })?;
        Ok(RationalFactors {
            ops: self.ops.clone(),
            t,
            c0: approx.c0,
            terms: Vec::new(),
            shared: Some(SharedKrylov {
                factor,
                params,
                poles: jobs.iter().map(|&(z, c, _)| (z, c)).collect(),
            }),
        })
    }
}

enum DirectSymbolic {
    Lu(LuSymbolic),
    Ldlt(Arc<LdltSymbolic>),
}

#[derive(Debug)]
enum PoleSolver {
    Lu(Box<SeqLu>),
    Ldlt(Box<LdltFactor>),
    Cholesky(SeqLlt),
    Krylov {
        precond: Arc<PrecondFactor>,
        params: MinresParams,
    },
}

#[derive(Debug)]
struct PoleTerm {
    pole: c64,
    residue: c64,
    solver: PoleSolver,
}

/// The one real factor of [`Backend::MultiShift`] and the poles it serves.
#[derive(Debug)]
struct SharedKrylov {
    factor: SpdFactor,
    params: MultiShiftParams,
    /// (z_j, c_j), the real pole (if any) last.
    poles: Vec<(c64, c64)>,
}

impl SharedKrylov {
    /// The factored matrix as a shifted matrix: B + γtL = γ(tL − zB) with z = −1/γ (the pole
    /// named when it is singular).
    fn real_pole(gamma: f64) -> c64 {
        c64::new(-1.0 / gamma, 0.0)
    }
}

/// All poles of one t, factored once (paper Eq. (12)); apply to any number of right-hand sides.
#[derive(Debug)]
pub struct RationalFactors {
    ops: Arc<PairOperators>,
    t: f64,
    c0: f64,
    terms: Vec<PoleTerm>,
    shared: Option<SharedKrylov>,
}

fn norm2(x: &[f64]) -> f64 {
    x.iter().map(|v| v * v).sum::<f64>().sqrt()
}

impl RationalFactors {
    /// Diffusion time t of these factors.
    pub fn t(&self) -> f64 {
        self.t
    }

    /// `r_n(t B⁻¹L) F = c0·F + 2 Re Σ_j c_j (tL − z_j B)⁻¹ (B F)` for F of size n × k.
    ///
    /// # Errors
    /// Size/NaN problems in `rhs`, non-finite solutions, non-convergence.
    pub fn apply(&self, rhs: MatRef<'_, f64>) -> Result<(Mat<f64>, BatchReport), SolveError> {
        check_rhs(rhs, self.ops.n)?;
        if let Some(shared) = &self.shared {
            return self.multi_shift(shared, rhs, true);
        }
        let n = self.ops.n;
        let mut g = Mat::<f64>::zeros(n, rhs.ncols());
        let mut col = vec![0.0; n];
        let mut bx = vec![0.0; n];
        for j in 0..rhs.ncols() {
            for i in 0..n {
                col[i] = rhs[(i, j)];
            }
            self.ops.mass_mul(&col, &mut bx);
            g.col_as_slice_mut(j).copy_from_slice(&bx);
        }
        let (mut out, report) = self.resolvent(g.as_ref())?;
        for j in 0..rhs.ncols() {
            for i in 0..n {
                out[(i, j)] += self.c0 * rhs[(i, j)];
            }
        }
        Ok((out, report))
    }

    /// `2 Re Σ_j c_j (tL − z_j B)⁻¹ G` (+ real pole), no c0 term, no multiplication by B.
    ///
    /// # Errors
    /// As [`Self::apply`].
    pub fn apply_resolvent(&self, rhs: MatRef<'_, f64>) -> Result<(Mat<f64>, BatchReport), SolveError> {
        check_rhs(rhs, self.ops.n)?;
        if let Some(shared) = &self.shared {
            return self.multi_shift(shared, rhs, false);
        }
        self.resolvent(rhs)
    }

    /// [`Backend::MultiShift`]: with A = B + γtL, S = A⁻¹B and c_j = 1 + γz_j,
    /// `(tL − z_jB)⁻¹ = γ(I − c_jS)⁻¹A⁻¹`, so
    /// - `apply`: r_n(tB⁻¹L)F = R(S)F with R(s) = c0 + s·Q(s) = r_n((1/s − 1)/γ);
    /// - `apply_resolvent`: Σ_j w_j c_j (tL − z_jB)⁻¹G = Q(S)A⁻¹G with
    ///   Q(s) = Σ_j w_j Re(c_j γ/(1 − c_j s)), w_j = 2 for a conjugate pair and 1 for the real pole.
    ///
    /// Each column is one Lanczos run; columns run in parallel. The report gives, per pole,
    /// the Galerkin (FOM) residual of its shifted system (I − c_jS)x = φ(S)u in the B-norm,
    /// relative to ‖φ(S)u‖_B (φ(s) = s for `apply`, 1 for the resolvent):
    /// `|c_j| β_m |e_mᵀ(I − c_jT)⁻¹φ(T)e₁| / ‖φ(T)e₁‖`.
    fn multi_shift(
        &self,
        shared: &SharedKrylov,
        rhs: MatRef<'_, f64>,
        with_mass: bool,
    ) -> Result<(Mat<f64>, BatchReport), SolveError> {
        let (n, k, gamma) = (self.ops.n, rhs.ncols(), shared.params.gamma);
        let weight = |z: c64| if z.im == 0.0 { 1.0 } else { 2.0 };
        let q = |s: f64| -> f64 {
            shared
                .poles
                .iter()
                .map(|&(z, c)| weight(z) * (c * gamma / (c64::new(1.0, 0.0) - (c64::new(1.0, 0.0) + z * gamma) * s)).re)
                .sum()
        };
        // R(s) = c0 + s Q(s); at s ≤ 0 (rounding below the spectrum (0, 1]) x = ∞ and R = c0.
        let r = |s: f64| if s <= 0.0 { self.c0 } else { self.c0 + s * q(s) };
        let params = LanczosParams {
            tol: shared.params.tol,
            max_iter: shared.params.max_iter,
        };
        let solve = |b: &[f64]| shared.factor.solve_vec(b);
        let mass = |x: &[f64]| {
            let mut y = vec![0.0; x.len()];
            self.ops.mass_mul(x, &mut y);
            y
        };
        let cols: Vec<(Vec<f64>, LanczosOutcome)> = (0..k)
            .into_par_iter()
            .map(|j| {
                // (finite: checked by the callers through `check_rhs`)
                let col: Vec<f64> = (0..n).map(|i| rhs[(i, j)]).collect();
                if with_mass {
                    lanczos_function(&solve, &mass, &col, &r, &params)
                } else {
                    lanczos_function(&solve, &mass, &solve(&col), &q, &params)
                }
            })
            .collect::<Result<_, SolveError>>()?;
        let mut out = Mat::<f64>::zeros(n, k);
        let mut poles: Vec<PoleReport> = shared
            .poles
            .iter()
            .map(|&(z, c)| PoleReport {
                pole: z,
                residue: c,
                method: SolveMethod::MultiShiftLanczos,
                iterations: 0,
                relative_residual: 0.0,
                residual_history: Vec::new(),
            })
            .collect();
        for (j, (x, outcome)) in cols.iter().enumerate() {
            if x.iter().any(|v| !v.is_finite()) {
                return Err(SolveError::SingularShiftedMatrix {
                    t: self.t,
                    pole: SharedKrylov::real_pole(gamma),
                });
            }
            out.col_as_slice_mut(j).copy_from_slice(x);
            if outcome.alpha.is_empty() {
                continue;
            }
            let (theta, u) = tridiagonal_eigen(&outcome.alpha, &outcome.beta[..outcome.alpha.len() - 1])?;
            let m = theta.len();
            let beta_m = outcome.beta[m - 1];
            let phi = |s: f64| if with_mass { s } else { 1.0 };
            let phi_norm = (0..m)
                .map(|i| {
                    let v: f64 = (0..m).map(|l| u[(i, l)] * u[(0, l)] * phi(theta[l])).sum();
                    v * v
                })
                .sum::<f64>()
                .sqrt();
            for (report, &(z, _)) in poles.iter_mut().zip(&shared.poles) {
                let c = c64::new(1.0, 0.0) + z * gamma;
                let last: c64 = (0..m)
                    .map(|l| {
                        c64::new(u[(m - 1, l)] * u[(0, l)] * phi(theta[l]), 0.0) / (c64::new(1.0, 0.0) - c * theta[l])
                    })
                    .sum();
                let residual = c.norm() * beta_m * last.norm() / phi_norm.max(f64::MIN_POSITIVE);
                report.relative_residual = report.relative_residual.max(residual);
                report.iterations = report.iterations.max(outcome.iterations);
            }
        }
        Ok((out, self.report(k, poles)))
    }

    fn report(&self, n_rhs: usize, poles: Vec<PoleReport>) -> BatchReport {
        BatchReport {
            t: self.t,
            n_rhs,
            poles,
        }
    }

    fn resolvent(&self, g: MatRef<'_, f64>) -> Result<(Mat<f64>, BatchReport), SolveError> {
        let n = self.ops.n;
        let k = g.ncols();
        let parts: Vec<(Mat<f64>, PoleReport)> = self
            .terms
            .par_iter()
            .map(|term| self.solve_term(term, g))
            .collect::<Result<_, SolveError>>()?;
        let mut out = Mat::<f64>::zeros(n, k);
        let mut poles = Vec::with_capacity(parts.len());
        for (m, rep) in parts {
            out += &m;
            poles.push(rep);
        }
        Ok((out, self.report(k, poles)))
    }

    /// Contribution 2 Re(c (tL − zB)⁻¹ G) (or c (tL − zB)⁻¹ G for the real pole).
    fn solve_term(&self, term: &PoleTerm, g: MatRef<'_, f64>) -> Result<(Mat<f64>, PoleReport), SolveError> {
        let ops = &*self.ops;
        let (n, k, t, z, c) = (ops.n, g.ncols(), self.t, term.pole, term.residue);
        let singular = || SolveError::SingularShiftedMatrix { t, pole: z };
        let mut out = Mat::<f64>::zeros(n, k);
        let mut report = PoleReport {
            pole: z,
            residue: c,
            method: SolveMethod::ComplexLu,
            iterations: 0,
            relative_residual: 0.0,
            residual_history: Vec::new(),
        };
        let is_real = z.im == 0.0;
        let weight = if is_real { 1.0 } else { 2.0 };
        match &term.solver {
            PoleSolver::Lu(_) | PoleSolver::Ldlt(_) => {
                let mut x = Mat::<c64>::from_fn(n, k, |i, j| c64::new(g[(i, j)], 0.0));
                match &term.solver {
                    PoleSolver::Lu(lu) => lu.solve_in_place(x.as_mut()),
                    PoleSolver::Ldlt(f) => {
                        report.method = SolveMethod::ComplexLdlt;
                        f.solve_in_place(x.as_mut())
                    }
                    _ => {}
                }
                let mut ax = vec![c64::new(0.0, 0.0); n];
                for j in 0..k {
                    let xj = x.col_as_slice(j);
                    if xj.iter().any(|v| !v.re.is_finite() || !v.im.is_finite()) {
                        return Err(singular());
                    }
                    ops.complex_mul(c64::new(t, 0.0), -z, xj, &mut ax);
                    let (mut num, mut den) = (0.0, 0.0);
                    for i in 0..n {
                        num += (ax[i] - g[(i, j)]).norm_sqr();
                        den += g[(i, j)] * g[(i, j)];
                        out[(i, j)] = weight * (c * xj[i]).re;
                    }
                    report.relative_residual = report.relative_residual.max(rel(num, den));
                }
            }
            PoleSolver::Cholesky(llt) => {
                report.method = SolveMethod::RealCholesky;
                let mut x = g.to_owned();
                llt.solve_in_place(x.as_mut());
                let (mut lx, mut bx) = (vec![0.0; n], vec![0.0; n]);
                for j in 0..k {
                    let xj = x.col_as_slice(j);
                    if xj.iter().any(|v| !v.is_finite()) {
                        return Err(singular());
                    }
                    ops.stiffness_mass_mul(xj, &mut lx, &mut bx);
                    let (mut num, mut den) = (0.0, 0.0);
                    for i in 0..n {
                        let r = t * lx[i] - z.re * bx[i] - g[(i, j)];
                        num += r * r;
                        den += g[(i, j)] * g[(i, j)];
                        out[(i, j)] = c.re * xj[i];
                    }
                    report.relative_residual = report.relative_residual.max(rel(num, den));
                }
            }
            PoleSolver::Krylov { precond, params } => {
                report.method = if is_real {
                    SolveMethod::ConjugateGradient
                } else {
                    SolveMethod::Minres
                };
                let cols: Vec<(Vec<f64>, usize, Vec<f64>, f64)> = (0..k)
                    .into_par_iter()
                    .map(|j| {
                        let b: Vec<f64> = (0..n).map(|i| g[(i, j)]).collect();
                        solve_krylov(ops, t, z, &b, precond, params)
                    })
                    .collect::<Result<_, SolveError>>()?;
                for (j, (x, its, hist, r)) in cols.into_iter().enumerate() {
                    for i in 0..n {
                        out[(i, j)] = if is_real {
                            c.re * x[i]
                        } else {
                            2.0 * (c.re * x[i] - c.im * x[n + i])
                        };
                    }
                    report.iterations = report.iterations.max(its);
                    report.relative_residual = report.relative_residual.max(r);
                    if j == 0 {
                        report.residual_history = hist;
                    }
                }
            }
        }
        Ok((out, report))
    }
}

fn rel(num: f64, den: f64) -> f64 {
    if den == 0.0 {
        num.sqrt()
    } else {
        (num / den).sqrt()
    }
}

/// One Krylov solve of (tL − zB)x = b with real b. Returns (x, iterations, history, true
/// relative residual); for complex z, x = [Re x; Im x] has length 2n.
fn solve_krylov(
    ops: &PairOperators,
    t: f64,
    z: c64,
    b: &[f64],
    precond: &PrecondFactor,
    params: &MinresParams,
) -> Result<(Vec<f64>, usize, Vec<f64>, f64), SolveError> {
    let n = ops.n;
    let (p, q) = (z.re, z.im);
    let mut lx = vec![0.0; n];
    let mut bx = vec![0.0; n];
    if q == 0.0 {
        let outcome = pcg(
            b,
            |x, y| {
                ops.stiffness_mass_mul(x, &mut lx, &mut bx);
                for i in 0..n {
                    y[i] = t * lx[i] - p * bx[i];
                }
            },
            |x| precond.apply(x, n),
            params.rel_tol,
            params.max_iters,
        );
        // The last finite residual estimate (a breakdown can end the history with NaN).
        let last = last_finite(&outcome.history);
        if !outcome.converged {
            return Err(SolveError::NoConvergence {
                residual: last,
                iterations: outcome.iterations,
                pole: z,
            });
        }
        return Ok((outcome.x, outcome.iterations, outcome.history, last));
    }
    // Real 2n form: [[K, qB], [qB, −K]] [u; v] = [b; 0], K = tL − pB.
    let mut rhs = vec![0.0; 2 * n];
    rhs[..n].copy_from_slice(b);
    let (mut lu, mut bu, mut lv, mut bv) = (vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let mut apply = |x: &[f64], y: &mut [f64]| {
        ops.stiffness_mass_mul(&x[..n], &mut lu, &mut bu);
        ops.stiffness_mass_mul(&x[n..], &mut lv, &mut bv);
        for i in 0..n {
            let ku = t * lu[i] - p * bu[i];
            let kv = t * lv[i] - p * bv[i];
            y[i] = ku + q * bv[i];
            y[n + i] = q * bu[i] - kv;
        }
    };
    let outcome = minres(
        &rhs,
        &mut apply,
        |x| precond.apply(x, n),
        params.rel_tol,
        params.max_iters,
    );
    // The last finite residual estimate (a breakdown can end the history with NaN).
    let last = last_finite(&outcome.history);
    if !outcome.converged || outcome.x.iter().any(|v| !v.is_finite()) {
        return Err(SolveError::NoConvergence {
            residual: last,
            iterations: outcome.iterations,
            pole: z,
        });
    }
    let mut ax = vec![0.0; 2 * n];
    apply(&outcome.x, &mut ax);
    let num: f64 = ax.iter().zip(&rhs).map(|(a, r)| (a - r) * (a - r)).sum();
    let r = rel(num, norm2(&rhs).powi(2));
    Ok((outcome.x, outcome.iterations, outcome.history, r))
}

/// The last finite entry of a residual history (1.0, the initial relative residual, if none).
fn last_finite(history: &[f64]) -> f64 {
    history.iter().rev().copied().find(|r| r.is_finite()).unwrap_or(1.0)
}
