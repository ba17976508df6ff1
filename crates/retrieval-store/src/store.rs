//! The store: schema, creation, appends, reads and the parallel scan.

use crate::metric::Metric;
use crate::StoreError;
use rayon::prelude::*;
use rusqlite::{params, Connection, OpenFlags, OptionalExtension, TransactionBehavior, MAIN_DB};
use std::io::Read;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Duration;

/// The value of the `format` metadata key of every store.
pub const FORMAT: &str = "wfem-retrieval-store";
/// The schema version this build reads and writes.
pub const FORMAT_VERSION: u32 = 1;
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

    /// Creates a new, empty store at `path`.
    ///
    /// The file is built under a temporary name in the same directory and renamed into place,
    /// so `path` never holds a half-created store. With `overwrite`, an existing store is
    /// replaced atomically (readers that have it open keep reading the old one), unless its
    /// write-ahead log is not empty ([`StoreError::InUse`]).
    ///
    /// # Errors
    /// [`StoreError::InvalidParameter`] for sizes out of range ([`MAX_DIMENSION`],
    /// [`MAX_CHUNK_BYTES`]); [`StoreError::NotAFile`] for a directory, FIFO, …;
    /// [`StoreError::Exists`]; [`StoreError::InUse`]; [`StoreError::Io`], [`StoreError::Sqlite`].
    pub fn create(path: &Path, params: &StoreParams, overwrite: bool) -> Result<Self, StoreError> {
        params
            .check()
            .map_err(|(name, reason)| StoreError::InvalidParameter { name, reason })?;
        if regular_or_absent(path)? {
            if !overwrite {
                return Err(StoreError::Exists { path: path.into() });
            }
            // A stale log would be replayed into the new file by the next opener.
            let wal = wal_path(path);
            if std::fs::metadata(&wal).map(|m| m.len() > 0).unwrap_or(false) {
                return Err(StoreError::InUse { path: path.into(), wal });
            }
        }
        let dir = match path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => PathBuf::from("."),
        };
        let file_name = path
            .file_name()
            .map(|s| s.to_string_lossy().into_owned())
            .ok_or_else(|| StoreError::InvalidParameter {
                name: "path",
                reason: format!("{} has no file name", path.display()),
            })?;
        let tmp = dir.join(format!(".{file_name}.{}.tmp", std::process::id()));
        let result = Self::write_empty(&tmp, params).and_then(|()| {
            std::fs::rename(&tmp, path).map_err(|source| StoreError::Io {
                path: path.into(),
                source,
            })
        });
        if result.is_err() {
            let _ = std::fs::remove_file(&tmp);
            let _ = std::fs::remove_file(wal_path(&tmp));
            let _ = std::fs::remove_file(shm_path(&tmp));
        }
        result?;
        // The replaced file's shared-memory index must not describe the new one.
        let _ = std::fs::remove_file(shm_path(path));
        Self::open(path)
    }

    fn write_empty(tmp: &Path, params: &StoreParams) -> Result<(), StoreError> {
        let sql = |source| sqlite_error(tmp, source);
        let _ = std::fs::remove_file(tmp);
        let mut conn = Connection::open(tmp).map_err(sql)?;
        // 64 KiB pages: a chunk blob spans a dozen overflow pages instead of two hundred.
        conn.pragma_update(None, "page_size", 65536).map_err(sql)?;
        conn.pragma_update(None, "journal_mode", "WAL").map_err(sql)?;
        conn.pragma_update(None, "synchronous", "FULL").map_err(sql)?;
        let tx = conn.transaction().map_err(sql)?;
        tx.execute_batch(
            "CREATE TABLE meta (key TEXT PRIMARY KEY NOT NULL, value BLOB NOT NULL) WITHOUT ROWID;
             CREATE TABLE shapes (id INTEGER PRIMARY KEY, name TEXT NOT NULL UNIQUE, info TEXT NOT NULL);
             CREATE TABLE chunks (chunk INTEGER PRIMARY KEY, rows INTEGER NOT NULL, data BLOB NOT NULL);",
        )
        .map_err(sql)?;
        for (key, value) in [
            ("format", FORMAT.to_string()),
            ("version", FORMAT_VERSION.to_string()),
            ("dimension", params.dimension.to_string()),
            ("chunk_rows", params.chunk_rows.to_string()),
        ] {
            tx.execute(
                "INSERT INTO meta (key, value) VALUES (?1, ?2)",
                params![key, value.as_bytes()],
            )
            .map_err(sql)?;
        }
        tx.commit().map_err(sql)?;
        // Leave a self-contained file (empty log) before it is renamed into place.
        conn.execute_batch("PRAGMA wal_checkpoint(TRUNCATE);").map_err(sql)?;
        conn.close().map_err(|(_, e)| sql(e))?;
        Ok(())
    }

    /// Opens an existing store for reading and appending.
    ///
    /// # Errors
    /// [`StoreError::NotAStore`], [`StoreError::UnsupportedVersion`], [`StoreError::Corrupt`],
    /// [`StoreError::Sqlite`] (missing file, locked, not SQLite).
    pub fn open(path: &Path) -> Result<Self, StoreError> {
        Self::open_with(path, false)
    }

    /// Opens an existing store read-only (any number of readers, concurrently with a writer).
    ///
    /// # Errors
    /// As [`Store::open`].
    pub fn open_readonly(path: &Path) -> Result<Self, StoreError> {
        Self::open_with(path, true)
    }

    fn open_with(path: &Path, read_only: bool) -> Result<Self, StoreError> {
        let conn = connect(path, read_only)?;
        let mut store = Self {
            conn,
            path: path.to_path_buf(),
            dimension: 0,
            chunk_rows: 0,
            read_only,
            identity: file_identity(path),
        };
        let not_a_store = |reason: String| StoreError::NotAStore {
            path: path.to_path_buf(),
            reason,
        };
        let has_meta: bool = store
            .conn
            .query_row(
                "SELECT COUNT(*) FROM sqlite_master WHERE type = 'table' AND name IN ('meta', 'shapes', 'chunks')",
                [],
                |r| r.get::<_, i64>(0),
            )
            .map_err(|e| sqlite_error(path, e))?
            == 3;
        if !has_meta {
            return Err(not_a_store("the tables meta, shapes and chunks are missing".into()));
        }
        let text = |key: &str| -> Result<String, StoreError> {
            let v = store
                .meta(key)?
                .ok_or_else(|| not_a_store(format!("no {key:?} entry")))?;
            String::from_utf8(v).map_err(|_| not_a_store(format!("the {key:?} entry is not text")))
        };
        let format = text("format")?;
        if format != FORMAT {
            return Err(not_a_store(format!("format {format:?}, expected {FORMAT:?}")));
        }
        let number = |key: &str| -> Result<usize, StoreError> {
            let t = text(key)?;
            t.parse::<usize>()
                .map_err(|_| not_a_store(format!("{key} = {t:?} is not a number")))
        };
        let version = number("version")?;
        if version != FORMAT_VERSION as usize {
            return Err(StoreError::UnsupportedVersion {
                path: path.to_path_buf(),
                found: u32::try_from(version).unwrap_or(u32::MAX),
                supported: FORMAT_VERSION,
            });
        }
        let (dimension, chunk_rows) = (number("dimension")?, number("chunk_rows")?);
        store.dimension = dimension;
        store.chunk_rows = chunk_rows;
        StoreParams { dimension, chunk_rows }
            .check()
            .map_err(|(name, reason)| StoreError::Corrupt {
                path: path.to_path_buf(),
                reason: format!("{name}: {reason}"),
            })?;
        store.check_counts()?;
        Ok(store)
    }

    /// The ids must be 0..n, the chunks 0, 1, … hold exactly n rows (full but the last), and
    /// every chunk blob is exactly `rows × dimension × 4` bytes (a `dimension` edited to 47
    /// over 48-wide blobs is refused, not read misaligned). Cheap: the chunk table and rowid
    /// bounds, not the blobs' contents.
    fn check_counts(&self) -> Result<(), StoreError> {
        let corrupt = |reason: String| StoreError::Corrupt {
            path: self.path.clone(),
            reason,
        };
        // One read transaction, so one snapshot: queries could otherwise straddle a writer's
        // commit (a reader opened during appends saw 50 ids but 100 rows and called the file
        // corrupt).
        let tx = self.conn.unchecked_transaction().map_err(self.sql())?;
        let (shapes, min_id): (i64, i64) = tx
            .query_row(
                "SELECT COALESCE(MAX(id) + 1, 0), COALESCE(MIN(id), 0) FROM shapes",
                [],
                |r| Ok((r.get(0)?, r.get(1)?)),
            )
            .map_err(self.sql())?;
        let mut stmt = tx
            .prepare("SELECT chunk, rows, length(data), typeof(data) FROM chunks ORDER BY chunk")
            .map_err(self.sql())?;
        let chunks = stmt
            .query_map([], |r| {
                Ok((
                    r.get::<_, i64>(0)?,
                    r.get::<_, i64>(1)?,
                    r.get::<_, i64>(2)?,
                    r.get::<_, String>(3)?,
                ))
            })
            .map_err(self.sql())?
            .collect::<Result<Vec<_>, _>>()
            .map_err(self.sql())?;
        let expected_chunks = (shapes.max(0) as usize).div_ceil(self.chunk_rows);
        let rows: i64 = chunks.iter().map(|c| c.1.max(0)).sum();
        if min_id != 0 || rows != shapes || chunks.len() != expected_chunks {
            return Err(corrupt(format!(
                "{shapes} shape ids (lowest {min_id}) but {rows} vector rows in {} chunks",
                chunks.len()
            )));
        }
        let last = chunks.len().saturating_sub(1);
        for (i, (chunk, rows, bytes, kind)) in chunks.iter().enumerate() {
            let full = i < last;
            let rows_ok = if full {
                *rows == self.chunk_rows as i64
            } else {
                (1..=self.chunk_rows as i64).contains(rows)
            };
            if *chunk != i as i64 || !rows_ok {
                return Err(corrupt(format!(
                    "chunk {chunk} (position {i}) holds {rows} rows of {} per chunk",
                    self.chunk_rows
                )));
            }
            let expected = rows * self.dimension as i64 * 4;
            if kind != "blob" || *bytes != expected {
                return Err(corrupt(format!(
                    "chunk {chunk} has {bytes} bytes ({kind}), but {rows} vectors of {} values need {expected}",
                    self.dimension
                )));
            }
        }
        Ok(())
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

    /// The metadata value of `key`, if any.
    ///
    /// # Errors
    /// [`StoreError::Sqlite`].
    pub fn meta(&self, key: &str) -> Result<Option<Vec<u8>>, StoreError> {
        self.conn
            .query_row("SELECT value FROM meta WHERE key = ?1", [key], |r| r.get(0))
            .optional()
            .map_err(self.sql())
    }

    /// Sets (inserts or replaces) a metadata value, in its own transaction.
    ///
    /// # Errors
    /// [`StoreError::InvalidParameter`] for a reserved key (`format`, `version`, `dimension`,
    /// `chunk_rows`) or a read-only store; [`StoreError::Sqlite`].
    pub fn set_meta(&mut self, key: &str, value: &[u8]) -> Result<(), StoreError> {
        self.writable()?;
        if RESERVED.contains(&key) {
            return Err(StoreError::InvalidParameter {
                name: "key",
                reason: format!("{key:?} is reserved by the store"),
            });
        }
        let path = self.path.clone();
        let sql = |source| sqlite_error(&path, source);
        let tx = begin_write(&mut self.conn, &path)?;
        tx.execute(
            "INSERT OR REPLACE INTO meta (key, value) VALUES (?1, ?2)",
            params![key, value],
        )
        .map_err(sql)?;
        tx.commit().map_err(sql)
    }

    /// Holds the write lock of the store at `path` (if it is one) while the caller replaces the
    /// file: a writer that opened the old file then fails with [`StoreError::Replaced`]. None
    /// when there is no store there (absent, or another kind of file).
    #[cfg(feature = "index")]
    pub(crate) fn lock_for_replace(path: &Path) -> Result<Option<ReplaceLock>, StoreError> {
        if !regular_or_absent(path)? {
            return Ok(None);
        }
        let flags = OpenFlags::SQLITE_OPEN_READ_WRITE | OpenFlags::SQLITE_OPEN_NO_MUTEX;
        let Ok(conn) = Connection::open_with_flags(path, flags) else {
            return Ok(None);
        };
        conn.busy_timeout(BUSY_TIMEOUT).map_err(|e| sqlite_error(path, e))?;
        let not_a_database = |e: &rusqlite::Error| matches!(e, rusqlite::Error::SqliteFailure(f, _) if f.code == rusqlite::ErrorCode::NotADatabase);
        // The log (`-wal`) is found by the file's name: frames a writer committed to the old
        // file and no one folded into it yet would be read as the new file's own after the
        // rename (its pages over the new file's). So the lock is taken with an empty log:
        // fold it in and truncate it (waiting for readers), take the write lock, and start
        // again if a writer committed in between.
        let started = std::time::Instant::now();
        loop {
            match conn.query_row("PRAGMA wal_checkpoint(TRUNCATE)", [], |_| Ok(())) {
                Ok(()) => {}
                // Not a database (e.g. a JSON index replaced by --force): nothing to lock.
                Err(e) if not_a_database(&e) => return Ok(None),
                Err(e) => return Err(sqlite_error(path, e)),
            }
            match conn.execute_batch("BEGIN IMMEDIATE") {
                Ok(()) => {}
                Err(e) if not_a_database(&e) => return Ok(None),
                Err(e) => return Err(sqlite_error(path, e)),
            }
            let log = std::fs::metadata(wal_path(path)).map_or(0, |m| m.len());
            if log == 0 {
                return Ok(Some(ReplaceLock(conn)));
            }
            conn.execute_batch("ROLLBACK").map_err(|e| sqlite_error(path, e))?;
            if started.elapsed() > BUSY_TIMEOUT {
                return Err(StoreError::InUse {
                    path: path.to_path_buf(),
                    wal: wal_path(path),
                });
            }
            std::thread::sleep(std::time::Duration::from_millis(5));
        }
    }

    fn writable(&self) -> Result<(), StoreError> {
        if self.read_only {
            return Err(StoreError::InvalidParameter {
                name: "store",
                reason: format!("{} was opened read-only", self.path.display()),
            });
        }
        Ok(())
    }

    /// Appends shapes in one transaction (all or none) and returns their ids. Existing shapes
    /// are not rewritten: only the last, partial chunk is extended.
    ///
    /// # Errors
    /// [`StoreError::EmptyName`], [`StoreError::DuplicateName`], [`StoreError::Dimension`],
    /// [`StoreError::NonFinite`] (checked before anything is written);
    /// [`StoreError::InvalidParameter`] for a read-only store; [`StoreError::Sqlite`].
    pub fn add(&mut self, entries: &[Entry<'_>]) -> Result<Vec<u64>, StoreError> {
        self.writable()?;
        let rows = self.encode(entries)?;
        let dim = self.dimension;
        let chunk_rows = self.chunk_rows;
        let path = self.path.clone();
        let sql = |source| sqlite_error(&path, source);
        let tx = begin_write(&mut self.conn, &path)?;
        // Under the write lock: the file at `path` must still be the one opened (a `build` that
        // replaced it holds this lock while renaming), else these shapes would go to a file
        // no one will read again.
        if self.identity.is_some() && file_identity(&self.path) != self.identity {
            return Err(StoreError::Replaced {
                path: self.path.clone(),
            });
        }
        // Nothing is added to a store whose stored vectors are not finite (a scan would fail on
        // them later; refuse now, naming the shape).
        {
            let mut stmt = tx
                .prepare("SELECT chunk, rows FROM chunks ORDER BY chunk")
                .map_err(sql)?;
            let plan = stmt
                .query_map([], |r| Ok((r.get::<_, i64>(0)?, r.get::<_, i64>(1)? as usize)))
                .map_err(sql)?
                .collect::<Result<Vec<_>, _>>()
                .map_err(sql)?;
            for (chunk, rows) in plan {
                read_chunk(&tx, &self.path, chunk, rows.min(chunk_rows), dim, chunk_rows)?;
            }
        }
        for e in entries {
            let taken: Option<i64> = tx
                .query_row("SELECT id FROM shapes WHERE name = ?1", [e.name], |r| r.get(0))
                .optional()
                .map_err(sql)?;
            if taken.is_some() {
                return Err(StoreError::DuplicateName { name: e.name.into() });
            }
        }
        let n0: i64 = tx
            .query_row("SELECT COALESCE(MAX(id) + 1, 0) FROM shapes", [], |r| r.get(0))
            .map_err(sql)?;
        let n0 = n0 as usize;
        {
            let mut insert = tx
                .prepare("INSERT INTO shapes (id, name, info) VALUES (?1, ?2, ?3)")
                .map_err(sql)?;
            for (i, e) in entries.iter().enumerate() {
                insert.execute(params![(n0 + i) as i64, e.name, e.info]).map_err(sql)?;
            }
        }
        // Fill the last partial chunk, then whole new ones.
        let mut next = 0usize; // rows of `rows` written so far
        let mut id = n0;
        while next < entries.len() {
            let chunk = id / chunk_rows;
            let offset = id % chunk_rows;
            let take = (chunk_rows - offset).min(entries.len() - next);
            let mut data: Vec<u8> = if offset > 0 {
                tx.query_row("SELECT data FROM chunks WHERE chunk = ?1", [chunk as i64], |r| r.get(0))
                    .map_err(sql)?
            } else {
                Vec::with_capacity(take * dim * 4)
            };
            if data.len() != offset * dim * 4 {
                return Err(StoreError::Corrupt {
                    path: self.path.clone(),
                    reason: format!("chunk {chunk} has {} bytes, expected {}", data.len(), offset * dim * 4),
                });
            }
            data.extend_from_slice(&rows[next * dim * 4..(next + take) * dim * 4]);
            tx.execute(
                "INSERT OR REPLACE INTO chunks (chunk, rows, data) VALUES (?1, ?2, ?3)",
                params![chunk as i64, (offset + take) as i64, data],
            )
            .map_err(sql)?;
            next += take;
            id += take;
        }
        tx.commit().map_err(sql)?;
        Ok((n0..n0 + entries.len()).map(|i| i as u64).collect())
    }

    /// Validates a batch and encodes its vectors as little-endian f32.
    fn encode(&self, entries: &[Entry<'_>]) -> Result<Vec<u8>, StoreError> {
        let mut names = std::collections::HashSet::with_capacity(entries.len());
        let mut out = Vec::with_capacity(entries.len() * self.dimension * 4);
        for (index, e) in entries.iter().enumerate() {
            if e.name.is_empty() {
                return Err(StoreError::EmptyName { index });
            }
            if !names.insert(e.name) {
                return Err(StoreError::DuplicateName { name: e.name.into() });
            }
            if e.vector.len() != self.dimension {
                return Err(StoreError::Dimension {
                    name: e.name.into(),
                    expected: self.dimension,
                    found: e.vector.len(),
                });
            }
            for (i, &x) in e.vector.iter().enumerate() {
                let y = x as f32;
                if !y.is_finite() {
                    return Err(StoreError::NonFinite {
                        name: e.name.into(),
                        index: i,
                        value: x,
                    });
                }
                out.extend_from_slice(&y.to_le_bytes());
            }
        }
        Ok(out)
    }

    /// The shape of `id`, if any.
    ///
    /// # Errors
    /// [`StoreError::Sqlite`].
    pub fn shape(&self, id: u64) -> Result<Option<ShapeRow>, StoreError> {
        self.conn
            .query_row("SELECT name, info FROM shapes WHERE id = ?1", [id as i64], |r| {
                Ok(ShapeRow {
                    id,
                    name: r.get(0)?,
                    info: r.get(1)?,
                })
            })
            .optional()
            .map_err(self.sql())
    }

    /// The shape named `name`, if any.
    ///
    /// # Errors
    /// [`StoreError::Sqlite`].
    pub fn find(&self, name: &str) -> Result<Option<ShapeRow>, StoreError> {
        self.conn
            .query_row("SELECT id, info FROM shapes WHERE name = ?1", [name], |r| {
                Ok(ShapeRow {
                    id: r.get::<_, i64>(0)? as u64,
                    name: name.into(),
                    info: r.get(1)?,
                })
            })
            .optional()
            .map_err(self.sql())
    }

    /// Every shape, by increasing id.
    ///
    /// # Errors
    /// [`StoreError::Sqlite`].
    pub fn shapes(&self) -> Result<Vec<ShapeRow>, StoreError> {
        let mut stmt = self
            .conn
            .prepare("SELECT id, name, info FROM shapes ORDER BY id")
            .map_err(self.sql())?;
        let rows = stmt
            .query_map([], |r| {
                Ok(ShapeRow {
                    id: r.get::<_, i64>(0)? as u64,
                    name: r.get(1)?,
                    info: r.get(2)?,
                })
            })
            .map_err(self.sql())?;
        rows.collect::<Result<Vec<_>, _>>().map_err(self.sql())
    }

    /// The vector of shape `id` (as stored, f32), if any.
    ///
    /// # Errors
    /// [`StoreError::Sqlite`], [`StoreError::Corrupt`].
    pub fn vector(&self, id: u64) -> Result<Option<Vec<f32>>, StoreError> {
        let n = self.len()? as u64;
        if id >= n {
            return Ok(None);
        }
        let chunk = (id as usize / self.chunk_rows) as i64;
        let offset = id as usize % self.chunk_rows;
        let values = read_chunk(
            &self.conn,
            &self.path,
            chunk,
            offset + 1,
            self.dimension,
            self.chunk_rows,
        )?;
        Ok(Some(values[offset * self.dimension..].to_vec()))
    }

    /// Every vector, row-major (`len() × dimension()`), by increasing id.
    ///
    /// # Errors
    /// [`StoreError::Sqlite`], [`StoreError::Corrupt`].
    pub fn vectors(&self) -> Result<Vec<f32>, StoreError> {
        let plan = self.plan()?;
        let total = plan.iter().map(|p| p.1).sum::<usize>().saturating_mul(self.dimension);
        let mut out = Vec::new();
        out.try_reserve_exact(total).map_err(|_| StoreError::TooLarge {
            path: self.path.clone(),
            what: format!("{total} stored values"),
        })?;
        for (chunk, rows) in plan {
            out.extend(read_chunk(
                &self.conn,
                &self.path,
                chunk,
                rows,
                self.dimension,
                self.chunk_rows,
            )?);
        }
        Ok(out)
    }

    /// The chunks and their row counts, as committed now.
    fn plan(&self) -> Result<Vec<(i64, usize)>, StoreError> {
        let mut stmt = self
            .conn
            .prepare("SELECT chunk, rows FROM chunks ORDER BY chunk")
            .map_err(self.sql())?;
        let rows = stmt
            .query_map([], |r| Ok((r.get::<_, i64>(0)?, r.get::<_, i64>(1)? as usize)))
            .map_err(self.sql())?;
        let plan = rows.collect::<Result<Vec<_>, _>>().map_err(self.sql())?;
        if let Some(&(chunk, rows)) = plan.iter().find(|p| p.1 > self.chunk_rows) {
            return Err(StoreError::Corrupt {
                path: self.path.clone(),
                reason: format!("chunk {chunk} holds {rows} rows of {} per chunk", self.chunk_rows),
            });
        }
        Ok(plan)
    }

    /// The `k` stored shapes nearest to a query under `metric` (exact, parallel; see
    /// [`Store::search`]).
    ///
    /// # Errors
    /// [`StoreError::Dimension`] / [`StoreError::NonFinite`] for a bad query; as
    /// [`Store::search`].
    pub fn search_metric<M: Metric + ?Sized>(
        &self,
        query: &[f64],
        k: usize,
        metric: &M,
    ) -> Result<Vec<Hit>, StoreError> {
        if query.len() != self.dimension {
            return Err(StoreError::Dimension {
                name: "query".into(),
                expected: self.dimension,
                found: query.len(),
            });
        }
        if let Some(index) = query.iter().position(|x| !x.is_finite()) {
            return Err(StoreError::NonFinite {
                name: "query".into(),
                index,
                value: query[index],
            });
        }
        if !metric.checks_values() {
            return self.search(k, |row| metric.eval(query, row));
        }
        if let Some((index, reason)) = query
            .iter()
            .enumerate()
            .find_map(|(i, &x)| metric.refuse(x).map(|r| (i, r)))
        {
            return Err(StoreError::InvalidParameter {
                name: "query",
                reason: format!("value {} at index {index} {reason}", query[index]),
            });
        }
        self.search_checked(k, |row| {
            match row
                .iter()
                .enumerate()
                .find_map(|(i, &x)| metric.refuse(f64::from(x)).map(|r| (i, r)))
            {
                Some((i, reason)) => Err(format!("value {} at index {i} {reason}", row[i])),
                None => Ok(metric.eval(query, row)),
            }
        })
    }

    /// The `k` stored shapes with the smallest `distance(vector)`, nearest first, ties broken
    /// by id (so the answer does not depend on the thread count). An exact scan of every
    /// committed vector: each rayon worker opens a read-only connection and reads whole chunks;
    /// only shapes committed when the scan starts are considered.
    ///
    /// # Errors
    /// [`StoreError::NanDistance`] if `distance` returns NaN; [`StoreError::Sqlite`],
    /// [`StoreError::Corrupt`].
    pub fn search<F>(&self, k: usize, distance: F) -> Result<Vec<Hit>, StoreError>
    where
        F: Fn(&[f32]) -> f64 + Sync,
    {
        self.search_checked(k, |row| Ok(distance(row)))
    }

    /// [`Store::search`] with a distance that may refuse a stored row (`Err(reason)`: e.g. a
    /// negative bin where the distance needs histograms), which fails the search with
    /// [`StoreError::InvalidRow`] naming the shape.
    ///
    /// # Errors
    /// [`StoreError::InvalidRow`]; as [`Store::search`].
    pub fn search_checked<F>(&self, k: usize, distance: F) -> Result<Vec<Hit>, StoreError>
    where
        F: Fn(&[f32]) -> Result<f64, String> + Sync,
    {
        let plan = self.plan()?;
        // No more hits than stored rows: k = 2⁶² must not size a heap.
        let k = k.min(plan.iter().map(|p| p.1).sum());
        if k == 0 {
            return Ok(Vec::new());
        }
        let next = AtomicUsize::new(0);
        let workers = rayon::current_num_threads().clamp(1, plan.len().max(1));
        let dim = self.dimension;
        let chunk_rows = self.chunk_rows;
        let path = self.path.as_path();
        let partial: Vec<Vec<(f64, u64)>> = (0..workers)
            .into_par_iter()
            .map(|_| -> Result<Vec<(f64, u64)>, StoreError> {
                let conn = connect(path, true)?;
                let mut best = TopK::new(k);
                loop {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    let Some(&(chunk, rows)) = plan.get(i) else { break };
                    let values = read_chunk(&conn, path, chunk, rows, dim, chunk_rows)?;
                    let first = chunk as u64 * chunk_rows as u64;
                    for (r, row) in values.chunks_exact(dim).enumerate() {
                        let id = first + r as u64;
                        let d = distance(row).map_err(|reason| StoreError::InvalidRow {
                            path: path.to_path_buf(),
                            id,
                            reason,
                        })?;
                        if d.is_nan() {
                            return Err(StoreError::NanDistance { id });
                        }
                        best.push(d, id);
                    }
                }
                Ok(best.into_sorted())
            })
            .collect::<Result<_, _>>()?;
        let mut all: Vec<(f64, u64)> = partial.into_iter().flatten().collect();
        all.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        all.truncate(k);
        all.into_iter()
            .map(|(distance, id)| {
                let row = self.shape(id)?.ok_or_else(|| StoreError::Corrupt {
                    path: self.path.clone(),
                    reason: format!("vector row {id} has no shape"),
                })?;
                Ok(Hit {
                    id,
                    name: row.name,
                    info: row.info,
                    distance,
                })
            })
            .collect()
    }
}

/// An SQLite error on `path`; "file is not a database" becomes [`StoreError::NotAStore`].
/// A write transaction on the store at `path`: it takes the write lock at once (waiting up to
/// the busy timeout), not at its first write.
fn begin_write<'c>(conn: &'c mut Connection, path: &Path) -> Result<rusqlite::Transaction<'c>, StoreError> {
    conn.transaction_with_behavior(TransactionBehavior::Immediate)
        .map_err(|source| sqlite_error(path, source))
}

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

