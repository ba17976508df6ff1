"""The Python package gives the same numbers as the `wfem` command-line tool (when it is built:
`cargo test-all` passes its path in WFEM_CLI)."""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
import scipy.io

import wfem
from conftest import REPO, index_meshes, write_off


@pytest.fixture(scope="module")
def cli() -> str:
    candidates = [os.environ.get("WFEM_CLI"), shutil.which("wfem"), str(REPO / "target" / "debug" / "wfem")]
    for c in candidates:
        if c and Path(c).is_file() and os.access(c, os.X_OK):
            return c
    pytest.skip("the wfem CLI is not built (cargo build; or set WFEM_CLI)")


@pytest.fixture(scope="module")
def mesh_file(tmp_path_factory):
    V, F = wfem.generate.bumpy(3)
    p = tmp_path_factory.mktemp("cli") / "bumpy.off"
    write_off(p, V, F)
    return p


def run(cli, *args):
    r = subprocess.run([cli, *map(str, args)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr


def test_heat_matches_the_cli(cli, mesh_file, tmp_path):
    V, F = wfem.read_mesh(mesh_file)
    f = np.random.default_rng(0).standard_normal(len(V))
    np.save(tmp_path / "f.npy", f)
    for method in ("fast", "rational"):
        out = tmp_path / f"g_{method}.npy"
        run(cli, "heat", mesh_file, "--t", "0.01", "--field", tmp_path / "f.npy", "--method", method, "-o", out)
        g = wfem.HeatKernel(V, F, method=method).apply(f, 0.01)
        assert np.max(np.abs(np.load(out).reshape(g.shape) - g)) <= 1e-13 * np.max(np.abs(f)), method


def test_hks_matches_the_cli(cli, mesh_file, tmp_path):
    V, F = wfem.read_mesh(mesh_file)
    out = tmp_path / "h.npy"
    # The truncated sum of 40 eigenpairs on both sides...
    run(cli, "hks", mesh_file, "--times", "0.01", "0.1", "--eigenpairs", "40", "--method", "spectral", "-o", out)
    h = wfem.hks(V, F, [0.01, 0.1], k=40, method="spectral")
    np.testing.assert_allclose(np.load(out), h, rtol=1e-10)
    # ... and the exact diagonal (no eigenpairs) on both sides.
    run(cli, "hks", mesh_file, "--times", "0.01", "0.1", "--method", "exact", "-o", out)
    h = wfem.hks(V, F, [0.01, 0.1], method="exact")
    np.testing.assert_allclose(np.load(out), h, rtol=1e-8)


def test_operators_match_the_cli(cli, mesh_file, tmp_path):
    run(cli, "operators", mesh_file, "--out", tmp_path / "ops")
    L, B, D = wfem.operators(*wfem.read_mesh(mesh_file))
    for name, m in [("stiffness", L), ("mass", B), ("lumped_mass", D)]:
        other = scipy.io.mmread(tmp_path / "ops" / f"{name}.mtx").tocsc()
        assert abs(other - m).max() <= 1e-15 * abs(m).max(), name


def test_retrieval_index_is_shared_with_the_cli(cli, tmp_path):
    # An index built in Python answers `wfem retrieval query`, and one built by the CLI opens
    # here and ranks the same way.
    paths = index_meshes(tmp_path)
    py_index = wfem.RetrievalIndex.build(paths, tmp_path / "py.sqlite", words=8)
    run(cli, "retrieval", "build", *paths, "--out", tmp_path / "cli.sqlite", "--words", "8")
    cli_index = wfem.RetrievalIndex.open(tmp_path / "cli.sqlite")
    V, F = wfem.read_mesh(paths[2])
    a = py_index.query_mesh(V, F, k=6)
    b = cli_index.query_mesh(V, F, k=6)
    assert [n for n, _ in a] == [n for n, _ in b]
    np.testing.assert_allclose([d for _, d in a], [d for _, d in b], atol=1e-9)
    out = subprocess.run(
        [str(cli), "retrieval", "query", str(tmp_path / "py.sqlite"), str(paths[2]), "--top", "6"],
        capture_output=True, text=True, check=True,
    ).stdout
    assert [line.split("\t")[2] for line in out.splitlines()] == [n for n, _ in a]


def test_query_id_matches_the_cli(cli, tmp_path):
    # Issue #42: RetrievalIndex.query_id ranks as `wfem retrieval query INDEX --id NAME`
    # (the same stored signature, the shape itself left out).
    paths = index_meshes(tmp_path)
    index = wfem.RetrievalIndex.build(paths, tmp_path / "py.sqlite", words=8)
    hits = index.query_id(paths[2].stem, k=5)
    out = subprocess.run(
        [str(cli), "retrieval", "query", str(tmp_path / "py.sqlite"), "--id", paths[2].stem, "--top", "5"],
        capture_output=True, text=True, check=True,
    ).stdout
    rows = [line.split("\t") for line in out.splitlines()]
    assert [r[2] for r in rows] == [n for n, _ in hits]
    np.testing.assert_allclose([float(r[1]) for r in rows], [d for _, d in hits], atol=1e-6)
    r = subprocess.run(
        [str(cli), "retrieval", "query", str(tmp_path / "py.sqlite"), "--id", "nothing-like-it"],
        capture_output=True, text=True,
    )
    assert r.returncode != 0 and "nothing-like-it" in r.stderr
    with pytest.raises(wfem.InvalidInputError):
        index.query_id("nothing-like-it")


def test_approx_matches_the_cli(cli, mesh_file, tmp_path):
    # Issue #24: the defaults of `wfem approx` and of HeatKernel.feature_approximation are the
    # same library call; the sidecar records what the Python dict does.
    import json

    V, F = wfem.read_mesh(mesh_file)
    f = V[:, 2] + 0.3 * np.sin(4 * V[:, 0])
    np.save(tmp_path / "f.npy", f)
    out = tmp_path / "a.npy"
    run(cli, "approx", mesh_file, "--field", tmp_path / "f.npy", "-o", out)
    record = json.loads((tmp_path / "a.json").read_text())["approximation"]
    mine = wfem.HeatKernel(V, F).feature_approximation(f)
    for key in ("coefficients", "sampling", "anchors"):
        assert record[key] == mine[key], key
    for a, b in zip(record["scales"], mine["scales"]):
        assert abs(a["t"] - b["t"]) <= 1e-12 * b["t"]
        assert a["anchors"] == b["anchors"]
        np.testing.assert_allclose(a["coefficients"], b["coefficients"], rtol=1e-9, atol=1e-12)
        assert abs(a["relative_linf_error"] - b["relative_linf_error"]) <= 1e-9


def test_vtu_outputs_open_in_meshio(cli, volumes, mesh_file, tmp_path):
    # Issue #39: a volume's field as a VTK unstructured grid of its tetrahedra (ParaView's
    # format), read back by meshio, equal to the .npy of the same run; a surface's as triangles.
    meshio = pytest.importorskip("meshio")
    vol = volumes / "flip-free-parametrization/cow.mesh"
    run(cli, "heat", vol, "--source", 100, "--t", 0.01, "-o", tmp_path / "h.vtu")
    run(cli, "heat", vol, "--source", 100, "--t", 0.01, "-o", tmp_path / "h.npy")
    m = meshio.read(tmp_path / "h.vtu")
    V, T = wfem.read_volume(vol)
    assert np.array_equal(m.points, V)
    assert [c.type for c in m.cells] == ["tetra"] and np.array_equal(m.cells[0].data, T)
    (values,) = m.point_data.values()
    assert np.array_equal(values, np.load(tmp_path / "h.npy"))
    run(cli, "geodesic", mesh_file, "--from", 0, "-o", tmp_path / "g.vtu")
    s = meshio.read(tmp_path / "g.vtu")
    assert [c.type for c in s.cells] == ["triangle"]
    assert np.allclose(s.point_data["geodesic_distance"], wfem.GeodesicSolver(*wfem.read_mesh(mesh_file)).distance(0), rtol=1e-12)
