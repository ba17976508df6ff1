//! Shape-driven feature points and the feature-driven approximation `f = f_glob + f_loc`
//! (paper, Sect. 4.2, Fig. 12–13).
//!
//! **What the paper prints and why it is not the default.** Sect. 4.2 defines the global
//! component as `f_glob := Σ_{i∈A} f(pᵢ) K_t eᵢ` over the persistent critical points A, with
//! scales `tᵢ = (i/10)/λ_k`, k = 20, and states an L∞ error below 2 %. With a sparse A that
//! sum is `K_t(f·χ_A)`: a few bumps of height ≈ f(pᵢ)·K_t eᵢ(pᵢ) ≪ f(pᵢ), so the error is
//! of the order of ‖f‖∞ — 47–140 % of the range at its best scale on the 18 maps of
//! docs/APPROX-RESULTS.md ([`Coefficients::FeatureValues`], kept selectable). The paper's own Sect. 4.1 identity
//! `K_t f = Σ_{all i} f(pᵢ) K_t eᵢ` and its Fig. 13(c) ("its smooth approximation K_t f")
//! point to what works: the default [`Coefficients::Anchored`] is
//!
//! `f_glob = Σ_{all i} f(pᵢ) K_t eᵢ + Σ_{i∈S} cᵢ K_t eᵢ = K_t f + Σ_{i∈S} cᵢ K_t eᵢ`,
//!
//! the smooth approximation K_t f plus the canonical basis functions of the persistent
//! critical points, with coefficients such that f_glob takes f's values there exactly
//! (`f_glob(pⱼ) = f(pⱼ)`, j ∈ S: the persistent features keep their values; S ⊆ A are the
//! anchors resolved at t, see [`RESOLVED_OVERLAP`]). Even so, the paper's first scale
//! `0.1/λ₂₀` already flattens thin parts (a cat's tail and ears, legs, 2–3 edges wide): 1.6–
//! 10.8 % of the range, above 2 % on 15 of the 18 maps. So the default hierarchy
//! ([`ScaleSampling::Geometric`]) starts at the mesh's own resolution `1/λ_max` (0.01–0.28 %
//! there) and ends at the paper's `1/λ_k`.
//!
//! **A noisy f** (issue #40). The paper decomposes "a noisy scalar function" and expects
//! f_loc to hold the noise; with f's own values at f's own critical points the anchors would
//! keep noise extremes. The default [`NoiseRule::Auto`] estimates the noise level σ̂ and a
//! scale t* from f alone ([`choose_scale`]: area-weighted GCV, Hutchinson traces) and, when
//! smoothing at t* has a lower estimated risk than keeping f and the noise is large enough
//! to matter at the paper's 2 % ([`NoiseRule::denoises`]; never on a map without noise),
//! takes the anchors at the persistent critical points of the
//! denoised map `K_t* f` and their values from the less biased `K_(t*/4) f`
//! ([`ANCHOR_VALUE_TIME_FRACTION`]); t* joins the hierarchy as its chosen scale
//! ([`FeatureApproximation::chosen`]), where f_glob is the denoised map and f_loc the noise.
//!
//! Notes: [`extrema`] and [`eigenfunction_features`] give shape-driven feature points (the
//! paper's alternative anchors); [`ranked_anchors`] orders the persistent critical points.

mod features;
mod global;
mod scale_choice;

pub use features::{eigenfunction_features, extrema, persistent_extremum_count, ranked_anchors, RankedAnchors};
pub use global::{fit_global_component, fit_to_values, global_component, GlobalComponent, RESOLVED_OVERLAP};
pub use scale_choice::{choose_scale, ScaleChoice, DEFAULT_TRACE_PROBES};

use crate::check;
use crate::scale::{largest_eigenvalue, LargestEigenParams};
use crate::spectral::{EigenParams, Eigenbasis};
use crate::{HeatError, HeatKernel};
use global::linf;
use mesh_fem::morse;
use mesh_fem::TriMesh;
use wfem_base::Choice;

