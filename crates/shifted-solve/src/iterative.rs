//! Preconditioned MINRES on the real 2n×2n symmetric form of (tL − zB)x = b, and
//! preconditioned CG for the real SPD pole of odd degrees.
//!
//! Splitting x = u + iv, z = p + iq, K_p = tL − pB, the complex symmetric system becomes the
//! real symmetric indefinite system (docs/NUMERICS.md §3.3b)
//!
//! ```text
//! [[K_p,  qB ],   [u]   [ Re b]
//!  [ qB, −K_p]] · [v] = [−Im b]
//! ```
//!
//! preconditioned by the SPD block diagonal diag(P, P), P = tL + sB. In the B-eigenbasis the
//! preconditioned spectrum is ±|tλ − z|/(tλ + s), so with s = |z| it lies in ±[~0.5, 1] and the
//! iteration count does not depend on the mesh size.

use crate::{OperatorPair, SolveError, SpdFactor};
use faer::MatMut;

/// Preconditioner of the MINRES / CG backend.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Preconditioner {
    /// diag(P, P) with P = tL + sB factored by sparse Cholesky (the recommended choice).
    ShiftedCholesky(PreconditionerShift),
    /// Jacobi: diag(tL + |z|B)⁻¹ on both blocks.
    Jacobi,
    /// No preconditioning (mesh-dependent iteration counts; for comparison only).
    None,
}

/// The shift s of the preconditioner P = tL + sB.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PreconditionerShift {
    /// s = |z_j|, one Cholesky per pole: κ ≤ 2 for every pole of degree 16 (docs/NUMERICS.md §3.3b).
    PoleModulus,
    /// One shared s for every pole, one Cholesky per t: κ ≤ 3.3 with s = 10 for degree 16.
    Shared(f64),
}

/// Parameters of the MINRES backend (paper Sect. 3: MINRES with preconditioning).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MinresParams {
    /// Stop when the preconditioned residual norm ‖r‖_{M⁻¹} has dropped by this factor.
    /// A relative error ε per pole is amplified by Σ 2|c_j| (937 for degree 16), hence 1e−14.
    pub rel_tol: f64,
    /// Iteration cap per pole and right-hand side; exceeding it is
    /// [`SolveError::NoConvergence`].
    pub max_iters: usize,
    /// Preconditioner.
    pub preconditioner: Preconditioner,
}

impl Default for MinresParams {
    fn default() -> Self {
        Self {
            rel_tol: 1e-14,
            max_iters: 1000,
            preconditioner: Preconditioner::ShiftedCholesky(PreconditionerShift::PoleModulus),
        }
    }
}

impl MinresParams {
    pub(crate) fn validate(&self) -> Result<(), SolveError> {
        if !(self.rel_tol.is_finite() && self.rel_tol > 0.0 && self.rel_tol < 1.0) {
            return Err(SolveError::InvalidParameter {
                name: "rel_tol",
                value: self.rel_tol,
                reason: "must lie in (0, 1)",
            });
        }
        if self.max_iters == 0 {
            return Err(SolveError::InvalidParameter {
                name: "max_iters",
                value: 0.0,
                reason: "must be at least 1",
            });
        }
        if let Preconditioner::ShiftedCholesky(PreconditionerShift::Shared(s)) = self.preconditioner {
            if !(s.is_finite() && s > 0.0) {
                return Err(SolveError::InvalidParameter {
                    name: "preconditioner shift",
                    value: s,
                    reason: "must be finite and > 0",
                });
            }
        }
        Ok(())
    }
}

/// A factored SPD preconditioner acting on n-vectors (applied blockwise to 2n-vectors).
#[derive(Debug)]
pub(crate) enum PrecondFactor {
    Cholesky(SpdFactor),
    Jacobi(Vec<f64>),
    Identity,
}

