//! Round trips, appends, search against brute force, errors, concurrent readers.

use retrieval_store::metric::{Metric, StandardMetric};
use retrieval_store::{Entry, Store, StoreError, StoreParams};
use std::path::Path;

/// A deterministic histogram-like vector for shape i.
pub fn vector(i: usize, dim: usize) -> Vec<f64> {
    let mut v: Vec<f64> = (0..dim)
        .map(|j| {
            let x = ((i * 7919 + j * 104_729) % 1000) as f64 / 1000.0;
            x * x + 1e-3
        })
        .collect();
    let s: f64 = v.iter().sum();
    v.iter_mut().for_each(|x| *x /= s);
    v
}

fn add_range(store: &mut Store, range: std::ops::Range<usize>) -> Vec<u64> {
    let dim = store.dimension();
    let names: Vec<String> = range.clone().map(|i| format!("shape-{i}")).collect();
    let vectors: Vec<Vec<f64>> = range.clone().map(|i| vector(i, dim)).collect();
    let entries: Vec<Entry<'_>> = names
        .iter()
        .zip(&vectors)
        .map(|(n, v)| Entry::new(n, "info", v))
        .collect();
    store.add(&entries).unwrap()
}

fn brute_force(n: usize, dim: usize, query: &[f64], k: usize, metric: StandardMetric) -> Vec<(u64, f64)> {
    let mut all: Vec<(u64, f64)> = (0..n)
        .map(|i| {
            let row: Vec<f32> = vector(i, dim).iter().map(|&x| x as f32).collect();
            (i as u64, metric.eval(query, &row))
        })
        .collect();
    all.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
    all.truncate(k);
    all
}

fn create(dir: &Path, dim: usize, chunk_rows: usize) -> Store {
    Store::create(
        &dir.join("index.sqlite"),
        &StoreParams {
            dimension: dim,
            chunk_rows,
        },
        false,
    )
    .unwrap()
}

#[test]
fn round_trip_meta_shapes_and_vectors() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("index.sqlite");
    {
        let mut store = Store::create(&path, &StoreParams::new(5), false).unwrap();
        assert!(store.is_empty().unwrap());
        store.set_meta("settings", b"{\"a\": 1}").unwrap();
        store.set_meta("settings", b"{\"a\": 2}").unwrap();
        store.set_meta("vocabulary", &[0u8, 1, 2, 255]).unwrap();
        assert_eq!(add_range(&mut store, 0..10), (0..10).collect::<Vec<u64>>());
    }
    let store = Store::open_readonly(&path).unwrap();
    assert_eq!(store.len().unwrap(), 10);
    assert_eq!(store.dimension(), 5);
    assert_eq!(store.meta("settings").unwrap().unwrap(), b"{\"a\": 2}");
    assert_eq!(store.meta("vocabulary").unwrap().unwrap(), vec![0u8, 1, 2, 255]);
    assert_eq!(store.meta("missing").unwrap(), None);
    let shapes = store.shapes().unwrap();
    assert_eq!(shapes.len(), 10);
    assert_eq!(shapes[3].name, "shape-3");
    assert_eq!(shapes[3].info, "info");
    assert_eq!(store.find("shape-7").unwrap().unwrap().id, 7);
    assert_eq!(store.find("nope").unwrap(), None);
    let all = store.vectors().unwrap();
    for i in 0..10 {
        let expect: Vec<f32> = vector(i, 5).iter().map(|&x| x as f32).collect();
        assert_eq!(&all[i * 5..(i + 1) * 5], &expect[..]);
        assert_eq!(store.vector(i as u64).unwrap().unwrap(), expect);
    }
    assert_eq!(store.vector(10).unwrap(), None);
}

#[test]
fn appends_fill_chunks_without_rewriting_and_search_matches_brute_force() {
    let dir = tempfile::tempdir().unwrap();
    let dim = 7;
    let mut store = create(dir.path(), dim, 4);
    let mut n = 0;
    // Batches of 1, 3, 5, 2, 9 cross chunk boundaries at every offset.
    for size in [1, 3, 5, 2, 9] {
        let ids = add_range(&mut store, n..n + size);
        assert_eq!(ids, (n as u64..(n + size) as u64).collect::<Vec<_>>());
        n += size;
        assert_eq!(store.len().unwrap(), n);
        for metric in [
            StandardMetric::L1,
            StandardMetric::ChiSquared,
            StandardMetric::Euclidean,
        ] {
            let query = vector(1000 + n, dim);
            for k in [1, 3, n, n + 5] {
                let hits = store.search_metric(&query, k, &metric).unwrap();
                let expect = brute_force(n, dim, &query, k, metric);
                assert_eq!(hits.len(), expect.len());
                for (h, (id, d)) in hits.iter().zip(&expect) {
                    assert_eq!(h.id, *id);
                    assert_eq!(h.distance, *d);
                    assert_eq!(h.name, format!("shape-{id}"));
                }
            }
        }
    }
    // Reopening checks the chunk invariants.
    let path = store.path().to_path_buf();
    drop(store);
    let store = Store::open(&path).unwrap();
    assert_eq!(store.len().unwrap(), n);
    assert!(store
        .search_metric(&vector(0, dim), 0, &StandardMetric::L1)
        .unwrap()
        .is_empty());
}

