//! Bags of features on HKS of generated meshes, checked against direct evaluations.

use crate::common;

use common::{dense_kernel_matrix, dense_spectrum};
use faer::Mat;
use mesh_fem::generate::{bumpy, icosphere, irregular_sphere};
use shape_retrieval::bof::{vertex_areas, Vocabulary, VocabularyParams};
use shape_retrieval::distance::{l1_distance, pairwise_l1};
use shape_retrieval::hks::{heat_kernel_signature, HksParams, Spectrum, SpectrumNormalization, TimeSampling};
use shape_retrieval::retrieval::evaluate;
use shape_retrieval::RetrievalError;

/// log HKS at 6 fixed times of the unit-area-normalized spectrum (first 80 eigenpairs).
fn descriptors(s: &common::DenseSpectrum) -> Mat<f64> {
    let k = 80.min(s.eigenvalues.len());
    let spectrum = Spectrum::new(&s.eigenvalues[..k], s.eigenvectors.subcols(0, k)).unwrap();
    let params = HksParams {
        times: TimeSampling::Explicit(vec![0.005, 0.008, 0.012, 0.02, 0.03, 0.05]),
        normalization: SpectrumNormalization::UnitArea { area: s.ops.area() },
        ..Default::default()
    };
    let h = heat_kernel_signature(&spectrum, &params).unwrap().values;
    Mat::from_fn(h.nrows(), h.ncols(), |i, j| h[(i, j)].ln())
}

#[test]
fn vertex_areas_are_row_sums_and_sum_to_area() {
    let s = dense_spectrum(&bumpy(1));
    let a = vertex_areas(s.ops.mass.as_ref());
    for (i, ai) in a.iter().enumerate() {
        let row: f64 = (0..s.mass.ncols()).map(|j| s.mass[(i, j)]).sum();
        assert!((ai - row).abs() < 1e-14 * row);
        assert!((ai - s.ops.lumped_diagonal[i]).abs() < 1e-14 * row);
    }
    assert!((a.iter().sum::<f64>() - s.ops.area()).abs() < 1e-12);
}

#[test]
fn soft_assignment_matches_formula_and_rows_sum_to_one() {
    let words = Mat::from_fn(3, 1, |i, _| i as f64);
    let voc = Vocabulary::new(words, 0.5).unwrap();
    let x = Mat::from_fn(4, 1, |i, _| [0.2, 1.0, 1.7, 1e3][i]);
    let theta = voc.soft_assignment(x.as_ref()).unwrap();
    for i in 0..3 {
        let w: Vec<f64> = (0..3)
            .map(|c| (-(x[(i, 0)] - c as f64).powi(2) / (2.0 * 0.25)).exp())
            .collect();
        let sum: f64 = w.iter().sum();
        for c in 0..3 {
            assert!((theta[(i, c)] - w[c] / sum).abs() < 1e-15);
        }
    }
    // Far from every word: no 0/0, all weight on the nearest word.
    assert_eq!(theta[(3, 2)], 1.0);
    for i in 0..4 {
        assert!(((0..3).map(|c| theta[(i, c)]).sum::<f64>() - 1.0).abs() < 1e-15);
    }
}

