//! The store: its public types and the helpers its parts share. One module per concern:
//! `open` (schema, creation, checks on open, connections), `append` (metadata, appends, the
//! replace lock), `read` (metadata, shapes, vectors), `scan` (the parallel top-k),
//! `integrity` (checksums, the full check, the upgrade of version 1 files).

mod append;
mod integrity;
mod open;
mod read;
mod scan;

use open::connect;
use scan::{read_chunk, Layout};

use crate::metric::Metric;
use crate::StoreError;
use rayon::prelude::*;
use rusqlite::{params, Connection, OpenFlags, OptionalExtension, TransactionBehavior};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Duration;
use wfem_base::tempfiles::{self, TempPath};

/// The value of the `format` metadata key of every store.
pub const FORMAT: &str = "wfem-retrieval-store";
/// The schema version this build writes: 2, every record with its checksum
/// ([`crate::check`]). Version 1 files (no checksums) are read as unchecked and not written.
pub const FORMAT_VERSION: u32 = 2;
/// The format before checksums.
const LEGACY_VERSION: u32 = 1;
/// Shapes per chunk by default: 4096 bags of 48 words are 768 KiB, large enough that the scan
/// is a sequence of long reads and small enough that appending to the last chunk is cheap.
pub const DEFAULT_CHUNK_ROWS: usize = 4096;

/// Reserved metadata keys (written by [`Store::create`], refused by [`Store::set_meta`]).
const RESERVED: [&str; 4] = ["format", "version", "dimension", "chunk_rows"];

/// Largest vector length a store accepts (4 MiB of f32 per shape; a retrieval index needs
/// its words plus the global eigenvalues, at most 66,536). Checked on create and on open, so a
/// tampered `dimension` cannot size an allocation.
pub const MAX_DIMENSION: usize = 1 << 20;
/// Largest chunk, in bytes (`chunk_rows × dimension × 4`): a chunk is read whole by the scan.
pub const MAX_CHUNK_BYTES: usize = 256 << 20;

/// How long a connection waits for a lock held by another writer before giving up.
const BUSY_TIMEOUT: Duration = Duration::from_secs(30);

/// Options of [`Store::create`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StoreParams {
    /// Length of every stored vector (≥ 1).
    pub dimension: usize,
    /// Shapes per chunk (≥ 1; default [`DEFAULT_CHUNK_ROWS`]).
    pub chunk_rows: usize,
}

impl StoreParams {
    /// Vectors of `dimension` values in chunks of [`DEFAULT_CHUNK_ROWS`].
    pub fn new(dimension: usize) -> Self {
        Self {
            dimension,
            chunk_rows: DEFAULT_CHUNK_ROWS,
        }
    }

    /// The sizes are in range: `dimension` in 1..=[`MAX_DIMENSION`], `chunk_rows` ≥ 1 and one
    /// chunk within [`MAX_CHUNK_BYTES`]; on failure, the parameter and the reason.
    fn check(&self) -> Result<(), (&'static str, String)> {
        if !(1..=MAX_DIMENSION).contains(&self.dimension) {
            return Err(("dimension", format!("{} is not in 1..={MAX_DIMENSION}", self.dimension)));
        }
        if self.chunk_rows == 0 {
            return Err(("chunk_rows", "must be at least 1".into()));
        }
        let bytes = self.chunk_rows.saturating_mul(self.dimension * 4);
        if bytes > MAX_CHUNK_BYTES {
            return Err((
                "chunk_rows",
                format!(
                    "{} rows of {} values make a chunk of {bytes} bytes (at most {MAX_CHUNK_BYTES}); use at most {} rows",
                    self.chunk_rows,
                    self.dimension,
                    MAX_CHUNK_BYTES / (self.dimension * 4)
                ),
            ));
        }
        Ok(())
    }
}

/// One shape to add: a unique non-empty name, free-form text, its vector.
#[derive(Clone, Copy, Debug)]
pub struct Entry<'a> {
    /// Unique name (e.g. the mesh path as given).
    pub name: &'a str,
    /// Free-form text stored with the shape (e.g. JSON with its class); may be empty.
    pub info: &'a str,
    /// The vector, of the store's dimension, finite and within the range of `f32`.
    pub vector: &'a [f64],
}

impl<'a> Entry<'a> {
    /// An entry.
    pub fn new(name: &'a str, info: &'a str, vector: &'a [f64]) -> Self {
        Self { name, info, vector }
    }
}

/// A stored shape without its vector.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ShapeRow {
    /// Id: its position in insertion order, from 0.
    pub id: u64,
    /// Its unique name.
    pub name: String,
    /// Its free-form text.
    pub info: String,
}

