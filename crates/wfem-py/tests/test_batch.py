"""wfem.batch on a 2-worker Dask LocalCluster (127.0.0.1) over ~20 generated meshes: the
result equals the serial run bit for bit; broken meshes are error rows; Parquet shards."""

from __future__ import annotations

import json
import os

import numpy as np
import pyarrow.parquet as pq
import pytest

import wfem
import wfem.batch
from conftest import write_off


@pytest.fixture(scope="module")
def collection(tmp_path_factory):
    d = tmp_path_factory.mktemp("meshes")
    paths = []
    shapes = [
        wfem.generate.icosphere(2),
        wfem.generate.irregular_sphere(2, 2.0),
        wfem.generate.bumpy(2),
        wfem.generate.torus(1.0, 0.35, 16, 10),
        wfem.generate.uv_sphere(10, 16),
    ]
    for i in range(19):
        V, F = shapes[i % len(shapes)]
        V = V * (1.0 + 0.1 * i) + 0.01 * np.sin(3.0 * V + i)
        p = d / f"shape{i:02d}.off"
        write_off(p, V, F)
        paths.append(str(p))
    broken = d / "broken.off"
    broken.write_text("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n")  # face uses vertex 7
    paths.insert(7, str(broken))
    paths.append(str(d / "missing.off"))
    return paths


OPTIONS = dict(kind="sihks", k=30, sihks={"time_unit": 1e-4, "tau_min": 0.0, "tau_max": 22.0})


@pytest.fixture(scope="module")
def vocabulary(collection):
    d = [wfem.descriptor(*wfem.read_mesh(p), kind="sihks", k=30, sihks=OPTIONS["sihks"]) for p in collection[:5]]
    return wfem.Vocabulary.train(np.vstack(d), 12, seed=3)


@pytest.fixture(scope="module")
def client():
    dd = pytest.importorskip("dask.distributed")
    cluster = dd.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1", dashboard_address=None
    )
    c = dd.Client(cluster)
    yield c
    c.close()
    cluster.close()


def _rows(table):
    return table.to_pylist()


def test_serial_run_has_error_rows_and_shards(collection, vocabulary, tmp_path):
    table = wfem.batch.bags(collection, vocabulary, tmp_path / "out", executor=wfem.batch.SerialExecutor(),
                            shard_size=6, **OPTIONS)
    rows = _rows(table)
    assert [r["path"] for r in rows] == collection
    bad = {r["path"]: r for r in rows if not r["ok"]}
    assert set(bad) == {collection[7], collection[-1]}
    assert bad[collection[7]]["error_type"] == "MeshError" and bad[collection[7]]["error_kind"] == "IndexOutOfRange"
    assert bad[collection[-1]]["error_type"] == "FileNotFoundError"
    for r in rows:
        if r["ok"]:
            assert len(r["bag"]) == 12 and abs(sum(r["bag"]) - 1) < 1e-12
    manifest = json.loads((tmp_path / "out" / "manifest.json").read_text())
    assert manifest["rows"] == len(collection) and manifest["failed"] == 2
    assert manifest["shards"] == [f"part-{i:05d}.parquet" for i in range(4)]
    assert not [f for f in os.listdir(tmp_path / "out") if f.endswith(".tmp")]
    back = wfem.batch.read(tmp_path / "out")
    assert back.equals(table)
    assert pq.read_table(tmp_path / "out" / "part-00000.parquet").num_rows == 6


def test_dask_equals_serial_bit_for_bit(collection, vocabulary, client, tmp_path):
    serial = wfem.batch.bags(collection, vocabulary, executor=wfem.batch.SerialExecutor(), **OPTIONS)
    distributed = wfem.batch.bags(collection, vocabulary, tmp_path / "dask", executor=client.get_executor(),
                                  **OPTIONS)
    assert distributed.equals(serial)
    a = np.array([r["bag"] for r in _rows(serial) if r["ok"]])
    b = np.array([r["bag"] for r in _rows(distributed) if r["ok"]])
    assert a.tobytes() == b.tobytes()
    assert wfem.batch.read(tmp_path / "dask").equals(distributed)
    # Descriptors too.
    d_serial = wfem.batch.descriptors(collection[:6], executor=wfem.batch.SerialExecutor(), **OPTIONS)
    d_dask = wfem.batch.descriptors(collection[:6], executor=client.get_executor(), **OPTIONS)
    assert d_dask.equals(d_serial)
    arrays = wfem.batch.descriptor_arrays(d_dask)
    V, F = wfem.read_mesh(collection[0])
    assert arrays[collection[0]].shape == (len(V), 8)


def test_default_process_pool(collection, vocabulary):
    table = wfem.batch.bags(collection[:4], vocabulary, **OPTIONS)
    serial = wfem.batch.bags(collection[:4], vocabulary, executor=wfem.batch.SerialExecutor(), **OPTIONS)
    assert [r["ok"] for r in _rows(table)] == [True, True, True, True]
    np.testing.assert_allclose(
        np.array([r["bag"] for r in _rows(table)]), np.array([r["bag"] for r in _rows(serial)]), rtol=1e-12
    )


def _serial(paths, out, **kw):
    return wfem.batch.descriptors(paths, out, executor=wfem.batch.SerialExecutor(), shard_size=2,
                                  **{**OPTIONS, **kw})


