//! Heat kernel signature (HKS) from a truncated spectrum of (L, B).
//!
//! The spectrum is the generalized eigenproblem `L φ_k = λ_k B φ_k` with `Φᵀ B Φ = I`
//! (paper, Eq. (4)); L is the cotangent stiffness, symmetric positive **semi**definite with a
//! positive diagonal (wfem's sign convention; libigl's `cotmatrix` is −L), and B the
//! consistent mass matrix. The wFEM heat kernel is `K_t = Φ D_t Φᵀ B`, `D_t = diag(e^{−λ_k t})`
//! (paper, Eq. (6)), truncated to the k given eigenpairs as in Eq. (8).
//!
//! Two diagonals of this kernel are in use and both are offered, named by what they are:
//!
//! * [`KernelDiagonal::KernelValue`]: `h(i, t) = Σ_k e^{−λ_k t} φ_k(i)²`, the diagonal of the
//!   symmetric kernel matrix `K̃_t = Φ D_t Φᵀ = K_t B⁻¹`, i.e. the value K_t(x_i, x_i) of the
//!   continuous heat kernel. This is Sun, Ovsjanikov & Guibas (SGP 2009) and what pyFM,
//!   DiffusionNet and most libraries compute. It has units of 1/area.
//! * [`KernelDiagonal::OperatorDiagonal`]: `h(i, t) = (Φ D_t Φᵀ B)_ii = Σ_k e^{−λ_k t} φ_k(i) (Bφ_k)(i)`,
//!   the diagonal of the wFEM heat kernel *matrix* of Eq. (6), as the paper uses it. It is
//!   dimensionless, and its sum over the vertices is exactly the heat trace `Σ_k e^{−λ_k t}`
//!   (`tr(Φ D_t Φᵀ B) = tr(D_t ΦᵀBΦ)`).
//!
//! Scale behaviour (paper, Sect. 5): scaling the surface by α maps `λ → α⁻²λ`, `φ → α⁻¹φ`,
//! `B → α²B`, so `K_t(αM) = K_{α⁻²t}(M)`. [`SpectrumNormalization`] evaluates the descriptor on
//! the shape rescaled so that λ_max = 1 (the paper's choice for its scale-invariant dense
//! descriptor, DHK3) or so that its area is 1; either makes both conventions scale-invariant.

use crate::{check, RetrievalError};
use faer::linalg::matmul::matmul;
use faer::sparse::linalg::matmul::sparse_dense_matmul;
use faer::sparse::SparseColMatRef;
use faer::{Accum, Mat, MatRef, Par};
use wfem_heat::KernelDiagonal;

/// Eigenvalues below `ZERO_EIGENVALUE_RTOL · λ_max` count as zero (the constant modes) when
/// choosing the automatic time range; pyFM uses the same relative threshold.
const ZERO_EIGENVALUE_RTOL: f64 = 1e-8;

/// A truncated spectrum of (L, B): k eigenvalues and n × k B-orthonormal eigenvectors,
/// optionally with the products `BΦ` needed by [`KernelDiagonal::OperatorDiagonal`].
///
/// Eigenvalues need not be sorted; they must be finite and non-negative up to round-off
/// (λ ≥ −1e−8·max|λ|), since L is positive semidefinite.
#[derive(Clone, Debug)]
pub struct Spectrum<'a> {
    eigenvalues: &'a [f64],
    eigenvectors: MatRef<'a, f64>,
    mass_eigenvectors: Option<Mat<f64>>,
    area: Option<f64>,
}

