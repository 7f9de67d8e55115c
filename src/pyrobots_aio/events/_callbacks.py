"""Running a monitor's callbacks, and keeping every task a monitor owns.

A callback is started from the write that fired the monitor, but no user code
runs inside the write: an action or a coroutine function only gets its task
created (its body starts at the next loop iteration), a plain function is
queued with ``call_soon``. A monitor's callbacks (``.do(a).do(b)``) start in
the order given, each with its own failure log, so one that raises neither
stops nor hides the others. Everything runs in the monitor's root context
(``current_action`` is None), so an action callback belongs to the robot's
root scope, whatever task wrote the state.
"""

from __future__ import annotations

import asyncio
import inspect
from collections import deque
from functools import partial
from typing import TYPE_CHECKING, Any

from .._core._grace import Ladder, Stage
from .._core._waiting import Countdown, wait_shielded
from ..actions import Action, ActionHandle, BoundAction
from ..actions._where import location

if TYPE_CHECKING:
    from collections.abc import Callable, Sequence
    from contextvars import Context

    from .._core._logging import ScopedLogger

_PLAIN, _COROUTINE, _ACTION = "function", "coroutine function", "action"
QUIET_PERIOD = 10.0
"""Seconds (loop time) after a logged callback failure during which repeats are only counted."""


def describe(callback: object, *, qualified: bool = True) -> str:
    """A name for ``callback``: its (qualified) name, or its repr."""
    if isinstance(callback, Action):
        return callback.name
    if isinstance(callback, BoundAction):
        return callback.action.name
    name = getattr(callback, "__qualname__" if qualified else "__name__", None)
    return name if isinstance(name, str) else repr(callback)


class Callback:
    """One callback given to ``do()``: what to call, with what, and its own failure log."""

    __slots__ = ("args", "failures", "fn", "kind", "label")

    def __init__(
        self, fn: Callable[..., Any], args: tuple[Any, ...], label: str, failures: FailureLog
    ) -> None:
        self.kind = _kind_of(fn)
        self.fn, self.args, self.label, self.failures = fn, args, label, failures


def _kind_of(fn: object) -> str:
    """How to start ``fn``: as an action, a coroutine function's task, or a plain call."""
    if isinstance(fn, Action | BoundAction):
        return _ACTION
    if inspect.iscoroutinefunction(fn):
        return _COROUTINE
    if callable(fn):
        return _PLAIN
    msg = (
        f"do() takes an action, a coroutine function or a function, got {fn!r} "
        f"({type(fn).__name__})"
    )
    raise TypeError(msg)


