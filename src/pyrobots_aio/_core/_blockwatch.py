"""A watchdog thread that notices when the event loop stops turning (DESIGN.md §13).

asyncio cannot interrupt code that never awaits (pyRobots' trace hook could):
a ``time.sleep``, a blocking socket or a long computation inside an action
freezes every action, monitor and the simulation. `BlockWatch` cannot stop
it either, but it says so, at once, with the culprit: one WARNING naming the
action (or task, or callback) that blocks the loop, the ``file:line`` where it
blocks and the loop thread's stack at that moment; and, once the loop turns
again, a `EventKind.LOOP_BLOCKED` event for the recorders with the whole
duration (and an INFO line).

How it watches, without costing the loop (Linux):

- The loop beats: a kernel timer (`Timer`, a ``timerfd``) becomes readable
  every ``threshold / 2``, and the loop's reader for it (a ready callback,
  like any I/O) re-arms a second timer, the deadline, to expire
  ``threshold`` after the next beat falls due.
- The watchdog thread blocks reading the deadline: in the kernel, without
  the GIL. While the loop turns, the deadline never expires and the thread
  never wakes, however busy the loop (waking a Python thread takes the GIL,
  which a busy loop hands on only at its next ``select``: a thread that
  polled would pay for that at every look, and the loop with it).
- The deadline expires: the loop has not run its beat for ``threshold``
  after it fell due. Time the loop thread spent waiting for a CPU since its
  last beat (other processes keeping both cores busy: Linux's
  ``/proc/self/task/<tid>/schedstat``) does not count: the deadline is
  pushed back by that much, so that a loaded machine is not reported as
  blocking code.
- A loop found outside any callback then (waiting in its selector, its
  thread woken for the beat but not yet holding the GIL) is not blocked
  either: the thread watches afresh from there.
- Otherwise the thread reads the loop thread's stack there and then, logs
  the WARNING, and waits (on a callback it posts) for the loop to turn: one
  report per block, however long it lasts.

A process that stands still as a whole (``SIGSTOP`` then ``SIGCONT``, a
paused virtual machine) is not blocked either, though the clock jumps ahead
meanwhile: the thread tells it by waking late, not for want of a CPU, while
the loop thread did not run either (see `BlockWatch._stood_still`), and then
watches afresh. A callback that blocks does not make the thread late (one
that sleeps leaves the CPU and the GIL to it), or runs meanwhile (one that
holds the GIL the thread needs to wake).

So a block is reported between ``threshold`` and ``1.5 * threshold`` after it
began (plus the thread's wake-up latency); blocks shorter than ``threshold``
are not reported. An idle loop wakes ``2 / threshold`` times a second for its
beat (tens of microseconds each).

Elsewhere (no ``timerfd``, or a loop without ``add_reader``) the thread polls
instead: every ``threshold / 2`` it looks at the loop thread's innermost
frame (``sys._current_frames``); a loop waiting in its selector, or busy in
its own machinery (``_run_once`` with no callback running), is turning. When
the loop is inside a callback, the thread probes it: it posts a callback that
stamps the time, and waits up to ``threshold`` (not counting the loop
thread's waits for a CPU) for it. Loops other than asyncio's own (uvloop)
have no Python frame to tell idle from busy: they are probed every time.

Time here is real (``time.monotonic``), never the loop's clock: a block is
real, and a virtual-time loop that jumps ahead is not blocked. Beats and
probes are plain ready callbacks: they take no virtual time and change no
timer's order.
"""

from __future__ import annotations

import asyncio
import contextlib
import os
import sys
import sysconfig
import threading
import time
import traceback
from asyncio import base_events, events
from dataclasses import dataclass
from typing import TYPE_CHECKING

from ._events import LoopBlocked
from ._numbers import finite
from ._timerfd import Timer

if TYPE_CHECKING:
    from collections.abc import Callable, Iterator
    from types import FrameType

    from ._instrument import Instruments
    from ._logging import ScopedLogger

