//! Mesh sizes of every criterion bench of the workspace (one source of truth, included with
//! `#[path]` by the crates' benches; depends on std only).
//!
//! * default: icosphere levels 5, 6, 7 = 10,242 / 40,962 / 163,842 vertices;
//! * `WFEM_BENCH_LARGE=1` adds level 8 = 655,362 vertices (opt-in: minutes per bench and
//!   several GB for the spectral method);
//! * `WFEM_BENCH_LEVELS=4,5` replaces the list (e.g. for a quick look).
//!
//! Benches that cost tens of seconds per iteration at 164K vertices (the rational method's 8
//! complex LUs, the spectral eigensolves, 1000-column blocks) run at 164K and above only with
//! `WFEM_BENCH_LARGE=1` ([`heavy`]), and the spectral method at 41K and above likewise
//! ([`spectral`]), so that a default `cargo bench` finishes in well under an hour on 2 cores.
//! `cargo xtask bench` measures them at every size once (median of a few one-shot runs).
//!
//! The test suite never runs benches: `cargo test` builds and runs only libs, bins, tests,
//! examples and doctests; bench targets run under `cargo bench` (or `cargo test --benches`).

/// Icosphere levels to benchmark (see the module docs).
#[allow(dead_code)]
pub fn levels() -> Vec<u32> {
    if let Ok(list) = std::env::var("WFEM_BENCH_LEVELS") {
        let parsed: Vec<u32> = list.split(',').filter_map(|x| x.trim().parse().ok()).collect();
        if !parsed.is_empty() {
            return parsed;
        }
    }
    let mut levels = vec![5, 6, 7];
    if large() {
        levels.push(8);
    }
    levels
}

/// `levels()` without the ones above `max` (for benches whose cost or memory explodes).
#[allow(dead_code)]
pub fn levels_up_to(max: u32) -> Vec<u32> {
    levels().into_iter().filter(|&l| l <= max).collect()
}

/// `WFEM_BENCH_LARGE=1`?
#[allow(dead_code)]
pub fn large() -> bool {
    std::env::var("WFEM_BENCH_LARGE").is_ok_and(|v| v == "1")
}

/// Whether an expensive bench (rational method, multi-column blocks) runs at `level`:
/// up to 41K vertices (level 6) by default, everywhere with `WFEM_BENCH_LARGE=1`.
#[allow(dead_code)]
pub fn heavy(level: u32) -> bool {
    level <= 6 || large()
}

/// Whether the spectral method (eigensolve with k up to 300) runs at `level`: up to 10K
/// vertices (level 5) by default, everywhere with `WFEM_BENCH_LARGE=1`.
#[allow(dead_code)]
pub fn spectral(level: u32) -> bool {
    level <= 5 || large()
}