/// How the coefficients of the global component are chosen (a registry,
/// [`wfem_base::Choice`]: the command line and the Python package read its names and help).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Coefficients {
    /// The default: the smooth approximation plus the persistent features,
    /// `f_glob = K_t f + Σ_{i∈S} cᵢ K_t eᵢ` with `f_glob(pⱼ) = f(pⱼ)` for every anchor
    /// j ∈ S resolved at t (`K_t[S,S] c = (f − K_t f)_S`; one block application `K_t [f, e_A]`
    /// per t). `K_t f = Σ_{all i} f(pᵢ) K_t eᵢ` is the paper's formula over all vertices
    /// (Sect. 4.1) and its Fig. 13(c); the corrections are its canonical basis at the
    /// persistent critical points (Sect. 4.2), which restore the extrema that diffusion
    /// flattens. An anchor closer to a more persistent one than the kernel's reach at t is
    /// not resolved there ([`RESOLVED_OVERLAP`]): interpolating both would make the
    /// interpolant swing between them. On a noisy f the anchors keep their noisy values
    /// (they are f's values): choose the persistence above the noise.
    #[default]
    Anchored,
    /// The paper's printed formula, `f_glob = Σ_{i∈A} f(pᵢ) K_t eᵢ` (Sect. 4.2): the feature
    /// values themselves. Since `Σᵢ f(pᵢ) K_t eᵢ = K_t(f·χ_A)` it costs one application of
    /// K_t. With A = all vertices it is K_t f (→ f as t → 0); with a sparse A it is small
    /// (each K_t eᵢ has B-mass 1ᵀBeᵢ, see [`crate::basis::canonical_limit`]), so the L∞ error
    /// is of the order of ‖f‖∞ (0.47–1.4 of the range at its best scale on the benchmark,
    /// docs/APPROX-RESULTS.md).
    FeatureValues,
    /// The best approximation of f in the span of the feature-driven basis:
    /// `f_glob = Σ_{i∈A} cᵢ K_t eᵢ` minimising `‖f − f_glob‖_M` (the M-orthogonal projection
    /// onto span{K_t eᵢ : i ∈ A}; nearly dependent directions of the Gram matrix dropped) —
    /// the "projection of f onto the basis functions" of Fig. 13(d). A few bumps of width √t
    /// cannot follow f between the anchors (issue #24: 0.86–0.98 of the range off on the TOSCA
    /// cat's z, 8 anchors, the paper's scales).
    LeastSquares,
    /// Interpolation on the anchors without the smooth part: `f_glob = Σ_{i∈A} cᵢ K_t eᵢ` with
    /// `f_glob(pⱼ) = f(pⱼ)` for j ∈ A, i.e. `K_t[A,A] c = f_A`. Between the anchors it falls
    /// to 0; at larger t the basis functions overlap and the interpolant oscillates (refused
    /// above 1e3 × max|f|).
    Interpolate,
    /// The paper's feature values with the basis normalised to a partition of unity:
    /// `f_glob = Σ_{i∈A} f(pᵢ) K_t eᵢ / Σ_{i∈A} K_t eᵢ` — a heat-kernel weighted average of the
    /// persistent feature values (Nadaraya–Watson regression with the heat kernel), between
    /// the smallest and the largest feature value; with few anchors a crude piecewise field.
    /// The weights are the basis functions with their small negative lobes set to 0.
    Normalized,
    /// No anchors: `f_glob = K_t f = Σ_{all i} f(pᵢ) K_t eᵢ`, the paper's "smooth
    /// approximation K_t f" (Fig. 13(c); Sect. 4.1). For a noisy f whose extrema are noise
    /// (the anchored default keeps their noisy values); it flattens the true extrema by the
    /// diffusion's bias instead.
    Smooth,
}

wfem_base::registry! {
    Coefficients as "coefficients" {
        Coefficients::Anchored = Coefficients::Anchored => "anchored":
            "K_t f plus the basis functions K_t e_i of the persistent critical points, keeping f's values there (default)",
        Coefficients::FeatureValues = Coefficients::FeatureValues => "feature-values" ["paper"]:
            "the paper's printed Σ f(p_i) K_t e_i (≈ 0 between sparse anchors)",
        Coefficients::LeastSquares = Coefficients::LeastSquares => "least-squares":
            "the M-orthogonal projection of f onto span{K_t e_i : i ∈ A}",
        Coefficients::Interpolate = Coefficients::Interpolate => "interpolate":
            "Σ c_i K_t e_i interpolating f on the anchors (0 between them)",
        Coefficients::Normalized = Coefficients::Normalized => "normalized":
            "Σ f(p_i) K_t e_i / Σ K_t e_i, a heat-kernel average of the feature values",
        Coefficients::Smooth = Coefficients::Smooth => "smooth":
            "K_t f without anchors (for a noisy f whose extrema are noise)",
    }
}

impl Coefficients {
    /// The formula of f_glob, as recorded in outputs.
    pub fn formula(&self) -> &'static str {
        match self {
            Coefficients::Anchored => "f_glob = K_t f + sum_j c_j K_t e_(a_j), f_glob(a_j) = f(a_j)",
            Coefficients::FeatureValues => "f_glob = sum_j f(a_j) K_t e_(a_j), c_j = f(a_j)",
            Coefficients::LeastSquares => "f_glob = sum_j c_j K_t e_(a_j), argmin ||f - f_glob||_M",
            Coefficients::Interpolate => "f_glob = sum_j c_j K_t e_(a_j), f_glob(a_j) = f(a_j)",
            Coefficients::Normalized => {
                "f_glob = sum_j f(a_j) w_j / sum_j w_j, w_j = max(K_t e_(a_j), 0), c_j = f(a_j)"
            }
            Coefficients::Smooth => "f_glob = K_t f",
        }
    }
}

