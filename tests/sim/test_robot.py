from __future__ import annotations

import asyncio
import itertools
import math

import pytest

from pyrobots_aio import ActionInterrupted, LockstepError, Outcome
from pyrobots_aio.sim import WHEELS, SimRobot, run

pytestmark = pytest.mark.virtual_time

REQUIRED_KEYS = {
    "bumper",
    "bumper_left",
    "bumper_right",
    "docked",
    "v",
    "w",
    "ir_front_center_left",
    "cliff_front_left",
}


@pytest.mark.asyncio
async def test_starts_docked_and_publishes_every_tick() -> None:
    async with SimRobot() as robot:
        assert robot.state.docked is True
        assert set(robot.state) >= REQUIRED_KEYS
        ir = [k for k in robot.state if k.startswith("ir_")]
        assert 5 <= len(ir) <= 7
        assert all(0 < robot.state[k] <= 0.4 for k in ir)
        version = robot.state.version("bumper")
        await robot.sleep(10.0)
        assert robot.sim.ticks == 500
        assert robot.state.version("bumper") == version + 500
        assert robot.state.timestamp("bumper") == pytest.approx(robot.time())
        assert robot.time() == pytest.approx(10.0)


@pytest.mark.asyncio
async def test_drive_distance_and_rotate_angle_reach_their_targets() -> None:
    async with SimRobot() as robot:
        await robot.undock()
        x0, y0, _ = robot.world.base_pose()
        done = await robot.drive_distance(0.8)
        assert done == pytest.approx(0.8, abs=0.003)
        x1, y1, _ = robot.world.base_pose()
        assert math.hypot(x1 - x0, y1 - y0) == pytest.approx(0.8, abs=0.01)
        turned = await robot.rotate_angle(-math.pi / 2)
        assert turned == pytest.approx(-math.pi / 2, abs=0.006)
        back = await robot.drive_distance(-0.3)
        assert back == pytest.approx(-0.3, abs=0.003)
        await robot.sleep(0.1)  # the wheels were stopped; the next ticks publish it
        assert robot.state.v == pytest.approx(0.0, abs=0.01)


@pytest.mark.asyncio
async def test_navigate_to_a_map_pose_and_back_to_the_dock() -> None:
    async with SimRobot() as robot:
        await robot.undock()
        await robot.navigate_to((0.0, 0.5, 0.0, 0.0, 0.0, math.pi / 2))
        x, y, yaw = robot.world.base_pose()
        assert (x, y) == (pytest.approx(0.0, abs=0.02), pytest.approx(0.5, abs=0.02))
        assert yaw == pytest.approx(math.pi / 2, abs=0.01)
        me = robot.poses.myself()
        assert (me.x, me.y) == (pytest.approx(x), pytest.approx(y))
        assert not robot.state.docked
        await robot.dock()
        assert robot.state.docked
        assert robot.state.bumper is False


@pytest.mark.asyncio
async def test_driving_into_a_wall_presses_the_bumper_and_lowers_ir() -> None:
    async with SimRobot() as robot:
        await robot.undock()
        readings = []
        robot.drive(0.25, 0.0)
        while not robot.state.bumper:
            await robot.sleep(0.1)
            readings.append(robot.state.ir_front_center_left)
            assert robot.time() < 30, "never reached the east wall"
        robot.stop()
        assert robot.state.bumper_left
        assert robot.state.bumper_right
        seen = [r for r in readings if r < 0.4]
        assert len(seen) >= 5
        assert all(later <= earlier + 0.01 for earlier, later in itertools.pairwise(seen))
        assert seen[-1] < 0.1
        assert robot.world.base_pose()[0] > 1.7


@pytest.mark.asyncio
async def test_cancelling_a_motion_stops_the_wheels_and_releases_them() -> None:
    async with SimRobot() as robot:
        await robot.undock()
        handle = robot.drive_distance(2.0)
        await robot.sleep(1.0)
        assert robot.resources.owner(WHEELS) is handle
        assert robot.state.v == pytest.approx(0.2, abs=0.01)
        handle.cancel("stop now")
        with pytest.raises(ActionInterrupted, match="stop now"):
            await handle
        assert robot.world.command == (0.0, 0.0)
        await robot.sleep(0.5)
        assert robot.state.v == pytest.approx(0.0, abs=0.005)
        assert robot.resources.owner(WHEELS) is None
        assert handle.outcome is Outcome.CANCELLED


async def _trajectory(seed: int) -> list[tuple[float, float, float]]:
    poses = []
    async with SimRobot(seed=seed) as robot:
        await robot.undock()
        walk = robot.drive_distance(0.6)
        for _ in range(100):
            await robot.sleep(0.05)
            poses.append(robot.world.base_pose())
        await walk
        await robot.rotate_angle(1.0)
        poses.append(robot.world.base_pose())
        poses.append(tuple(robot.state[k] for k in sorted(robot.state) if k.startswith("ir_")))
    return poses


def test_same_seed_same_trajectory() -> None:
    assert run(_trajectory, 7) == run(_trajectory, 7)


def test_lockstep_robot_under_an_ordinary_loop_says_so() -> None:
    async def main() -> None:
        async with SimRobot():
            pass

    with pytest.raises(LockstepError) as caught:
        asyncio.run(main())
    assert str(caught.value) == (
        "this simulated robot runs in lockstep virtual time (realtime=False), but the event "
        "loop is an ordinary one; start it with pyrobots_aio.sim.run(main) or the pytest "
        "marker @pytest.mark.virtual_time, or pass realtime=True"
    )


def test_realtime_robot_follows_the_wall_clock() -> None:
    async def main() -> int:
        async with SimRobot(realtime=True) as robot:
            await robot.sleep(0.2)
            return robot.sim.ticks

    assert 5 <= asyncio.run(main()) <= 11


def test_bad_arguments_are_rejected() -> None:
    with pytest.raises(ValueError, match=r"control_rate 33 Hz is not a whole number"):
        SimRobot(control_rate=33)
    robot = SimRobot()
    with pytest.raises(ValueError, match=r"v must be a finite number, got nan"):
        robot.drive(math.nan, 0.0)


@pytest.mark.asyncio
async def test_bad_motion_arguments_fail_the_action() -> None:
    async with SimRobot() as robot:
        with pytest.raises(ValueError, match=r"speed must be positive, got -1"):
            await robot.drive_distance(1.0, speed=-1)
        assert robot.world.command == (0.0, 0.0)