impl PrecondFactor {
    /// Builds the preconditioner for shift s (P = tL + sM), sequential inside one pole.
    pub fn build(pair: &OperatorPair, kind: Preconditioner, t: f64, s: f64) -> Result<Self, SolveError> {
        Ok(match kind {
            Preconditioner::ShiftedCholesky(_) => {
                let p = pair.combination(t, s);
                let llt = pair
                    .cholesky()?
                    .factor_sequential(p.as_ref())
                    .map_err(|e| SolveError::Factorization {
                        what: "Cholesky of the preconditioner tL + sM",
                        detail: e.to_string(),
                    })?;
                PrecondFactor::Cholesky(llt)
            }
            Preconditioner::Jacobi => PrecondFactor::Jacobi(pair.diagonal(t, s).iter().map(|d| 1.0 / d).collect()),
            Preconditioner::None => PrecondFactor::Identity,
        })
    }

    /// x ← M⁻¹ x for x of length n·blocks (blocks stored one after the other).
    pub fn apply(&self, x: &mut [f64], n: usize) {
        match self {
            PrecondFactor::Cholesky(llt) => {
                let blocks = x.len() / n;
                llt.solve_in_place(MatMut::from_column_major_slice_mut(x, n, blocks));
            }
            PrecondFactor::Jacobi(d) => {
                for block in x.chunks_mut(n) {
                    block.iter_mut().zip(d).for_each(|(v, d)| *v *= d);
                }
            }
            PrecondFactor::Identity => {}
        }
    }
}

/// Outcome of one Krylov solve.
#[derive(Debug, Clone)]
pub(crate) struct KrylovReport {
    pub x: Vec<f64>,
    pub iterations: usize,
    /// Relative residual estimate after each iteration (preconditioned norm for MINRES).
    pub history: Vec<f64>,
    pub converged: bool,
}

