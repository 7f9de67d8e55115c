"""What a robot starts and stops: its extensions and backend, on one exit stack, in order."""

from __future__ import annotations

import asyncio

import pytest

from pyrobots_aio import PyRobotsError, Robot, action


class Part:
    """A backend or extension that writes down when it starts and stops, and what ran then."""

    def __init__(self, name: str, log: list[str], *, fails: bool = False) -> None:
        self.name, self.log, self.fails = name, log, fails
        self.robot: Robot | None = None

    async def start(self, robot: Robot) -> None:
        self.log.append(f"start {self.name}")
        if self.fails:
            raise OSError(f"no {self.name} on /dev/ttyUSB0")
        self.robot = robot

    async def stop(self) -> None:
        assert self.robot is not None
        running = [info.name for info in self.robot.running()]
        self.log.append(f"stop {self.name} (running: {running})")


@action
async def wait_for_ever(robot: Robot, log: list[str]) -> None:
    try:
        await asyncio.sleep(3600)
    finally:
        log.append("action ends")


@pytest.mark.asyncio
async def test_parts_start_in_order_and_stop_in_reverse_once_every_action_ended() -> None:
    log: list[str] = []
    robot = Robot(backend=Part("base", log))
    robot.add_extension("first", Part("first", log))
    robot.add_extension("second", Part("second", log))
    async with robot:
        wait_for_ever(robot, log)
        await asyncio.sleep(0)
        log.append("body ends")
    assert log == [
        "start first",
        "start second",
        "start base",
        "body ends",
        "action ends",
        "stop base (running: [])",
        "stop second (running: [])",
        "stop first (running: [])",
    ]
    assert not robot.is_running


@pytest.mark.asyncio
async def test_a_part_that_fails_to_start_stops_those_started_before_it() -> None:
    log: list[str] = []
    robot = Robot(backend=Part("base", log, fails=True))
    robot.add_extension("node", Part("node", log))
    with pytest.raises(OSError, match="no base on /dev/ttyUSB0"):
        async with robot:
            pytest.fail("the body never runs")
    assert log == ["start node", "start base", "stop node (running: [])"]
    assert not robot.is_running
    async with Robot() as again:  # nothing was left bound to the loop
        assert again.is_running


@pytest.mark.asyncio
async def test_an_extension_is_reached_as_an_attribute_the_robot_owns() -> None:
    log: list[str] = []
    robot = Robot()
    lamp = Part("lamp", log)
    robot.add_extension("lamp", lamp)
    assert robot.lamp is lamp
    assert dict(robot.extensions) == {"lamp": lamp}
    assert "lamp" not in vars(robot)  # the robot's own table, not an attribute set from outside
    with pytest.raises(TypeError):
        robot.extensions["other"] = lamp  # type: ignore[index]


@pytest.mark.asyncio
async def test_extension_names_must_be_free_and_the_robot_stopped() -> None:
    @action
    async def lamp(robot: Robot) -> None:
        pass

    robot = Robot(actions=[lamp])
    robot.add_extension("node", Part("node", []))
    for name in ("state", "node", "lamp"):
        with pytest.raises(PyRobotsError) as caught:
            robot.add_extension(name, Part(name, []))
        assert str(caught.value) == (
            f"cannot add the extension {name!r}: Robot already has that name"
        )
    with pytest.raises(PyRobotsError) as caught:
        robot.add_extension("ros 2", Part("ros 2", []))
    assert str(caught.value) == (
        "an extension's name must be an identifier (robot.<name>), got 'ros 2'"
    )
    async with robot:
        with pytest.raises(PyRobotsError) as caught:
            robot.add_extension("late", Part("late", []))
        assert str(caught.value) == (
            "add extensions before 'async with robot:', not while <Robot running> runs"
        )


def test_the_backend_cannot_be_swapped_from_outside() -> None:
    robot = Robot(backend=Part("base", []))
    with pytest.raises(AttributeError):
        robot.backend = Part("other", [])  # type: ignore[misc]
