//! The eigensolver of the spectral path: `Eigenbasis::partial` (shift-and-invert thick-restart
//! block Lanczos, `shifted_solve::eigen::largest_eigenpairs`) for the k = 100 smallest pairs of
//! (L, B), on icospheres of area 4π (10K/41K vertices; 164K with `WFEM_BENCH_LARGE=1`), by
//! block size b (default 8) and basis bound (default 2k + b; also 3k: fewer restarts, more
//! memory).
//!
//! This is the eigensolve of `wfem hks --eigs 100`; the whole command against scipy's `eigsh`
//! is timed by `cargo xtask bench` (peers table, docs/BENCHMARKS.md).
//!
//! Run: `cargo bench -p wfem-heat --bench eigen`.
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, SamplingMode};
use mesh_fem::{assemble, generate, AssemblyParams};
use std::f64::consts::PI;
use std::time::Duration;
use wfem_heat::spectral::{EigenParams, Eigenbasis};

#[path = "../../../benches/common/levels.rs"]
mod levels;

fn bench(c: &mut Criterion) {
    let k = 100;
    // Seconds per eigensolve at 41K, tens at 164K: the latter only on request.
    for level in levels::levels()
        .into_iter()
        .filter(|&l| l <= 6 || (l == 7 && levels::large()))
    {
        let mesh = generate::icosphere(level).with_area(4.0 * PI).unwrap();
        let ops = assemble(&mesh, &AssemblyParams::default()).unwrap();
        let mut group = c.benchmark_group(format!("eigen_k100/n{}", mesh.n_vertices()));
        group
            .sampling_mode(SamplingMode::Flat)
            .sample_size(10)
            .warm_up_time(Duration::from_secs(1))
            .measurement_time(Duration::from_secs(10));
        for (block, max_dim) in [(4, None), (8, None), (16, None), (8, Some(3 * k))] {
            let params = EigenParams {
                block_size: block,
                max_dim,
                ..EigenParams::default()
            };
            let label = format!("b{block}_basis{}", params.basis_bound(k, mesh.n_vertices()));
            group.bench_with_input(BenchmarkId::new("partial", label), &params, |b, params| {
                b.iter(|| Eigenbasis::partial(&ops.stiffness, &ops.mass, k, params).unwrap())
            });
        }
        group.finish();
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
