//! How the shifted systems `(tL − z_j M) x = b` of the rational method (paper Eq. (12)–(13))
//! are solved. Each backend is one module:
//!
//! | module | backend | per t |
//! |---|---|---|
//! | [`ldlt`] | complex-symmetric supernodal LDLᵀ (default) | one complex factorization per pole |
//! | [`lu`] | pivoted complex sparse LU | one complex factorization per pole |
//! | [`minres`] | preconditioned MINRES on the real 2n form (the paper's choice) | one SPD preconditioner per pole (or one shared) |
//! | [`multishift`] | every pole in one shift-and-invert Lanczos space | one real Cholesky |
//!
//! A backend implements `PreparedBackend` (its t-independent preparation, e.g. a symbolic
//! analysis) and returns a `ShiftedSolve` for each t; [`Backend`] is the registry (one match
//! in `Backend::prepare`, the registry line with its names and help, and the [`SolveMethod`] of
//! its reports). **Adding a backend** = a new module here + a `Backend` variant with its line in
//! the `registry!` below and its arm in `Backend::prepare`; the command line and the Python
//! package read the names and help from the registry ([`wfem_base::Choice`]).

pub(crate) mod direct;
pub mod ldlt;
pub mod lu;
pub mod minres;
pub mod multishift;

use crate::function::KrylovParams;
use crate::iterative::MinresParams;
use crate::{OperatorPair, SolveError};
use faer::{c64, Mat, MatRef};
use std::fmt::Debug;
use std::sync::Arc;

/// How each shifted system (tL − z_j M) x = b is solved (the registry of backends).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Backend {
    /// Sparse complex LU (faer, COLAMD + partial pivoting) with one symbolic analysis shared by
    /// every pole and every t ([`lu`]).
    DirectLu,
    /// Complex-symmetric supernodal LDLᵀ without pivoting ([`ldlt`]): about half the work of
    /// the LU, sharing the real Cholesky's AMD ordering and supernodes; every solve reports
    /// its true residual.
    DirectLdlt,
    /// Preconditioned MINRES on the real 2n×2n symmetric form (the paper's choice; [`minres`]).
    Minres(MinresParams),
    /// All poles in one Krylov space, with one *real* sparse Cholesky per t ([`multishift`]):
    /// with A = M + γtL and S = A⁻¹M, `(tL − zM)⁻¹ = γ (I − (1 + γz) S)⁻¹ A⁻¹`.
    MultiShift(KrylovParams),
}

impl Default for Backend {
    /// The direct LDLᵀ: exact to rounding, every pole's residual reported.
    fn default() -> Self {
        Backend::DirectLdlt
    }
}

wfem_base::registry! {
    Backend as "rational backend" {
        Backend::DirectLdlt = Backend::DirectLdlt => "ldlt" ["direct-ldlt"]:
            "complex-symmetric sparse LDLᵀ, one factorization per pole (default)",
        Backend::DirectLu = Backend::DirectLu => "lu" ["direct-lu"]:
            "pivoted complex sparse LU, one factorization per pole",
        Backend::Minres(_) = Backend::Minres(MinresParams::default()) => "minres":
            "preconditioned MINRES per pole (the paper's choice)",
        Backend::MultiShift(_) = Backend::MultiShift(KrylovParams::default()) => "multishift" ["multi-shift"]:
            "all poles in one shift-and-invert Lanczos space: one real Cholesky per t",
    }
}

impl Backend {
    /// Validates the parameters and runs the t-independent preparation on `pair`.
    pub(crate) fn prepare(&self, pair: &Arc<OperatorPair>) -> Result<Box<dyn PreparedBackend>, SolveError> {
        match self {
            Backend::DirectLdlt => ldlt::LdltBackend::prepare(pair),
            Backend::DirectLu => lu::LuBackend::prepare(pair),
            Backend::Minres(p) => minres::MinresBackend::prepare(*p),
            Backend::MultiShift(p) => multishift::MultiShiftBackend::prepare(*p),
        }
    }
}

/// Which method solved one pole (reports).
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

/// One pole z_j of the rational approximant with its residue c_j.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Pole {
    pub z: c64,
    pub c: c64,
    /// The real pole of odd degrees (negative, so `tL − zM` is SPD): solved as a real system.
    pub real: bool,
}

impl Pole {
    /// The poles of `approx`: the upper-half-plane ones, then the real pole of odd degrees.
    pub fn all(approx: &crate::poles::RationalApprox) -> Vec<Pole> {
        let mut poles: Vec<Pole> = approx
            .poles
            .iter()
            .zip(approx.residues)
            .map(|(&z, &c)| Pole { z, c, real: false })
            .collect();
        if let Some((z, c)) = approx.real_pole {
            poles.push(Pole {
                z: c64::new(z, 0.0),
                c: c64::new(c, 0.0),
                real: true,
            });
        }
        poles
    }