def test_a_rerun_into_a_run_folder_is_refused_unless_replace_or_resume(collection, tmp_path):
    out = tmp_path / "run"
    first = _serial(collection[:5], out)
    assert sorted(os.listdir(out)) == ["manifest.json", "part-00000.parquet", "part-00001.parquet",
                                       "part-00002.parquet", "run.json"]
    with pytest.raises(wfem.InvalidInputError) as e:
        _serial(collection[:2], out)
    assert e.value.kind == "OutputExists" and "replace=True" in str(e.value)
    assert wfem.batch.read(out).equals(first)
    # replace: a shorter run leaves none of the earlier shards behind.
    second = _serial(collection[:2], out, replace=True)
    assert sorted(os.listdir(out)) == ["manifest.json", "part-00000.parquet", "run.json"]
    assert wfem.batch.read(out).equals(second)
    assert not [f for f in os.listdir(tmp_path) if f.startswith(".")]


def test_an_interrupted_replace_leaves_the_old_run_readable(collection, tmp_path):
    out = tmp_path / "run"
    first = _serial(collection[:3], out)

    class Interrupted(Exception):
        pass

    class Crashing(wfem.batch.SerialExecutor):
        def submit(self, fn, /, *args, **kwargs):
            raise Interrupted()

    with pytest.raises(Interrupted):
        wfem.batch.descriptors(collection[:3], out, executor=Crashing(), replace=True, **OPTIONS)
    assert wfem.batch.read(out).equals(first)
    assert not [f for f in os.listdir(tmp_path) if f.startswith(".")]


def test_resume_skips_written_shapes_and_refuses_other_settings(collection, tmp_path):
    out = tmp_path / "run"
    paths = collection[:6]
    full = _serial(paths, tmp_path / "reference")
    _serial(paths[:4], out)
    os.remove(out / "manifest.json")  # as if killed after its second shard
    with pytest.raises(wfem.InvalidInputError) as e:
        wfem.batch.read(out)
    assert e.value.kind == "Interrupted" and "resume=True" in str(e.value)
    seen = []

    class Counting(wfem.batch.SerialExecutor):
        def submit(self, fn, /, *args, **kwargs):
            seen.append(args[0])
            return super().submit(fn, *args, **kwargs)

    resumed = wfem.batch.descriptors(paths, out, executor=Counting(), shard_size=2, resume=True, **OPTIONS)
    assert seen == paths[4:]
    assert resumed.equals(full) and wfem.batch.read(out).equals(full)
    # Other settings, another shard size or other paths are refused, naming the difference.
    for kw, culprit in [(dict(k=20), "options"), (dict(shard_size=3), "shard_size")]:
        with pytest.raises(wfem.InvalidInputError) as e:
            wfem.batch.descriptors(paths, out, executor=wfem.batch.SerialExecutor(), resume=True,
                                   **{**OPTIONS, "shard_size": 2, **kw})
        assert e.value.kind == "ResumeMismatch" and culprit in str(e.value), str(e.value)
    with pytest.raises(wfem.InvalidInputError) as e:
        _serial(paths[::-1], out, resume=True)
    assert e.value.kind == "ResumeMismatch"


def test_read_says_exactly_what_is_wrong(collection, tmp_path):
    out = tmp_path / "run"
    _serial(collection[:4], out)
    (out / "part-00007.parquet").write_bytes(b"left by another run")
    with pytest.raises(wfem.InvalidInputError, match="part-00007.parquet is not listed"):
        wfem.batch.read(out)
    os.remove(out / "part-00007.parquet")
    os.remove(out / "part-00001.parquet")
    with pytest.raises(wfem.InvalidInputError, match="lists part-00001.parquet, which is missing"):
        wfem.batch.read(out)
    (out / "part-00001.parquet").write_bytes(b"not parquet")
    with pytest.raises(wfem.InvalidInputError, match="shard part-00001.parquet cannot be read"):
        wfem.batch.read(out)
    (out / "manifest.json").write_text("{")
    with pytest.raises(wfem.InvalidInputError, match="is not a wfem.batch manifest"):
        wfem.batch.read(out)
    with pytest.raises(wfem.InvalidInputError, match="no such folder"):
        wfem.batch.read(tmp_path / "absent")


def _dead_pid():
    import subprocess
    import sys

    p = subprocess.Popen([sys.executable, "-c", "pass"])
    p.wait()
    return p.pid


def test_a_run_killed_in_a_write_resumes_and_leaves_no_temp_file(collection, tmp_path):
    # Issue #41 point 4: killed (kill -9) while run.json was written, the folder holds only the
    # dead process's temporary file: a plain run and resume=True both start afresh.
    paths = collection[:6]
    full = _serial(paths, tmp_path / "reference")
    dead = _dead_pid()
    for kw in [{}, {"resume": True}]:
        out = tmp_path / f"killed-in-run-json-{len(kw)}"
        out.mkdir()
        (out / f".run.json.{dead}.tmp").write_text('{"kind": ')
        assert _serial(paths, out, **kw).equals(full)
        assert wfem.batch.read(out).equals(full)
        assert not [f for f in os.listdir(out) if f.endswith(".tmp")]
    # Killed while a shard was written: the resumed run removes the dead process's part file;
    # a temporary file of a process that still runs (this one) is left alone.
    out = tmp_path / "killed-in-a-shard"
    _serial(paths[:4], out)
    os.remove(out / "manifest.json")
    (out / f".part-00002.parquet.{dead}.tmp").write_bytes(b"PAR1 half")
    live = out / f".part-00009.parquet.{os.getpid()}.tmp"
    live.write_bytes(b"being written")
    assert _serial(paths, out, resume=True).equals(full)
    assert wfem.batch.read(out).equals(full)
    assert sorted(f for f in os.listdir(out) if f.endswith(".tmp")) == [live.name]
    # A replacing run killed before its rename leaves a sibling folder: the next replace removes it.
    stale = tmp_path / f".killed-in-a-shard.{dead}.new"
    stale.mkdir()
    (stale / "run.json").write_text("{}")
    assert _serial(paths, out, replace=True).equals(full)
    assert not stale.exists()
