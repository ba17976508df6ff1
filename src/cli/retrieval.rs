//! `wfem retrieval build|query`: Shape Google retrieval (bags of features of the
//! scale-invariant wFEM HKS, DHK3) over a collection of meshes.
//!
//! The index is one JSON file: the descriptor settings, the vocabulary (V words and σ) and
//! the normalised bag of features of every indexed file. A query computes its bag with the
//! same settings and ranks the files by L1 distance.

use super::{check_output, load_usable, CliError, MeshArgs};
use clap::{Args, Subcommand};
use faer::Mat;
use serde::{Deserialize, Serialize};
use shape_retrieval::hks::TimeSampling;
use shape_retrieval::{
    l1_distance, vertex_areas, Descriptor, DescriptorParams, RetrievalError, ShapeDescriptors, Vocabulary,
    VocabularyParams,
};
use std::io::Write;
use std::path::PathBuf;

/// Arguments of `wfem retrieval`.
#[derive(Args, Clone, Debug)]
pub struct RetrievalArgs {
    /// build or query.
    #[command(subcommand)]
    pub action: RetrievalAction,
}

/// The two retrieval actions.
#[derive(Subcommand, Clone, Debug)]
pub enum RetrievalAction {
    /// Index meshes: train a vocabulary on their descriptors and store every bag of features.
    Build {
        /// Mesh files to index.
        #[arg(required = true, num_args = 1..)]
        files: Vec<PathBuf>,
        /// Index file (JSON).
        #[arg(long)]
        out: PathBuf,
        /// Eigenpairs k per shape.
        #[arg(long, default_value_t = shape_retrieval::DEFAULT_EIGENPAIRS)]
        eigs: usize,
        /// Vocabulary size V.
        #[arg(long, default_value_t = 48)]
        words: usize,
        /// k-means seed.
        #[arg(long, default_value_t = 0)]
        seed: u64,
    },
    /// Rank the indexed meshes by similarity to a query mesh.
    Query {
        /// Index file written by `wfem retrieval build`.
        index: PathBuf,
        #[command(flatten)]
        #[allow(missing_docs)]
        input: MeshArgs,
        /// Number of results.
        #[arg(long, default_value_t = 5)]
        top: usize,
    },
}

/// The index file.
#[derive(Serialize, Deserialize, Debug, Clone, PartialEq)]
pub struct RetrievalIndex {
    /// Descriptor name (DHK3).
    pub descriptor: String,
    /// Eigenpairs k.
    pub eigenpairs: usize,
    /// HKS times in units of 1/λ_max.
    pub times: Vec<f64>,
    /// Vocabulary words, one row per word.
    pub words: Vec<Vec<f64>>,
    /// Soft-assignment width σ.
    pub sigma: f64,
    /// Indexed files and their bags (normalised to sum 1).
    pub entries: Vec<IndexEntry>,
}

/// One indexed file.
#[derive(Serialize, Deserialize, Debug, Clone, PartialEq)]
pub struct IndexEntry {
    /// The mesh file as given.
    pub file: PathBuf,
    /// Its bag of features.
    pub bag: Vec<f64>,
}

fn retrieval(e: RetrievalError) -> CliError {
    match e {
        RetrievalError::Heat(h) => CliError::Heat(h),
        RetrievalError::Mesh(m) => CliError::Mesh(m),
        other => CliError::Usage(other.to_string()),
    }
}

/// DHK3 times 4 ln10 · 10^{0.4 j}, j = 0…5 (units of 1/λ_max): from the finest resolved scale
/// to a hundred times it, 6 scales as in Shape Google.
fn default_times() -> Vec<f64> {
    (0..6)
        .map(|j| 4.0 * std::f64::consts::LN_10 * 10f64.powf(0.4 * j as f64))
        .collect()
}

/// DHK3 of a mesh and its vertex areas `B·1`.
fn describe(args: &MeshArgs, eigs: usize, times: &[f64]) -> Result<(Mat<f64>, Vec<f64>), CliError> {
    let mesh = load_usable(args)?;
    let params = DescriptorParams {
        eigenpairs: eigs,
        times: TimeSampling::Explicit(times.to_vec()),
        ..Default::default()
    };
    let mut shape = ShapeDescriptors::new(&mesh, &params).map_err(retrieval)?;
    let d = shape.dense(Descriptor::Dhk3).map_err(retrieval)?;
    Ok((d, vertex_areas(shape.operators().mass.as_ref())))
}

