"""The emergency stop on a DriveBase: the wheels stop at once, motion is refused until cleared."""

from __future__ import annotations

import asyncio
import math
from typing import TYPE_CHECKING

import pytest

from pyrobots_aio import EmergencyStopError, Outcome
from pyrobots_aio.sim import SimRobot
from pyrobots_aio.sim.random_walk import random_walk
from pyrobots_aio.testing import FakeBase

if TYPE_CHECKING:
    from collections.abc import Callable

    from pyrobots_aio import DriveBase

pytestmark = [pytest.mark.asyncio, pytest.mark.virtual_time]

BASES: dict[str, Callable[[], DriveBase]] = {"fake": FakeBase, "sim": SimRobot}
REFUSED = (
    "{what} refused: the emergency stop is latched ('cliff'); call "
    "robot.clear_emergency_stop() once it is safe to move"
)


def where(robot: DriveBase) -> tuple[float, float]:
    x, y, _ = robot.map_pose()
    return x, y


@pytest.mark.parametrize("kind", sorted(BASES))
async def test_a_cliff_stops_the_drive_at_once_and_refuses_motion_until_cleared(
    kind: str,
) -> None:
    async with BASES[kind]() as robot:
        robot.whenever("cliff_front_left", becomes=True).do(robot.emergency_stop, "cliff")
        await robot.undock()
        start = where(robot)
        drive = robot.drive_distance(1.0)
        await robot.sleep(1.0)
        robot.state.cliff_front_left = True  # one tick over the edge: the base rewrites it
        cliff = where(robot)
        assert await drive.wait_done() is Outcome.CANCELLED
        assert drive.cancel_reason == "emergency stop: cliff"
        await robot.sleep(0.2)
        stopped_at = where(robot)
        assert math.dist(stopped_at, cliff) < 0.01  # what the base coasts (nothing on the fake)
        assert math.dist(stopped_at, start) < 0.25
        await robot.sleep(1.0)
        assert math.dist(where(robot), stopped_at) < 0.001
        assert robot.state.v == pytest.approx(0.0, abs=0.001)
        with pytest.raises(EmergencyStopError) as refused:
            await robot.drive_distance(0.5)
        assert str(refused.value) == REFUSED.format(what="drive_distance")
        assert refused.value.reason == "cliff"
        with pytest.raises(EmergencyStopError, match=r"^rotate_angle refused"):
            await robot.rotate_angle(1.0)
        with pytest.raises(EmergencyStopError) as refused:
            robot.drive(0.1, 0.0)
        assert str(refused.value) == REFUSED.format(what="drive(0.1, 0.0)")
        robot.drive(0.0, 0.0)  # stopping is always allowed
        robot.stop()
        await robot.sleep(0.5)
        assert math.dist(where(robot), stopped_at) < 0.001
        robot.clear_emergency_stop()
        done = await robot.drive_distance(0.3)
        assert done == pytest.approx(0.3, abs=0.003)


async def test_the_stop_reaches_the_wheels_at_the_call() -> None:
    async with FakeBase() as robot:
        await robot.undock()
        drive = robot.drive_distance(1.0)
        await robot.sleep(1.0)
        assert robot.world.command[0] > 0.1
        robot.emergency_stop("operator")
        assert robot.world.command == (0.0, 0.0)  # before any task has run
        await drive.wait_done()


async def test_a_random_walk_ends_with_the_refusal_and_stands_still() -> None:
    async with FakeBase() as robot:
        robot.whenever("cliff_front_left", becomes=True).do(robot.emergency_stop, "cliff")
        with pytest.raises(EmergencyStopError, match=r"^\w+ refused: the emergency stop"):
            await _walk_into_a_cliff(robot)
        stopped_at = where(robot)
        await robot.sleep(5.0)
        assert math.dist(where(robot), stopped_at) < 1e-9
        assert robot.resources.held() == {}


async def _walk_into_a_cliff(robot: FakeBase) -> None:
    async def cliff_after(seconds: float) -> None:
        await robot.sleep(seconds)
        robot.state.cliff_front_left = True

    cliff = asyncio.create_task(cliff_after(4.0))
    try:
        await random_walk(robot, moves=20)
    finally:
        await cliff
