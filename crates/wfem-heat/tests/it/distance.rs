//! Diffusion distances through the rational method against the spectral formulas with the full
//! dense spectrum: wFEM `Σ_k e^{−λ_k t}((Bx_k)_i − (Bx_k)_j)²` (Eq. (18b)) and linear
//! `Σ_k e^{−2λ_k t}(x_k(i) − x_k(j))²` (docs/NUMERICS.md §1).

use crate::common;

use common::{matvec, ops_of, wfem};
use mesh_fem::{generate, FemOperators};
use wfem_heat::distance::{DiffusionDistance, DistanceKind, DistanceParams};
use wfem_heat::method::Method;
use wfem_heat::rkhs::diffusion_embeddings;
use wfem_heat::spectral::Eigenbasis;
use wfem_heat::{HeatError, HeatKernel, HeatParams};

/// The paper's rational method (the distances' original method).
fn rational(ops: &FemOperators) -> HeatKernel {
    HeatKernel::new(
        ops,
        HeatParams {
            method: Method::rational(shifted_solve::poles::DEFAULT_DEGREE),
            ..Default::default()
        },
    )
    .unwrap()
}

fn small_meshes() -> Vec<(&'static str, FemOperators)> {
    vec![
        ("icosphere3", ops_of(&generate::icosphere(3)).1),
        ("irregular_sphere2", ops_of(&generate::irregular_sphere(2, 5.6)).1),
        ("grid15", ops_of(&generate::grid(15, 15)).1),
    ]
}

/// Dense squared distances from vertex i to all vertices.
fn dense_row(ops: &FemOperators, basis: &Eigenbasis, kind: DistanceKind, t: f64, i: usize) -> Vec<f64> {
    let n = basis.vectors.nrows();
    let x = &basis.vectors;
    let (w, weight): (Vec<Vec<f64>>, Vec<f64>) = match kind {
        DistanceKind::MassWeighted => (
            (0..n)
                .map(|m| matvec(&ops.mass, &x.col(m).iter().copied().collect::<Vec<_>>()))
                .collect(),
            basis.values.iter().map(|l| (-l * t).exp()).collect(),
        ),
        DistanceKind::Diffusion => (
            (0..n).map(|m| x.col(m).iter().copied().collect()).collect(),
            basis.values.iter().map(|l| (-2.0 * l * t).exp()).collect(),
        ),
    };
    (0..n)
        .map(|j| (0..n).map(|m| weight[m] * (w[m][i] - w[m][j]).powi(2)).sum())
        .collect()
}

#[test]
fn rows_and_pairs_match_the_dense_spectral_formula() {
    for (name, ops) in small_meshes() {
        let n = ops.stiffness.nrows();
        let basis = Eigenbasis::dense(&ops.stiffness, &ops.mass).unwrap();
        // Every method of the kernel serves the distances: the rational method and the fast path.
        let kernels = [
            ("rational", rational(&ops)),
            ("fast", HeatKernel::new(&ops, HeatParams::default()).unwrap()),
        ];
        for (kind, (method, kernel)) in [DistanceKind::MassWeighted, DistanceKind::Diffusion]
            .into_iter()
            .flat_map(|k| kernels.iter().map(move |m| (k, m)))
        {
            for t in [0.01, 0.1] {
                let dd = DiffusionDistance::new(kernel, kind, t, &DistanceParams::default()).unwrap();
                for i in [0, n / 2] {
                    let exact = dense_row(&ops, &basis, kind, t, i);
                    let scale = exact.iter().fold(0.0f64, |a, &b| a.max(b));
                    let row = dd.row_squared(i).unwrap();
                    // The default diagonal of the diffusion distance is selected inversion (no
                    // probe columns); the mass-weighted one is probed.
                    let columns = dd.diagonal_info().unwrap().columns;
                    assert_eq!(columns == 0, kind == DistanceKind::Diffusion, "{kind:?}: {columns}");
                    let err = row.iter().zip(&exact).fold(0.0f64, |a, (r, e)| a.max((r - e).abs()));
                    assert!(
                        err < 1e-10 * scale,
                        "{name} {method} {kind:?} t={t} row {i}: error {:e}",
                        err / scale
                    );
                    eprintln!(
                        "{name} {method} {kind:?} t={t} row {i}: max error / max d² = {:e}",
                        err / scale
                    );
                    // Pairs: one column per pair, relative to each entry (no cancellation).
                    let pairs: Vec<(usize, usize)> = (0..n).step_by(7).map(|j| (i, j)).collect();
                    let got = dd.pairs_squared(&pairs).unwrap();
                    for (&(_, j), g) in pairs.iter().zip(&got) {
                        let e = exact[j];
                        assert!(
                            (g - e).abs() <= 1e-10 * e.max(1e-300) || (j == i && *g == 0.0),
                            "{name} {method} {kind:?} t={t} pair ({i},{j}): {g} vs {e}"
                        );
                    }
                    let d = dd.row(i).unwrap();
                    assert_eq!(d[i], 0.0);
                    assert!((d[n - 1] - row[n - 1].sqrt()).abs() <= 1e-15 * d[n - 1]);
                }
            }
        }
    }
}

