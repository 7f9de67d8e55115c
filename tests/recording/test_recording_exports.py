"""`pyrobots_aio.recording` and `pyrobots_aio.cli`: their docstring examples, and how they import
the packages below them: absolutely, as a program does (tests/test_layers.py pins that they
import only public modules, tests/test_exports.py pins their names)."""

from __future__ import annotations

import ast
import doctest
import importlib
from pathlib import Path

import pytest

import pyrobots_aio.cli
import pyrobots_aio.recording

SRC = Path(pyrobots_aio.recording.__file__).parent.parent


def _imported(path: Path) -> list[str]:
    """Every module a file imports, absolute, or '..x' for a parent-relative import."""
    found = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            found += [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and node.level != 1:
            found.append("." * node.level + (node.module or ""))
    return found


@pytest.mark.parametrize("package", ["recording", "cli"])
def test_the_packages_below_are_imported_absolutely(package: str) -> None:
    for path in sorted((SRC / package).glob("*.py")):
        for module in _imported(path):
            assert not module.startswith("."), f"{path.name} imports {module} (relative)"


@pytest.mark.parametrize(
    "module",
    [
        "recording._format",
        "recording._jsonl",
        "recording._map",
        "recording._mcap",
        "recording._memory",
        "recording._recorder",
        "recording._recording",
        "recording._summary",
        "recording._timeline",
        "cli._console",
        "cli._main",
    ],
)
def test_docstring_examples(module: str) -> None:
    mod = importlib.import_module(f"pyrobots_aio.{module}")
    result = doctest.testmod(mod, optionflags=doctest.ELLIPSIS, raise_on_error=False)
    assert result.failed == 0
    if module in {"recording._format", "recording._memory", "recording._recorder", "cli._console"}:
        assert result.attempted > 0
