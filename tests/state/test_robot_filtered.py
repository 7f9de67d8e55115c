"""``robot.filtered``: pyRobots' moving average, kept by the robot's state store."""

from __future__ import annotations

import pytest

from pyrobots_aio import Robot


def test_robot_filtered_averages_the_last_ten_values_by_default() -> None:
    robot = Robot()
    means = [robot.filtered("sonar", float(v)) for v in range(1, 13)]
    assert means[:3] == [1.0, 1.5, 2.0]
    assert means[9] == 5.5  # mean of 1..10
    assert means[11] == 7.5  # mean of 3..12
    assert "sonar" not in robot.state  # a window, not a state key


def test_robot_filtered_uses_the_windows_of_its_state_store() -> None:
    robot = Robot()
    assert robot.filtered("ir", 1.0, window=3) == 1.0
    assert robot.state.filtered("ir", 2.0, window=3) == 1.5
    assert robot.filtered("ir", 6.0, window=3) == 3.0
    assert robot.filtered("ir", 10.0, window=2) == 8.0  # resized: 6 and 10 remain


def test_two_robots_keep_separate_windows() -> None:
    first, second = Robot(), Robot()
    assert first.filtered("v", 1.0) == 1.0
    assert second.filtered("v", 3.0) == 3.0
    assert first.filtered("v", 2.0) == 1.5
    assert second.filtered("v", 5.0) == 4.0


@pytest.mark.asyncio
async def test_robot_filtered_works_while_the_robot_runs() -> None:
    async with Robot() as robot:
        robot.state.ir_left = 0.5
        readings = [robot.filtered("ir_left", v, window=4) for v in (0.5, 0.3, 0.1, 0.1)]
        assert readings == [0.5, 0.4, 0.3, 0.25]
        assert robot.state.ir_left == 0.5  # the key itself is untouched


def test_robot_filtered_rejects_a_bad_window() -> None:
    robot = Robot()
    with pytest.raises(ValueError, match=r"^window must be a positive integer, got -1$"):
        robot.filtered("ir", 1.0, window=-1)
    assert robot.filtered("ir", 4.0) == 4.0  # nothing was added by the refused call
