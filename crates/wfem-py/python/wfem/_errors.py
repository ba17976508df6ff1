"""The exceptions of wfem.

Every error raised by the library is a :class:`WfemError`. Each class also derives from the
built-in exception a caller would expect (``ValueError`` for bad input, ``RuntimeError`` for a
solver that fails, ``OSError`` for files), so ``except ValueError`` keeps working.

Every instance carries

* ``kind``: the name of the Rust error variant (e.g. ``"IndexOutOfRange"``), and
* the culprit as attributes, mirroring the Rust enum's fields: ``face``, ``vertex``, ``index``,
  ``pole``, ``residual``, ``iterations``, ``t``, ``path``, ``line``, … (all of them also in
  ``details``, a dict).

Hierarchy::

    WfemError(Exception)
    ├── InvalidInputError(ValueError)   bad argument: shape, dtype, NaN, parameter, time, vertex
    │   └── InvalidTypeError(TypeError)  an argument of the wrong type (e.g. k=1.5)
    ├── MeshError(ValueError)           the mesh or mesh file is unusable (face, vertex, line)
    │   └── MeshFileError(OSError)      the file cannot be read (path, errno)
    ├── RetrievalError(ValueError)      descriptor / retrieval data problems
    ├── SolverError(RuntimeError)       a factorization or eigensolver failed (matrix, pole)
    │   ├── ConvergenceError            an iteration stopped above its tolerance (residual, iterations)
    │   └── IllConditionedError         K_{-t} refused: the answer would be amplified noise
    ├── StoreError(OSError)             the SQLite retrieval index (path, reason)
    └── InternalError(RuntimeError)     a bug in wfem (please report it)
"""

from __future__ import annotations

from typing import Any

__all__ = [
    "WfemError",
    "InvalidInputError",
    "InvalidTypeError",
    "MeshError",
    "MeshFileError",
    "RetrievalError",
    "SolverError",
    "ConvergenceError",
    "IllConditionedError",
    "StoreError",
    "InternalError",
]


class WfemError(Exception):
    """Base class of every wfem error; ``kind`` names the Rust variant, ``details`` its fields."""

    kind: str
    details: dict[str, Any]

    def __init__(self, message: str, kind: str = "", **details: Any) -> None:
        super().__init__(message)
        self.kind = kind
        self.details = dict(details)
        for name, value in details.items():
            setattr(self, name, value)

    def __reduce__(self) -> tuple[Any, ...]:
        # Keep kind and details when pickled (process pools, Dask workers).
        return (_rebuild, (type(self), str(self), self.kind, self.details))


def _rebuild(cls: type[WfemError], message: str, kind: str, details: dict[str, Any]) -> WfemError:
    return cls(message, kind, **details)


class InvalidInputError(WfemError, ValueError):
    """A bad argument: wrong shape or dtype, NaN/inf, out-of-range parameter, time or vertex."""


class InvalidTypeError(InvalidInputError, TypeError):
    """An argument of the wrong type (also a ``TypeError``), e.g. ``k=1.5`` or ``k=None``."""


class MeshError(WfemError, ValueError):
    """The mesh (or mesh file) is unusable; names the face, vertex, or file line."""


class MeshFileError(MeshError, OSError):
    """A mesh file cannot be read (``path``, and ``errno`` when the OS gave one)."""


class RetrievalError(WfemError, ValueError):
    """Descriptor or retrieval data that the computation cannot use."""


class SolverError(WfemError, RuntimeError):
    """A factorization or eigendecomposition failed (names the matrix or pole)."""


class ConvergenceError(SolverError):
    """An iteration stopped above its tolerance (``residual`` or ``estimate``, ``iterations``)."""


class IllConditionedError(SolverError):
    """The inverse heat operator K_{-t} was refused (``amplification``, ``cap``, ``residual``)."""


class StoreError(WfemError, OSError):
    """The SQLite retrieval index cannot be created, opened or read (``path``, ``reason``)."""


class InternalError(WfemError, RuntimeError):
    """A bug in wfem (a Rust panic caught at the boundary); please report it."""


class TimeWarning(UserWarning):
    """A diffusion time whose result carries no information on this mesh: so small that
    ``K_t f`` equals f to 1e−12, or past the time at infinity (the heat has spread to its mean,
    a constant result). The message names the sensible range of times for the mesh, in the
    ``time_unit`` the times were given in. Silence it with
    ``warnings.simplefilter("ignore", wfem.TimeWarning)``."""


class RefusedShapesWarning(UserWarning):
    """Some files of a collection could not be used (unreadable, or a shape that cannot be
    described) and were left out of the index; the message names each file with its reason,
    and the index's ``refused`` lists them. Pass ``strict=True`` for all-or-nothing."""


def warn_user(message: str, category: type[Warning]) -> None:
    """``warnings.warn`` attributed to the caller's own code: the first frame outside the wfem
    package (however many wfem frames — wrappers, helpers — lie between), so the warning shows
    the user's line, and a DeprecationWarning is shown by Python's default filters."""
    import os
    import sys
    import warnings

    from types import FrameType

    package = os.path.dirname(os.path.abspath(__file__))
    # stacklevel 1 is this function, 2 its caller, …
    level = 2
    frame: FrameType | None = sys._getframe(1)
    while frame is not None and os.path.dirname(os.path.abspath(frame.f_code.co_filename)) == package:
        frame = frame.f_back
        level += 1
    warnings.warn(message, category, stacklevel=level)
