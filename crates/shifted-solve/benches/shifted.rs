//! Costs of the shifted solves on mesh-like matrices (icospheres, consistent FEM mass):
//! LU symbolic / numeric per pole / solve, Cholesky of the preconditioner, one real Cholesky
//! solve (faer's sequential sweep and our tree-parallel one), MINRES per pole, and
//! all 8 poles of degree 16 for one right-hand side (the K_t f of paper Eq. (13)).
//!
//! Per-pole factor and solve of each backend: `DirectLdlt` = `ldlt_numeric_per_pole` (factor,
//! including the assembly of tL − zB) + `ldlt_solve_1rhs` (solve, including the residual check);
//! `DirectLu` = `lu_numeric_per_pole` (factor) + `lu_solve_1rhs` (solve); `Minres` = `cholesky_numeric_P` (its per-pole preconditioner
//! factor) + `minres_per_pole_solve_only` (solve).
//!
//! Run: `cargo bench -p shifted-solve --bench shifted -- --warm-up-time 1 --measurement-time 5 --sample-size 10`
//! (icosphere levels 5, 6, 7 = 10K/41K/164K vertices, all 8 poles at 164K only with
//! `WFEM_BENCH_LARGE=1`, which also adds 655K;
//! `WFEM_BENCH_LEVELS=5,6` replaces the list: see `benches/common/levels.rs` at the root).

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Llt, Lu, SymbolicLlt, SymbolicLu};
use faer::sparse::SparseColMat;
use faer::{c64, Mat, Side};
use shifted_solve::backend::Backend;
use shifted_solve::iterative::{MinresParams, Preconditioner, PreconditionerShift};
use shifted_solve::poles::RationalApprox;
use shifted_solve::{CholeskyPattern, ShiftedSolver};

const T: f64 = 0.01;

fn shifted(l: &SparseColMat<usize, f64>, b: &SparseColMat<usize, f64>, z: c64) -> SparseColMat<usize, c64> {
    // L and B share one pattern (mesh-fem guarantees it).
    let vals = l
        .val()
        .iter()
        .zip(b.val())
        .map(|(&lv, &bv)| c64::new(T * lv - z.re * bv, -z.im * bv))
        .collect();
    SparseColMat::new(l.symbolic().to_owned().unwrap(), vals)
}

#[path = "../../../benches/common/levels.rs"]
mod levels;
use levels::levels;