#[test]
fn wfem_distance_is_the_b_distance_of_the_embeddings() {
    // d²(i,j) = ‖h_i − h_j‖_B² with h_i = K_{t/2} e_i (Eq. (18b)).
    let (_, ops) = ops_of(&generate::irregular_sphere(2, 5.6));
    let n = ops.stiffness.nrows();
    let t = 0.05;
    let kernel = rational(&ops);
    let dd = DiffusionDistance::new(&kernel, DistanceKind::MassWeighted, t, &DistanceParams::default()).unwrap();
    let verts = [3, 40, n - 1];
    let h = diffusion_embeddings(&kernel, &verts, t).unwrap();
    for a in 0..3 {
        for b in 0..3 {
            let diff: Vec<f64> = (0..n).map(|r| h[(r, a)] - h[(r, b)]).collect();
            let want = wfem(&ops).mass_norm(&diff).unwrap().powi(2);
            let got = dd.pairs_squared(&[(verts[a], verts[b])]).unwrap()[0];
            assert!(
                (got - want).abs() <= 1e-11 * want.max(1e-30),
                "({a},{b}): {got} vs {want}"
            );
        }
    }
    assert_eq!(dd.kind(), DistanceKind::MassWeighted);
    assert_eq!(dd.t(), t);
}

#[test]
fn symmetry_small_blocks_and_diagonal_is_hks() {
    let (_, ops) = ops_of(&generate::icosphere(2));
    let n = ops.stiffness.nrows();
    let basis = Eigenbasis::dense(&ops.stiffness, &ops.mass).unwrap();
    let t = 0.05;
    let small = DistanceParams {
        block: 5,
        ..Default::default()
    };
    let dd = DiffusionDistance::new(&rational(&ops), DistanceKind::Diffusion, t, &small).unwrap();
    // The diagonal of H̃_{2t} is the heat kernel signature HKS_{2t}(j) = Σ e^{−2λt} x(j)².
    let diag = dd.diagonal().unwrap();
    for j in [0, 17, n - 1] {
        let hks: f64 = (0..n)
            .map(|m| (-2.0 * t * basis.values[m]).exp() * basis.vectors[(j, m)].powi(2))
            .sum();
        assert!((diag[j] - hks).abs() < 1e-11 * hks, "HKS({j}): {} vs {hks}", diag[j]);
    }
    let a = dd.row_squared(4).unwrap();
    let b = dd.row_squared(90).unwrap();
    assert!((a[90] - b[4]).abs() < 1e-12 * a[90]);
    let p = dd.pairs_squared(&[(4, 90), (90, 4), (4, 4)]).unwrap();
    assert!((p[0] - p[1]).abs() < 1e-12 * p[0] && p[2] == 0.0);
    assert!((p[0] - a[90]).abs() < 1e-10 * p[0]);
}

