//! A data-driven choice of the smoothing scale of a noisy map, with no clean map: generalized
//! cross-validation of the heat smoother `f ↦ K_t f` (Craven & Wahba, Numer. Math. 31 (1979)
//! 377–403), in the vertex-area weights (issue #40).
//!
//! For f = clean + ε with independent noise per vertex, the smoother `S_t = K_t` (paper
//! Eq. (6)) is scored by
//!
//! `V(t) = (‖f − K_t f‖²_W / tr W) / (1 − tr(W K_t) / tr W)²`,
//!
//! W the lumped vertex areas, and the scale is the minimiser over the given times. The trace
//! `tr(W K_t)` comes from Hutchinson's estimator with Rademacher probes z,
//! `E[zᵀ W K_t z] = tr(W K_t)`, all times from one multi-time evaluation per probe block
//! ([`HeatKernel::apply_times`]). The denominator needs `tr(W K_t)/tr W` only to a small
//! absolute error against 1, so a few probes suffice (standard deviation about
//! `√(2/(p·n))` for p probes on n vertices of similar area). The noise level follows as
//! `σ̂² = (‖f − K_t f‖²_W / tr W) / (1 − tr(W K_t)/tr W)` at the chosen t.
//!
//! Measured on the 18 maps of `cargo xtask approx-eval` at σ = 5 % of the range (a 40-time
//! grid from 1/λ_max to 1/λ₂₀, 8 probes; a prototype run of 2026-12-02): `K_t f` at the
//! chosen t is within 1.04 × the L2 error of the best t chosen knowing the clean map on all
//! 18, and within 1.25 × its L∞ error on 14 (the other four are 1.30–1.65 ×, three of them
//! diffusion-distance maps: the kink at the tip of the distance cone wants a smaller t than
//! the L2 optimum). The default decomposition does not use it yet (issue #40).

use crate::{check, HeatError, HeatKernel};
use faer::Mat;
use wfem_base::rng::SplitMix64;

/// Rademacher probes of the trace estimate by default.
pub const DEFAULT_TRACE_PROBES: usize = 8;

/// Seed of the probes (the choice is deterministic).
pub const TRACE_SEED: u64 = 40;

/// The scale chosen by [`choose_scale`] and what it is based on.
#[derive(Clone, Debug, PartialEq)]
pub struct ScaleChoice {
    /// Index of the chosen time in the list given.
    pub index: usize,
    /// The chosen time.
    pub t: f64,
    /// The GCV score `V(t)` of every time, in the order given.
    pub scores: Vec<f64>,
    /// The estimated trace fraction `tr(W K_t) / tr W` (the smoother's degrees of freedom over
    /// the area) of every time.
    pub trace_fraction: Vec<f64>,
    /// The estimated standard deviation of the noise per vertex, in units of f.
    pub noise: f64,
}

/// The time of `times` that minimises the area-weighted GCV score of `f ↦ K_t f` (see the
/// module documentation), with `probes` Rademacher probes for the trace.
///
/// # Errors
/// [`HeatError::LengthMismatch`]/[`HeatError::NonFiniteInput`] for a bad f;
/// [`HeatError::InvalidTime`]/[`HeatError::InvalidParameter`] for a bad or empty list of times
/// or no probe; the kernel's errors.
pub fn choose_scale(kernel: &HeatKernel, f: &[f64], times: &[f64], probes: usize) -> Result<ScaleChoice, HeatError> {
    let n = kernel.n();
    check::vector(f, n)?;
    check::times(times)?;
    crate::limits::count("probes", probes, 1, 1024)?;
    let w = kernel.operators().vertex_areas();
    let area: f64 = w.iter().sum();
    let mut rng = SplitMix64::new(TRACE_SEED);
    let block = Mat::<f64>::from_fn(n, probes + 1, |i, j| match j {
        0 => f[i],
        _ if rng.next_u64() & 1 == 0 => 1.0,
        _ => -1.0,
    });
    let series = kernel.apply_times(block.as_ref(), times)?;
    let mut scores = Vec::with_capacity(times.len());
    let mut fractions = Vec::with_capacity(times.len());
    let mut residuals = Vec::with_capacity(times.len());
    for v in &series.values {
        let mut residual = 0.0;
        let mut trace = 0.0;
        for i in 0..n {
            let r = f[i] - v[(i, 0)];
            residual += w[i] * r * r;
            for j in 1..=probes {
                trace += w[i] * block[(i, j)] * v[(i, j)];
            }
        }
        let fraction = (trace / probes as f64 / area).clamp(0.0, 1.0);
        let dof = (1.0 - fraction).max(f64::EPSILON);
        residuals.push((residual / area, dof));
        scores.push(residual / area / (dof * dof));
        fractions.push(fraction);
    }
    let index = (0..times.len())
        .min_by(|&a, &b| scores[a].total_cmp(&scores[b]))
        .unwrap_or(0);
    let (residual, dof) = residuals[index];
    Ok(ScaleChoice {
        index,
        t: times[index],
        scores,
        trace_fraction: fractions,
        noise: (residual / dof).sqrt(),
    })
}
