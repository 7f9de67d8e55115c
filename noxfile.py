"""The one entry point for checks: `nox` runs lint, typecheck, tests, compiled, examples, ros2."""

from __future__ import annotations

import shutil
from pathlib import Path

import nox

nox.options.default_venv_backend = "uv|venv"
nox.options.sessions = ["lint", "typecheck", "tests", "compiled", "examples", "ros2"]
nox.options.reuse_existing_virtualenvs = True

INSTALL = ".[sim,mcap,live,test]"
ROS2_INSTALL = ".[sim,ros2,test]"
ROS2_TEST_INTERFACES = ("ros-test-msgs>=2.3", "ros-std-srvs>=5.5")  # the tests' own servers
# hatch_build.py: compile, or fail; the tests: expect the compiled build
COMPILED = {"PYROBOTS_AIO_BUILD": "compiled"}


def install_compiled(session: nox.Session, extras: str, *more: str) -> None:
    """Build the wheel with the actions core compiled (hatch_build.py), and install it.

    Never editable: an editable install is pure Python. The wheel is built anew
    each time, so an edited source is what gets compiled and installed.
    """
    # Not session.create_tmp(): it points TMPDIR into the project, where the tests' own
    # pytest runs (pytester) would find the project's configuration.
    wheels = Path(session.virtualenv.location) / "wheels"
    shutil.rmtree(wheels, ignore_errors=True)
    session.run("uv", "build", "--wheel", "--out-dir", str(wheels), env=COMPILED, external=True)
    (wheel,) = wheels.glob("pyrobots_aio-*.whl")
    fresh = ["--reinstall-package", "pyrobots-aio"] if session.venv_backend == "uv" else []
    session.install(*fresh, f"{wheel}[{extras}]", *more)


@nox.session
def lint(session: nox.Session) -> None:
    """Ruff: lint rules and formatting."""
    session.install("ruff>=0.6")
    session.run("ruff", "check", ".")
    session.run("ruff", "format", "--check", ".")


@nox.session
def typecheck(session: nox.Session) -> None:
    """mypy --strict over the library, then over the typing checks of its public API."""
    session.install("mypy>=1.10", "-e", INSTALL)
    session.run("mypy", "--strict", "src")
    session.run("mypy", "--strict", "tests/typing")


@nox.session
def tests(session: nox.Session) -> None:
    """The test suite (virtual time where time matters)."""
    session.install("-e", INSTALL)
    # The page test opens a real browser (chromium): skipped, with its reason, where there is
    # none; .ci/run installs it and sets PYROBOTS_BROWSER_REQUIRED, so under CI it runs.
    session.run("pytest", *session.posargs, env={"MUJOCO_GL": "egl"})


@nox.session
def compiled(session: nox.Session) -> None:
    """The test suite again, on the wheel's build: the actions core compiled (mypyc and C)."""
    install_compiled(session, "sim,mcap,live,test")
    session.run("pytest", *session.posargs, env={"MUJOCO_GL": "egl", **COMPILED})


@nox.session
def examples(session: nox.Session) -> None:
    """Run every example script from the command line, as a user would."""
    session.install("-e", INSTALL)
    session.run("python", "examples/run_all.py")


@nox.session
def ros2(session: nox.Session) -> None:
    """The ROS 2 tests on the ROS 2 Python wheels (real DDS on localhost); none may skip."""
    session.install("-e", ROS2_INSTALL, *ROS2_TEST_INTERFACES)
    env = {"PYROBOTS_AIO_REQUIRE_ROS2": "1", "MUJOCO_GL": "egl"}
    session.run("pytest", "tests/ros2", *session.posargs, env=env)


@nox.session
def bench(session: nox.Session) -> None:
    """Benchmarks, on the wheel's build (compiled): print a table and write bench-results.json."""
    # py_trees: the side-by-side comparison; the ros2 extra: bench_ros2's bridge and rclpy
    install_compiled(session, "sim,mcap,live,test,ros2", "py_trees>=2.2")
    session.run("python", "-m", "tests.bench", *session.posargs)
