//! The benchmark of the feature-driven approximation `f = f_glob + f_loc` (paper, Sect. 4.2,
//! Fig. 12–13; issue #24) on real meshes with known ground truth (`cargo xtask approx-eval`,
//! docs/APPROX-RESULTS.md).
//!
//! For every mesh of [`APPROX_CASES`] and every [`BenchField`] (a coordinate, the HKS at one
//! time, a diffusion-distance field — smooth maps whose values are known exactly):
//!
//! * **smooth**: the default decomposition of the clean map — relative L∞ error at the finest
//!   scale (the paper's claim: below 2 %), at the coarsest, the largest scale still within
//!   2 %, the error at the anchors and the persistent extrema of f_glob against f's;
//! * **noisy**: the map plus Gaussian noise of standard deviation [`NOISE_FRACTION`] of its
//!   range (seed [`NOISE_SEED`], [`wfem_base::rng::SplitMix64`]), decomposed with the anchors
//!   of every persistence of [`PERSISTENCE_SWEEP`] (Fig. 13: simplified from 40 % to 10 %):
//!   the distance of f_glob to the **clean** map at the best scale, the correlation of f_loc
//!   with the noise there, and the critical points of f_glob per persistence (Fig. 13(d));
//!   beside it the best any scale of `K_t f` alone achieves (no anchors: the smoother's own
//!   floor);
//! * the paper's printed formula ([`Coefficients::FeatureValues`] on its scales
//!   `(i/10)/λ_k`) beside the default, and the default coefficients on the paper's scales;
//! * **denoising** ([`denoise`], issue #40): per noise level of [`denoise::DENOISE_LEVELS`],
//!   the default at the scale it chooses without the clean map against the best smoothing
//!   chosen knowing it.
//!
//! The persistence sweep and the noise-level table take f as clean ([`NoiseRule::Keep`]:
//! anchors at f's critical points with f's values, issue #24's rule); the denoising column is
//! the default ([`NoiseRule::Auto`]).

pub mod denoise;

use crate::BenchError;
use denoise::DenoiseResult;
use mesh_fem::{assemble, morse, AssemblyParams, TriMesh};
use std::path::Path;
use wfem_base::rng::SplitMix64;
use wfem_heat::approx::{
    feature_approximation, fit_global_component, persistent_extremum_count, ranked_anchors, ApproxParams, Coefficients,
    FeatureApproximation, NoiseRule, Persistence, ScaleSampling,
};
use wfem_heat::distance::{DiffusionDistance, DistanceKind, DistanceParams};
use wfem_heat::spectral::{EigenParams, Eigenbasis};
use wfem_heat::{DiagonalParams, HeatKernel, HeatParams, KernelDiagonal};

/// One mesh of the benchmark: its path below the corpus folder and a short name.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ApproxCase {
    /// Short name in the tables.
    pub name: &'static str,
    /// Path below the mesh corpus folder (`wfem_corpus::meshes_dir` in the tests and xtask).
    pub mesh: &'static str,
}

/// The meshes of docs/APPROX-RESULTS.md: two TOSCA shapes (the cat of issue #24, a
/// centaur), two SHREC'07 four-legged animals and two classic models.
pub const APPROX_CASES: [ApproxCase; 6] = [
    ApproxCase {
        name: "TOSCA cat0",
        mesh: "tosca-bcicp-5k/TOSCA_Isometric/cat0.off",
    },
    ApproxCase {
        name: "TOSCA centaur0",
        mesh: "tosca-bcicp-5k/TOSCA_Isometric/centaur0.off",
    },
    ApproxCase {
        name: "SHREC'07 386",
        mesh: "shrec07-fourleg/386.off",
    },
    ApproxCase {
        name: "SHREC'07 398",
        mesh: "shrec07-fourleg/398.off",
    },
    ApproxCase {
        name: "bunny",
        mesh: "odedstein-meshes/bunny/bunny.obj",
    },
    ApproxCase {
        name: "spot",
        mesh: "common-3d-test-models/spot.obj",
    },
];

