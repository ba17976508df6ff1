"""Descriptors and bags of features over a collection of mesh files, on any executor.

Every function takes a list of mesh **paths** (workers read the files themselves, so nothing
large travels to them) and a :class:`concurrent.futures.Executor`:

* default: a local process pool (``spawn``; each worker limited to one Rust thread unless
  ``RAYON_NUM_THREADS`` is set, so the pool does not oversubscribe the cores);
* **Dask** (the documented engine, locally, on SLURM through dask-jobqueue, or on a cloud
  cluster)::

      from dask.distributed import Client, LocalCluster
      client = Client(LocalCluster(n_workers=8, threads_per_worker=1))
      table = wfem.batch.bags(paths, vocabulary, out_dir="bags/", executor=client.get_executor())

* :class:`SerialExecutor`: in this process, one mesh after the other (debugging, tests).

**One broken mesh gives an error row, never a failed job**: each row has ``ok``, and for a
failure ``error_type`` (e.g. ``"MeshError"``), ``error_kind`` (the Rust variant, e.g.
``"IndexOutOfRange"``) and ``error`` (the message). Rows come back in input order. With
``out_dir``, rows are written as Parquet shards ``part-00000.parquet``, … of ``shard_size`` rows,
each written atomically (temporary file + rename), then ``manifest.json`` listing them; a
directory without a manifest is an interrupted run. :func:`read` loads a finished output.

**One folder, one run.** ``run.json`` (written first) records the settings. A folder that
already holds a run is refused unless ``replace=True`` (the new run is written beside it and
renamed into place only once complete, so the old run stays readable until then) or
``resume=True`` (the shapes already in its shards are skipped; the settings, the shard size
and the order of the paths must be those of the first run, or it is refused). What a process
killed in a write left (``.<name>.<pid>.tmp`` of a process that no longer runs, e.g. after a
``kill -9``) is removed by the next run in the folder, and the half-built ``.<folder>.<pid>.new``
sibling of a killed ``replace=True`` run by the next replacing one; a folder that held nothing else (killed
while ``run.json`` was written) counts as empty.

Columns: ``path``, ``ok``, ``error_type``, ``error_kind``, ``error``, ``n_vertices``, ``n_faces``,
``area``, then ``descriptor`` (flattened row-major, with ``dim``; :func:`descriptor_arrays`
reshapes) or ``bag`` (the normalised bag, ``Θᵀa/Σa``).
"""

from __future__ import annotations

import concurrent.futures as cf
import json
import multiprocessing
import os
import threading
from typing import Any, Callable, Iterable, Sequence

import numpy as np

from . import _wfem

#: The library's default parameters by group (one place: the Rust crates).
_DEFAULTS = _wfem.DEFAULTS
#: Rows per Parquet shard unless told otherwise.
DEFAULT_SHARD_SIZE = 64

__all__ = ["descriptors", "bags", "read", "descriptor_arrays", "SerialExecutor", "default_executor"]


class SerialExecutor(cf.Executor):
    """Runs each task at submission, in this process (a drop-in Executor for debugging)."""

    def __init__(self) -> None:
        self._shutdown = False
        self._lock = threading.Lock()

    def submit(self, fn: Callable[..., Any], /, *args: Any, **kwargs: Any) -> cf.Future[Any]:
        with self._lock:
            if self._shutdown:
                raise RuntimeError("cannot submit after shutdown")
        future: cf.Future[Any] = cf.Future()
        try:
            future.set_result(fn(*args, **kwargs))
        except BaseException as e:  # noqa: BLE001 - delivered through the future
            future.set_exception(e)
        return future

    def shutdown(self, wait: bool = True, *, cancel_futures: bool = False) -> None:
        with self._lock:
            self._shutdown = True


def _limit_threads() -> None:
    # Runs in each worker of the default pool before wfem is imported there.
    os.environ.setdefault("RAYON_NUM_THREADS", "1")


def default_executor(max_workers: int | None = None) -> cf.Executor:
    """A process pool of ``max_workers`` (default: the number of CPUs) spawned workers."""
    return cf.ProcessPoolExecutor(
        max_workers=max_workers or os.cpu_count() or 1,
        mp_context=multiprocessing.get_context("spawn"),
        initializer=_limit_threads,
    )


