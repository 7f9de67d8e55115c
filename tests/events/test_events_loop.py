"""What monitors put on the event loop (DESIGN §5).

A callback of any kind starts within one loop iteration of the write that
fired it, and monitors that watch a state where nothing changes leave no
timer and no queued callback behind: they cost no CPU.
"""

from __future__ import annotations

import asyncio
from typing import Any

import pytest

from pyrobots_aio import Robot, action
from pyrobots_aio.loops import VirtualTimeLoop

pytestmark = pytest.mark.virtual_time

started: list[str] = []


@action
async def as_action(robot: Robot, monitor: str) -> None:
    started.append(f"action of {monitor}")
    await robot.sleep(3600)


async def as_coroutine(monitor: str) -> None:
    started.append(f"coroutine function of {monitor}")
    await asyncio.sleep(3600)


def as_function(monitor: str) -> None:
    started.append(f"function of {monitor}")


@pytest.fixture(autouse=True)
def _clear_started() -> None:
    started.clear()


def _virtual_loop() -> VirtualTimeLoop:
    loop = asyncio.get_running_loop()
    assert isinstance(loop, VirtualTimeLoop)
    return loop


@pytest.mark.parametrize(
    ("var", "cond"),
    [
        ("bumper", {"becomes": True}),
        ("bumper", {"value": True}),
        ("ir", {"below": 0.2}),
        ("ir", {"decrease": 0.5}),
        (lambda r: r.state.bumper, {}),
    ],
    ids=["edge", "level", "threshold", "decrease", "sync predicate"],
)
@pytest.mark.asyncio
async def test_every_kind_of_callback_starts_one_loop_iteration_after_the_write(
    var: Any, cond: dict[str, Any]
) -> None:
    async with Robot() as robot:
        robot.state.update(bumper=False, ir=1.0)
        for callback in (as_function, as_coroutine, as_action):
            robot.whenever(var, **cond).do(callback, callback.__name__)
        await asyncio.sleep(0)  # a level that holds at creation would fire now: none does
        assert started == []
        robot.state.update(bumper=True, ir=0.1)
        assert started == []  # no user code runs inside the write
        await asyncio.sleep(0)  # one loop iteration
        assert started == [
            "function of as_function",
            "coroutine function of as_coroutine",
            "action of as_action",
        ]


@pytest.mark.asyncio
async def test_idle_monitors_leave_no_timer_and_no_queued_callback() -> None:
    fired: list[str] = []

    async def far_from_dock(robot: Robot) -> bool:
        distance = robot.state.distance
        await robot.sleep(0.03)  # e.g. asks a planner
        return bool(distance > 2.0)

    loop = _virtual_loop()
    async with Robot() as robot:
        robot.state.update(bumper=False, battery=1.0, distance=0.0)
        t0 = loop.time()
        monitors = {
            "level": robot.whenever("bumper", value=True),
            "edge": robot.whenever("bumper", becomes=True),
            "increase": robot.whenever("battery", increase=0.5),
            "hold": robot.whenever("battery", below=0.2, held_for=2.0),
            "sync predicate": robot.whenever(lambda r: r.state.bumper),
            "async predicate": robot.whenever(far_from_dock),
        }
        for name, monitor in monitors.items():
            monitor.do(fired.append, name)
        robot.state.bumper = True  # levels and edges rise...
        robot.state.bumper = False  # ...and fall
        robot.state.battery = 0.1  # the hold begins
        robot.state.distance = 3.0  # the async predicate holds (at t0 + 0.03)...
        await robot.sleep(0.05)
        robot.state.distance = 0.0  # ...and stops holding (at t0 + 0.08)
        await robot.sleep(1.0)  # the evaluations and the rate limit's cool-downs are over
        assert [timer.when() - t0 for timer in loop.pending_timers()] == [2.0]  # the hold
        robot.state.battery = 1.6  # the hold is cancelled; the battery rose by 1.5
        await asyncio.sleep(0)
        assert fired == ["level", "edge", "sync predicate", "async predicate", "increase"]
        assert loop.pending_timers() == []
        assert loop.ready_callbacks() == []
        await robot.sleep(3600)
        assert fired == ["level", "edge", "sync predicate", "async predicate", "increase"]
        assert loop.pending_timers() == []
        assert loop.ready_callbacks() == []