/// The cases small enough for the test suites (< 3,000 vertices): the command line and the
/// Python package are tested against them.
pub const SMALL_CASES: [ApproxCase; 2] = [APPROX_CASES[3], APPROX_CASES[5]];

/// Standard deviation of the added noise, as a fraction of the range of the clean map.
pub const NOISE_FRACTION: f64 = 0.05;

/// Seed of the noise (issue #24).
pub const NOISE_SEED: u64 = 24;

/// Noise levels (standard deviation / range) at which the coordinate is also decomposed with
/// the defaults: where the paper's 2 % to the clean map is within reach.
pub const NOISE_LEVELS: [f64; 4] = [0.005, 0.01, 0.02, 0.05];

/// The persistence thresholds of the noisy maps, relative to the range (Fig. 13: 40 % → 10 %).
pub const PERSISTENCE_SWEEP: [f64; 4] = [0.4, 0.3, 0.2, 0.1];

/// The paper's claim: relative L∞ error below 2 % (Sect. 4.2).
pub const ERROR_THRESHOLD: f64 = 0.02;

/// The least correlation of f_loc with the noise the benchmark asks for.
pub const CORRELATION_THRESHOLD: f64 = 0.9;

/// Index k of λ_k (the paper's k = 20) for the HKS time and the diffusion distance.
const K: usize = 20;

/// A smooth map with known values.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BenchField {
    /// The z coordinate of the vertices (issue #24 used it on the cat).
    Coordinate,
    /// The heat kernel signature `H_t(i, i)` at `t = 5/λ₂₀` (exact diagonal).
    Hks,
    /// The diffusion distance `d_t(s, ·)` at `t = 1/λ₂₀` from the vertex s of largest z.
    Distance,
}

impl BenchField {
    /// Every field, in table order.
    pub const ALL: [BenchField; 3] = [BenchField::Coordinate, BenchField::Hks, BenchField::Distance];

    /// The short name in the tables.
    pub fn name(&self) -> &'static str {
        match self {
            BenchField::Coordinate => "z",
            BenchField::Hks => "HKS",
            BenchField::Distance => "diffusion distance",
        }
    }

    /// The field on a mesh, with its heat kernel and λ₂₀.
    ///
    /// # Errors
    /// [`BenchError::Heat`] from the kernel diagonal or the distance.
    pub fn values(&self, mesh: &TriMesh, kernel: &HeatKernel, lambda_k: f64) -> Result<Vec<f64>, BenchError> {
        let z: Vec<f64> = mesh.positions().iter().map(|p| p[2]).collect();
        Ok(match self {
            BenchField::Coordinate => z,
            BenchField::Hks => {
                let d = shape_retrieval::exact::exact_signature(
                    kernel,
                    &[5.0 / lambda_k],
                    KernelDiagonal::KernelValue,
                    &DiagonalParams::default(),
                )
                .map_err(BenchError::retrieval("HKS"))?;
                d.values.col(0).iter().copied().collect()
            }
            BenchField::Distance => {
                let source = (0..z.len()).max_by(|&a, &b| z[a].total_cmp(&z[b])).unwrap_or(0);
                let d = DiffusionDistance::new(
                    kernel,
                    DistanceKind::Diffusion,
                    1.0 / lambda_k,
                    &DistanceParams::default(),
                )?;
                d.row(source)?
            }
        })
    }
}

/// Gaussian noise of standard deviation `fraction · range` ([`NOISE_SEED`]).
pub fn noise(n: usize, range: f64, fraction: f64) -> Vec<f64> {
    noise_with_seed(n, range, fraction, NOISE_SEED)
}

/// Gaussian noise of standard deviation `fraction · range` from `seed`.
pub fn noise_with_seed(n: usize, range: f64, fraction: f64, seed: u64) -> Vec<f64> {
    let mut rng = SplitMix64::new(seed);
    (0..n).map(|_| fraction * range * rng.next_normal()).collect()
}

