//! The one check before an index (or vocabulary) file is written: the path is a regular file
//! or absent, it is none of the inputs, and an existing file is replaced only when asked.
//! `wfem retrieval build` (`--force`) and Python's `RetrievalIndex.build` (`overwrite=True`)
//! both call it, so a mistyped command cannot replace an index or an input mesh.

use crate::RetrievalError;
use std::path::Path;

fn storage(path: &Path, reason: impl Into<String>) -> RetrievalError {
    RetrievalError::Storage {
        path: path.to_path_buf(),
        reason: reason.into(),
    }
}

/// Whether `a` and `b` name the same existing file (same device and inode on Unix, same
/// canonical path elsewhere).
fn same_file(a: &Path, b: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        if let (Ok(x), Ok(y)) = (std::fs::metadata(a), std::fs::metadata(b)) {
            return x.dev() == y.dev() && x.ino() == y.ino();
        }
        false
    }
    #[cfg(not(unix))]
    {
        matches!((a.canonicalize(), b.canonicalize()), (Ok(x), Ok(y)) if x == y)
    }
}

/// Checks that an index may be written to `out`.
///
/// # Errors
/// [`RetrievalError::Storage`] naming `out` when it is a directory, FIFO or other non-regular
/// file; when it is one of `inputs` (a mesh or vocabulary being read); when it exists and
/// `overwrite` is false.
pub fn check_index_output(out: &Path, inputs: &[&Path], overwrite: bool) -> Result<(), RetrievalError> {
    if let Some(input) = inputs.iter().find(|i| same_file(out, i)) {
        return Err(storage(
            out,
            format!(
                "is also an input file ({}); an index is never written over its inputs",
                input.display()
            ),
        ));
    }
    match std::fs::symlink_metadata(out).and_then(|m| {
        if m.file_type().is_symlink() {
            std::fs::metadata(out)
        } else {
            Ok(m)
        }
    }) {
        Ok(m) if !m.is_file() => Err(storage(
            out,
            if m.is_dir() {
                "is a directory; an index is a regular file".to_string()
            } else {
                "exists and is not a regular file (a FIFO, socket or device); an index is a regular file".to_string()
            },
        )),
        Ok(_) if !overwrite => Err(storage(
            out,
            "already exists; replace it only on purpose (`--force` on the command line, `overwrite=True` in Python)",
        )),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refuses_existing_inputs_and_non_regular_files() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("index.sqlite");
        assert!(check_index_output(&file, &[], false).is_ok());
        std::fs::write(&file, b"x").unwrap();
        let e = check_index_output(&file, &[], false).unwrap_err().to_string();
        assert!(e.contains("already exists"), "{e}");
        assert!(check_index_output(&file, &[], true).is_ok());
        let e = check_index_output(&file, &[&file], true).unwrap_err().to_string();
        assert!(e.contains("is also an input file"), "{e}");
        let e = check_index_output(dir.path(), &[], true).unwrap_err().to_string();
        assert!(e.contains("is a directory"), "{e}");
    }
}
