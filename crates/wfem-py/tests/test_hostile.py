"""The hostile table of the Python API (issue #23), like the CLI's ``tests/it/hostile.rs``.

Every case runs in its own interpreter under an address-space cap (``RLIMIT_AS``) and a
timeout, so an abort (a failed allocation), a panic, a hang or a bare built-in exception is
seen as such: each case must end in a :class:`wfem.WfemError` subclass (or, where marked, a
correct result). The cases run two at a time; the table takes well under a minute.
"""

from __future__ import annotations

import concurrent.futures as cf
import json
import os
import subprocess
import sys
import textwrap

import pytest

#: Address-space cap of each case: far below what the hostile sizes would allocate (GB–TB).
CAP = 3 << 30
TIMEOUT = 60

PRELUDE = """
import json, os, resource, stat, sys
resource.setrlimit(resource.RLIMIT_AS, ({cap}, {cap}))
import numpy as np
import scipy.sparse as sp
import wfem, wfem.batch
d = sys.argv[1]
V, F = wfem.generate.icosphere(1)
K = wfem.HeatKernel(V, F)
f = V[:, 2].copy()
def store(name="s.sqlite", dim=3, n=4):
    s = wfem.VectorStore.create(os.path.join(d, name), dim)
    s.add([f"s{{i}}" for i in range(n)], np.full((n, dim), 1.0 / dim))
    return s
def mesh_file(name="m.off"):
    p = os.path.join(d, name)
    with open(p, "w") as fh:
        fh.write("OFF\\n%d %d 0\\n" % (len(V), len(F)))
        fh.writelines("%r %r %r\\n" % tuple(v) for v in V)
        fh.writelines("3 %d %d %d\\n" % tuple(t) for t in F)
    return p
"""

RUNNER = """
try:
{body}
    print(json.dumps({{"outcome": "ok"}}))
except wfem.WfemError as e:
    print(json.dumps({{"outcome": "wfem", "class": type(e).__name__, "message": str(e)}}))
except BaseException as e:
    print(json.dumps({{"outcome": "bare", "class": type(e).__name__, "message": str(e)}}))
"""

