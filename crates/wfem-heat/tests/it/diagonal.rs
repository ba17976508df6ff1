//! The exact heat kernel diagonal without eigenpairs (issue #17): probing with one factorization
//! for all times, against the dense diagonal, at times where 300 eigenpairs are far off.
use crate::common;
use common::*;
use mesh_fem::{generate, Mass};
use wfem_heat::diagonal::DiagonalMethod;
use wfem_heat::spectral::Eigenbasis;
use wfem_heat::{DiagonalParams, HeatError, HeatKernel, HeatParams, KernelDiagonal, Operators};

#[test]
fn probed_diagonal_matches_dense_where_truncation_fails() {
    let (_, ops) = ops_of(&generate::icosphere(4));
    let n = ops.n();
    let dense = Eigenbasis::dense(&ops.stiffness, &ops.mass).unwrap();
    // B X, for the operator diagonal Σ_k e^{−λ_k t} x_k(i)(Bx_k)(i).
    let mut bx = faer::Mat::<f64>::zeros(n, n);
    faer::sparse::linalg::matmul::sparse_dense_matmul(
        bx.as_mut(),
        faer::Accum::Replace,
        ops.mass.as_ref(),
        dense.vectors.as_ref(),
        1.0,
        faer::Par::Seq,
    );
    let kernel = HeatKernel::new(&ops, HeatParams::default()).unwrap();
    let times = [2e-4, 5e-4, 1e-3];
    let probing = DiagonalParams {
        method: DiagonalMethod::Probing { tol: 1e-10 },
        ..Default::default()
    };
    let series = kernel.diagonal(&times, KernelDiagonal::KernelValue, &probing).unwrap();
    let matrix = kernel
        .diagonal(&times, KernelDiagonal::OperatorDiagonal, &probing)
        .unwrap();
    eprintln!("n = {n}: {:?}", series.info);
    assert!(
        series.info.hops.is_some() && series.info.columns < n / 4,
        "{:?}",
        series.info
    );
    for (l, &t) in times.iter().enumerate() {
        let mut worst = 0.0f64;
        let mut worst_matrix = 0.0f64;
        let mut truncated = 0.0f64;
        for i in 0..n {
            // H_t(i,i) = Σ_k e^{−λ_k t} x_k(i)², K_t(i,i) = Σ_k e^{−λ_k t} x_k(i)(Bx_k)(i).
            let mut exact = 0.0;
            let mut k300 = 0.0;
            let mut exact_matrix = 0.0;
            for k in 0..n {
                let w = (-t * dense.values[k]).exp();
                let x = dense.vectors[(i, k)];
                exact += w * x * x;
                exact_matrix += w * x * bx[(i, k)];
                if k < 300 {
                    k300 += w * x * x;
                }
            }
            worst = worst.max((series.values[(i, l)] - exact).abs() / exact);
            worst_matrix = worst_matrix.max((matrix.values[(i, l)] - exact_matrix).abs() / exact_matrix);
            truncated = truncated.max((k300 - exact).abs() / exact);
        }
        eprintln!("t = {t}: probing {worst:.1e} (matrix {worst_matrix:.1e}), 300 eigenpairs {truncated:.2}");
        assert!(
            truncated >= 0.1,
            "t = {t}: the premise (300 pairs ≥ 10 % off) fails: {truncated}"
        );
        assert!(worst <= 1e-8, "t = {t}: {worst:e}");
        assert!(worst_matrix <= 1e-8, "t = {t}: {worst_matrix:e}");
        assert!(series.error_estimates[l].is_some_and(|e| e <= 1e-10));
    }
    // The exact method (n unit columns, here on a small mesh) agrees with probing; too many
    // probes are refused, not run.
    let (_, small) = ops_of(&generate::icosphere(2));
    let small_kernel = HeatKernel::new(&small, HeatParams::default()).unwrap();
    let exact = small_kernel
        .diagonal(
            &[1e-3],
            KernelDiagonal::KernelValue,
            &DiagonalParams {
                method: DiagonalMethod::UnitColumns,
                ..Default::default()
            },
        )
        .unwrap();
    let probed = small_kernel
        .diagonal(&[1e-3], KernelDiagonal::KernelValue, &probing)
        .unwrap();
    assert_eq!(exact.info.columns, small.n());
    for i in 0..small.n() {
        assert!((exact.values[(i, 0)] - probed.values[(i, 0)]).abs() <= 1e-8 * exact.values[(i, 0)]);
    }
    assert!(matches!(
        kernel.diagonal(
            &[10.0],
            KernelDiagonal::KernelValue,
            &DiagonalParams {
                max_columns: 100,
                ..probing.clone()
            }
        ),
        Err(HeatError::InvalidParameter {
            name: "max_columns",
            ..
        })
    ));
    assert!(matches!(
        kernel.diagonal(&[], KernelDiagonal::KernelValue, &DiagonalParams::default()),
        Err(HeatError::InvalidParameter { name: "times", .. })
    ));
}

