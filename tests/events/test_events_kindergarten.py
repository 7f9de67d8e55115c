"""The kindergarten behaviour of the pyRobots paper: background actions and five monitors.

A dummy robot blinks and looks at the child in the background while five
monitors react to a scripted morning: pacifier taken and given back, toy
squeezed, bumper pressed, child close, battery low.
"""

from __future__ import annotations

import asyncio

import pytest

from pyrobots_aio import EventKind, Robot, action
from pyrobots_aio.testing import EventLog

pytestmark = pytest.mark.virtual_time


class Kindergarten(Robot):
    """A dummy companion robot: what it says and does goes to ``said``."""

    def __init__(self, log: EventLog) -> None:
        super().__init__(dummy=True, instruments=[log])
        self.said: list[tuple[float, str]] = []
        self.blinks = 0
        self.looks = 0

    def say_now(self, text: str) -> None:
        self.said.append((self.time(), text))

    @action
    async def blink(self) -> None:
        while True:
            await self.sleep(3.0)
            self.blinks += 1

    @action
    async def look_at_child(self) -> None:
        while True:
            await self.sleep(0.5)
            self.looks += 1

    @action
    async def say(self, text: str, seconds: float = 0.5) -> None:
        self.say_now(text)
        await self.sleep(seconds)

    @action
    async def go_to_dock(self) -> None:
        self.say_now("going to dock")
        await self.sleep(2.0)
        self.state.docked = True


async def _morning(robot: Kindergarten) -> None:
    """The scripted state changes (a backend would write these)."""
    script: list[tuple[float, dict[str, object]]] = [
        (1.0, {"pacifier": False}),
        (2.0, {"scale": 0.3}),
        (2.5, {"scale": 0.7}),
        (3.0, {"scale": 1.0}),
        (3.5, {"scale": 1.3}),
        (4.0, {"pacifier": True}),
        (5.0, {"bumper": True}),
        (5.1, {"bumper": False}),
        (6.0, {"ir": 0.2}),
        (7.0, {"ir": 0.25}),
        (9.5, {"ir": 1.0}),
        (10.0, {"battery": 0.15}),
        (11.0, {"battery": 0.1}),
    ]
    start = robot.time()
    for at, values in script:
        await robot.sleep(start + at - robot.time())
        robot.state.update(values)


@pytest.mark.asyncio
async def test_kindergarten() -> None:
    log = EventLog()
    robot = Kindergarten(log)
    async with robot:
        robot.state.update(
            pacifier=True, scale=0.0, bumper=False, ir=1.0, battery=0.9, docked=False
        )
        t0 = robot.time()
        blinking, looking = robot.blink(), robot.look_at_child()

        robot.whenever("pacifier", becomes=False).do(robot.say, "waaah", 1.0)
        robot.whenever("pacifier", becomes=True).do(robot.say, "thank you")
        robot.whenever("scale", increase=0.5).do(robot.say, "hihi", 0.2)
        robot.whenever("bumper", becomes=True).do(robot.say, "ouch")
        robot.whenever("ir", below=0.3, max_firing_freq=0.5).do(robot.say, "hello!")
        robot.on("battery", below=0.2).do(robot.go_to_dock)

        await _morning(robot)
        await robot.sleep(2.75)  # until 13.75 s: no tie with a blink or a look
        assert not blinking.done()
        assert not looking.done()
        assert robot.state.docked is True
        assert robot.blinks == 4
        assert robot.looks == 27
    assert blinking.cancelled()
    assert looking.cancelled()
    assert robot.handles() == []
    assert robot.events.monitors() == []

    said = [(round(t - t0, 6), text) for t, text in robot.said]
    assert said == [
        (1.0, "waaah"),
        (2.5, "hihi"),
        (3.5, "hihi"),
        (4.0, "thank you"),
        (5.0, "ouch"),
        (6.0, "hello!"),
        (8.0, "hello!"),
        (10.0, "going to dock"),
    ]
    fired = {}
    for event in log.of_kind(EventKind.MONITOR_FIRED):
        fired.setdefault(event.name, []).append(round(event.time - t0, 6))
    assert fired == {
        "pacifier becomes=False": [1.0],
        "scale increase=0.5": [2.5, 3.5],
        "pacifier becomes=True": [4.0],
        "bumper becomes=True": [5.0],
        "ir below=0.3": [6.0, 8.0],
        "battery below=0.2": [10.0],
    }
    spawned = log.of_kind(EventKind.ACTION_SPAWNED)
    assert {e.data["parent"] for e in spawned} == {None}  # reactions run in the root scope
    assert log.outcomes("say") == ["succeeded"] * 7
    assert log.outcomes("go_to_dock") == ["succeeded"]


@pytest.mark.asyncio
async def test_kindergarten_runs_the_same_twice() -> None:
    """Two robots in a row (or at once) share nothing: the same script, the same result."""

    async def once() -> list[str]:
        log = EventLog()
        robot = Kindergarten(log)
        async with robot:
            robot.state.update(pacifier=True, bumper=False)
            robot.whenever("pacifier", becomes=False).do(robot.say, "waaah")
            robot.whenever("bumper", becomes=True).do(robot.say, "ouch")
            robot.state.pacifier = False
            robot.state.bumper = True
            await robot.sleep(1.0)
        return [text for _, text in robot.said]

    first, second = await asyncio.gather(once(), once())
    assert first == second == ["waaah", "ouch"]
