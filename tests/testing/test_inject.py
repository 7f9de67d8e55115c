"""inject_state / inject_bump: state written at the Nth start or end of a named action."""

from __future__ import annotations

from typing import Any

import pytest

from pyrobots_aio import Robot, action
from pyrobots_aio.testing import inject_bump, inject_state

pytestmark = [pytest.mark.asyncio, pytest.mark.virtual_time]


@action
async def step(robot: Robot, seconds: float) -> None:
    await robot.sleep(seconds)


def _writes(robot: Robot, key: str) -> list[tuple[float, Any]]:
    seen: list[tuple[float, Any]] = []
    robot.state.subscribe(lambda changes: seen.append((robot.time(), changes[key])), [key])
    return seen


async def test_it_writes_at_the_start_of_the_nth_action_of_that_name() -> None:
    async with Robot() as robot:
        robot.state.flag = 0
        seen = _writes(robot, "flag")
        with inject_state(robot, "step", {"flag": 1}, nth=2) as injection:
            assert not injection.done
            await step(robot, 1.0)
            second = step(robot, 2.0)
            await second
        assert seen == [(1.0, 1)]  # as the second one started, and once only
        assert (injection.time, injection.action_id) == (1.0, second.id)
        assert not list(robot.instruments)  # it let go of the robot


async def test_it_writes_at_the_end_and_releases_after_hold() -> None:
    async with Robot() as robot:
        robot.state.flag = 0
        seen = _writes(robot, "flag")
        with inject_state(robot, "step", {"flag": 1}, at="end", release={"flag": 0}, hold=0.5):
            await step(robot, 1.0)
            await robot.sleep(2.0)
        assert seen == [(1.0, 1), (1.5, 0)]


async def test_a_bump_presses_the_sides_asked_for() -> None:
    async with Robot() as robot:
        robot.state.update(bumper=False, bumper_left=False, bumper_right=False)
        fired: list[tuple[bool, bool]] = []
        robot.whenever("bumper", becomes=True).do(
            lambda: fired.append((robot.state.bumper_left, robot.state.bumper_right))
        )
        with inject_bump(robot, "step", side="left", hold=0.1) as bump:
            await step(robot, 1.0)
        assert bump.done
        assert fired == [(True, False)]
        assert robot.state.bumper is False  # released after 0.1 s, inside the step


async def test_removed_or_never_reached_it_writes_nothing() -> None:
    async with Robot() as robot:
        robot.state.flag = 0
        seen = _writes(robot, "flag")
        removed = inject_state(robot, "step", {"flag": 1})
        removed.remove()
        await step(robot, 1.0)
        with inject_state(robot, "step", {"flag": 2}, nth=2) as never:
            await step(robot, 1.0)
    assert seen == []
    assert (removed.done, never.done, never.time, never.action_id) == (False, False, None, None)
    assert repr(never) == "<Injection {'flag': 2} at the start of step #2: pending>"
    assert not list(robot.instruments)


async def test_bad_arguments_are_refused() -> None:
    robot = Robot()
    with pytest.raises(ValueError, match="nth") as caught:
        inject_state(robot, "step", {"flag": 1}, nth=0)
    assert str(caught.value) == "nth must be a whole number from 1 (the first 'step'), got 0"
    with pytest.raises(ValueError, match="at") as caught:
        inject_state(robot, "step", {"flag": 1}, at="middle")  # type: ignore[arg-type]
    assert str(caught.value) == "at must be 'start' or 'end', got 'middle'"
    with pytest.raises(ValueError, match="hold") as caught:
        inject_state(robot, "step", {"flag": 1}, hold=1.0)
    assert str(caught.value) == (
        "give both release= and hold= (seconds, >= 0), or neither; got hold=1.0"
    )
    with pytest.raises(ValueError, match="side") as caught:
        inject_bump(robot, "step", side="top")  # type: ignore[arg-type]
    assert str(caught.value) == "side must be 'left', 'right' or 'both', got 'top'"
    assert not list(robot.instruments)