fn bench(c: &mut Criterion) {
    // The solver runs faer sequentially inside each pole and parallelises across poles; measure
    // the faer primitives the same way.
    faer::set_global_parallelism(faer::Par::Seq);
    let approx = RationalApprox::cram(16).unwrap();
    let z = approx.poles[7];
    for level in levels() {
        let mesh = mesh_fem::generate::icosphere(level);
        let ops = mesh_fem::assemble(&mesh, &mesh_fem::AssemblyParams::default()).unwrap();
        let (l, b) = (ops.stiffness, ops.mass);
        let n = l.nrows();
        let f = Mat::<f64>::from_fn(n, 1, |i, _| ((i * 7919) % 1000) as f64 / 1000.0 - 0.5);
        let mut g = c.benchmark_group(format!("shifted-solve/n={n}"));
        g.sample_size(10)
            .sampling_mode(criterion::SamplingMode::Flat)
            .warm_up_time(std::time::Duration::from_secs(1))
            .measurement_time(std::time::Duration::from_secs(5));

        g.bench_function("lu_symbolic", |bch| {
            bch.iter(|| SymbolicLu::try_new(l.symbolic()).unwrap())
        });
        let sym = SymbolicLu::try_new(l.symbolic()).unwrap();
        let a = shifted(&l, &b, z);
        g.bench_function("lu_numeric_per_pole", |bch| {
            bch.iter(|| Lu::try_new_with_symbolic(sym.clone(), a.as_ref()).unwrap())
        });
        let lu = Lu::try_new_with_symbolic(sym.clone(), a.as_ref()).unwrap();
        let rhs = Mat::<c64>::from_fn(n, 1, |i, _| c64::new(f[(i, 0)], 0.0));
        g.bench_function("lu_solve_1rhs", |bch| bch.iter(|| lu.solve(&rhs)));

        let lsym = SymbolicLlt::try_new(l.symbolic(), Side::Lower).unwrap();
        let p = SparseColMat::new(
            l.symbolic().to_owned().unwrap(),
            l.val()
                .iter()
                .zip(b.val())
                .map(|(&lv, &bv)| T * lv + z.norm() * bv)
                .collect(),
        );
        g.bench_function("cholesky_numeric_P", |bch| {
            bch.iter(|| Llt::try_new_with_symbolic(lsym.clone(), p.as_ref(), Side::Lower).unwrap())
        });
        // One real Cholesky solve: faer's sequential supernodal sweep against our tree-parallel
        // sweep over disjoint elimination subtrees (src/trisolve.rs; the solve of the fast path
        // and of backward Euler).
        let llt = Llt::try_new_with_symbolic(lsym.clone(), p.as_ref(), Side::Lower).unwrap();
        let rhs_real = f.clone();
        g.bench_function("cholesky_solve_1rhs_faer_seq", |bch| bch.iter(|| llt.solve(&rhs_real)));
        let spd = CholeskyPattern::new(l.symbolic())
            .unwrap()
            .factor(p.as_ref(), faer::Par::Seq)
            .unwrap();
        let fv: Vec<f64> = f.col(0).iter().copied().collect();
        g.bench_function("cholesky_solve_1rhs_tree_parallel", |bch| {
            bch.iter(|| spd.solve_vec(&fv))
        });

        let minres = ShiftedSolver::new(l.as_ref(), b.as_ref(), Backend::Minres(MinresParams::default())).unwrap();
        let one_pole = RationalApprox {
            degree: 2,
            c0: 0.0,
            poles: &approx.poles[7..8],
            residues: &approx.residues[7..8],
            real_pole: None,
            max_error: 0.0,
        };
        let factors = minres.factor(&one_pole, T).unwrap();
        g.bench_function("minres_per_pole_solve_only", |bch| {
            bch.iter(|| factors.apply(f.as_ref()).unwrap())
        });

        let ldlt = ShiftedSolver::new(l.as_ref(), b.as_ref(), Backend::DirectLdlt).unwrap();
        g.bench_function("ldlt_numeric_per_pole", |bch| {
            bch.iter(|| ldlt.factor(&one_pole, T).unwrap())
        });
        let ldlt_factors = ldlt.factor(&one_pole, T).unwrap();
        g.bench_function("ldlt_solve_1rhs", |bch| {
            bch.iter(|| ldlt_factors.apply_resolvent(f.as_ref()).unwrap())
        });

        let direct = ShiftedSolver::new(l.as_ref(), b.as_ref(), Backend::DirectLu).unwrap();
        let shared = ShiftedSolver::new(
            l.as_ref(),
            b.as_ref(),
            Backend::Minres(MinresParams {
                preconditioner: Preconditioner::ShiftedCholesky(PreconditionerShift::Shared(10.0)),
                ..MinresParams::default()
            }),
        )
        .unwrap();
        // All 8 poles of the rational method (8 complex factorizations): 164K only with
        // WFEM_BENCH_LARGE=1 (tens of seconds per iteration).
        let all_poles = if levels::heavy(level) {
            vec![
                ("direct_ldlt", &ldlt),
                ("direct_lu", &direct),
                ("minres_s=|z|", &minres),
                ("minres_s=10", &shared),
            ]
        } else {
            Vec::new()
        };
        for (name, solver) in all_poles {
            g.bench_with_input(BenchmarkId::new("all_8_poles_deg16_1rhs", name), &f, |bch, f| {
                bch.iter(|| solver.apply(approx, T, f.as_ref()).unwrap())
            });
        }
        g.finish();
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
