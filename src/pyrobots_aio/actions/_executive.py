"""The executive: starts actions, keeps their registry, bounds their cleanup in time.

One `Executive` per robot. It spawns actions (each handle starts its own
task), keeps the running ones in a dict by id (for introspection and
``max_actions``; those without a parent are the robot's root scope), and
tells the instruments what happens. Everything else about an action (cancelling,
pausing, winding up) is its handle's.

Cancellation is bounded by the grace ladder (`pyrobots_aio._core._grace`):
`cancel_grace` after a cancellation an action whose body still runs is
cancelled again with a warning; after a second grace it is abandoned
(reported as an ERROR) so that shutdown always completes. An action whose
body has ended only waits for its cancelled children, each watched on its
own: a subtree takes at most two graces a level (a cleanup that starts a
child adds a level), never forever.
"""

from __future__ import annotations

import asyncio
import threading
import time
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
from .._core._grace import Ladder, Stage
from .._core._instrument import Instruments
from .._core._logging import LogScope
from .._core._loops import clock_of, makes_plain_tasks, running_here, wrong_loop
from .._core._numbers import finite
from .._core._waiting import wait_shielded
from .._exceptions import RobotNotRunningError, TooManyActions
from ..resources import ResourceManager
from ._handle import ActionHandle, all_done, current_action
from ._states import ActionState, Outcome

if TYPE_CHECKING:
    from collections.abc import Callable, Coroutine, Iterable

    from ._pause import Hooks

T = TypeVar("T")

# Bound once: Python 3.11 calls a method of an imported name through a generic attribute
# lookup (no specialized method call), and every action start makes these two calls.
_current_action = current_action.get
_start_action = ActionHandle._start


