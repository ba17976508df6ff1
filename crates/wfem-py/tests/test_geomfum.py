"""The geomfum drop-in (``wfem.geomfum``, issue #38 point 7) against geomfum's own eigen step:
robust_laplacian's operators and scipy's ``eigsh`` (geomfum's defaults)."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

import wfem
import wfem.geomfum

TriangleMesh = pytest.importorskip("geomfum.shape").TriangleMesh
spectral = pytest.importorskip("geomfum.descriptor.spectral")
robust_laplacian = pytest.importorskip("robust_laplacian")


def cat0(corpus) -> TriangleMesh:
    return TriangleMesh.from_file(str(corpus / "tosca-bcicp-5k/TOSCA_Isometric/cat0.off"))


def test_the_operators_are_robust_laplacians():
    V, F = wfem.generate.bumpy(3)
    mesh = TriangleMesh(V, F)
    for mollify in (1e-5, 0.0):
        L, M = wfem.geomfum.MeshLaplacianFinder(mollify)(mesh)
        L_ref, M_ref = robust_laplacian.mesh_laplacian(V, F, mollify_factor=mollify)
        assert sp.issparse(L) and sp.issparse(M)
        assert abs(L - L_ref).max() <= 1e-12 * abs(L_ref).max()
        assert abs(M - M_ref).max() <= 1e-12 * abs(M_ref).max()


def test_the_drop_in_gives_geomfums_spectrum(corpus):
    k = 40
    theirs = cat0(corpus)
    vals_ref, vecs_ref = theirs.laplacian.find_spectrum(spectrum_size=k)
    ours = cat0(corpus)
    vals, vecs = wfem.geomfum.find_spectrum(ours, spectrum_size=k)
    vals_ref, vecs_ref, vals, vecs = map(np.asarray, (vals_ref, vecs_ref, vals, vecs))
    scale = vals_ref.max()
    assert vals.shape == (k,) and vecs.shape == (ours.n_vertices, k)
    assert np.max(np.abs(vals - vals_ref)) < 1e-9 * scale
    # The mesh now carries wfem's operators and basis, as geomfum's own call leaves them.
    M = ours.laplacian.mass_matrix
    assert abs(M - theirs.laplacian.mass_matrix).max() < 1e-12 * abs(M).max()
    assert np.array_equal(np.asarray(ours.basis.full_vals), vals)
    gram = vecs.T @ (M @ vecs)
    assert np.max(np.abs(gram - np.eye(k))) < 1e-8
    simple = np.r_[True, np.diff(vals_ref) > 1e-6 * scale] & np.r_[np.diff(vals_ref) > 1e-6 * scale, True]
    dots = np.abs(np.sum(vecs * (M @ vecs_ref), axis=0))
    assert np.all(dots[simple] > 1 - 1e-6)
    # geomfum's own WKS on either basis then agrees.
    wks = spectral.WaveKernelSignature(n_domain=20)
    a, b = np.asarray(wks(theirs)), np.asarray(wks(ours))
    assert a.shape == b.shape
    assert np.max(np.abs(a - b)) < 1e-6 * np.abs(a).max()


def test_the_pieces_plug_into_geomfums_classes():
    from geomfum.laplacian import LaplacianSpectrumFinder

    V, F = wfem.generate.bumpy(3)
    mesh = TriangleMesh(V, F)
    mesh.laplacian.find(wfem.geomfum.MeshLaplacianFinder())
    finder = LaplacianSpectrumFinder(eig_solver=wfem.geomfum.Eigsh(12))
    vals, vecs = mesh.laplacian.find_spectrum(laplacian_spectrum_finder=finder)
    ref = TriangleMesh(V, F)
    vals_ref, _ = ref.laplacian.find_spectrum(spectrum_size=12)
    assert np.max(np.abs(np.asarray(vals) - np.asarray(vals_ref))) < 1e-9 * np.max(vals_ref)
    assert finder.spectrum_size == 12


def test_bad_geomfum_input_is_a_typed_error():
    V, F = wfem.generate.bumpy(2)
    mesh = TriangleMesh(V, F)
    for bad in (0, -3, 2.5, True, "10"):
        with pytest.raises(wfem.InvalidInputError):
            wfem.geomfum.find_spectrum(mesh, spectrum_size=bad)
    with pytest.raises(wfem.InvalidInputError):
        wfem.geomfum.Eigsh(5)(sp.eye(10).tocsc())
    with pytest.raises(wfem.WfemError):
        wfem.geomfum.find_spectrum(TriangleMesh(V, F), spectrum_size=10, mollify_factor=-1.0)
    with pytest.raises(wfem.WfemError):
        wfem.geomfum.find_spectrum(TriangleMesh(V, F), spectrum_size=10 * len(V))
