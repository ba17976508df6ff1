//! Per-pole cost of the complex-symmetric LDLᵀ against faer's real Cholesky on the same
//! pattern (one factorization each, sequential): `cargo run --release -p shifted-solve --example ldlt_profile -- LEVEL`.
use std::time::Instant;

use faer::sparse::linalg::cholesky::{factorize_symbolic_cholesky, CholeskySymbolicParams, SymmetricOrdering};
use faer::Side;
use shifted_solve::backend::Backend;
use shifted_solve::poles::RationalApprox;
use shifted_solve::{CholeskyPattern, ShiftedSolver};

fn main() {
    let level: u32 = std::env::args().nth(1).and_then(|s| s.parse().ok()).unwrap_or(5);
    let mesh = mesh_fem::generate::icosphere(level)
        .with_area(4.0 * std::f64::consts::PI)
        .expect("area");
    let ops = mesh_fem::assemble(&mesh, &mesh_fem::AssemblyParams::default()).expect("assembly");
    let (l, b) = (ops.stiffness, ops.mass);
    let n = l.nrows();
    let t = 0.01;
    let pattern = CholeskyPattern::new(l.symbolic()).expect("pattern");
    let a = faer::sparse::SparseColMat::<usize, f64>::try_new_from_triplets(
        n,
        n,
        &l.triplet_iter()
            .map(|e| faer::sparse::Triplet::new(e.row, e.col, t * *e.val))
            .chain(
                b.triplet_iter()
                    .map(|e| faer::sparse::Triplet::new(e.row, e.col, *e.val)),
            )
            .collect::<Vec<_>>(),
    )
    .expect("B + tL");
    let t0 = Instant::now();
    let f = pattern.factor(a.as_ref(), faer::Par::Seq).expect("cholesky");
    let chol = t0.elapsed().as_secs_f64();
    let rhs = faer::Mat::<f64>::from_fn(n, 1, |i, _| (i % 13) as f64);
    let mut x = rhs.clone();
    let t0 = Instant::now();
    f.solve_in_place(x.as_mut());
    let solve = t0.elapsed().as_secs_f64();
    let sym = factorize_symbolic_cholesky(
        l.symbolic(),
        Side::Lower,
        SymmetricOrdering::Amd,
        CholeskySymbolicParams::default(),
    )
    .expect("sym");
    println!(
        "n={n} nnz(L factor)={} real Cholesky B+tL: {chol:.3} s, 1 solve {solve:.4} s",
        sym.len_val()
    );
    let solver = ShiftedSolver::new(l.as_ref(), b.as_ref(), Backend::DirectLdlt).expect("solver");
    let approx = RationalApprox::cram(16).expect("cram");
    let single = RationalApprox {
        degree: 2,
        c0: 0.0,
        poles: &approx.poles[..1],
        residues: &approx.residues[..1],
        real_pole: None,
        max_error: 0.0,
    };
    let t0 = Instant::now();
    let fac = solver.factor(&single, t).expect("factor");
    let ldlt = t0.elapsed().as_secs_f64();
    let t0 = Instant::now();
    let _ = fac.apply_resolvent(rhs.as_ref()).expect("solve");
    let lsolve = t0.elapsed().as_secs_f64();
    println!(
        "complex LDLᵀ one pole: factor {ldlt:.3} s ({:.1}× real Cholesky), solve+residual {lsolve:.4} s",
        ldlt / chol
    );
}