class Executive:
    """Runs the actions of one robot (its root scope, registry and cancellation watchdog)."""

    def __init__(
        self,
        owner: object,
        *,
        resources: ResourceManager[ActionHandle[Any]] | None = None,
        max_actions: int | None = None,
        cancel_grace: float = 2.0,
        instruments: Instruments | None = None,
        log: LogScope | None = None,
    ) -> None:
        _check_options(max_actions, cancel_grace)
        self.owner = owner
        self.resources: ResourceManager[ActionHandle[Any]] = (
            resources if resources is not None else ResourceManager()
        )
        """The lock state of the robot: it answers what an action holds and awaits."""
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
        self.plain_tasks = False
        """Whether an action's task is made as ``asyncio.Task`` (`makes_plain_tasks`)."""
        self._running: dict[int, ActionHandle[Any]] = {}
        """Every action not yet done, by id, in start order."""
        self._next_id = 1
        self._ladder: Ladder[ActionHandle[Any]] | None = None
        self._closing = False

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
        self.plain_tasks = makes_plain_tasks(loop)
        self._ladder = Ladder(loop, self.cancel_grace, self._overdue)

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
        roots = self.roots()
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
            handle._cancel_subtree(reason, by)
        try:
            await wait_shielded(all_done(roots, self.loop))
        finally:
            if self._ladder is not None:
                self._ladder.close()
                self._ladder = None
            self._loop = None
            self._closing = False

    # -- starting ---------------------------------------------------------

    def spawn(
        self,
        name: str,
        fn: Callable[..., Coroutine[Any, Any, T]],
        coro: Coroutine[Any, Any, T],
        hooks: Hooks | None = None,
        uncapped: bool = False,  # positional: Python 3.11 specializes no call to keyword-only
    ) -> ActionHandle[T]:
        """Start ``coro`` (made by the action function ``fn``) as an action now; return its handle.

        Never blocks. If the action cannot start, ``coro`` is closed and the
        error says why. With ``uncapped`` it starts even at ``max_actions``
        (the emergency stop: it must never be refused for being one too many).
        """
        loop = self._loop
        parent = _current_action()
        if parent is not None and (parent._executive is not self or parent.done()):
            parent = None
        if (
            loop is None
            or get_ident() != self.thread_ident  # running_here(loop, ...), inlined
            or not loop.is_running()
            or (self._closing and parent is None)
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
        handle = _start_action(self, loop, ident, name, parent, fn, hooks, coro)
        self._running[ident] = handle
        if self.instruments.items:
            parent_id = parent.id if parent is not None else None
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

    # -- what the handles tell ---------------------------------------------

    def started(self, handle: ActionHandle[Any]) -> None:
        """Called by the action's task when its body starts (only when instruments listen)."""
        if self.instruments.items:
            self.instruments.emit(ActionStarted(self.loop.time(), handle.id, handle.name))

    def finished(self, handle: ActionHandle[Any]) -> None:
        """Called when an action is done: drop it from the registry."""
        self._running.pop(handle.id, None)
        if self.instruments.items:
            outcome = handle.outcome
            error = repr(handle._error) if outcome is Outcome.FAILED else None
            now = self.loop.time()
            event = ActionFinished(now, handle.id, handle.name, outcome.value, error)
            self.instruments.emit(event)

    def cancelling(
        self, handle: ActionHandle[Any], reason: str | None, by: ActionHandle[Any] | None
    ) -> None:
        """Called when cancellation of ``handle`` is requested: watch it with the grace ladder."""
        if self._ladder is not None:
            self._ladder.watch(handle)
        if self.instruments.items:
            by_id, now = by.id if by is not None else None, self.loop.time()
            self.instruments.emit(CancelRequested(now, handle.id, handle.name, reason, by_id))

    def froze(
        self,
        handle: ActionHandle[Any],
        nodes: list[ActionHandle[Any]],
        reason: str | None,
        by: ActionHandle[Any] | None,
    ) -> None:
        """Called when pausing or suspending ``handle`` froze ``nodes``."""
        if self.instruments.items:
            by_id, now = by.id if by is not None else None, self.loop.time()
            for node in nodes:
                event = ActionPaused(now, node.id, node.name, reason, by_id, handle.id)
                self.instruments.emit(event)

    def thawed(self, handle: ActionHandle[Any], nodes: list[ActionHandle[Any]]) -> None:
        """Called when resuming or unsuspending ``handle`` thawed ``nodes``."""
        if self.instruments.items:
            now = self.loop.time()
            for node in nodes:
                self.instruments.emit(ActionResumed(now, node.id, node.name, handle.id))

    # -- every action at once ---------------------------------------------

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
            handle._cancel_subtree(reason, by)
        await all_done(targets, self.loop)

    def all_done(self, handles: Iterable[ActionHandle[Any]]) -> asyncio.Future[None]:
        """A future done once every handle is (awaiting it never cancels them)."""
        return all_done(handles, self.loop)

    def _outermost_except(self, spared: set[ActionHandle[Any]]) -> list[ActionHandle[Any]]:
        """The highest actions not spared: roots, or children of spared ancestors."""
        found: list[ActionHandle[Any]] = []
        stack = self.roots()
        while stack:
            node = stack.pop()
            if node in spared:
                stack.extend(node.children)
            else:
                found.append(node)
        return found

    def pause_all(self, reason: str | None) -> None:
        """Pause every action of the root scope (their subtrees freeze with them)."""
        for handle in self.roots():
            handle.pause(reason)

    def resume_all(self) -> None:
        """Resume every paused action (in start order: parents before their children)."""
        for handle in list(self._running.values()):
            handle.resume()

    # -- the watchdog -----------------------------------------------------

    def _overdue(self, handle: ActionHandle[Any], stage: Stage) -> bool:
        """The grace ladder's step for a cancelled action; return whether to go on watching."""
        if handle.done():
            return False
        elapsed = self.cancel_grace if stage is Stage.ESCALATE else 2 * self.cancel_grace
        finishing = handle.state is ActionState.FINISHING
        if finishing or stage is Stage.ABANDON:
            # A body still running is cancelled again below, and with it the cleanup
            # it awaits; what it started and did not await is cut once it is over.
            self._cut_cleanup(handle, elapsed, warn=finishing)
        if finishing:
            # Its body is over: it only waits for its children, each of which the
            # watchdog bounds on its own (abandoning it would orphan them).
            return False
        where = handle.location() or "an unknown place"
        if stage is Stage.ESCALATE:
            self.log.warning(
                "action %s#%d still running %.3g s after cancellation, at %s; cancelling it again",
                handle.name,
                handle.id,
                self.cancel_grace,
                where,
            )
            handle._interrupt()
            if self.instruments.items:
                now = self.loop.time()
                self.instruments.emit(CancelEscalated(now, handle.id, handle.name, where))
            return True
        self.log.error(
            "action %s#%d ignored cancellation for %.3g s, at %s; abandoning it (its body is "
            "ended; its resources stay held until its task ends)",
            handle.name,
            handle.id,
            elapsed,
            where,
        )
        if self.instruments.items:
            now = self.loop.time()
            self.instruments.emit(ActionAbandonment(now, handle.id, handle.name, where))
        handle._abandon(elapsed)
        return False

    def _cut_cleanup(self, handle: ActionHandle[Any], elapsed: float, *, warn: bool) -> None:
        """Cancel the cleanup actions ``handle`` started that outlast its grace.

        With ``warn`` False (its body still runs, and the warning about it says
        where), they are cancelled without a warning of their own.
        """
        late = [child for child in handle.children if not child.cancel_requested]
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
        return [handle for handle in self._running.values() if handle.parent is None]


def _check_options(max_actions: object, cancel_grace: object) -> None:
    """Raise ValueError, naming the value and the fix, for bad executive options."""
    if max_actions is not None and (
        isinstance(max_actions, bool) or not isinstance(max_actions, int) or max_actions < 1
    ):
        msg = f"max_actions must be a positive integer or None, got {max_actions!r}"
        raise ValueError(msg)
    finite("cancel_grace", cancel_grace, positive=True, must="a positive number of seconds")
