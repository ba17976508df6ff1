//! # wfem-heat
//!
//! The wFEM heat kernel `K_t = exp(−t B⁻¹L) = X D_t Xᵀ B` (paper, Eq. (6)) applied to
//! functions on a triangle mesh, without computing the spectrum. Modules follow the paper:
//!
//! * [`Operators`] — the one validated context: L, the mass M of the kernel (`mesh_fem::Mass`:
//!   consistent B of the wFEM kernel, lumped D, identity; Table 1), their shared pattern,
//!   symbolic analysis and null space.
//! * [`HeatKernel`] — a context with a prepared [`Method`](method::Method), applied to many
//!   functions and times (`K_t f`, and the kernel matrix `K̃_t = K_t M⁻¹ = X D_t Xᵀ`); [`heat`]
//!   is the one-shot version. [`method`] lists the methods (Eq. (6), (8), (9), (11)–(13) and the fast
//!   exact path, the default).
//! * [`spectral`] — [`spectral::Eigenbasis`]: generalized eigenpairs `L x = λ M x`, dense or the k
//!   smallest (Eq. (4), (8)).
//! * [`rkhs`] — the time-dependent scalar product (Eq. (16)), the inverse `K_{−t}`, the
//!   reproducing kernel `H_t = X D_{−t} Xᵀ` and the embeddings (Prop. 3.1, Eq. (15)–(20)).
//! * [`distance`] — [`distance::DiffusionDistance`] on any kernel (Eq. (18)).
//! * [`geodesic`] — [`geodesic::GeodesicSolver`]: geodesic distances by the heat method (one
//!   backward-Euler step, the normalised gradient, a pinned Poisson solve) refined by an eikonal
//!   step, on meshes and point clouds, from vertices or points on faces.
//! * [`basis`] — the canonical basis `K_t eᵢ` (Sect. 4.1, Eq. (21)).
//! * [`approx`] — feature points and the feature-driven approximation f = f_glob + f_loc
//!   (Sect. 4.2).
//! * [`scale`] — λ_max and the scale-invariant kernel (Sect. 5).
//! * [`times`] — [`times::TimeScales`]: which diffusion times mean something on a mesh.
//! * [`diagonal`] — how diagonals of kernel matrices are computed: selected inversion (the
//!   default, exact at every t), probing, unit columns; [`KernelDiagonal`], [`DiagonalParams`]
//!   and [`DiagonalSeries`] are the kernel's side of it.
//!
//! The heat kernel *signature* (HKS) is a shape descriptor and is defined once, in the
//! `shape-retrieval` crate, on top of [`HeatKernel::apply_kernel_matrix`] and [`spectral::Eigenbasis`].
//!
//! ```
//! use mesh_fem::{assemble, generate, AssemblyParams};
//! use wfem_heat::{HeatKernel, HeatParams};
//!
//! let mesh = generate::icosphere(3).with_area(4.0 * std::f64::consts::PI)?;
//! let ops = assemble(&mesh, &AssemblyParams::default())?;
//! let kernel = HeatKernel::new(&ops, HeatParams::default())?; // wFEM kernel, fast exact path
//! let f: Vec<f64> = mesh.positions().iter().map(|p| p[0]).collect();
//! let g = kernel.apply(&f, 0.01)?; // g = K_t f
//! // The x coordinate is nearly an eigenfunction (λ ≈ 2 on the sphere of area 4π): g ≈ e^{−2t} f.
//! assert!((g[0] / f[0] - (-0.02f64).exp()).abs() < 3e-3);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! **Sign convention.** L is symmetric positive semidefinite (positive diagonal, `L·1 = 0`);
//! the paper prints it with the opposite sign.

#![warn(missing_docs)]
// Robustness (issue #8): no unwrap()/expect() on user-controlled data in library code; the few
// justified ones carry `#[allow]` and an `// invariant:` comment (checked by tests/it/no_unwrap.rs).
#![cfg_attr(not(test), warn(clippy::unwrap_used, clippy::expect_used))]

pub mod approx;
pub mod basis;
mod check;
pub mod diagonal;
pub mod distance;
mod eigenbasis;
mod error;
pub mod geodesic;
mod kernel;
pub mod limits;
pub mod method;
mod null_space;
mod operators;
pub mod rkhs;
pub mod scale;
pub mod spectral;
pub mod times;

// The curated root (ARCHITECTURE.md, "Crate roots"): the validated operators, the kernel applied
// to functions and its diagonal, the error. Every other item is reached through its public
// module only; mesh-fem and shifted-solve are dependencies of their own, not re-exported.
pub use error::HeatError;
pub use kernel::{
    heat, DiagonalParams, DiagonalSeries, HeatKernel, HeatParams, KernelDiagonal, TimeSeries, MAX_ROUNDING_ERROR,
};
pub use operators::{AsSparse, Conditioning, Operators};

/// The README's examples, compiled as doc tests.
#[doc = include_str!("../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;
