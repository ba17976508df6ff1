//! 2-norm condition numbers of the shifted matrices tL − zB and of the preconditioned real
//! 2n×2n operator (paper Fig. 2c,d, where the paper plots κ₂(tL + θ_i B), θ = −conj z).
//!
//! Both are computed on the real symmetric form A₂ = [[K, qB], [qB, −K]], K = tL − pB,
//! z = p + iq: its eigenvalues are ± the singular values of tL − zB (A₂ is the real
//! representation of the complex matrix up to an orthogonal sign flip). With the SPD
//! preconditioner M = diag(P, P), P = tL + sB, the operator T = M⁻¹A₂ is self-adjoint in the
//! M-inner product and κ = max|μ|/min|μ| over its (real) eigenvalues μ. Both extremes come from
//! Lanczos with full reorthogonalisation (in the M-inner product) on T² and on T⁻² (the latter
//! through a complex sparse LU of tL − zB), at most 60 steps each: the estimates are lower
//! bounds of max and upper bounds of min that are exact once the Krylov space is invariant.

use crate::factor::{lu_symbolic, SeqLu};
use crate::iterative::{PrecondFactor, Preconditioner, PreconditionerShift};
use crate::lanczos::largest_ritz_value;
use crate::solver::{check_time, ShiftedSolver};
use crate::{OperatorPair, SolveError};
use faer::c64;
use faer::Mat;

/// Condition numbers of one shifted system (paper Fig. 2c,d).
#[derive(Debug, Clone, PartialEq)]
pub struct ConditionReport {
    /// Diffusion time t.
    pub t: f64,
    /// The pole z (x-plane convention).
    pub pole: c64,
    /// Largest singular value of tL − zB.
    pub sigma_max: f64,
    /// Smallest singular value of tL − zB.
    pub sigma_min: f64,
    /// κ₂(tL − zB) = σ_max/σ_min.
    pub matrix: f64,
    /// Shift s of the preconditioner P = tL + sB.
    pub preconditioner_shift: f64,
    /// κ of the MINRES operator diag(P,P)⁻¹A₂ (ratio of extreme |eigenvalues|).
    pub preconditioned: f64,
}

const MAX_STEPS: usize = 60;

/// Largest eigenvalue of an operator S that is self-adjoint and positive in the M-inner
/// product: [`largest_ritz_value`] run for (at most) `MAX_STEPS` steps from a deterministic
/// start vector (a lower bound, exact once the Krylov space is invariant).
fn lanczos_max(
    dim: usize,
    apply_s: impl Fn(&[f64]) -> Result<Vec<f64>, SolveError> + Sync,
    apply_m: &(dyn Fn(&[f64]) -> Vec<f64> + Sync),
) -> Result<f64, SolveError> {
    // Deterministic, non-special start vector.
    let start: Vec<f64> = (0..dim)
        .map(|i| 1.0 + ((i * 2654435761) % 1000) as f64 / 1000.0)
        .collect();
    let apply = |v: &[f64], _: &[f64]| apply_s(v);
    let (theta, _, _) = largest_ritz_value(&start, &apply, apply_m, 0.0, dim.min(MAX_STEPS))?;
    Ok(theta)
}

