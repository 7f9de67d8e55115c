"""BlockWatch on a bare asyncio loop: a turning loop is left alone, each block is one event.

Every test runs both ways of watching: on the kernel's timers (Linux: the
loop beats, the thread sleeps until it misses a beat) and polling (where
there are none, or the loop has no readers).
"""

from __future__ import annotations

import asyncio
import gc
import inspect
import logging
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path
from subprocess import PIPE
from typing import TYPE_CHECKING

import pytest

from pyrobots_aio import EventKind, ExecEvent
from pyrobots_aio._core import _blockwatch
from pyrobots_aio._core._blockwatch import Blocker, BlockWatch, RunQueue
from pyrobots_aio._core._instrument import Instruments
from pyrobots_aio._core._logging import LogScope
from signal_support import HANG_GUARD, started

if TYPE_CHECKING:
    from collections.abc import Callable, Iterator

BOUND = 60.0
LOADED = 0.1
"""The default threshold: a loaded machine (a virtual one above all) stalls a process for
tens of milliseconds now and then, which a smaller one would report."""


class Kept:
    def __init__(self) -> None:
        self.events: list[ExecEvent] = []

    def on_event(self, event: ExecEvent) -> None:
        self.events.append(event)


class Warned(logging.Handler):
    def __init__(self) -> None:
        super().__init__(logging.DEBUG)
        self.records: list[logging.LogRecord] = []
        self.warned = threading.Event()

    def emit(self, record: logging.LogRecord) -> None:
        self.records.append(record)
        if record.levelno >= logging.WARNING:
            self.warned.set()


@pytest.fixture
def warned() -> Iterator[Warned]:
    handler = Warned()
    logger = logging.getLogger("pyrobots_aio.watchdog")
    logger.addHandler(handler)
    yield handler
    logger.removeHandler(handler)


@pytest.fixture(autouse=True)
def _frozen_heap() -> Iterator[None]:
    """The objects of the tests before are out of the garbage collector's way meanwhile.

    In a full run the heap holds millions of them, and a full collection that a test's
    own allocations set off walks them all: 0.9 s of a loop thread's CPU once, beside a
    CPU hog on each core. That is a real block, rightly reported, but of the run, not of
    what these tests check (a 0.1 s threshold).
    """
    gc.collect()
    gc.freeze()
    try:
        yield
    finally:
        gc.unfreeze()


@pytest.fixture(autouse=True, params=["timers", "polling"])
def mode(request: pytest.FixtureRequest, monkeypatch: pytest.MonkeyPatch) -> str:
    """How the watchdog watches: kernel timers, or (as where there are none) polling."""
    if request.param == "polling":

        def no_timers(*, blocking: bool = True) -> _blockwatch.Timer:
            raise OSError("no timerfd here: kernel timers as file descriptors are Linux's")

        monkeypatch.setattr(_blockwatch, "Timer", no_timers)
    return str(request.param)


def _watch(threshold: float, blocker: object = None) -> tuple[BlockWatch, Kept]:
    kept, hub = Kept(), Instruments()
    hub.add(kept)
    log = LogScope().logger("pyrobots_aio.watchdog")
    return BlockWatch(asyncio.get_running_loop(), threshold, log, hub, blocker), kept  # type: ignore[arg-type]


class Looks:
    """Counts the watchdog thread's looks at the loop, where it asks whether the loop turns.

    Each look of polling, and each look of the kernel timers' thread at a loop that
    stopped beating (or missed its deadline).
    """

    def __init__(self, watch: BlockWatch) -> None:
        self.count = 0
        self._turning = watch._turning
        self._wanted = 0
        self._reached = threading.Event()
        watch._turning = self._look  # type: ignore[method-assign]

    def _look(self) -> bool:
        self.count += 1  # (the watchdog's thread only)
        if self.count >= self._wanted:
            self._reached.set()
        return self._turning()

    async def idle_until(self, count: int) -> None:
        """Leave the loop idle in its selector until the thread has looked ``count`` times.

        The loop waits for a thread of asyncio's pool: its wake-up is one callback.
        """
        self._wanted = count
        assert await asyncio.to_thread(self._reached.wait, BOUND)


