"""The loop watchdog: a real block is reported once, naming its action, line and stack.

Blocks here are real (the test's action blocks the loop thread on a
``threading.Event`` that the watchdog's WARNING sets, or in ``time.sleep``),
the watchdog is a real thread, and every wait has a generous bound: the tests
check what is reported, never how fast (that is ``tests/bench/bench_watchdog.py``).
A loaded machine can stall the loop elsewhere for a threshold now and then, and
the watchdog rightly says so: the tests count the reports of their own block, at
its ``file:line``.
"""

from __future__ import annotations

import asyncio
import inspect
import logging
import math
import re
import threading
import time
from typing import TYPE_CHECKING, Any

import pytest

from pyrobots_aio import EventKind, ExecEvent, Robot, action
from pyrobots_aio.recording import (
    JsonlRecorder,
    McapRecorder,
    load,
    render_timeline_html,
    summarize,
)
from pyrobots_aio.sim import run
from pyrobots_aio.testing import EventLog

if TYPE_CHECKING:
    from collections.abc import Iterator
    from pathlib import Path

WATCHDOG = "pyrobots_aio.watchdog"
BOUND = 60.0  # seconds: only a broken watchdog waits this long


class Reports(logging.Handler):
    """Keeps the watchdog's records; `warned` is set by its first WARNING."""

    def __init__(self) -> None:
        super().__init__(logging.DEBUG)
        self.records: list[logging.LogRecord] = []
        self.warned = threading.Event()

    def emit(self, record: logging.LogRecord) -> None:
        self.records.append(record)
        if record.levelno == logging.WARNING:
            self.warned.set()

    def at(self, level: int, where: str | None = None) -> list[str]:
        """The messages at ``level``; with ``where``, those about the block at that file:line."""
        said = [r.getMessage() for r in self.records if r.levelno == level]
        return said if where is None else [m for m in said if _names(m, where)]


def _names(message: str, where: str) -> bool:
    """Whether the WARNING, or the INFO at the block's end, is about the block at ``where``."""
    return f" blocks it at {where}. " in message or message.endswith(f" at {where})")


@pytest.fixture
def reports() -> Iterator[Reports]:
    handler = Reports()
    logger = logging.getLogger(WATCHDOG)
    logger.addHandler(handler)
    level, logger.level = logger.level, logging.DEBUG
    try:
        yield handler
    finally:
        logger.removeHandler(handler)
        logger.setLevel(level)


def _here() -> str:
    """``file:line`` of the caller's next line."""
    caller = inspect.currentframe().f_back  # type: ignore[union-attr]
    assert caller is not None
    return f"{caller.f_code.co_filename}:{caller.f_lineno + 1}"


def _watchdogs() -> list[threading.Thread]:
    return [t for t in threading.enumerate() if "loop watchdog" in t.name]


def _blocked(events: EventLog, where: str | None = None) -> list[ExecEvent]:
    """The loop.blocked events; with ``where``, those of the block at that file:line."""
    blocked = events.of_kind(EventKind.LOOP_BLOCKED)
    return [e for e in blocked if where in (None, e.data["location"])]


@action
async def crunch(robot: Robot, reports: Reports, where: list[str]) -> str:
    """Blocks the loop until the watchdog has spoken, then some more."""
    await robot.sleep(0)
    reports.warned.clear()
    where.append(_here())
    reports.warned.wait(BOUND)  # a real block: the loop thread waits here
    time.sleep(0.5)  # noqa: ASYNC251 (the same block goes on for five thresholds)
    return "done"


@pytest.mark.asyncio
async def test_a_block_is_reported_once_naming_the_action_its_line_and_stack(
    reports: Reports,
) -> None:
    events, where = EventLog(), list[str]()
    async with Robot(actions=[crunch], instruments=[events]) as robot:
        assert await robot.crunch(reports, where) == "done"
        await asyncio.sleep(0)  # the loop turned: the end of the block is out
    [warning] = reports.at(logging.WARNING, where[0])  # one, though it lasted 5 thresholds more
    assert re.match(r"the event loop has not turned for \d+\.\d{3} s: ", warning)
    assert f": action crunch#1 blocks it at {where[0]}. " in warning
    assert "robot.to_thread(fn, *args)" in warning
    stack = warning.split("The blocking stack (most recent call last):\n")[1]
    lines = stack.splitlines()
    assert lines[0].endswith(", in _run")  # the action's task, from its first frame
    body = lines.index(f'  File "{__file__}", line {where[0].rsplit(":", 1)[1]}, in crunch')
    assert (
        lines[body + 1]
        == "    reports.warned.wait(BOUND)  # a real block: the loop thread waits here"
    )
    assert lines[-2].endswith(", in wait")  # ... down to where the thread is
    [end] = reports.at(logging.INFO, where[0])
    assert end.startswith("the event loop turned again after ")
    assert end.endswith(f" s (blocked by action crunch#1 at {where[0]})")
    [event] = _blocked(events, where[0])
    assert (event.action, event.name) == (1, "crunch")
    assert event.data["blocker"] == "action crunch#1"
    assert event.data["location"] == where[0]
    assert event.data["threshold"] == 0.1
    assert event.data["stack"] == stack + "\n"
    duration = event.data["duration"]
    assert isinstance(duration, float)
    assert duration >= 0.1  # the probe waited a whole threshold unanswered
    assert f"after {duration:.3f} s" in end


