"""Tetrahedral meshes from Python (issue #39): reading the real volume corpus, the operators
against libigl's tetrahedral cotmatrix and closed forms, the spectrum against scipy's dense
generalized eigensolver, the heat kernel against scipy's expm_multiply, geodesics through a solid
against Euclidean distances in a cube, and typed errors for bad tetrahedra."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg
import scipy.sparse.linalg as sla

import wfem

# (file, vertices, tetrahedra) as SOURCES.md of the volume corpus counts them.
FILES = [
    ("flip-free-parametrization/cow.mesh", 2304, 8103),
    ("libigl-tutorial-data/hand.msh", 7234, 29998),
    ("lapy/cubeTetra.vtk", 9261, 48000),
    ("scikit-fem/cuubat.msh", 419, 1391),
    ("sfepy/unit_ball.mesh", None, None),
]


@pytest.mark.parametrize("rel,n,m", FILES)
def test_read_volume_counts(volumes, rel, n, m):
    V, T = wfem.read_volume(volumes / rel)
    assert V.dtype == np.float64 and T.dtype == np.int64 and T.shape[1] == 4
    if n is not None:
        assert V.shape == (n, 3) and T.shape == (m, 4)
    r = wfem.validate_volume(V, T)
    assert r.n_vertices == len(V) and r.n_tets == len(T) and r.boundary_euler == 2


def test_operators_match_libigl_and_closed_forms(volumes):
    igl = pytest.importorskip("igl")
    V, T = wfem.read_volume(volumes / "flip-free-parametrization/cow.mesh")
    L, B, D = wfem.operators(V, T)
    Lref = -igl.cotmatrix(V, T)
    assert abs(L - Lref).max() < 1e-10 * abs(Lref).max()
    Dref = igl.massmatrix(V, T, igl.MASSMATRIX_TYPE_BARYCENTRIC)  # |T|/4 per corner
    assert abs(D - Dref).max() < 1e-13 * abs(Dref).max()
    vol = wfem.validate_volume(V, T).volume
    one = np.ones(len(V))
    assert abs(one @ (B @ one) - vol) < 1e-12 * vol
    assert np.allclose(D.diagonal(), B @ one, rtol=1e-12, atol=0)
    assert np.abs(L @ one).max() < 1e-10 * abs(L).max()
    # One tetrahedron: B = |T|/20 (1 + I), the P1 mass in closed form.
    Vt = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    _, Bt, _ = wfem.operators(Vt, np.array([[0, 1, 2, 3]]))
    assert np.allclose(Bt.toarray(), (np.ones((4, 4)) + np.eye(4)) / 6 / 20, rtol=1e-14)


def test_spectrum_heat_and_signatures_against_dense_references(volumes):
    V, T = wfem.read_volume(volumes / "scikit-fem/cuubat.msh")
    L, B, _ = wfem.operators(V, T)
    lam, X = scipy.linalg.eigh(L.toarray(), B.toarray())
    basis = wfem.eigenbasis(V, T, 12)
    assert np.allclose(basis.values, lam[:12], rtol=1e-9, atol=1e-9)
    # K_t f = exp(−t B⁻¹L) f (paper Eq. (6)) on the solid.
    f = np.zeros(len(V))
    f[7] = 1.0
    kernel = wfem.HeatKernel(V, T)
    A = scipy.linalg.solve(B.toarray(), L.toarray())
    for t in (1e-3, 1e-2, 0.1):
        ref = sla.expm_multiply(-t * A, f)
        assert np.abs(kernel.apply(f, t) - ref).max() < 1e-8 * np.abs(ref).max()
    # HKS of the volume = its eigenbasis' signature; WKS has one column per energy.
    h = wfem.hks(V, T, [0.05, 0.2], k=12)
    assert np.allclose(h, basis.hks([0.05, 0.2])[0], rtol=1e-12)
    ref_h = (X[:, :12] ** 2) @ np.exp(-np.outer(lam[:12], [0.05, 0.2]))  # the same 12 pairs, dense
    assert np.abs(h - ref_h).max() < 1e-8 * ref_h.max()
    assert wfem.wks(V, T, num_energies=5, k=12).shape == (len(V), 5)


def test_geodesics_through_a_cube_are_euclidean(volumes):
    V, T = wfem.read_volume(volumes / "lapy/cubeTetra.vtk")
    s = int(np.argmin(np.linalg.norm(V - 0.5, axis=1)))  # the centre
    d = wfem.GeodesicSolver(V, T).distance(s)  # the heat method, the default on a volume
    exact = np.linalg.norm(V - V[s], axis=1)
    keep = exact > 0
    err = np.abs(d[keep] - exact[keep]) / exact[keep]
    assert err.mean() < 0.05, err.mean()
    with pytest.raises(wfem.InvalidInputError):
        wfem.GeodesicSolver(V, T, refine=1)


def test_bad_tetrahedra_get_typed_errors(tmp_path):
    V = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    with pytest.raises(wfem.InvalidInputError):
        wfem.operators(V, np.array([[0, 1, 2, -1]]))
    with pytest.raises(wfem.MeshError):
        wfem.operators(V, np.array([[0, 1, 2, 9]]))
    with pytest.raises(wfem.MeshError, match="uses vertex 1099511627776"):
        wfem.operators(V, np.array([[0, 1, 2, 2**40]]))
    with pytest.raises(wfem.InvalidInputError):
        wfem.operators(V, np.array([[0.0, 1, 2, 3]]))
    with pytest.raises(wfem.InvalidInputError):
        wfem.HeatKernel(V, np.array([[0, 1, 2, 3]]), laplacian="robust")
    with pytest.raises(FileNotFoundError):
        wfem.read_volume(tmp_path / "none.mesh")
    bad = tmp_path / "bad.mesh"
    bad.write_text("MeshVersionFormatted 1\nDimension 3\nVertices\n-4\n")
    with pytest.raises(wfem.MeshError):
        wfem.read_volume(bad)
    flat = wfem.validate_volume(np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]]), np.array([[0, 1, 2, 3]]))
    assert not flat.usable and flat.problems[0]["severity"] == "Error"


def test_repair_volume_drops_the_unreferenced_vertex_of_sfepys_ball(volumes):
    V, T = wfem.read_volume(volumes / "sfepy/unit_ball.mesh")
    with pytest.raises(wfem.MeshError, match="belongs to no face or tetrahedron"):
        wfem.operators(V, T)
    V2, T2, r = wfem.repair_volume(V, T)
    assert r["dropped_vertices"] == 1 and r["vertex_map"][0] == -1 and len(V2) == len(V) - 1
    assert np.array_equal(V2, V[1:]) and np.array_equal(T2, T - 1)  # vertex 0 was the one
    L, B, _ = wfem.operators(V2, T2)
    assert abs(B.sum() - wfem.validate_volume(V2, T2).volume) < 1e-12
    # The first Neumann eigenvalue of the unit ball is (the first root of j1')^2 = 4.3330;
    # on this coarse polyhedral ball P1 overestimates it by a few per cent.
    lam = wfem.eigenbasis(V2, T2, 4).values
    assert abs(lam[0]) < 1e-8 and 4.33 < lam[1] < 4.33 * 1.08, lam


def test_shape_dna_of_a_solid_against_scipy_and_weyl(volumes):
    """The Shape-DNA of a solid: scipy's dense generalized eigenvalues normalised by the 3-D Weyl
    law λ_i^Weyl = (6π²i/V)^{2/3}; invariant to scale; a surface keeps λ_i A/(4πi)."""
    V, T = wfem.read_volume(volumes / "scikit-fem/cuubat.msh")
    L, B, D = wfem.operators(V, T)
    lam = scipy.linalg.eigh(L.toarray(), B.toarray(), eigvals_only=True)
    vol = wfem.validate_volume(V, T).volume
    m = 10
    g, ev = wfem.shape_dna(V, T, m, return_eigenvalues=True)
    i = np.arange(1, m + 1)
    assert np.allclose(ev[1:], lam[1 : m + 1], rtol=1e-9)
    assert np.allclose(g, lam[1 : m + 1] * vol ** (2 / 3) / (6 * np.pi**2 * i) ** (2 / 3), rtol=1e-9)
    assert np.allclose(wfem.shape_dna(V * 1e3, T, m), g, rtol=1e-8)
    log = wfem.shape_dna(V, T, m, kind="log-shape-dna")
    assert np.allclose(log, np.log(lam[1 : m + 1] * vol ** (2 / 3)), atol=1e-9)
    assert wfem.shape_dna(V, T, m, kind=wfem.GLOBAL_KINDS[-1]).shape == (32,)
    # A surface: the unit sphere's λ₁₋₃ = 2, area 4π.
    S, F = wfem.generate.icosphere(3)
    gs = wfem.shape_dna(S, F, 3)
    area = np.asarray(wfem.operators(S, F)[2].sum())
    basis = wfem.eigenbasis(S, F, 4)
    assert np.allclose(gs, basis.values[1:4] * area / (4 * np.pi * np.arange(1, 4)), rtol=1e-12)
    with pytest.raises(wfem.InvalidInputError):
        wfem.shape_dna(V, T, m, kind="no-such-kind")
    with pytest.raises(wfem.InvalidInputError):
        basis.shape_dna(4)
    with pytest.raises(wfem.InvalidInputError):
        basis.shape_dna(2, dimension=4)
