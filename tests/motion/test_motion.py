"""The motion layer on every base: the same tests for SimRobot, FakeBase (and more to come)."""

from __future__ import annotations

import asyncio
import itertools
import math
from typing import TYPE_CHECKING, Any

import pytest

from pyrobots_aio import ActionInterrupted, DriveBase, Outcome
from pyrobots_aio.motion import WHEELS
from pyrobots_aio.sim.random_walk import random_walk
from pyrobots_aio.testing import EventLog

HANG_GUARD = 60.0
"""Seconds of the robot's clock a wait may take at most (a hung test fails)."""

if TYPE_CHECKING:
    from collections.abc import Callable

    from pyrobots_aio.actions import ActionHandle

    from .conftest import Base

pytestmark = [pytest.mark.asyncio, pytest.mark.virtual_time]

KEYS = {"bumper", "bumper_left", "bumper_right", "docked", "v", "w"}


async def test_starts_docked_with_the_state_keys_and_frames_of_a_base(base: Base) -> None:
    async with base.make() as robot:
        assert isinstance(robot, DriveBase)
        assert robot.state.docked is True
        assert set(robot.state) >= KEYS
        ir = [key for key in robot.state if key.startswith("ir_")]
        assert 5 <= len(ir) <= 7
        assert all(0 < robot.state[key] <= 0.4 for key in ir)
        assert [key for key in robot.state if key.startswith("cliff_")]
        assert not any(robot.state[key] for key in robot.state if key.startswith("cliff_"))
        assert {"odom", "base_link", "dock"} <= robot.poses.frames()
        version = robot.state.version("v")
        await robot.sleep(1.0)
        assert robot.state.version("v") == version + round(1.0 / robot.control_period)


async def test_odom_and_map_poses_agree_with_the_frames(base: Base) -> None:
    async with base.make() as robot:
        await robot.undock()
        await robot.rotate_angle(1.0)
        await robot.drive_distance(0.3)
        seen = robot.poses.inframe("base_link", "odom")
        x, y, yaw = robot.odom_pose()
        assert (seen.x, seen.y) == (pytest.approx(x, abs=1e-9), pytest.approx(y, abs=1e-9))
        assert robot.poses.euler(seen)[2] == pytest.approx(yaw, abs=1e-9)
        me = robot.poses.myself()
        x, y, yaw = robot.map_pose()
        assert (me.x, me.y) == (pytest.approx(x, abs=1e-9), pytest.approx(y, abs=1e-9))
        assert robot.poses.euler(me)[2] == pytest.approx(yaw, abs=1e-9)


async def test_drive_distance_and_rotate_angle_reach_their_targets(base: Base) -> None:
    async with base.make() as robot:
        await robot.undock()
        x0, y0, _ = base.truth(robot)
        done = await robot.drive_distance(0.8)
        assert done == pytest.approx(0.8, abs=0.003)
        x1, y1, _ = base.truth(robot)
        assert math.hypot(x1 - x0, y1 - y0) == pytest.approx(0.8, abs=0.01)
        turned = await robot.rotate_angle(-math.pi / 2)
        assert turned == pytest.approx(-math.pi / 2, abs=0.006)
        back = await robot.drive_distance(-0.3)
        assert back == pytest.approx(-0.3, abs=0.003)
        await robot.sleep(0.1)  # the wheels were stopped; the next ticks publish it
        assert robot.state.v == pytest.approx(0.0, abs=0.01)


async def test_navigate_to_a_map_pose_and_back_to_the_dock(base: Base) -> None:
    async with base.make() as robot:
        await robot.undock()
        await robot.navigate_to((0.0, 0.5, 0.0, 0.0, 0.0, math.pi / 2))
        x, y, yaw = base.truth(robot)
        assert (x, y) == (pytest.approx(0.0, abs=0.02), pytest.approx(0.5, abs=0.02))
        assert yaw == pytest.approx(math.pi / 2, abs=0.01)
        assert not robot.state.docked
        await robot.dock()
        assert robot.state.docked
        assert robot.state.bumper is False


async def test_driving_into_a_wall_presses_the_bumper_and_lowers_ir(base: Base) -> None:
    async with base.make() as robot:
        await robot.undock()
        readings = []
        ticks = robot.state.version("v")
        robot.drive(0.25, 0.0)
        while not robot.state.bumper:
            await robot.sleep(0.1)
            readings.append(robot.state.ir_front_center_left)
            # 30 s of the base's own ticks, not of the loop: a sim-node that a loaded
            # machine holds back simulates fewer seconds than its loop's clock counts.
            driven = (robot.state.version("v") - ticks) * robot.control_period
            assert driven < 30, "never reached the east wall"
        robot.stop()
        # One tick more: over ROS 2 each bumper is a topic of its own, and the three
        # messages of one tick may land in separate loop iterations.
        await robot.sleep(robot.control_period)
        assert robot.state.bumper_left
        assert robot.state.bumper_right
        seen = [r for r in readings if r < 0.4]
        assert len(seen) >= 5
        assert all(later <= earlier + 0.01 for earlier, later in itertools.pairwise(seen))
        assert seen[-1] < 0.1
        assert base.truth(robot)[0] > 1.7


async def _moving(robot: DriveBase) -> None:
    await robot.sleep(0.5)
    assert robot.resources.owner(WHEELS) is not None
    assert (robot.state.v, robot.state.w) != (0.0, 0.0)


MOTIONS: dict[str, Callable[[DriveBase], ActionHandle[Any]]] = {
    "drive_distance": lambda robot: robot.drive_distance(2.0),
    "navigate_to": lambda robot: robot.navigate_to((1.0, 0.5, 0.0, 0.0, 0.0, 0.0)),
    "rotate_angle": lambda robot: robot.rotate_angle(3.0),
    "dock": lambda robot: robot.dock(),
    "undock": lambda robot: robot.undock(),
}


