"""Losslessness and rate limiting: short pulses, single-write pulses, level re-firing."""

from __future__ import annotations

import pytest

from pyrobots_aio import EventKind, Robot
from pyrobots_aio.testing import EventLog

pytestmark = pytest.mark.virtual_time


def _fired(log: EventLog, name: str) -> list[tuple[float, object, object]]:
    """(time, value, callback status) of each firing of the monitor called ``name``."""
    return [
        (e.time, e.data["value"], e.data["callback"])
        for e in log.of_kind(EventKind.MONITOR_FIRED, name)
    ]


@pytest.mark.asyncio
async def test_thirty_20ms_pulses_fire_thirty_times_on_edge_and_level() -> None:
    async with Robot() as robot:
        robot.state.button = False
        edge: list[float] = []
        level: list[float] = []
        robot.whenever("button", becomes=True).do(lambda: edge.append(robot.time()))
        robot.whenever("button", value=True).do(lambda: level.append(robot.time()))
        t0 = robot.time()
        for _ in range(30):
            robot.state.button = True
            await robot.sleep(0.02)
            robot.state.button = False
            await robot.sleep(0.5)
    starts = [pytest.approx(i * 0.52) for i in range(30)]
    assert [t - t0 for t in edge] == starts
    assert [t - t0 for t in level] == starts


@pytest.mark.asyncio
async def test_thirty_single_write_pulses_fire_thirty_times_on_edge_and_level() -> None:
    async with Robot() as robot:
        robot.state.button = False
        edge: list[float] = []
        level: list[float] = []
        on_edge = robot.whenever("button", becomes=True).do(lambda: edge.append(robot.time()))
        on_level = robot.whenever("button", value=True).do(lambda: level.append(robot.time()))
        for _ in range(30):
            robot.state.button = True  # the pulse lasts one write: False comes in the same step
            robot.state.button = False
            await robot.sleep(0.5)
        assert (on_edge.firings, on_level.firings) == (30, 30)
    assert len(edge) == len(level) == 30


@pytest.mark.asyncio
async def test_two_pulses_in_one_step_fire_twice_and_blocking_drops_the_second_callback() -> None:
    log = EventLog()
    async with Robot(instruments=[log]) as robot:
        robot.state.button = False
        calls = {"blocking": 0, "concurrent": 0}

        def count(which: str) -> None:
            calls[which] += 1

        blocking = robot.whenever("button", becomes=True).do(count, "blocking")
        concurrent = robot.whenever("button", becomes=True, blocking=False).do(count, "concurrent")
        for pressed in (True, False, True, False):
            robot.state.button = pressed
        await robot.sleep(0)
        assert (blocking.firings, concurrent.firings) == (2, 2)
        assert calls == {"blocking": 1, "concurrent": 2}
    statuses = [status for _, _, status in _fired(log, "button becomes=True")]
    assert statuses == ["started", "started", "dropped", "started"]


@pytest.mark.asyncio
async def test_value_held_for_one_second_at_10_hz_fires_11_times() -> None:
    """Fires at the rise, then every 0.1 s; the firing due at exactly 1.0 s runs before the
    write that ends the hold (a timer callback runs before the task it wakes)."""
    log = EventLog()
    async with Robot(instruments=[log]) as robot:
        robot.state.button = False
        monitor = robot.whenever("button", value=True, max_firing_freq=10)
        await robot.sleep(1.0)
        t0 = robot.time()
        robot.state.button = True
        await robot.sleep(1.0)
        robot.state.button = False
        await robot.sleep(1.0)
        assert monitor.firings == 11
    times = [t - t0 for t, _, _ in _fired(log, "button value=True")]
    assert times == [pytest.approx(k * 0.1) for k in range(11)]


@pytest.mark.asyncio
async def test_a_rise_during_the_cool_down_fires_when_it_ends() -> None:
    log = EventLog()
    async with Robot(instruments=[log]) as robot:
        robot.state.level = 0
        robot.whenever("level", value=1, max_firing_freq=4)  # cool-down 0.25 s
        t0 = robot.time()
        robot.state.level = 1
        robot.state.level = 0
        await robot.sleep(0.05)
        robot.state.level = 1  # in the cool-down: remembered
        robot.state.level = 2
        await robot.sleep(0.05)
        robot.state.level = 1  # a second one in the same cool-down: the same firing
        robot.state.level = 0
        await robot.sleep(1.0)
    fired = [(t - t0, value) for t, value, _ in _fired(log, "level value=1")]
    assert fired == [(0.0, 1), (pytest.approx(0.25), 1)]


@pytest.mark.asyncio
async def test_max_firing_freq_zero_fires_on_every_write_that_holds_and_never_by_itself() -> None:
    async with Robot() as robot:
        robot.state.ir = 1.0
        monitor = robot.whenever("ir", below=0.5, max_firing_freq=0)
        for value in (0.4, 0.3, 0.3, 0.9, 0.2):
            robot.state.ir = value
        await robot.sleep(10)
        assert monitor.firings == 4


@pytest.mark.asyncio
async def test_edge_conditions_are_never_rate_limited() -> None:
    async with Robot() as robot:
        robot.state.button = False
        monitor = robot.whenever("button", becomes=True, max_firing_freq=1)
        for _ in range(5):
            robot.state.button = True
            await robot.sleep(0.01)
            robot.state.button = False
            await robot.sleep(0.01)
        assert monitor.firings == 5


@pytest.mark.asyncio
async def test_a_level_that_holds_rearms_its_timer_only_while_it_holds() -> None:
    async with Robot() as robot:
        robot.state.button = True
        monitor = robot.whenever("button", value=True, max_firing_freq=10)
        await robot.sleep(0.25)  # fires at 0, 0.1, 0.2
        robot.state.button = False
        await robot.sleep(3600)
        assert monitor.firings == 3
