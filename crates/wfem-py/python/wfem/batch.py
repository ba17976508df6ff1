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


def _run(
    task: Callable[..., dict[str, Any]],
    extra: tuple[Any, ...],
    paths: Iterable[str | os.PathLike[str]],
    kind: str,
    out_dir: str | os.PathLike[str] | None,
    executor: cf.Executor | None,
    shard_size: int,
) -> Any:
    pa = _require("pyarrow")

    if shard_size < 1:
        from ._errors import InvalidInputError

        raise InvalidInputError("shard_size must be at least 1", "InvalidParameter", name="shard_size")
    names: list[str] = [os.fspath(p) for p in paths]
    own = executor is None
    ex: cf.Executor = default_executor() if executor is None else executor
    out = None if out_dir is None else os.fspath(out_dir)
    if out is not None:
        os.makedirs(out, exist_ok=True)
        manifest = os.path.join(out, "manifest.json")
        if os.path.exists(manifest):
            os.remove(manifest)
    shards: list[str] = []
    rows: list[dict[str, Any]] = []
    try:
        futures = [ex.submit(task, p, *extra) for p in names]
        pending: list[dict[str, Any]] = []
        for path, fut in zip(names, futures):
            try:
                row = fut.result()
            except Exception as e:  # noqa: BLE001 - a lost worker is an error row too
                row = _failure(path, e)
            rows.append(row)
            pending.append(row)
            if out is not None and len(pending) == shard_size:
                shards.append(_flush(pending, kind, out, len(shards)))
                pending = []
        if out is not None and (pending or not shards):
            shards.append(_flush(pending, kind, out, len(shards)))
    finally:
        if own:
            ex.shutdown(wait=True, cancel_futures=True)
    if out is not None:
        meta = {"kind": kind, "rows": len(rows), "failed": sum(not r["ok"] for r in rows), "shards": shards}
        tmp = os.path.join(out, f".manifest.json.{os.getpid()}.tmp")
        with open(tmp, "w") as f:
            json.dump(meta, f, indent=1)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, os.path.join(out, "manifest.json"))
    return _table(rows, kind) if rows else pa.Table.from_pylist([], schema=_schema(kind))


def _flush(rows: list[dict[str, Any]], kind: str, out: str, index: int) -> str:
    name = f"part-{index:05d}.parquet"
    _write_atomic(_table(rows, kind), os.path.join(out, name))
    return name


def descriptors(
    paths: Iterable[str | os.PathLike[str]],
    out_dir: str | os.PathLike[str] | None = None,
    *,
    executor: cf.Executor | None = None,
    kind: str = "sihks",
    k: int = 100,
    times: Sequence[float] | None = None,
    sihks: dict[str, Any] | None = None,
    shard_size: int = 64,
) -> Any:
    """The dense descriptor ``kind`` (see :func:`wfem.descriptors`) of every mesh, as a
    ``pyarrow.Table`` (one row per path, input order), also written to ``out_dir`` as Parquet
    shards when given."""
    options = {"kind": kind, "k": k, "times": None if times is None else list(times), "sihks": sihks}
    return _run(_descriptor_task, (options,), paths, "descriptor", out_dir, executor, shard_size)


def bags(
    paths: Iterable[str | os.PathLike[str]],
    vocabulary: Any,
    out_dir: str | os.PathLike[str] | None = None,
    *,
    executor: cf.Executor | None = None,
    kind: str = "sihks",
    k: int = 100,
    times: Sequence[float] | None = None,
    sihks: dict[str, Any] | None = None,
    shard_size: int = 64,
) -> Any:
    """The normalised bag of features ``Θᵀa/Σa`` of every mesh with ``vocabulary`` (a
    :class:`wfem.Vocabulary`), descriptor ``kind`` and vertex areas ``a = B·1``; see
    :func:`descriptors` for the output."""
    options = {"kind": kind, "k": k, "times": None if times is None else list(times), "sihks": sihks}
    voc = vocabulary.to_dict() if hasattr(vocabulary, "to_dict") else dict(vocabulary)
    return _run(_bag_task, (options, voc), paths, "bag", out_dir, executor, shard_size)


def read(out_dir: str | os.PathLike[str]) -> Any:
    """The table written by :func:`descriptors` or :func:`bags` into ``out_dir`` (refuses an
    interrupted run: no ``manifest.json``)."""
    pa = _require("pyarrow")
    pq = _require("pyarrow.parquet")

    out = os.fspath(out_dir)
    manifest = os.path.join(out, "manifest.json")
    if not os.path.exists(manifest):
        raise FileNotFoundError(2, "no manifest.json: the run did not finish", manifest)
    with open(manifest) as f:
        meta = json.load(f)
    return pa.concat_tables([pq.read_table(os.path.join(out, s)) for s in meta["shards"]])


def descriptor_arrays(table: Any) -> dict[str, np.ndarray]:
    """``{path: (n, dim) array}`` for the successful rows of a descriptor table."""
    out: dict[str, np.ndarray] = {}
    for row in table.to_pylist():
        if row["ok"]:
            out[row["path"]] = np.asarray(row["descriptor"], dtype=np.float64).reshape(row["n_vertices"], row["dim"])
    return out
