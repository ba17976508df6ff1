//! The wave kernel signature (Aubry, Schlickewei & Cremers 2011; beyond the paper), on the
//! same eigenpairs as the HKS: for log-energies e_j,
//!
//! `WKS(x, e) = Σ_k C_k(e) φ_k(x)² / Σ_k C_k(e)`,  `C_k(e) = exp(−(e − log λ_k)² / 2σ²)`,
//!
//! over the nonzero eigenvalues λ_k (those above 1e−8·λ_max) with M-orthonormal eigenvectors
//! φ_k (`ΦᵀMΦ = I`, Eq. (4)). The energies are pyFM's and geomfum's (`auto_WKS`,
//! `WksDefaultDomain`): from `e_min = log λ_first` (the first nonzero eigenvalue) to
//! `e_max = log λ_max`, `σ = 7 (e_max − e_min) / N`, both ends moved in by 2σ, N values evenly
//! spaced — so a user's pyFM descriptors carry over (`tests` check them against pyFM to 1e−10).
//! As in pyFM, for N < 28 the trimmed range is reversed (e_min + 2σ > e_max − 2σ): the grid then
//! runs from the high energies down and reaches past both ends; N ≥ 28 is what pyFM and the
//! default use.
//!
//! Unlike the HKS (low-pass in the frequency λ), each energy is a band pass around λ = e^{e}:
//! small energies see the global shape, large ones the fine detail, with a scale-independent
//! resolution in log λ.

use crate::hks::Spectrum;
use crate::{check, RetrievalError};
use faer::Mat;

/// Default number N of energies (pyFM's `num_E` in its examples and `FunctionalMapping`).
pub const DEFAULT_ENERGIES: usize = 100;

/// Eigenvalues at or below this fraction of λ_max count as zero (pyFM 1.3's threshold).
const ZERO_EIGENVALUE_RTOL: f64 = 1e-8;

/// The energies of [`wave_kernel_signature`].
#[derive(Clone, Debug, PartialEq)]
pub struct WksEnergies {
    /// The log-energies e_j (N of them).
    pub energies: Vec<f64>,
    /// The width σ of every band.
    pub sigma: f64,
}

/// The WKS (n × N) and its energies.
#[derive(Clone, Debug, PartialEq)]
pub struct WaveKernelSignature {
    /// The energies.
    pub energies: WksEnergies,
    /// `values[(x, j)] = WKS(x, e_j)`.
    pub values: Mat<f64>,
}

/// The N energies on a spectrum (see the module docs).
///
/// # Errors
/// [`RetrievalError::Empty`] for N = 0; [`RetrievalError::NoNonzeroEigenvalue`] when fewer than
/// two distinct nonzero eigenvalues span a range of energies.
pub fn wks_energies(eigenvalues: &[f64], num_energies: usize) -> Result<WksEnergies, RetrievalError> {
    check::non_empty("energies", num_energies)?;
    let max = eigenvalues.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let nonzero: Vec<f64> = eigenvalues
        .iter()
        .map(|v| v.abs())
        .filter(|&v| v > ZERO_EIGENVALUE_RTOL * max)
        .collect();
    let first = nonzero.iter().copied().fold(f64::INFINITY, f64::min);
    if nonzero.len() < 2 || !(max > first) {
        return Err(RetrievalError::NoNonzeroEigenvalue);
    }
    let (e_min, e_max) = (first.ln(), max.ln());
    let sigma = 7.0 * (e_max - e_min) / num_energies as f64;
    let (lo, hi) = (e_min + 2.0 * sigma, e_max - 2.0 * sigma);
    let energies = if num_energies == 1 {
        vec![lo]
    } else {
        (0..num_energies)
            .map(|j| lo + (hi - lo) * j as f64 / (num_energies - 1) as f64)
            .collect()
    };
    Ok(WksEnergies { energies, sigma })
}

/// The wave kernel signature on a spectrum with N energies (see the module docs).
///
/// # Errors
/// As [`wks_energies`]; [`RetrievalError::Heat`] for more energies than
/// `wfem_heat::limits::MAX_TIMES` or an n × N output beyond `wfem_heat::limits::OUTPUT_MEMORY`.
pub fn wave_kernel_signature(
    spectrum: &Spectrum<'_>,
    num_energies: usize,
) -> Result<WaveKernelSignature, RetrievalError> {
    wfem_heat::limits::times("energies", num_energies)?;
    wfem_heat::limits::columns("energies", num_energies, spectrum.eigenvectors().nrows())?;
    let values = spectrum.eigenvalues();
    let phi = spectrum.eigenvectors();
    let energies = wks_energies(values, num_energies)?;
    let max = values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let kept: Vec<usize> = (0..values.len())
        .filter(|&k| values[k].abs() > ZERO_EIGENVALUE_RTOL * max)
        .collect();
    let logs: Vec<f64> = kept.iter().map(|&k| values[k].abs().ln()).collect();
    let two_sigma2 = 2.0 * energies.sigma * energies.sigma;
    // Coefficients C (N × K), each energy's row scaled to unit sum.
    let mut coefficients = Mat::<f64>::zeros(energies.energies.len(), kept.len());
    for (j, &e) in energies.energies.iter().enumerate() {
        let row: Vec<f64> = logs.iter().map(|&l| (-(e - l) * (e - l) / two_sigma2).exp()).collect();
        let sum: f64 = row.iter().sum();
        for (k, c) in row.into_iter().enumerate() {
            coefficients[(j, k)] = if sum > 0.0 { c / sum } else { 0.0 };
        }
    }
    // WKS = (Φ_kept ∘ Φ_kept) Cᵀ.
    let n = phi.nrows();
    let squares = Mat::<f64>::from_fn(n, kept.len(), |i, k| {
        let x = phi[(i, kept[k])];
        x * x
    });
    let values = &squares * coefficients.transpose();
    Ok(WaveKernelSignature { energies, values })
}
