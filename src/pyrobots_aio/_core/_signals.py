"""Ending a robot program on Ctrl-C (SIGINT) and SIGTERM, in order, however often they come.

Under ``asyncio.run`` a first Ctrl-C cancels the main task, and the robot shuts
down as on any cancellation; but a second one raises `KeyboardInterrupt`
wherever the program happens to be: in the middle of that shutdown, of a
recorder's write, or of the event loop's own bookkeeping, where it can lose a
task's wake-up and leave the loop waiting forever. SIGTERM (what systemd,
docker and ``kill`` send) gets no shutdown at all: no cleanup, no end record.

`stop_on_signals` takes both signals over while its block runs, and handles
them as event loop callbacks, between two steps of the program, never inside
one:

1. the first cancels the task that entered the block: the robot shuts down as
   on any cancellation (actions cancelled, their cleanup bounded by
   ``cancel_grace``, the base stopped, recordings closed);
2. the second stops at once: every task is cancelled again, which cuts short
   the cleanup under way; the shutdown still stops the base and closes the
   recordings;
3. a third gets Python's default: `KeyboardInterrupt` where it lands (SIGINT),
   or the end of the process (SIGTERM), for a program that is stuck.

After a signal, the program ends as Python's own handlers would end it, but
after its cleanup, and by ``asyncio.run``'s rule: only if the cancellation
ended the task that entered the block. The cancellation goes on out of the
block; once that task is done, cancelled, `KeyboardInterrupt` (SIGINT) or
``SystemExit(143)`` (SIGTERM: 128 + 15, the status a shell reports for a
process that SIGTERM ended) comes out of the event loop, where
``asyncio.run``'s own `KeyboardInterrupt` would. A program that catches the
cancellation, cleans up and goes on, inside the block or around it, is not
ended: it gets the signals back as it leaves the block (caught inside), or
as its task ends (caught around it).

A block that raises keeps the signals while the program unwinds (the
recorders around ``async with robot`` write their last events and end record,
``asyncio.run`` cancels what is left): with Python's default back in place, a
second SIGTERM would end the process in the middle of a recorder's last write.
So the count goes on: a second signal cuts what is left of the cleanup short,
a third gets Python's default; the event loop gives the signals back to
Python when it closes, and a block entered meanwhile takes them afresh.

Every `Robot` does this around its own ``async with`` block, unless told not to
(``Robot(handle_signals=False)``) or the signals are taken already (by an
enclosing `stop_on_signals`, another robot, a server such as uvicorn);
`stop_on_signals` is for a wider block, e.g. code that must also end in order
after the robot has stopped.
"""

from __future__ import annotations

import asyncio
import functools
import inspect
import logging
import signal
import weakref
from typing import TYPE_CHECKING, Self

if TYPE_CHECKING:
    from types import TracebackType

_log = logging.getLogger("pyrobots_aio.signals")

CUT_PASSES = 5
"""Loop iterations in a row on which a second signal cancels every task (see `SignalStop._cut`)."""

SIGNALS = (signal.SIGINT, signal.SIGTERM)
"""The signals `stop_on_signals` handles."""


_lingering: weakref.WeakSet[SignalStop] = weakref.WeakSet()
"""Blocks left by a raise after a signal, still holding the signals (see `SignalStop._linger`)."""


def _runner_handler(handler: object) -> bool:
    """Whether ``handler`` is the one ``asyncio.run`` (an `asyncio.Runner`) installs."""
    func = getattr(handler, "func", None) if isinstance(handler, functools.partial) else None
    return getattr(func, "__func__", None) is getattr(asyncio.Runner, "_on_sigint", object())


def _takes_over(signum: int, handler: object) -> bool:
    """Whether to take ``signum`` over from ``handler``: only from Python's or asyncio's default."""
    if signum == signal.SIGINT:
        return handler is signal.default_int_handler or _runner_handler(handler)
    return handler is signal.SIG_DFL


def _started(task: asyncio.Task[object]) -> bool:
    """Whether ``task`` has begun to run its coroutine.

    A task cancelled before its first step never runs a line of it: an action's
    task would then end without winding the action up, and whoever waits for
    the action would wait forever. A task not yet started is left to start; an
    action of a cancelled parent sees the cancellation when it does.
    """
    coro = task.get_coro()
    return not inspect.iscoroutine(coro) or inspect.getcoroutinestate(coro) != "CORO_CREATED"