#[test]
fn trained_vocabulary_sigma_is_median_nearest_word_distance() {
    let s = dense_spectrum(&bumpy(2));
    let p = descriptors(&s);
    let voc = Vocabulary::train(
        p.as_ref(),
        &VocabularyParams {
            size: 12,
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(voc.size(), 12);
    let w = voc.words();
    let mut dist: Vec<f64> = (0..p.nrows())
        .map(|i| {
            (0..w.nrows())
                .map(|c| {
                    (0..p.ncols())
                        .map(|j| (p[(i, j)] - w[(c, j)]).powi(2))
                        .sum::<f64>()
                        .sqrt()
                })
                .fold(f64::INFINITY, f64::min)
        })
        .collect();
    dist.sort_by(f64::total_cmp);
    let n = dist.len();
    let median = if n % 2 == 1 {
        dist[n / 2]
    } else {
        0.5 * (dist[n / 2 - 1] + dist[n / 2])
    };
    assert!((voc.sigma() - median).abs() < 1e-14 * median);
    let given = Vocabulary::train(
        p.as_ref(),
        &VocabularyParams {
            size: 12,
            sigma: Some(0.3),
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(given.sigma(), 0.3);
    assert_eq!(given.words(), voc.words());
    // Subsampled training: deterministic, and σ is the median over the sample, close to the full one.
    let sub = VocabularyParams {
        size: 12,
        max_training_points: Some(100),
        ..Default::default()
    };
    let a = Vocabulary::train(p.as_ref(), &sub).unwrap();
    let b = Vocabulary::train(p.as_ref(), &sub).unwrap();
    assert_eq!(a.words(), b.words());
    assert!(
        (a.sigma() / voc.sigma() - 1.0).abs() < 0.5,
        "{} vs {}",
        a.sigma(),
        voc.sigma()
    );
    // Every word of a subsampled vocabulary is a mean of training rows, so it lies in their hull;
    // at least check it is within the range of the descriptors per coordinate.
    for c in 0..12 {
        for j in 0..p.ncols() {
            let col: Vec<f64> = (0..p.nrows()).map(|i| p[(i, j)]).collect();
            let (lo, hi) = col
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| (l.min(v), h.max(v)));
            assert!(a.words()[(c, j)] >= lo - 1e-12 && a.words()[(c, j)] <= hi + 1e-12);
        }
    }
    let too_small = VocabularyParams {
        size: 12,
        max_training_points: Some(5),
        ..Default::default()
    };
    assert!(matches!(
        Vocabulary::train(p.as_ref(), &too_small),
        Err(RetrievalError::TooFewDescriptors { n_points: 5, k: 12 })
    ));
}

#[test]
fn bag_of_features_sums_to_area() {
    let s = dense_spectrum(&bumpy(2));
    let p = descriptors(&s);
    let voc = Vocabulary::train(
        p.as_ref(),
        &VocabularyParams {
            size: 16,
            ..Default::default()
        },
    )
    .unwrap();
    let a = vertex_areas(s.ops.mass.as_ref());
    let bag = voc.bag_of_features(p.as_ref(), &a).unwrap();
    assert_eq!(bag.len(), 16);
    assert!((bag.iter().sum::<f64>() - s.ops.area()).abs() < 1e-12 * s.ops.area());
    assert!(bag.iter().all(|&v| v >= 0.0));
    // Normalised by the area it is a distribution.
    let normalized: Vec<f64> = bag.iter().map(|v| v / s.ops.area()).collect();
    assert!((normalized.iter().sum::<f64>() - 1.0).abs() < 1e-14);
    // Θᵀa computed directly.
    let theta = voc.soft_assignment(p.as_ref()).unwrap();
    for c in 0..16 {
        let want: f64 = (0..p.nrows()).map(|i| theta[(i, c)] * a[i]).sum();
        assert!((bag[c] - want).abs() < 1e-14 * s.ops.area());
    }
}

#[test]
fn spatially_sensitive_bag_is_symmetric_and_conserves_area() {
    let s = dense_spectrum(&bumpy(2));
    let p = descriptors(&s);
    let voc = Vocabulary::train(
        p.as_ref(),
        &VocabularyParams {
            size: 10,
            ..Default::default()
        },
    )
    .unwrap();
    let n = s.eigenvalues.len();
    let theta = voc.soft_assignment(p.as_ref()).unwrap();
    for t in [0.0, 0.01, 0.1] {
        // K_t Θ = Φ e^{−tΛ} Φᵀ B Θ with the full dense spectrum.
        let kernel = dense_kernel_matrix(&s, n, t) * &s.mass;
        let f = voc
            .spatially_sensitive_bag(p.as_ref(), s.ops.mass.as_ref(), |block| Ok(&kernel * block))
            .unwrap();
        // The spectral kernel of `Spectrum` plugs in the same way and agrees.
        let spectrum = Spectrum::new(&s.eigenvalues, s.eigenvectors.as_ref())
            .unwrap()
            .with_mass(s.ops.mass.as_ref())
            .unwrap();
        let g = voc
            .spatially_sensitive_bag(p.as_ref(), s.ops.mass.as_ref(), |block| {
                spectrum.apply_heat_kernel(t, block)
            })
            .unwrap();
        assert!((&f - &g).norm_max() < 1e-10 * f.norm_max());
        assert_eq!((f.nrows(), f.ncols()), (10, 10));
        let total: f64 = f.col_iter().flat_map(|c| c.iter().copied().collect::<Vec<_>>()).sum();
        assert!(
            (total - s.ops.area()).abs() < 1e-9 * s.ops.area(),
            "t = {t}: Σ F = {total}"
        );
        for i in 0..10 {
            for j in 0..10 {
                assert!((f[(i, j)] - f[(j, i)]).abs() < 1e-10 * f.norm_max());
            }
        }
        if t == 0.0 {
            // K_0 = I: F = Θᵀ B Θ, computed densely.
            let want = theta.transpose() * &s.mass * &theta;
            assert!((&f - &want).norm_max() < 1e-10 * want.norm_max());
        }
    }
}

#[test]
fn spatially_sensitive_bag_rejects_bad_kernel_output() {
    let s = dense_spectrum(&icosphere(1));
    let p = descriptors(&s);
    let voc = Vocabulary::train(
        p.as_ref(),
        &VocabularyParams {
            size: 4,
            ..Default::default()
        },
    )
    .unwrap();
    let wrong = voc.spatially_sensitive_bag(p.as_ref(), s.ops.mass.as_ref(), |b| Ok(Mat::zeros(b.nrows(), 3)));
    assert!(matches!(wrong, Err(RetrievalError::DimensionMismatch { .. })));
    let nan = voc.spatially_sensitive_bag(p.as_ref(), s.ops.mass.as_ref(), |b| {
        Ok(Mat::from_fn(b.nrows(), b.ncols(), |_, _| f64::NAN))
    });
    assert!(matches!(nan, Err(RetrievalError::NonFinite { .. })));
    let failing = voc.spatially_sensitive_bag(p.as_ref(), s.ops.mass.as_ref(), |_| {
        Err(RetrievalError::Empty { what: "kernel" })
    });
    assert!(matches!(failing, Err(RetrievalError::Empty { what: "kernel" })));
}

#[test]
fn l1_distances() {
    assert_eq!(l1_distance(&[1.0, 2.0, 3.0], &[0.0, 4.0, 3.0]).unwrap(), 3.0);
    assert!(matches!(
        l1_distance(&[1.0], &[1.0, 2.0]),
        Err(RetrievalError::DimensionMismatch { .. })
    ));
    assert!(matches!(
        l1_distance(&[f64::NAN], &[1.0]),
        Err(RetrievalError::NonFinite { .. })
    ));
    let d = pairwise_l1(&[vec![0.0, 1.0], vec![1.0, 1.0], vec![3.0, -1.0]]).unwrap();
    assert_eq!(d[(0, 1)], 1.0);
    assert_eq!(d[(2, 0)], 5.0);
    assert_eq!(d[(1, 1)], 0.0);
}

#[test]
fn vocabulary_errors() {
    let p = Mat::<f64>::zeros(5, 2);
    assert!(matches!(
        Vocabulary::train(p.as_ref(), &VocabularyParams::default()),
        Err(RetrievalError::TooFewDescriptors { n_points: 5, k: 48 })
    ));
    // All descriptors equal: the median nearest-word distance is 0, so σ is invalid.
    assert!(matches!(
        Vocabulary::train(
            p.as_ref(),
            &VocabularyParams {
                size: 2,
                ..Default::default()
            }
        ),
        Err(RetrievalError::InvalidParameter { name: "sigma", .. })
    ));
    let voc = Vocabulary::new(Mat::from_fn(2, 2, |i, j| (i + j) as f64), 1.0).unwrap();
    assert!(matches!(
        voc.soft_assignment(Mat::<f64>::zeros(3, 3).as_ref()),
        Err(RetrievalError::DimensionMismatch { .. })
    ));
    assert!(matches!(
        voc.bag_of_features(Mat::<f64>::zeros(3, 2).as_ref(), &[1.0]),
        Err(RetrievalError::DimensionMismatch { .. })
    ));
    assert!(matches!(
        Vocabulary::new(Mat::zeros(2, 2), -1.0),
        Err(RetrievalError::InvalidParameter { .. })
    ));
}

#[test]
fn shape_google_pipeline_separates_spheres_from_bumpy_shapes() {
    // Two classes, each shape at several scales/samplings: unit-area-normalized HKS makes the
    // bags scale-invariant, so retrieval should be perfect.
    let meshes = [
        (icosphere(2), 0u32),
        (icosphere(2).scaled(3.0).unwrap(), 0),
        (irregular_sphere(2, 2.0), 0),
        (bumpy(2), 1),
        (bumpy(2).scaled(0.5).unwrap(), 1),
        (bumpy(2).scaled(2.0).unwrap(), 1),
    ];
    let spectra: Vec<_> = meshes.iter().map(|(m, _)| dense_spectrum(m)).collect();
    let descs: Vec<Mat<f64>> = spectra.iter().map(descriptors).collect();
    let total_rows: usize = descs.iter().map(|d| d.nrows()).sum();
    let mut pooled = Mat::<f64>::zeros(total_rows, 6);
    let mut r = 0;
    for d in &descs {
        pooled.subrows_mut(r, d.nrows()).copy_from(d);
        r += d.nrows();
    }
    let voc = Vocabulary::train(
        pooled.as_ref(),
        &VocabularyParams {
            size: 16,
            ..Default::default()
        },
    )
    .unwrap();
    let bags: Vec<Vec<f64>> = spectra
        .iter()
        .zip(&descs)
        .map(|(s, d)| {
            let a = vertex_areas(s.ops.mass.as_ref());
            let area: f64 = a.iter().sum();
            voc.bag_of_features(d.as_ref(), &a)
                .unwrap()
                .into_iter()
                .map(|v| v / area)
                .collect()
        })
        .collect();
    let dist = pairwise_l1(&bags).unwrap();
    let labels: Vec<u32> = meshes.iter().map(|(_, l)| *l).collect();
    let report = evaluate(dist.as_ref(), &labels).unwrap();
    eprintln!("mAP = {}", report.mean_average_precision);
    assert_eq!(report.mean_average_precision, 1.0);
}

/// The streamed bag `Θᵀw` (Θ never formed, rows in blocks) against the plain formula, for
/// both assignments, over more rows than one block; and the same bits on one thread as on
/// three.
#[test]
fn streamed_bag_matches_the_formula_and_is_the_same_on_any_thread_count() {
    use shape_retrieval::bof::Assignment;
    let mut rng = wfem_base::rng::SplitMix64::new(42);
    let (v, d, n) = (24, 3, 1100);
    let words = Mat::from_fn(v, d, |_, _| 4.0 * rng.next_f64());
    let x = Mat::from_fn(n, d, |_, _| 5.0 * rng.next_f64() - 0.5);
    let a: Vec<f64> = (0..n).map(|_| 0.5 + rng.next_f64()).collect();
    let sigma = 0.3;
    let voc = Vocabulary::new(words.clone(), sigma).unwrap();
    let d2 = |i: usize, c: usize| (0..d).map(|j| (x[(i, j)] - words[(c, j)]).powi(2)).sum::<f64>();
    let global_min = (0..n)
        .flat_map(|i| (0..v).map(move |c| (i, c)))
        .map(|(i, c)| d2(i, c))
        .fold(f64::INFINITY, f64::min);
    for assignment in [Assignment::Normalized, Assignment::Kernel] {
        let mut want = vec![0.0; v];
        for (i, &ai) in a.iter().enumerate() {
            let shift = match assignment {
                Assignment::Normalized => (0..v).map(|c| d2(i, c)).fold(f64::INFINITY, f64::min),
                Assignment::Kernel => global_min,
            };
            let w: Vec<f64> = (0..v)
                .map(|c| (-(d2(i, c) - shift) / (2.0 * sigma * sigma)).exp())
                .collect();
            let sum: f64 = match assignment {
                Assignment::Normalized => w.iter().sum(),
                Assignment::Kernel => 1.0,
            };
            for (acc, wc) in want.iter_mut().zip(&w) {
                *acc += wc / sum * ai;
            }
        }
        let total: f64 = want.iter().sum();
        let got = voc.bag_with(x.as_ref(), &a, assignment).unwrap();
        for c in 0..v {
            assert!(
                (got[c] - want[c]).abs() <= 1e-13 * total,
                "{assignment:?} word {c}: {} vs {}",
                got[c],
                want[c]
            );
        }
        let on = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| voc.bag_with(x.as_ref(), &a, assignment).unwrap())
        };
        assert_eq!(on(1), on(3));
    }
}