fn connect(path: &Path, read_only: bool) -> Result<Connection, StoreError> {
    let sql = |source| sqlite_error(path, source);
    if !regular_or_absent(path)? {
        return Err(StoreError::Io {
            path: path.to_path_buf(),
            source: std::io::Error::new(std::io::ErrorKind::NotFound, "no such store file"),
        });
    }
    let flags = if read_only {
        OpenFlags::SQLITE_OPEN_READ_ONLY | OpenFlags::SQLITE_OPEN_NO_MUTEX
    } else {
        OpenFlags::SQLITE_OPEN_READ_WRITE | OpenFlags::SQLITE_OPEN_NO_MUTEX
    };
    let conn = Connection::open_with_flags(path, flags).map_err(sql)?;
    conn.busy_timeout(BUSY_TIMEOUT).map_err(sql)?;
    if !read_only {
        conn.pragma_update(None, "synchronous", "FULL").map_err(sql)?;
        return Ok(conn);
    }
    // A reader of a WAL file needs its shared-memory index (`-shm`), which it cannot create on
    // read-only media or in a read-only folder: there no writer can exist either, so the file
    // is opened as immutable (no locks, no log).
    match conn.query_row("SELECT COUNT(*) FROM sqlite_master", [], |r| r.get::<_, i64>(0)) {
        Ok(_) => Ok(conn),
        Err(rusqlite::Error::SqliteFailure(f, _))
            if matches!(
                f.code,
                rusqlite::ErrorCode::CannotOpen | rusqlite::ErrorCode::ReadOnly | rusqlite::ErrorCode::PermissionDenied
            ) =>
        {
            drop(conn);
            let conn =
                Connection::open_with_flags(immutable_uri(path), flags | OpenFlags::SQLITE_OPEN_URI).map_err(sql)?;
            Ok(conn)
        }
        Err(e) => Err(sql(e)),
    }
}

