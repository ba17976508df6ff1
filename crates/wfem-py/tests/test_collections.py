"""Issue #25 (Python side): a folder with broken files still indexes — each refused file is
named with its reason, ``strict=True`` keeps all-or-nothing — and describing shapes reports
progress (a callback on the caller's thread, a line per shape with ``progress=True``)."""

from __future__ import annotations

import threading
import warnings

import pytest

import wfem
from conftest import index_meshes


def broken_files(tmp_path):
    bad = tmp_path / "bad.off"
    bad.write_text("OFF\n3 1 0\n0 0 0\n1 0 0\n2 0 0\n3 0 1 2\n")  # one zero-area face
    garbage = tmp_path / "garbage.obj"
    garbage.write_text("this is not a mesh\n")
    return [bad, garbage]


def test_a_folder_with_broken_files_still_indexes(tmp_path):
    good = index_meshes(tmp_path)[:4]
    bad = broken_files(tmp_path)
    paths = [good[0], bad[0], *good[1:3], bad[1], good[3]]
    with pytest.warns(wfem.RefusedShapesWarning) as caught:
        index = wfem.RetrievalIndex.build(paths, tmp_path / "idx.sqlite", words=8, progress=False)
    assert index.names == [str(p) for p in good]
    assert [f for f, _ in index.refused] == [str(bad[0]), str(bad[1])]
    assert all(reason for _, reason in index.refused)
    message = str(caught[0].message)
    assert str(bad[0]) in message and str(bad[1]) in message and "strict=True" in message
    # The warning points at this file, not into the package.
    assert caught[0].filename == __file__

    # add_meshes alike: the good one is added, the broken one reported.
    (tmp_path / "more").mkdir()
    more = index_meshes(tmp_path / "more")[4:5]
    with pytest.warns(wfem.RefusedShapesWarning):
        assert index.add_meshes([bad[1], *more], progress=False) == 1
    assert index.refused == [(str(bad[1]), index.refused[0][1])]
    assert len(index) == 5


def test_strict_is_all_or_nothing(tmp_path):
    good = index_meshes(tmp_path)[:3]
    bad = broken_files(tmp_path)
    out = tmp_path / "strict.sqlite"
    with pytest.raises(wfem.WfemError, match="bad.off"):
        wfem.RetrievalIndex.build([*good, bad[0]], out, words=8, strict=True, progress=False)
    assert not out.exists()
    index = wfem.RetrievalIndex.build(good, out, words=8, progress=False)
    with pytest.raises(wfem.WfemError):
        index.add_meshes([bad[1]], strict=True, progress=False)
    assert len(index) == 3


def test_no_usable_file_raises_naming_each(tmp_path):
    bad = broken_files(tmp_path)
    with pytest.raises(wfem.WfemError, match="none of the 2") as e:
        wfem.RetrievalIndex.build(bad, tmp_path / "none.sqlite", progress=False)
    assert "bad.off" in str(e.value) and "garbage.obj" in str(e.value)
    assert not (tmp_path / "none.sqlite").exists()


def test_progress_callback_runs_on_the_callers_thread(tmp_path):
    good = index_meshes(tmp_path)[:4]
    bad = broken_files(tmp_path)[1:]
    calls = []

    def progress(done, total, name):
        calls.append((done, total, name, threading.get_ident()))

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", wfem.RefusedShapesWarning)
        wfem.RetrievalIndex.build([*good, *bad], tmp_path / "p.sqlite", words=8, progress=progress)
    assert [c[0] for c in calls] == [1, 2, 3, 4, 5]
    assert {c[1] for c in calls} == {5}
    assert sorted(c[2] for c in calls) == sorted(str(p) for p in [*good, *bad])
    assert {c[3] for c in calls} == {threading.get_ident()}


def test_progress_true_writes_a_line_per_shape_without_tqdm(tmp_path, capsys, monkeypatch):
    import sys

    monkeypatch.setitem(sys.modules, "tqdm", None)
    monkeypatch.setitem(sys.modules, "tqdm.auto", None)
    good = index_meshes(tmp_path)[:3]
    wfem.RetrievalIndex.build(good, tmp_path / "t.sqlite", words=8, progress=True)
    err = capsys.readouterr().err
    assert err.count("describing shapes: ") == 3 and "3/3" in err
    # Default in a non-interactive run (pytest's captured stderr): silent.
    wfem.RetrievalIndex.build(good, tmp_path / "u.sqlite", words=8)
    assert capsys.readouterr().err == ""


def test_a_raising_callback_stops_the_call(tmp_path):
    good = index_meshes(tmp_path)[:3]

    def progress(done, total, name):
        raise RuntimeError("stop here")

    with pytest.raises(Exception, match="stop here"):
        wfem.RetrievalIndex.build(good, tmp_path / "r.sqlite", words=8, progress=progress)
    assert not (tmp_path / "r.sqlite").exists()
    with pytest.raises(wfem.InvalidInputError, match="progress"):
        wfem.RetrievalIndex.build(good, tmp_path / "s.sqlite", words=8, progress="yes")
