"""Running a monitor's callback, and keeping every task a monitor owns.

A callback is started from the write that fired the monitor, but no user code
runs inside the write: an action or a coroutine function only gets its task
created (its body starts at the next loop iteration), a plain function is
queued with ``call_soon``. Everything runs in the monitor's root context
(``current_action`` is None), so an action callback belongs to the robot's
root scope, whatever task wrote the state.
"""

from __future__ import annotations

import asyncio
import inspect
import logging
from collections import deque
from typing import TYPE_CHECKING, Any

from ..actions import Action, ActionHandle, BoundAction
from ..actions._where import location

if TYPE_CHECKING:
    from collections.abc import Callable, Sequence
    from contextvars import Context

_log = logging.getLogger("pyrobots_aio.events")

_PLAIN, _COROUTINE, _ACTION = "function", "coroutine function", "action"


def describe(callback: object, *, qualified: bool = True) -> str:
    """A name for ``callback``: its (qualified) name, or its repr."""
    if isinstance(callback, Action):
        return callback.name
    if isinstance(callback, BoundAction):
        return callback.action.name
    name = getattr(callback, "__qualname__" if qualified else "__name__", None)
    return name if isinstance(name, str) else repr(callback)


class CallbackRunner:
    """Starts one monitor's callback and keeps the tasks it owns until they end.

    ``busy`` counts the callbacks in flight (queued, running, or their action
    not done); ``settled`` also waits for the monitor's own tasks (async
    predicate evaluations), which `track` registers.
    """

    __slots__ = (
        "_actions",
        "_args",
        "_callback",
        "_calls",
        "_context",
        "_idle_waiters",
        "_kind",
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
    ) -> None:
        self._loop = loop
        self._robot = robot
        self._context = context
        self.label = "a monitor's callback"  # what log messages call it
        self._on_settled = on_settled
        self._callback: Callable[..., Any] | None = None
        self._args: tuple[Any, ...] = ()
        self._kind = _PLAIN
        self._calls: deque[asyncio.Handle] = deque()
        self._tasks: dict[asyncio.Task[Any], bool] = {}  # task -> is a callback
        self._actions: set[ActionHandle[Any]] = set()
        self._idle_waiters: list[asyncio.Future[None]] = []

    @property
    def callback(self) -> Callable[..., Any] | None:
        """The callback given to ``do()``, or None."""
        return self._callback

    def set(self, callback: object, args: tuple[Any, ...]) -> None:
        """Register ``callback(*args)`` (an action, a coroutine function or a function)."""
        if isinstance(callback, Action | BoundAction):
            self._kind = _ACTION
        elif inspect.iscoroutinefunction(callback):
            self._kind = _COROUTINE
        elif callable(callback):
            self._kind = _PLAIN
        else:
            msg = (
                f"do() takes an action, a coroutine function or a function, got {callback!r} "
                f"({type(callback).__name__})"
            )
            raise TypeError(msg)
        self._callback, self._args = callback, args

    @property
    def busy(self) -> bool:
        """Whether a callback is queued or running."""
        return bool(self._calls or self._actions or any(self._tasks.values()))

    @property
    def settled(self) -> bool:
        """Whether nothing this runner keeps is in flight."""
        return not (self._calls or self._actions or self._tasks)

    # -- starting -------------------------------------------------------------

    def start(self) -> None:
        """Start one run of the callback; it begins at the next loop iteration."""
        if self._kind == _PLAIN:
            context = self._context.copy()
            self._calls.append(self._loop.call_soon(self._call_plain, context=context))
        elif self._kind == _COROUTINE:
            assert self._callback is not None
            self.track(self._callback(*self._args), callback=True)
        else:
            self._start_action()

    def track(self, coro: Any, *, callback: bool = False) -> asyncio.Task[Any]:
        """Run ``coro`` as a task of this runner, in the monitor's context."""
        task = self._loop.create_task(coro, name=self.label, context=self._context.copy())
        self._tasks[task] = callback
        task.add_done_callback(self._task_done)
        return task

    def _start_action(self) -> None:
        callback = self._callback
        assert callback is not None
        args = (self._robot, *self._args) if isinstance(callback, Action) else self._args
        try:
            handle = self._context.copy().run(callback, *args)
        except Exception:
            _log.exception("%s could not start its action", self.label)
            return
        self._keep(handle)

    def _keep(self, handle: ActionHandle[Any]) -> None:
        """Count ``handle`` as a callback in flight until the action is done."""
        self._actions.add(handle)
        handle.add_done_callback(lambda: self._action_done(handle))

    def _call_plain(self) -> None:
        self._calls.popleft()
        assert self._callback is not None
        try:
            result = self._callback(*self._args)
        except Exception:
            _log.exception("%s failed", self.label)
        else:
            if inspect.iscoroutine(result):  # a function returning a coroutine: run it
                self.track(result, callback=True)
            elif isinstance(result, ActionHandle):  # ``lambda: robot.say("hi")``: keep it
                self._keep(result)
        self._check_settled()

    def _task_done(self, task: asyncio.Task[Any]) -> None:
        self._tasks.pop(task, None)
        if not task.cancelled() and (error := task.exception()) is not None:
            _log.error("%s failed", self.label, exc_info=error)
        self._check_settled()

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

    def escalate(self, grace: float) -> None:
        """Cancel again, with a warning, every task still running a grace after cancellation."""
        for task in self._tasks:
            _log.warning(
                "%s still running %.3g s after cancellation, at %s; cancelling it again",
                self.label,
                grace,
                location(task.get_coro()) or "an unknown place",
            )
            task.cancel("it ignored cancellation")

    def abandon(self, grace: float) -> None:
        """Forget, with an error, what is still running two graces after cancellation."""
        for task in self._tasks:
            _log.error(
                "%s ignored cancellation for %.3g s, at %s; abandoning it (its task may "
                "outlive the robot)",
                self.label,
                2 * grace,
                location(task.get_coro()) or "an unknown place",
            )
        self._tasks.clear()
        self._actions.clear()  # the executive's watchdog abandons those
        self._check_settled()


async def settle(runners: Sequence[CallbackRunner], grace: float) -> None:
    """Wait until every runner has settled, bounded by two graces.

    After one grace, tasks still running are cancelled again (a warning names
    where they are); after a second one they are abandoned (an error). If the
    waiting task is cancelled meanwhile, the bounded wait still completes, then
    the cancellation is re-raised (so robot shutdown never leaves tasks behind).
    """
    loop = asyncio.get_running_loop()
    interrupted: BaseException | None = None
    for stage in (CallbackRunner.escalate, CallbackRunner.abandon):
        deadline = loop.time() + grace
        while (late := [r for r in runners if not r.settled]) and deadline > loop.time():
            try:
                await asyncio.wait([r.idle() for r in late], timeout=deadline - loop.time())
            except asyncio.CancelledError as exc:
                interrupted = exc
        if not late:
            break
        for runner in late:
            stage(runner, grace)
    if interrupted is not None:
        raise interrupted
