//! Shape retrieval as a model: settings → vocabulary → index → queries.
//!
//! The pipeline (Shape Google, Bronstein et al. ACM TOG 30(1) 2011, on the wFEM kernel of the
//! paper's Eq. (6)):
//!
//! 1. **Dense descriptor** p(x) per vertex ([`DescriptorSpec`]), from the k smallest eigenpairs
//!    of (L, B) (Eq. (4), truncated as in Eq. (8)). Default: SI-HKS with times in units of the
//!    surface area, exactly scale invariant ([`crate::sihks`]).
//! 2. **Vocabulary** ([`VocabularyModel`]): the descriptors of a training set are z-scored per
//!    dimension ([`Standardizer`], statistics kept with the vocabulary) and quantised by k-means
//!    into V words with a soft-assignment width σ ([`Vocabulary`]).
//! 3. **Bag** of a shape: `f = Θᵀ w / Σ w` with the soft assignment Θ (n × V) of its z-scored
//!    descriptors and vertex weights w ([`VertexWeights`]; default the areas `B·1` capped at 3
//!    medians), a histogram
//!    summing to 1.
//! 4. **Global signature** (optional fusion, [`GlobalSignature`]): the Shape-DNA
//!    `g_i = ln(λ_i A)`, i = 1 … m, of the same spectrum (A = 1ᵀB1), scale invariant.
//! 5. **Distance** between shapes X, Y: `d(X, Y) = d_bag(f_X, f_Y) + w_g · (1/m) Σ_i |g_i(X) − g_i(Y)|`
//!    with d_bag = L1 or χ² ([`BagDistance`]).
//!
//! [`RetrievalIndex`] holds the vocabulary, the bag settings and one entry (bag + global
//! signature) per indexed shape. A query costs one descriptor computation (one eigensolve) and
//! an O(N·V) scan of the entries: nothing the index holds is recomputed. Storage lives in
//! [`crate::store`]; this module has no file format.
//!
//! Training the vocabulary on the indexed collection itself is *optimistic* (the words are fit
//! to exactly the shapes that are then retrieved); train on disjoint shapes
//! ([`VocabularyModel::train`] on another set) to measure generalisation.

use crate::bof::{Assignment, Vocabulary, VocabularyParams};
use crate::check;
use crate::descriptor::{Descriptor, DescriptorParams, ShapeDescriptors};
use crate::distance::BagDistance;
use crate::global::GlobalKind;
use crate::hks::{heat_kernel_signature, HksParams, Spectrum, SpectrumNormalization, TimeSampling};
use crate::sihks::{scale_invariant_hks, SihksParams, TimeUnit};
use crate::spatial::{ShapeSpectrum, SpatialBag};
use crate::standardize::Standardizer;
use crate::RetrievalError;
use faer::{Mat, MatRef};
use mesh_fem::TriMesh;
use serde::{Deserialize, Serialize};
use wfem_heat::KernelDiagonal;

/// A dense (per-vertex) descriptor with its parameters: the one place a descriptor is computed
/// ([`Self::compute`]); [`Descriptor`] names it without parameters ([`Self::kind`]).
///
/// Every variant is computed from the k smallest eigenpairs of its kernel (see
/// [`crate::descriptor`]); the HKS variants are `h(x, t) = Σ_k e^{−λ_k t} φ_k(x)²` (the kernel
/// value k_t(x, x) of Eq. (6), resp. Eq. (7) for DHK1).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum DescriptorSpec {
    /// SI-HKS of the wFEM kernel with times `t = t₀·α^τ` (by default t₀ = A, the surface area:
    /// exactly scale invariant; [`crate::sihks`], [`TimeUnit::Area`]).
    SiHks {
        /// Base α of the time sampling (> 1).
        alpha: f64,
        /// First τ.
        tau_min: f64,
        /// Last τ.
        tau_max: f64,
        /// Step Δτ.
        tau_step: f64,
        /// Number K of Fourier magnitudes kept.
        frequencies: usize,
        /// The time unit t₀ (absent in files: the area).
        #[serde(default = "area_unit", skip_serializing_if = "is_area_unit")]
        time_unit: TimeUnit,
        /// Which diagonal of the kernel is sampled (absent in files: the kernel value).
        #[serde(default, skip_serializing_if = "is_kernel_value", with = "wfem_choice::serde_name")]
        convention: KernelDiagonal,
    },
    /// Log-HKS of the wFEM kernel on the shape rescaled to unit area, `ln(A·h(x, A·τ_j))` at the
    /// given dimensionless times τ_j ([`SpectrumNormalization::UnitArea`]); exactly scale
    /// invariant. (`A·h ≥ A·φ₀² = 1`, so the logarithm is defined and ≥ 0.)
    AreaHks {
        /// Times in units of the area.
        times: Vec<f64>,
    },
    /// DHK1: HKS of the lumped (Voronoi-cot) kernel, Eq. (7), at absolute times.
    Dhk1 {
        /// Times in the squared length unit of the meshes (or automatic per shape).
        times: TimeSampling,
    },
    /// DHK2: HKS of the wFEM kernel, Eq. (6), at absolute times.
    Dhk2 {
        /// Times in the squared length unit of the meshes (or automatic per shape).
        times: TimeSampling,
    },
    /// DHK3: HKS of the wFEM kernel with eigenvalues divided by λ_max of the k computed ones
    /// (the paper's scale-invariant dense descriptor, Sect. 5).
    Dhk3 {
        /// Times in units of 1/λ_max (or automatic per shape).
        times: TimeSampling,
    },
}

fn area_unit() -> TimeUnit {
    TimeUnit::Area(1.0)
}

fn is_area_unit(unit: &TimeUnit) -> bool {
    *unit == area_unit()
}

fn is_kernel_value(convention: &KernelDiagonal) -> bool {
    *convention == KernelDiagonal::KernelValue
}

/// The retrieval default: SI-HKS of the wFEM kernel (Eq. (6)), area time unit, α = 2,
/// τ ∈ [−12, 1] in steps of 1/8 (105 samples), K = 5 Fourier magnitudes.
///
/// Narrower and lower than [`SihksParams::default`] (τ ∈ [−10, 2], K = 8): on TOSCA-76
/// (`cargo xtask tosca-eval`, 48 words, χ²) that window gives mAP 0.986 (david 0.91); this one
/// 0.998 with the vocabulary trained on the 76 and 0.999 with one trained outside them, when it
/// was chosen (with today's cleaning and capped weights: 0.9972 and 0.9978, docs/SHREC-RESULTS.md).
/// The small
/// times resolve the humans' fingers and faces; frequencies ≥ 5 mostly carried noise. At
/// τ = −12 the 100th mode has tλ ≈ 4π·100·2⁻¹² ≈ 0.3 (Weyl), so the first samples see the
/// truncation of the spectrum: the descriptor depends (mildly) on k, which is recorded with it.
impl Default for DescriptorSpec {
    fn default() -> Self {
        Self::sihks(&SihksParams {
            tau_min: -12.0,
            tau_max: 1.0,
            num_frequencies: 5,
            ..SihksParams::default()
        })
    }
}

impl DescriptorSpec {
    /// The descriptor without its parameters.
    pub fn kind(&self) -> Descriptor {
        match self {
            DescriptorSpec::SiHks { .. } => Descriptor::SiHks,
            DescriptorSpec::AreaHks { .. } => Descriptor::AreaHks,
            DescriptorSpec::Dhk1 { .. } => Descriptor::Dhk1,
            DescriptorSpec::Dhk2 { .. } => Descriptor::Dhk2,
            DescriptorSpec::Dhk3 { .. } => Descriptor::Dhk3,
        }
    }

    /// SI-HKS with the given options.
    pub fn sihks(p: &SihksParams) -> Self {
        DescriptorSpec::SiHks {
            alpha: p.alpha,
            tau_min: p.tau_min,
            tau_max: p.tau_max,
            tau_step: p.tau_step,
            frequencies: p.num_frequencies,
            time_unit: p.time_unit,
            convention: p.convention,
        }
    }

    /// A descriptor with the times and SI-HKS options of `params` (the parameters of
    /// [`crate::ShapeDescriptors::dense`]; area-HKS takes its explicit times, or none).
    pub fn with_params(descriptor: Descriptor, params: &DescriptorParams) -> Self {
        let times = params.times.clone();
        match descriptor {
            Descriptor::SiHks => Self::sihks(&params.sihks),
            Descriptor::AreaHks => DescriptorSpec::AreaHks {
                times: match times {
                    TimeSampling::Explicit(t) => t,
                    TimeSampling::Auto { .. } => Vec::new(),
                },
            },
            Descriptor::Dhk1 => DescriptorSpec::Dhk1 { times },
            Descriptor::Dhk2 => DescriptorSpec::Dhk2 { times },
            Descriptor::Dhk3 => DescriptorSpec::Dhk3 { times },
        }
    }

