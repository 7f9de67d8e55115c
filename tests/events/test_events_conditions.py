"""Condition semantics: value, becomes, above/below, increase/decrease ratchets, held_for."""

from __future__ import annotations

import logging

import pytest

from pyrobots_aio import EventKind, Robot
from pyrobots_aio.events import EventMonitor
from pyrobots_aio.testing import EventLog

pytestmark = pytest.mark.virtual_time


def _values(log: EventLog, monitor: EventMonitor) -> list[object]:
    return [e.data["value"] for e in log.of_kind(EventKind.MONITOR_FIRED, monitor.name)]


def _times(log: EventLog, monitor: EventMonitor, t0: float) -> list[float]:
    return [e.time - t0 for e in log.of_kind(EventKind.MONITOR_FIRED, monitor.name)]


@pytest.mark.asyncio
async def test_increase_fires_from_the_last_firing_or_the_lowest_value_since() -> None:
    log = EventLog()
    async with Robot(instruments=[log]) as robot:
        robot.state.scale = 10.0
        squeezed = robot.whenever("scale", increase=1.0)  # reference: 10.0, the value now
        for value in (10.5, 11.0, 11.5, 10.0, 11.75, 12.0, 14.0, 13.0):
            robot.state.scale = value
    # 11.0 fires (reference 11.0); 11.5 does not; the fall to 10.0 drags the reference
    # down with it, so 11.75 fires (reference 11.75); 12.0 does not; 14.0 fires once.
    assert _values(log, squeezed) == [11.0, 11.75, 14.0]


@pytest.mark.asyncio
async def test_decrease_fires_from_the_last_firing_or_the_highest_value_since() -> None:
    log = EventLog()
    async with Robot(instruments=[log]) as robot:
        robot.state.battery = 1.0
        draining = robot.whenever("battery", decrease=0.25)
        for value in (0.875, 0.75, 0.5, 0.625, 0.375, 0.25):
            robot.state.battery = value
    # a rise (0.5 -> 0.625) lifts the reference: 0.375 is 0.25 below 0.625
    assert _values(log, draining) == [0.75, 0.5, 0.375]


def _steps(start: float, stop: float, step: float) -> list[float]:
    """``start`` to ``stop`` (included) by ``step``, each the float nearest its decimal."""
    count = round(abs(stop - start) / step)
    sign = 1 if stop > start else -1
    return [round(start + sign * step * k, 2) for k in range(1, count + 1)]


@pytest.mark.asyncio
@pytest.mark.parametrize(
    ("kind", "levels", "fired"),
    [
        # DESIGN §11: recharged from 0.5 to 1.0, then drained: 0.9, 0.8, ..., not only below 0.4
        (
            "decrease",
            _steps(0.5, 1.0, 0.05) + _steps(1.0, 0.0, 0.05),
            [0.9, 0.8, 0.7, 0.6, 0.5, 0.4, 0.3, 0.2, 0.1, 0.0],
        ),
        (
            "increase",
            _steps(0.5, 0.0, 0.05) + _steps(0.0, 1.0, 0.05),
            [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0],
        ),
    ],
)
async def test_the_reference_follows_the_other_way_then_fires_at_each_tenth(
    kind: str, levels: list[float], fired: list[float]
) -> None:
    log = EventLog()
    async with Robot(instruments=[log]) as robot:
        robot.state.battery = 0.5
        monitor = robot.whenever("battery", **{kind: 0.1})
        for level in levels:
            robot.state.battery = level
    assert _values(log, monitor) == fired


@pytest.mark.asyncio
@pytest.mark.parametrize("start", [None, float("nan")], ids=["None", "nan"])
async def test_a_nan_or_none_reading_never_becomes_the_reference(start: float | None) -> None:
    nan = float("nan")
    log = EventLog()
    async with Robot(instruments=[log]) as robot:
        robot.state.battery = start
        draining = robot.whenever("battery", decrease=0.1)
        charging = robot.whenever("battery", increase=0.1)
        for level in (nan, None, 1.0, nan, 0.9, None, 0.8, nan, 0.9, 1.0):
            robot.state.battery = level
    assert _values(log, draining) == [0.9, 0.8]
    assert _values(log, charging) == [0.9, 1.0]


@pytest.mark.asyncio
async def test_increase_takes_the_first_number_as_reference_when_the_key_starts_as_none() -> None:
    log = EventLog()
    async with Robot(instruments=[log]) as robot:
        robot.state.scale = None
        squeezed = robot.whenever("scale", increase=2)
        for value in (5, 6, 7, 8, None, 9):
            robot.state.scale = value
    assert _values(log, squeezed) == [7, 9]