@pytest.mark.asyncio
async def test_an_idle_loop_is_not_probed(mode: str) -> None:
    descriptors = set(os.listdir("/proc/self/fd"))
    watch, kept = _watch(LOADED)
    looks = Looks(watch)
    watch.start()
    try:
        await looks.idle_until(5)  # five looks at a loop waiting in its selector
    finally:
        watch.stop()
    assert watch.probes <= 1  # (one could catch the loop in the callback that wakes it)
    if mode == "timers":  # an idle loop stops beating at once; the thread looks instead
        assert watch.beats <= 2
        assert watch.wakes >= 5
    assert (watch.blocks, kept.events) == (0, [])
    assert set(os.listdir("/proc/self/fd")) == descriptors  # its timers are closed


async def _busy_until(done: Callable[[], bool]) -> None:
    """Turn the loop without a pause (short steps of pure Python) until ``done()``."""
    give_up = time.monotonic() + BOUND
    while not done():
        assert time.monotonic() < give_up, "the watch never got to it"
        sum(range(1_000))
        await asyncio.sleep(0)


@pytest.mark.asyncio
async def test_a_busy_loop_that_turns_carries_the_watch_and_is_never_reported(mode: str) -> None:
    # Timers: the loop beats, and the thread sleeps in the kernel. Polling: the thread looks
    # (and probes the loop when it finds it inside a callback), answered in time. How
    # seldom the thread wakes meanwhile depends on the CPU the machine gives each thread:
    # that is the bench's figure (watchdog_wakes_per_100_beats_busy).
    watch, kept = _watch(LOADED)
    looks = Looks(watch)
    watch.start()
    try:
        await _busy_until(lambda: (watch.beats if mode == "timers" else looks.count) >= 10)
    finally:
        watch.stop()
    assert (watch.blocks, kept.events) == (0, [])


@pytest.mark.asyncio
async def test_a_loop_busy_after_idling_beats_again(mode: str) -> None:
    watch, kept = _watch(LOADED)
    looks = Looks(watch)
    watch.start()
    try:
        await looks.idle_until(3)  # idle: the beat stops, the thread looks
        idle_beats, idle_looks = watch.beats, looks.count
        # busy: one look sees it (its CPU time), and it beats again (polling: looks on)
        await _busy_until(
            lambda: (
                (watch.beats - idle_beats if mode == "timers" else looks.count - idle_looks) >= 3
            )
        )
    finally:
        watch.stop()
    assert (watch.blocks, kept.events) == (0, [])
    if mode == "timers":
        assert idle_beats <= 2


@pytest.mark.asyncio
async def test_stop_right_after_a_block_emits_its_event_once(warned: Warned) -> None:
    watch, kept = _watch(0.05)
    watch.start()
    assert warned.warned.wait(BOUND)  # blocks this very callback until it is reported
    watch.stop()  # before the loop turned: stop() emits the event itself
    assert [e.kind for e in kept.events] == [EventKind.LOOP_BLOCKED]
    await asyncio.sleep(0.01)  # the loop turns: the queued emission finds it done
    [event] = kept.events
    assert event.data["blocker"] == f"task {asyncio.current_task().get_name()!r}"  # type: ignore[union-attr]
    assert not watch._thread.is_alive()


@pytest.mark.asyncio
async def test_a_loop_waiting_in_its_selector_past_its_beat_is_not_blocked(
    monkeypatch: pytest.MonkeyPatch, warned: Warned, mode: str
) -> None:
    # The loop never gets to its beat (its reader is gone) while it waits in its selector
    # with nothing to do: each time the thread wakes, the beat is overdue, as when a loop
    # thread back from its select waits for the GIL on a loaded machine. It is not blocked.
    if mode != "timers":
        pytest.skip("polling has no beat to miss")
    loop = asyncio.get_running_loop()
    looked = loop.create_future()

    def settle() -> None:
        if not looked.done():
            looked.set_result(None)

    class Deadline(_blockwatch.Timer):
        def wait(self) -> int:
            # The thread is back for its next wait: after a report, or enough wakes.
            if threading.current_thread() is watch._thread and (watch.blocks or watch.wakes >= 4):
                loop.call_soon_threadsafe(settle)
            return super().wait()

    monkeypatch.setattr(_blockwatch, "Timer", Deadline)
    watch, kept = _watch(LOADED)
    watch.start()
    assert watch._beat_timer is not None
    loop.remove_reader(watch._beat_timer.fd)
    try:
        await looked  # in the selector, nothing else scheduled
    finally:
        watch.stop()
    assert (watch.beats, watch.blocks, kept.events) == (0, 0, [])
    assert not warned.warned.is_set()


