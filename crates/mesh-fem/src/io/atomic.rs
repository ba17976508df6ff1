//! Atomic output: one file ([`write_atomic`]) or a set of files replaced all-or-nothing
//! ([`AtomicSet`]). This is the one writer every output of the workspace goes through.
//!
//! Each file is first written in full to a hidden temporary file beside its target
//! (`.NAME.tmp-PID-N`, same directory so that the final rename is atomic), flushed and fsynced;
//! only when every file of the set is written are they renamed onto their targets. A failure
//! (disk full, a target that is a directory, an error from the caller's writer) removes the
//! temporary files and leaves every target as it was. The temporary files are
//! [`wfem_base::tempfiles::TempPath`]s: a program ending on a signal removes them (and never
//! between two renames of a set), and a killed one's are removed by the next writer of the
//! same target.

use super::io_error;
use crate::MeshError;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use wfem_base::tempfiles::{self, TempPath};

/// Writes a file atomically: `write` fills a temporary file in the same directory, which is
/// flushed, fsynced and renamed onto `path`. If `write` (or any step) fails, the temporary
/// file is removed and `path` is left as it was (absent, or with its old content).
///
/// # Errors
/// [`MeshError::Io`] naming `path` for any failure, including an error returned by `write`.
pub fn write_atomic(path: &Path, write: impl FnOnce(&mut dyn Write) -> std::io::Result<()>) -> Result<(), MeshError> {
    let mut set = AtomicSet::new();
    set.stage(path, write)?;
    set.commit()
}

/// A set of output files written all-or-nothing.
///
/// ```
/// use mesh_fem::io::AtomicSet;
/// let dir = std::env::temp_dir().join(format!("mesh-fem-atomic-doc-{}", std::process::id()));
/// std::fs::create_dir_all(&dir)?;
/// let mut set = AtomicSet::new();
/// set.stage(&dir.join("a.txt"), |w| w.write_all(b"first"))?;
/// set.stage(&dir.join("b.txt"), |w| w.write_all(b"second"))?;
/// set.commit()?; // both files appear together, or neither changes
/// assert_eq!(std::fs::read(dir.join("b.txt"))?, b"second");
/// # std::fs::remove_dir_all(&dir)?;
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// Dropping a set without [`AtomicSet::commit`] removes its staged files.
#[derive(Debug, Default)]
pub struct AtomicSet {
    /// (temporary file, target) pairs, in staging order.
    staged: Vec<(TempPath, PathBuf)>,
}

impl AtomicSet {
    /// An empty set.
    pub fn new() -> Self {
        Self::default()
    }

    /// The targets staged so far.
    pub fn targets(&self) -> impl Iterator<Item = &Path> {
        self.staged.iter().map(|(_, target)| target.as_path())
    }

    /// Writes `fill` to a temporary file beside `path` (flushed and fsynced); the target is
    /// replaced only by [`Self::commit`].
    ///
    /// # Errors
    /// [`MeshError::Io`] naming `path` if the path names no file, the folder is not writable, a
    /// write fails or `fill` returns an error; [`MeshError::Invalid`] if `path` is already part
    /// of this set (two outputs would collide). On error the set keeps its earlier files.
    pub fn stage(
        &mut self,
        path: &Path,
        fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
    ) -> Result<(), MeshError> {
        if self.staged.iter().any(|(_, target)| same_file(target, path)) {
            return Err(MeshError::Invalid {
                reason: format!("two outputs would be written to the same file {}", path.display()),
            });
        }
        let (tmp, file) = TempPath::file(path).map_err(|e| io_error(path, e))?;
        let result = (|| -> std::io::Result<()> {
            let mut w = BufWriter::new(file);
            fill(&mut w)?;
            let file = w.into_inner().map_err(|e| e.into_error())?;
            file.sync_all()
        })();
        match result {
            Ok(()) => {
                self.staged.push((tmp, path.to_path_buf()));
                Ok(())
            }
            // Dropping `tmp` removes the temporary file.
            Err(e) => Err(io_error(path, e)),
        }
    }

    /// Renames every staged file onto its target, after checking that no target is a
    /// directory (the only common reason for a rename to fail once the data is written), so
    /// that the set is replaced as a whole or not at all.
    ///
    /// # Errors
    /// [`MeshError::Io`] naming the target that could not be replaced; the staged files are
    /// removed.
    pub fn commit(mut self) -> Result<(), MeshError> {
        // Dropping `staged` removes every temporary file that was not renamed.
        let staged = std::mem::take(&mut self.staged);
        if let Some((_, target)) = staged.iter().find(|(_, target)| target.is_dir()) {
            return Err(io_error(
                target,
                std::io::Error::new(std::io::ErrorKind::IsADirectory, "the output path is a directory"),
            ));
        }
        // A signal's cleanup runs before or after the renames, never between: every target is
        // its old file or its new one, as a set.
        tempfiles::while_locked(|| {
            for (tmp, target) in &staged {
                std::fs::rename(tmp.path(), target).map_err(|e| io_error(target, e))?;
            }
            Ok::<(), MeshError>(())
        })?;
        // Make the renames durable where the platform allows syncing a directory.
        #[cfg(unix)]
        for (_, target) in &staged {
            if let Ok(d) = File::open(parent_dir(target)) {
                let _ = d.sync_all();
            }
        }
        Ok(())
    }
}

/// The folder a path lives in (`.` for a bare file name).
pub(crate) fn parent_dir(path: &Path) -> PathBuf {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// Whether two output paths name the same file (compared after resolving their folders, so
/// `x.png` and `./x.png` collide).
fn same_file(a: &Path, b: &Path) -> bool {
    let resolve = |p: &Path| {
        let dir = parent_dir(p);
        let dir = dir.canonicalize().unwrap_or(dir);
        dir.join(p.file_name().unwrap_or_default())
    };
    a == b || resolve(a) == resolve(b)
}
