"""The place of the events package in the layers (tests/test_exports.py pins its names)."""

from __future__ import annotations

import ast
from pathlib import Path

from pyrobots_aio import events

PACKAGE = Path(events.__file__).parent
ALLOWED = {"_core", "_exceptions", "actions", "state"}


def _runtime_imports(tree: ast.Module) -> list[str]:
    """The packages of pyrobots_aio imported at run time (not under TYPE_CHECKING)."""
    found = []
    for node in tree.body:
        if isinstance(node, ast.ImportFrom) and node.level >= 2:
            found.append((node.module or "").split(".")[0])
        if (
            isinstance(node, ast.ImportFrom)
            and node.module
            and node.module.startswith("pyrobots_aio")
        ):
            found.append(node.module.split(".")[1])
    return found


def test_events_imports_only_lower_layers_and_actions() -> None:
    imported = {
        name
        for path in PACKAGE.glob("*.py")
        for name in _runtime_imports(ast.parse(path.read_text()))
    }
    assert imported <= ALLOWED, imported - ALLOWED
    assert "actions" in imported
