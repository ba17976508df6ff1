"""Point clouds and the robust Laplacian (issue #27), against robust_laplacian 1.1.0 (pinned in
requirements-test.txt) and closed-form identities."""

from __future__ import annotations

import numpy as np
import pytest
import robust_laplacian
import scipy.sparse.linalg as sla

import wfem


def sphere_points(n: int, seed: int = 0) -> np.ndarray:
    p = np.random.default_rng(seed).normal(size=(n, 3))
    return p / np.linalg.norm(p, axis=1)[:, None]


def max_rel_diff(a, b) -> float:
    d = abs(a - b).max()
    return float(d / abs(b).max())


def test_laplacian_names_come_from_the_library():
    assert wfem.LAPLACIANS == ("cotan", "robust")
    with pytest.raises(wfem.InvalidInputError, match="laplacian"):
        wfem.operators(*wfem.generate.icosphere(1), laplacian="intrinsic")


def test_robust_mesh_operators_equal_robust_laplacian(mesh):
    V, F = mesh
    L, B, D = wfem.operators(V, F, laplacian="robust")
    Lr, Mr = robust_laplacian.mesh_laplacian(np.asarray(V, float), np.asarray(F), mollify_factor=1e-5)
    assert max_rel_diff(L, Lr) < 1e-10
    assert max_rel_diff(D, Mr) < 1e-10
    # B: the consistent mass of the same intrinsic triangulation, row sums D.
    assert np.allclose(np.asarray(B.sum(axis=1)).ravel(), D.diagonal(), rtol=1e-12)


