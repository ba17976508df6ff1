//! Thick-restart block Lanczos ([`shifted_solve::eigen::largest_eigenpairs`]) on the shift-inverted
//! 1-D finite-element pair, whose generalized spectrum is known in closed form, so the reference
//! is independent of every eigensolver in the workspace.
//!
//! Linear elements on a uniform grid of N interior nodes, spacing h = 1/(N + 1), Dirichlet ends:
//! L = tridiag(−1, 2, −1)/h (stiffness), M = tridiag(1, 4, 1)·h/6 (consistent mass). The
//! eigenvectors are the sines sin(jπx) sampled at the nodes, with
//! `λ_j = (6/h²)(1 − cos θ_j)/(2 + cos θ_j)`, θ_j = jπh, j = 1…N (all simple).
use faer::sparse::{SparseColMat, Triplet};
use faer::{Mat, MatRef, Par};
use shifted_solve::eigen::{largest_eigenpairs, symmetric_block_mul, BlockLanczosParams, BlockLanczosReport};
use shifted_solve::{CholeskyPattern, SolveError};

fn fem_1d(nodes: usize) -> (SparseColMat<usize, f64>, SparseColMat<usize, f64>) {
    let h = 1.0 / (nodes + 1) as f64;
    let (mut lt, mut mt) = (Vec::new(), Vec::new());
    for i in 0..nodes {
        lt.push(Triplet::new(i, i, 2.0 / h));
        mt.push(Triplet::new(i, i, 4.0 * h / 6.0));
        if i + 1 < nodes {
            for (r, c) in [(i, i + 1), (i + 1, i)] {
                lt.push(Triplet::new(r, c, -1.0 / h));
                mt.push(Triplet::new(r, c, h / 6.0));
            }
        }
    }
    (
        SparseColMat::try_new_from_triplets(nodes, nodes, &lt).unwrap(),
        SparseColMat::try_new_from_triplets(nodes, nodes, &mt).unwrap(),
    )
}

/// The exact eigenvalues λ_1 < λ_2 < … of the 1-D pair.
fn fem_1d_spectrum(nodes: usize) -> Vec<f64> {
    let h = 1.0 / (nodes + 1) as f64;
    (1..=nodes)
        .map(|j| {
            let c = (j as f64 * std::f64::consts::PI * h).cos();
            6.0 / (h * h) * (1.0 - c) / (2.0 + c)
        })
        .collect()
}

/// The k smallest pairs of (L, M) through S = (L − σM)⁻¹M, as λ = σ + 1/θ, and the largest
/// relative residual `‖Sx − θx‖_M / θ` of the returned pairs, recomputed with fresh solves.
fn smallest(
    l: &SparseColMat<usize, f64>,
    m: &SparseColMat<usize, f64>,
    k: usize,
    sigma: f64,
    params: &BlockLanczosParams,
) -> Result<(Vec<f64>, BlockLanczosReport, f64), SolveError> {
    let n = l.nrows();
    let shifted = SparseColMat::try_new_from_triplets(
        n,
        n,
        &(0..n)
            .flat_map(|j| {
                let (lc, mc) = (l.as_ref(), m.as_ref());
                let rows_l = lc.symbolic().row_idx_of_col_raw(j).to_vec();
                let vals_l = lc.val_of_col(j).to_vec();
                let rows_m = mc.symbolic().row_idx_of_col_raw(j).to_vec();
                let vals_m = mc.val_of_col(j).to_vec();
                rows_l
                    .into_iter()
                    .zip(vals_l)
                    .map(move |(i, v)| Triplet::new(i, j, v))
                    .chain(
                        rows_m
                            .into_iter()
                            .zip(vals_m)
                            .map(move |(i, v)| Triplet::new(i, j, -sigma * v)),
                    )
            })
            .collect::<Vec<_>>(),
    )
    .unwrap();
    let factor = CholeskyPattern::new(shifted.symbolic())?.factor(shifted.as_ref(), Par::Seq)?;
    let apply = |_: MatRef<'_, f64>, mx: MatRef<'_, f64>| {
        let mut w = mx.to_owned();
        factor.solve_in_place(w.as_mut());
        Ok(w)
    };
    let mass = |x: MatRef<'_, f64>| symmetric_block_mul(m.as_ref(), x);
    let out = largest_eigenpairs(n, k, &apply, &mass, params)?;
    let sx = {
        let mut w = symmetric_block_mul(m.as_ref(), out.vectors.as_ref());
        factor.solve_in_place(w.as_mut());
        w
    };
    let worst = (0..out.values.len())
        .map(|c| {
            let theta = out.values[c];
            let r = Mat::<f64>::from_fn(n, 1, |i, _| sx[(i, c)] - theta * out.vectors[(i, c)]);
            let mr = symmetric_block_mul(m.as_ref(), r.as_ref());
            (0..n).map(|i| r[(i, 0)] * mr[(i, 0)]).sum::<f64>().sqrt() / theta
        })
        .fold(0.0, f64::max);
    Ok((out.values.iter().map(|&t| sigma + 1.0 / t).collect(), out, worst))
}

fn params(block_size: usize, max_basis: usize) -> BlockLanczosParams {
    BlockLanczosParams {
        block_size,
        tol: 1e-10,
        max_basis,
        max_restarts: 200,
        seed: 17,
    }
}

