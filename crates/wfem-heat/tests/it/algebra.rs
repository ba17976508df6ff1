//! Operator algebra of the wFEM heat kernel (paper, Sect. 3–4): semigroup, commutativity, heat
//! equation, inverse K_{−t}, scalar products (Eq. (16), (17)), RKHS (Eq. (15)) and the
//! embeddings of Eq. (18), all against the dense generalized eigendecomposition.

use crate::common;

use common::{dot, matvec, ops_of, unit, wfem};
use faer::Mat;
use mesh_fem::Mass;
use mesh_fem::{generate, FemOperators};
use wfem_heat::method::Method;
use wfem_heat::rkhs::{
    diffusion_embeddings, heat_inner_product, inverse_cg, inverse_spectral, reproducing_embedding,
    reproducing_kernel_apply, InverseParams,
};
use wfem_heat::spectral::{EigenParams, Eigenbasis};
use wfem_heat::{HeatError, HeatKernel, HeatParams};

/// Small meshes (area 4π): the brief's icosphere(2), irregular_sphere(2, 5.6), grid(15, 15).
fn small_meshes() -> Vec<(&'static str, FemOperators)> {
    vec![
        ("icosphere2", ops_of(&generate::icosphere(2)).1),
        ("irregular_sphere2", ops_of(&generate::irregular_sphere(2, 5.6)).1),
        ("grid15", ops_of(&generate::grid(15, 15)).1),
    ]
}

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

fn dense(ops: &FemOperators) -> Eigenbasis {
    Eigenbasis::dense(&ops.stiffness, &ops.mass).unwrap()
}

/// The first k eigenpairs of a basis.
fn truncate(basis: &Eigenbasis, k: usize) -> Eigenbasis {
    Eigenbasis {
        values: basis.values[..k].to_vec(),
        vectors: basis.vectors.as_ref().get(.., 0..k).to_owned(),
    }
}

fn col(m: &Mat<f64>, j: usize) -> Vec<f64> {
    m.col(j).iter().copied().collect()
}

/// ‖a − b‖_B / ‖b‖_B.
fn rel_b(ops: &FemOperators, a: &[f64], b: &[f64]) -> f64 {
    let d: Vec<f64> = a.iter().zip(b).map(|(x, y)| x - y).collect();
    wfem(ops).mass_norm(&d).unwrap() / wfem(ops).mass_norm(b).unwrap()
}

/// A band-limited function: a fixed combination of the first `k` eigenvectors.
fn band_limited(basis: &Eigenbasis, k: usize) -> Vec<f64> {
    let n = basis.vectors.nrows();
    (0..n)
        .map(|i| (0..k).map(|m| (1.0 + m as f64).recip() * basis.vectors[(i, m)]).sum())
        .collect()
}

/// A rough, broad-spectrum function: two impulses plus a linear ramp.
fn rough(n: usize) -> Vec<f64> {
    let mut f: Vec<f64> = (0..n).map(|i| (i as f64 / n as f64) - 0.5).collect();
    f[n / 3] += 2.0;
    f[(2 * n) / 3] -= 1.0;
    f
}

#[test]
fn semigroup_and_commutativity_to_the_rational_error() {
    for (name, ops) in small_meshes() {
        let n = ops.stiffness.nrows();
        let k = rational(&ops);
        let d = HeatKernel::new(
            &ops,
            HeatParams {
                mass: Mass::Consistent,
                method: Method::Dense,
            },
        )
        .unwrap();
        let f = rough(n);
        for (t1, t2) in [(0.01, 0.04), (0.1, 0.3), (0.002, 1.0)] {
            let k12 = k.apply(&k.apply(&f, t2).unwrap(), t1).unwrap();
            let k21 = k.apply(&k.apply(&f, t1).unwrap(), t2).unwrap();
            let ksum = k.apply(&f, t1 + t2).unwrap();
            let exact = d.apply(&f, t1 + t2).unwrap();
            // Each application errs by at most E_16 ≈ 2e−14 (float floor) in the B→B norm.
            let scale = wfem(&ops).mass_norm(&f).unwrap() / wfem(&ops).mass_norm(&exact).unwrap();
            for (what, v) in [("K_t1 K_t2", &k12), ("K_t2 K_t1", &k21), ("K_(t1+t2)", &ksum)] {
                let e = rel_b(&ops, v, &exact) / scale;
                assert!(e < 2e-13, "{name} t=({t1},{t2}) {what}: error {e:e}");
            }
            let e = rel_b(&ops, &k12, &k21) / scale;
            assert!(e < 2e-13, "{name}: commutativity {e:e}");
        }
    }
}

