"""Misuse is refused at creation, with messages that name the value and the fix."""

from __future__ import annotations

from typing import Any

import pytest

from pyrobots_aio import (
    InvalidConditionError,
    Robot,
    RobotNotRunningError,
    StateError,
    UnknownStateKeyError,
)

pytestmark = pytest.mark.virtual_time

SENSORS = {"bumper": False, "bumper_left": False, "bumper_right": False, "ir_left": 1.0}


def _refused(robot: Robot, *args: Any, **kwargs: Any) -> str:
    with pytest.raises(InvalidConditionError) as error:
        robot.whenever(*args, **kwargs)
    return str(error.value)


@pytest.mark.asyncio
async def test_a_key_not_in_the_state_lists_the_closest_keys() -> None:
    async with Robot() as robot:
        robot.state.update(SENSORS)
        with pytest.raises(UnknownStateKeyError) as error:
            robot.whenever("bumpr", becomes=True)
        assert str(error.value) == (
            "unknown state key 'bumpr'; closest: ['bumper', 'bumper_left']; "
            "known keys: ['bumper', 'bumper_left', 'bumper_right', 'ir_left']"
        )
        with pytest.raises(UnknownStateKeyError):
            await robot.wait("ir_front", below=0.2)
        assert robot.events.monitors() == []


@pytest.mark.asyncio
async def test_no_condition() -> None:
    async with Robot() as robot:
        robot.state.update(SENSORS)
        expected = (
            "monitor on 'bumper' has no condition; give one of value=, becomes=, above=, "
            "below=, increase=, decrease= (held_for= may be added to it)"
        )
        assert _refused(robot, "bumper") == expected
        assert _refused(robot, "bumper", held_for=1.0) == expected


@pytest.mark.asyncio
async def test_two_conditions() -> None:
    async with Robot() as robot:
        robot.state.update(SENSORS)
        assert _refused(robot, "ir_left", above=0.5, below=0.2) == (
            "monitor on 'ir_left' has 2 conditions (above=0.5, below=0.2); give only one "
            "(held_for= is the one that combines), or watch a predicate for a compound condition"
        )


@pytest.mark.asyncio
async def test_conditions_of_the_wrong_type() -> None:
    async with Robot() as robot:
        robot.state.update(SENSORS)
        assert _refused(robot, "ir_left", above="x") == (
            "above= must be a finite number, got 'x'; write e.g. above=0.3"
        )
        assert _refused(robot, "ir_left", below=True) == (
            "below= must be a finite number, got True (a bool is not a number); "
            "write e.g. below=0.3"
        )
        assert _refused(robot, "ir_left", below=float("nan")) == (
            "below= must be a finite number, got nan; write e.g. below=0.3"
        )
        assert _refused(robot, "ir_left", increase=0) == (
            "increase= must be a positive number, got 0; write e.g. increase=0.5"
        )
        assert _refused(robot, "ir_left", decrease=-0.5) == (
            "decrease= must be a positive number, got -0.5; write e.g. decrease=0.5"
        )
        assert _refused(robot, "bumper", becomes=True, held_for=-1) == (
            "held_for= must be a number of seconds >= 0, got -1; write e.g. held_for=2.0"
        )
        assert _refused(robot, "bumper", becomes=True, held_for="2s") == (
            "held_for= must be a number of seconds >= 0, got '2s'; write e.g. held_for=2.0"
        )


@pytest.mark.asyncio
@pytest.mark.parametrize("kind", ["value", "becomes"])
async def test_a_nan_target_that_can_never_be_equalled(kind: str) -> None:
    async with Robot() as robot:
        robot.state.ir_left = float("nan")
        assert _refused(robot, "ir_left", **{kind: float("nan")}) == (
            f"{kind}=nan can never fire: NaN equals nothing, not even NaN; to react to a NaN "
            "reading, watch a predicate: "
            "robot.whenever(lambda robot: math.isnan(robot.state['ir_left']))"
        )
        assert robot.events.monitors() == []


@pytest.mark.asyncio
async def test_a_numeric_condition_on_a_key_that_holds_no_number() -> None:
    async with Robot() as robot:
        robot.state.mode = "idle"
        assert _refused(robot, "mode", above=0.5) == (
            "above= compares numbers, but state key 'mode' holds 'idle' (str); "
            "use value= or becomes=, or a predicate"
        )


