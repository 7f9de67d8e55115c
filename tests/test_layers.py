"""Nothing imports upward: the layers of pyrobots_aio/__init__.py, pinned."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import pyrobots_aio

PACKAGE = Path(pyrobots_aio.__file__).parent
LAYERS = {
    "_exceptions": 0,
    "_core": 1,
    "loops": 1,
    "resources": 2,
    "state": 2,
    "poses": 2,
    "actions": 3,
    "events": 3,
    "telemetry": 3,
    "robot": 4,
    "motion": 4.5,
    "supervision": 4.5,
    "recording": 5,
    "sim": 5,
    "ros2": 5,
    "testing": 5,
    "cli": 5,
}


def _part(module: str) -> str | None:
    parts = module.split(".")
    if parts[0] != "pyrobots_aio" or len(parts) < 2:
        return None
    return parts[1].removesuffix(".py")


def _imports(path: Path) -> set[str]:
    here = ["pyrobots_aio", *path.relative_to(PACKAGE).with_suffix("").parts]
    package = here[:-1]  # for __init__.py too: "." is the package itself
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            found |= {alias.name for alias in node.names}
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package[: len(package) - node.level + 1]
                found.add(".".join([*base, node.module] if node.module else base))
            elif node.module:
                found.add(node.module)
    return found


MODULES = sorted(p for p in PACKAGE.rglob("*.py") if p.parent != PACKAGE or p.stem != "__init__")


@pytest.mark.parametrize("path", MODULES, ids=lambda p: str(p.relative_to(PACKAGE)))
def test_no_module_imports_a_higher_layer(path: Path) -> None:
    own = path.relative_to(PACKAGE).parts[0].removesuffix(".py")
    level = LAYERS[own]
    upward = {
        name
        for name in _imports(path)
        if (part := _part(name)) is not None and part in LAYERS and LAYERS[part] > level
    }
    assert not upward, f"{own} (layer {level}) imports upward: {sorted(upward)}"


def test_every_package_part_has_a_layer() -> None:
    parts = {p.name.removesuffix(".py") for p in PACKAGE.iterdir() if not p.name.startswith("__")}
    parts -= {"py.typed", "models"}
    assert parts == set(LAYERS)