class CallbackRunner:
    """Starts one monitor's callbacks and keeps the tasks it owns until they end.

    ``busy`` counts the callbacks in flight (queued, running, or their action
    not done); ``settled`` also waits for the monitor's own tasks (async
    predicate evaluations), which `track` registers.
    """

    __slots__ = (
        "_actions",
        "_callbacks",
        "_calls",
        "_context",
        "_failures",
        "_idle_waiters",
        "_log",
        "_loop",
        "_on_settled",
        "_robot",
        "_tasks",
        "label",
    )

    def __init__(
        self,
        loop: asyncio.AbstractEventLoop,
        robot: object,
        context: Context,
        on_settled: Callable[[], None],
        log: ScopedLogger,
        *,
        label: str,
    ) -> None:
        self._loop = loop
        self._log = log
        self._failures = FailureLog(loop, log)
        self._robot = robot
        self._context = context
        self.label = label  # what log messages call the monitor's own tasks
        self._on_settled = on_settled
        self._callbacks: list[Callback] = []
        self._calls: deque[asyncio.Handle] = deque()
        self._tasks: dict[asyncio.Task[Any], Callback | None] = {}  # None: the monitor's own
        self._actions: set[ActionHandle[Any]] = set()
        self._idle_waiters: list[asyncio.Future[None]] = []

    @property
    def callbacks(self) -> tuple[Callable[..., Any], ...]:
        """The callbacks given to ``do()``, in order."""
        return tuple(callback.fn for callback in self._callbacks)

    @property
    def has_callbacks(self) -> bool:
        """Whether ``do()`` gave any callback (cheaper than `callbacks`, for each firing)."""
        return bool(self._callbacks)

    def add(self, fn: Callable[..., Any], args: tuple[Any, ...]) -> None:
        """Register ``fn(*args)`` (an action, a coroutine function or a function)."""
        label = f"callback {describe(fn)} of {self.label}"
        self._callbacks.append(Callback(fn, args, label, FailureLog(self._loop, self._log)))

    @property
    def busy(self) -> bool:
        """Whether a callback is queued or running."""
        return bool(self._calls or self._actions or any(self._tasks.values()))  # None: own task

    @property
    def settled(self) -> bool:
        """Whether nothing this runner keeps is in flight."""
        return not (self._calls or self._actions or self._tasks)

    # -- starting -------------------------------------------------------------

    def start(self) -> None:
        """Start one run of every callback, in order; each begins at the next loop iteration."""
        for callback in self._callbacks:
            if callback.kind == _PLAIN:
                context = self._context.copy()
                handle = self._loop.call_soon(self._call_plain, callback, context=context)
                self._calls.append(handle)
            elif callback.kind == _COROUTINE:
                self.track(callback.fn(*callback.args), callback)
            else:
                self._start_action(callback)

    def track(self, coro: Any, callback: Callback | None = None) -> asyncio.Task[Any]:
        """Run ``coro`` as a task of this runner (of ``callback``, if given), in its context."""
        name = self._label_of(callback)
        task = self._loop.create_task(coro, name=name, context=self._context.copy())
        self._tasks[task] = callback
        task.add_done_callback(self._task_done)
        return task

    def _start_action(self, callback: Callback) -> None:
        fn, args = callback.fn, callback.args
        if isinstance(fn, Action):
            args = (self._robot, *args)
        try:
            handle = self._context.copy().run(fn, *args)
        except Exception as error:
            callback.failures.report(f"{callback.label} could not start its action", error)
            return
        self._keep(handle)

    def _keep(self, handle: ActionHandle[Any]) -> None:
        """Count ``handle`` as a callback in flight until the action is done."""
        self._actions.add(handle)
        handle.on_done(self._action_done)

    def _call_plain(self, callback: Callback) -> None:
        self._calls.popleft()
        try:
            result = callback.fn(*callback.args)
        except Exception as error:
            callback.failures.report(f"{callback.label} failed", error)
        else:
            if inspect.iscoroutine(result):  # a function returning a coroutine: run it
                self.track(result, callback)
            elif isinstance(result, ActionHandle):  # ``lambda: robot.say("hi")``: keep it
                self._keep(result)
        self._check_settled()

    def _task_done(self, task: asyncio.Task[Any]) -> None:
        callback = self._tasks.pop(task, None)
        if not task.cancelled() and (error := task.exception()) is not None:
            failures = self._failures if callback is None else callback.failures
            failures.report(f"{self._label_of(callback)} failed", error)
        self._check_settled()

    def _label_of(self, callback: Callback | None) -> str:
        """What logs call a task: its callback, or the monitor for the monitor's own tasks."""
        return self.label if callback is None else callback.label

    def _action_done(self, handle: ActionHandle[Any]) -> None:
        self._actions.discard(handle)
        self._check_settled()

    def _check_settled(self) -> None:
        if not self.settled:
            return
        waiters, self._idle_waiters = self._idle_waiters, []
        for fut in waiters:
            if not fut.done():
                fut.set_result(None)
        self._on_settled()

    # -- stopping -------------------------------------------------------------

    def cancel(self, reason: str) -> None:
        """Drop queued calls, cancel running tasks and actions (does not wait)."""
        while self._calls:
            self._calls.popleft().cancel()
        for task in self._tasks:
            task.cancel(reason)
        for handle in self._actions:
            handle.cancel(reason)
        self._check_settled()

    def idle(self) -> asyncio.Future[None]:
        """A future done once nothing is in flight."""
        fut = self._loop.create_future()
        if self.settled:
            fut.set_result(None)
        else:
            self._idle_waiters.append(fut)
        return fut

    def flush_failures(self) -> None:
        """Log the counts of failures not shown yet, the runner's and each callback's."""
        self._failures.flush()
        for callback in self._callbacks:
            callback.failures.flush()

    def escalate(self, grace: float) -> None:
        """Cancel again, with a warning, every task still running a grace after cancellation."""
        for task, callback in self._tasks.items():
            self._log.warning(
                "%s still running %.3g s after cancellation, at %s; cancelling it again",
                self._label_of(callback),
                grace,
                location(task.get_coro()) or "an unknown place",
            )
            task.cancel("it ignored cancellation")

    def abandon(self, grace: float) -> None:
        """Forget, with an error, what is still running two graces after cancellation."""
        for task, callback in self._tasks.items():
            self._log.error(
                "%s ignored cancellation for %.3g s, at %s; abandoning it (its task may "
                "outlive the robot)",
                self._label_of(callback),
                2 * grace,
                location(task.get_coro()) or "an unknown place",
            )
        self._tasks.clear()
        self._actions.clear()  # the executive's watchdog abandons those
        self._check_settled()