# (name, code, expected): "wfem" = a WfemError subclass; "ok" = runs (and its asserts hold).
CASES: list[tuple[str, str, str]] = [
    # Sizes: bounded before allocation, with the CLI's limits.
    ("approx num_times 1e9", "K.feature_approximation(f, num_times=10**9)", "wfem"),
    ("descriptors num_times 1e9", "wfem.descriptors(V, F, ['dhk1'], num_times=10**9)", "wfem"),
    ("hks num_times 1e9", "wfem.hks(V, F, num_times=10**9)", "wfem"),
    ("hks 100000 times", "wfem.hks(V, F, times=np.geomspace(1e-3, 1.0, 100000))", "wfem"),
    ("hks k 1e12 (clamped to n)", "wfem.hks(V, F, k=10**12)", "ok"),
    ("eigenbasis k 1e12", "wfem.eigenbasis(V, F, k=10**12)", "wfem"),
    ("descriptors k 1e12", "wfem.descriptors(V, F, ['hks'], k=10**12)", "wfem"),
    # Integers PyO3 cannot convert: negative or huge.
    ("canonical_limit 1e12", "K.canonical_limit([10**12])", "wfem"),
    ("canonical_limit -1", "K.canonical_limit([-1])", "wfem"),
    ("largest_eigenvalue max_iter -1", "K.largest_eigenvalue(max_iter=-1)", "wfem"),
    ("kmeans max_iter -1", "wfem.kmeans(np.random.rand(20, 2), 3, max_iter=-1)", "wfem"),
    ("kmeans k -1", "wfem.kmeans(np.random.rand(20, 2), -1)", "wfem"),
    ("HeatKernel k -1", "wfem.HeatKernel(V, F, method='spectral', k=-1)", "wfem"),
    ("HeatKernel degree 1e20", "wfem.HeatKernel(V, F, degree=10**20)", "wfem"),
    ("icosphere -1", "wfem.generate.icosphere(-1)", "wfem"),
    ("icosphere huge", "wfem.generate.icosphere(10**30)", "wfem"),
    ("hks k float", "wfem.hks(V, F, k=1.5)", "wfem"),
    ("hks k string", "wfem.hks(V, F, k='many')", "wfem"),
    ("distance row -1", "K.distance(0.01).row(-1)", "wfem"),
    ("eigenbasis max_restarts -1", "wfem.eigenbasis(V, F, k=5, max_restarts=-1)", "wfem"),
    # Times.
    ("distance t 1e308", "K.distance(1e308)", "wfem"),
    ("apply t nan", "K.apply(f, float('nan'))", "wfem"),
    # validate() reports instead of raising.
    (
        "validate NaN",
        "V2 = V.copy(); V2[3, 0] = np.nan; r = wfem.validate(V2, F)\n"
        "assert not r.usable and r.problems[0]['vertex'] == 3, r",
        "ok",
    ),
    # Operators validated as documented.
    (
        "from_operators unsymmetric L",
        "L, M, _ = wfem.operators(V, F); L = L.tolil(); L[0, 1] += 0.3; "
        "wfem.HeatKernel.from_operators(L.tocsc(), M)",
        "wfem",
    ),
    (
        "Eigenbasis.from_operators unsymmetric L",
        "L, M, _ = wfem.operators(V, F); L = L.tolil(); L[5, 0] -= 0.2; "
        "wfem.Eigenbasis.from_operators(L.tocsc(), M, k=5)",
        "wfem",
    ),
    (
        "from_operators indefinite L",
        "L = sp.csc_matrix(np.array([[1.0, 2.0], [2.0, 1.0]])); wfem.HeatKernel.from_operators(L, sp.identity(2, format='csc'))",
        "wfem",
    ),
    (
        "from_operators mis-sized M",
        "L, M, _ = wfem.operators(V, F); wfem.HeatKernel.from_operators(L, M[:-1, :-1])",
        "wfem",
    ),
    # The store: sizes, tampering, special files.
    ("store search k 2^62", "s = store(); assert len(s.search(np.full(3, 1/3), 2**62)) == 4", "ok"),
    ("store create dimension 1e12", "wfem.VectorStore.create(os.path.join(d, 'x.sqlite'), 10**12)", "wfem"),
    ("store create dimension -1", "wfem.VectorStore.create(os.path.join(d, 'x.sqlite'), -1)", "wfem"),
    (
        "store tampered dimension",
        "s = store(); p = s.path; del s\n"
        "import sqlite3; c = sqlite3.connect(p); "
        "c.execute(\"UPDATE meta SET value = CAST('4000000000000' AS BLOB) WHERE key = 'dimension'\"); "
        "c.commit(); c.close()\n"
        "wfem.VectorStore.open(p, readonly=True).vectors()",
        "wfem",
    ),
    ("store open directory", "wfem.VectorStore.open(d)", "wfem"),
    ("store open FIFO", "p = os.path.join(d, 'fifo'); os.mkfifo(p); wfem.VectorStore.open(p)", "wfem"),
    ("index open FIFO", "p = os.path.join(d, 'fifo'); os.mkfifo(p); wfem.RetrievalIndex.open(p)", "wfem"),
    ("index open directory", "wfem.RetrievalIndex.open(d)", "wfem"),
    ("index open missing", "wfem.RetrievalIndex.open(os.path.join(d, 'missing.sqlite'))", "wfem"),
    (
        "index build over its input",
        "p = mesh_file(); before = open(p, 'rb').read()\n"
        "try:\n    wfem.RetrievalIndex.build([p], p, overwrite=True)\n"
        "finally:\n    assert open(p, 'rb').read() == before, 'the input was overwritten'",
        "wfem",
    ),
    (
        "index build over an existing file",
        "p = os.path.join(d, 'keep.sqlite'); open(p, 'w').write('precious')\n"
        "try:\n    wfem.RetrievalIndex.build([mesh_file()], p)\n"
        "finally:\n    assert open(p).read() == 'precious'",
        "wfem",
    ),
    (
        "index query k -1",
        "wfem.RetrievalIndex.open(os.path.join(d, 'missing.sqlite')).query_mesh(V, F, k=-1)",
        "wfem",
    ),
    ("index build words -1", "wfem.RetrievalIndex.build([mesh_file()], os.path.join(d, 'i.sqlite'), words=-1)", "wfem"),
    ("index build words 1e9", "wfem.RetrievalIndex.build([mesh_file()], os.path.join(d, 'i.sqlite'), words=10**9)", "wfem"),
    # Volumes (issue #39): files and arrays.
    ("read_volume FIFO", "p = os.path.join(d, 'v.mesh'); os.mkfifo(p); wfem.read_volume(p)", "wfem"),
    ("read_volume directory", "p = os.path.join(d, 'v.msh'); os.mkdir(p); wfem.read_volume(p)", "wfem"),
    (
        "read_volume 1e9 vertices declared",
        "p = os.path.join(d, 'v.mesh'); open(p, 'w').write('MeshVersionFormatted 1\\nDimension 3\\nVertices\\n1000000000\\n0 0 0 0\\n'); "
        "wfem.read_volume(p)",
        "wfem",
    ),
    ("volume T index 2^40", "wfem.operators(np.eye(4, 3), np.array([[0, 1, 2, 2**40]]))", "wfem"),
    ("volume T huge index", "wfem.operators(np.eye(4, 3), np.array([[0, 1, 2, 2**62]]))", "wfem"),
    ("volume V nan", "wfem.HeatKernel(np.full((4, 3), np.nan), np.array([[0, 1, 2, 3]]))", "wfem"),
    ("volume flat tetrahedron", "wfem.HeatKernel(np.zeros((4, 3)), np.array([[0, 1, 2, 3]]))", "wfem"),
    ("volume empty", "wfem.operators(np.zeros((0, 3)), np.zeros((0, 4), dtype=np.int64))", "wfem"),
    ("volume geodesic source -1", "wfem.GeodesicSolver(np.vstack([np.zeros(3), np.eye(3)]), np.array([[0, 1, 2, 3]])).distance(-1)", "wfem"),
    # Batch outputs.
    ("batch read missing", "wfem.batch.read(os.path.join(d, 'nothing'))", "wfem"),
    ("batch shard_size 0", "wfem.batch.descriptors([], os.path.join(d, 'o'), shard_size=0)", "wfem"),
    ("batch read a file", "wfem.batch.read(mesh_file())", "wfem"),
]


