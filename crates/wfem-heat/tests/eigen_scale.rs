//! Scale invariance of the dense generalized eigendecomposition (paper, Eq. (4)–(6)) and the
//! exhausted-Krylov-space case of shift-invert block Lanczos.
//!
//! Scaling a mesh by α leaves L unchanged and multiplies M by α², so λ ← α⁻²λ exactly; the
//! dense oracle must reproduce that to rounding for any α.
mod common;
use common::*;
use mesh_fem::{assemble, generate, AssemblyParams, FemOperators, TriMesh};
use wfem_heat::{EigenParams, Eigenbasis, HeatError};

fn ops_raw(mesh: &TriMesh) -> FemOperators {
    assemble(mesh, &AssemblyParams::default()).expect("assembly")
}

fn assert_m_orthonormal(name: &str, e: &Eigenbasis, m: &faer::sparse::SparseColMat<usize, f64>, tol: f64) {
    let k = e.vectors.ncols();
    let cols: Vec<Vec<f64>> = (0..k).map(|c| e.vectors.col(c).iter().copied().collect()).collect();
    let mcols: Vec<Vec<f64>> = cols.iter().map(|x| matvec(m, x)).collect();
    for a in 0..k {
        for b in 0..k {
            let ip = dot(&cols[a], &mcols[b]);
            let expect = if a == b { 1.0 } else { 0.0 };
            assert!((ip - expect).abs() < tol, "{name}: <x{a}, x{b}>_M = {ip}");
        }
    }
}

/// λ(αΩ) = α⁻² λ(Ω) to 1e−10 relative (relative to λ₂ for the near-zero λ₁), λ₁ ≤
/// 1e−12 λ_max, and XᵀMX = I, for α from 1e−8 to 1e8.
#[test]
fn dense_eigenvalues_scale_as_alpha_minus_two() {
    for (name, mesh) in [
        ("icosphere2", generate::icosphere(2)),
        ("irregular_sphere2", generate::irregular_sphere(2, 5.6)),
    ] {
        let base_ops = ops_raw(&mesh);
        let base = Eigenbasis::dense(&base_ops.stiffness, &base_ops.mass).unwrap();
        let base_max = *base.values.last().unwrap();
        assert!(base.values[0].abs() <= 1e-12 * base_max, "{name}: λ₁ = {:e}", base.values[0]);
        for alpha in [1e-8, 1e-3, 2f64.powi(-10), 1.0, 1e3, 1e8] {
            let ops = ops_raw(&mesh.scaled(alpha).expect("scaled mesh"));
            let e = Eigenbasis::dense(&ops.stiffness, &ops.mass).unwrap();
            let lmax = *e.values.last().unwrap();
            assert!(e.values[0].abs() <= 1e-12 * lmax, "{name} α={alpha:e}: λ₁ = {:e} (λ_max {lmax:e})", e.values[0]);
            for (i, (&l, &l0)) in e.values.iter().zip(&base.values).enumerate() {
                let expect = l0 / (alpha * alpha);
                let err = (l - expect).abs() / expect.abs().max(base.values[1] / (alpha * alpha));
                assert!(err < 1e-10, "{name} α={alpha:e} λ_{i}: {l:e} vs {expect:e} ({err:e})");
            }
            assert_m_orthonormal(&format!("{name} α={alpha:e}"), &e, &ops.mass, 1e-10);
        }
    }
}
