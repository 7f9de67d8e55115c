"""robot.to_thread: blocking code off the loop, given up at once when its action is cancelled."""

from __future__ import annotations

import asyncio
import logging
import threading
import time
from typing import TYPE_CHECKING

import pytest

from pyrobots_aio import (
    EventLoopError,
    Outcome,
    PyRobotsError,
    Robot,
    RobotNotRunningError,
    TooManyAbandonedCalls,
    action,
)
from pyrobots_aio.actions import current_action
from pyrobots_aio.robot._offloop import ABANDONED_CALLS, LIVE_CALLS

if TYPE_CHECKING:
    from collections.abc import Iterator

BOUND = 60.0  # seconds: only a hung thread waits this long


class Gate:
    """Blocking calls the test releases together; it counts those that started and ended."""

    def __init__(self) -> None:
        self.release = threading.Event()
        self.fail = False  # every call raises once released
        self.started = 0
        self.ended = 0
        self._changed = threading.Condition()

    def pass_(self, value: str, fail: bool = False) -> str:
        self._count("started")
        try:
            assert self.release.wait(BOUND)
            if fail or self.fail:
                raise OSError(f"serial port gone ({value})")
            return value
        finally:
            self._count("ended")

    def _count(self, what: str) -> None:
        with self._changed:
            setattr(self, what, getattr(self, what) + 1)
            self._changed.notify_all()

    async def wait_for(self, what: str, count: int = 1) -> None:
        """Wait (in a helper thread) until ``count`` calls have ``what`` ("started", "ended")."""

        def wait() -> bool:
            with self._changed:
                return self._changed.wait_for(lambda: getattr(self, what) >= count, BOUND)

        assert await asyncio.to_thread(wait)


class LateErrors(logging.Handler):
    """Counts the ERRORs of pyrobots_aio.robot (logged in a worker thread or on the loop)."""

    def __init__(self) -> None:
        super().__init__(logging.ERROR)
        self.records: list[logging.LogRecord] = []
        self._seen = threading.Semaphore(0)

    def emit(self, record: logging.LogRecord) -> None:
        self.records.append(record)
        self._seen.release()

    async def wait_for(self, count: int) -> None:
        for _ in range(count):
            assert await asyncio.to_thread(self._seen.acquire, True, BOUND)


@pytest.fixture
def late() -> Iterator[LateErrors]:
    handler = LateErrors()
    logger = logging.getLogger("pyrobots_aio.robot")
    logger.addHandler(handler)
    try:
        yield handler
    finally:
        logger.removeHandler(handler)


def _to_threads() -> list[threading.Thread]:
    return [t for t in threading.enumerate() if t.name.startswith("pyrobots_aio to_thread_")]


def _join(threads: list[threading.Thread]) -> None:
    """Wait for these threads of robot.to_thread to end (after the robot's exit); none is left."""
    for thread in threads:
        thread.join(BOUND)
    assert _to_threads() == []


def _answer() -> int:
    return 42


@action
async def read_port(robot: Robot, gate: Gate, fail: bool = False) -> str:
    return await robot.to_thread(gate.pass_, "ok", fail)


@pytest.mark.asyncio
async def test_it_returns_the_call_s_result_from_another_thread_in_the_caller_s_context() -> None:
    @action
    async def where(robot: Robot) -> tuple[int, object]:
        return await robot.to_thread(lambda: (threading.get_ident(), current_action.get()))

    async with Robot(actions=[where]) as robot:
        handle = robot.where()
        thread, seen = await handle
    assert thread != threading.get_ident()
    assert seen is handle


@pytest.mark.asyncio
async def test_an_error_of_the_call_is_the_caller_s() -> None:
    gate = Gate()
    gate.release.set()
    async with Robot(actions=[read_port]) as robot:
        with pytest.raises(OSError, match=r"serial port gone \(ok\)"):
            await robot.read_port(gate, fail=True)


