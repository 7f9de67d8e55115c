"""The wheel is py3-none-any and ships the MJCF models; installed, it finds its own copy."""

from __future__ import annotations

import json
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
MODELS = ("arena.xml", "robot.xml", "scene.xml")
MODELS_IN_WHEEL = "pyrobots_aio/models/"
INTERFACES = ROOT / "src" / "pyrobots_aio" / "ros2" / "interfaces"


@pytest.fixture(scope="module")
def wheel(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The project's wheel, built by hatchling (the build backend) into a temporary dir."""
    out = tmp_path_factory.mktemp("dist")
    build = [sys.executable, "-m", "hatchling", "build", "--target", "wheel", "--directory", out]
    done = subprocess.run(build, cwd=ROOT, capture_output=True, text=True, check=False)
    assert done.returncode == 0, (
        f"building the wheel failed (hatchling comes with the 'test' extra):\n{done.stderr}"
    )
    (built,) = out.glob("pyrobots_aio-*.whl")
    return built


def test_the_wheel_is_pure_python_for_any_platform(wheel: Path) -> None:
    """One ``py3-none-any`` wheel (STYLE 16b): no compiled module, no C source."""
    assert wheel.name.endswith("-py3-none-any.whl")
    with zipfile.ZipFile(wheel) as archive:
        names = archive.namelist()
        (metadata,) = (name for name in names if name.endswith(".dist-info/WHEEL"))
        lines = archive.read(metadata).decode().splitlines()
    assert [line for line in lines if line.startswith(("Tag:", "Root-Is-Purelib:"))] == [
        "Root-Is-Purelib: true",
        "Tag: py3-none-any",
    ]
    assert [name for name in names if name.endswith((".so", ".pyd", ".c"))] == []


def test_the_wheel_ships_the_models(wheel: Path) -> None:
    with zipfile.ZipFile(wheel) as archive:
        shipped = sorted(name for name in archive.namelist() if name.startswith(MODELS_IN_WHEEL))
        assert shipped == [f"{MODELS_IN_WHEEL}{name}" for name in MODELS]
        for name in MODELS:
            assert (
                archive.read(f"pyrobots_aio/models/{name}") == (ROOT / "models" / name).read_bytes()
            )


def test_the_wheel_ships_the_interface_definitions(wheel: Path) -> None:
    """What ``pyrobots-aio ros2 interfaces build`` builds from: every file, as in the tree."""
    carried = sorted(p for p in INTERFACES.rglob("*") if p.is_file())
    assert len(carried) > 30
    with zipfile.ZipFile(wheel) as archive:
        for path in carried:
            name = f"pyrobots_aio/{path.relative_to(INTERFACES.parent.parent).as_posix()}"
            assert archive.read(name) == path.read_bytes()


FIND_MODELS = """
import json
import pyrobots_aio
from pyrobots_aio.sim import SimWorld, model_path, models_dir
world = SimWorld()
found = [pyrobots_aio.__file__, str(models_dir()), str(model_path()), str(world.model_path)]
print(json.dumps(found))
"""


def test_a_package_installed_from_the_wheel_finds_its_models(wheel: Path, tmp_path: Path) -> None:
    site = tmp_path / "site-packages"  # no checkout around it: only the packaged copy
    with zipfile.ZipFile(wheel) as archive:
        archive.extractall(site)
    done = subprocess.run(
        [sys.executable, "-c", FIND_MODELS],
        env={"PYTHONPATH": str(site), "PATH": ""},
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    package, directory, scene, loaded = json.loads(done.stdout)
    assert package == str(site / "pyrobots_aio" / "__init__.py")
    assert directory == str(site / "pyrobots_aio" / "models")
    assert scene == loaded == str(site / "pyrobots_aio" / "models" / "scene.xml")
