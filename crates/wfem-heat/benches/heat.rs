//! Fast exact path vs one backward-Euler step (one real sparse Cholesky of M + tL and one
//! solve) on icospheres of area 4π at t = 0.01.
//!
//! Run: `cargo bench -p wfem-heat --bench heat`.
use criterion::{criterion_group, criterion_main, Criterion};
use mesh_fem::{assemble, generate, AssemblyParams};
use std::f64::consts::PI;
use std::hint::black_box;
use std::time::Duration;
use wfem_heat::{FastParams, HeatKernel, HeatParams, Method};

fn bench(c: &mut Criterion) {
    let t = 0.01;
    for level in [5u32, 6] {
        let mesh = generate::icosphere(level).with_area(4.0 * PI).expect("area");
        let ops = assemble(&mesh, &AssemblyParams::default()).expect("assembly");
        let n = ops.n();
        let f: Vec<f64> = mesh.positions().iter().map(|p| p[0]).collect();
        let mut e = vec![0.0; n];
        e[n / 3] = 1.0;
        let be = HeatKernel::new(
            &ops,
            HeatParams {
                method: Method::BackwardEuler,
                ..Default::default()
            },
        )
        .unwrap();
        // The default method is the rational one; the fast path is named explicitly.
        let fast = HeatKernel::new(
            &ops,
            HeatParams {
                method: Method::Fast(FastParams::default()),
                ..Default::default()
            },
        )
        .unwrap();
        for gamma in [0.05, 0.1, 0.2, 0.4] {
            let params = HeatParams {
                method: Method::Fast(FastParams {
                    gamma,
                    ..Default::default()
                }),
                ..Default::default()
            };
            let k = HeatKernel::new(&ops, params).unwrap();
            for (what, v) in [("x", &f), ("e_i", &e)] {
                let (_, iters, est) = k.apply_fast_report(v, t).unwrap();
                eprintln!("n = {n}, γ = {gamma}, f = {what}: fast path {iters} iterations (estimate {est:.1e})");
            }
        }
        let mut group = c.benchmark_group(format!("heat_n{n}_t0.01"));
        group
            .sample_size(10)
            .warm_up_time(Duration::from_secs(1))
            .measurement_time(Duration::from_secs(4));
        // HeatKernel caches the factor of the last t, so every timed call below uses a new t
        // (relative change 1e−12) to include one full factorization, except `*_same_t`.
        let mut i = 0u64;
        let mut next_t = move || {
            i += 1;
            t * (1.0 + 1e-12 * i as f64)
        };
        group.bench_function("backward_euler", |b| {
            b.iter(|| be.apply(black_box(&f), next_t()).unwrap())
        });
        group.bench_function("fast_x", |b| b.iter(|| fast.apply(black_box(&f), next_t()).unwrap()));
        group.bench_function("fast_e_i", |b| b.iter(|| fast.apply(black_box(&e), next_t()).unwrap()));
        group.bench_function("fast_e_i_same_t", |b| b.iter(|| fast.apply(black_box(&e), t).unwrap()));
        group.finish();
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
