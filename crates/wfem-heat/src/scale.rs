//! The scale behaviour of the kernel (paper, Sect. 5): the largest eigenvalue λ_n and the
//! normalised, scale-invariant kernel.

use crate::{check, HeatError, HeatKernel, HeatParams, Operators};
use faer::Mat;
use mesh_fem::FemOperators;
use shifted_solve::lanczos::largest_ritz_value;
use wfem_base::rng::SplitMix64;

/// Options of [`largest_eigenvalue`] (Lanczos on M⁻¹L).
#[derive(Clone, Debug, PartialEq)]
pub struct LargestEigenParams {
    /// Relative residual tolerance `‖M⁻¹Lx − θx‖_M ≤ tol·θ` of the largest Ritz pair.
    pub tol: f64,
    /// Maximum number of Lanczos steps (capped at n).
    pub max_iter: usize,
    /// Seed of the random start vector.
    pub seed: u64,
}

impl Default for LargestEigenParams {
    fn default() -> Self {
        Self {
            tol: 1e-10,
            max_iter: 300,
            seed: 0x1a2b_3c4d,
        }
    }
}

/// The largest eigenvalue λ_n of `L x = λ M x` (paper, Sect. 5: the normalisation of the
/// scale-invariant kernel, "computed using the inverse method").
///
/// Lanczos ([`shifted_solve::lanczos::largest_ritz_value`]) on S = M⁻¹L, which is self-adjoint in
/// ⟨u, v⟩_M = uᵀMv, with full reorthogonalisation in that inner product: each step is one
/// product with L and one solve with M (the context's sparse Cholesky of M). The largest Ritz value θ of the tridiagonal
/// projection converges first (an extreme eigenvalue); it stops when the residual
/// `β_m |y_m| ≤ tol·θ` (then |θ − λ_n| ≲ tol²·λ_n·(gap factor) and θ ≤ λ_n always).
///
/// # Errors
/// [`HeatError::NotPositiveDefinite`] if M is not SPD; [`HeatError::InvalidParameter`] for bad
/// options or if the iteration does not reach the tolerance in `max_iter` steps.
pub fn largest_eigenvalue(ops: &Operators, params: &LargestEigenParams) -> Result<f64, HeatError> {
    let n = ops.n();
    if !(params.tol > 0.0 && params.tol < 1.0) {
        return Err(HeatError::InvalidParameter {
            name: "tol",
            reason: format!("{} is not in (0, 1)", params.tol),
        });
    }
    if params.max_iter == 0 {
        return Err(HeatError::InvalidParameter {
            name: "max_iter",
            reason: "must be positive".into(),
        });
    }
    let factor = ops.mass_factor()?;
    // S = M⁻¹L: w = M⁻¹(L v).
    let apply = |v: &[f64], _: &[f64]| Ok(factor.solve_vec(&ops.stiffness_mul(v)));
    let mass = |x: &[f64]| ops.mass_mul(x);
    let mut rng = SplitMix64::new(params.seed);
    let start: Vec<f64> = (0..n).map(|_| rng.next_centered()).collect();
    let steps = params.max_iter.min(n);
    let (theta, residual, converged) = largest_ritz_value(&start, &apply, &mass, params.tol, steps)?;
    if converged {
        Ok(theta)
    } else {
        Err(HeatError::InvalidParameter {
            name: "max_iter",
            reason: format!("Lanczos for λ_n did not converge in {steps} steps (relative residual {residual:.2e})"),
        })
    }
}

/// How [`NormalizedHeatKernel`] makes the time dimensionless (paper, Sect. 5).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Normalization {
    /// Eigenvalues divided by the largest one, λ/λ_n ∈ [0, 1] (the paper's choice):
    /// `K̂_τ = exp(−τ M⁻¹L/λ_n) = K_{τ/λ_n}`.
    #[default]
    LargestEigenvalue,
    /// By the surface area A = 1ᵀM1: `K̂_τ = K_{τ·A}`, i.e. eigenvalues λ·A. (The paper
    /// writes λ/area, which is not invariant: under M ↦ αM the eigenvalues scale by α⁻²
    /// and the area by α², so λ·A is the invariant combination.)
    Area,
}

/// A scale-invariant heat kernel (paper, Sect. 5): `K̂_τ = K_{τ/s}` with s = λ_n or s = 1/A
/// ([`Normalization`]). Because the wFEM kernel is scale-covariant,
/// `K_t(αM) = K_{α⁻²t}(M)` (λ ↦ α⁻²λ, B ↦ α²B), and s scales like α⁻², so
/// `K̂_τ(αM) = K̂_τ(M)` for every global scaling α.
#[derive(Debug)]
pub struct NormalizedHeatKernel {
    kernel: HeatKernel,
    normalization: Normalization,
    scale: f64,
}

impl NormalizedHeatKernel {
    /// Builds the kernel of `ops` with `params` ([`HeatKernel::new`]) and computes λ_n of
    /// `L x = λ M x` (M the kernel's mass) by [`largest_eigenvalue`], or the area 1ᵀM1.
    ///
    /// # Errors
    /// As [`HeatKernel::new`] and [`largest_eigenvalue`]; [`HeatError::InvalidParameter`] if
    /// the scale is not positive.
    pub fn new(ops: &FemOperators, params: HeatParams, normalization: Normalization) -> Result<Self, HeatError> {
        let kernel = HeatKernel::new(ops, params)?;
        let scale = match normalization {
            Normalization::LargestEigenvalue => largest_eigenvalue(kernel.operators(), &LargestEigenParams::default())?,
            Normalization::Area => 1.0 / kernel.operators().total_mass(),
        };
        if !(scale > 0.0 && scale.is_finite()) {
            return Err(HeatError::InvalidParameter {
                name: "normalization",
                reason: format!("{normalization:?} scale {scale:e} is not positive"),
            });
        }
        Ok(Self {
            kernel,
            normalization,
            scale,
        })
    }

    /// The normalising eigenvalue scale s: λ_n, or 1/A for [`Normalization::Area`].
    pub fn scale(&self) -> f64 {
        self.scale
    }

    /// The normalization used.
    pub fn normalization(&self) -> Normalization {
        self.normalization
    }

    /// The wrapped kernel.
    pub fn kernel(&self) -> &HeatKernel {
        &self.kernel
    }

    /// The physical time t = τ/s of the dimensionless time τ.
    pub fn time(&self, tau: f64) -> f64 {
        tau / self.scale
    }

    /// `K̂_τ f = K_{τ/s} f`.
    ///
    /// # Errors
    /// As [`HeatKernel::apply`].
    pub fn apply(&self, f: &[f64], tau: f64) -> Result<Vec<f64>, HeatError> {
        check::time(tau)?;
        self.kernel.apply(f, self.time(tau))
    }

    /// `K̂_τ` applied to every column of `f`.
    ///
    /// # Errors
    /// As [`HeatKernel::apply_many`].
    pub fn apply_many(&self, f: faer::MatRef<'_, f64>, tau: f64) -> Result<Mat<f64>, HeatError> {
        check::time(tau)?;
        self.kernel.apply_many(f, self.time(tau))
    }
}