DEFAULT_BLOCK_THRESHOLD = 0.1
"""Seconds the loop may go without turning before the watchdog reports it."""
IDLE_SHARE = 0.2
"""A loop busy less than this share of the time between two beats stops beating (Linux)."""
MIN_BLOCK_THRESHOLD = 0.01
"""The smallest threshold: the thread looks twice per threshold, so less would cost CPU."""
STILL_SHARE = 0.1
"""A share of the threshold: the thread woke this much late, and the loop thread ran as
little meanwhile, if the process stood still (see `BlockWatch._stood_still`)."""
JOIN_BOUND = 5.0
"""Seconds `BlockWatch.stop` waits for the thread (only a stuck log handler could need it)."""


class RunQueue:
    """How long a thread of this process has waited for a CPU so far (Linux).

    The scheduler's statistics: the second field of the thread's
    ``schedstat`` (nanoseconds spent runnable but not running), read from a
    file kept open (about 1 µs a read; opening it each time costs ten times
    that, and a loop's beat reads it).

    Examples:
        >>> import threading
        >>> queue = RunQueue(threading.get_native_id())
        >>> waited = queue.waited()
        >>> waited is None or waited >= 0.0
        True
        >>> queue.close()
        >>> queue.waited() is None
        True
    """

    def __init__(self, native_id: int | None) -> None:
        self._fd: int | None = None
        if native_id is not None:  # (None: closed from the start)
            with contextlib.suppress(OSError):  # not Linux, or no such thread
                self._fd = os.open(f"/proc/self/task/{native_id}/schedstat", os.O_RDONLY)

    def waited(self) -> float | None:
        """Seconds the thread has waited for a CPU so far (None: unknown, or closed)."""
        if self._fd is None:
            return None
        try:
            return int(os.pread(self._fd, 64, 0).split()[1]) / 1e9
        except (OSError, IndexError, ValueError):
            return None

    def close(self) -> None:
        """Close the file (`waited` answers None from then on)."""
        fd, self._fd = self._fd, None
        if fd is not None:
            os.close(fd)


_RUN_ONCE = base_events.BaseEventLoop._run_once.__code__  # type: ignore[attr-defined]  # one iteration
_CALLBACK = events.Handle._run.__code__  # one callback of an iteration (timers' too)
_LIBRARY = tuple(  # code outside the user's: the standard library and installed packages
    {
        os.path.join(sysconfig.get_paths()[key], "")
        for key in ("stdlib", "platstdlib", "purelib", "platlib")
    }
)


def check_block_threshold(value: object) -> float | None:
    """Return ``value`` as a threshold in seconds, or None (no watchdog).

    Raises:
        ValueError: Not None nor a finite number of seconds of at least
            `MIN_BLOCK_THRESHOLD`; the message names the value and the fix.

    Examples:
        >>> check_block_threshold(0.25), check_block_threshold(None)
        (0.25, None)
    """
    if value is None:
        return None
    return finite(
        "block_threshold",
        value,
        low=MIN_BLOCK_THRESHOLD,
        must=f"a number of seconds from {MIN_BLOCK_THRESHOLD} up, or None to turn the loop "
        "watchdog off",
    )


@dataclass(frozen=True, slots=True)
class Blocker:
    """What runs on the loop while it is blocked.

    Attributes:
        label: How the report names it (``"action crunch#3"``, ``"task 'x'"``).
        action: The id of the blocking action, if it is one.
        name: The name of the blocking action, if it is one.
        frame: The outermost frame of its code (an action's body), to look
            for the blocking ``file:line`` from there inwards.
    """

    label: str
    action: int | None = None
    name: str | None = None
    frame: FrameType | None = None


class _Probe:
    """One question to the loop: "do you turn?" (posted by the thread, answered by the loop)."""

    __slots__ = ("answered", "loop_time", "posted")

    def __init__(self, posted: float, loop_time: float) -> None:
        self.posted = posted
        self.loop_time = loop_time
        self.answered: float | None = None


@dataclass(frozen=True, slots=True, eq=False)  # each report is itself (list.remove)
class _Report:
    """A block as the thread saw it, for the event the loop emits once it turns again."""

    probe: _Probe
    label: str
    action: int | None
    name: str | None
    location: str | None
    stack: str


