"""A stopped simulator refuses new control loops instead of leaving them waiting forever."""

from __future__ import annotations

import asyncio

import pytest

from pyrobots_aio import LockstepError
from pyrobots_aio.sim import SimRobot

NOT_RUNNING = "the simulated robot is not running; use 'async with robot:' first"


@pytest.mark.virtual_time
@pytest.mark.asyncio
async def test_after_stop_a_controller_fails_at_once() -> None:
    # An action still running once the robot has stopped (an abandoned one, or one
    # cut loose by a second Ctrl-C) used to wait for a tick that never came.
    robot = SimRobot()
    async with robot:
        await robot.sleep(0.1)
    async with asyncio.timeout(60):  # before: a TimeoutError, a minute of virtual time later
        with pytest.raises(LockstepError) as caught:
            await robot.sim.control(lambda: False)
    assert str(caught.value) == NOT_RUNNING


@pytest.mark.virtual_time
@pytest.mark.asyncio
async def test_a_stopped_robot_runs_again() -> None:
    robot = SimRobot()
    async with robot:
        await robot.undock()
    async with robot:  # started again: its controllers run
        travelled = await robot.drive_distance(0.1)
    assert travelled == pytest.approx(0.1, abs=0.002)