/// A 2 × 2 block operator in L and B on the stacked vector x = [u; v] of length 2n: row i of
/// the result is `row((Lu)ᵢ, (Bu)ᵢ, (Lv)ᵢ, (Bv)ᵢ)`, split into its entries i and n + i.
fn stacked(ops: &OperatorPair, x: &[f64], row: impl Fn(f64, f64, f64, f64) -> (f64, f64)) -> Vec<f64> {
    let n = ops.n();
    let (mut lu, mut bu, mut lv, mut bv) = (vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    ops.stiffness_mass_mul(&x[..n], &mut lu, &mut bu);
    ops.stiffness_mass_mul(&x[n..], &mut lv, &mut bv);
    let mut y = vec![0.0; 2 * n];
    for i in 0..n {
        (y[i], y[n + i]) = row(lu[i], bu[i], lv[i], bv[i]);
    }
    y
}

impl ShiftedSolver {
    /// Estimates κ₂(tL − zB) and the condition number of the MINRES operator preconditioned
    /// with P = tL + sB (s = |z| when `preconditioner_shift` is `None`).
    ///
    /// # Errors
    /// [`SolveError::InvalidTime`], [`SolveError::InvalidParameter`] for a bad shift,
    /// [`SolveError::SingularShiftedMatrix`] if tL − zB cannot be factored.
    pub fn condition(
        &self,
        t: f64,
        pole: c64,
        preconditioner_shift: Option<f64>,
    ) -> Result<ConditionReport, SolveError> {
        check_time(t)?;
        let s = preconditioner_shift.unwrap_or(pole.norm());
        if !(s.is_finite() && s > 0.0) {
            return Err(SolveError::InvalidParameter {
                name: "preconditioner shift",
                value: s,
                reason: "must be finite and > 0",
            });
        }
        let ops = &**self.pair();
        let n = ops.n();
        let (p, q) = (pole.re, pole.im);
        let a2 = |x: &[f64]| {
            stacked(ops, x, |lu, bu, lv, bv| {
                (t * lu - p * bu + q * bv, q * bu - (t * lv - p * bv))
            })
        };
        let symbolic = lu_symbolic(ops.pattern()).map_err(|detail| SolveError::Factorization {
            what: "symbolic LU",
            detail,
        })?;
        let lu = SeqLu::new(&symbolic, ops.shifted(t, pole).as_ref())
            .map_err(|_| SolveError::SingularShiftedMatrix { t, pole })?;
        let a2_inv = |y: &[f64]| -> Result<Vec<f64>, SolveError> {
            // A₂[u; v] = [y₁; y₂]  ⇔  (tL − zB)(u + iv) = y₁ − i y₂.
            let mut x = Mat::<c64>::from_fn(n, 1, |i, _| c64::new(y[i], -y[n + i]));
            lu.solve_in_place(x.as_mut());
            let mut out = vec![0.0; 2 * n];
            for i in 0..n {
                out[i] = x[(i, 0)].re;
                out[n + i] = x[(i, 0)].im;
            }
            if out.iter().any(|v| !v.is_finite()) {
                return Err(SolveError::SingularShiftedMatrix { t, pole });
            }
            Ok(out)
        };
        let identity = |x: &[f64]| x.to_vec();
        let dim = 2 * n;
        let smax2 = lanczos_max(dim, |x| Ok(a2(&a2(x))), &identity)?;
        let sinv2 = lanczos_max(dim, |x| a2_inv(&a2_inv(x)?), &identity)?;
        let sigma_max = smax2.sqrt();
        let sigma_min = 1.0 / sinv2.sqrt();

        let precond = PrecondFactor::build(
            ops,
            Preconditioner::ShiftedCholesky(PreconditionerShift::Shared(s)),
            t,
            s,
        )?;
        let m_apply = |x: &[f64]| stacked(ops, x, |l0, b0, l1, b1| (t * l0 + s * b0, t * l1 + s * b1));
        let m_inv = |x: &[f64]| -> Vec<f64> {
            let mut y = x.to_vec();
            precond.apply(&mut y, n);
            y
        };
        // T = M⁻¹A₂ and T⁻¹ = A₂⁻¹M are self-adjoint in the M-inner product.
        let tmax2 = lanczos_max(dim, |x| Ok(m_inv(&a2(&m_inv(&a2(x))))), &m_apply)?;
        let tinv2 = lanczos_max(dim, |x| a2_inv(&m_apply(&a2_inv(&m_apply(x))?)), &m_apply)?;
        Ok(ConditionReport {
            t,
            pole,
            sigma_max,
            sigma_min,
            matrix: sigma_max / sigma_min,
            preconditioner_shift: s,
            preconditioned: (tmax2 * tinv2).sqrt(),
        })
    }
}
