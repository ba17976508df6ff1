"""Issue #25, the first hour of a new user: the README's quick start runs from any folder, and
a missing optional dependency is named with the extra that installs it."""

from __future__ import annotations

import re
import sys
import warnings
from pathlib import Path

import pytest

README = Path(__file__).resolve().parents[1] / "README.md"


def test_the_quick_start_runs_from_any_folder(tmp_path, monkeypatch):
    text = README.read_text()
    start = text.index("## Quick start")
    block = re.search(r"```python\n(.*?)```", text[start:], re.S)
    assert block is not None
    monkeypatch.chdir(tmp_path)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no TimeWarning either: its times are sensible
        scope: dict = {}
        exec(compile(block.group(1), str(README), "exec"), scope)
    assert scope["g"].shape == scope["f"].shape
    assert scope["h"].shape == (len(scope["V"]), 3)


def test_a_missing_optional_dependency_is_named(tmp_path, monkeypatch):
    import wfem.batch

    monkeypatch.setitem(sys.modules, "pyarrow", None)
    monkeypatch.setitem(sys.modules, "pyarrow.parquet", None)
    (tmp_path / "manifest.json").write_text('{"shards": []}')
    with pytest.raises(ModuleNotFoundError, match=r"needs pyarrow.*pip install 'wfem\[batch\]'"):
        wfem.batch.read(tmp_path)
