"""The typed stub of the lazy public API (``engine/__init__.pyi``) names what ``engine`` loads.

``engine/__init__.py`` loads each public name from its module on first use (``_WHERE``: name ->
module); type checkers read ``engine/__init__.pyi`` instead. The stub must import every public
name from the very module the lazy table loads it from, list the same ``__all__``, and each
name must resolve at run time to the object the stub promises.
"""
from __future__ import annotations

import ast
import importlib
from pathlib import Path

import pytest

import engine

STUB = Path(engine.__file__).with_suffix(".pyi")


def _stub():
    """``({name: module} imported by the stub, its __all__)``."""
    tree = ast.parse(STUB.read_text(encoding="utf-8"))
    imported, names_all = {}, None
    for node in tree.body:
        if isinstance(node, ast.ImportFrom):
            for alias in node.names:
                # ``import X as X``: the explicit re-export a stub needs (PEP 484)
                assert alias.asname == alias.name, f"{alias.name} is not re-exported as itself in {STUB.name}"
                imported[alias.name] = node.module
        elif isinstance(node, ast.Assign) and any(getattr(t, "id", None) == "__all__" for t in node.targets):
            names_all = ast.literal_eval(node.value)
    return imported, names_all


def test_the_stub_imports_each_public_name_from_where_it_is_loaded():
    imported, _ = _stub()
    assert imported == engine._WHERE


def test_the_stub_lists_the_same_all():
    _, names_all = _stub()
    assert names_all is not None, f"{STUB.name} has no __all__"
    assert sorted(names_all) == engine.__all__ == sorted(engine._WHERE)


def test_each_name_loads_the_object_of_its_module():
    for name, module in engine._WHERE.items():
        assert getattr(engine, name) is getattr(importlib.import_module(module), name)
    assert set(engine.__all__) <= set(dir(engine))


def test_the_stub_and_the_typed_marker_ship_with_the_package():
    """Both are in the package (a built wheel carries them through package-data)."""
    assert STUB.is_file() and (STUB.parent / "py.typed").is_file()
    tomllib = pytest.importorskip("tomllib")  # Python 3.11+

    data = tomllib.loads((STUB.parents[1] / "pyproject.toml").read_text(encoding="utf-8"))
    patterns = data["tool"]["setuptools"]["package-data"]["engine"]
    assert "*.pyi" in patterns and "py.typed" in patterns