/// How the hierarchy of scales t₁ < … < t_N is sampled (a registry like [`Coefficients`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum ScaleSampling {
    /// The default: geometric from the mesh's resolution to the paper's coarsest scale,
    /// `tᵢ = t_min (t_max/t_min)^{(i−1)/(N−1)}` with `t_min = 1/λ_max` (the finest mode of
    /// the mesh decays by 1/e: below it K_t is the identity up to the mesh's own
    /// discretisation) and `t_max = 1/λ_k`. Scale space is sampled geometrically: the
    /// paper's linear samples all lie within a factor 10 of t_max, and its finest one,
    /// `0.1/λ₂₀`, already flattens features two or three edges wide (tails, ears, legs) by
    /// 1.6–10.8 % of the range (docs/APPROX-RESULTS.md).
    #[default]
    Geometric,
    /// The paper's hierarchy, `tᵢ = (i/10) λ_k⁻¹`, i = 1..N (Sect. 4.2, "five to ten scales").
    Paper,
}

wfem_base::registry! {
    ScaleSampling as "scale sampling" {
        ScaleSampling::Geometric = ScaleSampling::Geometric => "geometric":
            "geometric from 1/λ_max (the mesh's resolution) to 1/λ_k (default)",
        ScaleSampling::Paper = ScaleSampling::Paper => "paper" ["linear"]:
            "the paper's t_i = (i/10)/λ_k",
    }
}

impl ScaleSampling {
    /// The N scales for the eigenvalues λ_k and λ_max (λ_max is used by
    /// [`ScaleSampling::Geometric`] only), increasing.
    pub fn times(&self, lambda_k: f64, lambda_max: f64, scales: usize) -> Vec<f64> {
        match self {
            ScaleSampling::Paper => multiscale_times(lambda_k, scales),
            ScaleSampling::Geometric => geometric_times(1.0 / lambda_max, 1.0 / lambda_k, scales),
        }
    }
}

/// What the decomposition does about noise in f (a registry like [`Coefficients`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum NoiseRule {
    /// The default: estimate the noise level σ̂ and the scale t* from f alone ([`choose_scale`]
    /// on [`DEFAULT_GCV_TIMES`] times geometric from 1/λ_max to 1/λ_k) and denoise when
    /// smoothing at t* has a lower estimated risk than keeping f and the noise matters at the
    /// paper's tolerance ([`NoiseRule::denoises`]); otherwise as [`NoiseRule::Keep`]. On a
    /// map without noise the result is that of [`NoiseRule::Keep`].
    #[default]
    Auto,
    /// f is taken as clean: the anchors are f's persistent critical points and keep f's values
    /// (issue #24's rule); no noise estimate.
    Keep,
    /// Always denoise at the GCV scale t* (named `always`: `denoise` is a flag of `wfem
    /// retrieval`): the anchors are the persistent critical points of
    /// `K_t* f`, their values `K_(t*/4) f` ([`ANCHOR_VALUE_TIME_FRACTION`]), and t* joins the
    /// scales.
    Denoise,
}

wfem_base::registry! {
    NoiseRule as "noise rule" {
        NoiseRule::Auto = NoiseRule::Auto => "auto":
            "estimate the noise (GCV); if smoothing lowers the estimated error, anchors and values from the denoised map (default)",
        NoiseRule::Keep = NoiseRule::Keep => "keep":
            "take f as clean: anchors at f's critical points keep f's values",
        NoiseRule::Denoise = NoiseRule::Denoise => "always":
            "always take anchors and values from the denoised map at the GCV scale",
    }
}

impl NoiseRule {
    /// Whether a decomposition under this rule takes its anchors and their values from the
    /// denoised map, given the noise estimate of f (n values, range `max f − min f`):
    /// [`NoiseRule::Denoise`] always, [`NoiseRule::Keep`] never, [`NoiseRule::Auto`] when
    /// smoothing at t* lowers the estimated error ([`ScaleChoice::smoothing_helps`]) **and**
    /// the noise matters at the paper's tolerance: its expected largest value over the n
    /// vertices, `σ̂ √(2 ln n)`, exceeds [`NOISE_TOLERANCE`] of the range. Below that, f is
    /// within the tolerance of its clean map as it is, and the decomposition of a smooth map
    /// is left as it was: the meshes of docs/APPROX-RESULTS.md carry a white component of
    /// 0.03–0.3 % of the range in their clean maps (the scans' roughness, the HKS of
    /// irregular triangles), which smoothing would remove, at 0.2–1.2 % for `σ̂ √(2 ln n)`.
    pub fn denoises(&self, choice: &ScaleChoice, n: usize, range: f64) -> bool {
        match self {
            NoiseRule::Keep => false,
            NoiseRule::Denoise => true,
            NoiseRule::Auto => {
                let largest = choice.noise * (2.0 * (n.max(1) as f64).ln()).sqrt();
                choice.smoothing_helps() && largest > NOISE_TOLERANCE * range
            }
        }
    }
}