impl<'a> Spectrum<'a> {
    /// Wraps eigenvalues `λ_k` (length k) and eigenvectors `Φ` (n × k, column k belongs to `λ_k`).
    ///
    /// # Errors
    /// [`RetrievalError::Empty`] for k = 0 or n = 0, [`RetrievalError::DimensionMismatch`] if
    /// `Φ` does not have k columns, [`RetrievalError::NonFinite`] for NaN/∞, and
    /// [`RetrievalError::NegativeEigenvalue`] for an eigenvalue below −1e−8·max|λ|.
    pub fn new(eigenvalues: &'a [f64], eigenvectors: MatRef<'a, f64>) -> Result<Self, RetrievalError> {
        check::non_empty("eigenvalues", eigenvalues.len())?;
        check::non_empty("eigenvectors (rows)", eigenvectors.nrows())?;
        check::same(
            "eigenvector columns vs eigenvalues",
            eigenvalues.len(),
            eigenvectors.ncols(),
        )?;
        check::finite_slice("eigenvalues", eigenvalues)?;
        check::finite_mat("eigenvectors", eigenvectors)?;
        let scale = eigenvalues.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        if let Some((index, &value)) = eigenvalues
            .iter()
            .enumerate()
            .find(|(_, &v)| v < -ZERO_EIGENVALUE_RTOL * scale.max(f64::MIN_POSITIVE))
        {
            return Err(RetrievalError::NegativeEigenvalue { index, value });
        }
        Ok(Self {
            eigenvalues,
            eigenvectors,
            mass_eigenvectors: None,
            area: None,
        })
    }

    /// Attaches the surface area `A = 1ᵀB1` (the sum of the mass matrix, paper Eq. (3)), for
    /// time windows in units of the area ([`crate::sihks::TimeUnit::Area`]).
    ///
    /// # Errors
    /// [`RetrievalError::InvalidParameter`] unless the area is finite and positive.
    pub fn with_area(mut self, area: f64) -> Result<Self, RetrievalError> {
        check::positive("area", area)?;
        self.area = Some(area);
        Ok(self)
    }

    /// The surface area, if attached ([`Self::with_area`]).
    pub fn area(&self) -> Option<f64> {
        self.area
    }

    /// Attaches the mass matrix the eigenvectors are orthonormal against (n × n): the consistent
    /// B for the wFEM kernel (Eq. (6)), or the lumped D if the spectrum is that of (L, D) (the
    /// Voronoi-cot kernel, Eq. (7)). Computes `BΦ` once. Orthonormality is not checked.
    ///
    /// # Errors
    /// [`RetrievalError::DimensionMismatch`] if B is not n × n.
    pub fn with_mass(mut self, mass: SparseColMatRef<'_, usize, f64>) -> Result<Self, RetrievalError> {
        let n = self.n_vertices();
        check::same("mass rows vs eigenvector rows", n, mass.nrows())?;
        check::same("mass columns vs eigenvector rows", n, mass.ncols())?;
        let mut bx = Mat::<f64>::zeros(n, self.n_eigenpairs());
        sparse_dense_matmul(bx.as_mut(), Accum::Replace, mass, self.eigenvectors, 1.0, Par::rayon(0));
        check::finite_mat("mass · eigenvectors", bx.as_ref())?;
        self.mass_eigenvectors = Some(bx);
        Ok(self)
    }

    /// Attaches a precomputed `BΦ` (n × k), e.g. from an eigensolver that already has it.
    ///
    /// # Errors
    /// [`RetrievalError::DimensionMismatch`] if it is not n × k, [`RetrievalError::NonFinite`].
    pub fn with_mass_eigenvectors(mut self, mass_eigenvectors: MatRef<'_, f64>) -> Result<Self, RetrievalError> {
        check::same(
            "BΦ rows vs eigenvector rows",
            self.n_vertices(),
            mass_eigenvectors.nrows(),
        )?;
        check::same(
            "BΦ columns vs eigenvalues",
            self.n_eigenpairs(),
            mass_eigenvectors.ncols(),
        )?;
        check::finite_mat("mass · eigenvectors", mass_eigenvectors)?;
        self.mass_eigenvectors = Some(mass_eigenvectors.to_owned());
        Ok(self)
    }

    /// Number of vertices n.
    pub fn n_vertices(&self) -> usize {
        self.eigenvectors.nrows()
    }

    /// Number of eigenpairs k.
    pub fn n_eigenpairs(&self) -> usize {
        self.eigenvalues.len()
    }

    /// The eigenvalues λ_k.
    pub fn eigenvalues(&self) -> &[f64] {
        self.eigenvalues
    }

