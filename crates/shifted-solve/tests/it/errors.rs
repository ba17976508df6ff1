//! Every error variant triggered from plain arrays.
use crate::common;

use common::*;
use faer::sparse::{SparseColMat, Triplet};
use faer::Mat;
use shifted_solve::backend::Backend;
use shifted_solve::iterative::{MinresParams, Preconditioner, PreconditionerShift};
use shifted_solve::poles::RationalApprox;
use shifted_solve::*;

fn path_laplacian() -> SparseColMat<usize, f64> {
    from_dense(&[&[1.0, -1.0, 0.0], &[-1.0, 2.0, -1.0], &[0.0, -1.0, 1.0]])
}

fn identity(n: usize) -> SparseColMat<usize, f64> {
    let t: Vec<_> = (0..n).map(|i| Triplet::new(i, i, 1.0)).collect();
    SparseColMat::try_new_from_triplets(n, n, &t).unwrap()
}

#[test]
fn no_convergence_names_the_pole() {
    let (l, b) = mesh_pair(2);
    let params = MinresParams {
        max_iters: 2,
        preconditioner: Preconditioner::Jacobi,
        ..MinresParams::default()
    };
    let s = ShiftedSolver::new(l.as_ref(), b.as_ref(), Backend::Minres(params)).unwrap();
    let f = random_rhs(l.nrows(), 1, 1);
    let err = s.apply(RationalApprox::cram(16).unwrap(), 0.1, f.as_ref()).unwrap_err();
    match err {
        SolveError::NoConvergence {
            iterations,
            residual,
            pole,
        } => {
            assert_eq!(iterations, 2);
            assert!(residual > 1e-14);
            assert!(RationalApprox::cram(16).unwrap().poles.contains(&pole));
        }
        e => panic!("unexpected {e}"),
    }
}

