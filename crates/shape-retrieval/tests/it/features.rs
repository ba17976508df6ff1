//! Repeatability with Dijkstra geodesics on the mesh graph, and descriptor robustness.

use crate::common;

use common::{dense_spectrum, sig};
use faer::Mat;
use mesh_fem::generate::{bumpy, icosphere};
use mesh_fem::TriMesh;
use shape_retrieval::features::{descriptor_distance, repeatability, FeatureSet};
use shape_retrieval::hks::{heat_kernel_signature, HksParams, Spectrum, SpectrumNormalization};
use shape_retrieval::RetrievalError;
use std::cmp::Reverse;
use std::collections::BinaryHeap;
use wfem_heat::KernelDiagonal;

/// Single-source Dijkstra on the edge graph of the mesh (edge length = Euclidean length).
fn dijkstra(mesh: &TriMesh, source: u32) -> Vec<f64> {
    let n = mesh.n_vertices();
    let p = mesh.positions();
    let mut adj: Vec<Vec<(usize, f64)>> = vec![Vec::new(); n];
    for f in mesh.faces() {
        for k in 0..3 {
            let (a, b) = (f[k] as usize, f[(k + 1) % 3] as usize);
            let len = ((0..3).map(|j| (p[a][j] - p[b][j]).powi(2)).sum::<f64>()).sqrt();
            adj[a].push((b, len));
            adj[b].push((a, len));
        }
    }
    let mut dist = vec![f64::INFINITY; n];
    let mut heap = BinaryHeap::new();
    dist[source as usize] = 0.0;
    // Distances are non-negative, so their bit patterns order like the values.
    heap.push(Reverse((0u64, source as usize)));
    while let Some(Reverse((bits, u))) = heap.pop() {
        let d = f64::from_bits(bits);
        if d > dist[u] {
            continue;
        }
        for &(v, w) in &adj[u] {
            let nd = d + w;
            if nd < dist[v] {
                dist[v] = nd;
                heap.push(Reverse((nd.to_bits(), v)));
            }
        }
    }
    dist
}

fn all_pairs(mesh: &TriMesh) -> Mat<f64> {
    let n = mesh.n_vertices();
    let rows: Vec<Vec<f64>> = (0..n as u32).map(|s| dijkstra(mesh, s)).collect();
    Mat::from_fn(n, n, |i, j| rows[i][j])
}

/// Brute-force rep(A, B): features of A whose image has a feature of B within r.
fn brute_rep(fa: &[u32], corr_a: &[Option<u32>], fb: &[u32], d_b: &Mat<f64>, r: f64) -> f64 {
    let with_gt: Vec<u32> = fa.iter().filter_map(|&f| corr_a[f as usize]).collect();
    let hits = with_gt
        .iter()
        .filter(|&&img| fb.iter().any(|&g| d_b[(img as usize, g as usize)] <= r))
        .count();
    hits as f64 / with_gt.len() as f64
}

#[test]
fn repeatability_hand_cases_on_identity_correspondence() {
    let mesh = icosphere(2);
    let n = mesh.n_vertices();
    let d = all_pairs(&mesh);
    let identity: Vec<Option<u32>> = (0..n as u32).map(Some).collect();
    let fx = [0u32, 10, 20];
    let fy = [0u32, 11, 50];
    let x = FeatureSet {
        features: &fx,
        n_vertices: n,
        correspondence: &identity,
    };
    let y = FeatureSet {
        features: &fy,
        n_vertices: n,
        correspondence: &identity,
    };
    let oracle = d.as_ref();
    // R = 0: only the shared vertex 0 repeats (unless 10/11 or 20/50 coincide, which they don't).
    let r0 = repeatability(x, y, 0.0, &oracle, &oracle).unwrap();
    assert_eq!((r0.y_in_x, r0.x_in_y, r0.overall), (1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0));
    // R ≥ the graph diameter: everything repeats.
    let big = repeatability(x, y, 10.0, &oracle, &oracle).unwrap();
    assert_eq!(big.overall, 1.0);
    // Identical feature sets repeat fully at any radius.
    let same = repeatability(x, x, 0.0, &oracle, &oracle).unwrap();
    assert_eq!(same.overall, 1.0);
}