    /// The eigenvectors Φ (n × k).
    pub fn eigenvectors(&self) -> MatRef<'a, f64> {
        self.eigenvectors
    }

    /// Applies the truncated wFEM heat kernel to a block of functions (paper, Eq. (8)):
    /// `K_t F = Φ D_t Φᵀ B F = Σ_k e^{−λ_k t} ⟨F, φ_k⟩_B φ_k`, for F n × m. Cost O(n·k·m).
    /// Suits [`crate::bof::Vocabulary::spatially_sensitive_bag`] as its kernel.
    ///
    /// # Errors
    /// [`RetrievalError::MassRequired`] without B, [`RetrievalError::DimensionMismatch`] if F
    /// does not have n rows, [`RetrievalError::InvalidParameter`] for t < 0 or non-finite,
    /// [`RetrievalError::NonFinite`] for NaN in F.
    pub fn apply_heat_kernel(&self, t: f64, functions: MatRef<'_, f64>) -> Result<Mat<f64>, RetrievalError> {
        if !(t.is_finite() && t >= 0.0) {
            return Err(RetrievalError::InvalidParameter {
                name: "t",
                value: t,
                reason: "must be finite and ≥ 0",
            });
        }
        let bx = self.mass_eigenvectors.as_ref().ok_or(RetrievalError::MassRequired)?;
        check::same("function rows vs vertices", self.n_vertices(), functions.nrows())?;
        check::finite_mat("functions", functions)?;
        // Coefficients c = D_t (BΦ)ᵀ F (k × m), then Φ c.
        let mut coefficients = Mat::<f64>::zeros(self.n_eigenpairs(), functions.ncols());
        matmul(
            coefficients.as_mut(),
            Accum::Replace,
            bx.transpose(),
            functions,
            1.0,
            Par::rayon(0),
        );
        for (k, &lambda) in self.eigenvalues.iter().enumerate() {
            let decay = (-lambda * t).exp();
            coefficients.row_mut(k).iter_mut().for_each(|c| *c *= decay);
        }
        let mut out = Mat::<f64>::zeros(self.n_vertices(), functions.ncols());
        matmul(
            out.as_mut(),
            Accum::Replace,
            self.eigenvectors,
            coefficients.as_ref(),
            1.0,
            Par::rayon(0),
        );
        Ok(out)
    }

    /// The largest eigenvalue λ_max of the given (truncated) spectrum.
    pub fn max_eigenvalue(&self) -> f64 {
        self.eigenvalues.iter().fold(0.0f64, |m, &v| m.max(v))
    }
}

/// Rescaling of the shape before the descriptor is evaluated, for scale invariance (paper, Sect. 5).
///
/// Rescaling a surface by s maps `λ → λ/s²` and `φ_k(i)² → φ_k(i)²/s²`, leaves
/// `φ_k(i)(Bφ_k)(i)` unchanged, and maps the times of the automatic sampling by `t → s² t`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum SpectrumNormalization {
    /// Use the spectrum as given (scale-covariant descriptor).
    #[default]
    None,
    /// Rescale so that the largest given eigenvalue is 1: `λ̃ = λ/λ_max` (and `φ̃² = φ²/λ_max` in the
    /// kernel-value convention). This is the paper's normalization for its scale-invariant dense
    /// descriptor (DHK3). The paper divides by λ_n of the full spectrum; here λ_max is the largest
    /// eigenvalue *given*, so pass a spectrum truncated at a consistent index when comparing shapes.
    MaxEigenvalue,
    /// Rescale to unit area: `λ̃ = λ·A` (and `φ̃² = φ²·A` in the kernel-value convention), A = area
    /// of the shape (`1ᵀB1`). (The paper writes λ/area; λ·area is the scale-invariant product.)
    UnitArea {
        /// The area A of the shape.
        area: f64,
    },
}

wfem_base::registry! {
    SpectrumNormalization as "spectrum normalization" {
        SpectrumNormalization::None = SpectrumNormalization::None => "none":
            "the spectrum as given: a scale-covariant descriptor (default)",
        SpectrumNormalization::MaxEigenvalue = SpectrumNormalization::MaxEigenvalue => "max-eigenvalue":
            "eigenvalues divided by the largest one given (the paper's DHK3)",
        SpectrumNormalization::UnitArea { .. } = SpectrumNormalization::UnitArea { area: 1.0 } => "area" ["unit-area"]:
            "the shape rescaled to unit area, λ·A (the area is the shape's own)",
    }
}

