"""A base plugs in one way: a DriveBackend that a DriveBase holds; sensors come from one table."""

from __future__ import annotations

import math

import pytest

from pyrobots_aio import DriveBase, RobotNotRunningError
from pyrobots_aio.motion import SENSORS, DriveBackend, Sensor, SensorKind
from pyrobots_aio.sim import SimRobot
from pyrobots_aio.testing import FakeBase, FakeWorld
from pyrobots_aio.testing._fakebase import FakeBackend


@pytest.mark.asyncio
@pytest.mark.virtual_time
async def test_every_base_holds_a_drive_backend_and_publishes_its_sensors() -> None:
    for robot in (SimRobot(), FakeBase()):
        assert isinstance(robot.backend, DriveBackend)
        assert robot.sensors == robot.backend.sensors
        async with robot:
            assert [key for key in robot.state if key in {s.key for s in SENSORS}] == [
                s.key for s in SENSORS
            ]


@pytest.mark.asyncio
@pytest.mark.virtual_time
async def test_a_backend_alone_makes_a_base() -> None:
    # No subclass: the backend is all a new base brings (here the fake's, at 100 Hz).
    robot = DriveBase(backend=FakeBackend(FakeWorld(), period=0.01))
    async with robot:
        await robot.undock()
        assert robot.control_period == 0.01
        assert await robot.drive_distance(0.3) == pytest.approx(0.3, abs=0.002)
        assert robot.state.docked is False
    assert robot.poses.inframe("base_link", "dock").x == pytest.approx(0.35 + 0.3 + 0.173, 1e-3)


@pytest.mark.asyncio
@pytest.mark.virtual_time
async def test_a_stopped_fake_refuses_a_controller_at_once() -> None:
    robot = FakeBase()
    async with robot:
        await robot.sleep(0.1)
    with pytest.raises(RobotNotRunningError) as caught:
        await robot.control(lambda: False)
    assert str(caught.value) == (
        "<FakeBackend 50 Hz tick 5> is not running; use 'async with robot:' first"
    )


@pytest.mark.asyncio
@pytest.mark.virtual_time
async def test_a_sensor_added_to_the_table_is_published_by_the_fake() -> None:
    back = Sensor("ir_back", SensorKind.RANGE, reach=0.4, bearing=math.pi)
    drop = Sensor("wheel_drop", SensorKind.FLAG)
    async with FakeBase(sensors=[*SENSORS, back, drop], start=(1.0, 0.0, math.pi)) as robot:
        # facing west, 1 m from the east wall: the rear sensor sees nothing, then the wall
        assert (robot.state.ir_back, robot.state.wheel_drop) == (0.4, False)
        robot.world.place(1.6, 0.0, math.pi)
        await robot.sleep(0.02)
        assert robot.state.ir_back == pytest.approx(2.0 - 1.6 - 0.165)


def test_a_sensor_says_what_it_lacks() -> None:
    with pytest.raises(
        ValueError, match=r"^a sensor's state key must be a non-empty string, got ''$"
    ):
        Sensor("", SensorKind.FLAG)
    with pytest.raises(
        ValueError, match=r"^the range sensor 'ir_back' needs a positive reach in metres, got 0.0$"
    ):
        Sensor("ir_back", SensorKind.RANGE)
    assert Sensor("cliff", SensorKind.FLAG).resting is False
