"""ActionHandle: one running action, its outcome, and the task that drives it.

The task runs `drive`, which wraps the user's coroutine: it records the
outcome, cancels and awaits the children still running when the body ends, runs
the finalizers (resource release) and only then marks the handle done. The task
itself always ends normally, so nothing leaks as "exception never retrieved".
A handle works with ``asyncio.wait``, ``asyncio.gather`` and
``asyncio.as_completed`` as a future does: done-callbacks receive the handle.
(Over 400 lines: the handle and the task that drives it are one state machine,
kept in one place.)
"""

from __future__ import annotations

import asyncio
import enum
import traceback
import weakref
from threading import get_ident
from typing import TYPE_CHECKING, Any, Generic, TypeVar, cast

from .._core._loops import running_here, wrong_loop
from .._exceptions import ActionAbandoned, ActionInterrupted, ActionSkipped
from ._context import current_action
from ._pause import Stepped, frozen, frozen_time
from ._phases import DONE, FINISHING, PENDING, RUNNING
from ._where import definition, location

if TYPE_CHECKING:
    from collections.abc import Awaitable, Callable, Coroutine, Generator
    from types import TracebackType

    from .._core._logging import ScopedLogger
    from ._executive import Executive

T = TypeVar("T")
Hooks = tuple["Callable[[Any], object] | None", "Callable[[Any], object] | None"]
"""An action's pause and resume hooks, each called with the robot (or None)."""


class Outcome(enum.Enum):
    """How an action ended; ``NOT_DONE`` while it is pending, waiting or running."""

    NOT_DONE = "not_done"
    SUCCEEDED = "succeeded"
    FAILED = "failed"
    CANCELLED = "cancelled"
    SKIPPED = "skipped"


class ActionState(enum.Enum):
    """Where an action is in its life, as `ActionInfo.state` reports it."""

    PENDING = "pending"
    """Started, its task not yet scheduled."""
    WAITING = "waiting"
    """Waiting for a resource."""
    RUNNING = "running"
    CANCELLING = "cancelling"
    """Cancellation requested; its cleanup is running."""
    PAUSED = "paused"
    """Frozen where it stands: it or an ancestor was paused (`ActionHandle.pause`).

    Or suspended: a ``@lock(..., preempt="suspend")`` request borrows its resource.
    """
    FINISHING = "finishing"
    """Its body has ended; its children are being cancelled and awaited."""
    DONE = "done"


_PHASE_STATES = {
    PENDING: ActionState.PENDING,
    FINISHING: ActionState.FINISHING,
    DONE: ActionState.DONE,
}


