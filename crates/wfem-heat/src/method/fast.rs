//! [`super::Method::Fast`], the fast exact path: shift-and-invert (restricted-denominator)
//! rational Krylov for `exp(−t M⁻¹L) f` (van den Eshof & Hochbruck, SIAM J. Sci. Comput. 27
//! (2006) 1438–1457).
//!
//! With A = M + γtL (SPD, one real sparse Cholesky per t) the operator
//! S = A⁻¹M = (I + γt M⁻¹L)⁻¹ is self-adjoint in ⟨u, v⟩_M = uᵀMv with eigenvalues
//! s = 1/(1 + γtλ) ∈ (0, 1]. Since tλ = (1/s − 1)/γ,
//!
//! `K_t f = g(S) f`, with `g(s) = exp(−(1/s − 1)/γ)`,
//!
//! and the kernel matrix `K̃_t = K_t M⁻¹ = g(S) S⁻¹ A⁻¹ = (g(s)/s)(S) A⁻¹` needs no solve with
//! M. m steps of Lanczos in the M-inner product ([`shifted_solve::function::lanczos_function`]) give
//! `K_t f ≈ ‖f‖_M V_m g(T_m) e₁`. Because g is smooth on (0, 1] and its poles are all at
//! s = 0, the convergence does not depend on ‖tL‖ (mesh size or t), only on the accuracy
//! wanted: a few tens of solves reach 1e−12.

use super::{FactorCache, PreparedMethod, TimesResult};
use crate::{HeatError, Operators};
use faer::{Mat, MatMut, MatRef};
use shifted_solve::function::{
    lanczos_function, lanczos_function_many, lanczos_functions, lanczos_functions_many, KrylovParams, LanczosReport,
};
use shifted_solve::SolveError;

/// Memory for the Krylov bases of the columns run in lockstep (doubles; 256 MB).
const BASIS_BUDGET: usize = 32 << 20;

/// Lanczos steps a column typically takes at 1e−11 (for sizing the chunks of columns).
const TYPICAL_STEPS: usize = 48;

/// The validated parameters and the factor of M + γtL of the last t.
#[derive(Debug)]
pub(crate) struct Fast {
    params: KrylovParams,
    cache: FactorCache,
}

impl Fast {
    pub(crate) fn prepare(ops: &Operators, params: KrylovParams) -> Result<Box<dyn PreparedMethod>, HeatError> {
        Ok(Box::new(Self::new(ops, params)?))
    }

    pub(crate) fn new(ops: &Operators, params: KrylovParams) -> Result<Self, HeatError> {
        params.validate().map_err(|e| match e {
            SolveError::InvalidParameter { name, value, reason } => HeatError::InvalidParameter {
                name,
                reason: format!("{value} {reason}"),
            },
            other => HeatError::Solve(other),
        })?;
        ops.pair().cholesky()?;
        Ok(Self {
            params,
            cache: FactorCache::default(),
        })
    }

    /// `h(S) u` for every column of `f` (`resolve`: first apply A⁻¹ to the column). One
    /// column runs alone with the parallel products and solves; several run in lockstep and
    /// share one block solve per Lanczos step ([`lanczos_function_many`]), in chunks whose
    /// Krylov bases fit in [`BASIS_BUDGET`].
    fn run(
        &self,
        ops: &Operators,
        f: MatRef<'_, f64>,
        t: f64,
        h: &(dyn Fn(f64) -> f64 + Sync),
        resolve: bool,
    ) -> Result<(Mat<f64>, Vec<LanczosReport>), HeatError> {
        let gamma = self.params.gamma;
        let factor = self.cache.get(ops, gamma * t, "M + γtL")?;
        let pair = ops.pair();
        let lanczos = self.params.lanczos();
        let (n, k) = (f.nrows(), f.ncols());
        let convert = |c0: usize| {
            move |e: SolveError| match e {
                SolveError::KrylovNoConvergence { iterations, estimate } => HeatError::KrylovNoConvergence {
                    column: c0,
                    iterations,
                    estimate,
                },
                other => HeatError::Solve(other),
            }
        };
        if k == 1 {
            // One vector: its solves and products with M use every core.
            let solve = |b: &[f64]| factor.solve_vec(b);
            let mass = |x: &[f64]| pair.mass_mul_par(x);
            let mut u: Vec<f64> = f.col(0).iter().copied().collect();
            if resolve {
                u = solve(&u);
            }
            let (g, outcome) = lanczos_function(&solve, &mass, &u, h, &lanczos).map_err(convert(0))?;
            return Ok((Mat::from_fn(n, 1, |i, _| g[i]), vec![outcome]));
        }
        let solve_block = |x: MatMut<'_, f64>| factor.solve_in_place(x);
        let mass = |x: &[f64]| {
            let mut y = vec![0.0; x.len()];
            pair.mass_mul(x, &mut y);
            y
        };
        let chunk = (BASIS_BUDGET / (n.max(1) * TYPICAL_STEPS)).clamp(1, 64);
        let mut u = f.to_owned();
        if resolve {
            factor.solve_in_place(u.as_mut());
        }
        let (out, outcomes) =
            lanczos_function_many(&solve_block, &mass, u.as_ref(), h, &lanczos, chunk).map_err(convert(0))?;
        Ok((out, outcomes))
    }

