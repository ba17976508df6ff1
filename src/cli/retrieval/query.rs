//! `wfem retrieval query`: the indexed shapes nearest to a query mesh or an indexed shape.

use super::super::{CliError, MeshArgs};
use super::*;
use clap::Args;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Arguments of `wfem retrieval query`.
#[derive(Args, Clone, Debug)]
pub struct QueryArgs {
    /// Index file written by `wfem retrieval build` (SQLite or JSON).
    pub index: PathBuf,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub input: Option<MeshArgs>,
    /// Query by an indexed shape instead of a mesh: NAME as `build` stored it, or its file
    /// name or stem. The others are ranked from its stored signature, nothing read or
    /// described (the shape itself is left out of the results).
    #[arg(long, value_name = "NAME", conflicts_with_all = ["mesh_file", "laplacian", "triangulate", "repair", "weld_tolerance"])]
    pub id: Option<String>,
    /// Number of results.
    #[arg(long, default_value_t = DEFAULT_TOP)]
    pub top: usize,
}

/// Runs `wfem retrieval query`.
pub fn run(args: &QueryArgs, out: &mut dyn Write) -> Result<(), CliError> {
    let QueryArgs {
        index: path,
        input,
        id,
        top,
    } = args;
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
    Ok(())
}

/// Results a query shows unless told otherwise (a screenful; the library's and Python's
/// default is [`shape_retrieval::model::DEFAULT_RESULTS`]).
const DEFAULT_TOP: usize = 5;

/// `wfem retrieval query INDEX MESH`: the `top` indexed shapes nearest to the query mesh, as
/// (distance, name).
fn query_by_mesh(path: &Path, input: &MeshArgs, top: usize) -> Result<Vec<(f64, String)>, CliError> {
    Ok(if is_sqlite(path)? {
        let store = SqliteIndex::new(path);
        let (settings, rows) = store.open()?;
        stored_sizes(&settings)?;
        note_unchecked(&rows);
        let query = read_query(input, &settings)?;
        let query = crate::cli::progress::run("describing the query", || {
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
        let query = crate::cli::progress::run("describing the query", || {
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
        crate::cli::progress::note(&format!(
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
fn read_query(input: &MeshArgs, index: &RetrievalIndex) -> Result<crate::cli::input::Input, CliError> {
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
    crate::cli::input::read_usable(&MeshArgs {
        laplacian: Some(recorded),
        ..input.clone()
    })
}
