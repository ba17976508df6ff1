//! Condition estimates (paper Fig. 2c,d) against dense SVD / dense generalized eigenvalues.
use crate::common;

use common::*;
use faer::c64;
use faer::{Mat, Side};
use shifted_solve::backend::Backend;
use shifted_solve::iterative::MinresParams;
use shifted_solve::poles::RationalApprox;
use shifted_solve::*;

/// Dense κ₂(tL − zB) and κ(diag(P,P)⁻¹A₂), P = tL + sB.
fn dense_conditions(
    l: &faer::sparse::SparseColMat<usize, f64>,
    b: &faer::sparse::SparseColMat<usize, f64>,
    t: f64,
    z: c64,
    s: f64,
) -> (f64, f64) {
    let (ld, bd) = (dense(l), dense(b));
    let n = ld.nrows();
    let a = Mat::<c64>::from_fn(n, n, |i, j| c64::new(t * ld[(i, j)], 0.0) - z * bd[(i, j)]);
    let sv = a.singular_values().unwrap();
    let kappa = sv.iter().cloned().fold(0.0, f64::max) / sv.iter().cloned().fold(f64::MAX, f64::min);
    // Generalized symmetric problem A₂ x = μ M x via M = R Rᵀ.
    let k = Mat::from_fn(n, n, |i, j| t * ld[(i, j)] - z.re * bd[(i, j)]);
    let a2 = Mat::from_fn(2 * n, 2 * n, |i, j| match (i < n, j < n) {
        (true, true) => k[(i, j)],
        (true, false) => z.im * bd[(i, j - n)],
        (false, true) => z.im * bd[(i - n, j)],
        (false, false) => -k[(i - n, j - n)],
    });
    let p = Mat::from_fn(n, n, |i, j| t * ld[(i, j)] + s * bd[(i, j)]);
    let m = Mat::from_fn(2 * n, 2 * n, |i, j| match (i < n, j < n) {
        (true, true) => p[(i, j)],
        (false, false) => p[(i - n, j - n)],
        _ => 0.0,
    });
    let r = m.llt(Side::Lower).unwrap().L().to_owned();
    let mut x = a2.clone();
    faer::linalg::triangular_solve::solve_lower_triangular_in_place(r.as_ref(), x.as_mut(), faer::Par::Seq);
    let mut c = x.transpose().to_owned();
    faer::linalg::triangular_solve::solve_lower_triangular_in_place(r.as_ref(), c.as_mut(), faer::Par::Seq);
    let c = Mat::from_fn(2 * n, 2 * n, |i, j| 0.5 * (c[(i, j)] + c[(j, i)]));
    let mu = c.self_adjoint_eigenvalues(Side::Lower).unwrap();
    let big = mu.iter().map(|v| v.abs()).fold(0.0, f64::max);
    let small = mu.iter().map(|v| v.abs()).fold(f64::MAX, f64::min);
    (kappa, big / small)
}

#[test]
fn condition_estimates_match_dense_svd_on_small_matrices() {
    let (l, b) = random_pair(25, 4);
    let solver = ShiftedSolver::new(l.as_ref(), b.as_ref(), Backend::DirectLu).unwrap();
    let approx = RationalApprox::cram(16).unwrap();
    for t in [1e-3, 0.1, 10.0] {
        for &z in approx.poles {
            let rep = solver.condition(t, z, None).unwrap();
            let (kappa, kappa_p) = dense_conditions(&l, &b, t, z, z.norm());
            // 2n = 50 ≤ 60 Lanczos steps: the Krylov space is exhausted, estimates are exact.
            assert!(
                (rep.matrix / kappa - 1.0).abs() < 1e-8,
                "t={t} z={z}: {} vs {kappa}",
                rep.matrix
            );
            assert!(
                (rep.preconditioned / kappa_p - 1.0).abs() < 1e-8,
                "t={t} z={z}: {} vs {kappa_p}",
                rep.preconditioned
            );
            // docs/NUMERICS.md §3.3b: with s = |z| the preconditioned κ of degree 16 is ≤ 2.
            assert!(rep.preconditioned <= 2.0 + 1e-9);
        }
    }
}

#[test]
fn condition_estimates_on_a_mesh_are_accurate_lower_bounds() {
    let (l, b) = mesh_pair(2);
    let solver = ShiftedSolver::new(l.as_ref(), b.as_ref(), Backend::Minres(MinresParams::default())).unwrap();
    let z = RationalApprox::cram(16).unwrap().poles[7];
    for (t, s) in [(0.01, None), (1.0, Some(10.0))] {
        let rep = solver.condition(t, z, s).unwrap();
        let (kappa, kappa_p) = dense_conditions(&l, &b, t, z, s.unwrap_or(z.norm()));
        assert!(
            rep.matrix <= kappa * (1.0 + 1e-9) && rep.matrix >= 0.99 * kappa,
            "{} vs {kappa}",
            rep.matrix
        );
        assert!(
            rep.preconditioned <= kappa_p * (1.0 + 1e-9) && rep.preconditioned >= 0.99 * kappa_p,
            "{} vs {kappa_p}",
            rep.preconditioned
        );
    }
}
