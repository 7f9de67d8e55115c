"""The executive: starts actions as tasks, keeps their tree, cancels within a grace period.

One `Executive` per robot. Running actions are kept in a dict by id (for
introspection and ``max_actions``) and, at the top, in the robot's root scope.
Cancellation is bounded by a watchdog: `cancel_grace` after a cancellation an
action whose body still runs is cancelled again with a warning; after a second
grace it is abandoned (reported as an ERROR) so that shutdown always completes.
An action whose body has ended only waits for its cancelled children, each
watched on its own: a subtree takes at most two graces a level (a cleanup that
starts a child adds a level), never forever.
"""

from __future__ import annotations

import asyncio
import threading
import time
from collections import deque
from threading import get_ident
from typing import TYPE_CHECKING, Any, TypeVar

from .._core._events import (
    ActionAbandonment,
    ActionFinished,
    ActionPaused,
    ActionResumed,
    ActionSpawned,
    ActionStarted,
    CancelEscalated,
    CancelRequested,
)
from .._core._instrument import Instruments
from .._core._logging import LogScope
from .._core._loops import clock_of, running_here, wrong_loop
from .._core._numbers import finite
from .._core._waiting import Countdown, wait_shielded
from .._exceptions import RobotNotRunningError, TooManyActions
from ._context import current_action
from ._handle import ActionHandle, ActionState, Outcome, drive
from ._pause import (
    freeze,
    freeze_subtree,
    frozen,
    run_hooks,
    stop_frozen_clock,
    thaw,
    thaw_subtree,
)
from ._phases import DONE

if TYPE_CHECKING:
    from collections.abc import Callable, Coroutine, Iterable

    from ._handle import Hooks

T = TypeVar("T")

_ESCALATE, _ABANDON = 1, 2


