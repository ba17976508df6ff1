"""Every numeric default is one Rust constant (issue #37, point 2): the Python layer and its stub
write no number in a signature — they read ``wfem._wfem.DEFAULTS`` (or a named module constant)
— and the native functions, left without an argument, use exactly the value in ``DEFAULTS``.
(The pyo3 signatures and the command line are scanned by ``tests/it/defaults.rs``.)"""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np

import wfem
from wfem import _wfem

PACKAGE = Path(wfem.__file__).parent
D = _wfem.DEFAULTS

#: Numeric literals allowed in a signature, with the reason they stay.
ALLOWED = {
    ("_geodesic.py", "geodesic_distance", "sources"): "the first vertex: a position, not a tuned value",
    ("_arrays.py", "as_float_array", "ndim"): "the array ranks a private converter accepts, not a parameter",
}


def numeric_defaults(path: Path) -> list[tuple[str, int, str, str]]:
    """(file, line, function, argument) of every default written as a number (also -x, a/b)."""
    out = []
    for node in ast.walk(ast.parse(path.read_text())):
        if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            continue
        a = node.args
        positional = a.posonlyargs + a.args
        defaults = [None] * (len(positional) - len(a.defaults)) + list(a.defaults)
        for arg, d in list(zip(positional, defaults)) + list(zip(a.kwonlyargs, a.kw_defaults)):
            if d is None:
                continue
            # An index into a table of defaults (``TORUS[0]``) is not a default written out.
            indices = {id(n) for s in ast.walk(d) if isinstance(s, ast.Subscript) for n in ast.walk(s.slice)}
            numbers = [
                n
                for n in ast.walk(d)
                if isinstance(n, ast.Constant)
                and isinstance(n.value, (int, float))
                and not isinstance(n.value, bool)
                and id(n) not in indices
            ]
            if numbers:
                out.append((path.name, d.lineno, node.name, arg.arg))
    return out


def test_the_scanner_finds_numbers_and_only_numbers(tmp_path):
    sample = tmp_path / "sample.py"
    sample.write_text(
        "def f(a, b=1, *, c=-2.5, d=1.0 / 16.0, e=None, g=True, h=X, i=D['eigen']['tol'], j='s', k=T[0]): ...\n"
    )
    found = {arg for (_f, _l, _fn, arg) in numeric_defaults(sample)}
    assert found == {"b", "c", "d"}


def test_no_signature_writes_a_number():
    files = sorted(PACKAGE.glob("*.py")) + [PACKAGE / "_wfem.pyi"]
    assert len(files) > 10
    found = [
        f"{file}:{line}: {fn}({arg}=…)"
        for (file, line, fn, arg) in (x for path in files for x in numeric_defaults(path))
        if (file, fn, arg) not in ALLOWED
    ]
    assert not found, "numeric defaults written out instead of read from wfem._wfem.DEFAULTS:\n" + "\n".join(found)


def test_every_group_holds_numbers():
    assert {"eigen", "diagonal", "distance", "inverse", "largest_eigenvalue", "sihks", "descriptor", "index", "global"} <= set(D)
    for group, values in D.items():
        assert values, group
        for name, value in values.items():
            assert isinstance(value, (int, float)) and not isinstance(value, bool), (group, name, value)


V, F = wfem.generate.bumpy(2)


def test_the_eigensolver_left_alone_uses_the_eigen_group():
    e = D["eigen"]
    alone = _wfem.Eigenbasis.from_mesh(V, F, 12)
    given = _wfem.Eigenbasis.from_mesh(
        V, F, 12, None, e["tol"], e["block_size"], None, e["seed"], None, e["max_restarts"]
    )
    assert np.array_equal(np.asarray(alone.values), np.asarray(given.values))
    # A different seed gives (slightly) different bits: the comparison can fail.
    other = _wfem.Eigenbasis.from_mesh(V, F, 12, None, e["tol"], e["block_size"], None, e["seed"] + 1)
    assert not np.array_equal(np.asarray(alone.vectors), np.asarray(other.vectors))


def test_the_sihks_left_alone_uses_the_sihks_group():
    basis = _wfem.Eigenbasis.from_mesh(V, F, 30)
    s = D["sihks"]
    alone = np.asarray(basis.sihks())
    given = np.asarray(
        basis.sihks(s["alpha"], s["tau_min"], s["tau_max"], s["tau_step"], s["time_unit"], s["num_frequencies"])
    )
    assert alone.shape[1] == s["num_frequencies"]
    assert np.array_equal(alone, given)


def test_kmeans_and_the_largest_eigenvalue_left_alone_use_their_groups():
    points = np.random.default_rng(3).normal(size=(200, 3))
    k = D["kmeans"]
    alone = _wfem.kmeans_clusters(points, 5)
    given = _wfem.kmeans_clusters(points, 5, k["max_iter"], k["seed"])
    assert np.array_equal(np.asarray(alone[0]), np.asarray(given[0]))
    kernel = wfem.HeatKernel(V, F)
    g = D["largest_eigenvalue"]
    assert kernel.largest_eigenvalue() == kernel._k.largest_eigenvalue(g["tol"], g["max_iter"], g["seed"])


def test_the_global_signature_left_alone_uses_the_global_group():
    """Shape-DNA's m and the dimension of Weyl's law come from shape_retrieval::global (the CLI's
    `wfem spectrum -m` reads the same constant)."""
    g = D["global"]
    basis = _wfem.Eigenbasis.from_mesh(V, F, 60)
    alone = np.asarray(basis.global_signature(g["eigenvalues"]))
    given = np.asarray(basis.global_signature(g["eigenvalues"], None, None, g["dimension"]))
    assert np.array_equal(alone, given)
    # The other dimension gives other values: the comparison can fail.
    assert not np.array_equal(alone, np.asarray(basis.global_signature(g["eigenvalues"], None, None, 3)))
    assert len(wfem.shape_dna(V, F)) == g["eigenvalues"]