/// ∂_t K_t f = −B⁻¹L K_t f (Sect. 4) by the central difference (K_{t+h} f − K_{t−h} f)/(2h).
/// Its error is C h² (truncation, C ≈ ‖(B⁻¹L)³K_t f‖/6) plus about ε‖f‖/h (rounding/rational
/// error ε); the dense kernel shows the h² order, the rational one reaches ≈1e−8 at the
/// balancing h = (3ε/C)^{1/3}.
#[test]
fn heat_equation_by_central_differences() {
    let (_, ops) = ops_of(&generate::icosphere(2));
    let n = ops.stiffness.nrows();
    let basis = dense(&ops);
    let dk = HeatKernel::new(
        &ops,
        HeatParams {
            mass: Mass::Consistent,
            method: Method::Dense,
        },
    )
    .unwrap();
    let rk = rational(&ops);
    let f = rough(n);
    let t = 0.05;
    // Exact derivative −X Λ D_t Xᵀ B f.
    let bf = matvec(&ops.mass, &f);
    let x = &basis.vectors;
    let c: Vec<f64> = (0..n)
        .map(|m| -basis.values[m] * (-t * basis.values[m]).exp() * dot(&col(x, m), &bf))
        .collect();
    let exact: Vec<f64> = (0..n).map(|i| (0..n).map(|m| x[(i, m)] * c[m]).sum()).collect();
    let fd = |k: &HeatKernel, h: f64| {
        let p = k.apply(&f, t + h).unwrap();
        let q = k.apply(&f, t - h).unwrap();
        let d: Vec<f64> = p.iter().zip(&q).map(|(a, b)| (a - b) / (2.0 * h)).collect();
        rel_b(&ops, &d, &exact)
    };
    // Order 2: halving h divides the (truncation-dominated) error by 4.
    let (e1, e2, e3) = (fd(&dk, 4e-3), fd(&dk, 2e-3), fd(&dk, 1e-3));
    for (a, b) in [(e1, e2), (e2, e3)] {
        let ratio = a / b;
        assert!(
            (3.8..4.2).contains(&ratio),
            "dense: errors {a:e} → {b:e}, ratio {ratio}"
        );
    }
    assert!(e3 < 1e-2, "dense: error {e3:e} at h = 1e−3");
    // Rational method at the balancing step.
    let c_trunc = e3 / 1e-6; // C from e = C h²
    let h = (3.0 * 2e-14 / c_trunc).cbrt();
    let er = fd(&rk, h);
    eprintln!("dense FD errors {e1:e} {e2:e} {e3:e}; rational {er:e} at h = {h:e}");
    assert!(er < 1e-7, "rational: error {er:e} at h = {h:e}");
    assert!(
        er < 10.0 * c_trunc * h * h + 1e-8,
        "rational: error {er:e} at h = {h:e}"
    );
}

