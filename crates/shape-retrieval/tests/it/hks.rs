//! HKS against dense references on generated meshes.

use crate::common;

use common::{dense_kernel_matrix, dense_spectrum, rel_err, sig};
use faer::Mat;
use mesh_fem::generate::{bumpy, icosphere};
use shape_retrieval::hks::{
    auto_times, heat_kernel_signature, heat_trace, HksParams, Spectrum, SpectrumNormalization, TimeSampling,
};
use shape_retrieval::RetrievalError;
use wfem_heat::KernelDiagonal;

#[test]
fn dense_spectrum_is_b_orthonormal() {
    let s = dense_spectrum(&bumpy(1));
    let g = s.eigenvectors.transpose() * &s.mass * &s.eigenvectors;
    let n = g.nrows();
    let err = (0..n)
        .flat_map(|i| (0..n).map(move |j| (i, j)))
        .fold(0.0f64, |m, (i, j)| {
            m.max((g[(i, j)] - if i == j { 1.0 } else { 0.0 }).abs())
        });
    assert!(err < 1e-10, "ΦᵀBΦ − I = {err}");
    assert!(s.eigenvalues[0].abs() < 1e-10);
}

#[test]
fn kernel_value_matches_dense_diagonal() {
    let s = dense_spectrum(&bumpy(2));
    let k = 60;
    let spectrum = Spectrum::new(&s.eigenvalues[..k], s.eigenvectors.subcols(0, k)).unwrap();
    let times = vec![0.01, 0.1, 1.0];
    let params = HksParams {
        times: TimeSampling::Explicit(times.clone()),
        ..Default::default()
    };
    let hks = heat_kernel_signature(&spectrum, &params).unwrap();
    for (j, &t) in times.iter().enumerate() {
        let h = dense_kernel_matrix(&s, k, t);
        let diag: Vec<f64> = (0..h.nrows()).map(|i| h[(i, i)]).collect();
        let got: Vec<f64> = hks.values.col(j).iter().copied().collect();
        assert!(rel_err(&got, &diag) < 1e-12, "t = {t}: {}", rel_err(&got, &diag));
    }
}

#[test]
fn matrix_diagonal_matches_dense_diagonal_and_sums_to_heat_trace() {
    let s = dense_spectrum(&bumpy(2));
    let k = 60;
    let spectrum = Spectrum::new(&s.eigenvalues[..k], s.eigenvectors.subcols(0, k))
        .unwrap()
        .with_mass(s.ops.mass.as_ref())
        .unwrap();
    let times = vec![0.01, 0.1, 1.0];
    let params = HksParams {
        convention: KernelDiagonal::OperatorDiagonal,
        times: TimeSampling::Explicit(times.clone()),
        ..Default::default()
    };
    let hks = heat_kernel_signature(&spectrum, &params).unwrap();
    let trace = heat_trace(&s.eigenvalues[..k], &times);
    for (j, &t) in times.iter().enumerate() {
        let kt = dense_kernel_matrix(&s, k, t) * &s.mass;
        let diag: Vec<f64> = (0..kt.nrows()).map(|i| kt[(i, i)]).collect();
        let got: Vec<f64> = hks.values.col(j).iter().copied().collect();
        assert!(rel_err(&got, &diag) < 1e-12, "t = {t}: {}", rel_err(&got, &diag));
        let sum: f64 = got.iter().sum();
        assert!(
            (sum - trace[j]).abs() < 1e-10 * trace[j],
            "Σ_i K_t(i,i) = {sum} vs Z(t) = {}",
            trace[j]
        );
    }
}

#[test]
fn matrix_diagonal_with_full_spectrum_is_one_at_small_time() {
    // X Xᵀ B = I for the full spectrum, so K_t(i,i) → 1 as t → 0.
    let s = dense_spectrum(&icosphere(2));
    let spectrum = Spectrum::new(&s.eigenvalues, s.eigenvectors.as_ref())
        .unwrap()
        .with_mass(s.ops.mass.as_ref())
        .unwrap();
    let params = HksParams {
        convention: KernelDiagonal::OperatorDiagonal,
        times: TimeSampling::Explicit(vec![1e-12]),
        ..Default::default()
    };
    let hks = heat_kernel_signature(&spectrum, &params).unwrap();
    for v in hks.values.col(0).iter() {
        assert!((v - 1.0).abs() < 1e-8, "{v}");
    }
}

