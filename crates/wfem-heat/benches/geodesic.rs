//! Geodesic distances (issue #38 point 4) on icospheres (10K/41K/164K vertices; 655K with
//! `WFEM_BENCH_LARGE=1`, `benches/common/levels.rs` at the workspace root): preparing the
//! default solver (fast marching on the intrinsic Delaunay triangulation) and one further query
//! from a single vertex, by fast marching and by the heat method (its prepare, two sparse
//! Cholesky factorizations, is not measured here: `examples/geodesic_timing.rs --heat`).
//!
//! Run: `cargo bench -p wfem-heat --bench geodesic`. The peers (potpourri3d, libigl) are timed
//! in `benches/peers/geodesics.py`; docs/BENCHMARKS.md has both side by side.
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, SamplingMode};
use mesh_fem::generate;
use std::hint::black_box;
use std::time::Duration;
use wfem_heat::geodesic::{GeodesicMethod, GeodesicParams, GeodesicSolver};

#[path = "../../../benches/common/levels.rs"]
mod levels;

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("geodesic");
    group.sampling_mode(SamplingMode::Flat);
    group.sample_size(10);
    group.warm_up_time(Duration::from_secs(1));
    for level in levels::levels() {
        let mesh = generate::icosphere(level);
        let n = mesh.n_vertices();
        let fmm = GeodesicParams::default();
        group.bench_with_input(BenchmarkId::new("fmm prepare", n), &mesh, |b, mesh| {
            b.iter(|| black_box(GeodesicSolver::new(mesh, &fmm).unwrap()));
        });
        for method in [GeodesicMethod::FastMarching, GeodesicMethod::Heat] {
            let params = GeodesicParams {
                method,
                ..GeodesicParams::default()
            };
            let solver = GeodesicSolver::new(&mesh, &params).unwrap();
            let name = match method {
                GeodesicMethod::FastMarching => "fmm query",
                GeodesicMethod::Heat => "heat query",
            };
            let mut source = 0u32;
            group.bench_with_input(BenchmarkId::new(name, n), &solver, |b, solver| {
                b.iter(|| {
                    // A different source each time, spread over the sphere.
                    source = (source + 7919) % n as u32;
                    black_box(solver.distance(&[source]).unwrap())
                });
            });
        }
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