class ActionHandle(Generic[T]):
    """A started action: await it for its result, cancel it, inspect it.

    Example:
        >>> import asyncio
        >>> from pyrobots_aio import Outcome, Robot, action
        >>> @action
        ... async def walk(robot: Robot, speed: float) -> None:
        ...     await robot.sleep(3600)
        >>> async def main() -> Outcome:
        ...     async with Robot(actions=[walk]) as robot:
        ...         handle = robot.walk(0.2)  # scheduled at once, not awaited
        ...         handle.cancel("bumper hit")  # returns at once
        ...         return await handle.wait_done()  # waits, never raises
        >>> asyncio.run(main())
        <Outcome.CANCELLED: 'cancelled'>
    """

    __slots__ = (
        "__weakref__",
        "_callbacks",
        "_cancel_by",
        "_cancel_reason",
        "_cancel_requested",
        "_children",
        "_coro",
        "_error",
        "_executive",
        "_finalizers",
        "_fn",
        "_frozen_since",
        "_frozen_total",
        "_hooks",
        "_internal",
        "_loop",
        "_outcome",
        "_pause_reason",
        "_paused",
        "_paused_by",
        "_phase",
        "_suspended",
        "_task",
        "_thaw",
        "_unretrieved",
        "_value",
        "_waiters",
        "awaiting",
        "finished_at",
        "held",
        "id",
        "name",
        "parent",
        "spawned_at",
        "started_at",
    )

    def __init__(
        self,
        executive: Executive,
        loop: asyncio.AbstractEventLoop,
        ident: int,
        name: str,
        parent: ActionHandle[Any] | None,
        *,
        spawned_at: float,
    ) -> None:
        self._executive = executive
        self._loop = loop
        self.id = ident
        self.name = name
        self.parent = parent
        self.spawned_at = spawned_at
        self.started_at: float | None = None
        self.finished_at: float | None = None
        self.held: tuple[str, ...] = ()
        self.awaiting: tuple[str, ...] = ()
        self._children: dict[ActionHandle[Any], None] = {}
        self._task: asyncio.Task[None] | None = None
        self._coro: Coroutine[Any, Any, T] | None = None
        self._fn: Callable[..., object] | None = None
        self._phase = PENDING
        self._outcome = Outcome.NOT_DONE
        self._value: T | None = None
        self._error: BaseException | None = None
        self._cancel_requested = False
        self._cancel_reason: str | None = None
        self._cancel_by: ActionHandle[Any] | None = None
        self._waiters: list[asyncio.Future[None]] | None = None
        self._callbacks: list[Callable[[ActionHandle[T]], object]] | None = None
        self._internal: list[Callable[[ActionHandle[T]], object]] | None = None
        self._finalizers: list[Callable[[], None]] | None = None
        self._unretrieved: weakref.finalize[Any, Any] | None = None
        self._paused = False
        self._pause_reason: str | None = None
        self._paused_by: ActionHandle[Any] | None = None
        self._suspended: str | None = None
        """The reason of the suspension that lends its resources to a preemptor, if any."""
        self._frozen_since: float | None = None
        self._frozen_total = 0.0
        self._thaw: asyncio.Future[None] | None = None
        self._hooks: Hooks | None = None

    # -- awaiting ---------------------------------------------------------

    def __await__(self) -> Generator[Any, None, T]:
        # A generator, with its helpers inlined: every awaited action pays for this.
        if self._phase != DONE:
            loop = self._loop
            if get_ident() != self._executive.thread_ident or not loop.is_running():
                what = f"await action {self.name}#{self.id}"  # running_here(), inlined
                raise wrong_loop(what, loop, self._executive.thread)
            fut: asyncio.Future[None] = asyncio.Future(loop=loop)
            if self._waiters is None:
                self._waiters = [fut]
            else:
                self._waiters.append(fut)
            try:
                yield from fut
            except asyncio.CancelledError:  # awaiting owns the action, as awaiting a task does
                reason = "the task awaiting it was cancelled"
                self._executive.cancel_tree(self, reason, current_action.get())
                raise
            finally:
                if not fut.done() and self._waiters is not None:
                    self._waiters.remove(fut)
        if self._unretrieved is not None:
            self._retrieved()
        if self._error is not None:
            raise self._error
        return self._value  # type: ignore[return-value]

    async def wait(self) -> T:
        """Wait for the action and return its result (pyRobots' spelling of ``await handle``).

        Like ``await handle``, it owns the action: if the waiting task is
        cancelled (a deadline of the caller's), the action is cancelled too.

        Raises:
            ActionInterrupted: The action was cancelled.
            ActionSkipped: The action did not run (a resource was busy).
            Exception: Whatever the action raised.
        """
        return await self

    async def wait_done(self) -> Outcome:
        """Wait until the action is done and return its `Outcome`, never raising its error.

        It does not own the action: a waiter that gives up (cancelled, or its
        ``asyncio.timeout`` expired) leaves the action running. ``await handle``
        owns it instead.
        """
        if self._phase != DONE:
            fut = self._waiter("wait for")
            try:
                await fut
            finally:
                self._forget_waiter(fut)
        self._retrieved()
        return self._outcome

    def _waiter(self, verb: str) -> asyncio.Future[None]:
        """A future the action's end completes; the caller must be on the robot's loop."""
        self._check_here(verb)
        fut = self._loop.create_future()
        if self._waiters is None:
            self._waiters = [fut]
        else:
            self._waiters.append(fut)
        return fut

    def _check_here(self, verb: str) -> None:
        """Raise `EventLoopError` unless the caller runs on the robot's loop.

        From another thread, the call would change the action behind the loop's
        back and take effect only when the loop next wakes (seconds later on an
        idle loop); the error names the thread-safe way in.
        """
        if not running_here(self._loop, self._executive.thread_ident):
            what = f"{verb} action {self.name}#{self.id}"
            raise wrong_loop(what, self._loop, self._executive.thread)

    def _forget_waiter(self, fut: asyncio.Future[None]) -> None:
        if not fut.done() and self._waiters is not None:
            self._waiters.remove(fut)

    # -- inspecting -------------------------------------------------------

    @property
    def outcome(self) -> Outcome:
        """The outcome so far (`Outcome.NOT_DONE` until the action is done)."""
        return self._outcome

    @property
    def state(self) -> ActionState:
        """Where the action is now (pending, waiting, running, cancelling, finishing, done)."""
        phase = self._phase
        if phase != RUNNING:
            return _PHASE_STATES[phase]
        if self._cancel_requested:
            return ActionState.CANCELLING
        if self._executive.paused and frozen(self):
            return ActionState.PAUSED
        return ActionState.WAITING if self.awaiting else ActionState.RUNNING

    @property
    def children(self) -> tuple[ActionHandle[Any], ...]:
        """The children of this action that are still running, oldest first."""
        return tuple(self._children)

    @property
    def cancel_reason(self) -> str | None:
        """The reason given when cancellation was requested, or None."""
        return self._cancel_reason

    @property
    def cancel_requested(self) -> bool:
        """Whether cancellation of this action has been requested."""
        return self._cancel_requested

    def done(self) -> bool:
        """Return True once the action has finished (any outcome), cleanup and children included."""
        return self._phase == DONE

    def cancelled(self) -> bool:
        """Return True if the action finished with outcome `Outcome.CANCELLED`."""
        return self._outcome is Outcome.CANCELLED

    def result(self) -> T:
        """Return the result of a finished action, or raise what awaiting it would raise.

        Raises:
            asyncio.InvalidStateError: The action is not done yet.
        """
        error = self.exception()
        if error is not None:
            raise error
        return self._value  # type: ignore[return-value]

    def exception(self) -> BaseException | None:
        """Return what awaiting the finished action would raise, or None if it succeeded.

        Raises:
            asyncio.InvalidStateError: The action is not done yet.
        """
        if self._phase != DONE:
            msg = f"action {self.name}#{self.id} is not done yet; await it or use wait_done()"
            raise asyncio.InvalidStateError(msg)
        self._retrieved()
        return self._error

    def childof(self, other: ActionHandle[Any]) -> bool:
        """Return True if ``other`` is this action's parent or a further ancestor."""
        node = self.parent
        while node is not None:
            if node is other:
                return True
            node = node.parent
        return False

    def location(self) -> str | None:
        """Return the ``file:line`` where the action's body is now suspended, if it runs."""
        if self._coro is None or self._phase != RUNNING:
            return None
        where = location(self._coro)
        if where is None and self._fn is not None:  # only internal frames: waiting for a lock
            where = definition(self._fn)
        return where

    # -- cancelling -------------------------------------------------------

    def cancel(self, reason: str | None = None) -> bool:
        """Request cancellation of this action and its whole subtree; return at once.

        The action sees `ActionCancelled` at its next ``await``; its cleanup may
        await. Returns False if the action was already done.

        Raises:
            EventLoopError: Called from another thread (use
                ``robot.call_soon_threadsafe(handle.cancel, reason)``).
        """
        if self._phase == DONE:
            return False
        self._check_here("cancel")
        self._executive.cancel_tree(self, reason, current_action.get())
        return True

    def pause(self, reason: str | None = None) -> bool:
        """Freeze this action and its subtree where they stand, without unwinding them.

        Each frozen action stops at its next resumption point (whatever it
        awaits may complete, but its code does not go on) until `resume`.
        Resources stay held; `Robot.sleep` does not count the frozen time;
        cancellation still reaches it at once (and its cleanup runs unfrozen).
        Pause hooks (``@action(on_pause=...)``) run now. Returns False if the
        action is done.

        Raises:
            EventLoopError: Called from another thread (use
                ``robot.call_soon_threadsafe(handle.pause, reason)``).

        Example:
            >>> import asyncio
            >>> from pyrobots_aio import Robot, action
            >>> @action
            ... async def count(robot: Robot, ticks: list[float]) -> None:
            ...     for _ in range(3):
            ...         await robot.sleep(1)
            ...         ticks.append(robot.time())
            >>> async def main() -> list[float]:
            ...     ticks: list[float] = []
            ...     async with Robot() as robot:
            ...         handle = count(robot, ticks)
            ...         await robot.sleep(1.5)
            ...         handle.pause("hold still")
            ...         await robot.sleep(10)
            ...         handle.resume()
            ...         await handle
            ...     return ticks
            >>> from pyrobots_aio.sim import run
            >>> run(main)  # ten frozen seconds in the middle of the second tick
            [1.0, 12.0, 13.0]
        """
        if self._phase == DONE:
            return False
        self._check_here("pause")
        self._executive.pause_tree(self, reason, current_action.get())
        return True

    def resume(self) -> bool:
        """Thaw what `pause` froze (descendants paused on their own stay paused).

        Returns False if this action was not paused (or is done).

        Raises:
            EventLoopError: Called from another thread (use
                ``robot.call_soon_threadsafe(handle.resume)``).
        """
        if self._phase == DONE:
            return False
        self._check_here("resume")
        if not self._paused:
            return False
        self._executive.resume_tree(self)
        return True

    @property
    def paused(self) -> bool:
        """Whether it is frozen: paused itself, or under a paused ancestor (and not cancelled)."""
        return bool(self._executive.paused) and frozen(self)

    @property
    def pause_reason(self) -> str | None:
        """The reason given to `pause` on this action, while it is paused.

        While it is not paused but suspended (a ``@lock(..., preempt="suspend")``
        request borrows its resource), the suspension's reason, which names the
        preemptor.
        """
        return self._pause_reason if self._paused else self._suspended

    def frozen_time(self) -> float:
        """Seconds (on the robot's clock) this action has spent frozen so far."""
        return frozen_time(self)

    # -- executive side ---------------------------------------------------

    def _suspend(self, reason: str, by: object) -> None:
        """Freeze this subtree while a preemptor borrows its resource (the resources layer's call).

        Apart from any pause: `resume` does not end it, `_unsuspend` does.
        """
        if self._phase != DONE:
            borrower = by if isinstance(by, ActionHandle) else None
            self._executive.suspend_tree(self, reason, borrower)

    def _unsuspend(self) -> None:
        """End the suspension: thaw what is no longer paused, run the resume hooks."""
        if self._phase != DONE:
            self._executive.unsuspend_tree(self)

    def add_finalizer(self, finalizer: Callable[[], None]) -> None:
        """Run ``finalizer()`` when the action ends, after its children, before it is done.

        The resources layer releases locks here, so a resource is held until the
        action's cleanup and its children are over. For an action the watchdog
        abandoned, they run when its task really ends, not when it is declared
        done: its resources stay held while its code may still drive them.
        """
        if self._finalizers is None:
            self._finalizers = []
        self._finalizers.append(finalizer)

    def add_done_callback(self, callback: Callable[[ActionHandle[T]], object]) -> None:
        """Call ``callback(handle)`` once the action is done, as asyncio's futures do.

        It is scheduled on the loop (``call_soon``) when the action is done, or at
        once if it already is. An exception in it is logged with its traceback on
        ``pyrobots_aio.actions`` and disturbs nothing else.
        """
        if self._phase == DONE:
            _schedule(callback, self)
            return
        if self._callbacks is None:
            self._callbacks = []
        self._callbacks.append(callback)

    def remove_done_callback(self, callback: Callable[[ActionHandle[T]], object]) -> int:
        """Remove every registration of ``callback``; return how many were removed."""
        if not self._callbacks:
            return 0
        kept = [cb for cb in self._callbacks if cb != callback]
        removed = len(self._callbacks) - len(kept)
        self._callbacks = kept
        return removed

    def _on_done(self, callback: Callable[[ActionHandle[T]], object]) -> None:
        """Call ``callback(handle)`` synchronously when done, before the done-callbacks.

        For the library's own bookkeeping (waiting for several actions, resource
        records, monitor callbacks in flight); the action must not be done yet.
        """
        if self._internal is None:
            self._internal = []
        self._internal.append(callback)

    def _interrupt(self) -> None:
        """Throw `ActionCancelled` into the body at its current await, if the body runs.

        A pending action is not touched: `drive` sees the request and never starts
        the body; a finishing one only waits for its (cancelled) children.
        """
        if self._phase == RUNNING and self._task is not None:
            self._task.cancel(self._cancel_reason)

    def _abandon(self, after: float) -> None:
        """Declare the action done (CANCELLED), then end its body and its task.

        `ActionAbandoned` (a ``BaseException``: ``except Exception`` and ``except
        ActionCancelled`` let it through) is thrown into the body at its current
        ``await``, and its task is cancelled, so that it ends and nothing (not
        ``asyncio.run``) waits for it forever. A body that catches even that
        runs on; its resources are released when its task has really ended.
        """
        task, body = self._task, self._coro
        self._settle(Outcome.CANCELLED, error=self._interrupted())
        self._complete(release=False)
        if task is None or task.done() or body is None:
            return
        try:
            body.throw(
                ActionAbandoned(
                    f"action {self.name}#{self.id} ignored cancellation for {after:.3g} s"
                )
            )
        except BaseException:  # the body ended, as it should: its task is cancelled below
            resisted = False
        else:  # it caught even that, and awaits again
            resisted = True
        if resisted:
            self._executive.log.error(
                "action %s#%d resisted being abandoned (it catches BaseException); its task "
                "and its resources live on until it ends",
                self.name,
                self.id,
            )
        task.cancel("abandoned: it ignored cancellation")

    def _interrupted(self, cause: BaseException | None = None) -> ActionInterrupted:
        error = ActionInterrupted(self, self._cancel_reason, self._cancel_by)
        error.__cause__ = cause
        return error

    def _settle(
        self, outcome: Outcome, value: Any = None, error: BaseException | None = None
    ) -> None:
        if self._phase == DONE:  # abandoned by the watchdog: its outcome is already told
            return
        self._outcome = outcome
        self._value = value
        self._error = error

    def _complete(self, *, release: bool = True) -> None:
        """Mark the action done and wake whoever waits for it (idempotent).

        With ``release`` False (an abandoned action) the finalizers wait for its
        task to end.
        """
        if self._phase == DONE:
            return
        if release and self._finalizers is not None:
            self._run_finalizers()
        executive = self._executive
        if executive.paused and (self._paused or self._suspended is not None):
            executive.unpause(self)
        self._phase = DONE
        self._coro = None
        self.finished_at = executive.clock()
        if self._callbacks is not None:  # scheduled first: they run before awaiters resume
            callbacks, self._callbacks = self._callbacks, None
            for callback in callbacks:
                _schedule(callback, self)
        waiting = False
        if self._waiters is not None:
            for fut in self._waiters:
                if not fut.done():
                    fut.set_result(None)
                    waiting = True
            self._waiters = None
        self._task = None  # the task's context refers back to this handle
        if self._outcome is Outcome.FAILED and not waiting:
            self._report_unless_retrieved()
        executive.finished(self)
        if self._internal is not None:
            internal, self._internal = self._internal, None
            for callback in internal:
                _call_back(callback, self)

    def _forgotten(self) -> bool:
        """Whether the action never started and nothing waits for it (a missing ``await``?)."""
        return self.started_at is None and not (
            self._cancel_requested or self._waiters or self._callbacks
        )

    def _report_unless_retrieved(self) -> None:
        """Log the failure once this handle is forgotten, unless its error was retrieved.

        Like asyncio's "exception was never retrieved": a handle kept and awaited
        later is not reported. The report is written now and the finalizer holds
        only its text: the error may refer back to this handle (a child's
        ActionInterrupted, a traceback's frames), which would keep it alive.
        """
        error = self._error
        report = "".join(traceback.format_exception(error)).rstrip() if error is not None else ""
        self._unretrieved = weakref.finalize(
            self, _report_failure, self._executive.log, self.name, self.id, report
        )

    def _retrieved(self) -> None:
        if self._unretrieved is not None:
            self._unretrieved.detach()
            self._unretrieved = None

    def _run_finalizers(self) -> None:
        if self._finalizers is None:
            return
        finalizers, self._finalizers = self._finalizers, None
        for finalizer in reversed(finalizers):
            try:
                finalizer()
            except Exception:
                self._executive.log.exception(
                    "finalizer of action %s#%d failed", self.name, self.id
                )

    def __repr__(self) -> str:
        parent = f" parent={self.parent.name}#{self.parent.id}" if self.parent else ""
        return f"<ActionHandle {self.name}#{self.id} {self.state.value}{parent}>"