/// At large t the diagonal tends to 1/area (the constant mode, kept exact by the null-space
/// deflation) for every method, without underflowing to 0 (issue #16: `hks --times 1e300`).
#[test]
fn diagonal_at_huge_times_is_one_over_area() {
    let (_, ops) = ops_of(&generate::icosphere(2));
    let n = ops.n();
    let area = ops.area();
    let kernel = HeatKernel::new(&ops, HeatParams::default()).unwrap();
    let series = kernel
        .diagonal(
            &[1e300],
            KernelDiagonal::KernelValue,
            &DiagonalParams {
                method: DiagonalMethod::UnitColumns,
                ..Default::default()
            },
        )
        .unwrap();
    for i in 0..n {
        assert!(
            (series.values[(i, 0)] * area - 1.0).abs() < 1e-10,
            "{}",
            series.values[(i, 0)] * area
        );
    }
}

/// The dense diagonals `H_t(i,i) = Σ_k e^{−λ_k t} x_k(i)²` and `K_t(i,i) = Σ_k e^{−λ_k t}
/// x_k(i)(Mx_k)(i)` of a pair (L, M) from its generalized eigendecomposition.
fn dense_diagonals(ops: &Operators, t: f64) -> (Vec<f64>, Vec<f64>) {
    let dense = Eigenbasis::dense_of(ops).unwrap();
    let n = ops.n();
    let mass = ops.mass();
    let mut mx = faer::Mat::<f64>::zeros(n, n);
    faer::sparse::linalg::matmul::sparse_dense_matmul(
        mx.as_mut(),
        faer::Accum::Replace,
        mass,
        dense.vectors.as_ref(),
        1.0,
        faer::Par::Seq,
    );
    let mut value = vec![0.0; n];
    let mut matrix = vec![0.0; n];
    for k in 0..n {
        let w = (-t * dense.values[k].max(0.0)).exp();
        for i in 0..n {
            let x = dense.vectors[(i, k)];
            value[i] += w * x * x;
            matrix[i] += w * x * mx[(i, k)];
        }
    }
    (value, matrix)
}

/// An icosphere and a grid side by side: two components, two null vectors.
fn two_components() -> mesh_fem::TriMesh {
    let (mut positions, mut faces) = generate::icosphere(2).into_parts();
    let offset = positions.len() as u32;
    let (grid_positions, grid_faces) = generate::grid(6, 6).into_parts();
    positions.extend(grid_positions.iter().map(|p| [p[0] + 3.0, p[1], p[2]]));
    faces.extend(grid_faces.iter().map(|f| [f[0] + offset, f[1] + offset, f[2] + offset]));
    mesh_fem::TriMesh::new(positions, faces).unwrap()
}

