//! `wfem retrieval vocab|build|query`: shape retrieval with bags of features of the wFEM heat
//! kernel (paper Sect. 5; Shape Google).
//!
//! * `vocab` trains a vocabulary (descriptor settings, z-score statistics, words) on a set of
//!   meshes and saves it;
//! * `build` indexes meshes: it trains a vocabulary on them (optimistic when the same shapes
//!   are then evaluated) or reuses one (`--vocab`), and stores every bag;
//! * `eval` indexes labelled meshes and reports leave-one-out retrieval measures
//!   ([`shape_retrieval::eval`]);
//! * `query` ranks the indexed meshes by distance to a query mesh: one descriptor computation
//!   and one scan of the index.
//!
//! Every file may be a mesh or a point cloud (`.ply` without faces, `.xyz`, `.pts`, `.csv`,
//! `.npy`), and one collection may mix them: a cloud is described with the robust Laplacian of
//! its 30-nearest-neighbour triangulations, and of the cleaning below only the spikes are put
//! back (the other steps repair triangulations). `--laplacian` (cotan by default) is the
//! Laplacian of the meshes; it is recorded in the vocabulary and the index, and `add` and
//! `query` describe their shapes with the recorded one (`query --laplacian` naming another is
//! refused).
//!
//! The defaults are [`shape_retrieval::model::RetrievalSettings::default`]: isolated spikes put
//! back, rough and incoherent (noisy, not merely coarse) shapes smoothed by the heat kernel down
//! to a roughness of 0.1 edge lengths, holes with rims up to 3√A closed by smooth patches that
//! are not themselves described, pinched vertices split and thin handles (cycles up to 0.35√A)
//! cut (clean, closed shapes of genus 0 are left as they are), coarse meshes refined, then SI-HKS with times `t = A·2^τ`,
//! τ ∈ [−12, 1] (A = surface area; exactly scale invariant), 5 Fourier magnitudes, k = 100,
//! z-scored, 512 words, soft assignment, vertex areas capped at 3 medians, χ² distance.
//! SHREC'11 (600 shapes, 30 classes, `cargo xtask real-eval`, docs/RETRIEVAL-RESULTS.md): mAP
//! 0.990 against 0.980 for Shape-DNA; TOSCA-76 0.997. Everything is recorded in
//! the vocabulary and index files (JSON, see [`shape_retrieval::store`]).

use super::choice::choice;
use super::{check_output, CliError, MeshArgs};
use clap::{Args, Subcommand};
use mesh_fem::io::Shape;
use mesh_fem::Laplacian;
use retrieval_store::index::SqliteIndex;
use shape_retrieval::descriptor::{Descriptor, DescriptorOptions, RETRIEVAL_SIHKS};
use shape_retrieval::distance::BagDistance;
use shape_retrieval::eval::ClassRule;
use shape_retrieval::global::GlobalKind;
use shape_retrieval::hks::TimeSampling;
use shape_retrieval::model::{
    Denoising, Despiking, GlobalSignature, HoleFilling, Refinement, RetrievalIndex, RetrievalSettings, ShapeFeatures,
    Smoothing, VertexWeights, VocabularyModel,
};
use shape_retrieval::spatial::SpatialBag;
use shape_retrieval::store::{IndexStore, JsonFile, VocabularyStore};
use shape_retrieval::RetrievalError;
use std::io::Write;
use std::path::{Path, PathBuf};
use wfem_base::Choice;

/// Arguments of `wfem retrieval`.
#[derive(Args, Clone, Debug)]
pub struct RetrievalArgs {
    /// vocab, build or query.
    #[command(subcommand)]
    pub action: RetrievalAction,
}