fn bag(vocabulary: &Vocabulary, d: &Mat<f64>, areas: &[f64]) -> Result<Vec<f64>, CliError> {
    let mut b = vocabulary.bag_of_features(d.as_ref(), areas).map_err(retrieval)?;
    let total: f64 = b.iter().sum();
    b.iter_mut().for_each(|x| *x /= total);
    Ok(b)
}

/// `wfem retrieval build|query`.
pub fn run(args: &RetrievalArgs, out: &mut dyn Write) -> Result<(), CliError> {
    match &args.action {
        RetrievalAction::Build {
            files,
            out: index_path,
            eigs,
            words,
            seed,
        } => {
            for f in files {
                check_output(f, index_path)?;
            }
            super::limits::retrieval_sizes(*eigs, *words)?;
            let times = default_times();
            let bar = super::progress::bar(files.len(), "describing shapes");
            let described = files
                .iter()
                .map(|f| {
                    let d = describe(&MeshArgs::new(f.clone()), *eigs, &times);
                    bar.inc(&f.display().to_string());
                    d
                })
                .collect::<Result<Vec<_>, _>>()?;
            bar.done();
            let rows: usize = described.iter().map(|(d, _)| d.nrows()).sum();
            let dim = times.len();
            let mut pooled = Mat::<f64>::zeros(rows, dim);
            let mut r0 = 0;
            for (d, _) in &described {
                for i in 0..d.nrows() {
                    for j in 0..dim {
                        pooled[(r0 + i, j)] = d[(i, j)];
                    }
                }
                r0 += d.nrows();
            }
            let vocabulary = Vocabulary::train(
                pooled.as_ref(),
                &VocabularyParams {
                    size: *words,
                    seed: *seed,
                    max_training_points: Some(50_000),
                    ..Default::default()
                },
            )
            .map_err(retrieval)?;
            let entries = files
                .iter()
                .zip(&described)
                .map(|(f, (d, a))| {
                    Ok(IndexEntry {
                        file: f.clone(),
                        bag: bag(&vocabulary, d, a)?,
                    })
                })
                .collect::<Result<Vec<_>, CliError>>()?;
            let w = vocabulary.words();
            let index = RetrievalIndex {
                descriptor: Descriptor::Dhk3.name().into(),
                eigenpairs: *eigs,
                times,
                words: (0..w.nrows())
                    .map(|i| (0..w.ncols()).map(|j| w[(i, j)]).collect())
                    .collect(),
                sigma: vocabulary.sigma(),
                entries,
            };
            let text = serde_json::to_string_pretty(&index).map_err(|e| CliError::Usage(e.to_string()))?;
            mesh_fem::io::write_atomic(index_path, |w| w.write_all(text.as_bytes()))?;
            writeln!(
                out,
                "indexed {} files ({} words) into {}",
                index.entries.len(),
                index.words.len(),
                index_path.display()
            )?;
        }
        RetrievalAction::Query { index, input, top } => {
            let text = super::read_text(index)?;
            let index: RetrievalIndex = serde_json::from_str(&text)
                .map_err(|e| CliError::Usage(format!("{} is not a wfem retrieval index: {e}", index.display())))?;
            let bags: Vec<&[f64]> = index.entries.iter().map(|e| e.bag.as_slice()).collect();
            super::limits::retrieval_index(index.eigenpairs, &index.times, &index.words, index.sigma, &bags)?;
            let dim = index.times.len();
            if index.words.iter().any(|w| w.len() != dim) {
                return Err(CliError::Usage("index words do not match its times".into()));
            }
            let words = Mat::from_fn(index.words.len(), dim, |i, j| index.words[i][j]);
            let vocabulary = Vocabulary::new(words, index.sigma).map_err(retrieval)?;
            let (d, a) = describe(input, index.eigenpairs, &index.times)?;
            let q = bag(&vocabulary, &d, &a)?;
            let mut ranked = index
                .entries
                .iter()
                .map(|e| Ok((l1_distance(&q, &e.bag).map_err(retrieval)?, &e.file)))
                .collect::<Result<Vec<_>, CliError>>()?;
            ranked.sort_by(|a, b| a.0.total_cmp(&b.0));
            for (rank, (dist, file)) in ranked.iter().take(*top).enumerate() {
                writeln!(out, "{}\t{dist:.6}\t{}", rank + 1, file.display())?;
            }
        }
    }
    Ok(())
}