/// [`ApproxParams::default`] taking f as clean ([`NoiseRule::Keep`]): the persistence sweep
/// and the noise-level table.
fn keep() -> ApproxParams {
    ApproxParams {
        noise: NoiseRule::Keep,
        ..ApproxParams::default()
    }
}

/// The decomposition of a smooth map.
#[derive(Clone, Debug, PartialEq)]
pub struct SmoothResult {
    /// Number of anchors (persistent critical points at the default 10 %).
    pub anchors: usize,
    /// Relative L∞ error of f_glob at the finest scale of the default hierarchy.
    pub finest_error: f64,
    /// … at the coarsest (t = 1/λ_k).
    pub coarsest_error: f64,
    /// The largest t·λ_k of the default hierarchy whose error is below [`ERROR_THRESHOLD`].
    pub largest_scale_within: Option<f64>,
    /// Largest relative error at the anchors over the scales where every anchor is resolved.
    pub anchor_error: f64,
    /// Largest number of f_glob's extrema with persistence ≥ 10 % over the scales, f's, and
    /// f's with persistence ≥ 5 %: smoothing moves persistences a little, so an extremum of f
    /// just below 10 % may reach it in f_glob; more than f has at 5 % would be spurious.
    pub persistent_extrema: (usize, usize, usize),
    /// The default coefficients on the paper's scales: error at t₁ = 0.1/λ_k.
    pub paper_scales_error: f64,
    /// The paper's printed formula on its scales: the smallest error over them.
    pub literal_error: f64,
}

/// The decomposition of a noisy map at one persistence.
#[derive(Clone, Debug, PartialEq)]
pub struct NoisyResult {
    /// The persistence threshold, relative to the range.
    pub persistence: f64,
    /// Number of anchors.
    pub anchors: usize,
    /// Index of the scale where f_glob is closest to the clean map.
    pub best_scale: usize,
    /// Its t·λ_k.
    pub best_t: f64,
    /// `‖f_glob − clean‖∞ / range(clean)` there.
    pub error: f64,
    /// Pearson correlation of f_loc with the noise there.
    pub correlation: f64,
    /// Critical points of f_glob with persistence ≥ the sweep's lowest threshold (10 % of the
    /// range: extrema and their paired saddles), at the scale that is best at the first
    /// persistence of the sweep (one t for the whole sweep, as in Fig. 13(d)). The
    /// lower-persistence ones are the residual noise of the smoothing at that scale, the
    /// same at every persistence.
    pub critical_points: usize,
}

/// One field of one mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct FieldResult {
    /// The field.
    pub field: BenchField,
    /// The clean map.
    pub smooth: SmoothResult,
    /// The noisy map, per persistence of [`PERSISTENCE_SWEEP`].
    pub noisy: Vec<NoisyResult>,
    /// Critical points of the noisy map itself with persistence ≥ 10 % of its range.
    pub noisy_input_critical_points: usize,
    /// [`Coefficients::Smooth`] (K_t f, no anchors) on the default scales: the best t·λ_k,
    /// `‖K_t f − clean‖∞ / range` there and the correlation of f − K_t f with the noise.
    pub smoother_floor: (f64, f64, f64),
    /// The paper's printed formula on its scales: the best distance to the clean map.
    pub literal_error: f64,
    /// The coordinate only: per noise level of [`NOISE_LEVELS`], the best distance of f_glob
    /// to the clean map over the default scales with f taken as clean, and with K_t f alone.
    pub noise_levels: Vec<(f64, f64, f64)>,
    /// The default on the noisy map, per level of [`denoise::DENOISE_LEVELS`] (issue #40).
    pub denoising: Vec<DenoiseResult>,
    /// Whether the default found noise to remove in the clean map (it must not).
    pub smooth_denoised: bool,
}

/// One mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct CaseResult {
    /// The case.
    pub case: ApproxCase,
    /// Number of vertices.
    pub n_vertices: usize,
    /// λ₂₀.
    pub lambda_k: f64,
    /// λ_max (the finest scale is 1/λ_max).
    pub lambda_max: f64,
    /// One entry per field of [`BenchField::ALL`].
    pub fields: Vec<FieldResult>,
}

