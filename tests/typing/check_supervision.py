"""Static checks of the supervision decorators' typing, run by ``mypy --strict tests/typing``.

`retry` and `timeout` give back the action they decorate with its real
parameters (ParamSpec) and result type, as `@action` does, in every form:
above ``@action``, on a method of a robot, on a bound action (the call form)
and on a plain ``async def``. Each line that must be a type error carries a
precise ``# type: ignore[code]``; with ``--strict`` an unneeded ignore is an
error itself, so this file passing proves the errors happen.
"""

from __future__ import annotations

from typing import assert_type

from pyrobots_aio import (
    ActionHandle,
    Outcome,
    Robot,
    StateMachine,
    action,
    exponential,
    retry,
    timeout,
)
from pyrobots_aio.supervision import Backoff, HealthLevel, HealthMonitor, HealthStatus, When


@retry(3, backoff=exponential(0.1, factor=2, jitter=0.5, seed=1), on=(ConnectionError,))
@action
async def fetch(robot: Robot, url: str, *, tries: int = 1) -> bytes:
    await robot.sleep(0.1 * tries)
    return url.encode()


@timeout(2)
@action
async def look(robot: Robot, pan: float) -> None:
    await robot.sleep(pan)


async def plain(robot: Robot, x: int) -> int:
    return x


class Pr2(Robot):
    @retry(2)
    @timeout(5)
    @action
    async def wave(self, times: int, hand: str = "right") -> str:
        await self.sleep(0.1)
        return f"{hand} hand waved {times} times"


async def decorated_actions_keep_their_parameters_and_result(robot: Robot, pr2: Pr2) -> None:
    assert_type(fetch(robot, "http://x"), ActionHandle[bytes])
    assert_type(await fetch(robot, "http://x", tries=2), bytes)
    assert_type(look(robot, 0.5), ActionHandle[None])
    assert_type(pr2.wave(3), ActionHandle[str])
    assert_type(await pr2.wave(3, hand="left"), str)


async def the_call_form_keeps_them_too(robot: Robot, pr2: Pr2) -> None:
    assert_type(retry(3)(pr2.wave)(2), ActionHandle[str])
    assert_type(await timeout(1)(look)(robot, 0.1), None)
    assert_type(retry(2)(plain)(robot, 4), ActionHandle[int])


async def machines_and_health(robot: Robot) -> None:
    machine = StateMachine("m", {"look": look, "end": None}, [("look", "end", Outcome.SUCCEEDED)])
    assert_type(machine(robot), ActionHandle[str])
    assert_type(When("bumper", becomes=True), When)
    assert_type(exponential(0.1), Backoff)
    health = HealthMonitor(robot)
    health.watch("battery", stale_after=5.0, check=lambda v: HealthLevel.OK)
    assert_type(health.start(), ActionHandle[None])
    assert_type(health.statuses(), dict[str, HealthStatus])
    assert_type(robot.emergency_stop("cliff"), ActionHandle[None])
    robot.add_emergency_stop_callback(lambda reason: [machine(robot)])


def wrong_calls_are_type_errors(robot: Robot, pr2: Pr2) -> None:
    fetch(robot, 42)  # type: ignore[arg-type]
    fetch(robot, "x", 2)  # type: ignore[call-arg]  # tries is keyword-only
    look(robot)  # type: ignore[call-arg]
    pr2.wave("3")  # type: ignore[arg-type]
    retry(3)(pr2.wave)()  # type: ignore[call-arg]
    retry(2)(plain)(robot, "4")  # type: ignore[arg-type]
    robot.emergency_stop(42)  # type: ignore[arg-type]
    robot.add_emergency_stop_callback(print)  # type: ignore[arg-type]  # it returns no actions
    When("bumper", becomes=True, sideways=1)  # type: ignore[call-arg]
