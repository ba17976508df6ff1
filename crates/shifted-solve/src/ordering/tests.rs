use faer::sparse::linalg::cholesky::{factorize_symbolic_cholesky, CholeskySymbolicParams, SymmetricOrdering};
use faer::sparse::{SparseColMat, SymbolicSparseColMat, Triplet};
use wfem_base::rng::SplitMix64;

use super::*;
use crate::CholeskyPattern;

/// A 3-D grid large enough for nested dissection to be tried.
const GRID: usize = 32;

/// The full symmetric pattern (with diagonal) of an undirected edge list.
fn pattern_of(n: usize, edges: &[(usize, usize)]) -> SymbolicSparseColMat<usize> {
    let mut trip: Vec<Triplet<usize, usize, f64>> = (0..n).map(|i| Triplet::new(i, i, 1.0)).collect();
    for &(i, j) in edges {
        trip.push(Triplet::new(i, j, 1.0));
        trip.push(Triplet::new(j, i, 1.0));
    }
    SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &trip)
        .expect("pattern")
        .symbolic()
        .to_owned()
        .expect("alloc")
}

fn grid_edges(dims: &[usize]) -> (usize, Vec<(usize, usize)>) {
    let n: usize = dims.iter().product();
    let mut edges = Vec::new();
    for v in 0..n {
        let mut stride = 1;
        let mut rest = v;
        for &d in dims {
            if rest % d + 1 < d {
                edges.push((v, v + stride));
            }
            rest /= d;
            stride *= d;
        }
    }
    (n, edges)
}

/// The 7-point (or 5-point) Laplacian of a grid plus the identity: symmetric positive definite.
fn grid_matrix(dims: &[usize]) -> SparseColMat<usize, f64> {
    let (n, edges) = grid_edges(dims);
    let mut diag = vec![1.0; n];
    let mut trip = Vec::new();
    for &(i, j) in &edges {
        trip.push(Triplet::new(i, j, -1.0));
        trip.push(Triplet::new(j, i, -1.0));
        diag[i] += 1.0;
        diag[j] += 1.0;
    }
    trip.extend(diag.iter().enumerate().map(|(i, &d)| Triplet::new(i, i, d)));
    SparseColMat::try_new_from_triplets(n, n, &trip).expect("grid matrix")
}

fn assert_permutation(perm: &Permutation, n: usize) {
    assert_eq!(perm.fwd.len(), n);
    assert_eq!(perm.inv.len(), n);
    let mut seen = vec![false; n];
    for (k, &v) in perm.fwd.iter().enumerate() {
        assert!(v < n && !seen[v], "index {v} repeated or out of range");
        seen[v] = true;
        assert_eq!(perm.inv[v], k);
    }
}

fn nd(pattern: &SymbolicSparseColMat<usize>, leaf_size: usize) -> Permutation {
    let params = NdParams {
        leaf_size,
        ..NdParams::default()
    };
    nested_dissection(pattern.as_ref(), params).expect("square pattern")
}

fn amd_permutation(pattern: SymbolicSparseColMatRef<'_, usize>) -> Permutation {
    super::amd_permutation(pattern).expect("amd")
}

#[test]
fn nd_is_a_permutation_on_tiny_graphs() {
    for n in 0..6 {
        let edges: Vec<_> = (1..n).map(|i| (i - 1, i)).collect();
        let pattern = pattern_of(n, &edges);
        assert_permutation(&nd(&pattern, 1), n);
    }
}

#[test]
fn nd_is_a_permutation_on_a_path_and_grids() {
    let path: Vec<_> = (1..1000).map(|i| (i - 1, i)).collect();
    assert_permutation(&nd(&pattern_of(1000, &path), 8), 1000);
    for dims in [&[40, 30][..], &[12, 11, 10][..]] {
        let (n, edges) = grid_edges(dims);
        for leaf in [1, 16, 200] {
            assert_permutation(&nd(&pattern_of(n, &edges), leaf), n);
        }
    }
}