pub(crate) fn range(f: &[f64]) -> f64 {
    let (lo, hi) = f
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| (a.min(x), b.max(x)));
    hi - lo
}

pub(crate) fn relative_linf(a: &[f64], b: &[f64], range: f64) -> f64 {
    a.iter().zip(b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs())) / range
}

/// Pearson correlation of two vectors (0 for a constant one).
pub fn correlation(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len() as f64;
    let ma = a.iter().sum::<f64>() / n;
    let mb = b.iter().sum::<f64>() / n;
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        sab += (x - ma) * (y - mb);
        saa += (x - ma) * (x - ma);
        sbb += (y - mb) * (y - mb);
    }
    if saa > 0.0 && sbb > 0.0 {
        sab / (saa * sbb).sqrt()
    } else {
        0.0
    }
}

/// Loads a case and prepares its kernel (default method) and λ_k.
///
/// # Errors
/// [`BenchError::Mesh`] for a missing or unusable mesh; [`BenchError::Heat`].
pub fn load_case(meshes_dir: &Path, case: &ApproxCase) -> Result<(TriMesh, HeatKernel, f64), BenchError> {
    let (mesh, _) = mesh_fem::io::load(&meshes_dir.join(case.mesh), &Default::default())?;
    let ops = assemble(&mesh, &AssemblyParams::default())?;
    let kernel = HeatKernel::new(&ops, HeatParams::default())?;
    let eig = Eigenbasis::partial_of(kernel.operators(), K, &EigenParams::default())?;
    let lambda_k = eig.values[K - 1];
    Ok((mesh, kernel, lambda_k))
}

/// Evaluates one mesh (every field, smooth and noisy).
///
/// # Errors
/// As [`load_case`]; [`BenchError::Heat`] from a decomposition.
pub fn evaluate_case(meshes_dir: &Path, case: &ApproxCase) -> Result<CaseResult, BenchError> {
    let (mesh, kernel, lambda_k) = load_case(meshes_dir, case)?;
    let oracle_times = denoise::oracle_times(&kernel, lambda_k)?;
    let mut fields = Vec::new();
    let mut lambda_max = f64::NAN;
    for field in BenchField::ALL {
        let clean = field.values(&mesh, &kernel, lambda_k)?;
        let (smooth, default) = evaluate_smooth(&mesh, &kernel, &clean, lambda_k)?;
        let denoising = denoise::evaluate_denoising(&mesh, &kernel, &clean, lambda_k, &oracle_times)?;
        lambda_max = default.lambda_max.unwrap_or(f64::NAN);
        let (noisy, noisy_input_critical_points, smoother_floor, literal_error) =
            evaluate_noisy(&mesh, &kernel, &clean, &default, lambda_k)?;
        let noise_levels = match field {
            BenchField::Coordinate => noise_sweep(&mesh, &kernel, &clean)?,
            _ => Vec::new(),
        };
        fields.push(FieldResult {
            field,
            smooth,
            noisy,
            noisy_input_critical_points,
            smoother_floor,
            literal_error,
            noise_levels,
            denoising,
            smooth_denoised: default.chosen.is_some(),
        });
    }
    Ok(CaseResult {
        case: *case,
        n_vertices: mesh.n_vertices(),
        lambda_k,
        lambda_max,
        fields,
    })
}

