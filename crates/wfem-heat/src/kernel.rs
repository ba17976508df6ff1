//! The heat kernel object `K_t = exp(−t M⁻¹L)` (paper, Eq. (5)–(9)): an operator context
//! ([`Operators`]) with a prepared [`Method`], applied to any number of functions and times.

use crate::check;
use crate::method::{Method, PreparedMethod};
use crate::spectral::Eigenbasis;
use crate::{HeatError, KernelKind, Operators};
use faer::sparse::SparseColMatRef;
use faer::{Mat, MatRef};
use mesh_fem::FemOperators;
use std::sync::Arc;

/// Options of [`HeatKernel::new`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct HeatParams {
    /// Which discrete kernel (mass matrix).
    pub kernel: KernelKind,
    /// How to evaluate it (default: the fast exact path, [`Method::Fast`]).
    pub method: Method,
}

/// The heat kernel of a mesh, `K_t = exp(−t M⁻¹L)` (paper, Eq. (6)), built once from the
/// operators and applied to any number of functions and times. Cheap to clone (shared).
///
/// L is the stiffness (symmetric positive semidefinite, positive diagonal; the paper prints
/// it with the opposite sign) and M the mass of the [`KernelKind`].
#[derive(Clone, Debug)]
pub struct HeatKernel {
    ops: Operators,
    method: Method,
    prepared: Arc<dyn PreparedMethod>,
}

impl HeatKernel {
    /// Builds the operator context of `params.kernel` ([`Operators::new`]) and prepares
    /// `params.method` on it.
    ///
    /// # Errors
    /// Those of [`Operators::new`] and [`Self::with_operators`].
    pub fn new(fem: &FemOperators, params: HeatParams) -> Result<Self, HeatError> {
        Self::with_operators(&Operators::new(fem, params.kernel)?, params.method)
    }

    /// Prepares `method` on a validated context (shared with other kernels, distances, …): the
    /// t-independent work of the method (the eigenpairs for `Dense`/`Spectral`, the factor of M
    /// for `Taylor`, the backend's analysis for `Rational`).
    ///
    /// # Errors
    /// [`HeatError::TooLargeForDense`]; [`HeatError::EigenNoConvergence`];
    /// [`HeatError::InvalidParameter`] for bad method parameters;
    /// [`HeatError::NotPositiveDefinite`]; [`HeatError::Solve`] (e.g. L not positive
    /// semidefinite for the rational method).
    pub fn with_operators(ops: &Operators, method: Method) -> Result<Self, HeatError> {
        let prepared = method.prepare(ops)?;
        Ok(Self {
            ops: ops.clone(),
            method,
            prepared: Arc::from(prepared),
        })
    }

    /// Number of vertices n.
    pub fn n(&self) -> usize {
        self.ops.n()
    }

    /// The operator context.
    pub fn operators(&self) -> &Operators {
        &self.ops
    }

    /// The method the kernel was built with.
    pub fn method(&self) -> &Method {
        &self.method
    }

    /// The mass matrix M of the kernel (B, D, I or a custom one).
    pub fn mass(&self) -> SparseColMatRef<'_, usize, f64> {
        self.ops.mass()
    }

    /// The eigenpairs, for the `Dense` and `Spectral` methods.
    pub fn eigenbasis(&self) -> Option<&Eigenbasis> {
        self.prepared.eigenbasis()
    }

    /// Applies the heat kernel, `g = K_t f = exp(−t M⁻¹L) f = X e^{−tΛ} XᵀM f`
    /// (paper, Eq. (6)), with the method of the kernel. `f` has length n.
    ///
    /// The null space of L (the constants on every connected component) is deflated exactly,
    /// `K_t f = Pf + (I − P) K_t (I − P) f` with P the M-orthogonal projector onto it, so every
    /// method conserves each component's mass `1_cᵀM K_t f = 1_cᵀM f` to rounding for any t
    /// (without it the drift grew like ε·t·λ_max: 1.6e−5 at t = 1e8·h̄²).
    ///
    /// # Errors
    /// [`HeatError::InvalidTime`] unless t is finite and positive;
    /// [`HeatError::LengthMismatch`]; [`HeatError::NonFiniteInput`];
    /// [`HeatError::KrylovNoConvergence`] (fast path).
    pub fn apply(&self, f: &[f64], t: f64) -> Result<Vec<f64>, HeatError> {
        let m = self.apply_many(MatRef::from_column_major_slice(f, f.len(), 1), t)?;
        Ok(m.col(0).iter().copied().collect())
    }

    /// Applies the heat kernel to every column of the n × k matrix `f`; one factorization
    /// (per t) serves all columns.
    ///
    /// # Errors
    /// As [`HeatKernel::apply`]; [`HeatError::NonFiniteInput`] names row and column.
    pub fn apply_many(&self, f: MatRef<'_, f64>, t: f64) -> Result<Mat<f64>, HeatError> {
        check::time(t)?;
        check::block(f, self.n())?;
        // K_t f = P f + (I − P) K_t (I − P) f with P the M-orthogonal projector onto the
        // constants of each component (exact: K_t P = P); see `null_space.rs`.
        let null_space = self.ops.null_space();
        let (deflated, coefs) = null_space.split(f);
        let mut g = self.prepared.apply(&self.ops, deflated.as_ref(), t)?;
        null_space.restore(&mut g, &coefs);
        Ok(g)
    }

    /// The heat-kernel matrix applied to a block, `H_t G = K_t M⁻¹ G = X D_t Xᵀ G`
    /// (NUMERICS §1): column i of `H_t` is the heat kernel `H_t(·, p_i)`, whose value at p_i is
    /// the heat kernel signature HKS_t(i), and `H_{2t}` is the Gram matrix of the diffusion
    /// distances. Symmetric positive definite. The null space is deflated exactly, so the
    /// constant part `Σ_c 1_c 1_cᵀ/1_cᵀM1_c` (the t → ∞ limit) is exact for every t.
    ///
    /// # Errors
    /// As [`Self::apply_many`]; [`HeatError::NotPositiveDefinite`] if M must be factored and
    /// cannot be.
    pub fn apply_kernel_matrix(&self, g: MatRef<'_, f64>, t: f64) -> Result<Mat<f64>, HeatError> {
        check::time(t)?;
        check::block(g, self.n())?;
        let null_space = self.ops.null_space();
        let (deflated, coefs) = null_space.split_dual(g);
        let mut h = self.prepared.apply_kernel_matrix(&self.ops, deflated.as_ref(), t)?;
        null_space.restore(&mut h, &coefs);
        Ok(h)
    }
}

impl HeatKernel {
    /// Fast path with its iteration count and final estimate (for benchmarks and
    /// diagnostics): the kernel's own fast method, or the default one.
    #[doc(hidden)]
    pub fn apply_fast_report(&self, f: &[f64], t: f64) -> Result<(Vec<f64>, usize, f64), HeatError> {
        check::time(t)?;
        check::vector(f, self.n())?;
        let (g, outcome) = crate::method::fast_report(&*self.prepared, &self.ops, f, t)?;
        Ok((g, outcome.iterations, outcome.estimate))
    }
}

/// One-shot `K_t f` with the default parameters (wFEM kernel, fast exact path).
///
/// # Errors
/// As [`HeatKernel::new`] and [`HeatKernel::apply`].
pub fn heat(ops: &FemOperators, f: &[f64], t: f64) -> Result<Vec<f64>, HeatError> {
    HeatKernel::new(ops, HeatParams::default())?.apply(f, t)
}
