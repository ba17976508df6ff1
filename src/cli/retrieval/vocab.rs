//! `wfem retrieval vocab`: trains a vocabulary on meshes and saves it.

use super::super::CliError;
use super::*;
use clap::Args;
use std::io::Write;
use std::path::PathBuf;

/// Arguments of `wfem retrieval vocab`.
#[derive(Args, Clone, Debug)]
pub struct VocabArgs {
    /// Training meshes or point clouds.
    #[arg(required = true, num_args = 1..)]
    pub files: Vec<PathBuf>,
    /// Vocabulary file (JSON).
    #[arg(long)]
    pub out: PathBuf,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub descriptor: DescriptorArgs,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub training: TrainingArgs,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub strict: StrictArg,
}

/// Runs `wfem retrieval vocab`.
pub fn run(args: &VocabArgs, out: &mut dyn Write) -> Result<(), CliError> {
    let VocabArgs {
        files,
        out: path,
        descriptor,
        training,
        strict,
    } = args;
    let mut settings = RetrievalSettings::default();
    crate::cli::limits::retrieval_sizes(descriptor.eigs, training.words)?;
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
        crate::cli::input::count_of(features.len(), "shape", "shapes"),
        vocabulary.info().descriptors,
        path.display()
    )?;
    refused.report(files.len(), "the vocabulary was trained")?;
    Ok(())
}