#[test]
fn repeatability_matches_brute_force_with_missing_ground_truth() {
    let mesh_x = icosphere(2);
    let mesh_y = bumpy(2);
    let n = mesh_x.n_vertices();
    let (dx, dy) = (all_pairs(&mesh_x), all_pairs(&mesh_y));
    // Ground truth: identity, except vertices 100..120 of Y and 30..40 of X have none (holes).
    let corr_y: Vec<Option<u32>> = (0..n as u32).map(|i| (!(100..120).contains(&i)).then_some(i)).collect();
    let corr_x: Vec<Option<u32>> = (0..n as u32).map(|i| (!(30..40).contains(&i)).then_some(i)).collect();
    let fx: Vec<u32> = (0..n as u32).step_by(7).collect();
    let fy: Vec<u32> = (3..n as u32).step_by(11).collect();
    let x = FeatureSet {
        features: &fx,
        n_vertices: n,
        correspondence: &corr_x,
    };
    let y = FeatureSet {
        features: &fy,
        n_vertices: n,
        correspondence: &corr_y,
    };
    for r in [0.05, 0.15, 0.3, 0.6] {
        // Closures computing Dijkstra on demand and precomputed matrices must agree.
        let ox = |a: u32, b: u32| dijkstra(&mesh_x, a)[b as usize];
        let oy = |a: u32, b: u32| dijkstra(&mesh_y, a)[b as usize];
        let rep = repeatability(x, y, r, &ox, &oy).unwrap();
        let rep_mat = repeatability(x, y, r, &dx.as_ref(), &dy.as_ref()).unwrap();
        assert_eq!(rep, rep_mat);
        let want_y = brute_rep(&fy, &corr_y, &fx, &dx, r);
        let want_x = brute_rep(&fx, &corr_x, &fy, &dy, r);
        assert_eq!(rep.y_in_x, want_y, "r = {r}");
        assert_eq!(rep.x_in_y, want_x, "r = {r}");
        assert_eq!(
            rep.y_with_ground_truth,
            fy.iter().filter(|&&f| corr_y[f as usize].is_some()).count()
        );
        assert!(
            rep.y_with_ground_truth < fy.len(),
            "the test should exercise missing ground truth"
        );
        assert!((rep.overall - 0.5 * (want_x + want_y)).abs() < 1e-15);
    }
}

#[test]
fn repeatability_errors() {
    let n = 4;
    let id: Vec<Option<u32>> = (0..n as u32).map(Some).collect();
    let none: Vec<Option<u32>> = vec![None; n];
    let f = [0u32, 1];
    let zero = |_: u32, _: u32| 0.0;
    let ok = FeatureSet {
        features: &f,
        n_vertices: n,
        correspondence: &id,
    };
    let bad_r = repeatability(ok, ok, -1.0, &zero, &zero);
    assert!(matches!(
        bad_r,
        Err(RetrievalError::InvalidParameter { name: "radius", .. })
    ));
    let out = FeatureSet {
        features: &[9],
        n_vertices: n,
        correspondence: &id,
    };
    assert!(matches!(
        repeatability(out, ok, 1.0, &zero, &zero),
        Err(RetrievalError::VertexOutOfRange { index: 9, .. })
    ));
    let short = FeatureSet {
        features: &f,
        n_vertices: n,
        correspondence: &id[..2],
    };
    assert!(matches!(
        repeatability(short, ok, 1.0, &zero, &zero),
        Err(RetrievalError::DimensionMismatch { .. })
    ));
    let no_gt = FeatureSet {
        features: &f,
        n_vertices: n,
        correspondence: &none,
    };
    assert!(matches!(
        repeatability(ok, no_gt, 1.0, &zero, &zero),
        Err(RetrievalError::NothingToAverage { .. })
    ));
    let nan = |_: u32, _: u32| f64::NAN;
    assert!(matches!(
        repeatability(ok, ok, 1.0, &nan, &zero),
        Err(RetrievalError::InvalidDistance { .. })
    ));
}