/// The retrieval actions.
#[derive(Subcommand, Clone, Debug)]
pub enum RetrievalAction {
    /// Train a vocabulary on meshes and save it (reuse it with `build --vocab`).
    Vocab {
        /// Training meshes or point clouds.
        #[arg(required = true, num_args = 1..)]
        files: Vec<PathBuf>,
        /// Vocabulary file (JSON).
        #[arg(long)]
        out: PathBuf,
        #[command(flatten)]
        #[allow(missing_docs)]
        descriptor: DescriptorArgs,
        #[command(flatten)]
        #[allow(missing_docs)]
        training: TrainingArgs,
        #[command(flatten)]
        #[allow(missing_docs)]
        strict: StrictArg,
    },
    /// Index meshes: describe them, train a vocabulary on them (or reuse `--vocab`), store every bag.
    ///
    /// Without `--vocab` the vocabulary is fit to the indexed shapes themselves: measuring
    /// retrieval on those same shapes is then optimistic. Train one on other shapes with
    /// `wfem retrieval vocab` for an honest measurement.
    Build {
        /// Mesh or point-cloud files to index.
        #[arg(required = true, num_args = 1..)]
        files: Vec<PathBuf>,
        /// Index file: an embedded SQLite file (any extension, e.g. `index.sqlite`; queries scan
        /// it in parallel and `add` appends to it), or one JSON document (`.json`).
        #[arg(long)]
        out: PathBuf,
        #[command(flatten)]
        #[allow(missing_docs)]
        vocab: VocabArg,
        /// Replace `--out` if it exists (without it an existing index is never overwritten).
        #[arg(long)]
        force: bool,
        #[command(flatten)]
        #[allow(missing_docs)]
        model: ModelArgs,
        #[command(flatten)]
        #[allow(missing_docs)]
        strict: StrictArg,
    },
    /// Evaluate retrieval on labelled meshes: index them, rank every shape against all the
    /// others from its stored signature (leave-one-out) and report mAP, nearest neighbour, first
    /// and second tier, E-measure and DCG, overall and per class, with the most confused
    /// classes.
    ///
    /// Classes come from `--labels` (lines `file,class`, paths relative to the label file) or
    /// from each path (`--class-from`). Without `--vocab` the vocabulary is trained on the
    /// evaluated shapes themselves, which is optimistic: for an honest number train one on
    /// other shapes with `wfem retrieval vocab` and pass it with `--vocab`.
    Eval {
        /// Mesh files (with `--labels`: only these of the label file; default all of them).
        files: Vec<PathBuf>,
        /// Label file: one `file,class` per line (an optional `file,class` header).
        #[arg(long)]
        labels: Option<PathBuf>,
        /// Without `--labels`, a file's class is the folder holding it (`folder`, default) or
        /// its name without extension and digits (`stem`: cat10.off → cat).
        #[arg(long, conflicts_with = "labels", value_parser = choice::<ClassRule>())]
        class_from: Option<ClassRule>,
        #[command(flatten)]
        #[allow(missing_docs)]
        vocab: VocabArg,
        /// Also write the report (with every query) as JSON.
        #[arg(long)]
        json: Option<PathBuf>,
        /// Also save the index (SQLite, or JSON for `.json`).
        #[arg(long)]
        index: Option<PathBuf>,
        #[command(flatten)]
        #[allow(missing_docs)]
        model: ModelArgs,
    },
    /// Add meshes to a SQLite index (their bags use the stored vocabulary; nothing is rebuilt).
    Add {
        /// Index file written by `wfem retrieval build` (SQLite).
        index: PathBuf,
        /// Mesh or point-cloud files to add (names must be new to the index).
        #[arg(required = true, num_args = 1..)]
        files: Vec<PathBuf>,
        #[command(flatten)]
        #[allow(missing_docs)]
        strict: StrictArg,
    },
    /// Rank the indexed shapes by distance to a query mesh or point cloud, or (--id) to an
    /// indexed shape.
    Query {
        /// Index file written by `wfem retrieval build` (SQLite or JSON).
        index: PathBuf,
        #[command(flatten)]
        #[allow(missing_docs)]
        input: Option<MeshArgs>,
        /// Query by an indexed shape instead of a mesh: NAME as `build` stored it, or its file
        /// name or stem. The others are ranked from its stored signature, nothing read or
        /// described (the shape itself is left out of the results).
        #[arg(long, value_name = "NAME", conflicts_with_all = ["mesh_file", "laplacian", "triangulate", "repair", "weld_tolerance"])]
        id: Option<String>,
        /// Number of results.
        #[arg(long, default_value_t = DEFAULT_TOP)]
        top: usize,
    },
    /// Verify every record of an index against its checksum and report what is damaged (exit
    /// status 1), or that it has no checksums to verify (4: an index of an older format, or
    /// JSON).
    Check {
        /// Index file written by `wfem retrieval build`.
        index: PathBuf,
        /// First add checksums to an index written before they existed (format version 1;
        /// refused if anything is found damaged).
        #[arg(long)]
        upgrade: bool,
    },
}

