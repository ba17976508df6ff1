"""Inputs: Fortran order, strides, float32/int32 and friends are converted; other dtypes are
refused clearly; inputs are never modified; objects with .vertices/.faces are accepted."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

import wfem


@pytest.fixture(scope="module")
def sphere():
    return wfem.generate.icosphere(2)


def _same_operators(V, F, V2, F2):
    for a, b in zip(wfem.operators(V, F), wfem.operators(V2, F2)):
        assert abs(a - b).max() == 0


def test_fortran_and_non_contiguous(sphere):
    V, F = sphere
    _same_operators(V, F, np.asfortranarray(V), np.asfortranarray(F))
    big = np.zeros((len(V), 7))
    big[:, ::3][:, :3] = V  # columns 0, 3, 6
    Vs = big[:, ::3]
    assert not Vs.flags.c_contiguous
    Fbig = np.zeros((len(F), 6), dtype=np.int64)
    Fbig[:, ::2] = F
    Fs = Fbig[:, ::2]
    assert not Fs.flags.c_contiguous
    _same_operators(V, F, Vs, Fs)
    K = wfem.HeatKernel(V, F)
    f = np.asfortranarray(np.column_stack([V[:, 0], V[:, 1]]))
    np.testing.assert_array_equal(K.apply(f, 0.1), K.apply(np.ascontiguousarray(f), 0.1))
    strided = np.repeat(V[:, 0], 2)[::2]
    np.testing.assert_array_equal(K.apply(strided, 0.1), K.apply(V[:, 0].copy(), 0.1))


def test_float32_and_small_ints_are_converted(sphere):
    V, F = sphere
    V32 = V.astype(np.float32)
    L32 = wfem.operators(V32, F.astype(np.int32))[0]
    L64 = wfem.operators(V32.astype(np.float64), F)[0]
    assert abs(L32 - L64).max() == 0
    for dt in (np.int32, np.uint32, np.int16, np.uint64):
        _same_operators(V, F, V, F.astype(dt))
    K = wfem.HeatKernel(V, F)
    np.testing.assert_array_equal(K.apply(V[:, 0].astype(np.float32), 0.1), K.apply(V[:, 0].astype(np.float32).astype(np.float64), 0.1))
    np.testing.assert_array_equal(K.apply(np.arange(K.n), 0.1), K.apply(np.arange(K.n, dtype=float), 0.1))


def test_refused_dtypes_and_shapes(sphere):
    V, F = sphere
    with pytest.raises(wfem.InvalidInputError, match="integer"):
        wfem.operators(V, F.astype(np.float64))
    with pytest.raises(wfem.InvalidInputError):
        wfem.operators(V.astype(np.complex128), F)
    with pytest.raises(wfem.InvalidInputError):
        wfem.operators(V > 0, F)
    with pytest.raises(wfem.InvalidInputError, match=r"\(n, 3\)"):
        wfem.operators(V[:, :2], F)
    with pytest.raises(wfem.InvalidInputError, match="triangles"):
        wfem.operators(V, np.column_stack([F, F, F[:, :1]]))
    # Four columns are tetrahedra (issue #39): these repeat a vertex, so they are flat.
    with pytest.raises(wfem.MeshError, match="zero volume"):
        wfem.operators(V, np.column_stack([F, F[:, :1]]))
    with pytest.raises(wfem.InvalidInputError, match=r"\(n, 3\)"):
        wfem.operators(V[:, :2])  # no F: a point cloud (issue #27), which must be (n, 3)
    with pytest.raises(wfem.MeshError) as e:
        wfem.operators(np.zeros((0, 3)), np.zeros((0, 3), dtype=int))
    assert e.value.kind == "Empty"


def test_inputs_are_never_modified(sphere):
    V, F = sphere
    V0, F0 = V.copy(), F.copy()
    Vr, Fr = V.copy(), F.copy()
    Vr.flags.writeable = False
    Fr.flags.writeable = False
    K = wfem.HeatKernel(Vr, Fr)
    f = V[:, 0].copy()
    f.flags.writeable = False
    K.apply(f, 0.1)
    wfem.hks(Vr, Fr, [0.1], k=10)
    wfem.repair(Vr, Fr, merge_duplicate_vertices=0.0, orient_faces=True)
    L, B, D = wfem.operators(V, F)
    L0 = L.copy()
    wfem.HeatKernel.from_operators(L, B)
    np.testing.assert_array_equal(V, V0)
    np.testing.assert_array_equal(F, F0)
    np.testing.assert_array_equal(f, V0[:, 0])
    assert abs(L - L0).max() == 0 and L.has_sorted_indices == L0.has_sorted_indices


def test_objects_with_vertices_and_faces(sphere):
    V, F = sphere
    mesh = trimesh.Trimesh(vertices=V, faces=F, process=False)
    _same_operators(V, F, *(lambda m: (m.vertices, m.faces))(mesh))
    L = wfem.operators(mesh)[0]
    assert abs(L - wfem.operators(V, F)[0]).max() == 0
    K = wfem.HeatKernel(mesh)
    assert K.n == len(V)

    class PyFMLike:  # pyFM's TriMesh exposes .vertices and .faces
        def __init__(self, v, f):
            self.vertices, self.faces = v, f

    assert wfem.hks(PyFMLike(V, F), times=[0.1], k=8).shape == (len(V), 1)