#[test]
fn spectral_inverse_round_trip_and_report() {
    for (name, ops) in small_meshes() {
        let basis = dense(&ops);
        let rk = rational(&ops);
        let t = 0.1;
        let f = band_limited(&basis, 9);
        let kb = truncate(&basis, 16);
        let (g, report) = inverse_spectral(&kb, &wfem(&ops), &f, t).unwrap();
        assert_eq!(report.k, 16);
        assert_eq!(report.lambda_k, basis.values[15]);
        assert!((report.amplification - (t * basis.values[15]).exp()).abs() < 1e-12 * report.amplification);
        assert!(report.relative_dropped() < 1e-12, "{name}: {report:?}");
        // Round trip K_t (K_{−t} f) = f.
        let back = rk.apply(&g, t).unwrap();
        let e = rel_b(&ops, &back, &f);
        assert!(e < 1e-12, "{name}: round trip {e:e}");
        // The same with the Lanczos pairs.
        let part = Eigenbasis::partial(&ops.stiffness, &ops.mass, 16, &EigenParams::default()).unwrap();
        let (g2, _) = inverse_spectral(&part, &wfem(&ops), &f, t).unwrap();
        let e = rel_b(&ops, &g2, &g);
        assert!(e < 1e-8, "{name}: partial vs dense {e:e}");
        // A rough f: the report states what was dropped, exactly ‖f − X_k X_kᵀ B f‖_B.
        let r = rough(ops.stiffness.nrows());
        let (_, rep) = inverse_spectral(&kb, &wfem(&ops), &r, t).unwrap();
        let bf = matvec(&ops.mass, &r);
        let kept: f64 = (0..16).map(|m| dot(&col(&basis.vectors, m), &bf).powi(2)).sum();
        let total = wfem(&ops).mass_norm(&r).unwrap().powi(2);
        let expected = (total - kept).sqrt();
        assert!(
            (rep.dropped_norm - expected).abs() < 1e-8 * total.sqrt(),
            "{name}: {rep:?} vs {expected}"
        );
        assert!(rep.relative_dropped() > 0.1, "{name}: {rep:?}");
    }
}

#[test]
fn cg_inverse_round_trip_on_band_limited_data() {
    for (name, ops) in small_meshes() {
        let basis = dense(&ops);
        let rk = rational(&ops);
        let t = 0.1;
        let f = band_limited(&basis, 9);
        let (g, rep) = inverse_cg(&rk, &f, t, &InverseParams::default()).unwrap();
        // Reference truncated to the band of f: the full basis would amplify the rounding
        // noise of f's high-frequency components by e^{tλ_max} (the caveat of the inverse).
        let (exact, _) = inverse_spectral(&truncate(&basis, 9), &wfem(&ops), &f, t).unwrap();
        let e = rel_b(&ops, &g, &exact);
        assert!(e < 1e-9, "{name}: K_(-t) f error {e:e}, {rep:?}");
        let back = rk.apply(&g, t).unwrap();
        assert!(rel_b(&ops, &back, &f) < 1e-9, "{name}: round trip");
        assert!(rep.relative_residual < 1e-9, "{name}: {rep:?}");
        let amp = wfem(&ops).mass_norm(&exact).unwrap() / wfem(&ops).mass_norm(&f).unwrap();
        assert!((rep.amplification - amp).abs() < 1e-8 * amp, "{name}: {rep:?} vs {amp}");
        assert!(rep.iterations <= 40, "{name}: {rep:?}");
        eprintln!("{name}: CG inverse error {e:e}, {rep:?}");
    }
}

