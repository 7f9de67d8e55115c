"""Stall detection on every base: a motion that commands the wheels and goes nowhere ends.

Without it a ``drive_distance`` into a wall pushed for ever (one port ran 804
simulated seconds so). Now it fails with a `MotionError` once the odometry has
shown no progress for the base's ``stall_timeout``; a motion that moves,
however it starts, never does.
"""

from __future__ import annotations

import asyncio
import math
from typing import TYPE_CHECKING

import pytest

from pyrobots_aio import MotionError, Outcome
from pyrobots_aio.motion import STALL_TIMEOUT, WHEELS
from pyrobots_aio.testing import EventLog, FakeBase

if TYPE_CHECKING:
    from .conftest import Base

pytestmark = [pytest.mark.asyncio, pytest.mark.virtual_time]

BOUND = 120.0
"""Simulated seconds a stalling test gets: without stall detection, a motion into a wall
pushes for ever (the loop never idles, so pytest's own timeout never gets to fire)."""


def stalled(action: str, v: str, w: str, seconds: str, timeout: str = "1.5") -> str:
    return (
        f"{action} stalled: the wheels were commanded v={v} m/s, w={w} rad/s, and the odometry "
        f"showed no progress for {seconds} s (something blocks the robot; "
        f"the bound is robot.stall_timeout = {timeout} s)"
    )


async def test_a_drive_into_a_wall_stops_with_a_motion_error_once_stalled(base: Base) -> None:
    log = EventLog()
    async with base.make(instruments=[log]) as robot, asyncio.timeout(BOUND):
        assert robot.stall_timeout == STALL_TIMEOUT == 1.5
        await robot.undock()
        start = robot.time()
        drive = robot.drive_distance(5.0)  # the east wall is 3.5 m ahead
        assert await drive.wait_done() is Outcome.FAILED
        assert str(drive.exception()) == stalled("drive_distance", "0.2", "0", "1.50")
        assert isinstance(drive.exception(), MotionError)
        assert robot.state.bumper  # it is against the wall ...
        assert base.truth(robot)[0] > 1.8
        assert robot.time() - start < 3.5 / 0.2 + 2.0  # ... and gave up 1.5 s after reaching it
        assert robot.resources.owner(WHEELS) is None
        await robot.sleep(0.5)
        assert robot.state.v == pytest.approx(0.0, abs=0.005)  # the wheels were stopped
    assert log.outcomes("drive_distance") == ["succeeded", "failed"]


async def test_the_bound_is_the_bases_stall_timeout(base: Base) -> None:
    async with base.make(stall_timeout=3) as robot, asyncio.timeout(BOUND):
        assert robot.stall_timeout == 3.0
        await robot.undock()
        await robot.drive_distance(2.0)
        with pytest.raises(MotionError) as caught:
            await robot.drive_distance(5.0, speed=0.1)
        assert str(caught.value) == stalled("drive_distance", "0.1", "0", "3.00", "3")
        robot.stall_timeout = 0.5  # it can change any time
        with pytest.raises(MotionError) as caught:
            await robot.drive_distance(1.0)
        assert str(caught.value) == stalled("drive_distance", "0.2", "0", "0.50", "0.5")


async def test_no_false_stall_from_rest_or_when_turning_or_reversing(base: Base) -> None:
    async with base.make(stall_timeout=0.2) as robot:  # ten control ticks
        await robot.undock()
        assert await robot.drive_distance(0.5) == pytest.approx(0.5, abs=0.003)
        assert await robot.rotate_angle(-2.0) == pytest.approx(-2.0, abs=0.006)
        assert await robot.drive_distance(-0.3) == pytest.approx(-0.3, abs=0.003)
        await robot.navigate_to((0.0, 0.5, 0.0, 0.0, 0.0, math.pi / 2))
        assert await robot.drive_distance(0.1, speed=0.004) == pytest.approx(0.1, abs=0.003)
        await robot.dock()
        assert robot.state.docked


async def test_a_paused_motion_does_not_count_its_frozen_time(base: Base) -> None:
    async with base.make(stall_timeout=0.5) as robot:
        await robot.undock()
        drive = robot.drive_distance(0.6)
        await robot.sleep(1.0)
        drive.pause("hold still")
        await robot.sleep(2.0)
        drive.resume()
        assert await drive == pytest.approx(0.6, abs=0.003)


async def test_jammed_wheels_stall_a_turn_and_a_navigation() -> None:
    async with FakeBase(start=(0.0, 0.0, 0.0)) as robot, asyncio.timeout(BOUND):
        robot.world.jammed = True
        with pytest.raises(MotionError) as caught:
            await robot.rotate_angle(1.0)
        assert str(caught.value) == stalled("rotate_angle", "0", "1", "1.50")
        with pytest.raises(MotionError) as caught:
            await robot.navigate_to((1.0, 0.0, 0.0, "map"))
        assert str(caught.value) == stalled("navigate_to", "0.2", "0", "1.50")
        assert robot.world.base_pose() == (0.0, 0.0, 0.0)
        assert robot.world.command == (0.0, 0.0)


async def test_a_bad_stall_timeout_is_refused_naming_it() -> None:
    message = r"^stall_timeout must be a positive number of seconds, got 0$"
    with pytest.raises(ValueError, match=message):
        FakeBase(stall_timeout=0)
    robot = FakeBase()
    with pytest.raises(ValueError, match=r"^stall_timeout must be .*, got nan$"):
        robot.stall_timeout = math.nan
    assert robot.stall_timeout == STALL_TIMEOUT
