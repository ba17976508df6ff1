//! Creating and opening a store: the schema, the checks on open, connections (read-only
//! media included) and what a closed reader leaves.

use super::*;

impl Store {
    /// Creates a new, empty store at `path`.
    ///
    /// The file is built in a temporary folder beside it and renamed into place, so `path`
    /// never holds a half-created store and nothing is left beside it (see
    /// [`wfem_base::tempfiles`]). With `overwrite`, an existing store is
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
        let file_name = path.file_name().ok_or_else(|| StoreError::InvalidParameter {
            name: "path",
            reason: format!("{} has no file name", path.display()),
        })?;
        // Built in a private folder beside the target (`.NAME.tmp-PID-N`, with SQLite's
        // journals), removed when dropped, on a signal (wfem_base::tempfiles) or, after a kill,
        // by the next writer of this path.
        let folder = TempPath::dir(path).map_err(|source| StoreError::Io {
            path: path.into(),
            source,
        })?;
        let tmp = folder.path().join(file_name);
        Self::write_empty(&tmp, params)?;
        tempfiles::while_locked(|| std::fs::rename(&tmp, path)).map_err(|source| StoreError::Io {
            path: path.into(),
            source,
        })?;
        drop(folder);
        // The replaced file's shared-memory index must not describe the new one.
        let _ = std::fs::remove_file(shm_path(path));
        Self::open(path)
    }

    fn write_empty(tmp: &Path, params: &StoreParams) -> Result<(), StoreError> {
        let sql = |source| sqlite_error(tmp, source);
        let mut conn = Connection::open(tmp).map_err(sql)?;
        // 64 KiB pages: a chunk blob spans a dozen overflow pages instead of two hundred.
        conn.pragma_update(None, "page_size", 65536).map_err(sql)?;
        conn.pragma_update(None, "journal_mode", "WAL").map_err(sql)?;
        conn.pragma_update(None, "synchronous", "FULL").map_err(sql)?;
        let tx = conn.transaction().map_err(sql)?;
        // A chunk's checksum comes before its data: SQLite stores columns in order, and a
        // column after a 768 KiB blob is reached only by walking the blob's overflow pages
        // (reading every chunk twice per scan: +50 % CPU in the benchmark).
        tx.execute_batch(
            "CREATE TABLE meta (key TEXT PRIMARY KEY NOT NULL, value BLOB NOT NULL, checksum INTEGER NOT NULL)
                 WITHOUT ROWID;
             CREATE TABLE shapes (id INTEGER PRIMARY KEY, name TEXT NOT NULL UNIQUE, info TEXT NOT NULL,
                 checksum INTEGER NOT NULL);
             CREATE TABLE chunks (chunk INTEGER PRIMARY KEY, rows INTEGER NOT NULL, checksum INTEGER NOT NULL,
                 data BLOB NOT NULL);",
        )
        .map_err(sql)?;
        for (key, value) in [
            ("format", FORMAT.to_string()),
            ("version", FORMAT_VERSION.to_string()),
            ("dimension", params.dimension.to_string()),
            ("chunk_rows", params.chunk_rows.to_string()),
        ] {
            tx.execute(
                "INSERT INTO meta (key, value, checksum) VALUES (?1, ?2, ?3)",
                params![key, value.as_bytes(), integrity::meta_sum(key, value.as_bytes())],
            )
            .map_err(sql)?;
        }
        tx.commit().map_err(sql)?;
        // Leave a self-contained file (empty log) before it is renamed into place.
        conn.execute_batch("PRAGMA wal_checkpoint(TRUNCATE);").map_err(sql)?;
        conn.close().map_err(|(_, e)| sql(e))?;
        Ok(())
    }

    /// Opens an existing store for reading and appending. Every metadata entry is verified
    /// against its checksum, and the chunk table against the store's invariants
    /// ([`crate::check`]). A store of format version 1 (no checksums) opens unchecked
    /// ([`Store::checksummed`] is false) and refuses writes ([`StoreError::NoChecksums`]).
    ///
    /// # Errors
    /// [`StoreError::NotAStore`], [`StoreError::UnsupportedVersion`],
    /// [`StoreError::CorruptIndex`], [`StoreError::UnreadableLog`], [`StoreError::Sqlite`]
    /// (missing file, locked, not SQLite).
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
        let header = {
            // One read transaction, so one snapshot: queries could otherwise straddle a
            // writer's commit (a reader opened during appends saw 50 ids but 100 rows and
            // called the file corrupt).
            let tx = conn.unchecked_transaction().map_err(|e| sqlite_error(path, e))?;
            require_tables(&tx, path)?;
            let checksums = integrity::has_checksums(&tx, "meta");
            let meta = read_meta(&tx, path, checksums)?;
            for (key, value, stored) in &meta {
                integrity::verify(path, *stored, integrity::meta_sum(key, value), || {
                    integrity::meta_record(key)
                })?;
            }
            let header = Header::parse(path, &meta, checksums)?;
            check_counts(&tx, path, &header)?;
            header
        };
        Ok(Self {
            conn,
            path: path.to_path_buf(),
            dimension: header.dimension,
            chunk_rows: header.chunk_rows,
            read_only,
            checksums: header.checksums,
            identity: file_identity(path),
        })
    }
}

