//! How `K_t f` is evaluated: the [`Method`] a user chooses (configuration) and, for each, one
//! module that prepares its t-independent data and applies the kernel (`PreparedMethod`).
//!
//! | method | module | prepared data | per t |
//! |---|---|---|---|
//! | [`Method::Dense`], [`Method::Spectral`] | `eigen` | the eigenpairs | a diagonal scaling |
//! | [`Method::Taylor`] | `taylor` | the Cholesky factor of M | one solve |
//! | [`Method::BackwardEuler`] | `backward_euler` | — | one Cholesky of M + tL |
//! | [`Method::Fast`] | `fast` | — | one Cholesky of M + γtL, a few tens of solves |
//! | [`Method::Rational`] | `rational` | the backend's symbolic analysis | one factorization per pole (or one, multi-shift) |
//!
//! **Adding a method** = a module here implementing `PreparedMethod` + a [`Method`] variant
//! with its line in the `registry!` (names, help, default parameters) and its arm in
//! `Method::prepare_connected`. The variant's prepared data lives in the module's type,
//! so no match can meet an impossible (method, data) pair.

mod backward_euler;
mod components;
mod eigen;
mod fast;
mod rational;
mod taylor;

use crate::spectral::{EigenParams, Eigenbasis};
use crate::{HeatError, Operators};
use faer::{Mat, MatRef};
use shifted_solve::backend::Backend;
use shifted_solve::function::KrylovParams;
use shifted_solve::SpdFactor;
use std::fmt::Debug;
use std::sync::{Arc, Mutex};

/// How to evaluate `K_t f`.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum Method {
    /// All n eigenpairs by a dense generalized eigendecomposition, `K_t f = X e^{−tΛ} XᵀMf`
    /// (Eq. (6)). Exact to rounding; O(n³) once, small meshes only
    /// (n ≤ [`crate::spectral::DENSE_MAX_VERTICES`]).
    Dense,
    /// The truncated spectral representation with the k smallest eigenpairs,
    /// `F_k = X_k e^{−tΛ_k} X_kᵀ M f` (Eq. (8)). Its error is the discarded tail, about
    /// e^{−tλ_{k+1}}‖f‖: large for small t (paper, Fig. 3).
    Spectral {
        /// Number of eigenpairs.
        k: usize,
        /// Eigensolver options.
        eigen: EigenParams,
    },
    /// First-order explicit Taylor step `M g = (M − tL) f`, i.e. `K_t ≈ I − tM⁻¹L`
    /// (Eq. (9)): one solve with M (factored once). It is a first-order method: the error of
    /// one step is `Σᵢ |e^{−tλᵢ} − 1 + tλᵢ| |cᵢ| ≈ t²λᵢ²/2` per eigencomponent cᵢ of f, so
    /// O(t²) for fixed smooth f, O(t) when a time T is covered in T/t steps, and unbounded
    /// (growing like tλ_max) for rough f: valid only for t → 0⁺. For comparison only.
    Taylor,
    /// One backward-Euler step `(M + tL) g = M f`, i.e. `K_t ≈ (I + tM⁻¹L)⁻¹`: one real
    /// sparse Cholesky per t. First order like [`Method::Taylor`] (one-step error
    /// `|1/(1 + tλ) − e^{−tλ}| ≈ t²λ²/2`, O(t) over a fixed horizon) but stable (it damps
    /// every mode). For comparison only.
    BackwardEuler,
    /// The fast exact path (beyond the paper): shift-and-invert rational Krylov on
    /// (M + γtL)⁻¹M, one real sparse Cholesky per t, reused for every iteration and every
    /// right-hand side; accurate to ≈1e−12 relative. See [`KrylovParams`].
    Fast(KrylovParams),
    /// The paper's generalized Chebyshev method (Eq. (11)–(13)): the best uniform rational
    /// approximation `e^{−x} ≈ c0 + 2 Re Σ_j c_j/(x − z_j)` of degree `degree` on [0, ∞)
    /// turns K_t f into `degree/2` complex shifted solves `(tL − z_j M) g_j = M f`,
    /// `K_t f ≈ c0 f + 2 Re Σ_j c_j g_j` (upper-half-plane poles; the paper's Eq. (13) is the
    /// same sum in the nuclear convention θ = −conj z, α = −conj c). The error is at most
    /// E_degree‖f‖_M (Eq. (14); E_16 = 2.1e−16, floored by rounding at ≈2e−14).
    /// The backend is the direct complex-symmetric LDLᵀ (default), the pivoted complex LU,
    /// MINRES (the paper's choice), or the multi-shift Lanczos that solves every pole in one
    /// Krylov space of (M + γtL)⁻¹M with a single real Cholesky; see [`shifted_solve::backend::Backend`].
    Rational {
        /// Degree n of r_n (see [`shifted_solve::poles::SHIPPED_DEGREES`]); E_n ≈ 9.289⁻ⁿ.
        degree: usize,
        /// How each shifted system is solved.
        backend: Backend,
    },
}