/// max |XᵀMX − I|.
fn orthonormality_error(x: &Mat<f64>, m: &SparseColMat<usize, f64>) -> f64 {
    let mx = symmetric_block_mul(m.as_ref(), x.as_ref());
    let g = x.transpose() * &mx;
    let mut worst = 0.0f64;
    for i in 0..g.nrows() {
        for j in 0..g.ncols() {
            let expect = if i == j { 1.0 } else { 0.0 };
            worst = worst.max((g[(i, j)] - expect).abs());
        }
    }
    worst
}

fn assert_matches_spectrum(tag: &str, lambda: &[f64], exact: &[f64]) {
    for (i, (&a, &e)) in lambda.iter().zip(exact).enumerate() {
        assert!((a - e).abs() <= 1e-10 * e, "{tag} λ_{i}: {a} vs exact {e}");
    }
}

/// Without restarts (the default-size basis) the k smallest pairs match the closed form, are
/// M-orthonormal and have small residuals in the original problem.
#[test]
fn smallest_pairs_match_the_closed_form() {
    let (l, m) = fem_1d(300);
    let exact = fem_1d_spectrum(300);
    let k = 20;
    let (lambda, out, res) = smallest(&l, &m, k, -1.0, &params(4, 2 * k + 8)).unwrap();
    assert!(out.converged());
    assert_eq!(lambda.len(), k);
    assert_matches_spectrum("fem_1d(300)", &lambda, &exact);
    assert!(orthonormality_error(&out.vectors, &m) < 1e-12);
    assert!(res < 2e-10, "{res}");
}

/// k large against the basis (k = 60, basis 80, block 4): many thick restarts with locking,
/// and still the exact spectrum, M-orthonormal vectors and small residuals.
#[test]
fn thick_restarts_with_locking_keep_accuracy() {
    let (l, m) = fem_1d(400);
    let exact = fem_1d_spectrum(400);
    let k = 60;
    let (lambda, out, res) = smallest(&l, &m, k, -1.0, &params(4, 80)).unwrap();
    assert!(out.converged(), "{} of {k}", out.values.len());
    assert!(out.restarts >= 3, "only {} restarts", out.restarts);
    assert_matches_spectrum("restarted", &lambda, &exact);
    assert!(out.max_residual <= 1e-10, "{}", out.max_residual);
    assert!(orthonormality_error(&out.vectors, &m) < 1e-11);
    assert!(res < 2e-10, "{res}");
}

/// The memory bound: the basis never holds more than `max_basis` columns (counted), whatever
/// the number of restarts, and a bound below k + 2b is raised to k + 2b.
#[test]
fn basis_never_exceeds_its_bound() {
    let (l, m) = fem_1d(500);
    for (k, b, bound) in [(10, 4, 40), (30, 6, 50), (40, 8, 20)] {
        let (_, out, _) = smallest(&l, &m, k, -1.0, &params(b, bound)).unwrap();
        let effective = bound.max(k + 2 * b);
        assert_eq!(out.basis_bound, effective, "k = {k}, b = {b}");
        assert!(
            out.basis_peak <= effective,
            "k = {k}, b = {b}: peak {} > bound {effective}",
            out.basis_peak
        );
        assert!(out.converged());
        // Every operator application is one block of b columns.
        assert_eq!(out.applications % b, 0);
    }
}

/// A bound within one block of n lets the basis span Rⁿ: exact pairs for every k ≤ n, also
/// when b does not divide n, without restarts.
#[test]
fn basis_reaching_n_gives_exact_pairs() {
    let (l, m) = fem_1d(23);
    let exact = fem_1d_spectrum(23);
    for k in [1, 5, 22, 23] {
        for b in [1, 3, 5] {
            let (lambda, out, _) = smallest(&l, &m, k, -1.0, &params(b, 23)).unwrap();
            assert_eq!(out.restarts, 0);
            assert_eq!(lambda.len(), k);
            assert_matches_spectrum(&format!("n = 23, k = {k}, b = {b}"), &lambda, &exact);
            assert!(orthonormality_error(&out.vectors, &m) < 1e-12);
        }
    }
}

/// Out of restarts, the converged pairs come back (fewer than asked), and they are right.
#[test]
fn no_restarts_left_returns_the_converged_pairs() {
    let (l, m) = fem_1d(400);
    let exact = fem_1d_spectrum(400);
    let mut p = params(4, 70);
    p.max_restarts = 1;
    let (lambda, out, res) = smallest(&l, &m, 60, -1.0, &p).unwrap();
    assert!(!out.converged());
    assert!(lambda.len() < 60);
    assert_eq!(out.restarts, 1);
    assert!(out.max_residual > 1e-10);
    assert_matches_spectrum("partial", &lambda, &exact);
    assert!(res < 2e-10, "{res}");
}

#[test]
fn invalid_parameters_are_typed_errors() {
    let (l, m) = fem_1d(10);
    for (k, p) in [
        (0, params(2, 10)),
        (11, params(2, 10)),
        (3, params(0, 10)),
        (
            3,
            BlockLanczosParams {
                tol: 0.0,
                ..params(2, 10)
            },
        ),
    ] {
        match smallest(&l, &m, k, -1.0, &p) {
            Err(SolveError::InvalidParameter { .. }) => {}
            other => panic!("k = {k}, {p:?}: {:?}", other.map(|o| o.0)),
        }
    }
}
