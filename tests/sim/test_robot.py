"""SimRobot as a simulator: its ticks, clocks, determinism and physics figures.

Its motion as a `DriveBase` (the actions, the bumper, cancelling) is tested on
every base alike in tests/motion.
"""

from __future__ import annotations

import asyncio
import math
from typing import TYPE_CHECKING, Any

import pytest

from pyrobots_aio import ActionInterrupted, LockstepError, Outcome
from pyrobots_aio.motion import ANGLE_TOLERANCE
from pyrobots_aio.sim import WHEELS, SimRobot, run

if TYPE_CHECKING:
    from collections.abc import Mapping


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


IR_RANGE = 0.4


async def _trajectory(seed: int) -> list[tuple[float, ...]]:
    """Leave the dock, turn north, drive up to the north wall: pose and IR at every tick."""
    rows: list[tuple[float, ...]] = []
    async with SimRobot(seed=seed) as robot:
        ir = sorted(k for k in robot.state if k.startswith("ir_"))

        def record(changes: Mapping[str, Any]) -> None:
            rows.append((*robot.world.base_pose(), *(changes[k] for k in ir)))

        subscription = robot.state.subscribe(record, ir)
        await robot.undock()
        await robot.rotate_angle(math.pi / 2)
        await robot.drive_distance(1.6)  # stops 0.17 m short of the wall
        await robot.rotate_angle(-1.0)  # sweeps the IR along the wall
        subscription.close()
    return rows


def test_same_seed_same_trajectory_and_another_seed_other_ir_noise() -> None:
    first = run(_trajectory, 7)
    seen = [value for row in first for value in row[3:] if value < IR_RANGE]
    assert len(seen) >= 300  # the IR saw the wall: noisy readings, which the seed decides
    assert first == run(_trajectory, 7)
    other = run(_trajectory, 8)
    assert [row[:3] for row in other] == [row[:3] for row in first]  # the physics is the same
    assert other != first


@pytest.mark.asyncio
async def test_the_world_clock_is_the_loop_clock_whenever_the_robot_starts() -> None:
    await asyncio.sleep(5.01)  # the loop's clock runs before the robot does
    robot = SimRobot()
    async with robot:
        assert robot.world.time == robot.time() == 5.01
        await robot.sleep(1.0)
        assert robot.world.time == robot.time() == pytest.approx(6.01)
        assert robot.state.timestamp("v") == robot.time()
        assert robot.world.steps == 500
    await asyncio.sleep(2.0)  # between runs the simulation is paused
    async with robot:
        assert robot.world.steps == 500
        assert robot.world.time == robot.time() == pytest.approx(8.01)
        await robot.sleep(0.5)
        assert robot.world.time == robot.time() == pytest.approx(8.51)
        assert robot.world.steps == 750


# rotate_angle turns on odometry and stops at the control tick nearest the goal: at most
# half a tick (0.02 s) at its slowest turn (0.15 rad/s) off. The true heading is further
# off by the wheels coasting to a halt and by the odometry's slip: about 0.05% of the turn
# here, allowed 0.06%.
STOP_ERROR = 0.15 * 0.02 / 2
COAST = 0.0005
SLIP = 0.0006


@pytest.mark.asyncio
@pytest.mark.parametrize("angle", [0.05, math.pi / 2, -math.pi, -2 * math.pi, 4 * math.pi])
async def test_rotate_angle_turns_the_true_heading(angle: float) -> None:
    async with SimRobot() as robot:
        await robot.undock()
        x0, y0, yaw0 = robot.world.base_pose()
        turned = await robot.rotate_angle(angle)
        await robot.sleep(0.5)  # at rest
        x, y, yaw = robot.world.base_pose()
        assert abs(turned - angle) <= STOP_ERROR < ANGLE_TOLERANCE
        assert abs(math.remainder(yaw - yaw0 - angle, math.tau)) <= (
            STOP_ERROR + COAST + SLIP * abs(angle)
        )
        assert math.hypot(x - x0, y - y0) < 0.002  # in place


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
    for rate in (0, -50, math.inf, "50"):
        with pytest.raises(ValueError, match="control_rate must be") as info:
            SimRobot(control_rate=rate)  # type: ignore[arg-type]
        assert str(info.value) == (
            f"control_rate must be a positive number of ticks per second, got {rate!r}"
        )
    for seed in ("x", -1, 1.5, True):
        with pytest.raises(ValueError, match="seed must be") as info:
            SimRobot(seed=seed)  # type: ignore[arg-type]
        assert str(info.value) == f"seed must be a non-negative integer, not {seed!r}"
    robot = SimRobot()
    with pytest.raises(ValueError, match=r"v must be a finite number, got nan"):
        robot.drive(math.nan, 0.0)


@pytest.mark.asyncio
async def test_bad_motion_arguments_fail_the_action_and_leave_the_wheels_still() -> None:
    async with SimRobot() as robot:
        with pytest.raises(ValueError, match=r"speed must be a positive finite number, got -1"):
            await robot.drive_distance(1.0, speed=-1)
        assert robot.world.command == (0.0, 0.0)
