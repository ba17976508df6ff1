//! Retrieval metrics against hand-computed values and a brute-force reference.

use faer::Mat;
use shape_retrieval::retrieval::{average_precision, evaluate, precision_recall, rank};
use shape_retrieval::RetrievalError;

#[test]
fn hand_computed_average_precision() {
    // Relevant at ranks 1 and 3 of 2 relevant: (1/1 + 2/3)/2.
    let ap = average_precision(&[true, false, true, false]).unwrap();
    assert!((ap - (1.0 + 2.0 / 3.0) / 2.0).abs() < 1e-15);
    // Ranks 2, 4, 5 of 3: (1/2 + 2/4 + 3/5)/3.
    let ap = average_precision(&[false, true, false, true, true]).unwrap();
    assert!((ap - (0.5 + 0.5 + 0.6) / 3.0).abs() < 1e-15);
    assert_eq!(average_precision(&[true, true, false]), Some(1.0));
    assert_eq!(average_precision(&[false, false]), None);
}

#[test]
fn rank_excludes_query_and_breaks_ties_by_index() {
    assert_eq!(rank(&[0.0, 3.0, 1.0, 1.0, 0.5], 0).unwrap(), vec![4, 2, 3, 1]);
    assert_eq!(rank(&[2.0, 0.0, 2.0], 1).unwrap(), vec![0, 2]);
    assert!(matches!(rank(&[1.0], 1), Err(RetrievalError::VertexOutOfRange { .. })));
    assert!(matches!(
        rank(&[1.0, f64::NAN], 0),
        Err(RetrievalError::NonFinite { index: 1, .. })
    ));
}

#[test]
fn hand_computed_map_on_small_matrix() {
    // Items 0,1 in class 7, item 2 in class 9, item 3 in class 7.
    let d = [
        [0.0, 1.0, 0.5, 3.0], // query 0: ranks 2,1,3 → rel [F,T,T] → (1/2 + 2/3)/2
        [1.0, 0.0, 2.0, 0.2], // query 1: ranks 3,0,2 → rel [T,T,F] → 1
        [0.5, 2.0, 0.0, 1.0], // query 2: class 9 alone → None
        [3.0, 0.2, 1.0, 0.0], // query 3: ranks 1,2,0 → rel [T,F,T] → (1 + 2/3)/2
    ];
    let m = Mat::from_fn(4, 4, |i, j| d[i][j]);
    let r = evaluate(m.as_ref(), &[7, 7, 9, 7]).unwrap();
    let ap0 = (0.5 + 2.0 / 3.0) / 2.0;
    let ap3 = (1.0 + 2.0 / 3.0) / 2.0;
    assert_eq!(r.average_precision[2], None);
    assert!((r.average_precision[0].unwrap() - ap0).abs() < 1e-15);
    assert_eq!(r.average_precision[1], Some(1.0));
    assert!((r.average_precision[3].unwrap() - ap3).abs() < 1e-15);
    assert!((r.mean_average_precision - (ap0 + 1.0 + ap3) / 3.0).abs() < 1e-15);
    assert_eq!(r.per_class.len(), 1);
    assert_eq!(r.per_class[0].label, 7);
    assert_eq!(r.per_class[0].n_queries, 3);
}

/// Deterministic pseudo-random numbers in [0, 1).
fn lcg(state: &mut u64) -> f64 {
    *state = state
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    (*state >> 11) as f64 / (1u64 << 53) as f64
}

#[test]
fn matches_brute_force_reference() {
    let mut s = 7u64;
    let m = 40;
    let labels: Vec<u32> = (0..m).map(|i| (i % 6) as u32).collect();
    // Distances correlated with the class, plus noise; distinct values so no ties.
    let d = Mat::from_fn(m, m, |i, j| {
        if i == j {
            0.0
        } else {
            let base = if labels[i] == labels[j] { 0.0 } else { 0.6 };
            base + lcg(&mut s)
        }
    });
    let r = evaluate(d.as_ref(), &labels).unwrap();
    let mut total = 0.0;
    for q in 0..m {
        // Brute force: for each other item j, its rank = 1 + #items closer than it.
        let others: Vec<usize> = (0..m).filter(|&j| j != q).collect();
        let rank_of = |j: usize| 1 + others.iter().filter(|&&o| d[(q, o)] < d[(q, j)]).count();
        let relevant: Vec<usize> = others.iter().copied().filter(|&j| labels[j] == labels[q]).collect();
        // P(k) at each relevant item's rank, counting relevant items ranked at or above it.
        let ap = relevant
            .iter()
            .map(|&j| {
                let k = rank_of(j);
                relevant.iter().filter(|&&o| rank_of(o) <= k).count() as f64 / k as f64
            })
            .sum::<f64>()
            / relevant.len() as f64;
        assert!((r.average_precision[q].unwrap() - ap).abs() < 1e-14, "query {q}");
        total += ap;
    }
    assert!((r.mean_average_precision - total / m as f64).abs() < 1e-14);
    // Per-class means agree with the per-query values.
    for c in &r.per_class {
        let aps: Vec<f64> = (0..m)
            .filter(|&q| labels[q] == c.label)
            .map(|q| r.average_precision[q].unwrap())
            .collect();
        assert!((c.mean_average_precision - aps.iter().sum::<f64>() / aps.len() as f64).abs() < 1e-14);
    }
    // Perfect separation gives mAP = 1.
    let perfect = Mat::from_fn(m, m, |i, j| if labels[i] == labels[j] { 0.1 } else { 1.0 });
    assert_eq!(evaluate(perfect.as_ref(), &labels).unwrap().mean_average_precision, 1.0);
}

#[test]
fn precision_recall_curve() {
    let pr = precision_recall(&[true, false, true, false]).unwrap();
    assert_eq!(pr.precision, vec![1.0, 0.5, 2.0 / 3.0, 0.5]);
    assert_eq!(pr.recall, vec![0.5, 0.5, 1.0, 1.0]);
    assert!(matches!(
        precision_recall(&[false]),
        Err(RetrievalError::NothingToAverage { .. })
    ));
}

#[test]
fn evaluate_errors() {
    let m = Mat::<f64>::zeros(3, 2);
    assert!(matches!(
        evaluate(m.as_ref(), &[0, 0, 0]),
        Err(RetrievalError::DimensionMismatch { .. })
    ));
    let m = Mat::<f64>::zeros(3, 3);
    assert!(matches!(
        evaluate(m.as_ref(), &[0, 0]),
        Err(RetrievalError::DimensionMismatch { .. })
    ));
    assert!(matches!(
        evaluate(m.as_ref(), &[0, 1, 2]),
        Err(RetrievalError::NothingToAverage { .. })
    ));
    let mut m = Mat::<f64>::zeros(2, 2);
    m[(0, 1)] = f64::NAN;
    assert!(matches!(
        evaluate(m.as_ref(), &[0, 0]),
        Err(RetrievalError::NonFinite { .. })
    ));
}
