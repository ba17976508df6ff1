"""The Python API takes every choice from the library's registries (issue #26): each argument
accepts exactly the registry's names and aliases, refuses others with the list of valid ones,
and the module constants are the registry's names."""

from __future__ import annotations

import numpy as np
import pytest

import wfem
from wfem import _wfem

V, F = wfem.generate.icosphere(2)
TABLES = wfem.choices()


def spellings(argument: str) -> list[tuple[str, str]]:
    """(spelling, canonical name) of every name and alias of a registry."""
    out = []
    for name, (_help, aliases) in TABLES[argument]["names"].items():
        out.append((name, name))
        out.extend((alias, name) for alias in aliases)
    return out


@pytest.mark.parametrize("argument", sorted(TABLES))
def test_every_spelling_is_canonicalised(argument):
    for spelling, name in spellings(argument):
        assert _wfem.canonical(argument, spelling) == name
        assert _wfem.canonical(argument, spelling.upper().replace("-", "_")) == name
    assert TABLES[argument]["default"] in TABLES[argument]["names"]


@pytest.mark.parametrize("argument", sorted(TABLES))
def test_unknown_names_are_refused_with_the_valid_ones(argument):
    with pytest.raises(wfem.InvalidInputError) as e:
        _wfem.canonical(argument, "no-such-name")
    for name in TABLES[argument]["names"]:
        assert name in str(e.value)


def test_module_constants_are_the_registries():
    assert wfem.METHODS == tuple(TABLES["method"]["names"])
    assert wfem.MASSES == tuple(TABLES["mass"]["names"])
    assert wfem.HKS_CONVENTIONS == tuple(TABLES["convention"]["names"])
    assert wfem.HKS_METHODS == tuple(TABLES["hks_method"]["names"])
    assert wfem.DESCRIPTORS == tuple(TABLES["descriptor"]["names"])
    assert set(wfem.PAPER_DESCRIPTORS) <= set(wfem.DESCRIPTORS)


@pytest.mark.parametrize("spelling,name", spellings("mass"))
def test_heat_kernel_takes_every_mass(spelling, name):
    K = wfem.HeatKernel(V, F, mass=spelling)
    assert K.mass_name == name
    g = K.apply(np.ones(len(V)), 0.1)
    assert np.allclose(g, 1.0)


@pytest.mark.parametrize("spelling,name", spellings("method"))
def test_heat_kernel_takes_every_method(spelling, name):
    options = {"k": 40} if name == _wfem.canonical("method", "spectral") else {}
    K = wfem.HeatKernel(V, F, method=spelling, **options)
    assert K.method == name


@pytest.mark.parametrize("spelling,name", spellings("backend"))
def test_heat_kernel_takes_every_backend(spelling, name):
    K = wfem.HeatKernel(V, F, backend=spelling)
    assert K.method == _wfem.canonical("method", "rational")
    ref = wfem.HeatKernel(V, F)
    f = V[:, 0].copy()
    assert np.allclose(K.apply(f, 0.05), ref.apply(f, 0.05), atol=1e-8)


@pytest.mark.parametrize("spelling,name", spellings("hks_method") + [(None, TABLES["hks_method"]["default"])])
def test_hks_takes_every_method(spelling, name):
    h = wfem.hks(V, F, times=[0.05, 0.2], method=spelling, k=40)
    assert h.shape == (len(V), 2)


@pytest.mark.parametrize("spelling,name", spellings("convention"))
def test_diagonal_and_hks_take_every_convention(spelling, name):
    K = wfem.HeatKernel(V, F)
    d = K.diagonal([0.1], spelling)
    h = wfem.hks(V, F, times=[0.1], convention=spelling, method=_wfem.canonical("hks_method", "exact"))
    assert np.allclose(d, h)


@pytest.mark.parametrize("spelling,name", spellings("distance"))
def test_distance_takes_every_kind(spelling, name):
    d = wfem.HeatKernel(V, F).distance(0.1, spelling)
    assert d.kind == name
    assert d.row(0)[0] == pytest.approx(0.0, abs=1e-10)


@pytest.mark.parametrize("spelling,name", spellings("descriptor"))
def test_descriptors_take_every_name(spelling, name):
    out = wfem.descriptors(V, F, [spelling], k=30, times=[0.1, 0.5, 1.0])
    assert out[spelling].shape[0] == len(V)


@pytest.mark.parametrize("spelling,name", spellings("metric"))
def test_store_search_takes_every_metric(tmp_path, spelling, name):
    store = wfem.VectorStore.create(tmp_path / "s.sqlite", 3)
    store.add(["a", "b"], np.array([[0.2, 0.3, 0.5], [0.5, 0.3, 0.2]]))
    hits = store.search([0.2, 0.3, 0.5], 2, metric=spelling)
    assert hits[0].name == "a"


def test_deprecated_kernel_and_lumped_still_work_with_a_warning():
    with pytest.warns(DeprecationWarning):
        K = wfem.HeatKernel(V, F, kernel="lumped", lumped="voronoi")
    assert K.mass_name == _wfem.canonical("mass", "voronoi")
    with pytest.warns(DeprecationWarning), pytest.raises(wfem.InvalidInputError):
        wfem.HeatKernel(V, F, kernel="wfem", lumped="voronoi")


def test_deprecated_exact_flag_is_method_exact_with_a_warning():
    times = [0.01, 0.1]
    with pytest.warns(DeprecationWarning) as caught:
        old = wfem.hks(V, F, times, exact=True)
    np.testing.assert_array_equal(old, wfem.hks(V, F, times, method="exact"))
    # Attributed to the caller's line (not to a wfem wrapper), so Python's default filters
    # show it.
    assert [w.filename for w in caught] == [__file__]


def test_an_old_name_warns_and_gives_the_new_one():
    """Issue #37, point 4: `KERNELS` was renamed `MASSES`; the old name works for one release."""
    with pytest.warns(DeprecationWarning, match="old name of wfem.MASSES"):
        old = wfem.KERNELS
    assert old is wfem.MASSES
    assert "KERNELS" not in wfem.__all__
    with pytest.raises(AttributeError):
        wfem.NO_SUCH_NAME


def test_index_store_is_the_old_name_of_vector_store():
    """Issue #37, point 4: the Python class of the SQLite vector store was `IndexStore`, the name
    of shape-retrieval's Rust trait for a place an index is saved to; it is `VectorStore` now and
    the old name works, with a warning, for one release."""
    with pytest.warns(DeprecationWarning, match="old name of wfem.VectorStore"):
        old = wfem.IndexStore
    assert old is wfem.VectorStore
    assert "IndexStore" not in wfem.__all__