@pytest.mark.asyncio
async def test_cancelling_the_action_stops_waiting_at_once_and_drops_the_result(
    late: LateErrors,
) -> None:
    gate = Gate()
    async with Robot(actions=[read_port]) as robot:
        handle = robot.read_port(gate)
        await gate.wait_for("started")
        handle.cancel("operator")
        assert await handle.wait_done() is Outcome.CANCELLED
        assert gate.ended == 0  # the call goes on in its thread
        gate.release.set()
        await gate.wait_for("ended")
        await asyncio.sleep(0.01)  # the loop hears of the dropped result
    assert late.records == []  # a result is dropped silently


@pytest.mark.asyncio
async def test_a_late_exception_of_an_abandoned_call_is_logged_with_its_traceback(
    late: LateErrors,
) -> None:
    gate = Gate()
    async with Robot(actions=[read_port]) as robot:
        handle = robot.read_port(gate, fail=True)
        await gate.wait_for("started")
        handle.cancel("operator")
        assert await handle.wait_done() is Outcome.CANCELLED
        gate.release.set()
        await late.wait_for(1)
    [record] = late.records
    assert record.getMessage() == (
        "robot.to_thread(Gate.pass_) raised after its caller was cancelled (its result is dropped)"
    )
    assert record.exc_info is not None
    assert isinstance(record.exc_info[1], OSError)
    assert "serial port gone (ok)" in logging.Formatter().format(record)


@pytest.mark.asyncio
async def test_it_refuses_another_thread_and_a_robot_that_is_not_running() -> None:
    robot = Robot()
    with pytest.raises(RobotNotRunningError, match="is not running"):
        await robot.to_thread(time.sleep, 0)
    async with robot:
        with pytest.raises(EventLoopError, match=r"cannot call robot.to_thread from thread"):
            await asyncio.to_thread(asyncio.run, robot.to_thread(time.sleep, 0))


@pytest.mark.asyncio
async def test_it_runs_in_the_robot_s_own_threads_which_end_with_it() -> None:
    gate = Gate()
    gate.release.set()
    async with Robot() as robot:
        calls = [robot.to_thread(gate.pass_, str(n)) for n in range(LIVE_CALLS)]
        assert await asyncio.gather(*calls) == [str(n) for n in range(LIVE_CALLS)]
        threads = _to_threads()
        assert 1 <= len(threads) <= LIVE_CALLS
        assert await robot.to_thread(threading.current_thread) in threads  # reused
    assert _to_threads() == []  # joined at the exit, none left behind
    assert not any(thread.is_alive() for thread in threads)


async def _abandon(robot: Robot, gate: Gate, count: int) -> None:
    """Leave ``count`` calls of ``gate.pass_`` abandoned, in rounds of LIVE_CALLS callers."""
    first = gate.started
    while (started := gate.started - first) < count:
        handles = [robot.read_port(gate) for _ in range(min(LIVE_CALLS, count - started))]
        await gate.wait_for("started", gate.started + len(handles))
        for handle in handles:
            handle.cancel("operator")
        for handle in handles:
            assert await handle.wait_done() is Outcome.CANCELLED


@pytest.mark.asyncio
async def test_an_abandoned_call_gives_its_turn_up_at_once() -> None:
    gate = Gate()
    async with Robot(actions=[read_port]) as robot:
        first = [robot.read_port(gate) for _ in range(LIVE_CALLS)]
        await gate.wait_for("started", LIVE_CALLS)
        last = robot.read_port(gate)
        await asyncio.sleep(0)
        assert gate.started == LIVE_CALLS  # it waits its turn
        first[0].cancel("operator")
        await gate.wait_for("started", LIVE_CALLS + 1)  # the abandoned call's turn
        assert gate.ended == 0
        gate.release.set()
        assert await asyncio.gather(*first[1:], last) == ["ok"] * LIVE_CALLS
        threads = _to_threads()
    _join(threads)


@pytest.mark.asyncio
async def test_a_later_call_never_waits_behind_abandoned_ones() -> None:
    gate = Gate()
    async with Robot(actions=[read_port]) as robot:
        await _abandon(robot, gate, LIVE_CALLS)
        assert await asyncio.wait_for(robot.to_thread(_answer), BOUND) == 42
        assert gate.ended == 0  # the abandoned calls still run
        threads = _to_threads()
    gate.release.set()
    _join(threads)


