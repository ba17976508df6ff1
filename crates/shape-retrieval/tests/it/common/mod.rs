//! Test helpers: a dense generalized eigendecomposition of (L, B) on small generated meshes,
//! the independent reference every descriptor test is checked against.
#![allow(dead_code)]

use faer::linalg::triangular_solve::{solve_lower_triangular_in_place, solve_upper_triangular_in_place};
use faer::{Mat, Par, Side};
use mesh_fem::{assemble, AssemblyParams, FemOperators, TriMesh};

/// A dense spectrum of (L, B): all n eigenpairs, `ΦᵀBΦ = I`, eigenvalues ascending.
pub struct DenseSpectrum {
    pub ops: FemOperators,
    pub eigenvalues: Vec<f64>,
    pub eigenvectors: Mat<f64>,
    pub stiffness: Mat<f64>,
    pub mass: Mat<f64>,
}

/// B = RRᵀ (Cholesky), C = R⁻¹ L R⁻ᵀ, C = UΛUᵀ, Φ = R⁻ᵀU.
pub fn dense_spectrum(mesh: &TriMesh) -> DenseSpectrum {
    let ops = assemble(mesh, &AssemblyParams::default()).expect("generated meshes assemble");
    let stiffness = ops.stiffness.to_dense();
    let mass = ops.mass.to_dense();
    let llt = mass.llt(Side::Lower).expect("B is SPD");
    let r = llt.L().to_owned();
    // Y = R⁻¹ L, then C = R⁻¹ Yᵀ = R⁻¹ L R⁻ᵀ (L symmetric).
    let mut y = stiffness.clone();
    solve_lower_triangular_in_place(r.as_ref(), y.as_mut(), Par::Seq);
    let mut c = y.transpose().to_owned();
    solve_lower_triangular_in_place(r.as_ref(), c.as_mut(), Par::Seq);
    // Symmetrize against round-off before the symmetric eigensolver.
    let c = Mat::from_fn(c.nrows(), c.ncols(), |i, j| 0.5 * (c[(i, j)] + c[(j, i)]));
    let evd = c.self_adjoint_eigen(Side::Lower).expect("symmetric eigendecomposition");
    let n = c.nrows();
    let eigenvalues: Vec<f64> = (0..n).map(|i| evd.S()[i]).collect();
    let mut eigenvectors = evd.U().to_owned();
    solve_upper_triangular_in_place(r.transpose(), eigenvectors.as_mut(), Par::Seq);
    DenseSpectrum {
        ops,
        eigenvalues,
        eigenvectors,
        stiffness,
        mass,
    }
}

/// Dense `Φ_k e^{−tΛ_k} Φ_kᵀ` (n × n) from the first k eigenpairs.
pub fn dense_kernel_matrix(s: &DenseSpectrum, k: usize, t: f64) -> Mat<f64> {
    let x = s.eigenvectors.subcols(0, k);
    let scaled = Mat::from_fn(x.nrows(), k, |i, c| x[(i, c)] * (-s.eigenvalues[c] * t).exp());
    &scaled * x.transpose()
}

/// Max absolute entry of a − b relative to max |b|.
pub fn rel_err(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    let scale = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    a.iter().zip(b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs())) / scale
}

/// Formats to `digits` significant digits (for snapshots).
pub fn sig(v: f64, digits: usize) -> String {
    format!("{:.*e}", digits - 1, v)
}

/// Four small, distinct closed shapes for retrieval tests: a bumpy sphere, a round sphere, a
/// torus and an ellipsoid (the sphere stretched 2.2 × 1 × 0.6), with their names.
pub fn small_collection() -> Vec<(String, TriMesh)> {
    use mesh_fem::generate::{bumpy, icosphere, torus};
    let sphere = icosphere(2);
    let ellipsoid = TriMesh::new(
        sphere
            .positions()
            .iter()
            .map(|p| [2.2 * p[0], p[1], 0.6 * p[2]])
            .collect(),
        sphere.faces().to_vec(),
    )
    .expect("a stretched sphere is a valid mesh");
    vec![
        ("bumpy".into(), bumpy(2)),
        ("sphere".into(), sphere),
        ("torus".into(), torus(1.0, 0.4, 24, 12)),
        ("ellipsoid".into(), ellipsoid),
    ]
}

/// Settings for fast tests: k = 30 eigenpairs, 6 words, otherwise the defaults.
pub fn small_settings() -> shape_retrieval::model::RetrievalSettings {
    let mut s = shape_retrieval::model::RetrievalSettings::default();
    s.descriptor.eigenpairs = 30;
    s.training.words = 6;
    s
}
