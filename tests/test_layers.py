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
    "loops": 2,
    "resources": 3,
    "state": 3,
    "poses": 3,
    "actions": 4,
    "events": 4,
    "telemetry": 4,
    "robot": 5,
    "motion": 6,
    "supervision": 6,
    "recording": 7,
    "sim": 7,
    "testing": 7,
    "ros2": 8,
    "cli": 9,
}


def _part(module: str) -> str | None:
    parts = module.split(".")
    if parts[0] != "pyrobots_aio" or len(parts) < 2:
        return None
    return parts[1].removesuffix(".py")


def _imports(where: tuple[str, ...], source: str) -> set[str]:
    """The modules imported by the module at ``where`` in the package (every import, lazy too)."""
    here = ["pyrobots_aio", *where]
    package = here[:-1]  # for __init__.py too: "." is the package itself
    found = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            found |= {alias.name for alias in node.names}
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package[: len(package) - node.level + 1]
                found.add(".".join([*base, node.module] if node.module else base))
            elif node.module:
                found.add(node.module)
    return found


def _upward(where: tuple[str, ...], source: str, layers: dict[str, float]) -> set[str]:
    """What the module at ``where`` imports from a layer above its own."""
    level = layers[where[0]]
    return {
        name
        for name in _imports(where, source)
        if (part := _part(name)) is not None and part in layers and layers[part] > level
    }


MODULES = sorted(p for p in PACKAGE.rglob("*.py") if p.parent != PACKAGE or p.stem != "__init__")


@pytest.mark.parametrize("path", MODULES, ids=lambda p: str(p.relative_to(PACKAGE)))
def test_no_module_imports_a_higher_layer(path: Path) -> None:
    where = path.relative_to(PACKAGE).with_suffix("").parts
    upward = _upward(where, path.read_text(), LAYERS)
    assert not upward, f"{where[0]} (layer {LAYERS[where[0]]}) imports upward: {sorted(upward)}"


def test_every_package_part_has_a_layer() -> None:
    parts = {p.name.removesuffix(".py") for p in PACKAGE.iterdir() if not p.name.startswith("__")}
    parts -= {"py.typed", "models"}
    assert parts == set(LAYERS)


def test_the_check_finds_the_old_import_of_cli_by_ros2() -> None:
    # ros2/_run.py once imported the scaled-time loop from the cli, in a function;
    # the layers had ros2 and cli side by side, and the check let it pass.
    source = "def scaled_loop(rate):\n    from ..cli._sim_node import ScaledTimeLoop\n"
    where = ("ros2", "_run")
    assert _upward(where, source, LAYERS) == {"pyrobots_aio.cli._sim_node"}
    assert _upward(where, source, LAYERS | {"ros2": 5, "cli": 5}) == set()


def test_the_check_reads_absolute_and_type_only_imports_too() -> None:
    source = (
        "from typing import TYPE_CHECKING\n"
        "import pyrobots_aio.recording\n"
        "if TYPE_CHECKING:\n"
        "    from ..robot import Robot\n"
    )
    assert _upward(("telemetry", "_live"), source, LAYERS) == {
        "pyrobots_aio.recording",
        "pyrobots_aio.robot",
    }
