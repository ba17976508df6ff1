//! Every backend against dense references.
use crate::common;

use common::*;
use faer::c64;
use faer::Mat;
use shifted_solve::backend::{Backend, BatchReport, SolveMethod};
use shifted_solve::function::KrylovParams;
use shifted_solve::iterative::{MinresParams, Preconditioner, PreconditionerShift};
use shifted_solve::poles::{RationalApprox, DEFAULT_DEGREE};
use shifted_solve::*;

fn backends() -> Vec<(&'static str, Backend)> {
    vec![
        ("lu", Backend::DirectLu),
        ("ldlt", Backend::DirectLdlt),
        ("minres-pole-shift", Backend::Minres(MinresParams::default())),
        (
            "minres-shared-shift",
            Backend::Minres(MinresParams {
                preconditioner: Preconditioner::ShiftedCholesky(PreconditionerShift::Shared(10.0)),
                ..MinresParams::default()
            }),
        ),
    ]
}

/// Each pole of degree 16 (and the real pole of degree 7): 2 Re (tL − zB)⁻¹ g from the solver
/// against a dense pivoted LU.
fn check_every_pole(
    l: &faer::sparse::SparseColMat<usize, f64>,
    b: &faer::sparse::SparseColMat<usize, f64>,
    ts: &[f64],
    tol: f64,
) {
    let n = l.nrows();
    let g = random_rhs(n, 2, 7);
    let r7 = RationalApprox::cram(7).unwrap();
    let (zr, _) = r7.real_pole.unwrap();
    for (name, backend) in backends() {
        let solver = ShiftedSolver::new(l.as_ref(), b.as_ref(), backend).unwrap();
        for &t in ts {
            let mut poles: Vec<c64> = RationalApprox::cram(16).unwrap().poles.to_vec();
            poles.push(c64::new(zr, 0.0));
            for z in poles {
                let approx = if z.im == 0.0 {
                    RationalApprox {
                        degree: 1,
                        c0: 0.0,
                        poles: &[],
                        residues: &[],
                        real_pole: Some((z.re, 1.0)),
                        max_error: 0.0,
                    }
                } else {
                    single_pole(z)
                };
                let (x, report) = solver.apply_resolvent(&approx, t, g.as_ref()).unwrap();
                let reference = dense_shifted_solve(l, b, t, z, &g);
                let w = if z.im == 0.0 { 1.0 } else { 2.0 };
                let expected = Mat::from_fn(n, 2, |i, j| w * reference[(i, j)].re);
                let err = rel_err(&x, &expected);
                assert!(
                    err <= tol,
                    "{name}: t = {t}, z = {z}: relative error {err:e} (report {report:?})"
                );
                assert!(report.max_relative_residual() < 1e-11, "{name}: residual {report:?}");
            }
        }
    }
}

#[test]
fn every_backend_matches_dense_solve_on_random_pairs() {
    for (n, seed) in [(40, 1), (120, 2)] {
        let (l, b) = random_pair(n, seed);
        check_every_pole(&l, &b, &[1e-3, 0.1, 5.0], 1e-12);
    }
}

#[test]
fn every_backend_matches_dense_solve_on_mesh_matrices() {
    let (l, b) = mesh_pair(2);
    check_every_pole(&l, &b, &[1e-4, 0.05, 10.0], 1e-12);
    let (l, b) = bumpy_pair(2);
    check_every_pole(&l, &b, &[0.01, 1.0], 1e-12);
}

/// r_n(t B⁻¹L) f against the dense generalized eigendecomposition: against r_n(tΛ) to 1e−12
/// (the solver error), and against exp(−tΛ) to E_n + 1e−13 (the approximation error).
fn max_abs(x: &Mat<f64>) -> f64 {
    let mut m: f64 = 0.0;
    for j in 0..x.ncols() {
        for i in 0..x.nrows() {
            m = m.max(x[(i, j)].abs());
        }
    }
    m
}

fn b_norm(b: &faer::sparse::SparseColMat<usize, f64>, x: &Mat<f64>) -> f64 {
    let bx = dense(b) * x;
    (0..x.nrows()).map(|i| x[(i, 0)] * bx[(i, 0)]).sum::<f64>().sqrt()
}

