"""The one entry point for checks: `nox` runs lint, typecheck, tests, examples, ros2 and docs."""

from __future__ import annotations

import nox

nox.options.default_venv_backend = "uv|venv"
nox.options.sessions = ["lint", "typecheck", "tests", "examples", "ros2", "docs"]
nox.options.reuse_existing_virtualenvs = True

INSTALL = ".[sim,mcap,live,test]"
ROS2_INSTALL = ".[sim,ros2-build,test]"  # ros2-build: tf2_msgs, irobot_create_msgs
ROS2_TEST_INTERFACES = ("ros-test-msgs>=2.3", "ros-std-srvs>=5.5")  # the tests' own servers


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
def examples(session: nox.Session) -> None:
    """Run every example script from the command line, as a user would."""
    session.install("-e", INSTALL)
    session.run("python", "examples/run_all.py")


@nox.session
def ros2(session: nox.Session) -> None:
    """The ROS 2 tests on the ROS 2 Python wheels (real DDS on localhost); none may skip."""
    session.install("-e", ROS2_INSTALL, *ROS2_TEST_INTERFACES)
    # once per environment (cached): the interface packages PyPI lacks, built here
    session.run("pyrobots-aio", "ros2", "interfaces", "build")
    env = {"PYROBOTS_AIO_REQUIRE_ROS2": "1", "MUJOCO_GL": "egl"}
    session.run("pytest", "tests/ros2", *session.posargs, env=env)


@nox.session
def docs(session: nox.Session) -> None:
    """The docs site, built with --strict: a broken link, reference or docstring fails it."""
    session.install("-e", ".[docs]")  # griffe reads the sources: no other extra needed
    # into site/: open site/index.html (the variable quiets Material's banner about its future)
    session.run("mkdocs", "build", "--strict", env={"NO_MKDOCS_2_WARNING": "1"})


@nox.session
def bench(session: nox.Session) -> None:
    """Benchmarks: print a table and write bench-results.json."""
    # py_trees: the side-by-side comparison; the ros2 extra: bench_ros2's bridge and rclpy
    session.install("-e", ".[sim,mcap,live,test,ros2]", "py_trees>=2.2")
    session.run("python", "-m", "tests.bench", *session.posargs)
