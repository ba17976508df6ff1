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


def _cube_tets(m: int):
    """The unit cube in m³ cells, six tetrahedra each (Kuhn), positively oriented."""
    g = np.linspace(0.0, 1.0, m + 1)
    V = np.stack(np.meshgrid(g, g, g, indexing="ij"), axis=-1).reshape(-1, 3)
    idx = lambda i, j, k: (i * (m + 1) + j) * (m + 1) + k
    T = []
    paths = [(0, 1, 2), (0, 2, 1), (1, 0, 2), (1, 2, 0), (2, 0, 1), (2, 1, 0)]
    for i in range(m):
        for j in range(m):
            for k in range(m):
                for p in paths:
                    c = [i, j, k]
                    tet = [idx(*c)]
                    for axis in p:
                        c[axis] += 1
                        tet.append(idx(*c))
                    T.append(tet)
    T = np.array(T, dtype=np.int64)
    a, b, c, d = (V[T[:, q]] for q in range(4))
    flip = np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a) < 0
    T[flip, 2], T[flip, 3] = T[flip, 3], T[flip, 2].copy()
    return V, T


@pytest.mark.parametrize("volume", [False, True])
def test_operators_are_canonical_csc_with_int32_indices(volume):
    # The index arrays come out int32 (what scipy keeps for such sizes: no conversion pass) and
    # the matrices are canonical CSC equal to the same matrices built from COO triplets.
    if volume:
        V, T = _cube_tets(3)
        mats = wfem.operators(V, T)
        assert abs(mats[1].sum() - 1.0) < 1e-14  # the consistent mass integrates to the volume
    else:
        V, F = wfem.generate.bumpy(2)
        mats = wfem.operators(V, F)
    for M in mats:
        assert M.format == "csc"
        assert M.indices.dtype == np.int32 and M.indptr.dtype == np.int32
        assert M.has_canonical_format
        again = sp.csc_matrix(sp.coo_matrix(M.toarray()))
        assert abs(M - again).max() == 0.0
