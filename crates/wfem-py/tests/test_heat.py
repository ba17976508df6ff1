"""K_t f against a dense scipy.linalg.eigh(L, B) reference, shapes of apply, from_operators."""

from __future__ import annotations

import igl
import numpy as np
import pytest
import robust_laplacian

import wfem
from conftest import dense_eigh


def reference(L, M, f, t):
    lam, X = dense_eigh(L, M)
    return X @ (np.exp(-lam * t)[:, None] * (X.T @ (M @ f).reshape(len(lam), -1)))


def functions(V):
    rng = np.random.default_rng(7)
    return np.column_stack([V[:, 0], V[:, 1] * V[:, 2], rng.standard_normal(len(V))])


# Up to 1e4 / λ_max on purpose: past the time at infinity the result must still be right.
@pytest.mark.filterwarnings("ignore::wfem.TimeWarning")
@pytest.mark.parametrize("kernel", ["wfem", "lumped", "linear"])
def test_apply_equals_dense_eigh_to_1e10(mesh, kernel):
    V, F = mesh
    L, B, D = wfem.operators(V, F)
    M = {"wfem": B, "lumped": D, "linear": None}[kernel]
    if M is None:
        import scipy.sparse as sp

        M = sp.identity(len(V), format="csc")
    K = wfem.HeatKernel(V, F, mass=kernel)
    f = functions(V)
    scale = 1.0 / max(np.linalg.eigvalsh(L.toarray())[-1], 1e-300)
    for t in (1e-3 * scale, scale, 100 * scale, 1e4 * scale):
        g = K.apply(f, t)
        ref = reference(L, M, f, t)
        assert np.max(np.abs(g - ref)) <= 1e-10 * np.max(np.abs(f)), (kernel, t)


@pytest.mark.parametrize("method,options", [("rational", {}), ("rational", {"backend": "lu"}), ("dense", {}),
                                            ("rational", {"backend": "multishift"})])
def test_other_exact_methods_agree(method, options):
    V, F = wfem.generate.irregular_sphere(2, 3.0)
    L, B, _ = wfem.operators(V, F)
    f = functions(V)[:, 0]
    K = wfem.HeatKernel(V, F, method=method, **options)
    assert K.method == method
    for t in (1e-3, 0.1):
        assert np.max(np.abs(K.apply(f, t) - reference(L, B, f, t)[:, 0])) <= 1e-10 * np.max(np.abs(f))


def test_apply_shapes_and_many_times():
    V, F = wfem.generate.icosphere(2)
    K = wfem.HeatKernel(V, F)
    n = len(V)
    f = V[:, 0].copy()
    F3 = functions(V)
    assert K.apply(f, 0.1).shape == (n,)
    assert K.apply(F3, 0.1).shape == (n, 3)
    ts = np.array([0.01, 0.1, 1.0])
    many = K.apply(F3, ts)
    assert many.shape == (3, n, 3)
    for j, t in enumerate(ts):
        np.testing.assert_array_equal(many[j], K.apply(F3, t))
    assert K.apply(f, [0.5]).shape == (1, n)
    # Columns are independent: applying to a block equals column by column.
    for c in range(3):
        np.testing.assert_allclose(K.apply(F3, 0.1)[:, c], K.apply(F3[:, c], 0.1), rtol=0, atol=1e-13)


def test_semigroup_and_mass_conservation(mesh):
    V, F = mesh
    K = wfem.HeatKernel(V, F)
    f = functions(V)[:, 2]
    a = K.apply(K.apply(f, 0.02), 0.03)
    b = K.apply(f, 0.05)
    assert np.max(np.abs(a - b)) <= 1e-10 * np.max(np.abs(f))
    area = K.vertex_areas
    assert abs(area @ K.apply(f, 10.0) - area @ f) <= 1e-11 * np.abs(area @ np.abs(f))


def test_from_operators_robust_laplacian_matches_dense():
    V, F = wfem.generate.bumpy(2)
    L, M = robust_laplacian.mesh_laplacian(V, F)
    K = wfem.HeatKernel.from_operators(L, M)
    assert K.kernel == "custom"
    f = V[:, 2]
    for t in (1e-3, 0.1):
        assert np.max(np.abs(K.apply(f, t) - reference(L, M, f, t)[:, 0])) <= 1e-10 * np.max(np.abs(f))


