//! Applications of the heat kernel on icospheres of area 4π (10K/41K/164K vertices; 655K with
//! `WFEM_BENCH_LARGE=1`, see `common/levels.rs`):
//!
//! * heat kernel signature at 100 scales (`shape_retrieval::hks::heat_kernel_signature`, automatic
//!   log-spaced times) from k = 100 eigenpairs (the eigensolve is benched in
//!   `wfem-heat/benches/heat.rs`);
//! * 1000 canonical basis functions `K_t e_i` (paper Sect. 4.1, `wfem_heat::canonical_basis`,
//!   rational r = 16 with LU factors shared by all 1000 right-hand sides), t = 0.01;
//! * wFEM diffusion distances from one vertex to all (`DiffusionDistance::row`), t = 0.01:
//!   cold (factorization and probed diagonal included) and warm (one more row).
//!
//! The last two run at 164K vertices only with `WFEM_BENCH_LARGE=1` (the n × 1000 result alone
//! is 1.3 GB there, and the 8 complex LU factors take ~10 GB).
//!
//! Run: `cargo bench --bench applications`.

use criterion::{criterion_group, criterion_main, Criterion, SamplingMode};
use mesh_fem::{assemble, generate, AssemblyParams};
use shape_retrieval::hks::{heat_kernel_signature, HksParams, Spectrum};
use std::f64::consts::PI;
use std::hint::black_box;
use std::time::Duration;
use wfem_heat::basis::canonical_basis;
use wfem_heat::distance::{DiffusionDistance, DistanceKind, DistanceParams};
use wfem_heat::spectral::{EigenParams, Eigenbasis};
use wfem_heat::{HeatKernel, HeatParams};

#[path = "common/levels.rs"]
mod levels;

fn bench(c: &mut Criterion) {
    let t = 0.01;
    for level in levels::levels() {
        let mesh = generate::icosphere(level).with_area(4.0 * PI).expect("area");
        let ops = assemble(&mesh, &AssemblyParams::default()).expect("assembly");
        let n = ops.n();
        let mut group = c.benchmark_group(format!("applications_n{n}"));
        group
            .sample_size(10)
            .sampling_mode(SamplingMode::Flat)
            .warm_up_time(Duration::from_secs(1))
            .measurement_time(Duration::from_secs(4));

        let basis = Eigenbasis::partial(&ops.stiffness, &ops.mass, 100, &EigenParams::default()).unwrap();
        let spectrum = Spectrum::new(&basis.values, basis.vectors.as_ref()).unwrap();
        group.bench_function("hks_100_scales_k100", |b| {
            b.iter(|| heat_kernel_signature(black_box(&spectrum), &HksParams::default()).unwrap())
        });

        if !levels::heavy(level) {
            group.finish();
            continue;
        }
        {
            let kernel = HeatKernel::new(&ops, HeatParams::default()).unwrap();
            let anchors: Vec<u32> = (0..1000u32).map(|i| (i as usize * n / 1000) as u32).collect();
            let mut i = 0u64;
            group.bench_function("canonical_basis_1000", |b| {
                b.iter(|| {
                    // A new t per call, so the factorizations (cached per t) are timed too.
                    i += 1;
                    canonical_basis(&kernel, black_box(&anchors), t * (1.0 + 1e-12 * i as f64)).unwrap()
                })
            });
        }

        let source = n / 3;
        group.bench_function("diffusion_distance_row_cold", |b| {
            b.iter(|| {
                let kernel = HeatKernel::new(&ops, HeatParams::default()).unwrap();
                DiffusionDistance::new(&kernel, DistanceKind::Diffusion, t, &DistanceParams::default())
                    .unwrap()
                    .row(black_box(source))
                    .unwrap()
            })
        });
        let kernel = HeatKernel::new(&ops, HeatParams::default()).unwrap();
        let dd = DiffusionDistance::new(&kernel, DistanceKind::Diffusion, t, &DistanceParams::default()).unwrap();
        dd.row(source).unwrap();
        group.bench_function("diffusion_distance_row_warm", |b| {
            b.iter(|| dd.row(black_box(source + 1)).unwrap())
        });
        group.finish();
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
