"""Argument conversion shared by the whole package.

Conventions (those of libigl): ``V`` is a float64 array of shape (n, 3), ``F`` an integer array
of shape (m, 3) (0-based vertex indices, one row per triangle). Any object with ``.vertices``
and ``.faces`` (a ``trimesh.Trimesh``, a pyFM ``TriMesh``, …) is accepted in place of (V, F).

* float32 (and other real float or integer) coordinates are converted to float64; integer
  faces of any width to int64; bool, complex, object and float faces are refused with
  :class:`~wfem.InvalidInputError` (faces must be integers).
* Fortran-ordered, strided or read-only arrays are fine: the compiled code copies what it
  reads. Inputs are never modified.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.sparse as sp

from ._errors import InvalidInputError

Array = np.ndarray


def _kind_name(a: np.ndarray) -> str:
    return f"{a.dtype} array"


def as_float_array(x: Any, name: str, ndim: tuple[int, ...] = (1, 2)) -> np.ndarray:
    """``x`` as a float64 array with one of the given numbers of dimensions."""
    try:
        a = np.asarray(x)
    except Exception as e:  # noqa: BLE001 - any conversion failure is bad input
        raise InvalidInputError(f"{name} cannot be converted to an array: {e}", "DType", name=name) from e
    if a.dtype.kind not in "fiu":
        raise InvalidInputError(
            f"{name} must hold real numbers (float or int), got a {_kind_name(a)}", "DType", name=name
        )
    if a.ndim not in ndim:
        want = " or ".join(f"{d}-D" for d in ndim)
        raise InvalidInputError(f"{name} must be {want}, got shape {a.shape}", "Shape", name=name)
    return a.astype(np.float64, copy=False)


def as_vector(x: Any, name: str) -> np.ndarray:
    """A float64 vector (1-D)."""
    return as_float_array(x, name, (1,))


def as_times(t: Any) -> tuple[list[float], bool]:
    """Diffusion times as a list, and whether a scalar was given."""
    a = as_float_array(t, "t", (0, 1))
    if a.ndim == 0:
        return [float(a)], True
    if a.size == 0:
        raise InvalidInputError("t is empty: give at least one diffusion time", "Empty", name="t")
    return [float(x) for x in a], False


def as_indices(x: Any, name: str) -> list[int]:
    """Non-negative integer indices (a scalar or 1-D sequence) as a list."""
    a = np.asarray(x)
    if a.ndim > 1:
        raise InvalidInputError(f"{name} must be 1-D, got shape {a.shape}", "Shape", name=name)
    if a.size and a.dtype.kind not in "iu":
        raise InvalidInputError(f"{name} must be integers, got a {_kind_name(a)}", "DType", name=name)
    a = a.reshape(-1).astype(np.int64)
    if a.size and a.min() < 0:
        bad = int(a[a < 0][0])
        raise InvalidInputError(f"{name} holds the negative index {bad}", "NegativeIndex", name=name, index=bad)
    return [int(i) for i in a]


def points_of(V: Any, F: Any = None) -> np.ndarray | None:
    """The points of a point cloud given where a mesh is accepted — ``F`` absent and ``V`` an
    (n, 3) array or an object with ``.vertices`` but no ``.faces`` — or None for a mesh."""
    if F is not None or (hasattr(V, "vertices") and hasattr(V, "faces")):
        return None
    if hasattr(V, "vertices"):
        V = V.vertices
    a = as_float_array(V, "P", (2,))
    if a.shape[1:] != (3,):
        raise InvalidInputError(f"P must have shape (n, 3), got {a.shape}", "Shape", name="P")
    return a


def as_mesh(V: Any, F: Any = None) -> tuple[np.ndarray, np.ndarray]:
    """(V float64 (n, 3), F int64 (m, 3)) from arrays or an object with .vertices/.faces."""
    if F is None:
        if hasattr(V, "vertices") and hasattr(V, "faces"):
            V, F = V.vertices, V.faces
        else:
            raise InvalidInputError(
                "give V and F, or one object with .vertices and .faces (e.g. a trimesh.Trimesh)",
                "MissingFaces",
            )
    v = as_float_array(V, "V", (2,))
    if v.shape[1:] != (3,):
        raise InvalidInputError(f"V must have shape (n, 3), got {v.shape}", "Shape", name="V")
    f = np.asarray(F)
    if f.dtype.kind not in "iu":
        raise InvalidInputError(
            f"F must hold integer vertex indices, got a {_kind_name(f)}"
            + (" (convert with F.astype(np.int64) if the values are whole numbers)" if f.dtype.kind == "f" else ""),
            "DType",
            name="F",
        )
    if f.ndim != 2 or f.shape[1] != 3:
        raise InvalidInputError(f"F must have shape (m, 3) (triangles) or (m, 4) (tetrahedra), got {f.shape}", "Shape", name="F")
    if f.dtype == np.uint64 and f.size and int(f.max()) > np.iinfo(np.int64).max:
        raise InvalidInputError("F holds indices beyond int64", "IndexOutOfRange", name="F")
    f = f.astype(np.int64, copy=False)
    if f.size and f.min() < 0:
        face = int(np.argwhere(f < 0)[0][0])
        raise InvalidInputError(
            f"face {face} uses the negative vertex index {int(f[face].min())}",
            "NegativeIndex",
            face=face,
            index=int(f[face].min()),
        )
    return v, f


SparseParts = tuple[np.ndarray, np.ndarray, np.ndarray, tuple[int, int]]


def as_sparse(A: Any, name: str) -> SparseParts:
    """A real square-or-not matrix (scipy.sparse or dense) as CSC parts for the compiled code."""
    try:
        if sp.issparse(A):
            if A.dtype.kind not in "fiu":
                raise InvalidInputError(f"{name} must be real, got dtype {A.dtype}", "DType", name=name)
            c = sp.csc_matrix(A, dtype=np.float64, copy=True)
        else:
            d = as_float_array(A, name, (2,))
            c = sp.csc_matrix(d)
    except InvalidInputError:
        raise
    except Exception as e:  # noqa: BLE001
        raise InvalidInputError(f"{name} cannot be read as a sparse matrix: {e}", "SparseMatrix", name=name) from e
    c.sum_duplicates()
    return (
        np.asarray(c.indptr, dtype=np.int64),
        np.asarray(c.indices, dtype=np.int64),
        np.asarray(c.data, dtype=np.float64),
        (int(c.shape[0]), int(c.shape[1])),
    )


def to_csc(parts: SparseParts) -> sp.csc_matrix:
    indptr, indices, data, shape = parts
    return sp.csc_matrix((data, indices, indptr), shape=shape)
