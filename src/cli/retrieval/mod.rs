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

mod add;
mod build;
mod check;
mod eval;
mod options;
mod query;
mod vocab;

use super::choice::choice;
use super::{check_output, CliError};
use clap::{Args, Subcommand};
use mesh_fem::io::Shape;
use mesh_fem::Laplacian;
pub use options::{DescriptorArgs, ModelArgs, TrainingArgs};
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
use std::path::PathBuf;
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
    Vocab(vocab::VocabArgs),
    /// Index meshes: describe them, train a vocabulary on them (or reuse `--vocab`), store every bag.
    ///
    /// Without `--vocab` the vocabulary is fit to the indexed shapes themselves: measuring
    /// retrieval on those same shapes is then optimistic. Train one on other shapes with
    /// `wfem retrieval vocab` for an honest measurement.
    Build(build::BuildArgs),
    /// Evaluate retrieval on labelled meshes: index them, rank every shape against all the
    /// others from its stored signature (leave-one-out) and report mAP, nearest neighbour, first
    /// and second tier, E-measure and DCG, overall and per class, with the most confused
    /// classes.
    ///
    /// Classes come from `--labels` (lines `file,class`, paths relative to the label file) or
    /// from each path (`--class-from`). Without `--vocab` the vocabulary is trained on the
    /// evaluated shapes themselves, which is optimistic: for an honest number train one on
    /// other shapes with `wfem retrieval vocab` and pass it with `--vocab`.
    Eval(eval::EvalArgs),
    /// Add meshes to a SQLite index (their bags use the stored vocabulary; nothing is rebuilt).
    Add(add::AddArgs),
    /// Rank the indexed shapes by distance to a query mesh or point cloud, or (--id) to an
    /// indexed shape.
    Query(query::QueryArgs),
    /// Verify every record of an index against its checksum and report what is damaged (exit
    /// status 1), or that it has no checksums to verify (4: an index of an older format, or
    /// JSON).
    Check(check::CheckArgs),
}

/// Runs one retrieval subcommand.
pub fn run(args: &RetrievalArgs, out: &mut dyn Write) -> Result<(), CliError> {
    match &args.action {
        RetrievalAction::Vocab(a) => vocab::run(a, out),
        RetrievalAction::Build(a) => build::run(a, out),
        RetrievalAction::Eval(a) => eval::run(a, out),
        RetrievalAction::Add(a) => add::run(a, out),
        RetrievalAction::Query(a) => query::run(a, out),
        RetrievalAction::Check(a) => check::check(&a.index, a.upgrade, out),
    }
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