def _failure(path: str, e: BaseException) -> dict[str, Any]:
    return {
        "path": path,
        "ok": False,
        "error_type": type(e).__name__,
        "error_kind": getattr(e, "kind", "") or "",
        "error": str(e),
    }


def _load(path: str) -> tuple[Any, Any, dict[str, Any]]:
    import wfem

    V, F = wfem.read_mesh(path)
    K = wfem.HeatKernel(V, F)
    areas = K.vertex_areas
    base = {
        "path": path,
        "ok": True,
        "error_type": None,
        "error_kind": None,
        "error": None,
        "n_vertices": int(V.shape[0]),
        "n_faces": int(F.shape[0]),
        "area": float(areas.sum()),
    }
    return (V, F), areas, base


def _descriptor_task(path: str, options: dict[str, Any]) -> dict[str, Any]:
    """One mesh → one row (never raises for a bad mesh)."""
    try:
        import wfem

        (V, F), _, row = _load(path)
        d = wfem.descriptor(V, F, **options)
        row["dim"] = int(d.shape[1])
        row["descriptor"] = np.ascontiguousarray(d).reshape(-1).tolist()
        return row
    except Exception as e:  # noqa: BLE001 - a broken mesh is a row, not a failed job
        return _failure(path, e)


def _bag_task(path: str, options: dict[str, Any], vocabulary: dict[str, Any]) -> dict[str, Any]:
    try:
        import wfem

        (V, F), areas, row = _load(path)
        d = wfem.descriptor(V, F, **options)
        voc = wfem.Vocabulary.from_dict(vocabulary)
        row["bag"] = voc.bag(d, areas).tolist()
        return row
    except Exception as e:  # noqa: BLE001
        return _failure(path, e)


def _require(module: str) -> Any:
    """An optional dependency of wfem.batch, or an error that names it and the extra that
    installs it (``pip install 'wfem[batch]'``)."""
    import importlib

    try:
        return importlib.import_module(module)
    except ModuleNotFoundError as e:
        top = module.split(".")[0]
        raise ModuleNotFoundError(
            f"wfem.batch needs {top}, an optional dependency of wfem: pip install 'wfem[batch]' "
            f"(or pip install {top})",
            name=e.name,
        ) from e


def _schema(kind: str) -> Any:
    pa = _require("pyarrow")

    fields = [
        ("path", pa.string()),
        ("ok", pa.bool_()),
        ("error_type", pa.string()),
        ("error_kind", pa.string()),
        ("error", pa.string()),
        ("n_vertices", pa.int64()),
        ("n_faces", pa.int64()),
        ("area", pa.float64()),
    ]
    if kind == "descriptor":
        fields += [("dim", pa.int64()), ("descriptor", pa.list_(pa.float64()))]
    else:
        fields += [("bag", pa.list_(pa.float64()))]
    return pa.schema(fields)


def _table(rows: Sequence[dict[str, Any]], kind: str) -> Any:
    pa = _require("pyarrow")

    schema = _schema(kind)
    return pa.Table.from_pylist([{name: row.get(name) for name in schema.names} for row in rows], schema=schema)


def _write_atomic(table: Any, path: str) -> None:
    pq = _require("pyarrow.parquet")

    tmp = os.path.join(os.path.dirname(path), f".{os.path.basename(path)}.{os.getpid()}.tmp")
    try:
        pq.write_table(table, tmp)
        with open(tmp, "rb") as f:
            os.fsync(f.fileno())
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)


def _fail(message: str, path: str, kind: str = "BatchOutput") -> Exception:
    from ._errors import InvalidInputError

    return InvalidInputError(message, kind, path=path)


_RUN = "run.json"
_MANIFEST = "manifest.json"


def _shard_name(index: int) -> str:
    return f"part-{index:05d}.parquet"


def _write_json(obj: Any, path: str) -> None:
    tmp = os.path.join(os.path.dirname(path), f".{os.path.basename(path)}.{os.getpid()}.tmp")
    with open(tmp, "w") as f:
        json.dump(obj, f, indent=1)
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)


