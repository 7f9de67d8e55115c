"""The wheel ships the MJCF models, and a package installed from it finds its own copy.

Its build hook (hatch_build.py) compiles the actions core where it can: how it
chooses and falls back is checked here; the compiled build itself is tested by
``nox -s compiled``, which runs the whole suite on it.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
MODELS = ("arena.xml", "robot.xml", "scene.xml")


def _build(out: Path, **env: str) -> subprocess.CompletedProcess[str]:
    """Build the project's wheel with hatchling (the build backend) into ``out``."""
    build = [sys.executable, "-m", "hatchling", "build", "--target", "wheel", "--directory", out]
    return subprocess.run(
        build, cwd=ROOT, env={**os.environ, **env}, capture_output=True, text=True, check=False
    )


@pytest.fixture(scope="module")
def wheel(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The project's pure-Python wheel, built into a temporary directory."""
    out = tmp_path_factory.mktemp("dist")
    done = _build(out, PYROBOTS_AIO_BUILD="python")
    assert done.returncode == 0, (
        f"building the wheel failed (hatchling comes with the 'test' extra):\n{done.stderr}"
    )
    (built,) = out.glob("pyrobots_aio-*.whl")
    return built


def _extension_modules(wheel: Path) -> list[str]:
    with zipfile.ZipFile(wheel) as archive:
        return [name for name in archive.namelist() if name.endswith((".so", ".pyd"))]


def test_a_pure_python_wheel_is_for_any_platform(wheel: Path) -> None:
    assert wheel.name == "pyrobots_aio-0.1.0-py3-none-any.whl"
    assert _extension_modules(wheel) == []


def test_a_failed_compile_falls_back_to_python_with_a_warning(tmp_path: Path) -> None:
    done = _build(tmp_path, PYROBOTS_AIO_BUILD="auto", CC="false")  # a compiler that fails
    assert done.returncode == 0, done.stderr
    assert "building the pure-Python wheel, the compiled core failed" in done.stderr
    (built,) = tmp_path.glob("pyrobots_aio-*.whl")
    assert built.name.endswith("-py3-none-any.whl")
    assert _extension_modules(built) == []


def test_a_failed_compile_fails_the_build_when_compiled_is_asked_for(tmp_path: Path) -> None:
    done = _build(tmp_path, PYROBOTS_AIO_BUILD="compiled", CC="false")
    assert done.returncode != 0
    assert list(tmp_path.glob("*.whl")) == []


def test_an_unknown_build_choice_is_refused(tmp_path: Path) -> None:
    done = _build(tmp_path, PYROBOTS_AIO_BUILD="fast")
    assert done.returncode != 0
    assert "PYROBOTS_AIO_BUILD='fast': expected one of auto, compiled, python" in done.stderr


def test_the_wheel_ships_the_models(wheel: Path) -> None:
    with zipfile.ZipFile(wheel) as archive:
        shipped = sorted(name for name in archive.namelist() if name.endswith(".xml"))
        assert shipped == [f"pyrobots_aio/models/{name}" for name in MODELS]
        for name in MODELS:
            assert (
                archive.read(f"pyrobots_aio/models/{name}") == (ROOT / "models" / name).read_bytes()
            )


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