/// Eigenpairs of [`Method::Spectral`] when none are given (the command line's default is
/// min(this, n)).
pub const DEFAULT_SPECTRAL_EIGENPAIRS: usize = 200;

wfem_base::registry! {
    Method as "heat method" {
        Method::Fast(_) = Method::fast() => "fast":
            "shift-and-invert rational Krylov with one real factorization per t (beyond the paper; exact to ≈1e−12 and the quickest: the default)",
        Method::Rational { .. } = Method::rational(shifted_solve::poles::DEFAULT_DEGREE) => "rational" ["chebyshev", "cram"]:
            "the paper's rational Chebyshev approximation, r shifted sparse solves (Eq. (11)–(13))",
        Method::Spectral { .. } = Method::spectral(DEFAULT_SPECTRAL_EIGENPAIRS) => "spectral" ["truncated"]:
            "the truncated spectral sum of the k smallest eigenpairs (Eq. (8)); inaccurate at small t",
        Method::Dense = Method::Dense => "dense":
            "all eigenpairs by a dense generalized eigendecomposition (small meshes; the exact reference)",
        Method::Taylor = Method::Taylor => "taylor":
            "one first-order Taylor step B g = (B − tL) f (Eq. (9)); inaccurate except at tiny t",
        Method::BackwardEuler = Method::BackwardEuler => "backward-euler" ["implicit-euler"]:
            "one backward-Euler step (B + tL) g = B f; inaccurate except at tiny t",
    }
}

/// A method as files record it (the sidecars of the command line): its name and the
/// parameters a caller chose — `{"name": "rational", "degree": 16, "backend": "ldlt"}`,
/// `{"name": "spectral", "eigenpairs": 200}`, `{"name": "fast"}`.
impl serde::Serialize for Method {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        use wfem_base::Choice;
        let mut map = serializer.serialize_map(None)?;
        map.serialize_entry("name", self.name())?;
        match self {
            Method::Rational { degree, backend } => {
                map.serialize_entry("degree", degree)?;
                map.serialize_entry("backend", backend.name())?;
            }
            Method::Spectral { k, .. } => map.serialize_entry("eigenpairs", k)?,
            _ => {}
        }
        map.end()
    }
}

/// Options a caller may give beside a method's name (command-line flags, keyword arguments):
/// each belongs to one method, and [`Method::with_options`] refuses it for another.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MethodOptions {
    /// Degree of the rational approximation ([`Method::Rational`]).
    pub degree: Option<usize>,
    /// Backend of the shifted solves ([`Method::Rational`]).
    pub backend: Option<Backend>,
    /// Number of eigenpairs ([`Method::Spectral`]).
    pub eigenpairs: Option<usize>,
}

impl MethodOptions {
    /// Whether an option of the rational method is given (a method left unnamed is then the
    /// rational one).
    pub fn names_rational(&self) -> bool {
        self.degree.is_some() || self.backend.is_some()
    }
}