#[test]
fn descriptor_distance_hand_cases() {
    let fx = Mat::from_fn(3, 2, |i, j| [[3.0, 4.0], [1.0, 0.0], [0.0, 2.0]][i][j]);
    let fy = Mat::from_fn(3, 2, |i, j| [[3.0, 4.0], [1.1, 0.0], [0.0, 0.0]][i][j]);
    // Pairs: (0,0) → 0; (1,1) → 0.1/1; (0,1) → ‖(3,4) − (1.1,0)‖/5 = √(1.9² + 4²)/5.
    let d = descriptor_distance(fx.as_ref(), fy.as_ref(), &[(0, 0), (1, 1), (0, 1)]).unwrap();
    let want = (0.0 + 0.1 + (1.9f64 * 1.9 + 16.0).sqrt() / 5.0) / 3.0;
    assert!((d - want).abs() < 1e-14, "{d} vs {want}");
    assert!(matches!(
        descriptor_distance(fy.as_ref(), fx.as_ref(), &[(2, 2)]),
        Err(RetrievalError::ZeroDescriptor { vertex: 2 })
    ));
    assert!(matches!(
        descriptor_distance(fx.as_ref(), fy.as_ref(), &[]),
        Err(RetrievalError::Empty { .. })
    ));
    assert!(matches!(
        descriptor_distance(fx.as_ref(), fy.as_ref(), &[(0, 5)]),
        Err(RetrievalError::VertexOutOfRange { index: 5, .. })
    ));
    let f3 = Mat::<f64>::zeros(3, 3);
    assert!(matches!(
        descriptor_distance(fx.as_ref(), f3.as_ref(), &[(0, 0)]),
        Err(RetrievalError::DimensionMismatch { .. })
    ));
}

