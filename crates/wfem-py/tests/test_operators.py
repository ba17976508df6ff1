"""wfem.operators against libigl (sign flipped: L = −igl.cotmatrix) and basic identities."""

from __future__ import annotations

import igl
import numpy as np
import pytest
import scipy.sparse as sp

import wfem


def _rel_diff(a, b) -> float:
    a, b = sp.csc_matrix(a), sp.csc_matrix(b)
    return abs(a - b).max() / max(abs(b).max(), 1e-300)


def test_operators_equal_igl_to_1e12(mesh):
    V, F = mesh
    L, B, D = wfem.operators(V, F)
    for m in (L, B, D):
        assert isinstance(m, sp.csc_matrix) and m.dtype == np.float64 and m.shape == (len(V), len(V))
    assert _rel_diff(L, -igl.cotmatrix(V, F)) <= 1e-12
    assert _rel_diff(B, igl.massmatrix(V, F, igl.MASSMATRIX_TYPE_FULL)) <= 1e-12
    assert _rel_diff(D, igl.massmatrix(V, F, igl.MASSMATRIX_TYPE_BARYCENTRIC)) <= 1e-12
    _, _, Dv = wfem.operators(V, F, lumped="voronoi")
    assert _rel_diff(Dv, igl.massmatrix(V, F, igl.MASSMATRIX_TYPE_VORONOI)) <= 1e-12


def test_operator_identities(mesh):
    V, F = mesh
    L, B, D = wfem.operators(V, F)
    n = len(V)
    assert abs(L @ np.ones(n)).max() <= 1e-12 * abs(L).max()
    assert (L.diagonal() > 0).all()  # positive semidefinite: positive diagonal
    assert abs(L - L.T).max() == 0 and abs(B - B.T).max() == 0
    np.testing.assert_allclose(np.asarray(B.sum(axis=1)).ravel(), D.diagonal(), rtol=1e-13)
    assert min(np.linalg.eigvalsh(L.toarray())) > -1e-10 * abs(L).max()


def test_heat_kernel_exposes_the_same_operators(mesh):
    V, F = mesh
    L, B, _ = wfem.operators(V, F)
    K = wfem.HeatKernel(V, F)
    assert _rel_diff(K.stiffness, L) == 0
    assert _rel_diff(K.mass, B) == 0
    np.testing.assert_allclose(K.vertex_areas, np.asarray(B.sum(axis=1)).ravel(), rtol=1e-14)


def test_real_mesh_operators_equal_igl(corpus):
    path = corpus / "tosca-bcicp-5k" / "TOSCA_Isometric" / "cat0.off"
    if not path.exists():
        pytest.skip(f"{path} is absent")
    V, F = wfem.read_mesh(path)
    Vi, Fi = igl.read_triangle_mesh(str(path))
    np.testing.assert_array_equal(V, Vi)
    np.testing.assert_array_equal(F, Fi)
    L, B, _ = wfem.operators(V, F)
    assert _rel_diff(L, -igl.cotmatrix(V, F)) <= 1e-12
    assert _rel_diff(B, igl.massmatrix(V, F, igl.MASSMATRIX_TYPE_FULL)) <= 1e-12
