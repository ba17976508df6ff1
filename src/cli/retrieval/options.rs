//! The descriptor, training and bag options of `vocab`, `build` and `eval` (recorded in the
//! vocabulary and the index).

use super::super::CliError;
use super::*;
use clap::Args;

/// The descriptor, training and bag options of `build` and `eval`.
#[derive(Args, Clone, Debug)]
pub struct ModelArgs {
    #[command(flatten)]
    #[allow(missing_docs)]
    pub descriptor: DescriptorArgs,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub training: TrainingArgs,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub bags: BagArgs,
}

/// Descriptor options (recorded in the vocabulary).
#[derive(Args, Clone, Debug)]
pub struct DescriptorArgs {
    /// Dense descriptor.
    #[arg(long, value_parser = choice::<Descriptor>(), default_value = Descriptor::default_name())]
    pub descriptor: Descriptor,
    /// Laplacian of the meshes, recorded in the vocabulary and the index (queries and added
    /// shapes are described with it): cotan (paper Eq. (3)) or robust (for non-manifold or
    /// badly triangulated collections). Point clouds always use the robust construction.
    #[arg(long, value_parser = choice::<Laplacian>(), default_value = Laplacian::default_name())]
    pub laplacian: Laplacian,
    /// Eigenpairs k per shape.
    #[arg(long = "eigenpairs", alias = "eigs", default_value_t = shape_retrieval::descriptor::DEFAULT_EIGENPAIRS)]
    pub eigs: usize,
    #[arg(long, allow_hyphen_values = true, help = defaulted("SI-HKS: first τ of the times t = A·2^τ (A = surface area)", RETRIEVAL_SIHKS.tau_min))]
    pub tau_min: Option<f64>,
    #[arg(long, allow_hyphen_values = true, help = defaulted("SI-HKS: last τ", RETRIEVAL_SIHKS.tau_max))]
    pub tau_max: Option<f64>,
    #[arg(long, help = defaulted("SI-HKS: step Δτ", RETRIEVAL_SIHKS.tau_step))]
    pub tau_step: Option<f64>,
    #[arg(long, help = defaulted("SI-HKS: number of Fourier magnitudes kept", RETRIEVAL_SIHKS.num_frequencies))]
    pub frequencies: Option<usize>,
    /// DHK1/DHK2: absolute times; DHK3: times in units of 1/λ_max (comma-separated).
    /// Default for DHK3: 4 ln10 · 10^{0.4 j}, j = 0…5; DHK1/DHK2 need them.
    #[arg(long, value_delimiter = ',')]
    pub times: Option<Vec<f64>>,
    /// Smooth the embedding first: positions ← K_t x with t = C·area (off by default).
    #[arg(long)]
    pub smoothing: Option<f64>,
    /// Spike removal: a vertex farther than T local edge lengths from the centroid of its
    /// neighbours is put back (default 3; `off` to keep spikes).
    #[arg(long, value_name = "T|off")]
    pub despike: Option<String>,
    /// Hole filling: every hole whose rim is at most P·√area is closed by a smooth patch
    /// before the shape is described; the patch is not itself described (default 3; `off` to
    /// describe open shapes as they are).
    #[arg(long, value_name = "P|off")]
    pub fill_holes: Option<String>,
    /// Denoising: shapes rougher than R (in edge lengths) are smoothed by the heat kernel until
    /// they are not (default 0.1; `off` to keep every shape as it is).
    #[arg(long, value_name = "R|off")]
    pub denoise: Option<String>,
    /// Refinement: a mesh with fewer than V·eigs vertices has every triangle split into four
    /// (same surface) until it has that many, so its eigenbasis is accurate; the shape is still
    /// described at its own vertices (default 20; `off` to compute on the mesh as it is).
    #[arg(long, value_name = "V|off")]
    pub refine: Option<String>,
}

/// `--spatial`: `C` (a positive time factor), `C:G` (and G ≥ 1 groups of words), or `off`.
fn spatial_bag(text: &str) -> Result<Option<SpatialBag>, CliError> {
    let (time, groups) = match text.split_once(':') {
        Some((time, groups)) => (time, Some(groups)),
        None => (text, None),
    };
    let Some(time) = number_or_off("--spatial", &Some(time.to_string()))? else {
        return Ok(None);
    };
    let bad = || {
        CliError::Usage(format!(
            "--spatial takes C, C:G (G a whole number ≥ 1) or `off`, got {text:?}"
        ))
    };
    let groups = match groups {
        None => None,
        Some(g) => Some(g.trim().parse::<usize>().ok().filter(|&g| g >= 1).ok_or_else(bad)?),
    };
    match time {
        None if groups.is_some() => Err(bad()),
        None => Ok(None),
        Some(time) => Ok(Some(SpatialBag { time, groups })),
    }
}

/// `--despike`/`--fill-holes`/`--denoise`/`--refine`/`--area-cap`: a positive number, or `off`.
fn number_or_off(flag: &str, text: &Option<String>) -> Result<Option<Option<f64>>, CliError> {
    let Some(text) = text else { return Ok(None) };
    if text == "off" {
        return Ok(Some(None));
    }
    match text.parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(Some(Some(v))),
        _ => Err(CliError::Usage(format!(
            "{flag} takes a positive number or `off`, got {text:?}"
        ))),
    }
}

