//! Singular shifted matrices tL − zB (z exactly a generalized eigenvalue) must give the typed
//! [`SolveError::SingularShiftedMatrix`], never NaN, ∞ or a huge finite garbage answer, for
//! complex-pole LU and real-pole Cholesky alike; and MINRES that runs out of iterations must
//! report it ([`SolveError::NoConvergence`] with the residual reached), never fall back to LU.
use faer::sparse::SparseColMat;
use faer::{c64, Mat};
use shifted_solve::backend::{Backend, BatchReport, SolveMethod};
use shifted_solve::iterative::{MinresParams, Preconditioner};
use shifted_solve::poles::RationalApprox;
use shifted_solve::*;

use crate::common;
use common::{from_dense, single_pole};

/// Path Laplacian on 3 vertices with B = I: generalized eigenvalues exactly 0, 1 and 3
/// (eigenvectors (1,1,1), (1,0,−1), (1,−2,1)).
fn path() -> (SparseColMat<usize, f64>, SparseColMat<usize, f64>) {
    let l = from_dense(&[&[1.0, -1.0, 0.0], &[-1.0, 2.0, -1.0], &[0.0, -1.0, 1.0]]);
    let b = from_dense(&[&[1.0, 0.0, 0.0], &[0.0, 1.0, 0.0], &[0.0, 0.0, 1.0]]);
    (l, b)
}

fn real_pole(z: f64) -> RationalApprox {
    RationalApprox {
        degree: 1,
        c0: 0.0,
        poles: Box::leak(Vec::new().into_boxed_slice()),
        residues: Box::leak(Vec::new().into_boxed_slice()),
        real_pole: Some((z, 1.0)),
        max_error: 0.0,
    }
}

fn rhs() -> Mat<f64> {
    // Not orthogonal to any eigenvector (a linear ramp would be orthogonal to (1, −2, 1)).
    Mat::from_fn(3, 2, |i, j| 1.0 + (i * i) as f64 + 0.5 * j as f64)
}

fn assert_singular(result: Result<(Mat<f64>, BatchReport), SolveError>, z: f64, what: &str) {
    match result {
        Err(SolveError::SingularShiftedMatrix { t, pole }) => {
            assert_eq!(t, 1.0, "{what}");
            assert_eq!(pole, c64::new(z, 0.0), "{what}");
        }
        Err(e) => panic!("{what}: unexpected error {e}"),
        Ok((x, rep)) => panic!("{what}: singular system solved to {x:?} ({rep:?})"),
    }
}

#[test]
fn pole_at_an_eigenvalue_is_a_typed_error() {
    let (l, b) = path();
    let s = ShiftedSolver::new(l.as_ref(), b.as_ref(), Backend::DirectLu).unwrap();
    let ldlt = ShiftedSolver::new(l.as_ref(), b.as_ref(), Backend::DirectLdlt).unwrap();
    for z in [0.0, 1.0, 3.0] {
        assert_singular(
            s.apply(&single_pole(c64::new(z, 0.0)), 1.0, rhs().as_ref()),
            z,
            "complex LU",
        );
        assert_singular(
            ldlt.apply(&single_pole(c64::new(z, 0.0)), 1.0, rhs().as_ref()),
            z,
            "complex-symmetric LDLᵀ",
        );
        assert_singular(s.apply(&real_pole(z), 1.0, rhs().as_ref()), z, "real Cholesky");
        assert_singular(
            s.apply_resolvent(&single_pole(c64::new(z, 0.0)), 1.0, rhs().as_ref()),
            z,
            "resolvent",
        );
    }
    // The Krylov backend on the same singular systems (g not in the range of L − zI): a typed
    // error that carries the (finite) residual reached, never NaN or a silent answer.
    for preconditioner in [Preconditioner::None, Preconditioner::Jacobi] {
        let params = MinresParams {
            preconditioner,
            max_iters: 50,
            ..MinresParams::default()
        };
        let m = ShiftedSolver::new(l.as_ref(), b.as_ref(), Backend::Minres(params)).unwrap();
        for z in [1.0, 3.0] {
            match m.apply(&single_pole(c64::new(z, 0.0)), 1.0, rhs().as_ref()) {
                Err(SolveError::NoConvergence { residual, .. }) => {
                    // A pole on the real axis is solved by CG on the real matrix tL − zB;
                    // on this singular, indefinite matrix its residual may grow (measured
                    // 5e10 after 50 steps), and it used to end in NaN (0/0 step length).
                    assert!(residual.is_finite() && residual > 1e-8, "{residual:e}")
                }
                Err(SolveError::SingularShiftedMatrix { .. }) => {}
                other => panic!("MINRES {preconditioner:?} z = {z}: {other:?}"),
            }
        }
    }
    // A pole next to, not at, an eigenvalue is solved (complex LU), and accurately:
    // (L − zI)⁻¹g with z = 1 + 1e−3 (a pole on the real axis counts once, not twice) against
    // the closed form in the eigenbasis.
    let z = 1.0 + 1e-3;
    let (x, _) = s
        .apply_resolvent(&single_pole(c64::new(z, 0.0)), 1.0, rhs().as_ref())
        .unwrap();
    let q = [([1.0, 1.0, 1.0], 0.0), ([1.0, 0.0, -1.0], 1.0), ([1.0, -2.0, 1.0], 3.0)];
    for j in 0..2 {
        let g: Vec<f64> = (0..3).map(|i| rhs()[(i, j)]).collect();
        let mut expect = [0.0; 3];
        for (v, lambda) in q {
            let vv: f64 = v.iter().map(|a| a * a).sum();
            let c: f64 = v.iter().zip(&g).map(|(a, b)| a * b).sum::<f64>() / vv / (lambda - z);
            for i in 0..3 {
                expect[i] += c * v[i];
            }
        }
        for i in 0..3 {
            assert!(
                (x[(i, j)] - expect[i]).abs() <= 1e-9 * expect[i].abs().max(1.0),
                "{i},{j}: {} vs {}",
                x[(i, j)],
                expect[i]
            );
        }
    }
}

#[test]
fn minres_out_of_iterations_reports_residual_and_does_not_fall_back() {
    let (l, b) = path();
    let params = MinresParams {
        max_iters: 1,
        preconditioner: Preconditioner::None,
        ..MinresParams::default()
    };
    let s = ShiftedSolver::new(l.as_ref(), b.as_ref(), Backend::Minres(params)).unwrap();
    let approx = RationalApprox::cram(16).unwrap();
    match s.apply(approx, 1.0, rhs().as_ref()) {
        Err(SolveError::NoConvergence {
            residual,
            iterations,
            pole,
        }) => {
            assert_eq!(iterations, 1);
            assert!(residual.is_finite() && residual > params.rel_tol, "{residual:e}");
            assert!(approx.poles.contains(&pole) || approx.real_pole.map(|p| p.0) == Some(pole.re));
        }
        other => panic!("expected NoConvergence, got {other:?}"),
    }
    // The same system converges with enough iterations (so the failure is the cap, not the
    // matrix), and the backend is still MINRES: the report names no LU.
    let s = ShiftedSolver::new(l.as_ref(), b.as_ref(), Backend::Minres(MinresParams::default())).unwrap();
    let (_, rep) = s.apply(approx, 1.0, rhs().as_ref()).unwrap();
    assert!(rep.poles.iter().all(|p| p.method != SolveMethod::ComplexLu), "{rep:?}");
    assert!(rep.total_iterations() > 0);
}
