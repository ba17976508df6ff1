//! The exact HKS (probing) and the per-time choice of `HksMethod::Auto`, against the dense
//! generalized eigendecomposition of (L, B) with all n eigenpairs (the independent truth).

use crate::common::{dense_spectrum, rel_err};
use faer::Mat;
use mesh_fem::generate;
use shape_retrieval::exact::{
    exact_signature, signature_by_method, truncation_bound, truncation_estimate, HksMethod, HksSource,
};
use shape_retrieval::hks::{heat_kernel_signature, HksParams, Spectrum, TimeSampling};
use wfem_heat::{DiagonalParams, HeatKernel, HeatParams, KernelDiagonal};

/// HKS (kernel-value convention) from the first k of the dense eigenpairs.
fn truncated(s: &crate::common::DenseSpectrum, k: usize, times: &[f64]) -> Mat<f64> {
    let spectrum = Spectrum::new(&s.eigenvalues[..k], s.eigenvectors.subcols(0, k)).unwrap();
    let params = HksParams {
        times: TimeSampling::Explicit(times.to_vec()),
        ..Default::default()
    };
    heat_kernel_signature(&spectrum, &params).unwrap().values
}

fn col(m: &Mat<f64>, j: usize) -> Vec<f64> {
    m.col(j).iter().copied().collect()
}

#[test]
fn truncation_bound_bounds_the_heat_trace_error_and_vanishes_with_the_whole_spectrum() {
    let mesh = generate::irregular_sphere(2, 0.3);
    let s = dense_spectrum(&mesh);
    let n = s.eigenvalues.len();
    assert_eq!(truncation_bound(&s.eigenvalues, n, 1e-3), 0.0);
    let k = 20;
    let mut last = f64::INFINITY;
    for t in [1e-3, 1e-2, 3e-2, 0.1, 0.3, 1.0, 10.0] {
        let full: f64 = s.eigenvalues.iter().map(|l| (-l * t).exp()).sum();
        let kept: f64 = s.eigenvalues[..k].iter().map(|l| (-l * t).exp()).sum();
        let error = (full - kept) / full;
        let bound = truncation_bound(&s.eigenvalues[..k], n, t);
        let estimate = truncation_estimate(&s.eigenvalues[..k], n, t);
        eprintln!("t = {t}: error {error:.2e}, estimate {estimate:.2e}, bound {bound:.2e}");
        assert!(bound >= error, "t = {t}: bound {bound:e} below the error {error:e}");
        assert!(
            estimate <= bound,
            "t = {t}: estimate {estimate:e} above the bound {bound:e}"
        );
        // The Weyl-law estimate is within a small factor of the true error, where the bound
        // is orders of magnitude above it.
        if error > 1e-14 && error < 0.1 {
            assert!(
                estimate >= error / 5.0 && estimate <= 5.0 * error,
                "t = {t}: estimate {estimate:e} vs error {error:e}"
            );
        }
        assert!(bound <= last, "the bound decreases with t");
        last = bound;
    }
    // Tight enough to be useful: at a large t both are tiny.
    assert!(truncation_bound(&s.eigenvalues[..k], n, 1.0) < 1e-6);
}

#[test]
fn exact_signature_matches_the_full_spectrum_where_truncation_fails() {
    let mesh = generate::irregular_sphere(2, 0.3);
    let s = dense_spectrum(&mesh);
    let n = s.eigenvalues.len();
    let kernel = HeatKernel::new(&s.ops, HeatParams::default()).unwrap();
    let times = [2e-3, 5e-3, 1e-2];
    let truth = truncated(&s, n, &times);
    let k30 = truncated(&s, 30, &times);
    for (convention, name) in [
        (KernelDiagonal::KernelValue, "kernel value"),
        (KernelDiagonal::OperatorDiagonal, "operator diagonal"),
    ] {
        let exact = exact_signature(&kernel, &times, convention, &DiagonalParams::default()).unwrap();
        for (j, t) in times.iter().enumerate() {
            let want = match convention {
                KernelDiagonal::KernelValue => col(&truth, j),
                // diag(Φ e^{−tΛ} Φᵀ B): the dense kernel matrix times B, diagonal only.
                KernelDiagonal::OperatorDiagonal => {
                    let x = &s.eigenvectors;
                    let bx = &s.mass * x;
                    (0..n)
                        .map(|i| {
                            (0..n)
                                .map(|c| (-s.eigenvalues[c] * t).exp() * x[(i, c)] * bx[(i, c)])
                                .sum()
                        })
                        .collect()
                }
            };
            let e = rel_err(&col(&exact.values, j), &want);
            assert!(e < 1e-8, "{name}, t = {t}: exact diagonal off by {e:e}");
        }
    }
    // And the truncated sum really is wrong there (so the test means something).
    assert!(rel_err(&col(&k30, 0), &col(&truth, 0)) > 0.1);
}

