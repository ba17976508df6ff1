"""The type stubs and the public names stay consistent with the module."""

from __future__ import annotations

import ast
import inspect
import subprocess
import sys
from pathlib import Path

import wfem
import wfem._wfem as native

STUB = Path(wfem.__file__).with_name("_wfem.pyi")


def test_all_names_exist_and_are_documented():
    for name in wfem.__all__:
        assert hasattr(wfem, name), name
        obj = getattr(wfem, name)
        if inspect.isfunction(obj) or inspect.isclass(obj):
            assert obj.__doc__, f"{name} has no docstring"
    public = {n for n in dir(wfem) if not n.startswith("_") and not inspect.ismodule(getattr(wfem, n))}
    assert public <= set(wfem.__all__) | {"annotations", "batch"}, public - set(wfem.__all__)


def test_stub_lists_exactly_the_native_names():
    tree = ast.parse(STUB.read_text())
    stubbed = set()
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            stubbed.add(node.name)
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            stubbed.add(node.target.id)
    runtime = {n for n in dir(native) if not n.startswith("_")} | {"__version__"}
    stubbed_public = {n for n in stubbed if not n.startswith("_") or n == "__version__"}
    assert stubbed_public == runtime, (stubbed_public ^ runtime)


def test_stubtest_accepts_the_native_module():
    # mypy's stubtest imports the module and compares every signature with the stub.
    r = subprocess.run(
        [sys.executable, "-m", "mypy.stubtest", "wfem._wfem", "--ignore-missing-stub"],
        capture_output=True,
        text=True,
    )
    assert r.returncode == 0, r.stdout + r.stderr


def test_package_type_checks():
    # The pure-Python layer is typed (py.typed): mypy finds no error in it.
    r = subprocess.run(
        [sys.executable, "-m", "mypy", "--ignore-missing-imports", "--no-error-summary", "-p", "wfem"],
        capture_output=True,
        text=True,
    )
    assert r.returncode == 0, r.stdout + r.stderr
