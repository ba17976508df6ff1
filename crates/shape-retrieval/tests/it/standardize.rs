//! z-scoring against a hand computation and its error paths.

use faer::Mat;
use shape_retrieval::standardize::Standardizer;
use shape_retrieval::RetrievalError;

#[test]
fn statistics_match_a_hand_computation() {
    // Column 0: 1, 2, 3, 6 → μ = 3, population variance (4 + 1 + 0 + 9)/4 = 3.5.
    // Column 1: 10, 10, 20, 20 → μ = 15, variance 25, s = 5.
    let rows = [[1.0, 10.0], [2.0, 10.0], [3.0, 20.0], [6.0, 20.0]];
    let x = Mat::from_fn(4, 2, |i, j| rows[i][j]);
    let z = Standardizer::fit(x.as_ref()).unwrap();
    assert_eq!(z.mean(), &[3.0, 15.0]);
    assert!((z.std()[0] - 3.5f64.sqrt()).abs() < 1e-15);
    assert_eq!(z.std()[1], 5.0);
    let y = z.apply(x.as_ref()).unwrap();
    assert!((y[(3, 0)] - 3.0 / 3.5f64.sqrt()).abs() < 1e-15);
    assert_eq!(y[(0, 1)], -1.0);
    // The standardised training set has zero mean and unit variance in every column.
    for j in 0..2 {
        let col: Vec<f64> = (0..4).map(|i| y[(i, j)]).collect();
        let m = col.iter().sum::<f64>() / 4.0;
        let v = col.iter().map(|c| (c - m) * (c - m)).sum::<f64>() / 4.0;
        assert!(m.abs() < 1e-15 && (v - 1.0).abs() < 1e-14, "column {j}: {m} {v}");
    }
}

#[test]
fn statistics_do_not_cancel_on_a_large_offset() {
    // Two-pass variance: values 1e9 + {0, 1, 2} keep s = √(2/3) to full precision (the one-pass
    // Σx² − nμ² formula loses every digit here).
    let x = Mat::from_fn(3, 1, |i, _| 1e9 + i as f64);
    let z = Standardizer::fit(x.as_ref()).unwrap();
    assert!((z.std()[0] - (2.0f64 / 3.0).sqrt()).abs() < 1e-9);
}

#[test]
fn bad_inputs_are_typed_errors() {
    let constant = Mat::from_fn(5, 2, |i, j| if j == 0 { i as f64 } else { 7.0 });
    assert!(matches!(
        Standardizer::fit(constant.as_ref()),
        Err(RetrievalError::ConstantDimension { dimension: 1, value }) if value == 7.0
    ));
    assert!(matches!(
        Standardizer::fit(Mat::<f64>::zeros(0, 3).as_ref()),
        Err(RetrievalError::Empty { .. })
    ));
    let nan = Mat::from_fn(3, 1, |i, _| if i == 1 { f64::NAN } else { 1.0 });
    assert!(matches!(
        Standardizer::fit(nan.as_ref()),
        Err(RetrievalError::NonFinite { index: 1, .. })
    ));
    let z = Standardizer::new(vec![0.0, 1.0], vec![1.0, 2.0]).unwrap();
    assert!(matches!(
        z.apply(Mat::<f64>::zeros(2, 3).as_ref()),
        Err(RetrievalError::DimensionMismatch { .. })
    ));
    assert!(matches!(
        Standardizer::new(vec![0.0], vec![0.0]),
        Err(RetrievalError::InvalidParameter { .. })
    ));
    assert!(matches!(
        Standardizer::new(vec![0.0, 1.0], vec![1.0]),
        Err(RetrievalError::DimensionMismatch { .. })
    ));
    // A result that overflows is refused rather than returned as ∞.
    let tiny = Standardizer::new(vec![0.0], vec![1e-300]).unwrap();
    assert!(matches!(
        tiny.apply(Mat::from_fn(1, 1, |_, _| 1e10).as_ref()),
        Err(RetrievalError::NonFinite { .. })
    ));
}
