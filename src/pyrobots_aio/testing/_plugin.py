"""The pytest plugin (``pytest11`` entry point ``pyrobots_aio``).

Markers:
    virtual_time: run the async test on the virtual-time loop, where
        ``asyncio.sleep(3600)`` returns at once with ``loop.time()`` 3600 s later.

Fixtures:
    robot: a running dummy ``Robot(dummy=True)`` with an `EventLog` attached.
    sim_robot: a running `pyrobots_aio.sim.SimRobot` in lockstep virtual time
        (a test using it runs on the virtual-time loop, marked or not).
    robot_events: the `EventLog` of the robot fixture in use.
    no_leaked_tasks: fails the test if an asyncio task it started is still
        pending when it ends (use it, or make it autouse in your conftest).

The robot fixtures also fail the test if a resource is still held, or an action
still runs, once the robot has shut down.
"""

from __future__ import annotations

import asyncio
from typing import TYPE_CHECKING

import pytest
import pytest_asyncio

from pyrobots_aio import Robot
from pyrobots_aio._core._clock import new_virtual_loop

from ._events import EventLog

if TYPE_CHECKING:
    from collections.abc import AsyncIterator, Callable, Mapping

    from pyrobots_aio.sim import SimRobot

_VIRTUAL_FIXTURES = frozenset({"sim_robot"})


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line(
        "markers", "allow_leaks: this test may leave asyncio tasks behind (not checked)."
    )
    config.addinivalue_line(
        "markers", "virtual_time: run this async test on the virtual-time event loop."
    )


def pytest_asyncio_loop_factories(
    config: pytest.Config, item: pytest.Item
) -> Mapping[str, Callable[[], asyncio.AbstractEventLoop]]:
    """Run tests marked ``virtual_time`` on the virtual-time loop, the others as usual."""
    fixtures = getattr(item, "fixturenames", ())
    if item.get_closest_marker("virtual_time") or _VIRTUAL_FIXTURES.intersection(fixtures):
        return {"virtual_time": new_virtual_loop}
    return {"asyncio": asyncio.new_event_loop}


@pytest_asyncio.fixture
async def no_leaked_tasks(request: pytest.FixtureRequest) -> AsyncIterator[None]:
    """Fail the test if an asyncio task it started is still pending when it ends."""
    before = asyncio.all_tasks()
    yield
    if request.node.get_closest_marker("allow_leaks"):
        return
    await asyncio.sleep(0)  # let tasks that were just woken finish their last step
    current = asyncio.current_task()
    left = [t for t in asyncio.all_tasks() - before if t is not current and not t.done()]
    assert not left, f"tasks outlived the test: {left!r}"


@pytest.fixture
def robot_events() -> EventLog:
    """The `EventLog` attached to the ``robot`` or ``sim_robot`` fixture."""
    return EventLog()


@pytest_asyncio.fixture
async def robot(robot_events: EventLog) -> AsyncIterator[Robot]:
    """A running dummy robot; checks that it leaves no action or lock behind."""
    async with Robot(dummy=True, instruments=[robot_events]) as running:
        yield running
    _check_clean(running)


@pytest_asyncio.fixture
async def sim_robot(robot_events: EventLog) -> AsyncIterator[SimRobot]:
    """A running simulated robot (docked, seed 0) in lockstep virtual time."""
    from pyrobots_aio.sim import SimRobot

    async with SimRobot(instruments=[robot_events]) as running:
        yield running
    _check_clean(running)


def _check_clean(robot: Robot) -> None:
    assert not robot.handles(), f"actions outlived the robot: {robot.handles()!r}"
    assert not robot.resources.held(), f"locks outlived the robot: {robot.resources!r}"