@pytest.mark.asyncio
async def test_the_blocker_hook_names_the_culprit(warned: Warned) -> None:
    watch, kept = _watch(0.05, lambda task: Blocker("the arm driver", 7, "reach"))
    watch.start()
    try:
        assert warned.warned.wait(BOUND)
        await asyncio.sleep(0)
    finally:
        watch.stop()
    assert ": the arm driver blocks it at " in warned.records[0].getMessage()
    [event] = kept.events
    assert (event.action, event.name, event.data["blocker"]) == (7, "reach", "the arm driver")


@pytest.mark.asyncio
async def test_a_failure_of_the_watchdog_itself_is_logged_not_silent(warned: Warned) -> None:
    def broken(task: object) -> Blocker:
        raise LookupError("no such action table")

    watch, _ = _watch(0.05, broken)
    watch.start()
    try:
        assert warned.warned.wait(BOUND)  # its ERROR ends the block
        await asyncio.sleep(0)
    finally:
        watch.stop()
    [record] = warned.records
    assert record.getMessage() == "the loop watchdog failed; the loop is no longer watched"
    assert record.exc_info is not None
    assert isinstance(record.exc_info[1], LookupError)


def test_the_run_queue_reads_this_threads_wait_for_a_cpu_from_a_kept_file() -> None:
    queue = RunQueue(threading.get_native_id())
    cpus = os.sched_getaffinity(0)
    cpu = min(cpus)
    # A busy process on this thread's only CPU: the thread waits for it, and the figure grows.
    rival = subprocess.Popen(
        [
            sys.executable,
            "-c",
            f"import os; os.sched_setaffinity(0, {{{cpu}}}); print(flush=True)\nwhile True: pass",
        ],
        stdout=PIPE,
    )
    try:
        assert rival.stdout is not None
        assert rival.stdout.readline() == b"\n"  # it spins on that CPU from now on
        initial = queue.waited()
        assert initial is not None  # Linux: the scheduler's statistics
        assert initial >= 0.0
        os.sched_setaffinity(0, {cpu})  # (this thread only)
        last, give_up = initial, time.monotonic() + BOUND
        while last == initial:  # the same file, read again: fresh figures each time
            assert time.monotonic() < give_up, "never waited for the CPU the rival spins on"
            sum(range(20_000))
            now = queue.waited()
            assert now is not None
            assert now >= last
            last = now
    finally:
        os.sched_setaffinity(0, cpus)
        rival.kill()
        rival.communicate()
        queue.close()
    assert queue.waited() is None  # closed
    assert RunQueue(2**31 - 1).waited() is None  # no such thread


@pytest.mark.parametrize("queued", [True, False], ids=["waiting-for-a-cpu", "blocking"])
@pytest.mark.asyncio
async def test_time_the_loop_waits_for_a_cpu_is_not_a_block(
    monkeypatch: pytest.MonkeyPatch, warned: Warned, queued: bool
) -> None:
    # The same stall of the loop thread, two ways. The kernel's counter of the loop
    # thread's waits for a CPU stands in for a loaded machine: while the thread "waits for
    # a CPU" all along, its wait grows with the wall clock, and no block is reported. Left
    # alone, it says the thread slept: a block, reported once. (The watchdog thread's own
    # counter is real either way: the machine may be loaded for real.)
    origin, counter = time.monotonic(), _blockwatch.RunQueue.waited
    watch, kept = _watch(0.05)

    def waited(self: RunQueue) -> float | None:
        return time.monotonic() - origin if self is watch._queue else counter(self)

    if queued:
        monkeypatch.setattr(_blockwatch.RunQueue, "waited", waited)
    watch.start()
    try:
        here = f"{__file__}:{inspect.currentframe().f_lineno + 1}"  # type: ignore[union-attr]
        time.sleep(0.3)  # noqa: ASYNC251  # the loop thread stalls; the counter says why
        await asyncio.sleep(0.01)
    finally:
        watch.stop()
    # (a loaded machine may stall the loop elsewhere: a report of the machine, not of this)
    reported = [r for r in warned.records if f" blocks it at {here}. " in r.getMessage()]
    assert len(reported) == (0 if queued else 1)
    assert len([e for e in kept.events if e.data["location"] == here]) == len(reported)
    if queued:
        assert (watch.blocks, kept.events, warned.warned.is_set()) == (0, [], False)


