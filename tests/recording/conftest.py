"""The recorded scenario the recording tests replay, with what it is known to have done.

On a plain ``Robot()`` in virtual time:

t=0     patrol#1 starts; wave#2 takes the arm for 0.5 s; patrol's child drive#3 takes
        the wheels for 2 s.
t=0.1   wave#4 is skipped: the arm is busy (wait=False).
t=2     drive#5 (10 s) takes the wheels.
t=3     bumper becomes True: the monitor starts reflex#6 (priority 5, preempt), which
        preempts drive#5 (cancelled); oops#7 starts and fails at 3.25; patrol#1 starts
        drive#8, which waits for the wheels until the reflex releases them at 4.
t=4     drive#8 drives for 1 s; patrol#1 succeeds at 5.
t=5     drive#9 (100 s) starts; at 5.5 the operator cancels it: "operator stop".
t=5.5   the robot stops; recording ends.
"""

from __future__ import annotations

import contextlib
from dataclasses import dataclass
from typing import TYPE_CHECKING

import pytest

from pyrobots_aio import ActionInterrupted, Resource, Robot, action, lock

if TYPE_CHECKING:
    from collections.abc import Awaitable, Callable

    from pyrobots_aio.recording import Recorder

WHEELS = Resource("wheels")
ARM = Resource("arm")


@action
@lock(WHEELS)
async def drive(robot: Robot, seconds: float) -> None:
    await robot.sleep(seconds)


@action
@lock(WHEELS, priority=5, preempt=True)
async def reflex(robot: Robot) -> None:
    await robot.sleep(1.0)


@action
@lock(ARM, wait=False)
async def wave(robot: Robot) -> None:
    await robot.sleep(0.5)


@action
async def oops(robot: Robot) -> None:
    await robot.sleep(0.25)
    raise ValueError("boom")


@action
async def patrol(robot: Robot) -> None:
    await drive(robot, 2.0)
    with contextlib.suppress(ActionInterrupted):
        await drive(robot, 10.0)
    await drive(robot, 1.0)


@dataclass
class Played:
    """What the scenario saw while it ran."""

    monitor: str
    end: float


async def play(recorder: Recorder) -> Played:
    """Run the scenario with ``recorder`` attached (in virtual time)."""
    robot = Robot()
    with recorder.attach(robot):
        async with robot:
            robot.state.bumper = False
            monitor = robot.whenever("bumper", becomes=True).do(reflex)
            walk = patrol(robot)
            wave(robot)
            await robot.sleep(0.1)
            await wave(robot).wait_done()
            await robot.sleep(2.9)
            robot.state.bumper = True
            failing = oops(robot)
            await robot.sleep(0.02)
            robot.state.bumper = False
            await failing.wait_done()
            await walk
            last = drive(robot, 100.0)
            await robot.sleep(0.5)
            last.cancel("operator stop")
            await last.wait_done()
            end = robot.time()
    return Played(monitor.name, end)


@pytest.fixture
def record_scenario() -> Callable[[Recorder], Awaitable[Played]]:
    """``await record_scenario(recorder)`` plays the scenario into ``recorder``."""
    return play