#[test]
fn cg_inverse_refuses_rough_data() {
    let (_, ops) = ops_of(&generate::icosphere(2));
    let n = ops.stiffness.nrows();
    let basis = dense(&ops);
    let rk = rational(&ops);
    // e^{tλ_max} is astronomic at t = 1.
    let t = 1.0;
    assert!(t * basis.values[n - 1] > 200.0);
    let f = unit(n, 7);
    let refused = inverse_cg(&rk, &f, t, &InverseParams::default());
    eprintln!("e_i at t = 1: {refused:?}");
    match refused {
        Err(HeatError::IllConditionedInverse { amplification, cap, .. }) => {
            assert_eq!(cap, 1e6);
            assert!(amplification.is_finite() && amplification > 0.0);
        }
        other => panic!("expected a refusal, got {other:?}"),
    }
    // A lower cap refuses even moderately rough data that the default accepts.
    let f = band_limited(&basis, 25);
    let t = 0.2;
    let (_, rep) = inverse_cg(&rk, &f, t, &InverseParams::default()).unwrap();
    let low = InverseParams {
        max_amplification: 0.5 * rep.amplification.max(1.0),
        ..Default::default()
    };
    assert!(rep.amplification > 1.0, "{rep:?}");
    assert!(matches!(
        inverse_cg(&rk, &f, t, &low),
        Err(HeatError::IllConditionedInverse { .. })
    ));
    // The spectral inverse refuses an overflowing e^{tλ_k}.
    assert!(matches!(
        inverse_spectral(&basis, &wfem(&ops), &f, 10.0),
        Err(HeatError::IllConditionedInverse { .. })
    ));
    // Bad parameters are named.
    let bad = InverseParams {
        tol: 0.0,
        ..Default::default()
    };
    assert!(matches!(
        inverse_cg(&rk, &f, t, &bad),
        Err(HeatError::InvalidParameter { name: "tol", .. })
    ));
}

#[test]
fn scalar_products_symmetry_positivity_and_dense_reference() {
    for (name, ops) in small_meshes() {
        let n = ops.stiffness.nrows();
        let basis = dense(&ops);
        let rk = rational(&ops);
        let t = 0.05;
        let f = rough(n);
        let g: Vec<f64> = (0..n).map(|i| ((i * 7) % 11) as f64 - 5.0).collect();
        // ⟨f, g⟩_B = fᵀBg.
        let fb = wfem(&ops).mass_inner_product(&f, &g).unwrap();
        assert!((fb - dot(&f, &matvec(&ops.mass, &g))).abs() < 1e-13 * fb.abs().max(1.0));
        // ⟨f, g⟩_t = fᵀ B X D_t Xᵀ B g (Eq. (16)).
        let bf = matvec(&ops.mass, &f);
        let bg = matvec(&ops.mass, &g);
        let x = &basis.vectors;
        let exact: f64 = (0..n)
            .map(|m| (-t * basis.values[m]).exp() * dot(&col(x, m), &bf) * dot(&col(x, m), &bg))
            .sum();
        let fg = heat_inner_product(&rk, &f, &g, t).unwrap();
        let gf = heat_inner_product(&rk, &g, &f, t).unwrap();
        let scale = wfem(&ops).mass_norm(&f).unwrap() * wfem(&ops).mass_norm(&g).unwrap();
        assert!((fg - exact).abs() < 1e-13 * scale, "{name}: {fg} vs {exact}");
        assert!((fg - gf).abs() < 1e-13 * scale, "{name}: symmetry {fg} vs {gf}");
        for v in [&f, &g, &unit(n, 3)] {
            let vv = heat_inner_product(&rk, v, v, t).unwrap();
            assert!(vv > 0.0, "{name}: ⟨v, v⟩_t = {vv}");
        }
    }
}

/// Eq. (17), corrected: ‖x_i − x_j‖_t² = e^{−λ_i t} + e^{−λ_j t} (the paper prints e^{+λt}).
#[test]
fn eq17_on_eigenvectors_has_negative_exponents() {
    for (name, ops) in small_meshes() {
        let basis = dense(&ops);
        let rk = rational(&ops);
        let t = 0.3;
        for (i, j) in [(0, 1), (1, 5), (3, 20), (10, 40)] {
            let d: Vec<f64> = (0..basis.vectors.nrows())
                .map(|r| basis.vectors[(r, i)] - basis.vectors[(r, j)])
                .collect();
            let got = heat_inner_product(&rk, &d, &d, t).unwrap();
            let (li, lj) = (basis.values[i], basis.values[j]);
            let corrected = (-li * t).exp() + (-lj * t).exp();
            let printed = (li * t).exp() + (lj * t).exp();
            assert!(
                (got - corrected).abs() < 1e-12,
                "{name} ({i},{j}): {got} vs {corrected}"
            );
            assert!((got - printed).abs() > 0.1, "{name}: the printed Eq. (17) would hold");
        }
    }
}