/// `--vocab` of `build` and `eval`.
#[derive(Args, Clone, Debug, Default)]
pub struct VocabArg {
    /// Reuse a vocabulary from `wfem retrieval vocab` (its descriptor settings are used;
    /// recommended: trained on other shapes). Without it, the vocabulary is trained on the given
    /// meshes themselves, which is optimistic when those same meshes are then used to measure
    /// retrieval.
    #[arg(long, conflicts_with_all = ["descriptor", "eigs", "tau_min", "tau_max", "tau_step", "frequencies", "times", "smoothing", "despike", "fill_holes", "denoise", "refine", "words", "seed", "no_zscore", "laplacian"])]
    pub vocab: Option<PathBuf>,
}

/// `--strict`: all-or-nothing over a collection.
#[derive(Args, Clone, Copy, Debug, Default)]
pub struct StrictArg {
    /// Refuse the whole collection when one file cannot be read or described. Without it,
    /// every usable file is used, each refused one is reported (file and reason) at the end,
    /// and the exit status is 3.
    #[arg(long)]
    pub strict: bool,
}

/// Files of a collection that could not be used, with why.
#[derive(Debug, Default)]
struct Refused {
    files: Vec<(String, String)>,
    strict: bool,
}

impl Refused {
    fn new(strict: StrictArg) -> Self {
        Self {
            files: Vec::new(),
            strict: strict.strict,
        }
    }

    /// Keeps the value, or (not strict) records the file as refused; strict: the error.
    fn keep<T>(&mut self, name: &str, result: Result<T, CliError>) -> Result<Option<T>, CliError> {
        match result {
            Ok(value) => Ok(Some(value)),
            Err(e) if !self.strict => {
                self.files.push((name.to_string(), e.to_string()));
                Ok(None)
            }
            Err(e) => Err(e),
        }
    }

    /// The library's tolerance for this flag.
    fn tolerance(&self) -> shape_retrieval::collection::Tolerance {
        if self.strict {
            shape_retrieval::collection::Tolerance::Strict
        } else {
            shape_retrieval::collection::Tolerance::Skip
        }
    }

    /// Records the shapes the library left out.
    fn extend(&mut self, left_out: Vec<shape_retrieval::collection::Refusal>) {
        self.files
            .extend(left_out.into_iter().map(|r| (r.name, r.reason.to_string())));
    }

    /// Nothing usable left: the error names every refused file.
    fn check_some(&self, left: usize, total: usize) -> Result<(), CliError> {
        if left > 0 {
            return Ok(());
        }
        let reasons: Vec<String> = self.files.iter().map(|(f, why)| format!("{f}: {why}")).collect();
        Err(CliError::Usage(format!(
            "none of the {total} files could be used: {}",
            reasons.join("; ")
        )))
    }

    /// After the outputs are written: each refused file on standard error, then
    /// [`CliError::Refused`] (exit status 3) if there was one.
    fn report(&self, total: usize, done: &str) -> Result<(), CliError> {
        if self.files.is_empty() {
            return Ok(());
        }
        for (file, why) in &self.files {
            super::progress::warn(&format!("refused {file}: {why}"));
        }
        Err(CliError::Refused {
            refused: self.files.len(),
            total,
            done: done.to_string(),
        })
    }
}

