//! Scale-invariant heat kernel signature (SI-HKS; Bronstein & Kokkinos, CVPR 2010).
//!
//! Scaling a surface by β maps `h(x, t) → β⁻² h(x, β⁻² t)` (kernel-value convention; see
//! [`crate::hks`] and the paper's Sect. 5: `K_t(βM) = K_{β⁻²t}(M)`, from the scale covariance of
//! the wFEM kernel Eq. (6)). With logarithmic times `t = t₀ α^τ` this becomes a shift in τ plus an
//! additive constant in `log h`:
//!
//! 1. sample `h̃(x, τ) = log h(x, t₀ α^τ)` for τ = τ_min, τ_min + Δτ, …, τ_max (m samples);
//! 2. take the forward difference `d_j = (h̃(τ_{j+1}) − h̃(τ_j))/Δτ` (j = 0 … m−2), which removes
//!    the constant `−2 log β`;
//! 3. take the modulus of the discrete Fourier transform along τ,
//!    `|D(ω)| = |Σ_j d_j e^{−2πi jω/(m−1)}|`, which removes the shift `2 log_α β`;
//! 4. keep the first K frequencies ω = 0 … K−1 (ω = 0 included).
//!
//! **Time unit.** With an absolute unit t₀ ([`TimeUnit::Absolute`], Bronstein & Kokkinos' choice)
//! step 3 is exact for circular shifts only: invariance holds up to the part of the derivative
//! that the shift moves out of the τ window (measured: a shape ×0.1 changes the descriptor by
//! 49 % with t₀ = 1). With the unit tied to the surface area, `t₀ = c·A` ([`TimeUnit::Area`],
//! A = 1ᵀB1, the default), the samples of a shape scaled by β are `t = c β²A α^τ`, so
//! `λ t` is unchanged and `log h` moves by the constant −2 log β only: steps 1–2 make the
//! descriptor **exactly** scale invariant, with no shift at all, for any window (test
//! `sihks_area_unit_is_exactly_scale_invariant`). Step 3 is then kept for its compact,
//! smooth low-frequency summary of the decay curve.
//!
//! **Default window** (area unit): α = 2, τ ∈ [−10, 2] in steps of 1/8 (97 samples), t₀ = A, K = 8.
//! For a surface of area A, Weyl's law λ_k ≈ 4πk/A puts `t·λ_k = 4πk·2^τ`: the window starts
//! where the 100th mode has `tλ ≈ 1.2` (the truncated spectrum of k = 100 eigenpairs is
//! resolved from there on, docs/NUMERICS.md §4) and ends at `t = 4A`, where only the constant mode is
//! left on TOSCA-like shapes (λ₁A ≳ 5). Chosen by the measurements of docs/SHREC-RESULTS.md.

use crate::check;
use crate::hks::{signature_rows, Spectrum};
use crate::RetrievalError;
use faer::Mat;
use rayon::prelude::*;
use wfem_heat::KernelDiagonal;

/// Vertices per block of the HKS table (4096 × 385 doubles ≈ 12 MB).
const VERTEX_BLOCK: usize = 4096;

/// Options of [`scale_invariant_hks`].
#[derive(Clone, Debug, PartialEq)]
pub struct SihksParams {
    /// Logarithm base α of the time sampling `t = t₀ α^τ` (default 2).
    pub alpha: f64,
    /// First τ (default −10).
    pub tau_min: f64,
    /// Last τ (default 2; included when `(tau_max − tau_min)/tau_step` is an integer).
    pub tau_max: f64,
    /// Step Δτ (default 1/8).
    pub tau_step: f64,
    /// Time unit t₀ (default `TimeUnit::Area(1.0)`: t₀ = A).
    pub time_unit: TimeUnit,
    /// Number K of Fourier magnitudes kept, frequencies 0 … K−1 (default 8).
    pub num_frequencies: usize,
    /// Which HKS diagonal is sampled (default [`KernelDiagonal::KernelValue`]).
    pub convention: KernelDiagonal,
}

impl Default for SihksParams {
    fn default() -> Self {
        Self {
            alpha: 2.0,
            tau_min: -10.0,
            tau_max: 2.0,
            tau_step: 1.0 / 8.0,
            time_unit: TimeUnit::Area(1.0),
            num_frequencies: 8,
            convention: KernelDiagonal::KernelValue,
        }
    }
}

/// Bronstein & Kokkinos' own sampling (CVPR 2010): times t = α^τ in the mesh's squared length
/// unit, α = 2, τ ∈ [1, 25] in steps of 1/16, K = 6 Fourier magnitudes. Scale invariant only
/// through the Fourier magnitudes (a rescaled shape shifts τ), so it suits shapes of similar
/// size; the default of Python's `Eigenbasis.sihks` and `wfem.sihks`.
pub const BRONSTEIN_KOKKINOS: SihksParams = SihksParams {
    alpha: 2.0,
    tau_min: 1.0,
    tau_max: 25.0,
    tau_step: 1.0 / 16.0,
    time_unit: TimeUnit::Absolute(1.0),
    num_frequencies: 6,
    convention: KernelDiagonal::KernelValue,
};

