"""Numbers the motion layer refuses or limits, on every base: huge, non-finite, absurd."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import pytest

from pyrobots_aio.motion._math import MAX_DISTANCE, MAX_TURN

if TYPE_CHECKING:
    from .conftest import Base

pytestmark = [pytest.mark.asyncio, pytest.mark.virtual_time]

HUGE = 10**400
TOO_LARGE = r"an int of about 10\*\*400 \(too large for a float\)"


async def test_an_int_too_large_for_a_float_is_a_value_error_naming_it(base: Base) -> None:
    async with base.make() as robot:
        with pytest.raises(ValueError, match=rf"^v must be a finite number, got {TOO_LARGE}$"):
            robot.drive(HUGE, 0.0)
        with pytest.raises(ValueError, match=rf"^w must be a finite number, got -{TOO_LARGE}$"):
            robot.drive(0.0, -HUGE)
        with pytest.raises(
            ValueError, match=rf"^distance must be .*, got {TOO_LARGE}; drive_distance takes metres"
        ):
            await robot.drive_distance(HUGE)
        with pytest.raises(ValueError, match=rf"^speed must be .*, got {TOO_LARGE}$"):
            await robot.drive_distance(0.1, speed=HUGE)
        with pytest.raises(
            ValueError, match=rf"^angle must be .*, got {TOO_LARGE}; rotate_angle turns by radians"
        ):
            await robot.rotate_angle(HUGE)
        with pytest.raises(ValueError, match=TOO_LARGE):
            await robot.navigate_to((HUGE, 0.0, 0.0, "map"))
        await robot.sleep(0.1)
        assert robot.state.docked  # nothing moved
        assert robot.handles() == []


async def test_a_huge_finite_speed_is_limited_to_the_top_speed_and_reported(base: Base) -> None:
    async with base.make() as robot:
        robot.drive(10.0, 0.0)  # beyond the top speed of every base here
        top, _ = robot.world.command
        assert 0.1 < top < 10.0
        robot.drive(1.7e308, 0.0)
        assert robot.world.command == (top, 0.0)  # what the wheels really get
        await robot.sleep(1.0)
        assert robot.state.v == pytest.approx(top, abs=0.01)
        assert all(math.isfinite(value) for value in base.truth(robot))
        robot.drive(-1.7e308, -1.7e308)  # the curvature is kept: a tight reverse turn
        v, w = robot.world.command
        assert all(math.isfinite(speed) for speed in (v, w))
        assert v < 0
        assert v == pytest.approx(w)
        robot.stop()
        assert robot.world.command == (0.0, 0.0)


async def test_a_turn_or_a_distance_beyond_any_robot_run_is_refused(base: Base) -> None:
    async with base.make() as robot:
        with pytest.raises(
            ValueError,
            match=r"^angle must be a finite number from -6283.19 to 6283.19, got 1e\+300; "
            r"rotate_angle turns by radians, at most 1000 turns",
        ):
            await robot.rotate_angle(1e300)
        with pytest.raises(ValueError, match=r"^distance must be a finite number from -100000 to"):
            await robot.drive_distance(-1e300)
        with pytest.raises(
            ValueError, match=r"^navigate_to\(\(1e\+300, 0.0, 0.0, 'map'\)\): the goal"
        ):
            await robot.navigate_to((1e300, 0.0, 0.0, "map"))
        assert robot.state.docked
    assert pytest.approx(2000 * math.pi) == MAX_TURN
    assert MAX_DISTANCE == 100_000.0


async def test_rotate_angle_turns_more_than_once_when_asked(base: Base) -> None:
    async with base.make() as robot:
        await robot.undock()
        _, _, yaw0 = base.truth(robot)
        turned = await robot.rotate_angle(4 * math.pi, speed=2.0)
        assert turned == pytest.approx(4 * math.pi, abs=0.01)
        _, _, yaw1 = base.truth(robot)
        assert math.remainder(yaw1 - yaw0, 2 * math.pi) == pytest.approx(0.0, abs=0.02)
