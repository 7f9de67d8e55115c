"""Callbacks: actions, coroutine functions, plain functions; failures, blocking, closing."""

from __future__ import annotations

import asyncio
import logging
from typing import Any

import pytest

from log_support import logged
from pyrobots_aio import (
    ActionCancelled,
    EventKind,
    Outcome,
    Robot,
    TooManyActions,
    action,
)
from pyrobots_aio.actions import ActionHandle, current_action
from pyrobots_aio.events._callbacks import QUIET_PERIOD
from pyrobots_aio.testing import EventLog

pytestmark = pytest.mark.virtual_time

seen_calls: list[tuple[str, tuple[Any, ...], ActionHandle[Any] | None]] = []


@action
async def greet(robot: Robot, *args: Any) -> None:
    """An unbound module-level action: receives the robot first, then the args of do()."""
    seen_calls.append(("greet", (robot, *args), current_action.get().parent))  # type: ignore[union-attr]


@action
async def pressing(robot: Robot) -> None:
    robot.state.bumper = True  # the write happens inside an action
    await robot.sleep(3600)


@action
async def long_walk(robot: Robot) -> None:
    await robot.sleep(10)


class Greeter(Robot):
    @action
    async def wave(self, *args: Any) -> None:
        seen_calls.append(("wave", args, current_action.get().parent))  # type: ignore[union-attr]


@pytest.fixture(autouse=True)
def _clear_seen() -> None:
    seen_calls.clear()


@pytest.mark.asyncio
async def test_an_unbound_action_gets_the_robot_first_and_runs_in_the_root_scope() -> None:
    async with Robot() as robot:
        robot.state.bumper = False
        robot.whenever("bumper", becomes=True).do(greet, "hello", 2)
        writer = pressing(robot)
        await robot.sleep(0.1)
        writer.cancel()
    assert seen_calls == [("greet", (robot, "hello", 2), None)]


@pytest.mark.asyncio
async def test_a_bound_action_gets_only_the_args_of_do() -> None:
    async with Greeter() as robot:
        robot.state.bumper = False
        robot.whenever("bumper", becomes=True).do(robot.wave, "hi")
        writer = pressing(robot)
        await robot.sleep(0.1)
        writer.cancel()
    assert seen_calls == [("wave", ("hi",), None)]


@pytest.mark.asyncio
async def test_an_attached_action_callback_is_spawned_as_an_action() -> None:
    log = EventLog()
    async with Robot(actions=[greet], instruments=[log]) as robot:
        robot.state.bumper = False
        robot.whenever("bumper", becomes=True).do(robot.greet, 1)
        robot.state.bumper = True
        await robot.sleep(0.1)
    assert seen_calls == [("greet", (robot, 1), None)]
    fired = log.first(EventKind.MONITOR_FIRED, "bumper becomes=True")
    spawned = log.first(EventKind.ACTION_SPAWNED, "greet")
    assert log.events.index(fired) < log.events.index(spawned)
    assert spawned.data == {"parent": None}
    assert log.outcomes("greet") == ["succeeded"]


@pytest.mark.asyncio
async def test_a_coroutine_function_gets_the_args_and_runs_as_a_task_outside_any_action() -> None:
    calls: list[tuple[Any, ...]] = []

    async def note(*args: Any) -> None:
        await asyncio.sleep(0.1)
        calls.append((*args, current_action.get(), asyncio.current_task() is not None))

    async with Robot() as robot:
        robot.state.bumper = False
        monitor = robot.whenever("bumper", becomes=True).do(note, "a", 1)
        writer = pressing(robot)
        await robot.sleep(0.01)
        assert monitor.running
        await robot.sleep(0.2)
        assert not monitor.running
        writer.cancel()
    assert calls == [("a", 1, None, True)]


@pytest.mark.asyncio
async def test_a_plain_function_gets_the_args_and_is_not_called_inside_the_write() -> None:
    calls: list[tuple[Any, ...]] = []
    async with Robot() as robot:
        robot.state.bumper = False
        robot.whenever("bumper", becomes=True).do(lambda *a: calls.append(a), "x", 3)
        robot.state.bumper = True
        assert calls == []  # not yet: called from the loop
        await asyncio.sleep(0)
        assert calls == [("x", 3)]