def _done_rows(out: str, settings: dict[str, Any], names: list[str]) -> tuple[list[dict[str, Any]], list[str]]:
    """Rows and shards of an earlier run in `out` to resume (checked against this run)."""
    import pyarrow.parquet as pq

    run_file = os.path.join(out, _RUN)
    if not os.path.exists(run_file):
        raise _fail(f"{out} holds no {_RUN}: not a wfem.batch output, cannot resume it", out)
    with open(run_file) as f:
        try:
            before = json.load(f)
        except ValueError as e:
            raise _fail(f"{run_file} is not valid JSON ({e}); cannot resume", run_file) from e
    for key in sorted(set(before) | set(settings)):
        if before.get(key) != settings.get(key):
            raise _fail(
                f"cannot resume {out}: its {key} is {before.get(key)!r}, this run's is {settings.get(key)!r} "
                "(a resumed run never mixes settings; use replace=True)",
                out,
                "ResumeMismatch",
            )
    rows: list[dict[str, Any]] = []
    shards: list[str] = []
    while os.path.exists(os.path.join(out, _shard_name(len(shards)))):
        name = _shard_name(len(shards))
        rows += pq.read_table(os.path.join(out, name)).to_pylist()
        shards.append(name)
    done = [r["path"] for r in rows]
    if done != names[: len(done)]:
        raise _fail(
            f"cannot resume {out}: its {len(done)} rows are not the first {len(done)} paths of this run "
            "(same paths in the same order are needed; use replace=True)",
            out,
            "ResumeMismatch",
        )
    return rows, shards


def _alive(pid: int) -> bool:
    """Whether a process with this id runs (one of another user counts as running)."""
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError, ValueError):
        return True
    return True


def _sweep_dead(out: str) -> list[str]:
    """Removes from `out` the temporary files ``.<name>.<pid>.tmp`` of processes that no longer
    run (a ``kill -9`` in a write) and returns their names; those of a running process stay."""
    removed = []
    for name in sorted(os.listdir(out)):
        parts = name.rsplit(".", 2)
        if not (name.startswith(".") and len(parts) == 3 and parts[2] == "tmp" and parts[1].isdigit()):
            continue
        if not _alive(int(parts[1])):
            try:
                os.remove(os.path.join(out, name))
                removed.append(name)
            except FileNotFoundError:
                pass
    return removed


def _sweep_dead_siblings(parent: str, base: str) -> None:
    """Removes the half-built ``.<base>.<pid>.new`` / ``.old`` folders of a replacing run whose
    process no longer runs."""
    import shutil

    for name in os.listdir(parent):
        if not name.startswith(f".{base}."):
            continue
        parts = name[len(base) + 2 :].split(".")
        if len(parts) == 2 and parts[0].isdigit() and parts[1] in ("new", "old") and not _alive(int(parts[0])):
            shutil.rmtree(os.path.join(parent, name), ignore_errors=True)


def _is_run(out: str) -> bool:
    """Whether `out` holds something of an earlier run, once what dead processes left half
    written is removed (a run killed while writing ``run.json`` leaves nothing else)."""
    if not os.path.isdir(out):
        return False
    _sweep_dead(out)
    return bool(os.listdir(out))


def _run(
    task: Callable[..., dict[str, Any]],
    extra: tuple[Any, ...],
    paths: Iterable[str | os.PathLike[str]],
    kind: str,
    out_dir: str | os.PathLike[str] | None,
    executor: cf.Executor | None,
    shard_size: int,
    settings: dict[str, Any],
    replace: bool,
    resume: bool,
) -> Any:
    import shutil

    if isinstance(shard_size, bool) or not isinstance(shard_size, int) or shard_size < 1:
        raise _fail(f"shard_size must be an integer ≥ 1, not {shard_size!r}", "", "InvalidParameter")
    if replace and resume:
        raise _fail("replace=True and resume=True exclude each other", "", "InvalidParameter")
    names: list[str] = [os.fspath(p) for p in paths]
    out = None if out_dir is None else os.fspath(out_dir)
    target = out  # the folder written to (a sibling when replacing)
    rows: list[dict[str, Any]] = []
    shards: list[str] = []
    settings = {"kind": kind, "shard_size": shard_size, **settings}
    if out is not None:
        if os.path.exists(out) and not os.path.isdir(out):
            raise _fail(f"{out} exists and is not a folder", out)
        if _is_run(out):
            if resume:
                rows, shards = _done_rows(out, settings, names)
                manifest = os.path.join(out, _MANIFEST)
                if os.path.exists(manifest):
                    os.remove(manifest)
            elif replace:
                parent = os.path.dirname(os.path.abspath(out))
                _sweep_dead_siblings(parent, os.path.basename(os.path.abspath(out)))
                target = os.path.join(parent, f".{os.path.basename(os.path.abspath(out))}.{os.getpid()}.new")
                shutil.rmtree(target, ignore_errors=True)
            else:
                raise _fail(
                    f"{out} already holds a run; pass replace=True to replace it (atomically) or "
                    "resume=True to finish it",
                    out,
                    "OutputExists",
                )
        assert target is not None
        os.makedirs(target, exist_ok=True)
        if not shards:
            _write_json(settings, os.path.join(target, _RUN))
    try:
        return _compute(task, extra, names, kind, out, target, executor, shard_size, rows, shards)
    except BaseException:
        if out is not None and target is not None and target != out:
            shutil.rmtree(target, ignore_errors=True)  # the old run stays as it was
        raise