class FailureLog:
    """Logs a callback's failures: each with its traceback, but repeats only as a count.

    After a failure is logged, further failures within `QUIET_PERIOD` seconds
    are counted, and the count is given with the next one logged (or by
    `flush`): a callback failing on every write of a 50 Hz key logs one
    traceback every ten seconds, not fifty a second.
    """

    __slots__ = ("_log", "_loop", "_quiet_until", "_since", "_suppressed")

    def __init__(self, loop: asyncio.AbstractEventLoop, log: ScopedLogger) -> None:
        self._loop = loop
        self._log = log
        self._quiet_until = -float("inf")
        self._suppressed = 0
        self._since = ""

    def report(self, what: str, error: BaseException) -> None:
        """Log ``what`` with ``error``'s traceback, or count it if one was logged just before."""
        now = self._loop.time()
        if now < self._quiet_until:
            self._suppressed += 1
            self._since = what
            return
        more = ""
        if self._suppressed:
            more = f" (and {self._suppressed} more times since the last report, not shown)"
        self._log.error("%s%s", what, more, exc_info=error)
        self._suppressed = 0
        self._quiet_until = now + QUIET_PERIOD

    def flush(self) -> None:
        """Log the count of failures not shown yet, if any."""
        if self._suppressed:
            self._log.error(
                "%s %d more times since the last report (tracebacks not shown)",
                self._since,
                self._suppressed,
            )
            self._suppressed = 0


async def settle(runners: Sequence[CallbackRunner], grace: float) -> None:
    """Wait until every runner has settled, bounded by the grace ladder (two graces).

    After one grace, tasks still running are cancelled again (a warning names
    where they are); after a second one they are abandoned (an error). If the
    waiting task is cancelled meanwhile, the bounded wait still completes, then
    the cancellation is re-raised (so robot shutdown never leaves tasks behind).
    """
    late = [r for r in runners if not r.settled]
    for runner in runners:
        runner.flush_failures()
    if not late:
        return
    loop = asyncio.get_running_loop()
    countdown = Countdown(loop, len(late))
    for runner in late:
        runner.idle().add_done_callback(countdown.tick)
    ladder: Ladder[Sequence[CallbackRunner]] = Ladder(loop, grace, partial(_overdue, grace))
    ladder.watch(late)
    try:
        await wait_shielded(countdown.future)
    finally:
        ladder.close()


def _overdue(grace: float, runners: Sequence[CallbackRunner], stage: Stage) -> bool:
    """The ladder's step: escalate, then abandon, what each runner still runs."""
    for runner in runners:
        if runner.settled:
            continue
        if stage is Stage.ESCALATE:
            runner.escalate(grace)
        else:
            runner.abandon(grace)
    return True
