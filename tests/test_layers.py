"""Nothing imports upward: the layers of pyrobots_aio/__init__.py, pinned."""

from __future__ import annotations

import ast
from collections.abc import Iterator
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
    "lowlevel": 6,
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


def _imported(where: tuple[str, ...], source: str) -> Iterator[tuple[str, str | None]]:
    """What the module at ``where`` in the package imports (every import, lazy too).

    Each import as ``(module, name)``: ``name`` is what ``from module import name``
    takes, None for ``import module``.
    """
    here = ["pyrobots_aio", *where]
    package = here[:-1]  # for __init__.py too: "." is the package itself
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            yield from ((alias.name, None) for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package[: len(package) - node.level + 1]
                module = ".".join([*base, node.module] if node.module else base)
            else:
                module = node.module or ""
            yield from ((module, alias.name) for alias in node.names)


def _imports(where: tuple[str, ...], source: str) -> set[str]:
    """The modules imported by the module at ``where`` in the package."""
    return {module for module, _ in _imported(where, source)}


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


PUBLIC_ONLY = {part for part, level in LAYERS.items() if level >= LAYERS["recording"]}
"""The parts that use the public API only (the package's docstring says which)."""


def _private(where: tuple[str, ...], source: str) -> set[str]:
    """What the module at ``where`` imports that is private to another part of the package.

    Private: a module with a ``_`` part in its path, or a ``_`` name (dunders such
    as ``__version__`` aside), outside the module's own part. ``_exceptions`` is
    the one private module allowed, for the names the package exports (the
    hierarchy is public there, as ``pyrobots_aio.StallError`` ...).
    """
    found = set()
    for module, name in _imported(where, source):
        parts = module.split(".")
        if parts[0] != "pyrobots_aio" or parts[1:2] == [where[0]]:
            continue
        if parts[1:] == ["_exceptions"] and name in pyrobots_aio.__all__:
            continue
        path = [*parts[1:], name or ""]
        if any(part.startswith("_") and not part.endswith("__") for part in path):
            found.add(module if name is None else f"{module}:{name}")
    return found


PUBLIC_ONLY_MODULES = [p for p in MODULES if p.relative_to(PACKAGE).parts[0] in PUBLIC_ONLY]


@pytest.mark.parametrize("path", PUBLIC_ONLY_MODULES, ids=lambda p: str(p.relative_to(PACKAGE)))
def test_the_upper_layers_import_only_public_modules_of_the_others(path: Path) -> None:
    where = path.relative_to(PACKAGE).with_suffix("").parts
    private = _private(where, path.read_text())
    assert not private, f"{where[0]} uses the public API only, but imports {sorted(private)}"


def test_the_check_finds_private_imports_of_other_parts() -> None:
    # sim, testing and ros2 once took these from private modules (now pyrobots_aio.lowlevel's)
    source = (
        "from .._core._numbers import finite\n"
        "from ..motion._math import limit_speeds\n"
        "from ..motion import _base\n"
        "from .. import _core\n"
        "from .._exceptions import _Bad\n"
        "def lazy():\n"
        "    import pyrobots_aio.poses._math\n"
    )
    assert _private(("sim", "_world"), source) == {
        "pyrobots_aio._core._numbers:finite",
        "pyrobots_aio.motion._math:limit_speeds",
        "pyrobots_aio.motion:_base",
        "pyrobots_aio:_core",
        "pyrobots_aio._exceptions:_Bad",
        "pyrobots_aio.poses._math",
    }


def test_the_check_lets_public_names_and_the_modules_own_part_through() -> None:
    source = (
        "from .._exceptions import StallError\n"
        "from .. import UnknownFrameError\n"
        "from ..lowlevel import finite\n"
        "from ..motion import DriveBase\n"
        "from ._models import ModelLayout\n"
        "from .._profiles import chosen_profile\n"
        "from pyrobots_aio import __version__\n"
        "import numpy._core\n"
    )
    assert _private(("testing", "explore", "_scenario"), source) == set()
