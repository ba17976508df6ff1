"""The wave kernel signature (issue #38) against a dense reference and pyFM's ``WKS`` on the same
eigenpairs, and the pyFM drop-in (``wfem.pyfm.process``) against pyFM's own ``process``."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg

import wfem
import wfem.pyfm

pyFM_wks = pytest.importorskip("pyFM.signatures.WKS_functions")
pyFM_mesh = pytest.importorskip("pyFM.mesh")


def reference_wks(evals: np.ndarray, evecs: np.ndarray, n_e: int) -> np.ndarray:
    """The formula of Aubry et al. with pyFM's energies, written out independently."""
    keep = evals > 1e-8 * evals.max()
    lam, phi = evals[keep], evecs[:, keep]
    e_min, e_max = np.log(lam.min()), np.log(lam.max())
    sigma = 7 * (e_max - e_min) / n_e
    energies = np.linspace(e_min + 2 * sigma, e_max - 2 * sigma, n_e)
    c = np.exp(-((energies[:, None] - np.log(lam)[None, :]) ** 2) / (2 * sigma**2))
    return (phi**2) @ (c / c.sum(axis=1, keepdims=True)).T


def test_wks_equals_the_dense_reference():
    V, F = wfem.generate.bumpy(2)
    L, B, _ = wfem.operators(V, F)
    evals, evecs = scipy.linalg.eigh(L.toarray(), B.toarray())
    k = 40
    ours = wfem.wks(basis=(evals[:k], evecs[:, :k]), num_energies=50)
    assert np.max(np.abs(ours - reference_wks(evals[:k], evecs[:, :k], 50))) < 1e-12
    # From the mesh: wfem's own eigenpairs of the wFEM kernel give the same signature.
    direct, energies = wfem.wks(V, F, k=k, num_energies=50, return_energies=True)
    assert energies.shape == (50,)
    assert np.max(np.abs(direct - ours)) < 1e-7 * np.abs(ours).max()


@pytest.mark.parametrize("n_e", [100, 10])
def test_wks_equals_pyfm_on_the_same_eigenpairs(n_e):
    V, F = wfem.generate.bumpy(3)
    mesh = pyFM_mesh.TriMesh(V, F)
    mesh.process(k=60, intrinsic=False)
    theirs = pyFM_wks.mesh_WKS(mesh, num_E=n_e)
    ours = wfem.wks(basis=(mesh.eigenvalues, mesh.eigenvectors), num_energies=n_e)
    assert ours.shape == theirs.shape
    assert np.max(np.abs(ours - theirs)) <= 1e-10 * np.abs(theirs).max()


def test_the_pyfm_drop_in_gives_pyfms_spectrum(corpus):
    path = str(corpus / "tosca-bcicp-5k/TOSCA_Isometric/cat0.off")
    for intrinsic in (False, True):
        theirs = pyFM_mesh.TriMesh(path, area_normalize=True, center=True).process(k=40, intrinsic=intrinsic)
        ours = wfem.pyfm.process(pyFM_mesh.TriMesh(path, area_normalize=True, center=True), k=40, intrinsic=intrinsic)
        scale = theirs.eigenvalues.max()
        assert np.max(np.abs(ours.eigenvalues - theirs.eigenvalues)) < 1e-9 * scale
        # Mass-orthonormal eigenvectors, equal up to sign where the eigenvalues are simple.
        gram = ours.eigenvectors.T @ (ours.mass @ ours.eigenvectors)
        assert np.max(np.abs(gram - np.eye(40))) < 1e-8
        dots = np.abs(np.sum(ours.eigenvectors * (theirs.mass @ theirs.eigenvectors), axis=0))
        simple = np.r_[True, np.diff(theirs.eigenvalues) > 1e-6 * scale] & np.r_[np.diff(theirs.eigenvalues) > 1e-6 * scale, True]
        assert np.all(dots[simple] > 1 - 1e-6)
        # pyFM's own descriptors then agree too.
        w1 = pyFM_wks.mesh_WKS(theirs, num_E=100)
        w2 = pyFM_wks.mesh_WKS(ours, num_E=100)
        assert np.max(np.abs(w1 - w2)) < 1e-6 * np.abs(w1).max()


def test_bad_wks_input_is_a_typed_error():
    V, F = wfem.generate.icosphere(2)
    with pytest.raises(wfem.WfemError):
        wfem.wks(V, F, num_energies=0)
    with pytest.raises(wfem.WfemError):
        wfem.wks(basis=(np.zeros(5), np.ones((10, 5))))  # no nonzero eigenvalue
    with pytest.raises(wfem.WfemError):
        wfem.wks(basis="no")
    with pytest.raises(wfem.WfemError):
        wfem.wks(basis=(np.ones(3), np.ones((10, 4))))  # shapes disagree


def test_pyfms_pipeline_gives_the_same_map_with_wfems_eigen_step(corpus):
    """examples/pyfm_zoomout.py: WKS, fit, ZoomOut on TOSCA cat0 ← cat2 with ground truth."""
    import importlib.util
    from pathlib import Path

    path = Path(__file__).resolve().parents[1] / "examples" / "pyfm_zoomout.py"
    spec = importlib.util.spec_from_file_location("pyfm_zoomout", path)
    example = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(example)
    folder = corpus / "tosca-bcicp-5k" / "TOSCA_Isometric"
    _, theirs = example.run(folder, "cat0", "cat2", 120, "pyfm")
    _, ours = example.run(folder, "cat0", "cat2", 120, "wfem")
    assert ours < 0.05, ours  # a good map (the left-right flip would be ~0.2 √A)
    assert abs(ours - theirs) < 0.05 * theirs, (ours, theirs)


def test_the_combined_descriptor_is_the_sihks_beside_the_wks():
    V, F = wfem.generate.bumpy(2)
    out = wfem.descriptors(V, F, ["si-hks+wks", "si-hks", "wks"], k=40)
    both = np.hstack([out["si-hks"], out["wks"]])
    assert out["si-hks+wks"].shape == both.shape
    assert np.array_equal(out["si-hks+wks"], both)
    assert "si-hks+wks" in wfem.DESCRIPTORS
