"""The SQLite retrieval index: round trip, adding without rebuilding, concurrent readers
(threads and another process), RetrievalIndex on meshes."""

from __future__ import annotations

import os
import subprocess
import sys
import threading

import numpy as np
import pytest

import wfem
from conftest import index_meshes, write_off


def random_bags(n, d, seed=0):
    rng = np.random.default_rng(seed)
    b = rng.random((n, d)) ** 3
    return b / b.sum(axis=1, keepdims=True)


def test_round_trip_and_search(tmp_path):
    path = tmp_path / "index.sqlite"
    bags = random_bags(300, 16)
    store = wfem.VectorStore.create(path, 16, chunk_rows=64)
    store.set_meta("settings", '{"a": 1}')
    ids = store.add([f"s{i}" for i in range(300)], bags, infos=[f"class{i % 3}" for i in range(300)])
    assert ids == list(range(300))
    again = wfem.VectorStore.open(path, readonly=True)
    assert len(again) == 300 and again.dimension == 16
    assert again.meta("settings") == b'{"a": 1}' and again.meta("nope") is None
    np.testing.assert_array_equal(again.vectors(), bags.astype(np.float32))
    assert again.find("s5") == (5, "class2")
    q = bags[42]
    hits = again.search(q, k=5)
    stored = bags.astype(np.float32).astype(np.float64)
    ref = np.argsort(np.abs(stored - q).sum(axis=1), kind="stable")[:5]
    assert [h.id for h in hits] == list(ref)
    assert hits[0].name == "s42" and hits[0].info == "class0" and hits[0].distance < 1e-6
    for metric in ("chi2", "euclidean"):
        assert again.search(q, k=1, metric=metric)[0].id == 42


def test_adding_does_not_rebuild_and_keeps_ids(tmp_path):
    path = tmp_path / "index.sqlite"
    store = wfem.VectorStore.create(path, 4, chunk_rows=8)
    b = random_bags(30, 4, seed=1)
    store.add([f"a{i}" for i in range(5)], b[:5])
    store.add([f"a{i}" for i in range(5, 30)], b[5:])
    assert [s[0] for s in store.shapes()] == list(range(30))
    np.testing.assert_array_equal(store.vectors(), b.astype(np.float32))
    with pytest.raises(wfem.InvalidInputError) as e:
        store.add(["a3"], b[:1])
    assert e.value.kind == "DuplicateName" and e.value.name == "a3"
    with pytest.raises(wfem.InvalidInputError) as e2:
        store.add(["x"], np.ones((1, 5)))
    assert e2.value.kind == "Dimension" and e2.value.expected == 4
    with pytest.raises(wfem.InvalidInputError):
        store.add(["y"], np.array([[np.nan, 0, 0, 1]]))
    assert len(store) == 30


def test_store_errors(tmp_path):
    with pytest.raises(wfem.StoreError) as e:
        wfem.VectorStore.open(tmp_path / "missing.sqlite")
    assert e.value.kind == "Io"
    junk = tmp_path / "junk.sqlite"
    junk.write_bytes(b"not a database at all, just bytes" * 10)
    with pytest.raises(wfem.StoreError) as e2:
        wfem.VectorStore.open(junk)
    assert e2.value.kind == "NotAStore"
    wfem.VectorStore.create(tmp_path / "a.sqlite", 3)
    with pytest.raises(wfem.StoreError) as e3:
        wfem.VectorStore.create(tmp_path / "a.sqlite", 3)
    assert e3.value.kind == "Exists"
    ro = wfem.VectorStore.open(tmp_path / "a.sqlite", readonly=True)
    with pytest.raises(wfem.InvalidInputError):
        ro.add(["x"], np.ones((1, 3)))


READER = r"""
import sys, numpy as np, wfem
s = wfem.VectorStore.open(sys.argv[1], readonly=True)
seen = []
for _ in range(40):
    n = len(s)
    assert n % 50 == 0, n
    hits = s.search(np.full(8, 1 / 8), k=3)
    assert len(hits) == min(3, n)
    seen.append(n)
print(max(seen))
"""


