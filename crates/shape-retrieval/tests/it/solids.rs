//! Descriptors of solids (issue #39): the HKS of a tetrahedral mesh and its Shape-DNA (Reuter et
//! al. 2006) with the 3-D Weyl normalisation, through the same code as on surfaces. References:
//! nalgebra's own dense generalized eigendecomposition of (L, B), the unit cube's analytic
//! Neumann spectrum π²(l² + m² + n²), and Weyl's law itself on that analytic spectrum.

use faer::sparse::SparseColMat;
use mesh_fem::generate::tet_cube;
use mesh_fem::volume::{assemble_volume, TetMesh};
use mesh_fem::{AssemblyParams, FemOperators, Mass};
use nalgebra::{DMatrix, DVector};
use shape_retrieval::exact::HksMethod;
use shape_retrieval::global::{operators_signature, GlobalKind, Measure};
use shape_retrieval::hks::TimeSampling;
use shape_retrieval::mesh_hks::{operators_hks, MeshHksParams};
use std::f64::consts::PI;
use wfem_heat::Operators;

/// The unit cube, n cells a side, with every interior vertex moved by a fixed pseudo-random
/// amount (so that the mesh has no symmetry a wrong formula could hide behind).
fn jittered_cube(n: usize) -> TetMesh {
    let cube = tet_cube(n);
    let h = 1.0 / n as f64;
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    let positions = cube
        .positions()
        .iter()
        .map(|p| {
            let interior = p.iter().all(|&x| x > 1e-9 && x < 1.0 - 1e-9);
            if interior {
                p.map(|x| x + 0.2 * h * next())
            } else {
                *p
            }
        })
        .collect();
    TetMesh::new(positions, cube.tets().to_vec()).unwrap()
}

fn operators(mesh: &TetMesh) -> (FemOperators, Operators) {
    let fem = assemble_volume(mesh, &AssemblyParams::default()).unwrap();
    let ops = Operators::new(&fem, Mass::Consistent).unwrap();
    (fem, ops)
}

fn dense(m: &SparseColMat<usize, f64>) -> DMatrix<f64> {
    let n = m.nrows();
    let mut d = DMatrix::<f64>::zeros(n, n);
    let s = m.symbolic();
    for j in 0..n {
        for p in s.col_range(j) {
            d[(s.row_idx()[p], j)] = m.val()[p];
        }
    }
    d
}

/// All eigenpairs of L x = λ B x by nalgebra (Cholesky B = CCᵀ, then the symmetric C⁻¹LC⁻ᵀ),
/// λ ascending, X B-orthonormal.
fn dense_pairs(fem: &FemOperators) -> (Vec<f64>, DMatrix<f64>) {
    let (l, b) = (dense(&fem.stiffness), dense(&fem.mass));
    let c = nalgebra::Cholesky::new(b).unwrap();
    let c_inv = c.l().try_inverse().unwrap();
    let s = &c_inv * l * c_inv.transpose();
    let e = nalgebra::SymmetricEigen::new(0.5 * (&s + s.transpose()));
    let mut order: Vec<usize> = (0..e.eigenvalues.len()).collect();
    order.sort_by(|&a, &b| e.eigenvalues[a].total_cmp(&e.eigenvalues[b]));
    let values = order.iter().map(|&i| e.eigenvalues[i]).collect();
    let x = c_inv.transpose() * &e.eigenvectors;
    let x = DMatrix::from_fn(x.nrows(), order.len(), |r, k| x[(r, order[k])]);
    (values, x)
}

/// The Neumann eigenvalues π²(l² + m² + n²) of the unit cube, ascending, the first `count`.
fn cube_spectrum(count: usize) -> Vec<f64> {
    // Every l, m, n up to 2·count^{1/3} + 3 > the radius of the count-th lattice point.
    let top = 2 * (count as f64).cbrt() as usize + 3;
    let mut v: Vec<f64> = (0..top)
        .flat_map(|l| (0..top).flat_map(move |m| (0..top).map(move |n| (l * l + m * m + n * n) as f64)))
        .map(|q| PI * PI * q)
        .collect();
    v.sort_by(f64::total_cmp);
    v.truncate(count);
    v
}

#[test]
fn shape_dna_of_a_solid_equals_the_dense_generalized_spectrum() {
    // 512 vertices: above the dense cut-off of smallest_eigenpairs, so block Lanczos runs.
    let mesh = jittered_cube(7);
    let (fem, ops) = operators(&mesh);
    let (values, _) = dense_pairs(&fem);
    let volume = mesh.volume();
    let m = 20;
    let sig = operators_signature(&ops, GlobalKind::WeylShapeDna, m, Measure::Volume(volume)).unwrap();
    assert_eq!(sig.eigenvalues.len(), m + 1);
    assert!(sig.eigenvalues[0].abs() < 1e-9);
    for (i, &reference) in values.iter().enumerate().take(m + 1).skip(1) {
        let ours = sig.eigenvalues[i];
        assert!(
            (ours - reference).abs() < 1e-9 * reference,
            "λ_{i}: {ours} vs nalgebra {reference}"
        );
        // g_i = λ_i V^{2/3} / (6π² i)^{2/3}, computed here from nalgebra's λ_i.
        let g = reference * volume.powf(2.0 / 3.0) / (6.0 * PI * PI * i as f64).powf(2.0 / 3.0);
        assert!((sig.signature[i - 1] - g).abs() < 1e-9 * g, "g_{i}");
    }
    let log = operators_signature(&ops, GlobalKind::LogShapeDna, m, Measure::Volume(volume)).unwrap();
    for (i, &reference) in values.iter().enumerate().take(m + 1).skip(1) {
        let expected = (reference * volume.powf(2.0 / 3.0)).ln();
        assert!((log.signature[i - 1] - expected).abs() < 1e-9);
    }
}