class Executive:
    """Runs the actions of one robot (its root scope, registry and cancellation watchdog)."""

    def __init__(
        self,
        owner: object,
        *,
        max_actions: int | None = None,
        cancel_grace: float = 2.0,
        instruments: Instruments | None = None,
        log: LogScope | None = None,
    ) -> None:
        _check_options(max_actions, cancel_grace)
        self.owner = owner
        self.max_actions = max_actions
        self.cancel_grace = float(cancel_grace)
        self.instruments = instruments if instruments is not None else Instruments()
        self.log_scope = log if log is not None else LogScope()
        self.log = self.log_scope.logger("pyrobots_aio.actions")
        self._loop: asyncio.AbstractEventLoop | None = None
        self.thread = ""
        self.thread_ident = 0
        """The ident of the thread the robot's loop runs in (`running_here`)."""
        self.clock: Callable[[], float] = time.monotonic
        """The loop's clock (`clock_of`): the actions' timestamps."""
        self._running: dict[int, ActionHandle[Any]] = {}
        self._roots: dict[ActionHandle[Any], None] = {}
        self._next_id = 1
        self._watch: deque[tuple[float, int, ActionHandle[Any]]] = deque()
        self._watch_timer: asyncio.TimerHandle | None = None
        self._closing = False
        self.paused = 0
        """How many actions are paused or suspended now (0: nothing is frozen, the fast path)."""

    # -- lifecycle --------------------------------------------------------

    @property
    def loop(self) -> asyncio.AbstractEventLoop:
        """The loop the robot runs on."""
        if self._loop is None:
            msg = f"{self.owner!r} is not running; use 'async with robot:' first"
            raise RobotNotRunningError(msg)
        return self._loop

    @property
    def is_running(self) -> bool:
        """Whether the robot is between ``__aenter__`` and the end of ``__aexit__``."""
        return self._loop is not None

    def open(self, loop: asyncio.AbstractEventLoop) -> None:
        """Start accepting actions on ``loop`` (the running loop, in this thread)."""
        self._loop = loop
        self.thread = threading.current_thread().name
        self.thread_ident = get_ident()
        self.clock = clock_of(loop)

    def check_loop(self, what: str) -> asyncio.AbstractEventLoop:
        """The robot's loop; `EventLoopError` if the caller is on another thread or loop."""
        loop = self.loop
        if not running_here(loop, self.thread_ident):
            raise wrong_loop(what, loop, self.thread)
        return loop

    async def close(self, reason: str) -> None:
        """Cancel every action and wait, bounded by the watchdog, even if cancelled meanwhile.

        From here on no new root action starts (`spawn` says the robot is shutting
        down); children, such as those a cleanup starts, still do. A cancellation
        of the calling task is held until every action is done, then re-raised.
        """
        self._closing = True
        roots = list(self._roots)
        by = current_action.get()
        for handle in roots:
            if handle._forgotten():
                self.log.warning(
                    "action %s#%d is cancelled by the robot's exit before it ever ran, and "
                    "nothing waits for it: a missing 'await'? (await the handle before "
                    "leaving 'async with robot:')",
                    handle.name,
                    handle.id,
                )
            self.cancel_tree(handle, reason, by)
        try:
            await wait_shielded(self.all_done(roots))
        finally:
            if self._watch_timer is not None:
                self._watch_timer.cancel()
                self._watch_timer = None
            self._watch.clear()
            self._loop = None
            self._closing = False

    # -- starting ---------------------------------------------------------

    def spawn(
        self,
        name: str,
        fn: Callable[..., Coroutine[Any, Any, T]],
        coro: Coroutine[Any, Any, T],
        hooks: Hooks | None = None,
        *,
        uncapped: bool = False,
    ) -> ActionHandle[T]:
        """Start ``coro`` (made by the action function ``fn``) as an action now; return its handle.

        Never blocks. If the action cannot start, ``coro`` is closed and the
        error says why. With ``uncapped`` it starts even at ``max_actions``
        (the emergency stop: it must never be refused for being one too many).
        """
        loop = self._loop
        parent = current_action.get()
        if parent is not None and (parent._executive is not self or parent._phase == DONE):
            parent = None
        if (
            loop is None
            or get_ident() != self.thread_ident  # running_here(loop, ...), inlined
            or not loop.is_running()
            or (parent is None and self._closing)
            or (
                self.max_actions is not None
                and len(self._running) >= self.max_actions
                and not uncapped
            )
        ):
            coro.close()
            raise self._refusal(name, loop, uncapped=uncapped)
        ident = self._next_id
        self._next_id = ident + 1
        handle: ActionHandle[T] = ActionHandle(
            self, loop, ident, name, parent, spawned_at=self.clock()
        )
        handle._fn = fn
        handle._hooks = hooks
        if self.paused and parent is not None and frozen(parent):
            handle._frozen_since = handle.spawned_at  # a child of a frozen action starts frozen
        handle._task = loop.create_task(drive(handle, coro), name=f"{name}#{ident}")
        self._running[ident] = handle
        if parent is None:
            self._roots[handle] = None
        else:
            parent._children[handle] = None
        if self.instruments.items:
            parent_id = parent.id if parent else None
            self.instruments.emit(ActionSpawned(loop.time(), ident, name, parent_id))
        return handle

    def _refusal(
        self, name: str, loop: asyncio.AbstractEventLoop | None, *, uncapped: bool = False
    ) -> Exception:
        """Why action ``name`` cannot start now (`spawn` found that it cannot)."""
        if loop is None:
            msg = (
                f"cannot start action {name!r}: {self.owner!r} is not running; "
                "start it inside 'async with robot:'"
            )
            return RobotNotRunningError(msg)
        if not running_here(loop, self.thread_ident):
            return wrong_loop(f"start action {name!r}", loop, self.thread)
        if self.max_actions is not None and len(self._running) >= self.max_actions and not uncapped:
            return TooManyActions(name, self.max_actions, list(self._running.values()))
        msg = (
            f"cannot start action {name!r}: {self.owner!r} is shutting down; start it "
            "before leaving 'async with robot:', or from an action's cleanup"
        )
        return RobotNotRunningError(msg)

    def started(self, handle: ActionHandle[Any]) -> None:
        """Called by the action's task when its body starts."""
        if self.instruments.items:
            self.instruments.emit(ActionStarted(self.loop.time(), handle.id, handle.name))

    def finished(self, handle: ActionHandle[Any]) -> None:
        """Called when an action is done: drop it from the registry and its scope."""
        self._running.pop(handle.id, None)
        parent = handle.parent
        if parent is None:
            self._roots.pop(handle, None)
        else:
            parent._children.pop(handle, None)
        if self.instruments.items:
            outcome = handle.outcome
            error = repr(handle._error) if outcome is Outcome.FAILED else None
            now = self.loop.time()
            event = ActionFinished(now, handle.id, handle.name, outcome.value, error)
            self.instruments.emit(event)

    # -- cancelling -------------------------------------------------------

    def cancel_tree(
        self, handle: ActionHandle[Any], reason: str | None, by: ActionHandle[Any] | None
    ) -> None:
        """Cancel ``handle`` and every descendant it has now, recording who and why.

        An action already cancelled is passed over with its subtree: what it
        started since its cancellation is its cleanup, which a second cancel
        never cuts short (the watchdog bounds it, counted from the first).
        """
        stack = [handle]
        while stack:
            node = stack.pop()
            if node._cancel_requested or node.done():
                continue
            stack.extend(node._children)
            node._cancel_requested = True
            node._cancel_reason = reason
            node._cancel_by = by
            if node._frozen_since is not None:  # cancellation thaws it: its cleanup runs
                stop_frozen_clock(node)
            node._interrupt()
            self._watch_later(node, _ESCALATE)
            if self.instruments.items:
                by_id = by.id if by is not None else None
                now = self.loop.time()
                self.instruments.emit(CancelRequested(now, node.id, node.name, reason, by_id))

    async def cancel_all(
        self, reason: str | None = None, keep: Iterable[ActionHandle[Any]] = ()
    ) -> None:
        """Cancel every action except those in ``keep`` (and their ancestors); wait for them."""
        spared = set(keep)
        for handle in list(spared):
            node = handle.parent
            while node is not None:
                spared.add(node)
                node = node.parent
        targets = self._outermost_except(spared)
        by = current_action.get()
        for handle in targets:
            self.cancel_tree(handle, reason, by)
        await self.all_done(targets)

    def _outermost_except(self, spared: set[ActionHandle[Any]]) -> list[ActionHandle[Any]]:
        """The highest actions not spared: roots, or children of spared ancestors."""
        found: list[ActionHandle[Any]] = []
        stack = list(self._roots)
        while stack:
            node = stack.pop()
            if node in spared:
                stack.extend(node._children)
            else:
                found.append(node)
        return found

    async def reap_children(self, handle: ActionHandle[Any]) -> None:
        """Wait for the children still running when ``handle``'s body ended.

        They are cancelled first, unless ``handle`` was itself cancelled: then
        its children of that time are cancelled already, and those its cleanup
        started run to their end (the watchdog bounds them).
        """
        while handle._children:
            children = list(handle._children)
            if not handle._cancel_requested:
                reason, by = f"its parent {handle.name}#{handle.id} finished", current_action.get()
                for child in children:
                    self.cancel_tree(child, reason, by)
            await self.all_done(children)

    def all_done(self, handles: Iterable[ActionHandle[Any]]) -> asyncio.Future[None]:
        """A future done once every handle is (awaiting it never cancels them)."""
        pending = [h for h in handles if not h.done()]
        countdown = Countdown(self.loop, len(pending))
        for handle in pending:
            handle._on_done(countdown.tick)
        return countdown.future

    # -- pausing ----------------------------------------------------------

    def pause_tree(
        self, handle: ActionHandle[Any], reason: str | None, by: ActionHandle[Any] | None
    ) -> None:
        """Pause ``handle``: freeze its subtree, run the pause hooks, record who and why."""
        if not handle._paused:
            self.paused += 1
        self._froze(handle, freeze(handle, reason, by), reason, by)

    def resume_tree(self, handle: ActionHandle[Any]) -> None:
        """Resume ``handle``: thaw what is no longer under a pause, run the resume hooks."""
        if handle._paused:
            handle._paused = False
            self.paused -= 1
        self._thawed(handle, thaw(handle))

    def suspend_tree(
        self, handle: ActionHandle[Any], reason: str, by: ActionHandle[Any] | None
    ) -> None:
        """Suspend ``handle`` (its resource is lent to ``by``): freeze as a pause, apart from it."""
        if handle._suspended is None:
            self.paused += 1
        handle._suspended = reason
        self._froze(handle, freeze_subtree(handle), reason, by)

    def unsuspend_tree(self, handle: ActionHandle[Any]) -> None:
        """End ``handle``'s suspension: thaw what is no longer frozen, run the resume hooks."""
        if handle._suspended is None:
            return
        handle._suspended = None
        self.paused -= 1
        self._thawed(handle, thaw_subtree(handle))

    def _froze(
        self,
        handle: ActionHandle[Any],
        newly: list[ActionHandle[Any]],
        reason: str | None,
        by: ActionHandle[Any] | None,
    ) -> None:
        if self.instruments.items:
            by_id, now = by.id if by is not None else None, self.loop.time()
            for node in newly:
                event = ActionPaused(now, node.id, node.name, reason, by_id, handle.id)
                self.instruments.emit(event)
        run_hooks(newly, 0, "pause")

    def _thawed(self, handle: ActionHandle[Any], thawed: list[ActionHandle[Any]]) -> None:
        if self.instruments.items:
            now = self.loop.time()
            for node in thawed:
                self.instruments.emit(ActionResumed(now, node.id, node.name, handle.id))
        run_hooks(thawed, 1, "resume")

    def unpause(self, handle: ActionHandle[Any]) -> None:
        """Count ``handle`` as neither paused nor suspended any more (it is done)."""
        if handle._paused:
            handle._paused = False
            self.paused -= 1
        if handle._suspended is not None:
            handle._suspended = None
            self.paused -= 1

    def pause_all(self, reason: str | None) -> None:
        """Pause every action of the root scope (their subtrees freeze with them)."""
        by = current_action.get()
        for handle in list(self._roots):
            if not handle.done():
                self.pause_tree(handle, reason, by)

    def resume_all(self) -> None:
        """Resume every paused action."""
        for handle in [h for h in self._running.values() if h._paused]:
            self.resume_tree(handle)

    # -- the watchdog -----------------------------------------------------

    def _watch_later(self, handle: ActionHandle[Any], stage: int) -> None:
        self._watch.append((self.loop.time() + self.cancel_grace, stage, handle))
        self._arm_watchdog()

    def _arm_watchdog(self) -> None:
        """Arm the watchdog's timer at the earliest deadline, unless it is armed already."""
        if self._watch and self._watch_timer is None:
            self._watch_timer = self.loop.call_at(self._watch[0][0], self._watchdog)

    def _watchdog(self) -> None:
        self._watch_timer = None
        now = self.loop.time()
        watch = self._watch
        while watch and watch[0][0] <= now:
            _, stage, handle = watch.popleft()
            if not handle.done():
                self._overdue(handle, stage)
        self._arm_watchdog()  # unless `_overdue` armed it already

    def _overdue(self, handle: ActionHandle[Any], stage: int) -> None:
        finishing = handle.state is ActionState.FINISHING
        if finishing or stage == _ABANDON:
            # A body still running is cancelled again below, and with it the cleanup
            # it awaits; what it started and did not await is cut once it is over.
            self._cut_cleanup(handle, stage * self.cancel_grace, warn=finishing)
        if finishing:
            # Its body is over: it only waits for its children, each of which the
            # watchdog bounds on its own (abandoning it would orphan them).
            return
        where = handle.location() or "an unknown place"
        if stage == _ESCALATE:
            self.log.warning(
                "action %s#%d still running %.3g s after cancellation, at %s; cancelling it again",
                handle.name,
                handle.id,
                self.cancel_grace,
                where,
            )
            handle._interrupt()
            self._watch_later(handle, _ABANDON)
            if self.instruments.items:
                now = self.loop.time()
                self.instruments.emit(CancelEscalated(now, handle.id, handle.name, where))
            return
        self.log.error(
            "action %s#%d ignored cancellation for %.3g s, at %s; abandoning it (its body is "
            "ended; its resources stay held until its task ends)",
            handle.name,
            handle.id,
            2 * self.cancel_grace,
            where,
        )
        if self.instruments.items:
            now = self.loop.time()
            self.instruments.emit(ActionAbandonment(now, handle.id, handle.name, where))
        handle._abandon(2 * self.cancel_grace)

    def _cut_cleanup(self, handle: ActionHandle[Any], elapsed: float, *, warn: bool) -> None:
        """Cancel the cleanup actions ``handle`` started that outlast its grace.

        With ``warn`` False (its body still runs, and the warning about it says
        where), they are cancelled without a warning of their own.
        """
        late = [child for child in handle._children if not child._cancel_requested]
        for child in late:
            if not warn:
                child.cancel(f"cleanup of {handle.name}#{handle.id} ran past cancel_grace")
                continue
            self.log.warning(
                "cleanup action %s#%d of %s#%d still running %.3g s after %s#%d was cancelled, "
                "at %s; cancelling it",
                child.name,
                child.id,
                handle.name,
                handle.id,
                elapsed,
                handle.name,
                handle.id,
                child.location() or "an unknown place",
            )
            child.cancel(f"cleanup of {handle.name}#{handle.id} ran past cancel_grace")

    # -- introspection ----------------------------------------------------

    def running(self) -> list[ActionHandle[Any]]:
        """Every action not yet done, in start order."""
        return list(self._running.values())

    def get(self, ident: int) -> ActionHandle[Any] | None:
        """The running action with this id, or None."""
        return self._running.get(ident)

    def roots(self) -> list[ActionHandle[Any]]:
        """The running actions of the root scope (started outside any action)."""
        return list(self._roots)


def _check_options(max_actions: object, cancel_grace: object) -> None:
    """Raise ValueError, naming the value and the fix, for bad executive options."""
    if max_actions is not None and (
        isinstance(max_actions, bool) or not isinstance(max_actions, int) or max_actions < 1
    ):
        msg = f"max_actions must be a positive integer or None, got {max_actions!r}"
        raise ValueError(msg)
    finite("cancel_grace", cancel_grace, positive=True, must="a positive number of seconds")
