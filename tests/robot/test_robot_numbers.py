"""A robot's numbers: sleep, cancel_grace, block_threshold, timeouts and filters refuse
NaN and ints too large for a float with a ValueError naming them."""

from __future__ import annotations

import math

import pytest

from pyrobots_aio import Robot, action
from pyrobots_aio.supervision import timeout

HUGE = 10**400
TOO_LARGE = r"an int of about 10\*\*400 \(too large for a float\)"


@pytest.mark.parametrize(
    ("option", "message"),
    [
        ("cancel_grace", "cancel_grace must be a positive number of seconds"),
        ("block_threshold", "block_threshold must be a number of seconds from 0.01 up"),
    ],
)
def test_robot_options_too_large_for_a_float_are_value_errors(option: str, message: str) -> None:
    with pytest.raises(ValueError, match=rf"^{message}.*, got {TOO_LARGE}$"):
        Robot(**{option: HUGE})


def test_a_timeout_too_large_for_a_float_is_a_value_error() -> None:
    with pytest.raises(
        ValueError, match=rf"^timeout must be a positive number of seconds, got {TOO_LARGE}$"
    ):
        timeout(HUGE)


@pytest.mark.asyncio
@pytest.mark.virtual_time
@pytest.mark.parametrize("seconds", [math.nan, HUGE], ids=["nan", "10**400"])
async def test_sleeping_a_nan_or_a_huge_int_is_a_value_error_in_and_out_of_actions(
    seconds: float,
) -> None:
    @action
    async def nap(robot: Robot) -> None:
        await robot.sleep(seconds)

    async with Robot() as robot:
        with pytest.raises(
            ValueError, match=r"^seconds must be a number of seconds \(or math.inf\)"
        ):
            await robot.sleep(seconds)
        with pytest.raises(ValueError, match=r"^seconds must be a number of seconds"):
            await nap(robot)
        start = robot.time()
        await robot.sleep(1.5)  # the clock and its timers are untouched
        assert robot.time() == start + 1.5
        await robot.sleep(-1)  # as asyncio.sleep: at once
        assert robot.time() == start + 1.5


def test_a_filtered_value_must_be_finite_and_a_window_bounded() -> None:
    robot = Robot()
    assert robot.filtered("ir", 1.0, 3) == 1.0
    for value in (math.nan, math.inf, HUGE):
        with pytest.raises(ValueError, match=r"^a filtered value must be a finite number, got "):
            robot.filtered("ir", value, 3)
    assert robot.filtered("ir", 3.0, 3) == 2.0  # the window was not spoiled
    with pytest.raises(
        ValueError,
        match=r"^window must be at most 1,000,000 values, got an int of about 10\*\*400$",
    ):
        robot.filtered("ir", 1.0, HUGE)
    assert robot.filtered("ir", 5.0, 3) == 3.0
