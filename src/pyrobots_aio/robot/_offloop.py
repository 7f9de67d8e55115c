"""Code that never awaits: which action blocks the loop, and running such code off it.

The loop watchdog (`pyrobots_aio._core._blockwatch`) asks `blocking_action`
which action runs the task on a blocked loop; `Workers` are the threads of
``robot.to_thread``.
"""

from __future__ import annotations

import asyncio
import collections
import contextvars
import functools
import os
import queue
import threading
from concurrent.futures import Executor, Future
from typing import TYPE_CHECKING, Any, Generic, ParamSpec, TypeVar, TypeVarTuple

from .._core._blockwatch import Blocker
from .._exceptions import RobotNotRunningError, TooManyAbandonedCalls

if TYPE_CHECKING:
    from collections.abc import Callable, Iterable

    from .._core._logging import ScopedLogger
    from ..actions import ActionHandle

    _Job = Callable[[], Callable[[], object]]
    """A call for a worker thread: it runs the call and returns what publishes its outcome."""

T = TypeVar("T")
Ts = TypeVarTuple("Ts")
P = ParamSpec("P")

LIVE_CALLS = min(32, (os.cpu_count() or 1) + 4)
"""Calls run at once for callers that still wait (as many as asyncio's default executor)."""

ABANDONED_CALLS = 32
"""Abandoned calls that may still run beside them before ``robot.to_thread`` refuses more."""


def blocking_action(
    handles: Iterable[ActionHandle[Any]], task: asyncio.Task[object] | None
) -> Blocker | None:
    """The action whose task is ``task`` (the one running on the blocked loop), if any.

    Called from the watchdog's thread while the loop is blocked: it only reads.
    """
    if task is None:
        return None
    for handle in handles:
        if handle.runs_in(task):
            body = handle.body_frame()  # where to look for the culprit line
            return Blocker(f"action {handle.name}#{handle.id}", handle.id, handle.name, body)
    return None


class Workers(Executor):
    """The threads of ``robot.to_thread`` for one run of a robot: started on demand, reused.

    At most `LIVE_CALLS` calls run at once for callers that still wait; later
    callers wait their turn, first come first served. A caller cancelled
    meanwhile gives its turn up at once: its call, abandoned, runs on in its
    thread (Python cannot stop a thread) and later calls get other threads,
    never waiting behind it. Never more than `ABANDONED_CALLS` abandoned calls
    run: each call running for a caller may yet be abandoned, so the turns
    shrink as abandoned calls fill that room (with 31, one call runs at a
    time), and while that many run, `run` refuses with `TooManyAbandonedCalls`.
    `close` waits for no call: idle threads end at once, busy ones as soon as
    their call returns.
    """

    def __init__(self, log: ScopedLogger) -> None:
        self._log = log
        self._live = 0  # calls running for callers that still wait (the loop's thread only)
        self._queue: collections.deque[asyncio.Event] = collections.deque()  # callers in turn
        self._lock = threading.Lock()  # what follows is shared with the worker threads
        self._idle: list[_Worker] = []
        self._abandoned: dict[_Call[Any], None] = {}
        self._closed = False
        self._started = 0

    async def run(self, loop: asyncio.AbstractEventLoop, fn: Callable[[*Ts], T], *args: *Ts) -> T:
        """Run ``fn(*args)`` in a worker thread; stop waiting (abandon it) when cancelled.

        The call runs in a copy of the caller's context. Abandoned, its result
        is dropped, and an exception it raises is logged with its traceback.
        """
        call = _Call(self, fn, *args)
        await self._take_turn(call.name)
        try:  # (the loop's run_in_executor: virtual time stands still until it returns)
            await asyncio.shield(loop.run_in_executor(self, call.run))
        except asyncio.CancelledError:
            self._abandon(call)  # counted as abandoned before its turn is given up
            raise
        finally:
            self._live -= 1
            self._wake()
        return call.result()

    async def _take_turn(self, name: str) -> None:
        """Wait until a call may run: first in line, and room for one more that may be abandoned.

        Raises:
            RobotNotRunningError: The robot has stopped.
            TooManyAbandonedCalls: `ABANDONED_CALLS` abandoned calls run.
        """
        turn = asyncio.Event()
        self._queue.append(turn)
        try:
            while True:
                abandoned = self._check_room(name)
                room = min(LIVE_CALLS, ABANDONED_CALLS - abandoned)
                if self._queue[0] is turn and self._live < room:
                    self._live += 1
                    return
                turn.clear()
                await turn.wait()  # a call gave its turn up, or a caller left the line
        finally:
            self._queue.remove(turn)
            self._wake()

    def _wake(self) -> None:
        """Have the first caller in line look again (the others follow when it leaves)."""
        if self._queue:
            self._queue[0].set()

    def _check_room(self, name: str) -> int:
        """The number of abandoned calls still running; raise if no call may start now."""
        if self._closed:
            msg = f"cannot call robot.to_thread({name}): the robot has stopped"
            raise RobotNotRunningError(msg)
        with self._lock:  # (their threads only ever lower it meanwhile)
            running = [call.name for call in self._abandoned]
        if len(running) >= ABANDONED_CALLS:
            raise TooManyAbandonedCalls(name, running)
        return len(running)

    def _abandon(self, call: _Call[Any]) -> None:
        """Its caller was cancelled: count it until it returns, then report a late error."""
        with self._lock:
            if not call.ended:
                self._abandoned[call] = None
                return
        self._late(call)  # it returned meanwhile, its result on its way to the loop

    def ended(self, call: _Call[Any]) -> None:
        """Called in the worker thread once ``call`` has returned or raised."""
        with self._lock:
            call.ended = True
            abandoned = call in self._abandoned
            if abandoned:
                del self._abandoned[call]
        if abandoned:
            self._late(call)

    def _late(self, call: _Call[Any]) -> None:
        if call.error is not None:
            self._log.error(
                "robot.to_thread(%s) raised after its caller was cancelled (its result is dropped)",
                call.name,
                exc_info=call.error,
            )

    def submit(self, fn: Callable[P, T], /, *args: P.args, **kwargs: P.kwargs) -> Future[T]:
        """Run ``fn(*args, **kwargs)`` at once in an idle thread, or in a new one."""
        future: Future[T] = Future()
        with self._lock:
            if self._closed:
                msg = "cannot schedule new calls after close()"
                raise RuntimeError(msg)
            if self._idle:
                worker = self._idle.pop()
            else:
                worker = _Worker(self, f"pyrobots_aio to_thread_{self._started}")
                self._started += 1
        worker.jobs.put(lambda: _run(future, fn, *args, **kwargs))
        return future

    def rest(self, worker: _Worker) -> bool:
        """Take ``worker``, done with its call, back as idle; False once closed (it ends)."""
        with self._lock:
            if self._closed:
                return False
            self._idle.append(worker)
            return True

    def close(self) -> None:
        """Take no more calls; end the idle threads now, the busy ones when their call returns.

        Abandoned calls still running are named in a WARNING.
        """
        with self._lock:
            self._closed = True
            idle, self._idle = self._idle, []
            running = [call.name for call in self._abandoned]
        self._wake()  # callers still in line are refused
        for worker in idle:
            worker.jobs.put(None)
        for worker in idle:
            worker.thread.join()  # idle: it ends at once
        if running:
            self._log.warning(
                "abandoned robot.to_thread calls still running at the robot's exit: %d (%s); "
                "each thread ends when its call returns (the process waits for it before it exits)",
                len(running),
                ", ".join(dict.fromkeys(running)),
            )


