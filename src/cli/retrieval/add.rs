//! `wfem retrieval add`: appends meshes to a SQLite index without rebuilding it.

use super::super::CliError;
use super::*;
use clap::Args;
use std::io::Write;
use std::path::PathBuf;

/// Arguments of `wfem retrieval add`.
#[derive(Args, Clone, Debug)]
pub struct AddArgs {
    /// Index file written by `wfem retrieval build` (SQLite).
    pub index: PathBuf,
    /// Mesh or point-cloud files to add (names must be new to the index).
    #[arg(required = true, num_args = 1..)]
    pub files: Vec<PathBuf>,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub strict: StrictArg,
}

/// Runs `wfem retrieval add`.
pub fn run(args: &AddArgs, out: &mut dyn Write) -> Result<(), CliError> {
    let AddArgs {
        index: path,
        files,
        strict,
    } = args;
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
    let bar = crate::cli::progress::bar(meshes.len(), "describing shapes");
    let described =
        shape_retrieval::collection::describe_entries(&settings, &meshes, refused.tolerance(), &|name| bar.inc(name));
    bar.done();
    let (entries, left_out) = described?;
    refused.extend(left_out);
    refused.check_some(entries.len(), files.len())?;
    store.append(&settings, &entries)?;
    writeln!(
        out,
        "added {} to {}",
        crate::cli::input::count_of(entries.len(), "file", "files"),
        path.display()
    )?;
    refused.report(files.len(), "the others were added")?;
    Ok(())
}
