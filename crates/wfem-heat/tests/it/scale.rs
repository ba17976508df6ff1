//! Scale covariance and scale invariance of the wFEM heat kernel (paper, Sect. 5) and the
//! largest eigenvalue λ_n against the dense generalized eigendecomposition.
use crate::common;
use common::*;
use mesh_fem::{assemble, generate, AssemblyParams, Mass};
use wfem_heat::method::Method;
use wfem_heat::scale::{largest_eigenvalue, LargestEigenParams, Normalization, NormalizedHeatKernel};
use wfem_heat::spectral::Eigenbasis;
use wfem_heat::{HeatError, HeatKernel, HeatParams, Operators};

fn mass_of(ops: &mesh_fem::FemOperators, kind: Mass) -> faer::sparse::SparseColMat<usize, f64> {
    match kind {
        Mass::Consistent => ops.mass.clone(),
        Mass::Lumped(_) => ops.lumped_mass(),
        Mass::Identity => ops.identity_mass(),
    }
}

/// K_t(αM) = K_{α⁻²t}(M) without any normalisation, α = 1e−3, 1, 1e3, for the rational
/// method, to 1e−10 relative; the dense reference for α = 1, 1e3 (at α = 1e−3 the dense
/// generalized eigendecomposition itself loses accuracy: measured λ₁ = 5e−3 instead of 0 and
/// eigenvalues off by 1.8e−6 relative, although L and α⁻²M agree to 2e−15, so K_t differs by
/// 6e−5 there; the rational method has no such problem).
#[test]
fn scale_covariance_without_normalisation() {
    let (mesh, ops) = ops_of(&generate::irregular_sphere(3, 5.6));
    let n = mesh.n_vertices();
    let f: Vec<f64> = (0..n).map(|i| ((i * 7919) % 101) as f64 / 101.0 - 0.5).collect();
    let e = unit(n, 17);
    for method in [Method::rational(shifted_solve::poles::DEFAULT_DEGREE), Method::Dense] {
        let params = HeatParams {
            mass: Mass::Consistent,
            method: method.clone(),
        };
        let base = HeatKernel::new(&ops, params.clone()).unwrap();
        let alphas: &[f64] = if method == Method::Dense {
            &[1.0, 1e3]
        } else {
            &[1e-3, 1.0, 1e3]
        };
        for &alpha in alphas {
            let scaled_ops = assemble(&mesh.scaled(alpha).unwrap(), &AssemblyParams::default()).unwrap();
            let scaled = HeatKernel::new(&scaled_ops, params.clone()).unwrap();
            for t0 in [1e-3, 0.1] {
                let t = alpha * alpha * t0; // time on αM
                for v in [&f, &e] {
                    let a = scaled.apply(v, t).unwrap();
                    let b = base.apply(v, t0).unwrap();
                    let err = rel_err(&a, &b);
                    assert!(err < 1e-10, "{method:?} α={alpha} t0={t0}: {err:e}");
                }
            }
        }
    }
}

/// λ_n by Lanczos on M⁻¹L agrees with the largest dense generalized eigenvalue to 1e−10
/// relative, for the three mass matrices and the three test meshes.
#[test]
fn largest_eigenvalue_matches_dense() {
    for (name, _, ops) in meshes() {
        for kind in [Mass::Consistent, Mass::Lumped(Default::default()), Mass::Identity] {
            let m = mass_of(&ops, kind);
            let dense = Eigenbasis::dense(&ops.stiffness, &m).unwrap();
            let expected = *dense.values.last().unwrap();
            let pair = Operators::from_matrices(ops.stiffness.as_ref(), m.as_ref()).unwrap();
            let got = largest_eigenvalue(&pair, &LargestEigenParams::default()).unwrap();
            let err = (got - expected).abs() / expected;
            assert!(err < 1e-10, "{name} {kind:?}: {got} vs {expected} ({err:e})");
        }
    }
}