    /// `K_t f` of one vector with its Lanczos outcome (for reports and benchmarks).
    pub(crate) fn apply_with_outcome(
        &self,
        ops: &Operators,
        f: &[f64],
        t: f64,
    ) -> Result<(Vec<f64>, LanczosReport), HeatError> {
        let gamma = self.params.gamma;
        let (g, mut outcomes) = self.run(
            ops,
            MatRef::from_column_major_slice(f, f.len(), 1),
            t,
            &|s| exp_of(s, gamma),
            false,
        )?;
        let outcome = outcomes.pop().ok_or(HeatError::DenseEigen)?;
        Ok((g.col(0).iter().copied().collect(), outcome))
    }
}

/// g(s) = exp(−(1/s − 1)/γ), continued by 0 for s ≤ 0 (rounding can push a Ritz value of S,
/// whose spectrum lies in (0, 1], marginally below zero).
fn exp_of(s: f64, gamma: f64) -> f64 {
    if s <= 0.0 {
        0.0
    } else {
        (-(1.0 / s - 1.0) / gamma).exp()
    }
}

impl Fast {
    /// Many times from one factor: `A = M + σL` with σ = γ·√(t_min·t_max) (the single-t
    /// choice σ = γt at the geometric centre of the window), and for each column one Krylov
    /// space serving every t: `K_t = g_t(S)`, `g_t(s) = exp(−(t/σ)(1/s − 1))` (for the
    /// kernel matrix `g_t(s)/s` on `A⁻¹` of the column). Each t stops on its own estimate.
    fn run_times(&self, ops: &Operators, f: MatRef<'_, f64>, times: &[f64], kernel_matrix: bool) -> TimesResult {
        let (t_min, t_max) = times
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(a, b), &t| (a.min(t), b.max(t)));
        // Measured on a 10K icosphere, f = e_i, 100 times over three decades: σ at the
        // geometric centre needs 78–81 steps (34 for one t); at a quarter of the window from
        // either end 122–145; other γ did not do better (0.03: 98–125, 0.3: 52–113).
        let sigma = self.params.gamma * (t_min * t_max).sqrt();
        let factor = self.cache.get(ops, sigma, "M + σL")?;
        let pair = ops.pair();
        let lanczos = self.params.lanczos();
        let solve = |b: &[f64]| factor.solve_vec(b);
        let ratios: Vec<f64> = times.iter().map(|&t| t / sigma).collect();
        let h = |l: usize, s: f64| {
            if s <= 0.0 {
                0.0
            } else {
                let g = (-ratios[l] * (1.0 / s - 1.0)).exp();
                if kernel_matrix {
                    g / s
                } else {
                    g
                }
            }
        };
        let (n, k, count) = (f.nrows(), f.ncols(), times.len());
        let convert = |e: SolveError| match e {
            SolveError::KrylovNoConvergence { iterations, estimate } => HeatError::KrylovNoConvergence {
                column: 0,
                iterations,
                estimate,
            },
            other => HeatError::Solve(other),
        };
        let mut u = f.to_owned();
        if kernel_matrix {
            factor.solve_in_place(u.as_mut());
        }
        let (values, outcomes): (Vec<Mat<f64>>, Vec<Vec<LanczosReport>>) = if k == 1 {
            // One vector: its solves and products with M use every core.
            let mass = |x: &[f64]| pair.mass_mul_par(x);
            let u0: Vec<f64> = u.col(0).iter().copied().collect();
            let (g, o) = lanczos_functions(&solve, &mass, &u0, &h, count, &lanczos).map_err(convert)?;
            (
                (0..count).map(|l| Mat::from_fn(n, 1, |i, _| g[(i, l)])).collect(),
                o.into_iter().map(|o| vec![o]).collect(),
            )
        } else {
            let solve_block = |x: MatMut<'_, f64>| factor.solve_in_place(x);
            let mass = |x: &[f64]| {
                let mut y = vec![0.0; x.len()];
                pair.mass_mul(x, &mut y);
                y
            };
            let chunk = (BASIS_BUDGET / (n.max(1) * TYPICAL_STEPS * 2)).clamp(1, 64);
            lanczos_functions_many(&solve_block, &mass, u.as_ref(), &h, count, &lanczos, chunk).map_err(convert)?
        };
        let estimates: Vec<f64> = outcomes
            .iter()
            .map(|per_column| per_column.iter().map(|o| o.estimate).fold(0.0, f64::max))
            .collect();
        Ok((values, estimates.into_iter().map(Some).collect()))
    }
}