#[test]
fn precomputed_mass_eigenvectors_equal_sparse_product() {
    let s = dense_spectrum(&bumpy(1));
    let bx = &s.mass * &s.eigenvectors;
    let a = Spectrum::new(&s.eigenvalues, s.eigenvectors.as_ref())
        .unwrap()
        .with_mass(s.ops.mass.as_ref())
        .unwrap();
    let b = Spectrum::new(&s.eigenvalues, s.eigenvectors.as_ref())
        .unwrap()
        .with_mass_eigenvectors(bx.as_ref())
        .unwrap();
    let params = HksParams {
        convention: KernelDiagonal::OperatorDiagonal,
        ..Default::default()
    };
    let ha = heat_kernel_signature(&a, &params).unwrap();
    let hb = heat_kernel_signature(&b, &params).unwrap();
    let diff = (&ha.values - &hb.values).norm_max();
    assert!(diff < 1e-12 * ha.values.norm_max());
}

/// Σ_l (2l+1)/(4π) e^{−l(l+1)t}: the HKS of the unit sphere (addition theorem Σ_m Y_lm² = (2l+1)/(4π)).
fn sphere_hks(t: f64) -> f64 {
    (0..200)
        .map(|l| (2 * l + 1) as f64 / (4.0 * std::f64::consts::PI) * (-((l * (l + 1)) as f64) * t).exp())
        .sum()
}

#[test]
fn sphere_hks_is_constant_and_matches_addition_theorem() {
    let s = dense_spectrum(&icosphere(3));
    let spectrum = Spectrum::new(&s.eigenvalues, s.eigenvectors.as_ref()).unwrap();
    let times = vec![0.05, 0.2, 1.0];
    let params = HksParams {
        times: TimeSampling::Explicit(times.clone()),
        ..Default::default()
    };
    let hks = heat_kernel_signature(&spectrum, &params).unwrap();
    for (j, &t) in times.iter().enumerate() {
        let col: Vec<f64> = hks.values.col(j).iter().copied().collect();
        let (lo, hi) = col
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(lo, hi), &v| (lo.min(v), hi.max(v)));
        let mean = col.iter().sum::<f64>() / col.len() as f64;
        let exact = sphere_hks(t);
        eprintln!(
            "t={t}: spread {:.3e}, mean {mean} vs exact {exact}: {:.3e}",
            (hi - lo) / mean,
            (mean - exact).abs() / exact
        );
        assert!((hi - lo) / mean < 4e-2, "spread {}", (hi - lo) / mean);
        assert!((mean - exact).abs() / exact < 5e-3, "mean {mean} vs {exact}");
    }
}

#[test]
fn heat_trace_matches_sphere_and_dense_trace() {
    let s = dense_spectrum(&icosphere(2));
    let t = 1.0;
    let z = heat_trace(&s.eigenvalues, &[t])[0];
    // tr(Φ e^{−tΛ} Φᵀ B) computed densely.
    let kt = dense_kernel_matrix(&s, s.eigenvalues.len(), t) * &s.mass;
    let tr: f64 = (0..kt.nrows()).map(|i| kt[(i, i)]).sum();
    assert!((z - tr).abs() < 1e-10 * z);
    let exact: f64 = (0..100)
        .map(|l| (2 * l + 1) as f64 * (-((l * (l + 1)) as f64) * t).exp())
        .sum();
    eprintln!("Z({t}) = {z} vs sphere {exact}");
    assert!((z - exact).abs() / exact < 2e-2, "{z} vs {exact}");
}

#[test]
fn scaled_hks_divides_by_heat_trace() {
    let s = dense_spectrum(&bumpy(1));
    let spectrum = Spectrum::new(&s.eigenvalues, s.eigenvectors.as_ref()).unwrap();
    let plain = heat_kernel_signature(&spectrum, &HksParams::default()).unwrap();
    let scaled = heat_kernel_signature(
        &spectrum,
        &HksParams {
            scaled: true,
            ..Default::default()
        },
    )
    .unwrap();
    let z = heat_trace(&s.eigenvalues, &plain.times);
    for (j, zj) in z.iter().enumerate() {
        for i in 0..plain.values.nrows() {
            let want = plain.values[(i, j)] / zj;
            assert!((scaled.values[(i, j)] - want).abs() <= 1e-14 * want.abs());
        }
    }
}

#[test]
fn auto_times_follow_sun_et_al() {
    let eigenvalues = [0.0, 2.0, 2.0, 6.0, 50.0];
    let t = auto_times(&eigenvalues, 100).unwrap();
    let c = 4.0 * std::f64::consts::LN_10;
    assert_eq!(t.len(), 100);
    assert_eq!(t[0], c / 50.0);
    assert_eq!(t[99], c / 2.0);
    let ratio = t[1] / t[0];
    assert!(t.windows(2).all(|w| (w[1] / w[0] - ratio).abs() < 1e-12));
    assert!(matches!(
        auto_times(&[0.0, 0.0], 10),
        Err(RetrievalError::NoNonzeroEigenvalue)
    ));
}