def _compute(
    task: Callable[..., dict[str, Any]],
    extra: tuple[Any, ...],
    names: list[str],
    kind: str,
    out: str | None,
    target: str | None,
    executor: cf.Executor | None,
    shard_size: int,
    rows: list[dict[str, Any]],
    shards: list[str],
) -> Any:
    import shutil

    pa = _require("pyarrow")

    todo = names[len(rows) :]
    own = executor is None and bool(todo)
    ex: cf.Executor | None = (default_executor() if own else executor) if todo else None
    try:
        futures = [ex.submit(task, p, *extra) for p in todo] if ex is not None else []
        pending: list[dict[str, Any]] = []
        for path, fut in zip(todo, futures):
            try:
                row = fut.result()
            except Exception as e:  # noqa: BLE001 - a lost worker is an error row too
                row = _failure(path, e)
            rows.append(row)
            pending.append(row)
            if target is not None and len(pending) == shard_size:
                shards.append(_flush(pending, kind, target, len(shards)))
                pending = []
        if target is not None and (pending or not shards):
            shards.append(_flush(pending, kind, target, len(shards)))
    finally:
        if own and ex is not None:
            ex.shutdown(wait=True, cancel_futures=True)
    if target is not None:
        meta = {"kind": kind, "rows": len(rows), "failed": sum(not r["ok"] for r in rows), "shards": shards}
        _write_json(meta, os.path.join(target, _MANIFEST))
        if out is not None and target != out:
            # The complete new run takes the old one's place; the old one is then removed.
            old = f"{target[:-4]}.old"
            shutil.rmtree(old, ignore_errors=True)
            os.rename(out, old)
            os.rename(target, out)
            shutil.rmtree(old, ignore_errors=True)
    return _table(rows, kind) if rows else pa.Table.from_pylist([], schema=_schema(kind))


def _flush(rows: list[dict[str, Any]], kind: str, out: str, index: int) -> str:
    name = _shard_name(index)
    _write_atomic(_table(rows, kind), os.path.join(out, name))
    return name


def descriptors(
    paths: Iterable[str | os.PathLike[str]],
    out_dir: str | os.PathLike[str] | None = None,
    *,
    executor: cf.Executor | None = None,
    kind: str = "sihks",
    k: int = _DEFAULTS["eigen"]["k"],
    times: Sequence[float] | None = None,
    sihks: dict[str, Any] | None = None,
    shard_size: int = DEFAULT_SHARD_SIZE,
    replace: bool = False,
    resume: bool = False,
) -> Any:
    """The dense descriptor ``kind`` (see :func:`wfem.descriptors`) of every mesh, as a
    ``pyarrow.Table`` (one row per path, input order), also written to ``out_dir`` as Parquet
    shards when given (``replace``/``resume``: see the module documentation)."""
    options = {"kind": kind, "k": k, "times": None if times is None else list(times), "sihks": sihks}
    return _run(
        _descriptor_task, (options,), paths, "descriptor", out_dir, executor, shard_size,
        {"options": options}, replace, resume,
    )