    /// The descriptor's defaults for retrieval, or `None` where it has none: the absolute
    /// times of DHK1/DHK2 and the area times of area-HKS depend on the collection.
    pub fn retrieval_default(descriptor: Descriptor) -> Option<Self> {
        match descriptor {
            Descriptor::SiHks => Some(Self::default()),
            Descriptor::Dhk3 => Some(Self::dhk3_default()),
            Descriptor::AreaHks | Descriptor::Dhk1 | Descriptor::Dhk2 => None,
        }
    }

    /// A descriptor at explicit times (SI-HKS, which samples its own times, gets its
    /// retrieval default).
    pub fn with_times(descriptor: Descriptor, times: Vec<f64>) -> Self {
        match descriptor {
            Descriptor::SiHks => Self::default(),
            Descriptor::AreaHks => DescriptorSpec::AreaHks { times },
            Descriptor::Dhk1 => DescriptorSpec::Dhk1 {
                times: TimeSampling::Explicit(times),
            },
            Descriptor::Dhk2 => DescriptorSpec::Dhk2 {
                times: TimeSampling::Explicit(times),
            },
            Descriptor::Dhk3 => DescriptorSpec::Dhk3 {
                times: TimeSampling::Explicit(times),
            },
        }
    }

    /// The paper's DHK3 at its CLI times `4 ln10 · 10^{0.4 j}`, j = 0 … 5 (units of 1/λ_max):
    /// six scales over two decades from the finest resolved one, as in Shape Google.
    pub fn dhk3_default() -> Self {
        DescriptorSpec::Dhk3 {
            times: TimeSampling::Explicit(
                (0..6)
                    .map(|j| 4.0 * std::f64::consts::LN_10 * 10f64.powf(0.4 * j as f64))
                    .collect(),
            ),
        }
    }

    /// The SI-HKS options of an SI-HKS descriptor (`None` for the others).
    pub fn sihks_params(&self) -> Option<SihksParams> {
        match *self {
            DescriptorSpec::SiHks {
                alpha,
                tau_min,
                tau_max,
                tau_step,
                frequencies,
                time_unit,
                convention,
            } => Some(SihksParams {
                alpha,
                tau_min,
                tau_max,
                tau_step,
                time_unit,
                num_frequencies: frequencies,
                convention,
            }),
            _ => None,
        }
    }

    /// The descriptor dimension d (for automatic times, their number).
    pub fn dimension(&self) -> usize {
        match self {
            DescriptorSpec::SiHks { frequencies, .. } => *frequencies,
            DescriptorSpec::AreaHks { times } => times.len(),
            DescriptorSpec::Dhk1 { times } | DescriptorSpec::Dhk2 { times } | DescriptorSpec::Dhk3 { times } => {
                match times {
                    TimeSampling::Explicit(t) => t.len(),
                    TimeSampling::Auto { num_times } => *num_times,
                }
            }
        }
    }

    /// Checks the parameters (the same checks the computation makes, without a shape).
    ///
    /// # Errors
    /// [`RetrievalError::InvalidParameter`] / [`RetrievalError::Empty`] naming the parameter.
    pub fn validate(&self) -> Result<(), RetrievalError> {
        let explicit = |times: &[f64]| {
            check::non_empty("times", times.len())?;
            times.iter().try_for_each(|&t| check::positive("time", t))
        };
        match self {
            DescriptorSpec::SiHks { frequencies, .. } => {
                let p = self.sihks_params().unwrap_or_default();
                let m = p.times(Some(1.0))?.len();
                if *frequencies == 0 || m < 3 || *frequencies > (m - 1) / 2 + 1 {
                    return Err(RetrievalError::InvalidParameter {
                        name: "frequencies",
                        value: *frequencies as f64,
                        reason: "must be in 1 ..= (number of τ samples − 1)/2 + 1, with at least 3 τ samples",
                    });
                }
                Ok(())
            }
            DescriptorSpec::AreaHks { times } => explicit(times),
            DescriptorSpec::Dhk1 { times } | DescriptorSpec::Dhk2 { times } | DescriptorSpec::Dhk3 { times } => {
                match times {
                    TimeSampling::Explicit(t) => explicit(t),
                    TimeSampling::Auto { num_times } => check::non_empty("times", *num_times),
                }
            }
        }
    }

    /// The descriptor (n × d) of one shape.
    ///
    /// # Errors
    /// Those of the eigensolver ([`ShapeDescriptors::eigenbasis`]), [`heat_kernel_signature`]
    /// and [`scale_invariant_hks`].
    pub fn compute(&self, shape: &mut ShapeDescriptors) -> Result<Mat<f64>, RetrievalError> {
        let area = shape.area();
        let basis = shape.eigenbasis(self.kind().uses_lumped())?;
        let spectrum = Spectrum::new(&basis.values, basis.vectors.as_ref())?.with_area(area)?;
        let hks = |times: TimeSampling, normalization| {
            heat_kernel_signature(
                &spectrum,
                &HksParams {
                    times,
                    normalization,
                    ..Default::default()
                },
            )
            .map(|h| h.values)
        };
        match self {
            DescriptorSpec::SiHks { .. } => scale_invariant_hks(&spectrum, &self.sihks_params().unwrap_or_default()),
            DescriptorSpec::AreaHks { times } => {
                let mut h = hks(
                    TimeSampling::Explicit(times.clone()),
                    SpectrumNormalization::UnitArea { area },
                )?;
                for j in 0..h.ncols() {
                    for i in 0..h.nrows() {
                        let v = h[(i, j)];
                        // NaN is not positive either.
                        if v.is_nan() || v <= 0.0 {
                            return Err(RetrievalError::NonPositiveSignature {
                                vertex: i,
                                time: times[j],
                                value: v,
                            });
                        }
                        h[(i, j)] = v.ln();
                    }
                }
                Ok(h)
            }
            DescriptorSpec::Dhk1 { times } | DescriptorSpec::Dhk2 { times } => {
                hks(times.clone(), SpectrumNormalization::None)
            }
            DescriptorSpec::Dhk3 { times } => hks(times.clone(), SpectrumNormalization::MaxEigenvalue),
        }
    }
}

/// Heat-kernel smoothing of the embedding before anything is computed (beyond the paper): the
/// vertex positions are replaced by `K_t x`, the wFEM heat kernel (Eq. (6)) applied to the three
/// coordinate functions, with `t = c·A` (A = 1ᵀB1, so the smoothing is scale invariant and does
/// not depend on the resolution). This is implicit fairing with the exact kernel: the
/// high-frequency part of the geometry (additive noise, isolated spikes) decays like
/// `e^{−λt}` while the shape's large scales are kept. Evaluated by the fast exact path of
/// [`wfem_heat::Method::Fast`] (one sparse Cholesky).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Smoothing {
    /// c in `t = c·A` (> 0).
    pub time: f64,
}

impl Smoothing {
    /// The mesh with positions `K_t x`, `t = c·A`, and the same faces.
    ///
    /// # Errors
    /// [`RetrievalError::InvalidParameter`] for c ≤ 0, [`RetrievalError::Mesh`] /
    /// [`RetrievalError::Heat`] from assembly and the kernel, and [`RetrievalError::Mesh`] if the
    /// smoothed positions do not form a valid mesh.
    pub fn apply(&self, mesh: &TriMesh) -> Result<TriMesh, RetrievalError> {
        check::positive("smoothing time", self.time)?;
        EmbeddingFlow::new(mesh)?.at(self.time)
    }
}

/// The heat flow of a mesh's embedding: `K_t x` for the three coordinate functions, `t = c·A`,
/// by the fast exact path of the wFEM kernel (one factorization per time). Shared by
/// [`Smoothing`] and [`Denoising`].
struct EmbeddingFlow<'m> {
    mesh: &'m TriMesh,
    kernel: wfem_heat::HeatKernel,
    area: f64,
    x: Mat<f64>,
}

