//! The multi-shift backend ([`super::Backend::MultiShift`]): every pole in one shift-and-invert
//! Lanczos space, with one *real* sparse Cholesky per t.
//!
//! With A = M + γtL and S = A⁻¹M,
//!
//! `tL − zM = (1/γ) A (I − (1 + γz) S)`, so `(tL − zM)⁻¹ = γ (I − (1 + γz) S)⁻¹ A⁻¹`:
//!
//! every shifted system of Eq. (13) is a function of the one operator S (shift invariance),
//! and so is their weighted sum. With `Q(s) = Σ_j w_j Re(γ c_j/(1 − (1 + γz_j) s))`:
//! - the rational part `Σ_j w_j Re(c_j (tL − z_jM)⁻¹ M F) = S Q(S) F`, so
//!   `r_n(tM⁻¹L) F = c0 F + S Q(S) F = R(S) F` with `R(s) = r_n((1/s − 1)/γ)`;
//! - the resolvent `Σ_j w_j Re(c_j (tL − z_jM)⁻¹ G) = Q(S) A⁻¹ G`.
//!
//! One Lanczos run per right-hand side ([`crate::function::lanczos_function`]) evaluates the sum in the
//! Galerkin sense of multi-shift FOM. Its tolerance controls the *sum* (what K_t f needs); the
//! per-pole Galerkin residuals are reported, and the poles nearest the spectrum of S converge
//! more slowly than the sum.

use super::{Pole, PoleReport, PreparedBackend, ShiftedSolve, SolveMethod};
use crate::function::{lanczos_function_many, KrylovParams, LanczosReport};
use crate::lanczos::tridiagonal_eigen;
use crate::{OperatorPair, SolveError, SpdFactor};
use faer::{c64, Mat, MatRef};
use std::sync::Arc;

/// Columns stepped together (one block solve per Lanczos step).
const LOCKSTEP_BLOCK: usize = 32;

/// The validated Krylov parameters (no t-independent work beyond the pair's analysis).
#[derive(Debug)]
pub(crate) struct MultiShiftBackend {
    params: KrylovParams,
}

impl MultiShiftBackend {
    pub(crate) fn prepare(params: KrylovParams) -> Result<Box<dyn PreparedBackend>, SolveError> {
        params.validate()?;
        Ok(Box::new(Self { params }))
    }
}

/// The one real factor of M + γtL and the poles it serves.
#[derive(Debug)]
pub(crate) struct MultiShiftSolve {
    pair: Arc<OperatorPair>,
    t: f64,
    factor: SpdFactor,
    params: KrylovParams,
    /// The real pole (if any) last.
    poles: Vec<Pole>,
}

/// The factored matrix as a shifted matrix: M + γtL = γ(tL − zM) with z = −1/γ (the pole named
/// when it is singular).
fn factored_pole(gamma: f64) -> c64 {
    c64::new(-1.0 / gamma, 0.0)
}

impl PreparedBackend for MultiShiftBackend {
    fn factor(&self, pair: &Arc<OperatorPair>, poles: &[Pole], t: f64) -> Result<Box<dyn ShiftedSolve>, SolveError> {
        let gamma = self.params.gamma;
        let factor = pair.factor_spd(gamma * t, 1.0, || SolveError::SingularShiftedMatrix {
            t,
            pole: factored_pole(gamma),
        })?;
        Ok(Box::new(MultiShiftSolve {
            pair: pair.clone(),
            t,
            factor,
            params: self.params,
            poles: poles.to_vec(),
        }))
    }
}

impl MultiShiftSolve {
    /// `Q(s) = Σ_j w_j Re(γ c_j / (1 − (1 + γz_j) s))`.
    fn q(&self, s: f64) -> f64 {
        let gamma = self.params.gamma;
        let one = c64::new(1.0, 0.0);
        self.poles
            .iter()
            .map(|p| p.weight() * (p.c * gamma / (one - (one + p.z * gamma) * s)).re)
            .sum()
    }