#[test]
fn ties_are_broken_by_id_whatever_the_thread_count() {
    let dir = tempfile::tempdir().unwrap();
    let mut store = create(dir.path(), 2, 3);
    let names: Vec<String> = (0..20).map(|i| format!("s{i}")).collect();
    let v = [0.5, 0.5];
    let entries: Vec<Entry<'_>> = names.iter().map(|n| Entry::new(n, "", &v)).collect();
    store.add(&entries).unwrap();
    let path = store.path().to_path_buf();
    for threads in [1, 2, 5] {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        let hits = pool.install(|| {
            let reader = Store::open_readonly(&path).unwrap();
            reader.search_metric(&[0.5, 0.5], 4, &StandardMetric::L1).unwrap()
        });
        assert_eq!(hits.iter().map(|h| h.id).collect::<Vec<_>>(), vec![0, 1, 2, 3]);
    }
}

#[test]
fn every_error_names_its_culprit() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("index.sqlite");
    assert!(matches!(
        Store::create(&path, &StoreParams::new(0), false),
        Err(StoreError::InvalidParameter { name: "dimension", .. })
    ));
    assert!(matches!(
        Store::create(
            &path,
            &StoreParams {
                dimension: 2,
                chunk_rows: 0
            },
            false
        ),
        Err(StoreError::InvalidParameter { name: "chunk_rows", .. })
    ));
    let mut store = Store::create(&path, &StoreParams::new(2), false).unwrap();
    assert!(matches!(
        Store::create(&path, &StoreParams::new(2), false),
        Err(StoreError::Exists { .. })
    ));
    let bad_len = store.add(&[Entry::new("a", "", &[1.0])]).unwrap_err();
    assert!(
        matches!(
            bad_len,
            StoreError::Dimension {
                expected: 2,
                found: 1,
                ..
            }
        ),
        "{bad_len}"
    );
    let nan = store.add(&[Entry::new("a", "", &[1.0, f64::NAN])]).unwrap_err();
    assert!(matches!(nan, StoreError::NonFinite { index: 1, .. }), "{nan}");
    let big = store.add(&[Entry::new("a", "", &[1e300, 0.0])]).unwrap_err();
    assert!(matches!(big, StoreError::NonFinite { index: 0, .. }), "{big}");
    let empty = store.add(&[Entry::new("", "", &[1.0, 0.0])]).unwrap_err();
    assert!(matches!(empty, StoreError::EmptyName { index: 0 }));
    let twice = store
        .add(&[Entry::new("a", "", &[1.0, 0.0]), Entry::new("a", "", &[0.0, 1.0])])
        .unwrap_err();
    assert!(matches!(twice, StoreError::DuplicateName { ref name } if name == "a"));
    store.add(&[Entry::new("a", "", &[1.0, 0.0])]).unwrap();
    let again = store.add(&[Entry::new("b", "", &[1.0, 0.0]), Entry::new("a", "", &[0.0, 1.0])]);
    assert!(matches!(again, Err(StoreError::DuplicateName { ref name }) if name == "a"));
    // A refused batch writes nothing.
    assert_eq!(store.len().unwrap(), 1);
    assert!(store.find("b").unwrap().is_none());
    assert!(matches!(
        store.set_meta("dimension", b"3"),
        Err(StoreError::InvalidParameter { name: "key", .. })
    ));
    assert!(matches!(
        store.search_metric(&[1.0], 1, &StandardMetric::L1),
        Err(StoreError::Dimension { .. })
    ));
    assert!(matches!(
        store.search_metric(&[1.0, f64::INFINITY], 1, &StandardMetric::L1),
        Err(StoreError::NonFinite { index: 1, .. })
    ));
    assert!(matches!(
        store.search(1, |_| f64::NAN),
        Err(StoreError::NanDistance { id: 0 })
    ));
    drop(store);

    let mut ro = Store::open_readonly(&path).unwrap();
    assert!(matches!(
        ro.add(&[Entry::new("c", "", &[1.0, 0.0])]),
        Err(StoreError::InvalidParameter { name: "store", .. })
    ));

    let missing = Store::open(&dir.path().join("missing.sqlite")).unwrap_err();
    assert!(matches!(missing, StoreError::Io { .. }), "{missing}");
    let text = dir.path().join("text.sqlite");
    std::fs::write(&text, "this is not a database, just some text that is long enough").unwrap();
    let not_db = Store::open(&text).unwrap_err();
    assert!(matches!(not_db, StoreError::NotAStore { .. }), "{not_db}");
    let other = dir.path().join("other.sqlite");
    rusqlite::Connection::open(&other)
        .unwrap()
        .execute_batch("CREATE TABLE t (x INTEGER);")
        .unwrap();
    assert!(matches!(Store::open(&other), Err(StoreError::NotAStore { .. })));
    let conn = rusqlite::Connection::open(&path).unwrap();
    // Edited in place, the version fails its checksum; a file of a version this build does not
    // know (here without checksum columns, so nothing contradicts it) is named as such.
    conn.execute("UPDATE meta SET value = CAST('9' AS BLOB) WHERE key = 'version'", [])
        .unwrap();
    assert!(matches!(Store::open(&path), Err(StoreError::CorruptIndex { .. })));
    conn.execute_batch(
        "ALTER TABLE meta DROP COLUMN checksum; ALTER TABLE shapes DROP COLUMN checksum;
         ALTER TABLE chunks DROP COLUMN checksum;",
    )
    .unwrap();
    drop(conn);
    assert!(matches!(
        Store::open(&path),
        Err(StoreError::UnsupportedVersion {
            found: 9,
            supported: 2,
            ..
        })
    ));
}

