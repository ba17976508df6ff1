"""Geodesic distances on meshes and point clouds: fast marching on the intrinsic Delaunay
triangulation (the default) or the heat method of Crane et al. 2013, potpourri3d's arguments."""

from __future__ import annotations

import os
from typing import Any, Callable, Sequence

import numpy as np

from . import _choices, _wfem
from ._arrays import as_float_array, as_indices, as_mesh, points_of
from ._errors import InvalidInputError, warn_user

#: The library's default parameters by group (one place: the Rust crates).
_DEFAULTS = _wfem.DEFAULTS

__all__ = ["GeodesicSolver", "GeodesicWarning", "geodesic_distance", "GEODESIC_METHODS"]

#: Names accepted by ``method=`` of :class:`GeodesicSolver`, default first (the library's registry).
GEODESIC_METHODS = _choices.names("geodesic_method")


class GeodesicWarning(UserWarning):
    """Some vertices lie in connected components without a source (their distance is ``inf``),
    or the heat method's heat underflowed far from the sources (its distances are unreliable
    there; ``method="fast-marching"`` has no such limit)."""


def _warn(unreachable: int, underflow: int) -> None:
    if unreachable:
        warn_user(
            f"{unreachable} vertices lie in connected components without a source: their distance is inf",
            GeodesicWarning,
        )
    if underflow:
        warn_user(
            f"the heat method's heat underflowed at {underflow} vertices far from the sources: their "
            'distances are unreliable; method="fast-marching" has no such limit',
            GeodesicWarning,
        )