@pytest.mark.asyncio
async def test_a_function_returning_a_coroutine_has_it_run() -> None:
    done: list[str] = []

    async def later(what: str) -> None:
        await asyncio.sleep(0.5)
        done.append(what)

    async with Robot() as robot:
        robot.state.bumper = False
        monitor = robot.whenever("bumper", becomes=True).do(lambda: later("ran"))
        robot.state.bumper = True
        await robot.sleep(0.1)
        assert monitor.running
        await robot.sleep(1.0)
    assert done == ["ran"]


@pytest.mark.asyncio
async def test_a_failing_callback_is_logged_and_the_monitor_goes_on(
    caplog: pytest.LogCaptureFixture,
) -> None:
    calls: list[str] = []

    def plain() -> None:
        calls.append("plain")
        raise ValueError("plain broke")

    async def coroutine() -> None:
        calls.append("coroutine")
        raise RuntimeError("coroutine broke")

    async with Robot() as robot:
        robot.state.bumper = False
        robot.whenever("bumper", becomes=True).do(plain)
        robot.whenever("bumper", becomes=True).do(coroutine)
        for _ in range(2):
            robot.state.bumper = True
            robot.state.bumper = False
            await robot.sleep(0.1)
    assert calls == ["plain", "coroutine"] * 2
    records = [r for r in caplog.records if r.name == "pyrobots_aio.events"]
    prefix = "callback test_a_failing_callback_is_logged_and_the_monitor_goes_on.<locals>"
    # The second failures come within the quiet period: counted, and told at shutdown.
    assert [r.getMessage() for r in records] == [
        f"{prefix}.plain of monitor 'bumper becomes=True' failed",
        f"{prefix}.coroutine of monitor 'bumper becomes=True' failed",
        f"{prefix}.plain of monitor 'bumper becomes=True' failed 1 more times since the last "
        "report (tracebacks not shown)",
        f"{prefix}.coroutine of monitor 'bumper becomes=True' failed 1 more times since the "
        "last report (tracebacks not shown)",
    ]
    assert [type(r.exc_info[1]) for r in records if r.exc_info] == [ValueError, RuntimeError]
    assert all(r.levelno == logging.ERROR for r in records)


@pytest.mark.asyncio
async def test_a_callback_failing_a_thousand_times_logs_one_traceback_and_a_count(
    caplog: pytest.LogCaptureFixture,
) -> None:
    def broken() -> None:
        raise ValueError("broken")

    async with Robot() as robot:
        robot.state.bumper = False
        robot.whenever("bumper", becomes=True).do(broken)
        for _ in range(1000):
            robot.state.bumper = True
            robot.state.bumper = False
            await robot.sleep(0.005)  # 5 s in all: within one quiet period
        await robot.sleep(QUIET_PERIOD)
        robot.state.bumper = True  # after the quiet period: logged again, with the count
        await robot.sleep(0)
    records = [r for r in caplog.records if r.name == "pyrobots_aio.events"]
    name = (
        "callback test_a_callback_failing_a_thousand_times_logs_one_traceback_and_a_count."
        "<locals>.broken of monitor 'bumper becomes=True' failed"
    )
    assert [r.getMessage() for r in records] == [
        name,
        f"{name} (and 999 more times since the last report, not shown)",
    ]
    assert all(r.exc_info is not None for r in records)


@pytest.mark.asyncio
async def test_a_failing_action_callback_is_logged_by_the_executive(
    caplog: pytest.LogCaptureFixture,
) -> None:
    @action
    async def broken(robot: Robot) -> None:
        raise OSError("servo unplugged")

    async with Robot() as robot:
        robot.state.bumper = False
        monitor = robot.whenever("bumper", becomes=True).do(broken)
        for _ in range(2):
            robot.state.bumper = True
            robot.state.bumper = False
            await robot.sleep(0.1)
        assert monitor.firings == 2
    records = [r for r in logged(caplog) if r.name.startswith("pyrobots_aio")]
    assert [r.getMessage().splitlines()[0] for r in records] == [
        "action broken#1 failed and nobody retrieved its error:",
        "action broken#2 failed and nobody retrieved its error:",
    ]
    assert all(r.getMessage().endswith("OSError: servo unplugged") for r in records)