impl Method {
    /// This method with `options` applied.
    ///
    /// # Errors
    /// [`HeatError::MisplacedOption`] for an option that does not belong to this method (it is
    /// refused, not ignored). (A degree that is not shipped is refused when the method is
    /// prepared, naming the shipped ones.)
    pub fn with_options(self, options: &MethodOptions) -> Result<Self, HeatError> {
        let misplaced = |option: &'static str, owner: Method| HeatError::MisplacedOption {
            option,
            method: wfem_base::Choice::name(&self),
            owner: wfem_base::Choice::name(&owner),
        };
        let rational = !matches!(self, Method::Rational { .. });
        if options.degree.is_some() && rational {
            return Err(misplaced(
                "degree",
                Method::rational(shifted_solve::poles::DEFAULT_DEGREE),
            ));
        }
        if options.backend.is_some() && rational {
            return Err(misplaced(
                "backend",
                Method::rational(shifted_solve::poles::DEFAULT_DEGREE),
            ));
        }
        if options.eigenpairs.is_some() && !matches!(self, Method::Spectral { .. }) {
            return Err(misplaced("eigenpairs", Method::spectral(DEFAULT_SPECTRAL_EIGENPAIRS)));
        }
        Ok(match self {
            Method::Rational { degree, backend } => Method::Rational {
                degree: options.degree.unwrap_or(degree),
                backend: options.backend.unwrap_or(backend),
            },
            Method::Spectral { k, eigen } => Method::Spectral {
                k: options.eigenpairs.unwrap_or(k),
                eigen,
            },
            other => other,
        })
    }

    /// The rational Chebyshev method of `degree` with the direct complex-symmetric LDLᵀ backend
    /// (docs/NUMERICS.md §3.3d; about half the work of the pivoted LU, residual reported per pole).
    pub fn rational(degree: usize) -> Self {
        Method::Rational {
            degree,
            backend: Backend::DirectLdlt,
        }
    }

    /// The spectral method with the `k` smallest eigenpairs and default eigensolver options.
    pub fn spectral(k: usize) -> Self {
        Method::Spectral {
            k,
            eigen: EigenParams::default(),
        }
    }

    /// The fast exact path with its default parameters.
    pub fn fast() -> Self {
        Method::Fast(KrylovParams::default())
    }

    /// Whether the method evaluates K_t exactly up to a stated tolerance (dense, fast,
    /// rational), as opposed to an approximation whose error depends on t and f (spectral
    /// truncation, first-order steps).
    pub fn is_exact(&self) -> bool {
        matches!(self, Method::Dense | Method::Fast(_) | Method::Rational { .. })
    }

    /// Validates the parameters and runs the t-independent preparation on `ops`: on every
    /// connected component separately when there are several (`components.rs`; the
    /// eigensolvers split components themselves, so that the eigenbasis stays one object).
    pub(crate) fn prepare(&self, ops: &Operators) -> Result<Box<dyn PreparedMethod>, HeatError> {
        let parts = ops.components().len();
        let eigen = matches!(self, Method::Dense | Method::Spectral { .. });
        if parts > 1 && parts <= components::MAX_PARTS && !eigen {
            return components::Components::prepare(ops, self);
        }
        self.prepare_connected(ops)
    }

    /// The preparation on one context, as it is.
    pub(crate) fn prepare_connected(&self, ops: &Operators) -> Result<Box<dyn PreparedMethod>, HeatError> {
        match self {
            Method::Dense => eigen::EigenMethod::dense(ops),
            Method::Spectral { k, eigen } => eigen::EigenMethod::partial(ops, *k, eigen),
            Method::Taylor => taylor::Taylor::prepare(ops),
            Method::BackwardEuler => backward_euler::BackwardEuler::prepare(ops),
            Method::Fast(params) => fast::Fast::prepare(ops, *params),
            Method::Rational { degree, backend } => rational::Rational::prepare(ops, *degree, *backend),
        }
    }
}

/// The default is the fast exact path ([`Method::Fast`]): one real sparse Cholesky per t and a
/// few tens of solves, accurate to ≈1e−12 — the fastest exact method for one or a few vectors
/// (docs/BENCHMARKS.md). The paper's rational method stays selectable.
impl Default for Method {
    fn default() -> Self {
        Method::fast()
    }
}

/// Values at several times with an optional per-time error estimate.
pub(crate) type TimesResult = Result<(Vec<Mat<f64>>, Vec<Option<f64>>), HeatError>;

/// The values and error estimates of every t of `times`, in order, from those `computed` for
/// the times below `t_inf` (in order): from `t_inf` on the (deflated) result is the n × k zero
/// block, without an estimate.
pub(crate) fn spread_times(
    times: &[f64],
    t_inf: f64,
    computed: (Vec<Mat<f64>>, Vec<Option<f64>>),
    (n, k): (usize, usize),
) -> (Vec<Mat<f64>>, Vec<Option<f64>>) {
    let (mut v, mut e) = (computed.0.into_iter(), computed.1.into_iter());
    let mut values = Vec::with_capacity(times.len());
    let mut errors = Vec::with_capacity(times.len());
    for &t in times {
        if t < t_inf {
            values.push(v.next().unwrap_or_else(|| Mat::zeros(n, k)));
            errors.push(e.next().flatten());
        } else {
            values.push(Mat::zeros(n, k));
            errors.push(None);
        }
    }
    (values, errors)
}

/// `M F`, column by column ([`Operators::mass_mul`]).
pub(crate) fn mass_columns(ops: &Operators, f: MatRef<'_, f64>) -> Mat<f64> {
    let mut mf = Mat::<f64>::zeros(f.nrows(), f.ncols());
    for j in 0..f.ncols() {
        let col: Vec<f64> = f.col(j).iter().copied().collect();
        mf.col_as_slice_mut(j).copy_from_slice(&ops.mass_mul(&col));
    }
    mf
}