def _wait_in_stdlib(reports: Reports) -> None:
    reports.warned.wait(BOUND)  # threading.py's frames are passed over, to this line


@action
async def crunch_in_helper(robot: Robot, reports: Reports, where: list[str]) -> None:
    reports.warned.clear()  # (a WARNING from before, of a loaded machine, does not count)
    where.append(_here())
    _wait_in_stdlib(reports)


@pytest.mark.asyncio
async def test_the_line_is_the_user_s_innermost_not_the_standard_library_s(
    reports: Reports,
) -> None:
    events, where = EventLog(), list[str]()
    async with Robot(actions=[crunch_in_helper], instruments=[events]) as robot:
        await robot.crunch_in_helper(reports, where)
    helper = inspect.getsourcelines(_wait_in_stdlib)[1] + 1
    [warning] = reports.at(logging.WARNING, f"{__file__}:{helper}")
    assert f"action crunch_in_helper#1 blocks it at {__file__}:{helper}. " in warning
    assert f"line {helper}, in _wait_in_stdlib" in warning
    assert 'threading.py", line' in warning  # the stack itself goes all the way in
    assert where[0] != f"{__file__}:{helper}"  # not the action's own line: the helper's
    [event] = _blocked(events, f"{__file__}:{helper}")
    assert event.name == "crunch_in_helper"


@pytest.mark.asyncio
async def test_a_block_outside_any_action_names_the_task_or_the_callback(
    reports: Reports,
) -> None:
    where: list[str] = []

    async def plain_task() -> None:
        reports.warned.clear()
        where.append(_here())
        reports.warned.wait(BOUND)

    events = EventLog()
    async with Robot(instruments=[events]):
        await asyncio.create_task(plain_task(), name="uploader")
        done = asyncio.get_running_loop().create_future()

        def callback() -> None:
            reports.warned.clear()
            where.append(_here())
            reports.warned.wait(BOUND)
            done.set_result(None)

        asyncio.get_running_loop().call_soon(callback)
        await done
    [first], [second] = (reports.at(logging.WARNING, line) for line in where)
    assert ": task 'uploader' blocks it at " in first
    assert ": a callback blocks it at " in second
    blocked = [event for line in where for event in _blocked(events, line)]
    assert [(e.action, e.name, e.data["blocker"]) for e in blocked] == [
        (None, None, "task 'uploader'"),
        (None, None, "a callback"),
    ]


@pytest.mark.asyncio
async def test_the_watchdog_thread_starts_and_stops_with_the_robot() -> None:
    before = set(threading.enumerate())
    robot = Robot()
    assert _watchdogs() == []  # nothing starts in __init__
    async with robot:
        [thread] = _watchdogs()
        assert thread.name == f"pyrobots_aio loop watchdog of {threading.current_thread().name}"
    assert not thread.is_alive()
    with pytest.raises(RuntimeError, match="inside"):
        async with robot:
            raise RuntimeError("inside")
    assert set(threading.enumerate()) == before


class _FailingBackend:
    async def start(self, robot: Robot) -> None:
        raise OSError("no robot on /dev/ttyUSB0")

    async def stop(self) -> None:
        raise AssertionError("never started")


@pytest.mark.asyncio
async def test_no_watchdog_thread_outlives_a_robot_that_failed_to_start() -> None:
    before = set(threading.enumerate())
    with pytest.raises(OSError, match="ttyUSB0"):
        async with Robot(backend=_FailingBackend()):
            pass
    assert set(threading.enumerate()) == before


@pytest.mark.asyncio
async def test_block_threshold_none_turns_the_watchdog_off(reports: Reports) -> None:
    events = EventLog()
    async with Robot(block_threshold=None, instruments=[events]) as robot:
        assert robot.block_threshold is None
        assert _watchdogs() == []
        time.sleep(0.3)  # noqa: ASYNC251 (a block nobody watches)
        await asyncio.sleep(0)
    assert reports.records == []
    assert _blocked(events) == []


@pytest.mark.parametrize(
    "value", [0, -0.1, 0.001, math.inf, math.nan, True, "0.1", [0.1]], ids=repr
)
def test_a_bad_block_threshold_is_refused_naming_it(value: object) -> None:
    with pytest.raises(ValueError, match=r"^block_threshold must be") as caught:
        Robot(block_threshold=value)  # type: ignore[arg-type]
    hint = " (a bool is not a number)" if value is True else ""
    assert str(caught.value) == (
        "block_threshold must be a number of seconds from 0.01 up, or None to turn the loop "
        f"watchdog off, got {value!r}{hint}"
    )


def test_the_threshold_is_a_number_of_seconds() -> None:
    assert Robot().block_threshold == 0.1
    assert Robot(block_threshold=2).block_threshold == 2.0
    with pytest.raises(AttributeError):
        Robot().block_threshold = 0.5  # type: ignore[misc]


