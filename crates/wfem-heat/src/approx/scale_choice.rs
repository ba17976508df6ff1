//! A data-driven choice of the smoothing scale of a noisy map, with no clean map: generalized
//! cross-validation of the heat smoother `f ↦ K_t f` (Craven & Wahba, Numer. Math. 31 (1979)
//! 377–403), in the vertex-area weights (issue #40).
//!
//! For f = clean + ε with independent noise of variance σ² per vertex, the smoother
//! `S_t = K_t` (paper Eq. (6), (21)) is scored by
//!
//! `V(t) = R(t) / (1 − τ(t))²,  R(t) = ‖f − K_t f‖²_W / tr W,  τ(t) = tr(W K_t) / tr W`,
//!
//! W the lumped vertex areas, and the scale t* is the minimiser over the given times. The
//! trace comes from Hutchinson's estimator with Rademacher probes z, `E[zᵀ W K_t z] =
//! tr(W K_t)`, all times from one multi-time evaluation per probe block
//! ([`HeatKernel::apply_times`]). The denominator needs τ only to a small absolute error
//! against 1, so a few probes suffice (standard deviation about `√(2/(p·n))` for p probes on
//! n vertices of similar area).
//!
//! **Noise level.** The same probes give `E(t) = E‖z − K_t z‖²_W / tr W`, the share of a unit
//! white noise's energy that K_t removes, exactly (no assumption on W against the mass).
//! Since `E R(t) = ‖(I − K_t) clean‖²_W / tr W + σ² E(t)` and the bias term of a map smooth at
//! the mesh's resolution is smallest at the finest time t₁, the estimate is
//! `σ̂² = R(t₁) / E(t₁)` — a difference-based estimate (Rice, Ann. Stat. 12 (1984) 1215–1230:
//! the finest smoother's residual over its share of the noise). [`ScaleChoice::gcv_noise`] is
//! the GCV estimate `√(R(t*)/(1 − τ(t*)))` at the chosen t, biased by the smoothing there.
//!
//! **Is there noise to remove?** On a map without noise V(t) still has a minimum (the bias grows
//! with t, the denominator too), so a scale is always chosen. Mallows' unbiased risk estimate
//! decides whether smoothing at t* beats keeping f: `E‖K_t f − clean‖²_W / tr W =
//! E R(t) − σ² + 2σ² τ(t)`, and keeping f costs σ². Smoothing at t* is better iff
//! `R(t*) < 2σ̂² (1 − τ(t*))`, i.e. `gcv_noise² < 2 σ̂²` ([`ScaleChoice::smoothing_helps`]);
//! a minimum at the finest time itself (the residual grows faster than the noise's share from
//! the first step on) is no evidence of noise. Neither the factor 2 nor the rule is fitted to
//! a benchmark: they are the two risks compared.
//!
//! Measured on the 18 maps of `cargo xtask approx-eval` at σ = 5 % of the range (a 40-time
//! grid from 1/λ_max to 1/λ₂₀, 8 probes): `K_t f` at the chosen t is within 1.04 × the L2
//! error of the best t chosen knowing the clean map on all 18, and within 1.25 × its L∞ error
//! on 14 (the other four are 1.30–1.65 ×, three of them diffusion-distance maps: the kink at
//! the tip of the distance cone wants a smaller t than the L2 optimum). The anchored default
//! ([`super::NoiseRule`]) adds the persistent features back (docs/APPROX-RESULTS.md).

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
    /// `R(t) = ‖f − K_t f‖²_W / tr W` of every time.
    pub residual: Vec<f64>,
    /// `E(t) = E‖z − K_t z‖²_W / tr W` of every time: the share of a unit white noise's energy
    /// that K_t removes (estimated with the same probes).
    pub noise_share: Vec<f64>,
    /// Index of the finest (smallest) time t₁ given.
    pub finest: usize,
    /// The estimated standard deviation σ̂ of the noise per vertex, in units of f:
    /// `√(R(t₁)/E(t₁))` at the finest time t₁ (see the module documentation).
    pub noise: f64,
    /// GCV's own estimate at the chosen time, `√(R(t*)/(1 − τ(t*)))`: biased up by the
    /// smoothing's bias at t* and down by the noise's share left in `K_t* f`.
    pub gcv_noise: f64,
    /// `K_t f` at the chosen time.
    pub smoothed: Vec<f64>,
}

impl ScaleChoice {
    /// Whether smoothing at the chosen t has a lower estimated risk than keeping f (Mallows'
    /// unbiased risk estimate with σ̂; see the module documentation): the chosen time is not
    /// the finest one and `gcv_noise² < 2 σ̂²`. False for a map without noise.
    pub fn smoothing_helps(&self) -> bool {
        self.index != self.finest && self.gcv_noise * self.gcv_noise < 2.0 * self.noise * self.noise
    }
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
    // Homogeneous in f: work on f/2ᵉ with 2ᵉ ≈ max|f| (exact), so that the squared residuals of
    // a field of 1e200 do not overflow, and scale back.
    let (down, up) = shifted_solve::lanczos::pow2_scale(super::global::linf(f));
    let mut rng = SplitMix64::new(TRACE_SEED);
    let block = Mat::<f64>::from_fn(n, probes + 1, |i, j| match j {
        0 => f[i] * down,
        _ if rng.next_u64() & 1 == 0 => 1.0,
        _ => -1.0,
    });
    let series = kernel.apply_times(block.as_ref(), times)?;
    let mut scores = Vec::with_capacity(times.len());
    let mut fractions = Vec::with_capacity(times.len());
    let mut residuals = Vec::with_capacity(times.len());
    let mut shares = Vec::with_capacity(times.len());
    for v in &series.values {
        let mut residual = 0.0;
        let mut trace = 0.0;
        let mut removed = 0.0;
        for i in 0..n {
            let r = block[(i, 0)] - v[(i, 0)];
            residual += w[i] * r * r;
            for j in 1..=probes {
                let z = block[(i, j)];
                trace += w[i] * z * v[(i, j)];
                removed += w[i] * (z - v[(i, j)]) * (z - v[(i, j)]);
            }
        }
        let fraction = (trace / probes as f64 / area).clamp(0.0, 1.0);
        let dof = (1.0 - fraction).max(f64::EPSILON);
        residuals.push(residual / area);
        shares.push(removed / probes as f64 / area);
        scores.push(residual / area / (dof * dof));
        fractions.push(fraction);
    }
    let index = (0..times.len())
        .min_by(|&a, &b| scores[a].total_cmp(&scores[b]))
        .unwrap_or(0);
    let dof = (1.0 - fractions[index]).max(f64::EPSILON);
    let finest = (0..times.len())
        .min_by(|&a, &b| times[a].total_cmp(&times[b]))
        .unwrap_or(0);
    Ok(ScaleChoice {
        index,
        t: times[index],
        finest,
        noise: up * (residuals[finest] / shares[finest].max(f64::MIN_POSITIVE)).sqrt(),
        gcv_noise: up * (residuals[index] / dof).sqrt(),
        smoothed: series.values[index].col(0).iter().map(|x| x * up).collect(),
        scores: scores.iter().map(|x| x * up * up).collect(),
        trace_fraction: fractions,
        residual: residuals.iter().map(|x| x * up * up).collect(),
        noise_share: shares,
    })
}