class SignalStop:
    """A ``with`` block that ends on SIGINT or SIGTERM after the robot's shutdown (see the module).

    Use `stop_on_signals` to make one. Its attribute ``received`` lists the
    signals received so far, and ``handled`` those it took over: it leaves a
    signal alone when the program, or the process starting it, handles or
    ignores it already (a handler other than Python's default or
    ``asyncio.run``'s, or ``SIG_IGN``), off the main thread, and where the
    event loop cannot handle signals (Windows).
    """

    def __init__(self) -> None:
        self.received: list[signal.Signals] = []
        self.handled: tuple[signal.Signals, ...] = ()
        self._loop: asyncio.AbstractEventLoop | None = None
        self._task: asyncio.Task[object] | None = None
        self._previous: dict[signal.Signals, object] = {}
        self._cancels = 0
        self._cutting: asyncio.Handle | None = None

    def __enter__(self) -> Self:
        loop = asyncio.get_running_loop()
        for earlier in list(_lingering):  # a new block: a signal now is a first one again
            earlier._restore()
        self._loop, self._task = loop, asyncio.current_task()
        for signum in SIGNALS:
            previous = signal.getsignal(signum)
            if not _takes_over(signum, previous):
                _log.debug("%s is handled by %r; left alone", signum.name, previous)
                continue
            try:
                loop.add_signal_handler(signum, self._receive, signum)
            except (ValueError, RuntimeError, NotImplementedError) as exc:
                _log.debug("cannot handle %s here: %s", signum.name, exc)
                continue
            self._previous[signum] = previous
        self.handled = tuple(self._previous)
        return self

    def _receive(self, signum: signal.Signals) -> None:
        self.received.append(signum)
        if len(self.received) == 1:
            again = "Ctrl-C" if signum == signal.SIGINT else signum.name
            _log.warning("%s: stopping the robot (%s again stops at once)", signum.name, again)
            self._cancel(self._task, f"{signum.name} received")
            return
        _log.warning("%s again: stopping at once, cutting the cleanup short", signum.name)
        self._restore()  # a third signal gets Python's default
        self._cut(f"{signum.name} received again", CUT_PASSES)

    def _cut(self, reason: str, passes: int) -> None:
        """Cancel every started task; again on the next ``passes - 1`` loop iterations.

        A second signal that comes before the first one's cancellation has
        reached the actions makes them start their cleanup now: the passes
        that follow cut that cleanup short too.
        """
        assert self._loop is not None
        for task in asyncio.all_tasks(self._loop):
            if _started(task):
                self._cancel(task, reason)
        self._cutting = None
        if passes > 1:
            self._cutting = self._loop.call_soon(self._cut, reason, passes - 1)

    def _cancel(self, task: asyncio.Task[object] | None, reason: str) -> None:
        if task is not None and task.cancel(reason) and task is self._task:
            self._cancels += 1

    def _restore(self) -> None:
        """Give the signals back to their previous handlers; stop cutting."""
        _lingering.discard(self)
        if self._cutting is not None:
            self._cutting.cancel()
            self._cutting = None
        loop, previous, self._previous = self._loop, self._previous, {}
        if loop is None or loop.is_closed():
            return  # the loop gave them back to Python's defaults as it closed
        for signum, handler in previous.items():
            loop.remove_signal_handler(signum)
            signal.signal(signum, handler)  # type: ignore[arg-type]

    def _linger(self) -> None:
        """Keep the signals after the block, until the next one or the loop's end.

        The block raises after a signal, and the program unwinds: the code
        around the block (a recorder's close) is not done yet. The loop's
        handlers stay in place, so the next signal is a second one (`_receive`
        cuts what is left and restores); closing the loop removes them, which
        puts Python's defaults back.
        """
        if self._previous:
            _lingering.add(self)

    def _answer_cancels(self) -> None:
        """Answer the cancellations of the task that the signals requested (``uncancel``)."""
        task = self._task
        if task is not None:
            for _ in range(min(self._cancels, task.cancelling())):
                task.uncancel()
        self._cancels = 0

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self._answer_cancels()
        task = self._task
        if not self.received or exc is None:
            # No signal; or the program caught the cancellation and left the block normally:
            # it goes on (asyncio.run's rule: a handled cancellation is no KeyboardInterrupt).
            self._restore()
            return
        self._linger()  # the program unwinds: what encloses the block still has cleanup to do
        if not isinstance(exc, asyncio.CancelledError):
            return  # a failure says more than the signal: let it through
        if task is None or task.cancelling():
            return  # someone else cancelled the task too: theirs to handle
        # The code around the block may still catch the cancellation: the task's end tells.
        task.add_done_callback(self._ended)

    def _ended(self, task: asyncio.Task[object]) -> None:
        """The task that entered the block is done: end the program if it ended cancelled.

        As ``asyncio.run`` does on Ctrl-C, and from the same place (the event
        loop): the exception leaves ``loop.run_until_complete``. A task that
        caught the cancellation around the block and ended otherwise goes on
        as the program wishes, with the signals given back.
        """
        self._answer_cancels()  # (a second signal after the block cancelled it again)
        if not task.cancelled():
            self._restore()
            return
        if task.cancelling():
            return  # someone else cancelled the task too: theirs to handle
        first = self.received[0]
        if first == signal.SIGINT:
            raise KeyboardInterrupt
        raise SystemExit(128 + first)

    def __repr__(self) -> str:
        handled = [s.name for s in self.handled]
        received = [s.name for s in self.received]
        return f"<SignalStop handling {handled}, received {received}>"


def stop_on_signals() -> SignalStop:
    """Stop a robot program in order on SIGINT and SIGTERM, however many come.

    Enter it in the main task, around the recorders and ``async with robot``
    so that their closing is inside: the first signal cancels that task (the
    robot shuts down, cleanup bounded by ``cancel_grace``), a second cuts the
    cleanup short, a third gets Python's default. After a signal, once the
    task that entered the block is done, `KeyboardInterrupt` (SIGINT) or
    ``SystemExit(143)`` (SIGTERM) comes out of the event loop, as under
    ``asyncio.run``: only if the cancellation ended that task, not if the
    program caught it (inside the block or around it) and went on; the count
    goes on until the event loop closes. Signals the program handles itself
    are left alone.

    Examples:
        >>> import asyncio
        >>> from pyrobots_aio.cli import stop_on_signals
        >>> from pyrobots_aio.recording import JsonlRecorder
        >>> from pyrobots_aio.sim import SimRobot
        >>> from pyrobots_aio.sim.random_walk import random_walk
        >>> async def main() -> None:
        ...     robot = SimRobot(realtime=True)
        ...     with stop_on_signals(), JsonlRecorder("walk.jsonl").attach(robot):
        ...         async with robot:
        ...             await random_walk(robot)
        >>> asyncio.run(main())  # doctest: +SKIP
    """
    return SignalStop()
