//! Checksums (issue #41): a damaged or edited record is a typed `CorruptIndex` naming it —
//! never a changed ranking or shifted distances with success — and `Store::check` lists every
//! damaged record. Files of format version 1 (no checksums) read as unchecked, refuse writes
//! and upgrade in place.

use super::store::vector;
use retrieval_store::metric::StandardMetric;
use retrieval_store::{Entry, Store, StoreError, StoreParams, FORMAT_VERSION};
use rusqlite::{params, Connection};
use std::path::{Path, PathBuf};

const DIM: usize = 8;

/// A store of `n` shapes `s0, s1, …` (vectors [`vector`]) in chunks of 4, with a settings entry.
fn filled(dir: &Path, n: usize) -> PathBuf {
    let path = dir.join("index.sqlite");
    let mut store = Store::create(
        &path,
        &StoreParams {
            dimension: DIM,
            chunk_rows: 4,
        },
        false,
    )
    .unwrap();
    store.set_meta("settings", br#"{"t": 0.125, "words": 8}"#).unwrap();
    let names: Vec<String> = (0..n).map(|i| format!("s{i}")).collect();
    let vectors: Vec<Vec<f64>> = (0..n).map(|i| vector(i, DIM)).collect();
    let entries: Vec<Entry<'_>> = names.iter().zip(&vectors).map(|(n, v)| Entry::new(n, "", v)).collect();
    store.add(&entries).unwrap();
    path
}

/// Flips one bit of a chunk's stored bytes, leaving its checksum as it was (what a bad sector
/// or a stray write does).
fn flip_bit(path: &Path, chunk: i64, byte: usize, bit: u8) {
    let conn = Connection::open(path).unwrap();
    let mut data: Vec<u8> = conn
        .query_row("SELECT data FROM chunks WHERE chunk = ?1", [chunk], |r| r.get(0))
        .unwrap();
    data[byte] ^= 1 << bit;
    conn.execute("UPDATE chunks SET data = ?1 WHERE chunk = ?2", params![data, chunk])
        .unwrap();
}

fn corrupt_record(err: &StoreError) -> &str {
    match err {
        StoreError::CorruptIndex { record, .. } => record,
        other => panic!("expected CorruptIndex, got {other:?}"),
    }
}

#[test]
fn issue_41_a_flipped_bit_in_a_stored_vector_is_corrupt_index_not_a_new_ranking() {
    // The issue's reproduction: 3 of 8 single-bit flips changed the ranking with exit 0 (the
    // query shape dropped out of its own top 5). Every flip, anywhere in a value (mantissa,
    // exponent, sign), is now refused naming the chunk and its shapes.
    for (byte, bit) in [(0, 0), (1, 3), (2, 7), (3, 0), (3, 6), (3, 7), (17, 4), (31, 2)] {
        let dir = tempfile::tempdir().unwrap();
        let path = filled(dir.path(), 10);
        // Chunk 1 holds shapes 4 to 7; byte 4·DIM·k + j is in shape 4 + k.
        let shape = 4 + byte / (DIM * 4);
        flip_bit(&path, 1, byte, bit);
        let store = Store::open_readonly(&path).unwrap();
        let err = store
            .search_metric(&vector(shape, DIM), 5, &StandardMetric::L1)
            .unwrap_err();
        assert_eq!(
            corrupt_record(&err),
            "chunk 1 (shapes 4 to 7)",
            "byte {byte} bit {bit}: {err}"
        );
        assert!(err.to_string().contains("checksum mismatch"), "{err}");
        let err = store.vector(shape as u64).unwrap_err();
        assert_eq!(corrupt_record(&err), "chunk 1 (shapes 4 to 7)");
        assert!(store.vectors().is_err());
        // Shapes in other chunks read as before.
        assert_eq!(store.vector(0).unwrap().unwrap().len(), DIM);
        assert_eq!(store.vector(9).unwrap().unwrap().len(), DIM);
        // Nothing is added to a damaged store.
        drop(store);
        let mut writer = Store::open(&path).unwrap();
        let v = vector(99, DIM);
        let err = writer.add(&[Entry::new("new", "", &v)]).unwrap_err();
        assert_eq!(corrupt_record(&err), "chunk 1 (shapes 4 to 7)");
        assert_eq!(writer.len().unwrap(), 10);
    }
}

#[test]
fn issue_41_one_changed_digit_in_the_settings_is_corrupt_index() {
    // The issue's reproduction: one digit of the stored settings changed shifted every
    // distance with exit 0. Opening now refuses the file, naming the entry.
    let dir = tempfile::tempdir().unwrap();
    let path = filled(dir.path(), 6);
    let conn = Connection::open(&path).unwrap();
    conn.execute(
        "UPDATE meta SET value = CAST(?1 AS BLOB) WHERE key = 'settings'",
        [r#"{"t": 0.135, "words": 8}"#],
    )
    .unwrap();
    drop(conn);
    for err in [
        Store::open_readonly(&path).unwrap_err(),
        Store::open(&path).unwrap_err(),
    ] {
        assert_eq!(corrupt_record(&err), "metadata \"settings\"", "{err}");
        assert!(err.to_string().contains("corrupt index"), "{err}");
    }
    // The reserved entries too: a dimension edited from 8 to 9 is refused by its checksum
    // before the chunk sizes would be.
    let dir = tempfile::tempdir().unwrap();
    let path = filled(dir.path(), 6);
    Connection::open(&path)
        .unwrap()
        .execute("UPDATE meta SET value = CAST('9' AS BLOB) WHERE key = 'dimension'", [])
        .unwrap();
    let err = Store::open_readonly(&path).unwrap_err();
    assert_eq!(corrupt_record(&err), "metadata \"dimension\"", "{err}");
}

#[test]
fn an_edited_shape_row_or_moved_chunk_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let path = filled(dir.path(), 12);
    let conn = Connection::open(&path).unwrap();
    conn.execute("UPDATE shapes SET name = 's99' WHERE id = 5", []).unwrap();
    drop(conn);
    let store = Store::open_readonly(&path).unwrap();
    let err = store.shapes().unwrap_err();
    assert_eq!(corrupt_record(&err), "shape 5 (\"s99\")");
    let err = store.shape(5).unwrap_err();
    assert_eq!(corrupt_record(&err), "shape 5 (\"s99\")");
    // A query whose hits include it fails rather than print the wrong name.
    let err = store
        .search_metric(&vector(5, DIM), 1, &StandardMetric::L1)
        .unwrap_err();
    assert_eq!(corrupt_record(&err), "shape 5 (\"s99\")");
    drop(store);

    // Two whole chunks exchanged: each is intact, but not where it was written.
    let dir = tempfile::tempdir().unwrap();
    let path = filled(dir.path(), 12);
    let conn = Connection::open(&path).unwrap();
    let data = |c: i64| -> Vec<u8> {
        conn.query_row("SELECT data FROM chunks WHERE chunk = ?1", [c], |r| r.get(0))
            .unwrap()
    };
    let (a, b) = (data(0), data(1));
    conn.execute("UPDATE chunks SET data = ?1 WHERE chunk = 0", [b])
        .unwrap();
    conn.execute("UPDATE chunks SET data = ?1 WHERE chunk = 1", [a])
        .unwrap();
    drop(conn);
    let store = Store::open_readonly(&path).unwrap();
    let err = store.vectors().unwrap_err();
    assert_eq!(corrupt_record(&err), "chunk 0 (shapes 0 to 3)");
}

#[test]
fn check_lists_every_damaged_record_and_passes_an_intact_store() {
    let dir = tempfile::tempdir().unwrap();
    let path = filled(dir.path(), 10);
    let report = Store::check(&path).unwrap();
    assert!(report.is_verified(), "{}", report.to_text());
    assert_eq!(
        (report.version, report.metadata, report.shapes, report.chunks),
        (FORMAT_VERSION, 5, 10, 3)
    );
    assert!(report.to_text().contains("intact"), "{}", report.to_text());

    flip_bit(&path, 0, 5, 1);
    flip_bit(&path, 2, 0, 0);
    let conn = Connection::open(&path).unwrap();
    conn.execute(
        "UPDATE meta SET value = CAST('{\"t\": 0.5}' AS BLOB) WHERE key = 'settings'",
        [],
    )
    .unwrap();
    conn.execute("UPDATE shapes SET info = 'x' WHERE id = 3", []).unwrap();
    drop(conn);
    let report = Store::check(&path).unwrap();
    let records: Vec<&str> = report.damage.iter().map(|d| d.record.as_str()).collect();
    assert_eq!(
        records,
        [
            "metadata \"settings\"",
            "shape 3 (\"s3\")",
            "chunk 0 (shapes 0 to 3)",
            "chunk 2 (shapes 8 to 9)"
        ],
        "{}",
        report.to_text()
    );
    assert!(!report.is_verified());
    let text = report.to_text();
    assert!(text.contains("DAMAGED: 4 damaged records"), "{text}");
}

/// Turns a store into one of format version 1 as earlier builds wrote it (no checksum
/// columns).
fn downgrade(path: &Path) {
    let conn = Connection::open(path).unwrap();
    conn.execute_batch(
        "ALTER TABLE meta DROP COLUMN checksum;
         ALTER TABLE shapes DROP COLUMN checksum;
         ALTER TABLE chunks DROP COLUMN checksum;
         UPDATE meta SET value = CAST('1' AS BLOB) WHERE key = 'version';",
    )
    .unwrap();
}

#[test]
fn a_version_1_store_reads_unchecked_refuses_writes_and_upgrades_in_place() {
    let dir = tempfile::tempdir().unwrap();
    let path = filled(dir.path(), 10);
    let before = Store::open_readonly(&path).unwrap().vectors().unwrap();
    downgrade(&path);
    let mut store = Store::open(&path).unwrap();
    assert!(!store.checksummed());
    assert_eq!(store.vectors().unwrap(), before);
    assert_eq!(
        store.search_metric(&vector(3, DIM), 1, &StandardMetric::L1).unwrap()[0].name,
        "s3"
    );
    let v = vector(99, DIM);
    let err = store.add(&[Entry::new("new", "", &v)]).unwrap_err();
    assert!(matches!(err, StoreError::NoChecksums { version: 1, .. }), "{err}");
    assert!(err.to_string().contains("--upgrade"), "{err}");
    let err = store.set_meta("x", b"y").unwrap_err();
    assert!(matches!(err, StoreError::NoChecksums { .. }), "{err}");
    drop(store);
    let report = Store::check(&path).unwrap();
    assert!(!report.checksums && report.damage.is_empty(), "{}", report.to_text());
    assert!(!report.is_verified());
    assert!(report.to_text().contains("unchecked"), "{}", report.to_text());

    let report = Store::upgrade(&path).unwrap();
    assert!(report.is_verified(), "{}", report.to_text());
    let mut store = Store::open(&path).unwrap();
    assert!(store.checksummed());
    assert_eq!(store.vectors().unwrap(), before);
    store.add(&[Entry::new("new", "", &v)]).unwrap();
    drop(store);
    assert!(Store::check(&path).unwrap().is_verified());
    // Upgrading again changes nothing.
    assert!(Store::upgrade(&path).unwrap().is_verified());
}

#[test]
fn a_damaged_version_1_store_is_not_upgraded() {
    let dir = tempfile::tempdir().unwrap();
    let path = filled(dir.path(), 6);
    downgrade(&path);
    let mut values = [0.1f32; 4 * DIM];
    values[DIM + 2] = f32::INFINITY; // shape 1, index 2
    let bytes: Vec<u8> = values.iter().flat_map(|x| x.to_le_bytes()).collect();
    Connection::open(&path)
        .unwrap()
        .execute("UPDATE chunks SET data = ?1 WHERE chunk = 0", [bytes])
        .unwrap();
    let report = Store::check(&path).unwrap();
    assert_eq!(report.damage.len(), 1, "{}", report.to_text());
    assert_eq!(report.damage[0].record, "shape 1");
    let err = Store::upgrade(&path).unwrap_err();
    assert_eq!(corrupt_record(&err), "shape 1");
    assert!(!Store::open_readonly(&path).unwrap().checksummed());
}