/// A unit of diffusion time, `t = c·unit`: the mesh's own squared length units, its surface
/// area A = 1ᵀB1 (exactly scale invariant: the paper's Sect. 5 scale covariance
/// `K_t(βM) = K_{β⁻²t}(M)` with A ↦ β²A), or its mean edge length squared ℓ̄² (potpourri3d's
/// convention). For the SI-HKS it is the unit t₀ of the times `t = t₀ α^τ`; for the command
/// line's and Python's times (`--time-unit`, `time_unit=`) a time τ given in the unit is
/// `t = τ·unit`, i.e. [`TimeUnit::with_factor`]`(τ)` resolved on the mesh.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum TimeUnit {
    /// t₀ in the squared length units of the mesh (Bronstein & Kokkinos; scale invariant only
    /// up to the window's ends).
    Absolute(f64),
    /// t₀ = c·A with A = 1ᵀB1 the surface area: exactly scale invariant (see the module docs).
    Area(f64),
    /// t₀ = c·ℓ̄² with ℓ̄ the mean length of the distinct edges (potpourri3d's time
    /// coefficient; depends on the sampling as well as on the scale).
    Edge(f64),
}

impl Default for TimeUnit {
    /// Times in the mesh's units, as given.
    fn default() -> Self {
        TimeUnit::Absolute(1.0)
    }
}

wfem_base::registry! {
    TimeUnit as "time unit" {
        TimeUnit::Absolute(_) = TimeUnit::Absolute(1.0) => "absolute":
            "times in the mesh's squared length units, as given (default)",
        TimeUnit::Area(_) = TimeUnit::Area(1.0) => "area":
            "times in units of the surface area A: t = τ·A, the same τ on any scaling of a shape",
        TimeUnit::Edge(_) = TimeUnit::Edge(1.0) => "edge" ["mean-edge-length"]:
            "times in units of the mean edge length squared: t = τ·ℓ̄² (potpourri3d's convention)",
    }
}

/// The lengths of a mesh that a [`TimeUnit`] refers to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeshLengths {
    /// The surface area A (Σ|T| = 1ᵀB1).
    pub area: f64,
    /// The mean length ℓ̄ of the distinct edges (as `wfem info` prints it).
    pub mean_edge_length: f64,
}

impl MeshLengths {
    /// The area and mean edge length of `mesh`.
    pub fn of(mesh: &mesh_fem::TriMesh) -> Self {
        Self {
            area: mesh.area(),
            mean_edge_length: mesh_fem::stats::mean_edge_length(mesh),
        }
    }
}

impl TimeUnit {
    /// The factor c of the unit.
    pub fn factor(self) -> f64 {
        match self {
            TimeUnit::Absolute(c) | TimeUnit::Area(c) | TimeUnit::Edge(c) => c,
        }
    }

    /// The same unit with the factor c.
    pub fn with_factor(self, c: f64) -> Self {
        match self {
            TimeUnit::Absolute(_) => TimeUnit::Absolute(c),
            TimeUnit::Area(_) => TimeUnit::Area(c),
            TimeUnit::Edge(_) => TimeUnit::Edge(c),
        }
    }

    /// t₀ for a surface of the given area.
    ///
    /// # Errors
    /// [`RetrievalError::AreaRequired`] for [`TimeUnit::Area`] without an area,
    /// [`RetrievalError::EdgeLengthRequired`] for [`TimeUnit::Edge`] (a spectrum knows no edge),
    /// [`RetrievalError::InvalidParameter`] for a non-positive factor or area.
    pub fn resolve(self, area: Option<f64>) -> Result<f64, RetrievalError> {
        match self {
            TimeUnit::Absolute(t0) => {
                check::positive("time_unit", t0)?;
                Ok(t0)
            }
            TimeUnit::Area(c) => {
                check::positive("time_unit (area factor)", c)?;
                let area = area.ok_or(RetrievalError::AreaRequired)?;
                check::positive("area", area)?;
                Ok(c * area)
            }
            TimeUnit::Edge(_) => Err(RetrievalError::EdgeLengthRequired),
        }
    }

    /// `c·1`, `c·A` or `c·ℓ̄²` on a mesh of these lengths.
    ///
    /// # Errors
    /// [`RetrievalError::InvalidParameter`] for a non-positive factor, area or edge length.
    pub fn on(self, lengths: &MeshLengths) -> Result<f64, RetrievalError> {
        match self {
            TimeUnit::Edge(c) => {
                check::positive("time_unit (edge factor)", c)?;
                check::positive("mean edge length", lengths.mean_edge_length)?;
                Ok(c * lengths.mean_edge_length * lengths.mean_edge_length)
            }
            unit => unit.resolve(Some(lengths.area)),
        }
    }
}