STOPPED = """
import asyncio, logging, os, signal, sys, threading, time
from pyrobots_aio._core import _blockwatch
from pyrobots_aio._core._blockwatch import BlockWatch
from pyrobots_aio._core._instrument import Instruments
from pyrobots_aio._core._logging import LogScope

logging.basicConfig(format="%(levelname)s %(message)s")
POLLING = sys.argv[1] == "polling"
if POLLING:
    def no_timers(*, blocking=True):
        raise OSError("no timerfd here")
    _blockwatch.Timer = no_timers


def spin(seconds, until=lambda: False):
    # Busy for ``seconds`` of this thread's CPU time (or until ``until()``): never a block.
    end = time.thread_time() + seconds
    while time.thread_time() < end and not until():
        pass
    return until()


def awaiting_the_answer(thread):
    # Whether the watchdog's thread waits for the loop's answer to its probe (in the kernel).
    frame, names = sys._current_frames().get(thread.ident), []
    while frame is not None:
        names.append(frame.f_code.co_name)
        frame = frame.f_back
    return names[:1] == ["wait"] and "_wait_while_scheduled" in names


async def main():
    loop = asyncio.get_running_loop()
    done = asyncio.Event()
    loop.add_reader(sys.stdin.fileno(), done.set)
    # 0.3 s: half the stop, and more than a loaded virtual machine's stolen time.
    watch = BlockWatch(loop, 0.3, LogScope().logger("pyrobots_aio.watchdog"), Instruments())
    probed, post = threading.Event(), watch._post

    def posting(probe, answer):
        posted = post(probe, answer)
        probed.set()
        return posted

    watch._post = posting
    watch.start()
    print("busy", flush=True)
    for _ in range(3):
        # Busy callbacks, never a block, until one is stopped in the middle. Timers:
        # 5 ms of CPU time each, for 0.3 s. Polling: while the watchdog's thread waits
        # for the answer to a probe it posted in that very callback (the only time a stop
        # can matter to polling; answered once the loop turns, after the callback). The
        # thread gets the GIL either at the loop's select (it finds the loop turning) or
        # after the 5 ms switch interval (in a callback: a probe): callbacks of up to
        # 30 ms make the probe the likely case.
        since = time.monotonic()
        while True:
            probed.clear()
            if POLLING:
                ready = spin(0.03, probed.is_set) and spin(
                    0.02, lambda: awaiting_the_answer(watch._thread)
                )
            else:
                spin(0.005)
                ready = time.monotonic() - since >= 0.3
            if ready:
                break
            await asyncio.sleep(0)
        print("stopping", flush=True)
        os.kill(os.getpid(), signal.SIGSTOP)  # the whole process, until the test continues it
        # Back, the callback goes on a while: the watchdog's thread, late for its deadline,
        # looks at the loop before it turns (and its probe is answered).
        spin(0.05)
        await asyncio.sleep(0)
    await done.wait()
    watch.stop()
    print(watch.blocks, flush=True)


asyncio.run(main())
"""


def _state(pid: int) -> str:
    """The process's state letter (``T``: stopped), from ``/proc/<pid>/stat``."""
    stat = Path(f"/proc/{pid}/stat").read_text()
    return stat[stat.rindex(")") + 2]


def test_a_process_that_was_stopped_is_not_reported_as_blocked(tmp_path: Path, mode: str) -> None:
    # SIGSTOP in the middle of a callback, 0.6 s, SIGCONT: the clock jumps, and both
    # threads go on at once; the watchdog's deadline (polling: its wait for the loop's
    # answer) expired meanwhile. It used to blame the callback the loop was in ("a
    # callback blocks it at <file:line>"). The process stops itself where a stop
    # matters, so the test sees the defect every time, however loaded the machine.
    script = tmp_path / "stopped.py"
    script.write_text(STOPPED, encoding="utf-8")
    with started(
        [sys.executable, str(script), mode], stdin=PIPE, stdout=PIPE, stderr=PIPE
    ) as child:
        assert child.stdout is not None
        assert child.stdout.readline() == "busy\n"
        for _ in range(3):
            assert child.stdout.readline() == "stopping\n"
            deadline = time.monotonic() + HANG_GUARD
            while _state(child.pid) != "T" and time.monotonic() < deadline:
                time.sleep(0.001)
            time.sleep(0.6)  # stopped (at least this long: twice the threshold)
            child.send_signal(signal.SIGCONT)
        out, err = child.communicate("done\n", timeout=HANG_GUARD)
    assert (child.returncode, out, err) == (0, "0\n", "")
