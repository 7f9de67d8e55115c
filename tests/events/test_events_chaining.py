"""Chained callbacks: ``monitor.do(a).do(b)`` runs both at each firing, in order (pyRobots)."""

from __future__ import annotations

import logging
from typing import Any

import pytest

from pyrobots_aio import ActionCancelled, EventKind, Robot, action
from pyrobots_aio.testing import EventLog

pytestmark = pytest.mark.virtual_time

order: list[tuple[str, Any]] = []


@action
async def note_action(robot: Robot, what: str) -> None:
    order.append(("action", what))


@pytest.fixture(autouse=True)
def _clear_order() -> None:
    order.clear()


def note(what: str) -> None:
    order.append(("function", what))


async def note_coroutine(what: str) -> None:
    order.append(("coroutine", what))


@pytest.mark.asyncio
async def test_chained_callbacks_of_every_kind_all_run_at_each_firing_in_order() -> None:
    async with Robot() as robot:
        robot.state.bumper = False
        monitor = robot.whenever("bumper", becomes=True)
        chained = monitor.do(note, "a").do(note_coroutine, "b").do(note_action, "c").do(note, "d")
        assert chained is monitor
        assert monitor.callbacks == (note, note_coroutine, note_action, note)
        for _ in range(2):
            robot.state.bumper = True
            robot.state.bumper = False
            await robot.sleep(0.1)
        assert monitor.firings == 2
    once = [("function", "a"), ("coroutine", "b"), ("action", "c"), ("function", "d")]
    assert order == once * 2


@pytest.mark.asyncio
async def test_a_one_shot_monitor_runs_each_chained_callback_once() -> None:
    async with Robot() as robot:
        robot.state.bumper = False
        robot.on("bumper", becomes=True).do(note, "a").do(note, "b")
        for _ in range(2):
            robot.state.bumper = True
            robot.state.bumper = False
            await robot.sleep(0.1)
    assert order == [("function", "a"), ("function", "b")]


@pytest.mark.asyncio
async def test_a_failing_callback_does_not_stop_or_hide_the_ones_chained_after_it(
    caplog: pytest.LogCaptureFixture,
) -> None:
    def plain() -> None:
        order.append(("function", "plain"))
        raise ValueError("plain broke")

    async def coroutine() -> None:
        order.append(("coroutine", "coroutine"))
        raise RuntimeError("coroutine broke")

    async with Robot() as robot:
        robot.state.bumper = False
        robot.whenever("bumper", becomes=True).do(plain).do(coroutine).do(note, "after")
        for _ in range(2):
            robot.state.bumper = True
            robot.state.bumper = False
            await robot.sleep(0.1)
    once = [("function", "plain"), ("coroutine", "coroutine"), ("function", "after")]
    assert order == once * 2
    records = [r for r in caplog.records if r.name == "pyrobots_aio.events"]
    prefix = (
        "callback test_a_failing_callback_does_not_stop_or_hide_the_ones_chained_after_it.<locals>"
    )
    monitor = "monitor 'bumper becomes=True'"
    names = [f"{prefix}.{name} of {monitor} failed" for name in ("plain", "coroutine")]
    # Each callback keeps its own failure log: the coroutine's first traceback is shown
    # although the function failed just before it; the repeats are counted at shutdown.
    assert [r.getMessage() for r in records] == [
        *names,
        *(f"{name} 1 more times since the last report (tracebacks not shown)" for name in names),
    ]
    assert [type(r.exc_info[1]) for r in records if r.exc_info] == [ValueError, RuntimeError]
    assert all(r.levelno == logging.ERROR for r in records)


async def _press_three_times(*, blocking: bool) -> list[object]:
    """Chain a 1 s coroutine and a function; press at 0, 0.4 and 1.2 s; the firings' statuses."""
    log = EventLog()

    async def slow(what: str) -> None:
        order.append(("coroutine", what))
        await robot.sleep(1.0)

    async with Robot(instruments=[log]) as robot:
        robot.state.button = False
        monitor = robot.whenever("button", becomes=True, blocking=blocking)
        monitor.do(slow, "slow").do(note, "fast")
        for pause in (0.4, 0.8, 1.5):
            robot.state.button = True
            robot.state.button = False
            await robot.sleep(pause)
    return [e.data["callback"] for e in log.of_kind(EventKind.MONITOR_FIRED)]


@pytest.mark.asyncio
async def test_blocking_drops_a_firing_while_any_chained_callback_still_runs() -> None:
    statuses = await _press_three_times(blocking=True)
    # The function ended at once, but the coroutine still ran at 0.4 s: that firing is dropped.
    assert statuses == ["started", "dropped", "started"]
    assert order == [("coroutine", "slow"), ("function", "fast")] * 2


@pytest.mark.asyncio
async def test_non_blocking_chained_callbacks_start_at_every_firing() -> None:
    assert await _press_three_times(blocking=False) == ["started"] * 3
    assert order == [("coroutine", "slow"), ("function", "fast")] * 3


@pytest.mark.asyncio
async def test_close_cancels_every_chained_callback_and_waits_for_their_cleanup() -> None:
    cleaned: list[tuple[str, float]] = []

    async def slow(name: str, cleanup: float) -> None:
        try:
            await robot.sleep(10)
        except ActionCancelled:
            await robot.sleep(cleanup)
            cleaned.append((name, robot.time() - t0))
            raise

    async with Robot() as robot:
        robot.state.button = False
        t0 = robot.time()
        monitor = robot.whenever("button", becomes=True).do(slow, "a", 0.5).do(slow, "b", 0.2)
        robot.state.button = True
        await robot.sleep(1.0)
        assert monitor.running
        await monitor.close()
        assert robot.time() - t0 == 1.5
        assert not monitor.running
    assert cleaned == [("b", 1.2), ("a", 1.5)]


@pytest.mark.asyncio
async def test_the_repr_lists_every_chained_callback() -> None:
    async with Robot() as robot:
        robot.state.bumper = False
        monitor = robot.whenever("bumper", becomes=True).do(print).do(note, "x")
        assert repr(monitor) == (
            f"<EventMonitor #{monitor.id} 'bumper becomes=True' monitoring, "
            "fired 0, callbacks print, note>"
        )
