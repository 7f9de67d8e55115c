"""FakeBase and its FakeWorld: kinematics, walls, sensors, dock, frames, ticking."""

from __future__ import annotations

import asyncio
import math

import pytest

from pyrobots_aio import MotionError, UnknownFrameError
from pyrobots_aio.testing import FakeBase, FakeWorld


def test_the_world_moves_along_exact_arcs() -> None:
    world = FakeWorld(start=(0.0, 0.0, 0.0))
    world.set_command(0.2, 0.5)
    for _ in range(100):
        world.step(0.02)
    # two seconds on a circle of radius v / w = 0.4 m, turning 1 rad
    x, y, yaw = world.base_pose()
    assert (x, y, yaw) == pytest.approx((0.4 * math.sin(1.0), 0.4 * (1 - math.cos(1.0)), 1.0))
    assert world.odom_pose() == pytest.approx(world.base_pose())


def test_a_wall_stops_the_robot_presses_the_bumper_and_the_wheels_slip() -> None:
    world = FakeWorld(start=(1.5, 0.0, 0.0))
    assert world.read_sensors()["bumper"] is False
    world.set_command(0.2, 0.0)
    for _ in range(250):  # 5 s at 0.2 m/s: a metre, of which 0.329 m fit before the wall
        world.step(0.02)
    x, y, _ = world.base_pose()
    assert (x, y) == (pytest.approx(2.0 - 0.171), 0.0)
    assert world.odom_pose()[0] == pytest.approx(1.0)  # the odometry counts the slipping wheels
    state = world.read_sensors()
    assert (state["bumper"], state["bumper_left"], state["bumper_right"]) == (True, True, True)
    world.place(2.0 - 0.171, 0.0, math.pi / 2)  # the wall on the right
    state = world.read_sensors()
    assert (state["bumper"], state["bumper_left"], state["bumper_right"]) == (True, False, True)
    world.place(2.0 - 0.171, 0.0, math.pi)  # the wall behind: no bumper there
    assert world.read_sensors()["bumper"] is False


def test_ir_ranges_reach_the_walls_and_read_the_range_beyond() -> None:
    world = FakeWorld(start=(1.7, 0.0, 0.0))
    state = world.read_sensors()
    # ir_front_center_left: 0.165 m from the centre at 5 degrees, looking outwards
    bearing = math.radians(5.0)
    ahead = (2.0 - 1.7 - 0.165 * math.cos(bearing)) / math.cos(bearing)
    assert state["ir_front_center_left"] == pytest.approx(ahead)
    assert state["ir_side_left"] == 0.4  # along the wall: nothing within range
    assert set(state) >= {"ir_right", "cliff_front_left", "docked", "v", "w"}
    assert not any(state[key] for key in state if key.startswith("cliff_"))


def test_docked_when_the_charging_contacts_lie_on_the_pad() -> None:
    world = FakeWorld()
    assert world.read_sensors()["docked"] is True
    world.set_command(0.2, 0.0)
    world.step(0.1)  # 20 mm out: the contacts left the 12 mm pad
    assert world.read_sensors()["docked"] is False
    rotated = FakeWorld(dock=(0.0, 1.9, -math.pi / 2))  # a dock on the north wall
    assert rotated.read_sensors()["docked"] is True
    assert rotated.base_pose() == pytest.approx((0.0, 1.9 - 0.173, -math.pi / 2))


@pytest.mark.asyncio
@pytest.mark.virtual_time
async def test_docking_behind_an_obstacle_fails_with_a_clear_error() -> None:
    in_front_of_the_dock = (-1.75, -0.3, -1.65, 0.3)
    async with FakeBase(obstacles=[in_front_of_the_dock], start=(0.0, 0.0, 0.0)) as robot:
        with pytest.raises(MotionError) as caught:
            await robot.dock()
        assert str(caught.value) == ("docking failed: reversed 0.7 m without touching the dock")
        assert not robot.state.docked
        assert robot.world.command == (0.0, 0.0)


@pytest.mark.asyncio
@pytest.mark.virtual_time
async def test_the_odom_frame_follows_the_slipping_odometry() -> None:
    async with FakeBase(start=(1.5, 0.0, 0.0)) as robot:
        robot.drive(0.2, 0.0)
        await robot.sleep(3.0)
        robot.stop()
        assert robot.odom_pose()[0] == pytest.approx(0.6)  # 3 s at 0.2 m/s of the wheels ...
        assert robot.world.base_pose()[0] == pytest.approx(2.0 - 0.171)  # ... against a wall
        seen = robot.poses.inframe("base_link", "odom")
        assert (seen.x, seen.y) == pytest.approx(robot.odom_pose()[:2])
        dock = robot.poses.inframe("dock", "map")
        assert (dock.x, dock.y) == pytest.approx((-1.9, 0.0))
        with pytest.raises(UnknownFrameError, match=r"^unknown frame 'arm'; known frames: \["):
            robot.poses.inframe("arm", "map")


@pytest.mark.asyncio
@pytest.mark.virtual_time
async def test_it_ticks_at_its_control_rate_and_not_after_it_stops() -> None:
    robot = FakeBase(control_rate=20)
    async with robot:
        await robot.sleep(1.0)
        assert robot.ticks == 20
        assert robot.state.timestamp("v") == robot.time()
    await asyncio.sleep(1.0)
    assert robot.ticks == 20


def test_it_runs_on_an_ordinary_loop_too() -> None:
    async def main() -> float:
        async with FakeBase() as robot:
            robot.drive(0.1, 0.0)
            await robot.sleep(0.2)
            return robot.odom_pose()[0]

    assert asyncio.run(main()) > 0.0


def test_a_bad_control_rate_is_refused() -> None:
    for rate in (0, -1, math.inf, "50", True):
        with pytest.raises(ValueError, match="control_rate") as caught:
            FakeBase(control_rate=rate)  # type: ignore[arg-type]
        hint = " (a bool is not a number)" if rate is True else ""
        assert str(caught.value) == (
            f"control_rate must be a positive number of ticks per second, got {rate!r}{hint}"
        )


def test_a_bad_room_obstacle_or_pose_is_refused() -> None:
    with pytest.raises(ValueError, match="room") as caught:
        FakeWorld(room=(2.0, -2.0, -2.0, 2.0))
    assert str(caught.value) == (
        "room must be (xmin, ymin, xmax, ymax) with xmin < xmax and ymin < ymax, "
        "got (2.0, -2.0, -2.0, 2.0)"
    )
    with pytest.raises(
        ValueError, match=r"^an obstacle must be finite numbers, got \(0.0, 0.0, nan, 1.0\)$"
    ):
        FakeWorld(obstacles=[(0.0, 0.0, math.nan, 1.0)])
    with pytest.raises(ValueError, match="would overlap") as caught:
        FakeWorld(obstacles=[(-0.1, -0.1, 0.1, 0.1)], start=(0.2, 0.0, 0.0))
    assert str(caught.value) == (
        "the robot (radius 0.171 m) at (0.2, 0.0) would overlap "
        "Box(x=0.0, y=0.0, yaw=0.0, hx=0.1, hy=0.1); place it where it is clear"
    )
    world = FakeWorld()
    with pytest.raises(
        ValueError, match=r"^the pose must be finite numbers, got \(0.0, inf, 0.0\)$"
    ):
        world.place(0.0, math.inf, 0.0)
    assert world.read_sensors()["docked"] is True  # unchanged