/// The paper's L∞ tolerance of the decomposition, relative to the range of f (Sect. 4.2:
/// "the L∞ error between the input and approximated map is below 2 %"): [`NoiseRule::Auto`]
/// leaves noise in f whose expected largest value is below it.
pub const NOISE_TOLERANCE: f64 = 0.02;

/// Number of times, geometric from 1/λ_max to 1/λ_k, among which [`NoiseRule::Auto`] and
/// [`NoiseRule::Denoise`] choose t* (a ratio of about 1.2–1.3 between neighbours on the
/// benchmark's meshes, where GCV's score is flat to a few per cent).
pub const DEFAULT_GCV_TIMES: usize = 40;

/// The anchors' values of a denoised decomposition are `K_(φ t*) f` with this φ: a smaller
/// scale than t* at the features, where the diffusion's bias (∝ t times the curvature of the
/// map, largest at its extrema) dominates and the noise's share (∝ 1/√t) is averaged over a
/// disc half as wide. The value 1/4 was chosen on the 18 maps of docs/APPROX-RESULTS.md at
/// σ = 5 % (within 1.25 × the oracle's L∞ error on all 18; 1/2 and 1/8 miss on one or two). A
/// held-out check (`shrec_bench::approx_eval::denoise::held_out`: six other meshes and the
/// benchmark's meshes, three other noise seeds, σ = 0.5/2/5 %) does not single it out: at
/// 5 % the L2 error stays within 1.1 × the oracle's nearly everywhere for φ = 1/2 and 1/4, but
/// the L∞ bound 1.25 × holds on about 85 % of the held-out maps, φ = 1/2 and 1/4 alike; an HKS
/// peak wants a larger φ (less noise in its value), a distance cone's tip a smaller one, and
/// some misses (TOSCA dog0's z) do not depend on φ at all (a feature below the anchors'
/// persistence). A per-anchor choice of the value's scale would be the next step.
pub const ANCHOR_VALUE_TIME_FRACTION: f64 = 0.25;

/// The paper's multiscale times `tᵢ = (i/10) λ_k⁻¹`, i = 1..=scales (Sect. 4.2).
pub fn multiscale_times(lambda_k: f64, scales: usize) -> Vec<f64> {
    (1..=scales).map(|i| i as f64 / 10.0 / lambda_k).collect()
}

/// `scales` times geometric from `t_min` to `t_max` (both included; one scale: `t_max`).
pub fn geometric_times(t_min: f64, t_max: f64, scales: usize) -> Vec<f64> {
    if scales <= 1 {
        return vec![t_max; scales];
    }
    let ratio = (t_max / t_min).ln();
    (0..scales)
        .map(|i| match i {
            0 => t_min,
            _ if i + 1 == scales => t_max,
            _ => t_min * (ratio * i as f64 / (scales - 1) as f64).exp(),
        })
        .collect()
}

/// Persistence threshold selecting the anchor set A among the critical points of f.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Persistence {
    /// Persistence ≥ fraction · (max f − min f) ([`morse::persistent_extrema_relative`]).
    Relative(f64),
    /// Persistence ≥ the value, in units of f ([`morse::persistent_extrema`]).
    Absolute(f64),
}

impl Persistence {
    /// The threshold in units of f, for a field of range `range`.
    pub fn absolute(&self, range: f64) -> f64 {
        match *self {
            Persistence::Relative(x) => x * range,
            Persistence::Absolute(x) => x,
        }
    }
}

/// Options of [`feature_approximation`].
#[derive(Clone, Debug, PartialEq)]
pub struct ApproxParams {
    /// Index k of the eigenvalue λ_k that sets the coarsest scale 1/λ_k (paper: k = 20).
    pub k: usize,
    /// Number N of scales.
    pub scales: usize,
    /// How the N scales are sampled (default: geometric from 1/λ_max to 1/λ_k).
    pub sampling: ScaleSampling,
    /// Threshold of the anchor set A (default: 10 % of the range, as in Fig. 13).
    pub persistence: Persistence,
    /// Coefficients of the global component (default: anchored).
    pub coefficients: Coefficients,
    /// Eigensolver options for λ_k.
    pub eigen: EigenParams,
    /// Lanczos options for λ_max (geometric sampling and the noise estimate).
    pub largest: LargestEigenParams,
    /// What to do about noise in f (default: [`NoiseRule::Auto`]).
    pub noise: NoiseRule,
    /// Number of candidate times of t* ([`DEFAULT_GCV_TIMES`]).
    pub gcv_times: usize,
    /// Rademacher probes of the GCV trace ([`DEFAULT_TRACE_PROBES`]).
    pub probes: usize,
    /// The anchors' values of a denoised decomposition are `K_(φ t*) f`, φ this fraction
    /// ([`ANCHOR_VALUE_TIME_FRACTION`]).
    pub value_time_fraction: f64,
}