/// The widest window `t_max / t_min` one factor serves in [`PreparedMethod::apply_times`]:
/// three decades take 78–81 Lanczos steps for a unit vector (see [`Fast::run_times`]); over
/// the four to five decades from a mesh's resolution `1/λ_max` to `1/λ₂₀` a rough column (a
/// noisy field, a random probe) stalled at the 200-step limit (estimate 3e−11 on TOSCA
/// centaur0). Wider lists are split into windows of at most this ratio, one factor each.
pub(crate) const WINDOW_RATIO: f64 = 1e3;

/// `times` grouped into windows of ratio at most [`WINDOW_RATIO`]: lists of indices into
/// `times`, by increasing t.
pub(crate) fn windows(times: &[f64]) -> Vec<Vec<usize>> {
    let mut order: Vec<usize> = (0..times.len()).collect();
    order.sort_by(|&a, &b| times[a].total_cmp(&times[b]));
    let mut out: Vec<Vec<usize>> = Vec::new();
    for i in order {
        match out.last_mut() {
            // The slack keeps a list of exactly three decades (as built by `powf`, the issue #17
            // benchmark) on one factor despite the rounding of its ends.
            Some(w) if times[i] <= WINDOW_RATIO * (1.0 + 1e-9) * times[w[0]] => w.push(i),
            _ => out.push(vec![i]),
        }
    }
    out
}

impl PreparedMethod for Fast {
    fn apply_times(&self, ops: &Operators, f: MatRef<'_, f64>, times: &[f64], kernel_matrix: bool) -> TimesResult {
        let groups = windows(times);
        if groups.len() <= 1 {
            return self.run_times(ops, f, times, kernel_matrix);
        }
        let mut values: Vec<Option<Mat<f64>>> = vec![None; times.len()];
        let mut estimates = vec![None; times.len()];
        for group in groups {
            let sub: Vec<f64> = group.iter().map(|&i| times[i]).collect();
            let (v, e) = self.run_times(ops, f, &sub, kernel_matrix)?;
            for ((&i, v), e) in group.iter().zip(v).zip(e) {
                values[i] = Some(v);
                estimates[i] = e;
            }
        }
        Ok((values.into_iter().flatten().collect(), estimates))
    }

    fn apply(&self, ops: &Operators, f: MatRef<'_, f64>, t: f64) -> Result<Mat<f64>, HeatError> {
        let gamma = self.params.gamma;
        Ok(self.run(ops, f, t, &|s| exp_of(s, gamma), false)?.0)
    }

    fn fast_report(&self, ops: &Operators, f: &[f64], t: f64) -> Option<Result<(Vec<f64>, LanczosReport), HeatError>> {
        Some(self.apply_with_outcome(ops, f, t))
    }

    /// `K̃_t G = (g(s)/s)(S) A⁻¹ G`: no solve with M.
    fn apply_kernel_matrix(&self, ops: &Operators, g: MatRef<'_, f64>, t: f64) -> Result<Mat<f64>, HeatError> {
        let gamma = self.params.gamma;
        let h = |s: f64| if s <= 0.0 { 0.0 } else { exp_of(s, gamma) / s };
        Ok(self.run(ops, g, t, &h, true)?.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn windows_cover_every_time_once_within_the_ratio() {
        let times = [5e-6, 1.0, 1e-2, 2e-6, 0.5, 1e-6, 3e-3];
        let groups = windows(&times);
        let mut seen: Vec<usize> = groups.iter().flatten().copied().collect();
        seen.sort_unstable();
        assert_eq!(seen, (0..times.len()).collect::<Vec<_>>());
        for g in &groups {
            let lo = g.iter().map(|&i| times[i]).fold(f64::INFINITY, f64::min);
            let hi = g.iter().map(|&i| times[i]).fold(0.0, f64::max);
            assert!(hi <= WINDOW_RATIO * (1.0 + 1e-9) * lo, "{g:?}");
        }
        // [1e−6, 5e−6] · [3e−3, 1e−2, 0.5, 1]: two windows.
        assert_eq!(groups, vec![vec![5, 3, 0], vec![6, 2, 4, 1]]);
        assert_eq!(windows(&[1.0, 2.0]), vec![vec![0, 1]]);
        let three_decades: Vec<f64> = (0..100)
            .map(|i| 0.1 * 0.7 * 1e3f64.powf(f64::from(i) / 99.0) * 1.3 / 0.7)
            .collect();
        assert_eq!(windows(&three_decades).len(), 1);
        assert!(windows(&[]).is_empty());
    }
}