/// Number of automatic times by default (the command line's and Python's too): 16 log-spaced
/// times cover the range `[4 ln10/λ_max, 4 ln10/λ_2]` at about four per decade, as DiffusionNet
/// and most HKS pipelines sample it.
pub const DEFAULT_NUM_TIMES: usize = 16;

/// How the diffusion times are chosen. In files, explicit times are a list of numbers and
/// automatic ones `{"num_times": T}`.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(untagged)]
pub enum TimeSampling {
    /// `num_times` values log-spaced between `4 ln10/λ_max` and `4 ln10/λ_2` of the (normalized)
    /// spectrum, λ_2 = the smallest eigenvalue above 1e−8·λ_max (Sun et al. 2009; pyFM `auto_HKS`).
    Auto {
        /// Number of times T (default [`DEFAULT_NUM_TIMES`]).
        num_times: usize,
    },
    /// Explicit positive times (in the units of the normalized spectrum).
    Explicit(Vec<f64>),
}

impl TimeSampling {
    /// Number of times T.
    pub fn len(&self) -> usize {
        match self {
            Self::Auto { num_times } => *num_times,
            Self::Explicit(times) => times.len(),
        }
    }

    /// Whether there is no time.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The bounds of [`wfem_heat::limits`], checked before anything is computed: at most
    /// [`wfem_heat::limits::MAX_TIMES`] times, and n × T values within
    /// [`wfem_heat::limits::OUTPUT_MEMORY`] on an n-vertex mesh.
    ///
    /// # Errors
    /// [`RetrievalError::Heat`] with [`wfem_heat::HeatError::InvalidParameter`] naming the times.
    pub fn check_size(&self, n: usize) -> Result<(), RetrievalError> {
        let name = match self {
            Self::Auto { .. } => "num_times",
            Self::Explicit(_) => "times",
        };
        if !self.is_empty() {
            wfem_heat::limits::times(name, self.len())?;
        }
        wfem_heat::limits::columns(name, self.len(), n)?;
        Ok(())
    }
}

impl Default for TimeSampling {
    fn default() -> Self {
        Self::Auto {
            num_times: DEFAULT_NUM_TIMES,
        }
    }
}

/// Options of [`heat_kernel_signature`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct HksParams {
    /// Which diagonal (default [`KernelDiagonal::KernelValue`]).
    pub convention: KernelDiagonal,
    /// Which times (default: 100 automatic log-spaced times).
    pub times: TimeSampling,
    /// Divide each time's column by the heat trace `Z(t) = Σ_k e^{−λ_k t}` ("scaled" HKS, pyFM
    /// `scaled=True`). Default `false`.
    pub scaled: bool,
    /// Rescaling for scale invariance (default none).
    pub normalization: SpectrumNormalization,
}

/// A heat kernel signature: one column per time.
#[derive(Clone, Debug)]
pub struct HeatKernelSignature {
    /// The times t_j used (in the units of the normalized spectrum), increasing for `Auto`.
    pub times: Vec<f64>,
    /// n × T values, `values[(i, j)] = h(i, t_j)`.
    pub values: Mat<f64>,
}

