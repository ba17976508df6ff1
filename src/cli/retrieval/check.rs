//! `wfem retrieval check INDEX [--upgrade]`: verifies every record of an index and reports
//! what is damaged (issue #41); `--upgrade` first adds checksums to an index written before
//! they existed.

use super::super::CliError;
use clap::Args;
use retrieval_store::index::SqliteIndex;
use shape_retrieval::store::{IndexStore, JsonFile};
use std::io::Write;
use std::path::Path;
use std::path::PathBuf;

/// Checks (and with `upgrade`, first upgrades) the index at `path`; prints one line per
/// damaged record and a summary. Exit status: 0 verified, 1 damaged ([`CliError::Damaged`]),
/// [`super::super::EXIT_UNCHECKED`] for an index without checksums that showed no damage.
pub fn check(path: &Path, upgrade: bool, out: &mut dyn Write) -> Result<(), CliError> {
    if !super::is_sqlite(path)? {
        if upgrade {
            return Err(CliError::Usage(format!(
                "--upgrade adds checksums to a SQLite index; {} is a JSON index, which has none: build a SQLite \
                 index instead (--out INDEX.sqlite)",
                path.display()
            )));
        }
        // Reading a JSON index validates all of it; there is nothing to verify it against.
        let index = JsonFile::new(path).load_index()?;
        writeln!(
            out,
            "{}: a JSON index of {} shapes: read and validated",
            path.display(),
            index.entries().len()
        )?;
        return Err(CliError::Unchecked {
            path: path.to_path_buf(),
            why: "a JSON index has no checksums (a SQLite index has: --out INDEX.sqlite)".into(),
        });
    }
    let index = SqliteIndex::new(path);
    if upgrade {
        let before = index.check()?;
        if before.checksums {
            writeln!(
                out,
                "{}: has checksums already (format version {})",
                path.display(),
                before.version
            )?;
        } else if before.damage.is_empty() {
            index.upgrade()?;
            writeln!(
                out,
                "{}: upgraded from format version {} to {}: checksums added",
                path.display(),
                before.version,
                retrieval_store::FORMAT_VERSION
            )?;
        }
    }
    let report = index.check()?;
    write!(out, "{}", report.to_text())?;
    if !report.damage.is_empty() {
        return Err(CliError::Damaged {
            path: path.to_path_buf(),
            damaged: report.damage.len(),
        });
    }
    if !report.checksums {
        return Err(CliError::Unchecked {
            path: path.to_path_buf(),
            why: format!(
                "format version {} has no checksums (`wfem retrieval check --upgrade {}` adds them)",
                report.version,
                path.display()
            ),
        });
    }
    Ok(())
}

/// Arguments of `wfem retrieval check`.
#[derive(Args, Clone, Debug)]
pub struct CheckArgs {
    /// Index file written by `wfem retrieval build`.
    pub index: PathBuf,
    /// First add checksums to an index written before they existed (format version 1;
    /// refused if anything is found damaged).
    #[arg(long)]
    pub upgrade: bool,
}