/// bumpy(2) with every vertex moved by a deterministic pseudo-random offset of size ≤ `amp`.
fn jittered(mesh: &TriMesh, amp: f64) -> TriMesh {
    let mut state = 99u64;
    let mut next = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((state >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    };
    let positions = mesh
        .positions()
        .iter()
        .map(|p| [p[0] + amp * next(), p[1] + amp * next(), p[2] + amp * next()])
        .collect();
    TriMesh::new(positions, mesh.faces().to_vec()).unwrap()
}

fn dense_hks(mesh: &TriMesh, params: &HksParams) -> Mat<f64> {
    let s = dense_spectrum(mesh);
    let k = 60;
    let spectrum = Spectrum::new(&s.eigenvalues[..k], s.eigenvectors.subcols(0, k))
        .unwrap()
        .with_mass(s.ops.mass.as_ref())
        .unwrap();
    heat_kernel_signature(&spectrum, params).unwrap().values
}

#[test]
fn hks_robustness_scale_and_noise() {
    let x = bumpy(2);
    let pairs: Vec<(u32, u32)> = (0..x.n_vertices() as u32).map(|i| (i, i)).collect();
    let dhk3 = HksParams {
        convention: KernelDiagonal::OperatorDiagonal,
        normalization: SpectrumNormalization::MaxEigenvalue,
        times: shape_retrieval::hks::TimeSampling::Explicit(vec![0.002, 0.005, 0.01, 0.02, 0.05, 0.1]),
        ..Default::default()
    };
    let plain = HksParams {
        normalization: SpectrumNormalization::None,
        ..dhk3.clone()
    };
    let fx = dense_hks(&x, &dhk3);
    // Global scale: the max-eigenvalue normalization removes it exactly.
    let scaled = dense_hks(&x.scaled(2.5).unwrap(), &dhk3);
    let d_scale = descriptor_distance(fx.as_ref(), scaled.as_ref(), &pairs).unwrap();
    assert!(d_scale < 1e-10, "{d_scale}");
    let d_plain = descriptor_distance(
        dense_hks(&x, &plain).as_ref(),
        dense_hks(&x.scaled(2.5).unwrap(), &plain).as_ref(),
        &pairs,
    )
    .unwrap();
    assert!(d_plain > 0.1, "{d_plain}");
    // Noise: the distance grows with the noise amplitude.
    let mut out = String::new();
    let mut last = 0.0;
    for amp in [0.002, 0.01, 0.03] {
        let d = descriptor_distance(fx.as_ref(), dense_hks(&jittered(&x, amp), &dhk3).as_ref(), &pairs).unwrap();
        assert!(d > last, "amp {amp}: {d} ≤ {last}");
        last = d;
        out += &format!("noise {amp}: {}\n", sig(d, 4));
    }
    out += &format!("scale 2.5 without normalization: {}\n", sig(d_plain, 4));
    insta::assert_snapshot!("hks_robustness_bumpy2", out);
}

#[test]
fn local_maxima_of_height_and_brute_force() {
    let mesh = icosphere(2);
    let n = mesh.n_vertices();
    // The height z has one maximum on the sphere: the topmost vertex.
    let z: Vec<f64> = mesh.positions().iter().map(|p| p[2]).collect();
    let top = (0..n).max_by(|&a, &b| z[a].total_cmp(&z[b])).unwrap() as u32;
    assert_eq!(
        shape_retrieval::features::local_maxima(mesh.faces(), &z, 1).unwrap(),
        vec![top]
    );
    // Pseudo-random values: compare with a brute-force k-ring from all-pairs hop distances.
    let mut state = 5u64;
    let values: Vec<f64> = (0..n)
        .map(|_| {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 40) as f64
        })
        .collect();
    let hops = all_pairs_hops(&mesh);
    for rings in [1, 2, 3] {
        let got = shape_retrieval::features::local_maxima(mesh.faces(), &values, rings).unwrap();
        let want: Vec<u32> = (0..n)
            .filter(|&v| {
                (0..n)
                    .all(|u| u == v || hops[v][u] > rings || values[v] > values[u] || (values[v] == values[u] && v > u))
            })
            .map(|v| v as u32)
            .collect();
        assert_eq!(got, want, "rings = {rings}");
        assert!(!got.is_empty());
    }
    // A constant function: ties go to the higher index, so the last vertex is a maximum and none
    // of its neighbours is.
    let flat = vec![1.0; n];
    let flat_max = shape_retrieval::features::local_maxima(mesh.faces(), &flat, 1).unwrap();
    let last = n - 1;
    assert!(flat_max.contains(&(last as u32)));
    assert!(flat_max
        .iter()
        .all(|&v| v as usize == last || hops[last][v as usize] > 1));
    assert!(matches!(
        shape_retrieval::features::local_maxima(mesh.faces(), &flat, 0),
        Err(RetrievalError::InvalidParameter { .. })
    ));
    assert!(matches!(
        shape_retrieval::features::local_maxima(&[[0, 1, 99]], &[1.0, 2.0], 1),
        Err(RetrievalError::VertexOutOfRange { index: 99, .. })
    ));
}

/// Hop (edge-count) distances between all vertex pairs, by BFS.
fn all_pairs_hops(mesh: &TriMesh) -> Vec<Vec<usize>> {
    let n = mesh.n_vertices();
    let mut adj = vec![Vec::new(); n];
    for f in mesh.faces() {
        for k in 0..3 {
            adj[f[k] as usize].push(f[(k + 1) % 3] as usize);
            adj[f[(k + 1) % 3] as usize].push(f[k] as usize);
        }
    }
    (0..n)
        .map(|s| {
            let mut d = vec![usize::MAX; n];
            d[s] = 0;
            let mut queue = std::collections::VecDeque::from([s]);
            while let Some(u) = queue.pop_front() {
                for &w in &adj[u] {
                    if d[w] == usize::MAX {
                        d[w] = d[u] + 1;
                        queue.push_back(w);
                    }
                }
            }
            d
        })
        .collect()
}
