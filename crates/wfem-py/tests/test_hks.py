"""HKS (both conventions), SI-HKS, DHK1–3 and the eigenbasis against a dense scipy reference."""

from __future__ import annotations

import numpy as np
import pytest

import wfem
from conftest import dense_eigh


def hks_ref(lam, X, M, times, convention="kernel-value", k=None):
    k = len(lam) if k is None else k
    lam, X = lam[:k], X[:, :k]
    Y = X if wfem.choices()["convention"]["default"] == wfem._wfem.canonical("convention", convention) else M @ X
    return np.column_stack([(X * Y) @ np.exp(-lam * t) for t in times])


@pytest.mark.parametrize("convention", wfem.HKS_CONVENTIONS)
def test_hks_with_all_eigenpairs_equals_dense_truth(mesh, convention):
    V, F = mesh
    L, B, _ = wfem.operators(V, F)
    lam, X = dense_eigh(L, B)
    times = [1e-3, 1e-2, 0.1, 1.0]
    h = wfem.hks(V, F, times, k=len(V), convention=convention)
    ref = hks_ref(lam, X, B, times, convention)
    assert h.shape == (len(V), len(times))
    assert np.max(np.abs(h - ref)) <= 1e-10 * np.max(np.abs(ref))
    # k = None: the dense decomposition.
    basis = wfem.eigenbasis(V, F, None)
    h2 = wfem.hks(V, F, times, basis=basis, convention=convention)
    assert np.max(np.abs(h2 - ref)) <= 1e-10 * np.max(np.abs(ref))


def test_exact_hks_from_the_kernel_matrix_equals_dense_truth():
    # Without any eigenpair: diag(H_t) = diag(K_t B⁻¹) column by column.
    V, F = wfem.generate.irregular_sphere(2, 3.0)
    L, B, _ = wfem.operators(V, F)
    lam, X = dense_eigh(L, B)
    K = wfem.HeatKernel(V, F)
    t = 1e-3
    H = K.apply_kernel_matrix(np.eye(len(V)), t)
    ref = hks_ref(lam, X, B, [t])[:, 0]
    assert np.max(np.abs(np.diag(H) - ref)) <= 1e-10 * np.max(ref)


def test_truncated_hks_equals_truncated_dense_sum():
    V, F = wfem.generate.bumpy(2)  # no symmetry: no eigenvalue multiplet cut by the truncation
    L, B, _ = wfem.operators(V, F)
    lam, X = dense_eigh(L, B)
    k = 30
    h, times = wfem.hks(V, F, k=k, num_times=8, return_times=True, method="spectral")
    assert len(times) == 8 and np.all(np.diff(times) > 0)
    ref = hks_ref(lam, X, B, times, k=k)
    assert np.max(np.abs(h - ref)) <= 1e-8 * np.max(np.abs(ref))
    scaled = wfem.hks(V, F, times, k=k, scaled=True)
    trace = np.exp(-np.outer(lam[:k], times)).sum(axis=0)
    np.testing.assert_allclose(scaled, ref / trace, rtol=1e-8)


@pytest.mark.parametrize("convention", wfem.HKS_CONVENTIONS)
def test_default_auto_hks_is_the_full_hks_where_truncation_fails(convention):
    # 30 eigenpairs are far off at t = 1e-3; the default replaces those columns by the exact
    # diagonal and keeps the truncated sum where its bound holds.
    V, F = wfem.generate.bumpy(2)
    L, B, _ = wfem.operators(V, F)
    lam, X = dense_eigh(L, B)
    times = [1e-3, 1e-2, 0.1, 1.0]
    full = hks_ref(lam, X, B, times, convention)
    truncated = wfem.hks(V, F, times, k=30, convention=convention, method="spectral")
    assert np.max(np.abs(truncated - full)) > 0.05 * np.max(np.abs(full))
    h = wfem.hks(V, F, times, k=30, convention=convention)
    assert np.max(np.abs(h - full)) <= 1e-3 * np.max(np.abs(full))
    with pytest.raises(wfem.InvalidInputError):
        wfem.hks(V, F, times, k=30, method="best")


def test_eigenbasis_is_b_orthonormal_and_projects():
    V, F = wfem.generate.bumpy(2)
    L, B, _ = wfem.operators(V, F)
    lam, _ = dense_eigh(L, B)
    basis = wfem.eigenbasis(V, F, 20)
    assert len(basis) == 20
    np.testing.assert_allclose(basis.values, lam[:20], rtol=1e-9, atol=1e-12)
    X = basis.vectors
    np.testing.assert_allclose(X.T @ B @ X, np.eye(20), atol=1e-10)
    f = X @ np.arange(20.0)
    np.testing.assert_allclose(basis.project(f), np.arange(20.0), atol=1e-9)
    np.testing.assert_allclose(basis.reconstruct(basis.project(f)), f, atol=1e-9)
    np.testing.assert_allclose(basis.heat(f, 0.1), X @ (np.exp(-0.1 * basis.values) * np.arange(20.0)), atol=1e-9)
    g, report = basis.inverse_heat(basis.heat(f, 0.1), 0.1)
    np.testing.assert_allclose(g, f, atol=1e-8)
    assert report["relative_dropped"] < 1e-8
    Lb, Bb = wfem.operators(V, F)[:2]
    other = wfem.Eigenbasis.from_operators(Lb, Bb, 20)
    np.testing.assert_allclose(other.values, basis.values, rtol=1e-12)


