//! Identities of the heat kernel `K_t = X D_t Xᵀ M` (paper, Eq. (6)) checked on the dense
//! reference and on the fast path, plus the real-mesh check.
use crate::common;
use common::*;
use mesh_fem::Mass;
use wfem_heat::method::Method;
use wfem_heat::{HeatKernel, HeatParams};

fn kernels(ops: &mesh_fem::FemOperators, kind: Mass) -> Vec<(&'static str, HeatKernel)> {
    vec![
        (
            "dense",
            HeatKernel::new(
                ops,
                HeatParams {
                    mass: kind,
                    method: Method::Dense,
                },
            )
            .unwrap(),
        ),
        (
            "fast",
            HeatKernel::new(
                ops,
                HeatParams {
                    mass: kind,
                    method: Method::rational(shifted_solve::poles::DEFAULT_DEGREE),
                },
            )
            .unwrap(),
        ),
    ]
}

/// Mass conservation 1ᵀM K_t f = 1ᵀM f, constants are fixed (K_t 1 = 1, since L1 = 0), and
/// M-self-adjointness fᵀM K_t g = gᵀM K_t f (M K_t = X⁻ᵀ D_t X⁻¹ is symmetric).
#[test]
fn conservation_constants_and_self_adjointness() {
    for (name, mesh, ops) in meshes() {
        let n = ops.n();
        let f = x_coordinate(&mesh);
        let g: Vec<f64> = mesh
            .positions()
            .iter()
            .map(|p| (3.0 * p[1]).sin() + p[2] * p[2])
            .collect();
        let ones = vec![1.0; n];
        for kind in [Mass::Consistent, Mass::Lumped(Default::default()), Mass::Identity] {
            for (method, k) in kernels(&ops, kind) {
                let m = k.mass();
                for t in [1e-3, 1e-1, 2.0] {
                    let kf = k.apply(&f, t).unwrap();
                    let kg = k.apply(&g, t).unwrap();
                    let m1 = matvec(m, &ones);
                    let (before, after) = (dot(&m1, &f), dot(&m1, &kf));
                    let scale = dot(&m1, &f.iter().map(|x| x.abs()).collect::<Vec<_>>());
                    assert!(
                        (before - after).abs() <= 1e-11 * scale,
                        "{name} {kind:?} {method} t={t}: mass {before} → {after}"
                    );
                    let k1 = k.apply(&ones, t).unwrap();
                    let dev = k1.iter().map(|x| (x - 1.0).abs()).fold(0.0, f64::max);
                    assert!(dev < 1e-11, "{name} {kind:?} {method} t={t}: K_t 1 off by {dev:e}");
                    let a = dot(&f, &matvec(m, &kg));
                    let b = dot(&g, &matvec(m, &kf));
                    // Both sides are sums of n products of size ≈ ‖f‖‖Mg‖/n; compare at that scale.
                    let tol = 1e-12 * norm(&f) * norm(&matvec(m, &g));
                    assert!((a - b).abs() <= tol, "{name} {kind:?} {method} t={t}: {a} vs {b}");
                }
            }
        }
    }
}

/// Long-time limit (paper, Sect. 4.1). From Eq. (6) with the constant eigenvector
/// x₁ = 1/√A (λ₁ = 0, A = 1ᵀM1), K_t e_i → x₁x₁ᵀM e_i = ((1ᵀM e_i)/A)·1 as t → ∞, the
/// M-weighted mean of e_i. (The paper writes (e_iᵀB1)·1, which is this formula for unit
/// area; for B this equals D_ii/A with D the barycentric lumped mass.)
#[test]
fn long_time_limit_is_the_mean() {
    for (name, _, ops) in meshes() {
        let n = ops.n();
        for kind in [Mass::Consistent, Mass::Lumped(Default::default()), Mass::Identity] {
            for (method, k) in kernels(&ops, kind) {
                let i = n / 2;
                let e = unit(n, i);
                let m1 = matvec(k.mass(), &vec![1.0; n]);
                let area: f64 = m1.iter().sum();
                let expected = m1[i] / area;
                // λ₂ ≥ 0.7 on these meshes of area 4π, so e^{−60λ₂} < 1e−18. The linear
                // kernel (M = I) runs on the time scale of L itself, whose eigenvalues are
                // smaller by the area per vertex A/n: stretch t by n/A.
                let t = if kind == Mass::Identity {
                    60.0 * n as f64 / ops.area()
                } else {
                    60.0
                };
                let g = k.apply(&e, t).unwrap();
                let dev = g.iter().map(|x| (x - expected).abs()).fold(0.0, f64::max);
                assert!(
                    dev <= 1e-10 * expected,
                    "{name} {kind:?} {method}: {dev:e} vs {expected:e}"
                );
            }
        }
    }
}

