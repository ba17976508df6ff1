//! The paper's iterative backend ([`super::Backend::Minres`]): preconditioned MINRES on the real
//! 2n×2n symmetric form of each complex system, and preconditioned CG on the SPD system of the
//! real pole (iterations: `crate::iterative`).

use super::{relative, Pole, PoleReport, PreparedBackend, ShiftedSolve, SolveMethod};
use crate::iterative::{minres, pcg, MinresParams, PrecondFactor, Preconditioner, PreconditionerShift};
use crate::{OperatorPair, SolveError};
use faer::{Mat, MatRef};
use rayon::prelude::*;
use std::sync::Arc;

/// The validated MINRES parameters (no t-independent work).
#[derive(Debug)]
pub(crate) struct MinresBackend {
    params: MinresParams,
}

impl MinresBackend {
    pub(crate) fn prepare(params: MinresParams) -> Result<Box<dyn PreparedBackend>, SolveError> {
        params.validate()?;
        Ok(Box::new(Self { params }))
    }
}

#[derive(Debug)]
struct Term {
    pole: Pole,
    precond: Arc<PrecondFactor>,
}

/// The preconditioners of every pole of one t.
#[derive(Debug)]
pub(crate) struct MinresSolve {
    pair: Arc<OperatorPair>,
    t: f64,
    params: MinresParams,
    terms: Vec<Term>,
}

impl PreparedBackend for MinresBackend {
    fn factor(&self, pair: &Arc<OperatorPair>, poles: &[Pole], t: f64) -> Result<Box<dyn ShiftedSolve>, SolveError> {
        let kind = self.params.preconditioner;
        let shared = match kind {
            Preconditioner::ShiftedCholesky(PreconditionerShift::Shared(s)) => {
                Some(Arc::new(PrecondFactor::build(pair, kind, t, s)?))
            }
            Preconditioner::None => Some(Arc::new(PrecondFactor::Identity)),
            _ => None,
        };
        let terms = poles
            .par_iter()
            .map(|&pole| {
                let precond = match &shared {
                    Some(p) => p.clone(),
                    None => Arc::new(PrecondFactor::build(pair, kind, t, pole.z.norm())?),
                };
                Ok(Term { pole, precond })
            })
            .collect::<Result<_, SolveError>>()?;
        Ok(Box::new(MinresSolve {
            pair: pair.clone(),
            t,
            params: self.params,
            terms,
        }))
    }
}

impl MinresSolve {
    fn term(&self, term: &Term, g: MatRef<'_, f64>) -> Result<(Mat<f64>, PoleReport), SolveError> {
        let (n, k) = (self.pair.n(), g.ncols());
        let pole = term.pole;
        let mut report = pole.report(if pole.on_real_axis() {
            SolveMethod::ConjugateGradient
        } else {
            SolveMethod::Minres
        });
        let cols: Vec<Solved> = (0..k)
            .into_par_iter()
            .map(|j| {
                let b: Vec<f64> = g.col(j).iter().copied().collect();
                self.solve(pole, &b, &term.precond)
            })
            .collect::<Result<_, SolveError>>()?;
        let mut out = Mat::<f64>::zeros(n, k);
        let c = pole.c;
        for (j, solved) in cols.into_iter().enumerate() {
            let x = &solved.x;
            for i in 0..n {
                out[(i, j)] = if pole.on_real_axis() {
                    c.re * x[i]
                } else {
                    2.0 * (c.re * x[i] - c.im * x[n + i])
                };
            }
            report.iterations = report.iterations.max(solved.iterations);
            report.relative_residual = report.relative_residual.max(solved.residual);
            if j == 0 {
                report.residual_history = solved.history;
            }
        }
        Ok((out, report))
    }

    /// One Krylov solve of (tL − zM)x = b with real b; for complex z, x = [Re x; Im x] has
    /// length 2n.
    fn solve(&self, pole: Pole, b: &[f64], precond: &PrecondFactor) -> Result<Solved, SolveError> {
        let (pair, t, params) = (&*self.pair, self.t, &self.params);
        let n = pair.n();
        let z = pole.z;
        let (p, q) = (z.re, z.im);
        let mut lx = vec![0.0; n];
        let mut mx = vec![0.0; n];
        let no_convergence = |history: &[f64], iterations| SolveError::NoConvergence {
            residual: last_finite(history),
            iterations,
            pole: z,
        };
        if pole.on_real_axis() {
            let outcome = pcg(
                b,
                |x, y| {
                    pair.stiffness_mass_mul(x, &mut lx, &mut mx);
                    for i in 0..n {
                        y[i] = t * lx[i] - p * mx[i];
                    }
                },
                |x| precond.apply(x, n),
                params.rel_tol,
                params.max_iters,
            );
            if !outcome.converged {
                return Err(no_convergence(&outcome.history, outcome.iterations));
            }
            // The last finite residual estimate (a breakdown can end the history with NaN).
            let residual = last_finite(&outcome.history);
            return Ok(Solved {
                x: outcome.x,
                iterations: outcome.iterations,
                history: outcome.history,
                residual,
            });
        }
        // Real 2n form: [[K, qM], [qM, −K]] [u; v] = [b; 0], K = tL − pM.
        let mut rhs = vec![0.0; 2 * n];
        rhs[..n].copy_from_slice(b);
        let (mut lu, mut mu, mut lv, mut mv) = (vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        let mut apply = |x: &[f64], y: &mut [f64]| {
            pair.stiffness_mass_mul(&x[..n], &mut lu, &mut mu);
            pair.stiffness_mass_mul(&x[n..], &mut lv, &mut mv);
            for i in 0..n {
                let ku = t * lu[i] - p * mu[i];
                let kv = t * lv[i] - p * mv[i];
                y[i] = ku + q * mv[i];
                y[n + i] = q * mu[i] - kv;
            }
        };
        let outcome = minres(
            &rhs,
            &mut apply,
            |x| precond.apply(x, n),
            params.rel_tol,
            params.max_iters,
        );
        if !outcome.converged || outcome.x.iter().any(|v| !v.is_finite()) {
            return Err(no_convergence(&outcome.history, outcome.iterations));
        }
        let mut ax = vec![0.0; 2 * n];
        apply(&outcome.x, &mut ax);
        let num: f64 = ax.iter().zip(&rhs).map(|(a, r)| (a - r) * (a - r)).sum();
        let den: f64 = rhs.iter().map(|r| r * r).sum();
        Ok(Solved {
            residual: relative(num, den),
            x: outcome.x,
            iterations: outcome.iterations,
            history: outcome.history,
        })
    }
}

/// One right-hand side solved: x, iterations, residual history, true relative residual.
struct Solved {
    x: Vec<f64>,
    iterations: usize,
    history: Vec<f64>,
    residual: f64,
}

impl ShiftedSolve for MinresSolve {
    fn resolvent(&self, g: MatRef<'_, f64>) -> Result<(Mat<f64>, Vec<PoleReport>), SolveError> {
        super::sum_over_poles(&self.terms, self.pair.n(), g.ncols(), |term| self.term(term, g))
    }
}

/// The last finite entry of a residual history (1.0, the initial relative residual, if none).
fn last_finite(history: &[f64]) -> f64 {
    history.iter().rev().copied().find(|r| r.is_finite()).unwrap_or(1.0)
}