    /// Whether z is real (then `tL − zM` is a real matrix).
    pub fn on_real_axis(&self) -> bool {
        self.z.im == 0.0
    }

    /// Weight of `Re(c (tL − zM)⁻¹ g)` in the sum: 2 for a conjugate pair, 1 for a pole on the
    /// real axis.
    pub fn weight(&self) -> f64 {
        if self.on_real_axis() {
            1.0
        } else {
            2.0
        }
    }

    /// The pole named by an error about it.
    pub fn singular(&self, t: f64) -> SolveError {
        SolveError::SingularShiftedMatrix { t, pole: self.z }
    }

    /// An empty report for this pole.
    pub fn report(&self, method: SolveMethod) -> PoleReport {
        PoleReport {
            pole: self.z,
            residue: self.c,
            method,
            iterations: 0,
            relative_residual: 0.0,
            residual_history: Vec::new(),
        }
    }
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
    /// Largest true relative residual ‖b − (tL − zM)x‖₂ / ‖b‖₂ over the right-hand sides
    /// (the Galerkin residual for [`Backend::MultiShift`]).
    pub relative_residual: f64,
    /// Convergence history of the first right-hand side (iterative methods only): the relative
    /// preconditioned residual norm after each iteration.
    pub residual_history: Vec<f64>,
}

/// Per-pole information of one [`crate::RationalFactors::apply`] call.
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

/// A backend's t-independent preparation on one operator pair.
pub(crate) trait PreparedBackend: Send + Sync + Debug {
    /// Prepares (factors, or sets up the iteration of) the shifted systems of every pole at t.
    fn factor(&self, pair: &Arc<OperatorPair>, poles: &[Pole], t: f64) -> Result<Box<dyn ShiftedSolve>, SolveError>;
}

/// The shifted systems of one t, prepared for any number of right-hand sides.
pub(crate) trait ShiftedSolve: Send + Sync + Debug {
    /// `Σ_j w_j Re(c_j (tL − z_j M)⁻¹ G)` (w_j = [`Pole::weight`]) for G of size n × k, with
    /// one report per pole.
    fn resolvent(&self, g: MatRef<'_, f64>) -> Result<(Mat<f64>, Vec<PoleReport>), SolveError>;

    /// `Σ_j w_j Re(c_j (tL − z_j M)⁻¹ M F)`, the rational part of r_n(tM⁻¹L)F; by default the
    /// resolvent of `M F`.
    fn mass_resolvent(
        &self,
        pair: &OperatorPair,
        f: MatRef<'_, f64>,
    ) -> Result<(Mat<f64>, Vec<PoleReport>), SolveError> {
        let n = pair.n();
        let mut g = Mat::<f64>::zeros(n, f.ncols());
        let mut col = vec![0.0; n];
        for j in 0..f.ncols() {
            col.iter_mut().zip(f.col(j).iter()).for_each(|(c, v)| *c = *v);
            pair.mass_mul(&col, g.col_as_slice_mut(j));
        }
        self.resolvent(g.as_ref())
    }
}

/// Σ over the poles of one term each (the resolvent sum of Eq. (12)), the terms computed in
/// parallel: the one loop every per-pole backend shares.
pub(crate) fn sum_over_poles<T: Sync>(
    terms: &[T],
    n: usize,
    ncols: usize,
    term: impl Fn(&T) -> Result<(Mat<f64>, PoleReport), SolveError> + Sync,
) -> Result<(Mat<f64>, Vec<PoleReport>), SolveError> {
    use rayon::prelude::*;
    let interrupt = wfem_base::interrupt::current();
    let parts: Vec<(Mat<f64>, PoleReport)> = terms
        .par_iter()
        .map(|t| {
            wfem_base::interrupt::within(interrupt.as_ref(), || {
                wfem_base::interrupt::checkpoint()?;
                term(t)
            })
        })
        .collect::<Result<_, SolveError>>()?;
    let mut out = Mat::<f64>::zeros(n, ncols);
    let mut reports = Vec::with_capacity(parts.len());
    for (m, r) in parts {
        out += &m;
        reports.push(r);
    }
    Ok((out, reports))
}

/// ‖num‖/‖den‖ from squared sums (the absolute residual for a zero right-hand side).
pub(crate) fn relative(num_sq: f64, den_sq: f64) -> f64 {
    if den_sq == 0.0 {
        num_sq.sqrt()
    } else {
        (num_sq / den_sq).sqrt()
    }
}
