//! Checksums of every record, their verification, the full check of a file and the upgrade
//! of a version 1 file (see [`crate::check`]).

use super::*;
use crate::check::{CheckReport, Damage};

/// CRC-32 of a record's domain tag, its identifying fields and its contents: a record copied
/// under another key, id or chunk number does not match either. crc32fast uses the CPU's
/// carry-less multiply (about 19 GB/s on the benchmark machine, a few percent of a scan).
fn crc(parts: &[&[u8]]) -> i64 {
    let mut h = crc32fast::Hasher::new();
    for p in parts {
        h.update(p);
    }
    i64::from(h.finalize())
}

pub(super) fn meta_sum(key: &str, value: &[u8]) -> i64 {
    crc(&[b"meta\0", key.as_bytes(), b"\0", value])
}

pub(super) fn shape_sum(id: u64, name: &str, info: &str) -> i64 {
    crc(&[b"shape\0", &id.to_le_bytes(), name.as_bytes(), b"\0", info.as_bytes()])
}

pub(super) fn chunk_sum(chunk: i64, rows: usize, data: &[u8]) -> i64 {
    crc(&[b"chunk\0", &chunk.to_le_bytes(), &(rows as u64).to_le_bytes(), data])
}

/// How a metadata entry is named in errors.
pub(super) fn meta_record(key: &str) -> String {
    format!("metadata {key:?}")
}

/// How a shape row is named in errors.
pub(super) fn shape_record(id: u64, name: &str) -> String {
    format!("shape {id} ({name:?})")
}

/// How a chunk is named in errors: its number and the ids of the shapes it holds.
pub(super) fn chunk_record(chunk: i64, rows: usize, chunk_rows: usize) -> String {
    let first = (chunk.max(0) as u64).saturating_mul(chunk_rows as u64);
    match rows {
        0 => format!("chunk {chunk}"),
        1 => format!("chunk {chunk} (shape {first})"),
        n => format!(
            "chunk {chunk} (shapes {first} to {})",
            first.saturating_add(n as u64 - 1)
        ),
    }
}

pub(super) fn corrupt(path: &Path, record: String, reason: impl Into<String>) -> StoreError {
    StoreError::CorruptIndex {
        path: path.to_path_buf(),
        record,
        reason: reason.into(),
    }
}

/// `Err` when a stored checksum (None: the file has none) does not match `computed`.
pub(super) fn verify(
    path: &Path,
    stored: Option<i64>,
    computed: i64,
    record: impl FnOnce() -> String,
) -> Result<(), StoreError> {
    match stored {
        Some(s) if s != computed => Err(corrupt(
            path,
            record(),
            format!("checksum mismatch (stored {s:08x}, contents {computed:08x})"),
        )),
        _ => Ok(()),
    }
}

/// Whether `table` has a `checksum` column (format version 2).
pub(super) fn has_checksums(conn: &Connection, table: &str) -> bool {
    conn.prepare(&format!("SELECT checksum FROM {table} LIMIT 0")).is_ok()
}

/// What is wrong with chunk `chunk` at position `position` of the chunk table (`last`: the
/// last position), holding `rows` rows in a blob of `bytes` bytes of SQLite type `kind`; None
/// when it is sound. Full chunks but the last, each `rows × dimension × 4` bytes.
pub(super) fn chunk_shape_problem(
    (chunk, position, last): (i64, usize, usize),
    rows: i64,
    (bytes, kind): (i64, &str),
    dimension: usize,
    chunk_rows: usize,
) -> Option<String> {
    let rows_ok = if position < last {
        rows == chunk_rows as i64
    } else {
        (1..=chunk_rows as i64).contains(&rows)
    };
    if chunk != position as i64 || !rows_ok {
        return Some(format!(
            "holds {rows} rows of {chunk_rows} per chunk at position {position} of the chunk table"
        ));
    }
    let expected = rows * dimension as i64 * 4;
    if kind != "blob" || bytes != expected {
        return Some(format!(
            "has {bytes} bytes ({kind}), but {rows} vectors of {dimension} values need {expected}"
        ));
    }
    None
}