impl<'m> EmbeddingFlow<'m> {
    fn new(mesh: &'m TriMesh) -> Result<Self, RetrievalError> {
        let ops = mesh_fem::assemble(mesh, &mesh_fem::AssemblyParams::default())?;
        let area: f64 = crate::bof::vertex_areas(ops.mass.as_ref()).iter().sum();
        let kernel = wfem_heat::HeatKernel::new(
            &ops,
            wfem_heat::HeatParams {
                mass: wfem_heat::Mass::Consistent,
                method: wfem_heat::Method::Fast(Default::default()),
            },
        )?;
        let p = mesh.positions();
        let x = Mat::from_fn(p.len(), 3, |i, j| p[i][j]);
        Ok(Self { mesh, kernel, area, x })
    }

    /// The mesh with positions `K_t x`, `t = c·A`, and the same faces.
    fn at(&self, c: f64) -> Result<TriMesh, RetrievalError> {
        let y = self.kernel.apply_many(self.x.as_ref(), c * self.area)?;
        let positions = (0..y.nrows()).map(|i| [y[(i, 0)], y[(i, 1)], y[(i, 2)]]).collect();
        Ok(TriMesh::new(positions, self.mesh.faces().to_vec())?)
    }
}

/// Removal of isolated spikes (shot noise) before anything is computed (beyond the paper): a
/// vertex farther than `threshold` local edge lengths from the centroid of its neighbours is put
/// back as the harmonic fill of its neighbours ([`mesh_fem::filter::despike`]). A spike changes
/// the heat kernel around it at every small time and adds a few very large vertex areas, so a
/// handful of spikes moves a shape's bag towards every other spiky shape; a mesh without
/// spikes is left unchanged.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Despiking {
    /// The threshold, in local edge lengths (> 0).
    pub threshold: f64,
}

impl Default for Despiking {
    fn default() -> Self {
        Self {
            threshold: mesh_fem::filter::DEFAULT_SPIKE_THRESHOLD,
        }
    }
}

/// Denoising by the heat kernel, as much as the shape needs (beyond the paper): a shape whose
/// [`mesh_fem::filter::roughness`] is above `roughness` **and** whose height coherence
/// ([`mesh_fem::filter::surface_noise`]) is below `max_coherence` has its positions replaced by
/// `K_t x` (as [`Smoothing`]) with the smallest `t = c·A` on a doubling ladder (c = 10⁻⁶,
/// 2·10⁻⁶, …, at most 10⁻²) that brings the roughness down to `roughness`; any other shape is
/// left unchanged. Additive noise raises the roughness of every vertex and makes the heights of
/// neighbours independent, so a noisy copy of a shape is smoothed back towards the clean one,
/// while clean shapes keep all their detail (a fixed smoothing time for every shape costs the
/// clean ones their small scales).
///
/// The coherence gate keeps coarse clean meshes as they are: on ~250-vertex meshes the
/// curvature changes from one edge to the next, so half of the SHREC'11 shapes read as rough
/// (0.1–0.18) and the roughness alone smoothed them, shrinking thin limbs (SHREC'11 mAP 0.943
/// with it, 0.980 without denoising; `cargo xtask real-eval`, docs/RETRIEVAL-RESULTS.md). Their
/// heights stay coherent (≥ 0.16), those of noisy shapes do not (≤ 0.02 from 0.2 mean edge
/// lengths of noise on).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Denoising {
    /// The target roughness, in edge lengths (> 0).
    pub roughness: f64,
    /// Shapes whose height coherence is at least this are never denoised (in (−1, 1]; `None`:
    /// no gate, the roughness alone decides — what files written before the gate hold).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_coherence: Option<f64>,
}

/// Default target of [`Denoising`]: above the roughness of every TOSCA shape (0.016–0.069 over
/// the 71 poses) and of the same shapes decimated to 10 % (≤ 0.088), at that of additive noise
/// of 0.1 mean edge lengths (0.10–0.11), below that of stronger noise (0.18 at 0.2).
pub const DEFAULT_TARGET_ROUGHNESS: f64 = 0.1;

/// Default coherence gate of [`Denoising`]: between the noisy TOSCA shapes (≤ 0.02 from 0.2
/// mean edge lengths of noise on; −0.07 … 0.17 at 0.1, where denoising changes no retrieval
/// number) and the coarse clean SHREC'11 shapes (≥ 0.16; TOSCA ≥ 0.40).
pub const DEFAULT_MAX_COHERENCE: f64 = 0.1;

impl Default for Denoising {
    fn default() -> Self {
        Self {
            roughness: DEFAULT_TARGET_ROUGHNESS,
            max_coherence: Some(DEFAULT_MAX_COHERENCE),
        }
    }
}

impl Denoising {
    /// Whether a mesh is denoised: rough and (with a gate) incoherent.
    pub fn applies_to(&self, mesh: &TriMesh) -> bool {
        let noise = mesh_fem::filter::surface_noise(mesh);
        noise.roughness > self.roughness && self.max_coherence.is_none_or(|c| noise.coherence < c)
    }

    /// The mesh, smoothed as much as needed (or unchanged).
    ///
    /// # Errors
    /// [`RetrievalError::InvalidParameter`] for a target ≤ 0 or a gate outside (−1, 1],
    /// [`RetrievalError::Mesh`] / [`RetrievalError::Heat`] from assembly and the kernel, and
    /// [`RetrievalError::Mesh`] if the smoothed positions do not form a valid mesh.
    pub fn apply(&self, mesh: &TriMesh) -> Result<TriMesh, RetrievalError> {
        self.validate()?;
        if !self.applies_to(mesh) {
            return Ok(mesh.clone());
        }
        let flow = EmbeddingFlow::new(mesh)?;
        let mut c = DENOISING_FIRST_TIME;
        loop {
            let smoothed = flow.at(c)?;
            if c >= DENOISING_LAST_TIME || mesh_fem::filter::roughness(&smoothed) <= self.roughness {
                return Ok(smoothed);
            }
            c *= 2.0;
        }
    }

    /// Checks the parameters.
    ///
    /// # Errors
    /// [`RetrievalError::InvalidParameter`] for a target ≤ 0 or a gate outside (−1, 1].
    pub fn validate(&self) -> Result<(), RetrievalError> {
        check::positive("target roughness", self.roughness)?;
        match self.max_coherence {
            Some(c) if !(c > -1.0 && c <= 1.0) => Err(RetrievalError::InvalidParameter {
                name: "largest coherence denoised",
                value: c,
                reason: "must be in (−1, 1]",
            }),
            _ => Ok(()),
        }
    }
}

/// Hole filling (beyond the paper): every hole whose rim is at most `max_perimeter · √A` long
/// is closed by a smooth patch ([`mesh_fem::holes::fill_holes`]; rims of touching holes are
/// split and closed one by one) before the shape is described. The patch changes the
/// operators — the heat no longer reflects at the rim of a hole the intact shape does not
/// have — but its vertices are not described: descriptors, weights and the cap of
/// [`VertexWeights::CappedArea`] are taken over the shape's own vertices only. Closed shapes
/// are left unchanged. Measured on the synthetic SHREC'10 data (docs/SHREC-RESULTS.md, outside
/// vocabulary, area weights): micro holes at strength ≤ 5 from 0.61 to 0.91 mAP, and the
/// cumulative ≤ 5 from 76.9 to 86.6 %.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HoleFilling {
    /// The longest rim closed, in units of √A (> 0).
    pub max_perimeter: f64,
}

impl Default for HoleFilling {
    fn default() -> Self {
        Self {
            max_perimeter: mesh_fem::holes::DEFAULT_MAX_HOLE_PERIMETER,
        }
    }
}

/// Repair of topological noise (beyond the paper), in two places of the cleaning: first,
/// every pinched vertex — where two parts were welded at a point or along an edge — is split
/// into one vertex per sheet ([`mesh_fem::handles::unweld`]); then, once holes are filled, on a
/// closed shape of genus > 0 every thin handle — a non-separating cycle of length at most
/// `max_handle · √A` — is removed with its tube and the openings closed
/// ([`mesh_fem::handles::cut_handles`]), shortest first. A tube glued between two parts that
/// touch (scans and simplifications leave them; the synthetic `handles` class makes them)
/// then no longer carries heat between them. Copies, patches and the removed tubes are not
/// described. Manifold shapes of genus 0 (nearly all) are left as they are; real handles are
/// longer than the bound (a torus 0.50 √A).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TopologyRepair {
    /// The longest handle cycle removed, in units of √A (> 0).
    pub max_handle: f64,
}

impl Default for TopologyRepair {
    fn default() -> Self {
        Self {
            max_handle: mesh_fem::handles::DEFAULT_MAX_HANDLE_LENGTH,
        }
    }
}