#[test]
fn nd_is_a_permutation_on_random_and_disconnected_graphs() {
    let mut rng = SplitMix64::new(39);
    for trial in 0..20 {
        let n = 1 + rng.next_below(3000);
        let m = rng.next_below(4 * n);
        // Some graphs sparse enough to fall apart into many components and isolated vertices.
        let m = if trial % 3 == 0 { m / 8 } else { m };
        let edges: Vec<_> = (0..m)
            .map(|_| (rng.next_below(n), rng.next_below(n)))
            .filter(|(i, j)| i != j)
            .collect();
        let pattern = pattern_of(n, &edges);
        assert_permutation(&nd(&pattern, 1 + rng.next_below(64)), n);
    }
    // Two grids side by side, never joined, plus isolated vertices.
    let (n, mut edges) = grid_edges(&[20, 20, 20]);
    edges.extend(grid_edges(&[20, 20, 20]).1.iter().map(|&(i, j)| (i + n, j + n)));
    assert_permutation(&nd(&pattern_of(2 * n + 7, &edges), 50), 2 * n + 7);
}

#[test]
fn separator_splits_a_3d_grid() {
    let (n, edges) = grid_edges(&[24, 24, 24]);
    let graph = Graph::from_pattern(pattern_of(n, &edges).as_ref());
    let side = separator::bisect(&graph, 0.6, 1).expect("a grid splits");
    let mut count = [0usize; 3];
    for &s in &side {
        count[s as usize] += 1;
    }
    for &(i, j) in &edges {
        assert!(side[i] + side[j] != 1, "edge {i}-{j} joins the two halves");
    }
    assert!(count[0].max(count[1]) <= (0.6 * n as f64) as usize, "{count:?}");
    assert!(count[0].min(count[1]) > 0);
    // A plane cut has 24² = 576 vertices; a level set of the BFS from a corner is a diagonal
    // section, at most 1.5 times larger.
    assert!(count[2] <= 900, "separator of {} vertices", count[2]);
}

#[test]
fn separator_check_can_fail() {
    // The check of the test above sees an edge across two halves if the separator is dropped.
    let (n, edges) = grid_edges(&[6, 6, 6]);
    let graph = Graph::from_pattern(pattern_of(n, &edges).as_ref());
    let side: Vec<u8> = separator::bisect(&graph, 0.6, 1)
        .expect("split")
        .iter()
        .map(|&s| s.min(1))
        .collect();
    assert!(edges.iter().any(|&(i, j)| side[i] + side[j] == 1));
}

#[test]
fn nd_gives_less_fill_than_amd_on_a_3d_grid_laplacian() {
    let a = grid_matrix(&[30, 30, 30]);
    let pattern = a.symbolic();
    let with_amd = fill_stats(pattern, &amd_permutation(pattern));
    let with_nd = fill_stats(
        pattern,
        &nd(&pattern.to_owned().expect("alloc"), NdParams::default().leaf_size),
    );
    assert!(
        with_nd.entries < with_amd.entries && with_nd.flops < with_amd.flops,
        "ND {with_nd:?} against AMD {with_amd:?}"
    );
}

#[test]
fn fill_stats_counts_a_tridiagonal_factor() {
    // A path in its natural order fills nothing: n diagonal entries and n − 1 below.
    let path: Vec<_> = (1..10).map(|i| (i - 1, i)).collect();
    let pattern = pattern_of(10, &path);
    let identity = Permutation::from_fwd((0..10).collect());
    let stats = fill_stats(pattern.as_ref(), &identity);
    assert_eq!(stats.entries, 19);
    assert_eq!(stats.flops, 9.0 * 4.0 + 1.0);
}

fn amd_symbolic(pattern: SymbolicSparseColMatRef<'_, usize>) -> SymbolicCholesky<usize> {
    factorize_symbolic_cholesky(
        pattern,
        faer::Side::Lower,
        SymmetricOrdering::Amd,
        CholeskySymbolicParams::default(),
    )
    .expect("symbolic")
}