impl KrylovReport {
    fn new(x: Vec<f64>, iterations: usize, history: Vec<f64>, converged: bool) -> Self {
        KrylovReport {
            x,
            iterations,
            history,
            converged,
        }
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Preconditioned MINRES (Elman–Silvester–Wathen form, docs/NUMERICS.md §3.4) for a symmetric operator
/// `apply_a` and SPD preconditioner `apply_m_inv`.
pub(crate) fn minres(
    b: &[f64],
    mut apply_a: impl FnMut(&[f64], &mut [f64]),
    mut apply_m_inv: impl FnMut(&mut [f64]),
    rel_tol: f64,
    max_iters: usize,
) -> KrylovReport {
    let m = b.len();
    let mut x = vec![0.0; m];
    let mut v_old = vec![0.0; m];
    let mut v = b.to_vec();
    let mut z = v.clone();
    apply_m_inv(&mut z);
    let mut gamma = dot(&z, &v).max(0.0).sqrt();
    let gamma1 = gamma;
    let mut history = Vec::new();
    if gamma1 == 0.0 || !gamma1.is_finite() {
        return KrylovReport::new(x, 0, history, gamma1 == 0.0);
    }
    let mut gamma_old = 1.0;
    let mut eta = gamma;
    let (mut s_old, mut s, mut c_old, mut c) = (0.0, 0.0, 1.0, 1.0);
    let mut w_old = vec![0.0; m];
    let mut w = vec![0.0; m];
    let mut az = vec![0.0; m];
    let mut w_new = vec![0.0; m];
    for it in 1..=max_iters {
        z.iter_mut().for_each(|e| *e /= gamma);
        apply_a(&z, &mut az);
        let delta = dot(&az, &z);
        // v_new = Az − (δ/γ) v − (γ/γ_old) v_old, written into v_old.
        for k in 0..m {
            v_old[k] = az[k] - (delta / gamma) * v[k] - (gamma / gamma_old) * v_old[k];
        }
        std::mem::swap(&mut v_old, &mut v); // v = v_new, v_old = previous v
        let mut z_new = v.clone();
        apply_m_inv(&mut z_new);
        let gamma_new = dot(&z_new, &v).max(0.0).sqrt();
        let a0 = c * delta - c_old * s * gamma;
        let a1 = (a0 * a0 + gamma_new * gamma_new).sqrt();
        if !(a1.is_finite() && a1 > 0.0) {
            // Breakdown (a1 = 0: the operator is singular on the Krylov space, e.g. a pole at
            // an eigenvalue). Stop before x and the residual turn into NaN: the error then
            // carries the last finite residual (x did not change in this step).
            history.push(history.last().copied().unwrap_or(1.0));
            return KrylovReport::new(x, it, history, false);
        }
        let a2 = s * delta + c_old * c * gamma;
        let a3 = s_old * gamma;
        let c_new = a0 / a1;
        let s_new = gamma_new / a1;
        for k in 0..m {
            w_new[k] = (z[k] - a3 * w_old[k] - a2 * w[k]) / a1;
            x[k] += c_new * eta * w_new[k];
        }
        eta *= -s_new;
        std::mem::swap(&mut w_old, &mut w);
        std::mem::swap(&mut w, &mut w_new);
        z = z_new;
        gamma_old = gamma;
        gamma = gamma_new;
        c_old = c;
        c = c_new;
        s_old = s;
        s = s_new;
        let rel = eta.abs() / gamma1;
        history.push(rel);
        if !rel.is_finite() || !a1.is_finite() {
            return KrylovReport::new(x, it, history, false);
        }
        // γ_new ≈ 0 relative to the current step (γ_new ≤ 1e−13·a₁): the Krylov space is
        // numerically invariant and x is the exact minimiser over it. That solves the system
        // (up to rounding) unless the operator is singular and b is not in its range; then the
        // residual stays large and it is not convergence. Either way iterating further would
        // only divide rounding noise by γ ≈ 0 (on the 6-dimensional real form of a 3 × 3 pair
        // γ fell to 5e−15 at step 6).
        let invariant = gamma <= 1e-13 * a1;
        if rel < rel_tol || (invariant && rel < rel_tol.max(1e-8)) {
            return KrylovReport::new(x, it, history, true);
        }
        if invariant {
            return KrylovReport::new(x, it, history, false);
        }
    }
    KrylovReport::new(x, max_iters, history, false)
}

/// Preconditioned conjugate gradients for an SPD operator; stops on ‖r‖₂/‖b‖₂ < rel_tol.
pub(crate) fn pcg(
    b: &[f64],
    mut apply_a: impl FnMut(&[f64], &mut [f64]),
    mut apply_m_inv: impl FnMut(&mut [f64]),
    rel_tol: f64,
    max_iters: usize,
) -> KrylovReport {
    let m = b.len();
    let mut x = vec![0.0; m];
    let mut r = b.to_vec();
    let b_norm = dot(b, b).sqrt();
    let mut history = Vec::new();
    if b_norm == 0.0 {
        return KrylovReport::new(x, 0, history, true);
    }
    let mut zv = r.clone();
    apply_m_inv(&mut zv);
    let mut p = zv.clone();
    let mut rz = dot(&r, &zv);
    let mut ap = vec![0.0; m];
    for it in 1..=max_iters {
        apply_a(&p, &mut ap);
        let alpha = rz / dot(&p, &ap);
        for k in 0..m {
            x[k] += alpha * p[k];
            r[k] -= alpha * ap[k];
        }
        let rel = dot(&r, &r).sqrt() / b_norm;
        history.push(rel);
        if !rel.is_finite() {
            break;
        }
        if rel < rel_tol {
            return KrylovReport::new(x, it, history, true);
        }
        zv.copy_from_slice(&r);
        apply_m_inv(&mut zv);
        let rz_new = dot(&r, &zv);
        let beta = rz_new / rz;
        rz = rz_new;
        for k in 0..m {
            p[k] = zv[k] + beta * p[k];
        }
    }
    let iterations = history.len();
    KrylovReport::new(x, iterations, history, false)
}