/// Eigenpairs of the mesh scaled by β: λ → λ/β², φ → φ/β, B → β²B.
fn scaled_spectrum(s: &common::DenseSpectrum, beta: f64) -> (Vec<f64>, Mat<f64>, Mat<f64>) {
    let eigenvalues = s.eigenvalues.iter().map(|l| l / (beta * beta)).collect();
    let eigenvectors = &s.eigenvectors * faer::Scale(1.0 / beta);
    let bx = (&s.mass * &s.eigenvectors) * faer::Scale(beta);
    (eigenvalues, eigenvectors, bx)
}

#[test]
fn normalizations_make_both_conventions_scale_invariant() {
    let s = dense_spectrum(&bumpy(1));
    let area = s.ops.area();
    let beta = 3.7;
    let (l2, x2, bx2) = scaled_spectrum(&s, beta);
    let bx = &s.mass * &s.eigenvectors;
    for convention in [KernelDiagonal::KernelValue, KernelDiagonal::OperatorDiagonal] {
        for (norm, norm2) in [
            (
                SpectrumNormalization::MaxEigenvalue,
                SpectrumNormalization::MaxEigenvalue,
            ),
            (
                SpectrumNormalization::UnitArea { area },
                SpectrumNormalization::UnitArea {
                    area: area * beta * beta,
                },
            ),
        ] {
            let a = Spectrum::new(&s.eigenvalues, s.eigenvectors.as_ref())
                .unwrap()
                .with_mass_eigenvectors(bx.as_ref())
                .unwrap();
            let b = Spectrum::new(&l2, x2.as_ref())
                .unwrap()
                .with_mass_eigenvectors(bx2.as_ref())
                .unwrap();
            let ha = heat_kernel_signature(
                &a,
                &HksParams {
                    convention,
                    normalization: norm,
                    ..Default::default()
                },
            )
            .unwrap();
            let hb = heat_kernel_signature(
                &b,
                &HksParams {
                    convention,
                    normalization: norm2,
                    ..Default::default()
                },
            )
            .unwrap();
            let diff = (&ha.values - &hb.values).norm_max() / ha.values.norm_max();
            assert!(diff < 1e-12, "{convention:?} {norm:?}: {diff}");
            // Without normalization the same times give different values.
            let plain = HksParams {
                convention,
                times: TimeSampling::Explicit(ha.times.clone()),
                ..Default::default()
            };
            let pa = heat_kernel_signature(&a, &plain).unwrap();
            let pb = heat_kernel_signature(&b, &plain).unwrap();
            assert!((&pa.values - &pb.values).norm_max() / pa.values.norm_max() > 0.1);
        }
    }
}

#[test]
fn bad_inputs_are_typed_errors() {
    let x = Mat::<f64>::zeros(4, 2);
    assert!(matches!(
        Spectrum::new(&[0.0], x.as_ref()),
        Err(RetrievalError::DimensionMismatch { .. })
    ));
    assert!(matches!(
        Spectrum::new(&[], Mat::<f64>::zeros(4, 0).as_ref()),
        Err(RetrievalError::Empty { .. })
    ));
    assert!(matches!(
        Spectrum::new(&[0.0, f64::NAN], x.as_ref()),
        Err(RetrievalError::NonFinite { index: 1, .. })
    ));
    assert!(matches!(
        Spectrum::new(&[-1.0, 2.0], x.as_ref()),
        Err(RetrievalError::NegativeEigenvalue { index: 0, .. })
    ));
    let mut y = Mat::<f64>::zeros(4, 2);
    y[(3, 1)] = f64::INFINITY;
    assert!(matches!(
        Spectrum::new(&[0.0, 1.0], y.as_ref()),
        Err(RetrievalError::NonFinite { index: 7, .. })
    ));
    let s = Spectrum::new(&[0.0, 1.0], x.as_ref()).unwrap();
    let md = HksParams {
        convention: KernelDiagonal::OperatorDiagonal,
        ..Default::default()
    };
    assert!(matches!(
        heat_kernel_signature(&s, &md),
        Err(RetrievalError::MassRequired)
    ));
    let neg = HksParams {
        times: TimeSampling::Explicit(vec![1.0, -1.0]),
        ..Default::default()
    };
    assert!(matches!(
        heat_kernel_signature(&s, &neg),
        Err(RetrievalError::InvalidParameter { name: "time", .. })
    ));
    let zero = HksParams {
        times: TimeSampling::Auto { num_times: 0 },
        ..Default::default()
    };
    assert!(matches!(
        heat_kernel_signature(&s, &zero),
        Err(RetrievalError::InvalidParameter { .. })
    ));
    let area = HksParams {
        normalization: SpectrumNormalization::UnitArea { area: 0.0 },
        ..Default::default()
    };
    assert!(matches!(
        heat_kernel_signature(&s, &area),
        Err(RetrievalError::InvalidParameter { name: "area", .. })
    ));
    assert!(matches!(
        s.clone().with_mass_eigenvectors(Mat::<f64>::zeros(3, 2).as_ref()),
        Err(RetrievalError::DimensionMismatch { .. })
    ));
}