/// One result of a search.
#[derive(Clone, Debug, PartialEq)]
pub struct Hit {
    /// Shape id.
    pub id: u64,
    /// Shape name.
    pub name: String,
    /// Its free-form text.
    pub info: String,
    /// Distance to the query.
    pub distance: f64,
}

/// The write lock of a store being replaced ([`Store::lock_for_replace`]); released on drop.
#[cfg(feature = "index")]
pub(crate) struct ReplaceLock(Connection);

#[cfg(feature = "index")]
impl Drop for ReplaceLock {
    fn drop(&mut self) {
        let _ = self.0.execute_batch("ROLLBACK");
    }
}

/// An open store (one SQLite connection; see the crate documentation).
#[derive(Debug)]
pub struct Store {
    conn: Connection,
    path: PathBuf,
    dimension: usize,
    chunk_rows: usize,
    read_only: bool,
    /// Whether the records carry checksums (format version 2).
    checksums: bool,
    /// The file opened (device and inode), to detect a store replaced under an open writer.
    identity: Option<(u64, u64)>,
}

/// Device and inode of the file at `path` (None where the platform has none, or on error).
fn file_identity(path: &Path) -> Option<(u64, u64)> {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        std::fs::metadata(path).ok().map(|m| (m.dev(), m.ino()))
    }
    #[cfg(not(unix))]
    {
        let _ = path;
        None
    }
}

/// `path` must be absent (Ok(false)) or a regular file (Ok(true)); a directory, FIFO, socket
/// or device is refused ([`StoreError::NotAFile`]).
pub(crate) fn regular_or_absent(path: &Path) -> Result<bool, StoreError> {
    match std::fs::metadata(path) {
        Ok(m) if m.is_file() => Ok(true),
        Ok(m) => Err(StoreError::NotAFile {
            path: path.to_path_buf(),
            kind: wfem_base::fs::file_kind(&m.file_type()),
        }),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(false),
        Err(source) => Err(StoreError::Io {
            path: path.to_path_buf(),
            source,
        }),
    }
}

fn wal_path(path: &Path) -> PathBuf {
    let mut s = path.as_os_str().to_owned();
    s.push("-wal");
    PathBuf::from(s)
}

fn shm_path(path: &Path) -> PathBuf {
    let mut s = path.as_os_str().to_owned();
    s.push("-shm");
    PathBuf::from(s)
}

impl Store {
    fn sql(&self) -> impl Fn(rusqlite::Error) -> StoreError + '_ {
        |source| sqlite_error(&self.path, source)
    }

    /// The file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Length of every vector.
    pub fn dimension(&self) -> usize {
        self.dimension
    }

    /// Shapes per chunk.
    pub fn chunk_rows(&self) -> usize {
        self.chunk_rows
    }

    /// Whether every record carries a checksum that reads verify (format version 2); false
    /// for a version 1 file, read unchecked (see [`Store::upgrade`]).
    pub fn checksummed(&self) -> bool {
        self.checksums
    }

    /// Number of shapes (committed, as seen by this connection).
    ///
    /// # Errors
    /// [`StoreError::Sqlite`].
    pub fn len(&self) -> Result<usize, StoreError> {
        let n: i64 = self
            .conn
            .query_row("SELECT COALESCE(MAX(id) + 1, 0) FROM shapes", [], |r| r.get(0))
            .map_err(self.sql())?;
        Ok(n as usize)
    }

    /// Whether the store holds no shape.
    ///
    /// # Errors
    /// [`StoreError::Sqlite`].
    pub fn is_empty(&self) -> Result<bool, StoreError> {
        Ok(self.len()? == 0)
    }
}

/// A write transaction on the store at `path`: it takes the write lock at once (waiting up to
/// the busy timeout), not at its first write.
fn begin_write<'c>(conn: &'c mut Connection, path: &Path) -> Result<rusqlite::Transaction<'c>, StoreError> {
    conn.transaction_with_behavior(TransactionBehavior::Immediate)
        .map_err(|source| sqlite_error(path, source))
}

/// An SQLite error on `path`; "file is not a database" becomes [`StoreError::NotAStore`].
fn sqlite_error(path: &Path, source: rusqlite::Error) -> StoreError {
    match source {
        rusqlite::Error::SqliteFailure(f, _) if f.code == rusqlite::ErrorCode::NotADatabase => StoreError::NotAStore {
            path: path.to_path_buf(),
            reason: "not an SQLite database".into(),
        },
        source => StoreError::Sqlite {
            path: path.to_path_buf(),
            source,
        },
    }
}