def test_concurrent_readers_threads_and_process(tmp_path):
    path = tmp_path / "index.sqlite"
    store = wfem.VectorStore.create(path, 8, chunk_rows=32)
    store.add([f"s{i}" for i in range(50)], random_bags(50, 8))
    proc = subprocess.Popen([sys.executable, "-c", READER, str(path)], stdout=subprocess.PIPE, text=True)
    errors = []

    def read():
        try:
            r = wfem.VectorStore.open(path, readonly=True)
            for _ in range(30):
                n = len(r)
                assert n % 50 == 0
                r.search(np.full(8, 1 / 8), k=2)
        except Exception as e:  # noqa: BLE001
            errors.append(e)

    threads = [threading.Thread(target=read) for _ in range(3)]
    for t in threads:
        t.start()
    for b in range(1, 20):
        store.add([f"s{i}" for i in range(50 * b, 50 * b + 50)], random_bags(50, 8, seed=b))
    for t in threads:
        t.join()
    out, _ = proc.communicate(timeout=120)
    assert proc.returncode == 0 and int(out) >= 50
    assert not errors
    assert len(store) == 1000


def test_retrieval_index_on_meshes(tmp_path):
    paths = index_meshes(tmp_path)
    index = wfem.RetrievalIndex.build(paths[:4], tmp_path / "idx.sqlite", words=8)
    assert len(index) == 4
    assert index.add_meshes(paths[4:]) == 2
    assert len(index) == 6 and index.names == [str(p) for p in paths]
    assert "vocabulary" in index.settings
    again = wfem.RetrievalIndex.open(tmp_path / "idx.sqlite")
    V, F = wfem.read_mesh(paths[2])
    hits = again.query_mesh(V * 3.0, F, k=2)
    # The default SI-HKS is exactly scale invariant: the same shape at other scales ranks first.
    assert {name for name, _ in hits} == {str(paths[2]), str(paths[3])}
    assert hits[0][1] < 1e-4
    # Adding a name twice is refused, and the index is unchanged.
    with pytest.raises(wfem.WfemError):
        index.add_meshes(paths[:1])
    assert len(index) == 6
    with pytest.raises(wfem.WfemError):
        wfem.RetrievalIndex.open(tmp_path / "m0_1.0.off")


def test_query_id_ranks_an_indexed_shape_from_its_stored_signature(tmp_path):
    # Issue #42: an indexed shape is ranked by name, nothing described again, as
    # `wfem retrieval query INDEX --id NAME`; the same ranking as describing its file again.
    paths = index_meshes(tmp_path)
    index = wfem.RetrievalIndex.build(paths, tmp_path / "idx.sqlite", words=8)
    name = str(paths[2])
    hits = index.query_id(name, k=5)
    assert len(hits) == 5 and name not in [n for n, _ in hits]
    # The other scale of the same shape first (SI-HKS is scale invariant).
    assert hits[0][0] == str(paths[3]) and hits[0][1] < 1e-4
    V, F = wfem.read_mesh(paths[2])
    described = [(n, d) for n, d in index.query_mesh(V, F, k=6) if n != name]
    assert [n for n, _ in hits] == [n for n, _ in described]
    # The stored signature is float32: distances agree to its precision.
    np.testing.assert_allclose([d for _, d in hits], [d for _, d in described], rtol=1e-5, atol=1e-6)
    # The file name and the stem name the same shape; k bounds the answer.
    assert index.query_id(paths[2].name, k=5) == hits
    assert index.query_id(paths[2].stem, k=2) == hits[:2]
    # A name of no indexed shape is refused, naming what is indexed.
    with pytest.raises(wfem.InvalidInputError) as err:
        index.query_id("nothing-like-it")
    assert "nothing-like-it" in str(err.value)