/// Every 16th vertex and every 11th time, 6 significant digits.
fn table(hks: &shape_retrieval::hks::HeatKernelSignature) -> String {
    let mut out = String::from("times:");
    let cols: Vec<usize> = (0..hks.times.len()).step_by(11).collect();
    for &j in &cols {
        out += &format!(" {}", sig(hks.times[j], 6));
    }
    out.push('\n');
    for i in (0..hks.values.nrows()).step_by(16) {
        out += &format!("v{i:03}:");
        for &j in &cols {
            out += &format!(" {}", sig(hks.values[(i, j)], 6));
        }
        out.push('\n');
    }
    out
}

/// The snapshots were taken with 100 automatic times (the default before it became
/// [`shape_retrieval::hks::DEFAULT_NUM_TIMES`] = 16); every 11th column is shown.
fn hundred() -> HksParams {
    HksParams {
        times: shape_retrieval::hks::TimeSampling::Auto { num_times: 100 },
        ..Default::default()
    }
}

#[test]
fn snapshot_hks_conventions_on_bumpy() {
    let s = dense_spectrum(&bumpy(2));
    let k = 100;
    let area = s.ops.area();
    let spectrum = Spectrum::new(&s.eigenvalues[..k], s.eigenvectors.subcols(0, k))
        .unwrap()
        .with_mass(s.ops.mass.as_ref())
        .unwrap();
    let kv = heat_kernel_signature(&spectrum, &hundred()).unwrap();
    insta::assert_snapshot!("hks_kernel_value_bumpy2_k100", table(&kv));
    let md = HksParams {
        convention: KernelDiagonal::OperatorDiagonal,
        ..hundred()
    };
    insta::assert_snapshot!(
        "hks_matrix_diagonal_bumpy2_k100",
        table(&heat_kernel_signature(&spectrum, &md).unwrap())
    );
    let scaled = HksParams {
        scaled: true,
        ..hundred()
    };
    insta::assert_snapshot!(
        "hks_scaled_bumpy2_k100",
        table(&heat_kernel_signature(&spectrum, &scaled).unwrap())
    );
    let dhk3 = HksParams {
        convention: KernelDiagonal::OperatorDiagonal,
        normalization: SpectrumNormalization::MaxEigenvalue,
        ..hundred()
    };
    insta::assert_snapshot!(
        "hks_dhk3_max_eigenvalue_bumpy2_k100",
        table(&heat_kernel_signature(&spectrum, &dhk3).unwrap())
    );
    let unit = HksParams {
        normalization: SpectrumNormalization::UnitArea { area },
        ..hundred()
    };
    insta::assert_snapshot!(
        "hks_unit_area_bumpy2_k100",
        table(&heat_kernel_signature(&spectrum, &unit).unwrap())
    );
}

#[test]
fn apply_heat_kernel_matches_dense_and_conserves_mass() {
    let s = dense_spectrum(&bumpy(2));
    let k = 50;
    let spectrum = Spectrum::new(&s.eigenvalues[..k], s.eigenvectors.subcols(0, k))
        .unwrap()
        .with_mass(s.ops.mass.as_ref())
        .unwrap();
    let f = Mat::from_fn(s.eigenvalues.len(), 3, |i, j| ((i * (j + 1)) as f64 * 0.1).cos());
    let t = 0.05;
    let got = spectrum.apply_heat_kernel(t, f.as_ref()).unwrap();
    let want = dense_kernel_matrix(&s, k, t) * &s.mass * &f;
    assert!((&got - &want).norm_max() < 1e-12 * want.norm_max());
    // 1ᵀB K_t f = 1ᵀB f: the constant mode is kept.
    let ones = Mat::from_fn(1, f.nrows(), |_, _| 1.0);
    let (before, after) = (&ones * &s.mass * &f, &ones * &s.mass * &got);
    for j in 0..3 {
        assert!((before[(0, j)] - after[(0, j)]).abs() < 1e-10 * before[(0, j)].abs().max(1.0));
    }
    let no_mass = Spectrum::new(&s.eigenvalues[..k], s.eigenvectors.subcols(0, k)).unwrap();
    assert!(matches!(
        no_mass.apply_heat_kernel(t, f.as_ref()),
        Err(RetrievalError::MassRequired)
    ));
    assert!(matches!(
        spectrum.apply_heat_kernel(-1.0, f.as_ref()),
        Err(RetrievalError::InvalidParameter { .. })
    ));
    assert!(matches!(
        spectrum.apply_heat_kernel(t, f.subrows(0, 5)),
        Err(RetrievalError::DimensionMismatch { .. })
    ));
}
