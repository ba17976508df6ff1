//! A writer killed in the middle of a transaction loses nothing already committed and leaves
//! nothing of the interrupted batch.
//!
//! The test runs this test binary again as a child (`crash::writer_child`, selected by an
//! environment variable; without it that test does nothing), which commits batches and reports
//! each on stdout, then starts a batch large enough to take seconds; the parent kills it
//! (SIGKILL) while that transaction is open, reopens the file and checks its contents.

use retrieval_store::metric::StandardMetric;
use retrieval_store::{Entry, Store, StoreParams};
use std::io::{BufRead, BufReader};
use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const CHILD_ENV: &str = "RETRIEVAL_STORE_CRASH_CHILD";
const DIM: usize = 16;
const SMALL: usize = 1000;
const COMMITTED: usize = 3;
/// Large enough that inserting it takes well over the parent's grace period.
const HUGE: usize = 400_000;

fn batch(range: std::ops::Range<usize>) -> (Vec<String>, Vec<Vec<f64>>) {
    (
        range.clone().map(|i| format!("shape-{i}")).collect(),
        range.map(|i| crate::store::vector(i, DIM)).collect(),
    )
}

fn add(store: &mut Store, range: std::ops::Range<usize>) {
    let (names, vectors) = batch(range);
    let entries: Vec<Entry<'_>> = names.iter().zip(&vectors).map(|(n, v)| Entry::new(n, "", v)).collect();
    store.add(&entries).unwrap();
}

#[test]
fn writer_child() {
    let Some(path) = std::env::var_os(CHILD_ENV) else {
        return;
    };
    let path = PathBuf::from(path);
    let mut store = Store::create(
        &path,
        &StoreParams {
            dimension: DIM,
            chunk_rows: 256,
        },
        false,
    )
    .unwrap();
    for b in 0..COMMITTED {
        add(&mut store, b * SMALL..(b + 1) * SMALL);
        println!("@@committed {}", b + 1);
    }
    println!("@@begin huge");
    add(&mut store, COMMITTED * SMALL..COMMITTED * SMALL + HUGE);
    println!("@@committed huge");
    // Wait to be killed.
    std::thread::sleep(Duration::from_secs(600));
}

#[test]
fn killed_writer_loses_nothing_committed() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("index.sqlite");
    let mut child = Command::new(std::env::current_exe().unwrap())
        .args(["crash::writer_child", "--exact", "--nocapture", "--test-threads=1"])
        .env(CHILD_ENV, &path)
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let stdout = child.stdout.take().unwrap();
    let mut lines = BufReader::new(stdout).lines();
    let mut committed = 0;
    loop {
        let line = lines.next().expect("child ended early").unwrap();
        if let Some(n) = line.strip_prefix("@@committed ") {
            assert_ne!(n, "huge", "the huge batch committed before the kill; make HUGE larger");
            committed = n.parse().unwrap();
        }
        if line == "@@begin huge" {
            break;
        }
    }
    assert_eq!(committed, COMMITTED);
    // Let the huge transaction write part of its pages (to the log), then kill it.
    let start = Instant::now();
    std::thread::sleep(Duration::from_millis(300));
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(start.elapsed() < Duration::from_secs(60));

    let mut store = Store::open(&path).unwrap();
    let n = COMMITTED * SMALL;
    assert_eq!(store.len().unwrap(), n);
    let all = store.vectors().unwrap();
    assert_eq!(all.len(), n * DIM);
    for i in [0, 1, SMALL, n - 1] {
        let expect: Vec<f32> = crate::store::vector(i, DIM).iter().map(|&x| x as f32).collect();
        assert_eq!(&all[i * DIM..(i + 1) * DIM], &expect[..]);
    }
    assert!(store.find(&format!("shape-{n}")).unwrap().is_none());
    let hits = store
        .search_metric(&crate::store::vector(5, DIM), 1, &StandardMetric::L1)
        .unwrap();
    assert_eq!(hits[0].id, 5);
    // The store keeps working after recovery.
    add(&mut store, n..n + 10);
    assert_eq!(store.len().unwrap(), n + 10);
}