impl Default for ApproxParams {
    fn default() -> Self {
        Self {
            k: 20,
            scales: 10,
            sampling: ScaleSampling::default(),
            persistence: Persistence::Relative(0.1),
            coefficients: Coefficients::default(),
            eigen: EigenParams::default(),
            largest: LargestEigenParams::default(),
            noise: NoiseRule::default(),
            gcv_times: DEFAULT_GCV_TIMES,
            probes: DEFAULT_TRACE_PROBES,
            value_time_fraction: ANCHOR_VALUE_TIME_FRACTION,
        }
    }
}

/// The decomposition `f = f_glob + f_loc` at one scale t.
#[derive(Clone, Debug)]
pub struct ScaleApproximation {
    /// The diffusion time t.
    pub t: f64,
    /// The global component (see [`Coefficients::formula`]).
    pub global: Vec<f64>,
    /// The local component `f_loc = f − f_glob`.
    pub local: Vec<f64>,
    /// The anchors whose basis functions carry a coefficient at this t (with
    /// [`Coefficients::Anchored`], the anchors resolved at t, most persistent first).
    pub anchors: Vec<u32>,
    /// The coefficients of their basis functions `K_t e_a` (see [`GlobalComponent`]).
    pub coefficients: Vec<f64>,
    /// `‖f − f_glob‖∞`.
    pub linf_error: f64,
    /// `‖f − f_glob‖∞ / (max f − min f)` (the paper's "L∞ error below 2 %"); equal to
    /// `linf_error` for a constant f.
    pub relative_linf_error: f64,
    /// `max_{a∈A} |f_glob(a) − v_a| / (max f − min f)` over all anchors of A, v_a the anchor's
    /// value (f(a), or the smoothed estimate of a denoised decomposition); 0 up to rounding at
    /// the resolved ones with [`Coefficients::Anchored`].
    pub anchor_error: f64,
    /// Number of critical points (maxima, minima, saddles) of f_glob
    /// ([`morse::critical_points`]; Fig. 13(d)). Where f_glob is numerically flat (far from
    /// every anchor at small t, values ≈ 1e−300) rounding creates spurious critical points;
    /// see [`ScaleApproximation::significant_critical_points`].
    pub critical_points: usize,
    /// Critical points of f_glob that are not rounding artefacts: the extrema of f_glob with
    /// persistence ≥ [`SIGNIFICANT_PERSISTENCE`] · (max f − min f) and their paired saddles
    /// ([`morse::persistent_extrema`]; the 2g unpaired saddles of a genus-g surface are not
    /// counted).
    pub significant_critical_points: usize,
    /// Extrema of f_glob with persistence at least the anchors' threshold
    /// ([`persistent_extremum_count`]); at most [`FeatureApproximation::persistent_extrema`]
    /// when f_glob has no spurious extrema above the threshold.
    pub persistent_extrema: usize,
}

/// Relative persistence (in units of the range of f) below which a critical point of f_glob
/// is counted as a rounding artefact in [`ScaleApproximation::significant_critical_points`].
pub const SIGNIFICANT_PERSISTENCE: f64 = 1e-6;

/// Relative L∞ error above which [`FeatureApproximation::warning`] warns when no scale
/// comes closer (the paper claims 2 %).
pub const WARN_RELATIVE_ERROR: f64 = 0.03;