async def drive(  # noqa: PLR0912 (one flat coroutine: every action pays for each frame)
    handle: ActionHandle[T], coro: Coroutine[Any, Any, T]
) -> None:
    """Run an action's body in its own task, then wind it up (the task's coroutine)."""
    current_action.set(handle)
    try:
        never_ran = handle._cancel_requested  # a local: the attribute changes while it runs
        if never_ran:  # cancelled before it ever ran: the body never starts
            coro.close()
            handle._settle(Outcome.CANCELLED, error=handle._interrupted())
        else:
            handle._coro = coro
            handle._phase = RUNNING
            executive = handle._executive
            handle.started_at = executive.clock()
            if executive.instruments.items:
                executive.started(handle)
            try:
                value = await cast("Awaitable[T]", Stepped(handle, coro))
            except (KeyboardInterrupt, SystemExit) as exc:  # record, then let through
                handle._settle(Outcome.FAILED, error=exc)
                handle._complete()
                raise
            except BaseException as exc:
                if handle._phase == DONE:  # abandoned: how its body ends changes nothing
                    return
                _settle_error(handle, exc)
            else:
                if handle._phase == DONE:
                    return
                if handle._cancel_requested:  # cancellation swallowed: still CANCELLED
                    handle._settle(Outcome.CANCELLED, value, handle._interrupted())
                else:
                    handle._outcome, handle._value = Outcome.SUCCEEDED, value
        handle._phase = FINISHING
        if handle._children:
            await _reap(handle)
        if handle._cancel_requested and handle._outcome is Outcome.SUCCEEDED:
            # cancelled while its children wound up: CANCELLED (a failure is never masked)
            handle._settle(Outcome.CANCELLED, error=handle._interrupted())
        handle._complete()
    finally:  # an abandoned action releases its resources only once its task ends
        if handle._finalizers is not None:
            handle._run_finalizers()