def test_retrieval_cleaning_is_recorded_and_selectable(tmp_path):
    paths = index_meshes(tmp_path)[:3]
    default = wfem.RetrievalIndex.build(paths, tmp_path / "a.sqlite", words=4)
    descriptor = default.settings["vocabulary"]["descriptor"]
    assert descriptor["despiking"] == {"threshold": 3.0}
    assert descriptor["denoising"] == {"roughness": 0.1, "max_coherence": 0.1}
    assert descriptor["topology_repair"] == {"max_handle": 0.35}
    assert descriptor["hole_filling"] == {"max_perimeter": wfem._wfem.DEFAULT_MAX_HOLE_PERIMETER} == {"max_perimeter": 3.0}
    assert descriptor["refinement"] == {"vertices_per_eigenpair": wfem._wfem.DEFAULT_VERTICES_PER_EIGENPAIR} == {
        "vertices_per_eigenpair": 20.0
    }
    assert default.settings["bags"]["weights"] == {"kind": "capped-area", "factor": 3.0}
    # Plain bags by default (the library's default, exported once).
    assert "spatial" not in default.settings["bags"] and wfem._wfem.DEFAULT_SPATIAL is None
    assert default.settings["vocabulary"]["training"]["words"] == 4
    spatial = wfem.RetrievalIndex.build(
        paths, tmp_path / "s.sqlite", words=4, spatial=wfem._wfem.DEFAULT_SPATIAL_TIME, spatial_groups=2
    )
    assert spatial.settings["bags"]["spatial"] == {"time": 2.0**-8, "groups": 2}
    V, F = wfem.read_mesh(paths[0])
    assert spatial.query_mesh(V, F, k=1)[0] == (str(paths[0]), pytest.approx(0.0, abs=1e-6))
    off = wfem.RetrievalIndex.build(
        paths, tmp_path / "b.sqlite", words=4, despike=None, fill_holes=None, denoise=0.2, spatial=None, refine=None
    )
    descriptor = off.settings["vocabulary"]["descriptor"]
    assert descriptor["despiking"] is None and descriptor["denoising"] == {"roughness": 0.2, "max_coherence": 0.1}
    assert "spatial" not in off.settings["bags"]
    assert descriptor["hole_filling"] is None
    assert "refinement" not in descriptor
    finer = wfem.RetrievalIndex.build(paths, tmp_path / "r.sqlite", words=4, refine=40.0)
    assert finer.settings["vocabulary"]["descriptor"]["refinement"] == {"vertices_per_eigenpair": 40.0}
    for bad in (
        {"despike": -1.0},
        {"despike": float("nan")},
        {"denoise": 0.0},
        {"fill_holes": -1.0},
        {"fill_holes": 0.0},
        {"fill_holes": float("inf")},
        {"spatial": 0.0},
        {"spatial": 0.01, "spatial_groups": 0},
        {"spatial": None, "spatial_groups": 3},
        {"refine": 0.0},
        {"refine": 5000.0},
        {"refine": float("nan")},
    ):
        with pytest.raises(
            wfem.InvalidInputError,
            match="spike threshold|target roughness|largest hole perimeter|spatial bag time|spatial(_| bag )groups"
            "|vertices per eigenpair",
        ):
            wfem.RetrievalIndex.build(paths, tmp_path / "c.sqlite", words=4, **bad)
    assert not (tmp_path / "c.sqlite").exists()


def _measures(rel):
    """AP, NN, FT, ST, E (first 32), normalised DCG of one relevance list, by definition."""
    rel = np.asarray(rel, dtype=bool)
    r = int(rel.sum())
    hits = np.cumsum(rel)
    ap = float(np.sum(hits[rel] / (np.flatnonzero(rel) + 1))) / r
    k = min(32, len(rel))
    p, rc = hits[k - 1] / k, hits[k - 1] / r
    e = 2 * p * rc / (p + rc) if p + rc > 0 else 0.0
    gain = np.array([1.0] + [1 / np.log2(j + 1) for j in range(1, len(rel))])
    ideal = gain[:r].sum()
    return {
        "map": ap,
        "nn": float(rel[0]),
        "first_tier": hits[r - 1] / r,
        "second_tier": hits[min(2 * r, len(rel)) - 1] / r,
        "e_measure": e,
        "dcg": float(gain[rel].sum() / ideal),
    }


def test_retrieval_index_evaluate(tmp_path):
    # Three classes of two shapes (each shape at scales 1 and 1.5), in class folders.
    paths = []
    shapes = {"ico": wfem.generate.icosphere(2), "bumpy": wfem.generate.bumpy(2), "torus": wfem.generate.torus()}
    for kind, (V, F) in shapes.items():
        folder = tmp_path / f"{kind}s"
        folder.mkdir()
        for j, s in enumerate((1.0, 1.5)):
            p = folder / f"{kind}{j}.off"
            write_off(p, V * s, F)
            paths.append(p)
    index = wfem.RetrievalIndex.build(paths, tmp_path / "idx.sqlite", words=8)
    report = index.evaluate()
    assert report["shapes"] == 6 and report["classes"] == 3 and report["queries"] == 6
    assert "optimistic" in report["vocabulary"] and report["text"].startswith("6 shapes, 3 classes")
    # Rankings obtained independently (one query per shape, itself dropped), measures by
    # definition: the report's per-query and overall values.
    names = index.names
    classes = [os.path.basename(os.path.dirname(n)) for n in names]
    total = {}
    for q, name in enumerate(names):
        V, F = wfem.read_mesh(name)
        ranked = [n for n, _ in index.query_mesh(V, F, k=6) if n != name]
        assert len(ranked) == 5
        m = _measures([classes[names.index(n)] == classes[q] for n in ranked])
        for key, value in m.items():
            assert report["per_query"][q]["measures"][key] == pytest.approx(value, abs=1e-12), (name, key)
            total[key] = total.get(key, 0.0) + value
    for key, value in total.items():
        assert report["overall"][key] == pytest.approx(value / 6, abs=1e-12)
    # The same from explicit classes (a list or a mapping) and from the stems.
    assert index.evaluate(classes)["overall"] == report["overall"]
    assert index.evaluate(dict(zip(names, classes)))["overall"] == report["overall"]
    stems = index.evaluate(class_from="stem")
    assert stems["classes"] == 3 and stems["overall"] == report["overall"]
    with pytest.raises(wfem.InvalidInputError):
        index.evaluate(class_from="grandparent")
    with pytest.raises(wfem.InvalidInputError):
        index.evaluate(classes[:3])
    with pytest.raises(wfem.InvalidInputError):
        index.evaluate({names[0]: "a"})