/// The result of [`feature_approximation`]: the anchor set and one decomposition per scale.
#[derive(Clone, Debug)]
pub struct FeatureApproximation {
    /// The anchors A: the persistent critical points (extrema and their paired saddles) of f,
    /// or of the denoised map `K_t* f` when [`Self::chosen`] is set, most persistent first
    /// ([`ranked_anchors`]).
    pub anchors: Vec<u32>,
    /// The anchors' values, in the order of `anchors`: f's, or `K_(φ t*) f` when denoised.
    pub anchor_values: Vec<f64>,
    /// The persistence of each anchor's pair, in units of f.
    pub anchor_persistence: Vec<f64>,
    /// The threshold of A in units of f (relative thresholds: of the range of the map the
    /// anchors come from).
    pub threshold: f64,
    /// `max f − min f`.
    pub range: f64,
    /// The eigenvalue λ_k of the coarsest scale.
    pub lambda_k: f64,
    /// The largest eigenvalue λ_max (geometric sampling; `None` for the paper's).
    pub lambda_max: Option<f64>,
    /// The coefficient rule used.
    pub coefficients: Coefficients,
    /// The scale sampling used.
    pub sampling: ScaleSampling,
    /// Number of critical points of f itself.
    pub input_critical_points: usize,
    /// Extrema with persistence at least the threshold ([`persistent_extremum_count`]) of the
    /// map the anchors come from (f, or `K_t* f` when denoised).
    pub persistent_extrema: usize,
    /// One entry per scale, increasing t: the hierarchy of `params.sampling`, with t* added
    /// when denoised.
    pub scales: Vec<ScaleApproximation>,
    /// The noise estimate and the GCV scale ([`choose_scale`]); `None` with [`NoiseRule::Keep`].
    pub noise: Option<ScaleChoice>,
    /// The rule that was asked for.
    pub noise_rule: NoiseRule,
    /// When f_glob is the denoised map: the index in `scales` of the chosen scale t* (f_glob
    /// there is the default's answer, f_loc the noise). `None` when f is taken as clean.
    pub chosen: Option<usize>,
}

/// Which option [`ApproxWarning`] suggests changing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ApproxHint {
    /// Another coefficient rule (the default).
    Coefficients(Coefficients),
    /// Another scale sampling (the default, which starts at the mesh's resolution).
    Sampling(ScaleSampling),
    /// f varies at the scale of the mesh (noise?) and was taken as clean: f_loc holds the
    /// noise, but the anchors keep f's noisy values (spikes in f_glob): the noise rule to use
    /// instead, or a persistence above the noise.
    Noise(NoiseRule),
}

/// A warning about a decomposition: f_glob stays farther from f than
/// [`WARN_RELATIVE_ERROR`] at every scale, or f is noisy at the mesh's resolution and the
/// anchored rule keeps the noisy values of its anchors.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ApproxWarning {
    /// The smallest relative L∞ error over the scales.
    pub best_relative_error: f64,
    /// The fraction of the vertices that are critical points of f.
    pub critical_fraction: f64,
    /// What to change.
    pub hint: ApproxHint,
}

impl ApproxWarning {
    /// The warning as a sentence; `option(parameter, value)` spells an option the way the
    /// caller's interface does (e.g. `--coefficients anchored` or `coefficients="anchored"`;
    /// `None`: the parameter without a value).
    pub fn message(&self, option: &dyn Fn(&str, Option<&str>) -> String) -> String {
        let head = format!(
            "f_glob is {:.1} % of the range of f away from f (relative L∞) even at its best scale",
            100.0 * self.best_relative_error
        );
        match self.hint {
            ApproxHint::Coefficients(c) => format!(
                "{head}; {} gives the smooth part plus the persistent features",
                option("coefficients", Some(c.name()))
            ),
            ApproxHint::Sampling(s) => format!(
                "{head}: the scales start too coarse for f; {} starts at the mesh's resolution",
                option("sampling", Some(s.name()))
            ),
            ApproxHint::Noise(rule) => format!(
                "{:.0} % of the vertices are critical points of f: it varies at the scale of the mesh (noise?). \
                 f was taken as clean: f_loc holds that, but the anchors keep f's noisy values (spikes in f_glob); \
                 {} takes the anchors and their values from the denoised map, or raise {} above the noise",
                100.0 * self.critical_fraction,
                option("noise", Some(rule.name())),
                option("persistence", None),
            ),
        }
    }
}

/// Fraction of the vertices that are critical points of f above which f counts as noisy at
/// the mesh's resolution ([`FeatureApproximation::warning`]). Independent noise makes about
/// half of them critical (a vertex of valence 6 is a maximum or a minimum with probability
/// 2/7, plus the saddles): 40–55 % on the benchmark's noisy maps (σ = 5 % of the range); its
/// smooth maps stay below 6 % (docs/APPROX-RESULTS.md).
pub const NOISY_CRITICAL_FRACTION: f64 = 0.25;