/// A method with its t-independent data, applied by [`crate::HeatKernel`].
pub(crate) trait PreparedMethod: Send + Sync + Debug {
    /// `K_t F` for every column of F (validated; the null space of L is deflated by the
    /// caller, so F is M-orthogonal to it).
    fn apply(&self, ops: &Operators, f: MatRef<'_, f64>, t: f64) -> Result<Mat<f64>, HeatError>;

    /// The kernel matrix applied to a block, `K̃_t G = K_t M⁻¹ G = X D_t Xᵀ G` (its columns are
    /// the heat-kernel functions `K̃_t(·, p_i)` for G = e_i; docs/NUMERICS.md §1). By default `M⁻¹G`
    /// (one Cholesky of M, cached) followed by [`Self::apply`]; methods that can avoid the
    /// solve with M do.
    fn apply_kernel_matrix(&self, ops: &Operators, g: MatRef<'_, f64>, t: f64) -> Result<Mat<f64>, HeatError> {
        let mut x = g.to_owned();
        ops.mass_factor()?.solve_in_place(x.as_mut());
        self.apply(ops, x.as_ref(), t)
    }

    /// `K_t F` (or `K̃_t F` with `kernel_matrix`) for every t of `times`, with a per-t error
    /// estimate where the method has one. By default one evaluation per t; methods that can
    /// serve many times from one factorization do.
    fn apply_times(&self, ops: &Operators, f: MatRef<'_, f64>, times: &[f64], kernel_matrix: bool) -> TimesResult {
        let values = times
            .iter()
            .map(|&t| {
                if kernel_matrix {
                    self.apply_kernel_matrix(ops, f, t)
                } else {
                    self.apply(ops, f, t)
                }
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok((values, vec![None; times.len()]))
    }

    /// The eigenpairs, for the spectral methods.
    fn eigenbasis(&self) -> Option<&Eigenbasis> {
        None
    }

    /// The fast path's `K_t f` of one vector with its Lanczos outcome (diagnostics), for the
    /// fast method only.
    fn fast_report(
        &self,
        _ops: &Operators,
        _f: &[f64],
        _t: f64,
    ) -> Option<Result<(Vec<f64>, shifted_solve::function::LanczosReport), HeatError>> {
        None
    }
}

/// `K_t f` by the fast path with its Lanczos outcome: the kernel's own fast method, or a
/// default one prepared for the occasion.
pub(crate) fn fast_report(
    prepared: &dyn PreparedMethod,
    ops: &Operators,
    f: &[f64],
    t: f64,
) -> Result<(Vec<f64>, shifted_solve::function::LanczosReport), HeatError> {
    match prepared.fast_report(ops, f, t) {
        Some(result) => result,
        None => fast::Fast::new(ops, KrylovParams::default())?.apply_with_outcome(ops, f, t),
    }
}

/// The factor of `M + s·L` of the last s, reused while s does not change (repeated `apply`
/// at one t then costs only the solves).
#[derive(Debug, Default)]
pub(crate) struct FactorCache {
    last: Mutex<Option<(f64, Arc<SpdFactor>)>>,
}

impl FactorCache {
    pub(crate) fn get(&self, ops: &Operators, s: f64, what: &str) -> Result<Arc<SpdFactor>, HeatError> {
        let mut cache = self.last.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
        if let Some((cached_s, factor)) = cache.as_ref() {
            if *cached_s == s {
                return Ok(factor.clone());
            }
        }
        let factor = Arc::new(ops.factor_shifted(s, || format!("{what} with shift {s:e}"))?);
        *cache = Some((s, factor.clone()));
        Ok(factor)
    }
}

#[cfg(test)]
mod serde_tests {
    use super::*;

    #[test]
    fn a_method_is_recorded_with_the_parameters_chosen() {
        let json = |m: &Method| serde_json::to_string(m).unwrap();
        assert_eq!(
            json(&Method::rational(16)),
            r#"{"name":"rational","degree":16,"backend":"ldlt"}"#
        );
        assert_eq!(json(&Method::spectral(200)), r#"{"name":"spectral","eigenpairs":200}"#);
        assert_eq!(json(&Method::fast()), r#"{"name":"fast"}"#);
        assert_eq!(json(&Method::BackwardEuler), r#"{"name":"backward-euler"}"#);
    }
}