#[test]
fn rational_operator_matches_dense_eigendecomposition() {
    let cases = [mesh_pair(3), random_pair(150, 3)];
    for (l, b) in &cases {
        let n = l.nrows();
        let (lambda, phi) = generalized_eigen(l, b);
        let f = random_rhs(n, 3, 11);
        for (name, backend) in backends() {
            let solver = ShiftedSolver::new(l.as_ref(), b.as_ref(), backend).unwrap();
            for degree in [7, 14, 16] {
                let approx = RationalApprox::cram(degree).unwrap();
                for t in [1e-4, 1e-2, 0.3, 10.0] {
                    let (kf, _) = solver.apply(approx, t, f.as_ref()).unwrap();
                    let rational = spectral_apply(&lambda, &phi, b, &f, |x| approx.eval(t * x));
                    let exact = spectral_apply(&lambda, &phi, b, &f, |x| (-t * x).exp());
                    // Relative to ‖f‖_∞: K_t is a contraction, and at large t the output is only
                    // the small mean of f, so relative-to-output would measure cancellation noise.
                    let e1 = rel_err(&kf, &rational).min(rel_err(&kf, &rational) * max_abs(&rational) / max_abs(&f));
                    assert!(e1 <= 1e-12, "{name} n={n} degree {degree} t={t}: vs r_n(tΛ) {e1:e}");
                    // Eq. (14): ‖r_n(tB⁻¹L) − K_t‖_{B→B} ≤ E_n, checked column by column; the 1e−12 is
                    // the solver error allowed above (MINRES stops at 1e−14 per pole, × Σ2|c_j|).
                    for j in 0..f.ncols() {
                        let e = b_norm(b, &(kf.subcols(j, 1).to_owned() - exact.subcols(j, 1)));
                        let fb = b_norm(b, &f.subcols(j, 1).to_owned());
                        assert!(
                            e <= (1.05 * approx.max_error + 1e-12) * fb,
                            "{name} n={n} degree {degree} t={t}: ‖error‖_B = {e:e}, ‖f‖_B = {fb:e}"
                        );
                    }
                }
            }
        }
    }
}

/// Factors are reused: many right-hand sides at once equal one at a time.
#[test]
fn factors_serve_many_right_hand_sides() {
    let (l, b) = mesh_pair(2);
    let n = l.nrows();
    let solver = ShiftedSolver::new(l.as_ref(), b.as_ref(), Backend::DirectLu).unwrap();
    let approx = RationalApprox::cram(DEFAULT_DEGREE).unwrap();
    let factors = solver.factor(approx, 0.1).unwrap();
    let f = random_rhs(n, 5, 3);
    let (all, report) = factors.apply(f.as_ref()).unwrap();
    assert_eq!(report.n_rhs, 5);
    assert_eq!(report.poles.len(), 8);
    for j in 0..5 {
        let fj = f.subcols(j, 1).to_owned();
        let (one, _) = factors.apply(fj.as_ref()).unwrap();
        let col = all.subcols(j, 1).to_owned();
        assert!(rel_err(&one, &col) < 1e-14);
    }
}

/// Mesh-independent MINRES iteration counts: icosphere level 3 vs level 5.
#[test]
fn minres_iterations_are_mesh_independent() {
    let approx = RationalApprox::cram(16).unwrap();
    let mut maxima = Vec::new();
    for level in [3, 5] {
        let (l, b) = mesh_pair(level);
        let solver = ShiftedSolver::new(l.as_ref(), b.as_ref(), Backend::Minres(MinresParams::default())).unwrap();
        let f = random_rhs(l.nrows(), 1, 5);
        let mut max_its = 0;
        for t in [1e-3, 0.1] {
            let (_, report) = solver.apply(approx, t, f.as_ref()).unwrap();
            for p in &report.poles {
                assert_eq!(p.method, SolveMethod::Minres);
                assert!(p.iterations <= 60, "level {level} t {t}: {p:?}");
                max_its = max_its.max(p.iterations);
            }
        }
        maxima.push(max_its);
    }
    // 16× more unknowns must not cost noticeably more iterations.
    assert!(maxima[1] <= maxima[0] + 8, "iterations grew with mesh size: {maxima:?}");
}