/// Computes the heat kernel signature h(i, t) at all vertices and times (paper, Eqs. (6), (8)).
///
/// `h(i,t) = c · Σ_k e^{−λ̃_k t} φ_k(i) ψ_k(i)` with `ψ = φ` ([`KernelDiagonal::KernelValue`]) or
/// `ψ = Bφ` ([`KernelDiagonal::OperatorDiagonal`]), λ̃ and c from [`SpectrumNormalization`], divided
/// by the heat trace `Σ_k e^{−λ̃_k t}` if `params.scaled`. Cost O(n·k·T), one parallel matrix
/// product. Truncation error relative to the full spectrum is about e^{−t λ_k} (docs/NUMERICS.md §4):
/// ≈1e−4 at the automatic smallest time.
///
/// ```
/// use faer::Mat;
/// use shape_retrieval::hks::{heat_kernel_signature, HksParams, Spectrum, TimeSampling};
///
/// // Two vertices, B = I: φ₀ = (1, 1)/√2 with λ₀ = 0 and φ₁ = (1, −1)/√2 with λ₁ = 2,
/// // so h(i, t) = (1 + e^{−2t})/2 at both vertices.
/// let r = 0.5f64.sqrt();
/// let phi = Mat::from_fn(2, 2, |i, k| if k == 1 && i == 1 { -r } else { r });
/// let spectrum = Spectrum::new(&[0.0, 2.0], phi.as_ref())?;
/// let params = HksParams { times: TimeSampling::Explicit(vec![0.5]), ..Default::default() };
/// let hks = heat_kernel_signature(&spectrum, &params)?;
/// assert!((hks.values[(0, 0)] - (1.0 + (-1.0f64).exp()) / 2.0).abs() < 1e-15);
/// # Ok::<(), shape_retrieval::RetrievalError>(())
/// ```
///
/// # Errors
/// [`RetrievalError::MassRequired`] for the operator-diagonal convention without mass,
/// [`RetrievalError::InvalidParameter`] for non-positive times, `num_times = 0` or a bad area,
/// [`RetrievalError::NoNonzeroEigenvalue`] for automatic times on a zero spectrum.
pub fn heat_kernel_signature(
    spectrum: &Spectrum<'_>,
    params: &HksParams,
) -> Result<HeatKernelSignature, RetrievalError> {
    params.times.check_size(spectrum.eigenvectors.nrows())?;
    let (eigenvalues, factor) = normalized_spectrum(spectrum, params.normalization, params.convention)?;
    let times = match &params.times {
        TimeSampling::Auto { num_times } => auto_times(&eigenvalues, *num_times)?,
        TimeSampling::Explicit(times) => {
            check::non_empty("times", times.len())?;
            for &t in times {
                check::positive("time", t)?;
            }
            times.clone()
        }
    };
    let mut values = signature_at(spectrum, &eigenvalues, factor, params.convention, &times)?;
    if params.scaled {
        let trace = heat_trace(&eigenvalues, &times);
        for (j, z) in trace.iter().enumerate() {
            // Z(t) ≥ e^{−λ_min t} > 0 unless every mode underflows; then the column is 0/0.
            if *z <= 0.0 {
                return Err(RetrievalError::InvalidParameter {
                    name: "time",
                    value: times[j],
                    reason: "heat trace underflows to 0 at this time, so the scaled HKS is undefined",
                });
            }
            let inv = 1.0 / z;
            values.col_mut(j).iter_mut().for_each(|v| *v *= inv);
        }
    }
    Ok(HeatKernelSignature { times, values })
}

/// The heat trace `Z(t) = tr K_t = Σ_k e^{−λ_k t}` of the given (truncated) spectrum, per time.
pub fn heat_trace(eigenvalues: &[f64], times: &[f64]) -> Vec<f64> {
    times
        .iter()
        .map(|&t| eigenvalues.iter().map(|&l| (-l * t).exp()).sum())
        .collect()
}

/// `num_times` times log-spaced from `4 ln10/λ_max` to `4 ln10/λ_2` (both included), λ_2 being
/// the smallest eigenvalue above 1e−8·λ_max (Sun et al. 2009; pyFM `np.geomspace`).
///
/// # Errors
/// [`RetrievalError::InvalidParameter`] for `num_times = 0`, [`RetrievalError::NoNonzeroEigenvalue`].
pub fn auto_times(eigenvalues: &[f64], num_times: usize) -> Result<Vec<f64>, RetrievalError> {
    check::at_least_one("num_times", num_times)?;
    let lambda_max = eigenvalues.iter().fold(0.0f64, |m, &v| m.max(v));
    let lambda_2 = eigenvalues
        .iter()
        .copied()
        .filter(|&v| v > ZERO_EIGENVALUE_RTOL * lambda_max)
        .fold(f64::INFINITY, f64::min);
    if !lambda_max.is_finite() || lambda_max <= 0.0 || !lambda_2.is_finite() {
        return Err(RetrievalError::NoNonzeroEigenvalue);
    }
    let c = 4.0 * std::f64::consts::LN_10;
    Ok(log_spaced(c / lambda_max, c / lambda_2, num_times))
}

