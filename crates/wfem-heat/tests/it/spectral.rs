//! The spectral method (paper, Eq. (8)) and the shift-invert Lanczos eigensolver against the
//! dense generalized eigendecomposition (Eq. (4)–(6)).
use crate::common;
use common::*;
use mesh_fem::{generate, Mass};
use wfem_heat::method::Method;
use wfem_heat::spectral::{EigenParams, Eigenbasis};
use wfem_heat::{HeatKernel, HeatParams};

fn mass_of(ops: &mesh_fem::FemOperators, kind: Mass) -> faer::sparse::SparseColMat<usize, f64> {
    match kind {
        Mass::Consistent => ops.mass.clone(),
        Mass::Lumped(_) => ops.lumped_mass(),
        Mass::Identity => ops.identity_mass(),
    }
}

/// The k smallest eigenvalues of shift-invert Lanczos agree with the dense ones to 1e−10
/// relative (relative to max(λ, λ₂) so that λ₁ = 0 is compared absolutely), and the
/// eigenvectors are M-orthonormal.
#[test]
fn partial_eigenvalues_match_dense() {
    for (name, _, ops) in meshes() {
        for kind in [Mass::Consistent, Mass::Lumped(Default::default()), Mass::Identity] {
            let m = mass_of(&ops, kind);
            let dense = Eigenbasis::dense(&ops.stiffness, &m).unwrap();
            let k = 40;
            let part = Eigenbasis::partial(&ops.stiffness, &m, k, &EigenParams::default()).unwrap();
            assert_eq!(part.values.len(), k);
            let scale = dense.values[1];
            for i in 0..k {
                let err = (part.values[i] - dense.values[i]).abs() / dense.values[i].max(scale);
                assert!(
                    err < 1e-10,
                    "{name} {kind:?} λ_{i}: {} vs {} ({err:e})",
                    part.values[i],
                    dense.values[i]
                );
            }
            // XᵀMX = I.
            for a in [0, k / 2, k - 1] {
                for b in [0, k / 3, k - 1] {
                    let xa: Vec<f64> = part.vectors.col(a).iter().copied().collect();
                    let xb: Vec<f64> = part.vectors.col(b).iter().copied().collect();
                    let ip = dot(&xa, &matvec(&m, &xb));
                    let expect = if a == b { 1.0 } else { 0.0 };
                    assert!((ip - expect).abs() < 1e-10, "{name} {kind:?} <x{a}, x{b}>_M = {ip}");
                }
            }
        }
    }
}

/// With k = n (icosphere level 2, 162 vertices; block size 6 divides n, so the Krylov space
/// fills R^n) the spectral sum is the dense kernel of Eq. (6).
#[test]
fn spectral_with_all_pairs_equals_dense() {
    let (mesh, ops) = ops_of(&generate::icosphere(2));
    let n = ops.n();
    let eigen = EigenParams {
        block_size: 6,
        max_dim: Some(n),
        ..Default::default()
    };
    let spectral = HeatKernel::new(
        &ops,
        HeatParams {
            mass: Mass::Consistent,
            method: Method::Spectral { k: n, eigen },
        },
    )
    .unwrap();
    let dense = HeatKernel::new(
        &ops,
        HeatParams {
            mass: Mass::Consistent,
            method: Method::Dense,
        },
    )
    .unwrap();
    let f = x_coordinate(&mesh);
    for t in [1e-3, 1e-1, 1.0] {
        let err = rel_err(&spectral.apply(&f, t).unwrap(), &dense.apply(&f, t).unwrap());
        assert!(err < 1e-10, "t = {t}: {err:e}");
    }
}

/// Paper, Fig. 3: at fixed t the truncation error decreases with k, and since the
/// eigenvectors are B-orthonormal it obeys the exact bound
/// ‖F_k − K_t f‖_B ≤ e^{−tλ_{k+1}} ‖f‖_B (Eq. (6) minus Eq. (8)).
#[test]
fn spectral_error_decreases_with_k_and_obeys_tail_bound() {
    let (_, ops) = ops_of(&generate::irregular_sphere(3, 5.6));
    let n = ops.n();
    let dense = Eigenbasis::dense(&ops.stiffness, &ops.mass).unwrap();
    let f = unit(n, 100);
    let t = 0.01;
    let reference = dense.apply_heat(&ops.mass, &f, t).unwrap();
    let bnorm = |v: &[f64]| dot(v, &matvec(&ops.mass, v)).sqrt();
    let mut previous = f64::INFINITY;
    for k in [8, 32, 128, 320] {
        let part = Eigenbasis::partial(&ops.stiffness, &ops.mass, k, &EigenParams::default()).unwrap();
        let g = part.apply_heat(&ops.mass, &f, t).unwrap();
        let d: Vec<f64> = g.iter().zip(&reference).map(|(a, b)| a - b).collect();
        let err = bnorm(&d);
        let bound = (-t * dense.values[k]).exp() * bnorm(&f);
        println!("k = {k}: error {err:.3e}, bound {bound:.3e}");
        assert!(err < previous, "error did not decrease at k = {k}");
        assert!(
            err <= bound * (1.0 + 1e-8) + 1e-13,
            "k = {k}: {err:e} > bound {bound:e}"
        );
        previous = err;
    }
}

/// Eigenvalues on a real scanned-style mesh (Spot, 829 vertices) match the dense ones.
#[test]
fn partial_eigenvalues_on_real_mesh() {
    let Some((_, ops)) = spot() else { return };
    let dense = Eigenbasis::dense(&ops.stiffness, &ops.mass).unwrap();
    let part = Eigenbasis::partial(&ops.stiffness, &ops.mass, 30, &EigenParams::default()).unwrap();
    for i in 1..30 {
        let err = (part.values[i] - dense.values[i]).abs() / dense.values[i];
        assert!(err < 1e-10, "λ_{i}: {err:e}");
    }
}

/// The restarted path: k = 100 pairs with a basis of at most 130 vectors (several thick
/// restarts with locking) on an icosphere (multiplicities up to 5, block size 8) and an
/// irregular sphere, against the dense oracle to 1e−10 relative, with XᵀMX = I to 1e−10.
#[test]
fn partial_with_restarts_matches_dense() {
    for (name, mesh) in [
        ("icosphere3", generate::icosphere(3)),
        ("irregular_sphere3", generate::irregular_sphere(3, 5.6)),
    ] {
        let (_, ops) = ops_of(&mesh);
        let dense = Eigenbasis::dense(&ops.stiffness, &ops.mass).unwrap();
        let k = 100;
        let params = EigenParams {
            max_dim: Some(130),
            ..Default::default()
        };
        assert_eq!(params.basis_bound(k, ops.n()), 130);
        let part = Eigenbasis::partial(&ops.stiffness, &ops.mass, k, &params).unwrap();
        let scale = dense.values[1];
        for i in 0..k {
            let err = (part.values[i] - dense.values[i]).abs() / dense.values[i].max(scale);
            assert!(
                err < 1e-10,
                "{name} λ_{i}: {} vs {} ({err:e})",
                part.values[i],
                dense.values[i]
            );
        }
        let mx = ops.mass.as_ref() * part.vectors.as_ref();
        let g = part.vectors.transpose() * &mx;
        for a in 0..k {
            for b in 0..k {
                let expect = if a == b { 1.0 } else { 0.0 };
                assert!(
                    (g[(a, b)] - expect).abs() < 1e-10,
                    "{name}: <x{a}, x{b}>_M = {}",
                    g[(a, b)]
                );
            }
        }
    }
}