def test_descriptors_equal_dense_formulas():
    V, F = wfem.generate.irregular_sphere(2, 2.0)
    L, B, _ = wfem.operators(V, F)
    _, _, Dv = wfem.operators(V, F, lumped="voronoi")
    times = [0.01, 0.1, 1.0]
    k = 20
    d = wfem.descriptors(V, F, ["dhk1", "dhk2", "dhk3", "sihks"], k=k, times=times)
    lam, X = dense_eigh(L, B)
    np.testing.assert_allclose(d["dhk2"], hks_ref(lam, X, B, times, k=k), rtol=1e-8)
    lamd, Xd = dense_eigh(L, Dv)
    np.testing.assert_allclose(d["dhk1"], hks_ref(lamd, Xd, Dv, times, k=k), rtol=1e-8)
    lmax = lam[k - 1]
    np.testing.assert_allclose(d["dhk3"], hks_ref(lam / lmax, X, B, times, k=k) / lmax, rtol=1e-8)
    assert d["sihks"].shape == (len(V), 8) and np.isfinite(d["sihks"]).all()


def test_sihks_is_scale_invariant():
    V, F = wfem.generate.bumpy(2)
    opts = dict(k=60, time_unit=1e-3, tau_min=0.0, tau_max=20.0)
    a = wfem.sihks(V, F, **opts)
    b = wfem.sihks(V * 2.0, F, **opts)
    assert np.median(np.abs(a - b) / np.abs(a).max(axis=1, keepdims=True)) < 0.05


def test_sparse_features():
    V, F = wfem.generate.bumpy(3)
    shk1, t = wfem.sparse_features(V, F, "shk1", k=40, return_time=True)
    shk2 = wfem.sparse_features(V, F, "shk2", k=40)
    assert t > 0 and len(shk1) >= len(shk2) >= 1
    assert set(shk2.tolist()) <= set(shk1.tolist())


@pytest.mark.parametrize("convention", wfem.HKS_CONVENTIONS)
def test_exact_hks_without_eigenpairs_equals_dense_truth(convention):
    V, F = wfem.generate.irregular_sphere(3, 2.0)  # 642 vertices
    L, B, _ = wfem.operators(V, F)
    lam, X = dense_eigh(L, B)
    times = [1e-4, 1e-3, 1e-2]
    h = wfem.hks(V, F, times, method="exact", convention=convention)
    ref = hks_ref(lam, X, B, times, convention)
    assert np.max(np.abs(h - ref) / np.abs(ref)) <= 1e-8
    values, info = wfem.HeatKernel(V, F).diagonal(times, convention, return_info=True)
    np.testing.assert_array_equal(values, h)
    assert info["probe_columns"] == 0  # selected inversion: no probe columns
    for method in ("probing", "unit-columns"):
        other, info = wfem.HeatKernel(V, F).diagonal(times, convention, method=method, return_info=True)
        assert np.max(np.abs(other - ref) / np.abs(ref)) <= 1e-8
        assert 0 < info["probe_columns"] <= len(V)
    with pytest.raises(wfem.InvalidInputError, match="selected-inversion"):
        wfem.HeatKernel(V, F).diagonal(times, method="eigen")
    # Exact values at the automatic times (chosen from 60 eigenpairs), as `wfem hks --method exact`.
    h, ts = wfem.hks(V, F, method="exact", k=60, return_times=True, convention=convention)
    ref = hks_ref(lam, X, B, ts, convention)
    assert len(ts) == wfem._wfem.DEFAULT_NUM_TIMES
    assert np.max(np.abs(h - ref) / np.abs(ref)) <= 1e-8


def test_apply_times_matches_apply():
    V, F = wfem.generate.bumpy(2)
    K = wfem.HeatKernel(V, F)
    f = V[:, 0]
    ts = [1e-3, 1e-2, 1e-1]
    values, estimates = K.apply_times(f, ts)
    assert values.shape == (3, len(V)) and len(estimates) == 3
    for j, t in enumerate(ts):
        assert np.max(np.abs(values[j] - K.apply(f, t))) <= 1e-10 * np.max(np.abs(f))