class BlockWatch:
    """Watch ``loop`` from a thread of its own; report when it stops turning.

    Create and `start` it on the loop's thread; `stop` it there too (it joins
    the thread, so nothing outlives it).

    Args:
        loop: The event loop to watch (running in the calling thread).
        threshold: Seconds without turning that make a block (real time).
        log: Where the WARNING (and the INFO line at the end of a block) go.
        instruments: Where the `EventKind.LOOP_BLOCKED` event goes.
        blocker: Called in the watchdog thread with the task running on the
            blocked loop (None: a plain callback); returns the action it runs,
            if any. It must only read.

    Examples:
        >>> import asyncio, logging, time
        >>> from pyrobots_aio._core._instrument import Instruments
        >>> from pyrobots_aio._core._logging import LogScope
        >>> async def main() -> list[str]:
        ...     events = []
        ...     class Keep:
        ...         def on_event(self, event: ExecEvent) -> None:
        ...             events.append(event.kind.value)
        ...     hub = Instruments()
        ...     hub.add(Keep())
        ...     log = LogScope().logger("pyrobots_aio.watchdog")
        ...     watch = BlockWatch(asyncio.get_running_loop(), 0.05, log, hub)
        ...     watch.start()
        ...     time.sleep(0.3)  # a block (never do this in an action)
        ...     await asyncio.sleep(0.01)  # the loop turns: the event is emitted
        ...     watch.stop()
        ...     return events
        >>> asyncio.run(main())
        ['loop.blocked']
    """

    def __init__(
        self,
        loop: asyncio.AbstractEventLoop,
        threshold: float,
        log: ScopedLogger,
        instruments: Instruments,
        blocker: Callable[[asyncio.Task[object] | None], Blocker | None] | None = None,
    ) -> None:
        self.threshold = threshold
        self.blocks = 0
        """How many blocks were reported so far."""
        self.beats = 0
        """How many times the loop beat (Linux: the loop's side of the watch)."""
        self.wakes = 0
        """How many times the thread woke on an expired deadline (the loop missed its beat)."""
        self.probes = 0
        """How many times the loop was probed (polling: it was inside a callback when looked at)."""
        self._loop = loop
        self._log = log
        self._instruments = instruments
        self._blocker = blocker
        self._loop_thread = threading.get_ident()
        self._loop_native_id = threading.get_native_id()
        self._cond = threading.Condition()
        self._stopping = False
        # Reported blocks whose event is not out yet: the loop emits each once it turns (a
        # second block may be reported before it does), or stop() does.
        self._pending: list[_Report] = []
        self._period = threshold / 2
        self._beat_timer: Timer | None = None
        self._deadline: Timer | None = None
        self._beat_at = time.monotonic()
        self._beat_cpu = 0.0
        self._beat_queued: float | None = None
        self._queue = RunQueue(None)  # opened by start(), closed by stop()
        self._own_queue = RunQueue(None)  # the thread's own: opened and closed by it
        self._beating = False  # the loop's side (while it is busy) or the thread's looks
        try:  # the loop thread's CPU clock, for the thread to tell an idle loop from a busy one
            self._loop_clock: int | None = time.pthread_getcpuclockid(self._loop_thread)
        except (AttributeError, OSError):
            self._loop_clock = None
        self._thread = threading.Thread(
            target=self._watch,
            name=f"pyrobots_aio loop watchdog of {threading.current_thread().name}",
            daemon=True,  # never holds the interpreter's exit, whatever happens
        )

    # -- the loop's side -------------------------------------------------------

    def start(self) -> None:
        """Start the beat (where there are kernel timers) and the thread."""
        self._queue = RunQueue(self._loop_native_id)
        try:
            beat, deadline = Timer(blocking=False), Timer()
        except OSError:  # not Linux: the thread polls
            pass
        else:
            try:
                self._loop.add_reader(beat.fd, self._beat, beat, deadline)
            except NotImplementedError:  # a loop without readers (Windows' proactor)
                beat.close()
                deadline.close()
            else:
                self._beat_timer, self._deadline = beat, deadline
                self._start_beating()
        self._thread.start()

    def stop(self) -> None:
        """Stop and join the thread; emit the event of a block that ended but is not out yet."""
        beat, deadline = self._beat_timer, self._deadline
        if beat is not None and not self._loop.is_closed():
            self._loop.remove_reader(beat.fd)
        with self._cond:
            self._stopping = True
            self._cond.notify_all()
        if deadline is not None:
            deadline.arm(0)  # the thread's read returns now
        # The thread leaves its waits at once; only a report being logged can hold it.
        self._thread.join(JOIN_BOUND)
        if self._thread.is_alive():
            self._log.error(
                "the loop watchdog thread did not stop within %s s (a log handler stuck?)",
                JOIN_BOUND,
            )
        else:  # the thread reads the deadline and the run queue no more
            self._queue.close()
            if deadline is not None and beat is not None:
                beat.close()
                deadline.close()
        for report in list(self._pending):
            self._ended(report)

    def _start_beating(self) -> None:
        """The loop is busy (or starts): it beats from now on, and the thread sleeps."""
        beat, deadline = self._beat_timer, self._deadline
        if self._beating or beat is None or deadline is None or self._stopping:
            return
        self._beating = True
        self._beat_queued = self._queue.waited()
        self._beat_cpu = time.thread_time()
        self._beat_at = time.monotonic()
        beat.arm(self._period, self._period)
        deadline.arm(self._period + self.threshold)

    def _beat(self, beat: Timer, deadline: Timer) -> None:
        """The loop turns (the reader of ``beat``): push the deadline back.

        A loop that was mostly idle since its last beat stops beating: waking
        it for nothing would cost more than the thread's looks, which take the
        GIL at once from an idle loop.
        """
        beat.wait()  # the expiries so far (none if it was read already)
        self.beats += 1
        now, cpu = time.monotonic(), time.thread_time()  # (this is the loop's thread)
        queued = self._queue.waited()
        busy = _share(cpu - self._beat_cpu, now - self._beat_at, _waited(queued, self._beat_queued))
        self._beat_queued = queued
        self._beat_cpu, self._beat_at = cpu, now
        if busy < IDLE_SHARE:  # the thread looks from now on, the first time in half a threshold
            self._beating = False
            beat.disarm()
            deadline.arm(self._period)
        else:
            deadline.arm(self._period + self.threshold)

    def _answer_and_beat(self, probe: _Probe) -> None:
        self._answer(probe)
        self._start_beating()

    def _answer(self, probe: _Probe) -> None:
        with self._cond:
            probe.answered = time.monotonic()
            self._cond.notify_all()

    def _ended(self, report: _Report) -> None:
        """The loop turns again after a reported block: record it (on the loop's thread)."""
        if report not in self._pending:  # already done by stop()
            return
        self._pending.remove(report)
        probe = report.probe
        duration = (probe.answered or time.monotonic()) - probe.posted
        self._log.info(
            "the event loop turned again after %.3f s (blocked by %s at %s)",
            duration,
            report.label,
            report.location or "an unknown place",
        )
        if self._instruments:
            event = LoopBlocked(
                probe.loop_time,
                report.action,
                report.name,
                duration=duration,
                threshold=self.threshold,
                blocker=report.label,
                location=report.location,
                stack=report.stack,
            )
            self._instruments.emit(event)

    # -- the thread's side -----------------------------------------------------

    def _watch(self) -> None:
        self._own_queue = RunQueue(threading.get_native_id())
        try:
            if self._deadline is None:
                self._poll()
            else:
                self._wait_on(self._deadline)
        except Exception:  # a bug here must not pass silently
            self._log.exception("the loop watchdog failed; the loop is no longer watched")
        finally:
            self._own_queue.close()

    def _wait_on(self, deadline: Timer) -> None:
        """Sleep until the loop misses its beat by ``threshold``; report it then (Linux)."""
        afresh = 0.0  # when the watch last began afresh (see below)
        while True:
            before = self._own_queue.waited()
            deadline.wait()  # in the kernel, without the GIL
            if self._stopping:
                return
            self.wakes += 1
            if not self._beating:  # a loop that was idle: look at it
                if not self._look_at_idle(deadline):
                    return
                continue
            # A process that stood still is not blocked; nor is a loop outside any callback
            # (in its selector: late to beat for want of the GIL, or it just stopped beating).
            # Either way a block can only begin from now on.
            if (
                self._stood_still(
                    deadline.expires, before, self._beat_at, self._beat_cpu, self._beat_queued
                )
                or self._turning()
            ):
                afresh = time.monotonic()
            # When the beat the loop missed fell due (or the watch began afresh).
            due = max(self._beat_at + self._period, afresh)
            queued = _waited(self._queue.waited(), self._beat_queued)
            rest = due + self.threshold + queued - time.monotonic()
            if rest > 0:  # it beat meanwhile, or its thread waited for a CPU: wait the rest
                deadline.arm(rest)
                continue
            probe = _Probe(due, self._loop.time())
            if not self._post(probe, self._answer):
                return
            self._report(probe)
            self._wait_for(probe, None)  # then its next beat arms the deadline again

    def _look_at_idle(self, deadline: Timer) -> bool:
        """Look at a loop that beats no more; False if it is closed.

        Waiting in its selector: look again in ``threshold / 2``. Inside a
        callback: probe it as polling does, and have it beat again (it is
        busy) when it answers.
        """
        now, cpu, queued = time.monotonic(), self._loop_cpu(), self._queue.waited()
        busy = _share(cpu - self._beat_cpu, now - self._beat_at, _waited(queued, self._beat_queued))
        self._beat_cpu, self._beat_at, self._beat_queued = cpu, now, queued
        # A busy loop lets the GIL go only at its selects, where this thread gets it and
        # finds it "turning": its CPU time tells it is busy (and must beat again).
        if busy < IDLE_SHARE and self._turning():
            deadline.arm(self._period)
            return True
        probe = _Probe(now, self._loop.time())
        self.probes += 1
        if not self._post(probe, self._answer_and_beat):
            return False
        if not self._wait_while_scheduled(probe):
            self._report(probe)
            self._wait_for(probe, None)
        return True

    def _loop_cpu(self) -> float:
        """The loop thread's CPU time so far (0.0 if unknown: then it always looks idle)."""
        return 0.0 if self._loop_clock is None else time.clock_gettime(self._loop_clock)

    def _poll(self) -> None:
        """Look at the loop every ``threshold / 2``; probe it when busy (no kernel timers)."""
        while self._rest(self._period):
            if self._turning():
                continue
            probe = _Probe(time.monotonic(), self._loop.time())
            self.probes += 1
            if not self._post(probe, self._answer):
                return
            if not self._wait_while_scheduled(probe):
                self._report(probe)
                self._wait_for(probe, None)

    def _post(self, probe: _Probe, answer: Callable[[_Probe], None]) -> bool:
        """Ask the loop to ``answer(probe)`` when it turns; False if the loop is closed."""
        try:
            self._loop.call_soon_threadsafe(answer, probe)
        except RuntimeError:  # the loop is closed: nothing left to watch
            return False
        return True

    def _rest(self, seconds: float) -> bool:
        """Wait ``seconds``; False if asked to stop meanwhile."""
        with self._cond:
            return not self._cond.wait_for(lambda: self._stopping, seconds)

    def _wait_for(self, probe: _Probe, timeout: float | None) -> bool:
        """Wait until the loop answers ``probe`` (or stop); False if ``timeout`` ran out first."""
        with self._cond:
            return self._cond.wait_for(
                lambda: probe.answered is not None or self._stopping, timeout
            )

    def _wait_while_scheduled(self, probe: _Probe) -> bool:
        """Wait for the loop's answer for ``threshold``, not counting its waits for a CPU.

        False: no answer though the loop thread could run (or slept) for
        ``threshold`` since the probe was posted. Time the whole process stood
        still does not count either: the wait begins afresh after it.
        """
        since, cpu, start = probe.posted, self._loop_cpu(), self._queue.waited()
        budget = self.threshold
        while True:
            before, until = self._own_queue.waited(), time.monotonic() + budget
            if self._wait_for(probe, budget):
                return True
            if self._stood_still(until, before, since, cpu, start):
                since, cpu, start = time.monotonic(), self._loop_cpu(), self._queue.waited()
            queued = _waited(self._queue.waited(), start)
            budget = since + self.threshold + queued - time.monotonic()
            if budget <= 0:
                return False

    def _stood_still(
        self, due: float, before: float | None, since: float, cpu: float, queued: float | None
    ) -> bool:
        """Whether the whole process stood still (stopped, its virtual machine paused).

        The thread, whose wait for a CPU was ``before`` when it began to wait,
        woke late after ``due``, and not for want of a CPU; and the loop
        thread, since ``since`` (when its CPU time was ``cpu`` and its wait
        for a CPU ``queued``), neither ran nor waited for a CPU for a while
        either: nothing of the process ran. A callback that blocks the loop
        does not make the thread late if it sleeps (the thread has the CPU and
        the GIL), and runs meanwhile if it holds the GIL.
        """
        if self._loop_clock is None:  # the loop's CPU time is unknown: it cannot tell
            return False
        now, still = time.monotonic(), STILL_SHARE * self.threshold
        if now - due - _waited(self._own_queue.waited(), before) <= still:
            return False
        idle = now - since - (self._loop_cpu() - cpu) - _waited(self._queue.waited(), queued)
        return idle > still

    def _turning(self) -> bool:
        """Whether the loop thread is outside any callback now (waiting, or between them)."""
        frame = sys._current_frames().get(self._loop_thread)
        while frame is not None:
            code = frame.f_code
            if code is _CALLBACK:
                return False
            if code is _RUN_ONCE:
                return True
            frame = frame.f_back
        return False  # no asyncio iteration on the stack (another loop): probe it

    def _report(self, probe: _Probe) -> None:
        """Log the block the loop is in now (on the watchdog's thread)."""
        report = self._look(probe)
        blocked = time.monotonic() - probe.posted
        if probe.answered is not None:  # it turned while we looked: the stack may be elsewhere
            report = _Report(probe, report.label, report.action, report.name, None, "")
            self._log.warning(
                "the event loop did not turn for %.3f s (it turned again before the watchdog "
                "could see where)",
                blocked,
            )
        else:
            self._log.warning(
                "the event loop has not turned for %.3f s: %s blocks it at %s. Code that "
                "never awaits stops every action, monitor and the simulation: await instead, "
                "or run the blocking call off the loop with robot.to_thread(fn, *args). "
                "The blocking stack (most recent call last):\n%s",
                blocked,
                report.label,
                report.location or "an unknown place",
                report.stack.rstrip(),
            )
        self.blocks += 1
        self._pending.append(report)
        try:
            self._loop.call_soon_threadsafe(self._ended, report)
        except RuntimeError:  # the loop is closed; stop() emits it if it still can
            return

    def _look(self, probe: _Probe) -> _Report:
        """What runs on the blocked loop, where, and its stack (frames are not kept)."""
        frames = list(_callback_frames(sys._current_frames().get(self._loop_thread)))
        task = asyncio.current_task(self._loop)
        blocker = self._blocker(task) if self._blocker is not None else None
        if blocker is None:
            blocker = Blocker("a callback" if task is None else f"task {task.get_name()!r}")
        location = _location(frames, blocker.frame)
        stack = traceback.extract_stack(frames[0], len(frames)) if frames else []
        return _Report(
            probe,
            blocker.label,
            blocker.action,
            blocker.name,
            location,
            "".join(traceback.format_list(stack)),
        )