@pytest.mark.asyncio
async def test_blocking_drops_firings_while_the_callback_runs() -> None:
    log = EventLog()
    runs: list[float] = []

    async def slow() -> None:
        runs.append(robot.time())
        await robot.sleep(1.0)

    async with Robot(instruments=[log]) as robot:
        robot.state.button = False
        t0 = robot.time()
        monitor = robot.whenever("button", becomes=True).do(slow)
        for _ in range(6):  # presses at 0, 0.4, 0.8, 1.2, 1.6, 2.0
            robot.state.button = True
            robot.state.button = False
            await robot.sleep(0.4)
        assert monitor.firings == 6
    assert [t - t0 for t in runs] == [0.0, pytest.approx(1.2)]
    statuses = [e.data["callback"] for e in log.of_kind(EventKind.MONITOR_FIRED)]
    assert statuses == ["started", "dropped", "dropped", "started", "dropped", "dropped"]


@pytest.mark.asyncio
async def test_non_blocking_callbacks_run_concurrently() -> None:
    running = 0
    most = 0

    async def slow() -> None:
        nonlocal running, most
        running += 1
        most = max(most, running)
        try:
            await robot.sleep(1.0)
        finally:
            running -= 1

    async with Robot() as robot:
        robot.state.button = False
        robot.whenever("button", becomes=True, blocking=False).do(slow)
        for _ in range(4):
            robot.state.button = True
            robot.state.button = False
            await robot.sleep(0.1)
        await robot.sleep(2.0)
    assert most == 4


@pytest.mark.asyncio
async def test_close_cancels_a_running_coroutine_callback_and_waits_for_its_cleanup() -> None:
    events: list[tuple[str, float]] = []

    async def slow() -> None:
        try:
            await robot.sleep(10)
        except ActionCancelled:
            await robot.sleep(0.5)  # cleanup may await
            events.append(("cleaned", robot.time() - t0))
            raise

    async with Robot() as robot:
        robot.state.button = False
        t0 = robot.time()
        monitor = robot.whenever("button", becomes=True).do(slow)
        robot.state.button = True
        await robot.sleep(1.0)
        await monitor.close()
        events.append(("closed", robot.time() - t0))
        assert not monitor.monitoring
        assert not monitor.running
        assert robot.events.monitors() == []
    assert events == [("cleaned", 1.5), ("closed", 1.5)]


@pytest.mark.asyncio
async def test_close_cancels_a_running_action_callback() -> None:
    log = EventLog()
    async with Robot(instruments=[log]) as robot:
        robot.state.button = False
        monitor = robot.whenever("button", becomes=True).do(long_walk)
        robot.state.button = True
        await robot.sleep(1.0)
        await monitor.close()
        assert robot.handles() == []
    assert log.outcomes("long_walk") == ["cancelled"]
    cancel = log.cancellations("long_walk")[0]
    assert cancel.data["reason"] == "monitor 'button becomes=True' closed"


@pytest.mark.asyncio
async def test_a_plain_function_that_starts_an_action_is_blocked_and_closed_by_its_monitor() -> (
    None
):
    log = EventLog()
    async with Robot(instruments=[log]) as robot:
        robot.state.button = False
        monitor = robot.whenever("button", becomes=True).do(lambda: long_walk(robot))
        for _ in range(3):  # the second and third presses come while the walk runs
            robot.state.button = True
            robot.state.button = False
            await robot.sleep(0.3)
        assert monitor.running
        assert len(robot.handles()) == 1
        await monitor.close()
        assert robot.handles() == []
        assert not monitor.running
    statuses = [e.data["callback"] for e in log.of_kind(EventKind.MONITOR_FIRED)]
    assert statuses == ["started", "dropped", "dropped"]
    assert log.outcomes("long_walk") == ["cancelled"]
    assert log.cancellations("long_walk")[0].data["reason"] == (
        "monitor 'button becomes=True' closed"
    )