/// The smooth-map metrics, and the default decomposition (its scales serve the noisy map).
fn evaluate_smooth(
    mesh: &TriMesh,
    kernel: &HeatKernel,
    clean: &[f64],
    lambda_k: f64,
) -> Result<(SmoothResult, FeatureApproximation), BenchError> {
    let default = feature_approximation(mesh, kernel, clean, &ApproxParams::default())?;
    let paper_scales = ApproxParams {
        sampling: ScaleSampling::Paper,
        ..ApproxParams::default()
    };
    let on_paper = feature_approximation(mesh, kernel, clean, &paper_scales)?;
    let literal = feature_approximation(
        mesh,
        kernel,
        clean,
        &ApproxParams {
            coefficients: Coefficients::FeatureValues,
            ..paper_scales
        },
    )?;
    let errors: Vec<f64> = default.scales.iter().map(|s| s.relative_linf_error).collect();
    let m = default.anchors.len();
    let smooth = SmoothResult {
        anchors: m,
        finest_error: errors.first().copied().unwrap_or(f64::NAN),
        coarsest_error: errors.last().copied().unwrap_or(f64::NAN),
        largest_scale_within: default
            .scales
            .iter()
            .filter(|s| s.relative_linf_error < ERROR_THRESHOLD)
            .map(|s| s.t * lambda_k)
            .fold(None, |a: Option<f64>, t| Some(a.map_or(t, |a| a.max(t)))),
        anchor_error: default
            .scales
            .iter()
            .filter(|s| s.anchors.len() == m)
            .map(|s| s.anchor_error)
            .fold(0.0, f64::max),
        persistent_extrema: (
            default.scales.iter().map(|s| s.persistent_extrema).max().unwrap_or(0),
            default.persistent_extrema,
            persistent_extremum_count(&morse::persistence(mesh, clean)?, 0.5 * default.threshold),
        ),
        paper_scales_error: on_paper.scales.first().map_or(f64::NAN, |s| s.relative_linf_error),
        literal_error: literal
            .scales
            .iter()
            .map(|s| s.relative_linf_error)
            .fold(f64::INFINITY, f64::min),
    };
    Ok((smooth, default))
}

type NoisyMetrics = (Vec<NoisyResult>, usize, (f64, f64, f64), f64);

/// Per noise level, the best distance to the clean map over the default scales: the defaults,
/// and K_t f alone ([`Coefficients::Smooth`]).
fn noise_sweep(mesh: &TriMesh, kernel: &HeatKernel, clean: &[f64]) -> Result<Vec<(f64, f64, f64)>, BenchError> {
    let r = range(clean);
    let mut out = Vec::new();
    for sigma in NOISE_LEVELS {
        let f: Vec<f64> = clean
            .iter()
            .zip(noise(clean.len(), r, sigma))
            .map(|(a, b)| a + b)
            .collect();
        let best = |coefficients: Coefficients| -> Result<f64, BenchError> {
            let params = ApproxParams { coefficients, ..keep() };
            let a = feature_approximation(mesh, kernel, &f, &params)?;
            Ok(a.scales
                .iter()
                .map(|s| relative_linf(&s.global, clean, r))
                .fold(f64::INFINITY, f64::min))
        };
        out.push((sigma, best(Coefficients::Anchored)?, best(Coefficients::Smooth)?));
    }
    Ok(out)
}