/// `file:PATH?immutable=1`, with the characters URIs reserve escaped.
fn immutable_uri(path: &Path) -> String {
    let mut uri = String::from("file:");
    for c in path.to_string_lossy().chars() {
        match c {
            '%' | '?' | '#' => uri.push_str(&format!("%{:02X}", c as u32)),
            c => uri.push(c),
        }
    }
    uri.push_str("?immutable=1");
    uri
}

impl Drop for Store {
    /// A read-only connection cannot remove the log and shared-memory files when it is the
    /// last one, so after closing it a brief read-write connection does (when the folder is
    /// writable and no one else has the file open): a closed store leaves no `-wal`/`-shm`.
    fn drop(&mut self) {
        if !self.read_only || !(wal_path(&self.path).exists() || shm_path(&self.path).exists()) {
            return;
        }
        let Ok(placeholder) = Connection::open_in_memory() else {
            return;
        };
        drop(std::mem::replace(&mut self.conn, placeholder));
        if file_identity(&self.path) != self.identity {
            return;
        }
        let flags = OpenFlags::SQLITE_OPEN_READ_WRITE | OpenFlags::SQLITE_OPEN_NO_MUTEX;
        if let Ok(conn) = Connection::open_with_flags(&self.path, flags) {
            // Reading the schema opens the log; closing the last connection checkpoints it and
            // removes both files.
            let _ = conn.query_row("SELECT COUNT(*) FROM sqlite_master", [], |r| r.get::<_, i64>(0));
            let _ = conn.close();
        }
    }
}