impl FeatureApproximation {
    /// A warning with the option to change: none when f_glob is the denoised map (f_loc is
    /// the noise, far from 0 by design); when no scale comes within [`WARN_RELATIVE_ERROR`] of
    /// f, the coefficient rule unless it is the default (or [`Coefficients::Smooth`], chosen
    /// for a noisy f: no warning); with the default rule, the sampling unless it is the
    /// default, else — also when f is noisy at the mesh's resolution
    /// ([`NOISY_CRITICAL_FRACTION`]) — the noise rule ([`NoiseRule::Auto`] after
    /// [`NoiseRule::Keep`], [`NoiseRule::Denoise`] when the estimate found no noise to
    /// remove).
    pub fn warning(&self) -> Option<ApproxWarning> {
        if self.chosen.is_some() {
            return None;
        }
        let best = self
            .scales
            .iter()
            .map(|s| s.relative_linf_error)
            .fold(f64::INFINITY, f64::min);
        let n = self.scales.first().map_or(0, |s| s.global.len());
        let critical_fraction = if n > 0 {
            self.input_critical_points as f64 / n as f64
        } else {
            0.0
        };
        let far = best > WARN_RELATIVE_ERROR;
        let noisy = critical_fraction >= NOISY_CRITICAL_FRACTION;
        let hint = match self.coefficients {
            Coefficients::Smooth => return None,
            Coefficients::Anchored if far && self.sampling != ScaleSampling::default() => {
                ApproxHint::Sampling(ScaleSampling::default())
            }
            Coefficients::Anchored if far || noisy => ApproxHint::Noise(match self.noise_rule {
                NoiseRule::Keep => NoiseRule::Auto,
                _ => NoiseRule::Denoise,
            }),
            Coefficients::Anchored => return None,
            _ if far => ApproxHint::Coefficients(Coefficients::default()),
            _ => return None,
        };
        Some(ApproxWarning {
            best_relative_error: best,
            critical_fraction,
            hint,
        })
    }
}

/// The feature-driven approximation of f (paper, Sect. 4.2, Fig. 12–13): the anchors A are
/// the critical points of f with persistence above `params.persistence`
/// ([`morse::persistence`], [`ranked_anchors`]), and at every scale t of
/// `params.sampling` (λ_k the k-th smallest eigenvalue of `L x = λ M x` by a partial
/// eigensolve, λ_max by Lanczos) f splits into f_glob ([`fit_global_component`] with
/// `params.coefficients`) and `f_loc = f − f_glob`, with the L∞ error, the error at the
/// anchors and the critical points of f_glob (Fig. 13(d)). On a noisy f
/// (`params.noise`, [`NoiseRule`]) the anchors are those of the denoised map `K_t* f`, their
/// values `K_(φ t*) f` ([`fit_to_values`]), and t* joins the scales as [`FeatureApproximation::chosen`].
///
/// # Errors
/// [`HeatError::LengthMismatch`]/[`HeatError::NonFiniteInput`] for a bad f;
/// [`HeatError::InvalidParameter`] for k = 0, k > n, scales outside
/// 1..=[`crate::limits::MAX_APPROX_SCALES`], a negative/NaN threshold, GCV times or probes
/// outside 1..=[`crate::limits::MAX_APPROX_SCALES`] and 1..=1024, or a value time fraction
/// outside (0, 1]; [`HeatError::Mesh`] when the mesh and the kernel disagree; the eigensolver
/// and kernel errors. Any triangle mesh is accepted — non-manifold ones and the
/// neighbourhood mesh of a point cloud included ([`morse::critical_points`] classifies a
/// non-manifold vertex by its lower and upper link components).
pub fn feature_approximation(
    mesh: &TriMesh,
    kernel: &HeatKernel,
    f: &[f64],
    params: &ApproxParams,
) -> Result<FeatureApproximation, HeatError> {
    check_inputs(mesh, kernel, f, params)?;
    let diagram = morse::persistence(mesh, f)?;
    let range = diagram.value_range;
    let input_critical_points = morse::critical_points(mesh, f)?.len();
    let eig = Eigenbasis::partial_of(kernel.operators(), params.k, &params.eigen)?;
    let lambda_k = eig.values[params.k - 1];
    if lambda_k.is_nan() || lambda_k <= 0.0 {
        return Err(HeatError::InvalidParameter {
            name: "k",
            reason: format!(
                "λ_{} = {lambda_k:e} is not positive (too few vertices or components)",
                params.k
            ),
        });
    }
    let needs_largest = params.sampling == ScaleSampling::Geometric || params.noise != NoiseRule::Keep;
    let largest = match needs_largest {
        true => Some(largest_eigenvalue(kernel.operators(), &params.largest)?.max(lambda_k)),
        false => None,
    };
    let lambda_max = largest.filter(|_| params.sampling == ScaleSampling::Geometric);
    let mut times = params
        .sampling
        .times(lambda_k, lambda_max.unwrap_or(lambda_k), params.scales);
    let noise = match (params.noise, largest) {
        (NoiseRule::Keep, _) | (_, None) => None,
        (_, Some(top)) => Some(choose_scale(
            kernel,
            f,
            &geometric_times(1.0 / top, 1.0 / lambda_k, params.gcv_times),
            params.probes,
        )?),
    };
    let denoised = noise.as_ref().filter(|c| params.noise.denoises(c, f.len(), range));
    let source = match denoised {
        None => AnchorSource::of_map(&diagram, f, params.persistence),
        Some(choice) => {
            let values = kernel.apply(f, params.value_time_fraction * choice.t)?;
            AnchorSource::of_map(
                &morse::persistence(mesh, &choice.smoothed)?,
                &values,
                params.persistence,
            )
        }
    };
    let chosen_t = denoised.map(|c| c.t);
    if let Some(t) = chosen_t {
        times.push(t);
        times.sort_by(f64::total_cmp);
        times.dedup();
    }
    let mut scales = Vec::with_capacity(times.len());
    for t in times {
        scales.push(decompose(mesh, kernel, f, &source, t, params.coefficients, range)?);
    }
    let chosen = chosen_t.and_then(|t| scales.iter().position(|s| s.t == t));
    Ok(FeatureApproximation {
        anchors: source.ranked.vertices,
        anchor_values: source.values,
        anchor_persistence: source.ranked.persistence,
        threshold: source.threshold,
        range,
        lambda_k,
        lambda_max,
        coefficients: params.coefficients,
        sampling: params.sampling,
        input_critical_points,
        persistent_extrema: source.persistent_extrema,
        scales,
        noise,
        noise_rule: params.noise,
        chosen,
    })
}

