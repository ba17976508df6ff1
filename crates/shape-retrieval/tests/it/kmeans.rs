//! k-means: recovery of separated clusters, determinism, Lloyd optimality, errors.

use faer::Mat;
use shape_retrieval::kmeans::{kmeans, KmeansParams};
use shape_retrieval::RetrievalError;

/// Points around `centers` with deterministic pseudo-random offsets of size ≤ `spread`.
fn blobs(centers: &[[f64; 3]], per: usize, spread: f64) -> (Mat<f64>, Vec<usize>) {
    let mut state = 12345u64;
    let mut next = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((state >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    };
    let n = centers.len() * per;
    let mut m = Mat::<f64>::zeros(n, 3);
    let mut labels = Vec::with_capacity(n);
    for i in 0..n {
        let c = i % centers.len();
        labels.push(c);
        for j in 0..3 {
            m[(i, j)] = centers[c][j] + spread * next();
        }
    }
    (m, labels)
}

#[test]
fn recovers_well_separated_clusters() {
    let centers = [
        [0.0, 0.0, 0.0],
        [10.0, 0.0, 0.0],
        [0.0, 10.0, 0.0],
        [0.0, 0.0, 10.0],
        [10.0, 10.0, 10.0],
    ];
    let (points, labels) = blobs(&centers, 40, 0.5);
    for seed in 0..5 {
        let report = kmeans(
            points.as_ref(),
            &KmeansParams {
                k: 5,
                seed,
                ..Default::default()
            },
        )
        .unwrap();
        assert!(report.converged);
        // Same partition: every true cluster maps to exactly one found cluster, and vice versa.
        let mut map = [u32::MAX; 5];
        for (i, &l) in labels.iter().enumerate() {
            if map[l] == u32::MAX {
                map[l] = report.assignment[i];
            }
            assert_eq!(map[l], report.assignment[i], "seed {seed}: cluster {l} split");
        }
        let mut found = map.to_vec();
        found.sort_unstable();
        found.dedup();
        assert_eq!(found.len(), 5, "seed {seed}: clusters merged");
        // Centres are the blob means, within the blob spread.
        for (l, c) in centers.iter().enumerate() {
            let m = map[l] as usize;
            let err: f64 = (0..3)
                .map(|j| (report.centers[(m, j)] - c[j]).powi(2))
                .sum::<f64>()
                .sqrt();
            assert!(err < 0.3, "seed {seed}: centre {l} off by {err}");
        }
    }
}

#[test]
fn deterministic_for_a_seed_and_lloyd_fixed_point() {
    let (points, _) = blobs(&[[0.0, 0.0, 0.0], [1.0, 1.0, 0.0], [3.0, 0.0, 1.0]], 50, 1.5);
    let params = KmeansParams {
        k: 7,
        seed: 42,
        ..Default::default()
    };
    let a = kmeans(points.as_ref(), &params).unwrap();
    let b = kmeans(points.as_ref(), &params).unwrap();
    assert_eq!(a.assignment, b.assignment);
    assert_eq!(a.centers, b.centers);
    assert!(a.converged);
    // At convergence every point is at its nearest centre and every centre is its points' mean.
    let n = points.nrows();
    let d2 = |i: usize, c: usize| {
        (0..3)
            .map(|j| (points[(i, j)] - a.centers[(c, j)]).powi(2))
            .sum::<f64>()
    };
    let mut inertia = 0.0;
    for i in 0..n {
        let own = d2(i, a.assignment[i] as usize);
        inertia += own;
        for c in 0..7 {
            assert!(own <= d2(i, c) + 1e-12);
        }
    }
    assert!((inertia - a.inertia).abs() < 1e-9 * inertia);
    for c in 0..7 {
        let members: Vec<usize> = (0..n).filter(|&i| a.assignment[i] as usize == c).collect();
        assert!(!members.is_empty());
        for j in 0..3 {
            let mean = members.iter().map(|&i| points[(i, j)]).sum::<f64>() / members.len() as f64;
            assert!((mean - a.centers[(c, j)]).abs() < 1e-12);
        }
    }
}

#[test]
fn duplicate_points_and_k_equal_n() {
    // Fewer distinct points than k: seeding must still terminate and every centre is a point.
    let points = Mat::from_fn(6, 2, |i, j| if i < 4 { 1.0 } else { (i + j) as f64 });
    let r = kmeans(
        points.as_ref(),
        &KmeansParams {
            k: 6,
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(r.assignment.len(), 6);
    assert!(r.inertia.abs() < 1e-12);
}

#[test]
fn errors() {
    let p = Mat::<f64>::zeros(3, 2);
    assert!(matches!(
        kmeans(
            p.as_ref(),
            &KmeansParams {
                k: 4,
                ..Default::default()
            }
        ),
        Err(RetrievalError::TooFewDescriptors { n_points: 3, k: 4 })
    ));
    assert!(matches!(
        kmeans(
            p.as_ref(),
            &KmeansParams {
                k: 0,
                ..Default::default()
            }
        ),
        Err(RetrievalError::InvalidParameter { name: "k", .. })
    ));
    assert!(matches!(
        kmeans(Mat::<f64>::zeros(0, 2).as_ref(), &KmeansParams::default()),
        Err(RetrievalError::Empty { .. })
    ));
    let mut q = Mat::<f64>::zeros(3, 2);
    q[(1, 1)] = f64::NAN;
    assert!(matches!(
        kmeans(
            q.as_ref(),
            &KmeansParams {
                k: 2,
                ..Default::default()
            }
        ),
        Err(RetrievalError::NonFinite { index: 3, .. })
    ));
}