@pytest.mark.parametrize("name", sorted(MOTIONS))
async def test_cancelling_any_motion_stops_the_wheels_and_releases_them(
    base: Base, name: str
) -> None:
    async with base.make() as robot:
        if name != "undock":
            await robot.undock()
            await robot.drive_distance(0.5)
        handle = MOTIONS[name](robot)
        await _moving(robot)
        handle.cancel("stop now")
        with pytest.raises(ActionInterrupted, match="stop now"):
            await handle
        assert robot.resources.owner(WHEELS) is None
        await robot.sleep(0.5)
        assert robot.state.v == pytest.approx(0.0, abs=0.005)
        assert robot.state.w == pytest.approx(0.0, abs=0.01)
        assert handle.outcome is Outcome.CANCELLED


async def _reaches(robot: DriveBase, v: float, within: float, tolerance: float) -> None:
    """Wait until ``robot.state.v`` is ``v``: ``within`` seconds in virtual time; over ROS 2,
    where the base is another process that a loaded machine may hold up, until a hang guard."""
    await robot.sleep(within)
    async with asyncio.timeout(HANG_GUARD):
        while abs(robot.state.v - v) > tolerance:
            await robot.sleep(robot.control_period)


async def test_drive_and_stop_command_the_wheels_without_locking_them(base: Base) -> None:
    async with base.make() as robot:
        robot.drive(0.1, 0.0)
        await _reaches(robot, 0.1, 1.0, 0.01)
        assert robot.state.v == pytest.approx(0.1, abs=0.01)
        assert not robot.state.docked
        assert robot.resources.owner(WHEELS) is None
        robot.stop()
        await _reaches(robot, 0.0, 0.5, 0.005)
        assert robot.state.v == pytest.approx(0.0, abs=0.005)


async def test_bad_motion_arguments_are_refused(base: Base) -> None:
    async with base.make() as robot:
        with pytest.raises(ValueError, match=r"^v must be a finite number, got nan$"):
            robot.drive(math.nan, 0.0)
        with pytest.raises(ValueError, match=r"^w must be a finite number, got '1'$"):
            robot.drive(0.0, "1")  # type: ignore[arg-type]
        with pytest.raises(ValueError, match=r"^speed must be a positive finite number, got -1$"):
            await robot.drive_distance(1.0, speed=-1)
        with pytest.raises(
            ValueError, match=r"^angle must be a finite number from -6283.19 to 6283.19, got inf; "
        ):
            await robot.rotate_angle(math.inf)
        await robot.sleep(0.1)
        assert robot.state.docked  # nothing moved
        assert abs(robot.state.v) < 1e-9


@pytest.mark.parametrize("seed", [0, 5])
async def test_the_random_walk_handles_every_bump_and_docks(base: Base, seed: int) -> None:
    log = EventLog()
    async with base.make(instruments=[log]) as robot:
        report = await random_walk(robot, seed=seed)
        assert not robot.state.bumper
        assert robot.state.docked
        assert robot.handles() == []
    assert (report.moves, report.docked) == (10, True)
    assert report.sim_time < 150
    assert set(log.outcomes("bumper_reflex")) <= {"succeeded"}
    assert len(log.outcomes("bumper_reflex")) <= report.bumps


async def test_pausing_a_drive_halfway_stops_the_robot_and_resuming_reaches_the_goal(
    base: Base,
) -> None:
    async with base.make() as robot:
        await robot.undock()
        x0, y0, _ = base.truth(robot)
        drive = robot.drive_distance(1.0)
        while math.hypot(base.truth(robot)[0] - x0, base.truth(robot)[1] - y0) < 0.5:
            await robot.sleep(robot.control_period)
        drive.pause("hold still")
        await robot.sleep(1.0)  # time to brake
        x1, y1, _ = base.truth(robot)
        await robot.sleep(3.0)
        assert robot.state.v == pytest.approx(0.0, abs=0.005)  # stopped, and stays so
        x2, y2, _ = base.truth(robot)
        assert math.hypot(x2 - x1, y2 - y1) < 0.002
        assert 0.5 < math.hypot(x1 - x0, y1 - y0) < 0.7
        drive.resume()
        done = await drive
        x3, y3, _ = base.truth(robot)
    assert done == pytest.approx(1.0, abs=0.003)
    assert math.hypot(x3 - x0, y3 - y0) == pytest.approx(1.0, abs=0.01)  # within 1 cm


async def test_pausing_the_bumper_reflex_pauses_its_subtree_only(base: Base) -> None:
    from pyrobots_aio.sim.random_walk import bumper_reflex

    async with base.make() as robot:
        await robot.undock()
        walk = robot.drive_distance(5.0)  # toward the wall ahead
        reflex = robot.on("bumper", becomes=True).do(bumper_reflex)
        while reflex.firings == 0:
            await robot.sleep(robot.control_period)
        (handle,) = [h for h in robot.handles() if h.name == "bumper_reflex"]
        while not handle.children:
            await robot.sleep(robot.control_period)
        handle.pause("look around")
        frozen = [h for h in robot.handles() if h.paused]
        assert {h.name for h in frozen} == {"bumper_reflex", "drive_distance"}
        assert all(h is handle or h.childof(handle) for h in frozen)
        await robot.sleep(2.0)
        assert robot.state.v == pytest.approx(0.0, abs=0.005)
        handle.resume()
        assert await handle.wait_done() is Outcome.SUCCEEDED
        assert await walk.wait_done() is Outcome.CANCELLED  # preempted by the reflex, as usual