def _flip_bit(path, chunk, byte, bit):
    import sqlite3

    with sqlite3.connect(path) as conn:
        (data,) = conn.execute("SELECT data FROM chunks WHERE chunk = ?", (chunk,)).fetchone()
        data = bytearray(data)
        data[byte] ^= 1 << bit
        conn.execute("UPDATE chunks SET data = ? WHERE chunk = ?", (bytes(data), chunk))
    conn.close()


def test_issue_41_a_flipped_bit_is_corrupt_index_and_check_names_it(tmp_path):
    path = tmp_path / "index.sqlite"
    bags = random_bags(40, 8)
    store = wfem.VectorStore.create(path, 8, chunk_rows=16)
    store.add([f"s{i}" for i in range(40)], bags)
    del store
    report = wfem.VectorStore.check(path)
    assert report.verified and report.shapes == 40 and report.chunks == 3 and report.damage == []
    _flip_bit(path, 1, 5, 2)
    store = wfem.VectorStore.open(path, readonly=True)
    assert store.checksummed
    with pytest.raises(wfem.StoreError) as e:
        store.search(bags[20], k=3)
    assert e.value.kind == "CorruptIndex" and e.value.record == "chunk 1 (shapes 16 to 31)"
    report = wfem.VectorStore.check(path)
    assert not report.verified
    assert report.damage[0][0] == "chunk 1 (shapes 16 to 31)" and "checksum" in report.damage[0][1]
    assert "DAMAGED" in report.text


def test_issue_41_a_retrieval_index_with_a_changed_setting_is_refused(tmp_path):
    import sqlite3

    paths = index_meshes(tmp_path)
    out = tmp_path / "idx.sqlite"
    wfem.RetrievalIndex.build(paths[:3], out, words=8)
    assert wfem.RetrievalIndex.check(out).verified
    with sqlite3.connect(out) as conn:
        (text,) = conn.execute("SELECT value FROM meta WHERE key = 'wfem-retrieval-index'").fetchone()
        text = bytes(text).decode()
        at = next(i for i, c in enumerate(text) if c.isdigit())
        text = text[:at] + ("8" if text[at] == "9" else "9") + text[at + 1 :]
        conn.execute("UPDATE meta SET value = CAST(? AS BLOB) WHERE key = 'wfem-retrieval-index'", (text,))
    conn.close()
    with pytest.raises(wfem.StoreError) as e:
        wfem.RetrievalIndex.open(out)
    assert e.value.kind == "CorruptIndex" and e.value.record == 'metadata "wfem-retrieval-index"'
    report = wfem.RetrievalIndex.check(out)
    assert [r for r, _ in report.damage] == ['metadata "wfem-retrieval-index"']


def test_issue_41_a_version_1_store_is_unchecked_until_upgraded(tmp_path):
    import sqlite3

    path = tmp_path / "index.sqlite"
    bags = random_bags(10, 4)
    wfem.VectorStore.create(path, 4).add([f"s{i}" for i in range(10)], bags)
    with sqlite3.connect(path) as conn:
        for table in ("meta", "shapes", "chunks"):
            conn.execute(f"ALTER TABLE {table} DROP COLUMN checksum")
        conn.execute("UPDATE meta SET value = CAST('1' AS BLOB) WHERE key = 'version'")
    conn.close()
    store = wfem.VectorStore.open(path)
    assert not store.checksummed
    with pytest.raises(wfem.StoreError) as e:
        store.add(["new"], bags[:1])
    assert e.value.kind == "NoChecksums"
    del store
    report = wfem.VectorStore.check(path)
    assert report.version == 1 and not report.checksums and not report.verified and report.damage == []
    assert wfem.VectorStore.upgrade(path).verified
    store = wfem.VectorStore.open(path)
    assert store.checksummed and store.add(["new"], bags[:1]) == [10]