@pytest.mark.asyncio
async def test_stop_all_monitoring_lets_running_callbacks_finish() -> None:
    finished: list[float] = []

    async def slow() -> None:
        await robot.sleep(1.0)
        finished.append(robot.time() - t0)

    async with Robot() as robot:
        robot.state.button = False
        t0 = robot.time()
        monitor = robot.whenever("button", becomes=True, blocking=False).do(slow)
        robot.state.button = True
        await robot.sleep(0.5)
        robot.events.stop_all_monitoring()
        assert not monitor.monitoring
        assert monitor.running
        assert robot.events.monitors() == [monitor]
        robot.state.button = False
        robot.state.button = True  # not watched any more
        await robot.sleep(2.0)
        assert monitor.firings == 1
        assert robot.events.monitors() == []
    assert finished == [1.0]


@pytest.mark.asyncio
async def test_cancel_all_stops_every_monitor_and_cancels_running_callbacks() -> None:
    cancelled: list[str] = []

    async def slow(name: str) -> None:
        try:
            await robot.sleep(10)
        except ActionCancelled:
            cancelled.append(name)
            raise

    async with Robot() as robot:
        robot.state.update(a=False, b=False)
        first = robot.whenever("a", becomes=True).do(slow, "a")
        second = robot.whenever("b", becomes=True).do(slow, "b")
        idle = robot.whenever("a", value=5)
        robot.state.update(a=True, b=True)
        await robot.sleep(0.1)
        await robot.events.cancel_all()
        assert sorted(cancelled) == ["a", "b"]
        assert not any(m.monitoring or m.running for m in (first, second, idle))
        assert robot.events.monitors() == []
        assert len(robot.events) == 0


@pytest.mark.asyncio
async def test_leaving_the_robot_cancels_callbacks_and_monitors() -> None:
    cancelled: list[str] = []

    async def slow() -> None:
        try:
            await robot.sleep(10)
        except ActionCancelled:
            cancelled.append("slow")
            raise

    async with Robot() as robot:
        robot.state.button = False
        monitor = robot.whenever("button", becomes=True).do(slow)
        walker = robot.whenever("button", becomes=True).do(long_walk)
        robot.state.button = True
        await robot.sleep(0.1)
    assert cancelled == ["slow"]
    assert not monitor.monitoring
    assert not walker.running
    assert robot.events.monitors() == []


@pytest.mark.asyncio
async def test_a_callback_that_ignores_cancellation_is_cancelled_again_then_abandoned(
    caplog: pytest.LogCaptureFixture,
) -> None:
    release = asyncio.Event()

    async def deaf() -> None:
        while not release.is_set():
            try:
                await release.wait()
            except ActionCancelled:
                continue

    robot = Robot(cancel_grace=0.5)
    try:
        async with robot:
            robot.state.button = False
            robot.whenever("button", becomes=True).do(deaf)
            robot.state.button = True
            await robot.sleep(0.1)
            t0 = robot.time()
        took = asyncio.get_running_loop().time() - t0
    finally:
        release.set()
        await asyncio.sleep(0)
    assert took == pytest.approx(1.0)
    records = [r for r in caplog.records if r.name == "pyrobots_aio.events"]
    name = "callback test_a_callback_that_ignores_cancellation_is_cancelled_again_then_abandoned"
    assert records[0].levelno == logging.WARNING
    assert (
        records[0]
        .getMessage()
        .startswith(
            f"{name}.<locals>.deaf of monitor 'button becomes=True' still running 0.5 s after "
            "cancellation, at "
        )
    )
    assert "test_events_callbacks.py:" in records[0].getMessage()
    assert records[1].levelno == logging.ERROR
    assert (
        records[1]
        .getMessage()
        .startswith(
            f"{name}.<locals>.deaf of monitor 'button becomes=True' "
            "ignored cancellation for 1 s, at "
        )
    )