/// `num` values log-spaced in [a, b], endpoints exact.
pub(crate) fn log_spaced(a: f64, b: f64, num: usize) -> Vec<f64> {
    if num == 1 {
        return vec![a];
    }
    let (la, lb) = (a.ln(), b.ln());
    (0..num)
        .map(|j| match j {
            0 => a,
            j if j + 1 == num => b,
            j => (la + (lb - la) * j as f64 / (num - 1) as f64).exp(),
        })
        .collect()
}

/// Normalized eigenvalues and the amplitude factor c of [`SpectrumNormalization`].
pub(crate) fn normalized_spectrum(
    spectrum: &Spectrum<'_>,
    normalization: SpectrumNormalization,
    convention: KernelDiagonal,
) -> Result<(Vec<f64>, f64), RetrievalError> {
    // s² = the squared rescaling factor: λ → λ/s², φ² → φ²/s².
    let s2 = match normalization {
        SpectrumNormalization::None => return Ok((spectrum.eigenvalues.to_vec(), 1.0)),
        SpectrumNormalization::MaxEigenvalue => {
            let lambda_max = spectrum.max_eigenvalue();
            if lambda_max <= 0.0 {
                return Err(RetrievalError::NoNonzeroEigenvalue);
            }
            lambda_max
        }
        SpectrumNormalization::UnitArea { area } => {
            check::positive("area", area)?;
            1.0 / area
        }
    };
    let eigenvalues = spectrum.eigenvalues.iter().map(|l| l / s2).collect();
    let factor = match convention {
        KernelDiagonal::KernelValue => 1.0 / s2,
        KernelDiagonal::OperatorDiagonal => 1.0,
    };
    Ok((eigenvalues, factor))
}

/// `c · Σ_k e^{−λ_k t_j} φ_k(i) ψ_k(i)` as an n × T matrix: P = c(Φ ∘ Ψ) (n × k) times
/// W = [e^{−λ_k t_j}] (k × T), one parallel GEMM.
pub(crate) fn signature_at(
    spectrum: &Spectrum<'_>,
    eigenvalues: &[f64],
    factor: f64,
    convention: KernelDiagonal,
    times: &[f64],
) -> Result<Mat<f64>, RetrievalError> {
    signature_rows(
        spectrum,
        eigenvalues,
        factor,
        convention,
        times,
        0..spectrum.n_vertices(),
    )
}

/// [`signature_at`] restricted to the vertices `rows` (a block of rows of the result).
pub(crate) fn signature_rows(
    spectrum: &Spectrum<'_>,
    eigenvalues: &[f64],
    factor: f64,
    convention: KernelDiagonal,
    times: &[f64],
    rows: std::ops::Range<usize>,
) -> Result<Mat<f64>, RetrievalError> {
    let phi = spectrum.eigenvectors.subrows(rows.start, rows.len());
    let psi = match convention {
        KernelDiagonal::KernelValue => phi,
        KernelDiagonal::OperatorDiagonal => spectrum
            .mass_eigenvectors
            .as_ref()
            .ok_or(RetrievalError::MassRequired)?
            .as_ref()
            .subrows(rows.start, rows.len()),
    };
    let (n, k) = (phi.nrows(), phi.ncols());
    let products = Mat::from_fn(n, k, |i, c| factor * phi[(i, c)] * psi[(i, c)]);
    let weights = Mat::from_fn(k, times.len(), |c, j| (-eigenvalues[c] * times[j]).exp());
    let mut values = Mat::<f64>::zeros(n, times.len());
    matmul(
        values.as_mut(),
        Accum::Replace,
        products.as_ref(),
        weights.as_ref(),
        1.0,
        Par::rayon(0),
    );
    Ok(values)
}