def _run(case: tuple[str, str, str], tmp: str) -> tuple[str, dict | None, str]:
    name, code, _ = case
    folder = os.path.join(tmp, "".join(c if c.isalnum() else "_" for c in name))
    os.makedirs(folder, exist_ok=True)
    script = PRELUDE.format(cap=CAP) + RUNNER.format(body=textwrap.indent(code, "    "))
    env = dict(os.environ, RAYON_NUM_THREADS="1")
    try:
        p = subprocess.run(
            [sys.executable, "-c", script, folder], capture_output=True, text=True, timeout=TIMEOUT, env=env
        )
    except subprocess.TimeoutExpired:
        return name, None, f"hang: no answer within {TIMEOUT} s"
    last = p.stdout.strip().splitlines()[-1:] if p.stdout.strip() else []
    if p.returncode != 0 or not last:
        return name, None, f"exit {p.returncode} (abort or crash): {p.stderr[-2000:]}"
    return name, json.loads(last[0]), p.stderr


def test_hostile_python_table(tmp_path):
    with cf.ThreadPoolExecutor(max_workers=2) as ex:
        results = list(ex.map(lambda c: _run(c, str(tmp_path)), CASES))
    failures = []
    for (name, code, expected), (_, outcome, stderr) in zip(CASES, results):
        if outcome is None:
            failures.append(f"{name}: {stderr}")
        elif outcome["outcome"] != expected:
            failures.append(f"{name}: expected {expected}, got {outcome}")
        elif "panicked" in stderr or "InternalError" == outcome.get("class"):
            failures.append(f"{name}: a panic: {outcome} {stderr[-500:]}")
    assert not failures, f"{len(failures)} of {len(CASES)} cases failed:\n" + "\n".join(failures)


def test_distance_at_the_largest_time_names_the_time_it_was_given():
    import wfem

    V, F = wfem.generate.icosphere(1)
    K = wfem.HeatKernel(V, F)
    with pytest.raises(wfem.WfemError) as e:
        K.distance(1e308)
    assert "inf" not in str(e.value), str(e.value)


def test_an_index_on_read_only_media_can_be_queried(tmp_path):
    """A store on a read-only mount opens read-only (immutable) and answers; the read-write
    open is a StoreError. Needs a private mount namespace (root or user namespaces); skipped
    where `unshare` is not allowed."""
    import shutil

    import numpy as np

    import wfem

    if shutil.which("unshare") is None:
        pytest.skip("no unshare")
    folder = tmp_path / "ro"
    folder.mkdir()
    s = wfem.VectorStore.create(folder / "s.sqlite", 3)
    s.add(["a", "b"], np.eye(3)[:2])
    del s
    assert sorted(os.listdir(folder)) == ["s.sqlite"]
    code = (
        "import wfem, numpy as np\n"
        f"p = {str(folder / 's.sqlite')!r}\n"
        "s = wfem.VectorStore.open(p, readonly=True)\n"
        "assert len(s) == 2 and s.search(np.array([1.0, 0, 0]), 1)[0].name == 'a'\n"
        "try:\n    wfem.VectorStore.open(p)\nexcept wfem.StoreError:\n    print('refused')\n"
    )
    mount = f"mount --bind {folder} {folder} && mount -o remount,bind,ro {folder}"
    probe = subprocess.run(["unshare", "-m", "sh", "-c", mount], capture_output=True)
    if probe.returncode != 0:
        pytest.skip("no private read-only mount here")
    p = subprocess.run(
        ["unshare", "-m", "sh", "-c", f"{mount} && {sys.executable} -c \"$0\"", code],
        capture_output=True,
        text=True,
        timeout=TIMEOUT,
    )
    assert p.returncode == 0 and p.stdout.strip() == "refused", p.stderr


def test_retrieval_index_file_errors_are_store_errors(tmp_path):
    """README: RetrievalIndex raises StoreError for its file (missing, a directory, not an index)."""
    import wfem

    (tmp_path / "empty.sqlite").write_bytes(b"")
    for p in [tmp_path / "missing.sqlite", tmp_path, tmp_path / "empty.sqlite"]:
        with pytest.raises(wfem.StoreError):
            wfem.RetrievalIndex.open(p)
