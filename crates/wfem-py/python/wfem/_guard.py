"""Every error out of the public API is a :class:`WfemError`.

The Rust side raises typed errors; what is left are the built-in errors Python raises *before*
our code runs: PyO3's conversion of an argument (``OverflowError`` for ``k=-1`` or
``degree=10**20`` into an unsigned integer, ``TypeError`` for ``k=1.5``) and ``int()`` /
``float()`` / NumPy conversions in the wrappers. :func:`guard` turns those into
:class:`InvalidInputError` (or :class:`InvalidTypeError`, which is also a ``TypeError``),
naming the culprit argument when it can be found, with the original error as ``__cause__``.
A call with the wrong number of arguments (a ``TypeError`` raised when the function is
entered) is left alone: that is a bug of the caller's code, not a bad value.
"""

from __future__ import annotations

import functools
import inspect
from typing import Any, Callable

from ._errors import InvalidInputError, InvalidTypeError, WfemError

_CONVERTED = (OverflowError, TypeError, ValueError, IndexError, KeyError)
_INT_RANGE = (-(2**63), 2**64 - 1)


def _culprit(fn: Callable[..., Any], args: tuple[Any, ...], kwargs: dict[str, Any]) -> str | None:
    """The first argument that is an out-of-range or negative integer, by name."""
    try:
        bound = inspect.signature(fn).bind(*args, **kwargs)
    except (TypeError, ValueError):
        return None
    for name, value in bound.arguments.items():
        values = value if isinstance(value, (list, tuple)) else [value]
        for v in values:
            if isinstance(v, int) and not isinstance(v, bool) and (v < 0 or v > _INT_RANGE[1]):
                return name
    return None


def _convert(fn: Callable[..., Any], e: Exception, args: tuple[Any, ...], kwargs: dict[str, Any]) -> WfemError:
    name = _culprit(fn, args, kwargs)
    where = f"argument {name!r}" if name else "an argument"
    label = getattr(fn, "__qualname__", getattr(fn, "__name__", "wfem"))
    if isinstance(e, OverflowError):
        message = f"{label}: {where} is out of range (negative, or too large for its type): {e}"
    else:
        message = f"{label}: {where} is invalid: {e}"
    cls = InvalidTypeError if isinstance(e, TypeError) else InvalidInputError
    details = {"name": name} if name else {}
    return cls(message, "InvalidArgument", **details)


def guard(fn: Callable[..., Any]) -> Callable[..., Any]:
    """Wraps a public function so built-in argument errors become WfemErrors."""
    if getattr(fn, "__wfem_guarded__", False):
        return fn

    @functools.wraps(fn)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        try:
            return fn(*args, **kwargs)
        except WfemError:
            raise
        except _CONVERTED as e:
            if getattr(e, "__wfem_callback__", False):
                # Raised by the caller's own callback (progress=): theirs, unchanged.
                raise
            tb = e.__traceback__
            if isinstance(e, TypeError) and (tb is None or tb.tb_next is None):
                # Raised while entering `fn`: a wrong call (arity, keyword), not a bad value.
                raise
            raise _convert(fn, e, args, kwargs) from e

    wrapper.__wfem_guarded__ = True  # type: ignore[attr-defined]
    return wrapper


def guard_class(cls: type) -> type:
    """Guards every public method, static/class method and property of a class, in place."""
    for name, attr in list(vars(cls).items()):
        if name.startswith("_") and name not in ("__init__", "__len__", "__getitem__", "__call__"):
            continue
        if isinstance(attr, staticmethod):
            setattr(cls, name, staticmethod(guard(attr.__func__)))
        elif isinstance(attr, classmethod):
            setattr(cls, name, classmethod(guard(attr.__func__)))
        elif isinstance(attr, property):
            setattr(cls, name, property(guard(attr.fget) if attr.fget else None, attr.fset, attr.fdel, attr.__doc__))
        elif inspect.isfunction(attr):
            setattr(cls, name, guard(attr))
    return cls


def guard_namespace(namespace: dict[str, Any], names: list[str]) -> None:
    """Guards the named functions and classes of a module (functions are rebound in
    `namespace` and in their defining module, classes patched in place)."""
    import sys

    for name in names:
        obj = namespace.get(name)
        if inspect.isclass(obj) and not issubclass(obj, BaseException):
            if obj.__module__.startswith("wfem"):
                guard_class(obj)
        elif inspect.isfunction(obj):
            g = guard(obj)
            namespace[name] = g
            home = sys.modules.get(obj.__module__)
            if home is not None and getattr(home, name, None) is obj:
                setattr(home, name, g)