/// Eq. (15): ⟨H_t(·, p_i), f⟩_t = f(p_i) — for every f with the full dense basis (small t, so
/// that e^{tλ_max} stays moderate), and for band-limited f with the truncated basis.
#[test]
fn reproduction_property() {
    for (name, ops) in small_meshes() {
        let n = ops.stiffness.nrows();
        let basis = dense(&ops);
        let rk = rational(&ops);
        // Full basis, arbitrary f.
        let t = 2e-3;
        let f = rough(n);
        for i in [0, n / 2, n - 1] {
            let (hi, rep) = reproducing_kernel_apply(&basis, &wfem(&ops), &unit(n, i), t).unwrap();
            assert!(rep.relative_dropped() < 1e-10, "{name}: {rep:?}");
            let v = heat_inner_product(&rk, &hi, &f, t).unwrap();
            // Error of the rational K_t: E·‖H_t e_i‖_B‖f‖_B.
            let tol = 1e-13 * wfem(&ops).mass_norm(&hi).unwrap() * wfem(&ops).mass_norm(&f).unwrap();
            assert!((v - f[i]).abs() < tol, "{name} i={i}: {v} vs {}", f[i]);
        }
        // Truncated basis, band-limited f, larger t.
        let t = 0.2;
        let kb = truncate(&basis, 25);
        let f = band_limited(&basis, 16);
        for i in [1, n / 3] {
            let (hi, rep) = reproducing_kernel_apply(&kb, &wfem(&ops), &unit(n, i), t).unwrap();
            assert_eq!(rep.k, 25);
            assert!(rep.relative_dropped() > 0.5, "{name}: e_i is not band-limited: {rep:?}");
            let v = heat_inner_product(&rk, &hi, &f, t).unwrap();
            let tol = 1e-13 * wfem(&ops).mass_norm(&hi).unwrap() * wfem(&ops).mass_norm(&f).unwrap();
            assert!((v - f[i]).abs() < tol, "{name} i={i}: {v} vs {} (tol {tol:e})", f[i]);
        }
    }
}

/// Eq. (18): S_t(i,j) = ⟨h_i, h_j⟩_B with h_i = K_{t/2} e_i (rational), and
/// H_t(i,j) = ⟨g_i, g_j⟩_B with g_i = H_{t/2} e_i (full and truncated spectral).
#[test]
fn eq18_gram_identities() {
    for (name, ops) in small_meshes() {
        let n = ops.stiffness.nrows();
        let basis = dense(&ops);
        let rk = rational(&ops);
        let x = &basis.vectors;
        let t = 0.1;
        let verts = [0, 5, n / 2, n - 2];
        let h = diffusion_embeddings(&rk, &verts, t).unwrap();
        // S_t(i,j) = Σ_m e^{−λ_m t} (Bx_m)_i (Bx_m)_j.
        let bx: Vec<Vec<f64>> = (0..n).map(|m| matvec(&ops.mass, &col(x, m))).collect();
        for (a, &i) in verts.iter().enumerate() {
            for (b, &j) in verts.iter().enumerate() {
                let s: f64 = (0..n).map(|m| (-t * basis.values[m]).exp() * bx[m][i] * bx[m][j]).sum();
                let got = wfem(&ops).mass_inner_product(&col(&h, a), &col(&h, b)).unwrap();
                let scale = (ops.mass.val().iter().fold(0.0f64, |u, v| u.max(v.abs()))).max(s.abs());
                assert!((got - s).abs() < 1e-12 * scale, "{name} S({i},{j}): {got} vs {s}");
            }
        }
        // H_t(i,j) = Σ_m e^{+λ_m t} x_m(i) x_m(j), truncated to k and with the full basis at a
        // small t.
        for (basis_k, tt) in [(truncate(&basis, 30), t), (basis.clone(), 2e-3)] {
            let k = basis_k.values.len();
            let g: Vec<Vec<f64>> = verts
                .iter()
                .map(|&i| reproducing_embedding(&basis_k, &wfem(&ops), i, tt).unwrap().0)
                .collect();
            for (a, &i) in verts.iter().enumerate() {
                for (b, &j) in verts.iter().enumerate() {
                    let hij: f64 = (0..k)
                        .map(|m| (tt * basis.values[m]).exp() * x[(i, m)] * x[(j, m)])
                        .sum();
                    let got = wfem(&ops).mass_inner_product(&g[a], &g[b]).unwrap();
                    let hii: f64 = (0..k).map(|m| (tt * basis.values[m]).exp() * x[(i, m)].powi(2)).sum();
                    assert!(
                        (got - hij).abs() < 1e-10 * hii,
                        "{name} k={k} H({i},{j}): {got} vs {hij}"
                    );
                }
            }
        }
    }
}

