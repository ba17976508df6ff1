//! L1 and χ² bag distances against hand computations.

use shape_retrieval::distance::{chi_squared_distance, l1_distance, pairwise_distances, BagDistance};
use shape_retrieval::RetrievalError;
use wfem_base::Choice;

#[test]
fn chi_squared_matches_a_hand_computation() {
    // a = (0.5, 0.5, 0), b = (0.25, 0.25, 0.5):
    // ½[(0.25)²/0.75 + (0.25)²/0.75 + (0.5)²/0.5] = ½[1/12 + 1/12 + 1/2] = 1/3.
    let (a, b) = ([0.5, 0.5, 0.0], [0.25, 0.25, 0.5]);
    assert!((chi_squared_distance(&a, &b).unwrap() - 1.0 / 3.0).abs() < 1e-15);
    assert_eq!(l1_distance(&a, &b).unwrap(), 1.0);
    // Symmetric, zero on equal histograms, 1 (resp. 2 for L1) on disjoint ones; empty bins skipped.
    assert_eq!(
        chi_squared_distance(&b, &a).unwrap(),
        chi_squared_distance(&a, &b).unwrap()
    );
    assert_eq!(chi_squared_distance(&a, &a).unwrap(), 0.0);
    assert_eq!(chi_squared_distance(&[1.0, 0.0], &[0.0, 1.0]).unwrap(), 1.0);
    assert_eq!(l1_distance(&[1.0, 0.0], &[0.0, 1.0]).unwrap(), 2.0);
    assert_eq!(chi_squared_distance(&[0.0, 0.0], &[0.0, 0.0]).unwrap(), 0.0);
}

#[test]
fn pairwise_matches_the_pair_formula() {
    let bags = vec![vec![0.5, 0.5, 0.0], vec![0.25, 0.25, 0.5], vec![0.0, 0.1, 0.9]];
    for d in BagDistance::ALL {
        let m = pairwise_distances(&bags, d).unwrap();
        for i in 0..3 {
            for j in 0..3 {
                assert_eq!(m[(i, j)], d.between(&bags[i], &bags[j]).unwrap(), "{}", d.name());
            }
        }
    }
}

#[test]
fn bad_bags_are_typed_errors() {
    assert!(matches!(
        chi_squared_distance(&[0.5, -0.1], &[0.5, 0.5]),
        Err(RetrievalError::NegativeBin { index: 1, .. })
    ));
    assert!(matches!(
        chi_squared_distance(&[0.5], &[0.5, 0.5]),
        Err(RetrievalError::DimensionMismatch { .. })
    ));
    assert!(matches!(
        l1_distance(&[f64::INFINITY], &[0.5]),
        Err(RetrievalError::NonFinite { .. })
    ));
    assert!(matches!(
        pairwise_distances(&[], BagDistance::L1),
        Err(RetrievalError::Empty { .. })
    ));
    assert!(matches!(
        pairwise_distances(&[vec![1.0], vec![1.0, 0.0]], BagDistance::ChiSquared),
        Err(RetrievalError::DimensionMismatch { .. })
    ));
}
