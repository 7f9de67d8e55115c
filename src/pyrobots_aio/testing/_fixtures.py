"""The plugin's fixtures and loop choice, registered when pytest-asyncio is recent enough."""

from __future__ import annotations

import asyncio
import contextlib
from typing import TYPE_CHECKING

import pytest
import pytest_asyncio

from .. import Robot
from ..sim import new_virtual_loop
from ._events import EventLog

if TYPE_CHECKING:
    from collections.abc import AsyncIterator, Callable, Mapping

    from ..sim import SimRobot

_VIRTUAL_FIXTURES = frozenset({"sim_robot"})


@pytest.hookimpl(optionalhook=True)
def pytest_asyncio_loop_factories(
    config: pytest.Config, item: pytest.Item
) -> Mapping[str, Callable[[], asyncio.AbstractEventLoop]]:
    """Run tests marked ``virtual_time`` on the virtual-time loop, the others as usual."""
    fixtures = getattr(item, "fixturenames", ())
    if item.get_closest_marker("virtual_time") or _VIRTUAL_FIXTURES.intersection(fixtures):
        return {"virtual_time": new_virtual_loop}
    return {"asyncio": asyncio.new_event_loop}


async def _tasks_left(before: set[asyncio.Task[object]]) -> list[asyncio.Task[object]]:
    """The tasks not in ``before``, other than this one, still pending after one iteration."""
    await asyncio.sleep(0)  # let tasks that were just woken finish their last step
    current = asyncio.current_task()
    return [t for t in asyncio.all_tasks() - before if t is not current and not t.done()]


@pytest_asyncio.fixture
async def no_leaked_tasks(request: pytest.FixtureRequest) -> AsyncIterator[None]:
    """Fail the test if an asyncio task it started is still pending when it ends."""
    before = asyncio.all_tasks()
    yield
    if request.node.get_closest_marker("allow_leaks"):
        return
    left = await _tasks_left(before)
    assert not left, f"tasks outlived the test: {left!r}"


@pytest.fixture
def robot_events() -> EventLog:
    """The `EventLog` attached to the ``robot`` or ``sim_robot`` fixture."""
    return EventLog()


@contextlib.asynccontextmanager
async def _running_checked(robot: Robot, request: pytest.FixtureRequest) -> AsyncIterator[None]:
    """Run ``robot``; once it has shut down, fail if a task or a lock outlived it."""
    before = asyncio.all_tasks()
    async with robot:
        yield
    if request.node.get_closest_marker("allow_leaks"):
        return
    held = robot.resources.held()
    assert not held, f"locks outlived the robot: {robot.resources!r}"
    left = await _tasks_left(before)
    assert not left, f"tasks outlived the robot: {left!r}"


@pytest_asyncio.fixture
async def robot(robot_events: EventLog, request: pytest.FixtureRequest) -> AsyncIterator[Robot]:
    """A running dummy robot; checks that no task or lock outlives it."""
    running = Robot(dummy=True, instruments=[robot_events])
    async with _running_checked(running, request):
        yield running


@pytest_asyncio.fixture
async def sim_robot(
    robot_events: EventLog, request: pytest.FixtureRequest
) -> AsyncIterator[SimRobot]:
    """A running simulated robot (docked, seed 0) in lockstep virtual time."""
    from ..sim import SimRobot

    running = SimRobot(instruments=[robot_events])
    async with _running_checked(running, request):
        yield running