@pytest.mark.asyncio
async def test_above_and_below_are_strict_levels() -> None:
    async with Robot() as robot:
        robot.state.ir = 1.0
        far = robot.whenever("ir", above=0.5, max_firing_freq=0)
        close = robot.whenever("ir", below=0.5, max_firing_freq=0)
        await robot.sleep(0)  # ir=1.0 already holds for "above": fires once at creation
        for value in (0.5, 0.75, 0.25, 0.5, None):
            robot.state.ir = value
        await robot.sleep(0)
        assert (far.firings, close.firings) == (2, 1)


@pytest.mark.asyncio
async def test_a_level_that_holds_at_creation_fires_once_do_is_chained() -> None:
    said: list[tuple[str, float]] = []
    async with Robot() as robot:
        robot.state.bumper = True
        t0 = robot.time()
        robot.whenever("bumper", value=True, max_firing_freq=0).do(
            lambda what: said.append((what, robot.time())), "already"
        )
        await robot.sleep(1.0)
    assert said == [("already", t0)]


@pytest.mark.asyncio
async def test_becomes_waits_for_a_change_into_the_value() -> None:
    async with Robot() as robot:
        robot.state.docked = True
        undocked = robot.whenever("docked", becomes=False)
        docked = robot.whenever("docked", becomes=True)  # already True: not a change
        for value in (True, False, False, True, True, False):
            robot.state.docked = value
        assert (undocked.firings, docked.firings) == (2, 1)


@pytest.mark.asyncio
async def test_value_compares_with_equality() -> None:
    async with Robot() as robot:
        robot.state.mode = "idle"
        walking = robot.whenever("mode", value="walk", max_firing_freq=0)
        for mode in ("walk", "walk", "idle", "run", "walk"):
            robot.state.mode = mode
        assert walking.firings == 3


@pytest.mark.asyncio
async def test_held_for_ignores_a_short_blip_and_fires_an_edge_once_after_the_hold() -> None:
    log = EventLog()
    async with Robot(instruments=[log]) as robot:
        robot.state.bumper = False
        t0 = robot.time()
        stuck = robot.whenever("bumper", becomes=True, held_for=0.5)
        robot.state.bumper = True
        await robot.sleep(0.3)
        robot.state.bumper = False  # a 0.3 s blip: no firing
        await robot.sleep(0.7)
        robot.state.bumper = True  # at 1.0 s, and held from then on
        await robot.sleep(5.0)
        assert stuck.firings == 1
    assert _times(log, stuck, t0) == [pytest.approx(1.5)]


@pytest.mark.asyncio
async def test_held_for_with_a_level_refires_at_the_rate_while_it_holds() -> None:
    log = EventLog()
    async with Robot(instruments=[log]) as robot:
        robot.state.ir = 1.0
        t0 = robot.time()
        close = robot.whenever("ir", below=0.3, held_for=1.0, max_firing_freq=2)
        robot.state.ir = 0.2
        await robot.sleep(0.4)
        robot.state.ir = 0.1  # still below: the hold goes on
        await robot.sleep(1.7)
        robot.state.ir = 0.5  # at 2.1 s
        await robot.sleep(2.0)
    assert _times(log, close, t0) == [pytest.approx(t) for t in (1.0, 1.5, 2.0)]
    assert _values(log, close) == [0.1, 0.1, 0.1]


@pytest.mark.asyncio
async def test_held_for_restarts_after_each_interruption() -> None:
    async with Robot() as robot:
        robot.state.ir = 1.0
        close = robot.whenever("ir", below=0.3, held_for=1.0)
        for _ in range(5):
            robot.state.ir = 0.2
            await robot.sleep(0.9)
            robot.state.ir = 0.5
            await robot.sleep(0.1)
        assert close.firings == 0


@pytest.mark.asyncio
async def test_a_value_that_cannot_be_compared_is_logged_once_and_does_not_fire(
    caplog: pytest.LogCaptureFixture,
) -> None:
    async with Robot() as robot:
        robot.state.ir = 1.0
        close = robot.whenever("ir", below=0.3, max_firing_freq=0)
        for value in ("near", "near", 0.1, "near"):
            robot.state.ir = value
        assert close.firings == 1
    records = [r for r in caplog.records if r.name == "pyrobots_aio.events"]
    assert [r.getMessage() for r in records] == [
        "ir below=0.3: testing 'near' failed (logged once until it succeeds again)",
        "ir below=0.3: testing 'near' failed (logged once until it succeeds again)",
    ]
    assert all(r.levelno == logging.ERROR and r.exc_info for r in records)