#[test]
fn shape_dna_of_the_unit_cube_converges_to_the_analytic_one() {
    let exact = cube_spectrum(11);
    let weyl = |i: usize, lambda: f64| lambda / (6.0 * PI * PI * i as f64).powf(2.0 / 3.0);
    let mut errors = Vec::new();
    for n in [4, 8] {
        let (_, ops) = operators(&tet_cube(n));
        let sig = operators_signature(&ops, GlobalKind::WeylShapeDna, 10, Measure::Volume(1.0)).unwrap();
        let worst = (1..=10)
            .map(|i| ((sig.signature[i - 1] - weyl(i, exact[i])) / weyl(i, exact[i])).abs())
            .fold(0.0f64, f64::max);
        errors.push(worst);
    }
    // P1 elements: O(h²) in the eigenvalues (the ratio of the errors at h and h/2 is about 4).
    assert!(errors[1] < 0.08, "{errors:?}");
    assert!(errors[0] / errors[1] > 3.0, "{errors:?}");
}

#[test]
fn the_3d_weyl_normalisation_tends_to_one_and_the_2d_one_does_not() {
    // Weyl's law on the analytic spectrum alone (no mesh): λ_i/λ_i^Weyl → 1. The Neumann
    // boundary term (+S λ/(16π) in N(λ)) keeps it below 1, approaching from below like i^{-1/3}.
    let exact = cube_spectrum(20_001);
    let solid = Measure::Volume(1.0);
    let ratio = |i: usize| solid.weyl_ratio(exact[i], i);
    let (a, b) = (ratio(2_000), ratio(20_000));
    assert!(
        (0.85..0.95).contains(&a) && (0.93..0.99).contains(&b) && b > a,
        "{a} {b}"
    );
    assert!((solid.weyl_eigenvalue(20_000) / exact[20_000] - 1.0 / b).abs() < 1e-12);
    // The surface normalisation λA/(4πi) of the same numbers drifts like i^{-1/3}: wrong in 3-D.
    let surface = Measure::Area(1.0);
    let drift = surface.weyl_ratio(exact[2_000], 2_000) / surface.weyl_ratio(exact[20_000], 20_000);
    assert!(drift > 1.8, "{drift}");
}

#[test]
fn shape_dna_of_a_solid_is_scale_invariant_only_with_its_volume() {
    let mesh = jittered_cube(4);
    let m = 12;
    let signature = |s: f64, measure: fn(f64) -> Measure, kind: GlobalKind| {
        let scaled = mesh.scaled(s).unwrap();
        let (_, ops) = operators(&scaled);
        operators_signature(&ops, kind, m, measure(scaled.volume()))
            .unwrap()
            .signature
    };
    for kind in [
        GlobalKind::WeylShapeDna,
        GlobalKind::LogShapeDna,
        GlobalKind::Biharmonic,
    ] {
        let unit = signature(1.0, Measure::Volume, kind);
        for s in [1e-3, 1e3] {
            let other = signature(s, Measure::Volume, kind);
            let diff = unit.iter().zip(&other).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
            assert!(diff < 1e-8, "{kind:?} at scale {s}: {diff:e}");
        }
    }
    // Taking the volume for an area breaks the invariance (the check can fail).
    let (a, b) = (
        signature(1.0, Measure::Area, GlobalKind::WeylShapeDna),
        signature(10.0, Measure::Area, GlobalKind::WeylShapeDna),
    );
    assert!((a[0] - b[0]).abs() > 1.0, "{} {}", a[0], b[0]);
}

#[test]
fn bad_requests_are_refused() {
    let (_, ops) = operators(&tet_cube(2));
    for m in [0, 27, 100] {
        assert!(operators_signature(&ops, GlobalKind::WeylShapeDna, m, Measure::Volume(1.0)).is_err());
    }
    for v in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert!(operators_signature(&ops, GlobalKind::WeylShapeDna, 3, Measure::Volume(v)).is_err());
    }
}

#[test]
fn hks_of_a_solid_equals_the_dense_heat_kernel_diagonal() {
    let mesh = jittered_cube(5);
    let (fem, _) = operators(&mesh);
    let (values, x) = dense_pairs(&fem);
    let times = vec![1e-3, 1e-2, 0.1];
    // The kernel value K̃_t(i, i) = Σ_k e^{−λ_k t} φ_k(i)², all n pairs: exact.
    let reference = |t: f64| -> DVector<f64> {
        let w = DVector::from_iterator(values.len(), values.iter().map(|l| (-t * l.max(0.0)).exp()));
        DVector::from_iterator(
            x.nrows(),
            (0..x.nrows()).map(|i| (0..x.ncols()).map(|k| w[k] * x[(i, k)].powi(2)).sum()),
        )
    };
    for method in [HksMethod::Exact, HksMethod::Spectral] {
        let params = MeshHksParams {
            method,
            times: TimeSampling::Explicit(times.clone()),
            eigenpairs: fem.n(),
            ..Default::default()
        };
        let h = operators_hks(&fem, &params, None, &mut |_| {}).unwrap();
        for (j, &t) in times.iter().enumerate() {
            let r = reference(t);
            let scale = r.amax();
            for i in 0..fem.n() {
                assert!(
                    (h.values[(i, j)] - r[i]).abs() < 1e-9 * scale,
                    "{method:?} t = {t}, vertex {i}: {} vs {}",
                    h.values[(i, j)],
                    r[i]
                );
            }
        }
    }
}
