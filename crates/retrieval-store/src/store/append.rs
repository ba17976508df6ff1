//! Writing: metadata, appends in one transaction, the lock a replacing `build` holds.

use super::*;

impl Store {
    /// Sets (inserts or replaces) a metadata value, in its own transaction.
    ///
    /// # Errors
    /// [`StoreError::InvalidParameter`] for a reserved key (`format`, `version`, `dimension`,
    /// `chunk_rows`) or a read-only store; [`StoreError::NoChecksums`] for a version 1 file;
    /// [`StoreError::Sqlite`].
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
            "INSERT OR REPLACE INTO meta (key, value, checksum) VALUES (?1, ?2, ?3)",
            params![key, value, integrity::meta_sum(key, value)],
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
        if !self.checksums {
            return Err(StoreError::NoChecksums {
                path: self.path.clone(),
                version: LEGACY_VERSION,
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
    /// [`StoreError::InvalidParameter`] for a read-only store; [`StoreError::NoChecksums`] for
    /// a version 1 file; [`StoreError::CorruptIndex`] when a stored chunk is damaged (nothing
    /// is added to a damaged store); [`StoreError::Sqlite`].
    pub fn add(&mut self, entries: &[Entry<'_>]) -> Result<Vec<u64>, StoreError> {
        self.writable()?;
        let rows = self.encode(entries)?;
        let dim = self.dimension;
        let chunk_rows = self.chunk_rows;
        let path = self.path.clone();
        let sql = |source| sqlite_error(&path, source);
        let layout = Layout {
            path: &path,
            dimension: dim,
            chunk_rows,
            checksums: self.checksums,
        };
        let tx = begin_write(&mut self.conn, &path)?;
        // Under the write lock: the file at `path` must still be the one opened (a `build` that
        // replaced it holds this lock while renaming), else these shapes would go to a file
        // no one will read again.
        if self.identity.is_some() && file_identity(&self.path) != self.identity {
            return Err(StoreError::Replaced {
                path: self.path.clone(),
            });
        }
        // Nothing is added to a store whose stored chunks are damaged or not finite (a scan
        // would fail on them later, and the last chunk's checksum is recomputed below: refuse
        // now, naming the chunk or the shape).
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
                read_chunk(&tx, &layout, chunk, rows.min(chunk_rows))?;
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
                .prepare("INSERT INTO shapes (id, name, info, checksum) VALUES (?1, ?2, ?3, ?4)")
                .map_err(sql)?;
            for (i, e) in entries.iter().enumerate() {
                let id = (n0 + i) as u64;
                insert
                    .execute(params![
                        id as i64,
                        e.name,
                        e.info,
                        integrity::shape_sum(id, e.name, e.info)
                    ])
                    .map_err(sql)?;
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
                return Err(integrity::corrupt(
                    &self.path,
                    integrity::chunk_record(chunk as i64, offset, chunk_rows),
                    format!("has {} bytes, expected {}", data.len(), offset * dim * 4),
                ));
            }
            data.extend_from_slice(&rows[next * dim * 4..(next + take) * dim * 4]);
            let sum = integrity::chunk_sum(chunk as i64, offset + take, &data);
            tx.execute(
                "INSERT OR REPLACE INTO chunks (chunk, rows, data, checksum) VALUES (?1, ?2, ?3, ?4)",
                params![chunk as i64, (offset + take) as i64, data, sum],
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
}
