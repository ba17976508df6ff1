//! K_t f by every method on icospheres of area 4π at t = 0.01 (10K/41K/164K vertices; 655K
//! with `WFEM_BENCH_LARGE=1`; see `benches/common/levels.rs` at the workspace root):
//!
//! * one backward-Euler step (one real sparse Cholesky of M + tL and one solve) and one Taylor
//!   step (Eq. (9));
//! * the fast exact path (shift-and-invert rational Krylov), f = x coordinate and f = e_i, and
//!   repeated calls at the same t (factor cached);
//! * the paper's rational method (Eq. (13)): degree 16 with the multi-shift backend (one real
//!   Cholesky, every size), with the direct LDLᵀ and the MINRES backends, and degree 7 (the
//!   paper's r) with LDLᵀ (these three at 164K only with `WFEM_BENCH_LARGE=1`);
//! * 100 log-spaced times over three decades from one factorization (`apply_times`);
//! * the exact diagonal K̃_t(i, i) by selected inversion, and a whole row of diffusion
//!   distances (one kernel column plus the diagonal of H_{2t});
//! * the spectral method (Eq. (8)) with k = 100, 200, 300 eigenpairs, eigensolve included
//!   (`HeatKernel::new` + `apply`), and the apply alone with the eigenpairs precomputed
//!   (41K and above only with `WFEM_BENCH_LARGE=1`: tens of seconds per iteration).
//!
//! Run: `cargo bench -p wfem-heat --bench heat`. The generated report (`cargo xtask bench`)
//! measures the same quantities at every size as one-shot medians with peak memory.
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, SamplingMode};
use mesh_fem::{assemble, generate, AssemblyParams};
use shifted_solve::backend::Backend;
use shifted_solve::function::KrylovParams;
use shifted_solve::iterative::MinresParams;
use std::f64::consts::PI;
use std::hint::black_box;
use std::time::Duration;
use wfem_heat::distance::{DiffusionDistance, DistanceKind, DistanceParams};
use wfem_heat::method::Method;
use wfem_heat::spectral::{EigenParams, Eigenbasis};
use wfem_heat::{DiagonalParams, HeatKernel, HeatParams, KernelDiagonal};

#[path = "../../../benches/common/levels.rs"]
mod levels;

fn kernel(ops: &mesh_fem::FemOperators, method: Method) -> HeatKernel {
    HeatKernel::new(
        ops,
        HeatParams {
            method,
            ..Default::default()
        },
    )
    .unwrap()
}

fn bench(c: &mut Criterion) {
    let t = 0.01;
    for level in levels::levels() {
        let mesh = generate::icosphere(level).with_area(4.0 * PI).expect("area");
        let ops = assemble(&mesh, &AssemblyParams::default()).expect("assembly");
        let n = ops.n();
        let f: Vec<f64> = mesh.positions().iter().map(|p| p[0]).collect();
        let mut e = vec![0.0; n];
        e[n / 3] = 1.0;
        let fast = kernel(&ops, Method::Fast(KrylovParams::default()));
        for (what, v) in [("x", &f), ("e_i", &e)] {
            let (_, iters, est) = fast.apply_fast_report(v, t).unwrap();
            eprintln!("n = {n}, f = {what}: fast path {iters} iterations (estimate {est:.1e})");
        }
        let mut group = c.benchmark_group(format!("heat_n{n}_t0.01"));
        group
            .sample_size(10)
            .sampling_mode(SamplingMode::Flat)
            .warm_up_time(Duration::from_secs(1))
            .measurement_time(Duration::from_secs(4));
        // HeatKernel caches the factors of the last t, so every timed call below uses a new t
        // (relative change 1e−12) to include every t-dependent factorization, except `*_same_t`.
        let mut i = 0u64;
        let mut next_t = move || {
            i += 1;
            t * (1.0 + 1e-12 * i as f64)
        };
        let be = kernel(&ops, Method::BackwardEuler);
        group.bench_function("backward_euler", |b| {
            b.iter(|| be.apply(black_box(&e), next_t()).unwrap())
        });
        let taylor = kernel(&ops, Method::Taylor);
        group.bench_function("taylor", |b| b.iter(|| taylor.apply(black_box(&e), t).unwrap()));
        group.bench_function("fast_x", |b| b.iter(|| fast.apply(black_box(&f), next_t()).unwrap()));
        group.bench_function("fast_e_i", |b| b.iter(|| fast.apply(black_box(&e), next_t()).unwrap()));
        group.bench_function("fast_e_i_same_t", |b| b.iter(|| fast.apply(black_box(&e), t).unwrap()));
        // Issue #17: 100 log-spaced t over three decades around t from one factorization
        // (`apply_times`), against one K_t f (`fast_x`): target ≤ 3×.
        let window: Vec<f64> = (0..100).map(|i| 0.1 * t * 1e3f64.powf(f64::from(i) / 99.0)).collect();
        let fx = faer::Mat::from_fn(n, 1, |i, _| f[i]);
        group.bench_function("fast_x_100_times", |b| {
            b.iter(|| {
                let w: Vec<f64> = window.iter().map(|&s| s * next_t() / t).collect();
                fast.apply_times(black_box(fx.as_ref()), &w).unwrap()
            })
        });
        // The multi-shift rational backend costs about what the fast path costs: every level.
        let mut rational = vec![(
            "rational_r16_multishift",
            Method::Rational {
                degree: 16,
                backend: Backend::MultiShift(KrylovParams::default()),
            },
        )];
        rational.extend(if levels::heavy(level) {
            vec![
                ("rational_r16_ldlt", Method::rational(16)),
                (
                    "rational_r16_minres",
                    Method::Rational {
                        degree: 16,
                        backend: Backend::Minres(MinresParams::default()),
                    },
                ),
                ("rational_r7_ldlt", Method::rational(7)),
            ]
        } else {
            Vec::new()
        });
        for (name, method) in rational {
            let k = kernel(&ops, method);
            group.bench_function(name, |b| b.iter(|| k.apply(black_box(&e), next_t()).unwrap()));
        }
        // The exact diagonal K̃_t(i, i) (the HKS without truncation) by selected inversion, and
        // a whole row of diffusion distances (one column plus that diagonal at 2t).
        let diagonal = DiagonalParams::default();
        group.bench_function("diagonal_selected_inversion", |b| {
            b.iter(|| {
                fast.diagonal(&[next_t()], KernelDiagonal::KernelValue, &diagonal)
                    .unwrap()
            })
        });
        group.bench_function("distance_row", |b| {
            b.iter(|| {
                let dd = DiffusionDistance::new(&fast, DistanceKind::Diffusion, next_t(), &DistanceParams::default())
                    .unwrap();
                dd.row(black_box(n / 3)).unwrap()
            })
        });
        let ks: &[usize] = if levels::spectral(level) { &[100, 200, 300] } else { &[] };
        for &k in ks {
            group.bench_with_input(BenchmarkId::new("spectral_incl_eigensolve", k), &k, |b, &k| {
                b.iter(|| kernel(&ops, Method::spectral(k)).apply(black_box(&e), t).unwrap())
            });
            let basis = Eigenbasis::partial(&ops.stiffness, &ops.mass, k, &EigenParams::default()).unwrap();
            group.bench_with_input(BenchmarkId::new("spectral_apply_only", k), &k, |b, _| {
                b.iter(|| basis.apply_heat(&ops.mass, black_box(&e), t).unwrap())
            });
        }
        group.finish();
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