/// The noisy-map metrics: the persistence sweep with the default coefficients and scales,
/// the smoother's floor and the literal formula.
fn evaluate_noisy(
    mesh: &TriMesh,
    kernel: &HeatKernel,
    clean: &[f64],
    default: &FeatureApproximation,
    lambda_k: f64,
) -> Result<NoisyMetrics, BenchError> {
    let r = range(clean);
    let e = noise(clean.len(), r, NOISE_FRACTION);
    let f: Vec<f64> = clean.iter().zip(&e).map(|(a, b)| a + b).collect();
    let diagram = morse::persistence(mesh, &f)?;
    let lowest = PERSISTENCE_SWEEP.iter().copied().fold(f64::INFINITY, f64::min) * diagram.value_range;
    let input_critical_points = morse::persistent_extrema(&diagram, lowest).len();
    let mut sweep = Vec::new();
    let mut fixed_scale = None;
    for &p in &PERSISTENCE_SWEEP {
        let params = ApproxParams {
            persistence: Persistence::Relative(p),
            ..keep()
        };
        let a = feature_approximation(mesh, kernel, &f, &params)?;
        let (best, error) = a
            .scales
            .iter()
            .enumerate()
            .map(|(i, s)| (i, relative_linf(&s.global, clean, r)))
            .fold((0, f64::INFINITY), |acc, x| if x.1 < acc.1 { x } else { acc });
        let fixed = *fixed_scale.get_or_insert(best);
        sweep.push(NoisyResult {
            persistence: p,
            anchors: a.anchors.len(),
            best_scale: best,
            best_t: a.scales[best].t * lambda_k,
            error,
            correlation: correlation(&a.scales[best].local, &e),
            critical_points: morse::persistent_extrema(&morse::persistence(mesh, &a.scales[fixed].global)?, lowest)
                .len(),
        });
    }
    // K_t f alone over the default scales (the smoother's floor).
    let mut floor = (f64::NAN, f64::INFINITY, 0.0);
    for s in &default.scales {
        let g = fit_global_component(kernel, &[], &f, s.t, Coefficients::Smooth)?.values;
        let error = relative_linf(&g, clean, r);
        if error < floor.1 {
            let local: Vec<f64> = f.iter().zip(&g).map(|(a, b)| a - b).collect();
            floor = (s.t * lambda_k, error, correlation(&local, &e));
        }
    }
    let anchors = ranked_anchors(&diagram, 0.1 * diagram.value_range).vertices;
    let mut literal = f64::INFINITY;
    for t in ScaleSampling::Paper.times(lambda_k, lambda_k, 10) {
        let g = fit_global_component(kernel, &anchors, &f, t, Coefficients::FeatureValues)?.values;
        literal = literal.min(relative_linf(&g, clean, r));
    }
    Ok((sweep, input_critical_points, floor, literal))
}

fn pct(x: f64) -> String {
    if x.is_finite() {
        format!("{:.2} %", 100.0 * x)
    } else {
        "–".into()
    }
}

fn mark(ok: bool) -> &'static str {
    if ok {
        "yes"
    } else {
        "**no**"
    }
}

/// True when the counts do not rise as the persistence rises (the sweep runs from high to
/// low persistence, so the counts must not fall along it) and the lowest persistence has
/// more than the highest.
pub fn falls_with_persistence(noisy: &[NoisyResult]) -> bool {
    let counts: Vec<usize> = noisy.iter().map(|r| r.critical_points).collect();
    counts.windows(2).all(|w| w[0] <= w[1]) && counts.first() < counts.last()
}

