"""FakeBase and its FakeWorld: kinematics, walls, sensors, dock, frames, ticking."""

from __future__ import annotations

import asyncio
import math

import pytest

from pyrobots_aio import MotionError, StallError, UnknownFrameError
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


def test_a_wall_stops_the_robot_presses_the_bumper_and_the_wheels_stall() -> None:
    world = FakeWorld(start=(1.5, 0.0, 0.0))
    assert world.read_sensors()["bumper"] is False
    world.set_command(0.2, 0.0)
    for _ in range(250):  # 5 s at 0.2 m/s: a metre, of which 0.329 m fit before the wall
        world.step(0.02)
    x, y, _ = world.base_pose()
    assert (x, y) == (pytest.approx(2.0 - 0.171), 0.0)
    assert world.odom_pose() == pytest.approx((0.329, 0.0, 0.0))  # the wheels stalled there
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


def test_the_odometry_follows_a_robot_sliding_along_a_wall() -> None:
    world = FakeWorld(start=(1.5, 0.0, math.pi / 4))
    world.set_command(0.2, 0.0)
    for _ in range(250):  # into the east wall at 45 degrees, then along it
        world.step(0.02)
    x, y, yaw = world.base_pose()
    assert (x, yaw) == pytest.approx((2.0 - 0.171, math.pi / 4))
    assert 0.5 < y < 0.71  # it slid north, slower than it drove
    c = s = math.sqrt(0.5)  # the odometry started facing its x axis: the map turned by -45 degrees
    expected = (c * (x - 1.5) + s * y, -s * (x - 1.5) + c * y, 0.0)
    assert world.odom_pose() == pytest.approx(expected, abs=1e-9)  # as the robot went
    assert world.read_sensors()["bumper"] is True


def test_jammed_wheels_move_nothing() -> None:
    world = FakeWorld(start=(0.0, 0.0, 0.0))
    world.jammed = True
    world.set_command(0.2, 1.0)
    world.step(1.0)
    assert (world.base_pose(), world.odom_pose()) == ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    world.jammed = False
    world.step(0.5)
    assert world.base_pose()[0] > 0.09


@pytest.mark.asyncio
@pytest.mark.virtual_time
async def test_docking_behind_an_obstacle_fails_with_a_stall() -> None:
    in_front_of_the_dock = (-1.75, -0.3, -1.65, 0.3)
    async with FakeBase(obstacles=[in_front_of_the_dock], start=(0.0, 0.0, 0.0)) as robot:
        with pytest.raises(StallError) as caught:
            await robot.dock()
        assert str(caught.value) == (
            "dock stalled: the wheels were commanded v=-0.05 m/s, w=0 rad/s, and the odometry "
            "showed no progress for 1.50 s (something blocks the robot; the bound is "
            "robot.stall_timeout = 1.5 s)"
        )
        assert not robot.state.docked
        assert robot.world.command == (0.0, 0.0)


class Mislocalised(FakeBase):
    """A robot that believes it is 0.4 m north of where it is."""

    def map_pose(self) -> tuple[float, float, float]:
        x, y, yaw = super().map_pose()
        return x, y + 0.4, yaw


@pytest.mark.asyncio
@pytest.mark.virtual_time
async def test_docking_beside_the_dock_fails_once_it_reversed_too_far() -> None:
    room_behind_the_dock = (-3.0, -2.0, 2.0, 2.0)
    async with Mislocalised(room=room_behind_the_dock, start=(0.0, 0.4, 0.0)) as robot:
        with pytest.raises(MotionError) as caught:
            await robot.dock()
        assert str(caught.value) == "docking failed: reversed 0.7 m without touching the dock"
        assert not robot.state.docked
        assert robot.world.base_pose()[:2] == pytest.approx((-1.45 - 0.7, -0.4), abs=0.03)


@pytest.mark.asyncio
@pytest.mark.virtual_time
async def test_the_odom_frame_places_base_link_at_the_odometry() -> None:
    async with FakeBase(start=(1.5, 0.0, 0.0)) as robot:
        robot.drive(0.2, 0.1)  # into the east wall, sliding along it
        await robot.sleep(3.0)
        robot.stop()
        assert robot.odom_pose()[0] == pytest.approx(2.0 - 0.171 - 1.5, abs=0.01)
        seen = robot.poses.inframe("base_link", "odom")
        assert (seen.x, seen.y) == pytest.approx(robot.odom_pose()[:2])
        assert robot.poses.euler(seen)[2] == pytest.approx(robot.odom_pose()[2])
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


def test_a_rate_so_slow_its_period_is_infinite_is_refused() -> None:
    with pytest.raises(ValueError, match="period") as caught:
        FakeBase(control_rate=1e-320)  # 1 / 1e-320 overflows: the world would step by inf
    assert str(caught.value) == "period must be a positive number of seconds, got inf"


def test_a_world_steps_only_by_finite_seconds_but_the_wheels_take_any_finite_number() -> None:
    world = FakeWorld()
    for dt in (math.nan, -0.1, "0.02"):
        with pytest.raises(ValueError, match="dt"):
            world.step(dt)  # type: ignore[arg-type]
    world.set_command(0.1, 0.5)
    for v, w in ((math.nan, 0.0), (0.0, math.inf), (True, 0.0)):
        with pytest.raises(ValueError, match="must be a finite number"):
            world.set_command(v, w)
    assert world.command == (0.1, 0.5)  # a refused command leaves the one before
    world.set_command(1, 0)  # an int is a number: scaled to the top wheel speed
    assert world.command == (0.306, 0.0)


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