/// The ladder of [`Denoising`]: c from 10⁻⁶ (well below an edge: a 5K-vertex shape has
/// ℓ̄² ≈ 4·10⁻⁴ A) doubling up to at most 10⁻².
const DENOISING_FIRST_TIME: f64 = 1e-6;
const DENOISING_LAST_TIME: f64 = 1e-2;

/// How a shape's vertices are described: the eigenpairs and the dense descriptor. A vocabulary
/// is only meaningful for descriptors computed with the same settings, so they are stored with it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct DescriptorSettings {
    /// Number k of eigenpairs (default 100).
    pub eigenpairs: usize,
    /// The descriptor (default SI-HKS, area time unit).
    pub descriptor: DescriptorSpec,
    /// Optional smoothing of the embedding by a fixed time, after despiking, denoising and
    /// hole filling (default: none).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub smoothing: Option<Smoothing>,
    /// Removal of isolated spikes first (default: on, threshold 3; `null` turns it off). As
    /// every field, a missing one takes the default, so a vocabulary or index written before
    /// this option existed is queried with it; on shapes without spikes it changes nothing.
    pub despiking: Option<Despiking>,
    /// Denoising as much as needed, after the spikes and before hole filling and any fixed
    /// smoothing (default: on, target roughness 0.1; `null` turns it off). A missing field
    /// takes the default, as for `despiking`; smooth shapes are left unchanged.
    pub denoising: Option<Denoising>,
    /// Hole filling after denoising and before any fixed smoothing (default: on, rims up to
    /// 3 √A; `null` turns it off). Unlike the other steps, **a missing field reads as off**:
    /// a vocabulary or index written before hole filling existed holds bags of unfilled
    /// shapes, and its queries must be described alike. Closed shapes are left unchanged.
    #[serde(default)]
    pub hole_filling: Option<HoleFilling>,
    /// Repair of topological noise: pinches split first, thin handles removed after hole
    /// filling (default: on, handle cycles up to 0.35 √A; `null` turns it off). **A missing
    /// field reads as off**, as for `hole_filling`. Manifold shapes of genus 0 are left
    /// unchanged.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub topology_repair: Option<TopologyRepair>,
}

impl Default for DescriptorSettings {
    fn default() -> Self {
        Self {
            eigenpairs: crate::DEFAULT_EIGENPAIRS,
            descriptor: DescriptorSpec::default(),
            smoothing: None,
            despiking: Some(Despiking::default()),
            denoising: Some(Denoising::default()),
            hole_filling: Some(HoleFilling::default()),
            topology_repair: Some(TopologyRepair::default()),
        }
    }
}

impl DescriptorSettings {
    /// Checks the parameters.
    ///
    /// # Errors
    /// [`RetrievalError::InvalidParameter`] for k < 2 (a descriptor needs a nonzero eigenvalue)
    /// and those of [`DescriptorSpec::validate`].
    pub fn validate(&self) -> Result<(), RetrievalError> {
        if self.eigenpairs < 2 {
            return Err(RetrievalError::InvalidParameter {
                name: "eigenpairs",
                value: self.eigenpairs as f64,
                reason: "must be at least 2",
            });
        }
        if let Some(s) = &self.smoothing {
            check::positive("smoothing time", s.time)?;
        }
        if let Some(d) = &self.despiking {
            check::positive("spike threshold", d.threshold)?;
        }
        if let Some(d) = &self.denoising {
            d.validate()?;
        }
        if let Some(h) = &self.hole_filling {
            check::positive("largest hole perimeter", h.max_perimeter)?;
        }
        if let Some(t) = &self.topology_repair {
            check::positive("longest handle cycle", t.max_handle)?;
        }
        self.descriptor.validate()
    }

    /// Assembles the operators of a mesh for these settings (no eigensolve yet).
    ///
    /// # Errors
    /// [`RetrievalError::Mesh`] if assembly fails, and those of [`Self::validate`].
    pub fn shape(&self, mesh: &TriMesh) -> Result<ShapeDescriptors, RetrievalError> {
        self.validate()?;
        // The cleaning steps, in order; each one that is on replaces the mesh. Every step that
        // adds vertices appends them, so the shape's own vertices stay the first `described`.
        let mut mesh = std::borrow::Cow::Borrowed(mesh);
        let mut described = mesh.n_vertices();
        if self.topology_repair.is_some() {
            let unwelded = mesh_fem::handles::unweld(&mesh);
            if !unwelded.copies.is_empty() {
                mesh = std::borrow::Cow::Owned(unwelded.mesh);
            }
        }
        if let Some(d) = &self.despiking {
            mesh = std::borrow::Cow::Owned(mesh_fem::filter::despike(&mesh, d.threshold)?.mesh);
        }
        // Denoising measures the roughness of the shape itself, so it comes before the
        // patches (smooth by construction) could dilute it.
        if let Some(d) = &self.denoising {
            mesh = std::borrow::Cow::Owned(d.apply(&mesh)?);
        }
        if let Some(h) = &self.hole_filling {
            mesh = std::borrow::Cow::Owned(mesh_fem::holes::fill_holes(&mesh, h.max_perimeter)?.mesh);
        }
        // Handles are found on closed shapes, so after the holes are filled.
        if let Some(t) = &self.topology_repair {
            let cut = mesh_fem::handles::cut_handles(&mesh, t.max_handle)?;
            if !cut.cut.is_empty() {
                // The tubes' vertices are gone: the shape's own vertices are the kept ones.
                described -= cut.removed.iter().filter(|&&v| (v as usize) < described).count();
                mesh = std::borrow::Cow::Owned(cut.mesh);
            }
        }
        if let Some(s) = &self.smoothing {
            mesh = std::borrow::Cow::Owned(s.apply(&mesh)?);
        }
        ShapeDescriptors::new(
            &mesh,
            &DescriptorParams {
                eigenpairs: self.eigenpairs,
                ..Default::default()
            },
        )?
        .described_only(described)
    }
}

/// Default cap of [`VertexWeights::CappedArea`], in medians of the vertex areas: the default
/// weights. On the TOSCA shapes (regular meshes) only a few vertices reach it (around
/// single-vertex tips); with hole filling on, it adds +0.3 / +0.6 / +1.0 points to the
/// synthetic SHREC'10 cumulative mAP at ≤ 3 / ≤ 4 / ≤ 5 (outside vocabulary,
/// docs/SHREC-RESULTS.md).
pub const DEFAULT_AREA_CAP: f64 = 3.0;

/// The weight `w_i` of each vertex in the bag `f = Θᵀ w / Σ w` (default: capped areas).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum VertexWeights {
    /// `w = B·1`: the vertex areas (barycentric lumped areas, Eq. (7)), i.e. `f ≈ ∫ θ dμ / A`.
    Area,
    /// `w_i = min(a_i, c · median(a))`: the areas, capped. A spike (shot noise) or a sliver
    /// fan inflates a few vertex areas by one or two orders of magnitude; the cap keeps those
    /// vertices from dominating the bag, while a regular mesh (a_i within a few times the
    /// median) keeps its plain area weights.
    CappedArea {
        /// The cap c, in medians (> 0).
        factor: f64,
    },
    /// `w_i = a_i · s(h_i / H)` with `h_i` the edge hops from vertex i to the nearest boundary
    /// vertex, s the smoothstep, H = `hops`: vertices at a hole's rim, whose heat kernel sees
    /// the reflecting boundary, count less. Closed meshes keep their area weights.
    BoundaryDamped {
        /// Hops H over which the weight rises from 0 to the area (≥ 1).
        hops: u32,
    },
    /// `w_i = min(a_i, c · median(a)) · s(h_i / H)` with `h_i` the edge hops from vertex i to
    /// the nearest vertex the cleaning added (hole patches, copies, the rims of removed
    /// handles), s the smoothstep: vertices whose small-scale heat kernel sees a repair count
    /// less. Shapes without repairs keep their capped areas.
    RepairDamped {
        /// The cap c, in medians (> 0).
        factor: f64,
        /// Hops H over which the weight rises from 0 (≥ 1).
        hops: u32,
    },
}