impl SihksParams {
    /// The sampled times `t₀ α^τ_j`, j = 0 … m−1, for a surface of the given area (needed by
    /// [`TimeUnit::Area`] only).
    ///
    /// # Errors
    /// [`RetrievalError::InvalidParameter`] for α ≤ 1, a non-positive step or t₀, or τ_max < τ_min;
    /// [`RetrievalError::AreaRequired`].
    pub fn times(&self, area: Option<f64>) -> Result<Vec<f64>, RetrievalError> {
        if !(self.alpha.is_finite() && self.alpha > 1.0) {
            return Err(RetrievalError::InvalidParameter {
                name: "alpha",
                value: self.alpha,
                reason: "must be > 1",
            });
        }
        check::positive("tau_step", self.tau_step)?;
        let t0 = self.time_unit.resolve(area)?;
        if !(self.tau_min.is_finite() && self.tau_max.is_finite() && self.tau_max >= self.tau_min) {
            return Err(RetrievalError::InvalidParameter {
                name: "tau_max",
                value: self.tau_max,
                reason: "must be finite and ≥ tau_min",
            });
        }
        // The small slack keeps τ_max when the range is a whole number of steps up to round-off.
        let m = ((self.tau_max - self.tau_min) / self.tau_step + 1e-9).floor() as usize + 1;
        Ok((0..m)
            .map(|j| t0 * self.alpha.powf(self.tau_min + j as f64 * self.tau_step))
            .collect())
    }
}

/// Computes the SI-HKS (n × K) at every vertex (Bronstein & Kokkinos 2010; see the module docs).
///
/// The HKS is evaluated from the given spectrum without normalization: the construction itself
/// removes the scale. Cost O(n·k·m) for the HKS plus O(n·m·K) for the transform.
///
/// # Errors
/// [`RetrievalError::InvalidParameter`] for bad parameters (see [`SihksParams::times`]) or
/// `num_frequencies` not in 1 ..= (m−1)/2 + 1; [`RetrievalError::MassRequired`];
/// [`RetrievalError::NonPositiveSignature`] if some h(x, t) ≤ 0 (e.g. a spectrum without the
/// constant mode underflowing at large t), since its logarithm is undefined;
/// [`RetrievalError::AreaRequired`] for [`TimeUnit::Area`] without [`Spectrum::with_area`].
pub fn scale_invariant_hks(spectrum: &Spectrum<'_>, params: &SihksParams) -> Result<Mat<f64>, RetrievalError> {
    let times = params.times(spectrum.area())?;
    let m = times.len();
    let n_diff = m.saturating_sub(1);
    let max_k = n_diff / 2 + 1;
    if params.num_frequencies == 0 || n_diff < 2 || params.num_frequencies > max_k {
        return Err(RetrievalError::InvalidParameter {
            name: "num_frequencies",
            value: params.num_frequencies as f64,
            reason: "must be in 1 ..= (number of τ samples − 1)/2 + 1, with at least 3 τ samples",
        });
    }
    let n = spectrum.n_vertices();
    let k_freq = params.num_frequencies;
    // Twiddle factors e^{−2πi jω/(m−1)} for ω < K, shared by every vertex.
    let twiddles: Vec<(f64, f64)> = (0..k_freq)
        .flat_map(|w| {
            (0..n_diff).map(move |j| {
                let phase = -2.0 * std::f64::consts::PI * ((j * w) % n_diff) as f64 / n_diff as f64;
                (phase.cos(), phase.sin())
            })
        })
        .collect();
    let mut out = Mat::<f64>::zeros(n, k_freq);
    // Blocks of vertices keep the n × m HKS table (m ≈ 400) small on large meshes.
    for start in (0..n).step_by(VERTEX_BLOCK) {
        let rows = start..(start + VERTEX_BLOCK).min(n);
        let hks = signature_rows(
            spectrum,
            spectrum.eigenvalues(),
            1.0,
            params.convention,
            &times,
            rows.clone(),
        )?;
        let block: Vec<Result<Vec<f64>, RetrievalError>> = (0..rows.len())
            .into_par_iter()
            .map(|r| {
                wfem_base::simd::clear_upper_state();
                let mut log_h = Vec::with_capacity(m);
                for (j, &t) in times.iter().enumerate() {
                    let value = hks[(r, j)];
                    if value.is_nan() || value <= 0.0 {
                        return Err(RetrievalError::NonPositiveSignature {
                            vertex: start + r,
                            time: t,
                            value,
                        });
                    }
                    log_h.push(value.ln());
                }
                let diff: Vec<f64> = log_h.windows(2).map(|w| (w[1] - w[0]) / params.tau_step).collect();
                Ok((0..k_freq)
                    .map(|w| {
                        let tw = &twiddles[w * n_diff..(w + 1) * n_diff];
                        let (re, im) = diff
                            .iter()
                            .zip(tw)
                            .fold((0.0, 0.0), |(re, im), (d, (c, s))| (re + d * c, im + d * s));
                        re.hypot(im)
                    })
                    .collect())
            })
            .collect();
        for (r, row) in block.into_iter().enumerate() {
            for (w, v) in row?.into_iter().enumerate() {
                out[(start + r, w)] = v;
            }
        }
    }
    Ok(out)
}