def bags(
    paths: Iterable[str | os.PathLike[str]],
    vocabulary: Any,
    out_dir: str | os.PathLike[str] | None = None,
    *,
    executor: cf.Executor | None = None,
    kind: str = "sihks",
    k: int = _DEFAULTS["eigen"]["k"],
    times: Sequence[float] | None = None,
    sihks: dict[str, Any] | None = None,
    shard_size: int = DEFAULT_SHARD_SIZE,
    replace: bool = False,
    resume: bool = False,
) -> Any:
    """The normalised bag of features ``Θᵀa/Σa`` of every mesh with ``vocabulary`` (a
    :class:`wfem.Vocabulary`), descriptor ``kind`` and vertex areas ``a = B·1``; see
    :func:`descriptors` for the output."""
    options = {"kind": kind, "k": k, "times": None if times is None else list(times), "sihks": sihks}
    voc = vocabulary.to_dict() if hasattr(vocabulary, "to_dict") else dict(vocabulary)
    record = {"options": options, "vocabulary": json.loads(json.dumps(voc, default=_plain))}
    return _run(_bag_task, (options, voc), paths, "bag", out_dir, executor, shard_size, record, replace, resume)


def _plain(x: Any) -> Any:
    # NumPy arrays and scalars in a vocabulary dict, as JSON.
    return x.tolist() if hasattr(x, "tolist") else str(x)


def read(out_dir: str | os.PathLike[str]) -> Any:
    """The table written by :func:`descriptors` or :func:`bags` into ``out_dir``.

    Raises :class:`wfem.InvalidInputError` (``kind="BatchOutput"``, ``path``) saying exactly
    what is wrong: no such folder, an interrupted run (no manifest; resume it), a manifest
    that is not JSON, a listed shard missing or unreadable, a shard not listed (left by
    another run), or a row count that differs from the manifest's."""
    pa = _require("pyarrow")
    pq = _require("pyarrow.parquet")

    out = os.fspath(out_dir)
    if not os.path.isdir(out):
        raise _fail(f"{out} is not a folder" if os.path.exists(out) else f"no such folder: {out}", out)
    manifest = os.path.join(out, _MANIFEST)
    present = sorted(f for f in os.listdir(out) if f.startswith("part-") and f.endswith(".parquet"))
    if not os.path.exists(manifest):
        raise _fail(
            f"{out} has no {_MANIFEST}: the run did not finish ({len(present)} shards written); "
            "run it again with resume=True",
            manifest,
            "Interrupted",
        )
    try:
        with open(manifest) as f:
            meta = json.load(f)
        listed = list(meta["shards"])
        expected_rows = int(meta["rows"])
    except (ValueError, KeyError, TypeError) as e:
        raise _fail(f"{manifest} is not a wfem.batch manifest: {e}", manifest) from e
    missing = [s for s in listed if s not in present]
    if missing:
        raise _fail(f"{out}: the manifest lists {missing[0]}, which is missing", os.path.join(out, missing[0]))
    extra = [s for s in present if s not in listed]
    if extra:
        raise _fail(
            f"{out}: {extra[0]} is not listed in the manifest (left by another run); the folder mixes runs",
            os.path.join(out, extra[0]),
        )
    tables = []
    for s in listed:
        try:
            tables.append(pq.read_table(os.path.join(out, s)))
        except (OSError, pa.ArrowException) as e:
            raise _fail(f"{out}: shard {s} cannot be read: {e}", os.path.join(out, s)) from e
    table = pa.concat_tables(tables)
    if table.num_rows != expected_rows:
        raise _fail(f"{out}: the shards hold {table.num_rows} rows, the manifest says {expected_rows}", manifest)
    return table


def descriptor_arrays(table: Any) -> dict[str, np.ndarray]:
    """``{path: (n, dim) array}`` for the successful rows of a descriptor table."""
    out: dict[str, np.ndarray] = {}
    for row in table.to_pylist():
        if row["ok"]:
            out[row["path"]] = np.asarray(row["descriptor"], dtype=np.float64).reshape(row["n_vertices"], row["dim"])
    return out


from ._guard import guard_namespace as _guard_namespace  # noqa: E402

_guard_namespace(globals(), ["descriptors", "bags", "read", "descriptor_arrays"])
