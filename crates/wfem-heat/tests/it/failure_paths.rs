//! Solver failure paths of the heat kernel (issue #8): every failure is a typed error that
//! carries what was reached (residual, iterations, the eigenpairs found), the method the user
//! asked for is the one that fails (no silent fallback to another method), and broken
//! operators (NaN entries, a zero row in the mass matrix) never produce NaN output.
use crate::common;
use common::*;
use mesh_fem::{generate, FemOperators, Mass};
use shifted_solve::backend::Backend;
use shifted_solve::function::KrylovParams;
use shifted_solve::iterative::{MinresParams, Preconditioner};
use shifted_solve::SolveError;
use wfem_heat::method::Method;
use wfem_heat::spectral::{EigenParams, Eigenbasis};
use wfem_heat::{HeatError, HeatKernel, HeatParams};

fn small() -> FemOperators {
    ops_of(&generate::icosphere(2)).1
}

fn all_methods() -> Vec<Method> {
    vec![
        Method::rational(shifted_solve::poles::DEFAULT_DEGREE),
        Method::Rational {
            degree: 16,
            backend: Backend::Minres(MinresParams::default()),
        },
        Method::Fast(KrylovParams::default()),
        Method::Dense,
        Method::spectral(10),
        Method::Taylor,
        Method::BackwardEuler,
    ]
}

/// MINRES capped at 2 iterations: the error carries the iterations and the residual reached
/// and comes back through the heat kernel unchanged (no fallback to the LU backend).
#[test]
fn minres_non_convergence_is_reported_not_replaced() {
    let ops = small();
    let params = MinresParams {
        max_iters: 2,
        preconditioner: Preconditioner::Jacobi,
        ..MinresParams::default()
    };
    let kernel = HeatKernel::new(
        &ops,
        HeatParams {
            mass: Mass::Consistent,
            method: Method::Rational {
                degree: 16,
                backend: Backend::Minres(params),
            },
        },
    )
    .unwrap();
    let f = x_coordinate(&ops_of(&generate::icosphere(2)).0);
    match kernel.apply(&f, 0.1) {
        Err(HeatError::Solve(SolveError::NoConvergence {
            residual, iterations, ..
        })) => {
            assert_eq!(iterations, 2);
            assert!(residual.is_finite() && residual > params.rel_tol, "{residual:e}");
        }
        other => panic!("expected MINRES NoConvergence, got {other:?}"),
    }
    // The same kernel keeps failing the same way (no cached fallback result).
    assert!(matches!(
        kernel.apply(&f, 0.1),
        Err(HeatError::Solve(SolveError::NoConvergence { iterations: 2, .. }))
    ));
}

/// The spectral method with a basis too small and no restart allowed: `HeatKernel::new`
/// returns `EigenNoConvergence` with the converged pairs (checked against the dense
/// reference), not a kernel silently built on the dense eigendecomposition.
#[test]
fn eigensolver_non_convergence_carries_pairs_and_does_not_fall_back() {
    let ops = small();
    let eigen = EigenParams {
        max_dim: Some(40),
        max_restarts: 0,
        tol: 1e-13,
        ..Default::default()
    };
    let bound = eigen.basis_bound(36, ops.n());
    let err = HeatKernel::new(
        &ops,
        HeatParams {
            mass: Mass::Consistent,
            method: Method::Spectral { k: 36, eigen },
        },
    )
    .unwrap_err();
    let dense = Eigenbasis::dense(&ops.stiffness, &ops.mass).unwrap();
    match err {
        HeatError::EigenNoConvergence {
            requested,
            converged,
            dimension,
            max_residual,
            found,
        } => {
            assert_eq!(requested, 36);
            assert!(converged < 36 && dimension <= bound, "{converged} {dimension}");
            assert!(max_residual > 1e-13);
            assert_eq!(found.values.len(), converged);
            assert_eq!(found.vectors.ncols(), converged);
            for (i, v) in found.values.iter().enumerate() {
                assert!((v - dense.values[i]).abs() <= 1e-8 * dense.values[i].max(1.0), "{i}");
            }
        }
        other => panic!("expected EigenNoConvergence, got {other}"),
    }
}

/// Applies every method to operators broken by `edit`; each must fail with a typed error
/// (at construction or application), never return NaN or ∞.
fn every_method_refuses(label: &str, edit: impl Fn(&mut FemOperators), row: usize, requirement: &str) {
    let mut ops = small();
    edit(&mut ops);
    let f = vec![1.0; ops.n()];
    for kind in [Mass::Consistent, Mass::Lumped(Default::default())] {
        for method in all_methods() {
            let built = HeatKernel::new(
                &ops,
                HeatParams {
                    mass: kind,
                    method: method.clone(),
                },
            );
            let result = built.and_then(|k| k.apply(&f, 0.1));
            match result {
                Err(HeatError::InvalidOperatorEntry {
                    row: r, requirement: q, ..
                }) => {
                    assert_eq!((r, q), (row, requirement), "{label} {kind:?} {method:?}");
                }
                Err(e) => panic!("{label} {kind:?} {method:?}: unexpected error {e}"),
                Ok(g) => panic!(
                    "{label} {kind:?} {method:?}: accepted, output finite: {}",
                    g.iter().all(|v| v.is_finite())
                ),
            }
        }
    }
}

fn set_entry(m: &mut faer::sparse::SparseColMat<usize, f64>, row: usize, col: usize, value: f64) {
    let s = m.symbolic().to_owned().unwrap();
    let mut vals = m.val().to_vec();
    for p in s.col_range(col) {
        if s.row_idx()[p] == row {
            vals[p] = value;
        }
    }
    *m = faer::sparse::SparseColMat::new(s, vals);
}

#[test]
fn nan_in_the_operators_is_a_typed_error_for_every_method() {
    every_method_refuses(
        "NaN in L",
        |ops| set_entry(&mut ops.stiffness, 5, 5, f64::NAN),
        5,
        "finite",
    );
    every_method_refuses(
        "NaN in B",
        |ops| {
            set_entry(&mut ops.mass, 7, 7, f64::NAN);
            ops.lumped_diagonal[7] = f64::NAN;
        },
        7,
        "finite",
    );
    every_method_refuses(
        "∞ in B",
        |ops| {
            set_entry(&mut ops.mass, 7, 7, f64::INFINITY);
            ops.lumped_diagonal[7] = f64::INFINITY;
        },
        7,
        "finite",
    );
}

#[test]
fn zero_mass_row_is_a_typed_error_for_every_method() {
    every_method_refuses(
        "zero row in B",
        |ops| {
            ops.lumped_diagonal[11] = 0.0;
            {
                let m = &mut ops.mass;
                let s = m.symbolic().to_owned().unwrap();
                let mut vals = m.val().to_vec();
                for j in 0..s.ncols() {
                    for p in s.col_range(j) {
                        if j == 11 || s.row_idx()[p] == 11 {
                            vals[p] = 0.0;
                        }
                    }
                }
                *m = faer::sparse::SparseColMat::new(s, vals);
            }
        },
        11,
        "> 0 on the diagonal",
    );
}