#[test]
fn corrupt_chunk_counts_are_refused_on_open() {
    let dir = tempfile::tempdir().unwrap();
    let mut store = create(dir.path(), 3, 2);
    add_range(&mut store, 0..5);
    let path = store.path().to_path_buf();
    drop(store);
    rusqlite::Connection::open(&path)
        .unwrap()
        .execute("DELETE FROM chunks WHERE chunk = 2", [])
        .unwrap();
    let err = Store::open(&path).unwrap_err();
    assert!(
        matches!(&err, StoreError::CorruptIndex { record, .. } if record == "the chunk table"),
        "{err}"
    );
}

#[test]
fn overwrite_replaces_atomically_and_open_readers_keep_the_old_store() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("index.sqlite");
    let mut old = Store::create(&path, &StoreParams::new(3), false).unwrap();
    add_range(&mut old, 0..4);
    drop(old);
    let reader = Store::open_readonly(&path).unwrap();
    assert_eq!(reader.len().unwrap(), 4);
    // The reader holds the file open: its log is empty between transactions, so replacing works.
    let new = Store::create(&path, &StoreParams::new(5), true).unwrap();
    assert_eq!(new.len().unwrap(), 0);
    assert_eq!(new.dimension(), 5);
    assert_eq!(reader.len().unwrap(), 4);
    assert_eq!(Store::open(&path).unwrap().dimension(), 5);
}

#[test]
fn concurrent_readers_see_whole_committed_batches() {
    let dir = tempfile::tempdir().unwrap();
    let dim = 6;
    let batch = 50;
    let batches = 20;
    let mut store = create(dir.path(), dim, 64);
    let path = store.path().to_path_buf();
    let stop = std::sync::atomic::AtomicBool::new(false);
    std::thread::scope(|s| {
        let readers: Vec<_> = (0..3)
            .map(|r| {
                let path = &path;
                let stop = &stop;
                s.spawn(move || {
                    let store = Store::open_readonly(path).unwrap();
                    let mut checks = 0;
                    while !stop.load(std::sync::atomic::Ordering::Relaxed) || checks == 0 {
                        let n = store.len().unwrap();
                        assert_eq!(n % batch, 0, "reader {r} saw a partial batch");
                        let all = store.vectors().unwrap();
                        assert!(all.len() >= n * dim);
                        assert_eq!(all.len() % (batch * dim), 0);
                        let hits = store.search_metric(&vector(7, dim), 3, &StandardMetric::L1).unwrap();
                        if n > 7 {
                            assert_eq!(hits[0].id, 7);
                            assert!(hits[0].distance < 1e-6);
                        }
                        checks += 1;
                    }
                    checks
                })
            })
            .collect();
        for b in 0..batches {
            add_range(&mut store, b * batch..(b + 1) * batch);
        }
        stop.store(true, std::sync::atomic::Ordering::Relaxed);
        for r in readers {
            assert!(r.join().unwrap() > 0);
        }
    });
    assert_eq!(store.len().unwrap(), batch * batches);
}