#[test]
fn auto_takes_the_spectral_sum_only_where_its_bound_holds() {
    let mesh = generate::irregular_sphere(2, 0.3);
    let s = dense_spectrum(&mesh);
    let n = s.eigenvalues.len();
    let kernel = HeatKernel::new(&s.ops, HeatParams::default()).unwrap();
    let k = 40;
    let times = [3e-3, 3e-2, 0.3, 3.0];
    let truth = truncated(&s, n, &times);
    let spectral = truncated(&s, k, &times);
    let tol = 1e-6;
    let (values, sources) = signature_by_method(
        &kernel,
        &s.eigenvalues[..k],
        spectral.clone(),
        &times,
        KernelDiagonal::KernelValue,
        HksMethod::Auto { tol },
        &DiagonalParams::default(),
    )
    .unwrap();
    let mut kinds = Vec::new();
    for (j, t) in times.iter().enumerate() {
        let e = rel_err(&col(&values, j), &col(&truth, j));
        match sources[j] {
            HksSource::Spectral { estimate, bound } => {
                assert!(estimate <= tol && estimate <= bound);
                assert!(
                    e < 1e-5,
                    "t = {t}: spectral column off by {e:e} (estimate {estimate:e})"
                );
            }
            HksSource::Exact { relative_tail } => {
                assert!(truncation_estimate(&s.eigenvalues[..k], n, *t) > tol);
                assert!(relative_tail <= 1e-10);
                assert!(e < 1e-8, "t = {t}: exact column off by {e:e}");
            }
        }
        kinds.push(wfem_base::Choice::name(&sources[j].method()));
    }
    assert_eq!(kinds, ["exact", "exact", "spectral", "spectral"]);

    // Spectral keeps the given values; Exact replaces them all.
    let (same, _) = signature_by_method(
        &kernel,
        &s.eigenvalues[..k],
        spectral.clone(),
        &times,
        KernelDiagonal::KernelValue,
        HksMethod::Spectral,
        &DiagonalParams::default(),
    )
    .unwrap();
    assert_eq!(same, spectral);
    let bad = signature_by_method(
        &kernel,
        &s.eigenvalues[..k],
        spectral.clone(),
        &times,
        KernelDiagonal::KernelValue,
        HksMethod::Auto { tol: 2.0 },
        &DiagonalParams::default(),
    );
    assert!(bad.is_err());
}

/// With probing parameters, auto keeps the spectral sum where probing is out of reach and
/// exact refuses; selected inversion (the default) reaches every time.
#[test]
fn auto_keeps_the_spectral_sum_where_probing_is_out_of_reach_and_exact_refuses() {
    // A mesh large enough for probing to use fewer columns than vertices at small t.
    let mesh = generate::icosphere(4);
    let ops = mesh_fem::assemble(&mesh, &mesh_fem::AssemblyParams::default()).unwrap();
    let kernel = HeatKernel::new(&ops, HeatParams::default()).unwrap();
    let n = kernel.n();
    // Two eigenvalues only: the truncation bound is large at both times, so both want the
    // exact diagonal.
    let eigenvalues = [0.0, 2.0];
    let times = [1e-5, 1e-2];
    let spectral = Mat::<f64>::zeros(n, times.len());
    // Allow exactly the probe columns the small t needs; the larger t needs more (the
    // refusal of `Exact` below says so).
    let probing = DiagonalParams {
        method: wfem_heat::diagonal::DiagonalMethod::Probing { tol: 1e-10 },
        ..Default::default()
    };
    let columns = |t: f64| {
        exact_signature(&kernel, &[t], KernelDiagonal::KernelValue, &probing)
            .unwrap()
            .info
            .columns
    };
    let small = columns(times[0]);
    assert!(small < n, "probing uses {small} of {n} columns at t = {}", times[0]);
    let params = DiagonalParams {
        max_columns: small,
        ..probing
    };
    let run_with = |method, params: &DiagonalParams| {
        signature_by_method(
            &kernel,
            &eigenvalues,
            spectral.clone(),
            &times,
            KernelDiagonal::KernelValue,
            method,
            params,
        )
    };
    let run = |method| run_with(method, &params);
    let (values, sources) = run(HksMethod::Auto { tol: 1e-6 }).unwrap();
    assert_eq!(sources[0].method(), HksMethod::Exact);
    assert_eq!(sources[1].method(), HksMethod::Spectral);
    assert!(values.col(0).iter().all(|&v| v > 0.0), "the exact column was filled in");
    assert!(values.col(1).iter().all(|&v| v == 0.0), "the spectral column kept");
    assert!(run(HksMethod::Exact).is_err());
    // Selected inversion: every time exact, equal to the probed column where probing works.
    let (all, sources) = run_with(HksMethod::Auto { tol: 1e-6 }, &DiagonalParams::default()).unwrap();
    assert!(sources.iter().all(|s| s.method() == HksMethod::Exact), "{sources:?}");
    for i in 0..n {
        assert!((all[(i, 0)] - values[(i, 0)]).abs() <= 1e-8 * all[(i, 0)]);
        assert!(all[(i, 1)] > 0.0);
    }
    assert!(run_with(HksMethod::Exact, &DiagonalParams::default()).is_ok());
}