/// On a real mesh (Spot), the fast path matches the dense reference for K_t e_i.
#[test]
fn fast_path_on_real_mesh() {
    let Some((mesh, ops)) = spot() else { return };
    let dense = HeatKernel::new(
        &ops,
        HeatParams {
            mass: Mass::Consistent,
            method: Method::Dense,
        },
    )
    .unwrap();
    let fast = HeatKernel::new(&ops, HeatParams::default()).unwrap();
    let f = x_coordinate(&mesh);
    let e = unit(ops.n(), 7);
    for t in [1e-4, 1e-2, 1.0] {
        for v in [&f, &e] {
            let err = rel_err(&fast.apply(v, t).unwrap(), &dense.apply(v, t).unwrap());
            assert!(err < 1e-10, "t = {t}: {err:e}");
        }
    }
}

/// apply_many equals column-by-column apply, and the one-shot `heat` equals the default
/// kernel.
#[test]
fn apply_many_and_one_shot_agree_with_apply() {
    let (_, mesh, ops) = meshes().remove(1);
    let n = ops.n();
    let f = x_coordinate(&mesh);
    let e = unit(n, 5);
    let kernel = HeatKernel::new(&ops, HeatParams::default()).unwrap();
    let mut cols = faer::Mat::<f64>::zeros(n, 2);
    for i in 0..n {
        cols[(i, 0)] = f[i];
        cols[(i, 1)] = e[i];
    }
    let many = kernel.apply_many(cols.as_ref(), 0.05).unwrap();
    for (c, v) in [(0, &f), (1, &e)] {
        let single = kernel.apply(v, 0.05).unwrap();
        let col: Vec<f64> = many.col(c).iter().copied().collect();
        // Several right-hand sides go through blocked (GEMM) triangular solves, one through
        // GEMV: same arithmetic, different summation order, so agreement is to rounding level.
        let err = rel_err(&col, &single);
        assert!(err < 1e-13, "column {c}: {err:e}");
    }
    let one_shot = wfem_heat::heat(&ops, &f, 0.05).unwrap();
    assert!(rel_err(&one_shot, &kernel.apply(&f, 0.05).unwrap()) < 1e-14);
}

/// For every method, apply_many on two columns equals apply on each column.
#[test]
fn apply_many_matches_apply_for_every_method() {
    let (_, mesh, ops) = meshes().remove(2);
    let n = ops.n();
    let f = x_coordinate(&mesh);
    let e = unit(n, 11);
    let mut cols = faer::Mat::<f64>::zeros(n, 2);
    for i in 0..n {
        cols[(i, 0)] = f[i];
        cols[(i, 1)] = e[i];
    }
    let methods = [
        Method::Dense,
        Method::Spectral {
            k: 20,
            eigen: Default::default(),
        },
        Method::Taylor,
        Method::BackwardEuler,
        Method::rational(shifted_solve::poles::DEFAULT_DEGREE),
    ];
    for method in methods {
        let k = HeatKernel::new(
            &ops,
            HeatParams {
                mass: Mass::Consistent,
                method: method.clone(),
            },
        )
        .unwrap();
        let many = k.apply_many(cols.as_ref(), 0.02).unwrap();
        for (c, v) in [(0, &f), (1, &e)] {
            let single = k.apply(v, 0.02).unwrap();
            let col: Vec<f64> = many.col(c).iter().copied().collect();
            assert!(rel_err(&col, &single) < 1e-13, "{method:?} column {c}");
        }
    }
}

/// The per-t factor cache never serves a stale factor: alternating times give the same
/// results as fresh kernels.
#[test]
fn factor_cache_follows_t() {
    let (_, mesh, ops) = meshes().remove(0);
    let f = x_coordinate(&mesh);
    for method in [
        Method::BackwardEuler,
        Method::rational(shifted_solve::poles::DEFAULT_DEGREE),
    ] {
        let params = HeatParams {
            mass: Mass::Consistent,
            method,
        };
        let k = HeatKernel::new(&ops, params.clone()).unwrap();
        for t in [0.1, 0.01, 0.1, 0.1, 1.0, 0.01] {
            let fresh = HeatKernel::new(&ops, params.clone()).unwrap().apply(&f, t).unwrap();
            // A stale factor would be off by O(1); parallel factorization may reorder sums.
            assert!(rel_err(&k.apply(&f, t).unwrap(), &fresh) < 1e-13, "t = {t}");
        }
    }
}
