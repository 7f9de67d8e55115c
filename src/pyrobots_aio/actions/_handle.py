"""ActionHandle: one running action, its outcome, and the task that runs it.

The handle owns its action's whole story, and writes all of its state. Its
task runs `ActionHandle._run`: the body (through the pause trampoline,
`Stepped`), then the wind-up: record the outcome, cancel and await the
children still running when the body ended, run the finalizers (resource
release) and only then mark the handle done. Cancelling walks the subtree
here, each action marking itself and cancelling its task, whose coroutine
above settles the handle: handle, task, handle. Pausing and suspending walk
it here too, through each action's `Freeze`. The executive that started it
(its `Host`) keeps the registry, watches cancelled actions with the grace
ladder, and tells the instruments.

The task itself always ends normally, so nothing leaks as "exception never
retrieved". A handle works with ``asyncio.wait``, ``asyncio.gather`` and
``asyncio.as_completed`` as a future does: done-callbacks receive the handle.
(Over 400 lines: the handle and the task that runs it are one state machine,
kept in one place.)
"""

from __future__ import annotations

import asyncio
import traceback
import weakref
from contextvars import ContextVar
from threading import get_ident
from typing import TYPE_CHECKING, Any, Generic, Protocol, TypeVar

from .._core._loops import running_here, wrong_loop
from .._core._waiting import Countdown
from .._exceptions import ActionAbandoned, ActionInterrupted, ActionSkipped
from ._pause import Freeze, Hook, Stepped, run_hooks
from ._states import ActionState, Outcome
from ._where import definition, location

if TYPE_CHECKING:
    from collections.abc import Callable, Coroutine, Generator, Iterable
    from types import FrameType, TracebackType

    from .._core._instrument import Instruments
    from .._core._logging import ScopedLogger
    from ..resources import ResourceManager
    from ._pause import Hooks

T = TypeVar("T")

_new = object.__new__
_Task, _Future = asyncio.Task, asyncio.Future
# A waiter is an asyncio.Future (the C one): its methods, called unbound, are specialized
# calls on Python 3.11 (a bound method call on an instance with a dict slot is not).
_done, _set_result = asyncio.Future.done, asyncio.Future.set_result
# Enum members as module globals: on Python 3.11 each ``Outcome.X`` is a slow class lookup
# (70 ns, through the enum's metaclass), and the hot paths read several.
PENDING, RUNNING = ActionState.PENDING, ActionState.RUNNING
FINISHING, DONE = ActionState.FINISHING, ActionState.DONE
"""The phases a handle goes through, in order (its other states are read from `RUNNING`)."""
CANCELLING, PAUSED, WAITING = ActionState.CANCELLING, ActionState.PAUSED, ActionState.WAITING
NOT_DONE, SUCCEEDED, FAILED = Outcome.NOT_DONE, Outcome.SUCCEEDED, Outcome.FAILED
CANCELLED, SKIPPED = Outcome.CANCELLED, Outcome.SKIPPED

current_action: ContextVar[ActionHandle[Any] | None] = ContextVar(
    "pyrobots_aio.current_action", default=None
)
"""The action whose body (or cleanup) the running task belongs to; None outside actions."""


class Host(Protocol):
    """What a handle needs of the executive that started it (`Executive` is one)."""

    owner: object
    """The robot, given to pause hooks."""
    thread: str
    thread_ident: int
    clock: Callable[[], float]
    plain_tasks: bool
    """Whether the loop's ``create_task`` makes a plain ``asyncio.Task`` (no task factory)."""
    log: ScopedLogger
    instruments: Instruments
    resources: ResourceManager[Any]

    @property
    def is_running(self) -> bool:
        """Whether the robot runs (its loop is `loop`)."""

    @property
    def loop(self) -> asyncio.AbstractEventLoop:
        """The robot's loop."""

    def started(self, handle: ActionHandle[Any]) -> None:
        """The body of ``handle`` starts (called only when instruments listen)."""

    def finished(self, handle: ActionHandle[Any]) -> None:
        """``handle`` is done: forget it."""

    def cancelling(
        self, handle: ActionHandle[Any], reason: str | None, by: ActionHandle[Any] | None
    ) -> None:
        """Cancellation of ``handle`` is requested: bound its cleanup in time."""

    def froze(
        self,
        handle: ActionHandle[Any],
        nodes: list[ActionHandle[Any]],
        reason: str | None,
        by: ActionHandle[Any] | None,
    ) -> None:
        """Pausing or suspending ``handle`` froze ``nodes``."""

    def thawed(self, handle: ActionHandle[Any], nodes: list[ActionHandle[Any]]) -> None:
        """Resuming or unsuspending ``handle`` thawed ``nodes``."""


