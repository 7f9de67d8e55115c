"""Static checks of `@action` typing, run by ``mypy --strict tests/typing`` (never by pytest).

`assert_type` pins what calling an action gives (its real parameters through
ParamSpec, ``ActionHandle[T]`` for its result). Each line that must be a type
error carries a precise ``# type: ignore[code]``: with ``--strict`` an ignore
that is not needed is itself an error, so this file passing proves the errors
happen.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, assert_type

from pyrobots_aio import ActionHandle, EventMonitor, Outcome, Resource, Robot, action, lock


@action
async def double(robot: Robot, x: int, *, scale: float = 1.0) -> int:
    await robot.sleep(0.1 * scale)
    return 2 * x


@action
async def walk(robot: Robot, speed: float) -> None:
    await robot.sleep(speed)


class Pr2(Robot):
    @action
    async def wave(self, times: int, hand: str = "right") -> str:
        await self.sleep(0.1)
        return f"{hand} hand waved {times} times"


async def calling_an_action_gives_a_typed_handle(robot: Robot) -> None:
    handle = double(robot, 21)
    assert_type(handle, ActionHandle[int])
    assert_type(double(robot, 21, scale=0.5), ActionHandle[int])
    assert_type(walk(robot, 0.2), ActionHandle[None])
    assert_type(await handle, int)
    assert_type(await handle.wait(), int)
    assert_type(await handle.wait_done(), Outcome)
    assert_type(handle.result(), int)
    assert_type(handle.cancel("bored"), bool)


async def bound_actions_keep_their_parameters(robot: Pr2) -> None:
    assert_type(robot.wave(3), ActionHandle[str])
    assert_type(robot.wave(3, hand="left"), ActionHandle[str])
    assert_type(await robot.wave(times=2), str)
    assert_type(Pr2.wave(robot, 3), ActionHandle[str])


def wrong_calls_are_type_errors(robot: Robot, pr2: Pr2) -> None:
    double(robot, "21")  # type: ignore[arg-type]
    double(robot, 21, speed=2.0)  # type: ignore[call-arg]
    double(robot, 21, 0.5)  # type: ignore[call-arg]  # scale is keyword-only
    double(x=21)  # type: ignore[call-arg]
    double(21)  # type: ignore[arg-type, call-arg]
    walk(robot)  # type: ignore[call-arg]
    pr2.wave("three")  # type: ignore[arg-type]
    pr2.wave(3, hands="left")  # type: ignore[call-arg]
    pr2.wave()  # type: ignore[call-arg]
    Pr2.wave(robot, 3)  # type: ignore[arg-type]
    handle: ActionHandle[str] = double(robot, 21)  # type: ignore[assignment]
    del handle


WHEELS = Resource("wheels")


@action
@lock(WHEELS, priority=10, preempt="suspend")
async def reflex(robot: Robot) -> str:
    return "backed off"


async def locks_take_suspend_and_aging(robot: Robot) -> None:
    assert_type(reflex(robot), ActionHandle[str])
    lock(WHEELS, preempt="cancel")  # type: ignore[arg-type]
    assert_type(robot.resources.aging, float | None)
    robot.resources.aging = 2.0
    assert_type(robot.resources.lenders(WHEELS), list[ActionHandle[Any]])


def pyrobots_habits(robot: Robot) -> None:
    """``.do()`` chains on the monitor itself; ``Resource()`` needs no name."""
    monitor = robot.whenever("bumper", becomes=True).do(print, "ouch").do(walk, 0.2)
    assert_type(monitor, EventMonitor)
    assert_type(monitor.callbacks, tuple[Callable[..., object], ...])
    assert_type(Resource().generated, bool)
