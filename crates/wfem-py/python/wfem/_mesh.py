"""Meshes: reading, validation, repair and the FEM operators L, B, D (paper, Eq. (3), (7))."""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.sparse as sp

from . import _wfem
from ._arrays import as_mesh, as_vector, points_of, to_csc
from ._cloud import DEFAULT_NEIGHBORS
from ._errors import InvalidInputError, MeshError

__all__ = [
    "read_mesh",
    "validate",
    "repair",
    "mesh_stats",
    "operators",
    "extrema",
    "ValidationReport",
    "RepairReport",
]


def read_mesh(path: str | os.PathLike[str], *, triangulate: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Reads a triangle mesh: ``(V, F)`` with V float64 (n, 3) and F int64 (m, 3).

    Formats by extension: ``.obj``, ``.ply`` (ASCII and binary), ``.off``, ``.stl``. The
    vertex order of the file is kept. Polygons with more than three corners are refused
    unless ``triangulate=True`` (fan triangulation).

    Raises:
        FileNotFoundError: no such file.
        MeshError: unknown extension, parse error (``path``, ``line``), polygon (``face``).
        MeshFileError: any other I/O error (``path``, ``errno``).
    """
    p = os.fspath(path)
    if not os.path.exists(p):
        raise FileNotFoundError(2, "No such mesh file", p)
    (V, F), _ = _wfem.read_mesh(p, triangulate)
    return V, F


@dataclass(frozen=True)
class ValidationReport:
    """What :func:`validate` found. ``problems`` lists every problem as a dict with ``kind``
    (e.g. ``"ZeroAreaFace"``), ``severity`` (``"Error"``/``"Warning"``) and the culprit
    (``face``, ``vertex``, ``edge``, …); ``usable`` is False when an error prevents assembling
    the operators."""

    n_vertices: int
    n_faces: int
    usable: bool
    problems: list[dict[str, Any]]
    counts: dict[str, int]
    summary: str

    def __str__(self) -> str:
        return self.summary


def validate(V: Any, F: Any = None) -> ValidationReport:
    """Checks a mesh before computing on it (nothing is changed).

    Errors (the operators cannot be assembled): faces repeating a vertex, zero-area faces,
    unreferenced vertices, an overflowing area. Warnings: non-manifold edges/vertices,
    duplicate faces, inconsistent orientation, several components, boundaries.
    """
    v, f = as_mesh(V, F)
    try:
        r = json.loads(_wfem.validate_mesh(v, f))
    except MeshError as e:
        # A mesh that cannot even be represented (a NaN coordinate, a face index out of range)
        # is reported like any other error, not raised: validate() answers "is it usable?".
        problem = {"kind": e.kind, "severity": "Error", **e.details}
        return ValidationReport(
            n_vertices=int(v.shape[0]),
            n_faces=int(f.shape[0]),
            usable=False,
            problems=[problem],
            counts={e.kind: 1},
            summary=f"not usable: {e}",
        )
    return ValidationReport(
        n_vertices=r["n_vertices"],
        n_faces=r["n_faces"],
        usable=r["usable"],
        problems=r["problems"],
        counts=r["counts"],
        summary=r["summary"],
    )


@dataclass(frozen=True)
class RepairReport:
    """What :func:`repair` changed. ``vertex_map[i]`` / ``face_map[j]`` is the new index of old
    vertex i / face j (``None`` if dropped; a merged vertex maps to the vertex it joined)."""

    vertex_map: list[int | None]
    face_map: list[int | None]
    merged_vertices: int
    dropped_vertices: int
    dropped_faces: list[int]
    dropped_degenerate_faces: list[int]
    dropped_duplicate_faces: list[int]
    flipped_faces: list[int]
    non_orientable_components: int
    unchanged: bool
    summary: str = field(repr=False)

    def __str__(self) -> str:
        return self.summary


def repair(
    V: Any,
    F: Any = None,
    *,
    merge_duplicate_vertices: float | None = None,
    drop_degenerate_faces: bool = False,
    drop_duplicate_faces: bool = False,
    orient_faces: bool = False,
    drop_unreferenced_vertices: bool = False,
) -> tuple[np.ndarray, np.ndarray, RepairReport]:
    """Applies the repairs you ask for (all off by default) and reports every change.

    Args:
        merge_duplicate_vertices: merge vertices closer than ``tol × bounding-box diagonal``
            (``0.0`` merges exact duplicates only).
        drop_degenerate_faces: drop faces repeating a vertex or with zero area.
        drop_duplicate_faces: keep the first of faces with the same three vertices.
        orient_faces: flip faces so every orientable component is consistently oriented.
        drop_unreferenced_vertices: drop vertices used by no face, renumbering the rest.

    Returns:
        ``(V', F', report)``; the inputs are not modified.
    """
    v, f = as_mesh(V, F)
    (v2, f2), r = _wfem.repair_mesh(
        v,
        f,
        merge_duplicate_vertices,
        drop_degenerate_faces,
        drop_duplicate_faces,
        orient_faces,
        drop_unreferenced_vertices,
    )
    return v2, f2, RepairReport(**json.loads(r))


def fill_holes(
    V: Any, F: Any = None, *, max_perimeter: float = _wfem.DEFAULT_MAX_HOLE_PERIMETER
) -> tuple[np.ndarray, np.ndarray, int]:
    """Closes every hole whose rim is at most ``max_perimeter × √area`` long with a smooth
    patch (concentric rings placed harmonically, the rim fixed) — what retrieval does before it
    describes a shape. Rims of holes that touch at a vertex are closed one by one; a flat open
    patch (rim ≥ 3.54 √area) is never closed at the default bound of 3.

    Returns:
        ``(V', F', holes_closed)``: ``V'[:len(V)]`` and ``F'[:len(F)]`` are the inputs
        unchanged, the patches' vertices and faces follow; the inputs are not modified.
    """
    v, f = as_mesh(V, F)
    (v2, f2), filled = _wfem.fill_holes(v, f, max_perimeter)
    return v2, f2, int(filled)


def mesh_stats(V: Any, F: Any = None) -> dict[str, Any]:
    """Counts, topology (Euler characteristic, genus, boundary loops, components) and geometry
    (area, edge lengths, angles) of a mesh."""
    v, f = as_mesh(V, F)
    return dict(json.loads(_wfem.mesh_stats(v, f)))


def operators(
    V: Any,
    F: Any = None,
    *,
    lumped: str | None = None,
    laplacian: str | None = None,
    mollify_factor: float | None = None,
    n_neighbors: int | None = None,
) -> tuple[sp.csc_matrix, sp.csc_matrix, sp.csc_matrix]:
    """The linear FEM operators ``(L, B, D)`` as ``scipy.sparse.csc_matrix`` (paper, Eq. (3), (7)).

    * ``L``: cotangent stiffness, ``L_ij = −(cot α_ij + cot β_ij)/2``. **L is symmetric positive
      semidefinite** (positive diagonal, ``L @ 1 = 0``): ``L = −igl.cotmatrix(V, F)``. The paper
      and libigl print the opposite sign.
    * ``B``: consistent mass, ``B_ij = |T|/12`` (i ≠ j), ``|T|/6`` (i = j) summed over triangles;
      ``1ᵀB1`` is the area.
    * ``D``: diagonal lumped mass (``lumped=``, a lumped mass of ``wfem.MASSES``):
      ``"barycentric"`` (default; row sums of B, Eq. (7)) or ``"voronoi"`` (mixed Voronoi
      areas, = ``igl.massmatrix(V, F, igl.MASSMATRIX_TYPE_VORONOI)``).

    All three share one sparsity pattern (vertex–edge graph plus diagonal).

    **Volumes**: ``operators(V, T)`` with T an (m, 4) array of tetrahedra gives the linear FEM
    operators of the solid (``L = −igl.cotmatrix(V, T)``, B with |T|/10 and |T|/20, D = |T|/4 per
    corner; LaPy's ``Solver(TetMesh(v, t), lump=False)`` stiffness and mass).

    ``laplacian="robust"`` (names in ``wfem.LAPLACIANS``) gives instead the intrinsic Delaunay
    Laplacian of the mesh's tufted cover (Sharp & Crane 2020; L and D equal robust_laplacian's
    ``mesh_laplacian``), with B and D on the intrinsic triangulation: for non-manifold, badly
    oriented or degenerate meshes (``mollify_factor``, default 1e-5, thickens flat faces).

    **Point clouds**: ``operators(P)`` with an (n, 3) array and no ``F`` builds L, B, D from
    local triangulations of the ``n_neighbors`` (default 30) nearest neighbours of every point
    (see :func:`wfem.cloud_operators`); a cloud always uses the robust construction.
    """
    from ._cloud import cloud_operators

    from ._volume import tets_of, volume_operators

    tets = tets_of(V, F)
    if tets is not None:
        if laplacian is not None or mollify_factor is not None:
            raise InvalidInputError("a volume has the linear FEM Laplacian only (laplacian=None)", "InvalidParameter", name="laplacian")
        return volume_operators(*tets, lumped)
    P = points_of(V, F)
    if P is not None:
        k = DEFAULT_NEIGHBORS if n_neighbors is None else n_neighbors
        return cloud_operators(P, lumped=lumped, n_neighbors=k, mollify_factor=mollify_factor, laplacian=laplacian)
    v, f = as_mesh(V, F)
    L, B, D = _wfem.operators(v, f, lumped, laplacian, mollify_factor)
    return to_csc(L), to_csc(B), to_csc(D)


def extrema(V: Any, F: Any, f: Any, *, persistence: float | None = None) -> np.ndarray:
    """Vertex indices of the local maxima and minima of a field ``f`` (n,), or only those whose
    topological persistence is at least ``persistence × (max f − min f)`` (paper, Sect. 4.2)."""
    v, faces = as_mesh(V, F)
    return np.asarray(_wfem.extrema(v, faces, as_vector(f, "f"), persistence), dtype=np.int64)