def test_from_operators_refuses_igl_sign_with_a_hint():
    V, F = wfem.generate.icosphere(1)
    with pytest.raises(wfem.InvalidInputError) as e:
        wfem.HeatKernel.from_operators(igl.cotmatrix(V, F), igl.massmatrix(V, F, igl.MASSMATRIX_TYPE_FULL))
    assert e.value.kind == "InvalidOperatorEntry"
    assert e.value.matrix.startswith("stiffness")
    # The negated matrix is accepted.
    K = wfem.HeatKernel.from_operators(-igl.cotmatrix(V, F), igl.massmatrix(V, F, igl.MASSMATRIX_TYPE_FULL))
    assert K.n == len(V)


def test_kernel_matrix_inner_products_embeddings():
    V, F = wfem.generate.icosphere(2)
    L, B, _ = wfem.operators(V, F)
    lam, X = dense_eigh(L, B)
    K = wfem.HeatKernel(V, F)
    t = 0.05
    Ht = X @ np.diag(np.exp(-lam * t)) @ X.T
    G = np.eye(len(V))[:, [0, 5]]
    np.testing.assert_allclose(K.apply_kernel_matrix(G, t), Ht @ G, atol=1e-11 * abs(Ht).max())
    f, g = V[:, 0], V[:, 1] ** 2
    assert abs(K.inner_product(f, g) - f @ B @ g) <= 1e-14 * abs(f) @ abs(B) @ abs(g)
    St = B @ Ht @ B
    assert abs(K.heat_inner_product(f, g, t) - f @ St @ g) <= 1e-10 * np.linalg.norm(f) * np.linalg.norm(g)
    E = K.diffusion_embedding([3, 7], t)
    ref = X @ np.diag(np.exp(-lam * t / 2)) @ X.T @ B
    np.testing.assert_allclose(E, ref[:, [3, 7]], atol=1e-11)
    C = K.canonical_basis([1, 2, 3], t)
    np.testing.assert_allclose(C, (X @ np.diag(np.exp(-lam * t)) @ X.T @ B)[:, [1, 2, 3]], atol=1e-11)
    lim = K.canonical_limit([1, 2])
    np.testing.assert_allclose(K.canonical_basis([1, 2], 1e6), np.tile(lim, (len(V), 1)), rtol=1e-8)


def test_diffusion_distances_match_dense():
    V, F = wfem.generate.icosphere(2)
    L, B, _ = wfem.operators(V, F)
    lam, X = dense_eigh(L, B)
    K = wfem.HeatKernel(V, F)
    t = 0.05
    A = X @ np.diag(np.exp(-2 * lam * t)) @ X.T  # H_{2t}
    d = K.distance(t)
    row = d.row(4)
    ref = np.sqrt(np.maximum(A[4, 4] - 2 * A[4] + np.diag(A), 0))
    np.testing.assert_allclose(row, ref, atol=1e-8 * ref.max())
    pairs = d.pairs([[0, 1], [4, 100]])
    np.testing.assert_allclose(pairs, [ref_pair(A, 0, 1), ref_pair(A, 4, 100)], rtol=1e-8)
    assert d.rows([4, 5]).shape == (2, len(V))
    S = B @ X @ np.diag(np.exp(-lam * t)) @ X.T @ B
    mw = K.distance(t, "mass-weighted", diagonal="columns").pairs([[2, 9]])
    np.testing.assert_allclose(mw, [ref_pair(S, 2, 9)], rtol=1e-8)


def ref_pair(A, i, j):
    return np.sqrt(A[i, i] - 2 * A[i, j] + A[j, j])


def test_inverse_and_largest_eigenvalue():
    V, F = wfem.generate.icosphere(2)
    L, B, _ = wfem.operators(V, F)
    lam, X = dense_eigh(L, B)
    K = wfem.HeatKernel(V, F)
    f = X[:, 1] + 0.5 * X[:, 4]  # band-limited
    g, report = K.inverse(f, 0.1)
    np.testing.assert_allclose(K.apply(g, 0.1), f, atol=1e-8)
    assert report["amplification"] >= 1
    assert abs(K.largest_eigenvalue() - lam[-1]) <= 1e-8 * lam[-1]


def test_feature_approximation_runs_and_reports():
    V, F = wfem.generate.bumpy(2)
    K = wfem.HeatKernel(V, F)
    f = V[:, 2] + 0.3 * np.sin(4 * V[:, 0])
    out = K.feature_approximation(f, k=10, scales=3)
    assert len(out["scales"]) == 3
    for s in out["scales"]:
        np.testing.assert_allclose(s["global_"] + s["local"], f, atol=1e-12)
    assert all(0 <= a < len(V) for a in out["anchors"])
    with pytest.raises(wfem.InvalidInputError):
        wfem.HeatKernel.from_operators(*wfem.operators(V, F)[:2]).feature_approximation(f)