@pytest.mark.parametrize(
    "name", ["common-3d-test-models/beetle.obj", "deftransfer-pyfm/camel_gallop/camel-gallop-01.off"]
)
def test_robust_operators_equal_robust_laplacian_on_non_manifold_real_meshes(corpus, name):
    V, F = wfem.read_mesh(corpus / name)
    used = np.unique(F)
    if len(used) < len(V):  # robust_laplacian keeps unreferenced vertices, wfem refuses them
        V, F, _ = wfem.repair(V, F, drop_unreferenced_vertices=True)
    L, _, D = wfem.operators(V, F, laplacian="robust")
    Lr, Mr = robust_laplacian.mesh_laplacian(np.asarray(V, float), np.asarray(F), mollify_factor=1e-5)
    assert max_rel_diff(L, Lr) < 1e-10
    assert max_rel_diff(D, Mr) < 1e-10
    # The lumped heat of the robust L is never negative (an M-matrix).
    f = np.zeros(len(V))
    f[len(V) // 2] = 1.0
    area = D.diagonal().sum()
    g = wfem.HeatKernel(V, F, mass="lumped", laplacian="robust").apply(f, 1e-3 * area)
    assert g.min() >= -1e-12 * g.max()


def test_point_cloud_operators_heat_and_hks():
    P = sphere_points(3000)
    L, B, D = wfem.operators(P)
    n = len(P)
    assert L.shape == B.shape == D.shape == (n, n)
    assert abs(L @ np.ones(n)).max() < 1e-10
    assert abs(L - L.T).max() == 0.0
    assert L.diagonal().min() > 0
    assert abs(D.diagonal().sum() - 4 * np.pi) < 0.01 * 4 * np.pi
    # The first eigenvalues of (L, B) against l(l+1) = 2 (×3), 6 (×5).
    lam = np.sort(sla.eigsh(L, k=9, M=B, sigma=-1e-3, which="LM")[0])
    assert abs(lam[0]) < 1e-8
    assert np.allclose(lam[1:4], 2.0, rtol=0.03) and np.allclose(lam[4:9], 6.0, rtol=0.04)
    # Heat: the z coordinate is an eigenfunction (λ = 2): K_t z ≈ e^{−2t} z.
    # (Relative L2 error in the mass norm: measured 1.4e-2; the largest pointwise error, 8e-2,
    # sits at a few points where the merged local triangles overlap.)
    K = wfem.HeatKernel(P)
    g = K.apply(P[:, 2], 0.1)
    r = g - np.exp(-0.2) * P[:, 2]
    assert np.sqrt(r @ (B @ r) / (g @ (B @ g))) < 0.03
    h = wfem.hks(P, times=[0.1, 1.0], k=30)
    assert h.shape == (n, 2) and np.all(h > 0)
    # A trimesh-like object with .vertices and no .faces is a cloud too.
    class Cloud:
        vertices = P

    L2, _, _ = wfem.operators(Cloud())
    assert abs(L2 - L).max() == 0.0


def test_cloud_operators_beat_robust_laplacian_on_the_sphere():
    P = sphere_points(2000, seed=1)
    expected = np.repeat([2.0, 6.0, 12.0, 20.0, 30.0], [3, 5, 7, 9, 11])[:25]

    def error(L, M):
        lam = np.sort(sla.eigsh(L, k=26, M=M, sigma=-1e-8, which="LM")[0])[1:26]
        return float(np.max(abs(lam - expected) / expected))

    L, B, _ = wfem.cloud_operators(P)
    Lr, Mr = robust_laplacian.point_cloud_laplacian(P, mollify_factor=1e-5, n_neighbors=30)
    ours, theirs = error(L, B), error(Lr, Mr)
    assert ours < theirs, (ours, theirs)


def test_from_operators_accepts_robust_laplacian_output():
    P = sphere_points(1500, seed=2)
    Lr, Mr = robust_laplacian.point_cloud_laplacian(P)
    K = wfem.HeatKernel.from_operators(Lr, Mr)
    g = K.apply(np.ones(len(P)), 0.5)
    assert np.allclose(g, 1.0, atol=1e-10)


def test_read_points_and_cloud_errors(tmp_path):
    P = sphere_points(100, seed=3)
    np.save(tmp_path / "p.npy", P)
    Q, normals = wfem.read_points(tmp_path / "p.npy")
    assert np.array_equal(P, Q) and normals is None
    np.savetxt(tmp_path / "p.xyz", np.hstack([P, P]))
    Q, normals = wfem.read_points(tmp_path / "p.xyz")
    assert np.allclose(P, Q) and np.allclose(normals, P)
    bad = P.copy()
    bad[5, 0] = np.nan
    with pytest.raises(wfem.WfemError, match="point 5"):
        wfem.operators(bad)
    dup = np.vstack([P, P[7:8]])
    with pytest.raises(wfem.WfemError, match="same coordinates as point 7"):
        wfem.HeatKernel(dup)
    with pytest.raises(wfem.InvalidInputError):
        wfem.operators(P, laplacian="cotan")


def surface_points(V: np.ndarray, F: np.ndarray, n: int, seed: int) -> np.ndarray:
    """n points uniform on a mesh's surface (faces by area, uniform barycentric coordinates)."""
    rng = np.random.default_rng(seed)
    tri = np.asarray(V, float)[np.asarray(F)]
    area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    f = rng.choice(len(tri), size=n, p=area / area.sum())
    u, v = rng.random(n), rng.random(n)
    flip = u + v > 1
    u[flip], v[flip] = 1 - u[flip], 1 - v[flip]
    return tri[f, 0] * (1 - u - v)[:, None] + tri[f, 1] * u[:, None] + tri[f, 2] * v[:, None]


def test_retrieval_index_mixes_meshes_and_point_clouds(tmp_path):
    from conftest import write_off

    sphere = wfem.generate.icosphere(3)
    shapes = {
        "sphere": sphere,
        "ellipsoid": (sphere[0] * np.array([2.2, 1.0, 0.6]), sphere[1]),
        "torus": wfem.generate.torus(1.0, 0.4, 48, 24),
    }
    paths = []
    for i, (name, (V, F)) in enumerate(shapes.items()):
        write_off(tmp_path / f"{name}.off", V, F)
        paths.append(tmp_path / f"{name}.off")
        cloud = surface_points(V, F, 1500, seed=i)
        if i % 2:
            np.savetxt(tmp_path / f"{name}-cloud.xyz", cloud)
            paths.append(tmp_path / f"{name}-cloud.xyz")
        else:
            np.save(tmp_path / f"{name}-cloud.npy", cloud)
            paths.append(tmp_path / f"{name}-cloud.npy")
    index = wfem.RetrievalIndex.build(paths, tmp_path / "idx.sqlite", words=6)
    assert len(index) == 6
    assert index.settings["vocabulary"]["descriptor"]["laplacian"] == "cotan"
    # A new cloud of the torus (an (n, 3) array alone is a point cloud) finds a torus first.
    V, F = shapes["torus"]
    query = surface_points(V, F, 1500, seed=99)
    hits = index.query_mesh(query, k=3)
    assert "torus" in hits[0][0], hits
    assert index.query_mesh(query, k=3, laplacian="cotan") == hits
    # The query is described with the index's Laplacian: another one is refused, by name.
    with pytest.raises(wfem.InvalidInputError, match="laplacian"):
        index.query_mesh(V, F, k=1, laplacian="robust")
    # Clouds are appended like meshes.
    csv = tmp_path / "more.csv"
    np.savetxt(csv, surface_points(V, F, 1200, seed=5), delimiter=",", header="x,y,z", comments="")
    assert index.add_meshes([csv]) == 1
    # A robust index records its Laplacian; names come from the library's registry.
    robust = wfem.RetrievalIndex.build(paths, tmp_path / "robust.sqlite", words=6, laplacian="robust")
    assert robust.settings["vocabulary"]["descriptor"]["laplacian"] == "robust"
    with pytest.raises(wfem.InvalidInputError, match="laplacian"):
        wfem.RetrievalIndex.build(paths, tmp_path / "bad.sqlite", words=6, laplacian="intrinsic")


def test_hks_of_a_cloud_reads_times_in_area_units():
    """``time_unit="area"`` on a cloud: t = τ·A with A measured on the cloud (as the CLI does),
    so the HKS is exactly scale covariant — a cloud scaled by s has K_t(x, x) divided by s²
    (the kernel value of a surface of area s²A) at the same τ; absolute times are not."""
    P = sphere_points(1500, seed=3)
    tau = [1e-3, 1e-2]
    h1 = wfem.hks(P, times=tau, time_unit="area", method="exact")
    h2 = wfem.hks(2.0 * P, times=tau, time_unit="area", method="exact")
    assert np.allclose(h2, h1 / 4.0, rtol=1e-8, atol=0.0)
    # Absolute times on the scaled cloud are another point of the curve.
    h3 = wfem.hks(2.0 * P, times=tau, method="exact")
    assert not np.allclose(h3, h1 / 4.0, rtol=1e-3)
    with pytest.raises(wfem.InvalidInputError, match="time_unit"):
        wfem.hks(P, times=tau, time_unit="fortnight")


def test_feature_approximation_and_edge_unit_on_a_cloud():
    # A kernel of a cloud keeps its neighbourhood mesh: the feature-driven approximation
    # runs (critical points on the non-manifold neighbourhood mesh) and keeps a smooth f
    # within 3 % of its range at the finest scale, as on a mesh; its kernel is the one of the
    # cloud's operators.
    P = sphere_points(1500, seed=3)
    f = P[:, 0] + 0.5 * P[:, 1] * P[:, 2]
    K = wfem.HeatKernel(P)
    out = K.feature_approximation(f, num_times=3)
    assert len(out["anchors"]) >= 2
    for s in out["scales"]:
        assert np.allclose(s["global_"] + s["local"], f, atol=1e-9)
    assert min(s["relative_linf_error"] for s in out["scales"]) <= 0.03
    L, B, _ = wfem.operators(P)
    ref = wfem.HeatKernel.from_operators(L, B)
    assert max_rel_diff(K.apply(f, 0.05), ref.apply(f, 0.05)) < 1e-10
    # The edge time unit is measured on the neighbourhood mesh (mean edge length squared).
    a = K.apply(f, 2.0, time_unit="edge")
    assert np.isfinite(a).all()
    # A laplacian= other than the robust one is refused for a cloud.
    with pytest.raises(wfem.InvalidInputError, match="laplacian"):
        wfem.HeatKernel(P, laplacian="cotan")


def test_every_error_carries_its_fields_as_attributes():
    # The exception attributes are generated from the library enums: variants the hand-written
    # mapping never covered (point-cloud errors) carry their culprit too.
    P = sphere_points(50)
    Q = P.copy()
    Q[7, 2] = np.inf
    with pytest.raises(wfem.MeshError) as info:
        wfem.operators(Q)
    e = info.value
    assert e.kind == "NonFinitePoint" and e.point == 7 and e.what == "coordinate"
    assert list(e.position[:2]) == [Q[7, 0], Q[7, 1]] and e.position[2] == np.inf
    with pytest.raises(wfem.MeshError) as info:
        wfem.operators(P[:2])
    assert info.value.kind == "TooFewPoints" and info.value.n_points == 2 and info.value.minimum == 3
    with pytest.raises(wfem.MeshError) as info:
        wfem.operators(np.vstack([P, P[4:5]]))
    assert info.value.kind == "DuplicatePoint" and info.value.point == 50 and info.value.duplicate_of == 4
