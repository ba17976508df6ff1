//! Hostile inputs and tampered files (issue #23): every case is a typed error naming the
//! culprit, never a panic, an abort or a silently wrong answer.

use super::store::vector;
use retrieval_store::metric::StandardMetric;
use retrieval_store::{Entry, Store, StoreError, StoreParams, MAX_DIMENSION};
use std::path::{Path, PathBuf};

fn filled(dir: &Path, dim: usize, chunk_rows: usize, n: usize) -> PathBuf {
    let path = dir.join("index.sqlite");
    let mut store = Store::create(
        &path,
        &StoreParams {
            dimension: dim,
            chunk_rows,
        },
        false,
    )
    .unwrap();
    let names: Vec<String> = (0..n).map(|i| format!("s{i}")).collect();
    let vectors: Vec<Vec<f64>> = (0..n).map(|i| vector(i, dim)).collect();
    let entries: Vec<Entry<'_>> = names.iter().zip(&vectors).map(|(n, v)| Entry::new(n, "", v)).collect();
    store.add(&entries).unwrap();
    path
}

fn tamper(path: &Path, sql: &str, blob: Option<Vec<u8>>) {
    let conn = rusqlite::Connection::open(path).unwrap();
    match blob {
        Some(b) => conn.execute(sql, [b]).unwrap(),
        None => conn.execute(sql, []).unwrap(),
    };
}

fn f32_bytes(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|x| x.to_le_bytes()).collect()
}

#[test]
fn a_huge_k_returns_every_shape_instead_of_overflowing() {
    let dir = tempfile::tempdir().unwrap();
    let path = filled(dir.path(), 4, 3, 7);
    let store = Store::open_readonly(&path).unwrap();
    let hits = store
        .search_metric(&vector(0, 4), 1 << 62, &StandardMetric::L1)
        .unwrap();
    assert_eq!(hits.len(), 7);
    assert_eq!(hits[0].name, "s0");
}

#[test]
fn sizes_are_bounded_before_anything_is_allocated() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("big.sqlite");
    for (dimension, chunk_rows, name) in [
        (1_000_000_000_000, 4096, "dimension"),
        (MAX_DIMENSION + 1, 1, "dimension"),
        (MAX_DIMENSION, 4096, "chunk_rows"),
        (4, usize::MAX, "chunk_rows"),
    ] {
        let err = Store::create(&path, &StoreParams { dimension, chunk_rows }, false).unwrap_err();
        assert!(
            matches!(&err, StoreError::InvalidParameter { name: n, .. } if *n == name),
            "{dimension} × {chunk_rows}: {err}"
        );
    }
    assert!(!path.exists());
}

/// Removes the checksum columns (a store of format version 1, as earlier builds wrote): what
/// is left to catch an edit are the structural checks below.
fn without_checksums(path: &Path) {
    tamper(
        path,
        "UPDATE meta SET value = CAST('1' AS BLOB) WHERE key = 'version'",
        None,
    );
    for table in ["meta", "shapes", "chunks"] {
        tamper(path, &format!("ALTER TABLE {table} DROP COLUMN checksum"), None);
    }
}

#[test]
fn a_tampered_dimension_is_refused_on_open() {
    let dir = tempfile::tempdir().unwrap();
    let path = filled(dir.path(), 48, 4, 6);
    // 4e12: would size a 16 TB read. Its checksum refuses it first; without checksums, the
    // bound does.
    tamper(
        &path,
        "UPDATE meta SET value = CAST('4000000000000' AS BLOB) WHERE key = 'dimension'",
        None,
    );
    let err = Store::open_readonly(&path).unwrap_err();
    assert!(matches!(err, StoreError::CorruptIndex { .. }), "{err}");
    without_checksums(&path);
    let err = Store::open_readonly(&path).unwrap_err();
    assert!(err.to_string().contains("is not in 1..="), "{err}");
    // 47 over 48-wide blobs: would read misaligned vectors.
    tamper(
        &path,
        "UPDATE meta SET value = CAST('47' AS BLOB) WHERE key = 'dimension'",
        None,
    );
    let err = Store::open(&path).unwrap_err().to_string();
    assert!(
        err.contains("chunk 0 (shapes 0 to 3): has 768 bytes") && err.contains("47 values"),
        "{err}"
    );
}