/// The tables of docs/APPROX-RESULTS.md (markdown), for the cases evaluated.
pub fn report_tables(results: &[CaseResult]) -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "### Smooth maps\n\n\
         Default decomposition (anchored coefficients, geometric scales from 1/λ_max to 1/λ₂₀, anchors at \
         10 % persistence). Errors are ‖f − f_glob‖∞ / (max f − min f).\n\n\
         | mesh | n | field | anchors | error at t₁ = 1/λ_max | error at 1/λ₂₀ | largest t·λ₂₀ within 2 % | \
         error at the anchors | extrema ≥ 10 %: f_glob / f (f ≥ 5 %) | default on the paper's t₁ = 0.1/λ₂₀ | \
         paper's formula, best t | finest < 2 % |\n\
         |---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---|"
    );
    for c in results {
        for f in &c.fields {
            let m = &f.smooth;
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {} | {} | {} | {:.0e} | {} / {} ({}) | {} | {} | {} |",
                c.case.name,
                c.n_vertices,
                f.field.name(),
                m.anchors,
                pct(m.finest_error),
                pct(m.coarsest_error),
                m.largest_scale_within.map_or("–".into(), |t| format!("{t:.3}")),
                m.anchor_error,
                m.persistent_extrema.0,
                m.persistent_extrema.1,
                m.persistent_extrema.2,
                pct(m.paper_scales_error),
                pct(m.literal_error),
                mark(m.finest_error < ERROR_THRESHOLD),
            );
        }
    }
    let persistences: Vec<String> = PERSISTENCE_SWEEP.iter().map(|p| format!("{:.0}", 100.0 * p)).collect();
    let sweep = persistences.join("/");
    let _ = writeln!(
        s,
        "\n### Noisy maps\n\n\
         The clean map plus Gaussian noise of σ = {:.0} % of its range (seed {NOISE_SEED}), taken as clean \
         (`--noise keep`: anchors at f's critical points with f's values), with the anchors at each persistence \
         {sweep} % (Fig. 13); error = ‖f_glob − clean‖∞ / range(clean) at the \
         best scale, first persistence; critical points of f_glob at that one scale for every persistence. \
         \"K_t f alone\" is the best scale of the smoother without anchors (`smooth` coefficients); the paper's \
         formula is at its own scales and 10 % persistence.\n\n\
         | mesh | field | critical points of f | anchors ({sweep} %) | best t·λ₂₀ | error to clean | corr(f_loc, noise) | \
         critical points of f_glob ({sweep} %) | `smooth`: best t·λ₂₀, error, corr | paper's formula: error | \
         within 2 % | corr ≥ 0.9 | falls with persistence |\n\
         |---|---|---:|---:|---:|---:|---:|---:|---:|---:|---|---|---|",
        100.0 * NOISE_FRACTION
    );
    for c in results {
        for f in &c.fields {
            let Some(first) = f.noisy.first() else { continue };
            let join = |g: &dyn Fn(&NoisyResult) -> String| f.noisy.iter().map(g).collect::<Vec<_>>().join("/");
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {:.4} | {} | {:.3} | {} | {:.4}, {}, {:.3} | {} | {} | {} | {} |",
                c.case.name,
                f.field.name(),
                f.noisy_input_critical_points,
                join(&|r| r.anchors.to_string()),
                first.best_t,
                pct(first.error),
                first.correlation,
                join(&|r| r.critical_points.to_string()),
                f.smoother_floor.0,
                pct(f.smoother_floor.1),
                f.smoother_floor.2,
                pct(f.literal_error),
                mark(first.error < ERROR_THRESHOLD),
                mark(first.correlation >= CORRELATION_THRESHOLD),
                mark(falls_with_persistence(&f.noisy)),
            );
        }
    }
    s
}

/// The noise-level table (the coordinate only).
pub fn noise_table(results: &[CaseResult]) -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
    let head: Vec<String> = NOISE_LEVELS.iter().map(|x| format!("σ = {:.1} %", 100.0 * x)).collect();
    let _ = writeln!(
        s,
        "\n### Noise levels\n\n\
         The coordinate z plus noise of each level (same seed), taken as clean (`--noise keep`, 10 % persistence): \
         the best ‖f_glob − clean‖∞ / range(clean) over the default scales, and (after the slash) the same for \
         K_t f alone.\n\n| mesh | {} |\n|---|{}",
        head.join(" | "),
        "---:|".repeat(NOISE_LEVELS.len())
    );
    for c in results {
        for f in c.fields.iter().filter(|f| !f.noise_levels.is_empty()) {
            let cells: Vec<String> = f
                .noise_levels
                .iter()
                .map(|(_, d, k)| format!("{} / {}", pct(*d), pct(*k)))
                .collect();
            let _ = writeln!(s, "| {} | {} |", c.case.name, cells.join(" | "));
        }
    }
    s
}