/// Decodes little-endian f32 and refuses a non-finite value, naming the shape.
pub(super) fn decode(
    path: &Path,
    chunk: i64,
    chunk_rows: usize,
    dim: usize,
    bytes: &[u8],
) -> Result<Vec<f32>, StoreError> {
    let values: Vec<f32> = bytes
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    if let Some(i) = values.iter().position(|x| !x.is_finite()) {
        let id = chunk as u64 * chunk_rows as u64 + (i / dim) as u64;
        return Err(corrupt(
            path,
            format!("shape {id}"),
            format!(
                "value {} at index {}: stored vectors must be finite",
                values[i],
                i % dim
            ),
        ));
    }
    Ok(values)
}

/// Most findings of SQLite's own structure check that a report lists.
const MAX_STRUCTURE_FINDINGS: usize = 20;

impl Store {
    /// Verifies every record of the store at `path` against its checksum, SQLite's own
    /// structure (`PRAGMA integrity_check`), the chunk table's invariants and every stored
    /// value (finite), reading one snapshot; reports every damaged record rather than stopping
    /// at the first. `row_problem(id, vector)` adds a check of each stored vector (e.g. a bag
    /// must be a histogram).
    ///
    /// A version 1 file (no checksums) is checked for the rest and reported with
    /// `checksums: false`.
    ///
    /// # Errors
    /// Only when nothing can be checked: [`StoreError::NotAStore`] (not SQLite, not a store),
    /// [`StoreError::UnsupportedVersion`], [`StoreError::Io`], [`StoreError::Sqlite`].
    pub fn check_with(
        path: &Path,
        row_problem: &dyn Fn(u64, &[f32]) -> Option<String>,
    ) -> Result<CheckReport, StoreError> {
        let conn = connect(path, true)?;
        let sql = |source| sqlite_error(path, source);
        let tx = conn.unchecked_transaction().map_err(sql)?;
        open::require_tables(&tx, path)?;
        let mut damage = Vec::new();
        let mut found = |record: String, reason: String| damage.push(Damage { record, reason });
        {
            let mut stmt = tx.prepare("PRAGMA integrity_check").map_err(sql)?;
            let lines = stmt.query_map([], |r| r.get::<_, String>(0)).map_err(sql)?;
            for line in lines.take(MAX_STRUCTURE_FINDINGS) {
                let line = line.map_err(sql)?;
                if line != "ok" {
                    found("the file".into(), line);
                }
            }
        }
        let checksums = has_checksums(&tx, "meta");
        let meta = open::read_meta(&tx, path, checksums)?;
        for (key, value, stored) in &meta {
            if let Err(StoreError::CorruptIndex { record, reason, .. }) =
                verify(path, *stored, meta_sum(key, value), || meta_record(key))
            {
                found(record, reason);
            }
        }
        let header = open::Header::parse(path, &meta, checksums);
        let header = match header {
            Ok(h) => h,
            Err(StoreError::CorruptIndex { record, reason, .. }) => {
                found(record, reason);
                return Ok(CheckReport {
                    path: path.to_path_buf(),
                    version: FORMAT_VERSION,
                    checksums,
                    metadata: meta.len(),
                    shapes: 0,
                    chunks: 0,
                    damage,
                });
            }
            Err(e) => return Err(e),
        };
        for table in ["shapes", "chunks"] {
            if has_checksums(&tx, table) != checksums {
                found(
                    format!("the {table} table"),
                    "its checksum column does not match the metadata table's".into(),
                );
            }
        }
        let shapes = check_shapes(&tx, path, checksums && has_checksums(&tx, "shapes"), &mut found)?;
        let chunks = check_chunks(
            &tx,
            path,
            (header.dimension, header.chunk_rows),
            (shapes, checksums && has_checksums(&tx, "chunks")),
            row_problem,
            &mut found,
        )?;
        Ok(CheckReport {
            path: path.to_path_buf(),
            version: header.version,
            checksums,
            metadata: meta.len(),
            shapes: shapes as usize,
            chunks,
            damage,
        })
    }

    /// [`Store::check_with`] without a check of the vectors' meaning.
    ///
    /// # Errors
    /// As [`Store::check_with`].
    pub fn check(path: &Path) -> Result<CheckReport, StoreError> {
        Self::check_with(path, &|_, _| None)
    }