#[test]
fn a_short_or_long_chunk_blob_is_refused_on_open() {
    let dir = tempfile::tempdir().unwrap();
    let path = filled(dir.path(), 2, 4, 6);
    tamper(
        &path,
        "UPDATE chunks SET data = ?1 WHERE chunk = 1",
        Some(f32_bytes(&[0.5; 5])),
    );
    let err = Store::open_readonly(&path).unwrap_err().to_string();
    assert!(err.contains("chunk 1 (shapes 4 to 5): has 20 bytes"), "{err}");
}

#[test]
fn non_finite_stored_values_are_refused_by_reads_and_appends() {
    let dir = tempfile::tempdir().unwrap();
    let path = filled(dir.path(), 2, 4, 6);
    let mut values = vec![0.5f32; 8];
    values[5] = f32::NAN; // shape 2, index 1
    tamper(
        &path,
        "UPDATE chunks SET data = ?1 WHERE chunk = 0",
        Some(f32_bytes(&values)),
    );
    // Its checksum refuses the chunk first, naming it.
    let store = Store::open(&path).unwrap();
    let err = store.vectors().unwrap_err().to_string();
    assert!(err.contains("chunk 0 (shapes 0 to 3): checksum mismatch"), "{err}");
    drop(store);
    // Without checksums, reads refuse the value, naming the shape; a write is refused anyway.
    without_checksums(&path);
    let mut store = Store::open(&path).unwrap();
    let err = store.vectors().unwrap_err().to_string();
    assert!(
        err.contains("shape 2: value NaN at index 1: stored vectors must be finite"),
        "{err}"
    );
    let err = store
        .search_metric(&[0.5, 0.5], 3, &StandardMetric::L1)
        .unwrap_err()
        .to_string();
    assert!(err.contains("shape 2"), "{err}");
    let v = [0.5, 0.5];
    let err = store.add(&[Entry::new("new", "", &v)]).unwrap_err();
    assert!(matches!(err, StoreError::NoChecksums { .. }), "{err}");
    assert_eq!(store.len().unwrap(), 6);
}

#[test]
fn chi_squared_refuses_negative_bins_instead_of_returning_zero() {
    let dir = tempfile::tempdir().unwrap();
    let path = filled(dir.path(), 2, 4, 4);
    let store = Store::open_readonly(&path).unwrap();
    let err = store
        .search_metric(&[-0.5, 1.5], 2, &StandardMetric::ChiSquared)
        .unwrap_err();
    assert!(
        matches!(err, StoreError::InvalidParameter { name: "query", .. }),
        "{err}"
    );
    drop(store);
    // Checksums catch damage, not meaning: a negative bin that a file holds consistently (here
    // one without checksums) is refused by the distance, naming the shape.
    without_checksums(&path);
    tamper(
        &path,
        "UPDATE chunks SET data = ?1 WHERE chunk = 0",
        Some(f32_bytes(&[0.5, 0.5, 0.5, 0.5, -1.0, 2.0, 0.5, 0.5])),
    );
    let store = Store::open_readonly(&path).unwrap();
    let err = store
        .search_metric(&[0.5, 0.5], 2, &StandardMetric::ChiSquared)
        .unwrap_err();
    assert!(matches!(err, StoreError::InvalidRow { id: 2, .. }), "{err}");
    // L1 has no such requirement.
    assert_eq!(
        store.search_metric(&[0.5, 0.5], 4, &StandardMetric::L1).unwrap().len(),
        4
    );
}

