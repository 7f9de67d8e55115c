"""Numbers a monitor refuses: NaN, infinities, bools and ints too large for a float."""

from __future__ import annotations

import math

import pytest

from pyrobots_aio import InvalidConditionError, Robot

pytestmark = [pytest.mark.asyncio, pytest.mark.virtual_time]

HUGE = 10**400
TOO_LARGE = r"an int of about 10\*\*400 \(too large for a float\)"


async def test_an_int_too_large_for_a_float_is_refused_for_every_number_of_a_monitor() -> None:
    refusals = {
        "max_firing_freq": (
            {"max_firing_freq": HUGE, "value": 1.0},
            rf"^max_firing_freq must be a number of firings per second >= 0 \(0: unlimited\), "
            rf"got {TOO_LARGE}$",
        ),
        "increase": (
            {"increase": HUGE},
            rf"^increase= must be a positive number, got {TOO_LARGE}; write e\.g\. increase=0\.5$",
        ),
        "decrease": (
            {"decrease": HUGE},
            rf"^decrease= must be a positive number, got {TOO_LARGE};",
        ),
        "above": ({"above": HUGE}, rf"^above= must be a finite number, got {TOO_LARGE};"),
        "below": ({"below": -HUGE}, r"^below= must be a finite number, got -an int of about"),
        "held_for": (
            {"above": 0.5, "held_for": HUGE},
            rf"^held_for= must be a number of seconds >= 0, got {TOO_LARGE}; write e\.g\.",
        ),
    }
    async with Robot() as robot:
        robot.state.level = 0.0
        for options, message in refusals.values():
            with pytest.raises(InvalidConditionError, match=message):
                robot.whenever("level", **options)  # type: ignore[arg-type]
        with pytest.raises(
            InvalidConditionError,
            match=rf"^poll= must be a number of seconds > 0 or None, got {TOO_LARGE}$",
        ):
            robot.whenever(lambda robot: True, poll=HUGE)
        assert robot.events.monitors() == []  # nothing half-made


@pytest.mark.parametrize("kind", ["above", "below"])
@pytest.mark.parametrize("value", [math.inf, -math.inf], ids=repr)
async def test_an_infinite_threshold_is_refused(kind: str, value: float) -> None:
    async with Robot() as robot:
        robot.state.level = 0.0
        with pytest.raises(InvalidConditionError, match=rf"^{kind}= must be a finite number, got"):
            robot.whenever("level", **{kind: value})  # type: ignore[arg-type]


async def test_an_infinite_reading_can_still_be_watched_for() -> None:
    """A rangefinder reads inf when nothing echoes: ``becomes=math.inf`` is a real condition."""
    async with Robot() as robot:
        robot.state.range = 1.0
        seen: list[float] = []
        robot.whenever("range", becomes=math.inf).do(lambda: seen.append(robot.state.range))
        robot.state.range = math.inf
        await robot.sleep(0.1)
    assert seen == [math.inf]
