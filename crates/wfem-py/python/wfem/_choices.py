"""The library's registries (masses, methods, backends, descriptors, …), read once from the
extension: every name, alias, help line and default comes from the Rust types, so the Python
layer keeps no copy of a name. ``wfem.choices()`` shows them."""

from __future__ import annotations

import warnings
from typing import Any

from . import _wfem
from ._errors import warn_user

_TABLES: dict[str, Any] = _wfem.choices()


def names(argument: str) -> tuple[str, ...]:
    """The canonical names accepted by ``argument`` (e.g. ``names("method")``), in order."""
    return tuple(_TABLES[argument]["names"])


def default(argument: str) -> str:
    """The default name of ``argument``."""
    return str(_TABLES[argument]["default"])


def canonical(argument: str, name: str) -> str:
    """The canonical spelling of ``name`` (an alias, any case, ``_`` for ``-``); an unknown
    name raises :class:`InvalidInputError` listing the valid ones."""
    return str(_wfem.canonical(argument, name))


def choices() -> dict[str, dict[str, Any]]:
    """Every choice of the API by the argument that takes it: ``{argument: {"default": name,
    "names": {name: (help, aliases)}}}``."""
    return {
        k: {"what": v["what"], "default": v["default"], "names": dict(v["names"])}
        for k, v in _TABLES.items()
        if isinstance(v, dict)
    }


def mass_of(mass: str | None, kernel: str | None, lumped: str | None) -> str | None:
    """``mass=`` with the older spellings folded in: ``kernel=`` (the same names) and ``lumped=``
    (the lumped mass of ``kernel="lumped"``), each with a :class:`DeprecationWarning`."""
    if kernel is not None:
        warn_user("kernel= is now mass= (same names)", DeprecationWarning)
        if mass is None:
            mass = kernel
    if lumped is not None:
        warn_user("lumped= is now mass= (e.g. mass='voronoi')", DeprecationWarning)
        lumped_masses = set(_TABLES["lumped_masses"])
        if canonical("mass", lumped) not in lumped_masses:
            from ._errors import InvalidInputError

            raise InvalidInputError(f"lumped={lumped!r} is not a lumped mass", "InvalidParameter", name="lumped")
        if mass is not None and canonical("mass", mass) not in lumped_masses:
            from ._errors import InvalidInputError

            raise InvalidInputError(
                f"lumped={lumped!r} refines a lumped mass, not mass={mass!r}: pass mass={lumped!r}",
                "InvalidParameter",
                name="lumped",
            )
        mass = lumped
    return mass