#[test]
fn errors_are_typed() {
    let (_, ops) = ops_of(&generate::icosphere(1));
    let n = ops.stiffness.nrows();
    let basis = dense(&ops);
    let rk = rational(&ops);
    assert!(matches!(
        wfem(&ops).mass_inner_product(&vec![1.0; n - 1], &vec![1.0; n]),
        Err(HeatError::LengthMismatch { .. })
    ));
    let mut bad = vec![1.0; n];
    bad[2] = f64::NAN;
    assert!(matches!(
        heat_inner_product(&rk, &bad, &vec![1.0; n], 0.1),
        Err(HeatError::NonFiniteInput { row: 2, .. })
    ));
    assert!(matches!(
        diffusion_embeddings(&rk, &[0, n], 0.1),
        Err(HeatError::VertexOutOfRange { index, .. }) if index == n
    ));
    assert!(matches!(
        reproducing_embedding(&basis, &wfem(&ops), n + 3, 0.1),
        Err(HeatError::VertexOutOfRange { .. })
    ));
    assert!(matches!(
        inverse_spectral(&basis, &wfem(&ops), &vec![1.0; n], -1.0),
        Err(HeatError::InvalidTime { .. })
    ));
    // A zero right-hand side has the zero inverse.
    let (g, rep) = inverse_cg(&rk, &vec![0.0; n], 0.1, &InverseParams::default()).unwrap();
    assert!(g.iter().all(|&v| v == 0.0) && rep.iterations == 0);
}

/// Issue #16: `inverse_cg` with its default options inverts K_t on a smooth field with the
/// default kernel (it refused one before: the stopping tolerance sat below what K_t is
/// evaluated to).
#[test]
fn issue_16_inverse_cg_default_on_a_smooth_field() {
    for (name, ops) in small_meshes() {
        let n = ops.n();
        let kernel = HeatKernel::new(&ops, HeatParams::default()).unwrap();
        let dense = dense(&ops);
        // A smooth field: the first 6 eigenfunctions with decaying weights.
        let f: Vec<f64> = (0..n)
            .map(|i| (1..7).map(|k| dense.vectors[(i, k)] / k as f64).sum())
            .collect();
        for t in [1e-3, 1e-2, 0.1] {
            let (g, report) =
                inverse_cg(&kernel, &f, t, &InverseParams::default()).unwrap_or_else(|e| panic!("{name} t = {t}: {e}"));
            let back = kernel.apply(&g, t).unwrap();
            let err = wfem(&ops)
                .mass_norm(&back.iter().zip(&f).map(|(a, b)| a - b).collect::<Vec<_>>())
                .unwrap()
                / wfem(&ops).mass_norm(&f).unwrap();
            assert!(err < 1e-8, "{name} t = {t}: {err:e} ({report:?})");
        }
    }
}