@pytest.mark.asyncio
async def test_a_numeric_condition_on_a_flag() -> None:
    async with Robot() as robot:
        robot.state.update(SENSORS, docked=True)
        assert _refused(robot, "bumper", above=0.5) == (
            "above= compares numbers, but state key 'bumper' holds False (bool); "
            "watch a flag with value= or becomes=, e.g. becomes=True"
        )
        assert _refused(robot, "docked", decrease=0.5, held_for=1.0) == (
            "decrease= compares numbers, but state key 'docked' holds True (bool); "
            "watch a flag with value= or becomes=, e.g. becomes=False"
        )
        with pytest.raises(InvalidConditionError) as error:
            robot.on("bumper_left", increase=1)
        assert str(error.value).startswith("increase= compares numbers, but state key")
        with pytest.raises(InvalidConditionError) as error:
            await robot.wait("bumper_right", below=0.5)
        assert str(error.value).startswith("below= compares numbers, but state key")
        assert robot.events.monitors() == []
        robot.whenever("ir_left", above=0.5)  # numbers are still welcome


@pytest.mark.asyncio
async def test_an_unknown_condition_suggests_the_closest() -> None:
    async with Robot() as robot:
        robot.state.update(SENSORS)
        assert _refused(robot, "bumper", valeu=True) == (
            "unknown condition 'valeu' (did you mean value=?); conditions are value=, "
            "becomes=, above=, below=, increase=, decrease= and held_for="
        )
        assert _refused(robot, "bumper", when=True) == (
            "unknown condition 'when'; conditions are value=, becomes=, above=, below=, "
            "increase=, decrease= and held_for="
        )


@pytest.mark.asyncio
async def test_a_key_condition_on_a_predicate() -> None:
    async with Robot() as robot:
        robot.state.update(SENSORS)
        assert _refused(robot, lambda r: r.state.bumper, value=True) == (
            "value= does not apply to a predicate: the predicate is the condition "
            "(return True while it holds); only held_for= may be added"
        )
        with pytest.raises(InvalidConditionError) as error:
            robot.on(lambda r: r.state.bumper, becomes=True)
        assert str(error.value).startswith("becomes= does not apply to a predicate")


@pytest.mark.asyncio
async def test_bad_frequency_poll_blocking_and_target() -> None:
    async with Robot() as robot:
        robot.state.update(SENSORS)
        assert _refused(robot, "bumper", -1, becomes=True) == (
            "max_firing_freq must be a number of firings per second >= 0 (0: unlimited), got -1"
        )
        assert _refused(robot, "bumper", max_firing_freq="fast", value=True) == (
            "max_firing_freq must be a number of firings per second >= 0 (0: unlimited), got 'fast'"
        )
        assert _refused(robot, "bumper", poll=0.5, value=True) == (
            "poll= applies to predicates; the key 'bumper' is checked on every write: drop poll="
        )
        assert _refused(robot, lambda r: r.state.bumper, poll=0) == (
            "poll= must be a number of seconds > 0 or None, got 0"
        )
        assert _refused(robot, "bumper", blocking="yes", value=True) == (
            "blocking must be True or False, got 'yes'"
        )
        assert _refused(robot, 42, value=True) == (
            "a monitor watches a state key (str) or a predicate f(robot) -> bool, got 42 (int)"
        )
        assert robot.events.monitors() == []


@pytest.mark.asyncio
async def test_monitors_need_a_running_robot() -> None:
    robot = Robot()
    robot.state.update(SENSORS)
    with pytest.raises(RobotNotRunningError) as error:
        robot.whenever("bumper", becomes=True)
    assert str(error.value) == (
        "cannot monitor 'bumper': <Robot stopped> is not running; "
        "create monitors inside 'async with robot:'"
    )
    with pytest.raises(RobotNotRunningError) as on_error:
        robot.on(lambda r: r.state.bumper)
    assert str(on_error.value) == (
        "cannot monitor '<lambda>': <Robot stopped> is not running; "
        "create monitors inside 'async with robot:'"
    )
    with pytest.raises(RobotNotRunningError):
        await robot.wait("bumper", value=True)
    async with robot:
        monitor = robot.whenever("bumper", becomes=True)
    assert not monitor.monitoring
    with pytest.raises(StateError):
        await monitor.wait()
