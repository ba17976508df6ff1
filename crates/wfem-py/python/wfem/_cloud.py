"""Point clouds (issue #27): reading them and their operators (L, B, D) from local
triangulations of the k nearest neighbours, the same ``(L, B, D)`` as a mesh's.

A point cloud is given as an (n, 3) float array ``P`` (or any object with ``.vertices`` and
no ``.faces``, e.g. a ``trimesh.PointCloud``) wherever a mesh ``V, F`` is accepted:
``wfem.operators(P)``, ``wfem.HeatKernel(P)``, ``wfem.eigenbasis(P)``, ``wfem.hks(P)``.
"""

from __future__ import annotations

import json
import os
from typing import Any

import numpy as np
import scipy.sparse as sp

from . import _choices, _wfem
from ._arrays import as_float_array, to_csc

__all__ = ["read_points", "cloud_operators", "LAPLACIANS", "DEFAULT_NEIGHBORS"]

#: Names accepted by ``laplacian=`` (the library's registry ``mesh_fem::Laplacian``): the
#: cotangent L (the default for meshes, paper Eq. (3)) or the robust one (the intrinsic
#: Delaunay Laplacian of the tufted cover, Sharp & Crane 2020; what point clouds always use).
LAPLACIANS: tuple[str, ...] = _choices.names("laplacian")

#: Neighbours of each point's local triangulation by default (robust_laplacian's k).
DEFAULT_NEIGHBORS: int = int(_wfem.DEFAULT_NEIGHBORS)


def read_points(path: str | os.PathLike[str]) -> tuple[np.ndarray, np.ndarray | None]:
    """Reads a point cloud: ``(P (n, 3), normals (n, 3) or None)`` from a PLY without faces, an
    ``.xyz`` (3 or 6 columns), ``.pts``, ``.csv`` (optional header) or ``.npy`` ((n, 3) or (n, 6))."""
    p, n = _wfem.read_points(os.fspath(path))
    return np.asarray(p), (None if n is None else np.asarray(n))


def cloud_operators(
    P: Any,
    *,
    normals: Any = None,
    lumped: str | None = None,
    n_neighbors: int = DEFAULT_NEIGHBORS,
    mollify_factor: float | None = None,
    laplacian: str | None = None,
    return_report: bool = False,
) -> Any:
    """``(L, B, D)`` of a point cloud as ``scipy.sparse.csc_matrix`` (see :func:`wfem.operators`).

    L is symmetric positive semidefinite (positive diagonal, ``L @ 1 = 0``; robust_laplacian's
    sign) and an M-matrix; B is the consistent mass of the intrinsic triangulation (what the
    wFEM kernel uses; robust_laplacian has no such matrix) and D its lumped mass. With
    ``return_report=True`` a dict of counts (neighbours used, triangles, flips) comes last.
    """
    p = as_float_array(P, "P", (2,))
    nrm = None if normals is None else as_float_array(normals, "normals", (2,))
    L, B, D, report = _wfem.cloud_operators(p, nrm, lumped, int(n_neighbors), mollify_factor, laplacian)
    out = (to_csc(L), to_csc(B), to_csc(D))
    return (*out, dict(json.loads(report))) if return_report else out


def cloud_pencil(
    P: Any, mass: str | None, *, laplacian: str | None = None, n_neighbors: int | None = None
) -> tuple[sp.csc_matrix, sp.csc_matrix]:
    """``(L, M)`` of a point cloud for the kernel of ``mass=`` (a name of ``wfem.MASSES``): M is
    B, D (with the mass's lumping) or I, as the library decides for that name."""
    matrix, lumping = _wfem.mass_matrix(mass)
    k = DEFAULT_NEIGHBORS if n_neighbors is None else n_neighbors
    L, B, D = cloud_operators(P, lumped=lumping, n_neighbors=k, laplacian=laplacian)
    M = {"B": B, "D": D, "I": sp.identity(B.shape[0], format="csc")}[matrix]
    return L, M
