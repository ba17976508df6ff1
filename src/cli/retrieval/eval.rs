//! `wfem retrieval eval`: leave-one-out retrieval measures on labelled meshes.

use super::super::CliError;
use super::*;
use clap::Args;
use std::io::Write;
use std::path::PathBuf;

/// Arguments of `wfem retrieval eval`.
#[derive(Args, Clone, Debug)]
pub struct EvalArgs {
    /// Mesh files (with `--labels`: only these of the label file; default all of them).
    pub files: Vec<PathBuf>,
    /// Label file: one `file,class` per line (an optional `file,class` header).
    #[arg(long)]
    pub labels: Option<PathBuf>,
    /// Without `--labels`, a file's class is the folder holding it (`folder`, default) or
    /// its name without extension and digits (`stem`: cat10.off → cat).
    #[arg(long, conflicts_with = "labels", value_parser = choice::<ClassRule>())]
    pub class_from: Option<ClassRule>,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub vocab: VocabArg,
    /// Also write the report (with every query) as JSON.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Also save the index (SQLite, or JSON for `.json`).
    #[arg(long)]
    pub index: Option<PathBuf>,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub model: ModelArgs,
}

/// Runs `wfem retrieval eval`.
pub fn run(args: &EvalArgs, out: &mut dyn Write) -> Result<(), CliError> {
    let EvalArgs {
        files,
        labels,
        class_from,
        vocab,
        json,
        index,
        model,
    } = args;
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
        let text =
            serde_json::to_string_pretty(&run.report).map_err(|e| CliError::Usage(format!("{}: {e}", p.display())))?;
        mesh_fem::io::write_atomic(p, |w| w.write_all(text.as_bytes()))?;
    }
    if let Some(p) = index {
        index_file(p).save_index(&run.index)?;
    }
    write!(out, "{}", run.report.to_text())?;
    if vocab.is_none() {
        crate::cli::progress::note(
            "for an honest evaluation train a vocabulary on other shapes \
             (`wfem retrieval vocab OTHER... --out vocab.json`) and pass `--vocab vocab.json`",
        );
    }
    Ok(())
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