impl VertexWeights {
    /// Checks the parameters.
    ///
    /// # Errors
    /// [`RetrievalError::InvalidParameter`] for a non-positive factor or zero hops.
    pub fn validate(&self) -> Result<(), RetrievalError> {
        match *self {
            VertexWeights::Area => Ok(()),
            VertexWeights::CappedArea { factor } => check::positive("capped-area factor", factor),
            VertexWeights::RepairDamped { factor, hops } => {
                check::positive("capped-area factor", factor)?;
                if hops == 0 {
                    Err(RetrievalError::InvalidParameter {
                        name: "repair hops",
                        value: 0.0,
                        reason: "must be at least 1",
                    })
                } else {
                    Ok(())
                }
            }
            VertexWeights::BoundaryDamped { hops } => {
                if hops == 0 {
                    Err(RetrievalError::InvalidParameter {
                        name: "boundary hops",
                        value: 0.0,
                        reason: "must be at least 1",
                    })
                } else {
                    Ok(())
                }
            }
        }
    }

    /// The weights of one shape: one per own vertex (`shape.described_vertices()`; the areas
    /// of rim vertices include their share of a filled hole's patch), non-negative, positive
    /// sum.
    ///
    /// # Errors
    /// [`RetrievalError::InvalidModel`] if every weight is zero (a mesh that is all boundary).
    pub fn compute(&self, shape: &ShapeDescriptors) -> Result<Vec<f64>, RetrievalError> {
        // The shape's own vertices only (not the patches of filled holes), so that the cap's
        // median is that of the shape.
        let mut areas = shape.vertex_areas();
        areas.truncate(shape.described_vertices());
        let weights = match *self {
            VertexWeights::Area => areas,
            VertexWeights::CappedArea { factor } => {
                let mut sorted = areas.clone();
                let cap = factor * crate::bof::median(&mut sorted);
                areas.into_iter().map(|a| a.min(cap)).collect()
            }
            VertexWeights::RepairDamped { factor, hops } => {
                let mut sorted = areas.clone();
                let cap = factor * crate::bof::median(&mut sorted);
                let h = added_hops(shape.mesh(), shape.described_vertices(), hops);
                areas
                    .iter()
                    .zip(&h)
                    .map(|(a, &d)| {
                        let x = (d as f64 / hops as f64).min(1.0);
                        a.min(cap) * x * x * (3.0 - 2.0 * x)
                    })
                    .collect()
            }
            VertexWeights::BoundaryDamped { hops } => {
                let h = boundary_hops(shape.mesh(), hops);
                areas
                    .iter()
                    .zip(&h)
                    .map(|(a, &d)| {
                        let x = (d as f64 / hops as f64).min(1.0);
                        a * x * x * (3.0 - 2.0 * x)
                    })
                    .collect()
            }
        };
        if weights.iter().sum::<f64>() > 0.0 {
            Ok(weights)
        } else {
            Err(RetrievalError::InvalidModel {
                what: "vertex weights",
                reason: "every vertex weight is zero".into(),
            })
        }
    }
}

/// Edge hops from every own vertex (the first `own`) to the nearest added vertex (index ≥
/// `own`), capped at `cap`.
fn added_hops(mesh: &TriMesh, own: usize, cap: u32) -> Vec<u32> {
    let n = mesh.n_vertices();
    let mut neighbors: Vec<Vec<u32>> = vec![Vec::new(); n];
    for f in mesh.faces() {
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            neighbors[a as usize].push(b);
            neighbors[b as usize].push(a);
        }
    }
    let mut hops = vec![cap; n];
    let frontier: Vec<u32> = (own as u32..n as u32).collect();
    frontier.iter().for_each(|&v| hops[v as usize] = 0);
    sweep_hops(&neighbors, &mut hops, frontier, cap);
    hops.truncate(own);
    hops
}

/// Breadth-first sweep from `frontier` (its vertices at 0 hops), one ring per round:
/// `hops[w]` becomes the edge hops from the frontier, where below `cap`.
fn sweep_hops(neighbors: &[Vec<u32>], hops: &mut [u32], mut frontier: Vec<u32>, cap: u32) {
    let mut depth = 0;
    while !frontier.is_empty() && depth + 1 < cap {
        depth += 1;
        let mut next = Vec::new();
        for v in frontier {
            for &w in &neighbors[v as usize] {
                if hops[w as usize] > depth {
                    hops[w as usize] = depth;
                    next.push(w);
                }
            }
        }
        frontier = next;
    }
}

/// Edge hops from every vertex to the nearest boundary vertex, capped at `cap` (closed meshes:
/// `cap` everywhere). A boundary vertex lies on an edge used by exactly one face.
fn boundary_hops(mesh: &TriMesh, cap: u32) -> Vec<u32> {
    let n = mesh.n_vertices();
    let mut edges: Vec<(u32, u32)> = Vec::with_capacity(3 * mesh.n_faces());
    for f in mesh.faces() {
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            edges.push((a.min(b), a.max(b)));
        }
    }
    edges.sort_unstable();
    let mut hops = vec![cap; n];
    let mut frontier = Vec::new();
    let mut neighbors: Vec<Vec<u32>> = vec![Vec::new(); n];
    let mut i = 0;
    while i < edges.len() {
        let mut j = i;
        while j < edges.len() && edges[j] == edges[i] {
            j += 1;
        }
        let (a, b) = edges[i];
        neighbors[a as usize].push(b);
        neighbors[b as usize].push(a);
        if j - i == 1 {
            for v in [a, b] {
                if hops[v as usize] != 0 {
                    hops[v as usize] = 0;
                    frontier.push(v);
                }
            }
        }
        i = j;
    }
    // Breadth-first sweep from the boundary, one ring per round.
    sweep_hops(&neighbors, &mut hops, frontier, cap);
    hops
}

/// The global spectral signature fused with the bag ([`crate::global`]): by default the
/// Shape-DNA of the wFEM spectrum in logarithms, `g_i = ln(λ_i A)`, i = 1 … m (λ₀ = 0
/// skipped; what files written before `kind` existed hold), scale invariant since λ → λ/β² and
/// A → β²A; its distance, weighted by `weight`, is added to the bag's.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GlobalSignature {
    /// Which signature (a missing field reads as [`GlobalKind::LogShapeDna`]).
    #[serde(default)]
    pub kind: GlobalKind,
    /// Number m of eigenvalues (≤ eigenpairs − 1).
    pub eigenvalues: usize,
    /// Weight w_g of its distance in the fused distance.
    pub weight: f64,
}

impl GlobalSignature {
    /// Checks the parameters against the number of eigenpairs k.
    ///
    /// # Errors
    /// [`RetrievalError::InvalidParameter`] for m = 0, m ≥ k, or a weight not finite and ≥ 0.
    pub fn validate(&self, eigenpairs: usize) -> Result<(), RetrievalError> {
        if self.eigenvalues == 0 || self.eigenvalues >= eigenpairs {
            return Err(RetrievalError::InvalidParameter {
                name: "global eigenvalues",
                value: self.eigenvalues as f64,
                reason: "must be in 1 ..= eigenpairs − 1",
            });
        }
        if !(self.weight.is_finite() && self.weight >= 0.0) {
            return Err(RetrievalError::InvalidParameter {
                name: "global weight",
                value: self.weight,
                reason: "must be finite and ≥ 0",
            });
        }
        Ok(())
    }

    /// The length of the signature.
    pub fn len(&self) -> usize {
        self.kind.len(self.eigenvalues)
    }

    /// Whether the signature is empty (never, for valid settings).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The signature of one shape ([`GlobalKind::compute`] on its wFEM eigenpairs and the areas
    /// of its own vertices).
    ///
    /// # Errors
    /// Those of the eigensolver and of [`GlobalKind::compute`].
    pub fn compute(&self, shape: &mut ShapeDescriptors) -> Result<Vec<f64>, RetrievalError> {
        let area = shape.area();
        let mut weights = shape.vertex_areas();
        weights.truncate(shape.described_vertices());
        let basis = shape.eigenbasis(false)?;
        self.kind
            .compute(&basis.values, basis.vectors.as_ref(), &weights, area, self.eigenvalues)
    }

    /// The distance of two signatures of this kind (inputs validated by the caller).
    pub(crate) fn distance(&self, g: &[f64], h: &[f64]) -> f64 {
        self.kind.distance(g, h)
    }
}

/// How bags are made and compared (everything after the vocabulary).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct BagSettings {
    /// Vertex weights of the bag (default `CappedArea { factor: 3 }`).
    pub weights: VertexWeights,
    /// How descriptors are spread over the words (default normalised, Shape Google).
    pub assignment: Assignment,
    /// Distance between bags (default χ²).
    pub distance: BagDistance,
    /// Optional fusion with the Shape-DNA (default: none).
    pub global: Option<GlobalSignature>,
    /// Spatially sensitive bags ([`crate::spatial`]): the bag becomes `[½ f, ½ F]`, the plain
    /// bag and the heat flow between words. A missing field reads as off (older files hold
    /// plain bags).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spatial: Option<SpatialBag>,
}

