"""Generated meshes (from ``mesh_fem::generate``): each function returns ``(V, F)``, V float64
(n, 3) and F int64 (m, 3). For tests, examples and benchmarks; no file needed."""

from __future__ import annotations

import numpy as np

from . import _wfem

__all__ = ["icosphere", "uv_sphere", "grid", "torus", "irregular_sphere", "bumpy"]

Mesh = tuple[np.ndarray, np.ndarray]


#: The test torus unless told otherwise: radii 1 and 0.3, 32 × 16 vertices.
TORUS = (1.0, 0.3, 32, 16)
#: How much the face areas of ``irregular_sphere`` vary unless told otherwise (about s⁴).
IRREGULARITY = 4.0


def icosphere(level: int) -> Mesh:
    """Unit icosphere: 10·4^level + 2 vertices (level 0: the icosahedron)."""
    return _wfem.icosphere(int(level))


def uv_sphere(rings: int, segments: int) -> Mesh:
    """Unit latitude/longitude sphere, rings ≥ 2, segments ≥ 3."""
    return _wfem.uv_sphere(int(rings), int(segments))


def grid(nx: int, ny: int) -> Mesh:
    """Open grid on the unit square [0, 1]² (z = 0) with nx × ny vertices (≥ 2 × 2)."""
    return _wfem.grid(int(nx), int(ny))


def torus(major: float = TORUS[0], minor: float = TORUS[1], nu: int = TORUS[2], nv: int = TORUS[3]) -> Mesh:
    """Torus with radii 0 < minor < major, nu × nv vertices (genus 1)."""
    return _wfem.torus(float(major), float(minor), int(nu), int(nv))


def irregular_sphere(level: int, s: float = IRREGULARITY) -> Mesh:
    """Unit sphere whose face areas vary by about s⁴ (a conformally dilated icosphere)."""
    return _wfem.irregular_sphere(int(level), float(s))


def bumpy(level: int) -> Mesh:
    """The CLI demo's irregular sphere with smooth radial bumps."""
    return _wfem.bumpy(int(level))
