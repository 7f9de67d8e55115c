"""Showing what runs while it runs: a live block on a terminal, plain lines otherwise.

`EventLines` is an instrument that turns notable executive events into one
line each (action started and finished, cancellations with who and why,
preemptions, monitor firings). `Progress` writes one line of counters every
few simulated seconds instead, for a log that stays short. `LiveStatus`
keeps a block at the bottom of the terminal (clock, counters, a few state
values, the running action tree) and redraws it in place about ten times a
(wall-clock) second; lines written through it (``LiveStatus.write``, which the
console log handler uses) scroll above the block.
"""

from __future__ import annotations

import asyncio
import contextlib
import re
import shutil
import time
from typing import TYPE_CHECKING, TextIO

from pyrobots_aio import (
    ActionAbandonment,
    ActionFinished,
    ActionSpawned,
    CancelEscalated,
    CancelRequested,
    MonitorFired,
    ResourceSkipped,
)

from ._console import format_time

if TYPE_CHECKING:
    from collections.abc import AsyncIterator, Callable, Coroutine

    from pyrobots_aio import ExecEvent, Robot

REFRESH = 0.1
"""Wall-clock seconds between redraws of the live block."""
TREE_LINES = 8
"""Most lines of the action tree shown."""
STATE_KEYS = ("bumper", "docked", "v", "w")
_DIRS = re.compile(r"(?<= at )\S*/(?=[^/\s]+:\d+)")
"""The directories of ``at /path/to/file.py:12`` in the action tree (shown as ``file.py:12``)."""


def _value(value: object) -> str:
    return f"{value:+.3f}" if isinstance(value, float) else str(value)


class EventLines:
    """An instrument that writes one line per notable event.

    Args:
        write: Called with each line (no newline).
        start: The loop time shown as 0 (the robot's start: the demo shows every
            time since then, its log lines' too).
        verbose: Also report actions starting and succeeding (plain mode); else
            only cancellations, failures, skips, preemptions and monitor firings.
    """

    def __init__(self, write: Callable[[str], object], start: float, *, verbose: bool) -> None:
        self._write = write
        self.start = start
        self.verbose = verbose
        self._names: dict[int, str] = {}

    def _label(self, ident: int | None) -> str:
        return "outside any action" if ident is None else self._names.get(ident, f"#{ident}")

    def on_event(self, event: ExecEvent) -> None:
        """Write the line for ``event``, if it deserves one."""
        text = self._describe(event)
        if text is not None:
            self._write(f"{format_time(event.time - self.start)}  {text}")

    def _describe(self, event: ExecEvent) -> str | None:
        me = f"{event.name}#{event.action}"
        match event:
            case ActionSpawned(parent=parent):
                if event.action is not None:
                    self._names[event.action] = me
                where = f" under {self._label(parent)}" if parent is not None else ""
                return f"start    {me}{where}" if self.verbose else None
            case ActionFinished(outcome=outcome, error=error):
                if outcome == "succeeded" and not self.verbose:
                    return None
                return f"{outcome:<8} {me}{f': {error}' if error else ''}"
            case CancelRequested(reason=reason, by=by):
                return f"cancel   {me} by {self._label(by)}{f': {reason}' if reason else ''}"
            case ResourceSkipped(busy=busy):
                return f"skip     {me}: {busy!r} is busy"
            case MonitorFired():
                return f"event    {event.name} fired"
            case CancelEscalated(location=where) | ActionAbandonment(location=where):
                return f"{event.kind.value.partition('.')[2]:<8} {me} at {where}"
        return None


@contextlib.asynccontextmanager
async def _running(work: Coroutine[None, None, None], name: str) -> AsyncIterator[None]:
    """Run ``work``, which never ends by itself, as a task while the body runs."""
    task = asyncio.get_running_loop().create_task(work, name=name)
    try:
        yield
    finally:
        task.cancel()
        try:
            await task
        except asyncio.CancelledError:
            # The task's own end is expected; the caller's cancellation (it was cancelled
            # while waiting here, or before) is not ours to drop.
            current = asyncio.current_task()
            if current is not None and current.cancelling():
                raise