/// Describes every mesh (in parallel, a bar per shape; `shape_retrieval::collection`); a shape
/// that cannot be described is refused (or, strict, the error).
fn describe_all(
    meshes: &[(String, Shape)],
    descriptor: &shape_retrieval::model::DescriptorSettings,
    bags: &shape_retrieval::model::BagSettings,
    refused: &mut Refused,
) -> Result<Vec<ShapeFeatures>, CliError> {
    use shape_retrieval::collection::describe_collection;
    let bar = super::progress::bar(meshes.len(), "describing shapes");
    let described = describe_collection(meshes, descriptor, bags, refused.tolerance(), &|name| bar.inc(name));
    bar.done();
    let described = described?;
    refused.extend(described.refused);
    refused.check_some(described.features.len(), meshes.len())?;
    Ok(described.features)
}

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

/// Results a query shows unless told otherwise (a screenful; the library's and Python's
/// default is [`shape_retrieval::model::DEFAULT_RESULTS`]).
const DEFAULT_TOP: usize = 5;

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
    fn apply(&self, settings: &mut RetrievalSettings) -> Result<(), CliError> {
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
    fn apply(&self, settings: &mut RetrievalSettings) {
        settings.training.words = self.words;
        settings.training.seed = self.seed;
        settings.training.standardize = !self.no_zscore;
    }
}