impl Default for BagSettings {
    fn default() -> Self {
        Self {
            weights: VertexWeights::CappedArea {
                factor: DEFAULT_AREA_CAP,
            },
            assignment: Assignment::Normalized,
            distance: BagDistance::default(),
            global: None,
            spatial: Some(SpatialBag::default()),
        }
    }
}

impl BagSettings {
    /// Checks the parameters against the number of eigenpairs k.
    ///
    /// # Errors
    /// Those of [`VertexWeights::validate`] and [`GlobalSignature::validate`].
    pub fn validate(&self, eigenpairs: usize) -> Result<(), RetrievalError> {
        self.weights.validate()?;
        if let Some(g) = &self.global {
            g.validate(eigenpairs)?;
        }
        if let Some(s) = &self.spatial {
            s.validate()?;
        }
        Ok(())
    }

    /// The length of a bag for V words: V, plus V(V+1)/2 with spatial bags.
    pub fn bag_len(&self, words: usize) -> usize {
        words + self.spatial.map_or(0, |_| SpatialBag::bins(words))
    }
}

/// Every user-selectable setting of `build`: the descriptor, the vocabulary training and the bags.
/// Deserialises from partial JSON (missing fields take their defaults).
#[derive(Clone, Debug, PartialEq, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RetrievalSettings {
    /// Eigenpairs and dense descriptor.
    pub descriptor: DescriptorSettings,
    /// Vocabulary training.
    pub training: TrainingParams,
    /// Bags and distances.
    pub bags: BagSettings,
}

/// Options of [`VocabularyModel::train`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TrainingParams {
    /// Number of words V (default [`DEFAULT_WORDS`]).
    pub words: usize,
    /// Seed of k-means++ and of the training subsample (default 0).
    pub seed: u64,
    /// Lloyd iterations (default 300).
    pub max_iter: usize,
    /// Train k-means on at most this many pooled descriptors (seeded subsample; default 50 000).
    pub max_training_points: usize,
    /// z-score the descriptor dimensions before quantisation (default `true`).
    pub standardize: bool,
}

/// Default vocabulary size: 96 words, twice Shape Google's 48. With spatially sensitive bags
/// (on by default) the finer vocabulary wins on the dev sets (docs/RETRIEVAL-RESULTS.md):
/// SHREC'11 mAP 0.986 against 0.983 with 48 words (mean of 3 seeds), the SHREC'10 protocol
/// with the handles class 99.1/96.1/93.3/90.8/85.9 against 99.2/95.1/91.9/89.0/83.7 (null-shape
/// vocabulary), TOSCA-76 0.996–0.997 both.
pub const DEFAULT_WORDS: usize = 96;

impl Default for TrainingParams {
    fn default() -> Self {
        Self {
            words: DEFAULT_WORDS,
            seed: 0,
            max_iter: 300,
            max_training_points: 50_000,
            standardize: true,
        }
    }
}

/// The dense descriptors of one shape with what its bag needs: the vertex weights and the
/// global signature. Computed once per shape ([`ShapeFeatures::compute`]) and reused for
/// training, indexing and querying.
#[derive(Clone, Debug)]
pub struct ShapeFeatures {
    /// A name for reports (e.g. the file).
    pub name: String,
    /// m × d dense descriptors (not z-scored), one row per own vertex of the shape (m = n
    /// unless holes were filled).
    pub descriptors: Mat<f64>,
    /// m vertex weights.
    pub weights: Vec<f64>,
    /// The global signature (empty without fusion).
    pub global: Vec<f64>,
    /// The eigenpairs of the described vertices, for spatial bags (`None` without them).
    pub spectrum: Option<ShapeSpectrum>,
}

impl ShapeFeatures {
    /// Describes one mesh: operators, one eigensolve, the dense descriptor, the weights and the
    /// global signature.
    ///
    /// # Errors
    /// [`RetrievalError::Mesh`] from assembly, and those of [`DescriptorSpec::compute`],
    /// [`VertexWeights::compute`], [`GlobalSignature::compute`].
    pub fn compute(
        name: &str,
        mesh: &TriMesh,
        descriptor: &DescriptorSettings,
        bags: &BagSettings,
    ) -> Result<Self, RetrievalError> {
        let mut shape = descriptor.shape(mesh)?;
        Self::from_shape(name, &mut shape, descriptor, bags)
    }

    /// As [`Self::compute`] on prepared operators (and possibly cached eigenbases).
    ///
    /// # Errors
    /// Those of [`Self::compute`].
    pub fn from_shape(
        name: &str,
        shape: &mut ShapeDescriptors,
        descriptor: &DescriptorSettings,
        bags: &BagSettings,
    ) -> Result<Self, RetrievalError> {
        bags.validate(descriptor.eigenpairs)?;
        let descriptors = descriptor.descriptor.compute(shape)?;
        let weights = bags.weights.compute(shape)?;
        let global = match &bags.global {
            Some(g) => g.compute(shape)?,
            None => Vec::new(),
        };
        let mut features = Self::new(name, shape, descriptors, weights, global)?;
        if bags.spatial.is_some() {
            features.attach_spectrum(shape)?;
        }
        Ok(features)
    }

    /// Keeps the wFEM eigenpairs of `shape` (restricted to its described vertices), which
    /// spatial bags need.
    ///
    /// # Errors
    /// Those of the eigensolver; [`RetrievalError::DimensionMismatch`] if `shape` is not the
    /// one described.
    pub fn attach_spectrum(&mut self, shape: &mut ShapeDescriptors) -> Result<(), RetrievalError> {
        let m = shape.described_vertices();
        check::same("described vertices vs features", self.weights.len(), m)?;
        let area = shape.area();
        let basis = shape.eigenbasis(false)?;
        self.spectrum = Some(ShapeSpectrum {
            values: basis.values.clone(),
            vectors: basis.vectors.subrows(0, m).to_owned(),
            area,
        });
        Ok(())
    }

    /// Assembles the features of `shape` from their parts, keeping the rows of the shape's own
    /// vertices only ([`ShapeDescriptors::described_vertices`]: the vertices of filled holes
    /// take part in the operators, not in the bags). `descriptors` has a row per vertex of the
    /// prepared mesh (or per own vertex), `weights` one per own vertex, as
    /// [`VertexWeights::compute`] gives them.
    ///
    /// # Errors
    /// [`RetrievalError::DimensionMismatch`] if the sizes do not match the shape.
    pub fn new(
        name: &str,
        shape: &ShapeDescriptors,
        descriptors: Mat<f64>,
        weights: Vec<f64>,
        global: Vec<f64>,
    ) -> Result<Self, RetrievalError> {
        let m = shape.described_vertices();
        check::same("vertex weights vs described vertices", m, weights.len())?;
        let descriptors = if descriptors.nrows() == m {
            descriptors
        } else {
            check::same(
                "descriptor rows vs vertices",
                shape.mesh().n_vertices(),
                descriptors.nrows(),
            )?;
            descriptors.subrows(0, m).to_owned()
        };
        Ok(Self {
            name: name.to_string(),
            descriptors,
            weights,
            global,
            spectrum: None,
        })
    }

    /// [`Self::compute`] for many meshes in parallel (one eigensolve per mesh), in input order.
    ///
    /// # Errors
    /// The first failure, as [`RetrievalError::Shape`] naming the mesh.
    pub fn compute_many(
        meshes: &[(String, TriMesh)],
        descriptor: &DescriptorSettings,
        bags: &BagSettings,
    ) -> Result<Vec<Self>, RetrievalError> {
        crate::collection::describe_collection(meshes, descriptor, bags, crate::collection::Tolerance::Strict, &|_| ())
            .map(|d| d.features)
    }
}

/// Where a vocabulary was trained: for provenance and for the "optimistic" warning.
#[derive(Clone, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrainingInfo {
    /// Names of the training shapes.
    pub shapes: Vec<String>,
    /// Number of pooled descriptors k-means ran on.
    pub descriptors: usize,
}

/// A trained vocabulary with everything needed to use it on new shapes: the descriptor settings,
/// the z-score statistics and the words. Its own artifact (`wfem retrieval vocab`).
#[derive(Clone, Debug)]
pub struct VocabularyModel {
    descriptor: DescriptorSettings,
    training: TrainingParams,
    standardizer: Option<Standardizer>,
    vocabulary: Vocabulary,
    info: TrainingInfo,
}