#[test]
fn mass_not_positive_definite() {
    let b = from_dense(&[&[1.0, 2.0, 0.0], &[2.0, 1.0, 0.0], &[0.0, 0.0, 1.0]]);
    let e = ShiftedSolver::new(path_laplacian().as_ref(), b.as_ref(), Backend::DirectLu).unwrap_err();
    assert!(matches!(e, SolveError::MassNotPositiveDefinite { .. }), "{e}");
    let b = from_dense(&[&[1.0, 0.0, 0.0], &[0.0, -1.0, 0.0], &[0.0, 0.0, 1.0]]);
    let e = ShiftedSolver::new(path_laplacian().as_ref(), b.as_ref(), Backend::DirectLu).unwrap_err();
    assert!(
        matches!(
            e,
            SolveError::BadDiagonal {
                which: "mass",
                index: 1,
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn indefinite_or_negated_stiffness() {
    // Positive diagonal, but eigenvalue −1.
    let l = from_dense(&[&[1.0, 2.0, 0.0], &[2.0, 1.0, 0.0], &[0.0, 0.0, 1.0]]);
    let e = ShiftedSolver::new(l.as_ref(), identity(3).as_ref(), Backend::DirectLu).unwrap_err();
    assert!(matches!(e, SolveError::StiffnessIndefinite { .. }), "{e}");
    // libigl sign convention (−L): negative diagonal.
    let (l, b) = mesh_pair(1);
    let neg = SparseColMat::new(l.symbolic().to_owned().unwrap(), l.val().iter().map(|v| -v).collect());
    let e = ShiftedSolver::new(neg.as_ref(), b.as_ref(), Backend::DirectLu).unwrap_err();
    assert!(matches!(e, SolveError::BadDiagonal { which: "stiffness", .. }), "{e}");
}

#[test]
fn not_symmetric_and_not_square() {
    let l = from_dense(&[&[1.0, -1.0, 0.0], &[-0.5, 1.0, 0.0], &[0.0, 0.0, 0.0]]);
    let e = ShiftedSolver::new(l.as_ref(), identity(3).as_ref(), Backend::DirectLu).unwrap_err();
    assert!(
        matches!(
            e,
            SolveError::NotSymmetric {
                which: "stiffness",
                row: 1,
                col: 0,
                ..
            }
        ),
        "{e}"
    );
    let rect = from_dense(&[&[1.0, 0.0, 0.0], &[0.0, 1.0, 0.0]]);
    let e = ShiftedSolver::new(rect.as_ref(), identity(3).as_ref(), Backend::DirectLu).unwrap_err();
    assert!(
        matches!(
            e,
            SolveError::NotSquare {
                which: "stiffness",
                nrows: 2,
                ncols: 3
            }
        ),
        "{e}"
    );
}

#[test]
fn mismatched_sizes() {
    let e = ShiftedSolver::new(path_laplacian().as_ref(), identity(4).as_ref(), Backend::DirectLu).unwrap_err();
    assert!(
        matches!(
            e,
            SolveError::DimensionMismatch {
                expected: 3,
                got: 4,
                ..
            }
        ),
        "{e}"
    );
    let s = ShiftedSolver::new(path_laplacian().as_ref(), identity(3).as_ref(), Backend::DirectLu).unwrap();
    let f = Mat::<f64>::zeros(4, 1);
    let e = s.apply(RationalApprox::cram(4).unwrap(), 1.0, f.as_ref()).unwrap_err();
    assert!(
        matches!(
            e,
            SolveError::DimensionMismatch {
                expected: 3,
                got: 4,
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn nan_in_matrices_or_rhs() {
    let l = from_dense(&[&[1.0, -1.0, 0.0], &[-1.0, f64::NAN, -1.0], &[0.0, -1.0, 1.0]]);
    let e = ShiftedSolver::new(l.as_ref(), identity(3).as_ref(), Backend::DirectLu).unwrap_err();
    assert!(
        matches!(
            e,
            SolveError::NonFinite {
                what: "stiffness",
                row: 1,
                col: 1,
                ..
            }
        ),
        "{e}"
    );
    let s = ShiftedSolver::new(path_laplacian().as_ref(), identity(3).as_ref(), Backend::DirectLu).unwrap();
    let mut f = Mat::<f64>::zeros(3, 2);
    f[(2, 1)] = f64::INFINITY;
    let e = s.apply(RationalApprox::cram(4).unwrap(), 1.0, f.as_ref()).unwrap_err();
    assert!(
        matches!(
            e,
            SolveError::NonFinite {
                what: "right-hand side",
                row: 2,
                col: 1,
                ..
            }
        ),
        "{e}"
    );
    let e = s
        .apply_resolvent(RationalApprox::cram(4).unwrap(), 1.0, f.as_ref())
        .unwrap_err();
    assert!(matches!(e, SolveError::NonFinite { .. }), "{e}");
}

#[test]
fn invalid_time_and_parameters() {
    let s = ShiftedSolver::new(path_laplacian().as_ref(), identity(3).as_ref(), Backend::DirectLu).unwrap();
    let f = Mat::<f64>::zeros(3, 1);
    let a = RationalApprox::cram(16).unwrap();
    for t in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert!(
            matches!(s.apply(a, t, f.as_ref()), Err(SolveError::InvalidTime { .. })),
            "t = {t}"
        );
        assert!(matches!(s.factor(a, t), Err(SolveError::InvalidTime { .. })));
    }
    let bad = MinresParams {
        rel_tol: 0.0,
        ..MinresParams::default()
    };
    let e = ShiftedSolver::new(path_laplacian().as_ref(), identity(3).as_ref(), Backend::Minres(bad)).unwrap_err();
    assert!(matches!(e, SolveError::InvalidParameter { name: "rel_tol", .. }), "{e}");
    let bad = MinresParams {
        preconditioner: Preconditioner::ShiftedCholesky(PreconditionerShift::Shared(-1.0)),
        ..MinresParams::default()
    };
    let e = ShiftedSolver::new(path_laplacian().as_ref(), identity(3).as_ref(), Backend::Minres(bad)).unwrap_err();
    assert!(matches!(e, SolveError::InvalidParameter { .. }), "{e}");
    let empty = SparseColMat::<usize, f64>::try_new_from_triplets(0, 0, &[]).unwrap();
    let e = ShiftedSolver::new(empty.as_ref(), empty.as_ref(), Backend::DirectLu).unwrap_err();
    assert!(matches!(e, SolveError::Empty), "{e}");
}

/// Zero right-hand side gives exactly zero, for every backend (no 0/0 in MINRES).
#[test]
fn zero_rhs_gives_zero() {
    let (l, b) = mesh_pair(1);
    for backend in [
        Backend::DirectLu,
        Backend::DirectLdlt,
        Backend::Minres(MinresParams::default()),
    ] {
        let s = ShiftedSolver::new(l.as_ref(), b.as_ref(), backend).unwrap();
        let f = Mat::<f64>::zeros(l.nrows(), 1);
        let (x, _) = s.apply(RationalApprox::cram(5).unwrap(), 0.3, f.as_ref()).unwrap();
        assert!((0..l.nrows()).all(|i| x[(i, 0)] == 0.0));
    }
}

/// Overflow inside a factorization (t = 1e308) is a typed error for both direct backends,
/// never NaN in the result.
#[test]
fn overflowing_shift_is_a_typed_error() {
    let (l, b) = mesh_pair(1);
    let f = Mat::<f64>::from_fn(l.nrows(), 1, |i, _| i as f64);
    for backend in [Backend::DirectLu, Backend::DirectLdlt] {
        let s = ShiftedSolver::new(l.as_ref(), b.as_ref(), backend).unwrap();
        match s.apply(RationalApprox::cram(16).unwrap(), 1e308, f.as_ref()) {
            Err(SolveError::SingularShiftedMatrix { t, .. }) => assert_eq!(t, 1e308),
            Err(e) => panic!("{backend:?}: unexpected error {e}"),
            Ok((x, _)) => assert!(
                (0..l.nrows()).all(|i| x[(i, 0)].is_finite()),
                "{backend:?}: non-finite result"
            ),
        }
    }
}