#[test]
fn largest_eigenvalue_rejects_bad_input() {
    let (_, ops) = ops_of(&generate::icosphere(1));
    let bad = LargestEigenParams {
        tol: 0.0,
        ..LargestEigenParams::default()
    };
    assert!(matches!(
        largest_eigenvalue(&wfem(&ops), &bad),
        Err(HeatError::InvalidParameter { name: "tol", .. })
    ));
    let (_, other) = ops_of(&generate::icosphere(2));
    assert!(matches!(
        Operators::from_matrices(ops.stiffness.as_ref(), other.mass.as_ref()),
        Err(HeatError::InconsistentOperators { .. })
    ));
    let too_few = LargestEigenParams {
        max_iter: 2,
        ..LargestEigenParams::default()
    };
    assert!(largest_eigenvalue(&wfem(&ops), &too_few).is_err());
}

/// The normalised kernel K̂_τ = K_{τ/s} (s = λ_n, or 1/area) is unchanged under a global
/// scaling of the mesh (α = 1e−3, 0.5, 1e3), and s scales like α⁻².
#[test]
fn normalised_kernel_is_scale_invariant() {
    let (mesh, ops) = ops_of(&generate::irregular_sphere(3, 5.6));
    let n = mesh.n_vertices();
    let f = x_coordinate(&mesh);
    let e = unit(n, 5);
    for normalization in [Normalization::LargestEigenvalue, Normalization::Area] {
        let base = NormalizedHeatKernel::new(&ops, HeatParams::default(), normalization).unwrap();
        assert_eq!(base.normalization(), normalization);
        for alpha in [1e-3, 0.5, 1e3] {
            let scaled_ops = assemble(&mesh.scaled(alpha).unwrap(), &AssemblyParams::default()).unwrap();
            let scaled = NormalizedHeatKernel::new(&scaled_ops, HeatParams::default(), normalization).unwrap();
            let ratio = scaled.scale() / base.scale() * alpha * alpha;
            assert!(
                (ratio - 1.0).abs() < 1e-9,
                "{normalization:?} α={alpha}: scale ratio {ratio}"
            );
            for tau in [0.5, 20.0] {
                let tau = match normalization {
                    // λ_n·t is O(1) for the normalised time; area-normalised times are small.
                    Normalization::LargestEigenvalue => tau,
                    Normalization::Area => tau * 1e-3,
                };
                for v in [&f, &e] {
                    let a = scaled.apply(v, tau).unwrap();
                    let b = base.apply(v, tau).unwrap();
                    let err = rel_err(&a, &b);
                    assert!(err < 1e-9, "{normalization:?} α={alpha} τ={tau}: {err:e}");
                }
            }
            // Without normalisation the kernel does change (covariance, not invariance).
            let raw = scaled.kernel().apply(&e, 0.01).unwrap();
            let raw_base = base.kernel().apply(&e, 0.01).unwrap();
            if alpha != 1.0 {
                assert!(rel_err(&raw, &raw_base) > 1e-3);
            }
        }
    }
}

/// K̂_τ = exp(−τ M⁻¹L/λ_n): checked against the dense eigenpairs, Σ e^{−τλ_k/λ_n} ⟨f, x_k⟩_M x_k.
#[test]
fn normalised_kernel_matches_dense_spectrum() {
    let (mesh, ops) = ops_of(&generate::icosphere(2));
    let k = NormalizedHeatKernel::new(&ops, HeatParams::default(), Normalization::LargestEigenvalue).unwrap();
    let dense = Eigenbasis::dense(&ops.stiffness, &ops.mass).unwrap();
    let lambda_n = *dense.values.last().unwrap();
    assert!((k.scale() - lambda_n).abs() < 1e-10 * lambda_n);
    let f = x_coordinate(&mesh);
    let tau = 3.0;
    let expected = dense.apply_heat(&ops.mass, &f, tau / lambda_n).unwrap();
    assert!(rel_err(&k.apply(&f, tau).unwrap(), &expected) < 1e-10);
    assert!(matches!(k.apply(&f, -1.0), Err(HeatError::InvalidTime { .. })));
}
