"""The place of `pyrobots_aio.poses` in the layers (tests/test_exports.py pins its names)."""

from __future__ import annotations

import ast
import sys
from pathlib import Path

import pyrobots_aio.poses

POSES_DIR = Path(pyrobots_aio.poses.__file__).parent
THIRD_PARTY = {"numpy", "transforms3d"}


def _imports(path: Path) -> list[str]:
    """Every import of a module, as 'numpy', '.x' (this package) or '..x' (the parent)."""
    found: list[str] = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            found.extend(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            found.append("." * node.level + (node.module or ""))
    return found


def test_poses_imports_only_stdlib_numpy_transforms3d_exceptions_and_numbers() -> None:
    modules = sorted(POSES_DIR.glob("*.py"))
    assert [m.name for m in modules] == [
        "__init__.py",
        "_frames.py",
        "_manager.py",
        "_math.py",
        "_parse.py",
        "_pose.py",
    ]
    for module in modules:
        for name in _imports(module):
            top = name.split(".")[0]
            allowed = (
                (name.startswith(".") and not name.startswith(".."))
                or name in {".._exceptions", ".._core._numbers"}  # _numbers: the number check
                or top in THIRD_PARTY
                or top in sys.stdlib_module_names
            )
            assert allowed, f"{module.name} imports {name}"
