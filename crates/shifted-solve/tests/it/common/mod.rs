//! Shared helpers: random SPD/SPSD pairs, mesh pairs, dense references.
#![allow(dead_code)]

use faer::sparse::{SparseColMat, Triplet};
use faer::{c64, Mat, Side};

/// The workspace generator (deterministic, dependency-free).
pub use wfem_base::rng::SplitMix64 as Rng;

/// A random weighted graph Laplacian L (symmetric PSD, L·1 = 0, a ring plus random chords)
/// and a random SPD B (diagonally dominant, ring pattern) — different sparsity patterns.
pub fn random_pair(n: usize, seed: u64) -> (SparseColMat<usize, f64>, SparseColMat<usize, f64>) {
    let mut rng = Rng::new(seed);
    let mut lt = Vec::new();
    let add_edge = |i: usize, j: usize, w: f64, lt: &mut Vec<Triplet<usize, usize, f64>>| {
        lt.push(Triplet::new(i, j, -w));
        lt.push(Triplet::new(j, i, -w));
        lt.push(Triplet::new(i, i, w));
        lt.push(Triplet::new(j, j, w));
    };
    for i in 0..n {
        let w = 0.5 + 10.0 * rng.next_f64();
        add_edge(i, (i + 1) % n, w, &mut lt);
        let j = (rng.next_u64() % n as u64) as usize;
        if j != i {
            let w = 5.0 * rng.next_f64();
            add_edge(i, j, w, &mut lt);
        }
    }
    let l = SparseColMat::try_new_from_triplets(n, n, &lt).unwrap();
    let mut bt = Vec::new();
    for i in 0..n {
        let off = 0.1 * rng.next_f64();
        bt.push(Triplet::new(i, (i + 2) % n, off));
        bt.push(Triplet::new((i + 2) % n, i, off));
        bt.push(Triplet::new(i, i, 0.5 + rng.next_f64()));
    }
    let b = SparseColMat::try_new_from_triplets(n, n, &bt).unwrap();
    (l, b)
}

/// L and consistent B of an icosphere (shared pattern).
pub fn mesh_pair(level: u32) -> (SparseColMat<usize, f64>, SparseColMat<usize, f64>) {
    let mesh = mesh_fem::generate::icosphere(level);
    let ops = mesh_fem::assemble(&mesh, &mesh_fem::AssemblyParams::default()).unwrap();
    (ops.stiffness, ops.mass)
}

/// L and consistent B of an irregular "bumpy" sphere (shared pattern).
pub fn bumpy_pair(level: u32) -> (SparseColMat<usize, f64>, SparseColMat<usize, f64>) {
    let mesh = mesh_fem::generate::bumpy(level);
    let ops = mesh_fem::assemble(&mesh, &mesh_fem::AssemblyParams::default()).unwrap();
    (ops.stiffness, ops.mass)
}

pub fn dense(a: &SparseColMat<usize, f64>) -> Mat<f64> {
    a.to_dense()
}

/// Dense generalized eigendecomposition of (L, B): returns (λ, Φ) with Φᵀ B Φ = I, via
/// B = R Rᵀ and C = R⁻¹ L R⁻ᵀ (faer dense `self_adjoint_eigen`).
pub fn generalized_eigen(l: &SparseColMat<usize, f64>, b: &SparseColMat<usize, f64>) -> (Vec<f64>, Mat<f64>) {
    let (l, b) = (dense(l), dense(b));
    let n = l.nrows();
    let llt = b.llt(Side::Lower).unwrap();
    let r = llt.L().to_owned();
    // C = R⁻¹ L R⁻ᵀ
    let mut x = l.clone();
    faer::linalg::triangular_solve::solve_lower_triangular_in_place(r.as_ref(), x.as_mut(), faer::Par::Seq);
    let mut c = x.transpose().to_owned();
    faer::linalg::triangular_solve::solve_lower_triangular_in_place(r.as_ref(), c.as_mut(), faer::Par::Seq);
    let c = Mat::from_fn(n, n, |i, j| 0.5 * (c[(i, j)] + c[(j, i)]));
    let evd = c.self_adjoint_eigen(Side::Lower).unwrap();
    let lambda: Vec<f64> = (0..n).map(|i| evd.S()[i]).collect();
    // Φ = R⁻ᵀ Q
    let mut phi = evd.U().to_owned();
    faer::linalg::triangular_solve::solve_upper_triangular_in_place(r.transpose(), phi.as_mut(), faer::Par::Seq);
    (lambda, phi)
}

/// Φ g(Λ) Φᵀ B F.
pub fn spectral_apply(
    lambda: &[f64],
    phi: &Mat<f64>,
    b: &SparseColMat<usize, f64>,
    f: &Mat<f64>,
    g: impl Fn(f64) -> f64,
) -> Mat<f64> {
    let bf = dense(b) * f;
    let mut coef = phi.transpose() * &bf;
    for i in 0..coef.nrows() {
        let s = g(lambda[i]);
        for j in 0..coef.ncols() {
            coef[(i, j)] *= s;
        }
    }
    phi * &coef
}

/// Dense complex solve (tL − zB) X = G.
pub fn dense_shifted_solve(
    l: &SparseColMat<usize, f64>,
    b: &SparseColMat<usize, f64>,
    t: f64,
    z: c64,
    g: &Mat<f64>,
) -> Mat<c64> {
    let (l, b) = (dense(l), dense(b));
    let n = l.nrows();
    let a = Mat::<c64>::from_fn(n, n, |i, j| c64::new(t * l[(i, j)], 0.0) - z * b[(i, j)]);
    let rhs = Mat::<c64>::from_fn(n, g.ncols(), |i, j| c64::new(g[(i, j)], 0.0));
    use faer::linalg::solvers::Solve;
    a.partial_piv_lu().solve(&rhs)
}

pub fn random_rhs(n: usize, k: usize, seed: u64) -> Mat<f64> {
    let mut rng = Rng::new(seed);
    Mat::from_fn(n, k, |_, _| rng.next_f64() - 0.5)
}

/// max_ij |a − b| / max_ij |b|.
pub fn rel_err(a: &Mat<f64>, b: &Mat<f64>) -> f64 {
    let mut num: f64 = 0.0;
    let mut den: f64 = 0.0;
    for j in 0..a.ncols() {
        for i in 0..a.nrows() {
            num = num.max((a[(i, j)] - b[(i, j)]).abs());
            den = den.max(b[(i, j)].abs());
        }
    }
    num / den
}

/// A sparse matrix from dense rows (zeros dropped).
pub fn from_dense(rows: &[&[f64]]) -> SparseColMat<usize, f64> {
    let mut t = Vec::new();
    for (i, r) in rows.iter().enumerate() {
        for (j, &v) in r.iter().enumerate() {
            if v != 0.0 {
                t.push(Triplet::new(i, j, v));
            }
        }
    }
    SparseColMat::try_new_from_triplets(rows.len(), rows[0].len(), &t).unwrap()
}

/// The one-term "approximation" 1/(x − z) (+ its conjugate): solves a single shifted system.
pub fn single_pole(z: c64) -> shifted_solve::poles::RationalApprox {
    shifted_solve::poles::RationalApprox {
        degree: 2,
        c0: 0.0,
        poles: Box::leak(vec![z].into_boxed_slice()),
        residues: Box::leak(vec![c64::new(1.0, 0.0)].into_boxed_slice()),
        real_pole: None,
        max_error: 0.0,
    }
}
