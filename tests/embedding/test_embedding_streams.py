"""Streaming endpoints over ``robot.watch``: what a handler that returns early leaves behind."""

from __future__ import annotations

import gc
import logging

import pytest

from log_support import logged
from pyrobots_aio import Robot


@pytest.mark.asyncio
async def test_a_stream_dropped_before_its_first_value_leaves_no_subscriber(
    caplog: pytest.LogCaptureFixture,
) -> None:
    async with Robot() as robot:
        robot.state.battery = 1.0
        changes = robot.watch("battery", buffer=4)  # a handler that then refuses the request
        del changes
        gc.collect()
        for level in range(10):
            robot.state.battery = level / 10
    warnings = [r.getMessage() for r in logged(caplog, logging.WARNING)]
    assert warnings == []


@pytest.mark.asyncio
async def test_a_stream_left_after_its_first_value_unsubscribes(
    caplog: pytest.LogCaptureFixture,
) -> None:
    async with Robot() as robot:
        robot.state.battery = 1.0
        changes = robot.watch("battery", buffer=4)
        robot.state.battery = 0.9
        assert await anext(changes) == 0.9
        await changes.aclose()  # what a framework does when the client leaves
        for level in range(10):
            robot.state.battery = level / 10
    warnings = [r.getMessage() for r in logged(caplog, logging.WARNING)]
    assert warnings == []