/// The reserved metadata of a store, read and validated.
pub(super) struct Header {
    pub(super) version: u32,
    pub(super) dimension: usize,
    pub(super) chunk_rows: usize,
    pub(super) checksums: bool,
}

impl Header {
    /// The format, version and sizes from the metadata rows (`checksums`: whether the file
    /// has checksum columns, which must agree with its version).
    pub(super) fn parse(
        path: &Path,
        meta: &[(String, Vec<u8>, Option<i64>)],
        checksums: bool,
    ) -> Result<Self, StoreError> {
        let not_a_store = |reason: String| StoreError::NotAStore {
            path: path.to_path_buf(),
            reason,
        };
        let text = |key: &str| -> Result<String, StoreError> {
            let v = meta
                .iter()
                .find(|m| m.0 == key)
                .ok_or_else(|| not_a_store(format!("no {key:?} entry")))?;
            String::from_utf8(v.1.clone()).map_err(|_| not_a_store(format!("the {key:?} entry is not text")))
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
        let version = u32::try_from(number("version")?).unwrap_or(u32::MAX);
        match (version, checksums) {
            (FORMAT_VERSION, true) | (LEGACY_VERSION, false) => {}
            (LEGACY_VERSION | FORMAT_VERSION, _) => {
                return Err(integrity::corrupt(
                    path,
                    integrity::meta_record("version"),
                    format!(
                        "version {version} {} checksum columns",
                        if checksums {
                            "but the tables have"
                        } else {
                            "but the tables have no"
                        }
                    ),
                ))
            }
            _ => {
                return Err(StoreError::UnsupportedVersion {
                    path: path.to_path_buf(),
                    found: version,
                    supported: FORMAT_VERSION,
                })
            }
        }
        let (dimension, chunk_rows) = (number("dimension")?, number("chunk_rows")?);
        StoreParams { dimension, chunk_rows }
            .check()
            .map_err(|(name, reason)| integrity::corrupt(path, integrity::meta_record(name), reason))?;
        Ok(Self {
            version,
            dimension,
            chunk_rows,
            checksums,
        })
    }
}

/// The three tables of a store must be there.
pub(super) fn require_tables(conn: &Connection, path: &Path) -> Result<(), StoreError> {
    let tables: i64 = conn
        .query_row(
            "SELECT COUNT(*) FROM sqlite_master WHERE type = 'table' AND name IN ('meta', 'shapes', 'chunks')",
            [],
            |r| r.get(0),
        )
        .map_err(|e| sqlite_error(path, e))?;
    if tables != 3 {
        return Err(StoreError::NotAStore {
            path: path.to_path_buf(),
            reason: "the tables meta, shapes and chunks are missing".into(),
        });
    }
    Ok(())
}

/// A metadata row: key, value and checksum (None in a version 1 file).
pub(super) type MetaRow = (String, Vec<u8>, Option<i64>);

/// Every metadata row (checksums None without `checksums`).
pub(super) fn read_meta(conn: &Connection, path: &Path, checksums: bool) -> Result<Vec<MetaRow>, StoreError> {
    let sql = |source| sqlite_error(path, source);
    let query = if checksums {
        "SELECT key, value, checksum FROM meta"
    } else {
        "SELECT key, value, NULL FROM meta"
    };
    let mut stmt = conn.prepare(query).map_err(sql)?;
    let rows = stmt
        .query_map([], |r| Ok((r.get(0)?, r.get(1)?, r.get(2)?)))
        .map_err(sql)?;
    rows.collect::<Result<Vec<_>, _>>().map_err(sql)
}

/// The ids must be 0..n, the chunks 0, 1, … hold exactly n rows (full but the last), and
/// every chunk blob is exactly `rows × dimension × 4` bytes (a `dimension` edited to 47 over
/// 48-wide blobs is refused, not read misaligned). Cheap: the chunk table and rowid bounds,
/// not the blobs' contents (those are verified when read).
fn check_counts(tx: &Connection, path: &Path, header: &Header) -> Result<(), StoreError> {
    let sql = |source| sqlite_error(path, source);
    let (shapes, min_id): (i64, i64) = tx
        .query_row(
            "SELECT COALESCE(MAX(id) + 1, 0), COALESCE(MIN(id), 0) FROM shapes",
            [],
            |r| Ok((r.get(0)?, r.get(1)?)),
        )
        .map_err(sql)?;
    let mut stmt = tx
        .prepare("SELECT chunk, rows, length(data), typeof(data) FROM chunks ORDER BY chunk")
        .map_err(sql)?;
    let chunks = stmt
        .query_map([], |r| {
            Ok((
                r.get::<_, i64>(0)?,
                r.get::<_, i64>(1)?,
                r.get::<_, i64>(2)?,
                r.get::<_, String>(3)?,
            ))
        })
        .map_err(sql)?
        .collect::<Result<Vec<_>, _>>()
        .map_err(sql)?;
    let expected_chunks = (shapes.max(0) as usize).div_ceil(header.chunk_rows);
    let rows: i64 = chunks.iter().map(|c| c.1.max(0)).sum();
    if min_id != 0 || rows != shapes || chunks.len() != expected_chunks {
        return Err(integrity::corrupt(
            path,
            "the chunk table".into(),
            format!(
                "{shapes} shape ids (lowest {min_id}) but {rows} vector rows in {} chunks",
                chunks.len()
            ),
        ));
    }
    let last = chunks.len().saturating_sub(1);
    for (i, (chunk, rows, bytes, kind)) in chunks.iter().enumerate() {
        if let Some(problem) = integrity::chunk_shape_problem(
            (*chunk, i, last),
            *rows,
            (*bytes, kind),
            header.dimension,
            header.chunk_rows,
        ) {
            return Err(integrity::corrupt(
                path,
                integrity::chunk_record(*chunk, (*rows).max(0) as usize, header.chunk_rows),
                problem,
            ));
        }
    }
    Ok(())
}

pub(super) fn connect(path: &Path, read_only: bool) -> Result<Connection, StoreError> {
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
    // read-only media or in a read-only folder, where no writer can exist either. An empty or
    // absent log holds nothing: the file is opened as immutable (no locks, no log). A log with
    // frames may hold committed changes that the file alone lacks (issue #41: immutable left
    // out the shapes of the last adds), so it is read without shared memory: no locking (the
    // `unix-none` VFS) in exclusive mode, where SQLite keeps the log's index in private memory.
    match conn.query_row("SELECT COUNT(*) FROM sqlite_master", [], |r| r.get::<_, i64>(0)) {
        Ok(_) => Ok(conn),
        Err(rusqlite::Error::SqliteFailure(f, _))
            if matches!(
                f.code,
                rusqlite::ErrorCode::CannotOpen | rusqlite::ErrorCode::ReadOnly | rusqlite::ErrorCode::PermissionDenied
            ) =>
        {
            drop(conn);
            let wal = wal_path(path);
            if std::fs::metadata(&wal).map_or(true, |m| m.len() == 0) {
                return Connection::open_with_flags(uri(path, "immutable=1"), flags | OpenFlags::SQLITE_OPEN_URI)
                    .map_err(sql);
            }
            let unreadable = |e: rusqlite::Error| StoreError::UnreadableLog {
                path: path.to_path_buf(),
                wal: wal.clone(),
                reason: e.to_string(),
            };
            let conn = Connection::open_with_flags(uri(path, "vfs=unix-none"), flags | OpenFlags::SQLITE_OPEN_URI)
                .map_err(unreadable)?;
            conn.pragma_update(None, "locking_mode", "EXCLUSIVE")
                .map_err(unreadable)?;
            conn.query_row("SELECT COUNT(*) FROM sqlite_master", [], |r| r.get::<_, i64>(0))
                .map_err(unreadable)?;
            Ok(conn)
        }
        Err(e) => Err(sql(e)),
    }
}

/// `file:PATH?QUERY`, with the characters URIs reserve escaped.
fn uri(path: &Path, query: &str) -> String {
    let mut uri = String::from("file:");
    for c in path.to_string_lossy().chars() {
        match c {
            '%' | '?' | '#' => uri.push_str(&format!("%{:02X}", c as u32)),
            c => uri.push(c),
        }
    }
    uri.push('?');
    uri.push_str(query);
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