impl BagArgs {
    fn apply(&self, settings: &mut RetrievalSettings) -> Result<(), CliError> {
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

/// Loads every file (in order, with a progress bar), refusing an output path among them:
/// meshes validated for `laplacian`, point clouds as read
/// ([`super::input::load_shape_quietly`]).
fn load_all(
    files: &[PathBuf],
    outputs: &[&std::path::Path],
    laplacian: Laplacian,
    refused: &mut Refused,
) -> Result<Vec<(String, Shape)>, CliError> {
    for f in files {
        for out in outputs {
            check_output(f, out)?;
        }
    }
    refuse_repeated(files)?;
    let bar = super::progress::bar(files.len(), "reading shapes");
    let mut meshes = Vec::with_capacity(files.len());
    for f in files {
        let name = f.display().to_string();
        let shape = super::input::load_shape_quietly(f, laplacian);
        bar.inc(&name);
        if let Some(shape) = refused.keep(&name, shape)? {
            meshes.push((name, shape));
        }
    }
    bar.done();
    refused.check_some(meshes.len(), files.len())?;
    Ok(meshes)
}

/// Refuses a collection that names one file more than once (as given or through another
/// path to it): each would be described again, and the index would hold it twice (issue #41:
/// 10,000 copies of one path ran for hours before failing on something unrelated).
fn refuse_repeated(files: &[PathBuf]) -> Result<(), CliError> {
    let mut first: std::collections::HashMap<PathBuf, (usize, usize)> = std::collections::HashMap::new();
    for (i, f) in files.iter().enumerate() {
        let key = std::fs::canonicalize(f).unwrap_or_else(|_| f.clone());
        first.entry(key).or_insert((i, 0)).1 += 1;
    }
    let mut repeated: Vec<(usize, usize)> = first.into_values().filter(|&(_, n)| n > 1).collect();
    if repeated.is_empty() {
        return Ok(());
    }
    repeated.sort_unstable();
    let named: Vec<String> = repeated
        .iter()
        .take(3)
        .map(|&(i, n)| format!("{} ({n} times)", files[i].display()))
        .collect();
    let more = repeated.len().saturating_sub(3);
    Err(CliError::Usage(format!(
        "{}{} given more than once: each shape is described once, give each file once",
        named.join(", "),
        if more > 0 {
            format!(" and {more} more files")
        } else {
            String::new()
        }
    )))
}

/// `wfem retrieval vocab|build|query`.
pub fn run(args: &RetrievalArgs, out: &mut dyn Write) -> Result<(), CliError> {
    match &args.action {
        RetrievalAction::Vocab {
            files,
            out: path,
            descriptor,
            training,
            strict,
        } => {
            let mut settings = RetrievalSettings::default();
            super::limits::retrieval_sizes(descriptor.eigs, training.words)?;
            descriptor.apply(&mut settings)?;
            training.apply(&mut settings);
            let mut refused = Refused::new(*strict);
            let meshes = load_all(files, &[path], settings.descriptor.laplacian, &mut refused)?;
            let features = describe_all(&meshes, &settings.descriptor, &settings.bags, &mut refused)?;
            let vocabulary = VocabularyModel::train(&settings.descriptor, &settings.training, &features)?;
            JsonFile::new(path).save_vocabulary(&vocabulary)?;
            writeln!(
                out,
                "trained {} words of {} on {} ({} descriptors) into {}",
                vocabulary.vocabulary().size(),
                settings.descriptor.descriptor.label(),
                super::input::count_of(features.len(), "shape", "shapes"),
                vocabulary.info().descriptors,
                path.display()
            )?;
            refused.report(files.len(), "the vocabulary was trained")?;
        }
        RetrievalAction::Build {
            files,
            out: path,
            vocab,
            force,
            model,
            strict,
        } => {
            let vocab = &vocab.vocab;
            let inputs: Vec<&std::path::Path> = files.iter().chain(vocab).map(PathBuf::as_path).collect();
            shape_retrieval::check_index_output(path, &inputs, *force)?;
            let (settings, vocabulary) = settings_and_vocabulary(vocab.as_deref(), model, &[path])?;
            let from = match vocab {
                Some(v) => format!("the vocabulary of {}", v.display()),
                None => "a vocabulary trained on these shapes (optimistic if they are also the test set)".into(),
            };
            let mut refused = Refused::new(*strict);
            let descriptor = vocabulary.as_ref().map_or(&settings.descriptor, |v| v.descriptor());
            let meshes = load_all(files, &[path], descriptor.laplacian, &mut refused)?;
            // RetrievalIndex::build, shape by shape: a bar per shape, refused shapes left out.
            let features = describe_all(&meshes, descriptor, &settings.bags, &mut refused)?;
            let vocabulary = match vocabulary {
                Some(v) => v,
                None => super::progress::run("training the vocabulary", || {
                    VocabularyModel::train(&settings.descriptor, &settings.training, &features)
                })?,
            };
            let mut index = RetrievalIndex::new(vocabulary, settings.bags.clone())?;
            for f in &features {
                index.insert(f)?;
            }
            index_file(path).save_index(&index)?;
            writeln!(
                out,
                "indexed {}{} ({} of {} words, {} distance) with {from} into {}",
                super::input::count_of(index.entries().len(), "file", "files"),
                clouds_among(&meshes, &features),
                index.vocabulary().descriptor().descriptor.label(),
                index.vocabulary().vocabulary().size(),
                index.bags().distance.name(),
                path.display()
            )?;
            refused.report(files.len(), "the index was built")?;
        }
        RetrievalAction::Eval {
            files,
            labels,
            class_from,
            vocab,
            json,
            index,
            model,
        } => {
            let vocab = &vocab.vocab;
            let outputs: Vec<&std::path::Path> = json.iter().chain(index).map(PathBuf::as_path).collect();
            let labelled = labelled_files(files, labels.as_deref(), class_from.unwrap_or_default())?;
            let (settings, vocabulary) = settings_and_vocabulary(vocab.as_deref(), model, &outputs)?;
            let paths: Vec<PathBuf> = labelled.iter().map(|(f, _)| f.clone()).collect();
            // Every labelled shape is needed: one that cannot be read is an error.
            let laplacian = vocabulary
                .as_ref()
                .map_or(settings.descriptor.laplacian, |v| v.descriptor().laplacian);
            let meshes = load_all(
                &paths,
                &outputs,
                laplacian,
                &mut Refused::new(StrictArg { strict: true }),
            )?;
            let classes: Vec<String> = labelled.into_iter().map(|(_, c)| c).collect();
            let run = shape_retrieval::eval::evaluate_collection(&meshes, &classes, &settings, vocabulary)?;
            if let Some(p) = json {
                let text = serde_json::to_string_pretty(&run.report)
                    .map_err(|e| CliError::Usage(format!("{}: {e}", p.display())))?;
                mesh_fem::io::write_atomic(p, |w| w.write_all(text.as_bytes()))?;
            }
            if let Some(p) = index {
                index_file(p).save_index(&run.index)?;
            }
            write!(out, "{}", run.report.to_text())?;
            if vocab.is_none() {
                super::progress::note(
                    "for an honest evaluation train a vocabulary on other shapes \
                     (`wfem retrieval vocab OTHER... --out vocab.json`) and pass `--vocab vocab.json`",
                );
            }
        }
        RetrievalAction::Add {
            index: path,
            files,
            strict,
        } => {
            if !is_sqlite(path)? {
                return Err(CliError::Usage(format!(
                    "{} is a JSON index, which is written whole: add needs a SQLite index (build with --out INDEX.sqlite)",
                    path.display()
                )));
            }
            let store = SqliteIndex::new(path);
            let (settings, _) = store.open()?;
            stored_sizes(&settings)?;
            let mut refused = Refused::new(*strict);
            let meshes = load_all(
                files,
                &[path],
                settings.vocabulary().descriptor().laplacian,
                &mut refused,
            )?;
            let bar = super::progress::bar(meshes.len(), "describing shapes");
            let described =
                shape_retrieval::collection::describe_entries(&settings, &meshes, refused.tolerance(), &|name| {
                    bar.inc(name)
                });
            bar.done();
            let (entries, left_out) = described?;
            refused.extend(left_out);
            refused.check_some(entries.len(), files.len())?;
            store.append(&settings, &entries)?;
            writeln!(
                out,
                "added {} to {}",
                super::input::count_of(entries.len(), "file", "files"),
                path.display()
            )?;
            refused.report(files.len(), "the others were added")?;
        }
        RetrievalAction::Query {
            index: path,
            input,
            id,
            top,
        } => {
            let ranked: Vec<(f64, String)> = match (id, input) {
                (Some(_), Some(input)) => {
                    return Err(CliError::Usage(format!(
                        "--id names an indexed shape in place of a query mesh: give {} or --id, not both",
                        input.mesh.display()
                    )))
                }
                (Some(name), None) => query_by_name(path, name, *top)?,
                (None, Some(input)) => query_by_mesh(path, input, *top)?,
                (None, None) => {
                    return Err(CliError::Usage(
                        "retrieval query needs a query mesh (or point cloud), or --id NAME of an indexed shape".into(),
                    ))
                }
            };
            for (rank, (distance, name)) in ranked.iter().enumerate() {
                writeln!(out, "{}\t{distance:.6}\t{name}", rank + 1)?;
            }
        }
        RetrievalAction::Check { index, upgrade } => super::retrieval_check::check(index, *upgrade, out)?,
    }
    Ok(())
}

/// `wfem retrieval query INDEX MESH`: the `top` indexed shapes nearest to the query mesh, as
/// (distance, name).
fn query_by_mesh(path: &Path, input: &MeshArgs, top: usize) -> Result<Vec<(f64, String)>, CliError> {
    Ok(if is_sqlite(path)? {
        let store = SqliteIndex::new(path);
        let (settings, rows) = store.open()?;
        stored_sizes(&settings)?;
        note_unchecked(&rows);
        let query = read_query(input, &settings)?;
        let query = super::progress::run("describing the query", || {
            settings.describe(&input.mesh.display().to_string(), &query.as_shape())
        })?;
        store
            .search(&settings, &rows, &query.signature, top)?
            .into_iter()
            .map(|h| (h.distance, h.name))
            .collect()
    } else {
        let index = JsonFile::new(path).load_index()?;
        stored_sizes(&index)?;
        let query = read_query(input, &index)?;
        let query = super::progress::run("describing the query", || {
            index.describe(&input.mesh.display().to_string(), &query.as_shape())
        })?;
        index
            .rank(&query.signature)?
            .iter()
            .take(top)
            .map(|r| (r.distance, index.entries()[r.entry].name.clone()))
            .collect()
    })
}

/// `wfem retrieval query INDEX --id NAME`: the `top` shapes nearest to the indexed shape
/// `name`, from its stored signature (itself left out), as (distance, name).
fn query_by_name(path: &Path, name: &str, top: usize) -> Result<Vec<(f64, String)>, CliError> {
    Ok(if is_sqlite(path)? {
        let store = SqliteIndex::new(path);
        let (settings, rows) = store.open()?;
        stored_sizes(&settings)?;
        note_unchecked(&rows);
        let (found, hits) = store.search_stored(&settings, &rows, name, top)?;
        if found != name {
            eprintln!("wfem: --id {name}: the indexed shape {found}");
        }
        hits.into_iter().map(|h| (h.distance, h.name)).collect()
    } else {
        let index = JsonFile::new(path).load_index()?;
        stored_sizes(&index)?;
        let entry = index.find(name)?;
        let found = &index.entries()[entry].name;
        if found != name {
            eprintln!("wfem: --id {name}: the indexed shape {found}");
        }
        index
            .rank_entry(entry)?
            .iter()
            .take(top)
            .map(|r| (r.distance, index.entries()[r.entry].name.clone()))
            .collect()
    })
}

/// A note on standard error when the index has no checksums (format version 1): a damaged
/// record would go unnoticed.
fn note_unchecked(store: &retrieval_store::Store) {
    if !store.checksummed() {
        super::progress::note(&format!(
            "{} has no checksums (an index of format version 1): damage would go unnoticed; \
             `wfem retrieval check --upgrade {}` adds them",
            store.path().display(),
            store.path().display()
        ));
    }
}

/// The query of `wfem retrieval query`, read as the index needs it: with the index's
/// Laplacian (a different `--laplacian` is refused: the query's bag would not be comparable
/// with the stored ones), repaired and validated as every subcommand's input; a point cloud
/// is kept as a cloud.
fn read_query(input: &MeshArgs, index: &RetrievalIndex) -> Result<super::input::Input, CliError> {
    let recorded = index.vocabulary().descriptor().laplacian;
    if let Some(asked) = input.laplacian.filter(|l| *l != recorded) {
        return Err(CliError::Usage(format!(
            "--laplacian {}: the index was built with the {} Laplacian, and a query is described as the indexed \
             shapes were (omit --laplacian, or build an index with --laplacian {})",
            asked.name(),
            recorded.name(),
            asked.name()
        )));
    }
    super::input::read_usable(&MeshArgs {
        laplacian: Some(recorded),
        ..input.clone()
    })
}

/// `, N of them point clouds` when the indexed shapes include clouds (for `build`'s line).
fn clouds_among(shapes: &[(String, Shape)], features: &[ShapeFeatures]) -> String {
    let clouds = features
        .iter()
        .filter(|f| {
            shapes
                .iter()
                .any(|(name, s)| *name == f.name && matches!(s, Shape::Cloud(_)))
        })
        .count();
    match clouds {
        0 => String::new(),
        1 if features.len() == 1 => ", a point cloud".to_string(),
        1 => ", 1 of them a point cloud".to_string(),
        n if n == features.len() => ", all point clouds".to_string(),
        n => format!(", {n} of them point clouds"),
    }
}

/// The settings of `build`/`eval` and the vocabulary to use: the one of `--vocab` (its
/// descriptor settings win), or none (trained on the indexed shapes with the given options).
fn settings_and_vocabulary(
    vocab: Option<&std::path::Path>,
    model: &ModelArgs,
    outputs: &[&std::path::Path],
) -> Result<(RetrievalSettings, Option<VocabularyModel>), CliError> {
    let ModelArgs {
        descriptor,
        training,
        bags,
    } = model;
    let mut settings = RetrievalSettings::default();
    bags.apply(&mut settings)?;
    match vocab {
        Some(v) => {
            for out in outputs {
                check_output(v, out)?;
            }
            let vocabulary = JsonFile::new(v).load_vocabulary()?;
            super::limits::retrieval_sizes(vocabulary.descriptor().eigenpairs, vocabulary.vocabulary().size())?;
            Ok((settings, Some(vocabulary)))
        }
        None => {
            super::limits::retrieval_sizes(descriptor.eigs, training.words)?;
            descriptor.apply(&mut settings)?;
            training.apply(&mut settings);
            Ok((settings, None))
        }
    }
}

/// The files of `eval` with their classes: from the label file (restricted to `files` if any
/// are given) or from each path by the class rule.
fn labelled_files(
    files: &[PathBuf],
    labels: Option<&std::path::Path>,
    rule: ClassRule,
) -> Result<Vec<(PathBuf, String)>, CliError> {
    use shape_retrieval::eval::read_label_file;
    match labels {
        Some(l) => {
            let all = read_label_file(l)?;
            if files.is_empty() {
                return Ok(all);
            }
            files
                .iter()
                .map(|f| {
                    all.iter()
                        .find(|(g, _)| {
                            g == f || matches!((g.canonicalize(), f.canonicalize()), (Ok(a), Ok(b)) if a == b)
                        })
                        .cloned()
                        .ok_or_else(|| CliError::Usage(format!("{} is not in {}", f.display(), l.display())))
                })
                .collect()
        }
        None => {
            if files.is_empty() {
                return Err(CliError::Usage("give mesh files, or --labels with a label file".into()));
            }
            Ok(files
                .iter()
                .map(|f| rule.class_of(f).map(|c| (f.clone(), c)))
                .collect::<Result<_, _>>()?)
        }
    }
}

/// The stored settings pass the same bounds as `build`'s options (a hand-edited k would
/// otherwise start an eigensolve of any size).
fn stored_sizes(index: &RetrievalIndex) -> Result<(), CliError> {
    super::limits::retrieval_sizes(
        index.vocabulary().descriptor().eigenpairs,
        index.vocabulary().vocabulary().size(),
    )
}

/// The store an index path names: JSON for `.json`, SQLite otherwise (the default).
fn index_file(path: &std::path::Path) -> Box<dyn IndexStore> {
    let json = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("json"));
    if json {
        Box::new(JsonFile::new(path))
    } else {
        Box::new(SqliteIndex::new(path))
    }
}

/// Whether an existing index file is SQLite (by its 16-byte header) or JSON (a `.json` name
/// or a document starting with `{`); anything else is refused here rather than parsed as JSON.
/// Regular files only: a FIFO is refused, not waited on.
pub(super) fn is_sqlite(path: &std::path::Path) -> Result<bool, CliError> {
    use std::io::Read;
    let mut file = mesh_fem::io::open_regular_file(path)?;
    let mut head = [0u8; 16];
    let mut n = 0;
    while n < head.len() {
        match file.read(&mut head[n..]) {
            Ok(0) => break,
            Ok(k) => n += k,
            Err(e) => return Err(CliError::Usage(format!("{}: {e}", path.display()))),
        }
    }
    if n == 16 && &head == b"SQLite format 3\0" {
        return Ok(true);
    }
    let json_name = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("json"));
    let json_text = head[..n].iter().find(|b| !b.is_ascii_whitespace()) == Some(&b'{');
    if json_name || json_text {
        return Ok(false);
    }
    Err(CliError::Usage(format!(
        "{} is not a wfem index: {} (an index is an SQLite file or a JSON document written by `wfem retrieval build`)",
        path.display(),
        if n == 0 {
            "the file is empty".to_string()
        } else {
            "neither SQLite nor JSON".to_string()
        }
    )))
}