@pytest.mark.parametrize(
    ("level", "said"),
    [(logging.WARNING, [logging.WARNING]), (logging.ERROR, [])],
    ids=["silent", "errors-only"],
)
@pytest.mark.asyncio
async def test_a_quiet_robot_s_watchdog_still_warns_unless_told_errors_only_and_records(
    reports: Reports, level: int, said: list[int]
) -> None:
    events = EventLog()
    async with Robot(instruments=[events], block_threshold=0.05) as robot:
        if level == logging.WARNING:
            robot.silent()  # pyRobots' loglevel(WARNING): a block report is what went wrong
        else:
            robot.loglevel(level)
        watch = robot._blockwatch
        assert watch is not None
        seen, report = threading.Event(), watch._report

        def reporting(probe: Any) -> None:  # (whatever the log shows)
            report(probe)
            seen.set()

        watch._report = reporting  # type: ignore[method-assign]
        where = _here()
        seen.wait(BOUND)  # a block until it is seen
        await asyncio.sleep(0)
    ours = [r.levelno for r in reports.records if _names(r.getMessage(), where)]
    assert ours == said  # not the INFO "turned again"
    assert len(_blocked(events, where)) == 1


# -- virtual time: a block is real time; a jump of the clock is not a block ------------------


@action
async def stall(robot: Robot, reports: Reports, where: list[str]) -> float:
    await robot.sleep(1.0)
    reports.warned.clear()
    where.append(_here())
    reports.warned.wait(BOUND)
    return robot.time()


@pytest.mark.asyncio
async def test_a_block_in_lockstep_simulation_is_reported_and_takes_no_virtual_time(
    sim_robot: Robot, robot_events: EventLog, reports: Reports
) -> None:
    t0, where = sim_robot.time(), list[str]()
    assert await stall(sim_robot, reports, where) == t0 + 1.0  # it took no simulated time
    await sim_robot.sleep(0.1)
    [warning] = reports.at(logging.WARNING, where[0])
    assert ": action stall#1 blocks it at " in warning
    [event] = _blocked(robot_events, where[0])
    assert event.time == t0 + 1.0  # stamped with the loop's clock where it blocked
    assert event.data["duration"] >= 0.1  # type: ignore[operator]  # real seconds


@pytest.mark.virtual_time
@pytest.mark.asyncio
async def test_virtual_time_jumping_ahead_is_not_a_block(reports: Reports) -> None:
    events = EventLog()
    async with Robot(instruments=[events]) as robot:
        await robot.sleep(3600.0)
        assert robot.time() >= 3600.0
    assert reports.records == []
    assert _blocked(events) == []


async def _busy_program(block_threshold: float | None) -> tuple[list[tuple[str, float]], int]:
    """Actions sleeping in virtual time, each step a few ms of real work: busy, never blocked."""

    @action
    async def worker(robot: Robot, period: float) -> None:
        for _ in range(25):
            end = time.perf_counter() + 0.002  # 2 ms of real work, far below a threshold
            while time.perf_counter() < end:
                pass
            await robot.sleep(period)

    events = EventLog()
    async with Robot(actions=[worker], instruments=[events], block_threshold=block_threshold) as r:
        watch = r._blockwatch
        await asyncio.gather(*(r.worker(0.01 * (i + 1)) for i in range(8)))
    seen = [  # (a loaded machine may stall the loop: a report of it is not the program's)
        (f"{e.kind.value} {e.name}#{e.action}", e.time)
        for e in events
        if e.kind is not EventKind.LOOP_BLOCKED
    ]
    return seen, 0 if watch is None else watch.beats + watch.probes


def test_the_watchdog_s_beats_and_probes_change_nothing_a_virtual_time_program_sees() -> None:
    watched, looks = run(_busy_program, 0.02)
    unwatched, _ = run(_busy_program, None)
    assert looks > 0  # the loop beat (or was probed) while it ran...
    assert watched == unwatched  # ...and every event came at the same virtual time


# -- recordings carry the event through ------------------------------------------------------


@pytest.mark.parametrize("recorder", [JsonlRecorder, McapRecorder])
@pytest.mark.asyncio
async def test_the_block_is_in_the_recording_and_replay_takes_it(
    recorder: type[JsonlRecorder | McapRecorder], tmp_path: Path, reports: Reports
) -> None:
    path = tmp_path / f"run.{'jsonl' if recorder is JsonlRecorder else 'mcap'}"
    robot, where = Robot(actions=[crunch]), list[str]()
    with recorder(path).attach(robot):
        async with robot:
            await robot.crunch(reports, where)
            await asyncio.sleep(0)
    recording = load(path)
    [event] = [
        e
        for e in recording.events
        if e.kind is EventKind.LOOP_BLOCKED and e.data["location"] == where[0]
    ]
    assert (event.action, event.name) == (1, "crunch")
    assert event.data["location"] == where[0]
    assert f"line {where[0].rsplit(':', 1)[1]}, in crunch" in str(event.data["stack"])
    assert summarize(recording).outcomes.succeeded == 1
    assert "crunch" in render_timeline_html(recording)