    /// One Lanczos run per column of `rhs` for `h(S)` (in lockstep); with `with_mass`, `h(s) = s·Q(s)` on
    /// the column itself (the rational part), else `h = Q` on `A⁻¹` times the column (the
    /// resolvent). Reports, per pole, the Galerkin (FOM) residual of its shifted system
    /// `(I − c_jS)x = φ(S)u` in the M-norm relative to ‖φ(S)u‖_M (φ(s) = s with the mass,
    /// 1 without): `|c_j| β_m |e_mᵀ(I − c_jT)⁻¹φ(T)e₁| / ‖φ(T)e₁‖`.
    fn run(&self, rhs: MatRef<'_, f64>, with_mass: bool) -> Result<(Mat<f64>, Vec<PoleReport>), SolveError> {
        let (n, k, gamma) = (self.pair.n(), rhs.ncols(), self.params.gamma);
        // At s ≤ 0 (rounding below the spectrum (0, 1]) x = ∞ and the rational part vanishes.
        let h_mass = |s: f64| if s <= 0.0 { 0.0 } else { s * self.q(s) };
        let h_plain = |s: f64| self.q(s);
        let mass = |x: &[f64]| {
            let mut y = vec![0.0; x.len()];
            self.pair.mass_mul(x, &mut y);
            y
        };
        let lanczos = self.params.lanczos();
        // All columns in lockstep, sharing one block solve per Lanczos step.
        let solve_block = |x: faer::MatMut<'_, f64>| self.factor.solve_in_place(x);
        let (values, outcomes) = if with_mass {
            lanczos_function_many(&solve_block, &mass, rhs, &h_mass, &lanczos, LOCKSTEP_BLOCK)?
        } else {
            let mut u = rhs.to_owned();
            self.factor.solve_in_place(u.as_mut());
            lanczos_function_many(&solve_block, &mass, u.as_ref(), &h_plain, &lanczos, LOCKSTEP_BLOCK)?
        };
        let cols: Vec<(Vec<f64>, LanczosReport)> = outcomes
            .into_iter()
            .enumerate()
            .map(|(j, o)| (values.col(j).iter().copied().collect(), o))
            .collect();
        let mut out = Mat::<f64>::zeros(n, k);
        let mut reports: Vec<PoleReport> = self
            .poles
            .iter()
            .map(|p| p.report(SolveMethod::MultiShiftLanczos))
            .collect();
        let one = c64::new(1.0, 0.0);
        for (j, (x, outcome)) in cols.iter().enumerate() {
            if x.iter().any(|v| !v.is_finite()) {
                return Err(SolveError::SingularShiftedMatrix {
                    t: self.t,
                    pole: factored_pole(gamma),
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
            for (report, pole) in reports.iter_mut().zip(&self.poles) {
                let c = one + pole.z * gamma;
                let last: c64 = (0..m)
                    .map(|l| c64::new(u[(m - 1, l)] * u[(0, l)] * phi(theta[l]), 0.0) / (one - c * theta[l]))
                    .sum();
                let residual = c.norm() * beta_m * last.norm() / phi_norm.max(f64::MIN_POSITIVE);
                report.relative_residual = report.relative_residual.max(residual);
                report.iterations = report.iterations.max(outcome.iterations);
            }
        }
        Ok((out, reports))
    }
}

impl ShiftedSolve for MultiShiftSolve {
    fn resolvent(&self, g: MatRef<'_, f64>) -> Result<(Mat<f64>, Vec<PoleReport>), SolveError> {
        self.run(g, false)
    }

    fn mass_resolvent(
        &self,
        _pair: &OperatorPair,
        f: MatRef<'_, f64>,
    ) -> Result<(Mat<f64>, Vec<PoleReport>), SolveError> {
        self.run(f, true)
    }
}