class GeodesicSolver:
    """Geodesic distances on one mesh or point cloud, prepared once for many queries.

    * ``method="fast-marching"`` (default): the eikonal equation on the intrinsic Delaunay
      triangulation (Sharp & Crane 2020) with each source's one-ring at its exact edge lengths;
      no factorization. Against exact polyhedral geodesics its mean error is 0.1–0.3 times the
      heat method's (docs/BENCHMARKS.md).
    * ``method="heat"``: the heat method — one backward-Euler solve ``(M + tL) u = δ`` with
      ``t = t_coef · h²`` (h the mean edge length), the normalised gradient, one Poisson solve
      pinned on every source: potpourri3d's ``MeshHeatMethodDistanceSolver`` numbers.

    ``use_robust=True`` (default, as potpourri3d) works on the intrinsic Delaunay triangulation
    of the tufted cover; ``False`` on the mesh's own triangles (cotangent Laplacian).
    ``refine=r`` splits every triangle into four r times first (same surface, more accurate,
    about 4ʳ times the work); distances are still returned at the mesh's vertices.

    A switch from potpourri3d is one line: ``pp3d.MeshHeatMethodDistanceSolver(V, F)`` →
    ``wfem.GeodesicSolver(V, F)``; ``compute_distance(i)`` and
    ``compute_distance_multisource(idx)`` work as there. Pass only P for a point cloud
    (potpourri3d's ``PointCloudHeatSolver(P)``).

    Args:
        V, F: vertices (n, 3) and triangles (m, 3), or one object with ``.vertices``/``.faces``,
            or a point cloud P (n, 3) without F.
        method: one of :data:`GEODESIC_METHODS`.
        t_coef: the heat method's time in units of h² (> 0).
        use_robust: the intrinsic Delaunay triangulation (meshes only).
        refine: midpoint refinements (0 to ``wfem._wfem.MAX_REFINE``).
        n_neighbors: neighbours of a point cloud's local triangulations.

    Raises:
        MeshError: the mesh cannot be used (names the face or vertex).
        InvalidInputError: a bad method, ``t_coef`` or ``refine``.
    """

    _s: Any

    def __init__(
        self,
        V: Any,
        F: Any = None,
        *,
        method: str | None = None,
        t_coef: float = _wfem.DEFAULT_T_COEF,
        use_robust: bool = True,
        refine: int = _DEFAULTS["geodesic"]["refine"],
        n_neighbors: int | None = None,
    ) -> None:
        from ._volume import tets_of

        tets = tets_of(V, F)
        if tets is not None:
            if refine:
                raise InvalidInputError("a volume cannot be refined; use refine=0", "InvalidParameter", name="refine")
            self._s = _wfem.GeodesicSolver.from_volume(*tets, method, float(t_coef))
            return
        P = points_of(V, F)
        if P is not None:
            if not use_robust or refine:
                raise InvalidInputError(
                    "a point cloud has only the robust triangulation and cannot be refined",
                    "InvalidParameter",
                    name="use_robust" if not use_robust else "refine",
                )
            self._s = _wfem.GeodesicSolver.from_cloud(as_float_array(P, "P", (2,)), method, float(t_coef), n_neighbors)
            return
        v, f = as_mesh(V, F)
        self._s = _wfem.GeodesicSolver.from_mesh(v, f, method, float(t_coef), bool(use_robust), int(refine))

    def __repr__(self) -> str:
        return f"GeodesicSolver(n={self.n}, t={self.t})"

    @property
    def n(self) -> int:
        """Number of vertices (points)."""
        return int(self._s.n)

    @property
    def t(self) -> float | None:
        """The heat method's time t = t_coef · h² (None for fast marching)."""
        return self._s.t

    @property
    def mean_edge_length(self) -> float:
        """The mean edge length h of the triangulation."""
        return float(self._s.mean_edge_length)

    @property
    def memory_bytes(self) -> int:
        """Approximate memory of the prepared solver."""
        return int(self._s.memory_bytes)

    def distance(self, sources: int | Sequence[int], points: Any = None) -> np.ndarray:
        """Distances (n,) to the nearest source: vertex indices, and ``points`` as rows
        ``(face, b0, b1, b2)`` of a face and barycentric coordinates (≥ 0, summing to 1).
        A vertex no source reaches gets ``inf`` (with a :class:`GeodesicWarning`)."""
        vertices = as_indices([sources] if np.isscalar(sources) else sources, "sources")
        pts: list[tuple[int, float, float, float]] = []
        if points is not None:
            p = np.asarray(points, dtype=float)
            if p.ndim != 2 or p.shape[1] != 4:
                raise InvalidInputError(f"points must have shape (m, 4), got {p.shape}", "Shape", name="points")
            if not np.all(np.isfinite(p[:, 0]) & (p[:, 0] == np.floor(p[:, 0]))):
                raise InvalidInputError("the first column of points holds face indices", "Invalid", name="points")
            faces = as_indices(p[:, 0].astype(np.int64), "points")
            pts = [(int(f), float(a), float(b), float(c)) for f, (a, b, c) in zip(faces, p[:, 1:])]
        d, (unreachable, underflow) = self._s.distance(vertices, pts)
        _warn(unreachable, underflow)
        return np.asarray(d)

    def distance_each(self, sources: Sequence[int]) -> np.ndarray:
        """One row per source vertex (|S|, n): row i is the distance from ``sources[i]``."""
        return np.asarray(self._s.distance_each(as_indices(sources, "sources")))

    def compute_distance(self, v_ind: int) -> np.ndarray:
        """potpourri3d's name: the distance from one vertex."""
        return self.distance([v_ind])

    def compute_distance_multisource(self, v_inds: Sequence[int]) -> np.ndarray:
        """potpourri3d's name: the distance to the nearest of several vertices."""
        return self.distance(v_inds)

    def all_pairs(
        self,
        out: str | os.PathLike[str],
        progress: Callable[[str], Any] | None = None,
        block_rows: int | None = None,
    ) -> str:
        """The n × n matrix of distances (row i from vertex i) streamed to the ``.npy`` file
        ``out`` in blocks of rows: memory holds the solver and 64 MB of rows whatever n. The
        file appears complete or not at all; an interrupted call leaves a partial file beside it
        that the same call continues. ``progress("done/total")`` is called after each block;
        ``block_rows`` rows are computed at a time (default: 64 MB of them). Returns the path."""
        from ._progress import user_callback

        path, _ = self._s.all_pairs(os.fspath(out), user_callback(progress), block_rows)
        return str(path)


def geodesic_distance(V: Any, F: Any = None, sources: int | Sequence[int] = 0, **options: Any) -> np.ndarray:
    """Geodesic distances (n,) from source vertices, with a solver prepared for this one call
    (options as :class:`GeodesicSolver`; prepare one solver for several calls)."""
    return GeodesicSolver(V, F, **options).distance(sources)
