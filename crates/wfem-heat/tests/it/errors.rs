//! Every typed error of wfem-heat, triggered from arrays.
use crate::common;
use common::*;
use mesh_fem::generate;
use shifted_solve::function::KrylovParams;
use wfem_heat::method::Method;
use wfem_heat::spectral::{EigenParams, Eigenbasis};
use wfem_heat::{HeatError, HeatKernel, HeatParams};

fn small() -> mesh_fem::FemOperators {
    ops_of(&generate::icosphere(2)).1
}

#[test]
fn invalid_time() {
    let ops = small();
    let k = HeatKernel::new(&ops, HeatParams::default()).unwrap();
    let f = vec![1.0; ops.n()];
    for t in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert!(matches!(k.apply(&f, t), Err(HeatError::InvalidTime { .. })), "t = {t}");
    }
}

#[test]
fn length_mismatch() {
    let ops = small();
    let k = HeatKernel::new(&ops, HeatParams::default()).unwrap();
    let err = k.apply(&[1.0, 2.0], 0.1).unwrap_err();
    assert!(matches!(err, HeatError::LengthMismatch { expected, found: 2 } if expected == ops.n()));
}

#[test]
fn non_finite_input_names_row_and_column() {
    let ops = small();
    let k = HeatKernel::new(&ops, HeatParams::default()).unwrap();
    let mut f = faer::Mat::<f64>::zeros(ops.n(), 3);
    f[(17, 2)] = f64::NAN;
    let err = k.apply_many(f.as_ref(), 0.1).unwrap_err();
    assert!(
        matches!(err, HeatError::NonFiniteInput { row: 17, column: 2, .. }),
        "{err}"
    );
}

#[test]
fn too_large_for_dense() {
    let (_, ops) = ops_of(&generate::icosphere(5));
    let err = HeatKernel::new(
        &ops,
        HeatParams {
            method: Method::Dense,
            ..Default::default()
        },
    )
    .unwrap_err();
    assert!(
        matches!(err, HeatError::TooLargeForDense { n_vertices: 10242, .. }),
        "{err}"
    );
}

#[test]
fn eigen_no_convergence_carries_found_pairs() {
    let ops = small();
    let params = EigenParams {
        max_dim: Some(48),
        tol: 1e-13,
        ..Default::default()
    };
    let err = Eigenbasis::partial(&ops.stiffness, &ops.mass, 40, &params).unwrap_err();
    match err {
        HeatError::EigenNoConvergence {
            requested: 40,
            converged,
            found,
            ..
        } => {
            assert!(converged < 40);
            assert_eq!(found.values.len(), converged);
            // The pairs that did converge are right.
            let dense = Eigenbasis::dense(&ops.stiffness, &ops.mass).unwrap();
            for (i, v) in found.values.iter().enumerate().skip(1) {
                assert!((v - dense.values[i]).abs() < 1e-8 * dense.values[i]);
            }
        }
        other => panic!("unexpected {other}"),
    }
}

#[test]
fn krylov_no_convergence() {
    let ops = small();
    let k = HeatKernel::new(
        &ops,
        HeatParams {
            method: Method::Fast(KrylovParams {
                max_iter: 2,
                ..Default::default()
            }),
            ..Default::default()
        },
    )
    .unwrap();
    let err = k.apply(&unit(ops.n(), 3), 0.1).unwrap_err();
    assert!(
        matches!(
            err,
            HeatError::KrylovNoConvergence {
                column: 0,
                iterations: 2,
                ..
            }
        ),
        "{err}"
    );
}

#[test]
fn invalid_parameters() {
    let ops = small();
    let err = Eigenbasis::partial(&ops.stiffness, &ops.mass, 0, &EigenParams::default()).unwrap_err();
    assert!(matches!(err, HeatError::InvalidParameter { name: "k", .. }));
    let err = Eigenbasis::partial(
        &ops.stiffness,
        &ops.mass,
        5,
        &EigenParams {
            shift: Some(1.0),
            ..Default::default()
        },
    )
    .unwrap_err();
    assert!(matches!(err, HeatError::InvalidParameter { name: "shift", .. }));
    let err = HeatKernel::new(
        &ops,
        HeatParams {
            method: Method::Fast(KrylovParams {
                gamma: -1.0,
                ..Default::default()
            }),
            ..Default::default()
        },
    )
    .unwrap_err();
    assert!(matches!(err, HeatError::InvalidParameter { name: "gamma", .. }));
}

#[test]
fn not_positive_definite_mass() {
    let mut ops = small();
    // A negated mass is refused by the entry check, naming the first diagonal entry.
    let neg: Vec<f64> = ops.mass.val().iter().map(|x| -x).collect();
    let mut negated = ops.clone();
    negated.mass = faer::sparse::SparseColMat::new(ops.mass.symbolic().to_owned().unwrap(), neg);
    let err = HeatKernel::new(&negated, HeatParams::default()).unwrap_err();
    assert!(
        matches!(err, HeatError::InvalidOperatorEntry { row: 0, col: 0, .. }),
        "{err}"
    );
    // Positive diagonal but indefinite (off-diagonal entries × 10): the Cholesky refuses it.
    let s = ops.mass.symbolic().to_owned().unwrap();
    let mut vals = ops.mass.val().to_vec();
    for j in 0..s.ncols() {
        for p in s.col_range(j) {
            if s.row_idx()[p] != j {
                vals[p] *= 10.0;
            }
        }
    }
    ops.mass = faer::sparse::SparseColMat::new(s, vals);
    let err = HeatKernel::new(
        &ops,
        HeatParams {
            method: Method::Taylor,
            ..Default::default()
        },
    )
    .unwrap_err();
    assert!(matches!(err, HeatError::NotPositiveDefinite { .. }), "{err}");
    let err = HeatKernel::new(
        &ops,
        HeatParams {
            method: Method::Dense,
            ..Default::default()
        },
    )
    .unwrap_err();
    assert!(matches!(err, HeatError::NotPositiveDefinite { .. }), "{err}");
}

#[test]
fn inconsistent_operators() {
    let mut ops = small();
    ops.mass = ops_of(&generate::icosphere(1)).1.mass;
    let err = HeatKernel::new(&ops, HeatParams::default()).unwrap_err();
    assert!(matches!(err, HeatError::InconsistentOperators { .. }), "{err}");
}
