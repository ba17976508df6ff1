"""Shared fixtures: small generated meshes (no files needed) and the optional real-mesh corpus
(``WFEM_MESHES``, default ``../shared/data/meshes`` beside the repository; tests that need it
are skipped when it is absent)."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg

import wfem

REPO = Path(__file__).resolve().parents[3]


def corpus_dir() -> Path | None:
    env = os.environ.get("WFEM_MESHES")
    d = Path(env) if env else REPO.parent / "shared" / "data" / "meshes"
    return d if d.is_dir() else None


@pytest.fixture(scope="session")
def corpus() -> Path:
    d = corpus_dir()
    if d is None:
        pytest.skip("the real-mesh corpus is absent (set WFEM_MESHES)")
    return d


def volumes_dir() -> Path | None:
    """The tetrahedral meshes: ``WFEM_VOLUMES``, else ``volumes`` beside the mesh corpus."""
    env = os.environ.get("WFEM_VOLUMES")
    if env:
        return Path(env) if Path(env).is_dir() else None
    meshes = corpus_dir()
    d = (meshes / ".." / "volumes").resolve() if meshes else REPO.parent / "shared" / "data" / "volumes"
    return d if d.is_dir() else None


@pytest.fixture(scope="session")
def volumes() -> Path:
    d = volumes_dir()
    if d is None:
        pytest.skip("the volume corpus is absent (set WFEM_VOLUMES)")
    return d


def small_meshes() -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Closed, open, genus-1 and irregular meshes of 100–300 vertices."""
    return {
        "icosphere2": wfem.generate.icosphere(2),
        "irregular": wfem.generate.irregular_sphere(2, 3.0),
        "grid": wfem.generate.grid(12, 10),
        "torus": wfem.generate.torus(1.0, 0.4, 14, 9),
        "bumpy": wfem.generate.bumpy(2),
    }


@pytest.fixture(scope="session", params=list(small_meshes()))
def mesh(request: pytest.FixtureRequest) -> tuple[np.ndarray, np.ndarray]:
    return small_meshes()[request.param]


def dense_eigh(L, M):
    """All eigenpairs of L x = λ M x with XᵀMX = I (scipy's LAPACK, independent of wfem)."""
    lam, X = scipy.linalg.eigh(L.toarray(), M.toarray())
    return lam, X


def write_off(path: Path, V: np.ndarray, F: np.ndarray) -> None:
    with open(path, "w") as f:
        f.write(f"OFF\n{len(V)} {len(F)} 0\n")
        for v in V:
            f.write(f"{float(v[0])!r} {float(v[1])!r} {float(v[2])!r}\n")
        for t in F:
            f.write(f"3 {t[0]} {t[1]} {t[2]}\n")


def index_meshes(tmp_path):
    """Six mesh files: three shapes, each at scales 1 and 1.5 (retrieval tests)."""
    paths = []
    for i, (V, F) in enumerate([wfem.generate.icosphere(2), wfem.generate.bumpy(2), wfem.generate.torus()]):
        for s in (1.0, 1.5):
            p = tmp_path / f"m{i}_{s}.off"
            write_off(p, V * s, F)
            paths.append(p)
    return paths