#[test]
fn jacobi_and_unpreconditioned_minres_agree_with_lu() {
    let (l, b) = mesh_pair(1);
    let n = l.nrows();
    let f = random_rhs(n, 1, 9);
    let approx = RationalApprox::cram(7).unwrap();
    let lu = ShiftedSolver::new(l.as_ref(), b.as_ref(), Backend::DirectLu).unwrap();
    let (reference, _) = lu.apply(approx, 0.2, f.as_ref()).unwrap();
    for pc in [Preconditioner::Jacobi, Preconditioner::None] {
        let params = MinresParams {
            preconditioner: pc,
            max_iters: 5000,
            ..MinresParams::default()
        };
        let s = ShiftedSolver::new(l.as_ref(), b.as_ref(), Backend::Minres(params)).unwrap();
        let (x, report) = s.apply(approx, 0.2, f.as_ref()).unwrap();
        assert!(rel_err(&x, &reference) < 1e-11, "{pc:?}: {report:?}");
    }
}

/// Solvers and factors are shared across threads by the callers (wfem-heat, shape-retrieval).
#[test]
fn solver_types_are_send_and_sync() {
    fn assert_send_sync<T: Send + Sync>() {}
    assert_send_sync::<ShiftedSolver>();
    assert_send_sync::<RationalFactors>();
    assert_send_sync::<RationalApprox>();
    assert_send_sync::<BatchReport>();
}

/// The complex-symmetric LDLᵀ (no pivoting) against the pivoted sparse LU on every pole of
/// degree 16 and the real pole of degree 7, for t over five decades, on a mesh large enough
/// (n = 2,562) that supernodes are wider than the unblocked dense kernel and have many
/// descendants. The rational operator itself is compared too.
#[test]
fn ldlt_matches_pivoted_lu_on_every_pole() {
    let (l, b) = bumpy_pair(4);
    let n = l.nrows();
    let g = random_rhs(n, 3, 11);
    let lu = ShiftedSolver::new(l.as_ref(), b.as_ref(), Backend::DirectLu).unwrap();
    let ldlt = ShiftedSolver::new(l.as_ref(), b.as_ref(), Backend::DirectLdlt).unwrap();
    let r16 = RationalApprox::cram(16).unwrap();
    for t in [1e-5, 1e-3, 1e-1, 1.0, 10.0] {
        for &z in r16.poles {
            let approx = single_pole(z);
            let (x, rep) = ldlt.apply_resolvent(&approx, t, g.as_ref()).unwrap();
            let (y, _) = lu.apply_resolvent(&approx, t, g.as_ref()).unwrap();
            assert_eq!(rep.poles[0].method, SolveMethod::ComplexLdlt);
            let err = rel_err(&x, &y);
            assert!(err < 1e-12, "t = {t}, z = {z}: LDLᵀ vs LU {err:e}");
            assert!(rep.max_relative_residual() < 1e-13, "t = {t}, z = {z}: {rep:?}");
        }
        for degree in [7, 16] {
            let approx = RationalApprox::cram(degree).unwrap();
            let (x, _) = ldlt.apply(approx, t, g.as_ref()).unwrap();
            let (y, _) = lu.apply(approx, t, g.as_ref()).unwrap();
            let err = rel_err(&x, &y);
            assert!(err < 1e-12, "t = {t}, degree {degree}: {err:e}");
        }
    }
}