/// The checks of [`feature_approximation`]'s inputs that need no computation.
fn check_inputs(mesh: &TriMesh, kernel: &HeatKernel, f: &[f64], params: &ApproxParams) -> Result<(), HeatError> {
    let n = kernel.n();
    if mesh.n_vertices() != n {
        return Err(HeatError::LengthMismatch {
            expected: n,
            found: mesh.n_vertices(),
        });
    }
    check::vector(f, n)?;
    crate::limits::count("num_times", params.scales, 1, crate::limits::MAX_APPROX_SCALES)?;
    crate::limits::count("gcv_times", params.gcv_times, 1, crate::limits::MAX_APPROX_SCALES)?;
    crate::limits::count("probes", params.probes, 1, 1024)?;
    let threshold_ok = match params.persistence {
        Persistence::Relative(x) | Persistence::Absolute(x) => x.is_finite() && x >= 0.0,
    };
    if !threshold_ok {
        return Err(HeatError::InvalidParameter {
            name: "persistence",
            reason: format!("{:?} must be finite and non-negative", params.persistence),
        });
    }
    let phi = params.value_time_fraction;
    if !(phi > 0.0 && phi <= 1.0) {
        return Err(HeatError::InvalidParameter {
            name: "value_time_fraction",
            reason: format!("{phi} must be in (0, 1] (the anchors' values are K_(φ t*) f)"),
        });
    }
    Ok(())
}

/// The anchors of a decomposition with their values, from the map they are taken from.
struct AnchorSource {
    ranked: RankedAnchors,
    /// One value per anchor.
    values: Vec<f64>,
    threshold: f64,
    persistent_extrema: usize,
}

impl AnchorSource {
    /// The persistent critical points of the map of `diagram` at `persistence` (relative to
    /// that map's range), with the values of `values` there.
    fn of_map(diagram: &morse::PersistenceDiagram, values: &[f64], persistence: Persistence) -> Self {
        let threshold = persistence.absolute(diagram.value_range);
        let ranked = ranked_anchors(diagram, threshold);
        AnchorSource {
            values: ranked.vertices.iter().map(|&a| values[a as usize]).collect(),
            persistent_extrema: persistent_extremum_count(diagram, threshold),
            threshold,
            ranked,
        }
    }
}

/// The decomposition at one scale t; `range` is `max f − min f`.
fn decompose(
    mesh: &TriMesh,
    kernel: &HeatKernel,
    f: &[f64],
    source: &AnchorSource,
    t: f64,
    coefficients: Coefficients,
    range: f64,
) -> Result<ScaleApproximation, HeatError> {
    let relative = |e: f64| if range > 0.0 { e / range } else { e };
    let anchors = &source.ranked.vertices;
    let fit = fit_to_values(kernel, anchors, &source.values, f, t, coefficients)?;
    let global = fit.values;
    let local: Vec<f64> = f.iter().zip(&global).map(|(a, b)| a - b).collect();
    let linf_error = linf(&local);
    let anchor_error = anchors
        .iter()
        .zip(&source.values)
        .map(|(&a, &v)| (global[a as usize] - v).abs())
        .fold(0.0f64, f64::max);
    let critical_points = morse::critical_points(mesh, &global)?.len();
    let global_diagram = morse::persistence(mesh, &global)?;
    let significant_critical_points = if range > 0.0 {
        morse::persistent_extrema(&global_diagram, SIGNIFICANT_PERSISTENCE * range).len()
    } else {
        critical_points
    };
    Ok(ScaleApproximation {
        t,
        linf_error,
        relative_linf_error: relative(linf_error),
        anchor_error: relative(anchor_error),
        critical_points,
        significant_critical_points,
        persistent_extrema: persistent_extremum_count(&global_diagram, source.threshold),
        anchors: fit.anchors,
        coefficients: fit.coefficients,
        global,
        local,
    })
}