class ActionHandle(Generic[T]):
    """A started action: await it for its result, cancel it, inspect it.

    Examples:
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
        "_cancel",
        "_children",
        "_coro",
        "_error",
        "_executive",
        "_finalizers",
        "_fn",
        "_freeze",
        "_hooks",
        "_internal",
        "_loop",
        "_outcome",
        "_phase",
        "_task",
        "_unretrieved",
        "_value",
        "_waiters",
        "finished_at",
        "id",
        "name",
        "parent",
        "started_at",
    )

    id: int
    name: str
    parent: ActionHandle[Any] | None
    started_at: float | None
    finished_at: float | None
    _executive: Host
    _loop: asyncio.AbstractEventLoop
    _fn: Callable[..., object]
    _hooks: Hooks | None
    _phase: ActionState
    _outcome: Outcome
    _value: T | None
    _error: BaseException | None
    _coro: Coroutine[Any, Any, T] | None
    _task: asyncio.Task[None] | None
    _children: dict[ActionHandle[Any], None] | None
    _cancel: tuple[str | None, ActionHandle[Any] | None] | None
    """Why and by whom cancellation was requested, once it was."""
    _freeze: Freeze | None
    _waiters: asyncio.Future[None] | list[asyncio.Future[None]] | None
    """The futures of the tasks awaiting it: one bare (the usual case), or a list of several."""
    _callbacks: list[Callable[[ActionHandle[T]], object]] | None
    _internal: list[Callable[[ActionHandle[T]], object]] | None
    _finalizers: list[Callable[[], None]] | None
    _unretrieved: weakref.finalize[Any, Any] | None

    @classmethod
    def _start(  # noqa: PLR0917 (every action pays for each call: positional is the cheapest)
        cls,
        executive: Host,
        loop: asyncio.AbstractEventLoop,
        ident: int,
        name: str,
        parent: ActionHandle[Any] | None,
        fn: Callable[..., object],
        hooks: Hooks | None,
        coro: Coroutine[Any, Any, T],
    ) -> ActionHandle[T]:
        """Start ``coro`` (made by the action function ``fn``) as the task of a new action.

        Not ``__init__``: calling a class costs an action a tenth more than this
        (Python 3.11 calls ``__init__`` through the generic path, with an argument tuple).
        """
        self: ActionHandle[T] = _new(cls)
        self._executive = executive
        self._loop = loop
        self.id = ident
        self.name = name
        self.parent = parent
        self._fn = fn
        self._hooks = hooks
        self.started_at = None
        self.finished_at = None
        self._phase = PENDING
        self._outcome = NOT_DONE
        self._value = None
        self._error = None
        self._coro = coro  # (`location` reads it only once the body runs)
        self._children = None
        self._cancel = None
        self._freeze = None
        self._waiters = None
        self._callbacks = None
        self._internal = None
        self._finalizers = None
        self._unretrieved = None
        if parent is not None:
            parent._adopt(self)
        run, task_name = self._run(coro), f"{name}#{ident}"
        if executive.plain_tasks:  # what loop.create_task would make, two Python calls sooner
            self._task = _Task(run, loop=loop, name=task_name)
        else:
            self._task = loop.create_task(run, name=task_name)
        return self

    def _adopt(self, child: ActionHandle[Any]) -> None:
        """Take ``child`` as a child; a child of a frozen action starts frozen."""
        if self._children is None:
            self._children = {child: None}
        else:
            self._children[child] = None
        freeze = self._freeze
        if freeze is not None and freeze.since is not None:
            child._frozen_from(self._loop.time())

    # -- awaiting ---------------------------------------------------------

    def __await__(self) -> Generator[Any, None, T]:
        # A generator, with its helpers inlined: every awaited action pays for this.
        if self._phase is not DONE:
            loop = self._loop
            if get_ident() != self._executive.thread_ident or not loop.is_running():
                what = f"await action {self.name}#{self.id}"  # running_here(), inlined
                raise wrong_loop(what, loop, self._executive.thread)
            fut: asyncio.Future[None] = _Future(loop=loop)
            if self._waiters is None:  # (`_add_waiter`'s usual case, here without the call)
                self._waiters = fut
            else:
                self._add_waiter(fut)
            try:
                yield from fut
            except asyncio.CancelledError:  # awaiting owns the action, as awaiting a task does
                self._forget_waiter(fut)
                self._cancel_subtree("the task awaiting it was cancelled", current_action.get())
                raise
            except BaseException:  # closed, or something else thrown in: it waits no more
                self._forget_waiter(fut)
                raise
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
        if self._phase is not DONE:
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
        fut: asyncio.Future[None] = _Future(loop=self._loop)
        self._add_waiter(fut)
        return fut

    def _add_waiter(self, fut: asyncio.Future[None]) -> None:
        """Count ``fut`` among the futures that the action's end completes."""
        waiters = self._waiters
        if waiters is None:
            self._waiters = fut
        elif isinstance(waiters, list):
            waiters.append(fut)
        else:
            self._waiters = [waiters, fut]

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
        """``fut``'s task awaits the action no more (a done one is forgotten already)."""
        if _done(fut):
            return
        waiters = self._waiters
        if waiters is fut:
            self._waiters = None
        elif isinstance(waiters, list):
            waiters.remove(fut)

    # -- inspecting -------------------------------------------------------

    @property
    def outcome(self) -> Outcome:
        """The outcome so far (`NOT_DONE` until the action is done)."""
        return self._outcome

    @property
    def state(self) -> ActionState:
        """Where the action is now (pending, waiting, running, cancelling, finishing, done)."""
        return self._state(bool(self._executive.resources.awaited_by(self)))

    def _state(self, waiting: bool) -> ActionState:
        """`state`, given whether the action waits for a resource (its manager's answer)."""
        phase = self._phase
        if phase is not RUNNING:
            return phase
        if self._cancel is not None:
            return CANCELLING
        if self._freeze is not None and self._freeze.since is not None:
            return PAUSED
        return WAITING if waiting else RUNNING

    @property
    def held(self) -> tuple[str, ...]:
        """Names of the resources it holds (the robot's resource manager answers)."""
        return self._executive.resources.held_by(self)

    @property
    def awaiting(self) -> tuple[str, ...]:
        """Names of the resources it waits for (the robot's resource manager answers)."""
        return self._executive.resources.awaited_by(self)

    @property
    def children(self) -> tuple[ActionHandle[Any], ...]:
        """The children of this action that are still running, oldest first."""
        return () if self._children is None else tuple(self._children)

    @property
    def cancel_reason(self) -> str | None:
        """The reason given when cancellation was requested, or None."""
        return None if self._cancel is None else self._cancel[0]

    @property
    def cancel_requested(self) -> bool:
        """Whether cancellation of this action has been requested."""
        return self._cancel is not None

    def done(self) -> bool:
        """Return True once the action has finished (any outcome), cleanup and children included."""
        return self._phase is DONE

    def cancelled(self) -> bool:
        """Return True if the action finished with outcome `CANCELLED`."""
        return self._outcome is CANCELLED

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
        if self._phase is not DONE:
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

    def runs_in(self, task: object) -> bool:
        """Whether ``task`` is the task running this action.

        The loop watchdog asks, from its own thread, which action blocks the
        loop (it only reads).
        """
        return self._task is task

    def body_frame(self) -> FrameType | None:
        """The frame of the action's body until the action is done, else None.

        The loop watchdog looks there, from its own thread, for the line that
        blocks the loop.
        """
        return getattr(self._coro, "cr_frame", None)

    def location(self) -> str | None:
        """Return the ``file:line`` where the action's body is now suspended, if it runs."""
        if self._coro is None or self._phase is not RUNNING:
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
        if self._phase is DONE:
            return False
        self._check_here("cancel")
        self._cancel_subtree(reason, current_action.get())
        return True

    def _cancel_subtree(self, reason: str | None, by: ActionHandle[Any] | None) -> None:
        """Cancel this action and every descendant it has now, recording who and why.

        An action already cancelled is passed over with its subtree: what it
        started since its cancellation is its cleanup, which a second cancel
        never cuts short (the executive's grace ladder bounds it, counted from
        the first). Each cancelled action thaws (its cleanup runs), its task is
        cancelled, and its executive starts watching it.
        """
        stack: list[ActionHandle[Any]] = [self]
        while stack:
            node = stack.pop()
            if node._cancel is not None or node._phase is DONE:
                continue
            if node._children:
                stack.extend(node._children)
            node._cancel = (reason, by)
            if node._freeze is not None:
                node._freeze.end(node._loop.time())
            node._interrupt()
            node._executive.cancelling(node, reason, by)

    def _interrupt(self) -> None:
        """Throw `ActionCancelled` into the body at its current await, if the body runs.

        A pending action is not touched: `_run` sees the request and never starts
        the body; a finishing one only waits for its (cancelled) children.
        """
        if self._phase is RUNNING and self._task is not None and self._cancel is not None:
            self._task.cancel(self._cancel[0])

    def _abandon(self, after: float) -> None:
        """Declare the action done (CANCELLED), then end its body and its task.

        `ActionAbandoned` (a ``BaseException``: ``except Exception`` and ``except
        ActionCancelled`` let it through) is thrown into the body at its current
        ``await``, and its task is cancelled, so that it ends and nothing (not
        ``asyncio.run``) waits for it forever. A body that catches even that
        runs on; its resources are released when its task has really ended.
        """
        task, body = self._task, self._coro if self._phase is RUNNING else None
        self._settle(CANCELLED, error=self._interrupted())
        self._complete(False)
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

    # -- pausing ----------------------------------------------------------

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

        Examples:
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
        if self._phase is DONE:
            return False
        self._check_here("pause")
        by = current_action.get()
        self._freezing().pause(reason, by)
        self._froze(reason, by)
        return True

    def resume(self) -> bool:
        """Thaw what `pause` froze (descendants paused on their own stay paused).

        Returns False if this action was not paused (or is done).

        Raises:
            EventLoopError: Called from another thread (use
                ``robot.call_soon_threadsafe(handle.resume)``).
        """
        if self._phase is DONE:
            return False
        self._check_here("resume")
        if self._freeze is None or not self._freeze.paused:
            return False
        self._freeze.unpause()
        self._thawed()
        return True

    def suspend(self, reason: str, by: object = None) -> None:
        """Freeze this subtree while ``by`` borrows its resources (a ``preempt="suspend"`` loan).

        The resources layer's call (see `pyrobots_aio.resources.Owner`); programs
        use `pause`. It freezes as a pause does, apart from any pause: `resume`
        does not end it, `unsuspend` does. Nothing happens if the action is done.

        Raises:
            EventLoopError: Called from another thread.
        """
        if self._phase is DONE:
            return
        self._check_here("suspend")
        self._freezing().suspend(reason)
        self._froze(reason, by if isinstance(by, ActionHandle) else None)

    def unsuspend(self) -> None:
        """End the suspension: thaw what is no longer frozen, run the resume hooks.

        Raises:
            EventLoopError: Called from another thread.
        """
        if self._phase is DONE:
            return
        self._check_here("unsuspend")
        if self._freeze is None or self._freeze.suspended is None:
            return
        self._freeze.unsuspend()
        self._thawed()

    @property
    def paused(self) -> bool:
        """Whether it is frozen: paused itself, or under a paused ancestor (and not cancelled)."""
        return self._freeze is not None and self._freeze.since is not None

    @property
    def pause_reason(self) -> str | None:
        """The reason given to `pause` on this action, while it is paused.

        While it is not paused but suspended (a ``@lock(..., preempt="suspend")``
        request borrows its resource), the suspension's reason, which names the
        preemptor.
        """
        freeze = self._freeze
        if freeze is None:
            return None
        return freeze.reason if freeze.paused else freeze.suspended

    def frozen_time(self) -> float:
        """Seconds (on the robot's clock) this action has spent frozen so far."""
        return 0.0 if self._freeze is None else self._freeze.spent(self._loop.time())

    def _freezing(self) -> Freeze:
        """This action's `Freeze`, made the first time it is needed."""
        if self._freeze is None:
            self._freeze = Freeze()
        return self._freeze

    def _frozen_from(self, now: float) -> None:
        """Start a frozen spell at ``now`` (this action is frozen from its start)."""
        self._freezing().begin(now)

    def _froze(self, reason: str | None, by: ActionHandle[Any] | None) -> None:
        """Freeze the subtree of this action, which was just paused or suspended.

        Each action in it that was not frozen yet starts a spell (deepest
        first); the walk stops at cancelled actions, whose cleanup runs on.
        """
        now = self._loop.time()
        newly = [node for node in self._subtree() if node._freezing().begin(now)]
        newly.reverse()
        executive = self._executive
        executive.froze(self, newly, reason, by)
        run_hooks(newly, Hook.PAUSE, executive.owner, executive.log)

    def _thawed(self) -> None:
        """Thaw what in this subtree nothing freezes any more (parents first), after a resume."""
        now = self._loop.time()
        thawed = []
        for node in self._subtree():
            freeze = node._freeze
            if freeze is not None and freeze.since is not None and not node._held_frozen():
                freeze.end(now)
                thawed.append(node)
        executive = self._executive
        executive.thawed(self, thawed)
        run_hooks(thawed, Hook.RESUME, executive.owner, executive.log)

    def _subtree(self) -> list[ActionHandle[Any]]:
        """This action and its descendants that may freeze (parents first).

        A cancelled action is left out with its subtree (cancellation thawed
        them; what they start is their cleanup), and so is one that is done.
        """
        found = []
        stack: list[ActionHandle[Any]] = [self]
        while stack:
            node = stack.pop()
            if node._cancel is not None or node._phase is DONE:
                continue
            found.append(node)
            if node._children:
                stack.extend(reversed(node._children))
        return found

    def _held_frozen(self) -> bool:
        """Whether it or an ancestor is paused or suspended, with no cancellation on the way."""
        node: ActionHandle[Any] | None = self
        while node is not None:
            if node._cancel is not None:
                return False
            if node._freeze is not None and node._freeze.holds:
                return True
            node = node.parent
        return False

    # -- ending -----------------------------------------------------------

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
        if self._phase is DONE:
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

    def on_done(self, callback: Callable[[ActionHandle[T]], object]) -> None:
        """Call ``callback(handle)`` as the action becomes done, before the done-callbacks.

        The library's own bookkeeping (waiting for several actions, monitor
        callbacks in flight) uses it; programs use `add_done_callback`. It is
        called synchronously, at once if the action is done already; an
        exception in it is logged.
        """
        if self._phase is DONE:
            _call_back(callback, self)
            return
        if self._internal is None:
            self._internal = []
        self._internal.append(callback)

    async def _run(self, coro: Coroutine[Any, Any, T]) -> None:  # noqa: PLR0912 (flat: hot)
        """Run the body in this action's task, then wind the action up (the task's coroutine)."""
        current_action.set(self)
        try:
            never_ran = self._cancel is not None  # a local: the attribute changes while it runs
            if never_ran:  # cancelled before it ever ran: the body never starts
                coro.close()
                self._settle(CANCELLED, error=self._interrupted())
            else:
                self._phase = RUNNING
                executive = self._executive
                clock = executive.clock  # read, then called: executive.clock() looks up a method
                self.started_at = clock()
                if executive.instruments.items:
                    executive.started(self)
                try:
                    if self._freeze is None:  # its first step runs here: most bodies end in it
                        try:
                            step = coro.send(None)
                        except StopIteration as end:
                            value = end.value
                        else:  # it awaits: the rest goes through the trampoline
                            value = await Stepped(self, coro, step)
                    else:  # frozen from its start (a child of a frozen action)
                        value = await Stepped(self, coro)
                except (KeyboardInterrupt, SystemExit) as exc:  # record, then let through
                    self._settle(FAILED, error=exc)
                    self._complete()
                    raise
                except BaseException as exc:
                    if self._phase is DONE:  # abandoned: how its body ends changes nothing
                        return
                    _settle_error(self, exc)
                else:
                    if self._phase is DONE:
                        return
                    if self._cancel is not None:  # cancellation swallowed: still CANCELLED
                        self._settle(CANCELLED, value, self._interrupted())
                    else:
                        self._outcome = SUCCEEDED
                        self._value = value
            if self._children:  # (without children, nothing runs between the body and the end)
                self._phase = FINISHING
                await self._reap()
                if self._cancel is not None and self._outcome is SUCCEEDED:
                    # cancelled while its children wound up: CANCELLED (a failure is never masked)
                    self._settle(CANCELLED, error=self._interrupted())
            self._complete()
        finally:  # an abandoned action releases its resources only once its task ends
            if self._finalizers is not None:
                self._run_finalizers()

    async def _reap(self) -> None:
        """Wait for the children still running when the body ended.

        They are cancelled first, unless this action was itself cancelled: then
        its children of that time are cancelled already, and those its cleanup
        started run to their end (the grace ladder bounds them).
        """
        try:
            while self._children:
                children = list(self._children)
                if self._cancel is None:
                    reason = f"its parent {self.name}#{self.id} finished"
                    for child in children:
                        child._cancel_subtree(reason, self)
                try:
                    await all_done(children, self._loop)
                except asyncio.CancelledError:
                    # Meant for the body, which ended before it arrived (it returned without
                    # awaiting again): the children still get waited for.
                    continue
        except BaseException:
            self._complete()
            raise

    def _interrupted(self, cause: BaseException | None = None) -> ActionInterrupted:
        reason, by = self._cancel if self._cancel is not None else (None, None)
        error = ActionInterrupted(self, reason, by)
        error.__cause__ = cause
        return error

    def _settle(
        self, outcome: Outcome, value: Any = None, error: BaseException | None = None
    ) -> None:
        if self._phase is DONE:  # abandoned by the watchdog: its outcome is already told
            return
        self._outcome = outcome
        self._value = value
        self._error = error

    def _complete(self, release: bool = True) -> None:  # positional: a specialized call
        """Mark the action done and wake whoever waits for it (idempotent).

        With ``release`` False (an abandoned action) the finalizers wait for its
        task to end.
        """
        if self._phase is DONE:
            return
        if self._finalizers is not None and release:
            self._run_finalizers()
        if self._freeze is not None:  # a done action is frozen no more
            self._freeze.unpause()
            self._freeze.unsuspend()
            self._freeze.end(self._loop.time())
        self._phase = DONE
        self._coro = None
        executive = self._executive
        clock = executive.clock
        self.finished_at = clock()
        if self._callbacks is not None:  # scheduled first: they run before awaiters resume
            callbacks, self._callbacks = self._callbacks, None
            for callback in callbacks:
                _schedule(callback, self)
        waiting = False
        waiters = self._waiters
        if waiters is not None:
            self._waiters = None
            if isinstance(waiters, list):
                waiting = _wake(waiters)
            elif not _done(waiters):  # (cancelled: its task is being woken already)
                _set_result(waiters, None)
                waiting = True
        self._task = None  # the task's context refers back to this handle
        if self._outcome is FAILED and not waiting:
            self._report_unless_retrieved()
        if self.parent is not None:
            self.parent._forget(self)
        executive.finished(self)
        if self._internal is not None:
            internal, self._internal = self._internal, None
            for callback in internal:
                _call_back(callback, self)

    def _forget(self, child: ActionHandle[Any]) -> None:
        """``child`` is done: it is a running child no more."""
        if self._children is not None:
            self._children.pop(child, None)

    def _forgotten(self) -> bool:
        """Whether the action never started and nothing waits for it (a missing ``await``?)."""
        return self.started_at is None and not (
            self._cancel is not None or self._waiters or self._callbacks
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


def _wake(waiters: list[asyncio.Future[None]]) -> bool:
    """Complete the waiters still pending; return whether there was one."""
    pending = [fut for fut in waiters if not _done(fut)]
    for fut in pending:
        _set_result(fut, None)
    return bool(pending)


def all_done(
    handles: Iterable[ActionHandle[Any]], loop: asyncio.AbstractEventLoop
) -> asyncio.Future[None]:
    """A future done once every handle is (awaiting it never cancels them)."""
    pending = [h for h in handles if not h.done()]
    countdown = Countdown(loop, len(pending))
    tick = countdown.tick
    for handle in pending:
        handle.on_done(tick)
    return countdown.future


def _settle_error(handle: ActionHandle[Any], exc: BaseException) -> None:
    if isinstance(exc, asyncio.CancelledError):
        handle._settle(CANCELLED, error=handle._interrupted())
    elif isinstance(exc, ActionSkipped) and exc.handle is None:
        # Its own lock request was refused. A skip that already names an action is a
        # child's, re-raised by awaiting it: for this action, an ordinary failure.
        exc.handle = handle
        handle._settle(SKIPPED, error=exc)
    elif handle._cancel is not None:
        handle._executive.log.warning(
            "action %s#%d failed during its cleanup", handle.name, handle.id, exc_info=exc
        )
        handle._settle(CANCELLED, error=handle._interrupted(exc))
    else:
        handle._settle(FAILED, error=exc.with_traceback(_from_the_body(exc)))


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


_OWN_MODULES = frozenset({__name__, Stepped.__module__})  # the task's and the trampoline's


def _report_failure(log: ScopedLogger, name: str, ident: int, report: str) -> None:
    log.error("action %s#%d failed and nobody retrieved its error:\n%s", name, ident, report)


def _schedule(callback: Callable[[ActionHandle[Any]], object], handle: ActionHandle[Any]) -> None:
    """Run a done-callback soon on the robot's loop (at once if no loop runs any more)."""
    executive = handle._executive
    loop = executive.loop if executive.is_running else asyncio._get_running_loop()
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