/// The first `rows` vectors of a chunk, decoded; every value must be finite (a tampered or
/// damaged blob is refused naming the shape, never ranked).
fn read_chunk(
    conn: &Connection,
    path: &Path,
    chunk: i64,
    rows: usize,
    dim: usize,
    chunk_rows: usize,
) -> Result<Vec<f32>, StoreError> {
    let sql = |source| sqlite_error(path, source);
    let corrupt = |reason: String| StoreError::Corrupt {
        path: path.to_path_buf(),
        reason,
    };
    if rows > chunk_rows {
        return Err(corrupt(format!(
            "chunk {chunk} holds {rows} rows of {chunk_rows} per chunk"
        )));
    }
    let mut blob = conn.blob_open(MAIN_DB, "chunks", "data", chunk, true).map_err(sql)?;
    // invariant: rows ≤ chunk_rows and chunk_rows × dim × 4 ≤ MAX_CHUNK_BYTES (checked on open).
    let bytes = rows * dim * 4;
    if blob.len() < bytes {
        return Err(corrupt(format!(
            "chunk {chunk} has {} bytes, expected at least {bytes}",
            blob.len()
        )));
    }
    let mut buf = vec![0u8; bytes];
    blob.read_exact(&mut buf).map_err(|source| StoreError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let values: Vec<f32> = buf
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    if let Some(i) = values.iter().position(|x| !x.is_finite()) {
        let id = chunk as u64 * chunk_rows as u64 + (i / dim) as u64;
        return Err(corrupt(format!(
            "shape {id} has the value {} at index {}: stored vectors must be finite",
            values[i],
            i % dim
        )));
    }
    Ok(values)
}

/// The k smallest (distance, id) pairs seen, as a max-heap on (distance, id).
struct TopK {
    k: usize,
    heap: std::collections::BinaryHeap<Ranked>,
}

#[derive(PartialEq)]
struct Ranked(f64, u64);

impl Eq for Ranked {}

impl PartialOrd for Ranked {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Ranked {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&other.0).then(self.1.cmp(&other.1))
    }
}

impl TopK {
    fn new(k: usize) -> Self {
        Self {
            k,
            heap: std::collections::BinaryHeap::with_capacity(k + 1),
        }
    }

    #[inline]
    fn push(&mut self, distance: f64, id: u64) {
        let item = Ranked(distance, id);
        if self.heap.len() < self.k {
            self.heap.push(item);
        } else if let Some(top) = self.heap.peek() {
            if item < *top {
                self.heap.pop();
                self.heap.push(item);
            }
        }
    }

    fn into_sorted(self) -> Vec<(f64, u64)> {
        self.heap.into_sorted_vec().into_iter().map(|r| (r.0, r.1)).collect()
    }
}
