"""robot.watch(key): every change, in order, bounded, ending cleanly when the robot stops."""

from __future__ import annotations

import asyncio
import logging
import math

import numpy as np
import pytest

from log_support import logged
from pyrobots_aio import Robot, RobotNotRunningError, UnknownStateKeyError

pytestmark = pytest.mark.virtual_time


@pytest.mark.asyncio
async def test_watch_yields_each_change_in_order_and_ends_when_the_robot_stops() -> None:
    seen: list[object] = []
    robot = Robot()
    async with robot:
        robot.state.docked = True

        async def consume() -> None:
            seen.extend([value async for value in robot.watch("docked")])

        consumer = asyncio.create_task(consume())
        await asyncio.sleep(0)
        for value in (True, False, False, True, None):
            robot.state.docked = value
            await robot.sleep(0.02)
    await asyncio.wait_for(consumer, 1)  # ended by the robot's exit, no error
    assert seen == [False, True, None]


@pytest.mark.asyncio
async def test_changes_are_kept_from_the_call_on_even_before_iterating() -> None:
    async with Robot() as robot:
        robot.state.v = 0.0
        changes = robot.watch("v")
        robot.state.v = 0.1
        robot.state.update(v=0.2, w=1.0)
        robot.state.w = 2.0  # another key: not seen
        got = [await anext(changes), await anext(changes)]
        await changes.aclose()
        robot.state.v = 0.3
    assert got == [0.1, 0.2]
    assert robot.events._feeds == {}  # closing the iterator unsubscribed it


@pytest.mark.asyncio
async def test_a_slow_consumer_loses_the_oldest_values_with_one_warning(
    caplog: pytest.LogCaptureFixture,
) -> None:
    async with Robot() as robot:
        robot.state.ir = 0.0
        changes = robot.watch("ir", buffer=3)
        for n in range(1, 11):
            robot.state.ir = n / 10
        got = [await anext(changes) for _ in range(3)]
        await changes.aclose()
    assert got == [0.8, 0.9, 1.0]
    assert [r.getMessage() for r in logged(caplog, logging.WARNING)] == [
        "watch('ir') fell 3 values behind; dropping the oldest (raise buffer= or consume faster)"
    ]


@pytest.mark.asyncio
async def test_nan_and_arrays_count_as_expected() -> None:
    async with Robot() as robot:
        robot.state.reading = math.nan
        robot.state.scan = np.zeros(2)
        readings, scans = robot.watch("reading"), robot.watch("scan")
        robot.state.reading = math.nan  # NaN again: no change
        robot.state.reading = 1.0
        robot.state.scan = np.zeros(2)  # arrays: each write is a change
        assert await anext(readings) == 1.0
        assert (await anext(scans) == np.zeros(2)).all()
        await readings.aclose()
        await scans.aclose()


@pytest.mark.asyncio
async def test_watch_refuses_bad_input() -> None:
    async with Robot() as robot:
        robot.state.bumper = False
        with pytest.raises(UnknownStateKeyError, match=r"unknown state key 'bumpr'; closest"):
            robot.watch("bumpr")
        with pytest.raises(ValueError, match=r"buffer must be a positive number of values, got 0"):
            robot.watch("bumper", buffer=0)
    with pytest.raises(RobotNotRunningError, match="is not running"):
        robot.watch("bumper")