    /// Adds checksums to a version 1 store in place (one transaction; the file becomes version
    /// 2) and returns the check of the result. The contents are first checked as a version 1
    /// file can be (structure, counts, finite values); a file with damage is refused, since
    /// its checksums would bless it. Nothing is done to a version 2 file.
    ///
    /// # Errors
    /// [`StoreError::CorruptIndex`] for damage found first; as [`Store::open`].
    pub fn upgrade(path: &Path) -> Result<CheckReport, StoreError> {
        let before = Self::check(path)?;
        if let Some(d) = before.damage.first() {
            return Err(corrupt(path, d.record.clone(), d.reason.clone()));
        }
        if before.checksums {
            return Ok(before);
        }
        let mut store = Self::open(path)?;
        let sql = |source| sqlite_error(path, source);
        let tx = begin_write(&mut store.conn, path)?;
        if has_checksums(&tx, "meta") {
            // Another process upgraded it meanwhile.
            drop(tx);
            drop(store);
            return Self::check(path);
        }
        tx.execute_batch(
            "ALTER TABLE meta ADD COLUMN checksum INTEGER NOT NULL DEFAULT 0;
             ALTER TABLE shapes ADD COLUMN checksum INTEGER NOT NULL DEFAULT 0;
             CREATE TABLE chunks_v2 (chunk INTEGER PRIMARY KEY, rows INTEGER NOT NULL, checksum INTEGER NOT NULL,
                 data BLOB NOT NULL);",
        )
        .map_err(sql)?;
        tx.execute(
            "UPDATE meta SET value = ?1 WHERE key = 'version'",
            [FORMAT_VERSION.to_string().as_bytes()],
        )
        .map_err(sql)?;
        let meta: Vec<(String, Vec<u8>)> = {
            let mut stmt = tx.prepare("SELECT key, value FROM meta").map_err(sql)?;
            let rows = stmt.query_map([], |r| Ok((r.get(0)?, r.get(1)?))).map_err(sql)?;
            rows.collect::<Result<_, _>>().map_err(sql)?
        };
        for (key, value) in &meta {
            tx.execute(
                "UPDATE meta SET checksum = ?1 WHERE key = ?2",
                params![meta_sum(key, value), key],
            )
            .map_err(sql)?;
        }
        let shapes: Vec<(i64, String, String)> = {
            let mut stmt = tx.prepare("SELECT id, name, info FROM shapes").map_err(sql)?;
            let rows = stmt
                .query_map([], |r| Ok((r.get(0)?, r.get(1)?, r.get(2)?)))
                .map_err(sql)?;
            rows.collect::<Result<_, _>>().map_err(sql)?
        };
        for (id, name, info) in &shapes {
            tx.execute(
                "UPDATE shapes SET checksum = ?1 WHERE id = ?2",
                params![shape_sum(*id as u64, name, info), id],
            )
            .map_err(sql)?;
        }
        // The chunks are copied into a table with the checksum before the data, as
        // `Store::create` makes it (see there), one chunk in memory at a time.
        let chunks: Vec<i64> = {
            let mut stmt = tx.prepare("SELECT chunk FROM chunks").map_err(sql)?;
            let rows = stmt.query_map([], |r| r.get(0)).map_err(sql)?;
            rows.collect::<Result<_, _>>().map_err(sql)?
        };
        for chunk in chunks {
            let (rows, data): (i64, Vec<u8>) = tx
                .query_row("SELECT rows, data FROM chunks WHERE chunk = ?1", [chunk], |r| {
                    Ok((r.get(0)?, r.get(1)?))
                })
                .map_err(sql)?;
            let sum = chunk_sum(chunk, rows.max(0) as usize, &data);
            tx.execute(
                "INSERT INTO chunks_v2 (chunk, rows, checksum, data) VALUES (?1, ?2, ?3, ?4)",
                params![chunk, rows, sum, data],
            )
            .map_err(sql)?;
        }
        tx.execute_batch("DROP TABLE chunks; ALTER TABLE chunks_v2 RENAME TO chunks;")
            .map_err(sql)?;
        tx.commit().map_err(sql)?;
        drop(store);
        Self::check(path)
    }
}

