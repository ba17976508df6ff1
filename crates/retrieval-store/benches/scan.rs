//! A top-10 query over a million bags (issue #14: "well under a second on this machine").
//!
//! Builds (once, reused across runs) a store of `WFEM_STORE_BENCH_SHAPES` (default 1,000,000)
//! random 48-word histograms under `target/tmp`, then times, for L1 and χ² (every chunk read
//! is verified against its checksum, issue #41):
//!
//! * `open_readonly` + `search_metric(k = 10)`: what `wfem retrieval query` pays per call;
//! * `search_metric` on an open store: what a long-lived process (Python) pays per query.
use criterion::{criterion_group, criterion_main, Criterion};
use retrieval_store::metric::StandardMetric;
use retrieval_store::{Entry, Store, StoreParams};
use std::path::PathBuf;
use std::time::Instant;

const WORDS: usize = 48;

fn histogram(seed: u64) -> Vec<f64> {
    // The workspace's one seeded generator.
    let mut rng = wfem_base::rng::SplitMix64::new(seed);
    let mut v: Vec<f64> = (0..WORDS).map(|_| rng.next_f64().powi(3)).collect();
    let total: f64 = v.iter().sum();
    v.iter_mut().for_each(|x| *x /= total);
    v
}

fn store_path(shapes: usize) -> PathBuf {
    // One file per format version: a file of an older version would be read unchecked.
    PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!(
        "retrieval-store-bench-{shapes}-v{}.sqlite",
        retrieval_store::FORMAT_VERSION
    ))
}

fn build(shapes: usize) -> PathBuf {
    let path = store_path(shapes);
    if let Ok(store) = Store::open_readonly(&path) {
        if store.len().unwrap() == shapes && store.dimension() == WORDS && store.checksummed() {
            return path;
        }
    }
    let start = Instant::now();
    let mut store = Store::create(&path, &StoreParams::new(WORDS), true).unwrap();
    let batch = 50_000;
    for b0 in (0..shapes).step_by(batch) {
        let b1 = (b0 + batch).min(shapes);
        let names: Vec<String> = (b0..b1).map(|i| format!("shapes/{i:07}.off")).collect();
        let vectors: Vec<Vec<f64>> = (b0..b1).map(|i| histogram(i as u64)).collect();
        let entries: Vec<Entry<'_>> = names.iter().zip(&vectors).map(|(n, v)| Entry::new(n, "", v)).collect();
        store.add(&entries).unwrap();
    }
    let size = std::fs::metadata(&path).map(|m| m.len()).unwrap_or(0);
    eprintln!(
        "built {shapes} bags of {WORDS} words in {:.1} s ({:.0} MB)",
        start.elapsed().as_secs_f64(),
        size as f64 / 1e6
    );
    path
}

fn scan(c: &mut Criterion) {
    let shapes: usize = std::env::var("WFEM_STORE_BENCH_SHAPES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1_000_000);
    let path = build(shapes);
    let query = histogram(u64::MAX);
    let mut group = c.benchmark_group(format!("retrieval_store_top10_{shapes}"));
    group.sample_size(10);
    for (name, metric) in [("l1", &StandardMetric::L1), ("chi2", &StandardMetric::ChiSquared)] {
        group.bench_function(format!("open_and_query_{name}"), |b| {
            b.iter(|| {
                let store = Store::open_readonly(&path).unwrap();
                store.search_metric(&query, 10, metric).unwrap()
            })
        });
        let store = Store::open_readonly(&path).unwrap();
        group.bench_function(format!("query_{name}"), |b| {
            b.iter(|| store.search_metric(&query, 10, metric).unwrap())
        });
    }
    group.finish();
}

criterion_group!(benches, scan);
criterion_main!(benches);
