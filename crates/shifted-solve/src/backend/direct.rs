//! What the direct backends ([`super::ldlt`], [`super::lu`]) share: one complex factor per
//! complex pole, a real sparse Cholesky for the real pole of odd degrees, solves with many
//! right-hand sides and the true residual of every solve.
//!
//! **Scale.** Each matrix `tL − zM` is factored as `c·(tL − zM)` with c = 2⁻ᵉ a power of two
//! such that its largest diagonal entry is ≈ 1 (exact: powers of two change no digit). The
//! factorizations multiply entries together, so without it a mesh scaled by 10¹⁵⁰ with t to
//! match (entries near 10²⁹⁸) overflowed in the Schur complement updates and a mesh scaled by
//! 10⁻⁷⁸ underflowed into subnormals, while K_t itself is scale covariant (paper Sect. 5).

use super::{relative, Pole, PoleReport, ShiftedSolve, SolveMethod};
use crate::{OperatorPair, SolveError, SpdFactor};
use faer::{c64, Mat, MatMut, MatRef};
use rayon::prelude::*;
use std::fmt::Debug;
use std::sync::Arc;

/// A factored complex shifted matrix `c·(tL − zM)`.
pub(crate) trait ComplexFactor: Send + Sync + Debug {
    /// Overwrites `rhs` (n × k) with the solution of the factored system.
    fn solve_in_place(&self, rhs: MatMut<'_, c64>);
}

/// The factor of one pole.
#[derive(Debug)]
enum Factor {
    Complex(Box<dyn ComplexFactor>),
    /// The real pole: `tL − zM` is SPD.
    Real(SpdFactor),
}

#[derive(Debug)]
struct Term {
    pole: Pole,
    factor: Factor,
    /// The power of two c the matrix was multiplied by before factoring.
    scale: f64,
}

/// Every pole of one t, factored.
#[derive(Debug)]
pub(crate) struct DirectSolve {
    pair: Arc<OperatorPair>,
    t: f64,
    method: SolveMethod,
    terms: Vec<Term>,
}

/// The power of two 2⁻ᵉ with 2ᵉ ≈ the largest |diagonal entry| of `tL − zM`
/// ([`crate::lanczos::pow2_scale`]).
pub(crate) fn shift_scale(pair: &OperatorPair, t: f64, z: c64) -> f64 {
    let l = pair.diagonal(1.0, 0.0);
    let m = pair.diagonal(0.0, 1.0);
    let big = l
        .iter()
        .zip(&m)
        .map(|(&l, &m)| c64::new(t * l - z.re * m, -z.im * m).norm())
        .fold(0.0f64, f64::max);
    crate::lanczos::pow2_scale(big).0
}

/// Factors every pole at t (in parallel): complex poles with `complex` (given the scaled
/// values of `c·(tL − zM)` on the shared pattern), the real pole by a real Cholesky.
pub(crate) fn factor_all(
    pair: &Arc<OperatorPair>,
    poles: &[Pole],
    t: f64,
    method: SolveMethod,
    complex: impl Fn(&[c64]) -> Result<Box<dyn ComplexFactor>, ()> + Sync,
) -> Result<Box<dyn ShiftedSolve>, SolveError> {
    let cholesky = pair.cholesky()?;
    let terms = poles
        .par_iter()
        .map(|&pole| {
            let scale = shift_scale(pair, t, pole.z);
            let factor = if pole.real {
                let a = pair.combination(scale * t, -scale * pole.z.re);
                Factor::Real(cholesky.factor_sequential(a.as_ref()).map_err(|_| pole.singular(t))?)
            } else {
                let values: Vec<c64> = pair.shifted_values(t, pole.z).into_iter().map(|v| v * scale).collect();
                Factor::Complex(complex(&values).map_err(|()| pole.singular(t))?)
            };
            Ok(Term { pole, factor, scale })
        })
        .collect::<Result<Vec<_>, SolveError>>()?;
    Ok(Box::new(DirectSolve {
        pair: pair.clone(),
        t,
        method,
        terms,
    }))
}

impl DirectSolve {
    /// Contribution `w Re(c (tL − zM)⁻¹ G)` of one pole and its report.
    fn term(&self, term: &Term, g: MatRef<'_, f64>) -> Result<(Mat<f64>, PoleReport), SolveError> {
        let pair = &*self.pair;
        let (n, k, t) = (pair.n(), g.ncols(), self.t);
        let Pole { z, c, .. } = term.pole;
        let w = term.pole.weight();
        let mut out = Mat::<f64>::zeros(n, k);
        match &term.factor {
            Factor::Complex(f) => {
                let mut report = term.pole.report(self.method);
                let mut x = Mat::<c64>::from_fn(n, k, |i, j| c64::new(term.scale * g[(i, j)], 0.0));
                f.solve_in_place(x.as_mut());
                let mut ax = vec![c64::new(0.0, 0.0); n];
                for j in 0..k {
                    let xj = x.col_as_slice(j);
                    if xj.iter().any(|v| !v.re.is_finite() || !v.im.is_finite()) {
                        return Err(term.pole.singular(t));
                    }
                    pair.complex_mul(c64::new(t, 0.0), -z, xj, &mut ax);
                    let (mut num, mut den) = (0.0, 0.0);
                    for i in 0..n {
                        num += (ax[i] - g[(i, j)]).norm_sqr();
                        den += g[(i, j)] * g[(i, j)];
                        out[(i, j)] = w * (c * xj[i]).re;
                    }
                    report.relative_residual = report.relative_residual.max(relative(num, den));
                }
                Ok((out, report))
            }
            Factor::Real(llt) => {
                let mut report = term.pole.report(SolveMethod::RealCholesky);
                let mut x = Mat::<f64>::from_fn(n, k, |i, j| term.scale * g[(i, j)]);
                llt.solve_in_place(x.as_mut());
                let (mut lx, mut mx) = (vec![0.0; n], vec![0.0; n]);
                for j in 0..k {
                    let xj = x.col_as_slice(j);
                    if xj.iter().any(|v| !v.is_finite()) {
                        return Err(term.pole.singular(t));
                    }
                    pair.stiffness_mass_mul(xj, &mut lx, &mut mx);
                    let (mut num, mut den) = (0.0, 0.0);
                    for i in 0..n {
                        let r = t * lx[i] - z.re * mx[i] - g[(i, j)];
                        num += r * r;
                        den += g[(i, j)] * g[(i, j)];
                        out[(i, j)] = w * c.re * xj[i];
                    }
                    report.relative_residual = report.relative_residual.max(relative(num, den));
                }
                Ok((out, report))
            }
        }
    }
}

impl ShiftedSolve for DirectSolve {
    fn resolvent(&self, g: MatRef<'_, f64>) -> Result<(Mat<f64>, Vec<PoleReport>), SolveError> {
        super::sum_over_poles(&self.terms, self.pair.n(), g.ncols(), |term| self.term(term, g))
    }
}
