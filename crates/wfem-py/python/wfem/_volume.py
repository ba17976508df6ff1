"""Tetrahedral meshes (volumes): reading, validation and the linear FEM operators of the
tetrahedra. Every function that takes a mesh ``(V, F)`` also takes a volume ``(V, T)`` with T
an (m, 4) integer array: :class:`HeatKernel`, :func:`eigenbasis`, :func:`hks`, :func:`wks`,
:class:`GeodesicSolver` (the heat method through the solid), :func:`operators`."""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp

from . import _wfem
from ._arrays import as_float_array, to_csc
from ._errors import InvalidInputError

__all__ = ["read_volume", "validate_volume", "repair_volume", "VolumeReport", "tets_of", "volume_pencil"]


def read_volume(path: str | os.PathLike[str]) -> tuple[np.ndarray, np.ndarray]:
    """Reads a tetrahedral mesh: ``(V, T)`` with V float64 (n, 3) and T int64 (m, 4).

    Formats by extension: MEDIT ``.mesh`` (libigl, TetWild, sfepy), Gmsh ``.msh`` (2.2 ASCII or
    binary, 4.1 ASCII), legacy VTK ``.vtk`` (ASCII; LaPy's files included), TetGen ``.ele``
    (with its ``.node``). The vertex order of the file is kept; other elements (surface
    triangles, edges) are not used — ``wfem.read_volume(p)`` is LaPy's ``TetMesh.read_vtk(p)``
    ``(v, t)``.

    Raises:
        FileNotFoundError: no such file.
        MeshError: unknown extension, parse error (``path``, ``line``), a count the file cannot hold.
    """
    p = os.fspath(path)
    if not os.path.exists(p):
        raise FileNotFoundError(2, "No such volume file", p)
    (V, T), _ = _wfem.read_volume(p)
    return V, T


@dataclass(frozen=True)
class VolumeReport:
    """What :func:`validate_volume` found: counts, Σ|T|, the boundary surface (its Euler
    characteristic is 2 for a solid ball; its components and total genus ``(2c − χ)/2``, ``None``
    when the boundary is not a closed 2-manifold), quality ``(min, median)`` of 6√2|T|/ℓ³_rms
    with the worst tetrahedron, and
    every problem (``severity`` ``"Error"`` — flat tetrahedra, unreferenced vertices, a face of
    three tetrahedra — or ``"Warning"`` — mixed orientation, slivers, components)."""

    n_vertices: int
    n_tets: int
    volume: float
    n_boundary_faces: int
    n_boundary_vertices: int
    boundary_euler: int
    n_boundary_components: int
    boundary_genus: int | None
    n_components: int
    quality: tuple[float, float]
    worst_tet: int
    usable: bool
    problems: list[dict[str, Any]]


def validate_volume(V: Any, T: Any) -> VolumeReport:
    """Checks a tetrahedral mesh (nothing is changed)."""
    v, t = tets_of(V, T, required=True)  # type: ignore[misc]
    r = json.loads(_wfem.validate_volume(v, t))
    r["quality"] = tuple(r["quality"])
    return VolumeReport(**r)


def repair_volume(
    V: Any, T: Any, *, orient: bool = True, degenerate: bool = True, unreferenced: bool = True
) -> tuple[np.ndarray, np.ndarray, dict[str, Any]]:
    """Explicit repairs of a tetrahedral mesh (the input is not changed): ``orient`` makes every
    signed volume positive, ``degenerate`` drops flat tetrahedra, ``unreferenced`` drops
    vertices in no tetrahedron (renumbering the rest in order). Returns ``(V, T, report)`` with
    ``report["vertex_map"][i]`` the new index of old vertex i (−1: dropped) and the counts."""
    v, t = tets_of(V, T, required=True)  # type: ignore[misc]
    (V2, T2), r = _wfem.repair_volume(v, t, bool(orient), bool(degenerate), bool(unreferenced))
    report = json.loads(r)
    report["vertex_map"] = np.asarray(report["vertex_map"], dtype=np.int64)
    return V2, T2, report


def tets_of(V: Any, F: Any, *, required: bool = False) -> tuple[np.ndarray, np.ndarray] | None:
    """``(V float64 (n, 3), T int64 (m, 4))`` when ``F`` is an array of tetrahedra (4 columns),
    else None (a surface or a point cloud)."""
    if F is None or hasattr(F, "faces"):
        if required:
            raise InvalidInputError("give V and T (an (m, 4) array of tetrahedra)", "MissingTets", name="T")
        return None
    f = np.asarray(F)
    if f.ndim != 2 or f.shape[1] != 4:
        if required:
            raise InvalidInputError(f"T must have shape (m, 4) (tetrahedra), got {f.shape}", "Shape", name="T")
        return None
    if f.dtype.kind not in "iu":
        raise InvalidInputError(f"T must hold integer vertex indices, got {f.dtype}", "DType", name="T")
    if f.size and f.min() < 0:
        tet = int(np.argwhere(f < 0)[0][0])
        raise InvalidInputError(f"tetrahedron {tet} uses a negative vertex index", "NegativeIndex", tet=tet)
    v = as_float_array(V, "V", (2,))
    if v.shape[1:] != (3,):
        raise InvalidInputError(f"V must have shape (n, 3), got {v.shape}", "Shape", name="V")
    return v, f.astype(np.int64, copy=False)


def volume_operators(v: np.ndarray, t: np.ndarray, lumped: str | None = None) -> tuple[sp.csc_matrix, sp.csc_matrix, sp.csc_matrix]:
    """``(L, B, D)`` of the linear tetrahedral elements: ``L = −igl.cotmatrix(V, T)``, B the
    consistent mass (|T|/10 on the diagonal, |T|/20 off it), D its row sums (|T|/4 per corner)."""
    L, B, D = _wfem.volume_operators(v, t, lumped)
    return to_csc(L), to_csc(B), to_csc(D)


def volume_pencil(v: np.ndarray, t: np.ndarray, mass: str | None) -> tuple[sp.csc_matrix, sp.csc_matrix]:
    """``(L, M)`` of a volume for the kernel of ``mass=`` (B, D or I as the library decides)."""
    matrix, lumping = _wfem.mass_matrix(mass)
    L, B, D = volume_operators(v, t, lumping)
    M = {"B": B, "D": D, "I": sp.identity(B.shape[0], format="csc")}[matrix]
    return L, M
