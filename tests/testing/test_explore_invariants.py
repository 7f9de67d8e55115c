"""The shipped invariants: each holds on a sound run and names what broke on a faulty one."""

from __future__ import annotations

import asyncio
from typing import TYPE_CHECKING

import pytest

from pyrobots_aio import (
    ActionSpawned,
    InvariantViolation,
    ResourceAcquired,
    ResourceReleased,
    action,
)
from pyrobots_aio.resources import _rules
from pyrobots_aio.testing import FakeBase
from pyrobots_aio.testing.explore import (
    At,
    Bump,
    EmergencyStop,
    Hit,
    Preempt,
    Scenario,
    completes,
    ends_docked,
    no_action_outlives_robot,
    no_forward_into_bumper,
    no_resource_held_twice,
    still_while_stopped,
)

if TYPE_CHECKING:
    from pathlib import Path


def _violations(behaviour: object, invariant: object, *hits: Hit) -> list[str]:
    scenario = Scenario(behaviour, base=FakeBase, invariants=[invariant])  # type: ignore[arg-type]
    return scenario.run(hits).violations


async def _drive_on(robot: FakeBase) -> None:
    robot.drive(0.1, 0.0)  # whatever is pressed or latched
    await robot.sleep(1.0)


def test_driving_on_into_a_held_bump_breaks_no_forward_into_bumper() -> None:
    assert _violations(_drive_on, no_forward_into_bumper(), Hit(Bump(), At(0.5))) == []
    assert _violations(_drive_on, no_forward_into_bumper(), Hit(Bump(hold=1.0), At(0.5))) == [
        "at t=0.720 the base was commanded forward (v=0.100 m/s) with the front bumper pressed "
        "since t=0.500 (more than 0.2 s)"
    ]


def test_wheels_driven_under_the_emergency_stop_break_still_while_stopped() -> None:
    async def rogue(robot: FakeBase) -> None:
        await robot.sleep(1.0)
        robot.backend.set_velocity(0.1, 0.0)  # type: ignore[union-attr] (past the executive)
        await robot.sleep(1.0)

    stop = Hit(EmergencyStop(clear_after=None), At(0.5))
    assert _violations(_drive_on, still_while_stopped(), stop) == []
    assert _violations(rogue, still_while_stopped(), stop) == [
        "at t=1.020 the wheels were commanded (v=0.100, w=0.000) under the emergency stop "
        "latched since t=0.500"
    ]


@action
async def deaf(robot: FakeBase) -> None:
    while True:
        try:
            await asyncio.sleep(1.0)
        except asyncio.CancelledError:
            continue


def test_an_action_that_ignores_cancellation_breaks_no_action_outlives_robot() -> None:
    async def leaves_one_behind(robot: FakeBase) -> None:
        deaf(robot)

    (why,) = _violations(leaves_one_behind, no_action_outlives_robot())
    assert why.startswith("actions ignored their cancellation and were abandoned: ['deaf #")


def test_two_holders_of_one_resource_break_no_resource_held_twice() -> None:
    seen: list[str] = []

    async def behaviour(robot: FakeBase) -> None:
        (holders,) = [i for i in robot.instruments if type(i).__name__ == "_Holders"]
        for event in (
            ActionSpawned(0.0, 1, "a", parent=None),
            ActionSpawned(0.0, 2, "b", parent=1),
            ActionSpawned(0.0, 3, "c", parent=None),
            ResourceAcquired(0.0, 1, "a", ("wheels",), ("wheels",), 0),
            ResourceAcquired(0.1, 2, "b", ("wheels",), ("wheels",), 0),  # a child: allowed
            ResourceReleased(0.2, 2, "b", ("wheels",), ("wheels",), 0),
            ResourceAcquired(0.3, 3, "c", ("wheels",), ("wheels",), 0),
        ):
            holders.on_event(event)

    invariant = no_resource_held_twice()
    seen = _violations(behaviour, invariant)
    assert seen == ["at t=0.300 c #3 acquired 'wheels' held by action #1"]


def test_a_real_double_hold_is_found_and_shrunk_to_the_reflex_that_took_the_wheels(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    async def drive(robot: FakeBase) -> None:
        await robot.drive_distance(0.5)

    scenario = Scenario(
        drive,
        base=FakeBase,
        disturbances=[Preempt],  # a reflex that takes the wheels (preempt=True)
        invariants=[no_resource_held_twice()],
        horizon=2.0,
    )
    scenario.explore(examples=20)  # the lock manager preempts the drive: held once, always
    # a planted bug: the lock manager no longer sees a holder in a request's way
    monkeypatch.setattr(_rules, "holder_in_way", lambda grant, leaf: None)
    with pytest.raises(InvariantViolation) as found:
        scenario.explore(examples=20, record_dir=tmp_path)
    assert found.value.schedule == (Hit(Preempt(0.1), At(0.0)),)
    assert found.value.violations == (
        "at t=0.000 preempting_reflex #2 acquired 'wheels' held by action #1",
    )


def test_completes_and_ends_docked() -> None:
    async def fails(robot: FakeBase) -> None:
        await robot.undock()
        raise RuntimeError("lost")

    assert _violations(fails, completes()) == ["the behaviour raised RuntimeError('lost')"]
    assert _violations(fails, ends_docked()) == ["the robot did not end on its dock"]