class _Call(Generic[T]):
    """One call of ``robot.to_thread``: what to run, in which context, and how it ended."""

    __slots__ = ("context", "ended", "error", "fn", "name", "value", "workers")

    def __init__(self, workers: Workers, fn: Callable[[*Ts], T], *args: *Ts) -> None:
        self.workers = workers
        self.name: str = getattr(fn, "__qualname__", repr(fn))
        self.fn: Callable[[], T] = lambda: fn(*args)
        self.context = contextvars.copy_context()
        self.value: T | None = None
        self.error: BaseException | None = None
        self.ended = False

    def run(self) -> None:
        """Run the call (in a worker thread); it never raises: the caller does, on the loop."""
        try:
            self.value = self.context.run(self.fn)
        except BaseException as exc:  # kept for the caller, who raises it on the loop
            self.error = exc
        finally:
            self.workers.ended(self)

    def result(self) -> T:
        """The call's value, or raise its error (on the loop, once it ended)."""
        error, self.error = self.error, None  # the error's traceback must not hold this call
        if error is not None:
            raise error
        return self.value  # type: ignore[return-value]


class _Worker:
    """One thread of `Workers`: runs the calls it is handed, one at a time."""

    def __init__(self, workers: Workers, name: str) -> None:
        self.workers = workers
        self.jobs: queue.SimpleQueue[_Job | None] = queue.SimpleQueue()
        self.thread = threading.Thread(target=self._serve, name=name)
        self.thread.start()

    def _serve(self) -> None:
        while (job := self.jobs.get()) is not None:
            publish = job()
            # Idle before the outcome is out: by the time the loop sees it, this thread
            # is one that `Workers.close` joins (or, closed already, it is ending).
            resting = self.workers.rest(self)
            publish()
            if not resting:
                return


def _run(
    future: Future[T], fn: Callable[P, T], *args: P.args, **kwargs: P.kwargs
) -> Callable[[], object]:
    """Run ``fn`` for ``future`` in a worker thread; return what sets its outcome."""
    if not future.set_running_or_notify_cancel():
        return _nothing
    try:
        value = fn(*args, **kwargs)
    except BaseException as exc:  # the future carries it to its owner
        return functools.partial(future.set_exception, exc)
    return functools.partial(future.set_result, value)


def _nothing() -> None:
    """The outcome of a call cancelled before it ran: nothing to set."""
