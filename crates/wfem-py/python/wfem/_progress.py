"""Progress of long collection calls (``RetrievalIndex.build`` / ``add_meshes``): the Rust side
reports each finished shape; this module turns that into what the caller asked for."""

from __future__ import annotations

import sys
from contextlib import contextmanager
from typing import Any, Callable, Iterator, Union

from ._errors import InvalidInputError

#: ``progress=`` of the collection calls: ``None`` (default: a tqdm bar when tqdm is installed
#: and standard error is a terminal, otherwise silent), ``True`` (a bar — tqdm, or one line per
#: shape on standard error without it), ``False`` (silent), or a callable
#: ``progress(done, total, name)`` called on the caller's thread after each shape.
ProgressArg = Union[None, bool, Callable[[int, int, str], object]]


def user_callback(fn: Callable[..., Any] | None) -> Callable[..., Any] | None:
    """``fn`` with its exceptions marked as the caller's own: the public API re-raises them as
    they were (type, message, traceback) instead of re-typing them as an invalid argument."""
    if fn is None:
        return None

    def call(*args: Any) -> Any:
        try:
            return fn(*args)
        except BaseException as e:
            try:
                e.__wfem_callback__ = True  # type: ignore[attr-defined]
            except (AttributeError, TypeError):
                pass
            raise

    return call


def _tqdm() -> Any:
    try:
        from tqdm.auto import tqdm  # type: ignore[import-not-found, import-untyped, unused-ignore]
    except ImportError:
        return None
    return tqdm


@contextmanager
def reporter(progress: ProgressArg, total: int, what: str) -> Iterator[Callable[[str], None] | None]:
    """The callback to hand to the extension (``step(name)`` per finished shape), or ``None``
    for silence; a bar is closed when the call ends, however it ends."""
    if progress is None:
        interactive = hasattr(sys.stderr, "isatty") and sys.stderr.isatty()
        progress = bool(interactive and _tqdm() is not None)
    if progress is False:
        yield None
        return
    if progress is True:
        tqdm = _tqdm()
        if tqdm is not None:
            bar = tqdm(total=total, desc=what, unit="shape")
            try:
                yield lambda name: bar.update(1)
            finally:
                bar.close()
            return
        done = [0]

        def line(name: str) -> None:
            done[0] += 1
            print(f"{what}: {done[0]}/{total} {name}", file=sys.stderr, flush=True)

        yield line
        return
    if not callable(progress):
        raise InvalidInputError(
            f"progress must be None, True, False or a callable progress(done, total, name), "
            f"not {type(progress).__name__}",
            kind="InvalidParameter",
            name="progress",
        )
    user = user_callback(progress)
    count = [0]

    def call(name: str) -> None:
        count[0] += 1
        user(count[0], total, name)  # type: ignore[misc]

    yield call
