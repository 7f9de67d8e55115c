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
    Robot,
    RobotNotRunningError,
    action,
)
from pyrobots_aio.actions import current_action

if TYPE_CHECKING:
    from collections.abc import Iterator

BOUND = 60.0  # seconds: only a hung thread waits this long


class Gate:
    """A blocking call the test releases: it tells when it started and when it ended."""

    def __init__(self) -> None:
        self.started = threading.Event()
        self.release = threading.Event()
        self.ended = threading.Event()

    def pass_(self, value: str, fail: bool = False) -> str:
        self.started.set()
        try:
            assert self.release.wait(BOUND)
            if fail:
                raise OSError(f"serial port gone ({value})")
            return value
        finally:
            self.ended.set()


class LateErrors(logging.Handler):
    """Sets `seen` (an asyncio.Event) when pyrobots_aio.robot logs an ERROR."""

    def __init__(self) -> None:
        super().__init__(logging.ERROR)
        self.records: list[logging.LogRecord] = []
        self.seen = asyncio.Event()

    def emit(self, record: logging.LogRecord) -> None:
        self.records.append(record)
        self.seen.set()  # logged on the loop's thread (a done callback)


@pytest.fixture
def late() -> Iterator[LateErrors]:
    handler = LateErrors()
    logger = logging.getLogger("pyrobots_aio.robot")
    logger.addHandler(handler)
    try:
        yield handler
    finally:
        logger.removeHandler(handler)


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
        assert await asyncio.to_thread(gate.started.wait, BOUND)
        handle.cancel("operator")
        assert await handle.wait_done() is Outcome.CANCELLED
        assert not gate.ended.is_set()  # the call goes on in its thread
        gate.release.set()
        assert await asyncio.to_thread(gate.ended.wait, BOUND)
        await asyncio.sleep(0.01)  # the loop hears of the dropped result
    assert late.records == []  # a result is dropped silently


@pytest.mark.asyncio
async def test_a_late_exception_of_an_abandoned_call_is_logged_with_its_traceback(
    late: LateErrors,
) -> None:
    gate = Gate()
    async with Robot(actions=[read_port]) as robot:
        handle = robot.read_port(gate, fail=True)
        assert await asyncio.to_thread(gate.started.wait, BOUND)
        handle.cancel("operator")
        assert await handle.wait_done() is Outcome.CANCELLED
        gate.release.set()
        await asyncio.wait_for(late.seen.wait(), BOUND)
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
async def test_it_uses_the_loop_s_executor_threads_only() -> None:
    before = set(threading.enumerate())
    async with Robot() as robot:
        await asyncio.gather(*(robot.to_thread(time.sleep, 0.01) for _ in range(50)))
    new = set(threading.enumerate()) - before
    assert {t.name.rsplit("_", 1)[0] for t in new} <= {"asyncio"}  # the default executor's


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