#[test]
fn symbolic_stats_match_the_column_counts() {
    // Read from faer's supernodal structure or from our column counts: the same factor.
    let a = grid_matrix(&[16, 16, 16]);
    let symbolic = amd_symbolic(a.symbolic());
    let (fwd, inv) = symbolic.perm().expect("AMD permutes").arrays();
    let perm = Permutation {
        fwd: fwd.to_vec(),
        inv: inv.to_vec(),
    };
    let from_counts = fill_stats(a.symbolic(), &perm);
    let from_structure = symbolic_stats(&symbolic);
    assert!(from_structure.entries >= from_counts.entries);
    assert!(
        (from_structure.entries as f64) < 1.2 * from_counts.entries as f64,
        "{from_structure:?} {from_counts:?}"
    );
}

#[test]
fn choose_keeps_amd_below_the_thresholds_and_never_a_bigger_factor() {
    // Too small, and a surface-like 2-D grid: not tried.
    let small = grid_matrix(&[20, 20, 20]);
    let choice = choose(small.symbolic(), &amd_symbolic(small.symbolic()));
    assert_eq!((choice.chosen, choice.nd), (FillOrdering::Amd, None));
    let flat = grid_matrix(&[200, 200]);
    let choice = choose(flat.symbolic(), &amd_symbolic(flat.symbolic()));
    assert_eq!((choice.chosen, choice.nd), (FillOrdering::Amd, None));
    let big = grid_matrix(&[GRID, GRID, GRID]);
    let choice = choose_with(big.symbolic(), &amd_symbolic(big.symbolic()), 0.0);
    let (amd, nd) = (choice.amd, choice.nd.expect("tried"));
    let nd_wins = nd.flops < amd.flops && nd.entries <= amd.entries;
    assert_eq!(choice.chosen == FillOrdering::NestedDissection, nd_wins);
    assert_eq!(choice.permutation.is_some(), nd_wins);
    assert!(nd_wins, "ND {nd:?} against AMD {amd:?} on a {GRID}³ grid");
}

#[test]
fn factor_with_the_chosen_ordering_solves_to_1e_12() {
    // GRID³ ≥ ND_MIN_N: with the work threshold lowered, the analysis of factor.rs tries
    // nested dissection and keeps it, simplicial or supernodal.
    let a = grid_matrix(&[GRID, GRID, GRID]);
    let n = a.nrows();
    let supernodal = CholeskySymbolicParams {
        supernodal_flop_ratio_threshold: faer::sparse::linalg::SupernodalThreshold::FORCE_SUPERNODAL,
        ..Default::default()
    };
    for params in [CholeskySymbolicParams::default(), supernodal] {
        let (symbolic, ordering) = crate::factor::analyse_with(a.symbolic(), params, 0.0).expect("analysis");
        let pattern = CholeskyPattern::from_symbolic(symbolic, ordering);
        assert_eq!(pattern.ordering(), FillOrdering::NestedDissection);
        let factor = pattern.factor(a.as_ref(), faer::Par::Seq).expect("SPD");
        let b: Vec<f64> = (0..n).map(|i| ((i * 7919) % 101) as f64 - 50.0).collect();
        let x = factor.solve_vec(&b);
        // Independent check: multiply back with the matrix itself.
        let mut r = b.clone();
        for (j, &xj) in x.iter().enumerate() {
            for (&i, &v) in a.row_idx_of_col_raw(j).iter().zip(a.val_of_col(j)) {
                r[i] -= v * xj;
            }
        }
        let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
        let rel = norm(&r) / norm(&b);
        assert!(rel < 1e-12, "relative residual {rel:e}");
    }
}