@pytest.mark.asyncio
async def test_each_firing_is_reported_to_the_instruments() -> None:
    log = EventLog()
    async with Robot(instruments=[log]) as robot:
        robot.state.update(ir=1.0, pose=None)
        t0 = robot.time()
        monitor = robot.whenever("ir", below=0.5, max_firing_freq=0).do(lambda: None)
        robot.whenever("pose", becomes=(1, 2))
        await robot.sleep(1.0)
        robot.state.ir = 0.25
        robot.state.ir = 0.125  # the callback is still queued: dropped
        robot.state.pose = (1, 2)  # not a JSON scalar: recorded as its repr
    fired = log.of_kind(EventKind.MONITOR_FIRED)
    assert [(e.time - t0, e.name, e.action) for e in fired] == [
        (1.0, "ir below=0.5", None),
        (1.0, "ir below=0.5", None),
        (1.0, "pose becomes=(1, 2)", None),
    ]
    assert fired[0].data == {
        "monitor": monitor.id,
        "var": "ir",
        "condition": "below=0.5",
        "value": 0.25,
        "callback": "started",
    }
    assert (fired[1].data["value"], fired[1].data["callback"]) == (0.125, "dropped")
    assert (fired[2].data["value"], fired[2].data["callback"]) == ("(1, 2)", "none")


@pytest.mark.asyncio
async def test_do_with_a_non_callable_is_refused_and_registers_nothing() -> None:
    async with Robot() as robot:
        robot.state.bumper = False
        monitor = robot.whenever("bumper", becomes=False).do(print)
        with pytest.raises(TypeError) as type_error:
            monitor.do(42)  # type: ignore[arg-type]
        assert str(type_error.value) == (
            "do() takes an action, a coroutine function or a function, got 42 (int)"
        )
        assert monitor.callbacks == (print,)


@pytest.mark.asyncio
async def test_firings_before_do_run_no_callback() -> None:
    calls: list[str] = []
    async with Robot() as robot:
        robot.state.bumper = False
        monitor = robot.whenever("bumper", becomes=True)
        robot.state.bumper = True
        monitor.do(calls.append, "late")
        robot.state.bumper = False
        await robot.sleep(0)
        assert (monitor.firings, calls) == (1, [])
        robot.state.bumper = True
        await robot.sleep(0)
        assert (monitor.firings, calls) == (2, ["late"])
    assert robot.events.monitors() == []


@pytest.mark.asyncio
async def test_action_outcome_when_the_robot_stops_during_a_callback() -> None:
    @action
    async def forever(robot: Robot) -> None:
        await robot.sleep(3600)

    handles: list[ActionHandle[Any]] = []
    async with Robot() as robot:
        robot.state.bumper = False
        robot.whenever("bumper", becomes=True).do(lambda: handles.append(forever(robot)))
        robot.state.bumper = True
        await robot.sleep(0.1)
    assert [h.outcome for h in handles] == [Outcome.CANCELLED]


@pytest.mark.asyncio
async def test_an_action_callback_that_cannot_start_is_logged(
    caplog: pytest.LogCaptureFixture,
) -> None:
    @action
    async def forever(robot: Robot) -> None:
        await robot.sleep(3600)

    async with Robot(max_actions=1) as robot:
        robot.state.bumper = False
        forever(robot)
        monitor = robot.whenever("bumper", becomes=True).do(greet)
        robot.state.bumper = True
        await robot.sleep(0.1)
        assert (monitor.firings, monitor.running) == (1, False)
    records = [r for r in caplog.records if r.name == "pyrobots_aio.events"]
    assert [r.getMessage() for r in records] == [
        "callback greet of monitor 'bumper becomes=True' could not start its action"
    ]
    assert records[0].exc_info is not None
    assert isinstance(records[0].exc_info[1], TooManyActions)
    assert seen_calls == []


@pytest.mark.asyncio
async def test_cancel_all_finishes_its_bounded_wait_when_its_caller_is_cancelled() -> None:
    cleaned: list[float] = []

    async def slow() -> None:
        try:
            await robot.sleep(10)
        except ActionCancelled:
            await robot.sleep(0.5)
            cleaned.append(robot.time() - t0)
            raise

    async with Robot() as robot:
        robot.state.button = False
        t0 = robot.time()
        monitor = robot.whenever("button", becomes=True).do(slow)
        robot.state.button = True
        await robot.sleep(0.1)
        stopper = asyncio.create_task(robot.events.cancel_all())
        await robot.sleep(0.2)
        stopper.cancel()
        with pytest.raises(asyncio.CancelledError):
            await stopper
        assert cleaned == [pytest.approx(0.6)]  # the wait went on to the end of the cleanup
        assert robot.time() - t0 == pytest.approx(0.6)
        assert not monitor.running
