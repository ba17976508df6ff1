//! `wfem retrieval build`: indexes meshes (a vocabulary trained on them, or `--vocab`).

use super::super::CliError;
use super::*;
use clap::Args;
use std::io::Write;
use std::path::PathBuf;

/// Arguments of `wfem retrieval build`.
#[derive(Args, Clone, Debug)]
pub struct BuildArgs {
    /// Mesh or point-cloud files to index.
    #[arg(required = true, num_args = 1..)]
    pub files: Vec<PathBuf>,
    /// Index file: an embedded SQLite file (any extension, e.g. `index.sqlite`; queries scan
    /// it in parallel and `add` appends to it), or one JSON document (`.json`).
    #[arg(long)]
    pub out: PathBuf,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub vocab: VocabArg,
    /// Replace `--out` if it exists (without it an existing index is never overwritten).
    #[arg(long)]
    pub force: bool,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub model: ModelArgs,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub strict: StrictArg,
}

/// Runs `wfem retrieval build`.
pub fn run(args: &BuildArgs, out: &mut dyn Write) -> Result<(), CliError> {
    let BuildArgs {
        files,
        out: path,
        vocab,
        force,
        model,
        strict,
    } = args;
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
        None => crate::cli::progress::run("training the vocabulary", || {
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
        crate::cli::input::count_of(index.entries().len(), "file", "files"),
        clouds_among(&meshes, &features),
        index.vocabulary().descriptor().descriptor.label(),
        index.vocabulary().vocabulary().size(),
        index.bags().distance.name(),
        path.display()
    )?;
    refused.report(files.len(), "the index was built")?;
    Ok(())
}