/// [`Backend::MultiShift`] (all poles in one shift-and-invert Lanczos space, one real Cholesky)
/// against the dense generalized eigendecomposition: `apply` equals r_n(tΛ) applied spectrally,
/// for an odd degree (real pole) and the default one, t over five decades, on a mesh, a bumpy
/// mesh with irregular areas and a random pair. `apply_resolvent` (which starts the Lanczos run
/// from A⁻¹G and evaluates Q(s) instead of R(s)) equals the pivoted LU's.
#[test]
fn multi_shift_matches_dense_rational_operator_and_lu() {
    let params = KrylovParams {
        tol: 1e-13,
        ..KrylovParams::default()
    };
    let cases = [mesh_pair(3), bumpy_pair(3), random_pair(150, 3)];
    for (case, (l, b)) in cases.iter().enumerate() {
        let n = l.nrows();
        let (lambda, phi) = generalized_eigen(l, b);
        let f = random_rhs(n, 3, 5);
        let shared = ShiftedSolver::new(l.as_ref(), b.as_ref(), Backend::MultiShift(params)).unwrap();
        let lu = ShiftedSolver::new(l.as_ref(), b.as_ref(), Backend::DirectLu).unwrap();
        for degree in [7, 16] {
            let approx = RationalApprox::cram(degree).unwrap();
            for t in [1e-4, 1e-2, 0.3, 10.0] {
                let (kf, report) = shared.apply(approx, t, f.as_ref()).unwrap();
                let rational = spectral_apply(&lambda, &phi, b, &f, |x| approx.eval(t * x));
                let err = rel_err(&kf, &rational) * max_abs(&rational) / max_abs(&f);
                assert!(err <= 1e-11, "case {case} degree {degree} t={t}: {err:e}");
                assert_eq!(report.poles.len(), approx.n_solves());
                for pole in &report.poles {
                    assert_eq!(pole.method, SolveMethod::MultiShiftLanczos);
                    assert!(pole.iterations > 0 && pole.iterations <= n);
                    // Per-pole Galerkin residuals: measured ≤ 4e−9 (the tolerance controls the
                    // sum; poles near the spectrum of S converge more slowly).
                    assert!(pole.relative_residual <= 1e-6, "{pole:?}");
                }
                let (x, _) = shared.apply_resolvent(approx, t, f.as_ref()).unwrap();
                let (y, _) = lu.apply_resolvent(approx, t, f.as_ref()).unwrap();
                let err = rel_err(&x, &y);
                assert!(err <= 1e-10, "case {case} degree {degree} t={t}: resolvent {err:e}");
            }
        }
    }
}

/// The multi-shift backend's typed errors: bad parameters, the iteration cap, NaN input.
#[test]
fn multi_shift_errors_are_typed() {
    let (l, b) = mesh_pair(2);
    let n = l.nrows();
    for bad in [
        KrylovParams {
            gamma: 0.0,
            ..Default::default()
        },
        KrylovParams {
            tol: 1.5,
            ..Default::default()
        },
        KrylovParams {
            max_iter: 0,
            ..Default::default()
        },
    ] {
        let err = ShiftedSolver::new(l.as_ref(), b.as_ref(), Backend::MultiShift(bad)).unwrap_err();
        assert!(matches!(err, SolveError::InvalidParameter { .. }), "{err:?}");
    }
    let capped = KrylovParams {
        max_iter: 2,
        ..Default::default()
    };
    let solver = ShiftedSolver::new(l.as_ref(), b.as_ref(), Backend::MultiShift(capped)).unwrap();
    let approx = RationalApprox::cram(16).unwrap();
    let f = random_rhs(n, 1, 3);
    let err = solver.apply(approx, 0.1, f.as_ref()).unwrap_err();
    assert!(
        matches!(err, SolveError::KrylovNoConvergence { iterations: 2, .. }),
        "{err:?}"
    );
    let mut g = f.clone();
    g[(4, 0)] = f64::NAN;
    let err = solver.apply(approx, 0.1, g.as_ref()).unwrap_err();
    assert!(matches!(err, SolveError::NonFinite { .. }), "{err:?}");
}

/// `SpdFactor` on a pattern large enough (n = 10,242 ≥ 8,192) for the tree-parallel solve: the
/// residual ‖Ax − b‖/‖b‖ of one and of several right-hand sides, and one-at-a-time equals
/// all-at-once.
#[test]
fn spd_factor_solves_large_patterns() {
    let (l, b) = mesh_pair(5);
    let n = l.nrows();
    assert!(n >= 8192);
    let a = faer::sparse::SparseColMat::<usize, f64>::new(
        l.symbolic().to_owned().unwrap(),
        l.val().iter().zip(b.val()).map(|(x, y)| 0.01 * x + y).collect(),
    );
    let factor = CholeskyPattern::new(a.symbolic())
        .unwrap()
        .factor(a.as_ref(), faer::Par::Seq)
        .unwrap();
    let rhs = random_rhs(n, 3, 17);
    let mut x = rhs.clone();
    factor.solve_in_place(x.as_mut());
    let residual = &a * &x - &rhs;
    let rel = residual.norm_l2() / rhs.norm_l2();
    assert!(rel < 1e-13, "{rel:e}");
    for j in 0..3 {
        let bj: Vec<f64> = rhs.col(j).iter().copied().collect();
        let xj = factor.solve_vec(&bj);
        let diff = xj
            .iter()
            .zip(x.col(j).iter())
            .fold(0.0f64, |m, (p, q)| m.max((p - q).abs()));
        assert!(diff <= 1e-13 * x.norm_max(), "column {j}: {diff:e}");
    }
}