impl VocabularyModel {
    /// Trains on the descriptors of `shapes`: pool them, fit the z-score statistics (if
    /// `params.standardize`) on the pool, then k-means on a seeded subsample of at most
    /// `max_training_points` z-scored rows; σ = the median nearest-word distance.
    ///
    /// # Errors
    /// [`RetrievalError::Empty`] without shapes, [`RetrievalError::DimensionMismatch`] if the
    /// descriptors disagree with the settings, and those of [`Standardizer::fit`] and
    /// [`Vocabulary::train`].
    pub fn train(
        descriptor: &DescriptorSettings,
        params: &TrainingParams,
        shapes: &[ShapeFeatures],
    ) -> Result<Self, RetrievalError> {
        descriptor.validate()?;
        check::non_empty("training shapes", shapes.len())?;
        let d = descriptor.descriptor.dimension();
        for s in shapes {
            check::same("training descriptor dimension", d, s.descriptors.ncols())?;
        }
        let rows: usize = shapes.iter().map(|s| s.descriptors.nrows()).sum();
        let mut pooled = Mat::<f64>::zeros(rows, d);
        let mut r0 = 0;
        for s in shapes {
            pooled
                .as_mut()
                .submatrix_mut(r0, 0, s.descriptors.nrows(), d)
                .copy_from(s.descriptors.as_ref());
            r0 += s.descriptors.nrows();
        }
        let standardizer = if params.standardize {
            let z = Standardizer::fit(pooled.as_ref())?;
            pooled = z.apply(pooled.as_ref())?;
            Some(z)
        } else {
            None
        };
        let vocabulary = Vocabulary::train(
            pooled.as_ref(),
            &VocabularyParams {
                size: params.words,
                max_iter: params.max_iter,
                seed: params.seed,
                sigma: None,
                max_training_points: Some(params.max_training_points),
            },
        )?;
        Ok(Self {
            descriptor: descriptor.clone(),
            training: *params,
            standardizer,
            vocabulary,
            info: TrainingInfo {
                shapes: shapes.iter().map(|s| s.name.clone()).collect(),
                descriptors: rows.min(params.max_training_points),
            },
        })
    }

    /// Reassembles a model from its parts (e.g. read from storage), checking consistency.
    ///
    /// # Errors
    /// [`RetrievalError::InvalidModel`] if the settings are invalid or the dimensions of the
    /// statistics and words disagree with the descriptor.
    pub fn from_parts(
        descriptor: DescriptorSettings,
        training: TrainingParams,
        standardizer: Option<Standardizer>,
        vocabulary: Vocabulary,
        info: TrainingInfo,
    ) -> Result<Self, RetrievalError> {
        let invalid = |reason: String| RetrievalError::InvalidModel {
            what: "vocabulary",
            reason,
        };
        descriptor.validate().map_err(|e| invalid(e.to_string()))?;
        let d = descriptor.descriptor.dimension();
        if vocabulary.words().ncols() != d {
            return Err(invalid(format!(
                "words have dimension {} but the {} descriptor has {d}",
                vocabulary.words().ncols(),
                descriptor.descriptor.kind().label()
            )));
        }
        if let Some(z) = &standardizer {
            if z.dimension() != d {
                return Err(invalid(format!(
                    "z-score statistics have dimension {} but the descriptor has {d}",
                    z.dimension()
                )));
            }
        }
        if training.words != vocabulary.size() {
            return Err(invalid(format!(
                "{} words stored, {} recorded as trained",
                vocabulary.size(),
                training.words
            )));
        }
        Ok(Self {
            descriptor,
            training,
            standardizer,
            vocabulary,
            info,
        })
    }

    /// The descriptor settings the words were trained for.
    pub fn descriptor(&self) -> &DescriptorSettings {
        &self.descriptor
    }

    /// The training parameters.
    pub fn training(&self) -> &TrainingParams {
        &self.training
    }

    /// The z-score statistics (`None` if trained without standardisation).
    pub fn standardizer(&self) -> Option<&Standardizer> {
        self.standardizer.as_ref()
    }

    /// The words and σ.
    pub fn vocabulary(&self) -> &Vocabulary {
        &self.vocabulary
    }

    /// Where it was trained.
    pub fn info(&self) -> &TrainingInfo {
        &self.info
    }

    /// The normalised bag `Θᵀw / 1ᵀΘᵀw` of descriptors (n × d) with vertex weights w (length n)
    /// and the given assignment Θ (for the normalised assignment the denominator is Σw).
    ///
    /// # Errors
    /// Those of [`Standardizer::apply`] and [`Vocabulary::bag_of_features`];
    /// [`RetrievalError::InvalidModel`] if the weights sum to zero.
    pub fn bag(
        &self,
        descriptors: MatRef<'_, f64>,
        weights: &[f64],
        assignment: Assignment,
    ) -> Result<Vec<f64>, RetrievalError> {
        let theta = self.assignment(descriptors, assignment)?;
        Self::normalised_bag(theta.as_ref(), weights)
    }

    /// The assignment Θ (n × V) of descriptors (n × d, not z-scored) to the words.
    ///
    /// # Errors
    /// Those of [`Standardizer::apply`] and [`Vocabulary::soft_assignment`].
    pub fn assignment(&self, descriptors: MatRef<'_, f64>, assignment: Assignment) -> Result<Mat<f64>, RetrievalError> {
        let standardized;
        let descriptors = match &self.standardizer {
            Some(z) => {
                standardized = z.apply(descriptors)?;
                standardized.as_ref()
            }
            None => descriptors,
        };
        match assignment {
            Assignment::Normalized => self.vocabulary.soft_assignment(descriptors),
            Assignment::Kernel => self.vocabulary.kernel_assignment(descriptors),
        }
    }

    /// The bag of a shape under `bags`: the normalised bag, followed by the spatial histogram
    /// when `bags.spatial` is on (each half of the mass; see [`crate::spatial`]).
    ///
    /// # Errors
    /// Those of [`Self::assignment`] and [`SpatialBag::histogram`];
    /// [`RetrievalError::InvalidModel`] if the weights sum to zero or the features lack the
    /// eigenpairs a spatial bag needs.
    pub fn shape_bag(&self, features: &ShapeFeatures, bags: &BagSettings) -> Result<Vec<f64>, RetrievalError> {
        let theta = self.assignment(features.descriptors.as_ref(), bags.assignment)?;
        let bag = Self::normalised_bag(theta.as_ref(), &features.weights)?;
        let Some(spatial) = &bags.spatial else {
            return Ok(bag);
        };
        let spectrum = features.spectrum.as_ref().ok_or_else(|| RetrievalError::InvalidModel {
            what: "features",
            reason: format!(
                "{}: spatial bags need the eigenpairs (ShapeFeatures::attach_spectrum)",
                features.name
            ),
        })?;
        let flow = spatial.histogram(theta.as_ref(), &features.weights, spectrum)?;
        Ok(bag.iter().chain(&flow).map(|x| 0.5 * x).collect())
    }

    /// `Θᵀw / 1ᵀΘᵀw`.
    fn normalised_bag(theta: MatRef<'_, f64>, weights: &[f64]) -> Result<Vec<f64>, RetrievalError> {
        check::same("vertex weights vs descriptors", theta.nrows(), weights.len())?;
        check::finite_slice("vertex weights", weights)?;
        let mut bag: Vec<f64> = (0..theta.ncols())
            .map(|c| theta.col(c).iter().zip(weights).map(|(t, a)| t * a).sum())
            .collect();
        let total: f64 = bag.iter().sum();
        if !(total > 0.0 && total.is_finite()) {
            return Err(RetrievalError::InvalidModel {
                what: "bag",
                reason: format!("the vertex weights sum to {total}"),
            });
        }
        bag.iter_mut().for_each(|x| *x /= total);
        Ok(bag)
    }
}

/// The retrieval signature of one shape: its normalised bag and its global signature.
#[derive(Clone, Debug, PartialEq)]
pub struct ShapeSignature {
    /// The bag (length V, non-negative, sums to 1).
    pub bag: Vec<f64>,
    /// The global signature (length m; empty without fusion).
    pub global: Vec<f64>,
}

/// One indexed shape.
#[derive(Clone, Debug, PartialEq)]
pub struct IndexEntry {
    /// Its name (the file as given to `build`).
    pub name: String,
    /// Its signature.
    pub signature: ShapeSignature,
}

/// One result of a query: the entry and its distance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ranked {
    /// Position of the entry in the index.
    pub entry: usize,
    /// Its distance to the query (≥ 0).
    pub distance: f64,
}