/// Edges of a grid with its face and body diagonals too (the 27-point stencil): about 13
/// neighbours below each vertex, as dense as a tetrahedral pencil.
fn dense_grid_edges(m: usize) -> (usize, Vec<(usize, usize)>) {
    let id = |i: usize, j: usize, k: usize| (i * m + j) * m + k;
    let mut edges = Vec::new();
    for i in 0..m {
        for j in 0..m {
            for k in 0..m {
                for (di, dj, dk) in (0..27).map(|c| (c / 9, c / 3 % 3, c % 3)) {
                    let (a, b, c) = (i + di, j + dj, k + dk);
                    // Neighbours at +0/+1/+2 − 1 in each direction, each pair once.
                    if (di, dj, dk) <= (1, 1, 1) || a < 1 || b < 1 || c < 1 || a > m || b > m || c > m {
                        continue;
                    }
                    edges.push((id(i, j, k), id(a - 1, b - 1, c - 1)));
                }
            }
        }
    }
    (m * m * m, edges)
}

#[test]
fn the_side_by_side_choice_is_taken_by_large_dense_patterns_only() {
    // 76³ = 438,976 rows ≥ ND_EAGER_MIN_N: the 7-point stencil (4 entries per lower column) is
    // not dense enough, the 27-point one (14) is; a smaller dense one is not large enough.
    let sparse = grid_matrix(&[76, 76, 76]);
    assert!(!eager(sparse.symbolic()));
    let (n, edges) = dense_grid_edges(76);
    assert!(n >= ND_EAGER_MIN_N);
    assert!(eager(pattern_of(n, &edges).as_ref()));
    let (n, edges) = dense_grid_edges(40);
    assert!(!eager(pattern_of(n, &edges).as_ref()));
}

#[test]
fn the_side_by_side_choice_keeps_the_better_ordering_and_solves() {
    // choose_eager on a GRID³ grid: ND kept when AMD is dense enough (threshold 0) and its
    // factor is smaller, AMD with a huge threshold; either way a valid permutation, and
    // factor.rs solves with it to 1e-12.
    let a = grid_matrix(&[GRID, GRID, GRID]);
    let n = a.nrows();
    let nd = choose_eager(a.symbolic(), 0.0).expect("AMD");
    assert_eq!(nd.chosen, FillOrdering::NestedDissection, "{:?} / {:?}", nd.amd, nd.nd);
    assert_permutation(nd.permutation.as_ref().expect("kept"), n);
    let amd = choose_eager(a.symbolic(), f64::INFINITY).expect("AMD");
    assert_eq!(amd.chosen, FillOrdering::Amd);
    let amd_perm = amd.permutation.expect("kept");
    assert_permutation(&amd_perm, n);
    assert_eq!(
        amd_perm.fwd,
        amd_permutation(a.symbolic()).fwd,
        "faer's AMD permutation"
    );
    for choice in [
        nd,
        OrderingChoice {
            permutation: Some(amd_perm),
            ..amd
        },
    ] {
        let perm = choice.permutation.expect("kept");
        let perm = faer::perm::PermRef::new_checked(&perm.fwd, &perm.inv, n);
        let symbolic = factorize_symbolic_cholesky(
            a.symbolic(),
            faer::Side::Lower,
            SymmetricOrdering::Custom(perm),
            CholeskySymbolicParams::default(),
        )
        .expect("symbolic");
        let pattern = CholeskyPattern::from_symbolic(std::sync::Arc::new(symbolic), choice.chosen);
        let factor = pattern.factor(a.as_ref(), faer::Par::Seq).expect("numeric");
        let x: Vec<f64> = (0..n).map(|i| ((i * 7919) % 101) as f64 / 101.0 - 0.5).collect();
        let mut b = vec![0.0; n];
        for (j, &xj) in x.iter().enumerate() {
            for (&i, &v) in a.row_idx_of_col_raw(j).iter().zip(a.val_of_col(j)) {
                b[i] += v * xj;
            }
        }
        let mut y = faer::Mat::from_fn(n, 1, |i, _| b[i]);
        factor.solve_in_place(y.as_mut());
        let err = (0..n).map(|i| (y[(i, 0)] - x[i]).abs()).fold(0.0, f64::max);
        assert!(err < 1e-12, "{:?}: {err:e}", choice.chosen);
    }
}