/// Every shape row against its checksum, ids 0..n; returns n (one past the highest id).
fn check_shapes(
    tx: &Connection,
    path: &Path,
    checksums: bool,
    found: &mut dyn FnMut(String, String),
) -> Result<u64, StoreError> {
    let sql = |source| sqlite_error(path, source);
    let query = if checksums {
        "SELECT id, name, info, checksum FROM shapes ORDER BY id"
    } else {
        "SELECT id, name, info, NULL FROM shapes ORDER BY id"
    };
    let mut stmt = tx.prepare(query).map_err(sql)?;
    let mut rows = stmt.query([]).map_err(sql)?;
    let mut expected = 0u64;
    while let Some(r) = rows.next().map_err(sql)? {
        let id: i64 = r.get(0).map_err(sql)?;
        let text = |i: usize| -> String {
            r.get_ref(i)
                .ok()
                .and_then(|v| v.as_str().ok().map(str::to_owned))
                .unwrap_or_else(|| "<not text>".into())
        };
        let (name, info) = (text(1), text(2));
        let stored: Option<i64> = r.get(3).map_err(sql)?;
        let record = || shape_record(id as u64, &name);
        if id != expected as i64 {
            found(
                record(),
                format!("id {id} where {expected} comes next (ids are 0, 1, 2, …)"),
            );
        }
        expected = (id.max(0) as u64).saturating_add(1);
        if let Err(StoreError::CorruptIndex { record, reason, .. }) =
            verify(path, stored, shape_sum(id as u64, &name, &info), record)
        {
            found(record, reason);
        }
    }
    Ok(expected)
}

/// Every chunk: its place in the table, size, checksum, finite values and `row_problem`;
/// returns the number of chunks.
fn check_chunks(
    tx: &Connection,
    path: &Path,
    (dimension, chunk_rows): (usize, usize),
    (shapes, checksums): (u64, bool),
    row_problem: &dyn Fn(u64, &[f32]) -> Option<String>,
    found: &mut dyn FnMut(String, String),
) -> Result<usize, StoreError> {
    let sql = |source| sqlite_error(path, source);
    let count: i64 = tx
        .query_row("SELECT COUNT(*) FROM chunks", [], |r| r.get(0))
        .map_err(sql)?;
    let count = count.max(0) as usize;
    let expected = (shapes as usize).div_ceil(chunk_rows);
    let rows_total: i64 = tx
        .query_row("SELECT COALESCE(SUM(rows), 0) FROM chunks", [], |r| r.get(0))
        .map_err(sql)?;
    if count != expected || rows_total != shapes as i64 {
        found(
            "the chunk table".into(),
            format!("{shapes} shapes but {rows_total} vector rows in {count} chunks"),
        );
    }
    let query = if checksums {
        "SELECT chunk, rows, data, typeof(data), length(data), checksum FROM chunks ORDER BY chunk"
    } else {
        "SELECT chunk, rows, data, typeof(data), length(data), NULL FROM chunks ORDER BY chunk"
    };
    let mut stmt = tx.prepare(query).map_err(sql)?;
    let mut rows = stmt.query([]).map_err(sql)?;
    let mut position = 0usize;
    while let Some(r) = rows.next().map_err(sql)? {
        let chunk: i64 = r.get(0).map_err(sql)?;
        let n: i64 = r.get(1).map_err(sql)?;
        let kind: String = r.get(3).map_err(sql)?;
        let bytes: i64 = r.get(4).map_err(sql)?;
        let stored: Option<i64> = r.get(5).map_err(sql)?;
        let record = chunk_record(chunk, n.max(0) as usize, chunk_rows);
        position += 1;
        if let Some(problem) = chunk_shape_problem(
            (chunk, position - 1, count.saturating_sub(1)),
            n,
            (bytes, &kind),
            dimension,
            chunk_rows,
        ) {
            found(record, problem);
            continue;
        }
        let data = r.get_ref(2).map_err(sql)?.as_blob().map_err(|e| sql(e.into()))?;
        if let Err(StoreError::CorruptIndex { record, reason, .. }) =
            verify(path, stored, chunk_sum(chunk, n as usize, data), || record.clone())
        {
            found(record, reason);
            continue;
        }
        match decode(path, chunk, chunk_rows, dimension, data) {
            Ok(values) => {
                let first = chunk as u64 * chunk_rows as u64;
                for (i, row) in values.chunks_exact(dimension).enumerate() {
                    if let Some(problem) = row_problem(first + i as u64, row) {
                        found(format!("shape {}", first + i as u64), problem);
                    }
                }
            }
            Err(StoreError::CorruptIndex { record, reason, .. }) => found(record, reason),
            Err(e) => return Err(e),
        }
    }
    Ok(count)
}