#[test]
fn errors_are_typed() {
    let (_, ops) = ops_of(&generate::icosphere(1));
    let n = ops.stiffness.nrows();
    let dd = DiffusionDistance::new(
        &rational(&ops),
        DistanceKind::MassWeighted,
        0.1,
        &DistanceParams::default(),
    )
    .unwrap();
    assert!(matches!(
        dd.row(n),
        Err(HeatError::VertexOutOfRange { index, n_vertices }) if index == n && n_vertices == n
    ));
    assert!(matches!(
        dd.pairs(&[(0, 1), (n + 2, 0)]),
        Err(HeatError::VertexOutOfRange { .. })
    ));
    assert!(matches!(
        DiffusionDistance::new(
            &rational(&ops),
            DistanceKind::Diffusion,
            f64::NAN,
            &DistanceParams::default()
        ),
        Err(HeatError::InvalidTime { .. })
    ));
    let bad = DistanceParams {
        block: 0,
        ..Default::default()
    };
    assert!(matches!(
        DiffusionDistance::new(&rational(&ops), DistanceKind::MassWeighted, 0.1, &bad),
        Err(HeatError::InvalidParameter { name: "block", .. })
    ));
    // The rational degree is the kernel's: an unsupported one is refused when the kernel is built.
    assert!(HeatKernel::new(
        &ops,
        HeatParams {
            method: Method::rational(1000),
            ..Default::default()
        }
    )
    .is_err());
}

/// Probing: the colouring needs a number of columns set by the decay of A (about a factor 6 per
/// edge hop here), not by n; the probed diagonal agrees with exact unit-vector columns. On
/// small meshes (or at large t) it falls back to the exact diagonal.
#[test]
fn probed_diagonal_matches_exact_columns() {
    use wfem_heat::diagonal::DiagonalMethod;
    let (_, ops) = ops_of(&generate::icosphere(4));
    let n = ops.stiffness.nrows();
    // A short time (√(4t) < edge length): the kernel is local.
    let t = 2e-4;
    for kind in [DistanceKind::MassWeighted, DistanceKind::Diffusion] {
        let params = DistanceParams {
            diagonal: DiagonalMethod::Probing { tol: 1e-8 },
            ..Default::default()
        };
        let dd = DiffusionDistance::new(&rational(&ops), kind, t, &params).unwrap();
        let row = dd.row_squared(n / 2).unwrap();
        let info = dd.diagonal_info().unwrap().clone();
        assert!(
            info.hops.is_some() && info.columns < n / 4,
            "{kind:?}: {info:?} (n = {n})"
        );
        let d = dd.diagonal().unwrap();
        let sample: Vec<usize> = (0..n).step_by(97).collect();
        let e = {
            let mut e = faer::Mat::<f64>::zeros(n, sample.len());
            for (c, &j) in sample.iter().enumerate() {
                e[(j, c)] = 1.0;
            }
            e
        };
        let y = dd.gram_apply(e.as_ref()).unwrap();
        let mut worst = 0.0f64;
        for (c, &j) in sample.iter().enumerate() {
            worst = worst.max((d[j] - y[(j, c)]).abs() / y[(j, c)].abs());
        }
        eprintln!("{kind:?} t={t}: {info:?}, worst sampled diagonal error {worst:e} (n = {n})");
        assert!(worst < 1e-7, "{kind:?}: diagonal error {worst:e}");
        // The row is consistent with pairs (which need no diagonal).
        let pairs: Vec<(usize, usize)> = sample.iter().map(|&j| (n / 2, j)).collect();
        let p = dd.pairs_squared(&pairs).unwrap();
        let scale = row.iter().fold(0.0f64, |a, &b| a.max(b));
        for (&(_, j), pj) in pairs.iter().zip(&p) {
            assert!((row[j] - pj).abs() < 1e-7 * scale, "{kind:?} j={j}: {} vs {pj}", row[j]);
        }
    }
    // Small mesh and large t: the colouring would need more than n/4 columns, so the diagonal
    // is exact.
    let (_, ops) = ops_of(&generate::icosphere(2));
    for t in [0.002, 1.0] {
        let dd = DiffusionDistance::new(
            &rational(&ops),
            DistanceKind::MassWeighted,
            t,
            &DistanceParams::default(),
        )
        .unwrap();
        dd.diagonal().unwrap();
        let info = dd.diagonal_info().unwrap();
        assert_eq!((info.columns, info.hops), (ops.stiffness.nrows(), None));
    }
    let bad = DistanceParams {
        diagonal: DiagonalMethod::Probing { tol: 0.0 },
        ..Default::default()
    };
    assert!(matches!(
        DiffusionDistance::new(&rational(&ops), DistanceKind::MassWeighted, 0.1, &bad),
        Err(HeatError::InvalidParameter {
            name: "diagonal.tol",
            ..
        })
    ));
}