class Progress:
    """One line of counters every ``every`` seconds of loop time, while `showing` runs.

    Args:
        write: Called with each line (no newline).
        tally: The counters shown.
        every: Seconds of loop time (simulated time, in lockstep) between lines.
    """

    def __init__(self, write: Callable[[str], object], tally: Tally, every: float) -> None:
        self._write = write
        self._tally = tally
        self._every = every

    def line(self, since_start: float) -> str:
        """The line for ``since_start`` seconds into the run."""
        t = self._tally
        return (
            f"{format_time(since_start)}  progress {t.actions} actions, {t.cancelled} cancelled, "
            f"{t.failed} failed, {t.firings} monitor firings"
        )

    def showing(self, start: float) -> contextlib.AbstractAsyncContextManager[None]:
        """Write the lines, counting from loop time ``start``, while the body runs."""
        return _running(self._lines(start), "pyrobots-aio progress")

    async def _lines(self, start: float) -> None:
        loop = asyncio.get_running_loop()
        due = start
        while True:
            due += self._every
            await asyncio.sleep(due - loop.time())  # to the tick, however late the last line
            self._write(self.line(due - start))


class LiveStatus:
    """The live block at the bottom of a terminal, redrawn in place.

    Args:
        stream: The terminal.
        headline: Called at each redraw for the block's first line.
    """

    def __init__(self, stream: TextIO, headline: Callable[[], str]) -> None:
        self._stream = stream
        self._headline = headline
        self._robot: Robot | None = None
        self._drawn = 0

    # -- a stream for the console log handler -------------------------------

    def write(self, text: str) -> int:
        """Write ``text`` above the block (the block is redrawn on `flush`)."""
        self._erase()
        self._stream.write(text)
        return len(text)

    def flush(self) -> None:
        """Redraw the block and flush the terminal."""
        self._draw()
        self._stream.flush()

    def isatty(self) -> bool:
        """True: colours are welcome."""
        return True

    def line(self, text: str) -> None:
        """Write one line above the block."""
        self.write(text + "\n")
        self.flush()

    # -- the block ----------------------------------------------------------------

    @contextlib.asynccontextmanager
    async def showing(self, robot: Robot) -> AsyncIterator[None]:
        """Keep the block up to date while the ``async with`` body runs; erase it after."""
        self._robot = robot
        try:
            async with _running(self._refresh(), "pyrobots-aio live status"):
                yield
        finally:
            self._erase()
            self._robot = None
            self._stream.flush()

    async def _refresh(self) -> None:
        # Loop time may run far faster than the wall clock (lockstep): check often,
        # redraw only when a tenth of a wall-clock second has passed.
        last = 0.0
        while True:
            await asyncio.sleep(REFRESH)
            now = time.perf_counter()
            if now - last >= REFRESH:
                last = now
                self._erase()
                self.flush()

    def lines(self) -> list[str]:
        """The block's lines as they would be drawn now."""
        lines = [self._headline()]
        robot = self._robot
        if robot is not None:
            state = robot.state
            shown = [f"{k}={_value(state[k])}" for k in STATE_KEYS if k in state]
            if shown:
                lines.append("  state   " + "  ".join(shown))
            tree = _DIRS.sub("", robot.action_tree()).splitlines()
            more = [f"  ... and {len(tree) - TREE_LINES} more"] if len(tree) > TREE_LINES else []
            lines += ["  running " + (tree[0] if tree else "")]
            lines += ["          " + t for t in tree[1:TREE_LINES]] + more
        return lines

    def _draw(self) -> None:
        if self._drawn or self._robot is None:
            return
        width = max(20, shutil.get_terminal_size().columns - 1)
        lines = [line[:width] for line in self.lines()]
        self._stream.write("".join(line + "\n" for line in lines))
        self._drawn = len(lines)

    def _erase(self) -> None:
        if self._drawn:
            self._stream.write(f"\x1b[{self._drawn}F\x1b[J")
            self._drawn = 0


class Tally:
    """An instrument counting what the live block's headline shows."""

    def __init__(self) -> None:
        self.actions = 0
        self.cancelled = 0
        self.failed = 0
        self.firings = 0

    def on_event(self, event: ExecEvent) -> None:
        """Count one event."""
        if isinstance(event, ActionSpawned):
            self.actions += 1
        elif isinstance(event, ActionFinished):
            self.cancelled += event.outcome == "cancelled"
            self.failed += event.outcome == "failed"
        elif isinstance(event, MonitorFired):
            self.firings += 1
