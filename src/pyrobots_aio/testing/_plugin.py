"""The pytest plugin (``pytest11`` entry point ``pyrobots_aio``).

Markers:
    virtual_time: run the async test on the virtual-time loop, where
        ``asyncio.sleep(3600)`` returns at once with ``loop.time()`` 3600 s later
        (the test is run by pytest-asyncio: ``@pytest.mark.asyncio``).
    allow_leaks: the leak checks below are skipped for this test.
    explore(examples=N, workers=W): the ``explore`` fixture tries N schedules
        (default 100) in W processes (default 1).

Fixtures:
    robot: a running dummy ``Robot(dummy=True)`` with an `EventLog` attached.
    sim_robot: a running `pyrobots_aio.sim.SimRobot` in lockstep virtual time
        (a test using it runs on the virtual-time loop, marked or not).
    robot_events: the `EventLog` of the robot fixture in use.
    no_leaked_tasks: fails the test if an asyncio task it started is still
        pending when it ends (use it, or make it autouse in your conftest).
    module_robot, module_sim_robot, module_robot_events: one robot, and its
        `EventLog`, for all the tests of a module, on the module's loop.
    session_robot, session_sim_robot, session_robot_events: the same for the
        whole session, on the session's loop.
    explore: ``explore(scenario)`` searches a `pyrobots_aio.testing.explore.Scenario`
        with the marker's examples, the ``--explore-profile`` (``ci``, the
        default: derandomized; ``dev``; ``long``), recording a failure into
        the test's ``tmp_path`` (needs the ``explore`` extra).

Loop scopes: ``robot``, ``sim_robot`` and ``no_leaked_tasks`` are
function-scoped and run on the loop of the test that uses them, whatever its
scope (``@pytest.mark.asyncio(loop_scope="module")`` gets a fresh robot per
test on the module's loop). The ``module_*`` and ``session_*`` robots live on
the module's or the session's loop, so the tests using them are marked
``@pytest.mark.asyncio(loop_scope="module")`` (or ``"session"``); a test on
another loop fails with a message saying which mark to add.

Event loops: only the tests that ask for virtual time (the marker, or a
``*sim_robot`` fixture) get the virtual-time loop. The plugin answers
pytest-asyncio's ``pytest_asyncio_loop_factories`` hook (first result wins)
first for those, and not for the others, so a project's own loop stands: its
own implementation of the hook (a hook of its own marked ``tryfirst`` would
take virtual time's place too), or a uvloop event loop policy. When no plugin
answers, tests get ``asyncio.new_event_loop()``, as without the hook.

Once the robot fixtures' robot has shut down, the fixture fails the test if an
action ignored cancellation and was abandoned, if a task started since the
robot started is still pending (a stray ``create_task``), or if a resource is
still held. A test that asks for virtual time but that pytest-asyncio does not run
(no ``@pytest.mark.asyncio`` in strict mode, or not ``async def``) fails with
a message saying so.

The fixtures and the marker need pytest-asyncio 1.4 or newer (its loop
factories); without it, every other pytest run is untouched and a test that
asks for them gets an error saying what to install.
"""

from __future__ import annotations

import importlib.metadata

import pytest

from . import _explore_fixture
from ._profiles import ENVIRONMENT, PROFILES

REQUIRED = (1, 4)
INSTALL = 'pip install "pytest-asyncio>=1.4" (or pip install -e ".[testing]" in a checkout)'


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption(
        "--explore-profile",
        choices=PROFILES,
        default=None,
        help=f"the explore fixture's Hypothesis profile (default: ${ENVIRONMENT}, else ci)",
    )


def pytest_configure(config: pytest.Config) -> None:
    config.pluginmanager.register(_explore_fixture, "pyrobots_aio.explore")
    config.addinivalue_line(
        "markers",
        "explore(examples=N, workers=W): the explore fixture tries N schedules (default 100) "
        "in W processes (default 1).",
    )
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
        config.pluginmanager.register(_fixtures.DefaultLoop(), "pyrobots_aio.default_loop")
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
