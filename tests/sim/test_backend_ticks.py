"""Lockstep ticks run back to back while nothing falls between them, and only then."""

from __future__ import annotations

import asyncio
import itertools

import pytest

from pyrobots_aio.motion._ticking import TICKS_PER_TURN
from pyrobots_aio.sim import SimRobot

pytestmark = [pytest.mark.asyncio, pytest.mark.virtual_time]


async def test_a_timer_between_two_ticks_sees_the_first_and_not_the_second() -> None:
    robot = SimRobot()  # 50 Hz: ticks at 0.02, 0.04, ...
    loop = asyncio.get_running_loop()
    seen: list[tuple[float, int, float]] = []

    def look() -> None:
        seen.append((loop.time(), robot.sim.ticks, robot.state.timestamp("v")))

    async with robot:
        start = loop.time()
        for k in range(40):  # one timer between each two ticks, a few ticks apart
            loop.call_at(start + 0.03 + 0.1 * k, look)
        await robot.sleep(5.0)  # the ticks in between run back to back
    assert len(seen) == 40
    for k, (now, ticks, stamp) in enumerate(seen):
        assert now == start + 0.03 + 0.1 * k
        assert ticks == 1 + 5 * k  # the tick at start + 0.02 + 0.1 k, not the one after
        assert stamp == pytest.approx(start + 0.02 + 0.1 * k, abs=1e-9)


async def test_the_loop_still_polls_io_every_few_ticks() -> None:
    robot = SimRobot()
    loop = asyncio.get_running_loop()
    selector = loop._selector  # type: ignore[attr-defined]  # where each turn polls I/O
    polled = selector.select
    turns: list[int] = []

    def select(timeout: float | None = None) -> object:
        turns.append(robot.sim.ticks)
        return polled(timeout)

    async with robot:
        selector.select = select
        try:
            await robot.sleep(2.0)  # 100 ticks with nothing else to do
        finally:
            del selector.select
    steps = [b - a for a, b in itertools.pairwise(turns)]
    assert sum(steps) >= 90
    assert max(steps) == TICKS_PER_TURN  # back to back, up to the bound
    assert all(0 <= step <= TICKS_PER_TURN for step in steps)  # I/O waits that long at most