/// Vocabulary training options.
#[derive(Args, Clone, Debug)]
pub struct TrainingArgs {
    /// Vocabulary size V.
    #[arg(long, default_value_t = shape_retrieval::model::DEFAULT_WORDS)]
    pub words: usize,
    /// k-means seed.
    #[arg(long, default_value_t = shape_retrieval::model::TrainingParams::default().seed)]
    pub seed: u64,
    /// Do not z-score the descriptor dimensions before k-means.
    #[arg(long)]
    pub no_zscore: bool,
}

/// Bag options (recorded in the index).
#[derive(Args, Clone, Debug)]
pub struct BagArgs {
    /// Distance between bags.
    #[arg(long, value_parser = choice::<BagDistance>(), default_value = BagDistance::default_name())]
    pub distance: BagDistance,
    /// Vertex weights: areas capped at C times their median (default 3), so that a few
    /// inflated vertex areas (spikes, slivers) cannot dominate a bag; `off` for plain areas.
    #[arg(long, value_name = "C|off")]
    pub area_cap: Option<String>,
    /// Spatially sensitive bags (Shape Google Sect. 4.2; off by default): the bag also holds
    /// the heat that flows between words in time t = C·A (e.g. 2⁻⁸ = 0.00390625), or with `C:G`
    /// between G groups of similar words (G(G+1)/2 bins instead of V(V+1)/2); `off` for plain
    /// bags.
    #[arg(long, value_name = "C|C:G|off")]
    pub spatial: Option<String>,
    /// Fuse with a global spectral signature of M eigenvalues at weight W: `M:W` (e.g. `40:0.3`).
    #[arg(long)]
    pub fusion: Option<String>,
    /// The global signature of `--fusion`.
    #[arg(long, requires = "fusion", value_parser = choice::<GlobalKind>(), default_value = GlobalKind::default_name())]
    pub fusion_kind: GlobalKind,
}

/// The help of an option whose default is a library constant (for options that are `None`
/// unless given, so that a misplaced one can be refused).
fn defaulted(help: &str, default: impl std::fmt::Display) -> String {
    format!("{help} [default: {default}]")
}

/// A descriptor option that does not apply, or missing times, named by the flags.
fn descriptor_error(e: RetrievalError) -> CliError {
    let flag = |option: &str| format!("--{}", option.replace('_', "-"));
    match e {
        RetrievalError::MisplacedOption {
            option,
            descriptor,
            owners,
        } => CliError::Usage(format!(
            "{} is an option of --descriptor {}, not of --descriptor {descriptor}",
            flag(option),
            owners.join(" or ")
        )),
        RetrievalError::MissingTimes { descriptor } => CliError::Usage(format!(
            "--descriptor {descriptor} has no default times (they depend on the collection's scale): give them with --times"
        )),
        other => CliError::Retrieval(other),
    }
}

impl DescriptorArgs {
    pub(super) fn apply(&self, settings: &mut RetrievalSettings) -> Result<(), CliError> {
        settings.descriptor.eigenpairs = self.eigs;
        settings.descriptor.laplacian = self.laplacian;
        settings.descriptor.smoothing = self.smoothing.map(|time| Smoothing { time });
        if let Some(v) = number_or_off("--despike", &self.despike)? {
            settings.descriptor.despiking = v.map(|threshold| Despiking { threshold });
        }
        if let Some(v) = number_or_off("--fill-holes", &self.fill_holes)? {
            settings.descriptor.hole_filling = v.map(|max_perimeter| HoleFilling { max_perimeter });
        }
        if let Some(v) = number_or_off("--refine", &self.refine)? {
            settings.descriptor.refinement = v.map(|vertices_per_eigenpair| Refinement { vertices_per_eigenpair });
        }
        if let Some(v) = number_or_off("--denoise", &self.denoise)? {
            settings.descriptor.denoising = v.map(|roughness| Denoising {
                roughness,
                ..Default::default()
            });
        }
        let options = DescriptorOptions {
            times: self.times.clone().map(TimeSampling::Explicit),
            tau_min: self.tau_min,
            tau_max: self.tau_max,
            tau_step: self.tau_step,
            frequencies: self.frequencies,
            ..Default::default()
        };
        settings.descriptor.descriptor = self
            .descriptor
            .clone()
            .for_collection(&options)
            .map_err(descriptor_error)?;
        settings.descriptor.validate()?;
        Ok(())
    }
}

impl TrainingArgs {
    pub(super) fn apply(&self, settings: &mut RetrievalSettings) {
        settings.training.words = self.words;
        settings.training.seed = self.seed;
        settings.training.standardize = !self.no_zscore;
    }
}

impl BagArgs {
    pub(super) fn apply(&self, settings: &mut RetrievalSettings) -> Result<(), CliError> {
        settings.bags.distance = self.distance;
        if let Some(v) = number_or_off("--area-cap", &self.area_cap)? {
            settings.bags.weights = v.map_or(VertexWeights::Area, |factor| VertexWeights::CappedArea { factor });
        }
        if let Some(text) = &self.spatial {
            settings.bags.spatial = spatial_bag(text)?;
        }
        settings.bags.global = match &self.fusion {
            None => None,
            Some(text) => {
                let bad = || CliError::Usage(format!("--fusion {text:?}: expected M:W, e.g. 20:0.5"));
                let (m, w) = text.split_once(':').ok_or_else(bad)?;
                Some(GlobalSignature {
                    kind: self.fusion_kind,
                    eigenvalues: m.trim().parse().map_err(|_| bad())?,
                    weight: w.trim().parse().map_err(|_| bad())?,
                })
            }
        };
        Ok(())
    }
}