/// The summary of docs/APPROX-RESULTS.md, every number taken from `results`.
pub fn report_summary(results: &[CaseResult]) -> String {
    use std::fmt::Write as _;
    let fields: Vec<&FieldResult> = results.iter().flat_map(|c| &c.fields).collect();
    let n = fields.len();
    let span = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        (
            v.first().copied().unwrap_or(f64::NAN),
            v.last().copied().unwrap_or(f64::NAN),
        )
    };
    let count = |p: &dyn Fn(&FieldResult) -> bool| fields.iter().filter(|f| p(f)).count();
    let (_, finest_max) = span(&mut fields.iter().map(|f| f.smooth.finest_error).collect());
    let finest_ok = count(&|f| f.smooth.finest_error < ERROR_THRESHOLD);
    let (lit_lo, lit_hi) = span(&mut fields.iter().map(|f| f.smooth.literal_error).collect());
    let paper_bad = count(&|f| f.smooth.paper_scales_error >= ERROR_THRESHOLD);
    let (pap_lo, pap_hi) = span(&mut fields.iter().map(|f| f.smooth.paper_scales_error).collect());
    let (_, anchor_max) = span(&mut fields.iter().map(|f| f.smooth.anchor_error).collect());
    let spurious = count(&|f| f.smooth.persistent_extrema.0 > f.smooth.persistent_extrema.2);
    let noisy_ok = count(&|f| f.noisy.first().is_some_and(|r| r.error < ERROR_THRESHOLD));
    let (nd_lo, nd_hi) = span(&mut fields.iter().filter_map(|f| f.noisy.first().map(|r| r.error)).collect());
    let (fl_lo, fl_hi) = span(&mut fields.iter().map(|f| f.smoother_floor.1).collect());
    let corr_default = count(&|f| f.noisy.first().is_some_and(|r| r.correlation >= CORRELATION_THRESHOLD));
    let corr_smooth = count(&|f| f.smoother_floor.2 >= CORRELATION_THRESHOLD);
    let falls = count(&|f| falls_with_persistence(&f.noisy));
    let mut s = String::new();
    let _ = writeln!(
        s,
        "## Summary\n\n\
         {n} maps ({} meshes × {} fields). Every number below comes from the tables.\n\n\
         * **Smooth maps, the paper's claim (L∞ error below 2 %)**: met by the default at the finest scale on \
         {finest_ok} of {n} maps (largest error {}). f_glob keeps f's values at every resolved anchor (largest \
         error there {anchor_max:.0e} of the range) and has more extrema of persistence ≥ 10 % than f has ≥ 5 % on \
         {spurious} of {n} maps.\n\
         * **The paper's printed formula** `f_glob = Σ_(i∈A) f(p_i) K_t e_i` (coefficients `feature-values`, its \
         scales `(i/10)/λ₂₀`) stays {}–{} of the range away at its best scale: with a few anchors it is a few bumps \
         of height f(p_i)·K_t e_i(p_i) ≪ f(p_i) on a field that is ≈ 0 elsewhere. It cannot meet the claim; it \
         stays selectable (`--coefficients feature-values --sampling paper`).\n\
         * **The paper's scales**: with the default coefficients, the first of them, t₁ = 0.1/λ₂₀, is already \
         {}–{} away (above 2 % on {paper_bad} of {n} maps): it flattens parts two or three edges wide (tails, ears, \
         legs, the tip of a distance cone). The default scales start at the mesh's resolution 1/λ_max instead \
         (geometric up to 1/λ₂₀); the table gives the largest t·λ₂₀ that stays within 2 %.\n\
         * **Noisy maps (σ = {:.0} % of the range), persistence sweep**: taken as clean, f_glob within 2 % of the clean map at the best scale on \
         {noisy_ok} of {n} maps ({}–{}). This criterion is out of reach of heat-kernel smoothing at this noise: \
         K_t f alone, at the best of the ten scales chosen knowing the clean map, stays {}–{} away — the residual \
         noise of K_t f falls below 2 % only at scales where its bias on thin parts already exceeds 2 % (and on \
         the coarser meshes the noise at a vertex is averaged over a few dozen neighbours at most). Taken as clean \
         (`--noise keep`), the decomposition is farther still because its anchors keep f's values, noise \
         included (the global extrema of a noisy map are its largest noise values); see the noise-level table for \
         where the claim holds. f_loc correlates ≥ 0.9 with the noise on {corr_default} of {n} maps taken as clean \
         and on {corr_smooth} of {n} with `--coefficients smooth`; the critical points of f_glob (persistence ≥ 10 %) fall with the persistence \
         as in Fig. 13(d) on {falls} of {n}.\n",
        results.len(),
        BenchField::ALL.len(),
        pct(finest_max),
        pct(lit_lo),
        pct(lit_hi),
        pct(pap_lo),
        pct(pap_hi),
        100.0 * NOISE_FRACTION,
        pct(nd_lo),
        pct(nd_hi),
        pct(fl_lo),
        pct(fl_hi),
    );
    s
}