#[test]
fn directories_and_fifos_are_named_as_such() {
    let dir = tempfile::tempdir().unwrap();
    let err = Store::open_readonly(dir.path()).unwrap_err();
    assert!(
        matches!(
            err,
            StoreError::NotAFile {
                kind: "a directory",
                ..
            }
        ),
        "{err}"
    );
    let err = Store::create(dir.path(), &StoreParams::new(3), true).unwrap_err();
    assert!(matches!(err, StoreError::NotAFile { .. }), "{err}");
    #[cfg(unix)]
    {
        let fifo = dir.path().join("fifo.sqlite");
        let status = std::process::Command::new("mkfifo").arg(&fifo).status().unwrap();
        assert!(status.success());
        let err = Store::open(&fifo).unwrap_err();
        assert!(
            matches!(
                err,
                StoreError::NotAFile {
                    kind: "a FIFO (named pipe)",
                    ..
                }
            ),
            "{err}"
        );
        let err = Store::create(&fifo, &StoreParams::new(3), true).unwrap_err();
        assert!(matches!(err, StoreError::NotAFile { .. }), "{err}");
        use std::os::unix::fs::FileTypeExt;
        assert!(
            std::fs::metadata(&fifo).unwrap().file_type().is_fifo(),
            "the FIFO is left as it was"
        );
    }
    let missing = Store::open(&dir.path().join("missing.sqlite")).unwrap_err().to_string();
    assert!(missing.contains("no such store file"), "{missing}");
}

#[test]
fn a_closed_reader_leaves_no_log_or_shared_memory_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = filled(dir.path(), 3, 4, 5);
    let names = || {
        let mut v: Vec<String> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    };
    assert_eq!(names(), ["index.sqlite"]);
    {
        let store = Store::open_readonly(&path).unwrap();
        assert_eq!(
            store.search_metric(&vector(1, 3), 2, &StandardMetric::L1).unwrap()[0].id,
            1
        );
        assert_eq!(store.vectors().unwrap().len(), 15);
    }
    assert_eq!(names(), ["index.sqlite"]);
}

#[test]
fn an_append_to_a_replaced_store_fails_and_adds_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let path = filled(dir.path(), 3, 4, 5);
    let mut writer = Store::open(&path).unwrap();
    // Another process replaces the file (e.g. a `build` of the same path).
    drop(Store::create(&path, &StoreParams::new(3), true).unwrap());
    let v = vector(9, 3);
    let err = writer.add(&[Entry::new("late", "", &v)]).unwrap_err();
    assert!(matches!(err, StoreError::Replaced { .. }), "{err}");
    assert_eq!(Store::open(&path).unwrap().len().unwrap(), 0);
}

#[test]
fn closing_a_writer_of_a_replaced_store_keeps_the_new_files_log() {
    // SQLite finds the log by the file's name: if the last connection to the replaced file
    // folded it into the old file and deleted `-wal` on close, the new file's commits would be
    // lost. SQLite skips that checkpoint for a file that moved (`databaseIsUnmoved` in
    // pager.c); this pins it for the SQLite we bundle and for our own `Drop`.
    let dir = tempfile::tempdir().unwrap();
    let path = filled(dir.path(), 3, 4, 5);
    let stale = Store::open(&path).unwrap();
    assert_eq!(stale.len().unwrap(), 5);
    drop(Store::create(&path, &StoreParams::new(3), true).unwrap());
    let mut fresh = Store::open(&path).unwrap();
    let v = vector(9, 3);
    fresh.add(&[Entry::new("new", "", &v)]).unwrap();
    drop(stale);
    // Another process opening the file now sees the committed shape, and so does everyone
    // once the writer closed.
    assert_eq!(Store::open_readonly(&path).unwrap().len().unwrap(), 1);
    drop(fresh);
    let again = Store::open(&path).unwrap();
    assert_eq!(again.len().unwrap(), 1);
    assert_eq!(again.vectors().unwrap().len(), 3);
}