/// A retrieval index: vocabulary, bag settings, and the signature of every indexed shape.
#[derive(Clone, Debug)]
pub struct RetrievalIndex {
    vocabulary: VocabularyModel,
    bags: BagSettings,
    entries: Vec<IndexEntry>,
}

impl RetrievalIndex {
    /// An empty index.
    ///
    /// # Errors
    /// Those of [`BagSettings::validate`].
    pub fn new(vocabulary: VocabularyModel, bags: BagSettings) -> Result<Self, RetrievalError> {
        bags.validate(vocabulary.descriptor.eigenpairs)?;
        Ok(Self {
            vocabulary,
            bags,
            entries: Vec::new(),
        })
    }

    /// Reassembles an index from stored parts, validating every entry: bag length V, bag values
    /// finite, in [0, 1] and summing to 1 (±1e−6), global signatures finite of length m.
    ///
    /// # Errors
    /// [`RetrievalError::InvalidModel`] naming the entry and the value.
    pub fn from_parts(
        vocabulary: VocabularyModel,
        bags: BagSettings,
        entries: Vec<IndexEntry>,
    ) -> Result<Self, RetrievalError> {
        let mut index = Self::new(vocabulary, bags).map_err(|e| RetrievalError::InvalidModel {
            what: "index",
            reason: e.to_string(),
        })?;
        for e in entries {
            index.push_checked(e)?;
        }
        Ok(index)
    }

    fn push_checked(&mut self, entry: IndexEntry) -> Result<(), RetrievalError> {
        let invalid = |reason: String| RetrievalError::InvalidModel { what: "index", reason };
        let (i, name) = (self.entries.len(), &entry.name);
        let v = self.bags.bag_len(self.vocabulary.vocabulary.size());
        let bag = &entry.signature.bag;
        if bag.len() != v {
            return Err(invalid(format!(
                "entry {i} ({name}): bag has {} bins, the settings {v}",
                bag.len()
            )));
        }
        if let Some((j, x)) = bag
            .iter()
            .enumerate()
            .find(|(_, x)| !(x.is_finite() && (0.0..=1.0).contains(*x)))
        {
            return Err(invalid(format!(
                "entry {i} ({name}): bag value {x:e} at word {j} is not in [0, 1]"
            )));
        }
        let sum: f64 = bag.iter().sum();
        if (sum - 1.0).abs() > 1e-6 {
            return Err(invalid(format!("entry {i} ({name}): bag sums to {sum}, not 1")));
        }
        let m = self.bags.global.map_or(0, |g| g.len());
        let global = &entry.signature.global;
        if global.len() != m {
            return Err(invalid(format!(
                "entry {i} ({name}): global signature has {} values, the settings {m}",
                global.len()
            )));
        }
        // Every global signature of a real shape is within a few hundred of 0 (ln(λA), λA/4πi,
        // histogram bins); this also keeps every sum finite.
        if let Some((j, x)) = global.iter().enumerate().find(|(_, x)| x.is_nan() || x.abs() >= 1e3) {
            return Err(invalid(format!(
                "entry {i} ({name}): global value {x:e} at {j} is not finite or not below 1e3"
            )));
        }
        self.entries.push(entry);
        Ok(())
    }

    /// The vocabulary model.
    pub fn vocabulary(&self) -> &VocabularyModel {
        &self.vocabulary
    }

    /// The bag settings.
    pub fn bags(&self) -> &BagSettings {
        &self.bags
    }

    /// The indexed shapes.
    pub fn entries(&self) -> &[IndexEntry] {
        &self.entries
    }

    /// Computes the features of a mesh with the index's settings (one eigensolve).
    ///
    /// # Errors
    /// Those of [`ShapeFeatures::compute`].
    pub fn features(&self, name: &str, mesh: &TriMesh) -> Result<ShapeFeatures, RetrievalError> {
        ShapeFeatures::compute(name, mesh, &self.vocabulary.descriptor, &self.bags)
    }

    /// The signature of a described shape.
    ///
    /// # Errors
    /// Those of [`VocabularyModel::bag`]; [`RetrievalError::DimensionMismatch`] if the global
    /// signature does not match the settings.
    pub fn signature(&self, features: &ShapeFeatures) -> Result<ShapeSignature, RetrievalError> {
        let bag = self.vocabulary.shape_bag(features, &self.bags)?;
        let m = self.bags.global.map_or(0, |g| g.len());
        check::same("global signature length", m, features.global.len())?;
        check::finite_slice("global signature", &features.global)?;
        Ok(ShapeSignature {
            bag,
            global: features.global.clone(),
        })
    }

    /// The entry of a mesh with the index's settings: [`Self::features`] (one eigensolve) and
    /// [`Self::signature`] — what an append stores and a query compares.
    ///
    /// # Errors
    /// Those of [`Self::features`] and [`Self::signature`].
    pub fn describe(&self, name: &str, mesh: &TriMesh) -> Result<IndexEntry, RetrievalError> {
        let features = self.features(name, mesh)?;
        Ok(IndexEntry {
            name: name.to_string(),
            signature: self.signature(&features)?,
        })
    }

    /// Adds a described shape.
    ///
    /// # Errors
    /// Those of [`Self::signature`].
    pub fn insert(&mut self, features: &ShapeFeatures) -> Result<(), RetrievalError> {
        let signature = self.signature(features)?;
        self.push_checked(IndexEntry {
            name: features.name.clone(),
            signature,
        })
    }

    /// The fused distance between two signatures (see the module docs).
    ///
    /// # Errors
    /// [`RetrievalError::DimensionMismatch`], [`RetrievalError::NonFinite`],
    /// [`RetrievalError::NegativeBin`].
    pub fn distance(&self, a: &ShapeSignature, b: &ShapeSignature) -> Result<f64, RetrievalError> {
        let bag = self.bags.distance.between(&a.bag, &b.bag)?;
        check::same("global signature lengths", a.global.len(), b.global.len())?;
        check::finite_slice("global signature", &a.global)?;
        check::finite_slice("global signature", &b.global)?;
        Ok(self.fused(bag, &a.global, &b.global))
    }

    fn fused(&self, bag: f64, a: &[f64], b: &[f64]) -> f64 {
        match &self.bags.global {
            Some(g) if g.weight > 0.0 => bag + g.weight * g.distance(a, b),
            _ => bag,
        }
    }

    /// The distance of a validated query ([`Self::distance`] checked it against one entry) to
    /// a stored signature given as its bag followed by its global signature (`row`, V + m
    /// values), without checks: the inner loop of a scan over an external store.
    pub fn row_distance(&self, query: &ShapeSignature, row: &[f64]) -> f64 {
        let v = query.bag.len().min(row.len());
        let (bag, global) = row.split_at(v);
        self.fused(self.bags.distance.unchecked(&query.bag, bag), &query.global, global)
    }

    /// Every entry by increasing distance to the query signature (ties → lower entry index):
    /// one O(N·V) scan.
    ///
    /// # Errors
    /// Those of [`Self::distance`] (for the query only: entries were validated on insertion).
    pub fn rank(&self, query: &ShapeSignature) -> Result<Vec<Ranked>, RetrievalError> {
        if let Some(first) = self.entries.first() {
            // Validates the query once; the scan below then uses the unchecked formulas.
            self.distance(query, &first.signature)?;
        }
        let mut ranked: Vec<Ranked> = self
            .entries
            .iter()
            .enumerate()
            .map(|(entry, e)| Ranked {
                entry,
                distance: self.fused(
                    self.bags.distance.unchecked(&query.bag, &e.signature.bag),
                    &query.global,
                    &e.signature.global,
                ),
            })
            .collect();
        ranked.sort_by(|a, b| a.distance.total_cmp(&b.distance).then(a.entry.cmp(&b.entry)));
        Ok(ranked)
    }

    /// Builds an index in one go: describes `meshes` (in parallel), trains the vocabulary on them
    /// unless one is given (training on the indexed shapes themselves is optimistic; see the
    /// module docs), and inserts every mesh.
    ///
    /// # Errors
    /// Those of [`ShapeFeatures::compute_many`], [`VocabularyModel::train`], [`Self::insert`].
    pub fn build(
        meshes: &[(String, TriMesh)],
        settings: &RetrievalSettings,
        vocabulary: Option<VocabularyModel>,
    ) -> Result<Self, RetrievalError> {
        crate::collection::build_index(
            meshes,
            settings,
            vocabulary,
            crate::collection::Tolerance::Strict,
            &|_| (),
        )
        .map(|(index, _)| index)
    }
}
