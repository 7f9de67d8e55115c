"""The pytest plugin (``pytest11`` entry point ``pyrobots_aio``).

Markers:
    virtual_time: run the async test on the virtual-time loop, where
        ``asyncio.sleep(3600)`` returns at once with ``loop.time()`` 3600 s later.
    allow_leaks: the leak checks below are skipped for this test.

Fixtures:
    robot: a running dummy ``Robot(dummy=True)`` with an `EventLog` attached.
    sim_robot: a running `pyrobots_aio.sim.SimRobot` in lockstep virtual time
        (a test using it runs on the virtual-time loop, marked or not).
    robot_events: the `EventLog` of the robot fixture in use.
    no_leaked_tasks: fails the test if an asyncio task it started is still
        pending when it ends (use it, or make it autouse in your conftest).

Once the ``robot``/``sim_robot`` fixture's robot has shut down, the fixture
fails the test if a task started since the robot started is still pending (an
action that ignored cancellation and was abandoned, a stray ``create_task``) or
a resource is still held.

The fixtures and the marker need pytest-asyncio 1.4 or newer (its loop
factories); without it, every other pytest run is untouched and a test that
asks for them gets an error saying what to install.
"""

from __future__ import annotations

import importlib.metadata

import pytest

REQUIRED = (1, 4)
INSTALL = "pip install 'pyrobots-aio[testing]' (pytest-asyncio>=1.4)"


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line(
        "markers", "allow_leaks: this test may leave asyncio tasks behind (not checked)."
    )
    config.addinivalue_line(
        "markers", "virtual_time: run this async test on the virtual-time event loop."
    )
    problem = _pytest_asyncio_problem()
    if problem is None:
        from . import _fixtures

        config.pluginmanager.register(_fixtures, "pyrobots_aio.fixtures")
    else:
        from . import _missing

        _missing.PROBLEM = f"{problem}; {INSTALL}"
        config.pluginmanager.register(_missing, "pyrobots_aio.fixtures")


def _pytest_asyncio_problem() -> str | None:
    """Why the fixtures cannot work here, or None if pytest-asyncio is recent enough."""
    try:
        version = importlib.metadata.version("pytest-asyncio")
    except importlib.metadata.PackageNotFoundError:
        return "the pyrobots_aio fixtures and virtual_time marker need pytest-asyncio"
    release = tuple(int(part) for part in version.split(".")[:2] if part.isdigit())
    if release < REQUIRED:
        return (
            f"the pyrobots_aio fixtures and virtual_time marker need pytest-asyncio>=1.4, "
            f"found {version}"
        )
    return None