def _share(cpu: float, elapsed: float, queued: float) -> float:
    """The share of ``elapsed`` a thread ran (``cpu``), its waits for a CPU left out.

    A busy loop on a loaded machine waits for a CPU between its turns: that is
    not idling, and must not stop its beat.
    """
    return cpu / max(elapsed - queued, 1e-9)


def _waited(now: float | None, then: float | None) -> float:
    """Seconds of waiting for a CPU between two `RunQueue.waited` readings (0 if unknown)."""
    return now - then if now is not None and then is not None else 0.0


def _callback_frames(frame: FrameType | None) -> Iterator[FrameType]:
    """The frames of the running callback, innermost first (the whole stack if none)."""
    while frame is not None and frame.f_code is not _CALLBACK:
        yield frame
        frame = frame.f_back


def _location(frames: list[FrameType], outer: FrameType | None) -> str | None:
    """The ``file:line`` where the loop blocks: the innermost frame of the user's code.

    Frames of the standard library and installed packages are passed over (a
    ``socket.recv``, a ``requests.get``), to the line that called them; with
    ``outer`` (an action's body) the search stops there, and falls back to it.
    """
    if outer is not None and outer in frames:
        frames = frames[: frames.index(outer) + 1]
    else:
        outer = frames[0] if frames else None
    for frame in frames:
        filename = frame.f_code.co_filename
        if not filename.startswith(_LIBRARY) and not filename.startswith("<"):
            return f"{filename}:{frame.f_lineno}"
    return None if outer is None else f"{outer.f_code.co_filename}:{outer.f_lineno}"