async def _reap(handle: ActionHandle[Any]) -> None:
    """Wait for the children still running when the body ended (the executive's rules)."""
    try:
        while handle._children:
            try:
                await handle._executive.reap_children(handle)
            except asyncio.CancelledError:
                # Meant for the body, which ended before it arrived (it returned without
                # awaiting again): the children still get waited for.
                continue
    except BaseException:
        handle._complete()
        raise


def _settle_error(handle: ActionHandle[Any], exc: BaseException) -> None:
    if isinstance(exc, asyncio.CancelledError):
        handle._settle(Outcome.CANCELLED, error=handle._interrupted())
    elif isinstance(exc, ActionSkipped) and exc.handle is None:
        # Its own lock request was refused. A skip that already names an action is a
        # child's, re-raised by awaiting it: for this action, an ordinary failure.
        exc.handle = handle
        handle._settle(Outcome.SKIPPED, error=exc)
    elif handle._cancel_requested:
        handle._executive.log.warning(
            "action %s#%d failed during its cleanup", handle.name, handle.id, exc_info=exc
        )
        handle._settle(Outcome.CANCELLED, error=handle._interrupted(exc))
    else:
        handle._settle(Outcome.FAILED, error=exc.with_traceback(_from_the_body(exc)))


def _from_the_body(error: BaseException) -> TracebackType | None:
    """The traceback of ``error`` from the action's own code on.

    The executive's frames (the task's and the pause trampoline's) are dropped:
    they hold the handle, which holds the error, and the cycle would keep a
    forgotten failure from being reported when its handle goes.
    """
    tb = error.__traceback__
    while tb is not None and tb.tb_frame.f_globals.get("__name__") in _OWN_MODULES:
        tb = tb.tb_next
    return tb


_OWN_MODULES = frozenset({__name__, frozen.__module__})  # the task's and the trampoline's


def _report_failure(log: ScopedLogger, name: str, ident: int, report: str) -> None:
    log.error("action %s#%d failed and nobody retrieved its error:\n%s", name, ident, report)


def _schedule(callback: Callable[[ActionHandle[Any]], object], handle: ActionHandle[Any]) -> None:
    """Run a done-callback soon on the robot's loop (at once if no loop runs any more)."""
    loop = handle._executive._loop or asyncio._get_running_loop()
    if loop is None:
        _call_back(callback, handle)
    else:
        loop.call_soon(_call_back, callback, handle)


def _call_back(callback: Callable[[ActionHandle[Any]], object], handle: ActionHandle[Any]) -> None:
    """Call a done-callback; log what it raises (it must not disturb the executive)."""
    try:
        callback(handle)
    except Exception:
        handle._executive.log.exception(
            "done-callback %r of action %s#%d failed", callback, handle.name, handle.id
        )
