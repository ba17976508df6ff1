//! Assembly of the FEM operators L, B and D (`mesh_fem::assemble`) on icospheres of
//! 10K, 41K and 164K vertices (655K with `WFEM_BENCH_LARGE=1`, see `benches/common/levels.rs`),
//! and, separately, the generation of those meshes.
//!
//! Run: `cargo bench --bench assembly -- --warm-up-time 1 --measurement-time 5 --sample-size 10`.
//! The timed region is the call to `assemble`; freeing the returned matrices is not timed
//! (`iter_with_large_drop`), as for a caller that keeps the operators.
//! Results and the comparison with libigl are in `docs/BENCHMARKS.md`.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use mesh_fem::generate::icosphere;
use mesh_fem::{assemble, AssemblyParams, Lumping};
use std::hint::black_box;

#[path = "common/levels.rs"]
mod levels;

fn bench_assembly(c: &mut Criterion) {
    let mut group = c.benchmark_group("assemble_LBD");
    for level in levels::levels() {
        let mesh = icosphere(level);
        let n = mesh.n_vertices();
        group.throughput(Throughput::Elements(mesh.n_faces() as u64));
        group.bench_with_input(BenchmarkId::new("icosphere", n), &mesh, |b, mesh| {
            b.iter_with_large_drop(|| assemble(black_box(mesh), &AssemblyParams::default()))
        });
    }
    group.finish();

    let mut group = c.benchmark_group("assemble_LBD_voronoi");
    let mesh = icosphere(levels::levels().into_iter().max().unwrap_or(5));
    let params = AssemblyParams {
        lumping: Lumping::Voronoi,
        ..Default::default()
    };
    group.bench_with_input(BenchmarkId::new("icosphere", mesh.n_vertices()), &mesh, |b, mesh| {
        b.iter_with_large_drop(|| assemble(black_box(mesh), &params))
    });
    group.finish();
}

fn bench_generation(c: &mut Criterion) {
    let mut group = c.benchmark_group("generate_icosphere");
    for level in levels::levels() {
        let n = mesh_fem::generate::icosphere_vertex_count(level);
        group.bench_with_input(BenchmarkId::new("vertices", n), &level, |b, &level| {
            b.iter(|| icosphere(black_box(level)).n_vertices())
        });
    }
    group.finish();
}

criterion_group!(benches, bench_assembly, bench_generation);
criterion_main!(benches);
