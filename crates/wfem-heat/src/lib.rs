//! # wfem-heat
//!
//! The wFEM heat kernel `K_t = exp(−t B⁻¹L) = X D_t Xᵀ B` (paper, Eq. (6)) applied to
//! functions on a triangle mesh.
//!
//! * [`HeatKernel`]: built once from [`mesh_fem::FemOperators`], applied to many functions
//!   and times; [`heat`] is the one-shot version.
//! * [`KernelKind`]: the wFEM kernel (consistent mass B), the lumped kernel (D, Eq. (7)) and
//!   the linear kernel (B = I) of the paper's Table 1.
//! * [`Method`]: the dense reference (Eq. (6)), the truncated spectral sum (Eq. (8)), the
//!   Taylor and backward-Euler steps (Eq. (9)) and a fast exact path (shift-and-invert
//!   rational Krylov, one real sparse Cholesky per t).
//! * [`Eigenbasis`]: generalized eigenpairs `L x = λ M x`, dense or the k smallest.
//! * Canonical basis and features (Sect. 4.1–4.2): [`canonical_basis`] (K_t eᵢ for many
//!   anchors, one factorization set), [`canonical_limit`], [`auto_diffusion`],
//!   [`eigenfunction_features`], [`feature_approximation`] (f = f_glob + f_loc over the
//!   multiscale hierarchy tᵢ = (i/10)/λ_k).
//! * Scale (Sect. 5): [`largest_eigenvalue`] (λ_n by Lanczos on M⁻¹L) and the scale-invariant
//!   [`NormalizedHeatKernel`].
//!
//! ```
//! use mesh_fem::{assemble, generate, AssemblyParams};
//! use wfem_heat::{HeatKernel, HeatParams};
//!
//! let mesh = generate::icosphere(3).with_area(4.0 * std::f64::consts::PI)?;
//! let ops = assemble(&mesh, &AssemblyParams::default())?;
//! let kernel = HeatKernel::new(&ops, HeatParams::default())?; // wFEM kernel, fast path
//! let f: Vec<f64> = mesh.positions().iter().map(|p| p[0]).collect();
//! let g = kernel.apply(&f, 0.01)?; // g = K_t f
//! // The x coordinate is nearly an eigenfunction (λ ≈ 2 on the sphere of area 4π): g ≈ e^{−2t} f.
//! assert!((g[0] / f[0] - (-0.02f64).exp()).abs() < 3e-3);
//! # Ok::<(), wfem_heat::HeatError>(())
//! ```
//!
//! **Sign convention.** L is symmetric positive semidefinite (positive diagonal, `L·1 = 0`);
//! the paper prints it with the opposite sign.

#![warn(missing_docs)]
// Robustness (issue #8): no unwrap()/expect() on user-controlled data in library code; the few
// justified ones carry `#[allow]` and an `// invariant:` comment (checked by tests/no_unwrap.rs).
#![cfg_attr(not(test), warn(clippy::unwrap_used, clippy::expect_used))]

mod basis;
mod eigen;
mod error;
mod kernel;
mod krylov;
mod null_space;
mod sparse;

pub use basis::{
    auto_diffusion, canonical_basis, canonical_limit, eigenfunction_features, extrema, feature_approximation,
    global_component, largest_eigenvalue, multiscale_times, ApproxParams, AutoDiffusion, Coefficients,
    FeatureApproximation, LargestEigenParams, Normalization, NormalizedHeatKernel, Persistence, ScaleApproximation,
    SIGNIFICANT_PERSISTENCE,
};
// ---- operator algebra, RKHS and diffusion distances ----
mod algebra;
mod distance;
pub use algebra::{
    embedding_g, embedding_h, embeddings_h, inner_b, inner_t, inverse_cg, inverse_spectral, norm_b, rkhs_apply,
    InverseParams, InverseReport, TruncationReport,
};
pub use distance::{DiagonalInfo, DiagonalMethod, DiffusionDistance, DistanceKind, DistanceParams};

pub use eigen::{EigenParams, Eigenbasis, DENSE_MAX_VERTICES};
pub use error::HeatError;
pub use kernel::{heat, HeatKernel, HeatParams, KernelKind, Method};
pub use krylov::FastParams;