@pytest.mark.asyncio
async def test_while_32_abandoned_calls_run_a_call_is_refused_with_their_count(
    late: LateErrors,
) -> None:
    gate = Gate()
    async with Robot(actions=[read_port]) as robot:
        await _abandon(robot, gate, ABANDONED_CALLS - 1)
        assert await robot.to_thread(_answer) == 42  # one below the limit
        await _abandon(robot, gate, 1)
        with pytest.raises(TooManyAbandonedCalls) as refused:
            await robot.to_thread(_answer)
        assert str(refused.value) == (
            "cannot call robot.to_thread(_answer): 32 abandoned calls still run in its threads "
            "(Gate.pass_ (32)), the most it keeps; their callers were cancelled, but Python "
            "cannot stop a thread: give the blocking calls a timeout so that they return"
        )
        assert refused.value.running == ["Gate.pass_"] * 32
        assert isinstance(refused.value, PyRobotsError)
        assert gate.ended == 0
        gate.fail = True
        gate.release.set()
        await late.wait_for(ABANDONED_CALLS)  # each reported once it is no longer counted
        assert await robot.to_thread(_answer) == 42
        threads = _to_threads()
    _join(threads)  # (a thread whose call just returned may still be on its way out)


@pytest.mark.asyncio
async def test_callers_waiting_in_a_batch_never_take_the_abandoned_calls_past_32() -> None:
    # Any running call may yet be abandoned: beside 31 abandoned, one runs at a time. Before,
    # a batch of callers passed the check together, and, all cancelled, left 37 running.
    gate = Gate()
    async with Robot(actions=[read_port]) as robot:
        await _abandon(robot, gate, ABANDONED_CALLS - 1)
        batch = [robot.read_port(gate) for _ in range(LIVE_CALLS)]
        await gate.wait_for("started", ABANDONED_CALLS)  # the first of them runs
        for handle in batch:
            handle.cancel("operator")
        for handle in batch:
            assert await handle.wait_done() is Outcome.CANCELLED
        with pytest.raises(TooManyAbandonedCalls) as refused:
            await robot.to_thread(_answer)
        assert refused.value.running == ["Gate.pass_"] * ABANDONED_CALLS
        assert gate.started == ABANDONED_CALLS  # the rest of the batch never ran
        threads = _to_threads()
    gate.release.set()
    _join(threads)


@pytest.mark.asyncio
async def test_the_exit_does_not_wait_for_an_abandoned_call_and_names_it(
    caplog: pytest.LogCaptureFixture,
) -> None:
    gate = Gate()
    async with Robot(actions=[read_port]) as robot:
        robot.read_port(gate)  # cancelled by the exit: abandoned
        await gate.wait_for("started")
        [thread] = _to_threads()
    assert gate.ended == 0  # the exit did not wait for it
    [warning] = [r for r in caplog.records if "still running at the robot's exit" in r.message]
    assert warning.levelno == logging.WARNING
    assert warning.getMessage() == (
        "abandoned robot.to_thread calls still running at the robot's exit: 1 (Gate.pass_); "
        "each thread ends when its call returns (the process waits for it before it exits)"
    )
    assert thread.is_alive()
    gate.release.set()
    _join([thread])  # it ends once its call returns: nothing is left behind


def _slow_read(seconds: float) -> str:
    time.sleep(seconds)
    return "read"


@pytest.mark.virtual_time
@pytest.mark.asyncio
async def test_in_virtual_time_the_call_takes_no_time_and_timers_wait_for_it() -> None:
    async with Robot() as robot:
        sleeper = asyncio.create_task(robot.sleep(0.001))
        t0 = robot.time()
        assert await robot.to_thread(_slow_read, 0.05) == "read"
        assert robot.time() == t0  # 50 ms of real time took no virtual time...
        assert not sleeper.done()  # ...and a 1 ms timer did not fire meanwhile
        await sleeper
        assert robot.time() == t0 + 0.001