/// Selected inversion gives both diagonals to 1e−10 of the dense reference at every scale —
/// small t where truncation fails, medium t where probing would need most columns, large t
/// near the constant limit — for the wFEM and the lumped kernel, on one and on two components.
#[test]
fn selected_inversion_diagonal_matches_dense_at_every_time() {
    let (_, sphere) = ops_of(&generate::icosphere(3));
    let (_, two) = ops_of(&two_components());
    for (name, ops) in [("icosphere", &sphere), ("two components", &two)] {
        for kind in [Mass::Consistent, Mass::Lumped(Default::default())] {
            let kernel = HeatKernel::new(
                ops,
                HeatParams {
                    mass: kind,
                    ..Default::default()
                },
            )
            .unwrap();
            let params = DiagonalParams {
                method: DiagonalMethod::SelectedInversion,
                ..Default::default()
            };
            let times = [1e-4, 1e-2, 1.0, 1e300];
            let value = kernel.diagonal(&times, KernelDiagonal::KernelValue, &params).unwrap();
            let matrix = kernel
                .diagonal(&times, KernelDiagonal::OperatorDiagonal, &params)
                .unwrap();
            assert_eq!((value.info.columns, value.info.hops), (0, None));
            for (c, &t) in times.iter().enumerate() {
                let (dv, dm) = dense_diagonals(kernel.operators(), t.min(1e6));
                for i in 0..ops.n() {
                    let ev = (value.values[(i, c)] - dv[i]).abs() / dv[i];
                    let em = (matrix.values[(i, c)] - dm[i]).abs() / dm[i];
                    assert!(
                        ev < 1e-10 && em < 1e-10,
                        "{name} {kind:?} t = {t} i = {i}: {ev:e} {em:e}"
                    );
                }
            }
        }
    }
}

/// Scale covariance of the selected-inversion diagonal (issue #16's scaled meshes): on the
/// mesh scaled by s at time s²t, `H(i, i)` is the unscaled one divided by s² (1/area), for s
/// from 1e−100 to 1e100 — the factorizations are scaled by exact powers of two.
#[test]
fn selected_inversion_diagonal_is_scale_covariant() {
    let (mesh, ops) = ops_of(&generate::icosphere(2));
    let params = DiagonalParams::default();
    let t = 0.05;
    let base = HeatKernel::new(&ops, HeatParams::default())
        .unwrap()
        .diagonal(&[t], KernelDiagonal::KernelValue, &params)
        .unwrap();
    for s in [1e-100, 1e-30, 1e30, 1e100] {
        let scaled = mesh_fem::assemble(&mesh.scaled(s).unwrap(), &Default::default()).unwrap();
        let d = HeatKernel::new(&scaled, HeatParams::default())
            .unwrap()
            .diagonal(&[s * s * t], KernelDiagonal::KernelValue, &params)
            .unwrap();
        for i in 0..ops.n() {
            let want = base.values[(i, 0)] / (s * s);
            let e = (d.values[(i, 0)] - want).abs() / want;
            assert!(e < 1e-10, "s = {s:e}, i = {i}: {e:e}");
        }
    }
}

/// Issue #23: an abandoned computation stops at its next checkpoint — the exact diagonal
/// (selected inversion, pole by pole), K_t f by every path, the partial eigensolver — with
/// `SolveError::Interrupted`, and the same calls succeed without the raised interrupt.
#[test]
fn a_raised_interrupt_stops_every_long_path() {
    use shifted_solve::SolveError;
    use wfem_base::interrupt::Interrupt;
    let (_, ops) = ops_of(&generate::icosphere(3));
    let kernel = HeatKernel::new(&ops, HeatParams::default()).unwrap();
    let rational = HeatKernel::new(
        &ops,
        HeatParams {
            method: wfem_heat::method::Method::Rational {
                degree: shifted_solve::poles::DEFAULT_DEGREE,
                backend: Default::default(),
            },
            ..Default::default()
        },
    )
    .unwrap();
    let f: Vec<f64> = (0..ops.n()).map(|i| (i % 7) as f64).collect();
    let interrupted = |e: HeatError| matches!(e, HeatError::Solve(SolveError::Interrupted(_)));
    let raised = Interrupt::new();
    raised.raise();
    raised.install(|| {
        let e = kernel
            .diagonal(&[1e-3, 1e-2], KernelDiagonal::KernelValue, &DiagonalParams::default())
            .unwrap_err();
        assert!(interrupted(e));
        assert!(interrupted(kernel.apply(&f, 1e-2).unwrap_err()));
        assert!(interrupted(rational.apply(&f, 1e-2).unwrap_err()));
        let e = Eigenbasis::partial_of(kernel.operators(), 20, &Default::default()).unwrap_err();
        assert!(interrupted(e));
    });
    let quiet = Interrupt::new();
    quiet.install(|| {
        kernel
            .diagonal(&[1e-3], KernelDiagonal::KernelValue, &DiagonalParams::default())
            .unwrap();
        rational.apply(&f, 1e-2).unwrap();
        Eigenbasis::partial_of(kernel.operators(), 20, &Default::default()).unwrap();
    });
}
